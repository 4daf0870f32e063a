//! The camera blur as a line integral: each pixel's mean of the bilinear image along its streak,
//! read from running (prefix) sums that the pixels of a band share, instead of N taps.
//!
//! A pixel whose velocity `v` is mostly horizontal (`|vx| >= |vy|`, the *major* axis x) is
//! blurred along a curve through it, over the major coordinates `u` in `[x - a, x + a]`,
//! `a = |vx| / 2`: the mean of the image over `u`, which is the mean over the shutter of a
//! streak crossed at constant speed along `u` (as the taps `x + vx t`, `t` in `[-1/2, 1/2]`).
//! Mostly vertical velocities run the same code with the axes swapped.
//!
//! The image is cut into strips [`strip_width`] columns wide. In a strip, curve `k` (any integer, also
//! outside the image) is `Y_k(u) = k + s (u - c) + q (u - c)^2 / 2`, where `c` is the strip's
//! middle column and `s`, `q` are the slope `vy / vx` of the velocity field at `(c, k)` and its
//! change along the field between the strip's quarter columns (row `k` clamped into the image):
//! the flow line of the field through `(c, k)` to second order. Curves are cut into bands of
//! [`BAND`] consecutive `k`; for each band the curves `k - 1 ..= k + BAND + 1` are sampled
//! once per integer `u` over the strip widened by the band's longest half-streak (the image
//! linearly interpolated across the major axis between the two rows about `Y_k(u)`, positions
//! clamped to the image as the taps clamp them) and summed in f64 (trapezoids). A pixel
//! `(x, y)` lies between curves `k` and `k + 1` at `y = (1 - f) Y_k(x) + f Y_{k+1}(x)`; its
//! value is `(1 - f)` times curve `k`'s mean over `[x - a, x + a]` plus `f` times curve
//! `k + 1`'s, each mean two lookups of the running sum (linearly interpolated between samples).
//!
//! So a pixel costs O(1) whatever its streak's length. The curves follow the field: along a
//! camera rotation's streaks (curved on screen) they bend as the streaks do, where the taps
//! run along a chord. A pixel is blurred this way only when its curve fits it: the
//! interpolated curve's slope at the pixel is within [`LINE_TOLERANCE`] pixels of the pixel's
//! own over the half-streak, and the two curves are 0.25 to 2 pixels apart at the pixel and at
//! both ends of the streak. A band takes its curves only where that is cheaper than the taps:
//! when its fitting pixels times [`SAMPLES_PER_PIXEL`] exceed the samples of its running sums
//! (few fitting pixels, or short strips under long streaks, do not pay for the sums).
//!
//! Every other pixel (a moving object's, a streak shorter than [`MIN_STREAK`] pixels or longer
//! than the image's sides, a depth edge where the field jumps, a fan of directions too wide for
//! a band, a band not worth its curves) takes the N-tap blur with its own velocity
//! ([`LineField::taps_row`]: the vector row taps of
//! [`Taps::blur_row_skipping`](super::camera::Taps::blur_row_skipping) over the row's
//! pixels not blurred as a line): the bits of the taps there. The curves and the classes read
//! the velocities of [`LineField::row`], which may differ from the taps' by rounding.
//!
//! Each pixel belongs to one band of one strip (the bands of a strip split each of its columns
//! into runs of rows, in order), and whether it is a line and its value depend on that band
//! alone: the result does not depend on the number of threads.
use std::mem::MaybeUninit;

use rayon::prelude::*;

/// Columns (rows, for vertical streaks) of a strip in images up to 1920 pixels along the
/// major axis.
pub const STRIP: usize = 256;

/// Columns (rows) of a strip along a major axis `len` pixels long: [`STRIP`], wider in the same
/// proportion past 1920 pixels (a camera's field changes over a fixed fraction of the image, and
/// the streaks, the sums' overhang, grow with it: 512 at 3840).
pub fn strip_width(len: usize) -> usize {
    STRIP.max(len * STRIP / 1920)
}
/// Curves of a band.
pub const BAND: usize = 32;
/// Largest distance (pixels) between a pixel's streak and the curve it is read along, at the
/// ends of the streak (the slopes' difference times the half-streak).
pub const LINE_TOLERANCE: f64 = 2.0;
/// Shortest streak (pixels along the major axis) blurred as a line integral: shorter ones take
/// the taps, which are then at most a pixel apart.
pub const MIN_STREAK: f32 = 16.0;
/// Half-width (pixels) of the central differences that give a curve's bend.
const DIFF: usize = 8;
/// Largest difference between the slope's steps on either side of a strip's middle pixel
/// (over [`DIFF`] pixels) for its curve to bend with them: a larger one is a depth edge.
const CURVE_JUMP: f64 = 1e-3;

/// What the line blur reads of a pixel's motion.
pub(crate) trait LineField: Sync {
    /// Writes into `line` (`(w,)`) whether each pixel of row `y` may be blurred along a curve
    /// (1) or keeps the taps (0: a moving object's pixel), and into `v` the velocity `(vx, vy)`
    /// (pixels over the shutter) of each that may (any value for the others).
    fn row(&self, y: usize, v: &mut [[f32; 2]], line: &mut [u8]);
    /// Writes the pixels of output row `y` (`(w, 4)`) that `skip` (`(w,)`) does not mark, each
    /// blurred by the taps along its own velocity (which may differ from [`LineField::row`]'s
    /// by rounding); returns whether such a velocity was NaN.
    fn taps_row(&self, rgba: &[f32], y: usize, row: &mut [MaybeUninit<f32>], skip: &[bool])
        -> bool;
}

/// The velocities of every pixel ([`LineField::row`]) and their classes (0: taps, 1: a line
/// along x may do, 2: along y).
struct Field {
    v: Vec<[f32; 2]>,
    class: Vec<u8>,
    w: usize,
    /// [`line_blur_masked`]'s `saved`.
    saved: f64,
}

impl Field {
    /// Asks the cache for the velocities and classes of pixels `(x, rows)` (a column of a band
    /// whose major axis is x: one row's cache line for each, the rows too many at once for
    /// the hardware's prefetcher to follow).
    #[inline(always)]
    fn prefetch_column(&self, x: usize, rows: std::ops::Range<usize>) {
        #[cfg(target_arch = "x86_64")]
        for y in rows {
            let i = y * self.w + x;
            use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
            let (v, c) = (self.v[i..].as_ptr() as *const i8, self.class[i..].as_ptr());
            // SAFETY: hints, both point into the buffers
            unsafe {
                _mm_prefetch::<_MM_HINT_T0>(v);
                _mm_prefetch::<_MM_HINT_T0>(c as *const i8);
            }
        }
    }

