//! The raster frame's stats, the tiles' writer into a [`Frame`] and the box resolve of
//! supersampled tiles.
//!
//! Resolve: the colour of a pixel is the mean of its s x s samples (a box filter). Depth, id and
//! velocity come from the pixel's *nearest* sample (smallest depth; the first in row order on
//! ties), so they always describe one real surface rather than a blend of two.
use super::bins::TILE;
use super::blend::Sample;
use crate::frame::Frame;

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

/// Raw pointers into the frame's buffers, shared by the tile workers. Each tile writes only its
/// own pixel rectangle, and rectangles of different tiles are disjoint.
pub struct Output {
    rgba: *mut f32,
    depth: *mut f32,
    ids: *mut i32,
    velocity: Option<*mut f32>,
    width: usize,
    height: usize,
}

// SAFETY: the pointers are only written through `write_tile`, whose callers give each tile a
// distinct rectangle; no element is ever written by two threads, and none is read.
unsafe impl Send for Output {}
unsafe impl Sync for Output {}

impl Output {
    /// The pointers the tiles write through, into the spare capacity of a frame made by
    /// [`Frame::with_capacity`] (velocity only when the frame has that channel). `frame` must
    /// outlive every use and not be touched until [`assume_written`].
    pub fn new(frame: &mut Frame) -> Output {
        let n = frame.len();
        Output {
            rgba: frame.rgba.as_mut_ptr(),
            depth: frame.depth.as_mut_ptr(),
            ids: frame.ids.as_mut_ptr(),
            velocity: frame
                .velocity
                .as_mut()
                .filter(|v| v.capacity() >= 2 * n && n > 0)
                .map(|v| v.as_mut_ptr()),
            width: frame.width as usize,
            height: frame.height as usize,
        }
    }
}

/// Gives the buffers of a [`Frame::with_capacity`] frame their full length.
///
/// # Safety
/// Every pixel of the frame must have been written through its [`Output`]
/// (`Output::write_tile` over tiles that cover the frame).
pub unsafe fn assume_written(frame: &mut Frame) {
    let n = frame.len();
    debug_assert!(frame.depth.capacity() >= n && frame.rgba.capacity() >= 4 * n);
    // SAFETY: the capacities were reserved by `with_capacity` and the caller guarantees every
    // element up to these lengths was written (f32 and i32 have no invalid bit patterns).
    unsafe {
        frame.rgba.set_len(4 * n);
        frame.depth.set_len(n);
        frame.ids.set_len(n);
        if let Some(v) = &mut frame.velocity {
            if v.capacity() >= 2 * n {
                v.set_len(2 * n);
            }
        }
    }
}

