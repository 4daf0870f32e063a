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

use super::{check_image, filled, put4};
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

/// The screen motion of a pixel of known depth between two cameras (module docs).
#[derive(Clone, Copy)]
pub(crate) struct PixelMotion {
    m: DMat4,
    p00: f64,
    p11: f64,
    p02: f64,
    p12: f64,
    wf: f64,
    hf: f64,
    /// `q` of [`PixelMotion::at`] as `base + x dx + y dy + m.w_axis / d` ([`PixelMotion::at_affine`]).
    base: DVec4,
    dx: DVec4,
    dy: DVec4,
    /// Whether the cameras are the same (exactly no motion).
    pub still: bool,
}

impl PixelMotion {
    /// The motion of a `w` x `h` image seen by `cur` that was seen by `prev`.
    pub fn new(cur: &CameraMatrices, prev: &CameraMatrices, w: usize, h: usize) -> Self {
        let p = &cur.projection;
        let m = prev.projection * prev.view * cur.view.inverse();
        let (wf, hf) = (w as f64, h as f64);
        let (p00, p11, p02, p12) = (p.x_axis.x, p.y_axis.y, p.z_axis.x, p.z_axis.y);
        PixelMotion {
            m,
            p00,
            p11,
            p02,
            p12,
            wf,
            hf,
            base: m.x_axis * ((1.0 / wf - 1.0 + p02) / p00)
                + m.y_axis * ((1.0 - 1.0 / hf + p12) / p11)
                - m.z_axis,
            dx: m.x_axis * (2.0 / (wf * p00)),
            dy: m.y_axis * (-2.0 / (hf * p11)),
            // A static camera: exactly no motion (the matrix product would leave ~1e-13 pixels).
            still: cur.view == prev.view && cur.projection == prev.projection,
        }
    }

    /// The velocity of pixel `(x, y)` at view-axis depth `d` times `scale` (0 behind the
    /// previous camera, or for a still camera).
    #[inline]
    pub fn at(&self, x: usize, y: usize, d: f32, scale: f64) -> [f32; 2] {
        if self.still {
            return [0.0, 0.0];
        }
        let ny = 1.0 - 2.0 * (y as f64 + 0.5) / self.hf;
        let nx = 2.0 * (x as f64 + 0.5) / self.wf - 1.0;
        let d = d as f64;
        let q = self.m
            * DVec4::new(
                (nx + self.p02) / self.p00,
                (ny + self.p12) / self.p11,
                -1.0,
                1.0 / d,
            );
        if q.w <= 0.0 {
            return [0.0, 0.0];
        }
        let px = (q.x / q.w + 1.0) * 0.5 * self.wf;
        let py = (1.0 - q.y / q.w) * 0.5 * self.hf;
        [
            ((x as f64 + 0.5 - px) * scale) as f32,
            ((y as f64 + 0.5 - py) * scale) as f32,
        ]
    }

    /// [`PixelMotion::at`] (scale 1) of each pixel of row `y` with depths `depth` into `out`,
    /// `q` as an affine function of `x`, `y` and `1 / d` (a few multiply-adds instead of a 4x4
    /// product, in a loop the compiler vectorises: the same velocity to rounding, not the same
    /// bits).
    #[inline(always)]
    pub fn row_affine(&self, y: usize, depth: &[f32], out: &mut [[f32; 2]]) {
        if self.still {
            out.fill([0.0, 0.0]);
            return;
        }
        let yf = y as f64;
        let (b, dx, dy, dd) = (self.base, self.dx, self.dy, self.m.w_axis);
        let (cx, cy, cw) = (b.x + dy.x * yf, b.y + dy.y * yf, b.w + dy.w * yf);
        let (sx, sy) = (0.5 * self.wf, 0.5 * self.hf);
        let ry = yf + 0.5;
        for (x, (o, &d)) in out.iter_mut().zip(depth).enumerate() {
            let (xf, r) = (x as f64, 1.0 / d as f64);
            let qw = cw + dx.w * xf + dd.w * r;
            let inv = 1.0 / qw;
            let px = ((cx + dx.x * xf + dd.x * r) * inv + 1.0) * sx;
            let py = (1.0 - (cy + dx.y * xf + dd.y * r) * inv) * sy;
            let v = [(xf + 0.5 - px) as f32, (ry - py) as f32];
            *o = if qw > 0.0 { v } else { [0.0, 0.0] };
        }
    }
}

