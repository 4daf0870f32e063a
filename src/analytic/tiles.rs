//! The frame: prims of every face over every segment, binning into tiles, and the tiles in
//! parallel (fragments, visibility over time, shading, resolve of each pixel's samples).
use std::cell::RefCell;
use std::time::Instant;

use rayon::prelude::*;

use super::input::{prepare, validate, Prepared};
pub use super::input::{Backdrop, Input, MovingDraw};
use super::prim::{self, Corners, Edges, Prim, OPAQUE};
use super::resolve::{self, Backdrop as Behind, Frag, Link, Scratch, BACK, NONE};
use super::shade::{SampleShader, TilePrim};
use crate::error::{Error, Result};

/// Tile side in samples (a multiple of every supersampling factor).
pub const TILE: i32 = 32;
/// Faces set up per parallel job.
const CHUNK: usize = 2048;
/// Most (tile, prim) pairs a frame may bin (8 bytes each while binning).
pub const MAX_BIN_ENTRIES: u64 = 1 << 27;
/// Most fragments one tile may hold at once (24 bytes each).
pub const MAX_TILE_FRAGMENTS: usize = 1 << 22;

/// Counts and timings of one frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    /// Triangle-segments set up (after culling and the view test).
    pub prims: u64,
    /// (tile, prim) pairs binned.
    pub bin_entries: u64,
    /// Spans of covered time found at samples (fragments).
    pub intervals: u64,
    /// Visible pieces shaded.
    pub pieces: u64,
    /// Fragments merged into neighbours because a tile reached its fragment budget.
    pub merges: u64,
    /// Samples tested against a prim, and covered spans found before chaining.
    pub tests: u64,
    pub spans: u64,
    /// Thread time (summed over threads, ms) finding spans and resolving samples.
    pub ms_cover: f64,
    pub ms_resolve: f64,
    /// Segments of the shutter.
    pub segments: u64,
    /// Milliseconds: preparation, prim set-up, binning, tiles, whole frame.
    pub ms_prepare: f64,
    pub ms_setup: f64,
    pub ms_bin: f64,
    pub ms_tiles: f64,
    pub ms_total: f64,
}

/// A rendered frame, row-major `height` x `width` pixels.
#[derive(Clone, Debug, Default)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// (H,W,4) premultiplied linear RGBA, integrated over the shutter.
    pub rgba: Vec<f32>,
    /// (H,W) view depth of the surface in front at the reference time, inf for none.
    pub depth: Vec<f32>,
    /// (H,W) object id of that surface, -1 for none.
    pub ids: Vec<i32>,
    /// (H,W,2) its screen motion over the shutter, pixels.
    pub velocity: Vec<f32>,
    pub stats: Stats,
}

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
struct Counts {
    intervals: u64,
    pieces: u64,
    merges: u64,
    tests: u64,
    spans: u64,
    ns_cover: u64,
    ns_resolve: u64,
}

