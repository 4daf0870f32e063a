//! The triangle-max glow of Kraus's eq. 10 along a direction:
//! `A_glow[i] = max_{|k| <= w} (1 - |k| / w) A[i + k]`, zero outside the image.
//!
//! Its weight at `k = 0` is 1, so it never lowers alpha. Each row is two sweeps with a monotone
//! deque of the sources that can still win (see `glow_row`): O(1) per pixel on masks and smooth
//! alpha, O(w) only for alpha that keeps growing with distance over the whole window.
//! Along an oblique direction the glow runs on sheared rows (see `lines`) and the result is
//! `max(glow, A)` so that the interpolation never lowers alpha either.
use rayon::prelude::*;

use super::lines::{directional, plan};
use super::{check_direction, check_image, check_premultiplied, MAX_LENGTH};
use crate::error::{Error, Result};

/// Scratch buffers of one thread: the candidate sources of the sweep.
#[derive(Default)]
pub(crate) struct GlowScratch {
    cand: Vec<u32>,
}

/// Eq. 10 on one row: `out[i] = max_{|k| <= w} (1 - |k| / w) a[i + k]`; `w = 0` copies.
///
/// Two sweeps (sources on the right of the target, then on the left). A source `j` nearer to
/// the target than a source `j'` with `a[j] >= a[j']` dominates it for every later target, so
/// each sweep keeps only the sources within reach whose alpha strictly grows with distance (a
/// monotone deque: `cand[lo..]`, nearest last) and takes the best of those. For masks and smooth
/// alpha the deque holds one or two sources, so the cost is O(1) per pixel whatever `w` is.
pub(crate) fn glow_row(a: &[f32], w: usize, out: &mut [f32], s: &mut GlowScratch) {
    let n = a.len();
    if w == 0 {
        out.copy_from_slice(a);
        return;
    }
    // A constant row (an opaque or empty stretch) is its own glow.
    let (lo, hi) = a
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    if lo == hi && lo >= 0.0 {
        out.copy_from_slice(a);
        return;
    }
    let wf = w as f32;
    let q = &mut s.cand;
    // Sources at or right of the target (sweep right to left).
    q.clear();
    let mut lo = 0;
    for i in (0..n).rev() {
        let ai = a[i];
        while q.len() > lo && a[q[q.len() - 1] as usize] <= ai {
            q.pop();
        }
        q.push(i as u32);
        while q[lo] as usize - i >= w {
            lo += 1;
        }
        let mut best = ai;
        for &j in &q[lo..q.len() - 1] {
            let j = j as usize;
            best = best.max((1.0 - (j - i) as f32 / wf) * a[j]);
        }
        out[i] = best;
    }
    // Sources at or left of the target (sweep left to right).
    q.clear();
    lo = 0;
    for i in 0..n {
        let ai = a[i];
        while q.len() > lo && a[q[q.len() - 1] as usize] <= ai {
            q.pop();
        }
        q.push(i as u32);
        while i - q[lo] as usize >= w {
            lo += 1;
        }
        let mut best = out[i];
        for &j in &q[lo..q.len() - 1] {
            let j = j as usize;
            best = best.max((1.0 - (i - j) as f32 / wf) * a[j]);
        }
        out[i] = best.max(0.0);
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
    check_premultiplied("alpha", alpha, 1)?;
    let Some(p) = plan(direction, width) else {
        return Ok(alpha.to_vec());
    };
    let mut out = directional::<1, 1, GlowScratch>("alpha", alpha, w, h, &p, |src, _, o, s| {
        glow_row(src, p.radius, o, s);
        true
    })?;
    if p.slope != 0.0 {
        out.par_iter_mut()
            .zip(alpha.par_iter())
            .for_each(|(o, a)| *o = o.max(*a));
    }
    Ok(out)
}