fn velocity_unchecked(
    depth: &[f32],
    w: usize,
    h: usize,
    cur: &CameraMatrices,
    prev: &CameraMatrices,
    scale: f64,
) -> Vec<f32> {
    let motion = PixelMotion::new(cur, prev, w, h);
    let mut out = vec![0.0f32; w * h * 2];
    if motion.still {
        return out;
    }
    out.par_chunks_mut(w * 2).enumerate().for_each(|(y, row)| {
        for x in 0..w {
            let v = motion.at(x, y, depth[y * w + x], scale);
            row[2 * x] = v[0];
            row[2 * x + 1] = v[1];
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
    let taps = Taps::new(samples);
    let simd = super::simd();
    filled(w * h * 4, |out| {
        out.par_chunks_mut(w * 4).enumerate().for_each(|(y, row)| {
            taps.blur_row(rgba, (w, h), y, row, simd, |x| {
                let i = y * w + x;
                [velocity[2 * i], velocity[2 * i + 1]]
            });
        })
    })
}

/// The taps of the centred blur: `t_i = i / (N - 1) - 1/2` and `1 / N`.
pub(crate) struct Taps {
    t: Vec<f32>,
    inv: f32,
}

impl Taps {
    /// The taps of an `samples`-sample blur (>= 1).
    pub fn new(samples: usize) -> Self {
        let t = if samples == 1 {
            vec![]
        } else {
            (0..samples)
                .map(|s| s as f32 / (samples - 1) as f32 - 0.5)
                .collect()
        };
        Taps {
            t,
            inv: 1.0 / samples as f32,
        }
    }

    /// Whether every tap of pixel `(x, y)` along `v` and the texels right of and below it lie
    /// inside the `(w, h)` image (no tap is clamped): `|t| <= 1/2` puts every tap within
    /// `|v| / 2` of the pixel, one pixel more for the texel to its right or below, one for the
    /// rounding. False for a NaN velocity.
    #[inline(always)]
    fn inside((w, h): (usize, usize), (x, y): (usize, usize), [vx, vy]: [f32; 2]) -> bool {
        let (ex, ey) = (0.5 * vx.abs() + 2.0, 0.5 * vy.abs() + 2.0);
        let (xf, yf) = (x as f32, y as f32);
        xf - ex >= 0.0 && yf - ey >= 0.0 && xf + ex <= (w - 1) as f32 && yf + ey <= (h - 1) as f32
    }

    /// Writes every pixel of output row `y` (`(w, 4)`, uninitialised) of the `(w, h)` image
    /// `rgba` blurred along `velocity(x)`, the velocity of pixel `x` of the row (called once a
    /// pixel, in order). With `simd` (AVX2 detected), the pixels whose taps are all inside run
    /// two by two in one vector, tap by tap along the row ([`Taps::row_avx`]): the same bits as
    /// [`Taps::blur`].
    #[inline]
    pub fn blur_row(
        &self,
        rgba: &[f32],
        (w, h): (usize, usize),
        y: usize,
        row: &mut [std::mem::MaybeUninit<f32>],
        simd: bool,
        velocity: impl FnMut(usize) -> [f32; 2],
    ) {
        self.blur_row_skipping(rgba, (w, h), y, row, simd, None, velocity);
    }

    /// [`Taps::blur_row`] leaving out the pixels `skip` marks (`(w,)` when given): they are
    /// neither written nor asked their velocity; the others get the same bits.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub fn blur_row_skipping(
        &self,
        rgba: &[f32],
        (w, h): (usize, usize),
        y: usize,
        row: &mut [std::mem::MaybeUninit<f32>],
        simd: bool,
        skip: Option<&[bool]>,
        mut velocity: impl FnMut(usize) -> [f32; 2],
    ) {
        if let Some(s) = skip {
            assert_eq!(s.len(), w);
        }
        #[cfg(target_arch = "x86_64")]
        if simd && !self.t.is_empty() && rgba.len() == w * h * 4 && crate::simd::simd_enabled() {
            // SAFETY: AVX2 was detected and `rgba` holds the (h, w) image whole.
            unsafe { self.row_avx(rgba, (w, h), y, row, skip, &mut velocity) };
            return;
        }
        for x in 0..w {
            if skip.is_some_and(|s| s[x]) {
                continue;
            }
            put4(row, x, self.blur(rgba, (w, h), (x, y), velocity(x)));
        }
    }

    /// [`Taps::blur_row_skipping`] with AVX2, tap by tap: the row is taken [`CHUNK`] pixels at
    /// a time, the pixels whose taps are all inside two by two ([`tap_pair`]; each with the next
    /// such pixel not skipped), those with clamped taps likewise ([`tap_pair_clamped`]), a
    /// pixel left without a partner or with a zero or NaN velocity alone ([`Taps::blur`]). Each pair's sum runs over the taps in their
    /// order, lane for lane the IEEE operations of [`Taps::blur`] (the same bits), but every pair of the chunk takes its
    /// first tap before any takes its second: neighbouring pixels' taps read neighbouring
    /// texels, so the chunk's reads run along two rows of the image per tap instead of jumping
    /// between `2 * samples` rows per pixel (the blur was waiting on those loads).
    ///
    /// # Safety
    /// AVX2 is present; `rgba` holds `w * h * 4` values; `self.t` is not empty.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn row_avx(
        &self,
        rgba: &[f32],
        (w, h): (usize, usize),
        y: usize,
        row: &mut [std::mem::MaybeUninit<f32>],
        skip: Option<&[bool]>,
        velocity: &mut impl FnMut(usize) -> [f32; 2],
    ) {
        use std::arch::x86_64::*;
        let mut vs = [[0.0f32; 2]; CHUNK];
        let mut origin = [_mm_setzero_ps(); CHUNK / 2];
        let mut vel = [_mm_setzero_ps(); CHUNK / 2];
        let mut pair = [(0usize, 0usize); CHUNK / 2];
        let yf = y as f32;
        let mut x0 = 0;
        while x0 < w {
            let n = (w - x0).min(CHUNK);
            let skipped = skip.map(|s| &s[x0..x0 + n]);
            for (k, v) in vs[..n].iter_mut().enumerate() {
                if !skipped.is_some_and(|s| s[k]) {
                    *v = velocity(x0 + k);
                }
            }
            // 1: every tap inside, 2: a finite velocity with taps to clamp, 0: the pixel as it
            // is or a NaN (`Taps::blur`), 3: skipped
            let kind = |k: usize| {
                let [vx, vy] = vs[k];
                if skipped.is_some_and(|s| s[k]) {
                    3
                } else if (vx == 0.0 && vy == 0.0) || !(vx.is_finite() && vy.is_finite()) {
                    0
                } else if Self::inside((w, h), (x0 + k, y), vs[k]) {
                    1
                } else {
                    2
                }
            };
            // pairs of the same kind (each pixel with the next of its kind, neighbours unless
            // a skipped pixel or one of the other kind lies between), those inside first,
            // those clamped from the end
            let (mut inner, mut outer) = (0, CHUNK / 2);
            let mut pending = [usize::MAX; 3];
            for k in 0..n {
                let a = kind(k);
                if a == 3 {
                    continue;
                }
                if a == 0 {
                    put4(row, x0 + k, self.blur(rgba, (w, h), (x0 + k, y), vs[k]));
                    continue;
                }
                let p = pending[a];
                if p == usize::MAX {
                    pending[a] = k;
                    continue;
                }
                pending[a] = usize::MAX;
                let q = if a == 1 {
                    inner += 1;
                    inner - 1
                } else {
                    outer -= 1;
                    outer
                };
                let (xa, xb) = (x0 + p, x0 + k);
                origin[q] = _mm_setr_ps(xa as f32, xb as f32, yf, yf);
                vel[q] = _mm_setr_ps(vs[p][0], vs[k][0], vs[p][1], vs[k][1]);
                pair[q] = (xa, xb);
            }
            for &p in &pending[1..] {
                if p != usize::MAX {
                    put4(row, x0 + p, self.blur(rgba, (w, h), (x0 + p, y), vs[p]));
                }
            }
            let mut acc = [_mm256_setzero_ps(); CHUNK / 2];
            let (wm, hm) = (w as i32 - 1, h as i32 - 1);
            let edge = _mm_setr_epi32(wm, wm, hm, hm);
            for &t in &self.t {
                for q in 0..inner {
                    // SAFETY: both pixels of the pair are inside (kind 1): their taps' texels
                    // lie in `rgba`
                    acc[q] = _mm256_add_ps(acc[q], tap_pair(rgba, w, origin[q], vel[q], t));
                }
                for q in outer..CHUNK / 2 {
                    // (kind 2: finite velocities, every texel clamped into the image)
                    let tap = tap_pair_clamped(rgba, w, edge, origin[q], vel[q], t);
                    acc[q] = _mm256_add_ps(acc[q], tap);
                }
            }
            let inv = _mm256_set1_ps(self.inv);
            for q in (0..inner).chain(outer..CHUNK / 2) {
                let mut out = [0.0f32; 8];
                _mm256_storeu_ps(out.as_mut_ptr(), _mm256_mul_ps(acc[q], inv));
                put4(row, pair[q].0, [out[0], out[1], out[2], out[3]]);
                put4(row, pair[q].1, [out[4], out[5], out[6], out[7]]);
            }
            x0 += n;
        }
    }

    /// Pixel `(x, y)` of the `(w, h)` image `rgba` blurred along `v` (module docs of
    /// [`velocity_blur`]): the pixel itself for one sample or a zero velocity. Far enough from
    /// the edges that no tap is clamped, the four texels of a tap are read as two pairs.
    #[inline]
    pub fn blur(
        &self,
        rgba: &[f32],
        (w, h): (usize, usize),
        (x, y): (usize, usize),
        v: [f32; 2],
    ) -> [f32; 4] {
        let i = y * w + x;
        let [vx, vy] = v;
        if self.t.is_empty() || (vx == 0.0 && vy == 0.0) {
            return [
                rgba[i * 4],
                rgba[i * 4 + 1],
                rgba[i * 4 + 2],
                rgba[i * 4 + 3],
            ];
        }
        let inside = Self::inside((w, h), (x, y), v);
        let (xf, yf) = (x as f32, y as f32);
        let mut acc = [0.0f32; 4];
        for &t in &self.t {
            let (px, py) = (xf + vx * t, yf + vy * t);
            let (x0, y0) = (floorf(px), floorf(py));
            let (fx, fy) = (px - x0, py - y0);
            let (x0, y0) = (x0 as i64, y0 as i64);
            let (a, b, c, d) = if inside {
                let top = (y0 as usize * w + x0 as usize) * 4;
                let bot = top + w * 4;
                let (ab, cd) = (&rgba[top..top + 8], &rgba[bot..bot + 8]);
                (&ab[..4], &ab[4..], &cd[..4], &cd[4..])
            } else {
                let fetch = |x: i64, y: i64| -> &[f32] {
                    let x = x.clamp(0, w as i64 - 1) as usize;
                    let y = y.clamp(0, h as i64 - 1) as usize;
                    &rgba[(y * w + x) * 4..(y * w + x) * 4 + 4]
                };
                (
                    fetch(x0, y0),
                    fetch(x0 + 1, y0),
                    fetch(x0, y0 + 1),
                    fetch(x0 + 1, y0 + 1),
                )
            };
            for k in 0..4 {
                let top = a[k] + fx * (b[k] - a[k]);
                let bot = c[k] + fx * (d[k] - c[k]);
                acc[k] += top + fy * (bot - top);
            }
        }
        acc.map(|a| a * self.inv)
    }
}

/// Pixels per chunk of [`Taps::row_avx`] (pairs of them in registers' worth of sums).
#[cfg(target_arch = "x86_64")]
const CHUNK: usize = 128;

/// One tap `t` of the pixel pair at `origin` (`(xa, xb, y, y)`) with velocities `vel`
/// (`(vx0, vx1, vy0, vy1)`): the bilinear samples of both pixels side by side (lanes 0-3 and
/// 4-7), [`Taps::blur`]'s operations in its order: the position `x + vx t`, `y + vy t`, its
/// floor (truncation, then one less where that rose), the fractions, the four texels as two
/// pairs of 256-bit loads, and `top = a + fx (b - a)`, `bot = c + fx (d - c)`, `top + fy (bot -
/// top)`.
///
/// # Safety
/// AVX2 is present; the tap's texels of both pixels (at the floored position, one right and
/// one down) lie inside `rgba`, an `(h, w, 4)` image.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn tap_pair(
    rgba: &[f32],
    w: usize,
    origin: std::arch::x86_64::__m128,
    vel: std::arch::x86_64::__m128,
    t: f32,
) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    let p = rgba.as_ptr();
    let below = w * 4;
    let (i, frac) = floor_frac(origin, vel, t);
    let (x0, x1) = (
        _mm_cvtsi128_si32(i) as usize,
        _mm_extract_epi32::<1>(i) as usize,
    );
    let (y0, y1) = (
        _mm_extract_epi32::<2>(i) as usize,
        _mm_extract_epi32::<3>(i) as usize,
    );
    let (t0, t1) = ((y0 * w + x0) * 4, (y1 * w + x1) * 4);
    debug_assert!(t0.max(t1) + below + 8 <= rgba.len());
    let (ab0, ab1) = (_mm256_loadu_ps(p.add(t0)), _mm256_loadu_ps(p.add(t1)));
    let (cd0, cd1) = (
        _mm256_loadu_ps(p.add(t0 + below)),
        _mm256_loadu_ps(p.add(t1 + below)),
    );
    let a = _mm256_permute2f128_ps::<0x20>(ab0, ab1);
    let b = _mm256_permute2f128_ps::<0x31>(ab0, ab1);
    let c = _mm256_permute2f128_ps::<0x20>(cd0, cd1);
    let d = _mm256_permute2f128_ps::<0x31>(cd0, cd1);
    bilerp([a, b, c, d], frac)
}

