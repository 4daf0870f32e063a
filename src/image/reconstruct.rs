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
//!    `|c| >= 0.5`, half of them at `X +- t c`, Guertin's second direction, which recovers a
//!    pixel whose motion differs from its neighbourhood's), `t = (i + j) / m` with a per-pixel
//!    jitter `j` in `[0, 1)` (a hash of the pixel, so the result is deterministic), each taken at
//!    the nearest pixel `Y` (taps outside the image are dropped). A tap at distance `d` is split
//!    by depth into a foreground part `f = clamp(0.5 - (z_Y - z_X) / (s z), 0, 1)` and a background
//!    part `1 - f` (`s` the relative `soft_depth`, `z` the nearer depth): the foreground part
//!    counts when the tap's own motion reaches `X` (`clamp(|v_Y / 2| - d + 1, 0, 1)`), the
//!    background part when the pixel's own motion reaches the tap (`clamp(|c| - d + 1, 0, 1)`).
//!    The centre pixel is a tap at `d = 0`. With `N` taps, weighted sums `F` (foreground) and `B`
//!    (background) of colours and their weights `wf`, `wb`:
//!    `out = (F + B) / N + (B / wb) * clamp(1 - (wf + wb) / N, 0, 1)`: each tap stands for `1/N`
//!    of the shutter, and the taps that reach nothing are filled with the pixel's background.
//!
//! Rows are gathered in parallel and read only the inputs, so the result is bit-identical for
//! any thread count.
use rayon::prelude::*;

use super::{check_finite, check_image};
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

/// Half velocities clamped to `tile` pixels, per pixel.
fn half_velocities(velocity: &[f32], tile: f32) -> Vec<[f32; 2]> {
    velocity
        .par_chunks(2)
        .map(|v| {
            let h = [0.5 * v[0], 0.5 * v[1]];
            let l = len2(h).sqrt();
            if l > tile {
                [h[0] * tile / l, h[1] * tile / l]
            } else {
                h
            }
        })
        .collect()
}

/// The tile max of `half` over `tile x tile` blocks, then the 3x3 neighbour max of tiles:
/// `(tiles_x, tiles_y, neighbour max per tile)`.
fn neighbour_max(half: &[[f32; 2]], w: usize, h: usize, tile: usize) -> (usize, Vec<[f32; 2]>) {
    let (tx, ty) = (w.div_ceil(tile), h.div_ceil(tile));
    let longest = |a: [f32; 2], b: [f32; 2]| if len2(b) > len2(a) { b } else { a };
    let tiles: Vec<[f32; 2]> = (0..tx * ty)
        .into_par_iter()
        .map(|t| {
            let (bx, by) = (t % tx, t / tx);
            let mut m = [0.0f32; 2];
            for y in by * tile..((by + 1) * tile).min(h) {
                for x in bx * tile..((bx + 1) * tile).min(w) {
                    m = longest(m, half[y * w + x]);
                }
            }
            m
        })
        .collect();
    let nmax = (0..tx * ty)
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
        .collect();
    (tx, nmax)
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
    check_image("rgba", rgba, w, h, 4)?;
    check_image("depth", depth, w, h, 1)?;
    check_image("velocity", velocity, w, h, 2)?;
    check_finite("rgba", rgba)?;
    check_finite("velocity", velocity)?;
    if depth.par_iter().any(|d| d.is_nan() || *d <= 0.0) {
        return Err(Error::value(
            "depth",
            "must be > 0 (inf for no surface), not NaN",
        ));
    }
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
    let half = half_velocities(velocity, params.tile as f32);
    let (tx, nmax) = neighbour_max(&half, w, h, params.tile);
    let mut out = vec![0.0f32; w * h * 4];
    let g = Gather {
        rgba,
        depth,
        half: &half,
        nmax: &nmax,
        tx,
        w,
        h,
        params,
    };
    out.par_chunks_mut(w * 4).enumerate().for_each(|(y, row)| {
        for x in 0..w {
            let o = &mut row[x * 4..x * 4 + 4];
            gather(&g, (x, y), o);
        }
    });
    Ok(out)
}

/// What every pixel's gather reads: the image and its depth, the half velocities, the tiles'
/// neighbour max (`tx` tiles a row), the size `w` x `h` and the parameters.
#[derive(Clone, Copy)]
struct Gather<'a> {
    rgba: &'a [f32],
    depth: &'a [f32],
    half: &'a [[f32; 2]],
    nmax: &'a [[f32; 2]],
    tx: usize,
    w: usize,
    h: usize,
    params: ReconstructParams,
}

