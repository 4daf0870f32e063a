//! One image row of the opaque blur: the checks that decide what a row needs (finite values and
//! alphas in [0, 1], the span of non-zero alpha, a constant alpha) and the fused pass that runs
//! the box filter's running sums, Kraus's eq. 7 and the composite in one sweep, writing each
//! output pixel once.
//!
//! Every kernel has a plain form and, on x86-64 CPUs with AVX2 (detected at run time), a vector
//! form that performs the same IEEE operations in the same order on the same values (four f64
//! lanes are the four channels of a running sum, four f32 lanes the channels of a pixel), so both
//! give the same bits and the choice never shows in a result. The vector form of the fused pass
//! runs two rows side by side: a running sum is one chain of dependent additions, and two
//! independent chains keep the adders busy.
use super::ALPHA_EPS;
use crate::error::{Error, Result};
use std::mem::MaybeUninit;

/// How the blurred layer is combined with the base image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Composite {
    /// `sub + (1 - A_sub) base`: a moving foreground over the sharp image (figure 6).
    Over,
    /// `base + (1 - A_base) sub`: a moving background under the sharp foreground (figure 7).
    Under,
}

impl Composite {
    /// Parse `over` or `under`; anything else is an error naming `mode`.
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "over" => Ok(Composite::Over),
            "under" => Ok(Composite::Under),
            _ => Err(Error::value(
                "mode",
                format!("expected 'over' or 'under', got {s:?}"),
            )),
        }
    }
}

/// Eq. 7 and the composite for one pixel: the blurred pixel `blur`, its glow, the base pixel.
#[inline(always)]
pub(crate) fn finish(blur: [f32; 4], glow: f32, base: &[f32], comp: Option<Composite>) -> [f32; 4] {
    let s = if blur[3] > ALPHA_EPS {
        glow / blur[3]
    } else {
        0.0
    };
    let sub = [blur[0] * s, blur[1] * s, blur[2] * s, glow];
    match comp {
        None => sub,
        Some(Composite::Over) => {
            let k = 1.0 - glow;
            [
                sub[0] + k * base[0],
                sub[1] + k * base[1],
                sub[2] + k * base[2],
                sub[3] + k * base[3],
            ]
        }
        Some(Composite::Under) => {
            let k = 1.0 - base[3];
            [
                base[0] + k * sub[0],
                base[1] + k * sub[1],
                base[2] + k * sub[2],
                base[3] + k * sub[3],
            ]
        }
    }
}

/// Whether a `(n, 4)` row is premultiplied colour as the opaque blur needs it: every value
/// finite (no NaN, no infinity) and every alpha in [0, 1] (`super::alpha_out_of_range`).
pub(crate) fn premultiplied(v: &[f32], simd: bool) -> bool {
    alpha_range(v, simd).is_some()
}

/// `Some((lo, hi))`, the smallest and the largest alpha of a `(n, 4)` row (`n >= 1`), when the
/// row is [`premultiplied`]; `None` when it is not. One pass: the check and the range together.
pub(crate) fn alpha_range(v: &[f32], simd: bool) -> Option<(f32, f32)> {
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: `simd` is true only where AVX2 was detected.
        return unsafe { avx::alpha_range(v) };
    }
    let _ = simd;
    // Lane-wise accumulators over 16 values (4 pixels) so that the loop vectorises.
    let mut bad = [0u32; 16];
    let mut lo = [f32::INFINITY; 16];
    let mut hi = [f32::NEG_INFINITY; 16];
    let mut chunks = v.chunks_exact(16);
    for c in &mut chunks {
        for i in 0..16 {
            let b = c[i].to_bits();
            bad[i] |= ((b & 0x7f80_0000) == 0x7f80_0000) as u32;
            bad[i] |= (i & 3 == 3) as u32 & super::alpha_out_of_range(b) as u32;
            lo[i] = if c[i] < lo[i] { c[i] } else { lo[i] };
            hi[i] = if c[i] > hi[i] { c[i] } else { hi[i] };
        }
    }
    let tail = chunks.remainder();
    if bad.iter().any(|&b| b != 0) || !tail_premultiplied(tail) {
        return None;
    }
    let alphas = (3..16).step_by(4).map(|i| (lo[i], hi[i]));
    let tails = tail.chunks_exact(4).map(|p| (p[3], p[3]));
    Some(
        alphas
            .chain(tails)
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), (a, b)| {
                (l.min(a), h.max(b))
            }),
    )
}

