//! Filters along a line: turning any direction into rows.
//!
//! A direction whose major axis is y is handled by transposing the image (and back). For a
//! major axis x with slope `t = dy / dx` (|t| <= 1, t != 0) the image is *sheared*: sheared row
//! `j` samples column `x` of the image at `y = j + x t` with linear interpolation in y, so one
//! step along a sheared row is one step along the direction (one pixel in x, `t` in y). The row
//! filter then runs along sheared rows with running sums, and the result is sheared back: output
//! pixel `(x, y)` interpolates sheared rows `floor(y - x t)` and the next one at column `x`.
//! Both interpolations are linear in y only; outside the image everything reads as zero.
//! The cost is a few passes over the image, independent of the filter length.
use rayon::prelude::*;
use std::borrow::Cow;

use super::transpose;
use crate::error::{Error, Result};

/// How a direction maps onto rows: transpose or not, slope of the sheared rows, tap radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinePlan {
    /// The major axis is y: filter the transposed image.
    pub transpose: bool,
    /// Minor over major component of the direction, in [-1, 1]; 0 for an axis direction.
    pub slope: f64,
    /// Taps reach `radius` major-axis pixels on each side.
    pub radius: usize,
}

/// The plan for `direction` (any length, +x right, +y down) and a reach of `reach` pixels along
/// it: `radius = floor(reach * c)` with `c = max(|dx|, |dy|) / |direction|`. `None` when the
/// direction is zero or the radius is 0 (the filter is the identity).
pub fn plan(direction: [f32; 2], reach: f32) -> Option<LinePlan> {
    let (dx, dy) = (direction[0] as f64, direction[1] as f64);
    let norm = dx.hypot(dy);
    if norm <= 0.0 || reach <= 0.0 || norm.is_nan() || reach.is_nan() {
        return None;
    }
    let transpose = dy.abs() > dx.abs();
    let (major, minor) = if transpose { (dy, dx) } else { (dx, dy) };
    let radius = (reach as f64 * major.abs() / norm).floor() as usize;
    if radius == 0 {
        return None;
    }
    Some(LinePlan {
        transpose,
        slope: minor / major,
        radius,
    })
}

/// `floor(v)` for |v| < 2^52 without a libm call (baseline x86-64 has no rounding instruction).
#[inline(always)]
pub(crate) fn floor(v: f64) -> f64 {
    let i = v as i64 as f64;
    if i > v {
        i - 1.0
    } else {
        i
    }
}

/// Rows `j0 .. j0 + rows` of the sheared image of a `w x h` image with slope `t`: every row
/// that some output pixel interpolates.
pub(crate) fn shear_range(w: usize, h: usize, t: f64, c0: f64) -> (i64, usize) {
    let e = -(w as f64 - 1.0) * t;
    let j0 = (e.min(0.0) - c0).floor() as i64;
    let j1 = (e.max(0.0) + (h as f64 - 1.0) - c0).floor() as i64 + 1;
    (j0, (j1 - j0 + 1) as usize)
}

/// Per-column integer and fractional parts of `x t + c0` (`sign = 1`, the shear) or of
/// `-x t - c0` (`sign = -1`, the way back). Row `j` of the shear samples image row
/// `j + floor[x]` and the next one with weight `frac[x]`: the fraction does not depend on `j`.
pub(crate) struct Phase {
    floor: Vec<i64>,
    frac: Vec<f32>,
}

impl Phase {
    pub(crate) fn new(w: usize, t: f64, c0: f64, sign: f64) -> Self {
        let mut p = Phase {
            floor: Vec::with_capacity(w),
            frac: Vec::with_capacity(w),
        };
        for x in 0..w {
            let u = sign * (x as f64 * t + c0);
            let fl = floor(u);
            p.floor.push(fl as i64);
            p.frac.push((u - fl) as f32);
        }
        p
    }
}

