//! The row filter of the opaque blur along any direction other than a row: one sheared (or
//! transposed) row into five values a pixel, the box mean's RGBA and the glow (`lines`; the
//! output pixels that interpolate two such rows are finished in `sheared_finish`).
//!
//! As in `opaque_row`, the filter has a plain form and an AVX2 form that performs the same IEEE
//! operations in the same order, so both give the same bits.
use super::glow::{glow_row, GlowScratch};
use super::opaque_row::{alpha_constant, alpha_span};

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
