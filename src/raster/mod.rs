//! The CPU rasterizer: camera, clipping, triangle setup, binning, tiles, blending, buffers.
//!
//! Pipeline of one frame (`rasterize`):
//! 1. transform: vertices projected and snapped to fixed point once each (clip-space positions
//!    kept only when velocity needs them), previous positions to homogeneous pixels, normals;
//! 2. setup (parallel over runs of faces): clip against near/far and a guard band, cull back
//!    faces, orient, bound, and give small triangles the box of the samples they cover
//!    (`setup.rs`, `clip.rs`, `coverage.rs`);
//! 3. binning into 64x64-sample tiles, in submission order, each bin holding copies of its
//!    triangles (`bins.rs`);
//! 4. tiles in parallel (rayon): an opaque pass with a visibility buffer, then a transparent pass
//!    with per-sample fragment lists composited exactly or unsorted (`tile.rs`, `blend.rs`, and
//!    past `FRAGMENT_CAP` a sample the k-buffer of `kbuffer.rs`), then
//!    the box resolve into the frame (`buffers.rs`).
//!
//! Every step is deterministic and no step depends on how work is split between threads, so the
//! output is bit-identical for any thread count.
// Index loops over 3- and 4-vectors read better than iterator chains here; NaN-rejecting
// `!(x > y)` comparisons are intended.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]
mod background;
mod bins;
mod blend;
mod buffers;
mod camera;
mod clip;
mod coverage;
mod draw;
mod fragment;
mod interp;
mod kbuffer;
mod options;
mod setup;
mod shade;
mod tile;

pub use background::Background;
pub use blend::FRAGMENT_CAP;
pub use buffers::Stats;
use buffers::{assume_written, Output};
pub use camera::check_size;
pub use camera::{Camera, MAX_INTERNAL_SIDE, MAX_PIXELS, MAX_SIDE, SAMPLES};
pub use draw::{faces_from_i64, vertex_normals, Draw};
use options::check_options;
pub use options::{Blend, Light, Options, Shading};

use crate::budget::{self, Need};
use crate::error::{Error, Result};
use crate::frame::Frame;
use bins::TILE;
use rayon::prelude::*;
pub use setup::on_sample_grid;
use setup::{Chunk, Screen, Viewport};
use shade::{homogeneous_pixel, Prepared, Shader};
use std::cell::RefCell;
use std::time::Instant;
use tile::{TileReport, TileScratch};

/// Faces set up per parallel job (a clipped face may become up to 7 triangles, so a chunk
/// holds at most 28672 < 2^16 triangles).
const CHUNK_FACES: usize = 4096;

/// The draw's vertices projected to the viewport (for the set-up), in clip space when shading
/// needs them (velocity), and what shading needs per vertex.
fn transform(
    draw: &Draw,
    vp: glam::DMat4,
    viewport: &Viewport,
    opts: &Options,
    w: f64,
    h: f64,
) -> (Prepared, Screen) {
    let project = |p: &[f64; 3]| setup::clip_position(&vp, p);
    let vertices = draw.vertices.par_iter().with_min_len(4096);
    let mut screen = Screen::default();
    let clip: Vec<[f64; 4]> = if draw.previous.is_some() {
        let (clip, pos_attr): (Vec<[f64; 4]>, (Vec<_>, Vec<_>)) = vertices
            .map(|p| {
                let c = project(p);
                (c, viewport.project(&c))
            })
            .unzip();
        (screen.pos, screen.attr) = pos_attr;
        clip
    } else {
        (screen.pos, screen.attr) = vertices.map(|p| viewport.project(&project(p))).unzip();
        Vec::new()
    };
    let prev = draw.previous.as_ref().map(|prev| {
        prev.par_iter()
            .with_min_len(4096)
            .map(|p| homogeneous_pixel(&project(p), w, h))
            .collect()
    });
    let normals = match (draw.shading.unwrap_or(opts.shading), &draw.normals) {
        (Shading::Flat, _) => None,
        (Shading::Lambert, Some(n)) => Some(n.clone()),
        (Shading::Lambert, None) => Some(vertex_normals(&draw.vertices, &draw.faces)),
    };
    (
        Prepared {
            clip,
            prev,
            normals,
        },
        screen,
    )
}

thread_local! {
    /// Each thread's tile buffers, kept across tiles and frames: a tile resets what it reads, so
    /// reuse changes no result, and the ~300 KB of buffers (and the fragment lists grown to the
    /// frame's depth complexity, at most `FRAGMENT_CAP` fragments a sample) are not allocated
    /// and page-faulted again per frame.
    static SCRATCH: RefCell<TileScratch> = RefCell::new(TileScratch::default());
}