/// Sheared row `j` of a `(h, w, C)` image: `out[x] = lerp(img[floor(y)][x], img[floor(y)+1][x], frac(y))`
/// with `y = j + x t + c0` (`phase` from `Phase::new(w, t, c0, 1.0)`), zero outside the image.
/// `c0` in [0, 1) is the phase of a crop whose first column is not column 0 of the full image.
/// Only columns `xa .. xa + n` are computed, into `out[(x - xa) * C ..]`.
pub(crate) fn shear_row<const C: usize>(
    img: &[f32],
    w: usize,
    h: usize,
    phase: &Phase,
    j: i64,
    (xa, n): (usize, usize),
    out: &mut [f32],
) {
    // The columns whose two samples are both in the image (y0 in [0, h - 2]) form one interval
    // (the floors are monotone): there the loop needs no test.
    let fl = &phase.floor[xa..xa + n];
    let (lo, hi) = (-j, h as i64 - 2 - j);
    let (ia, ib) = if fl.len() < 2 || fl[0] <= fl[fl.len() - 1] {
        (
            fl.partition_point(|&f| f < lo),
            fl.partition_point(|&f| f <= hi),
        )
    } else {
        (
            fl.partition_point(|&f| f > hi),
            fl.partition_point(|&f| f >= lo),
        )
    };
    let ib = ib.max(ia);
    assert!(img.len() >= w * h * C && out.len() >= n * C && xa + n <= w);
    let (fl, fr) = (
        &phase.floor[xa + ia..xa + ib],
        &phase.frac[xa + ia..xa + ib],
    );
    #[cfg(target_arch = "x86_64")]
    if C == 4 && super::simd() {
        // SAFETY: AVX2 was detected; every pixel read is in the image (as below).
        unsafe { shear4_avx(img, w, j, fl, fr, xa + ia, &mut out[ia * 4..ib * 4]) };
        return shear_edges::<C>(img, w, h, phase, j, (xa, n), (ia, ib), out);
    }
    let o = &mut out[ia * C..ib * C];
    for (k, (o, (&fl, &f))) in o.chunks_exact_mut(C).zip(fl.iter().zip(fr)).enumerate() {
        let x = xa + ia + k;
        let y0 = (j + fl) as usize;
        debug_assert!(y0 + 1 < h);
        // SAFETY: y0 + 1 < h (the interval's definition) and x < w, so both pixels are in
        // `img` (asserted to hold h * w * C values).
        let (a, b) = unsafe {
            (
                img.get_unchecked((y0 * w + x) * C..(y0 * w + x) * C + C),
                img.get_unchecked(((y0 + 1) * w + x) * C..((y0 + 1) * w + x) * C + C),
            )
        };
        for c in 0..C {
            o[c] = (1.0 - f) * a[c] + f * b[c];
        }
    }
    shear_edges::<C>(img, w, h, phase, j, (xa, n), (ia, ib), out)
}

/// How many sheared rows ahead `shear4_avx` prefetches.
#[cfg(target_arch = "x86_64")]
const AHEAD: usize = 4;

/// `shear_row`'s interior for four channels: the same operations lane for lane.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn shear4_avx(
    img: &[f32],
    w: usize,
    j: i64,
    fl: &[i64],
    fr: &[f32],
    x0: usize,
    out: &mut [f32],
) {
    use std::arch::x86_64::*;
    let (p, o) = (img.as_ptr(), out.as_mut_ptr());
    for (k, (&fl, &f)) in fl.iter().zip(fr).enumerate() {
        let x = x0 + k;
        let y0 = (j + fl) as usize;
        if x % 4 == 0 {
            // The pixels that sheared row j + AHEAD reads here (a diagonal walk through the
            // image defeats the hardware prefetchers); a prefetch past the image is harmless.
            let at = p.wrapping_add(((y0 + AHEAD) * w + x) * 4);
            _mm_prefetch::<_MM_HINT_T0>(at as *const i8);
            _mm_prefetch::<_MM_HINT_T0>(at.wrapping_add(w * 4) as *const i8);
        }
        let a = _mm_loadu_ps(p.add((y0 * w + x) * 4));
        let b = _mm_loadu_ps(p.add(((y0 + 1) * w + x) * 4));
        let v = _mm_add_ps(
            _mm_mul_ps(_mm_set1_ps(1.0 - f), a),
            _mm_mul_ps(_mm_set1_ps(f), b),
        );
        _mm_storeu_ps(o.add(k * 4), v);
    }
}