/// [`tap_pair`] with every texel clamped to the image, as [`Taps::blur`] fetches them near the
/// edges: the floored position's texel and those right of and below it each clamped to `[0, w -
/// 1] x [0, h - 1]` (`edge`: `(w - 1, w - 1, h - 1, h - 1)`), read four floats at a time; the
/// interpolation from the unclamped fractions, in [`tap_pair`]'s order.
///
/// # Safety
/// AVX2 is present; `rgba` is an `(h, w, 4)` image; the velocities are finite and the position
/// within `+-2^31` (every velocity is within `MAX_VELOCITY`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn tap_pair_clamped(
    rgba: &[f32],
    w: usize,
    edge: std::arch::x86_64::__m128i,
    origin: std::arch::x86_64::__m128,
    vel: std::arch::x86_64::__m128,
    t: f32,
) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    let p = rgba.as_ptr();
    let (i, frac) = floor_frac(origin, vel, t);
    let zero = _mm_setzero_si128();
    let lo = _mm_min_epi32(_mm_max_epi32(i, zero), edge);
    let hi = _mm_min_epi32(
        _mm_max_epi32(_mm_add_epi32(i, _mm_set1_epi32(1)), zero),
        edge,
    );
    let (lo, hi) = (
        std::mem::transmute::<__m128i, [i32; 4]>(lo),
        std::mem::transmute::<__m128i, [i32; 4]>(hi),
    );
    // texel (x, y) of pixel k (0 or 1): lanes k of x and 2 + k of y
    let texel = |x: i32, y: i32| _mm_loadu_ps(p.add((y as usize * w + x as usize) * 4));
    let a = _mm256_set_m128(texel(lo[1], lo[3]), texel(lo[0], lo[2]));
    let b = _mm256_set_m128(texel(hi[1], lo[3]), texel(hi[0], lo[2]));
    let c = _mm256_set_m128(texel(lo[1], hi[3]), texel(lo[0], hi[2]));
    let d = _mm256_set_m128(texel(hi[1], hi[3]), texel(hi[0], hi[2]));
    bilerp([a, b, c, d], frac)
}

