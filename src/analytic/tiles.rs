//! One tile of samples: each of its prims' covered spans at its samples become fragments
//! (chained across neighbouring triangles of one surface), then each sample's fragments are
//! resolved over time and shaded.
//!
//! Memory is bounded: a pass over the tile holds at most about [`Input::tile_budget`] bytes
//! of fragments, links and prims (the vectors' capacity may reach twice that, and is kept by
//! the thread for its next tile until the strip of tile rows is done); past it the pass stops
//! and the tile is done again in halves, down to single samples, with the same result. Only a
//! single sample past the budget on its own fails, with a memory error naming it.
use std::cell::RefCell;
use std::time::Instant;

use super::chain::{Found, SpanOf};
use super::hull;
use super::input::{Input, Prepared};
use super::poly::MAX_SPANS;
use super::prim::{Corners, Cover, Edges, Prim};
use super::resolve::{self, Scratch, Seen, NOTHING};
use super::shade::{SampleShader, TilePrim};
use super::visibility::{Frag, Link, Overflow, StaticSample, BACK, BACKDROP, NONE};
use crate::error::{Error, Result};

/// Tile side in samples (a multiple of every supersampling factor).
pub const TILE: i32 = 32;

/// The tile rows `[r0, r1)` of the sample rows `[y0, y1)` (not empty).
pub fn tile_rows(y0: i32, y1: i32) -> (i32, i32) {
    (y0 / TILE, (y1 - 1) / TILE + 1)
}

/// What one tile counted.
#[derive(Clone, Copy, Debug, Default)]
pub struct Counts {
    /// Fragments after chaining, visible pieces.
    pub intervals: u64,
    pub pieces: u64,
    /// Passes that outgrew the memory budget and were done again as two halves.
    pub splits: u64,
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

/// One object visible at one sample of a tile (the exposure channel, [`Input::exposure`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Visible {
    /// The sample: row-major index in the tile (TILE wide).
    pub sample: u32,
    /// The object id (-1: no surface).
    pub id: i32,
    /// The filter's weight of the time it is in front, its first and last instant then.
    pub weight: f64,
    pub first: f32,
    pub last: f32,
}

/// What one tile gives: its samples' results (row-major, TILE wide), the objects visible at
/// them (empty unless the exposure channel is on) and its counts.
pub type TileOut = (Vec<SampleOut>, Vec<Visible>, Counts);

/// What a sample outside the image (in a tile at the edge) holds.
const EMPTY: SampleOut = SampleOut {
    rgba: [0.0; 4],
    depth: f32::INFINITY,
    id: -1,
    velocity: [0.0; 2],
};

/// A rectangle of samples `[x0, x1) x [y0, y1)` (image samples) within one tile.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Rect {
    x0: i32,
    y0: i32,
    x1: i32,
    y1: i32,
}

impl Rect {
    /// The rectangle's two halves: the upper and lower rows, or for one row the left and right
    /// columns; None for one sample.
    fn halves(self) -> Option<(Rect, Rect)> {
        if self.y1 - self.y0 > 1 {
            let m = (self.y0 + self.y1) / 2;
            Some((Rect { y1: m, ..self }, Rect { y0: m, ..self }))
        } else if self.x1 - self.x0 > 1 {
            let m = (self.x0 + self.x1) / 2;
            Some((Rect { x1: m, ..self }, Rect { x0: m, ..self }))
        } else {
            None
        }
    }
}

struct TileScratch {
    /// Fragments and links in the order they are found.
    found: Found,
    /// Fragments grouped by sample: sample `j` owns `frags[start[j]..start[j + 1]]`.
    frags: Vec<Frag>,
    start: Vec<u32>,
    /// The prims with spans in this pass, in bin order (fragments and links index them).
    prims: Vec<TilePrim>,
    /// The current prim's columns per row of the tile.
    rows: [(i32, i32); TILE as usize],
    cursor: Vec<u32>,
    sweep: Scratch,
    out: Vec<SampleOut>,
    visible: Vec<Visible>,
}