/// `shear_row` at the columns outside its interior `ia .. ib` (relative to `xa`).
#[allow(clippy::too_many_arguments)]
fn shear_edges<const C: usize>(
    img: &[f32],
    w: usize,
    h: usize,
    phase: &Phase,
    j: i64,
    (xa, n): (usize, usize),
    (ia, ib): (usize, usize),
    out: &mut [f32],
) {
    for x in (xa..xa + ia).chain(xa + ib..xa + n) {
        let y0 = j + phase.floor[x];
        let f = phase.frac[x];
        let o = &mut out[(x - xa) * C..(x - xa) * C + C];
        if y0 >= 0 && y0 + 1 < h as i64 {
            let a = &img[(y0 as usize * w + x) * C..][..C];
            let b = &img[((y0 + 1) as usize * w + x) * C..][..C];
            for c in 0..C {
                o[c] = (1.0 - f) * a[c] + f * b[c];
            }
            continue;
        }
        o.fill(0.0);
        if y0 >= 0 && y0 < h as i64 {
            let p = &img[(y0 as usize * w + x) * C..][..C];
            for c in 0..C {
                o[c] += (1.0 - f) * p[c];
            }
        }
        if y0 + 1 >= 0 && y0 + 1 < h as i64 {
            let p = &img[((y0 + 1) as usize * w + x) * C..][..C];
            for c in 0..C {
                o[c] += f * p[c];
            }
        }
    }
}

/// Runs the row filter `f(src_row (n*CI), n, out_row (n*CO), scratch) -> bool` along `plan`'s
/// direction over a `(h, w, CI)` image and returns the `(h, w, CO)` result in the image's
/// orientation. `f` either writes its whole output row and returns true, or returns false for
/// a row that is all zero (and need not write it).
pub(crate) fn directional<const CI: usize, const CO: usize, S: Default + Send>(
    name: &'static str,
    img: &[f32],
    w: usize,
    h: usize,
    plan: &LinePlan,
    f: impl Fn(&[f32], usize, &mut [f32], &mut S) -> bool + Sync + Send,
) -> Result<Vec<f32>> {
    directional_at::<CI, CO, S>(name, img, w, h, plan, 0.0, Live::All, f)
}

/// Where the image a row filter runs over can be non-zero: a sheared row that reads only zeros
/// there is neither built nor filtered (a row filter gives zero on a zero row, and a skipped
/// row reads as zero: the same values).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Live<'a> {
    /// Anywhere.
    All,
    /// Only in the inclusive box `(x0, x1, y0, y1)`.
    Box([usize; 4]),
    /// Only at the pixels whose fourth channel is non-zero in this `(h, w, 4)` image, of the
    /// size and orientation the shear runs over (a transposed filter reads it as
    /// [`Live::All`]).
    Alpha(&'a [f32]),
}

/// `directional` on a crop whose first major-axis pixel is pixel `major_offset` of the full
/// image, so that the shear samples the same positions as on the full image. `live`: where the
/// image can be non-zero (in the image's orientation).
#[allow(clippy::too_many_arguments)]
pub(crate) fn directional_at<const CI: usize, const CO: usize, S: Default + Send>(
    name: &'static str,
    img: &[f32],
    w: usize,
    h: usize,
    plan: &LinePlan,
    major_offset: f64,
    live: Live<'_>,
    f: impl Fn(&[f32], usize, &mut [f32], &mut S) -> bool + Sync + Send,
) -> Result<Vec<f32>> {
    let live = match live {
        Live::Box([x0, x1, y0, y1]) if plan.transpose => Live::Box([y0, y1, x0, x1]),
        Live::Alpha(_) if plan.transpose => Live::All,
        other => other,
    };
    let (src, w2, h2): (Cow<[f32]>, usize, usize) = if plan.transpose {
        (Cow::Owned(transpose::<CI>(img, w, h)), h, w)
    } else {
        (Cow::Borrowed(img), w, h)
    };
    let mut out = super::pool::take_for(name, w2 * h2 * CO)?;
    if plan.slope == 0.0 {
        out.par_chunks_mut(w2 * CO)
            .zip(src.par_chunks(w2 * CI))
            .for_each_init(S::default, |s, (o, i)| {
                if !f(i, w2, o, s) {
                    o.fill(0.0);
                }
            });
    } else {
        let sh =
            build_sheared::<CI, CO, S>(name, &src, w2, h2, plan.slope, major_offset, live, &f)?;
        out.par_chunks_mut(w2 * CO)
            .enumerate()
            .for_each(|(y, o)| sh.unshear_row(w2, y, o));
        super::pool::give(sh.data);
    }
    // (the transposes' scratch back to the pool: a window-sized buffer each, whose fresh pages
    // cost more than the copies)
    if let Cow::Owned(v) = src {
        super::pool::give(v);
    }
    Ok(if plan.transpose {
        let back = transpose::<CO>(&out, w2, h2);
        super::pool::give(out);
        back
    } else {
        out
    })
}

