//! Camera motion blur (Chapman 2011): per-pixel velocity from the depth buffer and the combined
//! current-to-previous matrix, then a centred N-sample blur along it.
//!
//! Pixel `(x, y)` (centre `(x + 0.5, y + 0.5)`, NDC `nx = 2 (x + 0.5) / w - 1`,
//! `ny = 1 - 2 (y + 0.5) / h`) at view-axis depth `d` is the view-space point
//! `d ((nx + P02) / P00, (ny + P12) / P11, -1)`, written homogeneously as `(.., -1, 1 / d)` so
//! that `d = inf` (sky) is a direction, moved only by the camera's rotation. The matrix
//! `prev_projection * prev_view * inverse(view)` takes it to the previous clip space; the
//! velocity is the current minus the previous pixel position (+x right, +y down, pixels), as in
//! the rasterizer's velocity buffer. A point behind the previous camera gets velocity 0.
use glam::{DMat4, DVec4};
use rayon::prelude::*;

use super::check_image;
use crate::error::{Error, Result};

/// A perspective camera as matrices (OpenGL conventions, as `motionblur.Camera`).
#[derive(Clone, Copy, Debug)]
pub struct CameraMatrices {
    /// World-to-camera.
    pub view: DMat4,
    /// Perspective projection: last row `(0, 0, -1, 0)`.
    pub projection: DMat4,
}

impl CameraMatrices {
    /// Checks the matrices (finite, a perspective projection), naming `name` in errors.
    pub fn new(view: DMat4, projection: DMat4, name: &'static str) -> Result<Self> {
        let finite = view.to_cols_array().iter().all(|v| v.is_finite())
            && projection.to_cols_array().iter().all(|v| v.is_finite());
        if !finite {
            return Err(Error::value(name, "matrices must be finite"));
        }
        if projection.row(3) != DVec4::new(0.0, 0.0, -1.0, 0.0)
            || projection.x_axis.x == 0.0
            || projection.y_axis.y == 0.0
        {
            return Err(Error::value(
                name,
                "projection must be a perspective projection",
            ));
        }
        if view.determinant().abs() < 1e-12 {
            return Err(Error::value(name, "view matrix is singular"));
        }
        Ok(Self { view, projection })
    }
}

/// Velocity `(h, w, 2)` in pixels of every pixel of the `(h, w)` depth map seen by `current`,
/// when the camera moved from `previous` (module docs).
pub fn camera_velocity(
    depth: &[f32],
    w: usize,
    h: usize,
    current: &CameraMatrices,
    previous: &CameraMatrices,
) -> Result<Vec<f32>> {
    check_image("depth", depth, w, h, 1)?;
    if depth.par_iter().any(|d| d.is_nan() || *d <= 0.0) {
        return Err(Error::value(
            "depth",
            "contains NaN or values <= 0 (use +inf for background)",
        ));
    }
    Ok(velocity_unchecked(depth, w, h, current, previous, 1.0))
}

fn velocity_unchecked(
    depth: &[f32],
    w: usize,
    h: usize,
    cur: &CameraMatrices,
    prev: &CameraMatrices,
    scale: f64,
) -> Vec<f32> {
    let m = prev.projection * prev.view * cur.view.inverse();
    let p = &cur.projection;
    let (p00, p11, p02, p12) = (p.x_axis.x, p.y_axis.y, p.z_axis.x, p.z_axis.y);
    let (wf, hf) = (w as f64, h as f64);
    let mut out = vec![0.0f32; w * h * 2];
    if cur.view == prev.view && cur.projection == prev.projection {
        // A static camera: exactly no motion (the matrix product would leave ~1e-13 pixels).
        return out;
    }
    out.par_chunks_mut(w * 2).enumerate().for_each(|(y, row)| {
        let ny = 1.0 - 2.0 * (y as f64 + 0.5) / hf;
        for x in 0..w {
            let nx = 2.0 * (x as f64 + 0.5) / wf - 1.0;
            let d = depth[y * w + x] as f64;
            let q = m * DVec4::new((nx + p02) / p00, (ny + p12) / p11, -1.0, 1.0 / d);
            if q.w <= 0.0 {
                continue;
            }
            let px = (q.x / q.w + 1.0) * 0.5 * wf;
            let py = (1.0 - q.y / q.w) * 0.5 * hf;
            row[2 * x] = ((x as f64 + 0.5 - px) * scale) as f32;
            row[2 * x + 1] = ((y as f64 + 0.5 - py) * scale) as f32;
        }
    });
    out
}

/// `floor(v)` for |v| < 2^31 without a libm call.
#[inline(always)]
fn floorf(v: f32) -> f32 {
    let i = v as i32 as f32;
    if i > v {
        i - 1.0
    } else {
        i
    }
}

/// Largest `fps / target_fps` factor of `camera_motion_blur`.
pub const MAX_FPS_RATIO: f64 = 1000.0;
/// Longest velocity `velocity_blur` takes, in pixels per component: a streak that long already
/// crosses any image (sides are at most 16384 pixels); `camera_motion_blur` clamps to it.
pub const MAX_VELOCITY: f32 = 1e6;

