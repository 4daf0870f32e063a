//! Thin-lens depth of field from a pinhole image and its depth (issue #24).
//!
//! A thin lens of radius `A` (Mitsuba's `thinlens` `aperture_radius`) focused on the plane at
//! distance `F` along the view axis images a point at view-axis depth `z` as a disc: the rays from
//! the lens disc through the point cross the focal plane within `A |1 - F / z|` of the pinhole
//! ray, and the focal plane spans `2 F tan(yfov / 2)` over the image's `h` pixels, so the circle of
//! confusion has the signed radius `s = r_inf (1 - F / z)` pixels (negative in front of the
//! focus) with `r_inf = h A / (2 F tan(yfov / 2))` (Kraus's eq. 5 with `f / (2N) = A`).
//!
//! Kernels `K_j`: `K_0` the identity, `K_1` the 3x3 binomial (`[1, 2, 1] / 4` on each axis),
//! `K_j` for `j >= 2` the `(j - 1)`-level pyramid blur (`pyramid`). Each has the second moment
//! of a disc of radius `r_j` = 0, `sqrt(2)`, then `sqrt(2 * 4^L - 1)` for `L` levels
//! (`dof::pyramid_disc_radius`: 2.65, 5.57, 11.3 ... pixels). A pixel with `r_j <= |s| <
//! r_{j+1}` belongs to sub-image `(side, j)` and is blurred by the mixture `(1 - t) K_j + t
//! K_{j+1}` with `t = (s^2 - r_j^2) / (r_{j+1}^2 - r_j^2)`, the mixture with the disc's variance
//! `s^2 / 4`; the last `j` takes every larger `|s|` with `K_j` alone. Kernels go up to the first
//! `r_j` at or beyond the largest `|s|` (at most [`MAX_LENS_LEVELS`] pyramid levels).
//!
//! Sub-images are processed from the farthest (largest positive `s`) to the nearest and blended
//! with "over" (Kraus's eq. 6), but with the ordinary (not opaque) blur, so a blurred silhouette
//! turns partially transparent as the thin lens's does. What it uncovers is filled as Kraus and
//! Strengert (2007) fill disoccluded pixels: before the blur, sub-image `j` is extended under the
//! pixels of nearer sub-images by its push-pull interpolation over `j + 2` levels. Each blur is
//! divided by the blur of an all-ones image, so the image border does not fade to transparent,
//! a sub-image whose alpha exceeds 1 (mixtures of different `t`) is scaled back to 1, and a last
//! push-pull fill under the result, up to the pinhole's alpha (the fill's colour with that
//! alpha), closes what the mixtures leave uncovered. An image all at the focus comes back
//! unchanged, a uniform opaque one stays uniform at any depths.
use rayon::prelude::*;

use super::dof::pyramid_disc_radius;
use super::pyramid::{blur_unchecked, levels_to_one, push_pull_unchecked};
use super::{check_image, check_premultiplied, ALPHA_EPS};
use crate::error::{Error, Result};

/// The thin lens, in scene units, and the vertical field of view in radians.
#[derive(Clone, Copy, Debug)]
pub struct LensParams {
    /// Radius of the lens (Mitsuba's `aperture_radius`).
    pub aperture: f64,
    /// Distance of the focal plane along the view axis.
    pub focus_distance: f64,
    /// Vertical field of view.
    pub yfov: f64,
}

/// Most pyramid levels of the thin-lens blur (a circle of confusion of radius 362 pixels).
pub const MAX_LENS_LEVELS: usize = 8;

fn check(p: &LensParams) -> Result<()> {
    for (v, name) in [
        (p.aperture, "aperture"),
        (p.focus_distance, "focus_distance"),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::value(
                name,
                format!("must be finite and > 0, got {v}"),
            ));
        }
    }
    if !(p.yfov > 0.0 && p.yfov < std::f64::consts::PI) {
        return Err(Error::value(
            "yfov",
            format!("must be in (0, pi), got {}", p.yfov),
        ));
    }
    Ok(())
}

/// `r_inf`, the circle of confusion's radius in pixels of a point at infinity (module docs).
pub fn lens_r_infinity(p: &LensParams, h: usize) -> f64 {
    h as f64 * p.aperture / (2.0 * p.focus_distance * (p.yfov / 2.0).tan())
}

/// Radius in pixels of the disc with the second moment of kernel `K_j` (module docs).
pub fn lens_kernel_radius(j: usize) -> f64 {
    match j {
        0 => 0.0,
        1 => std::f64::consts::SQRT_2,
        _ => pyramid_disc_radius(j - 1),
    }
}

