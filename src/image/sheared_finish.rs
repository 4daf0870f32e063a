//! Eq. 7 and the composite of the output pixels of the opaque blur along an oblique direction:
//! each output pixel interpolates the five filtered values (box mean RGBA and glow, see
//! `sheared_row`) of two sheared rows (`lines`), raises the glow to its own alpha, rescales and
//! composites.
//!
//! As in `opaque_row`, each kernel has a plain form and an AVX2 form that performs the same IEEE
//! operations in the same order, so both give the same bits.
use super::lines::Sheared;
use super::opaque_row::{finish, Composite};
use std::mem::MaybeUninit;

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

/// What the output rows of a crop need of its filtered sheared rows, computed once: the runs of
/// columns that read the same two sheared rows (`Sheared::runs`), and for the direct path of
/// the AVX2 form each column's sheared row and weights and where each sheared row is.
pub(crate) struct Unshear {
    runs: Vec<(usize, usize)>,
    /// Per column: `Sheared::row_offset`.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    offset: Vec<isize>,
    /// Per column: the weights `1 - frac` and `frac`.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    weights: Vec<[f32; 2]>,
    /// How many sheared rows before row `k` fail to hold all the columns that output rows
    /// `0 .. ch - 1` may read of them (`ch` rows in all), at `bad[k]`.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    bad: Vec<u32>,
    /// Output rows.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    rows: usize,
    /// Per sheared row: column `x` of it is at `data[index + 5 x ..]` (for `x` in its span),
    /// then `AHEAD` zeros so that a prefetch may name a row past the last.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    index: Vec<isize>,
    /// The smallest and largest row offset.
    offsets: (isize, isize),
}

/// How many output rows ahead the direct path prefetches.
const AHEAD: usize = 4;

impl Unshear {
    /// For the `ch` output rows of a crop `cw` columns wide.
    pub(crate) fn new(sh: &Sheared<5>, cw: usize, ch: usize) -> Self {
        let runs = sh.runs(cw);
        let run_rows: Vec<_> = runs
            .iter()
            .map(|&(xs, xe)| (xs, xe, sh.row_offset(xs) as isize))
            .collect();
        let offset = (0..cw).map(|x| sh.row_offset(x) as isize).collect();
        let weights = sh.fracs()[..cw].iter().map(|&f| [1.0 - f, f]).collect();
        let index = sh
            .row_list()
            .map(|(s, _, o)| (o as isize - s as isize) * 5)
            .chain([0; AHEAD])
            .collect();
        let offsets = run_rows
            .iter()
            .fold((isize::MAX, isize::MIN), |(lo, hi), r| {
                (lo.min(r.2), hi.max(r.2))
            });
        // Output row y < ch - 1 reads sheared rows y + k and y + k + 1 over a run of row offset
        // k, so sheared row j is read over the runs whose offset is in [j - (ch - 1), j]: a
        // window of runs (the offsets are monotone in x), whose columns it must hold.
        let up = run_rows.first().map(|r| r.2) <= run_rows.last().map(|r| r.2);
        let mut bad = vec![0u32];
        for (j, (s, e, _)) in sh.row_list().enumerate() {
            let (lo, hi) = (j as isize + 1 - ch as isize, j as isize);
            let (r0, r1) = match up {
                true => (
                    run_rows.partition_point(|r| r.2 < lo),
                    run_rows.partition_point(|r| r.2 <= hi),
                ),
                false => (
                    run_rows.partition_point(|r| r.2 > hi),
                    run_rows.partition_point(|r| r.2 >= lo),
                ),
            };
            let holds = r0 >= r1 || (s <= run_rows[r0].0 && run_rows[r1 - 1].1 <= e);
            bad.push(bad[j] + !holds as u32);
        }
        Unshear {
            runs,
            offset,
            weights,
            bad,
            rows: ch,
            index,
            offsets,
        }
    }
    /// The crop's width.
    fn width(&self) -> usize {
        self.runs.last().map_or(0, |r| r.1)
    }