    /// Pixel `(x, y)`'s velocity if its class is a line along x (`x_major`) or y.
    #[inline(always)]
    fn line(&self, x: usize, y: usize, x_major: bool) -> Option<[f32; 2]> {
        let i = y * self.w + x;
        (self.class[i] == if x_major { 1 } else { 2 }).then(|| self.v[i])
    }
}

/// What [`line_blur`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct LineStats {
    /// Pixels blurred as a line integral (the others took the taps).
    pub line_pixels: usize,
    /// Whether a tap velocity was NaN.
    pub nan: bool,
}

/// How a pixel is blurred (the rule [`classify`] applies, kept as the tests' oracle).
#[cfg(test)]
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Class {
    Taps,
    /// a line integral along x (true) or y (false) may do
    Line(bool),
}

#[cfg(test)]
fn class([vx, vy]: [f32; 2], (w, h): (usize, usize)) -> Class {
    if !(vx.is_finite() && vy.is_finite()) {
        return Class::Taps;
    }
    let (ax, ay) = (vx.abs(), vy.abs());
    let major = ax.max(ay);
    // a streak longer than twice the image's sides only adds clamped texels: the taps
    if major < MIN_STREAK || major > 2.0 * (w + h) as f32 {
        return Class::Taps;
    }
    Class::Line(ax >= ay)
}

/// Turns a row's `line` flags ([`LineField::row`]) into classes (0: taps, 1: a line along x
/// may do, 2: along y) from its velocities `v`; returns whether a velocity is NaN and whether a
/// class is 2. A pixel flagged 1 is a line when both components are finite and the longer's
/// length is in `[MIN_STREAK, 2 (w + h)]` (a streak longer than twice the image's sides only
/// adds clamped texels: the taps), along x when `|vx| >= |vy|`. (Without branches, so that
/// the loop runs in vectors.)
fn classify(c: &mut [u8], v: &[[f32; 2]], (w, h): (usize, usize)) -> (bool, bool) {
    let (mut nan, mut vertical) = (false, false);
    let longest = 2.0 * (w + h) as f32;
    for (c, &[vx, vy]) in c.iter_mut().zip(v) {
        let flagged = *c != 0;
        nan |= flagged & (vx.is_nan() | vy.is_nan());
        let (ax, ay) = (vx.abs(), vy.abs());
        let along_x = ax >= ay;
        let major = if along_x { ax } else { ay };
        // (a NaN or an infinity fails the length's bounds or the finite test)
        let line = flagged
            & (vx.is_finite() & vy.is_finite())
            & (major >= MIN_STREAK)
            & (major <= longest);
        vertical |= line & !along_x;
        *c = u8::from(line) * (2 - u8::from(along_x));
    }
    (nan, vertical)
}

/// The image's axes seen from one major axis: `(m, n)` are the major and minor coordinates.
#[derive(Clone, Copy)]
struct Axes {
    x_major: bool,
    w: usize,
    h: usize,
}

impl Axes {
    fn major_len(&self) -> usize {
        if self.x_major {
            self.w
        } else {
            self.h
        }
    }
    fn minor_len(&self) -> usize {
        if self.x_major {
            self.h
        } else {
            self.w
        }
    }
    #[inline(always)]
    fn xy(&self, m: usize, n: usize) -> (usize, usize) {
        if self.x_major {
            (m, n)
        } else {
            (n, m)
        }
    }
    /// `(major, minor)` components of `v`.
    #[inline(always)]
    fn split(&self, [vx, vy]: [f32; 2]) -> (f32, f32) {
        if self.x_major {
            (vx, vy)
        } else {
            (vy, vx)
        }
    }
}

/// The output image, written pixel by pixel from several threads (each pixel once), and the
/// mask of the pixels blurred as a line integral.
#[derive(Clone, Copy)]
struct Out(*mut MaybeUninit<f32>, *mut bool);
// SAFETY: the threads write disjoint pixels (module docs: each pixel belongs to one band).
unsafe impl Send for Out {}
unsafe impl Sync for Out {}

impl Out {
    /// # Safety
    /// `i` is a pixel of the image and no other thread writes it.
    #[inline(always)]
    unsafe fn put(self, i: usize, v: [f32; 4]) {
        for (k, c) in v.into_iter().enumerate() {
            (*self.0.add(i * 4 + k)).write(c);
        }
        *self.1.add(i) = true;
    }
}

/// The `(h, w, 4)` image `rgba` blurred along each pixel's velocity (module docs): a line
/// integral where it fits, the field's taps elsewhere. `rgba` is finite.
pub(crate) fn line_blur(
    rgba: &[f32],
    (w, h): (usize, usize),
    field: &impl LineField,
) -> (Vec<f32>, LineStats) {
    line_blur_masked(rgba, (w, h), field, SAMPLES_PER_PIXEL, None)
}

/// [`line_blur`] with `saved` samples of the curves a pixel's taps cost beyond its line
/// integral ([`SAMPLES_PER_PIXEL`]; infinite: every pixel the curves fit is a line), copying
/// into `mask` (`(h, w)`, when given) the mask of the pixels blurred as a line integral.
fn line_blur_masked(
    rgba: &[f32],
    (w, h): (usize, usize),
    field: &impl LineField,
    saved: f64,
    mask: Option<&mut [bool]>,
) -> (Vec<f32>, LineStats) {
    let mut stats = LineStats::default();
    // every pixel's velocity and class, once
    let mut classes = vec![0u8; w * h];
    let mut v = vec![[0.0f32; 2]; w * h];
    let flags = v
        .par_chunks_mut(w)
        .zip(classes.par_chunks_mut(w))
        .enumerate()
        .map(|(y, (v, c))| {
            field.row(y, v, c);
            classify(c, v, (w, h))
        })
        .reduce(|| (false, false), |a, b| (a.0 | b.0, a.1 | b.1));
    let (nan, vertical) = flags;
    stats.nan = nan;
    let field_v = Field {
        v,
        class: classes,
        w,
        saved,
    };
    let mut lines = vec![false; w * h];
    let out = super::filled(w * h * 4, |out| {
        let put = Out(out.as_mut_ptr(), lines.as_mut_ptr());
        for x_major in [true, false] {
            if !x_major && !vertical {
                break;
            }
            let axes = Axes { x_major, w, h };
            let strips = axes.major_len().div_ceil(strip_width(axes.major_len()));
            stats.line_pixels += (0..strips)
                .into_par_iter()
                .map(|j| {
                    #[cfg(target_arch = "x86_64")]
                    if super::simd() {
                        // SAFETY: AVX2 was detected
                        return unsafe { strip_avx(rgba, axes, j, &field_v, put) };
                    }
                    strip(rgba, axes, j, &field_v, put)
                })
                .sum::<usize>();
        }
        // every other pixel: the taps, row by row (the vector taps along runs of such pixels)
        stats.nan |= out
            .par_chunks_mut(w * 4)
            .zip(lines.par_chunks(w))
            .enumerate()
            .map(|(y, (row, skip))| field.taps_row(rgba, y, row, skip))
            .reduce(|| false, |a, b| a | b);
    });
    if let Some(m) = mask {
        m.copy_from_slice(&lines);
    }
    (out, stats)
}