impl Default for TileScratch {
    fn default() -> Self {
        TileScratch {
            found: Found::default(),
            frags: Vec::new(),
            start: Vec::new(),
            prims: Vec::new(),
            rows: [(0, 0); TILE as usize],
            cursor: Vec::new(),
            sweep: Scratch::default(),
            out: Vec::new(),
            visible: Vec::new(),
        }
    }
}

thread_local! {
    static SCRATCH: RefCell<TileScratch> = RefCell::new(TileScratch::default());
}

/// Frees the tile buffers every thread of the current pool keeps for its next tile (up to
/// twice the tile budget each): between strips of a frame, whose tiles may need far less than
/// the last strip's, and at its end.
pub fn release_scratch() {
    rayon::broadcast(|_| {
        SCRATCH.with(|cell| {
            if let Ok(mut sc) = cell.try_borrow_mut() {
                *sc = TileScratch::default();
            }
        })
    });
}

/// What every tile reads.
pub struct Ctx<'a> {
    /// The frame's input and its draws prepared.
    pub input: &'a Input<'a>,
    pub prepared: &'a [Prepared<'a>],
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
    let c0 = f.map(|i| pr.clip_at(k, i as usize));
    let c1 = f.map(|i| pr.clip_at(k + 1, i as usize));
    Corners::new(c0, c1, f64::from(ws), f64::from(hs))
}