/// [`premultiplied`] of the last pixels of a row (fewer than four), one by one.
fn tail_premultiplied(v: &[f32]) -> bool {
    v.chunks(4).all(|p| {
        p.iter().all(|v| v.is_finite())
            && p.len() == 4
            && !super::alpha_out_of_range(p[3].to_bits())
    })
}

/// First and last pixel with non-zero alpha in a `(n, 4)` row.
pub(crate) fn alpha_span(row: &[f32], simd: bool) -> Option<(usize, usize)> {
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: `simd` is true only where AVX2 was detected.
        return unsafe { avx::alpha_span(row) };
    }
    let _ = simd;
    // Blocks of 16 pixels are tested with an OR of the alpha bits, then the first and last
    // non-empty blocks are searched.
    const B: usize = 16;
    let nz = |c: &[f32]| {
        c.chunks_exact(4)
            .fold(0u32, |m, p| m | (p[3].to_bits() & 0x7fff_ffff))
            != 0
    };
    let blocks = row.len().div_ceil(4 * B);
    let block = |b: usize| &row[b * 4 * B..((b + 1) * 4 * B).min(row.len())];
    let first = (0..blocks).find(|&b| nz(block(b)))?;
    let last = (first..blocks).rev().find(|&b| nz(block(b)))?;
    let lo = block(first).chunks_exact(4).position(|p| p[3] != 0.0)? + first * B;
    let hi = block(last).chunks_exact(4).rposition(|p| p[3] != 0.0)? + last * B;
    Some((lo, hi))
}

/// Whether the alpha of the finite `(n, 4)` row is one value `>= 0` (so its glow is itself):
/// every alpha equal to the first one (and so the smallest to the largest), which is `>= 0`.
/// Stops at the first block of pixels with a different alpha.
pub(crate) fn alpha_constant(row: &[f32], simd: bool) -> bool {
    #[cfg(target_arch = "x86_64")]
    if simd && row.len() >= 8 {
        // SAFETY: `simd` is true only where AVX2 was detected.
        return unsafe { avx::alpha_constant(row) };
    }
    let _ = simd;
    let Some(&a0) = row.get(3) else {
        return false;
    };
    a0 >= 0.0 && row.chunks_exact(4).all(|p| p[3] == a0)
}

/// The glow of a row's pixels: one value for the whole span (a row whose alpha is constant is
/// its own glow), or the glow of pixels `xa ..` of the span.
#[derive(Clone, Copy)]
pub(crate) enum Glow<'a> {
    Const(f32),
    Row(&'a [f32]),
}

/// One row for `box_finish`: the source row and the base row (`(n, 4)` each; the base is not
/// read without a composite), the output row, the pixels `xa .. xb` to write and their glow.
pub(crate) struct RowJob<'a> {
    pub(crate) src: &'a [f32],
    pub(crate) base: &'a [f32],
    pub(crate) out: &'a mut [MaybeUninit<f32>],
    pub(crate) span: (usize, usize),
    pub(crate) glow: Glow<'a>,
}

