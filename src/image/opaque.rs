//! Opaque image blur (Kraus section 3.2, eq. 7) and image-based opaque motion blur (section 4.1):
//! a box blur of the premultiplied colours, the triangle-max glow of the alpha (eq. 10) with the
//! same radius, and the rescale `RGBA_sub = RGBA_blur * A_glow / A_blur`, optionally composited
//! over a base image (figure 6, moving foreground) or under it (figure 7, moving background).
//!
//! Where `A_blur <= ALPHA_EPS` the colour is 0 (no division by zero, no NaN); the opacity is
//! always `A_glow`, so the result never has less opacity than the input. Along an image row the
//! whole filter is one fused pass (running sums, glow, rescale, composite) per row.
use rayon::prelude::*;

use super::boxblur::box_row_each;
use super::glow::{glow_row, GlowScratch};
use super::lines::{directional, plan};
use super::{check_direction, check_finite, check_image, ALPHA_EPS};
use crate::{Error, Result};

/// How the blurred layer is combined with the base image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Composite {
    /// `sub + (1 - A_sub) base`: a moving foreground over the sharp image (figure 6).
    Over,
    /// `base + (1 - A_base) sub`: a moving background under the sharp foreground (figure 7).
    Under,
}

impl Composite {
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "over" => Ok(Composite::Over),
            "under" => Ok(Composite::Under),
            _ => Err(Error::value(
                "mode",
                format!("expected 'over' or 'under', got {s:?}"),
            )),
        }
    }
}

/// Eq. 7 and the composite for one pixel.
#[inline(always)]
fn finish(blur: [f32; 4], glow: f32, base: &[f32], comp: Option<Composite>) -> [f32; 4] {
    let s = if blur[3] > ALPHA_EPS {
        glow / blur[3]
    } else {
        0.0
    };
    let sub = [blur[0] * s, blur[1] * s, blur[2] * s, glow];
    match comp {
        None => sub,
        Some(Composite::Over) => {
            let k = 1.0 - glow;
            [
                sub[0] + k * base[0],
                sub[1] + k * base[1],
                sub[2] + k * base[2],
                sub[3] + k * base[3],
            ]
        }
        Some(Composite::Under) => {
            let k = 1.0 - base[3];
            [
                base[0] + k * sub[0],
                base[1] + k * sub[1],
                base[2] + k * sub[2],
                base[3] + k * sub[3],
            ]
        }
    }
}

#[derive(Default)]
struct RowScratch {
    glow: GlowScratch,
    a: Vec<f32>,
    g: Vec<f32>,
}

fn finite_row(r: &[f32]) -> bool {
    r.iter().fold(true, |ok, v| ok & v.is_finite())
}

fn opaque_impl(
    rgba: &[f32],
    base: Option<&[f32]>,
    w: usize,
    h: usize,
    direction: [f32; 2],
    length: f32,
    comp: Option<Composite>,
) -> Result<Vec<f32>> {
    check_image("rgba", rgba, w, h, 4)?;
    if let Some(b) = base {
        check_image("base", b, w, h, 4)?;
    }
    check_direction(direction, length, "length")?;
    let base_img = base.unwrap_or(rgba);
    let mut out = vec![0.0f32; w * h * 4];
    let p = plan(direction, length * 0.5);
    match p {
        Some(p) if !p.transpose && p.slope == 0.0 => {
            // One fused pass per row: glow, running sums, rescale, composite.
            let r = p.radius;
            let ok = out
                .par_chunks_mut(w * 4)
                .zip(rgba.par_chunks(w * 4))
                .zip(base_img.par_chunks(w * 4))
                .map_init(RowScratch::default, |s, ((o, src), b)| {
                    if !(finite_row(src) && finite_row(b)) {
                        return false;
                    }
                    s.a.clear();
                    s.a.extend(src.chunks_exact(4).map(|px| px[3]));
                    s.g.resize(w, 0.0);
                    glow_row(&s.a, r, &mut s.g, &mut s.glow);
                    let g = &s.g;
                    box_row_each(src, w, r, |x, m| {
                        let v = finish(m, g[x], &b[x * 4..x * 4 + 4], comp);
                        o[x * 4..x * 4 + 4].copy_from_slice(&v);
                    });
                    true
                })
                .reduce(|| true, |a, b| a & b);
            if !ok {
                check_finite("rgba", rgba)?;
                check_finite("base", base_img)?;
            }
        }
        Some(p) => {
            check_finite("rgba", rgba)?;
            if base.is_some() {
                check_finite("base", base_img)?;
            }
            let r = p.radius;
            let five = directional::<4, 5, RowScratch>(rgba, w, h, &p, |src, n, o, s| {
                s.a.clear();
                s.a.extend(src.chunks_exact(4).map(|px| px[3]));
                s.g.resize(n, 0.0);
                glow_row(&s.a, r, &mut s.g, &mut s.glow);
                let g = &s.g;
                box_row_each(src, n, r, |x, m| {
                    o[x * 5..x * 5 + 4].copy_from_slice(&m);
                    o[x * 5 + 4] = g[x];
                });
            });
            let oblique = p.slope != 0.0;
            out.par_chunks_mut(w * 4).enumerate().for_each(|(y, o)| {
                for x in 0..w {
                    let i = y * w + x;
                    let f = &five[i * 5..i * 5 + 5];
                    let mut g = f[4];
                    if oblique {
                        g = g.max(rgba[i * 4 + 3]);
                    }
                    let v = finish(
                        [f[0], f[1], f[2], f[3]],
                        g,
                        &base_img[i * 4..i * 4 + 4],
                        comp,
                    );
                    o[x * 4..x * 4 + 4].copy_from_slice(&v);
                }
            });
        }
        None => {
            check_finite("rgba", rgba)?;
            check_finite("base", base_img)?;
            out.par_chunks_mut(4)
                .zip(rgba.par_chunks(4))
                .zip(base_img.par_chunks(4))
                .for_each(|((o, px), b)| {
                    o.copy_from_slice(&finish([px[0], px[1], px[2], px[3]], px[3], b, comp))
                });
        }
    }
    Ok(out)
}

/// Opaque image blur of a `(h, w, 4)` premultiplied image along `direction` over `length` pixels:
/// box blur, glow of the same radius, eq. 7. No compositing.
pub fn opaque_blur(
    rgba: &[f32],
    w: usize,
    h: usize,
    direction: [f32; 2],
    length: f32,
) -> Result<Vec<f32>> {
    opaque_impl(rgba, None, w, h, direction, length, None)
}

/// Opaque motion blur (figures 6 and 7): `opaque_blur(rgba)` composited `mode` the base image
/// (`rgba` itself when `base` is `None`).
#[allow(clippy::too_many_arguments)]
pub fn opaque_motion_blur(
    rgba: &[f32],
    base: Option<&[f32]>,
    w: usize,
    h: usize,
    direction: [f32; 2],
    length: f32,
    mode: Composite,
) -> Result<Vec<f32>> {
    opaque_impl(rgba, base, w, h, direction, length, Some(mode))
}
