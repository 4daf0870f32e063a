//! The frame: prims of every face over every segment, binning into tiles, the tiles in
//! parallel (`tiles.rs`), and the box resolve of each pixel's samples.
use std::time::Instant;

use rayon::prelude::*;

use super::hull;
use super::input::{prepare, validate, Input, Prepared};
use super::prim::Prim;
use super::shade::TilePrim;
use super::strips::{self, Plan};
use super::tiles::{
    corners, release_scratch, tile_rows, Counts, Ctx, SampleOut, TileOut, Visible, TILE,
};
use crate::error::{Error, Result};
use crate::frame::{Exposure, Frame};

/// Most (tile, prim) pairs a frame may bin (8 bytes each while binning).
pub const MAX_BIN_ENTRIES: u64 = 1 << 27;
/// Most bytes of prims set up once for all the tiles they reach (`TilePrim`, about 520 bytes
/// each); past it each tile sets up its own.
const SHARED_PRIM_BYTES: usize = 256 << 20;
/// Counts and timings of one frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    /// Triangle-segments set up (after culling and the view test).
    pub prims: u64,
    /// (tile, prim) pairs binned.
    pub bin_entries: u64,
    /// Spans of covered time found at samples (fragments).
    pub intervals: u64,
    /// Stretches of time shaded, each of fixed layers and triangles (one quadrature) or of one
    /// uniform composite.
    pub pieces: u64,
    /// Tile passes that outgrew the memory budget ([`Input::tile_budget`]) and were done again
    /// as two halves (the result is the same; only the time grows).
    pub splits: u64,
    /// Samples tested against a prim.
    pub tests: u64,
    /// Covered spans found at samples, before chaining.
    pub spans: u64,
    /// Thread time (summed over threads, ms) finding spans.
    pub ms_cover: f64,
    /// Thread time (summed over threads, ms) resolving and shading samples.
    pub ms_resolve: f64,
    /// Segments of the shutter.
    pub segments: u64,
    /// Strips of tile rows the frame was set up and rendered in, one at a time (1: the whole
    /// frame at once; more where its prims would pass twice [`Input::tile_budget`]).
    pub strips: u64,
    /// Milliseconds preparing the draws (clip positions, normals).
    pub ms_prepare: f64,
    /// Milliseconds setting up prims (and sharing them between tiles).
    pub ms_setup: f64,
    /// Milliseconds binning prims into tiles.
    pub ms_bin: f64,
    /// Milliseconds in the tiles.
    pub ms_tiles: f64,
    /// Milliseconds for the whole frame.
    pub ms_total: f64,
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Renders one frame: rgba integrated over the shutter; depth, ids and velocity (always
/// written) of the surface in front at the reference time; with [`Input::exposure`], the
/// exposure channel; and the frame's counts and timings. Errors name
/// the offending argument.
pub fn render(input: &Input) -> Result<(Frame, Stats)> {
    let t_all = Instant::now();
    validate(input)?;
    let s = input.samples;
    let (ws, hs) = (input.width * s, input.height * s);
    let mut stats = Stats {
        segments: (input.times.len() - 1) as u64,
        ..Stats::default()
    };

    let t = Instant::now();
    // a frame set up strip by strip computes the clip positions each strip uses (`clip.rs`)
    let whole = strips::whole(input);
    let prepared: Vec<Prepared> = input
        .draws
        .iter()
        .map(|d| prepare(input, d, whole))
        .collect();
    stats.ms_prepare = ms(t);

    let (tx, ty) = ((ws as i32 + TILE - 1) / TILE, (hs as i32 + TILE - 1) / TILE);
    let t = Instant::now();
    let plan = Plan::new(input, &prepared, ws, hs, ty);
    stats.ms_setup = ms(t);

    // The frame is written one row of tiles at a time, each row into its own band of pixel
    // rows: only the rows in flight hold their samples' results (a frame's worth of them at
    // 1080p with 2x2 samples would be 265 MB), the tiles of a row run in parallel too.
    let (w, h) = (input.width as usize, input.height as usize);
    let mut frame = Frame::new(input.width, input.height, false);
    let mut velocity = vec![0.0; 2 * w * h];
    let mut exposure = input
        .exposure
        .map(|n| Exposure::new(input.width, input.height, n + 1, "exposure"))
        .transpose()?;
    let band = (TILE as usize / s as usize) * w;
    let exposure_bands: Vec<Option<ExposureBand>> = match &mut exposure {
        None => (0..h.div_ceil(band / w)).map(|_| None).collect(),
        Some(e) => {
            let p = e.planes as usize;
            (e.fraction.chunks_mut(p * band))
                .zip(e.first.chunks_mut(p * band))
                .zip(e.last.chunks_mut(p * band))
                .map(|((fraction, first), last)| {
                    Some(ExposureBand {
                        fraction,
                        first,
                        last,
                        planes: p,
                    })
                })
                .collect()
        }
    };
    let mut bands: Vec<Band> = (frame.rgba.chunks_mut(4 * band))
        .zip(frame.depth.chunks_mut(band))
        .zip(frame.ids.chunks_mut(band))
        .zip(velocity.chunks_mut(2 * band))
        .zip(exposure_bands)
        .enumerate()
        .map(|(y, ((((rgba, depth), ids), velocity), exposure))| Band {
            rgba,
            depth,
            ids,
            velocity,
            exposure,
            width: w,
            y0: y as i32 * TILE / s as i32,
        })
        .collect();
    // The rows of tiles strip by strip, each with only the prims that reach it set up.
    let frame_ctx = FrameCtx {
        input,
        prepared: &prepared,
        plan: &plan,
        ws,
        hs,
        tx,
    };
    stats.strips = plan.strips.len() as u64;
    let mut rest = &mut bands[..];
    let mut bound = 0;
    for (si, &(r0, r1)) in plan.strips.iter().enumerate() {
        let (now, later) = rest.split_at_mut((r1 - r0) as usize);
        rest = later;
        frame_ctx.strip(si, r0, now, &mut bound, &mut stats)?;
    }
    drop(bands);
    stats.ms_total = ms(t_all);
    frame.velocity = Some(velocity);
    frame.exposure = exposure;
    Ok((frame, stats))
}

/// What every strip of tile rows reads.
struct FrameCtx<'a> {
    input: &'a Input<'a>,
    prepared: &'a [Prepared<'a>],
    plan: &'a Plan,
    /// Image size in samples, and in tiles across.
    ws: u32,
    hs: u32,
    tx: i32,
}