/// Writes pixels `xa .. xb` of each job's output row: the mean of the `2r + 1` source pixels
/// `x - r ..= x + r` (zero outside the row; running sums in f64, started at `xa - r`), eq. 7 with
/// the job's glow, and the composite with its base. Every row has `n` pixels; one or two jobs.
/// `stream`: the output is too large to stay in the cache (a full frame), so the vector form
/// writes it with non-temporal stores, which do not read each line before writing it: the same
/// values, a third less memory traffic.
pub(crate) fn box_finish(
    jobs: &mut [RowJob],
    n: usize,
    r: usize,
    comp: Option<Composite>,
    simd: bool,
    stream: bool,
) {
    for j in jobs.iter() {
        let (xa, xb) = j.span;
        assert!(j.src.len() == n * 4 && j.base.len() == n * 4 && j.out.len() == n * 4);
        assert!(xa <= xb && xb <= n);
        if let Glow::Row(g) = j.glow {
            assert!(g.len() >= xb - xa);
        }
    }
    #[cfg(target_arch = "x86_64")]
    if simd {
        // SAFETY: AVX2 was detected; the lengths were checked above.
        unsafe { avx::box_finish(jobs, n, r, comp, stream) };
        return;
    }
    let _ = (simd, stream);
    for j in jobs.iter_mut() {
        let (xa, xb) = j.span;
        let (base, out, glow) = (j.base, &mut *j.out, j.glow);
        super::boxblur::box_row_range(j.src, n, r, xa, xb, |x, m| {
            let g = match glow {
                Glow::Const(c) => c,
                Glow::Row(g) => g[x - xa],
            };
            super::put4(out, x, finish(m, g, &base[x * 4..x * 4 + 4], comp));
        });
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use avx::{finish4, NONE, OVER, UNDER};

#[cfg(target_arch = "x86_64")]
mod avx {
    //! The AVX2 forms. Callers check that AVX2 is present and that the slices are long enough.
    //! The fused pass keeps a row's running sum in one 256-bit register (four f64 channels);
    //! two rows advance side by side, and every four steps the eight blurred alphas of the two
    //! rows are gathered into one register so that eq. 7 takes one division for eight pixels.
    use super::{Composite, Glow, RowJob, ALPHA_EPS};
    use std::arch::x86_64::*;

    /// `super::alpha_range`: the exponent test of every value, and on the alpha lanes the
    /// range test of `super::super::alpha_out_of_range` (above 1.0 as a signed integer, or
    /// negative other than -0.0), with the smallest and the largest value of every lane.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn alpha_range(v: &[f32]) -> Option<(f32, f32)> {
        let exp = _mm256_set1_epi32(0x7f80_0000);
        let one = _mm256_set1_epi32(0x3f80_0000);
        let neg0 = _mm256_set1_epi32(i32::MIN);
        let zero = _mm256_setzero_si256();
        let alpha = _mm256_setr_epi32(0, 0, 0, -1, 0, 0, 0, -1);
        let mut bad = _mm256_setzero_si256();
        let mut lo = [_mm256_set1_ps(f32::INFINITY); 2];
        let mut hi = [_mm256_set1_ps(f32::NEG_INFINITY); 2];
        let mut chunks = v.chunks_exact(16);
        for c in &mut chunks {
            let p = c.as_ptr();
            for k in 0..2 {
                let f = _mm256_loadu_ps(p.add(8 * k));
                lo[k] = _mm256_min_ps(lo[k], f);
                hi[k] = _mm256_max_ps(hi[k], f);
                let x = _mm256_castps_si256(f);
                bad = _mm256_or_si256(bad, _mm256_cmpeq_epi32(_mm256_and_si256(x, exp), exp));
                let above = _mm256_cmpgt_epi32(x, one);
                let neg =
                    _mm256_andnot_si256(_mm256_cmpeq_epi32(x, neg0), _mm256_cmpgt_epi32(zero, x));
                let out = _mm256_and_si256(_mm256_or_si256(above, neg), alpha);
                bad = _mm256_or_si256(bad, out);
            }
        }
        let tail = chunks.remainder();
        if _mm256_testz_si256(bad, bad) == 0 || !super::tail_premultiplied(tail) {
            return None;
        }
        let mut l = [0.0f32; 8];
        let mut h = [0.0f32; 8];
        _mm256_storeu_ps(l.as_mut_ptr(), _mm256_min_ps(lo[0], lo[1]));
        _mm256_storeu_ps(h.as_mut_ptr(), _mm256_max_ps(hi[0], hi[1]));
        let (mut lo, mut hi) = (l[3].min(l[7]), h[3].max(h[7]));
        for p in tail.chunks_exact(4) {
            (lo, hi) = (lo.min(p[3]), hi.max(p[3]));
        }
        Some((lo, hi))
    }

    /// Whether pixels `2i` and `2i + 1` of the row (8 floats at `p`) have a non-zero alpha.
    #[inline(always)]
    unsafe fn pair_nonzero(p: *const f32) -> bool {
        let m = _mm256_setr_epi32(0, 0, 0, 0x7fff_ffff, 0, 0, 0, 0x7fff_ffff);
        _mm256_testz_si256(_mm256_loadu_si256(p as *const __m256i), m) == 0
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn alpha_span(row: &[f32]) -> Option<(usize, usize)> {
        let n = row.len() / 4;
        let pairs = n / 2;
        let p = row.as_ptr();
        let nz = |x: usize| row[x * 4 + 3] != 0.0;
        let lo = match (0..pairs).find(|&i| pair_nonzero(p.add(i * 8))) {
            Some(i) => (2 * i..2 * i + 2).find(|&x| nz(x))?,
            None => (2 * pairs..n).find(|&x| nz(x))?,
        };
        let hi = match (2 * pairs..n).rev().find(|&x| nz(x)) {
            Some(x) => x,
            None => {
                let i = (0..pairs).rev().find(|&i| pair_nonzero(p.add(i * 8)))?;
                (2 * i..2 * i + 2).rev().find(|&x| nz(x))?
            }
        };
        Some((lo, hi))
    }

    /// `super::alpha_constant`: the alphas compared with the first one, 16 pixels at a time.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn alpha_constant(row: &[f32]) -> bool {
        let a0 = row[3];
        if a0.is_nan() || a0 < 0.0 {
            return false;
        }
        let first = _mm256_set1_ps(a0);
        let mut chunks = row.chunks_exact(64);
        for c in &mut chunks {
            let p = c.as_ptr();
            let eq = [0, 1, 2, 3, 4, 5, 6, 7]
                .map(|i| _mm256_cmp_ps::<_CMP_EQ_OQ>(_mm256_loadu_ps(p.add(8 * i)), first));
            let e01 = _mm256_and_ps(_mm256_and_ps(eq[0], eq[1]), _mm256_and_ps(eq[2], eq[3]));
            let e23 = _mm256_and_ps(_mm256_and_ps(eq[4], eq[5]), _mm256_and_ps(eq[6], eq[7]));
            if _mm256_movemask_ps(_mm256_and_ps(e01, e23)) & 0x88 != 0x88 {
                return false;
            }
        }
        chunks.remainder().chunks_exact(4).all(|p| p[3] == a0)
    }

    /// The composite as a const parameter of the AVX2 kernels: none, over, under.
    pub(crate) const NONE: u8 = 0;
    pub(crate) const OVER: u8 = 1;
    pub(crate) const UNDER: u8 = 2;

    /// Eq. 7 and the composite of one pixel: `m` its blurred RGBA, `g` its glow in every lane,
    /// `base` its base pixel (`super::finish`, lane for lane).
    #[inline(always)]
    pub(crate) unsafe fn finish4<const C: u8>(m: __m128, g: __m128, base: *const f32) -> __m128 {
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

    /// One row of the fused pass: its pointers, span, glow and running sum.
    struct Row {
        src: *const f32,
        base: *const f32,
        out: *mut f32,
        xa: usize,
        xb: usize,
        /// The glow of pixel `x` is `glow[x - xa]`, or `cg` when `glow` is null.
        glow: *const f32,
        cg: f32,
        sum: __m256d,
    }

    /// Pixel `i` of a `(n, 4)` row as four f64 lanes.
    #[inline(always)]
    unsafe fn px(p: *const f32, i: usize) -> __m256d {
        _mm256_cvtps_pd(_mm_loadu_ps(p.add(i * 4)))
    }

    impl Row {
        #[inline(always)]
        unsafe fn new(j: &mut RowJob, n: usize, r: usize) -> Self {
            let (xa, xb) = j.span;
            let (glow, cg) = match j.glow {
                Glow::Const(c) => (std::ptr::null(), c),
                Glow::Row(g) => (g.as_ptr(), 0.0),
            };
            let src = j.src.as_ptr();
            let mut sum = _mm256_setzero_pd();
            if xa < xb {
                for i in xa.saturating_sub(r)..=(xa + r).min(n - 1) {
                    sum = _mm256_add_pd(sum, px(src, i));
                }
            }
            Row {
                src,
                base: j.base.as_ptr(),
                out: j.out.as_mut_ptr() as *mut f32,
                xa,
                xb,
                glow,
                cg,
                sum,
            }
        }

        /// The glow of pixels `x .. x + 4`.
        #[inline(always)]
        unsafe fn glow4(&self, x: usize) -> __m128 {
            match self.glow.is_null() {
                true => _mm_set1_ps(self.cg),
                false => _mm_loadu_ps(self.glow.add(x - self.xa)),
            }
        }

        /// The mean of the taps of the current pixel, as four f32 lanes.
        #[inline(always)]
        unsafe fn mean(&self, inv: __m256d) -> __m128 {
            _mm256_cvtpd_ps(_mm256_mul_pd(self.sum, inv))
        }

        /// Moves the running sum from pixel `x` to `x + 1` (entering tap, then leaving tap).
        #[inline(always)]
        unsafe fn advance(&mut self, x: usize, n: usize, r: usize) {
            if x + r + 1 < n {
                self.sum = _mm256_add_pd(self.sum, px(self.src, x + r + 1));
            }
            if x >= r {
                self.sum = _mm256_sub_pd(self.sum, px(self.src, x - r));
            }
        }

        /// Pixel `x` alone (eq. 7 with its own division), then the next sum.
        #[inline(always)]
        unsafe fn step<const C: u8>(&mut self, x: usize, n: usize, r: usize, inv: __m256d) {
            let m = self.mean(inv);
            let g = match self.glow.is_null() {
                true => _mm_set1_ps(self.cg),
                false => _mm_broadcast_ss(&*self.glow.add(x - self.xa)),
            };
            let o = finish4::<C>(m, g, self.base.add(x * 4));
            _mm_storeu_ps(self.out.add(x * 4), o);
            self.advance(x, n, r);
        }
    }

    /// Pixels `x .. x + 4` of two rows: four steps of both running sums, then eq. 7 of the
    /// eight pixels with one division (`super::finish`'s operations, lane for lane). `NT`:
    /// non-temporal stores (both output rows 16-byte aligned).
    #[inline(always)]
    unsafe fn block4<const C: u8, const NT: bool>(
        a: &mut Row,
        b: &mut Row,
        x: usize,
        n: usize,
        r: usize,
        inv: __m256d,
    ) {
        let mut v = [_mm256_setzero_ps(); 4];
        let inner = x >= r && x + 4 + r < n;
        // The next two rows (the next job of this thread, usually) on their way into the cache
        // while these are computed; a prefetch past the image is harmless.
        _mm_prefetch::<_MM_HINT_T0>(a.src.wrapping_add(x * 4 + 2 * n * 4) as *const i8);
        _mm_prefetch::<_MM_HINT_T0>(b.src.wrapping_add(x * 4 + 2 * n * 4) as *const i8);
        for (i, v) in v.iter_mut().enumerate() {
            *v = _mm256_set_m128(b.mean(inv), a.mean(inv));
            if inner {
                a.sum = _mm256_add_pd(a.sum, px(a.src, x + i + r + 1));
                b.sum = _mm256_add_pd(b.sum, px(b.src, x + i + r + 1));
                a.sum = _mm256_sub_pd(a.sum, px(a.src, x + i - r));
                b.sum = _mm256_sub_pd(b.sum, px(b.src, x + i - r));
            } else {
                a.advance(x + i, n, r);
                b.advance(x + i, n, r);
            }
        }
        // The alphas of pixels x .. x + 4 of row a (low half) and of row b (high half).
        let t0 = _mm256_shuffle_ps::<0xff>(v[0], v[1]);
        let t1 = _mm256_shuffle_ps::<0xff>(v[2], v[3]);
        let alpha = _mm256_shuffle_ps::<0x88>(t0, t1);
        let g = _mm256_set_m128(b.glow4(x), a.glow4(x));
        let keep = _mm256_cmp_ps::<_CMP_GT_OQ>(alpha, _mm256_set1_ps(ALPHA_EPS));
        let s = _mm256_and_ps(_mm256_div_ps(g, alpha), keep);
        let k = _mm256_sub_ps(_mm256_set1_ps(1.0), g);
        macro_rules! finish {
            ($i:literal) => {{
                const I: i32 = $i * 0x55;
                let gi = _mm256_permute_ps::<I>(g);
                let sub =
                    _mm256_blend_ps::<0x88>(_mm256_mul_ps(v[$i], _mm256_permute_ps::<I>(s)), gi);
                let (pa, pb) = (a.base.add((x + $i) * 4), b.base.add((x + $i) * 4));
                let o = match C {
                    OVER => _mm256_add_ps(
                        sub,
                        _mm256_mul_ps(_mm256_permute_ps::<I>(k), _mm256_loadu2_m128(pb, pa)),
                    ),
                    UNDER => {
                        let base = _mm256_loadu2_m128(pb, pa);
                        let kb =
                            _mm256_sub_ps(_mm256_set1_ps(1.0), _mm256_permute_ps::<0xff>(base));
                        _mm256_add_ps(base, _mm256_mul_ps(kb, sub))
                    }
                    _ => sub,
                };
                if NT {
                    _mm_stream_ps(a.out.add((x + $i) * 4), _mm256_castps256_ps128(o));
                    _mm_stream_ps(b.out.add((x + $i) * 4), _mm256_extractf128_ps::<1>(o));
                } else {
                    _mm256_storeu2_m128(b.out.add((x + $i) * 4), a.out.add((x + $i) * 4), o);
                }
            }};
        }
        finish!(0);
        finish!(1);
        finish!(2);
        finish!(3);
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn box_finish(
        jobs: &mut [RowJob],
        n: usize,
        r: usize,
        comp: Option<Composite>,
        stream: bool,
    ) {
        // non-temporal stores need 16-byte aligned pixels (every pixel is when its row is)
        let aligned = jobs.iter().all(|j| j.out.as_ptr() as usize % 16 == 0);
        match (comp, stream && aligned) {
            (None, false) => rows::<NONE, false>(jobs, n, r),
            (Some(Composite::Over), false) => rows::<OVER, false>(jobs, n, r),
            (Some(Composite::Under), false) => rows::<UNDER, false>(jobs, n, r),
            (None, true) => rows::<NONE, true>(jobs, n, r),
            (Some(Composite::Over), true) => rows::<OVER, true>(jobs, n, r),
            (Some(Composite::Under), true) => rows::<UNDER, true>(jobs, n, r),
        }
        if stream {
            // the non-temporal stores ordered before whatever this thread does next (the
            // rayon join that hands the rows over)
            _mm_sfence();
        }
    }

    #[target_feature(enable = "avx2")]
    unsafe fn rows<const C: u8, const NT: bool>(jobs: &mut [RowJob], n: usize, r: usize) {
        let inv = _mm256_set1_pd(1.0 / (2 * r + 1) as f64);
        let (a, b) = match jobs {
            [a, b] => (a, b),
            _ => {
                for j in jobs.iter_mut() {
                    let mut a = Row::new(j, n, r);
                    for x in a.xa..a.xb {
                        a.step::<C>(x, n, r, inv);
                    }
                }
                return;
            }
        };
        let (mut a, mut b) = (Row::new(a, n, r), Row::new(b, n, r));
        // Each row on its own up to where both are in their spans, side by side while both
        // are, then each on its own to the end of its span.
        let m0 = a.xa.max(b.xa);
        let m1 = a.xb.min(b.xb).max(m0);
        for x in a.xa..m0.min(a.xb) {
            a.step::<C>(x, n, r, inv);
        }
        for x in b.xa..m0.min(b.xb) {
            b.step::<C>(x, n, r, inv);
        }
        let mut x = m0;
        while x + 4 <= m1 {
            block4::<C, NT>(&mut a, &mut b, x, n, r, inv);
            x += 4;
        }
        for x in x..m1 {
            a.step::<C>(x, n, r, inv);
            b.step::<C>(x, n, r, inv);
        }
        for x in m1.max(a.xa)..a.xb {
            a.step::<C>(x, n, r, inv);
        }
        for x in m1.max(b.xa)..b.xb {
            b.step::<C>(x, n, r, inv);
        }
    }
}
