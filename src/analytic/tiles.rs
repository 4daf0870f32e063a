//! One tile of samples: each of its prims' covered spans at its samples become fragments
//! (chained across neighbouring triangles of one surface), then each sample's fragments are
//! resolved over time and shaded.
use std::cell::RefCell;
use std::time::Instant;

use super::hull;
use super::input::{Input, Prepared};
use super::prim::{self, Corners, Cover, Edges, Prim, OPAQUE};
use super::resolve::{self, Scratch};
use super::shade::{SampleShader, TilePrim};
use super::visibility::{Backdrop as Behind, Frag, Link, BACK, NONE};

/// Tile side in samples (a multiple of every supersampling factor).
pub const TILE: i32 = 32;

/// The current prim's segment, as its spans are recorded.
struct SpanOf {
    /// The prim's index in the tile.
    li: u32,
    /// The segment's start and length in shutter time.
    t0: f64,
    dt: f64,
}

/// What one tile counted.
#[derive(Clone, Copy, Debug, Default)]
pub struct Counts {
    /// Fragments after chaining, visible pieces, merges.
    pub intervals: u64,
    pub pieces: u64,
    pub merges: u64,
    /// Samples tested against a prim, covered spans found.
    pub tests: u64,
    pub spans: u64,
    /// Nanoseconds finding spans and resolving samples.
    pub ns_cover: u64,
    pub ns_resolve: u64,
}

/// One sample's result.
#[derive(Clone, Copy, Debug)]
pub struct SampleOut {
    /// Premultiplied RGBA integrated over the shutter.
    pub rgba: [f32; 4],
    /// View depth, object id and screen motion of the surface in front at the reference time.
    pub depth: f32,
    pub id: i32,
    pub velocity: [f32; 2],
}

/// Two spans join into one chain only where their depths meet at the shared instant (the same
/// surface point seen by both triangles), within this fraction of the depth.
const CHAIN_DEPTH_TOLERANCE: f32 = 1e-4;

struct TileScratch {
    /// Fragments in the order they are found, with their sample's index in the tile.
    raw: Vec<(u32, Frag)>,
    links: Vec<Link>,
    /// Per sample: the fragment found last (index in `raw`) and the last link of its chain.
    tail: Vec<(u32, u32)>,
    /// Fragments grouped by sample: sample `j` owns `frags[start[j]..start[j + 1]]`.
    frags: Vec<Frag>,
    start: Vec<u32>,
    prims: Vec<TilePrim>,
    /// The current prim's columns per row of the tile.
    rows: [(i32, i32); TILE as usize],
    cursor: Vec<u32>,
    sweep: Scratch,
    out: Vec<SampleOut>,
}

impl Default for TileScratch {
    fn default() -> Self {
        TileScratch {
            raw: Vec::new(),
            links: Vec::new(),
            tail: Vec::new(),
            frags: Vec::new(),
            start: Vec::new(),
            prims: Vec::new(),
            rows: [(0, 0); TILE as usize],
            cursor: Vec::new(),
            sweep: Scratch::default(),
            out: Vec::new(),
        }
    }
}

thread_local! {
    static SCRATCH: RefCell<TileScratch> = RefCell::new(TileScratch::default());
}

/// What every tile reads.
pub struct Ctx<'a> {
    /// The frame's input and its draws prepared.
    pub input: &'a Input<'a>,
    pub prepared: &'a [Prepared],
    /// Every prim of the frame (bins hold indices into it).
    pub prims: &'a [Prim],
    /// Every prim set up for the tiles, or empty: each tile sets up its own.
    pub shared: &'a [TilePrim],
    /// The shutter filter's breaks.
    pub breaks: &'a [f64],
    /// Image size in samples.
    pub ws: i32,
    pub hs: i32,
}

/// The corners of prim `p` in an image of `ws` x `hs` samples.
pub fn corners(input: &Input, prepared: &[Prepared], p: &Prim, ws: i32, hs: i32) -> Corners {
    let d = &input.draws[p.draw as usize];
    let pr = &prepared[p.draw as usize];
    let f = d.faces[p.face as usize];
    let k = p.seg as usize;
    let c0 = f.map(|i| pr.clip[k * pr.nv + i as usize]);
    let c1 = f.map(|i| pr.clip[(k + 1) * pr.nv + i as usize]);
    Corners::new(c0, c1, f64::from(ws), f64::from(hs))
}

