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
use rayon::prelude::*;

use super::boxblur::box_filter;
use super::coverage::Window;
use super::coverage_cut::{cut, CoverageObject, CoverageSource};
use super::lines::{build_sheared, LinePlan, Live};
use super::{check_finite, pool};
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
    let (layer, zl) = cut(source, object, label, window, w, (plan.transpose, only));
    if !finite {
        check_finite("rgba", &layer)?;
        check_finite("rgba", &zl)?;
    }
    // (both layers are zero off the group's pixels, where the depth layer's fourth channel is)
    let live = Live::Alpha(&zl);
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
