//! The per-pixel velocity-buffer motion blur of game engines: McGuire et al. 2012's
//! reconstruction filter with Guertin et al. 2014's improvements (tile max velocity, neighbour
//! max, a gather along both the neighbourhood's and the pixel's own velocity, foreground and
//! background classified by depth and accumulated apart).
//!
//! Input: one sharp frame at mid-shutter, premultiplied `rgba` `(h, w, 4)`, view-axis `depth`
//! `(h, w)` (`inf` where nothing is hit) and `velocity` `(h, w, 2)`, the screen motion of each
//! pixel's surface over the whole shutter (pixels). A surface at pixel `Y` with velocity `v`
//! sweeps the segment `Y + s v / 2`, `s` in `[-1, 1]`, during the shutter.
//!
//! 1. **Tile max**: the velocity of largest length in each `tile x tile` block, as a half
//!    vector `v / 2` clamped to `tile` pixels (so that a 3x3 neighbourhood of tiles holds every
//!    surface that can reach a pixel; longer motion is shortened, as in the paper).
//! 2. **Neighbour max**: the largest of the 3x3 tiles around each tile.
//! 3. **Gather** at pixel `X` (half velocity `c`, neighbour max `n`): when `|n| < 0.5` the pixel
//!    is copied. Otherwise `samples` taps are placed symmetrically at `X +- t n` (and, when
//!    `|c| >= 0.5`, half of them at `X +- t c_r`, Guertin's second direction, which recovers a
//!    pixel whose motion differs from its neighbourhood's; `c_r` is the half velocity of the
//!    first moving pixel of the pixel's run of eight, below), `t = (i + j) / m` with a jitter `j`
//!    in `[0, 1)` shared by a run of eight pixels of a row (a hash of the run's first pixel, so
//!    the result is deterministic; a tile's rows are cut into runs from its left edge, the last
//!    one shorter when the tile is not a multiple of 8 wide), each taken at the nearest pixel
//!    `Y` (taps outside the image are dropped). Along `n` and along `c_r`, a pixel's tap is the
//!    run's first pixel's nearest pixel moved along the row by the pixel's place in the run (the
//!    nearest pixel of its own tap up to rounding), so the run's taps are eight neighbouring
//!    pixels at one distance: one load each rather than a gather (the moving pixels of a run
//!    share one direction as they share one jitter). A tap at distance `d` is split by depth
//!    into a foreground part `f = clamp(0.5 - (z_Y - z_X) / (s z), 0, 1)` and a background
//!    part `1 - f` (`s` the relative `soft_depth`, `z` the nearer depth): the foreground part
//!    counts when the tap's own motion reaches `X` (`clamp(|v_Y / 2| - d + 1, 0, 1)`), the
//!    background part when the pixel's own motion reaches the tap (`clamp(|c| - d + 1, 0, 1)`).
//!    The centre pixel is a tap at `d = 0`. With `N` taps, weighted sums `F` (foreground) and `B`
//!    (background) of colours and their weights `wf`, `wb`:
//!    `out = (F + B) / N + (B / wb) * clamp(1 - (wf + wb) / N, 0, 1)`: each tap stands for `1/N`
//!    of the shutter, and the taps that reach nothing are filled with the pixel's background.
//!
//! Most of a frame does not move: a tap whose distance is at least the half speed of every
//! pixel it can land on, and the pixel's own, plus one, weighs nothing in either sum and only
//! counts in `N`. A grid of 16x16-pixel cells (`reach`) bounds those speeds, so such taps are
//! counted without reading the images, and a still pixel's gather stops at the first tap whose
//! distance passes that bound (the taps along one direction are placed at increasing distance):
//! the same bits as gathering every tap (the skipped terms are exact zeros), at the cost of the
//! taps that can weigh something.
//!
//! Rows are gathered in parallel and read only the inputs, so the result is bit-identical for
//! any thread count.
use std::mem::MaybeUninit;

use rayon::prelude::*;

use super::reach::{Reach, CELL};
use super::{check_finite, check_image, filled, filled_with};
use crate::error::{Error, Result};

/// Largest number of gather taps per pixel.
pub const MAX_TAPS: usize = 256;

/// Options of [`reconstruct`].
#[derive(Clone, Copy, Debug)]
pub struct ReconstructParams {
    /// Taps per pixel, 2 to 256 (taps come in pairs: an odd count uses one fewer).
    pub samples: usize,
    /// Tile size in pixels (>= 1); half velocities are clamped to it.
    pub tile: usize,
    /// Depth softness of the foreground/background split, relative to depth (> 0).
    pub soft_depth: f32,
}

/// A deterministic value in `[0, 1)` per pixel (an integer hash).
fn jitter(x: usize, y: usize) -> f32 {
    let mut h = (x as u32).wrapping_mul(0x8da6_b343) ^ (y as u32).wrapping_mul(0xd816_3841);
    h ^= h >> 13;
    h = h.wrapping_mul(0x5bd1_e995);
    h ^= h >> 15;
    (h >> 8) as f32 / (1u32 << 24) as f32
}

fn len2(v: [f32; 2]) -> f32 {
    v[0] * v[0] + v[1] * v[1]
}

/// The longest velocity of a `(h, w, 2)` velocity buffer, `max sqrt(vx^2 + vy^2)` in float64
/// (what picks the default tile), NaN when any length is NaN, 0 for no pixels. The same for
/// any thread count (a maximum does not depend on the order).
pub fn max_speed(velocity: &[f32]) -> f64 {
    // sqrt is correctly rounded and non-decreasing, so the longest length is the square root of
    // the largest squared length: one root for the image, not one a pixel.
    let (most, nan) = velocity
        .par_chunks(2 << 12)
        .map(longest2)
        .reduce(|| (0.0, false), |a, b| (a.0.max(b.0), a.1 | b.1));
    if nan {
        f64::NAN
    } else {
        most.sqrt()
    }
}

/// [`max_speed`] of the window `(y0, y1, x0, x1)` of a `w` pixels wide velocity buffer, read
/// in place (the same value as of a copy of the window: a maximum does not depend on the
/// order).
pub fn max_speed_in(velocity: &[f32], w: usize, (y0, y1, x0, x1): Window) -> f64 {
    let rows = (y0..y1)
        .into_par_iter()
        .with_min_len((1usize << 13).div_ceil((x1 - x0).max(1)));
    let (most, nan) = rows
        .map(|y| longest2(&velocity[2 * (y * w + x0)..2 * (y * w + x1)]))
        .reduce(|| (0.0, false), |a, b| (a.0.max(b.0), a.1 | b.1));
    if nan {
        f64::NAN
    } else {
        most.sqrt()
    }
}

/// The largest squared length (float64) of the velocities `c` (pairs), and whether one is NaN.
/// Lanes of 8 pixels keep them apart, so that the loop vectorises.
fn longest2(c: &[f32]) -> (f64, bool) {
    let mut lanes = [0.0f64; 8];
    let mut nan = false;
    let mut pixels = c.chunks_exact(16);
    for p in &mut pixels {
        for k in 0..8 {
            let (x, y) = (p[2 * k] as f64, p[2 * k + 1] as f64);
            let l = x * x + y * y;
            nan |= l.is_nan();
            lanes[k] = lanes[k].max(l);
        }
    }
    for v in pixels.remainder().chunks_exact(2) {
        let (x, y) = (v[0] as f64, v[1] as f64);
        let l = x * x + y * y;
        nan |= l.is_nan();
        lanes[0] = lanes[0].max(l);
    }
    (lanes.iter().fold(0.0f64, |m, l| m.max(*l)), nan)
}

/// The largest squared length of `v` (0 for none), over 8 lanes.
#[cfg(test)]
fn max_len2(v: &[[f32; 2]]) -> f32 {
    let mut lanes = [0.0f32; 8];
    let mut chunks = v.chunks_exact(8);
    for c in &mut chunks {
        for k in 0..8 {
            lanes[k] = lanes[k].max(len2(c[k]));
        }
    }
    let rest = chunks
        .remainder()
        .iter()
        .fold(0.0f32, |m, v| m.max(len2(*v)));
    lanes.iter().fold(rest, |m, l| m.max(*l))
}