/// The curves of a strip: `(s, q)` of each minor row (module docs), about major coordinate `c`.
struct Curves {
    c: f64,
    sq: Vec<(f64, f64)>,
}

impl Curves {
    /// The curves of the strip `m0 .. m1` (major coordinates) of `axes`: the slope at the
    /// middle column `c` and its derivatives across and along the major axis by central
    /// differences [`DIFF`] pixels wide (a row whose five pixels are not all lines along this
    /// axis, or whose differences on either side disagree by more than [`CURVE_JUMP`]: a depth
    /// edge, takes the nearest such row's curve).
    fn new(axes: Axes, (m0, m1): (usize, usize), field: &Field) -> Self {
        let n = axes.minor_len();
        let cm = (m0 + m1 - 1) / 2;
        let slope = |m: usize, r: usize| {
            let (x, y) = axes.xy(m, r);
            let (a, b) = axes.split(field.line(x, y, axes.x_major)?);
            Some(b as f64 / a as f64)
        };
        // the differences' steps, shorter in a narrow strip or image
        let dm = DIFF.min(cm - m0).min(m1 - 1 - cm);
        let dn = DIFF.min((n - 1) / 2);
        let derivative = |lo: f64, mid: f64, hi: f64, d: usize| {
            let ok = d > 0 && ((hi - mid) - (mid - lo)).abs() <= CURVE_JUMP;
            ok.then(|| (hi - lo) / (2 * d) as f64)
        };
        let mut sq: Vec<Option<(f64, f64)>> = (0..n)
            .map(|r| {
                let s = slope(cm, r)?;
                let sx = if dm > 0 {
                    derivative(slope(cm - dm, r)?, s, slope(cm + dm, r)?, dm)?
                } else {
                    0.0
                };
                let (r0, r1) = (r.saturating_sub(dn), (r + dn).min(n - 1));
                let sy = if r1 - r0 == 2 * dn && dn > 0 {
                    derivative(slope(cm, r0)?, s, slope(cm, r1)?, dn)?
                } else {
                    // (an edge row: the one-sided difference)
                    let (a, b) = (slope(cm, r0)?, slope(cm, r1)?);
                    if r1 > r0 {
                        (b - a) / (r1 - r0) as f64
                    } else {
                        0.0
                    }
                };
                // the slope's change along the curve (d/du of s(u, Y(u)))
                Some((s, sx + s * sy))
            })
            .collect();
        // rows whose middle pixel does not fit take the nearest row's curve above, else below
        let mut last = None;
        for v in sq.iter_mut() {
            match v {
                Some(_) => last = *v,
                None => *v = last,
            }
        }
        let mut last = None;
        for v in sq.iter_mut().rev() {
            match v {
                Some(_) => last = *v,
                None => *v = last,
            }
        }
        Curves {
            c: cm as f64,
            sq: sq.into_iter().map(|v| v.unwrap_or((0.0, 0.0))).collect(),
        }
    }

    #[inline(always)]
    fn params(&self, k: i64) -> (f64, f64) {
        self.sq[k.clamp(0, self.sq.len() as i64 - 1) as usize]
    }

    /// `Y_k(u)`.
    #[inline(always)]
    fn y(&self, k: i64, u: f64) -> f64 {
        let (s, q) = self.params(k);
        let d = u - self.c;
        k as f64 + d * (s + 0.5 * q * d)
    }

    /// The labels of the curves at the strip's first and last of `n` minor rows, over its
    /// major coordinates `span`: the lowest and the highest.
    fn labels(&self, (m0, m1): (usize, usize), n: usize) -> (i64, i64) {
        let (mut k_lo, mut k_hi) = (i64::MAX, i64::MIN);
        let last = (n - 1) as i64;
        for m in m0..m1 {
            let u = m as f64;
            k_lo = k_lo.min((-self.y(0, u)).floor() as i64);
            k_hi = k_hi.max((last as f64 + (last as f64 - self.y(last, u))).ceil() as i64);
        }
        (k_lo, k_hi)
    }
}

/// [`strip`] compiled for AVX2 (its four channels in one vector): the same operations, no
/// fused multiply-adds, the same bits.
///
/// # Safety
/// AVX2 is present.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn strip_avx(rgba: &[f32], axes: Axes, j: usize, field: &Field, out: Out) -> usize {
    strip(rgba, axes, j, field, out)
}

/// Blurs as a line integral the pixels of strip `j` of `axes` whose class is a line along its
/// major axis and whose curves fit them, band by band where that is cheaper than their taps
/// ([`worth_it`]); returns how many.
#[inline(always)]
fn strip(rgba: &[f32], axes: Axes, j: usize, field: &Field, out: Out) -> usize {
    let width = strip_width(axes.major_len());
    let m0 = j * width;
    let span = (m0, (m0 + width).min(axes.major_len()));
    let curves = Curves::new(axes, span, field);
    let (k_lo, k_hi) = curves.labels(span, axes.minor_len());
    // (the thread's buffers of the last strip, taken and given back: no allocation a strip)
    let mut scratch = SCRATCH.with(|s| s.take());
    scratch.next.clear();
    scratch.next.resize(span.1 - span.0, 0);
    let mut count_lines = 0;
    let mut kb = k_lo - 1;
    loop {
        let last = kb + BAND as i64 > k_hi + 1;
        let band = Band { kb, last, span };
        count_lines += band.blur(rgba, axes, &curves, field, out, &mut scratch);
        if last {
            break;
        }
        kb += BAND as i64;
    }
    SCRATCH.with(|s| s.replace(scratch));
    count_lines
}

