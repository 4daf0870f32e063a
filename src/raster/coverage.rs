//! Fixed-point coverage: which samples a set-up triangle covers.
//!
//! Screen coordinates are snapped to 1/256 of a sample (8 sub-pixel bits) and every coverage
//! decision is exact integer arithmetic on the snapped corners. A sample is inside when its three
//! edge functions are all >= 0 after the top-left bias. With the triangle oriented clockwise on
//! screen (positive area, y down), an edge is *top* when horizontal and running right, *left*
//! when running up; samples exactly on such an edge belong to the triangle, samples exactly on
//! other edges do not. Two triangles that share an edge see it with opposite directions, so
//! exactly one of them owns a sample on it: no gaps (seams) and no double hits.
//!
//! The set-up (`setup.rs`) uses `Edges::covered_box` to shrink the box of a small triangle to
//! the samples it covers (or to drop it when it covers none); the tiles (`tile.rs`) walk the
//! covered samples row by row with `Edges::spans`.

/// Sub-pixel bits of the fixed-point screen coordinates.
pub const SUBPIXEL_BITS: u32 = 8;
/// One sample in fixed point.
pub const ONE: i64 = 1 << SUBPIXEL_BITS;
/// Half a sample: sample centres sit at +0.5.
pub const HALF: i64 = ONE / 2;

/// Edge functions of a triangle, ready to walk samples.
#[derive(Clone, Copy)]
pub struct Edges {
    /// Value change per sample step in x and in y.
    dx: [i64; 3],
    dy: [i64; 3],
    /// 1 for edges that are not top-left (their samples are excluded), else 0.
    bias: [i64; 3],
    x: [i64; 3],
    y: [i64; 3],
}

impl Edges {
    /// The edges of the triangle with fixed-point corners `x`, `y` (positive area, y down).
    #[inline]
    pub fn new(x: [i32; 3], y: [i32; 3]) -> Self {
        let x = x.map(i64::from);
        let y = y.map(i64::from);
        let mut e = Edges {
            dx: [0; 3],
            dy: [0; 3],
            bias: [0; 3],
            x,
            y,
        };
        for k in 0..3 {
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            let (ex, ey) = (x[j] - x[i], y[j] - y[i]);
            e.dx[k] = -ey;
            e.dy[k] = ex;
            let top = ey == 0 && ex > 0;
            let left = ey < 0;
            e.bias[k] = if top || left { 0 } else { 1 };
        }
        e
    }

    /// Unbiased edge values at the centre of sample (ix, iy).
    #[inline]
    pub fn at(&self, ix: i32, iy: i32) -> [i64; 3] {
        let px = i64::from(ix) * ONE + HALF;
        let py = i64::from(iy) * ONE + HALF;
        [0, 1, 2].map(|k| {
            let i = (k + 1) % 3;
            self.dx[k] * (px - self.x[i]) + self.dy[k] * (py - self.y[i])
        })
    }

    /// Calls `f(ix, iy)` for every covered sample in the box, row by row, left to right.
    #[inline]
    pub fn cover(&self, bx: [i32; 4], mut f: impl FnMut(i32, i32)) {
        self.spans(bx, |iy, x0, x1| {
            for ix in x0..=x1 {
                f(ix, iy);
            }
        });
    }

    /// The inclusive box of the samples covered inside `bx`, None when none is.
    #[inline]
    pub fn covered_box(&self, bx: [i32; 4]) -> Option<[i32; 4]> {
        let mut b = [i32::MAX, i32::MAX, i32::MIN, i32::MIN];
        self.spans(bx, |iy, x0, x1| {
            b[0] = b[0].min(x0);
            b[1] = b[1].min(iy);
            b[2] = b[2].max(x1);
            b[3] = iy;
        });
        (b[0] <= b[2]).then_some(b)
    }

    /// Calls `f(iy, x0, x1)` for every row of the box holding covered samples, top to bottom,
    /// with the covered samples x0..=x1 of the row.
    ///
    /// Each edge function is affine along a row, so the covered samples of a row form one span
    /// whose ends follow from exact integer division; boxes wider than `SPAN_MIN` samples compute
    /// the span (long thin triangles, such as a motion volume's swept sides, have large boxes and
    /// few covered samples), narrower ones test every sample. Both give exactly the samples whose
    /// three biased edge values are >= 0.
    #[inline]
    pub fn spans(&self, bx: [i32; 4], mut f: impl FnMut(i32, i32, i32)) {
        let mut row = self.at(bx[0], bx[1]);
        for k in 0..3 {
            row[k] -= self.bias[k];
        }
        let sx = self.dx.map(|d| d * ONE);
        let sy = self.dy.map(|d| d * ONE);
        let last = i64::from(bx[2] - bx[0]);
        for iy in bx[1]..=bx[3] {
            let (lo, hi) = if last >= SPAN_MIN {
                span(row, sx, last)
            } else {
                scan(row, sx, last)
            };
            if lo <= hi {
                f(iy, bx[0] + lo as i32, bx[0] + hi as i32);
            }
            row[0] += sy[0];
            row[1] += sy[1];
            row[2] += sy[2];
        }
    }
}