/// Half velocities clamped to `tile` pixels and their lengths, per pixel; None when a
/// velocity is not finite (the every-tap oracle's; [`halves`] is the filter's).
#[cfg(test)]
fn half_velocities(velocity: &[f32], tile: f32) -> Option<(Vec<[f32; 2]>, Vec<f32>)> {
    const BLOCK: usize = 1 << 14;
    let n = velocity.len() / 2;
    let mut finite = true;
    let mut speed = Vec::new();
    let half = filled_with(n, |half| {
        speed = filled_with(n, |speed| {
            finite = half
                .par_chunks_mut(BLOCK)
                .zip(speed.par_chunks_mut(BLOCK))
                .zip(velocity.par_chunks(2 * BLOCK))
                .map(|((hs, ss), vs)| {
                    let mut ok = true;
                    for ((hv, sv), v) in hs.iter_mut().zip(ss.iter_mut()).zip(vs.chunks_exact(2)) {
                        ok &= v[0].is_finite() & v[1].is_finite();
                        let h = [0.5 * v[0], 0.5 * v[1]];
                        let l = len2(h).sqrt();
                        let c = if l > tile {
                            [h[0] * tile / l, h[1] * tile / l]
                        } else {
                            h
                        };
                        hv.write(c);
                        sv.write(len2(c).sqrt());
                    }
                    ok
                })
                .reduce(|| true, |a, b| a & b);
        });
    });
    finite.then_some((half, speed))
}

/// The tile max of `half` over `tile x tile` blocks, then the 3x3 neighbour max of tiles:
/// `(tiles_x, neighbour max per tile)` (the every-tap oracle's; [`tile_max`] is the
/// filter's).
#[cfg(test)]
fn neighbour_max(half: &[[f32; 2]], w: usize, h: usize, tile: usize) -> (usize, Vec<[f32; 2]>) {
    let (tx, ty) = (w.div_ceil(tile), h.div_ceil(tile));
    // per tile, the first pixel (in row order) of the largest squared length, [0, 0] when all
    // are 0: what folding `longest` over the pixels from [0, 0] gives, found in two passes (a
    // maximum over lanes, then the first pixel that reaches it)
    let tiles: Vec<[f32; 2]> = (0..tx * ty)
        .into_par_iter()
        .map(|t| {
            let (bx, by) = (t % tx, t / tx);
            let (x0, x1) = (bx * tile, ((bx + 1) * tile).min(w));
            let ys = by * tile..((by + 1) * tile).min(h);
            let row = |y: usize| &half[y * w + x0..y * w + x1];
            let most = ys.clone().fold(0.0f32, |m, y| m.max(max_len2(row(y))));
            if most > 0.0 {
                let mut first = ys.flat_map(row).filter(|v| len2(**v) == most);
                *first.next().expect("the maximum is some pixel's")
            } else {
                [0.0; 2]
            }
        })
        .collect();
    (tx, neighbours(&tiles, tx, ty))
}

/// The 3x3 neighbour max of a `tx` x `ty` grid of tile maxima.
fn neighbours(tiles: &[[f32; 2]], tx: usize, ty: usize) -> Vec<[f32; 2]> {
    let longest = |a: [f32; 2], b: [f32; 2]| if len2(b) > len2(a) { b } else { a };
    (0..tx * ty)
        .into_par_iter()
        .map(|t| {
            let (bx, by) = ((t % tx) as i64, (t / tx) as i64);
            let mut m = [0.0f32; 2];
            for dy in -1..=1i64 {
                for dx in -1..=1i64 {
                    let (x, y) = (bx + dx, by + dy);
                    if x >= 0 && y >= 0 && (x as usize) < tx && (y as usize) < ty {
                        m = longest(m, tiles[y as usize * tx + x as usize]);
                    }
                }
            }
            m
        })
        .collect()
}

/// The first pass over the velocities ([`halves`]).
struct Halves {
    /// The lengths of the half velocities clamped to `tile` pixels ([`half_at`]).
    speed: Vec<f32>,
    /// Per row, the largest squared length of `half` over each tile's part of the row (`tx` a
    /// row).
    tile_rows: Vec<f32>,
    /// Per row, the largest `speed` over each reach cell's part of the row (`cw` a row).
    cell_rows: Vec<f32>,
}

/// The pixels `(y0, y1, x0, x1)` (rows `y0..y1`, columns `x0..x1`) outside which every velocity
/// is 0, as the caller knows it (the window a sharp frame drew its moving objects in).
pub type Window = (usize, usize, usize, usize);

/// The lengths of the half velocities clamped to `tile` pixels, per pixel, with the maxima per
/// row that the tile max and the reach cells need, in one pass that also checks the depths:
/// (None when a velocity is not finite, whether every depth is > 0 or inf). The half velocities
/// themselves are not kept ([`half_at`] gives them again where needed). With `moving` a window
/// smaller than the image, only its velocities are read (every other is 0, the caller's
/// promise, so the speeds and maxima are the same); `speed` is then zeroed memory written in
/// the window only, else written once, never zeroed first.
fn halves(
    velocity: &[f32],
    depth: &[f32],
    (w, h): (usize, usize),
    tile: usize,
    moving: Window,
) -> (Option<Halves>, bool) {
    let (tx, cw) = (w.div_ceil(tile), w.div_ceil(CELL));
    let mut tile_rows = vec![0.0f32; h * tx];
    let mut cell_rows = vec![0.0f32; h * cw];
    let (y0, y1, x0, x1) = moving;
    let tl = tile as f32;
    if (y0, y1, x0, x1) == (0, h, 0, w) {
        let rows = (1usize << 14).div_ceil(w);
        let (mut finite, mut deep) = (true, true);
        let speed = filled_with(w * h, |speed| {
            (finite, deep) = speed
                .par_chunks_mut(rows * w)
                .zip(velocity.par_chunks(2 * rows * w))
                .zip(depth.par_chunks(rows * w))
                .zip(tile_rows.par_chunks_mut(rows * tx))
                .zip(cell_rows.par_chunks_mut(rows * cw))
                .map(|((((ss, vs), ds), ts), cs)| {
                    let ok = half_rows(vs, (ss, w), (0, w), (tl, tile), (ts, cs));
                    (ok, deep_enough(ds))
                })
                .reduce(|| (true, true), |a, b| (a.0 & b.0, a.1 & b.1));
        });
        let out = Halves {
            speed,
            tile_rows,
            cell_rows,
        };
        return (finite.then_some(out), deep);
    }
    // zeroed memory: pages the window's rows do not write stay the system's zero pages
    let mut speed = vec![0.0f32; w * h];
    let finite = if y0 < y1 && x0 < x1 {
        let rows = (1usize << 14).div_ceil(x1 - x0);
        // SAFETY: MaybeUninit<f32> has f32's layout; every value is initialised (zeros).
        let sp: &mut [MaybeUninit<f32>] =
            unsafe { std::slice::from_raw_parts_mut(speed.as_mut_ptr().cast(), speed.len()) };
        sp[y0 * w..y1 * w]
            .par_chunks_mut(rows * w)
            .zip(velocity[2 * y0 * w..2 * y1 * w].par_chunks(2 * rows * w))
            .zip(tile_rows[y0 * tx..y1 * tx].par_chunks_mut(rows * tx))
            .zip(cell_rows[y0 * cw..y1 * cw].par_chunks_mut(rows * cw))
            .map(|(((ss, vs), ts), cs)| half_rows(vs, (ss, w), (x0, x1), (tl, tile), (ts, cs)))
            .reduce(|| true, |a, b| a & b)
    } else {
        true
    };
    let deep = depth
        .par_chunks(1 << 14)
        .map(deep_enough)
        .reduce(|| true, |a, b| a & b);
    let out = Halves {
        speed,
        tile_rows,
        cell_rows,
    };
    (finite.then_some(out), deep)
}

