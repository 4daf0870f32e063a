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
pub(crate) fn shear_row<const C: usize>(
    img: &[f32],
    w: usize,
    h: usize,
    phase: &Phase,
    j: i64,
    out: &mut [f32],
) {
    for x in 0..w {
        let y0 = j + phase.floor[x];
        let f = phase.frac[x];
        let o = &mut out[x * C..x * C + C];
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

/// Output row `y` of the un-sheared image from sheared rows `j0 ..` (`used[k]`: row `j0 + k`
/// holds anything): `out[x]` interpolates sheared rows `floor(y - x t - c0)` and the next one at
/// column `x` (`phase` from `Phase::new(w, t, c0, -1.0)`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn unshear_row<const C: usize>(
    sheared: &[f32],
    used: &[bool],
    w: usize,
    j0: i64,
    phase: &Phase,
    y: usize,
    out: &mut [f32],
) {
    let rows = used.len() as i64;
    for x in 0..w {
        let i = y as i64 + phase.floor[x] - j0;
        let f = phase.frac[x];
        let o = &mut out[x * C..x * C + C];
        let ua = i >= 0 && i < rows && used[i as usize];
        let ub = i + 1 >= 0 && i + 1 < rows && used[(i + 1) as usize];
        if ua && ub {
            let a = &sheared[(i as usize * w + x) * C..][..C];
            let b = &sheared[((i + 1) as usize * w + x) * C..][..C];
            for c in 0..C {
                o[c] = (1.0 - f) * a[c] + f * b[c];
            }
            continue;
        }
        o.fill(0.0);
        if ua {
            let p = &sheared[(i as usize * w + x) * C..][..C];
            for c in 0..C {
                o[c] += (1.0 - f) * p[c];
            }
        }
        if ub {
            let p = &sheared[((i + 1) as usize * w + x) * C..][..C];
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
    img: &[f32],
    w: usize,
    h: usize,
    plan: &LinePlan,
    f: impl Fn(&[f32], usize, &mut [f32], &mut S) -> bool + Sync + Send,
) -> Vec<f32> {
    directional_at::<CI, CO, S>(img, w, h, plan, 0.0, None, f)
}

/// `directional` on a crop whose first major-axis pixel is pixel `major_offset` of the full
/// image, so that the shear samples the same positions as on the full image. `live`: the
/// inclusive box `(x0, x1, y0, y1)` outside of which `f` would see nothing (its rows are all
/// zero): sheared rows that miss it are neither built nor filtered.
pub(crate) fn directional_at<const CI: usize, const CO: usize, S: Default + Send>(
    img: &[f32],
    w: usize,
    h: usize,
    plan: &LinePlan,
    major_offset: f64,
    live: Option<[usize; 4]>,
    f: impl Fn(&[f32], usize, &mut [f32], &mut S) -> bool + Sync + Send,
) -> Vec<f32> {
    let live = live.map(|[x0, x1, y0, y1]| {
        if plan.transpose {
            [y0, y1, x0, x1]
        } else {
            [x0, x1, y0, y1]
        }
    });
    let (src, w2, h2): (Cow<[f32]>, usize, usize) = if plan.transpose {
        (Cow::Owned(transpose::<CI>(img, w, h)), h, w)
    } else {
        (Cow::Borrowed(img), w, h)
    };
    let mut out = super::pool::take(w2 * h2 * CO);
    if plan.slope == 0.0 {
        out.par_chunks_mut(w2 * CO)
            .zip(src.par_chunks(w2 * CI))
            .for_each_init(S::default, |s, (o, i)| {
                if !f(i, w2, o, s) {
                    o.fill(0.0);
                }
            });
    } else {
        let sh = build_sheared::<CI, CO, S>(&src, w2, h2, plan.slope, major_offset, live, &f);
        out.par_chunks_mut(w2 * CO)
            .enumerate()
            .for_each(|(y, o)| sh.unshear_row(w2, y, o));
        super::pool::give(sh.data);
    }
    if plan.transpose {
        transpose::<CO>(&out, w2, h2)
    } else {
        out
    }
}

/// A filtered sheared image: rows `j0 ..`, `used[k]` when row `j0 + k` holds anything.
pub(crate) struct Sheared<const CO: usize> {
    pub(crate) data: Vec<f32>,
    used: Vec<bool>,
    j0: i64,
    back: Phase,
}

impl<const CO: usize> Sheared<CO> {
    /// Output row `y` of the image the sheared rows came from (see `unshear_row`).
    pub(crate) fn unshear_row(&self, w: usize, y: usize, out: &mut [f32]) {
        unshear_row::<CO>(&self.data, &self.used, w, self.j0, &self.back, y, out);
    }
}

/// Shears a `(h, w, CI)` image with slope `t` (see the module docs; `major_offset` and `live` as
/// in `directional_at`, `live` already in this orientation) and runs the row filter `f` on every
/// sheared row that can meet the live box.
pub(crate) fn build_sheared<const CI: usize, const CO: usize, S: Default + Send>(
    src: &[f32],
    w: usize,
    h: usize,
    t: f64,
    major_offset: f64,
    live: Option<[usize; 4]>,
    f: &(impl Fn(&[f32], usize, &mut [f32], &mut S) -> bool + Sync + Send),
) -> Sheared<CO> {
    let c0 = (major_offset * t).rem_euclid(1.0);
    let (j0, rows) = shear_range(w, h, t, c0);
    let fwd = Phase::new(w, t, c0, 1.0);
    let back = Phase::new(w, t, c0, -1.0);
    let mut data = super::pool::take(rows * w * CO);
    let mut used = vec![false; rows];
    // Sheared rows that can meet the live box: j + x t + c0 in (y0 - 1, y1 + 1), x in [x0, x1].
    let (jlo, jhi) = match live {
        Some([x0, x1, y0, y1]) => {
            let (ua, ub) = (x0 as f64 * t + c0, x1 as f64 * t + c0);
            (
                (y0 as f64 - 1.0 - ua.max(ub)).floor() as i64,
                (y1 as f64 + 1.0 - ua.min(ub)).ceil() as i64,
            )
        }
        None => (i64::MIN, i64::MAX),
    };
    data.par_chunks_mut(w * CO)
        .zip(used.par_iter_mut())
        .enumerate()
        .for_each_init(
            || (vec![0.0f32; w * CI], S::default()),
            |(row, s), (k, (o, u))| {
                let j = j0 + k as i64;
                if j < jlo || j > jhi {
                    return;
                }
                shear_row::<CI>(src, w, h, &fwd, j, row);
                *u = f(row, w, o, s);
            },
        );
    Sheared {
        data,
        used,
        j0,
        back,
    }
}
