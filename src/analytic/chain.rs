//! The fragments of one pass over a tile, as its prims' covered spans are found: a span at a
//! sample becomes a new fragment, or the next link of the chain of the fragment found last at
//! that sample when it continues it (the same surface, the neighbouring triangle, touching in
//! time with the depths meeting). Prims come ordered along their motion (`frame.rs`), so the
//! triangles of one surface passing over a sample arrive one after the other and chain; each
//! link keeps its triangle and its depth, so a chain resolves and shades exactly as its
//! separate spans would, with fewer layers to sort.
use super::prim::{Edges, SampleEdges, OPAQUE};
use super::shade::TilePrim;
use super::visibility::{Frag, Link, Overflow, BACK, NONE};

/// The current prim and its segment, as its spans are recorded.
pub struct SpanOf<'a> {
    /// The prim, set up for the tile.
    pub tp: &'a TilePrim,
    /// The prim's index among the pass's prims (`TileScratch::prims` in `tiles.rs`).
    pub li: u32,
    /// The segment's start and length in shutter time.
    pub t0: f64,
    pub dt: f64,
    /// Spans recorded for the prim so far.
    pub spans: u64,
}

/// Two spans join into one chain only where their depths meet at the shared instant (the same
/// surface point seen by both triangles), within this fraction of the depth.
const CHAIN_DEPTH_TOLERANCE: f32 = 1e-4;

/// Fragments and links found in one pass, and each sample's last fragment.
#[derive(Default)]
pub struct Found {
    /// Fragments in the order they are found, with their sample's index in the tile.
    pub raw: Vec<(u32, Frag)>,
    /// The links of every fragment's chain.
    pub links: Vec<Link>,
    /// Per sample: the fragment found last (index in `raw`) and the last link of its chain.
    tail: Vec<(u32, u32)>,
}

impl Found {
    /// Empties the lists for a pass over `samples` samples.
    pub fn clear(&mut self, samples: usize) {
        self.raw.clear();
        self.links.clear();
        self.tail.clear();
        self.tail.resize(samples, (NONE, NONE));
    }

    /// Makes room for `n` more spans without allocating in [`Found::add_span`], or fails.
    pub fn reserve(&mut self, n: usize) -> Result<(), Overflow> {
        self.raw.try_reserve(n).map_err(|_| Overflow)?;
        self.links.try_reserve(n).map_err(|_| Overflow)
    }

    /// Records the span `[a, b]` (local time) of the current prim at tile sample `j` (its
    /// edges there `q`), with `flag` (`BACK` for a back-facing span): joined to the sample's last
    /// fragment when it continues it, else a new fragment.
    #[inline(always)]
    pub fn add_span(
        &mut self,
        prims: &[TilePrim],
        span: &mut SpanOf,
        (q, j): (&SampleEdges, usize),
        [a, b]: [f64; 2],
        flag: u32,
    ) {
        let (t0, t1) = (
            (span.t0 + a * span.dt) as f32,
            (span.t0 + b * span.dt) as f32,
        );
        if !(t1 > t0) {
            return;
        }
        span.spans += 1;
        let tp = span.tp;
        let e = &tp.edges;
        let f = Frag {
            t0,
            t1,
            z0: depth_near(e, q, a, b),
            z1: depth_near(e, q, b, a),
            prim: span.li | flag,
            chain: 0,
            n: 1,
        };
        if self.join(prims, j, &f, tp) {
            return;
        }
        self.links.push(Link {
            t0,
            z0: f.z0,
            prim: span.li,
            next: NONE,
        });
        let link = (self.links.len() - 1) as u32;
        self.tail[j] = (self.raw.len() as u32, link);
        self.raw.push((j as u32, Frag { chain: link, ..f }));
    }

    /// Joins `f` (a span of the tile's prim `tp`, not yet in `prims`) to the fragment found
    /// last at sample `j` when it continues it: the same draw, facing and opacity, touching in
    /// time, with the depths meeting there (`CHAIN_DEPTH_TOLERANCE`). Each link keeps its own
    /// depth, so a chain is as exact as its separate spans. Returns whether it did.
    #[inline(always)]
    fn join(&mut self, prims: &[TilePrim], j: usize, f: &Frag, tp: &TilePrim) -> bool {
        let (ti, tl) = self.tail[j];
        if ti == NONE {
            return false;
        }
        let t = self.raw[ti as usize].1;
        let hi = (t.prim & !BACK) as usize;
        let head = if hi == prims.len() { tp } else { &prims[hi] };
        if head.draw != tp.draw
            || (t.prim & BACK) != (f.prim & BACK)
            || (head.flags & OPAQUE) != (tp.flags & OPAQUE)
        {
            return false;
        }
        let meet =
            |za: f32, zb: f32| (za - zb).abs() <= CHAIN_DEPTH_TOLERANCE * za.abs().max(zb.abs());
        let li = f.prim & !BACK;
        if t.t1 == f.t0 && meet(t.z1, f.z0) {
            self.links.push(Link {
                t0: f.t0,
                z0: f.z0,
                prim: li,
                next: NONE,
            });
            let link = (self.links.len() - 1) as u32;
            self.links[tl as usize].next = link;
            self.tail[j].1 = link;
            let g = &mut self.raw[ti as usize].1;
            g.t1 = f.t1;
            g.z1 = f.z1;
            g.n += 1;
            return true;
        }
        if t.t0 == f.t1 && meet(f.z1, t.z0) {
            self.links.push(Link {
                t0: f.t0,
                z0: f.z0,
                prim: li,
                next: t.chain,
            });
            let g = &mut self.raw[ti as usize].1;
            g.chain = (self.links.len() - 1) as u32;
            g.t0 = f.t0;
            g.z0 = f.z0;
            g.prim = f.prim;
            g.n += 1;
            return true;
        }
        false
    }
}

/// The view depth at local time `tau` at a span's end, or a little inside the span (towards
/// `other`) where the triangle is edge-on at the end itself.
#[inline(always)]
fn depth_near(e: &Edges, q: &SampleEdges, tau: f64, other: f64) -> f32 {
    // the end itself first (`tau + 0 * (other - tau)` is `tau`)
    match e.depth(q, tau) {
        Some(z) => z as f32,
        None => depth_inside(e, q, tau, other),
    }
}

/// [`depth_near`] where the triangle is edge-on at the end itself.
#[cold]
fn depth_inside(e: &Edges, q: &SampleEdges, tau: f64, other: f64) -> f32 {
    for f in [1e-6, 1e-3, 0.5] {
        if let Some(z) = e.depth(q, tau + f * (other - tau)) {
            return z as f32;
        }
    }
    f32::INFINITY
}