/// The tap's position `origin + vel t` of a pixel pair, floored (truncation, then one less
/// where that rose) as integers, and its fractions: [`Taps::blur`]'s operations in its order.
///
/// # Safety
/// AVX2 is present.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn floor_frac(
    origin: std::arch::x86_64::__m128,
    vel: std::arch::x86_64::__m128,
    t: f32,
) -> (std::arch::x86_64::__m128i, std::arch::x86_64::__m128) {
    use std::arch::x86_64::*;
    let pos = _mm_add_ps(origin, _mm_mul_ps(vel, _mm_set1_ps(t)));
    let trunc = _mm_cvtepi32_ps(_mm_cvttps_epi32(pos));
    let fl = _mm_sub_ps(
        trunc,
        _mm_and_ps(_mm_cmpgt_ps(trunc, pos), _mm_set1_ps(1.0)),
    );
    (_mm_cvttps_epi32(fl), _mm_sub_ps(pos, fl))
}

/// The bilinear samples of a pixel pair from its four texels `[a, b, c, d]` (each pixel's in
/// lanes 0-3 and 4-7: at the floored position, right of it, below it, below right) and its
/// fractions `frac` (`(fx0, fx1, fy0, fy1)`): `top = a + fx (b - a)`, `bot = c + fx (d - c)`,
/// `top + fy (bot - top)`, [`Taps::blur`]'s order.
///
/// # Safety
/// AVX2 is present.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn bilerp(
    [a, b, c, d]: [std::arch::x86_64::__m256; 4],
    frac: std::arch::x86_64::__m128,
) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    let fx = _mm256_set_m128(
        _mm_shuffle_ps::<0x55>(frac, frac),
        _mm_shuffle_ps::<0x00>(frac, frac),
    );
    let fy = _mm256_set_m128(
        _mm_shuffle_ps::<0xff>(frac, frac),
        _mm_shuffle_ps::<0xaa>(frac, frac),
    );
    let top = _mm256_add_ps(a, _mm256_mul_ps(fx, _mm256_sub_ps(b, a)));
    let bot = _mm256_add_ps(c, _mm256_mul_ps(fx, _mm256_sub_ps(d, c)));
    _mm256_add_ps(top, _mm256_mul_ps(fy, _mm256_sub_ps(bot, top)))
}

