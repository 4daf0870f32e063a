//! One sheared row (`lines`): its samples of the image (`shear_row`, for every filter along an
//! oblique line) and the opaque blur's filter of it into five values a pixel, the box mean's
//! RGBA and the glow (`filter_row`; the output pixels that interpolate two such rows are
//! finished in `sheared_finish`).
//!
//! As in `opaque_row`, the kernels have a plain form and an AVX2 form that performs the same
//! IEEE operations in the same order, so both give the same bits.
use super::glow::{glow_row, GlowScratch};
use super::lines::Phase;
use super::opaque_row::{alpha_constant, alpha_span};

/// Sheared row `j` of a `(h, w, C)` image: `out[x] = lerp(img[floor(y)][x], img[floor(y)+1][x], frac(y))`
/// with `y = j + x t + c0` (`phase` from `Phase::new(w, t, c0, 1.0)`), zero outside the image.
/// `c0` in [0, 1) is the phase of a crop whose first column is not column 0 of the full image.
/// Only columns `xa .. xa + n` are computed, into `out[(x - xa) * C ..]`.
pub(crate) fn shear_row<const C: usize>(
    img: &[f32],
    w: usize,
    h: usize,
    phase: &Phase,
    j: i64,
    (xa, n): (usize, usize),
    out: &mut [f32],
) {
    // The columns whose two samples are both in the image (y0 in [0, h - 2]) form one interval
    // (the floors are monotone): there the loop needs no test.
    let fl = &phase.floor[xa..xa + n];
    let (lo, hi) = (-j, h as i64 - 2 - j);
    let (ia, ib) = if fl.len() < 2 || fl[0] <= fl[fl.len() - 1] {
        (
            fl.partition_point(|&f| f < lo),
            fl.partition_point(|&f| f <= hi),
        )
    } else {
        (
            fl.partition_point(|&f| f > hi),
            fl.partition_point(|&f| f >= lo),
        )
    };
    let ib = ib.max(ia);
    assert!(img.len() >= w * h * C && out.len() >= n * C && xa + n <= w);
    let (fl, fr) = (
        &phase.floor[xa + ia..xa + ib],
        &phase.frac[xa + ia..xa + ib],
    );
    #[cfg(target_arch = "x86_64")]
    if C == 4 && super::simd() {
        // SAFETY: AVX2 was detected; every pixel read is in the image (as below).
        unsafe { shear4_avx(img, w, j, fl, fr, xa + ia, &mut out[ia * 4..ib * 4]) };
        return shear_edges::<C>(img, w, h, phase, j, (xa, n), (ia, ib), out);
    }
    let o = &mut out[ia * C..ib * C];
    for (k, (o, (&fl, &f))) in o.chunks_exact_mut(C).zip(fl.iter().zip(fr)).enumerate() {
        let x = xa + ia + k;
        let y0 = (j + fl) as usize;
        debug_assert!(y0 + 1 < h);
        // SAFETY: y0 + 1 < h (the interval's definition) and x < w, so both pixels are in
        // `img` (asserted to hold h * w * C values).
        let (a, b) = unsafe {
            (
                img.get_unchecked((y0 * w + x) * C..(y0 * w + x) * C + C),
                img.get_unchecked(((y0 + 1) * w + x) * C..((y0 + 1) * w + x) * C + C),
            )
        };
        for c in 0..C {
            o[c] = (1.0 - f) * a[c] + f * b[c];
        }
    }
    shear_edges::<C>(img, w, h, phase, j, (xa, n), (ia, ib), out)
}

/// How many sheared rows ahead `shear4_avx` prefetches.
#[cfg(target_arch = "x86_64")]
const AHEAD: usize = 4;

/// `shear_row`'s interior for four channels: the same operations lane for lane.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn shear4_avx(
    img: &[f32],
    w: usize,
    j: i64,
    fl: &[i64],
    fr: &[f32],
    x0: usize,
    out: &mut [f32],
) {
    use std::arch::x86_64::*;
    let (p, o) = (img.as_ptr(), out.as_mut_ptr());
    for (k, (&fl, &f)) in fl.iter().zip(fr).enumerate() {
        let x = x0 + k;
        let y0 = (j + fl) as usize;
        if x % 4 == 0 {
            // The pixels that sheared row j + AHEAD reads here (a diagonal walk through the
            // image defeats the hardware prefetchers); a prefetch past the image is harmless.
            let at = p.wrapping_add(((y0 + AHEAD) * w + x) * 4);
            _mm_prefetch::<_MM_HINT_T0>(at as *const i8);
            _mm_prefetch::<_MM_HINT_T0>(at.wrapping_add(w * 4) as *const i8);
        }
        let a = _mm_loadu_ps(p.add((y0 * w + x) * 4));
        let b = _mm_loadu_ps(p.add(((y0 + 1) * w + x) * 4));
        let v = _mm_add_ps(
            _mm_mul_ps(_mm_set1_ps(1.0 - f), a),
            _mm_mul_ps(_mm_set1_ps(f), b),
        );
        _mm_storeu_ps(o.add(k * 4), v);
    }
}

