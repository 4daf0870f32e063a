//! The two halves of an accumulation (its even and its odd time samples, each summed apart)
//! made into the frame and the sum of squares of their difference, which its error estimate
//! reads, over the window the samples drew in, in one pass.
//!
//! Each part is a weighted mean of some samples (`mass`, the shutter weight they carry): its
//! pixels are a `base` image (the static layer, or a whole frame) with the `drawn` pixels of
//! its own window in place. Per pixel and channel, in float64, each half is
//! `(0 + m_1 v_1 + m_2 v_2 + ...) / M` (`v_i` its parts' values in order, `M` their masses
//! summed from 0 in order); the difference `d = a - b` composited over a background `pre`
//! (premultiplied) is `d_k + (-d_alpha) pre_k`; the frame is `(a M_a + b M_b) / (M_a + M_b)`
//! rounded to float32. The squares `d_k * d_k` are summed from 0 along each row (pixels in
//! order, channels in order), and the rows' sums from 0 in row order, whatever the threads.
//! When every part names its `sub` half (0 or 1 within its half: the quarters of a grid), each
//! half's two sub-halves are compared the same way (each sub-half's sum times its mass's
//! reciprocal: only these squares are kept, so a product serves for a division) and their
//! squares summed over both halves.
//! A part may carry an `end` coefficient (a stratified grid's first sample `-m`, its last `+m`,
//! `m` its share of the total mass: every other part 0): the pixel's `e = sum(end v)` (from 0
//! in order) is added to the halves' difference before it is composited, and `2 e` to each
//! sub-halves' difference. The two halves of a stratified grid are the grid shifted a quarter
//! of their strata either way (the sub-halves an eighth and three eighths), and a shifted rule
//! is off by the shift times the pixel's change from the shutter's opening to its close; the
//! frame (the unshifted midpoint rule) is not, and `e`, that change over the grid's samples,
//! takes the term out of the differences. When a part has an end coefficient the squares of
//! the difference without it (the plain halves') are summed too: with several subsamples a
//! pixel the term can cancel a difference it should not (see `HalfSums.frame`), and the plain
//! sum bounds the estimate from below.
//! These are numpy's operations in `HalfSums.frame`'s order, so the bits are those of that
//! numpy code (tests/methods/test_accumulation_frame.py compares them).
use crate::error::{Error, Result};

/// One part of a half: its samples' weighted mean over the image.
#[derive(Clone, Copy, Debug)]
pub struct HalfPart<'a> {
    /// 0 for the even half, 1 for the odd one.
    pub half: usize,
    /// The shutter weight of its samples (its weight in the half's mean).
    pub mass: f64,
    /// `(H, W, 4)` premultiplied RGBA: the pixels outside `window`.
    pub base: &'a [f32],
    /// `(x0, y0, x1, y1)` of the image the part drew in, with its `drawn` pixels.
    pub window: Option<([usize; 4], &'a [f32])>,
    /// Its half within its half (0 or 1), when the grid is drawn in quarters.
    pub sub: Option<usize>,
    /// Its coefficient in the differences' end term (see the module docs; 0 for most parts).
    pub end: f64,
}

/// The frame's window and the squares of the halves' composited difference there (see the
/// module docs).
#[derive(Clone, Debug)]
pub struct Halves {
    /// The sum over the window's pixels and channels of `(a - b)^2`, composited over the
    /// background.
    pub square_sum: f64,
    /// The same of each half's two sub-halves, summed over both halves, when every part has a
    /// `sub`.
    pub sub_square_sum: Option<f64>,
    /// The same as `square_sum` without the end term, when a part has an end coefficient.
    pub plain_square_sum: Option<f64>,
    /// `(h, w, 4)` float32: the frame, both halves by their masses.
    pub frame: Vec<f32>,
    /// The masses of the even and the odd half.
    pub masses: [f64; 2],
}

