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

/// Scratch buffers of one thread (block maxima).
#[derive(Default)]
pub(crate) struct GlowScratch {
    blocks: Vec<f32>,
}

/// Eq. 10 on one row: `out[i] = max_{|k| <= w} (1 - |k| / w) a[i + k]`; `w = 0` copies.
///
/// The row is cut into blocks of `w + 1` pixels; the window of any pixel of block `b` lies in
/// blocks `b - 1 ..= b + 1`, so the maximum `m` of those three block maxima bounds every tap.
/// A pixel with `a >= m` keeps `a`; otherwise taps are visited nearest first until
/// `m (1 - d / w)` cannot beat the best value found.
pub(crate) fn glow_row(a: &[f32], w: usize, out: &mut [f32], s: &mut GlowScratch) {
    let n = a.len();
    if w == 0 {
        out.copy_from_slice(a);
        return;
    }
    let bs = w + 1;
    let nb = n.div_ceil(bs);
    s.blocks.clear();
    s.blocks.extend(a.chunks(bs).map(|c| {
        c.iter()
            .fold(f32::NEG_INFINITY, |m, &v| if v > m { v } else { m })
    }));
    let wf = w as f32;
    for b in 0..nb {
        let lo = s.blocks[b.saturating_sub(1)];
        let hi = s.blocks[(b + 1).min(nb - 1)];
        let m = lo.max(s.blocks[b]).max(hi).max(0.0);
        let (x0, x1) = (b * bs, ((b + 1) * bs).min(n));
        for i in x0..x1 {
            let ai = a[i];
            if ai >= m {
                out[i] = ai;
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
            out[i] = best.max(0.0);
        }
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