impl Ctx<'_> {
    /// One tile: its samples' results, the objects visible at them and its counts. Fails only
    /// where one sample alone needs more than the memory budget ([`Input::tile_budget`]).
    pub fn tile(&self, tx: i32, ty: i32, bin: &[u32]) -> Result<TileOut> {
        SCRATCH.with(|cell| match cell.try_borrow_mut() {
            Ok(mut sc) => self.tile_dispatch(tx, ty, bin, &mut sc),
            Err(_) => self.tile_dispatch(tx, ty, bin, &mut TileScratch::default()),
        })
    }

    /// [`Ctx::tile_with`] compiled for AVX2 where the CPU has it and the vector forms are not
    /// switched off (`crate::simd`; the build targets plain x86-64): the same operations in
    /// the same order, no fused multiply-add (Rust never contracts), so the same bits, in fewer
    /// instructions (rounding, blends, wider moves).
    fn tile_dispatch(
        &self,
        tx: i32,
        ty: i32,
        bin: &[u32],
        sc: &mut TileScratch,
    ) -> Result<TileOut> {
        #[cfg(target_arch = "x86_64")]
        if crate::simd::simd_enabled() {
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
    ) -> Result<TileOut> {
        self.tile_with(tx, ty, bin, sc)
    }

    /// The tile in passes: the whole tile first; a pass whose fragments, links and prims would
    /// hold more than the budget stops and is done again as two halves (rows, then columns),
    /// down to one sample. A sample's result depends on its own fragments only, which are the
    /// same in any pass that holds it, so the output is the same bits whatever the budget.
    #[inline(always)]
    fn tile_with(&self, tx: i32, ty: i32, bin: &[u32], sc: &mut TileScratch) -> Result<TileOut> {
        let (x0, y0) = (tx * TILE, ty * TILE);
        let whole = Rect {
            x0,
            y0,
            x1: (x0 + TILE).min(self.ws),
            y1: (y0 + TILE).min(self.hs),
        };
        let mut counts = Counts::default();
        let mut out = std::mem::take(&mut sc.out);
        out.clear();
        out.resize((TILE * TILE) as usize, EMPTY);
        sc.sweep.sweep.max_cuts = self.input.tile_budget / std::mem::size_of::<f64>();
        sc.sweep.exposure = self.input.exposure.is_some();
        sc.visible.clear();
        // a stack of rectangles to do: each split pushes two halves of at most 10 levels
        let mut todo = [whole; 12];
        let mut n = 1;
        while n > 0 {
            n -= 1;
            let r = todo[n];
            let clock = Instant::now();
            let mut c = Counts::default();
            let covered = self.cover(r, x0, y0, bin, sc, &mut c);
            counts.ns_cover += clock.elapsed().as_nanos() as u64;
            if covered.is_err() {
                counts.splits += 1;
                let Some((a, b)) = r.halves() else {
                    return Err(self.over_budget(r.x0, r.y0, "more covered spans"));
                };
                todo[n] = b;
                todo[n + 1] = a;
                n += 2;
                continue;
            }
            counts.tests += c.tests;
            counts.spans += c.spans;
            counts.intervals += sc.found.raw.len() as u64;
            let clock = Instant::now();
            let resolved = self.resolve_rect(r, x0, y0, sc, &mut out, &mut counts);
            counts.ns_resolve += clock.elapsed().as_nanos() as u64;
            if let Err((ix, iy)) = resolved {
                return Err(self.over_budget(ix, iy, "more depth crossings"));
            }
        }
        let result = out.clone();
        sc.out = out;
        Ok((result, sc.visible.clone(), counts))
    }

    /// The memory error of sample `(ix, iy)`, which alone holds `what` than the budget allows.
    #[cold]
    fn over_budget(&self, ix: i32, iy: i32, what: &str) -> Error {
        let s = self.input.samples as i32;
        Error::memory(
            "draws",
            format!(
                "sample ({ix}, {iy}) (pixel ({}, {})) holds {what} than fit the analytic \
                 kernel's budget of {} bytes per tile pass (motionblur.analytic.TILE_BUDGET_BYTES) \
                 or than could be allocated; raise the budget, or use fewer moving triangles \
                 stacked over one sample, fewer segments or less supersampling",
                ix / s,
                iy / s,
                self.input.tile_budget
            ),
        )
    }

    /// Asks for prim `pi` and its shared set-up to be brought into the cache (the next prim
    /// of a bin, while the current one is tested: prims are reached in bin order, which
    /// hardware prefetchers cannot foresee).
    #[inline(always)]
    fn prefetch(&self, pi: usize) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            let lines = |p: *const i8, bytes: usize| {
                for off in (0..bytes).step_by(64) {
                    // SAFETY: a prefetch never faults, whatever the address (SSE is part of
                    // x86-64).
                    unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(off)) };
                }
            };
            if let Some(p) = self.prims.get(pi) {
                lines((p as *const Prim).cast(), std::mem::size_of::<Prim>());
            }
            if let Some(tp) = self.shared.get(pi) {
                lines(
                    (tp as *const TilePrim).cast(),
                    std::mem::size_of::<TilePrim>(),
                );
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = pi;
    }

    /// Bytes the pass holds in fragments (found and grouped), links and prims.
    fn held(sc: &TileScratch) -> usize {
        use std::mem::size_of;
        sc.found.raw.len() * (size_of::<(u32, Frag)>() + size_of::<Frag>())
            + sc.found.links.len() * size_of::<Link>()
            + sc.prims.len() * size_of::<TilePrim>()
    }

    /// Finds the fragments of the tile's samples in `r` (tile origin `(x0, y0)`), grouped by
    /// sample into `sc.frags`; only prims with spans there are kept, in bin order (their
    /// index orders fragments, so the order is the same whatever `r`). Fails where they would
    /// hold more than the budget, or an allocation fails.
    #[inline(always)]
    fn cover(
        &self,
        r: Rect,
        x0: i32,
        y0: i32,
        bin: &[u32],
        sc: &mut TileScratch,
        counts: &mut Counts,
    ) -> std::result::Result<(), Overflow> {
        let times = self.input.times;
        let budget = self.input.tile_budget;
        sc.found.clear((TILE * TILE) as usize);
        sc.prims.clear();
        // room for every prim of the bin at once (within the budget): grown by doubling, the
        // prims (520 bytes each) would hold up to twice what they need
        let room = bin.len().min(budget / std::mem::size_of::<TilePrim>() + 1);
        sc.prims.try_reserve(room).map_err(|_| Overflow)?;
        // most spans one prim adds in `r`: front and back spans at every sample
        let most = ((r.x1 - r.x0) * (r.y1 - r.y0)) as usize * 2 * MAX_SPANS;
        for (k, &pi) in bin.iter().enumerate() {
            if let Some(&next) = bin.get(k + 1) {
                self.prefetch(next as usize);
            }
            let p = &self.prims[pi as usize];
            let (ya, yb) = (p.bbox[1].max(r.y0), p.bbox[3].min(r.y1));
            let (xa, xb) = (p.bbox[0].max(r.x0), p.bbox[2].min(r.x1));
            if ya >= yb || xa >= xb {
                continue;
            }
            let owned;
            let tp = match self.shared.get(pi as usize) {
                Some(tp) => tp,
                None => {
                    let c = corners(self.input, self.prepared, p, self.ws, self.hs);
                    owned = TilePrim::new(self.input, self.prepared, p, &c);
                    &owned
                }
            };
            // room for every span the prim can add, so that the pushes below never allocate
            sc.found.reserve(most)?;
            let e = &tp.edges;
            let mut span = SpanOf {
                tp,
                li: sc.prims.len() as u32,
                t0: times[p.seg as usize],
                dt: times[p.seg as usize + 1] - times[p.seg as usize],
                spans: 0,
            };
            let simple = Edges::simple(p);
            let rows = &mut sc.rows[..(yb - ya) as usize];
            let hull = &p.hull[..p.nhull as usize];
            let (ra, rb) = hull::row_spans(hull, ya, xa, xb, rows);
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
                    let mut add = |s: [f64; 2], flag: u32| {
                        sc.found.add_span(&sc.prims, &mut span, (&q, j), s, flag)
                    };
                    if let Some(front) = simple {
                        match e.covered_front(front, &q) {
                            Cover::Nothing => {}
                            Cover::One(a, b) => add([a, b], 0),
                            Cover::Many(s) => s.as_slice().iter().for_each(|s| add(*s, 0)),
                        }
                        continue;
                    }
                    let (front, back) = e.covered(p, &q);
                    front.as_slice().iter().for_each(|s| add(*s, 0));
                    back.as_slice().iter().for_each(|s| add(*s, BACK));
                }
            }
            // a prim is kept when a fragment or link refers to it (every counted span does)
            counts.spans += span.spans;
            if span.spans > 0 {
                sc.prims.try_reserve(1).map_err(|_| Overflow)?;
                sc.prims.push(tp.clone());
                if Self::held(sc) > budget {
                    return Err(Overflow);
                }
            }
        }
        group_by_sample(sc)
    }

    /// Resolves and shades the samples of `r` (tile origin `(x0, y0)`) from the fragments
    /// [`Ctx::cover`] found, into `out`. Fails with the sample whose depth crossings would
    /// outgrow the budget.
    #[inline(always)]
    fn resolve_rect(
        &self,
        r: Rect,
        x0: i32,
        y0: i32,
        sc: &mut TileScratch,
        out: &mut [SampleOut],
        counts: &mut Counts,
    ) -> std::result::Result<(), (i32, i32)> {
        let mut row_breaks = Vec::new();
        for iy in r.y0..r.y1 {
            let (window, t_ref) = self.row_window(iy, &mut row_breaks);
            let breaks = if window.is_some() {
                &row_breaks[..]
            } else {
                self.breaks
            };
            for ix in r.x0..r.x1 {
                let j = ((iy - y0) * TILE + (ix - x0)) as usize;
                let frags = &mut sc.frags[sc.start[j] as usize..sc.start[j + 1] as usize];
                let bg = self.behind(ix, iy);
                if frags.is_empty() {
                    if sc.sweep.exposure {
                        let layer = if bg.depth.is_finite() {
                            BACKDROP
                        } else {
                            NOTHING
                        };
                        let whole = Seen {
                            layer,
                            weight: 1.0,
                            first: 0.0,
                            last: 1.0,
                        };
                        sc.visible.push(visible(j, bg.id, &whole));
                    }
                    out[j] = SampleOut {
                        rgba: if bg.depth.is_finite() {
                            bg.rgba
                        } else {
                            [0.0; 4]
                        },
                        depth: bg.depth,
                        id: bg.id,
                        velocity: [0.0; 2],
                    };
                    continue;
                }
                let mut shader = SampleShader {
                    input: self.input,
                    prepared: self.prepared,
                    prims: &sc.prims,
                    links: &sc.found.links,
                    cursor: std::mem::take(&mut sc.cursor),
                    x: f64::from(ix) + 0.5,
                    y: f64::from(iy) + 0.5,
                    last: (NONE, [[0.0; 3]; 3]),
                };
                shader.warm(frags);
                shader.reset(frags.len());
                let r = resolve::resolve(
                    frags,
                    &sc.found.links,
                    &bg,
                    &mut shader,
                    resolve::Timing {
                        shutter: self.input.shutter,
                        breaks,
                        quad: self.input.quadrature,
                        t_ref,
                        window,
                    },
                    &mut sc.sweep,
                )
                .map_err(|_| (ix, iy))?;
                counts.pieces += u64::from(r.pieces);
                for s in &sc.sweep.seen {
                    let id = match s.layer {
                        BACKDROP => bg.id,
                        NOTHING => -1,
                        fi => shader.object_id(shader.prim_at(&frags[fi], s.first)),
                    };
                    sc.visible.push(visible(j, id, s));
                }
                out[j] = match r.front {
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
                sc.cursor = shader.cursor;
            }
        }
        Ok(())
    }

    /// Sample row `iy`'s rolling-shutter window ([`crate::analytic::Rolling`]) and reference
    /// instant; with a window, `breaks` then holds its ends inside (0, 1) and the filter's
    /// breaks mapped into it, ascending. A global shutter: None and the reference time.
    fn row_window(&self, iy: i32, breaks: &mut Vec<f64>) -> (Option<(f64, f64)>, f64) {
        let t_ref = self.input.reference_time;
        let y = iy / self.input.samples as i32;
        match self.input.rolling.window(y, self.input.height) {
            None => (None, t_ref),
            Some((o, s)) => {
                breaks.clear();
                breaks.push(o);
                breaks.extend(self.breaks.iter().map(|b| o + s * b));
                breaks.push(o + s);
                breaks.retain(|b| *b > 0.0 && *b < 1.0);
                (Some((o, s)), o + s * t_ref)
            }
        }
    }

    fn behind(&self, ix: i32, iy: i32) -> StaticSample {
        match &self.input.backdrop {
            None => StaticSample {
                rgba: [0.0; 4],
                depth: f32::INFINITY,
                id: -1,
            },
            Some(b) => {
                let i = (iy * self.ws + ix) as usize;
                StaticSample {
                    rgba: b.rgba_at(i),
                    depth: b.depth[i],
                    id: b.ids[i],
                }
            }
        }
    }
}