/// What [`camera_frame_blur`] reads of a rendered frame besides its colour and depth: the
/// velocity buffer `(h, w, 2)` of its moving objects (pixels over the shutter so far), the
/// object id of each pixel `(h, w)` (-1 for none) and which ids are moving objects.
#[derive(Clone, Copy, Debug)]
pub struct FrameMotion<'a> {
    /// The rasterizer's velocity buffer, `(h, w, 2)`.
    pub velocity: &'a [f32],
    /// Object id per pixel, `(h, w)`.
    pub ids: &'a [i32],
    /// `moving[id]`: whether object `id` moves (ids past the end do not).
    pub moving: &'a [bool],
}

/// Taps of the blur where [`camera_frame_blur`]'s line integral does not fit.
pub const LINE_FALLBACK_SAMPLES: usize = 16;

/// The blur of the `camera_velocity` method in one pass: each pixel's velocity is its moving
/// object's from the velocity buffer, else the camera's ([`camera_velocity`] from `depth`),
/// times `scale` (float32), clamped to `+-MAX_VELOCITY`, and the pixel is blurred along it as
/// [`velocity_blur`] does with `samples` taps (`Some(n)`), or, with `None`, as the line
/// integral along its streak where it fits (the `camera_line` module: the camera's pixels,
/// their velocities from the same matrices in fewer operations) and with 16 taps
/// (`LINE_FALLBACK_SAMPLES`) elsewhere; no velocity image is made. Returns the image and
/// the number of pixels blurred as a line integral. Errors name `rgba` (not finite), `depth`
/// (NaN or <= 0), `samples` (out of `[1, MAX_SAMPLES]`) or `velocity` (NaN after the scaling).
pub fn camera_frame_blur(
    rgba: &[f32],
    depth: &[f32],
    (w, h): (usize, usize),
    frame: FrameMotion<'_>,
    cameras: (&CameraMatrices, &CameraMatrices),
    (scale, samples): (f32, Option<usize>),
) -> Result<(Vec<f32>, usize)> {
    check_image("rgba", rgba, w, h, 4)?;
    check_image("depth", depth, w, h, 1)?;
    check_image("velocity", frame.velocity, w, h, 2)?;
    if frame.ids.len() != w * h {
        return Err(Error::shape("ids", format!("expected ({h},{w}) values")));
    }
    if let Some(samples) = samples {
        if samples == 0 || samples > MAX_SAMPLES {
            return Err(Error::value(
                "samples",
                format!("must be in [1, {MAX_SAMPLES}], got {samples}"),
            ));
        }
    }
    super::check_finite("rgba", rgba)?;
    if depth.par_iter().any(|d| d.is_nan() || *d <= 0.0) {
        return Err(Error::value(
            "depth",
            "contains NaN or values <= 0 (use +inf for background)",
        ));
    }
    let field = CameraField {
        motion: PixelMotion::new(cameras.0, cameras.1, w, h),
        depth,
        frame,
        scale,
        w,
        h,
        taps: Taps::new(samples.unwrap_or(LINE_FALLBACK_SAMPLES)),
    };
    let (out, bad, lines) = match samples {
        Some(_) => {
            let (out, bad) = taps_frame_blur(rgba, (w, h), &field);
            (out, bad, 0)
        }
        None => {
            let (out, stats) = super::camera_line::line_blur(rgba, (w, h), &field);
            (out, stats.nan, stats.line_pixels)
        }
    };
    if bad {
        return Err(Error::value(
            "velocity",
            "is NaN (a camera or depth too extreme)",
        ));
    }
    Ok((out, lines))
}