/// A filtered sheared image: rows `j0 ..`, each stored only over the columns where it can be
/// non-zero. Row `j0 + k` holds columns `spans[k].0 .. spans[k].0 + spans[k].1` at
/// `data[offs[k] * CO ..]`; every other value of the row is zero (a span of length 0: the whole
/// row is zero). A sheared row meets the image only where `j + x t + c0` is in `(-1, h)`, about
/// `(h + 1) / |t|` columns, so the buffer holds at most `w (h + 1)` pixels whatever the slope
/// and the width (a full `rows x w` buffer would be `w^2 |t|` for a long thin image).
pub(crate) struct Sheared<const CO: usize> {
    pub(crate) data: Vec<f32>,
    spans: Vec<(usize, usize)>,
    offs: Vec<usize>,
    j0: i64,
    back: Phase,
}

impl<const CO: usize> Sheared<CO> {
    /// The `CO` values of sheared row `k` (relative to `j0`) at column `x`, `None` when zero.
    #[inline(always)]
    fn at(&self, k: i64, x: usize) -> Option<&[f32]> {
        if k < 0 || k >= self.spans.len() as i64 {
            return None;
        }
        let (s, n) = self.spans[k as usize];
        if x < s || x >= s + n {
            return None;
        }
        Some(&self.data[(self.offs[k as usize] + x - s) * CO..][..CO])
    }

    /// The runs of output columns `(start, end)` that interpolate the same two sheared rows in
    /// every output row (the integer part of `-x t - c0` is constant over a run).
    pub(crate) fn runs(&self, w: usize) -> Vec<(usize, usize)> {
        let fl = &self.back.floor;
        let mut runs = Vec::with_capacity(w / 2 + 1);
        let mut a = 0;
        for x in 1..=w {
            if x == w || fl[x] != fl[a] {
                runs.push((a, x));
                a = x;
            }
        }
        runs
    }

    /// The sheared rows that output row `y` interpolates at column `x` (`k`, the one of weight
    /// `1 - frac[x]`, and `k + 1`), each as `(start, end, offset)`: the row holds columns
    /// `start .. end` at `data[offset * CO ..]` (empty for a zero row).
    #[inline(always)]
    pub(crate) fn rows_at(&self, y: usize, x: usize) -> [(usize, usize, usize); 2] {
        let k = y as i64 + self.back.floor[x] - self.j0;
        let row = |k: i64| -> (usize, usize, usize) {
            if k < 0 || k >= self.spans.len() as i64 {
                return (0, 0, 0);
            }
            let (s, n) = self.spans[k as usize];
            (s, s + n, self.offs[k as usize])
        };
        [row(k), row(k + 1)]
    }

    /// The weights of the second sheared row at every column (`rows_at`).
    pub(crate) fn fracs(&self) -> &[f32] {
        &self.back.frac
    }

    /// The sheared row (relative to `j0`) that output row `y` reads with weight `1 - frac[x]`
    /// at column `x` is `y + row_offset(x)` (`rows_at`).
    #[inline]
    pub(crate) fn row_offset(&self, x: usize) -> i64 {
        self.back.floor[x] - self.j0
    }