thread_local! {
    /// The bins of this thread's last frame: their buffers are reused by the next frame.
    static KEPT_BINS: RefCell<bins::Bins> = RefCell::new(bins::Bins::default());
}

/// References the kept bins may hold room for between frames (4 + 100 bytes each).
const KEEP_REFS: usize = 1 << 19;

/// Runs `f` with this thread's tile buffers (fresh ones if they are already in use).
fn with_scratch<R>(f: impl FnOnce(&mut TileScratch) -> R) -> R {
    SCRATCH.with(|cell| match cell.try_borrow_mut() {
        Ok(mut scratch) => {
            let out = f(&mut scratch);
            scratch.trim();
            out
        }
        Err(_) => f(&mut TileScratch::default()),
    })
}

/// Bytes a vertex takes while a frame is drawn: its fixed-point position and residuals, clip
/// position and previous position (velocity), normal.
const VERTEX_BYTES: u64 = 8 + 12 + 32 + 32 + 12;

/// What a frame allocates before binning: the frame (32 bytes a pixel), each vertex's
/// transform and each face's set-up triangle (more when clipped). The threads' tile buffers
/// are not counted: they are kept between frames and bounded whatever the frame (~180 KB a
/// thread, and the transparent pass's lists at most `FRAGMENT_CAP` fragments a sample, ~14 MB
/// a thread at the deepest).
fn frame_need(camera: &Camera, draws: &[Draw]) -> Result<Need> {
    let vertices: u64 = draws.iter().map(|d| d.vertices.len() as u64).sum();
    let faces: u64 = draws.iter().map(|d| d.faces.len() as u64).sum();
    Need::new("rasterize")
        .add(
            &[
                ("width", u64::from(camera.width)),
                ("height", u64::from(camera.height)),
            ],
            32,
        )?
        .add(&[("vertices", vertices)], VERTEX_BYTES)?
        .add(
            &[("faces", faces)],
            std::mem::size_of::<setup::Tri>() as u64,
        )
}

/// Renders `draws` seen by `camera`: the frame (velocity only when a draw carries previous
/// positions) and its counts and timings. Errors name the offending argument.
pub fn rasterize(camera: &Camera, draws: &[Draw], opts: &Options) -> Result<(Frame, Stats)> {
    rasterize_over(camera, draws, opts, None)
}

/// Checks a frame's request before anything is allocated: the size, options, the background's
/// lengths (its values are checked by the tiles as they load them), the draws, the number of
/// set-up jobs and the memory the frame needs before binning (returned).
fn check_frame(
    camera: &Camera,
    draws: &[Draw],
    opts: &Options,
    background: Option<&Background>,
) -> Result<Need> {
    check_size(camera.width, camera.height, opts.samples)?;
    check_options(opts)?;
    if let Some(bg) = background {
        let s = opts.samples as usize;
        bg.validate_shape(camera.width as usize * s, camera.height as usize * s)?;
    }
    for d in draws {
        d.validate()?;
    }
    let n_chunks: usize = draws
        .iter()
        .map(|d| d.faces.len().div_ceil(CHUNK_FACES))
        .sum();
    if n_chunks >= 1 << 16 {
        return Err(Error::value(
            "draws",
            "too many faces or draws in one frame",
        ));
    }
    let need = frame_need(camera, draws)?;
    need.check()?;
    Ok(need)
}

/// Sets up every draw's faces, runs of `CHUNK_FACES` in parallel, in submission order.
fn setup_chunks(
    draws: &[Draw],
    vp: &glam::DMat4,
    screens: &[Screen],
    viewport: &Viewport,
) -> Vec<Chunk> {
    let jobs: Vec<(usize, std::ops::Range<usize>)> = draws
        .iter()
        .enumerate()
        .flat_map(|(di, d)| {
            (0..d.faces.len())
                .step_by(CHUNK_FACES)
                .map(move |a| (di, a..(a + CHUNK_FACES).min(d.faces.len())))
        })
        .collect();
    jobs.into_par_iter()
        .map(|(di, range)| {
            setup::setup_chunk(di as u32, &draws[di], vp, &screens[di], range, viewport)
        })
        .collect()
}

