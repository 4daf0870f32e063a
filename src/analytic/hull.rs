//! The swept hull of a prim: the convex hull of its corners' six end positions, which rows of
//! samples it reaches inside a tile, and whether it overlaps a tile at all.
//!
//! Only samples inside the hull are tested against a prim (`tiles.rs`), so these bounds must be
//! conservative: every bound here is grown by a margin larger than its rounding.
use super::poly::{ceil_i64, floor_i64};

/// Hull points are single precision, `n` of them (0 for prims without a hull).
pub type Hull = [[f32; 2]; 6];

/// Convex hull (counter-clockwise in a y-up sense, i.e. clockwise on screen) of six points, in
/// single precision, grown by a hair so that rounding never drops a covered sample.
pub fn convex_hull(pts: &[[f64; 2]; 6]) -> (Hull, u8) {
    let mut p = *pts;
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let turn = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    // Andrew's monotone chain on a stack array (at most 6 + 5 points before the last pop)
    let mut h = [[0.0f64; 2]; 12];
    let mut m = 0;
    for &q in p.iter() {
        while m >= 2 && turn(h[m - 2], h[m - 1], q) <= 0.0 {
            m -= 1;
        }
        h[m] = q;
        m += 1;
    }
    let lower = m + 1;
    for &q in p.iter().rev().skip(1) {
        while m >= lower && turn(h[m - 2], h[m - 1], q) <= 0.0 {
            m -= 1;
        }
        h[m] = q;
        m += 1;
    }
    m -= 1;
    let mut out = [[0.0f32; 2]; 6];
    let n = m.min(6);
    for (o, q) in out.iter_mut().zip(&h[..m]) {
        *o = [q[0] as f32, q[1] as f32];
    }
    (out, n as u8)
}

/// How far a row's span may reach past the hull's boundary points found near the row's centre.
const EPS: f64 = 1e-3;

/// The rows `r` (centre `y0 + r + 0.5`, `r < rows`) in which the hull can reach a sample column
/// of `[bx0, bx1)`: rows whose centre lies near the part of the hull inside that vertical strip
/// (grown by more than `row_spans`'s margins). Every row outside gets no columns from
/// [`row_spans`], so a tile skips them without changing what it tests.
fn strip_rows(hull: &[[f32; 2]], y0: i32, bx0: i32, bx1: i32, rows: usize) -> (usize, usize) {
    let big = hull
        .iter()
        .map(|p| f64::from(p[0].abs().max(p[1].abs())))
        .fold(0.0f64, f64::max);
    // `row_spans` widens a row by at most EPS + 1e-6 * |x|; this is wider than that.
    let m = 0.01 + 2e-6 * big;
    let (xl, xh) = (f64::from(bx0) + 0.5 - m, f64::from(bx1) - 0.5 + m);
    let (mut ylo, mut yhi) = (f64::MAX, f64::MIN);
    let n = hull.len();
    for i in 0..n {
        let p = hull[i].map(f64::from);
        let q = hull[(i + 1) % n].map(f64::from);
        let (a, b) = (p[0].min(q[0]), p[0].max(q[0]));
        if b < xl || a > xh {
            continue;
        }
        let (ca, cb) = (a.max(xl), b.min(xh));
        let (ya, yb) = if q[0] == p[0] {
            (p[1], q[1])
        } else {
            let y = |x: f64| p[1] + (x - p[0]) / (q[0] - p[0]) * (q[1] - p[1]);
            (y(ca), y(cb))
        };
        ylo = ylo.min(ya.min(yb));
        yhi = yhi.max(ya.max(yb));
    }
    if ylo > yhi {
        return (0, 0);
    }
    let d = m + EPS;
    let r0 = (ceil_i64(ylo - d - f64::from(y0) - 0.5).max(0) as usize).min(rows);
    let r1 = (floor_i64(yhi + d - f64::from(y0) - 0.5)
        .saturating_add(1)
        .max(0) as usize)
        .min(rows);
    (r0, r1.max(r0))
}

/// The sample columns `[x0, x1)` that the hull reaches in each sample row `y0 + r` (centre
/// `y0 + r + 0.5`) within `[bx0, bx1)`, for `r` in the returned range `r0..r1` (a sub-range of
/// `0..out.len()`; rows outside it reach none and are not written). `(0, 0)` where a row in the
/// range reaches none. An empty hull (prims that clip) reaches every column. One pass over the
/// hull's edges (each touches only the rows it spans).
#[inline(always)]
pub fn row_spans(
    hull: &[[f32; 2]],
    y0: i32,
    bx0: i32,
    bx1: i32,
    out: &mut [(i32, i32)],
) -> (usize, usize) {
    let rows = out.len();
    if hull.is_empty() {
        out.fill((bx0, bx1));
        return (0, rows);
    }
    let (ra, rb) = strip_rows(hull, y0, bx0, bx1, rows);
    if ra >= rb {
        return (0, 0);
    }
    rows_in(hull, y0, bx0, bx1, out, ra, rb);
    (ra, rb)
}