/// One sample's result.
#[derive(Clone, Copy, Debug)]
struct SampleOut {
    rgba: [f32; 4],
    depth: f32,
    id: i32,
    velocity: [f32; 2],
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

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Renders one frame. Errors name the offending argument.
pub fn render(input: &Input) -> Result<Frame> {
    let t_all = Instant::now();
    validate(input)?;
    let s = input.samples;
    let (ws, hs) = (input.width * s, input.height * s);
    let mut stats = Stats {
        segments: (input.times.len() - 1) as u64,
        ..Stats::default()
    };

    let t = Instant::now();
    let prepared: Vec<Prepared> = input.draws.iter().map(|d| prepare(input, d)).collect();
    stats.ms_prepare = ms(t);

    let t = Instant::now();
    let prims = setup_prims(input, &prepared, ws, hs);
    stats.prims = prims.len() as u64;
    stats.ms_setup = ms(t);

    let t = Instant::now();
    let (tx, ty) = ((ws as i32 + TILE - 1) / TILE, (hs as i32 + TILE - 1) / TILE);
    let (offsets, entries) = bin(&prims, tx, ty)?;
    stats.bin_entries = entries.len() as u64;
    stats.ms_bin = ms(t);

    let t = Instant::now();
    let breaks = input.shutter.breaks();
    let ctx = Ctx {
        input,
        prepared: &prepared,
        prims: &prims,
        breaks: &breaks,
        ws: ws as i32,
        hs: hs as i32,
    };
    let tiles: Vec<(Vec<SampleOut>, Counts)> = (0..(tx * ty) as usize)
        .into_par_iter()
        .map(|i| {
            let bin = &entries[offsets[i] as usize..offsets[i + 1] as usize];
            ctx.tile(i as i32 % tx, i as i32 / tx, bin)
        })
        .collect();
    stats.ms_tiles = ms(t);

    let mut frame = Frame {
        width: input.width,
        height: input.height,
        rgba: vec![0.0; 4 * (input.width * input.height) as usize],
        depth: vec![f32::INFINITY; (input.width * input.height) as usize],
        ids: vec![-1; (input.width * input.height) as usize],
        velocity: vec![0.0; 2 * (input.width * input.height) as usize],
        stats: Stats::default(),
    };
    for (i, (samples, counts)) in tiles.iter().enumerate() {
        stats.intervals += counts.intervals;
        stats.pieces += counts.pieces;
        stats.merges += counts.merges;
        stats.tests += counts.tests;
        stats.spans += counts.spans;
        stats.ms_cover += counts.ns_cover as f64 * 1e-6;
        stats.ms_resolve += counts.ns_resolve as f64 * 1e-6;
        let (x0, y0) = ((i as i32 % tx) * TILE, (i as i32 / tx) * TILE);
        write_pixels(&mut frame, samples, x0, y0, ws as i32, hs as i32, s as i32);
    }
    stats.ms_total = ms(t_all);
    frame.stats = stats;
    Ok(frame)
}

/// Every face of every draw over every segment, in (segment, draw, face) order.
fn setup_prims(input: &Input, prepared: &[Prepared], ws: u32, hs: u32) -> Vec<Prim> {
    let segments = input.times.len() - 1;
    let mut out = Vec::new();
    for seg in 0..segments {
        for (di, (d, p)) in input.draws.iter().zip(prepared).enumerate() {
            let chunks: Vec<Vec<Prim>> = d
                .faces
                .par_chunks(CHUNK)
                .enumerate()
                .map(|(ci, faces)| {
                    let mut v = Vec::new();
                    for (j, f) in faces.iter().enumerate() {
                        let alpha =
                            f.map(|i| d.rgba[if d.rgba.len() == 1 { 0 } else { i as usize }][3]);
                        if alpha.iter().all(|a| *a <= 0.0) {
                            continue;
                        }
                        let c0 = f.map(|i| p.clip[seg * p.nv + i as usize]);
                        let c1 = f.map(|i| p.clip[(seg + 1) * p.nv + i as usize]);
                        let corners = Corners::new(c0, c1, f64::from(ws), f64::from(hs));
                        let Some((flags, front, back, bbox, hull, nhull)) =
                            prim::setup(&corners, &c0, &c1, d.cull_back, ws, hs)
                        else {
                            continue;
                        };
                        let opaque = p.opaque_everywhere || alpha.iter().all(|a| *a >= 1.0);
                        v.push(Prim {
                            draw: di as u32,
                            face: (ci * CHUNK + j) as u32,
                            seg: seg as u32,
                            flags: flags | if opaque { OPAQUE } else { 0 },
                            front,
                            back,
                            bbox,
                            hull,
                            nhull,
                        });
                    }
                    v
                })
                .collect();
            let mut group: Vec<Prim> = chunks.into_iter().flatten().collect();
            order_along_motion(&mut group, p, seg, ws, hs);
            out.extend(group);
        }
    }
    out
}

/// Orders one draw's prims of one segment so that its leading side comes first: along the
/// draw's mean screen motion, a sample is reached by the triangles in this order, so the spans
/// of neighbouring triangles arrive one after the other and chain (a stable sort: ties keep
/// face order).
fn order_along_motion(group: &mut [Prim], p: &Prepared, seg: usize, ws: u32, hs: u32) {
    let (w, h) = (f64::from(ws), f64::from(hs));
    let step = (p.nv / 1024).max(1);
    let (mut dx, mut dy) = (0.0, 0.0);
    for v in (0..p.nv).step_by(step) {
        let (a, b) = (p.clip[seg * p.nv + v], p.clip[(seg + 1) * p.nv + v]);
        if a[3] > 0.0 && b[3] > 0.0 {
            let pa = prim::homogeneous_pixel(&a, w, h);
            let pb = prim::homogeneous_pixel(&b, w, h);
            dx += pb[0] / pb[2] - pa[0] / pa[2];
            dy += pb[1] / pb[2] - pa[1] / pa[2];
        }
    }
    if !(dx * dx + dy * dy > 0.0) {
        return;
    }
    let key = |q: &Prim| {
        let cx = f64::from(q.bbox[0] + q.bbox[2]);
        let cy = f64::from(q.bbox[1] + q.bbox[3]);
        -(cx * dx + cy * dy)
    };
    group.sort_by(|a, b| key(a).total_cmp(&key(b)));
}

/// Tile bins: `offsets` (tiles + 1) into `entries` (prim indices, in prim order per tile).
fn bin(prims: &[Prim], tx: i32, ty: i32) -> Result<(Vec<u32>, Vec<u32>)> {
    let tiles_of = |p: &Prim| {
        let b = p.bbox;
        (
            b[0] / TILE,
            b[1] / TILE,
            (b[2] - 1) / TILE + 1,
            (b[3] - 1) / TILE + 1,
        )
    };
    let bound: u64 = prims
        .par_iter()
        .map(|p| {
            let (a, b, c, d) = tiles_of(p);
            ((c - a) * (d - b)) as u64
        })
        .sum();
    if bound > MAX_BIN_ENTRIES {
        return Err(Error::value(
            "draws",
            format!(
                "the moving triangles' swept bounds span {bound} tiles in all, past the budget of \
                 {MAX_BIN_ENTRIES} ({} MiB); use fewer or smaller triangles, fewer segments or a \
                 smaller image",
                MAX_BIN_ENTRIES * 8 >> 20
            ),
        ));
    }
    let pairs: Vec<Vec<(u32, u32)>> = prims
        .par_chunks(4096)
        .enumerate()
        .map(|(ci, chunk)| {
            let mut v = Vec::new();
            for (j, p) in chunk.iter().enumerate() {
                let (a, b, c, d) = tiles_of(p);
                for y in b..d.min(ty) {
                    for x in a..c.min(tx) {
                        let r = [x * TILE, y * TILE, (x + 1) * TILE, (y + 1) * TILE];
                        if prim::overlaps(p, r[0], r[1], r[2], r[3]) {
                            v.push(((y * tx + x) as u32, (ci * 4096 + j) as u32));
                        }
                    }
                }
            }
            v
        })
        .collect();
    let n = (tx * ty) as usize;
    let mut offsets = vec![0u32; n + 1];
    for v in &pairs {
        for &(t, _) in v {
            offsets[t as usize + 1] += 1;
        }
    }
    for i in 0..n {
        offsets[i + 1] += offsets[i];
    }
    let mut fill = offsets.clone();
    let mut entries = vec![0u32; offsets[n] as usize];
    for v in &pairs {
        for &(t, p) in v {
            entries[fill[t as usize] as usize] = p;
            fill[t as usize] += 1;
        }
    }
    Ok((offsets, entries))
}

/// What every tile reads.
struct Ctx<'a> {
    input: &'a Input<'a>,
    prepared: &'a [Prepared],
    prims: &'a [Prim],
    breaks: &'a [f64],
    ws: i32,
    hs: i32,
}