    /// Every sheared row as `(start, end, offset)`, as `rows_at` gives them.
    pub(crate) fn row_list(&self) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        self.spans
            .iter()
            .zip(&self.offs)
            .map(|(&(s, n), &o)| (s, s + n, o))
    }

    /// Output row `y` over the columns of `run` as pieces `emit(x0, x1, a, b, frac)`: `a` and
    /// `b` are the values of the two sheared rows that `unshear_row` interpolates at columns
    /// `x0 .. x1` (`CO` per column; `None` where that row is zero there) and `frac` their
    /// weights of `b`.
    #[inline]
    pub(crate) fn pieces(
        &self,
        y: usize,
        (xs, xe): (usize, usize),
        mut emit: impl FnMut(usize, usize, Option<&[f32]>, Option<&[f32]>, &[f32]),
    ) {
        let [ra, rb] = self.rows_at(y, xs);
        let slice = |r: (usize, usize, usize), x0: usize, x1: usize| -> Option<&[f32]> {
            (r.0 <= x0 && x1 <= r.1)
                .then(|| &self.data[(r.2 + x0 - r.0) * CO..(r.2 + x1 - r.0) * CO])
        };
        let frac = &self.back.frac;
        if ra.0 <= xs && xe <= ra.1 && rb.0 <= xs && xe <= rb.1 {
            return emit(xs, xe, slice(ra, xs, xe), slice(rb, xs, xe), &frac[xs..xe]);
        }
        // Near the ends of the sheared rows: split the run where either row starts or ends.
        let mut cuts = [xs, xe, ra.0, ra.1, rb.0, rb.1].map(|c| c.clamp(xs, xe));
        cuts.sort_unstable();
        for c in cuts.windows(2) {
            let (x0, x1) = (c[0], c[1]);
            if x0 < x1 {
                emit(x0, x1, slice(ra, x0, x1), slice(rb, x0, x1), &frac[x0..x1]);
            }
        }
    }

    /// Output row `y` of the image the sheared rows came from: `out[x]` interpolates sheared
    /// rows `floor(y - x t - c0)` and the next one at column `x` (zero where a row is zero).
    pub(crate) fn unshear_row(&self, w: usize, y: usize, out: &mut [f32]) {
        for x in 0..w {
            let o = &mut out[x * CO..x * CO + CO];
            match self.value(x, y) {
                Some(v) => o.copy_from_slice(&v),
                None => o.fill(0.0),
            }
        }
    }

    /// Pixel `(x, y)` of the image the sheared rows came from (`unshear_row`'s), `None` where
    /// both sheared rows it interpolates are zero there.
    #[inline(always)]
    pub(crate) fn value(&self, x: usize, y: usize) -> Option<[f32; CO]> {
        let i = y as i64 + self.back.floor[x] - self.j0;
        let f = self.back.frac[x];
        let mut o = [0.0f32; CO];
        match (self.at(i, x), self.at(i + 1, x)) {
            (Some(a), Some(b)) => {
                for c in 0..CO {
                    o[c] = (1.0 - f) * a[c] + f * b[c];
                }
            }
            (Some(a), None) => {
                for c in 0..CO {
                    o[c] = (1.0 - f) * a[c];
                }
            }
            (None, Some(b)) => {
                for c in 0..CO {
                    o[c] = f * b[c];
                }
            }
            (None, None) => return None,
        }
        Some(o)
    }
}

/// Columns `(start, len)` of sheared row `j` that read the image: `y0 = j + floor[x]` in
/// `[-1, h - 1]` (`floor` is monotone in `x`, so they form one interval).
fn row_span(fwd: &Phase, t: f64, h: usize, j: i64) -> (usize, usize) {
    let (lo, hi) = (-1 - j, h as i64 - 1 - j);
    let fl = &fwd.floor;
    let (a, b) = if t > 0.0 {
        (
            fl.partition_point(|&f| f < lo),
            fl.partition_point(|&f| f <= hi),
        )
    } else {
        (
            fl.partition_point(|&f| f > hi),
            fl.partition_point(|&f| f >= lo),
        )
    };
    (a, b.saturating_sub(a))
}

/// Which of the sheared rows `j0 .. j0 + rows` (`fwd`: the shear's phase) read a live pixel
/// (fourth channel non-zero) of the `(h, w, 4)` image `alpha`: row `j` reads rows `j + floor[x]`
/// and the next of column `x`, so a live pixel `(x, y)` marks rows `y - floor[x]` and the one
/// before.
fn live_rows(alpha: &[f32], w: usize, fwd: &Phase, (j0, rows): (i64, usize)) -> Vec<bool> {
    let mut hit = vec![false; rows];
    let mut mark = |j: i64| {
        if let Some(k) = usize::try_from(j - j0).ok().filter(|&k| k < rows) {
            hit[k] = true;
        }
    };
    for (i, px) in alpha.chunks_exact(4).enumerate() {
        if px[3] != 0.0 {
            let (x, y) = (i % w, i / w);
            let j = y as i64 - fwd.floor[x];
            mark(j);
            mark(j - 1);
        }
    }
    hit
}