impl Ctx<'_> {
    /// One tile: its samples' results (row-major, TILE wide) and counts (intervals, pieces,
    /// merges).
    pub fn tile(&self, tx: i32, ty: i32, bin: &[u32]) -> (Vec<SampleOut>, Counts) {
        SCRATCH.with(|cell| match cell.try_borrow_mut() {
            Ok(mut sc) => self.tile_dispatch(tx, ty, bin, &mut sc),
            Err(_) => self.tile_dispatch(tx, ty, bin, &mut TileScratch::default()),
        })
    }

    /// [`Ctx::tile_with`] compiled for AVX2 where the CPU has it (the build targets plain
    /// x86-64): the same operations in the same order, no fused multiply-add (Rust never
    /// contracts), so the same bits, in fewer instructions (rounding, blends, wider moves).
    fn tile_dispatch(
        &self,
        tx: i32,
        ty: i32,
        bin: &[u32],
        sc: &mut TileScratch,
    ) -> (Vec<SampleOut>, Counts) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: `tile_avx2` only requires AVX2, which the CPU was just found to have.
            return unsafe { self.tile_avx2(tx, ty, bin, sc) };
        }
        self.tile_with(tx, ty, bin, sc)
    }

    /// See [`Ctx::tile_dispatch`]. Safety: the CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn tile_avx2(
        &self,
        tx: i32,
        ty: i32,
        bin: &[u32],
        sc: &mut TileScratch,
    ) -> (Vec<SampleOut>, Counts) {
        self.tile_with(tx, ty, bin, sc)
    }

    #[inline(always)]
    fn tile_with(
        &self,
        tx: i32,
        ty: i32,
        bin: &[u32],
        sc: &mut TileScratch,
    ) -> (Vec<SampleOut>, Counts) {
        let clock = Instant::now();
        let (x0, y0) = (tx * TILE, ty * TILE);
        let (x1, y1) = ((x0 + TILE).min(self.ws), (y0 + TILE).min(self.hs));
        let times = self.input.times;
        sc.raw.clear();
        sc.links.clear();
        sc.prims.clear();
        sc.tail.clear();
        sc.tail.resize((TILE * TILE) as usize, (NONE, NONE));
        let mut counts = Counts::default();
        for (li, &pi) in bin.iter().enumerate() {
            let p = &self.prims[pi as usize];
            let owned;
            let tp = match self.shared.get(pi as usize) {
                Some(tp) => tp,
                None => {
                    let c = corners(self.input, self.prepared, p, self.ws, self.hs);
                    owned = TilePrim::new(self.input, self.prepared, p, &c);
                    &owned
                }
            };
            let e = &tp.edges;
            let span = SpanOf {
                li: li as u32,
                t0: times[p.seg as usize],
                dt: times[p.seg as usize + 1] - times[p.seg as usize],
            };
            let simple = Edges::simple(p);
            let (ya, yb) = (p.bbox[1].max(y0), p.bbox[3].min(y1));
            let rows = &mut sc.rows[..(yb - ya).max(0) as usize];
            let hull = &p.hull[..p.nhull as usize];
            let (ra, rb) = hull::row_spans(hull, ya, p.bbox[0].max(x0), p.bbox[2].min(x1), rows);
            for iy in ya + ra as i32..ya + rb as i32 {
                let (xa, xb) = sc.rows[(iy - ya) as usize];
                if xa >= xb {
                    continue;
                }
                let row = e.row(f64::from(iy) + 0.5);
                for ix in xa..xb {
                    let q = e.at_row(f64::from(ix) + 0.5, &row);
                    counts.tests += 1;
                    let j = ((iy - y0) * TILE + (ix - x0)) as usize;
                    if let Some(front) = simple {
                        match e.covered_front(front, &q) {
                            Cover::Nothing => {}
                            Cover::One(a, b) => {
                                self.add_span(sc, &span, tp, &q, j, a, b, 0, &mut counts);
                            }
                            Cover::Many(s) => {
                                for s in s.as_slice() {
                                    self.add_span(sc, &span, tp, &q, j, s[0], s[1], 0, &mut counts);
                                }
                            }
                        }
                        continue;
                    }
                    let (front, back) = e.covered(p, &q);
                    for s in front.as_slice() {
                        self.add_span(sc, &span, tp, &q, j, s[0], s[1], 0, &mut counts);
                    }
                    for s in back.as_slice() {
                        self.add_span(sc, &span, tp, &q, j, s[0], s[1], BACK, &mut counts);
                    }
                }
            }
            sc.prims.push(tp.clone());
        }
        counts.intervals = sc.raw.len() as u64;
        // group by sample (a stable counting sort)
        let n = (TILE * TILE) as usize;
        sc.start.clear();
        sc.start.resize(n + 1, 0);
        for (j, _) in &sc.raw {
            sc.start[*j as usize + 1] += 1;
        }
        for j in 0..n {
            sc.start[j + 1] += sc.start[j];
        }
        sc.frags.clear();
        sc.frags.resize(
            sc.raw.len(),
            Frag {
                t0: 0.0,
                t1: 0.0,
                z0: 0.0,
                z1: 0.0,
                prim: 0,
                chain: 0,
                n: 0,
            },
        );
        {
            let mut fill: [u32; (TILE * TILE) as usize] = [0; (TILE * TILE) as usize];
            fill.copy_from_slice(&sc.start[..n]);
            for (j, f) in &sc.raw {
                sc.frags[fill[*j as usize] as usize] = *f;
                fill[*j as usize] += 1;
            }
        }
        counts.ns_cover = clock.elapsed().as_nanos() as u64;
        let clock = Instant::now();
        let mut out = std::mem::take(&mut sc.out);
        out.clear();
        let t_ref = self.input.reference_time;
        for iy in y0..y0 + TILE {
            for ix in x0..x0 + TILE {
                if ix >= x1 || iy >= y1 {
                    out.push(SampleOut {
                        rgba: [0.0; 4],
                        depth: f32::INFINITY,
                        id: -1,
                        velocity: [0.0; 2],
                    });
                    continue;
                }
                let j = ((iy - y0) * TILE + (ix - x0)) as usize;
                let frags = &mut sc.frags[sc.start[j] as usize..sc.start[j + 1] as usize];
                let bg = self.behind(ix, iy);
                if frags.is_empty() {
                    out.push(SampleOut {
                        rgba: if bg.depth.is_finite() {
                            bg.rgba
                        } else {
                            [0.0; 4]
                        },
                        depth: bg.depth,
                        id: bg.id,
                        velocity: [0.0; 2],
                    });
                    continue;
                }
                let mut shader = SampleShader {
                    input: self.input,
                    prepared: self.prepared,
                    prims: &sc.prims,
                    links: &sc.links,
                    cursor: std::mem::take(&mut sc.cursor),
                    x: f64::from(ix) + 0.5,
                    y: f64::from(iy) + 0.5,
                    last: (NONE, [[0.0; 3]; 3]),
                };
                shader.reset(frags.len());
                let r = resolve::resolve(
                    frags,
                    &sc.links,
                    &bg,
                    &mut shader,
                    self.input.shutter,
                    self.breaks,
                    self.input.quadrature,
                    t_ref,
                    &mut sc.sweep,
                );
                counts.pieces += u64::from(r.pieces);
                let o = match r.front {
                    Some((fi, z)) => {
                        let p = shader.prim_at(&frags[fi], t_ref);
                        SampleOut {
                            rgba: r.rgba,
                            depth: z as f32,
                            id: shader.object_id(p),
                            velocity: shader.velocity(p, t_ref),
                        }
                    }
                    None => SampleOut {
                        rgba: r.rgba,
                        depth: bg.depth,
                        id: bg.id,
                        velocity: [0.0; 2],
                    },
                };
                out.push(o);
                sc.cursor = shader.cursor;
            }
        }
        let result = out.clone();
        sc.out = out;
        counts.ns_resolve = clock.elapsed().as_nanos() as u64;
        (result, counts)
    }

    /// Records the span `[a, b]` (local time) of the current prim at tile sample `j`: joined to
    /// the sample's last fragment when it continues it, else a new fragment.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn add_span(
        &self,
        sc: &mut TileScratch,
        span: &SpanOf,
        tp: &TilePrim,
        q: &prim::SampleEdges,
        j: usize,
        a: f64,
        b: f64,
        flag: u32,
        counts: &mut Counts,
    ) {
        let (t0, t1) = (
            (span.t0 + a * span.dt) as f32,
            (span.t0 + b * span.dt) as f32,
        );
        if !(t1 > t0) {
            return;
        }
        counts.spans += 1;
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
        if self.join(sc, j, &f, tp) {
            return;
        }
        sc.links.push(Link {
            t0,
            z0: f.z0,
            prim: span.li,
            next: NONE,
        });
        let link = (sc.links.len() - 1) as u32;
        sc.tail[j] = (sc.raw.len() as u32, link);
        sc.raw.push((j as u32, Frag { chain: link, ..f }));
    }

    /// Joins `f` (a span of the tile's prim `tp`, not yet in `sc.prims`) to the fragment found
    /// last at sample `j` when it continues it: the same draw, facing and opacity, touching in
    /// time, with the depths meeting there (`CHAIN_DEPTH_TOLERANCE`). Each link keeps its own
    /// depth, so a chain is as exact as its separate spans. Returns whether it did.
    #[inline(always)]
    fn join(&self, sc: &mut TileScratch, j: usize, f: &Frag, tp: &TilePrim) -> bool {
        let (ti, tl) = sc.tail[j];
        if ti == NONE {
            return false;
        }
        let t = sc.raw[ti as usize].1;
        let hi = (t.prim & !BACK) as usize;
        let head = if hi == sc.prims.len() {
            tp
        } else {
            &sc.prims[hi]
        };
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
            sc.links.push(Link {
                t0: f.t0,
                z0: f.z0,
                prim: li,
                next: NONE,
            });
            let link = (sc.links.len() - 1) as u32;
            sc.links[tl as usize].next = link;
            sc.tail[j].1 = link;
            let g = &mut sc.raw[ti as usize].1;
            g.t1 = f.t1;
            g.z1 = f.z1;
            g.n += 1;
            return true;
        }
        if t.t0 == f.t1 && meet(f.z1, t.z0) {
            sc.links.push(Link {
                t0: f.t0,
                z0: f.z0,
                prim: li,
                next: t.chain,
            });
            let g = &mut sc.raw[ti as usize].1;
            g.chain = (sc.links.len() - 1) as u32;
            g.t0 = f.t0;
            g.z0 = f.z0;
            g.prim = f.prim;
            g.n += 1;
            return true;
        }
        false
    }

    fn behind(&self, ix: i32, iy: i32) -> Behind {
        match &self.input.backdrop {
            None => Behind {
                rgba: [0.0; 4],
                depth: f32::INFINITY,
                id: -1,
            },
            Some(b) => {
                let i = (iy * self.ws + ix) as usize;
                Behind {
                    rgba: [
                        b.rgba[4 * i],
                        b.rgba[4 * i + 1],
                        b.rgba[4 * i + 2],
                        b.rgba[4 * i + 3],
                    ],
                    depth: b.depth[i],
                    id: b.ids[i],
                }
            }
        }
    }
}

/// The view depth at local time `tau` at a span's end, or a little inside the span (towards
/// `other`) where the triangle is edge-on at the end itself.
#[inline(always)]
fn depth_near(e: &Edges, q: &prim::SampleEdges, tau: f64, other: f64) -> f32 {
    // the end itself first (`tau + 0 * (other - tau)` is `tau`)
    match e.depth(q, tau) {
        Some(z) => z as f32,
        None => depth_inside(e, q, tau, other),
    }
}

/// [`depth_near`] where the triangle is edge-on at the end itself.
#[cold]
fn depth_inside(e: &Edges, q: &prim::SampleEdges, tau: f64, other: f64) -> f32 {
    for f in [1e-6, 1e-3, 0.5] {
        if let Some(z) = e.depth(q, tau + f * (other - tau)) {
            return z as f32;
        }
    }
    f32::INFINITY
}