/// `span` by testing every step: the first and last steps where all three values are >= 0
/// (the covered steps between them are all covered, the set being an interval).
#[inline]
fn scan(mut e: [i64; 3], d: [i64; 3], last: i64) -> (i64, i64) {
    let (mut lo, mut hi) = (i64::MAX, -1);
    for i in 0..=last {
        if (e[0] | e[1] | e[2]) >= 0 {
            lo = lo.min(i);
            hi = i;
        }
        e[0] += d[0];
        e[1] += d[1];
        e[2] += d[2];
    }
    (lo, hi)
}

/// Boxes at least this many samples wide (minus one) are walked by spans.
const SPAN_MIN: i64 = 8;

/// The steps i in [0, last] where `e[k] + i * d[k] >= 0` for every edge k, as an inclusive range
/// (empty when lo > hi).
#[inline]
fn span(e: [i64; 3], d: [i64; 3], last: i64) -> (i64, i64) {
    let (mut lo, mut hi) = (0i64, last);
    for k in 0..3 {
        let (e, d) = (e[k], d[k]);
        if d > 0 {
            if e < 0 {
                // first i with e + i d >= 0: ceil(-e / d)
                let a = -e;
                lo = lo.max(a / d + i64::from(a % d != 0));
            }
        } else if d < 0 {
            // last i with e + i d >= 0: floor(e / -d), none when e < 0
            hi = if e < 0 { -1 } else { hi.min(e / -d) };
        } else if e < 0 {
            hi = -1;
        }
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every sample of the box tested on its own.
    fn brute(e: &Edges, bx: [i32; 4]) -> Vec<(i32, i32)> {
        let mut out = Vec::new();
        for iy in bx[1]..=bx[3] {
            for ix in bx[0]..=bx[2] {
                let v = e.at(ix, iy);
                if (0..3).all(|k| v[k] - e.bias[k] >= 0) {
                    out.push((ix, iy));
                }
            }
        }
        out
    }

    /// Reproducible triangles (slivers and axis-aligned edges included), oriented as set up,
    /// with a box around each.
    fn triangles(count: usize) -> Vec<(Edges, [i32; 4])> {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = |m: i32| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % m as u64) as i32
        };
        (0..count)
            .map(|n| {
                let scale = [ONE as i32 * 70, ONE as i32 * 8, 3 * ONE as i32][n % 3];
                let mut x = [0; 3].map(|_| next(scale) - scale / 8);
                let mut y = [0; 3].map(|_| next(scale) - scale / 8);
                if n % 7 == 0 {
                    y[1] = y[0]; // a horizontal edge
                }
                if n % 11 == 0 {
                    x[2] = x[1]; // a vertical edge
                }
                let area = i64::from(x[1] - x[0]) * i64::from(y[2] - y[0])
                    - i64::from(x[2] - x[0]) * i64::from(y[1] - y[0]);
                if area < 0 {
                    x.swap(1, 2);
                    y.swap(1, 2);
                }
                let bx = [next(5) - 2, next(5) - 2, next(70), next(70)];
                (Edges::new(x, y), bx)
            })
            .collect()
    }

    #[test]
    fn spans_visit_exactly_the_covered_samples_in_order() {
        let mut covered = 0;
        for (e, bx) in triangles(4000) {
            let mut got = Vec::new();
            e.cover(bx, |ix, iy| got.push((ix, iy)));
            let want = brute(&e, bx);
            covered += want.len();
            assert_eq!(got, want, "box {bx:?}");
        }
        assert!(covered > 10_000, "the test triangles must cover samples");
    }

    #[test]
    fn the_covered_box_holds_every_covered_sample_and_is_tight() {
        let (mut none, mut some) = (0, 0);
        for (e, bx) in triangles(4000) {
            let want = brute(&e, bx);
            match e.covered_box(bx) {
                None => {
                    assert!(want.is_empty());
                    none += 1;
                }
                Some(b) => {
                    some += 1;
                    assert_eq!(brute(&e, b), want, "the samples of {bx:?} are all in {b:?}");
                    let xs = want.iter().map(|p| p.0);
                    let ys = want.iter().map(|p| p.1);
                    let tight = [
                        xs.clone().min().unwrap(),
                        ys.clone().min().unwrap(),
                        xs.max().unwrap(),
                        ys.max().unwrap(),
                    ];
                    assert_eq!(b, tight);
                }
            }
        }
        assert!(none > 100 && some > 1000, "{none} {some}");
    }
}
