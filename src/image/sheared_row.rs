//! The row kernels of the opaque blur along any direction other than a row: the filter of one
//! sheared (or transposed) row into five values a pixel (the box mean's RGBA and the glow), and
//! eq. 7 with the composite of the output pixels that interpolate two such rows (`lines`).
//!
//! As in `opaque_row`, each has a plain form and an AVX2 form that performs the same IEEE
//! operations in the same order, so both give the same bits.
use super::glow::{glow_row, GlowScratch};
use super::lines::Sheared;
use super::opaque_row::{alpha_constant, alpha_span, finish, Composite};
use std::mem::MaybeUninit;

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

/// One piece of an output row (`lines::Sheared::pieces`): output pixels `x0 .. x1` interpolate
/// the five values of two filtered rows, `a` (weight `1 - frac`) and `b` (weight `frac`), each
/// `None` where that row is zero; their glow is raised to the source alpha (`alpha[x * 4]`),
/// then eq. 7 and the composite with `base` (`base[x * 4 ..]`) go to `out[x * 4 ..]`.
pub(crate) struct Piece<'a> {
    pub(crate) a: Option<&'a [f32]>,
    pub(crate) b: Option<&'a [f32]>,
    pub(crate) frac: &'a [f32],
    pub(crate) alpha: &'a [f32],
    pub(crate) base: &'a [f32],
    pub(crate) out: &'a mut [MaybeUninit<f32>],
}

/// Crop row `y` of the output from the filtered sheared rows `sh`, run by run (`Sheared::runs`):
/// `alpha`, `base` and `out` are the row's `(cw, 4)` source (for its alpha), base and output
/// pixels. Where both sheared rows cover a run (all but the ends of the
/// sheared rows) the run goes straight to `finish_piece`'s arithmetic; elsewhere piece by piece.
#[allow(clippy::too_many_arguments)]
pub(crate) fn finish_row(
    sh: &Sheared<5>,
    runs: &[(usize, usize)],
    y: usize,
    alpha: &[f32],
    base: &[f32],
    out: &mut [MaybeUninit<f32>],
    comp: Option<Composite>,
    simd: bool,
) {
    let cw = runs.last().map_or(0, |r| r.1);
    assert!(alpha.len() >= cw * 4 && base.len() >= cw * 4 && out.len() >= cw * 4);
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: AVX2 was detected; the row lengths were checked above.
        unsafe { avx::finish_row(sh, runs, y, alpha, base, out, comp) };
        return;
    }
    for &run in runs {
        finish_pieces(sh, run, y, alpha, base, out, comp, simd);
    }
}

/// `finish_row` over one run, piece by piece.
#[allow(clippy::too_many_arguments)]
#[inline]
fn finish_pieces(
    sh: &Sheared<5>,
    run: (usize, usize),
    y: usize,
    alpha: &[f32],
    base: &[f32],
    out: &mut [MaybeUninit<f32>],
    comp: Option<Composite>,
    simd: bool,
) {
    sh.pieces(y, run, |x0, x1, a, b, frac| {
        let piece = Piece {
            a,
            b,
            frac,
            alpha: &alpha[x0 * 4 + 3..x1 * 4],
            base: &base[x0 * 4..x1 * 4],
            out: &mut out[x0 * 4..x1 * 4],
        };
        finish_piece(piece, comp, simd);
    });
}

/// The interpolation of one of the five values, as `lines::Sheared::unshear_row` computes it.
#[inline(always)]
fn lerp(a: Option<&[f32]>, b: Option<&[f32]>, f: f32, i: usize) -> f32 {
    match (a, b) {
        (Some(a), Some(b)) => (1.0 - f) * a[i] + f * b[i],
        (Some(a), None) => (1.0 - f) * a[i],
        (None, Some(b)) => f * b[i],
        (None, None) => 0.0,
    }
}

