//! The triangle-max glow of Kraus's eq. 10 along a direction:
//! `A_glow[i] = max_{|k| <= w} (1 - |k| / w) A[i + k]`, zero outside the image.
//!
//! Its weight at `k = 0` is 1, so it never lowers alpha. Per pixel it first takes the flat
//! window maximum `M` (van Herk / Gil-Werman, O(1) per pixel); when `A[i] >= M` the answer is
//! `A[i]`, when `M = 0` it is 0, and otherwise taps are visited nearest first and the search stops
//! as soon as `M (1 - d / w)` cannot beat the best value found. On masks and smooth alpha the
//! search ends after about the distance to the nearest opaque pixel; the worst case is O(w).
//! Along an oblique direction the glow runs on sheared rows (see `lines`) and the result is
//! `max(glow, A)` so that the interpolation never lowers alpha either.
use rayon::prelude::*;

use super::lines::{directional, plan};
use super::{check_direction, check_finite, check_image, MAX_LENGTH};
use crate::{Error, Result};

/// Scratch buffers of one thread (padded row, prefix and suffix maxima, window maxima).
#[derive(Default)]
pub(crate) struct GlowScratch {
    pad: Vec<f32>,
    pre: Vec<f32>,
    suf: Vec<f32>,
    max: Vec<f32>,
}

/// Flat maximum of `a` over `[i - w, i + w]` (zero outside) into `s.max` (van Herk / Gil-Werman).
fn window_max(a: &[f32], w: usize, s: &mut GlowScratch) {
    let n = a.len();
    let k = 2 * w + 1;
    let len = n + 2 * w;
    s.pad.clear();
    s.pad.resize(len, 0.0);
    s.pad[w..w + n].copy_from_slice(a);
    s.pre.resize(len, 0.0);
    s.suf.resize(len, 0.0);
    for j in 0..len {
        s.pre[j] = if j % k == 0 {
            s.pad[j]
        } else {
            s.pre[j - 1].max(s.pad[j])
        };
    }
    for j in (0..len).rev() {
        s.suf[j] = if j % k == k - 1 || j == len - 1 {
            s.pad[j]
        } else {
            s.suf[j + 1].max(s.pad[j])
        };
    }
    s.max.resize(n, 0.0);
    for i in 0..n {
        s.max[i] = s.suf[i].max(s.pre[i + k - 1]);
    }
}

/// Eq. 10 on one row: `out[i] = max_{|k| <= w} (1 - |k| / w) a[i + k]`; `w = 0` copies.
pub(crate) fn glow_row(a: &[f32], w: usize, out: &mut [f32], s: &mut GlowScratch) {
    let n = a.len();
    if w == 0 {
        out.copy_from_slice(a);
        return;
    }
    window_max(a, w, s);
    let wf = w as f32;
    for i in 0..n {
        let m = s.max[i];
        let ai = a[i];
        if ai >= m {
            out[i] = ai;
            continue;
        }
        if m <= 0.0 {
            out[i] = ai.max(0.0);
            continue;
        }
        let mut best = ai;
        for d in 1..=w {
            let wt = 1.0 - d as f32 / wf;
            if m * wt <= best || (d > i && i + d >= n) {
                break;
            }
            if d <= i {
                best = best.max(wt * a[i - d]);
            }
            if i + d < n {
                best = best.max(wt * a[i + d]);
            }
        }
        out[i] = best;
    }
}

/// Eq. 10 glow of a `(h, w)` alpha image along `direction` with half-width `width` pixels
/// (radius `floor(width * c)` major-axis taps, see `lines::plan`). Never lowers alpha.
pub fn glow(
    alpha: &[f32],
    w: usize,
    h: usize,
    direction: [f32; 2],
    width: f32,
) -> Result<Vec<f32>> {
    check_image("alpha", alpha, w, h, 1)?;
    check_direction(direction, width, "width")?;
    if width > MAX_LENGTH / 2.0 {
        return Err(Error::value("width", "is absurdly large"));
    }
    check_finite("alpha", alpha)?;
    let Some(p) = plan(direction, width) else {
        return Ok(alpha.to_vec());
    };
    let mut out = directional::<1, 1, GlowScratch>(alpha, w, h, &p, |src, _, o, s| {
        glow_row(src, p.radius, o, s)
    });
    if p.slope != 0.0 {
        out.par_iter_mut()
            .zip(alpha.par_iter())
            .for_each(|(o, a)| *o = o.max(*a));
    }
    Ok(out)
}
