//! Depth of field by sub-images (Kraus section 3.1, eqs. 1-6).
//!
//! Sub-image `i` (from `-(layers/2)` to `layers - 1 - layers/2`, negative in front of the focal
//! plane) has the blur radius `r_i = sqrt(2 * 4^|i| - 1)` pixels (`r_0 = 0`) and the depth
//! `z_i` of the thin lens (eqs. 2-4) with `r_inf = h / (2 z_focal tan(yfov / 2)) * f / (2 N)`
//! (eq. 5). Behind the focal plane `z_i = z_focal / (1 - r_i / r_inf)` is negative or infinite
//! when `r_i >= r_inf`: such a depth is taken as +inf, and sub-images that start beyond infinity
//! are dropped. The matting function of sub-image `i` ramps up from `z_{i-2}` to `z_{i-1}`, is 1
//! on `[z_{i-1}, z_i]` and ramps down to 0 at `z_{i+1}` (figure 2); the foremost sub-image is 1
//! in front of `z_{i-1}` and the backmost is 1 behind `z_i`. Each sub-image is the pinhole colour
//! with opacity 1 times its weight, blurred by the opaque pyramid blur with `|i|` levels and
//! blended over the buffer from far to near (eq. 6).
//!
//! The radius departs from Kraus's eq. 1 (`1.7 * 2^(|i| - 1)`): `r_inf` (eq. 5) is the radius of
//! the circle of confusion, a disc, while the `L`-level pyramid blur of sub-image `i` has the
//! per-axis variance `4^L / 2 - 1/4` (about its centre, for a source pixel at an even position),
//! that of a disc of radius `2 sigma = sqrt(2 * 4^L - 1)` (2.65, 5.57, 11.3, 22.6 pixels), 1.6x
//! eq. 1's: with eq. 1 every sub-image was blurred as a circle of confusion 1.6x too wide, and
//! the result was farther from Mitsuba's `thinlens` than the pinhole image (issue #24). Eq. 1's
//! values are about the pyramid kernel's Gaussian sigma (1.45, 3.25, 6.65, 13.6 fit best).
use rayon::prelude::*;

use super::pyramid::opaque_unchecked;
use super::{check_image, MAX_LEVELS};
use crate::error::{Error, Result};

/// Camera and lens of the depth of field. Depths and focal length in scene units, `yfov` in
/// radians.
#[derive(Clone, Copy, Debug)]
pub struct DofParams {
    /// Distance of the focal plane along the view axis.
    pub focal_depth: f64,
    /// Focal length of the lens.
    pub focal_length: f64,
    /// Aperture as an f-number (focal length over aperture diameter).
    pub f_number: f64,
    /// Vertical field of view.
    pub yfov: f64,
    /// Number of sub-images (see the module docs).
    pub layers: usize,
}

/// Most sub-images accepted (the farthest would need 8 pyramid levels).
pub const MAX_LAYERS: usize = 2 * (MAX_LEVELS / 2) + 1;

fn check(p: &DofParams) -> Result<()> {
    let pos = |v: f64, name: &'static str| -> Result<()> {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::value(
                name,
                format!("must be finite and > 0, got {v}"),
            ));
        }
        Ok(())
    };
    pos(p.focal_depth, "focal_depth")?;
    pos(p.focal_length, "focal_length")?;
    pos(p.f_number, "f_number")?;
    if !(p.yfov > 0.0 && p.yfov < std::f64::consts::PI) {
        return Err(Error::value(
            "yfov",
            format!("must be in (0, pi), got {}", p.yfov),
        ));
    }
    if p.layers == 0 || p.layers > MAX_LAYERS {
        return Err(Error::value(
            "layers",
            format!("must be in [1, {MAX_LAYERS}], got {}", p.layers),
        ));
    }
    Ok(())
}

/// Radius in pixels of the disc with the second moment of the `levels`-level pyramid blur
/// (module docs): `sqrt(2 * 4^levels - 1)`, 0 for no level.
pub fn pyramid_disc_radius(levels: usize) -> f64 {
    if levels == 0 {
        return 0.0;
    }
    (2.0 * 4f64.powi(levels as i32) - 1.0).sqrt()
}