/// The halves of `parts` over `window` (`x0, y0, x1, y1`) of a `width` x `height` image,
/// their difference composited over `pre` (premultiplied RGBA) and the frame.
pub fn halves(
    parts: &[HalfPart<'_>],
    (width, height): (usize, usize),
    window: [usize; 4],
    pre: [f64; 4],
) -> Result<Halves> {
    let [x0, y0, x1, y1] = window;
    if !(x0 < x1 && y0 < y1 && x1 <= width && y1 <= height) {
        return Err(Error::value(
            "window",
            "must be a non-empty rectangle of the image",
        ));
    }
    for p in parts {
        check_part(p, (width, height))?;
    }
    let (masses, sub_masses, subs) = part_masses(parts);
    let (w, h) = (x1 - x0, y1 - y0);
    let mut frame = vec![0.0f32; w * h * 4];
    let mut sums = vec![[0.0f64; 3]; h];
    let ends = parts.iter().any(|p| p.end != 0.0);
    let pass = Pass {
        parts,
        masses,
        inv_sub_masses: subs.then(|| sub_masses.map(|m| m.map(|x| 1.0 / x))),
        pre,
        quarters: subs && in_quarter_order(parts) && !ends,
        ends,
        width,
        cols: (x0, x1),
    };
    let row = |(y, (out, sum)): (usize, (&mut [f32], &mut [f64; 3]))| pass.row(y0 + y, out, sum);
    if w * h < SERIAL_PIXELS {
        frame
            .chunks_mut(w * 4)
            .zip(sums.iter_mut())
            .enumerate()
            .for_each(row);
    } else {
        use rayon::prelude::*;
        frame
            .par_chunks_mut(w * 4)
            .zip(sums.par_iter_mut())
            .enumerate()
            .for_each(row);
    }
    let total = |j: usize| sums.iter().fold(0.0f64, |t, s| t + s[j]);
    Ok(Halves {
        square_sum: total(0),
        sub_square_sum: subs.then(|| total(1)),
        plain_square_sum: ends.then(|| total(2)),
        frame,
        masses,
    })
}

/// The halves' masses, the four sub-halves' and whether the sub-halves are compared: when
/// every part names one and each of the four has a mass.
fn part_masses(parts: &[HalfPart<'_>]) -> ([f64; 2], [[f64; 2]; 2], bool) {
    let mut masses = [0.0f64; 2];
    let mut sub_masses = [[0.0f64; 2]; 2];
    for p in parts {
        masses[p.half] += p.mass;
        if let Some(sub) = p.sub {
            sub_masses[p.half][sub] += p.mass;
        }
    }
    let subs = !parts.is_empty()
        && parts.iter().all(|p| p.sub.is_some())
        && sub_masses.iter().flatten().all(|m| *m > 0.0);
    (masses, sub_masses, subs)
}

/// A grid drawn in quarters, in order: part `j` of half `j % 2`, sub-half `j / 2`. Each half's
/// sum `(0 + m v) + m' v'` is then its two sub-halves' sums added (the same bits), each value
/// multiplied and added once.
fn in_quarter_order(parts: &[HalfPart<'_>]) -> bool {
    parts.len() == 4
        && parts
            .iter()
            .enumerate()
            .all(|(j, p)| p.half == j % 2 && p.sub == Some(j / 2))
}

/// Windows of fewer pixels are made on the calling thread (no pool: a hand-off to it costs
/// more than such a window); larger ones row by row in parallel (the same bits: each pixel
/// is its own).
pub const SERIAL_PIXELS: usize = 1 << 16;

/// One pixel of a [`halves`] pass.
struct Pixel {
    /// Its frame value.
    frame: [f32; 4],
    /// The halves' difference plus the end term, composited over the background.
    difference: [f64; 4],
    /// Each half's two sub-halves' composited difference (plus twice the end term), with subs.
    subs: Option<[[f64; 4]; 2]>,
    /// The halves' composited difference without the end term, when a part has one.
    plain: Option<[f64; 4]>,
}

/// What every pixel of one [`halves`] pass reads.
struct Pass<'p, 'a> {
    parts: &'p [HalfPart<'a>],
    masses: [f64; 2],
    /// Each half's two sub-halves' reciprocal masses, when they are compared.
    inv_sub_masses: Option<[[f64; 2]; 2]>,
    pre: [f64; 4],
    /// Four parts, part `j` of half `j % 2` and sub-half `j / 2` (`in_quarter_order`), none
    /// with an end coefficient.
    quarters: bool,
    /// Whether a part has an end coefficient (the plain difference's squares are summed too).
    ends: bool,
    /// The image's width and the window's columns `x0..x1`.
    width: usize,
    cols: (usize, usize),
}

impl Pass<'_, '_> {
    /// Row `y` of the window: its frame values into `out` and the squares into `sum`
    /// (the halves', the sub-halves', the plain halves').
    fn row(&self, y: usize, out: &mut [f32], sum: &mut [f64; 3]) {
        let (parts, width, (x0, x1)) = (self.parts, self.width, self.cols);
        // the row cut where a part's window starts or ends: between two cuts every part
        // reads one slice (its drawn row or its base's), no per-pixel window test
        let mut cuts = vec![x0, x1];
        for p in parts {
            if let Some(([wx0, wy0, wx1, wy1], _)) = p.window {
                if (wy0..wy1).contains(&y) {
                    cuts.extend([wx0, wx1].into_iter().filter(|c| (x0 + 1..x1).contains(c)));
                }
            }
        }
        cuts.sort_unstable();
        cuts.dedup();
        let mut srcs: Vec<&[f32]> = Vec::with_capacity(parts.len());
        // the running sums in locals (kept in registers; through `sum` they went to memory at
        // every add), added in the same order
        let [mut squares, mut sub_squares, mut plain_squares] = *sum;
        for seg in cuts.windows(2) {
            let (s0, s1) = (seg[0], seg[1]);
            srcs.clear();
            srcs.extend(parts.iter().map(|p| row_slice(p, width, y, s0, s1)));
            for x in s0..s1 {
                let k = (x - s0) * 4;
                let px = if self.quarters {
                    self.pixel_quarters([0, 1, 2, 3].map(|j| &srcs[j][k..k + 4]))
                } else {
                    self.pixel(|j| &srcs[j][k..k + 4])
                };
                let i = (x - x0) * 4;
                out[i..i + 4].copy_from_slice(&px.frame);
                for v in px.difference {
                    squares += v * v;
                }
                if let Some(d) = px.plain {
                    for v in d {
                        plain_squares += v * v;
                    }
                }
                if let Some(e) = px.subs {
                    for half in e {
                        for v in half {
                            sub_squares += v * v;
                        }
                    }
                }
            }
        }
        *sum = [squares, sub_squares, plain_squares];
    }

    /// A pixel's [`Pixel`], part `j`'s value `value(j)`.
    #[inline]
    fn pixel<'v>(&self, value: impl Fn(usize) -> &'v [f32]) -> Pixel {
        let mut sums = [[0.0f64; 4]; 2];
        let mut subs = [[[0.0f64; 4]; 2]; 2];
        let mut end = [0.0f64; 4];
        for (j, p) in self.parts.iter().enumerate() {
            let v = value(j);
            for (s, v) in sums[p.half].iter_mut().zip(v) {
                *s += f64::from(*v) * p.mass;
            }
            if let (Some(sub), Some(_)) = (p.sub, self.inv_sub_masses) {
                for (s, v) in subs[p.half][sub].iter_mut().zip(v) {
                    *s += f64::from(*v) * p.mass;
                }
            }
            if p.end != 0.0 {
                for (e, v) in end.iter_mut().zip(v) {
                    *e += f64::from(*v) * p.end;
                }
            }
        }
        let (frame, d) = self.frame_and_difference(sums[0], sums[1]);
        let twice = end.map(|e| 2.0 * e);
        let subs = self.inv_sub_masses.map(|im| {
            [0, 1].map(|half| self.composited(subs[half][0], subs[half][1], im[half], twice))
        });
        Pixel {
            frame,
            difference: self.over_background(std::array::from_fn(|k| d[k] + end[k])),
            subs,
            plain: self.ends.then(|| self.over_background(d)),
        }
    }

    /// The frame value of a pixel whose halves' weighted sums are `a0` and `b0`, and their
    /// means' difference `a - b` (not composited): each mean divided once, serving both.
    #[inline]
    fn frame_and_difference(&self, a0: [f64; 4], b0: [f64; 4]) -> ([f32; 4], [f64; 4]) {
        let m = self.masses;
        let a = a0.map(|s| s / m[0]);
        let b = b0.map(|s| s / m[1]);
        let total = m[0] + m[1];
        let frame = std::array::from_fn(|k| ((a[k] * m[0] + b[k] * m[1]) / total) as f32);
        (frame, std::array::from_fn(|k| a[k] - b[k]))
    }

    /// [`Self::pixel`] of four parts, part `j` of half `j % 2` and sub-half `j / 2`: each
    /// sub-half `0 + m v`, each half its two sub-halves added (the same bits).
    #[inline]
    fn pixel_quarters(&self, v: [&[f32]; 4]) -> Pixel {
        let p = self.parts;
        let q: [[f64; 4]; 4] =
            std::array::from_fn(|j| std::array::from_fn(|k| 0.0 + f64::from(v[j][k]) * p[j].mass));
        // q[0], q[2]: half 0's sub-halves; q[1], q[3]: half 1's
        let a0: [f64; 4] = std::array::from_fn(|k| q[0][k] + q[2][k]);
        let b0: [f64; 4] = std::array::from_fn(|k| q[1][k] + q[3][k]);
        let (frame, d) = self.frame_and_difference(a0, b0);
        let im = self
            .inv_sub_masses
            .expect("quarters compare their sub-halves");
        let subs = [
            self.composited(q[0], q[2], im[0], [0.0; 4]),
            self.composited(q[1], q[3], im[1], [0.0; 4]),
        ];
        Pixel {
            frame,
            difference: self.over_background(d),
            subs: Some(subs),
            plain: None,
        }
    }

    /// `a (1 / ma) - b (1 / mb) + end` composited over the background, given the reciprocals
    /// (the sub-halves' difference: only its squares are kept, so a product serves for a
    /// division).
    #[inline]
    fn composited(&self, a: [f64; 4], b: [f64; 4], [ia, ib]: [f64; 2], end: [f64; 4]) -> [f64; 4] {
        self.over_background(std::array::from_fn(|k| a[k] * ia - b[k] * ib + end[k]))
    }

    /// A difference `d` (premultiplied) composited over the background: `d + (-d_alpha) pre`.
    #[inline]
    fn over_background(&self, d: [f64; 4]) -> [f64; 4] {
        let scale = -d[3];
        std::array::from_fn(|k| d[k] + scale * self.pre[k])
    }
}

/// Pixels `x0..x1` of row `y` of a part, all inside its window or all outside it: its drawn
/// values inside, its base's outside.
#[inline]
fn row_slice<'a>(p: &HalfPart<'a>, width: usize, y: usize, x0: usize, x1: usize) -> &'a [f32] {
    if let Some(([wx0, wy0, wx1, wy1], drawn)) = p.window {
        if (wx0..wx1).contains(&x0) && (wy0..wy1).contains(&y) {
            let i = ((y - wy0) * (wx1 - wx0) + (x0 - wx0)) * 4;
            return &drawn[i..i + (x1 - x0) * 4];
        }
    }
    let i = (y * width + x0) * 4;
    &p.base[i..i + (x1 - x0) * 4]
}