/// Whether every depth of `d` is > 0 or inf (not NaN).
fn deep_enough(d: &[f32]) -> bool {
    d.iter().fold(true, |k, d| k & !(d.is_nan() || *d <= 0.0))
}

/// [`half_row`] of each row of `vs` (velocities, `2 w` a row) into the rows of `ss` (speeds,
/// `w` a row) and of the maxima `ts` (`tx` a row) and `cs` (`cw` a row), over the columns
/// `x0..x1` of each row; whether all are finite.
fn half_rows(
    vs: &[f32],
    (ss, w): (&mut [MaybeUninit<f32>], usize),
    (x0, x1): (usize, usize),
    (tl, tile): (f32, usize),
    (ts, cs): (&mut [f32], &mut [f32]),
) -> bool {
    let (tx, cw) = (w.div_ceil(tile), w.div_ceil(CELL));
    // the row's squared lengths and lengths
    let (mut l2, mut sp) = (vec![0.0f32; x1 - x0], vec![0.0f32; x1 - x0]);
    let mut ok = true;
    let rows = ss
        .chunks_mut(w)
        .zip(vs.chunks(2 * w))
        .zip(ts.chunks_mut(tx).zip(cs.chunks_mut(cw)));
    for ((sr, vr), maxima) in rows {
        let (vr, sr) = (&vr[2 * x0..2 * x1], &mut sr[x0..x1]);
        ok &= half_row(vr, (tl, tile), (sr, x0), (&mut l2, &mut sp), maxima);
    }
    ok
}

/// The velocity `v`'s half, clamped to `tl` pixels.
#[inline(always)]
fn clamped_half(v: [f32; 2], tl: f32) -> [f32; 2] {
    let hv = [0.5 * v[0], 0.5 * v[1]];
    let l = len2(hv).sqrt();
    if l > tl {
        [hv[0] * tl / l, hv[1] * tl / l]
    } else {
        hv
    }
}

/// Pixel `i`'s half velocity clamped to `tl` pixels, as [`halves`] computes it.
#[inline(always)]
fn half_at(velocity: &[f32], i: usize, tl: f32) -> [f32; 2] {
    clamped_half([velocity[2 * i], velocity[2 * i + 1]], tl)
}

/// One row of [`halves`]: the lengths `sr` of the half velocities of the velocities `vr`
/// clamped to `tl` pixels (`tile`), the row's columns from `x0` on, the largest squared length
/// over each tile's part of them and the largest length over each cell's part (`maxima`, the
/// whole row's: tiles and cells from column 0), with the squared lengths and the lengths in
/// `l2` and `sp` on the way; whether all are finite. In AVX2 when present (the same IEEE
/// operations, so the same bits; maxima of values >= 0 in any order).
fn half_row(
    vr: &[f32],
    (tl, tile): (f32, usize),
    (sr, x0): (&mut [MaybeUninit<f32>], usize),
    (l2, sp): (&mut [f32], &mut [f32]),
    maxima: (&mut [f32], &mut [f32]),
) -> bool {
    #[inline(always)]
    fn run(
        vr: &[f32],
        (tl, tile): (f32, usize),
        (sr, x0): (&mut [MaybeUninit<f32>], usize),
        (l2, sp): (&mut [f32], &mut [f32]),
        (tr, cr): (&mut [f32], &mut [f32]),
    ) -> bool {
        let w = sr.len();
        let (vr, l2, sp) = (&vr[..2 * w], &mut l2[..w], &mut sp[..w]);
        let mut ok = true;
        for x in 0..w {
            let v = [vr[2 * x], vr[2 * x + 1]];
            ok &= v[0].is_finite() & v[1].is_finite();
            let c = clamped_half(v, tl);
            l2[x] = len2(c);
            sp[x] = l2[x].sqrt();
            sr[x].write(sp[x]);
        }
        // the parts of the columns x0..x0 + w in each block of `size` columns from column 0
        let blocks = |size: usize, v: &[f32], m: &mut [f32]| {
            let mut a = 0;
            while a < w {
                let k = (x0 + a) / size;
                let b = ((k + 1) * size - x0).min(w);
                m[k] = max_lanes(&v[a..b]);
                a = b;
            }
        };
        blocks(tile, l2, tr);
        blocks(CELL, sp, cr);
        ok
    }
    #[cfg(target_arch = "x86_64")]
    if crate::simd::simd_enabled() {
        #[target_feature(enable = "avx2")]
        unsafe fn avx(
            vr: &[f32],
            tile: (f32, usize),
            sr: (&mut [MaybeUninit<f32>], usize),
            rows: (&mut [f32], &mut [f32]),
            maxima: (&mut [f32], &mut [f32]),
        ) -> bool {
            run(vr, tile, sr, rows, maxima)
        }
        // SAFETY: AVX2 was detected.
        return unsafe { avx(vr, (tl, tile), (sr, x0), (l2, sp), maxima) };
    }
    run(vr, (tl, tile), (sr, x0), (l2, sp), maxima)
}

/// Whether every value of `v` is finite (in AVX2 when present).
fn all_finite(v: &[f32]) -> bool {
    #[inline(always)]
    fn run(v: &[f32]) -> bool {
        v.iter().fold(true, |ok, v| ok & v.is_finite())
    }
    #[cfg(target_arch = "x86_64")]
    if crate::simd::simd_enabled() {
        #[target_feature(enable = "avx2")]
        unsafe fn avx(v: &[f32]) -> bool {
            run(v)
        }
        // SAFETY: AVX2 was detected.
        return unsafe { avx(v) };
    }
    run(v)
}

/// The largest of `v` (0 for none, every value >= 0), over 8 lanes.
#[inline(always)]
fn max_lanes(v: &[f32]) -> f32 {
    let mut lanes = [0.0f32; 8];
    let mut chunks = v.chunks_exact(8);
    for c in &mut chunks {
        for k in 0..8 {
            lanes[k] = lanes[k].max(c[k]);
        }
    }
    let rest = chunks.remainder().iter().fold(0.0f32, |m, v| m.max(*v));
    lanes.iter().fold(rest, |m, l| m.max(*l))
}

/// The tile max of [`halves`]' half velocities over `tile x tile` blocks (per tile, the first
/// pixel in row order of the largest squared length, `[0, 0]` when all are 0), then the 3x3
/// neighbour max of tiles: `(tiles_x, neighbour max per tile)`.
fn tile_max(
    hv: &Halves,
    velocity: &[f32],
    (w, h): (usize, usize),
    tile: usize,
) -> (usize, Vec<[f32; 2]>) {
    let (tx, ty) = (w.div_ceil(tile), h.div_ceil(tile));
    let tiles: Vec<[f32; 2]> = (0..tx * ty)
        .into_par_iter()
        .map(|t| {
            let (bx, by) = (t % tx, t / tx);
            let ys = by * tile..((by + 1) * tile).min(h);
            let most = ys
                .clone()
                .fold(0.0f32, |m, y| m.max(hv.tile_rows[y * tx + bx]));
            if most > 0.0 {
                // the first row that reaches it, then its first pixel that does
                let y = ys
                    .into_iter()
                    .find(|y| hv.tile_rows[y * tx + bx] == most)
                    .expect("the maximum is some row's");
                (y * w + bx * tile..y * w + ((bx + 1) * tile).min(w))
                    .map(|i| half_at(velocity, i, tile as f32))
                    .find(|v| len2(*v) == most)
                    .expect("the maximum is some pixel's")
            } else {
                [0.0; 2]
            }
        })
        .collect();
    (tx, neighbours(&tiles, tx, ty))
}

/// The reconstruction filter (module docs): returns `(h, w, 4)` premultiplied RGBA.
pub fn reconstruct(
    rgba: &[f32],
    depth: &[f32],
    velocity: &[f32],
    w: usize,
    h: usize,
    params: ReconstructParams,
) -> Result<Vec<f32>> {
    reconstruct_moving(rgba, depth, velocity, (w, h), params, (0, h, 0, w))
}

