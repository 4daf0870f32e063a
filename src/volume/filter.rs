//! Temporal (shutter) filters of the motion volume.
//!
//! A motion volume of `n` segments has `n + 1` contour rings at the shutter times `t_i = i / n`;
//! ring `n` is the leading contour (shutter close), ring 0 the trailing one (shutter open).
//!
//! - `ramp`, the paper's (sections 3.4 and 4.2), exactly as stated there: leading vertices are
//!   opaque, trailing vertices and ring `i` get `alpha_i = max(0.1, 1 - D_i / E)` where `D_i` is
//!   the path length from ring `i` to the leading ring (the sum of the segment lengths after it)
//!   and `E` the object's extent along the summed motion vector; the rasterizer interpolates
//!   linearly in between. With `E = 0` and a moving object every other ring gets the floor 0.1.
//!   It is a look, not a measurement: its total coverage is not the object's area.
//! - `box`, `triangle`, `gaussian` (our own design): shutter weights `w(t)` on [0, 1] with unit
//!   integral (box 1; triangle peaking at 0.5; gaussian centred at 0.5 with sigma 1/6,
//!   truncated to [0, 1] and renormalised). Each vertex gets the weighted fraction of the
//!   shutter during which the object covers its image, from the coverage model of
//!   the coverage model (`coverage.rs`); no floor, so a long streak is as faint as it physically is.
//!
//! Without motion every filter gives alpha 1.
use crate::error::{Error, Result};
use crate::shutter::erf;

/// A temporal filter over the shutter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Filter {
    /// The paper's ramp.
    Ramp,
    /// Uniform weight over the shutter.
    Box,
    /// Weight rising linearly to the middle of the shutter and falling back.
    Triangle,
    /// Gaussian weight centred on the middle of the shutter (sigma 1/6).
    Gaussian,
}

/// The lowest opacity given to a ring (the paper's `max(0.1, ...)`).
pub const ALPHA_FLOOR: f64 = 0.1;

impl Filter {
    /// The filters' names, as [`Filter::parse`] takes them.
    pub const NAMES: [&'static str; 4] = ["ramp", "box", "triangle", "gaussian"];

    /// Parse `ramp`, `box`, `triangle` or `gaussian`; anything else is an error naming `filter`.
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "ramp" => Ok(Filter::Ramp),
            "box" => Ok(Filter::Box),
            "triangle" => Ok(Filter::Triangle),
            "gaussian" => Ok(Filter::Gaussian),
            _ => Err(Error::value(
                "filter",
                format!(
                    "unknown filter {name:?}; expected 'ramp', 'box', 'triangle' or 'gaussian'"
                ),
            )),
        }
    }

    /// Cumulative weight `W(t) = integral of w over [0, t]`, `t` in [0, 1]; `W(1) = 1`.
    pub fn cumulative(self, t: f64) -> f64 {
        let t = t.clamp(0.0, 1.0);
        match self {
            Filter::Ramp => t * t,
            Filter::Box => t,
            Filter::Triangle => {
                if t <= 0.5 {
                    2.0 * t * t
                } else {
                    1.0 - 2.0 * (1.0 - t) * (1.0 - t)
                }
            }
            Filter::Gaussian => gaussian_cumulative(t),
        }
    }

    /// The filter's weight of the shutter interval `[a, b]`: `W(b) - W(a)`.
    pub fn weight(self, a: f64, b: f64) -> f64 {
        self.cumulative(b) - self.cumulative(a)
    }

    /// [`Filter::cumulative`] with the gaussian from its definition (the error function's
    /// series), for difference quotients over tiny steps, which would magnify the table's
    /// 1e-14 error (a spin's ring weights).
    pub fn cumulative_exact(self, t: f64) -> f64 {
        match self {
            Filter::Gaussian => gaussian_cumulative_exact(t.clamp(0.0, 1.0)),
            f => f.cumulative(t),
        }
    }

    /// The paper's ramp opacity of the `n + 1` rings for segment lengths `lengths` (`n` of
    /// them, world units) and the extent `extent` along the summed motion vector.
    pub fn ring_alphas(self, lengths: &[f64], extent: f64) -> Vec<f64> {
        let n = lengths.len();
        let total: f64 = lengths.iter().sum();
        let mut out = vec![1.0; n + 1];
        if total == 0.0 {
            return out;
        }
        // D_i = sum of the lengths of segments i+1..n, accumulated from the leading end.
        let mut d = 0.0;
        for i in (0..n).rev() {
            d += lengths[i];
            out[i] = if d == 0.0 {
                1.0
            } else if extent > 0.0 {
                (1.0 - d / extent).clamp(ALPHA_FLOOR, 1.0)
            } else {
                ALPHA_FLOOR
            };
        }
        out
    }

    /// Equally spaced cuts of each joining segment for the coverage model (`q`, giving `q - 1`
    /// cuts, plus two per-vertex cuts): 1 for box (its coverage is piecewise linear), 4 for
    /// triangle (a cut at its peak) and 6 for gaussian (curved).
    pub fn knots_per_segment(self) -> usize {
        match self {
            Filter::Ramp | Filter::Box => 1,
            Filter::Triangle => 4,
            Filter::Gaussian => 6,
        }
    }
}

