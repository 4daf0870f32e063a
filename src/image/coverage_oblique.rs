//! One velocity group of `opaque_image`'s coverage glow ([`super::coverage_blur`]) blurred
//! along an oblique direction and added into the object's sums, without the window-sized
//! images in between: its layer and depth layer are cut straight into the orientation the
//! shear runs in (a mostly vertical direction's, transposed), sheared and box-filtered only
//! along the sheared rows that read one of the group's pixels (every other row is zero), and
//! each pixel is sheared back straight into the sums, skipped where both rows it reads are zero
//! (a sum from +0 never holds -0, so adding a zero leaves it as it is).
//!
//! When every colour and depth the object's windows read is finite ([`finite`]), only the
//! group's own pixels are cut, over zeros: the layers are zero elsewhere up to the sign of a
//! zero, which the filter's sums from +0 do not keep.
//!
//! The arithmetic is that of cutting the layers, blurring each with
//! [`box_blur`](super::box_blur) and adding them, value for value in the same order: the same
//! bits (the oracle of `coverage_blur`'s tests).
use std::mem::MaybeUninit;

use rayon::prelude::*;

use super::boxblur::box_filter;
use super::coverage::Window;
use super::coverage_cut::{cut_pixel, label_row, pasted_row, CoverageObject, CoverageSource};
use super::lines::{build_sheared, LinePlan, Live};
use super::{check_finite, pool, pooled, put4};
use crate::error::Result;

/// Whether every colour of `source` in the union window `uw` (and of its pasted window) and
/// every depth there is finite: then every layer `coverage_blur` cuts there is finite.
pub(super) fn finite(source: &CoverageSource, (y0, y1, x0, x1): Window, w: usize) -> bool {
    let ok = |v: &[f32]| v.iter().all(|v| v.is_finite());
    let rows = (y0..y1).into_par_iter();
    let pasted = source
        .pasted
        .is_none_or(|(_, p)| p.par_chunks(1 << 14).all(ok));
    pasted
        && rows.all(|y| {
            ok(&source.rgba[(y * w + x0) * 4..(y * w + x1) * 4])
                && ok(&source.depth[y * w + x0..y * w + x1])
        })
}

/// Adds group `label`'s layer and depth layer over `window` (frame pixels), box-blurred as
/// `plan` says (an oblique direction: `plan.slope != 0`), into `acc` and `acc_z` (each
/// `(y1 - y0, x1 - x0, 4)` over the union window `uw` of the object's groups, which holds
/// `window`). `finite`: what [`finite`] says of `uw`. Fails as `box_blur` does on a layer that
/// is not finite, naming `rgba`.
#[allow(clippy::too_many_arguments)]
pub(super) fn add_oblique(
    (acc, acc_z): (&mut [f32], &mut [f32]),
    uw: Window,
    (source, object, label): (&CoverageSource, &CoverageObject, i32),
    window: Window,
    plan: &LinePlan,
    w: usize,
    finite: bool,
) -> Result<()> {
    debug_assert!(plan.slope != 0.0);
    let (y0, y1, x0, x1) = window;
    let (pw, ph) = (x1 - x0, y1 - y0);
    let (w2, h2) = if plan.transpose { (ph, pw) } else { (pw, ph) };
    let only = finite.then_some(label);
    let (layer, zl) = cut_oriented(source, object, label, window, w, (plan.transpose, only));
    if !finite {
        check_finite("rgba", &layer)?;
        check_finite("rgba", &zl)?;
    }
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
                // (the two shears have the same rows and spans: where one reads only zero
                // rows, so does the other)
                let Some(v) = sc.value(x, y) else {
                    continue;
                };
                for (s, v) in a[k..k + 4].iter_mut().zip(v) {
                    *s += v;
                }
                let v = sz.value(x, y).unwrap_or([0.0; 4]);
                for (s, v) in az[k..k + 4].iter_mut().zip(v) {
                    *s += v;
                }
            }
        });
    pool::give(sc.data);
    pool::give(sz.data);
    Ok(())
}

/// The layer and the depth layer of group `label` over `window` (`coverage_blur`'s `cut`),
/// each `(y1 - y0, x1 - x0, 4)`, or `(x1 - x0, y1 - y0, 4)` transposed (`transposed`: the
/// window's column `c` is row `c`). With `only` (the group's label), only the group's pixels
/// are cut, over zeros (module docs).
fn cut_oriented(
    source: &CoverageSource,
    object: &CoverageObject,
    label: i32,
    window: Window,
    w: usize,
    (transposed, only): (bool, Option<i32>),
) -> (Vec<f32>, Vec<f32>) {
    let (y0, y1, x0, x1) = window;
    let (cols, rows) = (x1 - x0, y1 - y0);
    let n = rows * cols * 4;
    let fill = |out: &mut [MaybeUninit<f32>], depth_layer: bool| {
        let pick = |(l, z): ([f32; 4], [f32; 4])| if depth_layer { z } else { l };
        if only.is_some() {
            sparse(out, (source, object, label), window, w, transposed, pick);
        } else if !transposed {
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

/// `cut_oriented`'s rows of the group's pixels only: each row zeros, then the group's pixels of
/// the object's labels along it cut by `cut_pixel` (`pick`: the layer or the depth layer).
fn sparse(
    out: &mut [MaybeUninit<f32>],
    (source, object, label): (&CoverageSource, &CoverageObject, i32),
    (y0, y1, x0, x1): Window,
    w: usize,
    transposed: bool,
    pick: impl Fn(([f32; 4], [f32; 4])) -> [f32; 4] + Sync,
) {
    let (oy0, oy1, ox0, ox1) = object.window;
    let ocols = ox1 - ox0;
    // the window's rows and columns that meet the object's
    let (ra, rb) = (oy0.max(y0), oy1.min(y1));
    let (ca, cb) = (ox0.max(x0), ox1.min(x1));
    let len = if transposed { y1 - y0 } else { x1 - x0 };
    out.par_chunks_mut(len * 4).enumerate().for_each(|(k, o)| {
        o.fill(MaybeUninit::new(0.0));
        // (frame pixels (y, x) along oriented row k, and their place in it)
        let mut put = |y: usize, x: usize, at: usize| {
            if object.labels[(y - oy0) * ocols + x - ox0] == label {
                let (labels, pasted) = (label_row(object, y), pasted_row(source, y));
                put4(
                    o,
                    at,
                    pick(cut_pixel(source, labels, pasted, label, (y, x, w))),
                );
            }
        };
        if transposed {
            let x = x0 + k;
            if (ca..cb).contains(&x) {
                (ra..rb).for_each(|y| put(y, x, y - y0));
            }
        } else {
            let y = y0 + k;
            if (ra..rb).contains(&y) {
                (ca..cb).for_each(|x| put(y, x, x - x0));
            }
        }
    });
}
