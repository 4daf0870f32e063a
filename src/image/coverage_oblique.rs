//! One velocity group of `opaque_image`'s coverage glow ([`super::coverage_blur`]) blurred
//! along an oblique direction and added into the object's sums, without the window-sized
//! images in between: its layer and depth layer are cut straight into the orientation the
//! shear runs in (a mostly vertical direction's, transposed), sheared and box-filtered only
//! along the sheared rows that read one of the group's pixels (every other row is zero), and
//! each pixel is sheared back straight into the sums, skipped where both rows it reads are zero
//! (a sum from +0 never holds -0, so adding a zero leaves it as it is).
//!
//! The arithmetic is that of cutting the layers, blurring each with
//! [`box_blur`](super::box_blur) and adding them, value for value in the same order: the same
//! bits (the oracle of `coverage_blur`'s tests).
use std::mem::MaybeUninit;

use rayon::prelude::*;

use super::boxblur::box_filter;
use super::coverage::Window;
use super::coverage_blur::{cut_pixel, label_row, pasted_row, CoverageObject, CoverageSource};
use super::lines::{build_sheared, LinePlan, Live};
use super::{check_finite, pool, pooled, put4};
use crate::error::Result;

/// Adds group `label`'s layer and depth layer over `window` (frame pixels), box-blurred as
/// `plan` says (an oblique direction: `plan.slope != 0`), into `acc` and `acc_z` (each
/// `(y1 - y0, x1 - x0, 4)` over the union window `uw` of the object's groups, which holds
/// `window`). Fails as `box_blur` does on a layer that is not finite, naming `rgba`.
pub(super) fn add_oblique(
    (acc, acc_z): (&mut [f32], &mut [f32]),
    uw: Window,
    (source, object, label): (&CoverageSource, &CoverageObject, i32),
    window: Window,
    plan: &LinePlan,
    w: usize,
) -> Result<()> {
    debug_assert!(plan.slope != 0.0);
    let (y0, y1, x0, x1) = window;
    let (pw, ph) = (x1 - x0, y1 - y0);
    let (w2, h2) = if plan.transpose { (ph, pw) } else { (pw, ph) };
    let (layer, zl) = cut_oriented(source, object, label, window, w, plan.transpose);
    check_finite("rgba", &layer)?;
    check_finite("rgba", &zl)?;
    // (both layers are zero off the group's pixels, where the depth layer's fourth channel is)
    let live = Live::Alpha {
        alpha: &zl,
        transposed: false,
    };
    let f = box_filter(plan.radius);
    let sc = build_sheared::<4, 4, ()>("rgba", &layer, w2, h2, plan.slope, 0.0, live, &f)?;
    let sz = build_sheared::<4, 4, ()>("rgba", &zl, w2, h2, plan.slope, 0.0, live, &f)?;
    pool::give(layer);
    pool::give(zl);
    let (uy0, _, ux0, ux1) = uw;
    let row = (ux1 - ux0) * 4;
    acc.par_chunks_mut(row)
        .zip(acc_z.par_chunks_mut(row))
        .skip(y0 - uy0)
        .take(ph)
        .enumerate()
        .for_each(|(r, (a, az))| {
            for c in 0..pw {
                // (the window's pixel (r, c) in the shear's orientation)
                let (x, y) = if plan.transpose { (r, c) } else { (c, r) };
                let k = (x0 - ux0 + c) * 4;
                if let Some(v) = sc.value(x, y) {
                    for (s, v) in a[k..k + 4].iter_mut().zip(v) {
                        *s += v;
                    }
                }
                if let Some(v) = sz.value(x, y) {
                    for (s, v) in az[k..k + 4].iter_mut().zip(v) {
                        *s += v;
                    }
                }
            }
        });
    pool::give(sc.data);
    pool::give(sz.data);
    Ok(())
}

/// The layer and the depth layer of group `label` over `window` (`coverage_blur`'s `cut`),
/// each `(y1 - y0, x1 - x0, 4)`, or `(x1 - x0, y1 - y0, 4)` transposed (`transposed`: the
/// window's column `c` is row `c`).
fn cut_oriented(
    source: &CoverageSource,
    object: &CoverageObject,
    label: i32,
    (y0, y1, x0, x1): Window,
    w: usize,
    transposed: bool,
) -> (Vec<f32>, Vec<f32>) {
    let (cols, rows) = (x1 - x0, y1 - y0);
    let n = rows * cols * 4;
    let fill = |out: &mut [MaybeUninit<f32>], depth_layer: bool| {
        let pick = |(l, z): ([f32; 4], [f32; 4])| if depth_layer { z } else { l };
        if !transposed {
            out.par_chunks_mut(cols * 4).enumerate().for_each(|(r, o)| {
                let y = y0 + r;
                let (labels, pasted) = (label_row(object, y), pasted_row(source, y));
                for c in 0..cols {
                    put4(
                        o,
                        c,
                        pick(cut_pixel(source, labels, pasted, label, (y, x0 + c, w))),
                    );
                }
            });
        } else {
            out.par_chunks_mut(rows * 4).enumerate().for_each(|(c, o)| {
                for r in 0..rows {
                    let y = y0 + r;
                    let (labels, pasted) = (label_row(object, y), pasted_row(source, y));
                    put4(
                        o,
                        r,
                        pick(cut_pixel(source, labels, pasted, label, (y, x0 + c, w))),
                    );
                }
            });
        }
    };
    (pooled(n, |u| fill(u, false)), pooled(n, |u| fill(u, true)))
}