impl FrameCtx<'_> {
    /// Strip `si`, the tile rows `r0..` of `bands` (one band of pixel rows each): their prims
    /// and the clip positions they use set up, binned (shared between tiles within a memory
    /// budget) and their tiles rendered into the bands, the threads' tile buffers freed after;
    /// adds to `stats`, and to `bound` the tiles the bounds of the prims that start here span (each prim is counted in its first strip only: the frame's sum, checked
    /// against [`MAX_BIN_ENTRIES`] as it grows).
    fn strip(
        &self,
        si: usize,
        r0: i32,
        bands: &mut [Band],
        bound: &mut u64,
        stats: &mut Stats,
    ) -> Result<()> {
        let input = self.input;
        let (ws, hs, tx) = (self.ws, self.hs, self.tx);
        let r1 = r0 + bands.len() as i32;
        let t = Instant::now();
        let prims = self.plan.prims_of(input, self.prepared, ws, hs, si);
        // the draws reading the clip positions of this strip's prims, when it has its own
        let tables = self.plan.tables(input, self.prepared, &prims);
        let views: Vec<Prepared> = (self.prepared.iter().zip(&tables))
            .map(|(p, t)| p.with_table(t))
            .collect();
        let prepared = if tables.is_empty() {
            self.prepared
        } else {
            &views[..]
        };
        for p in &prims {
            let (a, b, c, d) = tiles_of(p);
            if b >= r0 {
                stats.prims += 1;
                *bound += ((c - a) * (d - b)) as u64;
            }
        }
        if *bound > MAX_BIN_ENTRIES {
            return Err(too_many_bins(*bound));
        }
        stats.ms_setup += ms(t);

        let t = Instant::now();
        let (offsets, entries) = bin(&prims, tx, r0, r1)?;
        stats.bin_entries += entries.len() as u64;
        stats.ms_bin += ms(t);

        // Prims that reach several tiles are set up once for all of them, within a budget.
        let t = Instant::now();
        let fits = entries.len() > prims.len()
            && prims.len() * std::mem::size_of::<TilePrim>() <= SHARED_PRIM_BYTES;
        let shared: Vec<TilePrim> = if self.plan.shares(input, prims.len(), fits) {
            prims
                .par_iter()
                .with_min_len(256)
                .map(|p| {
                    let c = corners(input, prepared, p, ws as i32, hs as i32);
                    TilePrim::new(input, prepared, p, &c)
                })
                .collect()
        } else {
            Vec::new()
        };
        stats.ms_setup += ms(t);

        let t = Instant::now();
        let breaks = input.shutter.breaks();
        let ctx = Ctx {
            input,
            prepared,
            prims: &prims,
            shared: &shared,
            breaks: &breaks,
            ws: ws as i32,
            hs: hs as i32,
        };
        let s = input.samples as i32;
        let rows: Vec<Vec<Counts>> = bands
            .par_iter_mut()
            .enumerate()
            .map(|(i, out)| {
                let y = r0 + i as i32;
                let tiles: Vec<TileOut> = (0..tx)
                    .into_par_iter()
                    .map(|x| {
                        let i = ((y - r0) * tx + x) as usize;
                        ctx.tile(x, y, &entries[offsets[i] as usize..offsets[i + 1] as usize])
                    })
                    .collect::<Result<_>>()?;
                for (x, (samples, visible, _)) in tiles.iter().enumerate() {
                    let (x0, y0) = (x as i32 * TILE, y * TILE);
                    write_pixels(out, samples, x0, y0, ws as i32, hs as i32, s);
                    write_exposure(out, visible, x0, y0, s);
                }
                Ok(tiles.into_iter().map(|(_, _, c)| c).collect())
            })
            .collect::<Result<_>>()?;
        release_scratch();
        stats.ms_tiles += ms(t);
        for counts in rows.iter().flatten() {
            stats.intervals += counts.intervals;
            stats.pieces += counts.pieces;
            stats.splits += counts.splits;
            stats.tests += counts.tests;
            stats.spans += counts.spans;
            stats.ms_cover += counts.ns_cover as f64 * 1e-6;
            stats.ms_resolve += counts.ns_resolve as f64 * 1e-6;
        }
        Ok(())
    }
}