/// The 3x3 binomial blur of a `(h, w, c)` image (zero outside).
fn binomial(img: &[f32], w: usize, h: usize, c: usize) -> Vec<f32> {
    let mut rows = vec![0.0f32; img.len()];
    rows.par_chunks_mut(w * c)
        .zip(img.par_chunks(w * c))
        .for_each(|(o, r)| {
            for x in 0..w {
                for k in 0..c {
                    let left = if x > 0 { r[(x - 1) * c + k] } else { 0.0 };
                    let right = if x + 1 < w { r[(x + 1) * c + k] } else { 0.0 };
                    o[x * c + k] = 0.25 * left + 0.5 * r[x * c + k] + 0.25 * right;
                }
            }
        });
    let mut out = vec![0.0f32; img.len()];
    out.par_chunks_mut(w * c).enumerate().for_each(|(y, o)| {
        let mid = &rows[y * w * c..(y + 1) * w * c];
        for (i, v) in o.iter_mut().enumerate() {
            *v = 0.5 * mid[i];
        }
        for ny in [y.wrapping_sub(1), y + 1] {
            if ny < h {
                let r = &rows[ny * w * c..(ny + 1) * w * c];
                for (v, n) in o.iter_mut().zip(r) {
                    *v += 0.25 * n;
                }
            }
        }
    });
    out
}

/// Kernel `K_j` on a `(h, w, c)` image (zero outside).
fn kernel(img: &[f32], w: usize, h: usize, c: usize, j: usize) -> Vec<f32> {
    match j {
        0 => img.to_vec(),
        1 => binomial(img, w, h, c),
        _ => blur_unchecked(img, w, h, c, j - 1),
    }
}

/// `K_j` of a `(h, w, 4)` image divided by `K_j` of an all-ones image (`ones`).
fn normalized_blur(img: &[f32], w: usize, h: usize, j: usize, ones: &[f32]) -> Vec<f32> {
    if j == 0 {
        return img.to_vec();
    }
    let mut out = kernel(img, w, h, 4, j);
    out.par_chunks_mut(4)
        .zip(ones.par_iter())
        .for_each(|(o, &n)| {
            let s = if n > 0.0 { 1.0 / n } else { 0.0 };
            for v in o.iter_mut() {
                *v *= s;
            }
        });
    out
}

/// Which sub-image every pixel of a lens blur goes to: `pos`, in blending order (back layers
/// k = top..0 at 0..=top, front layers k = 0..top at top+1..=2top+1), and its weight `t` of
/// kernel `K_{k+1}` (the rest of `K_k`).
struct SubImages {
    /// The largest kernel level the circles of confusion need.
    top: usize,
    pos: Vec<u16>,
    t: Vec<f32>,
}

impl SubImages {
    /// The sub-images of the pixels at view-axis `depth` of an image `h` rows high.
    fn new(depth: &[f32], p: &LensParams, h: usize) -> Self {
        let r_inf = lens_r_infinity(p, h);
        let f = p.focus_distance;
        let coc = |d: f32| -> f64 {
            if d.is_infinite() {
                r_inf
            } else {
                r_inf * (1.0 - f / d as f64)
            }
        };
        let s_max = depth
            .par_iter()
            .map(|&d| coc(d).abs())
            .reduce(|| 0.0, f64::max);
        let mut top = 0;
        while top < MAX_LENS_LEVELS + 1 && lens_kernel_radius(top) < s_max {
            top += 1;
        }
        let radii: Vec<f64> = (0..=top).map(lens_kernel_radius).collect();
        let (pos, t): (Vec<u16>, Vec<f32>) = depth
            .par_iter()
            .map(|&d| {
                let s = coc(d);
                let a = s.abs();
                let k = radii.iter().rposition(|&r| r <= a).unwrap_or(0);
                let t = if k < top {
                    let (lo, hi) = (radii[k] * radii[k], radii[k + 1] * radii[k + 1]);
                    ((a * a - lo) / (hi - lo)).clamp(0.0, 1.0) as f32
                } else {
                    0.0
                };
                let pos = if s >= 0.0 { top - k } else { top + 1 + k };
                (pos as u16, t)
            })
            .unzip();
        SubImages { top, pos, t }
    }