/// [`reconstruct`] of a frame whose velocities are 0 outside the window `moving` (`(y0, y1,
/// x0, x1)`, the caller's promise, not checked: the velocity method's sharp frame, drawn over
/// a still layer in that window): only the window's velocities are read, for the same bits.
pub fn reconstruct_moving(
    rgba: &[f32],
    depth: &[f32],
    velocity: &[f32],
    (w, h): (usize, usize),
    params: ReconstructParams,
    moving: Window,
) -> Result<Vec<f32>> {
    let (y0, y1, x0, x1) = moving;
    if !(y0 <= y1 && y1 <= h && x0 <= x1 && x1 <= w) {
        return Err(Error::value(
            "moving",
            format!("({y0}, {y1}, {x0}, {x1}) is not a window of the ({h}, {w}) image"),
        ));
    }
    check_image("rgba", rgba, w, h, 4)?;
    check_image("depth", depth, w, h, 1)?;
    check_image("velocity", velocity, w, h, 2)?;
    // The images are checked within the passes that read them anyway; on any failure the
    // checks run again in their order (rgba, velocity, depth, then the parameters), so the
    // error names what the first failing check names.
    let first_error =
        |e: Error| -> Error { check_inputs(rgba, depth, velocity).err().unwrap_or(e) };
    check_params(params).map_err(first_error)?;
    let (hv, deep) = halves(velocity, depth, (w, h), params.tile, moving);
    let hv = hv.ok_or_else(|| first_error(Error::value("velocity", "contains NaN or inf")))?;
    if !deep {
        return Err(first_error(depth_error()));
    }
    let (tx, nmax) = tile_max(&hv, velocity, (w, h), params.tile);
    // every tap lies within |n| (plus the rounding to a pixel) of its pixel along each axis
    let (nx, ny) = nmax.iter().fold((0.0f32, 0.0f32), |(a, b), n| {
        (a.max(n[0].abs()), b.max(n[1].abs()))
    });
    let reach = Reach::from_rows(&hv.cell_rows, w, h, nx, ny);
    let speed = &hv.speed;
    let g = Gather {
        rgba,
        depth,
        velocity,
        speed,
        w,
        h,
        params,
        reach: &reach,
    };
    let mut finite = true;
    // (the vector gather indexes the images with 32-bit lanes)
    let simd = super::simd() && w * h * 4 < i32::MAX as usize && w < (1 << 24) && h < (1 << 24);
    let out = filled(w * h * 4, |out| {
        finite = out
            .par_chunks_mut(w * 4)
            .enumerate()
            .map(|(y, row)| {
                // the row's pixels tile by tile: one neighbour max (and its length) a tile,
                // not two integer divisions a pixel
                let tiles = &nmax[(y / params.tile) * tx..];
                for (k, xs) in (0..w).step_by(params.tile).enumerate() {
                    let n = tiles[k];
                    let rn = len2(n).sqrt();
                    let end = (xs + params.tile).min(w);
                    if rn < 0.5 {
                        // no pixel of a still neighbourhood moves (|c| <= |n|): `gather`'s
                        // copies, as one
                        let i = y * w;
                        super::write_copy(
                            &mut row[xs * 4..end * 4],
                            &rgba[(i + xs) * 4..(i + end) * 4],
                        );
                        continue;
                    }
                    // the tile's runs of eight pixels (the last may be shorter)
                    for x0 in (xs..end).step_by(8) {
                        let lanes = (end - x0).min(8);
                        // eight pixels side by side (the same bits as one by one); a shorter
                        // run reads eight and keeps its own
                        if simd && x0 + 8 <= w {
                            prefetch(&g, y * w + x0 + AHEAD);
                            let out = &mut row[x0 * 4..(x0 + lanes) * 4];
                            if still8(&g, (x0, y), (n, rn), out)
                                || gather8(&g, (x0, y), (n, rn), out)
                            {
                                continue;
                            }
                        }
                        for x in x0..x0 + lanes {
                            let i = y * w + x;
                            if rn.max(speed[i]) < 0.5 {
                                // `gather`'s copy of a still pixel in a still neighbourhood
                                row[x * 4..x * 4 + 4]
                                    .iter_mut()
                                    .zip(&rgba[i * 4..i * 4 + 4])
                                    .for_each(|(d, s)| _ = d.write(*s));
                            } else {
                                super::put4(row, x, gather(&g, (x, y), x0, (n, rn)));
                            }
                        }
                    }
                }
                all_finite(&rgba[y * w * 4..(y + 1) * w * 4])
            })
            .reduce(|| true, |a, b| a & b);
    });
    if !finite {
        return Err(Error::value("rgba", "contains NaN or inf"));
    }
    Ok(out)
}

/// How many pixels ahead along a row the vector runs ask for their inputs.
const AHEAD: usize = 64;

/// Asks for pixel `i`'s depth, half speed, velocity and colour (and the next 7 pixels'
/// colours) to be brought into the cache: the vector runs read each row's inputs in order, with
/// the taps' reads between them.
#[inline(always)]
fn prefetch(g: &Gather<'_>, i: usize) {
    #[cfg(target_arch = "x86_64")]
    if i < g.w * g.h {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // SAFETY: SSE is x86_64's baseline; a prefetch reads nothing and cannot fault (the last
        // pixel's next colours may lie past the image: the addresses use wrapping_add).
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(g.depth.as_ptr().wrapping_add(i).cast());
            _mm_prefetch::<_MM_HINT_T0>(g.speed.as_ptr().wrapping_add(i).cast());
            _mm_prefetch::<_MM_HINT_T0>(g.velocity.as_ptr().wrapping_add(2 * i).cast());
            _mm_prefetch::<_MM_HINT_T0>(g.rgba.as_ptr().wrapping_add(4 * i).cast());
            _mm_prefetch::<_MM_HINT_T0>(g.rgba.as_ptr().wrapping_add(4 * i + 16).cast());
        }
    }
}

/// The images' checks in their order: finite rgba and velocity, depth > 0 or inf.
fn check_inputs(rgba: &[f32], depth: &[f32], velocity: &[f32]) -> Result<()> {
    check_finite("rgba", rgba)?;
    check_finite("velocity", velocity)?;
    if depth.par_iter().any(|d| d.is_nan() || *d <= 0.0) {
        return Err(depth_error());
    }
    Ok(())
}

fn depth_error() -> Error {
    Error::value("depth", "must be > 0 (inf for no surface), not NaN")
}

fn check_params(params: ReconstructParams) -> Result<()> {
    if !(2..=MAX_TAPS).contains(&params.samples) {
        return Err(Error::value(
            "samples",
            format!("must be in [2, {MAX_TAPS}], got {}", params.samples),
        ));
    }
    if params.tile == 0 {
        return Err(Error::value("tile", "must be >= 1 pixel"));
    }
    if !(params.soft_depth.is_finite() && params.soft_depth > 0.0) {
        return Err(Error::value("soft_depth", "must be finite and > 0"));
    }
    Ok(())
}

/// What every pixel's gather reads besides its tile's neighbour max: the image and its depth,
/// the velocities, the size `w` x `h`, the parameters and the cells' speeds.
#[derive(Clone, Copy)]
struct Gather<'a> {
    rgba: &'a [f32],
    depth: &'a [f32],
    /// The velocities (the half velocities are [`half_at`] of them).
    velocity: &'a [f32],
    /// The half velocities' lengths per pixel.
    speed: &'a [f32],
    w: usize,
    h: usize,
    params: ReconstructParams,
    reach: &'a Reach,
}

/// Past this distance from its pixel a tap weighs nothing when `speed` bounds the half speeds
/// of the tapped pixel and of the pixel itself: `(r - d + 1).clamp(0, 1)` is 0 from
/// `d >= r + 1`, with one pixel more for the rounding of `r + 1`.
#[inline(always)]
fn weightless_from(speed: f32) -> f32 {
    speed + 2.0
}