/// A band of a strip: the pixels between its curves `kb` and `kb + BAND` (to the strip's last
/// minor row if `last`) over the strip's major coordinates `span`.
#[derive(Clone, Copy)]
struct Band {
    kb: i64,
    last: bool,
    span: (usize, usize),
}

/// What [`Band::fits`] found: the band's pixels whose class is a line along the major axis,
/// the longest of their velocities' major components, and that of the pixels the curves fit.
#[derive(Default)]
struct Found {
    pixels: usize,
    reach: f32,
    fit_reach: f32,
}

impl Band {
    /// Blurs the band's pixels its curves fit if that is cheaper than their taps (its
    /// line pixels first, then those that fit; [`worth_it`]); returns how many.
    #[inline(always)]
    fn blur(
        self,
        rgba: &[f32],
        axes: Axes,
        curves: &Curves,
        field: &Field,
        out: Out,
        s: &mut Scratch,
    ) -> usize {
        let (k0, count) = (self.kb - 1, BAND + 3);
        let width = self.span.1 - self.span.0;
        s.params.clear();
        s.params
            .extend((0..count).map(|l| curves.params(k0 + l as i64)));
        s.pairs.clear();
        let steps = s
            .params
            .windows(2)
            .map(|p| (p[1].0 - p[0].0, 0.5 * (p[1].1 - p[0].1)));
        s.pairs.extend(steps);
        let found = self.fits(axes, curves, field, s);
        // (not even if every pixel fitted: the fits are not used)
        if !worth_it(
            found.pixels,
            count * sums_len(width, found.reach),
            field.saved,
        ) {
            return 0;
        }
        let len = sums_len(width, found.fit_reach);
        let u_lo = self.span.0 as i64 - (len - width) as i64 / 2;
        if !worth_it(s.fits.len(), count * len, field.saved) {
            return 0;
        }
        build(
            rgba,
            axes,
            &s.params,
            (curves.c, k0),
            (u_lo, len),
            (&mut s.lines, &mut s.acc, &mut s.prev),
        );
        for p in s.fits.iter() {
            let v = value(&s.lines, (count, u_lo, len), p);
            let (x, y) = axes.xy(p.m as usize, p.r as usize);
            // SAFETY: pixel (x, y) belongs to this band alone
            unsafe { out.put(y * axes.w + x, v) };
        }
        s.fits.len()
    }

    /// Walks the band column by column (advancing `s.next`, each column's first minor row
    /// not yet taken by a band): counts its line pixels and puts those the curves
    /// `s.params` fit into `s.fits`.
    #[inline(always)]
    fn fits(self, axes: Axes, curves: &Curves, field: &Field, s: &mut Scratch) -> Found {
        let Scratch {
            next,
            fits,
            params,
            pairs,
            col,
            ..
        } = s;
        let n = axes.minor_len();
        let k0 = self.kb - 1;
        fits.clear();
        let mut found = Found::default();
        for (m, start) in (self.span.0..self.span.1).zip(next.iter_mut()) {
            let end = if self.last {
                n
            } else {
                // (the ceiling, without a libm call)
                let e = curves.y(self.kb + BAND as i64, m as f64);
                let t = e as i64;
                let e = if (t as f64) < e { t + 1 } else { t };
                (e.max(*start as i64) as usize).min(n)
            };
            // (a cache line holds 8 velocities: the rows' next ones, two lines ahead)
            let ahead = m + 2 * PREFETCH_COLUMNS;
            if axes.x_major && (m - self.span.0) % PREFETCH_COLUMNS == 0 && ahead < self.span.1 {
                field.prefetch_column(ahead, *start..end);
            }
            // the curve at or below the column's last pixel; None until the column's
            // curves are laid out (at its first line pixel)
            let mut below: Option<usize> = None;
            for r in *start..end {
                let (x, y) = axes.xy(m, r);
                let Some(v) = field.line(x, y, axes.x_major) else {
                    continue;
                };
                let (a, b) = axes.split(v);
                found.pixels += 1;
                found.reach = found.reach.max(a.abs());
                let l = below.get_or_insert_with(|| {
                    col.at(curves, params, k0, m as f64);
                    0
                });
                if let Some((l, f)) = fit(col, pairs, curves.c, r as f64, (a, b), l) {
                    found.fit_reach = found.fit_reach.max(a.abs());
                    fits.push(Fit::new(m, r, l, f, a));
                }
            }
            *start = end;
        }
        found
    }
}

/// Columns of [`Field`]'s velocities in a cache line.
const PREFETCH_COLUMNS: usize = 8;

/// The buffers of a strip, kept by each thread from one strip to the next.
#[derive(Default)]
struct Scratch {
    next: Vec<usize>,
    fits: Vec<Fit>,
    lines: Vec<[f32; 4]>,
    params: Vec<(f64, f64)>,
    /// `(s1 - s0, (q1 - q0) / 2)` of each curve `0` and the next `1` of `params`.
    pairs: Vec<(f64, f64)>,
    acc: Vec<[f64; 4]>,
    prev: Vec<[f64; 4]>,
    col: Column,
}

thread_local! {
    static SCRATCH: std::cell::Cell<Scratch> = std::cell::Cell::default();
}

/// Entries of a band's running sums over a strip `width` pixels wide whose pixels' streaks are
/// at most `reach` pixels long: the strip widened by half a streak and two pixels each side.
#[inline(always)]
fn sums_len(width: usize, reach: f32) -> usize {
    width + 2 * ((0.5 * reach).ceil() as usize + 2)
}

/// Whether a band is blurred as a line integral: its `fits` pixels' taps would cost more than
/// sampling its curves `samples` times and reading the pixels from the sums (cost measured in
/// samples: a pixel's 16 taps save [`SAMPLES_PER_PIXEL`] samples over its line integral).
#[inline(always)]
fn worth_it(fits: usize, samples: usize, saved: f64) -> bool {
    fits as f64 * saved > samples as f64
}

/// Samples of the curves that cost what a pixel's 16 taps cost beyond its line integral's
/// fit and lookups (a sample ~4 ns, the taps ~45 ns, the rest ~15 ns at 320x240 to 640x480;
/// tuning seeds: 4 to 16 measured within the machine's noise, 6 kept).
pub const SAMPLES_PER_PIXEL: f64 = 6.0;

/// A pixel the band's curves fit: major and minor coordinates `m`, `r`, the curve `l` below it,
/// its fraction `f` of the way to curve `l + 1`, its velocity's major component `a`.
struct Fit {
    m: u32,
    r: u32,
    l: u32,
    a: f32,
    f: f64,
}