/// Sample `j`'s entry of the layer `s` in front there, object `id`.
fn visible(j: usize, id: i32, s: &Seen) -> Visible {
    Visible {
        sample: j as u32,
        id,
        weight: s.weight,
        first: s.first as f32,
        last: s.last as f32,
    }
}

/// Groups the fragments found into `sc.frags` by sample, each sample's in the order found (a
/// stable counting sort), `sc.start` the first of every sample's.
fn group_by_sample(sc: &mut TileScratch) -> std::result::Result<(), Overflow> {
    let n = (TILE * TILE) as usize;
    sc.start.clear();
    sc.start.resize(n + 1, 0);
    for (j, _) in &sc.found.raw {
        sc.start[*j as usize + 1] += 1;
    }
    for j in 0..n {
        sc.start[j + 1] += sc.start[j];
    }
    sc.frags.clear();
    sc.frags
        .try_reserve(sc.found.raw.len())
        .map_err(|_| Overflow)?;
    sc.frags.resize(
        sc.found.raw.len(),
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
    let mut fill: [u32; (TILE * TILE) as usize] = [0; (TILE * TILE) as usize];
    fill.copy_from_slice(&sc.start[..n]);
    for (j, f) in &sc.found.raw {
        sc.frags[fill[*j as usize] as usize] = *f;
        fill[*j as usize] += 1;
    }
    Ok(())
}