/// The taps' sums of one pixel: foreground and background colours, their weights, the taps.
#[derive(Clone, Copy)]
struct Sums {
    fg: [f32; 4],
    bg: [f32; 4],
    wf: f32,
    wb: f32,
    taps: f32,
}

/// The pixel a tap at `st dir` (`st = s t`) of pixel `(x, y)` lands on, None off the image:
/// the pixel nearest `(a + 0.5 + st dir_x, y + 0.5 + st dir_y)` moved `x - a` pixels along
/// the row (module docs). Along the neighbour max `a` is the first pixel of `x`'s run of
/// eight, so that the run's taps land on neighbouring pixels; along the pixel's own velocity
/// `a = x` (the pixel nearest its own tap).
#[inline(always)]
fn tap_at(
    (w, h): (usize, usize),
    (a, x, y): (usize, usize, usize),
    st: f32,
    dir: [f32; 2],
) -> Option<(usize, usize)> {
    let px = a as f32 + 0.5 + st * dir[0];
    let py = y as f32 + 0.5 + st * dir[1];
    if !(py >= 0.0 && py < h as f32) {
        return None;
    }
    let sx = px.floor() as i64 + (x - a) as i64;
    if sx < 0 || sx >= w as i64 {
        return None;
    }
    Some((sx as usize, py as usize))
}

/// The distance of a tap at pixel `(sx, sy)` from its pixel `(x, y)`: the pixels' distance,
/// at most `tr` (the tap's `t |dir|`).
#[inline(always)]
fn tap_distance((sx, sy): (usize, usize), (x, y): (usize, usize), tr: f32) -> f32 {
    let (dx, dy) = (sx as f32 - x as f32, sy as f32 - y as f32);
    (dx * dx + dy * dy).sqrt().min(tr)
}

/// The gather of pixel `(x, y)` (module docs); `x0` the first pixel of its run of eight, `n`
/// the neighbour max of its tile, `rn` its length.
fn gather(g: &Gather<'_>, (x, y): (usize, usize), x0: usize, (n, rn): ([f32; 2], f32)) -> [f32; 4] {
    let Gather {
        rgba,
        depth,
        velocity,
        speed,
        w,
        h,
        params,
        reach,
    } = *g;
    let i = y * w + x;
    let c = half_at(velocity, i, params.tile as f32);
    let rc = speed[i];
    if rn.max(rc) < 0.5 {
        return [
            rgba[i * 4],
            rgba[i * 4 + 1],
            rgba[i * 4 + 2],
            rgba[i * 4 + 3],
        ];
    }
    let zx = depth[i];
    let mut sums = Sums {
        fg: [0.0; 4],
        bg: [0.0; 4],
        wf: 0.0,
        wb: 0.0,
        taps: 0.0,
    };
    let tap = |yi: usize, d: f32, s: &mut Sums| {
        let zy = depth[yi];
        let near = zx.min(zy);
        let f = if zx == zy {
            0.5
        } else {
            (0.5 - (zy - zx) / (params.soft_depth * near)).clamp(0.0, 1.0)
        };
        let a = f * (speed[yi] - d + 1.0).clamp(0.0, 1.0);
        let b = (1.0 - f) * (rc - d + 1.0).clamp(0.0, 1.0);
        let col = &rgba[yi * 4..yi * 4 + 4];
        for ((f, g), c) in s.fg.iter_mut().zip(s.bg.iter_mut()).zip(col) {
            *f += a * c;
            *g += b * c;
        }
        s.wf += a;
        s.wb += b;
        s.taps += 1.0;
    };
    tap(i, 0.0, &mut sums);
    let pairs = params.samples / 2;
    let both = rc >= 0.5 && rn >= 0.5;
    let j = jitter(x0, y);
    // a moving pixel's own direction is its run's: the half velocity of the run's first moving
    // pixel (the run: from x0 to the tile's right edge, eight pixels at most)
    let end = ((x0 / params.tile + 1) * params.tile).min(w).min(x0 + 8);
    let first = (x0..end).find(|&k| speed[y * w + k] >= 0.5).unwrap_or(x);
    let cr = half_at(velocity, y * w + first, params.tile as f32);
    // a still pixel's taps run along n at increasing distance t rn: from the first one past
    // every speed they can meet (the tap's pixel is within 0.71 of t n: one pixel more), the
    // rest weigh nothing and only count
    let stop = if both {
        f32::INFINITY
    } else {
        weightless_from(reach.reach[reach.index(x, y)].max(rc)) + 1.0
    };
    for p in 0..pairs {
        // (direction, its length, the pair's place along it, pairs along it, the pixel whose
        // tap is moved to this one: the run's first along n and along the run's own direction)
        let (dir, r, q, m, a) = if both && p % 2 == 1 {
            (cr, len2(cr).sqrt(), p / 2, pairs / 2, x0)
        } else if both {
            (n, rn, p / 2, pairs - pairs / 2, x0)
        } else if rn >= 0.5 {
            (n, rn, p, pairs, x0)
        } else {
            (c, rc, p, pairs, x)
        };
        let t = (q as f32 + j) / m.max(1) as f32;
        if t * r >= stop {
            sums.taps += count_taps(g, (a, x, y), j, dir, (p, pairs), m);
            break;
        }
        for s in [-1.0f32, 1.0] {
            let Some((sx, sy)) = tap_at((w, h), (a, x, y), s * t, dir) else {
                continue;
            };
            let d = tap_distance((sx, sy), (x, y), t * r);
            if d >= weightless_from(reach.cell[reach.index(sx, sy)].max(rc)) {
                sums.taps += 1.0; // weighs nothing: both sums would add exact zeros
            } else {
                tap(sy * w + sx, d, &mut sums);
            }
        }
    }
    finish(&sums, &rgba[i * 4..i * 4 + 4])
}

/// The pixel's colour from its taps' sums (module docs); `own` its sharp colour.
#[inline(always)]
fn finish(sums: &Sums, own: &[f32]) -> [f32; 4] {
    let Sums {
        fg,
        bg,
        wf,
        wb,
        taps,
    } = *sums;
    let fill = (1.0 - (wf + wb) / taps).clamp(0.0, 1.0);
    let inv = 1.0 / taps;
    let mut out = [0.0f32; 4];
    for k in 0..4 {
        let back = if wb > 0.0 { bg[k] / wb } else { own[k] };
        out[k] = (fg[k] + bg[k]) * inv + back * fill;
    }
    out
}

/// [`gather`] of the first `lanes` (1 to 8) pixels of the run of eight `(x..x + 8, y)` (`x`
/// its first pixel, `x + 8 <= w`; neighbour max `n`, its length `rn >= 0.5`) when nothing
/// moves within reach of any of them: the reach grid is 0 at both ends of the run, so every
/// pixel's half speed is 0 and its stop is `weightless_from(0) + 1`. When the run's first tap
/// (`j / pairs * rn`, the run's jitter `j`) already lies past that stop, each pixel is its
/// centre tap and the count of its other taps, which [`gather`] computes for it with the same
/// operations: the same bits, without the taps' set-up (most of a frame whose movers are
/// small), written to `out` (the `lanes` pixels' RGBA); false (nothing written) otherwise.
#[inline]
fn still8(
    g: &Gather<'_>,
    (x, y): (usize, usize),
    (n, rn): ([f32; 2], f32),
    out: &mut [MaybeUninit<f32>],
) -> bool {
    let lanes = out.len() / 4;
    let reach = g.reach;
    if rn.is_nan()
        || rn < 0.5
        || reach.reach[reach.index(x, y)] != 0.0
        || reach.reach[reach.index(x + lanes - 1, y)] != 0.0
    {
        return false;
    }
    let pairs = g.params.samples / 2;
    let stop = weightless_from(0.0) + 1.0;
    // the first pair's distance, as `gather` places it: t = (0 + j) / pairs along n
    let j = jitter(x, y);
    let first = (0.0 + j) / pairs.max(1) as f32;
    if first * rn < stop {
        return false;
    }
    #[cfg(test)]
    tests::STILL_RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    #[cfg(target_arch = "x86_64")]
    if crate::simd::simd_enabled() {
        // SAFETY: AVX2 was detected; x + 8 <= w, so the run's 32 values lie inside `rgba`.
        if unsafe { still8_avx(g, (x, y), n, pairs, out) } {
            return true;
        }
    }
    for l in 0..lanes {
        let i = (y * g.w + x + l) * 4;
        let c = &g.rgba[i..i + 4];
        let half = std::array::from_fn(|k| 0.0 + 0.5 * c[k]);
        let sums = Sums {
            fg: half,
            bg: half,
            wf: 0.0 + 0.5,
            wb: 0.0 + 0.5,
            taps: 1.0 + count_taps(g, (x, x + l, y), j, n, (0, pairs), pairs),
        };
        super::put4(out, l, finish(&sums, c));
    }
    true
}

