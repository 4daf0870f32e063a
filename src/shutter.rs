//! Shutter filters: how much each instant of the shutter weighs: a density `w(t)` on [0, 1] with unit
//! integral and its cumulative `W(t)`.
//!
//! `box` (uniform), `ramp` (`w = 2t`, the motion-volume paper's, rising to the close),
//! `triangle` (peak at 0.5), `gaussian` (centred at 0.5, sigma 1/6, truncated to [0, 1] and
//! renormalised) and `weights`: M non-negative numbers for M equal strata of the shutter, the
//! piecewise-constant density they define. These are the scene's filters
//! (`motionblur.scene.shutter_cdf`).
use crate::error::{Error, Result};

/// A shutter filter.
#[derive(Clone, Debug, PartialEq)]
pub enum Shutter {
    /// Uniform weight.
    Box,
    /// `w(t) = 2 t`.
    Ramp,
    /// `w(t) = 4 t` up to 0.5, then `4 (1 - t)`.
    Triangle,
    /// A normal density centred at 0.5 with sigma 1/6, truncated to [0, 1].
    Gaussian,
    /// Piecewise constant: `cum` holds the M + 1 cumulative weights at `i / M` (0 to 1).
    Weights {
        /// Cumulative weights at the strata boundaries, from 0 to 1.
        cum: Vec<f64>,
    },
    /// A trapezoid, as a mechanical shutter opens and closes: the density rises linearly over
    /// `[0, open]`, holds, and falls linearly over `[1 - close, 1]` (RenderMan's and Cycles'
    /// shutter curves of this shape).
    Trapezoid {
        /// Length of the opening ramp, in [0, 1].
        open: f64,
        /// Length of the closing ramp, in [0, 1 - open].
        close: f64,
    },
}

const SQRT_2PI: f64 = 2.506_628_274_631_000_5;

fn phi(x: f64) -> f64 {
    0.5 * (1.0 + erf(x / std::f64::consts::SQRT_2))
}

impl Shutter {
    /// `box`, `ramp`, `triangle` or `gaussian`; an error naming `shutter` otherwise.
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "box" => Ok(Shutter::Box),
            "ramp" => Ok(Shutter::Ramp),
            "triangle" => Ok(Shutter::Triangle),
            "gaussian" => Ok(Shutter::Gaussian),
            _ => Err(Error::value(
                "shutter",
                format!(
                    "unknown filter {name:?}; expected 'box', 'ramp', 'triangle' or 'gaussian'"
                ),
            )),
        }
    }

    /// The piecewise-constant filter of `w` (M >= 1 finite weights >= 0 with a positive sum).
    pub fn weights(w: &[f64]) -> Result<Self> {
        if w.is_empty() {
            return Err(Error::shape("shutter", "weights must not be empty"));
        }
        if w.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(Error::value("shutter", "weights must be finite and >= 0"));
        }
        let total: f64 = w.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return Err(Error::value(
                "shutter",
                "weights must have a positive, finite sum",
            ));
        }
        let mut cum = Vec::with_capacity(w.len() + 1);
        let mut run = 0.0;
        cum.push(0.0);
        for x in w {
            run += x;
            cum.push(run / total);
        }
        Ok(Shutter::Weights { cum })
    }

    /// The trapezoid of ramps `open` and `close` (each >= 0, `open + close <= 1`); an error
    /// naming `shutter` otherwise.
    pub fn trapezoid(open: f64, close: f64) -> Result<Self> {
        let ok = |x: f64| x.is_finite() && x >= 0.0;
        if !(ok(open) && ok(close) && open + close <= 1.0) {
            return Err(Error::value(
                "shutter",
                format!(
                    "trapezoid ramps must be >= 0 with open + close <= 1, got {open} and {close}"
                ),
            ));
        }
        Ok(Shutter::Trapezoid { open, close })
    }

    /// `W(t)`, the weight of [0, t] (`W(0) = 0`, `W(1) = 1`).
    pub fn cumulative(&self, t: f64) -> f64 {
        let t = t.clamp(0.0, 1.0);
        match self {
            Shutter::Box => t,
            Shutter::Ramp => t * t,
            Shutter::Triangle => {
                if t <= 0.5 {
                    2.0 * t * t
                } else {
                    1.0 - 2.0 * (1.0 - t) * (1.0 - t)
                }
            }
            Shutter::Gaussian => {
                let (lo, hi) = (phi(-3.0), phi(3.0));
                (phi((t - 0.5) * 6.0) - lo) / (hi - lo)
            }
            Shutter::Weights { cum } => {
                let m = cum.len() - 1;
                let x = t * m as f64;
                let i = (x.floor() as usize).min(m - 1);
                cum[i] + (x - i as f64) * (cum[i + 1] - cum[i])
            }
            Shutter::Trapezoid { open, close } => trapezoid_cumulative(*open, *close, t),
        }
    }

    /// `w(t)`, the density at `t` in [0, 1].
    pub fn density(&self, t: f64) -> f64 {
        let t = t.clamp(0.0, 1.0);
        match self {
            Shutter::Box => 1.0,
            Shutter::Ramp => 2.0 * t,
            Shutter::Triangle => 4.0 * t.min(1.0 - t),
            Shutter::Gaussian => {
                let x = (t - 0.5) * 6.0;
                6.0 * (-0.5 * x * x).exp() / SQRT_2PI / (phi(3.0) - phi(-3.0))
            }
            Shutter::Weights { cum } => {
                let m = cum.len() - 1;
                let i = ((t * m as f64).floor() as usize).min(m - 1);
                (cum[i + 1] - cum[i]) * m as f64
            }
            Shutter::Trapezoid { open, close } => {
                let h = 1.0 / (1.0 - 0.5 * (open + close)); // the flat part's height
                let rise = if *open > 0.0 { t / open } else { 1.0 };
                let fall = if *close > 0.0 { (1.0 - t) / close } else { 1.0 };
                h * rise.min(fall).min(1.0)
            }
        }
    }

    /// Interior instants where the density has a kink or a jump (pieces of visible time are
    /// split there so that each piece's quadrature sees a smooth density).
    pub fn breaks(&self) -> Vec<f64> {
        match self {
            Shutter::Triangle => vec![0.5],
            Shutter::Weights { cum } => {
                let m = cum.len() - 1;
                (1..m).map(|i| i as f64 / m as f64).collect()
            }
            Shutter::Trapezoid { open, close } => [*open, 1.0 - close]
                .into_iter()
                .filter(|&t| t > 0.0 && t < 1.0)
                .collect(),
            _ => Vec::new(),
        }
    }
}