impl Ctx<'_> {
    fn corners(&self, p: &Prim) -> Corners {
        let d = &self.input.draws[p.draw as usize];
        let pr = &self.prepared[p.draw as usize];
        let f = d.faces[p.face as usize];
        let k = p.seg as usize;
        let c0 = f.map(|i| pr.clip[k * pr.nv + i as usize]);
        let c1 = f.map(|i| pr.clip[(k + 1) * pr.nv + i as usize]);
        Corners::new(c0, c1, f64::from(self.ws), f64::from(self.hs))
    }

    /// One tile: its samples' results (row-major, TILE wide) and counts (intervals, pieces,
    /// merges).
    fn tile(&self, tx: i32, ty: i32, bin: &[u32]) -> (Vec<SampleOut>, Counts) {
        SCRATCH.with(|cell| match cell.try_borrow_mut() {
            Ok(mut sc) => self.tile_with(tx, ty, bin, &mut sc),
            Err(_) => self.tile_with(tx, ty, bin, &mut TileScratch::default()),
        })
    }

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
            let tp = TilePrim::new(self.input, self.prepared, p, &self.corners(p));
            let e = &tp.edges;
            let span = SpanOf {
                li: li as u32,
                t0: times[p.seg as usize],
                dt: times[p.seg as usize + 1] - times[p.seg as usize],
            };
            let simple = Edges::simple(p);
            let (ya, yb) = (p.bbox[1].max(y0), p.bbox[3].min(y1));
            let rows = &mut sc.rows[..(yb - ya).max(0) as usize];
            prim::row_spans(p, ya, p.bbox[0].max(x0), p.bbox[2].min(x1), rows);
            for iy in ya..yb {
                let (xa, xb) = sc.rows[(iy - ya) as usize];
                if xa >= xb {
                    continue;
                }
                let row = e.row(f64::from(iy) + 0.5);
                for ix in xa..xb {
                    let q = e.at_row(f64::from(ix) + 0.5, &row);
                    counts.tests += 1;
                    let j = ((iy - y0) * TILE + (ix - x0)) as usize;
                    if simple {
                        match e.covered_front(&q) {
                            Some(None) => continue,
                            Some(Some((a, b))) => {
                                self.add_span(sc, &span, &tp, &q, j, a, b, 0, &mut counts);
                                continue;
                            }
                            None => {}
                        }
                    }
                    let (front, back) = e.covered(p, &q);
                    for s in front.as_slice() {
                        self.add_span(sc, &span, &tp, &q, j, s[0], s[1], 0, &mut counts);
                    }
                    for s in back.as_slice() {
                        self.add_span(sc, &span, &tp, &q, j, s[0], s[1], BACK, &mut counts);
                    }
                }
            }
            sc.prims.push(tp);
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
fn depth_near(e: &Edges, q: &prim::SampleEdges, tau: f64, other: f64) -> f32 {
    for f in [0.0, 1e-6, 1e-3, 0.5] {
        if let Some(z) = e.depth(q, tau + f * (other - tau)) {
            return z as f32;
        }
    }
    f32::INFINITY
}