/// [`still8`]'s run when all its pixels' taps fall inside the image (so each counts
/// `1 + 2 pairs` taps), in AVX2: each pixel's colour `c` becomes `(h + h) / N + (h / 0.5)
/// (1 - 1 / N)` with `h = 0 + 0.5 c`, [`finish`]'s operations on the centre tap's sums
/// (`h / 0.5` as `2 h`: scaling by a power of two is exact either way), written to `out`;
/// false (nothing written) when a tap can leave the image.
///
/// # Safety
/// AVX2 is present, `x + 8 <= w` and `out` holds 4 to 32 values.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn still8_avx(
    g: &Gather<'_>,
    (x, y): (usize, usize),
    n: [f32; 2],
    pairs: usize,
    out: &mut [MaybeUninit<f32>],
) -> bool {
    use std::arch::x86_64::*;
    // count_taps' closed form: every tap within |n| + 1 of the first and last pixel centres
    let (ax, ay) = (n[0].abs() + 1.0, n[1].abs() + 1.0);
    let (x0, x7, yf) = (x as f32 + 0.5, (x + 7) as f32 + 0.5, y as f32 + 0.5);
    if !(x0 - ax >= 0.0 && yf - ay >= 0.0 && x7 + ax < g.w as f32 && yf + ay < g.h as f32) {
        return false;
    }
    let zero = _mm256_setzero_ps();
    let taps = 1.0 + (2 * pairs) as f32;
    let inv = 1.0 / taps;
    let fill = (1.0 - (0.5f32 + 0.5) / taps).clamp(0.0, 1.0);
    let (inv, fill, half, two) = (
        _mm256_set1_ps(inv),
        _mm256_set1_ps(fill),
        _mm256_set1_ps(0.5),
        _mm256_set1_ps(2.0),
    );
    #[cfg(test)]
    tests::STILL_VECTOR_RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let mut px = [0.0f32; 32];
    let src = g.rgba.as_ptr().add((y * g.w + x) * 4);
    for r in 0..4 {
        let h = _mm256_add_ps(zero, _mm256_mul_ps(half, _mm256_loadu_ps(src.add(8 * r))));
        let o = _mm256_add_ps(
            _mm256_mul_ps(_mm256_add_ps(h, h), inv),
            _mm256_mul_ps(_mm256_mul_ps(h, two), fill),
        );
        if out.len() == 32 {
            _mm256_storeu_ps(out.as_mut_ptr().add(8 * r).cast(), o);
        } else {
            _mm256_storeu_ps(px.as_mut_ptr().add(8 * r), o);
        }
    }
    if out.len() < 32 {
        super::write_copy(out, &px[..out.len()]);
    }
    true
}

/// [`gather`] of the first `lanes` (1 to 8) pixels of the run of eight `(x..x + 8, y)` (`x`
/// its first pixel, `x + 8 <= w`; neighbour max `n`, its length `rn`) at once, in AVX2, when
/// the neighbourhood moves (`rn >= 0.5`). Lane `l` performs [`gather`]'s IEEE operations for
/// pixel `x + l` in its order: the same bits, written to `out` (the `lanes` pixels' RGBA);
/// false (nothing written) when the neighbourhood is still or without AVX2.
#[inline]
fn gather8(
    g: &Gather<'_>,
    (x, y): (usize, usize),
    (n, rn): ([f32; 2], f32),
    out: &mut [MaybeUninit<f32>],
) -> bool {
    if rn.is_nan() || rn < 0.5 {
        return false;
    }
    #[cfg(target_arch = "x86_64")]
    if crate::simd::simd_enabled() {
        // SAFETY: AVX2 was detected; x + 8 <= w (the caller's run), the images hold w * h
        // pixels with w * h * 4 < 2^31 (the caller's `simd`), and every lane reads only pixels
        // it checked to be inside the image.
        unsafe { gather8_avx(g, (x, y), (n, rn), out) };
        return true;
    }
    false
}

/// The colours of the eight pixels at `p` (premultiplied RGBA, 32 values) as four vectors of
/// their red, green, blue and alpha.
///
/// # Safety
/// AVX2 is present and `p` points at 32 readable values.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn load_rgba8(p: *const f32) -> [std::arch::x86_64::__m256; 4] {
    use std::arch::x86_64::*;
    let pair = |a: usize| {
        _mm256_insertf128_ps::<1>(
            _mm256_castps128_ps256(_mm_loadu_ps(p.add(4 * a))),
            _mm_loadu_ps(p.add(4 * a + 16)),
        )
    };
    // pixels (0 | 4), (1 | 5), (2 | 6), (3 | 7), then a 4 x 4 transpose in each half
    let (t0, t1, t2, t3) = (pair(0), pair(1), pair(2), pair(3));
    let (a, b) = (_mm256_unpacklo_ps(t0, t1), _mm256_unpackhi_ps(t0, t1));
    let (c, d) = (_mm256_unpacklo_ps(t2, t3), _mm256_unpackhi_ps(t2, t3));
    [
        _mm256_shuffle_ps::<0x44>(a, c),
        _mm256_shuffle_ps::<0xEE>(a, c),
        _mm256_shuffle_ps::<0x44>(b, d),
        _mm256_shuffle_ps::<0xEE>(b, d),
    ]
}

/// Writes four vectors of the red, green, blue and alpha of eight pixels as the pixels' RGBA
/// (32 values, [`load_rgba8`] backwards) to `out`, or its first `out.len()` values.
///
/// # Safety
/// AVX2 is present and `out` holds at most 32 values.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn store_rgba8(c: [std::arch::x86_64::__m256; 4], out: &mut [MaybeUninit<f32>]) {
    use std::arch::x86_64::*;
    let (a, b) = (
        _mm256_unpacklo_ps(c[0], c[1]),
        _mm256_unpackhi_ps(c[0], c[1]),
    );
    let (e, f) = (
        _mm256_unpacklo_ps(c[2], c[3]),
        _mm256_unpackhi_ps(c[2], c[3]),
    );
    // pixels (0 | 4), (1 | 5), (2 | 6), (3 | 7)
    let (p0, p1) = (
        _mm256_shuffle_ps::<0x44>(a, e),
        _mm256_shuffle_ps::<0xEE>(a, e),
    );
    let (p2, p3) = (
        _mm256_shuffle_ps::<0x44>(b, f),
        _mm256_shuffle_ps::<0xEE>(b, f),
    );
    let rows = [
        _mm256_permute2f128_ps::<0x20>(p0, p1),
        _mm256_permute2f128_ps::<0x20>(p2, p3),
        _mm256_permute2f128_ps::<0x31>(p0, p1),
        _mm256_permute2f128_ps::<0x31>(p2, p3),
    ];
    if out.len() == 32 {
        for (r, v) in rows.into_iter().enumerate() {
            _mm256_storeu_ps(out.as_mut_ptr().add(8 * r).cast(), v);
        }
    } else {
        let mut px = [0.0f32; 32];
        for (r, v) in rows.into_iter().enumerate() {
            _mm256_storeu_ps(px.as_mut_ptr().add(8 * r), v);
        }
        super::write_copy(out, &px[..out.len()]);
    }
}