/// `shear_row` at the columns outside its interior `ia .. ib` (relative to `xa`).
#[allow(clippy::too_many_arguments)]
fn shear_edges<const C: usize>(
    img: &[f32],
    w: usize,
    h: usize,
    phase: &Phase,
    j: i64,
    (xa, n): (usize, usize),
    (ia, ib): (usize, usize),
    out: &mut [f32],
) {
    for x in (xa..xa + ia).chain(xa + ib..xa + n) {
        let y0 = j + phase.floor[x];
        let f = phase.frac[x];
        let o = &mut out[(x - xa) * C..(x - xa) * C + C];
        if y0 >= 0 && y0 + 1 < h as i64 {
            let a = &img[(y0 as usize * w + x) * C..][..C];
            let b = &img[((y0 + 1) as usize * w + x) * C..][..C];
            for c in 0..C {
                o[c] = (1.0 - f) * a[c] + f * b[c];
            }
            continue;
        }
        o.fill(0.0);
        if y0 >= 0 && y0 < h as i64 {
            let p = &img[(y0 as usize * w + x) * C..][..C];
            for c in 0..C {
                o[c] += (1.0 - f) * p[c];
            }
        }
        if y0 + 1 >= 0 && y0 + 1 < h as i64 {
            let p = &img[((y0 + 1) as usize * w + x) * C..][..C];
            for c in 0..C {
                o[c] += f * p[c];
            }
        }
    }
}

/// Scratch buffers of one thread for `filter_row`.
#[derive(Default)]
pub(crate) struct FilterScratch {
    glow: GlowScratch,
    a: Vec<f32>,
    g: Vec<f32>,
}

/// The filter of one `(n, 4)` row into `(n, 5)` values: the mean of the `2r + 1` pixels
/// `x - r ..= x + r` (zero outside; running sums in f64) and eq. 10's glow of the alpha, over
/// the pixels within reach of non-zero alpha; zero elsewhere. Returns false (writing nothing)
/// when the row's alpha is zero everywhere.
pub(crate) fn filter_row(
    src: &[f32],
    n: usize,
    r: usize,
    out: &mut [f32],
    s: &mut FilterScratch,
    simd: bool,
) -> bool {
    let Some((lo, hi)) = alpha_span(src, simd) else {
        return false;
    };
    let (xa, xb) = (lo.saturating_sub(r), (hi + r + 1).min(n));
    out[..xa * 5].fill(0.0);
    out[xb * 5..].fill(0.0);
    let row = &src[xa * 4..xb * 4];
    s.g.resize(xb - xa, 0.0);
    if alpha_constant(row, simd) {
        // A constant alpha is its own glow (`glow_row` would copy it).
        s.g.iter_mut()
            .zip(row.chunks_exact(4))
            .for_each(|(g, p)| *g = p[3]);
    } else {
        s.a.clear();
        s.a.extend(row.chunks_exact(4).map(|px| px[3]));
        glow_row(&s.a, r, &mut s.g, &mut s.glow);
    }
    #[cfg(target_arch = "x86_64")]
    if simd {
        assert!(src.len() == n * 4 && out.len() == n * 5 && xb <= n);
        // SAFETY: AVX2 was detected; the lengths were checked above.
        unsafe { avx::means5(src, n, r, (xa, xb), &s.g, out) };
        return true;
    }
    let g = &s.g;
    super::boxblur::box_row_range(src, n, r, xa, xb, |x, m| {
        out[x * 5..x * 5 + 4].copy_from_slice(&m);
        out[x * 5 + 4] = g[x - xa];
    });
    true
}

#[cfg(target_arch = "x86_64")]
mod avx {
    //! The AVX2 form. Callers check that AVX2 is present and that the slices are long enough.
    use std::arch::x86_64::*;

    /// Pixel `i` of a `(n, 4)` row as four f64 lanes.
    #[inline(always)]
    unsafe fn px(p: *const f32, i: usize) -> __m256d {
        _mm256_cvtps_pd(_mm_loadu_ps(p.add(i * 4)))
    }

    /// `filter_row`'s running sums (the plain form's operations and order): the means of
    /// pixels `xa .. xb` and their glow `g[x - xa]` into `out[x * 5 ..]`.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn means5(
        src: &[f32],
        n: usize,
        r: usize,
        (xa, xb): (usize, usize),
        g: &[f32],
        out: &mut [f32],
    ) {
        if xa >= xb {
            return;
        }
        let (p, o) = (src.as_ptr(), out.as_mut_ptr());
        let inv = _mm256_set1_pd(1.0 / (2 * r + 1) as f64);
        let mut s = _mm256_setzero_pd();
        for i in xa.saturating_sub(r)..=(xa + r).min(n - 1) {
            s = _mm256_add_pd(s, px(p, i));
        }
        let emit = |x: usize, s: __m256d| {
            _mm_storeu_ps(o.add(x * 5), _mm256_cvtpd_ps(_mm256_mul_pd(s, inv)));
            *o.add(x * 5 + 4) = g[x - xa];
        };
        // The entering tap (x + r + 1 < n) and the leaving one (x >= r) switch once each.
        let add_end = n.saturating_sub(r + 1).clamp(xa, xb);
        let sub_start = r.clamp(xa, xb);
        let e0 = add_end.min(sub_start);
        for x in xa..e0 {
            emit(x, s);
            s = _mm256_add_pd(s, px(p, x + r + 1));
        }
        for x in e0..add_end {
            emit(x, s);
            s = _mm256_add_pd(s, px(p, x + r + 1));
            s = _mm256_sub_pd(s, px(p, x - r));
        }
        for x in add_end..sub_start.max(add_end) {
            emit(x, s);
        }
        for x in sub_start.max(add_end)..xb {
            emit(x, s);
            s = _mm256_sub_pd(s, px(p, x - r));
        }
    }
}