/// Largest number of blur samples accepted.
pub const MAX_SAMPLES: usize = 1024;

/// Centred blur of a `(h, w, 4)` image along per-pixel `velocity` `(h, w, 2)` (pixels):
/// `out = (1/N) sum_i I(p + v (i / (N - 1) - 1/2))`, `i = 0 .. N-1`, bilinear samples clamped to
/// the image edge. `N = 1` or a zero velocity returns the pixel unchanged.
pub fn velocity_blur(
    rgba: &[f32],
    velocity: &[f32],
    w: usize,
    h: usize,
    samples: usize,
) -> Result<Vec<f32>> {
    check_image("rgba", rgba, w, h, 4)?;
    check_image("velocity", velocity, w, h, 2)?;
    if samples == 0 || samples > MAX_SAMPLES {
        return Err(Error::value(
            "samples",
            format!("must be in [1, {MAX_SAMPLES}], got {samples}"),
        ));
    }
    if rgba.par_iter().any(|v| !v.is_finite()) {
        return Err(Error::value("rgba", "contains NaN or inf"));
    }
    if velocity
        .par_iter()
        .any(|v| !v.is_finite() || v.abs() > MAX_VELOCITY)
    {
        return Err(Error::value(
            "velocity",
            format!("must be finite and within +-{MAX_VELOCITY:e} pixels (MAX_VELOCITY)"),
        ));
    }
    Ok(blur_unchecked(rgba, velocity, w, h, samples))
}

fn blur_unchecked(rgba: &[f32], velocity: &[f32], w: usize, h: usize, samples: usize) -> Vec<f32> {
    let mut out = vec![0.0f32; w * h * 4];
    let inv = 1.0 / samples as f32;
    let fetch = |x: i64, y: i64| -> &[f32] {
        let x = x.clamp(0, w as i64 - 1) as usize;
        let y = y.clamp(0, h as i64 - 1) as usize;
        &rgba[(y * w + x) * 4..(y * w + x) * 4 + 4]
    };
    out.par_chunks_mut(w * 4).enumerate().for_each(|(y, row)| {
        for x in 0..w {
            let i = y * w + x;
            let (vx, vy) = (velocity[2 * i], velocity[2 * i + 1]);
            let o = &mut row[x * 4..x * 4 + 4];
            if samples == 1 || (vx == 0.0 && vy == 0.0) {
                o.copy_from_slice(&rgba[i * 4..i * 4 + 4]);
                continue;
            }
            let mut acc = [0.0f32; 4];
            for s in 0..samples {
                let t = s as f32 / (samples - 1) as f32 - 0.5;
                let (px, py) = (x as f32 + vx * t, y as f32 + vy * t);
                let (x0, y0) = (floorf(px), floorf(py));
                let (fx, fy) = (px - x0, py - y0);
                let (x0, y0) = (x0 as i64, y0 as i64);
                let (a, b) = (fetch(x0, y0), fetch(x0 + 1, y0));
                let (c, d) = (fetch(x0, y0 + 1), fetch(x0 + 1, y0 + 1));
                for k in 0..4 {
                    let top = a[k] + fx * (b[k] - a[k]);
                    let bot = c[k] + fx * (d[k] - c[k]);
                    acc[k] += top + fy * (bot - top);
                }
            }
            for k in 0..4 {
                o[k] = acc[k] * inv;
            }
        }
    });
    out
}

/// The parameters of [`camera_motion_blur`]: the two cameras, the taps and the velocity's scale.
#[derive(Clone, Copy, Debug)]
pub struct CameraBlur {
    /// The camera of the image.
    pub current: CameraMatrices,
    /// The camera of the previous frame.
    pub previous: CameraMatrices,
    /// Taps of the centred blur, 1 to [`MAX_SAMPLES`].
    pub samples: usize,
    /// The velocity's factor, the target-fps factor `fps / target_fps` (1 by default), in
    /// `[0, MAX_FPS_RATIO]`.
    pub scale: f64,
}

/// Chapman's camera motion blur of a `(h, w, 4)` image with its `(h, w)` depth: velocity from
/// the cameras times `scale`, then the centred `samples`-sample blur ([`CameraBlur`]). A static
/// camera returns the image unchanged.
pub fn camera_motion_blur(
    rgba: &[f32],
    depth: &[f32],
    w: usize,
    h: usize,
    blur: &CameraBlur,
) -> Result<Vec<f32>> {
    let &CameraBlur {
        current,
        previous,
        samples,
        scale,
    } = blur;
    if !(0.0..=MAX_FPS_RATIO).contains(&scale) {
        return Err(Error::value(
            "fps",
            format!("fps / target_fps must be in [0, {MAX_FPS_RATIO}], got {scale}"),
        ));
    }
    let mut v = camera_velocity(depth, w, h, &current, &previous)?;
    if scale != 1.0 {
        v.par_iter_mut()
            .for_each(|x| *x = (*x as f64 * scale) as f32);
    }
    // Velocities from points very close to the previous camera plane can be huge: clamp them.
    v.par_iter_mut()
        .for_each(|x| *x = x.clamp(-MAX_VELOCITY, MAX_VELOCITY));
    velocity_blur(rgba, &v, w, h, samples)
}