/// The velocities [`camera_frame_blur`] blurs along.
struct CameraField<'a> {
    motion: PixelMotion,
    depth: &'a [f32],
    frame: FrameMotion<'a>,
    scale: f32,
    w: usize,
    h: usize,
    /// The taps where the line integral does not fit.
    taps: Taps,
}

impl CameraField<'_> {
    /// The velocity the taps blur pixel `(x, y)` along (the bits the method always had).
    #[inline(always)]
    fn tap_velocity(&self, x: usize, y: usize) -> [f32; 2] {
        let i = y * self.w + x;
        let v = if self.moves(i) {
            [self.frame.velocity[2 * i], self.frame.velocity[2 * i + 1]]
        } else {
            self.motion.at(x, y, self.depth[i], 1.0)
        };
        v.map(|c| (c * self.scale).clamp(-MAX_VELOCITY, MAX_VELOCITY))
    }

    /// [`LineField::row`](super::camera_line::LineField::row) compiled for AVX2.
    ///
    /// # Safety
    /// AVX2 is present.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn row_avx(&self, y: usize, v: &mut [[f32; 2]], line: &mut [u8]) {
        self.row_plain(y, v, line);
    }

    /// [`LineField::row`](super::camera_line::LineField::row): the camera's velocity from
    /// [`PixelMotion::row_affine`] times the scale, clamped, at every pixel (not read at a
    /// moving object's).
    #[inline(always)]
    fn row_plain(&self, y: usize, v: &mut [[f32; 2]], line: &mut [u8]) {
        let i = y * self.w;
        for (x, line) in line.iter_mut().enumerate() {
            *line = u8::from(!self.moves(i + x));
        }
        self.motion.row_affine(y, &self.depth[i..i + self.w], v);
        let scale = self.scale;
        for v in v.iter_mut() {
            *v = v.map(|c| (c * scale).clamp(-MAX_VELOCITY, MAX_VELOCITY));
        }
    }

    #[inline(always)]
    fn moves(&self, i: usize) -> bool {
        let id = self.frame.ids[i];
        id >= 0 && self.frame.moving.get(id as usize).copied().unwrap_or(false)
    }
}