impl Fit {
    /// (sides are at most 16384 pixels: the coordinates and curves fit in 32 bits)
    #[inline(always)]
    fn new(m: usize, r: usize, l: usize, f: f64, a: f32) -> Self {
        Fit {
            m: m as u32,
            r: r as u32,
            l: l as u32,
            a,
            f,
        }
    }
}

/// Samples curves `k0 .. k0 + count` at the integer major coordinates `u_lo .. u_lo + len`
/// and sums each into `lines` (`len * count` running sums, entry `i * count + l` curve `l`'s
/// integral from `u_lo` to `u_lo + i` of its samples joined by straight lines: the curves side
/// by side, so that a pixel's four lookups and the sums' writes stay within a few pages).
#[inline(always)]
fn build(
    rgba: &[f32],
    axes: Axes,
    params: &[(f64, f64)],
    (c, k0): (f64, i64),
    (u_lo, len): (i64, usize),
    (lines, acc, prev): Sums<'_>,
) {
    let count = params.len();
    // (every entry is written below: no clearing)
    lines.resize(count * len, [0.0; 4]);
    let (mlen, nlen) = (axes.major_len() as i64, axes.minor_len());
    let nmax = (nlen - 1) as f64;
    let (sm, sn) = if axes.x_major {
        (1, axes.w)
    } else {
        (axes.w, 1)
    };
    let at = Sampler {
        rgba,
        c,
        k0,
        u_lo,
        mlen,
        nlen,
        nmax,
        sm,
        sn,
    };
    // the curves side by side, one major coordinate at a time: at each, their texels lie in
    // neighbouring minor rows of one column (a few cache lines), where curve by curve the
    // reads would run diagonally across the image
    acc.clear();
    acc.resize(count, [0.0f64; 4]);
    prev.clear();
    let first = at.column(0);
    prev.extend(
        params
            .iter()
            .enumerate()
            .map(|(l, &p)| at.sample(first, l, p)),
    );
    lines[..count].fill([0.0; 4]);
    // (a cache line holds 4 texels: one a row every 4 columns when the major axis is x, the
    // next row's when it is y)
    let (every, ahead) = if axes.x_major { (4, 8) } else { (1, 2) };
    for (i, sums) in lines.chunks_exact_mut(count).enumerate().skip(1) {
        if i % every == 0 && i + ahead < len {
            at.prefetch(i + ahead, params);
        }
        let column = at.column(i);
        let curves = params.iter().zip(acc.iter_mut().zip(prev.iter_mut()));
        for (l, ((&p, (a, b)), out)) in curves.zip(sums.iter_mut()).enumerate() {
            let g = at.sample(column, l, p);
            // (whole arrays in and out, no `map`, no call: one vector each)
            let sum = [
                a[0] + 0.5 * (b[0] + g[0]),
                a[1] + 0.5 * (b[1] + g[1]),
                a[2] + 0.5 * (b[2] + g[2]),
                a[3] + 0.5 * (b[3] + g[3]),
            ];
            *a = sum;
            *b = g;
            *out = [sum[0] as f32, sum[1] as f32, sum[2] as f32, sum[3] as f32];
        }
    }
}

/// [`build`]'s running sums and its two buffers of a sum and a sample per curve.
type Sums<'a> = (
    &'a mut Vec<[f32; 4]>,
    &'a mut Vec<[f64; 4]>,
    &'a mut Vec<[f64; 4]>,
);

/// What [`build`] samples the image with.
struct Sampler<'a> {
    rgba: &'a [f32],
    c: f64,
    k0: i64,
    u_lo: i64,
    mlen: i64,
    nlen: usize,
    nmax: f64,
    sm: usize,
    sn: usize,
}

impl Sampler<'_> {
    /// What the samples at major coordinate `u_lo + i` share: `u - c` and the offset of the
    /// image's column `u` (clamped).
    #[inline(always)]
    fn column(&self, i: usize) -> (f64, usize) {
        let u = self.u_lo + i as i64;
        (
            u as f64 - self.c,
            u.clamp(0, self.mlen - 1) as usize * self.sm,
        )
    }

    /// Asks the cache for the texels the curves `params` read at major coordinate `u_lo + i`
    /// (from the row under the first curve to the row over the last): the image's rows there
    /// are read a few texels at a time, too many at once for the hardware's prefetcher to
    /// follow (the samples were waiting on those loads).
    #[inline(always)]
    fn prefetch(&self, i: usize, params: &[(f64, f64)]) {
        #[cfg(target_arch = "x86_64")]
        {
            let (d, m) = self.column(i);
            let y = |l: usize| {
                let (s, q) = params[l];
                (self.k0 + l as i64) as f64 + d * (s + 0.5 * q * d)
            };
            let lo = (y(0) - 1.0).max(0.0).min(self.nmax) as usize;
            let hi = (y(params.len() - 1) + 2.0).max(0.0).min(self.nmax) as usize;
            // (along x, a row's cache line holds the texels of 4 minor coordinates)
            let step = if self.sn == 1 { 4 } else { 1 };
            for r in (lo..=hi + step - 1).step_by(step) {
                let t = (m + r.min(self.nlen - 1) * self.sn) * 4;
                let p = self.rgba[t..].as_ptr() as *const i8;
                // SAFETY: a hint, `p` points into the image
                unsafe { std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(p) };
            }
        }
    }

    /// Sample `i` of curve `l` (parameters `(s, q)`, `(d, m)` from [`Sampler::column`] of
    /// `i`): the image at major coordinate `u_lo + i` (clamped), linearly interpolated across
    /// between the rows about the curve.
    #[inline(always)]
    fn sample(&self, (d, m): (f64, usize), l: usize, (s, q): (f64, f64)) -> [f64; 4] {
        let y = (self.k0 + l as i64) as f64 + d * (s + 0.5 * q * d);
        // (`clamp` to [0, nmax] without its check of the bounds: not NaN, params are finite)
        let y = if y < 0.0 {
            0.0
        } else if y > self.nmax {
            self.nmax
        } else {
            y
        };
        // (y >= 0: the floor; through i64, a cheaper conversion than to usize's)
        let r0 = y as i64;
        let f = (y - r0 as f64) as f32;
        let r0 = r0 as usize;
        let r1 = (r0 + 1).min(self.nlen - 1);
        let (t0, t1) = ((m + r0 * self.sn) * 4, (m + r1 * self.sn) * 4);
        let (a, b) = (&self.rgba[t0..t0 + 4], &self.rgba[t1..t1 + 4]);
        [
            (a[0] + f * (b[0] - a[0])) as f64,
            (a[1] + f * (b[1] - a[1])) as f64,
            (a[2] + f * (b[2] - a[2])) as f64,
            (a[3] + f * (b[3] - a[3])) as f64,
        ]
    }
}