/// Shears a `(h, w, CI)` image with slope `t` (see the module docs; `major_offset` and `live` as
/// in `directional_at`, a box already in this orientation) and runs the row filter `f` on every
/// sheared row that can meet what is live, over the columns where the row meets the image
/// (the filters read zero outside their row, which is what the rest of the sheared row holds).
/// Fails naming `name` if the buffer cannot be allocated.
#[allow(clippy::too_many_arguments)]
pub(crate) fn build_sheared<const CI: usize, const CO: usize, S: Default + Send>(
    name: &'static str,
    src: &[f32],
    w: usize,
    h: usize,
    t: f64,
    major_offset: f64,
    live: Live<'_>,
    f: &(impl Fn(&[f32], usize, &mut [f32], &mut S) -> bool + Sync + Send),
) -> Result<Sheared<CO>> {
    let c0 = (major_offset * t).rem_euclid(1.0);
    let (j0, rows) = shear_range(w, h, t, c0);
    let fwd = Phase::new(w, t, c0, 1.0);
    let back = Phase::new(w, t, c0, -1.0);
    // Sheared rows that can meet the live box: j + x t + c0 in (y0 - 1, y1 + 1), x in [x0, x1].
    let (jlo, jhi) = match live {
        Live::Box([x0, x1, y0, y1]) => {
            let (ua, ub) = (x0 as f64 * t + c0, x1 as f64 * t + c0);
            (
                (y0 as f64 - 1.0 - ua.max(ub)).floor() as i64,
                (y1 as f64 + 1.0 - ua.min(ub)).ceil() as i64,
            )
        }
        _ => (i64::MIN, i64::MAX),
    };
    let hit = match live {
        Live::Alpha(alpha) => Some(live_rows(alpha, w, &fwd, (j0, rows))),
        _ => None,
    };
    let mut spans = Vec::new();
    let mut offs = Vec::new();
    spans
        .try_reserve_exact(rows)
        .and_then(|_| offs.try_reserve_exact(rows))
        .map_err(|_| {
            Error::value(
                name,
                format!("is too large to filter ({rows} sheared rows)"),
            )
        })?;
    let mut total = 0usize;
    for k in 0..rows {
        let j = j0 + k as i64;
        let dead = hit.as_ref().is_some_and(|hit| !hit[k]);
        let span = if j < jlo || j > jhi || dead {
            (0, 0)
        } else {
            row_span(&fwd, t, h, j)
        };
        spans.push(span);
        offs.push(total);
        total += span.1;
    }
    // Every column meets the image on at most h + 1 sheared rows.
    debug_assert!(total <= w * (h + 1));
    let mut data = super::pool::take_for(name, total * CO)?;
    // One mutable slice per row, then the rows in parallel.
    let mut parts: Vec<(&mut (usize, usize), &mut [f32])> = Vec::new();
    parts.try_reserve_exact(rows).map_err(|_| {
        Error::value(
            name,
            format!("is too large to filter ({rows} sheared rows)"),
        )
    })?;
    let mut rest: &mut [f32] = &mut data;
    for span in spans.iter_mut() {
        let (head, tail) = rest.split_at_mut(span.1 * CO);
        parts.push((span, head));
        rest = tail;
    }
    parts.par_iter_mut().enumerate().for_each_init(
        || (vec![0.0f32; w * CI], S::default()),
        |(row, s), (k, (span, o))| {
            let (x0, n) = **span;
            if n == 0 {
                return;
            }
            let j = j0 + k as i64;
            let row = &mut row[..n * CI];
            shear_row::<CI>(src, w, h, &fwd, j, (x0, n), row);
            if !f(row, n, o, s) {
                span.1 = 0;
            }
        },
    );
    Ok(Sheared {
        data,
        spans,
        offs,
        j0,
        back,
    })
}