/// [`row_spans`] for the rows `ra..rb` only.
fn rows_in(
    hull: &[[f32; 2]],
    y0: i32,
    bx0: i32,
    bx1: i32,
    out: &mut [(i32, i32)],
    ra: usize,
    rb: usize,
) {
    let rows = out.len();
    let mut lo = [f64::MAX; 64];
    let mut hi = [f64::MIN; 64];
    debug_assert!(rows <= 64);
    let n = hull.len();
    let yc = |r: usize| f64::from(y0) + r as f64 + 0.5;
    // rows whose centre lies in [a, b], within ra..rb
    let row_range = |a: f64, b: f64| {
        let r0 = ceil_i64(a - f64::from(y0) - 0.5).max(0) as usize;
        let r1 = (floor_i64(b - f64::from(y0) - 0.5).saturating_add(1).max(0) as usize).min(rows);
        let r0 = r0.max(ra);
        r0..r1.min(rb).max(r0.min(rb))
    };
    for i in 0..n {
        let p = hull[i].map(f64::from);
        let q = hull[(i + 1) % n].map(f64::from);
        let (ya, yb) = if p[1] <= q[1] {
            (p[1], q[1])
        } else {
            (q[1], p[1])
        };
        let flat = (q[1] - p[1]).abs() < 1e-12;
        for r in row_range(ya - EPS, yb + EPS) {
            let (xl, xh) = if flat {
                (p[0].min(q[0]), p[0].max(q[0]))
            } else {
                let u = ((yc(r) - p[1]) / (q[1] - p[1])).clamp(0.0, 1.0);
                let x = p[0] + u * (q[0] - p[0]);
                (x, x)
            };
            lo[r] = lo[r].min(xl);
            hi[r] = hi[r].max(xh);
        }
    }
    for r in ra..rb {
        let (l, h) = (lo[r], hi[r]);
        if l > h {
            out[r] = (0, 0);
            continue;
        }
        let margin = EPS + 1e-6 * l.abs().max(h.abs());
        let x0 = ceil_i64(l - margin - 0.5).clamp(bx0 as i64, bx1 as i64) as i32;
        let x1 = floor_i64(h + margin - 0.5)
            .saturating_add(1)
            .clamp(bx0 as i64, bx1 as i64) as i32;
        out[r] = (x0, x1.max(x0));
    }
}

/// A prim's hull set up for overlap tests against many tiles: each edge's start, direction and
/// threshold (the separating-axis test of [`Separator::overlaps`]), computed once.
pub struct Separator {
    bbox: [i32; 4],
    n: usize,
    /// Per edge: start point, direction, and `-1e-3 * length`.
    edges: [[f64; 5]; 6],
    /// 1 or -1: the hull's orientation, so "outside" is known for either winding.
    sgn: f64,
}

impl Separator {
    /// Sets up the hull `hull` with the sample bounds `bbox`.
    pub fn new(bbox: [i32; 4], hull: &[[f32; 2]]) -> Self {
        let n = hull.len();
        let mut edges = [[0.0; 5]; 6];
        let mut area = 0.0;
        for i in 0..n {
            let p = hull[i].map(f64::from);
            let q = hull[(i + 1) % n].map(f64::from);
            area += p[0] * q[1] - q[0] * p[1];
            let (ex, ey) = (q[0] - p[0], q[1] - p[1]);
            let len = (ex * ex + ey * ey).sqrt();
            edges[i] = [p[0], p[1], ex, ey, -1e-3 * len];
        }
        let sgn = if area >= 0.0 { 1.0 } else { -1.0 };
        Separator {
            bbox,
            n,
            edges,
            sgn,
        }
    }

    /// True when the hull may overlap the sample rectangle `[x0, x1) x [y0, y1)`.
    pub fn overlaps(&self, x0: i32, y0: i32, x1: i32, y1: i32) -> bool {
        let b = self.bbox;
        if b[0] >= x1 || b[2] <= x0 || b[1] >= y1 || b[3] <= y0 {
            return false;
        }
        if self.n < 3 {
            return true;
        }
        // Separating axis along each hull edge's outward normal (sample centres: +0.5).
        let corners = [
            [f64::from(x0) + 0.5, f64::from(y0) + 0.5],
            [f64::from(x1) - 0.5, f64::from(y0) + 0.5],
            [f64::from(x0) + 0.5, f64::from(y1) - 0.5],
            [f64::from(x1) - 0.5, f64::from(y1) - 0.5],
        ];
        for &[px, py, ex, ey, thr] in &self.edges[..self.n] {
            let all_out = corners
                .iter()
                .all(|c| self.sgn * (ex * (c[1] - py) - ey * (c[0] - px)) < thr);
            if all_out {
                return false;
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Row spans of every row, without the strip cut.
    fn spans_everywhere(
        hull: &[[f32; 2]],
        y0: i32,
        bx0: i32,
        bx1: i32,
        rows: usize,
    ) -> Vec<(i32, i32)> {
        let mut all = vec![(0, 0); rows];
        rows_in(hull, y0, bx0, bx1, &mut all, 0, rows);
        all
    }

    #[test]
    fn the_strip_cut_drops_only_rows_that_reach_no_column() {
        // a thin diagonal sliver (a small triangle's sweep) and a fat quad, across tiles
        let hulls: [&[[f32; 2]]; 3] = [
            &[
                [3.2, 10.1],
                [4.0, 9.5],
                [150.7, 58.3],
                [151.2, 59.4],
                [149.9, 59.9],
            ],
            &[[-40.0, -7.5], [90.25, 2.0], [70.0, 95.5], [-10.0, 60.0]],
            &[[20.5, 20.5], [20.5, 40.5]],
        ];
        for hull in hulls {
            for ty in 0..4 {
                for tx in 0..6 {
                    let (x0, y0) = (tx * 32, ty * 32 - 8);
                    let mut out = [(0, 0); 32];
                    let (a, b) = row_spans(hull, y0, x0, x0 + 32, &mut out);
                    let want = spans_everywhere(hull, y0, x0, x0 + 32, 32);
                    for r in 0..32 {
                        let got = if r >= a && r < b { out[r] } else { (0, 0) };
                        let (g, w) = (got.1 > got.0, want[r].1 > want[r].0);
                        assert_eq!(g, w, "row {r} of tile {tx},{ty}");
                        if w {
                            assert_eq!(got, want[r], "row {r} of tile {tx},{ty}");
                        }
                    }
                }
            }
        }
    }
}