/// The band's curves `k0 .. k0 + count` at one major coordinate `u`: their minor coordinates
/// and slopes there, and their parameters `(s, q)`.
#[derive(Default)]
struct Column {
    u: f64,
    ys: Vec<f64>,
    slopes: Vec<f64>,
}

impl Column {
    #[inline(always)]
    fn at(&mut self, curves: &Curves, params: &[(f64, f64)], k0: i64, u: f64) {
        self.u = u;
        let d = u - curves.c;
        self.ys.clear();
        self.slopes.clear();
        // (two passes that run in vectors)
        let ys = params.iter().enumerate();
        self.ys
            .extend(ys.map(|(l, &(s, q))| (k0 + l as i64) as f64 + d * (s + 0.5 * q * d)));
        self.slopes.extend(params.iter().map(|&(s, q)| s + q * d));
    }
}

/// Whether the band's curves fit the pixel at minor coordinate `y` of the band's column `col`
/// with velocity components `(a, b)` (major, minor) (module docs): the curve below it and its
/// fraction of the way to the next; `l` is a curve at or below the last pixel's in the column
/// (updated).
#[inline(always)]
fn fit(
    col: &Column,
    pairs: &[(f64, f64)],
    c: f64,
    y: f64,
    (a, b): (f32, f32),
    l: &mut usize,
) -> Option<(usize, f64)> {
    let ys = &col.ys;
    let last = ys.len() - 1;
    while *l + 1 < last && ys[*l + 1] <= y {
        *l += 1;
    }
    let l = *l;
    let (y0, y1) = (ys[l], ys[l + 1]);
    let gap = y1 - y0;
    if !(y0 <= y && y < y1 && (0.25..=2.0).contains(&gap)) {
        return None;
    }
    let f = (y - y0) / gap;
    let half = 0.5 * (a as f64).abs();
    let sc = col.slopes[l] + f * (col.slopes[l + 1] - col.slopes[l]);
    // |sc - b / a| * half, without the division
    if (sc * a as f64 - b as f64).abs() * 0.5 > LINE_TOLERANCE {
        return None;
    }
    // the gap between the two curves at both ends of the streak
    let (ds, dq) = pairs[l];
    for d in [col.u - half - c, col.u + half - c] {
        let g = 1.0 + d * (ds + dq * d);
        if !(0.25..=2.0).contains(&g) {
            return None;
        }
    }
    Some((l, f))
}

/// The line integral of pixel `p` from the running sums `lines` of `count` curves (`len`
/// entries a curve from major coordinate `u_lo`).
#[inline(always)]
fn value(lines: &[[f32; 4]], (count, u_lo, len): (usize, i64, usize), p: &Fit) -> [f32; 4] {
    let (u, half, l) = (p.m as f64, 0.5 * (p.a as f64).abs(), p.l as usize);
    let (lo, hi) = (u - half - u_lo as f64, u + half - u_lo as f64);
    // (lo > 0: the floors; through i64, cheaper conversions than usize's)
    let (i0, i1) = (lo as i64, hi as i64);
    let (t0, t1) = (lo - i0 as f64, hi - i1 as f64);
    let (i0, i1) = (i0 as usize, i1 as usize);
    debug_assert!(lo > 0.0 && i1 + 1 < len);
    let (m0, m1) = (
        span(lines, (l, count), (i0, t0), (i1, t1)),
        span(lines, (l + 1, count), (i0, t0), (i1, t1)),
    );
    let inv = 1.0 / (2.0 * half);
    let mut out = [0.0f32; 4];
    for c in 0..4 {
        out[c] = ((m0[c] + p.f * (m1[c] - m0[c])) * inv) as f32;
    }
    out
}