/// [`gather8`] in AVX2 (its docs). Every tap of the run lies on eight neighbouring pixels of a
/// row (module docs: along `n`, and the moving lanes' along the run's own direction): one load
/// each, a gather only at the image's left and right edges.
///
/// # Safety
/// AVX2 is present, `x + 8 <= w`, `w * h * 4 < 2^31`, `out` holds 4 to 32 values.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn gather8_avx(
    g: &Gather<'_>,
    (x, y): (usize, usize),
    (n, rn): ([f32; 2], f32),
    out: &mut [MaybeUninit<f32>],
) {
    use std::arch::x86_64::*;
    let lanes = out.len() / 4;
    let Gather {
        rgba,
        depth,
        speed,
        w,
        h,
        params,
        reach,
        ..
    } = *g;
    let i0 = y * w + x;
    let iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    let yf = _mm256_set1_ps(y as f32);
    let rc = _mm256_loadu_ps(speed.as_ptr().add(i0));
    let zx = _mm256_loadu_ps(depth.as_ptr().add(i0));
    let j = jitter(x, y);
    // stop = weightless_from(reach of the pixel's cell .max(rc)) + 1, per lane; the run's
    // eight pixels lie in at most two cells
    let in_cells = |grid: &[f32], row: usize, b: usize| {
        let (lo, hi) = (b / CELL, (b + 7) / CELL);
        _mm256_blendv_ps(
            _mm256_set1_ps(grid[row + hi]),
            _mm256_set1_ps(grid[row + lo]),
            _mm256_castsi256_ps(_mm256_cmpgt_epi32(
                _mm256_set1_epi32(((lo + 1) * CELL - b) as i32),
                iota,
            )),
        )
    };
    let cells = in_cells(&reach.reach, (y / CELL) * reach.cw, x);
    let (zero, one, half) = (
        _mm256_setzero_ps(),
        _mm256_set1_ps(1.0),
        _mm256_set1_ps(0.5),
    );
    let two = _mm256_set1_ps(2.0);
    let live = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(lanes as i32), iota));
    // a moving pixel (`both`: its own and the neighbourhood's direction) never stops early
    let moving = _mm256_cmp_ps::<_CMP_GE_OQ>(rc, half);
    let stop = _mm256_blendv_ps(
        _mm256_add_ps(_mm256_add_ps(_mm256_max_ps(cells, rc), two), one),
        _mm256_set1_ps(f32::INFINITY),
        moving,
    );
    let soft = _mm256_set1_ps(params.soft_depth);
    let clamp01 = |v: __m256| _mm256_max_ps(_mm256_min_ps(v, one), zero);
    let own = _mm256_add_epi32(_mm256_set1_epi32(i0 as i32), iota);
    // the centre tap (d = 0): zy = zx, so f = 0.5, and rc + 1 >= 1 makes both weights 0.5
    let mine = load_rgba8(rgba.as_ptr().add(i0 * 4));
    let mut fg: [__m256; 4] =
        std::array::from_fn(|k| _mm256_add_ps(zero, _mm256_mul_ps(half, mine[k])));
    let mut bg = fg;
    let (mut wf, mut wb) = (_mm256_add_ps(zero, half), _mm256_add_ps(zero, half));
    let mut taps = one;
    // a tap's weights per lane from the tapped pixels' depths `zy` and half speeds `sy` at
    // distance `d`, zero where not `real` (the others add exact zeros, which change no sum:
    // none of them is -0 after the +0 start)
    let weights = |zy: __m256, sy: __m256, d: __m256, real: __m256| {
        let near = _mm256_min_ps(zx, zy);
        let q = _mm256_div_ps(_mm256_sub_ps(zy, zx), _mm256_mul_ps(soft, near));
        let f = _mm256_blendv_ps(
            clamp01(_mm256_sub_ps(half, q)),
            half,
            _mm256_cmp_ps::<_CMP_EQ_OQ>(zx, zy),
        );
        let a = _mm256_mul_ps(f, clamp01(_mm256_add_ps(_mm256_sub_ps(sy, d), one)));
        let b = _mm256_mul_ps(
            _mm256_sub_ps(one, f),
            clamp01(_mm256_add_ps(_mm256_sub_ps(rc, d), one)),
        );
        (_mm256_and_ps(a, real), _mm256_and_ps(b, real))
    };
    let mut add = |(a, b): (__m256, __m256), col: [__m256; 4]| {
        for k in 0..4 {
            fg[k] = _mm256_add_ps(fg[k], _mm256_mul_ps(a, col[k]));
            bg[k] = _mm256_add_ps(bg[k], _mm256_mul_ps(b, col[k]));
        }
        wf = _mm256_add_ps(wf, a);
        wb = _mm256_add_ps(wb, b);
    };
    // one tap per lane at pixel index `yi` (a gather), where `real`
    let gathered = |yi: __m256i, real: __m256| {
        let yi = _mm256_blendv_epi8(own, yi, _mm256_castps_si256(real));
        let zy = _mm256_i32gather_ps::<4>(depth.as_ptr(), yi);
        let sy = _mm256_i32gather_ps::<4>(speed.as_ptr(), yi);
        let c4 = _mm256_slli_epi32::<2>(yi);
        let col: [__m256; 4] = std::array::from_fn(|k| {
            _mm256_i32gather_ps::<4>(
                rgba.as_ptr(),
                _mm256_add_epi32(c4, _mm256_set1_epi32(k as i32)),
            )
        });
        (zy, sy, col)
    };
    let pairs = params.samples / 2;
    let hl = _mm256_set1_ps(h as f32);
    let wi = _mm256_set1_epi32(w as i32);
    let mut still = _mm256_andnot_ps(moving, live);
    let movers = _mm256_and_ps(moving, live);
    let any = |m: __m256| _mm256_movemask_ps(m) != 0;
    // the moving lanes' own direction: the half velocity of the run's first moving pixel, and
    // its length
    let (cr, rr) = if any(movers) {
        let first = _mm256_movemask_ps(movers).trailing_zeros() as usize;
        let c = half_at(g.velocity, i0 + first, params.tile as f32);
        (c, len2(c).sqrt())
    } else {
        ([0.0; 2], 0.0)
    };
    // the still lanes' taps of eight pairs at a time, computed eight at a time: `t`, `t rn`,
    // and for each sign (`8 s` + pair) the run's first pixel's tap column `base`, its row
    // (-1 off the image) and its distance
    let empty = RunTaps {
        t: [0.0; 8],
        tr: [0.0; 8],
        base: [0; 16],
        row: [0; 16],
        d: [0.0; 16],
    };
    // the still lanes' along n (`tabs[0]`: t = (p + j) / pairs), the moving lanes' along n
    // (`tabs[1]`: t = (p / 2 + j) / m, even pairs) and along their own direction (`tabs[2]`,
    // odd pairs)
    let mut tabs = [empty; 3];
    let fill = |p0: usize, m: usize, (n, rn): ([f32; 2], f32), tab: &mut RunTaps| {
        let pv = _mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(p0 as i32), iota));
        let t = _mm256_div_ps(
            _mm256_add_ps(pv, _mm256_set1_ps(j)),
            _mm256_set1_ps(m.max(1) as f32),
        );
        let tr = _mm256_mul_ps(t, _mm256_set1_ps(rn));
        _mm256_storeu_ps(tab.t.as_mut_ptr(), t);
        _mm256_storeu_ps(tab.tr.as_mut_ptr(), tr);
        for (k, s) in [-1.0f32, 1.0].into_iter().enumerate() {
            let st = _mm256_mul_ps(_mm256_set1_ps(s), t);
            let px = _mm256_add_ps(
                _mm256_set1_ps(x as f32 + 0.5),
                _mm256_mul_ps(st, _mm256_set1_ps(n[0])),
            );
            let py = _mm256_add_ps(
                _mm256_set1_ps(y as f32 + 0.5),
                _mm256_mul_ps(st, _mm256_set1_ps(n[1])),
            );
            let on = _mm256_castps_si256(_mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GE_OQ>(py, zero),
                _mm256_cmp_ps::<_CMP_LT_OQ>(py, hl),
            ));
            let base = _mm256_cvtps_epi32(_mm256_floor_ps(px));
            let sy = _mm256_cvttps_epi32(py);
            let dx = _mm256_cvtepi32_ps(_mm256_sub_epi32(base, _mm256_set1_epi32(x as i32)));
            let dy = _mm256_sub_ps(_mm256_cvtepi32_ps(sy), yf);
            let d2 = _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy));
            let d = _mm256_min_ps(_mm256_sqrt_ps(d2), tr);
            let row = _mm256_or_si256(
                _mm256_and_si256(on, sy),
                _mm256_andnot_si256(on, _mm256_set1_epi32(-1)),
            );
            _mm256_storeu_si256(tab.base.as_mut_ptr().add(8 * k).cast(), base);
            _mm256_storeu_si256(tab.row.as_mut_ptr().add(8 * k).cast(), row);
            _mm256_storeu_ps(tab.d.as_mut_ptr().add(8 * k), d);
        }
    };
    let mut counted = [0.0f32; 8];
    for p in 0..pairs {
        // the still lanes' pair along n at t = (p + j) / pairs, the moving lanes' along n
        // (even pairs) or their own direction (odd pairs) at t = (p / 2 + j) / m: each lane
        // takes one of them, in `gather`'s order. A job: its lanes, its table and pair
        let mut jobs = [(zero, 0, 0); 2];
        let mut count = 0;
        if any(still) {
            let q = p % 8;
            if q == 0 {
                fill(p, pairs, (n, rn), &mut tabs[0]);
            }
            let ends = _mm256_and_ps(
                still,
                _mm256_cmp_ps::<_CMP_GE_OQ>(_mm256_set1_ps(tabs[0].tr[q]), stop),
            );
            let ended = _mm256_movemask_ps(ends);
            if ended != 0 {
                for (l, c) in counted.iter_mut().enumerate() {
                    if ended & (1 << l) != 0 {
                        *c = count_taps(g, (x, x + l, y), j, n, (p, pairs), pairs);
                    }
                }
                still = _mm256_andnot_ps(ends, still);
            }
            if any(still) {
                jobs[count] = (still, 0, q);
                count += 1;
            }
        }
        if any(movers) {
            let odd = p % 2 == 1;
            let m = if odd { pairs / 2 } else { pairs - pairs / 2 };
            let (which, dir) = if odd { (2, (cr, rr)) } else { (1, (n, rn)) };
            let q = (p / 2) % 8;
            if q == 0 {
                fill(p / 2, m, dir, &mut tabs[which]);
            }
            jobs[count] = (movers, which, q);
            count += 1;
        }
        if count == 0 {
            break;
        }
        for &(mask, which, q) in &jobs[..count] {
            // the run's first pixel's tap, moved along the row lane by lane
            let tab = &tabs[which];
            for k in 0..2 {
                let i = 8 * k + q;
                if tab.row[i] < 0 {
                    continue;
                }
                let (base, sy, d) = (tab.base[i] as i64, tab.row[i] as usize, tab.d[i]);
                let whole = base >= 0 && base + 8 <= w as i64;
                let bl = _mm256_add_epi32(_mm256_set1_epi32(base as i32), iota);
                let inside = if whole {
                    mask
                } else {
                    let ins = _mm256_and_si256(
                        _mm256_cmpgt_epi32(bl, _mm256_set1_epi32(-1)),
                        _mm256_cmpgt_epi32(wi, bl),
                    );
                    _mm256_and_ps(_mm256_castsi256_ps(ins), mask)
                };
                if !any(inside) {
                    continue;
                }
                taps = _mm256_add_ps(taps, _mm256_and_ps(inside, one));
                let d = _mm256_set1_ps(d);
                let row = (sy / CELL) * reach.cw;
                let cell = if whole {
                    in_cells(&reach.cell, row, base as usize)
                } else {
                    let cidx = _mm256_and_si256(
                        _mm256_add_epi32(_mm256_set1_epi32(row as i32), _mm256_srai_epi32::<4>(bl)),
                        _mm256_castps_si256(inside),
                    );
                    _mm256_i32gather_ps::<4>(reach.cell.as_ptr(), cidx)
                };
                let from = _mm256_add_ps(_mm256_max_ps(cell, rc), two);
                let real = _mm256_andnot_ps(_mm256_cmp_ps::<_CMP_GE_OQ>(d, from), inside);
                if !any(real) {
                    continue;
                }
                let k = sy * w + base as usize;
                if whole {
                    let zy = _mm256_loadu_ps(depth.as_ptr().add(k));
                    let sp = _mm256_loadu_ps(speed.as_ptr().add(k));
                    add(
                        weights(zy, sp, d, real),
                        load_rgba8(rgba.as_ptr().add(4 * k)),
                    );
                } else {
                    let yi = _mm256_add_epi32(_mm256_set1_epi32((sy * w) as i32), bl);
                    let (zy, sp, col) = gathered(yi, real);
                    add(weights(zy, sp, d, real), col);
                }
            }
        }
    }
    // `finish`, lane by lane
    let taps = _mm256_add_ps(taps, _mm256_loadu_ps(counted.as_ptr()));
    let fill = clamp01(_mm256_sub_ps(
        one,
        _mm256_div_ps(_mm256_add_ps(wf, wb), taps),
    ));
    let inv = _mm256_div_ps(one, taps);
    let some = _mm256_cmp_ps::<_CMP_GT_OQ>(wb, zero);
    let colours = std::array::from_fn(|k| {
        let back = _mm256_blendv_ps(mine[k], _mm256_div_ps(bg[k], wb), some);
        _mm256_add_ps(
            _mm256_mul_ps(_mm256_add_ps(fg[k], bg[k]), inv),
            _mm256_mul_ps(back, fill),
        )
    });
    store_rgba8(colours, out);
}

