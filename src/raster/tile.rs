//! Coverage and the two passes of one screen tile.
//!
//! Coverage: a sample is inside when its three fixed-point edge functions are all >= 0 after
//! the top-left bias. With the triangle oriented clockwise on screen (positive area, y down), an
//! edge is *top* when horizontal and running right, *left* when running up; samples exactly on
//! such an edge belong to the triangle, samples exactly on other edges do not. Two triangles
//! that share an edge see it with opposite directions, so exactly one of them owns a sample on
//! it: no gaps (seams) and no double hits.
//!
//! Pass 1 (opaque) keeps the nearest opaque fragment of each sample in a visibility buffer
//! (1/w and a triangle reference), and shades only the winners. Pass 2 (transparent) collects
//! the transparent fragments in front of the opaque surface; `blend.rs` composites them.
use super::background::Background;
use super::bins::TILE;
use super::blend::{Frag, FragLists, Sample};
use super::interp::Planes;
use super::options::Blend;
use super::setup::{Tri, HALF, MAY_OPAQUE, MAY_TRANSPARENT, ONE};
use super::shade::{Shader, TriShade};

const NONE: u32 = u32::MAX;

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
    #[inline]
    pub fn new(t: &Tri) -> Self {
        let x = t.x.map(i64::from);
        let y = t.y.map(i64::from);
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

/// Reusable per-thread buffers of a tile.
pub struct TileScratch {
    pub zbuf: Vec<f32>,
    winner: Vec<u32>,
    pub samples: Vec<Sample>,
    frags: FragLists,
}

impl Default for TileScratch {
    fn default() -> Self {
        let n = (TILE * TILE) as usize;
        TileScratch {
            zbuf: vec![0.0; n],
            winner: vec![NONE; n],
            samples: vec![Sample::BACKGROUND; n],
            frags: FragLists::default(),
        }
    }
}

impl TileScratch {
    /// Releases fragment-list memory beyond what a thread keeps between tiles.
    pub fn trim(&mut self) {
        self.frags.trim();
    }
}

/// Renders the samples `rect` = [x0, y0, x1, y1) of a tile from its triangle references (in
/// submission order) into `scratch.samples` (row stride TILE), starting from `bg` when given
/// (else from the empty background). Returns the fragment count, and whether `bg` holds a bad
/// value in the rectangle (`Background::load`).
pub fn render_tile(
    rect: [i32; 4],
    refs: &[u32],
    sh: &Shader,
    blend: Blend,
    bg: Option<&Background>,
    scratch: &mut TileScratch,
) -> (u64, bool) {
    let [tx0, ty0, tx1, ty1] = rect;
    let clamp = |t: &Tri| {
        [
            t.bbox[0].max(tx0),
            t.bbox[1].max(ty0),
            t.bbox[2].min(tx1 - 1),
            t.bbox[3].min(ty1 - 1),
        ]
    };
    let local = |ix: i32, iy: i32| ((iy - ty0) * TILE + (ix - tx0)) as usize;
    let TileScratch {
        zbuf,
        winner,
        samples,
        frags,
    } = scratch;
    let bad_background = match bg {
        // Samples outside `rect` are never read back; the opaque pass only touches `rect`.
        Some(bg) => bg.load(rect, zbuf, samples),
        None => {
            zbuf.fill(0.0);
            false
        }
    };
    let mut fragments = 0u64;
    let mut any_transparent = false;
    // Whether a triangle that may be opaque reaches the tile (`winner` is reset then only).
    let mut any_opaque = false;

    // Pass 1: opaque fragments, nearest wins (strictly nearer: the first submitted keeps ties).
    for &r in refs {
        let t = sh.tri(r);
        any_transparent |= t.flags & MAY_TRANSPARENT != 0;
        if t.flags & MAY_OPAQUE == 0 {
            continue;
        }
        let bx = clamp(t);
        if bx[0] > bx[2] || bx[1] > bx[3] {
            continue;
        }
        if !any_opaque {
            winner.fill(NONE);
            any_opaque = true;
        }
        let edges = Edges::new(t);
        let planes = Planes::new(t);
        // only a triangle that may also be transparent needs its alpha per sample
        let mixed = (t.flags & MAY_TRANSPARENT != 0).then(|| sh.prepare(r));
        edges.cover(bx, |ix, iy| {
            fragments += 1;
            if let Some(ts) = &mixed {
                if ts.alpha(ts.lambdas(&planes, ix, iy)) < 1.0 {
                    return;
                }
            }
            let z = planes.invw(ix, iy) as f32;
            let s = local(ix, iy);
            if z > zbuf[s] {
                zbuf[s] = z;
                winner[s] = r;
            }
        });
    }

    // Shade the opaque winners (neighbouring samples mostly share a triangle: keep its planes).
    // Without opaque triangles every sample keeps the background.
    if !any_opaque {
        if bg.is_none() {
            for iy in ty0..ty1 {
                let row = local(tx0, iy);
                samples[row..row + (tx1 - tx0) as usize].fill(Sample::BACKGROUND);
            }
        }
    } else {
        let mut cached = (NONE, None::<(Planes, TriShade)>);
        for iy in ty0..ty1 {
            for ix in tx0..tx1 {
                let s = local(ix, iy);
                let r = winner[s];
                if r == NONE && bg.is_some() {
                    continue; // the background sample loaded above stays
                }
                samples[s] = if r == NONE {
                    Sample::BACKGROUND
                } else {
                    if cached.0 != r {
                        cached = (r, Some((Planes::new(sh.tri(r)), sh.prepare(r))));
                    }
                    let (planes, ts) = cached.1.as_ref().expect("set above");
                    let sh = ts.shade(ts.lambdas(planes, ix, iy));
                    Sample {
                        rgba: sh.rgba,
                        invw: zbuf[s],
                        id: sh.id,
                        velocity: sh.velocity,
                    }
                };
            }
        }
    }
    if !any_transparent {
        return (fragments, bad_background);
    }

    // Pass 2: transparent fragments in front of the opaque surface.
    frags.clear((TILE * TILE) as usize);
    for &r in refs {
        let t = sh.tri(r);
        if t.flags & MAY_TRANSPARENT == 0 {
            continue;
        }
        let bx = clamp(t);
        if bx[0] > bx[2] || bx[1] > bx[3] {
            continue;
        }
        let edges = Edges::new(t);
        let planes = Planes::new(t);
        let mixed = t.flags & MAY_OPAQUE != 0;
        let ts = sh.prepare(r);
        edges.spans(bx, |iy, x0, x1| {
            for ix in x0..=x1 {
                let s = local(ix, iy);
                let z = planes.invw(ix, iy) as f32;
                if z <= zbuf[s] {
                    continue;
                }
                let lam = ts.lambdas(&planes, ix, iy);
                if mixed && ts.alpha(lam) >= 1.0 {
                    continue;
                }
                fragments += 1;
                let shaded = ts.shade(lam);
                if shaded.rgba[3] > 0.0 {
                    frags.push(Frag {
                        sample: s as u32,
                        invw: z,
                        shaded,
                    });
                }
            }
        });
    }
    frags.composite(&mut samples[..(TILE * TILE) as usize], blend);
    (fragments, bad_background)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Edges of the triangle with fixed-point corners (x, y), as `Edges::new` builds them.
    fn edges(x: [i32; 3], y: [i32; 3]) -> Edges {
        let mut e = Edges {
            dx: [0; 3],
            dy: [0; 3],
            bias: [0; 3],
            x: x.map(i64::from),
            y: y.map(i64::from),
        };
        for k in 0..3 {
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            let (ex, ey) = (e.x[j] - e.x[i], e.y[j] - e.y[i]);
            e.dx[k] = -ey;
            e.dy[k] = ex;
            e.bias[k] = if (ey == 0 && ex > 0) || ey < 0 { 0 } else { 1 };
        }
        e
    }

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

    #[test]
    fn spans_visit_exactly_the_covered_samples_in_order() {
        // xorshift: reproducible corners, slivers and axis-aligned edges included
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = |m: i32| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % m as u64) as i32
        };
        let mut covered = 0;
        for n in 0..4000 {
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
            let e = edges(x, y);
            let bx = [next(5) - 2, next(5) - 2, next(70), next(70)];
            let mut got = Vec::new();
            e.cover(bx, |ix, iy| got.push((ix, iy)));
            let want = brute(&e, bx);
            covered += want.len();
            assert_eq!(got, want, "triangle {x:?} {y:?} box {bx:?}");
        }
        assert!(covered > 10_000, "the test triangles must cover samples");
    }
}