    /// Sub-image `q` of the `(h, w, 4)` image `rgba`, blurred: its pixels (those not moved to
    /// `K_{k+1}`) blurred by `K_k` over the pixels behind it pushed and pulled in, plus the
    /// moved part blurred by `K_{k+1}`; `ones[j]` is `K_j` of an all-ones image.
    fn blurred(&self, rgba: &[f32], w: usize, h: usize, q: usize, ones: &[Vec<f32>]) -> Vec<f32> {
        let (top, pos, t) = (self.top, &self.pos, &self.t);
        let k = if q <= top { top - q } else { q - top - 1 };
        let q = q as u16;
        let layer: Vec<f32> = rgba
            .par_chunks(4)
            .zip(pos.par_iter())
            .flat_map_iter(|(c, &pq)| {
                let on = if pq == q { 1.0 } else { 0.0 };
                [c[0] * on, c[1] * on, c[2] * on, c[3] * on]
            })
            .collect();
        let ext = push_pull_unchecked(&layer, w, h, k + 2);
        drop(layer);
        let mixed = k < top
            && pos
                .par_iter()
                .zip(t.par_iter())
                .any(|(&pq, &tt)| pq == q && tt > 0.0);
        let mut pa = vec![0.0f32; w * h * 4];
        let mut pb = if mixed {
            vec![0.0f32; w * h * 4]
        } else {
            Vec::new()
        };
        pa.par_chunks_mut(4)
            .zip(rgba.par_chunks(4))
            .zip(ext.par_chunks(4))
            .zip(pos.par_iter().zip(t.par_iter()))
            .for_each(|(((o, c), e), (&pq, &tt))| {
                if pq == q {
                    for i in 0..4 {
                        o[i] = c[i] * (1.0 - tt);
                    }
                } else if pq > q {
                    for i in 0..4 {
                        o[i] = e[i] * c[3];
                    }
                }
            });
        drop(ext);
        if mixed {
            pb.par_chunks_mut(4)
                .zip(rgba.par_chunks(4))
                .zip(pos.par_iter().zip(t.par_iter()))
                .for_each(|((o, c), (&pq, &tt))| {
                    if pq == q {
                        for i in 0..4 {
                            o[i] = c[i] * tt;
                        }
                    }
                });
        }
        let mut sub = normalized_blur(&pa, w, h, k, &ones[k]);
        drop(pa);
        if mixed {
            let b = normalized_blur(&pb, w, h, k + 1, &ones[k + 1]);
            sub.par_iter_mut()
                .zip(b.par_iter())
                .for_each(|(s, b)| *s += b);
        }
        sub
    }
}

/// Thin-lens depth of field of a `(h, w, 4)` premultiplied pinhole image with view-axis `depth`
/// `(h, w)` (finite > 0 or +inf). Returns the `(h, w, 4)` premultiplied result.
pub fn lens_blur(
    rgba: &[f32],
    depth: &[f32],
    w: usize,
    h: usize,
    p: &LensParams,
) -> Result<Vec<f32>> {
    check_image("rgba", rgba, w, h, 4)?;
    check_image("depth", depth, w, h, 1)?;
    check(p)?;
    check_premultiplied("rgba", rgba, 4)?;
    if depth.par_iter().any(|d| d.is_nan() || *d <= 0.0) {
        return Err(Error::value(
            "depth",
            "contains NaN or values <= 0 (use +inf for background)",
        ));
    }
    let subs = SubImages::new(depth, p, h);
    let top = subs.top;
    let mut used = vec![false; 2 * top + 2];
    for &q in &subs.pos {
        used[q as usize] = true;
    }
    let ones_img = vec![1.0f32; w * h];
    let ones: Vec<Vec<f32>> = (0..=top)
        .map(|j| {
            if j == 0 {
                Vec::new()
            } else {
                kernel(&ones_img, w, h, 1, j)
            }
        })
        .collect();
    drop(ones_img);
    // The sub-images composited back to front.
    let mut buf = vec![0.0f32; w * h * 4];
    for (q, _) in used.iter().enumerate().filter(|(_, u)| **u) {
        let sub = subs.blurred(rgba, w, h, q, &ones);
        buf.par_chunks_mut(4)
            .zip(sub.par_chunks(4))
            .for_each(|(o, s)| {
                let sc = if s[3] > 1.0 { 1.0 / s[3] } else { 1.0 };
                let k = 1.0 - s[3] * sc;
                for i in 0..4 {
                    o[i] = s[i] * sc + k * o[i];
                }
            });
    }
    let fill = push_pull_unchecked(&buf, w, h, levels_to_one(w, h));
    buf.par_chunks_mut(4)
        .zip(fill.par_chunks(4))
        .zip(rgba.par_chunks(4))
        .for_each(|((o, f), c)| {
            // the fill's colour under the pixel, up to the pinhole's alpha
            let deficit = c[3] - o[3];
            if deficit > 0.0 && f[3] > ALPHA_EPS {
                let k = deficit / f[3];
                for i in 0..4 {
                    o[i] += k * f[i];
                }
            }
            o[3] = o[3].min(1.0);
        });
    Ok(buf)
}