/// Box resolve of a tile's samples into the frame's pixels: colour mean; depth, id and velocity
/// of the nearest sample (the first in row order on ties).
fn write_pixels(
    frame: &mut Frame,
    samples: &[SampleOut],
    x0: i32,
    y0: i32,
    ws: i32,
    hs: i32,
    s: i32,
) {
    let w = frame.width as usize;
    let norm = 1.0 / (s * s) as f32;
    for py in (y0 / s)..((y0 + TILE).min(hs) / s) {
        for px in (x0 / s)..((x0 + TILE).min(ws) / s) {
            let mut c = [0.0f32; 4];
            let mut best: Option<&SampleOut> = None;
            for j in 0..s {
                for i in 0..s {
                    let (sx, sy) = (px * s + i - x0, py * s + j - y0);
                    let o = &samples[(sy * TILE + sx) as usize];
                    for k in 0..4 {
                        c[k] += o.rgba[k];
                    }
                    if o.depth.is_finite() && best.is_none_or(|b| o.depth < b.depth) {
                        best = Some(o);
                    }
                }
            }
            let i = py as usize * w + px as usize;
            for k in 0..4 {
                frame.rgba[4 * i + k] = if s == 1 { c[k] } else { c[k] * norm };
            }
            if let Some(b) = best {
                frame.depth[i] = b.depth;
                frame.ids[i] = b.id;
                frame.velocity[2 * i] = b.velocity[0];
                frame.velocity[2 * i + 1] = b.velocity[1];
            }
        }
    }
}