/// Writes the output pixels of `p` (see `Piece`).
pub(crate) fn finish_piece(p: Piece, comp: Option<Composite>, simd: bool) {
    let n = p.frac.len();
    assert!(p.a.is_none_or(|a| a.len() == n * 5) && p.b.is_none_or(|b| b.len() == n * 5));
    assert!(p.alpha.len() + 3 >= n * 4 && p.base.len() >= n * 4 && p.out.len() >= n * 4);
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: AVX2 was detected; the lengths were checked above.
        unsafe { avx::finish_piece(p, comp) };
        return;
    }
    let _ = simd;
    for x in 0..n {
        let f = p.frac[x];
        let v =
            [0, 1, 2, 3].map(|c| lerp(p.a.map(|a| &a[x * 5..]), p.b.map(|b| &b[x * 5..]), f, c));
        let g = lerp(p.a.map(|a| &a[x * 5..]), p.b.map(|b| &b[x * 5..]), f, 4).max(p.alpha[x * 4]);
        let o = finish(v, g, &p.base[x * 4..x * 4 + 4], comp);
        super::put4(p.out, x, o);
    }
}

#[cfg(target_arch = "x86_64")]
mod avx {
    //! The AVX2 forms. Callers check that AVX2 is present and that the slices are long enough.
    use super::{lerp, Composite, Piece, Sheared};
    use crate::image::ALPHA_EPS;
    use std::arch::x86_64::*;
    use std::mem::MaybeUninit;

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