/// The tiles `[x0, y0, x1, y1)` a prim's bounds reach (unclipped to the image).
fn tiles_of(p: &Prim) -> (i32, i32, i32, i32) {
    let b = p.bbox;
    let (y0, y1) = tile_rows(b[1], b[3]);
    (b[0] / TILE, y0, (b[2] - 1) / TILE + 1, y1)
}

/// The error of a frame whose prims' bounds span `bound` tiles, past [`MAX_BIN_ENTRIES`].
fn too_many_bins(bound: u64) -> Error {
    Error::value(
        "draws",
        format!(
            "the moving triangles' swept bounds span {bound} tiles in all, past the budget of \
             {MAX_BIN_ENTRIES} ({} MiB); use fewer or smaller triangles, fewer segments or a \
             smaller image",
            (MAX_BIN_ENTRIES * 8) >> 20
        ),
    )
}

/// Tile bins of the tile rows `r0..r1`: `offsets` (tiles + 1) into `entries` (prim indices,
/// in prim order per tile).
fn bin(prims: &[Prim], tx: i32, r0: i32, r1: i32) -> Result<(Vec<u32>, Vec<u32>)> {
    let bound: u64 = prims
        .par_iter()
        .map(|p| {
            let (a, b, c, d) = tiles_of(p);
            ((c - a) * (d - b)) as u64
        })
        .sum();
    if bound > MAX_BIN_ENTRIES {
        return Err(too_many_bins(bound));
    }
    let pairs: Vec<Vec<(u32, u32)>> = prims
        .par_chunks(4096)
        .enumerate()
        .map(|(ci, chunk)| {
            let mut v = Vec::new();
            for (j, p) in chunk.iter().enumerate() {
                let (a, b, c, d) = tiles_of(p);
                let sep = hull::Separator::new(p.bbox, &p.hull[..p.nhull as usize]);
                for y in b.max(r0)..d.min(r1) {
                    for x in a..c.min(tx) {
                        let r = [x * TILE, y * TILE, (x + 1) * TILE, (y + 1) * TILE];
                        if sep.overlaps(r[0], r[1], r[2], r[3]) {
                            v.push((((y - r0) * tx + x) as u32, (ci * 4096 + j) as u32));
                        }
                    }
                }
            }
            v
        })
        .collect();
    let n = (tx * (r1 - r0)) as usize;
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

/// The frame's pixel rows `y0..` that one row of tiles writes.
struct Band<'a> {
    rgba: &'a mut [f32],
    depth: &'a mut [f32],
    ids: &'a mut [i32],
    velocity: &'a mut [f32],
    /// The exposure channel's rows, when it is on.
    exposure: Option<ExposureBand<'a>>,
    /// Pixels per row.
    width: usize,
    /// The band's first pixel row in the frame.
    y0: i32,
}