impl super::camera_line::LineField for CameraField<'_> {
    #[inline]
    fn row(&self, y: usize, v: &mut [[f32; 2]], line: &mut [u8]) {
        #[cfg(target_arch = "x86_64")]
        if super::simd() {
            // SAFETY: AVX2 was detected
            unsafe { self.row_avx(y, v, line) };
            return;
        }
        self.row_plain(y, v, line);
    }

    #[inline]
    fn taps_row(
        &self,
        rgba: &[f32],
        y: usize,
        row: &mut [std::mem::MaybeUninit<f32>],
        skip: &[bool],
    ) -> bool {
        let mut nan = false;
        let (dims, simd) = ((self.w, self.h), super::simd());
        self.taps
            .blur_row_skipping(rgba, dims, y, row, simd, Some(skip), |x| {
                let v = self.tap_velocity(x, y);
                nan |= v[0].is_nan() || v[1].is_nan();
                v
            });
        nan
    }
}

/// [`camera_frame_blur`] with the field's taps at every pixel: the image and whether a velocity
/// was NaN.
fn taps_frame_blur(
    rgba: &[f32],
    (w, h): (usize, usize),
    field: &CameraField<'_>,
) -> (Vec<f32>, bool) {
    let taps = &field.taps;
    let simd = super::simd();
    let mut bad = false;
    let out = filled(w * h * 4, |out| {
        bad = out
            .par_chunks_mut(w * 4)
            .enumerate()
            .map(|(y, row)| {
                let mut bad = false;
                taps.blur_row(rgba, (w, h), y, row, simd, |x| {
                    let v = field.tap_velocity(x, y);
                    bad |= v[0].is_nan() || v[1].is_nan();
                    v
                });
                bad
            })
            .reduce(|| false, |a, b| a | b);
    });
    (out, bad)
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The blur with every texel fetched through the edge clamp (no inside shortcut), serial.
    fn clamped(rgba: &[f32], velocity: &[f32], w: usize, h: usize, samples: usize) -> Vec<f32> {
        let mut out = rgba.to_vec();
        let fetch = |x: i64, y: i64| {
            let (x, y) = (
                x.clamp(0, w as i64 - 1) as usize,
                y.clamp(0, h as i64 - 1) as usize,
            );
            &rgba[(y * w + x) * 4..(y * w + x) * 4 + 4]
        };
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let (vx, vy) = (velocity[2 * i], velocity[2 * i + 1]);
                if samples == 1 || (vx == 0.0 && vy == 0.0) {
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
                    out[i * 4 + k] = acc[k] * (1.0 / samples as f32);
                }
            }
        }
        out
    }

    #[test]
    fn taps_inside_the_image_read_what_the_clamped_taps_read() {
        // velocities from sub-pixel to longer than the image, pixels at and near every edge;
        // rows of one chunk of the vector form and of several
        for (w, h) in [(53, 31), (301, 23)] {
            check_against_clamped(w, h);
        }
    }

    fn check_against_clamped(w: usize, h: usize) {
        let rgba: Vec<f32> = (0..w * h * 4)
            .map(|i| ((i * 37) % 101) as f32 / 101.0)
            .collect();
        let velocity: Vec<f32> = (0..w * h * 2)
            .map(|i| (((i * 7919) % 211) as f32 - 105.0) * [0.01, 0.1, 0.5, 1.0][i % 4])
            .collect();
        for samples in [1, 2, 5, 16] {
            let ours = velocity_blur(&rgba, &velocity, w, h, samples).unwrap();
            let want = clamped(&rgba, &velocity, w, h, samples);
            assert!(
                ours.iter()
                    .zip(&want)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "samples {samples}"
            );
        }
    }

    /// A camera 4 units from the origin looking down -z, and the previous one moved `dx` along
    /// x: a pan over a plane in front of it.
    fn panning_cameras((w, h): (usize, usize), dx: f64) -> (CameraMatrices, CameraMatrices) {
        let eye = |x: f64| {
            let mut v = glam::DMat4::IDENTITY;
            v.w_axis.x = x;
            v.w_axis.z = -4.0;
            v
        };
        let proj = glam::DMat4::perspective_rh_gl(0.8, w as f64 / h as f64, 0.1, 50.0);
        let cur = CameraMatrices::new(eye(0.0), proj, "camera").unwrap();
        (
            cur,
            CameraMatrices::new(eye(dx), proj, "previous_camera").unwrap(),
        )
    }

    #[test]
    fn camera_frame_blur_same_on_one_thread() {
        // (rows of several chunks of the vector form)
        let (w, h) = (300, 30);
        let rgba: Vec<f32> = (0..w * h * 4).map(|i| (i % 7) as f32 / 7.0).collect();
        let depth: Vec<f32> = (0..w * h).map(|i| 1.0 + (i % 5) as f32).collect();
        let velocity: Vec<f32> = (0..w * h * 2).map(|i| (i % 9) as f32 - 4.0).collect();
        let ids: Vec<i32> = (0..w * h).map(|i| (i % 3) as i32 - 1).collect();
        let (cur, prev) = panning_cameras((w, h), 0.2);
        let frame = FrameMotion {
            velocity: &velocity,
            ids: &ids,
            moving: &[true, false],
        };
        for samples in [Some(16), None] {
            let run =
                || camera_frame_blur(&rgba, &depth, (w, h), frame, (&cur, &prev), (2.0, samples));
            let a = run().unwrap();
            let b = crate::on_threads(1, run).unwrap();
            assert_eq!(a, b);
            assert_ne!(a.0, rgba);
        }
    }

    #[test]
    fn camera_frame_line_blur_keeps_the_taps_bits_where_it_takes_them() {
        // a camera panning over a plane (every camera pixel may be a line) and a moving
        // object's block (its pixels take the taps along the velocity buffer's velocity)
        let (w, h) = (320, 96);
        let rgba: Vec<f32> = (0..w * h * 4)
            .map(|i| ((i / 4) % w) as f32 * 0.01 + ((i / 4) / w) as f32 * 0.02 + (i % 4) as f32)
            .collect();
        let depth = vec![5.0f32; w * h];
        let velocity: Vec<f32> = (0..w * h * 2).map(|i| (i % 2) as f32 * 6.0 - 3.0).collect();
        let ids: Vec<i32> = (0..w * h)
            .map(|i| i32::from((40..60).contains(&(i / w)) && (100..150).contains(&(i % w))) - 1)
            .map(|id| if id == 0 { 0 } else { -1 })
            .collect();
        let (cur, prev) = panning_cameras((w, h), 1.5);
        let frame = FrameMotion {
            velocity: &velocity,
            ids: &ids,
            moving: &[true],
        };
        let run = |samples| {
            camera_frame_blur(&rgba, &depth, (w, h), frame, (&cur, &prev), (1.0, samples)).unwrap()
        };
        let ((taps, _), (line, lines)) = (run(Some(16)), run(None));
        let same =
            |i: usize| (0..4).all(|c| taps[i * 4 + c].to_bits() == line[i * 4 + c].to_bits());
        // the moving block's pixels are the taps'; every pixel not a line too (at most
        // `lines` pixels differ)
        assert!((0..w * h).filter(|&i| ids[i] == 0).all(same));
        let differ = (0..w * h).filter(|&i| !same(i)).count();
        assert!(lines > w * h / 2 && differ <= lines, "{lines} {differ}");
    }
}