/// `r_inf` of eq. 5 for an image `h` pixels high.
pub fn r_infinity(p: &DofParams, h: usize) -> f64 {
    h as f64 / (2.0 * p.focal_depth * (p.yfov / 2.0).tan()) * p.focal_length / (2.0 * p.f_number)
}

/// Depth `z_i` of sub-image `i` (eqs. 1-4), +inf where eq. 4 is negative or infinite.
fn depth_of(p: &DofParams, r_inf: f64, i: i64) -> f64 {
    if i == 0 {
        return p.focal_depth;
    }
    let r = pyramid_disc_radius(i.unsigned_abs() as usize);
    if i < 0 {
        p.focal_depth / (1.0 + r / r_inf)
    } else if r < r_inf {
        p.focal_depth / (1.0 - r / r_inf)
    } else {
        f64::INFINITY
    }
}

/// The sub-images actually used, as `(i, z_{i-2}, z_{i-1}, z_i, z_{i+1})`, far to near
/// order reversed (front first).
pub fn layer_depths(p: &DofParams, h: usize) -> Result<Vec<(i64, [f64; 4])>> {
    check(p)?;
    let r_inf = r_infinity(p, h);
    let lo = -((p.layers / 2) as i64);
    let hi = lo + p.layers as i64 - 1;
    Ok((lo..=hi)
        .map(|i| {
            (
                i,
                [
                    depth_of(p, r_inf, i - 2),
                    depth_of(p, r_inf, i - 1),
                    depth_of(p, r_inf, i),
                    depth_of(p, r_inf, i + 1),
                ],
            )
        })
        .filter(|(i, z)| *i == lo || z[1].is_finite())
        .collect())
}

/// The matting weight of a pixel at depth `d` (figure 2).
fn weight(d: f64, z: &[f64; 4], front: bool, back: bool) -> f32 {
    let [za, zb, zc, zd] = *z;
    if d < zb {
        if front {
            return 1.0;
        }
        if d <= za {
            return 0.0;
        }
        return ((d - za) / (zb - za)) as f32;
    }
    if d <= zc || back {
        return 1.0;
    }
    if d >= zd {
        return 0.0;
    }
    if zd.is_infinite() {
        return 1.0;
    }
    ((zd - d) / (zd - zc)) as f32
}

/// Depth of field of a `(h, w, 4)` premultiplied pinhole image with view-axis `depth` `(h, w)`
/// (finite > 0 or +inf). Returns the `(h, w, 4)` premultiplied result.
pub fn depth_of_field(
    rgba: &[f32],
    depth: &[f32],
    w: usize,
    h: usize,
    p: &DofParams,
) -> Result<Vec<f32>> {
    check_image("rgba", rgba, w, h, 4)?;
    check_image("depth", depth, w, h, 1)?;
    let layers = layer_depths(p, h)?;
    if rgba.par_iter().any(|v| !v.is_finite()) {
        return Err(Error::value("rgba", "contains NaN or inf"));
    }
    if depth.par_iter().any(|d| d.is_nan() || *d <= 0.0) {
        return Err(Error::value(
            "depth",
            "contains NaN or values <= 0 (use +inf for background)",
        ));
    }
    let mut buf = vec![0.0f32; w * h * 4];
    let n = layers.len();
    for (k, (i, z)) in layers.iter().enumerate().rev() {
        let (front, back) = (k == 0, k == n - 1);
        let mut sub = vec![0.0f32; w * h * 4];
        sub.par_chunks_mut(4)
            .zip(rgba.par_chunks(4))
            .zip(depth.par_iter())
            .for_each(|((o, c), &d)| {
                let wt = weight(d as f64, z, front, back);
                o[0] = wt * c[0];
                o[1] = wt * c[1];
                o[2] = wt * c[2];
                o[3] = wt;
            });
        let levels = i.unsigned_abs() as usize;
        let sub = if levels > 0 {
            opaque_unchecked(&sub, w, h, levels)
        } else {
            sub
        };
        buf.par_chunks_mut(4)
            .zip(sub.par_chunks(4))
            .for_each(|(b, s)| {
                let k = 1.0 - s[3];
                for c in 0..4 {
                    b[c] = s[c] + k * b[c];
                }
            });
    }
    Ok(buf)
}