/// Renders every tile of `bins` in parallel over `background` (or nothing) and resolves it
/// into `out`, the frame's `w` x `h` pixels of `s` x `s` samples; the tiles' reports summed.
fn render_tiles(
    bins: &bins::Bins,
    shader: &Shader,
    background: Option<&Background>,
    out: &Output,
    [w, h, s]: [u32; 3],
) -> TileReport {
    let tiles_x = bins.tiles_x;
    let pixels_per_tile = (TILE as u32 / s) as usize;
    (0..bins.tiles_x * bins.tiles_y)
        .into_par_iter()
        .map(|t| {
            let (tx, ty) = (t % tiles_x, t / tiles_x);
            let px = [
                tx * pixels_per_tile,
                ty * pixels_per_tile,
                ((tx + 1) * pixels_per_tile).min(w as usize),
                ((ty + 1) * pixels_per_tile).min(h as usize),
            ];
            let s = s as usize;
            let rect = [px[0] * s, px[1] * s, px[2] * s, px[3] * s].map(|v| v as i32);
            let (refs, tris) = bins.tile(t);
            with_scratch(|scratch| {
                let mut report = match (refs.is_empty(), background) {
                    (true, None) => {
                        scratch.samples.fill(blend::Sample::BACKGROUND);
                        TileReport::default()
                    }
                    (true, Some(bg)) => TileReport {
                        bad_background: bg.load(rect, &mut scratch.zbuf, &mut scratch.samples),
                        ..Default::default()
                    },
                    _ => tile::render_tile(
                        rect,
                        refs,
                        tris,
                        shader,
                        shader.opts.blend,
                        background,
                        scratch,
                    ),
                };
                let t = Instant::now();
                // SAFETY: tiles partition the frame, so this rectangle is written by this task only.
                unsafe { out.write_tile(&scratch.samples, px, s) };
                report.ms[3] = (t.elapsed()).as_secs_f64() * 1e3;
                report
            })
        })
        .reduce(TileReport::default, TileReport::add)
}

/// Renders `draws` seen by `camera` over the opaque `background` (one entry per sample, see
/// `background.rs`), or over nothing when None. Errors name the offending argument.
pub fn rasterize_over(
    camera: &Camera,
    draws: &[Draw],
    opts: &Options,
    background: Option<&Background>,
) -> Result<(Frame, Stats)> {
    let t0 = Instant::now();
    let need = check_frame(camera, draws, opts, background)?;
    let (w, h) = (camera.width, camera.height);
    let s = opts.samples;
    let vp_matrix = camera.view_projection();
    let mut frame = Frame::with_capacity(w, h, draws.iter().any(|d| d.previous.is_some()))?;

    // 1. Transform.
    let viewport = Viewport::new(w * s, h * s);
    let (prepared, screens): (Vec<Prepared>, Vec<Screen>) = draws
        .iter()
        .map(|d| transform(d, vp_matrix, &viewport, opts, f64::from(w), f64::from(h)))
        .unzip();
    let t1 = Instant::now();

    // 2. Set-up.
    let chunks = setup_chunks(draws, &vp_matrix, &screens, &viewport);
    let t2 = Instant::now();

    // 3. Binning.
    let mut bins = KEPT_BINS.with(RefCell::take);
    bins.build(&chunks, viewport.ws, viewport.hs, need)?;
    let t3 = Instant::now();

    // 4. Tiles.
    let shader = Shader {
        draws,
        prepared: &prepared,
        chunks: &chunks,
        opts,
        width: f64::from(w),
        height: f64::from(h),
    };
    let out = Output::new(&mut frame);
    let report = render_tiles(&bins, &shader, background, &out, [w, h, s]);
    if report.refused > 0 {
        return Err(budget::refused("draws", report.refused));
    }
    // The tiles partition the frame, so together they loaded every sample of the background's
    // window: a bad value anywhere in it was seen (rendering over it reads no value as an index
    // and cannot fail). The full check names it.
    if let (true, Some(bg)) = (report.bad_background, background) {
        bg.validate_values((w * s) as usize, (h * s) as usize)?;
        return Err(Error::value(
            "background",
            "depth must be > 0 and rgba finite",
        ));
    }
    // SAFETY: the tiles partition the frame (tiles_x * tiles_y tiles of pixels_per_tile
    // pixels, clamped to the image, cover every pixel) and each wrote its rectangle above.
    unsafe { assume_written(&mut frame) };
    let t4 = Instant::now();

    if bins.refs.capacity() <= KEEP_REFS {
        bins.tris.clear();
        KEPT_BINS.with(|kept| kept.replace(bins));
    }
    let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
    let stats = Stats {
        triangles: chunks.iter().map(|c| c.tris.len() as u64).sum(),
        fragments: report.fragments,
        approximated: report.approximated,
        culled: chunks.iter().map(|c| c.culled).sum(),
        clipped: chunks.iter().map(|c| c.clipped).sum(),
        ms_transform: ms(t0, t1),
        ms_setup: ms(t1, t2),
        ms_bin: ms(t2, t3),
        ms_raster: ms(t3, t4),
        ms_coverage: report.ms[0],
        ms_shade: report.ms[1],
        ms_transparent: report.ms[2],
        ms_resolve: report.ms[3],
        ms_total: ms(t0, t4),
    };
    Ok((frame, stats))
}

#[cfg(test)]
mod tests;