fn gather(g: &Gather<'_>, (x, y): (usize, usize), out: &mut [f32]) {
    let Gather {
        rgba,
        depth,
        half,
        nmax,
        tx,
        w,
        h,
        params,
    } = *g;
    let i = y * w + x;
    let n = nmax[(y / params.tile) * tx + x / params.tile];
    let c = half[i];
    let (rn, rc) = (len2(n).sqrt(), len2(c).sqrt());
    if rn.max(rc) < 0.5 {
        out.copy_from_slice(&rgba[i * 4..i * 4 + 4]);
        return;
    }
    let zx = depth[i];
    let (mut fg, mut bg) = ([0.0f32; 4], [0.0f32; 4]);
    let (mut wf, mut wb, mut taps) = (0.0f32, 0.0f32, 0.0f32);
    let mut tap = |yi: usize, d: f32| {
        let zy = depth[yi];
        let near = zx.min(zy);
        let f = if zx == zy {
            0.5
        } else {
            (0.5 - (zy - zx) / (params.soft_depth * near)).clamp(0.0, 1.0)
        };
        let ry = len2(half[yi]).sqrt();
        let a = f * (ry - d + 1.0).clamp(0.0, 1.0);
        let b = (1.0 - f) * (rc - d + 1.0).clamp(0.0, 1.0);
        let col = &rgba[yi * 4..yi * 4 + 4];
        for k in 0..4 {
            fg[k] += a * col[k];
            bg[k] += b * col[k];
        }
        wf += a;
        wb += b;
        taps += 1.0;
    };
    tap(i, 0.0);
    let pairs = params.samples / 2;
    let both = rc >= 0.5 && rn >= 0.5;
    let j = jitter(x, y);
    for p in 0..pairs {
        let (dir, r, q, m) = if both && p % 2 == 1 {
            (c, rc, p / 2, pairs / 2)
        } else if both {
            (n, rn, p / 2, pairs - pairs / 2)
        } else if rn >= 0.5 {
            (n, rn, p, pairs)
        } else {
            (c, rc, p, pairs)
        };
        let t = (q as f32 + j) / m.max(1) as f32;
        for s in [-1.0f32, 1.0] {
            let (px, py) = (
                x as f32 + 0.5 + s * t * dir[0],
                y as f32 + 0.5 + s * t * dir[1],
            );
            if px < 0.0 || py < 0.0 || px >= w as f32 || py >= h as f32 {
                continue;
            }
            let (sx, sy) = (px as usize, py as usize);
            let d = (((sx as f32 - x as f32).powi(2)) + ((sy as f32 - y as f32).powi(2))).sqrt();
            tap(sy * w + sx, d.min(t * r));
        }
    }
    let fill = (1.0 - (wf + wb) / taps).clamp(0.0, 1.0);
    let inv = 1.0 / taps;
    for k in 0..4 {
        let back = if wb > 0.0 {
            bg[k] / wb
        } else {
            rgba[i * 4 + k]
        };
        out[k] = (fg[k] + bg[k]) * inv + back * fill;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> ReconstructParams {
        ReconstructParams {
            samples: 16,
            tile: 8,
            soft_depth: 0.01,
        }
    }

    #[test]
    fn no_motion_copies_the_frame() {
        let (w, h) = (13, 7);
        let rgba: Vec<f32> = (0..w * h * 4).map(|i| (i % 11) as f32 / 11.0).collect();
        let depth = vec![2.0f32; w * h];
        let vel = vec![0.0f32; w * h * 2];
        let out = reconstruct(&rgba, &depth, &vel, w, h, params()).unwrap();
        assert_eq!(out, rgba);
    }

    #[test]
    fn a_moving_square_spreads_and_keeps_its_coverage() {
        // a 10-pixel opaque square moving 12 pixels right over nothing
        let (w, h) = (48, 20);
        let mut rgba = vec![0.0f32; w * h * 4];
        let mut depth = vec![f32::INFINITY; w * h];
        let mut vel = vec![0.0f32; w * h * 2];
        for y in 5..15 {
            for x in 19..29 {
                let i = y * w + x;
                rgba[i * 4..i * 4 + 4].copy_from_slice(&[1.0, 0.5, 0.25, 1.0]);
                depth[i] = 3.0;
                vel[i * 2] = 12.0;
            }
        }
        let out = reconstruct(&rgba, &depth, &vel, w, h, params()).unwrap();
        let alpha = |x: usize| out[(10 * w + x) * 4 + 3];
        // the streak reaches 6 pixels past each edge, fading
        assert!(alpha(16) > 0.05 && alpha(16) < 0.9, "{}", alpha(16));
        assert!(alpha(10) < 1e-6);
        // total coverage of the row is kept within 15%
        let total: f32 = (0..w).map(alpha).sum();
        assert!((total - 10.0).abs() < 1.5, "{total}");
        // colour stays premultiplied: rgb = alpha * colour
        let i = (10 * w + 17) * 4;
        assert!((out[i] - out[i + 3]).abs() < 1e-5);
        assert!((out[i + 1] - 0.5 * out[i + 3]).abs() < 1e-5);
    }

    #[test]
    fn same_result_on_one_thread() {
        let (w, h) = (40, 30);
        let rgba: Vec<f32> = (0..w * h * 4).map(|i| (i % 7) as f32 / 7.0).collect();
        let depth: Vec<f32> = (0..w * h).map(|i| 1.0 + (i % 5) as f32).collect();
        let vel: Vec<f32> = (0..w * h * 2).map(|i| (i % 9) as f32 - 4.0).collect();
        let a = reconstruct(&rgba, &depth, &vel, w, h, params()).unwrap();
        let b = crate::on_threads(1, || {
            reconstruct(&rgba, &depth, &vel, w, h, params()).unwrap()
        });
        assert_eq!(a, b);
    }

    #[test]
    fn bad_input_names_the_argument() {
        let (w, h) = (4, 4);
        let rgba = vec![0.0f32; w * h * 4];
        let depth = vec![1.0f32; w * h];
        let vel = vec![0.0f32; w * h * 2];
        let mut p = params();
        p.samples = 1;
        let e = reconstruct(&rgba, &depth, &vel, w, h, p).unwrap_err();
        assert!(e.to_string().contains("samples"));
        let e = reconstruct(&rgba, &[0.0; 16], &vel, w, h, params()).unwrap_err();
        assert!(e.to_string().contains("depth"));
    }
}