/// A part's half is 0 or 1, its base the image's size, its window inside the image and its
/// drawn pixels the window's size.
fn check_part(p: &HalfPart<'_>, (width, height): (usize, usize)) -> Result<()> {
    if p.half > 1 {
        return Err(Error::value("half", "must be 0 or 1"));
    }
    if p.sub.is_some_and(|s| s > 1) {
        return Err(Error::value("sub", "must be 0 or 1"));
    }
    if !p.end.is_finite() {
        return Err(Error::value("end", "must be finite"));
    }
    if p.base.len() != width * height * 4 {
        return Err(Error::shape("base", "must be (H, W, 4) of the image"));
    }
    if let Some(([x0, y0, x1, y1], drawn)) = p.window {
        if !(x0 <= x1 && y0 <= y1 && x1 <= width && y1 <= height) {
            return Err(Error::value("window", "must lie inside the image"));
        }
        if drawn.len() != (x1 - x0) * (y1 - y0) * 4 {
            return Err(Error::shape("drawn", "must be (y1 - y0, x1 - x0, 4)"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_parts_a_half_give_their_weighted_means() {
        // a 3 x 2 image; half 0: one part of mass 0.5 drawing pixel (1, 0); half 1: two parts
        // of masses 0.25 and 0.25, the second drawing pixel (2, 1)
        let base: Vec<f32> = (0..24).map(|i| i as f32 / 24.0).collect();
        let d0 = [1.0f32, 0.5, 0.25, 1.0];
        let d1 = [0.0f32, 0.0, 1.0, 0.5];
        let parts = [
            HalfPart {
                half: 0,
                mass: 0.5,
                base: &base,
                window: Some(([1, 0, 2, 1], &d0)),
                sub: None,
                end: 0.0,
            },
            HalfPart {
                half: 1,
                mass: 0.25,
                base: &base,
                window: None,
                sub: None,
                end: 0.0,
            },
            HalfPart {
                half: 1,
                mass: 0.25,
                base: &base,
                window: Some(([2, 1, 3, 2], &d1)),
                sub: None,
                end: 0.0,
            },
        ];
        let pre = [0.1, 0.2, 0.3, 1.0];
        let out = halves(&parts, (3, 2), [0, 0, 3, 2], pre).unwrap();
        assert_eq!(out.masses, [0.5, 0.5]);
        assert!(out.sub_square_sum.is_none());
        let mut squares = 0.0;
        for y in 0..2 {
            for x in 0..3 {
                let i = (y * 3 + x) * 4;
                let base = |k: usize| f64::from(base[i + k]);
                let a: [f64; 4] = std::array::from_fn(|k| {
                    if (x, y) == (1, 0) {
                        f64::from(d0[k])
                    } else {
                        base(k)
                    }
                });
                let b: [f64; 4] = std::array::from_fn(|k| {
                    let second = if (x, y) == (2, 1) {
                        f64::from(d1[k])
                    } else {
                        base(k)
                    };
                    (base(k) * 0.25 + second * 0.25) / 0.5
                });
                for k in 0..4 {
                    let d = a[k] - b[k] - (a[3] - b[3]) * pre[k];
                    squares += d * d;
                    let f = ((a[k] + b[k]) / 2.0) as f32;
                    assert!((out.frame[i + k] - f).abs() <= 1e-6, "({x}, {y}) {k}");
                }
            }
        }
        assert!((out.square_sum - squares).abs() < 1e-12 && squares > 0.1);
    }

    /// Four pixel values (premultiplied, opaque) of 1 x 1 images.
    const FOUR: [[f32; 4]; 4] = [
        [0.1, 0.2, 0.3, 1.0],
        [0.4, 0.1, 0.0, 1.0],
        [0.3, 0.3, 0.1, 1.0],
        [0.0, 0.5, 0.2, 1.0],
    ];

    #[test]
    fn sub_halves_compare_the_quarters_within_each_half() {
        // a 1 x 1 image, four parts of mass 0.25 with values q0..q3 (premultiplied, opaque);
        // half 0 is q0, q2 and half 1 q1, q3: the sub-halves' squares are
        // (q0 - q2)^2 + (q1 - q3)^2 over the channels, and none without every part's sub
        let q = FOUR;
        let parts: Vec<HalfPart<'_>> = q
            .iter()
            .enumerate()
            .map(|(j, v)| HalfPart {
                half: j % 2,
                mass: 0.25,
                base: v,
                window: None,
                sub: Some(j / 2),
                end: 0.0,
            })
            .collect();
        let out = halves(&parts, (1, 1), [0, 0, 1, 1], [0.0; 4]).unwrap();
        let d = |a: usize, b: usize, k: usize| f64::from(q[a][k]) - f64::from(q[b][k]);
        let want: f64 = (0..4)
            .map(|k| d(0, 2, k).powi(2) + d(1, 3, k).powi(2))
            .sum();
        assert!((out.sub_square_sum.unwrap() - want).abs() < 1e-12);
        let halves_want: f64 = (0..4)
            .map(|k| {
                let a = (f64::from(q[0][k]) + f64::from(q[2][k])) / 2.0;
                let b = (f64::from(q[1][k]) + f64::from(q[3][k])) / 2.0;
                (a - b).powi(2)
            })
            .sum();
        assert!((out.square_sum - halves_want).abs() < 1e-12);
        // the same parts in another order (half 0's first: no longer the quarters' order) go
        // through the general per-part sums: the same bits, each half's parts in the same order
        let reordered = [parts[0], parts[2], parts[1], parts[3]];
        let general = halves(&reordered, (1, 1), [0, 0, 1, 1], [0.0; 4]).unwrap();
        assert_eq!(general.square_sum.to_bits(), out.square_sum.to_bits());
        assert_eq!(
            general.sub_square_sum.unwrap().to_bits(),
            out.sub_square_sum.unwrap().to_bits()
        );
        assert_eq!(general.frame, out.frame);
        let mut partial = parts.clone();
        partial[3].sub = None;
        let out = halves(&partial, (1, 1), [0, 0, 1, 1], [0.0; 4]).unwrap();
        assert!(out.sub_square_sum.is_none());
    }

    #[test]
    fn bad_parts_name_what_is_wrong() {
        let base = vec![0.0f32; 24];
        let drawn = vec![0.0f32; 4];
        let part = |half, window| HalfPart {
            half,
            mass: 1.0,
            base: &base,
            window,
            sub: None,
            end: 0.0,
        };
        let err = |parts: &[HalfPart<'_>], win| {
            halves(parts, (3, 2), win, [0.0; 4])
                .unwrap_err()
                .to_string()
        };
        assert!(err(&[part(2, None)], [0, 0, 3, 2]).contains("half"));
        assert!(err(&[part(0, Some(([0, 0, 2, 1], &drawn)))], [0, 0, 3, 2]).contains("drawn"));
        assert!(err(&[part(0, Some(([0, 0, 4, 1], &drawn)))], [0, 0, 3, 2]).contains("window"));
        assert!(err(&[part(0, None)], [0, 0, 3, 3]).contains("window"));
        let short = vec![0.0f32; 20];
        let p = HalfPart {
            half: 0,
            mass: 1.0,
            base: &short,
            window: None,
            sub: None,
            end: 0.0,
        };
        assert!(err(&[p], [0, 0, 3, 2]).contains("base"));
        let p = HalfPart {
            end: f64::NAN,
            ..part(0, None)
        };
        assert!(err(&[p], [0, 0, 3, 2]).contains("end"));
    }

    #[test]
    fn end_coefficients_add_the_end_term_to_the_differences() {
        // a 1 x 1 image, four samples of mass 0.25 with values v0..v3 (premultiplied, opaque),
        // each its own quarter: the first with end -0.25, the last +0.25; e = (v3 - v0) / 4 is
        // added to the halves' difference and 2 e to each sub-halves' one; the frame is the
        // samples' mean, the bits of the parts without ends (which take the quarters' path)
        let v = FOUR;
        let part = |j: usize, end: f64| HalfPart {
            half: j % 2,
            mass: 0.25,
            base: &v[j],
            window: None,
            sub: Some(j / 2),
            end,
        };
        let ends = [part(0, -0.25), part(1, 0.0), part(2, 0.0), part(3, 0.25)];
        let plain = ends.map(|p| HalfPart { end: 0.0, ..p });
        let out = halves(&ends, (1, 1), [0, 0, 1, 1], [0.0; 4]).unwrap();
        let flat = halves(&plain, (1, 1), [0, 0, 1, 1], [0.0; 4]).unwrap();
        let x = |j: usize, k: usize| f64::from(v[j][k]);
        let e = |k: usize| (x(3, k) - x(0, k)) / 4.0;
        let halves_want: f64 = (0..4)
            .map(|k| ((x(0, k) + x(2, k)) / 2.0 - (x(1, k) + x(3, k)) / 2.0 + e(k)).powi(2))
            .sum();
        let subs_want: f64 = (0..4)
            .map(|k| {
                (x(0, k) - x(2, k) + 2.0 * e(k)).powi(2) + (x(1, k) - x(3, k) + 2.0 * e(k)).powi(2)
            })
            .sum();
        assert!((out.square_sum - halves_want).abs() < 1e-12);
        assert!((out.sub_square_sum.unwrap() - subs_want).abs() < 1e-12);
        assert!((out.square_sum - flat.square_sum).abs() > 1e-3);
        assert_eq!(out.frame, flat.frame);
        // the plain difference's squares ride along with the ends (the bits of the parts
        // without them), and only with them
        assert_eq!(
            out.plain_square_sum.map(f64::to_bits),
            Some(flat.square_sum.to_bits())
        );
        assert!(flat.plain_square_sum.is_none());
    }
}
