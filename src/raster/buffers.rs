//! The frame's buffers (colour, depth, ids, velocity) and the box resolve of supersampled tiles.
//!
//! Resolve: the colour of a pixel is the mean of its s x s samples (a box filter). Depth, id and
//! velocity come from the pixel's *nearest* sample (smallest depth; the first in row order on
//! ties), so they always describe one real surface rather than a blend of two.
use super::bins::TILE;
use super::blend::Sample;
use crate::budget::try_reserve;
use crate::error::Result;

/// Timings and counts of one frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    /// Triangles after clipping and culling (those rasterized).
    pub triangles: u64,
    /// Samples covered by those triangles (both passes).
    pub fragments: u64,
    /// Samples (of the supersampled image) holding more than `FRAGMENT_CAP` (32) transparent
    /// fragments with `Blend::Exact`: their nearest 32 were composited exactly over the rest
    /// merged into one layer (alpha exact, colour an alpha-weighted mean).
    pub approximated: u64,
    /// Faces culled as back-facing.
    pub culled: u64,
    /// Faces clipped against the near or far plane or the guard band.
    pub clipped: u64,
    /// Milliseconds transforming vertices.
    pub ms_transform: f64,
    /// Milliseconds setting up triangles.
    pub ms_setup: f64,
    /// Milliseconds binning triangles into tiles.
    pub ms_bin: f64,
    /// Milliseconds rasterizing and resolving the tiles (wall clock; the four stages below are
    /// its parts, each summed over the tiles, so with several threads they add up to more).
    pub ms_raster: f64,
    /// Thread milliseconds of the opaque pass's coverage and depth test.
    pub ms_coverage: f64,
    /// Thread milliseconds shading the opaque pass's visible samples.
    pub ms_shade: f64,
    /// Thread milliseconds of the transparent pass: coverage, depth test, shading, compositing.
    pub ms_transparent: f64,
    /// Thread milliseconds resolving samples into the frame's buffers.
    pub ms_resolve: f64,
    /// Milliseconds for the whole frame.
    pub ms_total: f64,
}

/// A rendered frame: row-major buffers of `height` x `width` pixels.
#[derive(Clone, Debug, Default)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// (H,W,4) premultiplied linear RGBA.
    pub rgba: Vec<f32>,
    /// (H,W) view-axis distance of the nearest surface, inf for background.
    pub depth: Vec<f32>,
    /// (H,W) object id of the nearest surface, -1 for background.
    pub ids: Vec<i32>,
    /// (H,W,2) screen motion in pixels of the nearest surface.
    pub velocity: Vec<f32>,
    /// Counts and timings of the frame.
    pub stats: Stats,
}

/// Raw pointers into the frame's buffers, shared by the tile workers. Each tile writes only its
/// own pixel rectangle, and rectangles of different tiles are disjoint.
pub struct Output {
    rgba: *mut f32,
    depth: *mut f32,
    ids: *mut i32,
    velocity: *mut f32,
    width: usize,
    height: usize,
}

// SAFETY: the pointers are only written through `write_tile`, whose callers give each tile a
// distinct rectangle; no element is ever written by two threads, and none is read.
unsafe impl Send for Output {}
unsafe impl Sync for Output {}

