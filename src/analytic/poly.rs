//! Signs of low-degree polynomials on the unit interval, as sets of spans.
//!
//! Coverage of a moving triangle at one sample is decided by the signs of three quadratics (its
//! edge functions), a cubic (its orientation) and, for triangles that cross the near or far
//! plane, two more cubics. [`Spans`] is a short sorted list of disjoint closed sub-intervals of
//! [0, 1]; [`Spans::nonneg_quadratic`] and [`Spans::positive_cubic`] build one from a polynomial
//! and [`Spans::intersect`] combines them.
//!
//! Watertightness: two triangles sharing an edge see that edge's function with opposite signs,
//! computed from the same numbers. The roots are found from a canonical sign (the leading
//! non-zero coefficient made positive) and the sign of each piece is read at its midpoint with
//! Horner's rule, which is symmetric under negation, so the two triangles split the time axis at
//! bit-identical instants: one owns each piece, never both and never neither. Where a function
//! is exactly zero on a whole piece (a sample on a still edge), `tie` breaks the tie the same
//! way for both sides (see [`Spans::nonneg_quadratic`]).

/// At most this many disjoint spans are kept (a cubic's positive set has at most 2 in [0, 1],
/// a quadratic's at most 2; intersections can only split further up to this).
pub const MAX_SPANS: usize = 4;

/// Disjoint closed sub-intervals `[a, b]` of [0, 1], sorted, `a < b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spans {
    n: usize,
    s: [[f64; 2]; MAX_SPANS],
}

impl Default for Spans {
    fn default() -> Self {
        Self::EMPTY
    }
}

#[inline]
fn horner2(a: f64, b: f64, c: f64, t: f64) -> f64 {
    (a * t + b) * t + c
}

#[inline]
fn horner3(c: [f64; 4], t: f64) -> f64 {
    ((c[3] * t + c[2]) * t + c[1]) * t + c[0]
}

/// The sign of `a t^2 + b t + c` on all of [0, 1] when its ends decide it without roots: a
/// concave (or linear) function positive at both ends is positive throughout (`Some(true)`),
/// a convex (or linear) one negative at both ends negative throughout (`Some(false)`), and so
/// is a function monotone on [0, 1] (its slopes `b` at 0 and `2a + b` at 1 of one sign) of
/// one sign at both ends, whatever its curvature: an edge that does not cross the sample
/// during the segment then costs no square root. The test is symmetric under negation (every
/// quantity compared flips sign exactly), so neighbours sharing an edge agree.
#[inline(always)]
fn ends_decide(a: f64, b: f64, c: f64) -> Option<bool> {
    let (f0, f1) = (c, (a + b) + c);
    let s1 = 2.0 * a + b;
    let monotone = (b >= 0.0 && s1 >= 0.0) || (b <= 0.0 && s1 <= 0.0);
    if (a <= 0.0 || monotone) && f0 > 0.0 && f1 > 0.0 {
        Some(true)
    } else if (a >= 0.0 || monotone) && f0 < 0.0 && f1 < 0.0 {
        Some(false)
    } else {
        None
    }
}

/// `x.floor() as i64` (saturating, NaN to 0) without a libm call: the build targets plain
/// x86-64, which has no rounding instruction, and sample bounds take this per hull row.
#[inline(always)]
pub fn floor_i64(x: f64) -> i64 {
    let i = x as i64;
    if (i as f64) > x {
        i.saturating_sub(1)
    } else {
        i
    }
}

/// `x.ceil() as i64` (saturating, NaN to 0) without a libm call, as [`floor_i64`].
#[inline(always)]
pub fn ceil_i64(x: f64) -> i64 {
    let i = x as i64;
    if (i as f64) < x {
        i.saturating_add(1)
    } else {
        i
    }
}

