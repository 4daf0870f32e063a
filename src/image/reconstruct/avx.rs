//! The AVX2 paths of the reconstruction ([`super`]): eight pixels of a run of a row at a time,
//! lane for lane the IEEE operations of the scalar gather (the same bits: the parent module's
//! vector-against-plain and every-tap tests).
use std::mem::MaybeUninit;

use super::*;

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
pub(super) unsafe fn still8_avx(
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
        super::super::write_copy(out, &px[..out.len()]);
    }
    true
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
        super::super::write_copy(out, &px[..out.len()]);
    }
}

/// [`gather8`] in AVX2 (its docs). The still lanes' taps and the moving lanes' taps along `n`
/// lie on eight neighbouring pixels of a row (module docs): one load each, a gather only at the
/// image's left and right edges; the moving lanes' taps along their own velocities are
/// gathered.
///
/// # Safety
/// AVX2 is present, `x + 8 <= w`, `w * h * 4 < 2^31`, `out` holds 4 to 32 values.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn gather8_avx(
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
    let xf = _mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_set1_epi32(x as i32), iota));
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
    let (wl, hl) = (_mm256_set1_ps(w as f32), _mm256_set1_ps(h as f32));
    let (wi, cw) = (
        _mm256_set1_epi32(w as i32),
        _mm256_set1_epi32(reach.cw as i32),
    );
    let (xc, yc) = (_mm256_add_ps(xf, half), _mm256_add_ps(yf, half));
    let mut still = _mm256_andnot_ps(moving, live);
    let movers = _mm256_and_ps(moving, live);
    let any = |m: __m256| _mm256_movemask_ps(m) != 0;
    // the moving lanes' own half velocities
    let (c0, c1) = if any(movers) {
        let c: [[f32; 2]; 8] =
            std::array::from_fn(|l| half_at(g.velocity, i0 + l, params.tile as f32));
        (
            _mm256_loadu_ps(c.map(|v| v[0]).as_ptr()),
            _mm256_loadu_ps(c.map(|v| v[1]).as_ptr()),
        )
    } else {
        (zero, zero)
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
    // the still lanes' (`tab`: t = (p + j) / pairs) and the moving lanes' along n (`mtab`:
    // t = (p / 2 + j) / m, even pairs)
    let (mut tab, mut mtab) = (empty, empty);
    let fill = |p0: usize, m: usize, tab: &mut RunTaps| {
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
        // (even pairs) or their own velocity (odd pairs) at t = (p / 2 + j) / m: each lane
        // takes one of them, in `gather`'s order. A job: its t, its lanes, and along n the
        // table (`mtab` or not) and pair of its taps
        let mut jobs = [(0.0f32, zero, None); 2];
        let mut count = 0;
        if any(still) {
            let q = p % 8;
            if q == 0 {
                fill(p, pairs, &mut tab);
            }
            let t = tab.t[q];
            let ends = _mm256_and_ps(
                still,
                _mm256_cmp_ps::<_CMP_GE_OQ>(_mm256_set1_ps(tab.tr[q]), stop),
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
                jobs[count] = (t, still, Some((false, q)));
                count += 1;
            }
        }
        if any(movers) {
            let odd = p % 2 == 1;
            let m = if odd { pairs / 2 } else { pairs - pairs / 2 };
            if odd {
                let t = ((p / 2) as f32 + j) / m.max(1) as f32;
                jobs[count] = (t, movers, None);
            } else {
                let q = (p / 2) % 8;
                if q == 0 {
                    fill(p / 2, m, &mut mtab);
                }
                jobs[count] = (mtab.t[q], movers, Some((true, q)));
            }
            count += 1;
        }
        if count == 0 {
            break;
        }
        for &(t, mask, along_n) in &jobs[..count] {
            for (k, s) in [-1.0f32, 1.0].into_iter().enumerate() {
                if let Some((mover, q)) = along_n {
                    // the run's first pixel's tap, moved along the row lane by lane
                    let tab = if mover { &mtab } else { &tab };
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
                            _mm256_add_epi32(
                                _mm256_set1_epi32(row as i32),
                                _mm256_srai_epi32::<4>(bl),
                            ),
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
                } else {
                    // each lane's own tap along its own velocity
                    let tr = _mm256_mul_ps(_mm256_set1_ps(t), rc);
                    let stv = _mm256_set1_ps(s * t);
                    let px = _mm256_add_ps(xc, _mm256_mul_ps(stv, c0));
                    let py = _mm256_add_ps(yc, _mm256_mul_ps(stv, c1));
                    let inside = _mm256_and_ps(
                        _mm256_and_ps(
                            _mm256_cmp_ps::<_CMP_GE_OQ>(px, zero),
                            _mm256_cmp_ps::<_CMP_GE_OQ>(py, zero),
                        ),
                        _mm256_and_ps(
                            _mm256_cmp_ps::<_CMP_LT_OQ>(px, wl),
                            _mm256_cmp_ps::<_CMP_LT_OQ>(py, hl),
                        ),
                    );
                    let inside = _mm256_and_ps(inside, mask);
                    if !any(inside) {
                        continue;
                    }
                    let sx = _mm256_cvttps_epi32(px);
                    let sy = _mm256_cvttps_epi32(py);
                    let dx = _mm256_sub_ps(_mm256_cvtepi32_ps(sx), xf);
                    let dy = _mm256_sub_ps(_mm256_cvtepi32_ps(sy), yf);
                    let d2 = _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy));
                    let d = _mm256_min_ps(_mm256_sqrt_ps(d2), tr);
                    let ins = _mm256_castps_si256(inside);
                    let cidx = _mm256_and_si256(
                        _mm256_add_epi32(
                            _mm256_mullo_epi32(_mm256_srli_epi32::<4>(sy), cw),
                            _mm256_srli_epi32::<4>(sx),
                        ),
                        ins,
                    );
                    let cell = _mm256_i32gather_ps::<4>(reach.cell.as_ptr(), cidx);
                    let from = _mm256_add_ps(_mm256_max_ps(cell, rc), two);
                    let real = _mm256_andnot_ps(_mm256_cmp_ps::<_CMP_GE_OQ>(d, from), inside);
                    taps = _mm256_add_ps(taps, _mm256_and_ps(inside, one));
                    if any(real) {
                        let yi = _mm256_add_epi32(_mm256_mullo_epi32(sy, wi), sx);
                        let (zy, sp, col) = gathered(yi, real);
                        add(weights(zy, sp, d, real), col);
                    }
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