/// Eight pairs of taps of a run's still (or moving) pixels along `n` ([`gather8_avx`]).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct RunTaps {
    /// `t` of each pair.
    t: [f32; 8],
    /// `t |n|`.
    tr: [f32; 8],
    /// For each sign (`8 s` + pair), the column of the run's first pixel's tap.
    base: [i32; 16],
    /// Its row, -1 off the image.
    row: [i32; 16],
    /// Its distance.
    d: [f32; 16],
}

/// The taps of pairs `p0..pairs` along `dir` (`m` pairs a direction: `t = (p + j) / m`, `j`
/// the run's jitter) of pixel `(x, y)` that fall inside the image, as the gather places them
/// ([`tap_at`]: `a` the pixel whose tap is moved to `x`'s).
fn count_taps(
    g: &Gather<'_>,
    (a, x, y): (usize, usize, usize),
    j: f32,
    dir: [f32; 2],
    (p0, pairs): (usize, usize),
    m: usize,
) -> f32 {
    let (xf, yf) = (x as f32 + 0.5, y as f32 + 0.5);
    // |t| <= 1: every tap within |dir| + 1 of the pixel centre (a tap moved along the row
    // lands on the nearest pixel of the pixel's own tap, up to rounding), which is inside on
    // all sides
    let (ax, ay) = (dir[0].abs() + 1.0, dir[1].abs() + 1.0);
    if xf - ax >= 0.0 && yf - ay >= 0.0 && xf + ax < g.w as f32 && yf + ay < g.h as f32 {
        return (2 * (pairs - p0)) as f32;
    }
    let mut taps = 0.0f32;
    for q in p0..pairs {
        let t = (q as f32 + j) / m.max(1) as f32;
        for s in [-1.0f32, 1.0] {
            if tap_at((g.w, g.h), (a, x, y), s * t, dir).is_some() {
                taps += 1.0;
            }
        }
    }
    taps
}

#[cfg(test)]
mod tests;