/// Box resolve of a tile's samples into the band's pixels: colour mean; depth, id and velocity
/// of the nearest sample (the first in row order on ties).
fn write_pixels(
    band: &mut Band,
    samples: &[SampleOut],
    x0: i32,
    y0: i32,
    ws: i32,
    hs: i32,
    s: i32,
) {
    let w = band.width;
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
            let i = (py - band.y0) as usize * w + px as usize;
            for k in 0..4 {
                band.rgba[4 * i + k] = if s == 1 { c[k] } else { c[k] * norm };
            }
            if let Some(b) = best {
                band.depth[i] = b.depth;
                band.ids[i] = b.id;
                band.velocity[2 * i] = b.velocity[0];
                band.velocity[2 * i + 1] = b.velocity[1];
            }
        }
    }
}

/// The exposure channel's pixel rows of one band: (rows, W, planes) each.
struct ExposureBand<'a> {
    fraction: &'a mut [f32],
    first: &'a mut [f32],
    last: &'a mut [f32],
    planes: usize,
}

/// Adds the objects visible at a tile's samples to the band's exposure (when it is on): per
/// pixel and object, the mean over the pixel's samples of the filter's weight of the time the
/// object is in front there (a sample where it never is counts 0), and the earliest first and
/// latest last instant over them (NaN where it never is in front).
fn write_exposure(band: &mut Band, visible: &[Visible], x0: i32, y0: i32, s: i32) {
    let Some(ex) = &mut band.exposure else {
        return;
    };
    let norm = 1.0 / f64::from(s * s);
    for v in visible {
        let (sx, sy) = (x0 + v.sample as i32 % TILE, y0 + v.sample as i32 / TILE);
        let plane = if v.id < 0 {
            ex.planes - 1
        } else {
            v.id as usize
        };
        if plane >= ex.planes {
            continue; // ids are checked against the planes by `validate`
        }
        let i = ((sy / s - band.y0) as usize * band.width + (sx / s) as usize) * ex.planes + plane;
        ex.fraction[i] += (v.weight * norm) as f32;
        // `min` and `max` of NaN (never seen so far) and a number are the number
        ex.first[i] = ex.first[i].min(v.first);
        ex.last[i] = ex.last[i].max(v.last);
    }
}