/// Real roots of `a t^2 + b t + c` strictly inside (0, 1), ascending, from the canonical sign.
#[inline]
pub fn quadratic_roots(a: f64, b: f64, c: f64) -> ([f64; 2], usize) {
    // Canonical sign: the same roots for the function and its negation, bit for bit.
    let neg = a < 0.0 || (a == 0.0 && (b < 0.0 || (b == 0.0 && c < 0.0)));
    let (a, b, c) = if neg { (-a, -b, -c) } else { (a, b, c) };
    let mut r = [0.0; 2];
    let mut n = 0;
    let mut push = |x: f64| {
        if x > 0.0 && x < 1.0 {
            r[n] = x;
            n += 1;
        }
    };
    if a == 0.0 {
        if b != 0.0 {
            push(-c / b);
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc > 0.0 {
            let sq = disc.sqrt();
            let q = -0.5 * (b + if b >= 0.0 { sq } else { -sq });
            let r1 = q / a;
            let r2 = if q != 0.0 { c / q } else { r1 };
            let (lo, hi) = if r1 <= r2 { (r1, r2) } else { (r2, r1) };
            push(lo);
            if hi != lo {
                push(hi);
            }
        }
        // disc <= 0: no sign change (a double root touches zero without crossing)
    }
    (r, n)
}

/// Roots of the cubic `c[0] + c[1] t + c[2] t^2 + c[3] t^3` strictly inside (0, 1), ascending:
/// the derivative's roots split [0, 1] into monotone pieces, each bracketed root is found by
/// bisection to full precision.
pub fn cubic_roots(c: [f64; 4]) -> ([f64; 3], usize) {
    cubic_roots_between(c, 0.0, 1.0)
}

/// [`cubic_roots`] strictly inside (`lo`, `hi`), a part of [0, 1]: only the monotone pieces
/// within it are bisected.
pub fn cubic_roots_between(c: [f64; 4], lo: f64, hi: f64) -> ([f64; 3], usize) {
    let inside = |r: [f64; 2], n: usize| {
        let mut out = [0.0; 3];
        let mut m = 0;
        for &x in &r[..n] {
            if x > lo && x < hi {
                out[m] = x;
                m += 1;
            }
        }
        (out, m)
    };
    if c[3] == 0.0 {
        let (r, n) = quadratic_roots(c[2], c[1], c[0]);
        return inside(r, n);
    }
    let (d, nd) = quadratic_roots(3.0 * c[3], 2.0 * c[2], c[1]);
    let (d, nd) = inside(d, nd);
    let mut cuts = [0.0; 4];
    cuts[0] = lo;
    cuts[1..1 + nd].copy_from_slice(&d[..nd]);
    cuts[1 + nd] = hi;
    let mut out = [0.0; 3];
    let mut n = 0;
    for w in cuts[..nd + 2].windows(2) {
        let (mut lo_w, mut hi_w) = (w[0], w[1]);
        let (flo, fhi) = (horner3(c, lo_w), horner3(c, hi_w));
        if flo == 0.0 || fhi == 0.0 || (flo > 0.0) == (fhi > 0.0) {
            continue; // no sign change inside (roots at the cuts are not crossings we need)
        }
        let rising = fhi > 0.0;
        for _ in 0..64 {
            let mid = 0.5 * (lo_w + hi_w);
            if mid <= lo_w || mid >= hi_w {
                break;
            }
            if (horner3(c, mid) > 0.0) == rising {
                hi_w = mid;
            } else {
                lo_w = mid;
            }
        }
        let r = 0.5 * (lo_w + hi_w);
        if r > lo && r < hi && (n == 0 || r > out[n - 1]) {
            out[n] = r;
            n += 1;
        }
    }
    (out, n)
}

impl Spans {
    /// No time at all.
    pub const EMPTY: Spans = Spans {
        n: 0,
        s: [[0.0; 2]; MAX_SPANS],
    };
    /// The whole interval [0, 1].
    pub const FULL: Spans = Spans {
        n: 1,
        s: [[0.0, 1.0], [0.0; 2], [0.0; 2], [0.0; 2]],
    };

    /// The spans, sorted and disjoint.
    #[inline]
    pub fn as_slice(&self) -> &[[f64; 2]] {
        &self.s[..self.n]
    }

    /// True when no time is covered.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Appends `[a, b]` after the last span (joining it when they touch; ignored when empty).
    #[inline]
    pub fn push(&mut self, a: f64, b: f64) {
        if b <= a {
            return;
        }
        if self.n > 0 && self.s[self.n - 1][1] >= a {
            self.s[self.n - 1][1] = b; // adjacent pieces of the same sign join
            return;
        }
        if self.n < MAX_SPANS {
            self.s[self.n] = [a, b];
            self.n += 1;
        }
    }

    /// Where `a t^2 + b t + c >= 0` on [0, 1]. The function's sign is read at the middle of each
    /// piece between its roots; a piece where it is exactly zero is kept when `tie()` is true
    /// (the caller passes a rule that is true for exactly one of a function and its negation).
    #[inline]
    pub fn nonneg_quadratic(a: f64, b: f64, c: f64, tie: impl Fn(f64) -> bool) -> Spans {
        match ends_decide(a, b, c) {
            Some(true) => return Spans::FULL,
            Some(false) => return Spans::EMPTY,
            None => {}
        }
        let (r, n) = quadratic_roots(a, b, c);
        let mut out = Spans::EMPTY;
        let mut lo = 0.0;
        for k in 0..=n {
            let hi = if k < n { r[k] } else { 1.0 };
            let mid = 0.5 * (lo + hi);
            let v = horner2(a, b, c, mid);
            if v > 0.0 || (v == 0.0 && tie(mid)) {
                out.push(lo, hi);
            }
            lo = hi;
        }
        out
    }

    /// [`Spans::nonneg_quadratic`] as one span or none, `Ok(Some((a, b)))` or `Ok(None)`, or
    /// `Err((r0, r1))` when it is the two spans `[0, r0]` and `[r1, 1]` (the same set).
    #[inline(always)]
    pub fn nonneg_quadratic_one(
        a: f64,
        b: f64,
        c: f64,
        tie: impl Fn(f64) -> bool,
    ) -> Result<Option<(f64, f64)>, (f64, f64)> {
        match ends_decide(a, b, c) {
            Some(true) => return Ok(Some((0.0, 1.0))),
            Some(false) => return Ok(None),
            None => {}
        }
        let (r, n) = quadratic_roots(a, b, c);
        let keep = |lo: f64, hi: f64| {
            let mid = 0.5 * (lo + hi);
            let v = horner2(a, b, c, mid);
            v > 0.0 || (v == 0.0 && tie(mid))
        };
        match n {
            0 => Ok(keep(0.0, 1.0).then_some((0.0, 1.0))),
            1 => {
                let (k0, k1) = (keep(0.0, r[0]), keep(r[0], 1.0));
                Ok(match (k0, k1) {
                    (true, true) => Some((0.0, 1.0)),
                    (true, false) => Some((0.0, r[0])),
                    (false, true) => Some((r[0], 1.0)),
                    (false, false) => None,
                })
            }
            _ => {
                let k = [keep(0.0, r[0]), keep(r[0], r[1]), keep(r[1], 1.0)];
                match k {
                    [false, false, false] => Ok(None),
                    [true, false, false] => Ok(Some((0.0, r[0]))),
                    [false, true, false] => Ok(Some((r[0], r[1]))),
                    [false, false, true] => Ok(Some((r[1], 1.0))),
                    [true, true, false] => Ok(Some((0.0, r[1]))),
                    [false, true, true] => Ok(Some((r[0], 1.0))),
                    [true, true, true] => Ok(Some((0.0, 1.0))),
                    [true, false, true] => Err((r[0], r[1])),
                }
            }
        }
    }

    /// Where the cubic `c[0] + c[1] t + c[2] t^2 + c[3] t^3` is `> 0` (`sign` 1) or `< 0`
    /// (`sign` -1) on [0, 1], read at the middle of each piece between its roots.
    pub fn signed_cubic(c: [f64; 4], sign: f64) -> Spans {
        let (r, n) = cubic_roots(c);
        let mut out = Spans::EMPTY;
        let mut lo = 0.0;
        for k in 0..=n {
            let hi = if k < n { r[k] } else { 1.0 };
            if sign * horner3(c, 0.5 * (lo + hi)) > 0.0 {
                out.push(lo, hi);
            }
            lo = hi;
        }
        out
    }

    /// The times in both `self` and `other`.
    #[inline]
    pub fn intersect(&self, other: &Spans) -> Spans {
        let mut out = Spans::EMPTY;
        let (mut i, mut j) = (0, 0);
        while i < self.n && j < other.n {
            let a = self.s[i][0].max(other.s[j][0]);
            let b = self.s[i][1].min(other.s[j][1]);
            if a < b {
                out.push(a, b);
            }
            if self.s[i][1] < other.s[j][1] {
                i += 1;
            } else {
                j += 1;
            }
        }
        out
    }

    /// The times in `self` or `other` (tests compare sets with it).
    #[cfg(test)]
    pub fn union(&self, other: &Spans) -> Spans {
        let mut all = [[0.0; 2]; 2 * MAX_SPANS];
        let mut m = 0;
        for s in self.as_slice().iter().chain(other.as_slice()) {
            all[m] = *s;
            m += 1;
        }
        let all = &mut all[..m];
        all.sort_by(|x, y| x[0].total_cmp(&y[0]));
        let mut out = Spans::EMPTY;
        for s in all.iter() {
            out.push(s[0], s[1]);
        }
        out
    }
}

/// `c[0] + c[1] t + c[2] t^2 + c[3] t^3` at `t`.
#[inline]
pub fn cubic_at(c: [f64; 4], t: f64) -> f64 {
    horner3(c, t)
}

/// `a t^2 + b t + c` at `t`.
#[inline]
pub fn quadratic_at(a: f64, b: f64, c: f64, t: f64) -> f64 {
    horner2(a, b, c, t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_decide_agrees_with_the_roots_and_with_the_negation() {
        // curved edge functions that do not cross zero on [0, 1] (vertex outside or inside),
        // and ones that do: wherever the ends decide, the roots' pieces agree, and the negated
        // function is decided the other way (so two triangles sharing the edge agree)
        let mut state = 12345u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 4.0 - 2.0
        };
        let mut decided = 0;
        for _ in 0..20000 {
            let (a, b, c) = (next(), next(), next());
            let Some(pos) = ends_decide(a, b, c) else {
                assert_eq!(ends_decide(-a, -b, -c), None);
                continue;
            };
            decided += 1;
            assert_eq!(ends_decide(-a, -b, -c), Some(!pos));
            let (r, n) = quadratic_roots(a, b, c);
            let mut lo = 0.0;
            for k in 0..=n {
                let hi = if k < n { r[k] } else { 1.0 };
                assert_eq!(horner2(a, b, c, 0.5 * (lo + hi)) > 0.0, pos, "{a} {b} {c}");
                lo = hi;
            }
        }
        assert!(decided > 5000, "{decided}");
    }

    #[test]
    fn integer_floor_and_ceil_match_the_float_ones() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.5,
            -2.5,
            1e-300,
            -1e-300,
            4503599627370495.5,
            -4503599627370495.5,
            9.2e18,
            -9.2e18,
            9.3e18,
            -9.3e18,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MAX,
            f64::MIN,
        ];
        let mut x = 1.0e-3f64;
        while x < 1e20 {
            xs.extend([
                x,
                -x,
                x.next_up(),
                -x.next_up(),
                x.next_down(),
                -x.next_down(),
            ]);
            x *= 1.37;
        }
        for k in -300..300 {
            let v = f64::from(k) * 0.25;
            xs.extend([v, v.next_up(), v.next_down()]);
        }
        for x in xs {
            assert_eq!(floor_i64(x), x.floor() as i64, "floor {x}");
            assert_eq!(ceil_i64(x), x.ceil() as i64, "ceil {x}");
        }
    }

    #[test]
    fn quadratic_roots_match_the_closed_form_and_are_sign_symmetric() {
        // (t - 0.25)(t - 0.75) = t^2 - t + 0.1875
        let (r, n) = quadratic_roots(1.0, -1.0, 0.1875);
        assert_eq!(n, 2);
        assert!((r[0] - 0.25).abs() < 1e-15 && (r[1] - 0.75).abs() < 1e-15);
        let (rn, nn) = quadratic_roots(-1.0, 1.0, -0.1875);
        assert_eq!((r, n), (rn, nn));
        // linear
        let (r, n) = quadratic_roots(0.0, 2.0, -1.0);
        assert_eq!((r[0], n), (0.5, 1));
        // nearly linear: the small root stays accurate
        let (r, n) = quadratic_roots(1e-14, 2.0, -1.0);
        assert_eq!(n, 1);
        assert!((r[0] - 0.5).abs() < 1e-14);
    }

    #[test]
    fn nonneg_quadratic_and_its_negation_partition_the_interval() {
        let tie = |_: f64| true;
        let cases = [
            (1.0, -1.0, 0.1875),
            (0.0, 3.0, -1.0),
            (-2.0, 0.5, 0.3),
            (0.0, 0.0, 1.0),
            (1e-3, -0.7, 0.2),
        ];
        for (a, b, c) in cases {
            let p = Spans::nonneg_quadratic(a, b, c, tie);
            let q = Spans::nonneg_quadratic(-a, -b, -c, |_| false);
            let total: f64 = p
                .as_slice()
                .iter()
                .chain(q.as_slice())
                .map(|s| s[1] - s[0])
                .sum();
            assert_eq!(total, 1.0, "{a} {b} {c}: {p:?} {q:?}");
            assert!(p.intersect(&q).is_empty());
        }
    }

    #[test]
    fn zero_functions_follow_the_tie_rule() {
        assert_eq!(
            Spans::nonneg_quadratic(0.0, 0.0, 0.0, |_| true),
            Spans::FULL
        );
        assert!(Spans::nonneg_quadratic(0.0, 0.0, 0.0, |_| false).is_empty());
    }

    #[test]
    fn cubic_roots_are_found_in_every_monotone_piece() {
        // (t - 0.1)(t - 0.5)(t - 0.9)
        let c = [-0.045, 0.59, -1.5, 1.0];
        let (r, n) = cubic_roots(c);
        assert_eq!(n, 3);
        for (x, y) in r.iter().zip([0.1, 0.5, 0.9]) {
            assert!((x - y).abs() < 1e-12, "{r:?}");
        }
        let pos = Spans::signed_cubic(c, 1.0);
        assert_eq!(pos.as_slice().len(), 2);
        assert!((pos.as_slice()[0][0] - 0.1).abs() < 1e-12);
        assert!((pos.as_slice()[1][1] - 1.0).abs() < 1e-15);
        // within a part of [0, 1]: only the roots strictly inside it
        let (b, m) = cubic_roots_between(c, 0.3, 0.95);
        assert_eq!(m, 2);
        assert!(
            (b[0] - 0.5).abs() < 1e-12 && (b[1] - 0.9).abs() < 1e-12,
            "{b:?}"
        );
        assert_eq!(cubic_roots_between(c, 0.5, 0.9).1, 0);
        // a quadratic (no cubic term) the same way: (t - 0.2)(t - 0.6)
        let (q, m) = cubic_roots_between([0.12, -0.8, 1.0, 0.0], 0.4, 1.0);
        assert_eq!(m, 1);
        assert!((q[0] - 0.6).abs() < 1e-12);
    }

    #[test]
    fn intersection_and_union() {
        let a = Spans::nonneg_quadratic(1.0, -1.0, 0.1875, |_| true); // [0, .25] u [.75, 1]
        let b = Spans::nonneg_quadratic(0.0, 1.0, -0.5, |_| true); // [.5, 1]
        let i = a.intersect(&b);
        assert_eq!(i.as_slice().len(), 1);
        assert!((i.as_slice()[0][0] - 0.75).abs() < 1e-15);
        let u = a.union(&b);
        assert_eq!(u.as_slice().len(), 2);
        assert_eq!(u.as_slice()[1], [0.5, 1.0]);
    }
}