/// `W(t)` of the trapezoid with ramps `open` and `close` (`t` in [0, 1]).
fn trapezoid_cumulative(open: f64, close: f64, t: f64) -> f64 {
    let h = 1.0 / (1.0 - 0.5 * (open + close));
    if t < open {
        return 0.5 * h * t * t / open;
    }
    let end = 1.0 - close;
    if t <= end {
        return h * (0.5 * open + (t - open));
    }
    let left = 1.0 - t; // the weight after t: a triangle of height h * left / close
    1.0 - 0.5 * h * left * left / close
}

/// The error function: its Taylor series for |x| < 3 (absolute error below 1e-13 there), an
/// asymptotic expansion of erfc beyond (absolute error below 1e-7). The filters use |x| <= 2.2.
pub fn erf(x: f64) -> f64 {
    let ax = x.abs();
    if ax < 3.0 {
        // erf(x) = 2/sqrt(pi) * sum_n (-1)^n x^(2n+1) / (n! (2n+1))
        let z = x * x;
        let mut term = x;
        let mut sum = x;
        let mut n = 0.0;
        while term.abs() > 1e-17 * sum.abs().max(1e-300) {
            n += 1.0;
            term *= -z / n;
            sum += term / (2.0 * n + 1.0);
            if n > 200.0 {
                break;
            }
        }
        sum * std::f64::consts::FRAC_2_SQRT_PI
    } else {
        let z = 1.0 / (ax * ax);
        let erfc = (-ax * ax).exp() / (ax * std::f64::consts::PI.sqrt())
            * (1.0 - 0.5 * z + 0.75 * z * z - 1.875 * z * z * z);
        (1.0 - erfc).copysign(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erf_matches_known_values() {
        for (x, want) in [
            (0.0, 0.0),
            (0.1, 0.112_462_916_018_284_9),
            (0.5, 0.520_499_877_813_046_5),
            (1.0, 0.842_700_792_949_714_9),
            (2.0, 0.995_322_265_018_952_7),
            (-1.5, -0.966_105_146_475_310_7),
            (-2.2, -0.998_137_153_702_018),
        ] {
            assert!((erf(x) - want).abs() < 1e-13, "erf({x}) = {}", erf(x));
        }
    }

    #[test]
    fn density_integrates_to_the_cumulative() {
        let filters = [
            Shutter::Box,
            Shutter::Ramp,
            Shutter::Triangle,
            Shutter::Gaussian,
            Shutter::weights(&[1.0, 0.0, 3.0, 2.0]).unwrap(),
            Shutter::trapezoid(0.1, 0.25).unwrap(),
            Shutter::trapezoid(0.0, 0.5).unwrap(),
            Shutter::trapezoid(0.5, 0.5).unwrap(),
        ];
        for f in filters {
            assert!(f.cumulative(0.0).abs() < 1e-15);
            assert!((f.cumulative(1.0) - 1.0).abs() < 1e-12);
            // midpoint rule on a fine grid aligned with the strata
            let n = 4000;
            let mut run = 0.0;
            for i in 0..n {
                let (a, b) = (i as f64 / n as f64, (i + 1) as f64 / n as f64);
                run += f.density(0.5 * (a + b)) * (b - a);
                if (i + 1) % 400 == 0 {
                    assert!((run - f.cumulative(b)).abs() < 1e-6, "{f:?} at {b}");
                }
            }
        }
    }

    #[test]
    fn bad_weights_name_the_shutter() {
        for w in [&[][..], &[-1.0, 2.0], &[0.0, 0.0], &[f64::NAN]] {
            let e = Shutter::weights(w).unwrap_err();
            assert!(e.to_string().starts_with("shutter"), "{e}");
        }
        assert!(Shutter::parse("boxy").is_err());
    }
}