    /// `super::finish_row`: each run whose two sheared rows are both present goes through
    /// `run`, the others piece by piece.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn finish_row(
        sh: &Sheared<5>,
        runs: &[(usize, usize)],
        y: usize,
        alpha: &[f32],
        base: &[f32],
        out: &mut [MaybeUninit<f32>],
        comp: Option<Composite>,
    ) {
        match comp {
            None => row::<NONE>(sh, runs, y, alpha, base, out),
            Some(Composite::Over) => row::<OVER>(sh, runs, y, alpha, base, out),
            Some(Composite::Under) => row::<UNDER>(sh, runs, y, alpha, base, out),
        }
    }

    #[inline(always)]
    unsafe fn row<const C: u8>(
        sh: &Sheared<5>,
        runs: &[(usize, usize)],
        y: usize,
        alpha: &[f32],
        base: &[f32],
        out: &mut [MaybeUninit<f32>],
    ) {
        let (data, fracs) = (sh.data.as_ptr(), sh.fracs());
        let (pa, pb, po) = (alpha.as_ptr(), base.as_ptr(), out.as_mut_ptr() as *mut f32);
        let comp = match C {
            OVER => Some(Composite::Over),
            UNDER => Some(Composite::Under),
            _ => None,
        };
        for &(xs, xe) in runs {
            let [ra, rb] = sh.rows_at(y, xs);
            // The rows that output row y + AHEAD reads here, on their way into the cache (the
            // diagonal walk through the sheared rows defeats the hardware prefetchers).
            let [_, rf] = sh.rows_at(y + AHEAD, xs);
            if rf.0 <= xs && xe <= rf.1 {
                let at = data.add((rf.2 + xs - rf.0) * 5);
                _mm_prefetch::<_MM_HINT_T0>(at as *const i8);
                _mm_prefetch::<_MM_HINT_T0>(at.add((xe - xs) * 5 - 1) as *const i8);
            }
            if ra.0 <= xs && xe <= ra.1 && rb.0 <= xs && xe <= rb.1 {
                let (oa, ob) = ((ra.2 + xs - ra.0) * 5, (rb.2 + xs - rb.0) * 5);
                debug_assert!(oa.max(ob) + (xe - xs) * 5 <= sh.data.len());
                run::<C>(
                    data.add(oa),
                    data.add(ob),
                    fracs.get_unchecked(xs..xe),
                    pa.add(xs * 4),
                    pb.add(xs * 4),
                    po.add(xs * 4),
                );
            } else {
                super::finish_pieces(sh, (xs, xe), y, alpha, base, out, comp, true);
            }
        }
    }

    /// How many output rows ahead `row` prefetches.
    const AHEAD: usize = 4;

    const NONE: u8 = 0;
    const OVER: u8 = 1;
    const UNDER: u8 = 2;

    #[inline(always)]
    unsafe fn run<const C: u8>(
        a: *const f32,
        b: *const f32,
        frac: &[f32],
        alpha: *const f32,
        base: *const f32,
        out: *mut f32,
    ) {
        for (x, &f) in frac.iter().enumerate() {
            let (fv, gv) = (_mm_set1_ps(f), _mm_set1_ps(1.0 - f));
            let (pa, pb) = (a.add(x * 5), b.add(x * 5));
            let m = _mm_add_ps(
                _mm_mul_ps(gv, _mm_loadu_ps(pa)),
                _mm_mul_ps(fv, _mm_loadu_ps(pb)),
            );
            let g5 = (1.0 - f) * *pa.add(4) + f * *pb.add(4);
            let g = _mm_set1_ps(g5.max(*alpha.add(x * 4 + 3)));
            let o = finish::<C>(m, g, base.add(x * 4));
            _mm_storeu_ps(out.add(x * 4), o);
        }
    }

    /// `opaque_row::finish`, lane for lane.
    #[inline(always)]
    unsafe fn finish<const C: u8>(m: __m128, g: __m128, base: *const f32) -> __m128 {
        let one = _mm_set1_ps(1.0);
        let a = _mm_shuffle_ps::<0xff>(m, m);
        let keep = _mm_cmpgt_ps(a, _mm_set1_ps(ALPHA_EPS));
        let s = _mm_and_ps(_mm_div_ps(g, a), keep);
        let sub = _mm_blend_ps::<0b1000>(_mm_mul_ps(m, s), g);
        match C {
            OVER => _mm_add_ps(sub, _mm_mul_ps(_mm_sub_ps(one, g), _mm_loadu_ps(base))),
            UNDER => {
                let b = _mm_loadu_ps(base);
                let k = _mm_sub_ps(one, _mm_shuffle_ps::<0xff>(b, b));
                _mm_add_ps(b, _mm_mul_ps(k, sub))
            }
            _ => sub,
        }
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn finish_piece(p: Piece, comp: Option<Composite>) {
        let n = p.frac.len();
        let (pa, pb) = (p.a.map(|a| a.as_ptr()), p.b.map(|b| b.as_ptr()));
        let out = p.out.as_mut_ptr() as *mut f32;
        let (alpha, base) = (p.alpha.as_ptr(), p.base.as_ptr());
        let one = _mm_set1_ps(1.0);
        for x in 0..n {
            let f = *p.frac.get_unchecked(x);
            let (fv, gv) = (_mm_set1_ps(f), _mm_set1_ps(1.0 - f));
            let m = match (pa, pb) {
                (Some(a), Some(b)) => _mm_add_ps(
                    _mm_mul_ps(gv, _mm_loadu_ps(a.add(x * 5))),
                    _mm_mul_ps(fv, _mm_loadu_ps(b.add(x * 5))),
                ),
                (Some(a), None) => _mm_mul_ps(gv, _mm_loadu_ps(a.add(x * 5))),
                (None, Some(b)) => _mm_mul_ps(fv, _mm_loadu_ps(b.add(x * 5))),
                (None, None) => _mm_setzero_ps(),
            };
            let g5 = lerp(
                pa.map(|a| std::slice::from_raw_parts(a.add(x * 5), 5)),
                pb.map(|b| std::slice::from_raw_parts(b.add(x * 5), 5)),
                f,
                4,
            );
            let g = _mm_set1_ps(g5.max(*alpha.add(x * 4)));
            // `opaque_row::finish`, lane for lane.
            let a = _mm_shuffle_ps::<0xff>(m, m);
            let keep = _mm_cmpgt_ps(a, _mm_set1_ps(ALPHA_EPS));
            let s = _mm_and_ps(_mm_div_ps(g, a), keep);
            let sub = _mm_blend_ps::<0b1000>(_mm_mul_ps(m, s), g);
            let o = match comp {
                Some(Composite::Over) => _mm_add_ps(
                    sub,
                    _mm_mul_ps(_mm_sub_ps(one, g), _mm_loadu_ps(base.add(x * 4))),
                ),
                Some(Composite::Under) => {
                    let b = _mm_loadu_ps(base.add(x * 4));
                    let k = _mm_sub_ps(one, _mm_shuffle_ps::<0xff>(b, b));
                    _mm_add_ps(b, _mm_mul_ps(k, sub))
                }
                None => sub,
            };
            _mm_storeu_ps(out.add(x * 4), o);
        }
    }
}