/// Knot intervals of the gaussian's cumulative weight table.
const GAUSSIAN_KNOTS: usize = 4096;

/// The gaussian's cumulative weight from its definition (the error function's series, about 40
/// terms): `(Phi(6 (t - 1/2)) - Phi(-3)) / (Phi(3) - Phi(-3))`.
fn gaussian_cumulative_exact(t: f64) -> f64 {
    let phi = |x: f64| 0.5 * (1.0 + erf(x / std::f64::consts::SQRT_2));
    let (lo, hi) = (phi(-3.0), phi(3.0));
    (phi((t - 0.5) * 6.0) - lo) / (hi - lo)
}

/// The gaussian's weight `w(t)`, the derivative of [`gaussian_cumulative_exact`].
fn gaussian_density(t: f64) -> f64 {
    let x = (t - 0.5) * 6.0;
    let phi = |x: f64| 0.5 * (1.0 + erf(x / std::f64::consts::SQRT_2));
    let norm = phi(3.0) - phi(-3.0);
    6.0 * (-0.5 * x * x).exp() / ((2.0 * std::f64::consts::PI).sqrt() * norm)
}

/// The gaussian's cumulative weight, cubic Hermite between [`GAUSSIAN_KNOTS`] + 1 knots of its
/// value and slope (computed once): within 1e-14 of the definition, exact at 0 and 1, a few
/// multiplications instead of the error function's series (the coverage model asks for it
/// twice per vertex and covering segment).
fn gaussian_cumulative(t: f64) -> f64 {
    static TABLE: std::sync::OnceLock<Vec<[f64; 2]>> = std::sync::OnceLock::new();
    let table = TABLE.get_or_init(|| {
        (0..=GAUSSIAN_KNOTS)
            .map(|i| {
                let t = i as f64 / GAUSSIAN_KNOTS as f64;
                [gaussian_cumulative_exact(t), gaussian_density(t)]
            })
            .collect()
    });
    let h = 1.0 / GAUSSIAN_KNOTS as f64;
    let x = t.clamp(0.0, 1.0) * GAUSSIAN_KNOTS as f64;
    let i = (x.floor() as usize).min(GAUSSIAN_KNOTS - 1);
    let s = x - i as f64;
    let ([w0, d0], [w1, d1]) = (table[i], table[i + 1]);
    let (s2, s3) = (s * s, s * s * s);
    (2.0 * s3 - 3.0 * s2 + 1.0) * w0
        + (s3 - 2.0 * s2 + s) * h * d0
        + (-2.0 * s3 + 3.0 * s2) * w1
        + (s3 - s2) * h * d1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cumulative_weights_end_at_one() {
        for f in [
            Filter::Ramp,
            Filter::Box,
            Filter::Triangle,
            Filter::Gaussian,
        ] {
            assert!(f.cumulative(0.0).abs() < 1e-12);
            assert!((f.cumulative(1.0) - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn gaussian_table_is_its_definition() {
        // Every knot, and between knots at odd offsets, against the error function's series.
        let mut worst: f64 = 0.0;
        for k in 0..=40_000 {
            let t = k as f64 / 40_000.0 + if k % 3 == 1 { 7.3e-6 } else { 0.0 };
            let t = t.min(1.0);
            worst = worst.max((gaussian_cumulative(t) - gaussian_cumulative_exact(t)).abs());
        }
        assert!(worst < 1e-14, "{worst:e}");
        assert_eq!(gaussian_cumulative(0.0), 0.0);
        assert_eq!(gaussian_cumulative(1.0), 1.0);
        // The slope is the weight: a difference quotient of the definition.
        let h = 1e-6;
        let q =
            (gaussian_cumulative_exact(0.3 + h) - gaussian_cumulative_exact(0.3 - h)) / (2.0 * h);
        assert!((gaussian_density(0.3) - q).abs() < 1e-8);
    }

    #[test]
    fn ramp_is_the_papers_formula() {
        let a = Filter::Ramp.ring_alphas(&[1.0, 1.0, 2.0], 5.0);
        assert_eq!(a[3], 1.0);
        assert!((a[2] - (1.0 - 2.0 / 5.0)).abs() < 1e-15);
        assert!((a[1] - (1.0 - 3.0 / 5.0)).abs() < 1e-15);
        assert!((a[0] - 0.2).abs() < 1e-15);
        assert_eq!(
            Filter::Ramp.ring_alphas(&[10.0], 1.0),
            vec![ALPHA_FLOOR, 1.0]
        );
        assert_eq!(
            Filter::Ramp.ring_alphas(&[1.0], 0.0),
            vec![ALPHA_FLOOR, 1.0]
        );
        assert_eq!(Filter::Ramp.ring_alphas(&[0.0, 0.0], 1.0), vec![1.0; 3]);
        assert!(Filter::parse("median").is_err());
    }
}