impl Frame {
    /// A frame of the given size with background-initialised buffers.
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Frame {
            width,
            height,
            rgba: vec![0.0; 4 * n],
            depth: vec![f32::INFINITY; n],
            ids: vec![-1; n],
            velocity: vec![0.0; 2 * n],
            stats: Stats::default(),
        }
    }

    /// A frame of the given size whose buffers are allocated but empty (length 0), to be
    /// filled by the tiles through `output` and then `assume_written`: the tiles write every
    /// pixel, so filling the buffers first would only write the frame's 32 bytes a pixel twice.
    /// An allocation the system refuses is an error naming `width`.
    pub fn unwritten(width: u32, height: u32) -> Result<Self> {
        let n = width as usize * height as usize;
        let mut frame = Frame {
            width,
            height,
            ..Default::default()
        };
        try_reserve(&mut frame.rgba, 4 * n, "width")?;
        try_reserve(&mut frame.depth, n, "width")?;
        try_reserve(&mut frame.ids, n, "width")?;
        try_reserve(&mut frame.velocity, 2 * n, "width")?;
        Ok(frame)
    }

    /// The pointers the tiles write through (into the buffers' capacity). `self` must outlive
    /// every use.
    pub fn output(&mut self) -> Output {
        Output {
            rgba: self.rgba.as_mut_ptr(),
            depth: self.depth.as_mut_ptr(),
            ids: self.ids.as_mut_ptr(),
            velocity: self.velocity.as_mut_ptr(),
            width: self.width as usize,
            height: self.height as usize,
        }
    }

    /// Gives the buffers of an `unwritten` frame their full length.
    ///
    /// # Safety
    /// Every pixel of the frame must have been written through `output` (`Output::write_tile`
    /// over tiles that cover the frame).
    pub unsafe fn assume_written(&mut self) {
        let n = self.width as usize * self.height as usize;
        debug_assert!(self.depth.capacity() >= n && self.rgba.capacity() >= 4 * n);
        // SAFETY: the capacities were reserved by `unwritten` and the caller guarantees every
        // element up to these lengths was written (f32 and i32 have no invalid bit patterns).
        unsafe {
            self.rgba.set_len(4 * n);
            self.depth.set_len(n);
            self.ids.set_len(n);
            self.velocity.set_len(2 * n);
        }
    }
}

impl Output {
    /// Resolves the tile's samples (row stride TILE) covering pixels [px0, px1) x [py0, py1)
    /// with `s` x `s` samples per pixel and writes them.
    ///
    /// # Safety
    /// The pixel rectangle must lie inside the frame and no other thread may write it.
    pub unsafe fn write_tile(&self, samples: &[Sample], px: [usize; 4], s: usize) {
        // SAFETY: the caller's contract, passed on.
        unsafe {
            match s {
                1 => self.resolve::<1>(samples, px),
                2 => self.resolve::<2>(samples, px),
                4 => self.resolve::<4>(samples, px),
                _ => unreachable!("samples are checked to be 1, 2 or 4"),
            }
        }
    }

    /// `write_tile` for `S` x `S` samples a pixel.
    ///
    /// # Safety
    /// As `write_tile`.
    #[inline(always)]
    unsafe fn resolve<const S: usize>(&self, samples: &[Sample], px: [usize; 4]) {
        let [px0, py0, px1, py1] = px;
        debug_assert!(px1 <= self.width && py1 <= self.height);
        let norm = 1.0 / (S * S) as f32;
        for y in py0..py1 {
            for x in px0..px1 {
                let mut c = [0.0f32; 4];
                // the nearest sample: the first of the largest 1/w, none when all are 0
                let mut best = None;
                let mut best_invw = Sample::BACKGROUND.invw;
                for j in 0..S {
                    let row = ((y - py0) * S + j) * TILE as usize + (x - px0) * S;
                    for (i, smp) in samples[row..row + S].iter().enumerate() {
                        for k in 0..4 {
                            c[k] += smp.rgba[k];
                        }
                        if smp.invw > best_invw {
                            best_invw = smp.invw;
                            best = Some(row + i);
                        }
                    }
                }
                let best = best.map_or(Sample::BACKGROUND, |i| samples[i]);
                let o = y * self.width + x;
                // SAFETY: (x, y) is inside the frame and owned by this tile (caller's contract).
                unsafe {
                    for k in 0..4 {
                        *self.rgba.add(4 * o + k) = if S == 1 { c[k] } else { c[k] * norm };
                    }
                    *self.depth.add(o) = if best.invw > 0.0 {
                        1.0 / best.invw
                    } else {
                        f32::INFINITY
                    };
                    *self.ids.add(o) = best.id;
                    *self.velocity.add(2 * o) = best.velocity[0];
                    *self.velocity.add(2 * o + 1) = best.velocity[1];
                }
            }
        }
    }
}