/// The running sum of curve `l` of `count` between positions `i0 + t0` and `i1 + t1` (entries
/// and fractions), each linearly interpolated.
#[inline(always)]
fn span(
    lines: &[[f32; 4]],
    (l, count): (usize, usize),
    (i0, t0): (usize, f64),
    (i1, t1): (usize, f64),
) -> [f64; 4] {
    let at = |i: usize| lines[i * count + l];
    let (p0, p1, q0, q1) = (at(i0), at(i0 + 1), at(i1), at(i1 + 1));
    let mut out = [0.0f64; 4];
    for c in 0..4 {
        let (p0, p1, q0, q1) = (p0[c] as f64, p1[c] as f64, q0[c] as f64, q1[c] as f64);
        out[c] = (q0 + t1 * (q1 - q0)) - (p0 + t0 * (p1 - p0));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::image::camera::Taps;

    /// A velocity image `(h, w, 2)`; the pixels `moving` marks take the taps.
    struct Image<'a> {
        v: &'a [f32],
        w: usize,
        h: usize,
        moving: &'a [bool],
        taps: Taps,
    }

    impl Image<'_> {
        fn at(&self, x: usize, y: usize) -> [f32; 2] {
            let i = y * self.w + x;
            [self.v[2 * i], self.v[2 * i + 1]]
        }
    }

    impl LineField for Image<'_> {
        fn row(&self, y: usize, v: &mut [[f32; 2]], line: &mut [u8]) {
            for x in 0..self.w {
                v[x] = self.at(x, y);
                line[x] = u8::from(!self.moving[y * self.w + x]);
            }
        }
        fn taps_row(
            &self,
            rgba: &[f32],
            y: usize,
            row: &mut [MaybeUninit<f32>],
            skip: &[bool],
        ) -> bool {
            let mut nan = false;
            let simd = crate::image::simd();
            let dims = (self.w, self.h);
            self.taps
                .blur_row_skipping(rgba, dims, y, row, simd, Some(skip), |x| {
                    let v = self.at(x, y);
                    nan |= v[0].is_nan() || v[1].is_nan();
                    v
                });
            nan
        }
    }

    /// A smooth image: periods of 23 pixels or more along each axis, every channel different.
    fn smooth(w: usize, h: usize) -> Vec<f32> {
        let mut out = Vec::with_capacity(w * h * 4);
        for y in 0..h {
            for x in 0..w {
                let (x, y) = (x as f32, y as f32);
                let t = std::f32::consts::TAU;
                out.push(0.5 + 0.25 * (t * x / 29.0).sin() + 0.25 * (t * y / 23.0).cos());
                out.push(0.5 + 0.4 * (t * (x + y) / 31.0).sin());
                out.push(0.5 + 0.4 * (t * (2.0 * x - y) / 47.0).cos());
                out.push(1.0);
            }
        }
        out
    }

    /// The mean of the bilinear image along the chord `p + v t`, `t` in `[-1/2, 1/2]`, by
    /// `n` taps at the midpoints of `n` equal pieces, each texel clamped to the image.
    fn dense(
        rgba: &[f32],
        (w, h): (usize, usize),
        (x, y): (usize, usize),
        v: [f32; 2],
        n: usize,
    ) -> [f64; 4] {
        let px = |x: i64, y: i64, c: usize| {
            let (x, y) = (
                x.clamp(0, w as i64 - 1) as usize,
                y.clamp(0, h as i64 - 1) as usize,
            );
            rgba[(y * w + x) * 4 + c] as f64
        };
        let mut acc = [0.0f64; 4];
        for i in 0..n {
            let t = (i as f64 + 0.5) / n as f64 - 0.5;
            let (sx, sy) = (x as f64 + v[0] as f64 * t, y as f64 + v[1] as f64 * t);
            let (x0, y0) = (sx.floor(), sy.floor());
            let (fx, fy) = (sx - x0, sy - y0);
            let (x0, y0) = (x0 as i64, y0 as i64);
            for (c, a) in acc.iter_mut().enumerate() {
                let top = px(x0, y0, c) + fx * (px(x0 + 1, y0, c) - px(x0, y0, c));
                let bot = px(x0, y0 + 1, c) + fx * (px(x0 + 1, y0 + 1, c) - px(x0, y0 + 1, c));
                *a += top + fy * (bot - top);
            }
        }
        acc.map(|a| a / n as f64)
    }

    /// Runs the line blur of `rgba` along `v` (no pixel moving): the image, the mask of the
    /// pixels blurred as a line integral.
    fn run(
        rgba: &[f32],
        v: &[f32],
        (w, h): (usize, usize),
        moving: &[bool],
        saved: f64,
    ) -> (Vec<f32>, Vec<bool>) {
        let taps = Taps::new(16);
        let field = Image {
            v,
            w,
            h,
            moving,
            taps,
        };
        let mut mask = vec![false; w * h];
        let (out, stats) = line_blur_masked(rgba, (w, h), &field, saved, Some(&mut mask));
        assert_eq!(stats.line_pixels, mask.iter().filter(|m| **m).count());
        (out, mask)
    }

    /// The largest difference from the dense-tap oracle over the pixels blurred as a line
    /// integral, and how many there are.
    fn worst(rgba: &[f32], v: &[f32], (w, h): (usize, usize)) -> (f64, usize) {
        let (out, mask) = run(rgba, v, (w, h), &vec![false; w * h], f64::INFINITY);
        let mut worst = 0.0f64;
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if !mask[i] {
                    continue;
                }
                let want = dense(rgba, (w, h), (x, y), [v[2 * i], v[2 * i + 1]], 4096);
                for c in 0..4 {
                    worst = worst.max((out[i * 4 + c] as f64 - want[c]).abs());
                }
            }
        }
        (worst, mask.iter().filter(|m| **m).count())
    }

    /// Tolerance against the oracle: the line integral reads the image between integer major
    /// coordinates as straight lines and across the minor axis interpolates two curves a pixel
    /// apart (a second tent across the streak): second-order errors in the image's curvature,
    /// at most `|I''| / 8` with `|I''| <= 0.4 (2 pi / 23)^2 ~ 0.03` for [`smooth`] (4e-3);
    /// averaged along the streak they are well under that. The 16 taps miss by 1e-2 or more
    /// on these streaks (asserted: the test tells the two apart).
    const ORACLE_TOL: f64 = 4e-3;

    #[test]
    fn constant_velocity_matches_the_dense_oracle_edges_included() {
        // oblique mostly horizontal and mostly vertical streaks, and one longer than the image
        // (every streak near an edge reads clamped texels)
        let (w, h) = (97, 61);
        let rgba = smooth(w, h);
        for v in [
            [41.0f32, 12.0],
            [-9.0, 37.5],
            [150.0, -20.0],
            [-30.0, -30.0],
        ] {
            let vel: Vec<f32> = (0..w * h).flat_map(|_| v).collect();
            let (err, n) = worst(&rgba, &vel, (w, h));
            assert_eq!(n, w * h, "v {v:?}: every pixel fits a constant field");
            assert!(err < ORACLE_TOL, "v {v:?}: {err}");
        }
        // the 16 taps are told apart from the oracle on the same streaks
        let vel: Vec<f32> = (0..w * h).flat_map(|_| [150.0f32, -20.0]).collect();
        let taps = super::super::camera::velocity_blur(&rgba, &vel, w, h, 16).unwrap();
        let far = (0..w * h)
            .flat_map(|i| {
                let want = dense(&rgba, (w, h), (i % w, i / w), [150.0, -20.0], 4096);
                (0..4).map(move |c| (i, c, want[c]))
            })
            .map(|(i, c, want)| (taps[i * 4 + c] as f64 - want).abs())
            .fold(0.0, f64::max);
        assert!(far > 3.0 * ORACLE_TOL, "taps {far}");
    }

    #[test]
    fn slowly_varying_velocity_matches_the_dense_oracle() {
        // the length grows across the image on one direction (parallel curves), and a
        // direction turning slowly: the curves follow the field and bend off each pixel's
        // chord (the oracle's) by `q a^2 / 2`, `q` ~ 2.5e-4 a pixel (2e-4 and 1e-4 radians a
        // pixel along x and y), `a` = 20: 0.05 pixel at the streak's ends, a third of that on
        // average, times gradients up to 0.11 a pixel: under 2e-3 in value, within tolerance
        let (w, h) = (120, 70);
        let rgba = smooth(w, h);
        let grow: Vec<f32> = (0..w * h)
            .flat_map(|i| {
                let l = 20.0 + 0.3 * (i % w) as f32;
                [l, 0.3 * l]
            })
            .collect();
        let turn: Vec<f32> = (0..w * h)
            .flat_map(|i| {
                let a = 0.3 + 2e-4 * (i % w) as f32 + 1e-4 * (i / w) as f32;
                [40.0 * a.cos(), 40.0 * a.sin()]
            })
            .collect();
        for (name, vel) in [("grow", grow), ("turn", turn)] {
            let (err, n) = worst(&rgba, &vel, (w, h));
            assert!(n > w * h * 9 / 10, "{name}: {n} line pixels");
            assert!(err < ORACLE_TOL, "{name}: {err}");
        }
    }

    #[test]
    fn pixels_that_do_not_fit_take_the_taps_bits() {
        let (w, h) = (90, 50);
        let rgba: Vec<f32> = (0..w * h * 4)
            .map(|i| ((i * 37) % 101) as f32 / 101.0)
            .collect();
        // a constant field; at the right a direction that changes from pixel to pixel; a block
        // of moving pixels across both; short streaks at the bottom
        let vel: Vec<f32> = (0..w * h)
            .flat_map(|i| {
                let (x, y) = (i % w, i / w);
                if y >= 44 {
                    [6.0, 2.0]
                } else if x < 65 {
                    [30.0, 5.0]
                } else {
                    let a = ((i * 7919) % 360) as f32;
                    [35.0 * a.cos(), 35.0 * a.sin()]
                }
            })
            .collect();
        let moving: Vec<bool> = (0..w * h)
            .map(|i| (20..30).contains(&(i / w)) && (i % w) % 3 == 0)
            .collect();
        let (out, mask) = run(&rgba, &vel, (w, h), &moving, f64::INFINITY);
        let taps = super::super::camera::velocity_blur(&rgba, &vel, w, h, 16).unwrap();
        let mut fell = 0;
        for i in 0..w * h {
            if moving[i] || i / w >= 44 {
                assert!(!mask[i], "pixel {i} must take the taps");
            }
            if !mask[i] {
                fell += 1;
                assert_eq!(&out[i * 4..i * 4 + 4], &taps[i * 4..i * 4 + 4], "pixel {i}");
            }
        }
        // most of the constant part runs as a line integral, most of the random part not (a
        // random direction passes when its slope is within LINE_TOLERANCE / 17.5 of the
        // field's, 25 of 360 degrees either way: ~7%; 12% measured)
        let left = (0..w * h)
            .filter(|&i| i % w < 40 && i / w < 44 && mask[i])
            .count();
        let right = (0..w * h)
            .filter(|&i| i % w >= 65 && i / w < 44 && mask[i])
            .count();
        assert!(left > 40 * 44 * 8 / 10, "left {left}");
        assert!(right < 25 * 44 / 5, "right {right}");
        assert!(fell > 0);
    }

    #[test]
    fn a_band_with_few_fitting_pixels_takes_the_taps() {
        // one row in 8 may be lines (the others' pixels are moving): a band's 4 such rows of
        // 256 pixels save 1024 * SAMPLES_PER_PIXEL (6144) samples, under the 35 curves times
        // 300 samples (10500) it would build (and in the 44-pixel strip at the right): every
        // pixel takes the taps, the taps' bits; with the rule off (every fitting pixel a
        // line) those rows are lines
        let (w, h) = (300, 64);
        let rgba = smooth(w, h);
        let vel: Vec<f32> = (0..w * h).flat_map(|_| [40.0f32, 5.0]).collect();
        let moving: Vec<bool> = (0..w * h).map(|i| (i / w) % 8 != 0).collect();
        let (out, mask) = run(&rgba, &vel, (w, h), &moving, SAMPLES_PER_PIXEL);
        assert!(mask.iter().all(|m| !m));
        let taps = super::super::camera::velocity_blur(&rgba, &vel, w, h, 16).unwrap();
        assert!(out
            .iter()
            .zip(&taps)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
        let (_, mask) = run(&rgba, &vel, (w, h), &moving, f64::INFINITY);
        let lines = mask.iter().filter(|m| **m).count();
        assert!(lines > w * h / 20, "{lines}");
        // all pixels may be lines: the bands are worth their curves
        let (_, mask) = run(&rgba, &vel, (w, h), &vec![false; w * h], SAMPLES_PER_PIXEL);
        assert!(mask.iter().filter(|m| **m).count() > w * h * 8 / 10);
    }

    #[test]
    fn classify_applies_the_class_rule() {
        // the rule's edges: NaN and infinite components, lengths about MIN_STREAK and the
        // longest streak 2 (w + h), ties |vx| = |vy|, signed zeros; flags 0 and 1
        let dims = (40, 30);
        let longest = 2.0 * 70.0f32;
        let edges = [
            0.0f32,
            -0.0,
            1.0,
            MIN_STREAK.next_down(),
            MIN_STREAK,
            -MIN_STREAK,
            20.0,
            -20.0,
            longest,
            longest.next_up(),
            -longest,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let v: Vec<[f32; 2]> = edges
            .iter()
            .flat_map(|&a| edges.iter().map(move |&b| [a, b]))
            .collect();
        for flag in [0u8, 1] {
            let mut c = vec![flag; v.len()];
            let (nan, vertical) = classify(&mut c, &v, dims);
            let want: Vec<u8> = v
                .iter()
                .map(|&p| match (flag, class(p, dims)) {
                    (1, Class::Line(true)) => 1,
                    (1, Class::Line(false)) => 2,
                    _ => 0,
                })
                .collect();
            assert_eq!(c, want, "flag {flag}");
            assert_eq!(nan, flag == 1, "flag {flag}");
            assert_eq!(vertical, flag == 1, "flag {flag}");
        }
    }

    #[test]
    fn same_on_one_thread() {
        let (w, h) = (700, 90);
        let rgba = smooth(w, h);
        let vel: Vec<f32> = (0..w * h)
            .flat_map(|i| {
                let a = 0.2 + 4e-4 * (i % w) as f32 - 1e-3 * (i / w) as f32;
                let l = 60.0 + 0.1 * (i % w) as f32;
                if (i % w) > 600 {
                    [5.0 * a.cos(), 60.0]
                } else {
                    [l * a.cos(), l * a.sin()]
                }
            })
            .collect();
        let moving = vec![false; w * h];
        let a = run(&rgba, &vel, (w, h), &moving, SAMPLES_PER_PIXEL);
        let b = crate::on_threads(1, || run(&rgba, &vel, (w, h), &moving, SAMPLES_PER_PIXEL));
        assert!(a
            .0
            .iter()
            .zip(&b.0)
            .all(|(p, q)| p.to_bits() == q.to_bits()));
        assert_eq!(a.1, b.1);
        assert!(a.1.iter().filter(|m| **m).count() > w * h / 2);
    }
}