    /// Whether both sheared rows that output row `y` reads hold every column of every run (so
    /// that no pixel of the row is a piece of a zero row). Not the crop's last row.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    fn direct(&self, y: usize) -> bool {
        let (y, (k0, k1)) = (y as isize, self.offsets);
        let n = self.bad.len() as isize - 1;
        y + 1 < self.rows as isize
            && y + k0 >= 0
            && y + k1 + 1 < n
            && self.bad[(y + k1 + 2) as usize] == self.bad[(y + k0) as usize]
    }
}

/// Crop row `y` of the output from the filtered sheared rows `sh` (`u` from `Unshear::new`):
/// `alpha`, `base` and `out` are the row's `(cw, 4)` source (for its alpha), base and output
/// pixels; `scratch` a buffer of the calling thread. The plain form goes piece by piece. The
/// AVX2 form interpolates a row whose sheared rows hold all its columns (`Unshear::direct`)
/// into `scratch` column by column and finishes eight pixels at a time; any other row it takes
/// run by run, a run whose two sheared rows are both present in one stretch.
#[allow(clippy::too_many_arguments)]
pub(crate) fn finish_row(
    sh: &Sheared<5>,
    u: &Unshear,
    y: usize,
    alpha: &[f32],
    base: &[f32],
    out: &mut [MaybeUninit<f32>],
    comp: Option<Composite>,
    simd: bool,
    scratch: &mut Vec<f32>,
) {
    let cw = u.width();
    assert!(alpha.len() >= cw * 4 && base.len() >= cw * 4 && out.len() >= cw * 4);
    #[cfg(target_arch = "x86_64")]
    if simd {
        if u.direct(y) {
            scratch.resize(cw * 5, 0.0);
            // SAFETY: AVX2 was detected; the row lengths were checked above and `direct` says
            // that every column the row reads is in the sheared rows.
            unsafe { avx::direct_row(sh, u, y, alpha, base, out, comp, scratch) };
        } else {
            // SAFETY: AVX2 was detected; the row lengths were checked above.
            unsafe { avx::finish_row(sh, &u.runs, y, alpha, base, out, comp) };
        }
        return;
    }
    let _ = scratch;
    for &run in &u.runs {
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
    use super::{lerp, Composite, Piece, Sheared, Unshear, AHEAD};
    use crate::image::opaque_row::{finish4, NONE, OVER, UNDER};
    use crate::image::ALPHA_EPS;
    use std::arch::x86_64::*;
    use std::mem::MaybeUninit;

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

    /// `super::finish_row` of a row that `Unshear::direct` accepts: the interpolated values of
    /// every column into `buf` (the mean RGBA of column `x` at `buf[x * 4 ..]`, the glow raised
    /// to the source alpha at `buf[cw * 4 + x]`), then eq. 7 and the composite of eight pixels
    /// at a time with one division (`run`'s operations, lane for lane).
    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn direct_row(
        sh: &Sheared<5>,
        u: &Unshear,
        y: usize,
        alpha: &[f32],
        base: &[f32],
        out: &mut [MaybeUninit<f32>],
        comp: Option<Composite>,
        buf: &mut [f32],
    ) {
        let cw = u.width();
        debug_assert!(buf.len() >= cw * 5 && u.direct(y));
        debug_assert!(u.offset.len() == cw && u.weights.len() == cw);
        let data = sh.data.as_ptr();
        let (mb, gb) = buf.split_at_mut(cw * 4);
        let (mb, gb) = (mb.as_mut_ptr(), gb.as_mut_ptr());
        let (pa, offset, weights) = (alpha.as_ptr(), u.offset.as_ptr(), u.weights.as_ptr());
        // Sheared row `y + k` is at `data[*rows.offset(k) ..]`, the one that output row
        // `y + AHEAD` reads at `data[*ahead.offset(k) ..]` (the index has AHEAD rows of
        // padding).
        let rows = u.index.as_ptr().add(y);
        let ahead = rows.add(AHEAD);
        for x in 0..cw {
            let k = *offset.add(x);
            let [omf, f] = *weights.add(x);
            // The pixel that output row y + AHEAD reads here, on its way into the cache (the
            // diagonal walk through the sheared rows defeats the hardware prefetchers); a
            // prefetch outside the data is harmless.
            let next = data.wrapping_offset(*ahead.offset(k) + 5 * x as isize);
            _mm_prefetch::<_MM_HINT_T0>(next as *const i8);
            let a = data.offset(*rows.offset(k) + 5 * x as isize);
            let b = data.offset(*rows.offset(k + 1) + 5 * x as isize);
            let m = _mm_add_ps(
                _mm_mul_ps(_mm_set1_ps(omf), _mm_loadu_ps(a)),
                _mm_mul_ps(_mm_set1_ps(f), _mm_loadu_ps(b)),
            );
            let g5 = omf * *a.add(4) + f * *b.add(4);
            _mm_storeu_ps(mb.add(x * 4), m);
            *gb.add(x) = g5.max(*pa.add(x * 4 + 3));
        }
        let (pb, po) = (base.as_ptr(), out.as_mut_ptr() as *mut f32);
        match comp {
            None => eq7::<NONE>(mb, gb, cw, pb, po),
            Some(Composite::Over) => eq7::<OVER>(mb, gb, cw, pb, po),
            Some(Composite::Under) => eq7::<UNDER>(mb, gb, cw, pb, po),
        }
    }

    /// Eq. 7 and the composite of `n` pixels: mean RGBA `m[x * 4 ..]`, glow `g[x]`, base
    /// `base[x * 4 ..]`, into `out[x * 4 ..]`; eight pixels at a time, then one by one.
    #[inline(always)]
    unsafe fn eq7<const C: u8>(
        m: *const f32,
        g: *const f32,
        n: usize,
        base: *const f32,
        out: *mut f32,
    ) {
        let one = _mm256_set1_ps(1.0);
        // Pixel 2i of a block in the low half of register i, pixel 2i + 1 in the high half.
        let order = _mm256_setr_epi32(0, 2, 4, 6, 1, 3, 5, 7);
        let mut x = 0;
        while x + 8 <= n {
            let v = [0, 1, 2, 3].map(|i| _mm256_loadu_ps(m.add((x + 2 * i) * 4)));
            let t0 = _mm256_shuffle_ps::<0xff>(v[0], v[1]);
            let t1 = _mm256_shuffle_ps::<0xff>(v[2], v[3]);
            let alpha = _mm256_shuffle_ps::<0x88>(t0, t1);
            let gv = _mm256_permutevar8x32_ps(_mm256_loadu_ps(g.add(x)), order);
            let keep = _mm256_cmp_ps::<_CMP_GT_OQ>(alpha, _mm256_set1_ps(ALPHA_EPS));
            let s = _mm256_and_ps(_mm256_div_ps(gv, alpha), keep);
            let k = _mm256_sub_ps(one, gv);
            macro_rules! finish {
                ($i:literal) => {{
                    const I: i32 = $i * 0x55;
                    let gi = _mm256_permute_ps::<I>(gv);
                    let sub = _mm256_blend_ps::<0x88>(
                        _mm256_mul_ps(v[$i], _mm256_permute_ps::<I>(s)),
                        gi,
                    );
                    let at = (x + 2 * $i) * 4;
                    let o = match C {
                        OVER => _mm256_add_ps(
                            sub,
                            _mm256_mul_ps(_mm256_permute_ps::<I>(k), _mm256_loadu_ps(base.add(at))),
                        ),
                        UNDER => {
                            let b = _mm256_loadu_ps(base.add(at));
                            let kb = _mm256_sub_ps(one, _mm256_permute_ps::<0xff>(b));
                            _mm256_add_ps(b, _mm256_mul_ps(kb, sub))
                        }
                        _ => sub,
                    };
                    _mm256_storeu_ps(out.add(at), o);
                }};
            }
            finish!(0);
            finish!(1);
            finish!(2);
            finish!(3);
            x += 8;
        }
        for x in x..n {
            let o = finish4::<C>(
                _mm_loadu_ps(m.add(x * 4)),
                _mm_set1_ps(*g.add(x)),
                base.add(x * 4),
            );
            _mm_storeu_ps(out.add(x * 4), o);
        }
    }

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
            let o = finish4::<C>(m, g, base.add(x * 4));
            _mm_storeu_ps(out.add(x * 4), o);
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