/// Whether the resolve runs its vector form (`crate::simd`: AVX2 detected and not switched off).
fn simd() -> bool {
    crate::simd::simd_enabled()
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
                1 => self.copy_samples(samples, px, simd()),
                2 => self.resolve::<2>(samples, px),
                4 => self.resolve::<4>(samples, px),
                _ => unreachable!("samples are checked to be 1, 2 or 4"),
            }
        }
    }

    /// Writes pixel `o` (row-major index): `rgba`, and the depth (1/`invw`, infinite where it is
    /// not positive), id and velocity of the nearest sample `best`.
    ///
    /// # Safety
    /// Pixel `o` must be inside the frame and owned by the calling tile.
    #[inline(always)]
    unsafe fn put(&self, o: usize, rgba: [f32; 4], best: &Sample) {
        // SAFETY: the caller's contract.
        unsafe {
            for (k, c) in rgba.into_iter().enumerate() {
                *self.rgba.add(4 * o + k) = c;
            }
            *self.depth.add(o) = if best.invw > 0.0 {
                1.0 / best.invw
            } else {
                f32::INFINITY
            };
            *self.ids.add(o) = best.id;
            if let Some(v) = self.velocity {
                *v.add(2 * o) = best.velocity[0];
                *v.add(2 * o + 1) = best.velocity[1];
            }
        }
    }

    /// `write_tile` for one sample a pixel: `resolve::<1>`'s values, eight pixels at a time in
    /// AVX2 where the CPU has it (the same operations: `0 + rgba`, one IEEE division for the
    /// depth, the background where 1/w is not positive).
    ///
    /// # Safety
    /// As `write_tile`.
    unsafe fn copy_samples(&self, samples: &[Sample], px: [usize; 4], simd: bool) {
        let [px0, py0, px1, py1] = px;
        debug_assert!(px1 <= self.width && py1 <= self.height);
        let mut x8 = px0;
        #[cfg(target_arch = "x86_64")]
        if simd {
            for y in py0..py1 {
                let row = &samples[(y - py0) * TILE as usize..][..px1 - px0];
                // SAFETY: AVX2 was detected; the row's pixels are in the frame and this tile's.
                unsafe { x8 = self.row8(row, y, px0) };
            }
        }
        // The pixels the vector form left (all of them without AVX2).
        for y in py0..py1 {
            for x in x8..px1 {
                let smp = samples[(y - py0) * TILE as usize + (x - px0)];
                let best = if smp.invw > 0.0 {
                    smp
                } else {
                    Sample::BACKGROUND
                };
                let rgba = smp.rgba.map(|c| 0.0 + c);
                // SAFETY: (x, y) is inside the frame and owned by this tile (caller's contract).
                unsafe { self.put(y * self.width + x, rgba, &best) };
            }
        }
    }

    /// The first multiple of eight pixels of a row of samples, written to output row `y` from
    /// column `x0` on; returns the first column it did not write.
    ///
    /// # Safety
    /// AVX2 must be present; as `write_tile` for the row's pixels.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn row8(&self, row: &[Sample], y: usize, x0: usize) -> usize {
        use std::arch::x86_64::*;
        const _: () = assert!(std::mem::size_of::<Sample>() == 32);
        let n8 = row.len() / 8 * 8;
        let src = row.as_ptr() as *const f32;
        let o = y * self.width + x0;
        let zero = _mm256_setzero_ps();
        for b in (0..n8).step_by(8) {
            // SAFETY: samples b .. b + 8 are in `row`; pixels o + b .. o + b + 8 are the tile's.
            unsafe {
                let s = |i: usize| _mm256_loadu_ps(src.add((b + i) * 8));
                let v = [s(0), s(1), s(2), s(3), s(4), s(5), s(6), s(7)];
                // rgba: the low halves, two pixels per store.
                for i in (0..8).step_by(2) {
                    let c = _mm256_permute2f128_ps::<0x20>(v[i], v[i + 1]);
                    _mm256_storeu_ps(self.rgba.add(4 * (o + b + i)), _mm256_add_ps(zero, c));
                }
                // (invw, id, vx, vy) of the eight samples as four rows of eight.
                let hi = |i: usize| _mm256_permute2f128_ps::<0x31>(v[i], v[i + 4]);
                let (h0, h1, h2, h3) = (hi(0), hi(1), hi(2), hi(3));
                let t0 = _mm256_unpacklo_ps(h0, h1); // w0 w1 id0 id1 | w4 w5 id4 id5
                let t1 = _mm256_unpackhi_ps(h0, h1); // x0 x1 y0 y1 | ...
                let t2 = _mm256_unpacklo_ps(h2, h3);
                let t3 = _mm256_unpackhi_ps(h2, h3);
                let invw = _mm256_shuffle_ps::<0x44>(t0, t2); // w0 w1 w2 w3 | w4 ..
                let ids = _mm256_shuffle_ps::<0xee>(t0, t2);
                let vx = _mm256_shuffle_ps::<0x44>(t1, t3);
                let vy = _mm256_shuffle_ps::<0xee>(t1, t3);
                let near = _mm256_cmp_ps::<_CMP_GT_OQ>(invw, zero);
                let depth = _mm256_blendv_ps(
                    _mm256_set1_ps(f32::INFINITY),
                    _mm256_div_ps(_mm256_set1_ps(1.0), invw),
                    near,
                );
                _mm256_storeu_ps(self.depth.add(o + b), depth);
                let none = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
                let ids = _mm256_blendv_ps(none, ids, near);
                _mm256_storeu_si256(
                    self.ids.add(o + b) as *mut __m256i,
                    _mm256_castps_si256(ids),
                );
                if let Some(vel) = self.velocity {
                    let (vx, vy) = (_mm256_and_ps(vx, near), _mm256_and_ps(vy, near));
                    let lo = _mm256_unpacklo_ps(vx, vy); // x0 y0 x1 y1 | x4 y4 x5 y5
                    let hi = _mm256_unpackhi_ps(vx, vy); // x2 y2 x3 y3 | x6 y6 x7 y7
                    let a = _mm256_permute2f128_ps::<0x20>(lo, hi);
                    let c = _mm256_permute2f128_ps::<0x31>(lo, hi);
                    _mm256_storeu_ps(vel.add(2 * (o + b)), a);
                    _mm256_storeu_ps(vel.add(2 * (o + b) + 8), c);
                }
            }
        }
        x0 + n8
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
                let rgba = if S == 1 { c } else { c.map(|v| v * norm) };
                // SAFETY: (x, y) is inside the frame and owned by this tile (caller's contract).
                unsafe { self.put(y * self.width + x, rgba, &best) };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_sample_resolve_vector_and_plain_forms_agree() {
        // A tile of varied samples (covered, empty, negative or zero 1/w, -0 colours) written
        // by both forms into two frames, with and without velocity, widths with a tail.
        let n = (TILE * TILE) as usize;
        let samples: Vec<Sample> = (0..n)
            .map(|i| {
                let k = i as f32;
                Sample {
                    rgba: [k * 0.25, -0.0, 1.0 / (1.0 + k), 0.5],
                    invw: [0.5 + k, 0.0, -1.0, 1e-30][i % 4],
                    id: i as i32 % 7,
                    velocity: [k, -k],
                }
            })
            .collect();
        for (w, h, velocity) in [(64, 64, true), (61, 37, false), (13, 5, true)] {
            let run = |simd| {
                let mut f = Frame::with_capacity(w as u32, h as u32, velocity).unwrap();
                let out = Output::new(&mut f);
                // SAFETY: one tile covering the frame, written once.
                unsafe {
                    out.copy_samples(&samples, [0, 0, w, h], simd);
                    assume_written(&mut f);
                }
                f
            };
            let (a, b) = (run(true), run(false));
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&a.rgba), bits(&b.rgba));
            assert_eq!(bits(&a.depth), bits(&b.depth));
            assert_eq!(a.ids, b.ids);
            let vel = |f: &Frame| f.velocity.as_deref().map(bits);
            assert_eq!(vel(&a), vel(&b));
            assert_eq!(a.velocity.map(|v| v.len()), velocity.then_some(2 * w * h));
        }
    }
}
