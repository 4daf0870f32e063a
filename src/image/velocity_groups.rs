//! Whether a moving object's pixel velocities certainly form one group of the `opaque_image`
//! method's split (`groups=True`): numpy gives each velocity `v` the key
//!
//! ```text
//! sector = floor((atan2(vy, vx) + pi) / (2 pi) * sectors) mod sectors
//! size   = floor(log(max(hypot(vx, vy), 1)) / log(ratio))
//! ```
//!
//! and one key for every pixel means one group. Here no key is computed per pixel: the
//! velocities are checked to lie strictly inside one sector's wedge (two cross products each)
//! and their lengths inside one size bin (the shortest and the longest), each at least
//! [`MARGIN`] from the bin's edges, far beyond the rounding of numpy's functions (a few units
//! in the last place, about 1e-15 relative), so numpy's floors agree with the exact ones. The
//! one exact edge case allowed is a velocity along +x (`vy` = +-0, `vx` > 0): `atan2(+-0, x > 0)`
//! is +-0 exactly (IEEE 754 and C99 Annex F), on the sector edge at angle 0, whose sector is
//! then `floor(sectors / 2)`. "Not certain" says nothing: the caller computes the keys.

/// How far (radians, and units of the size bins) a velocity must lie from a bin's edge.
pub const MARGIN: f64 = 1e-9;

/// True when every velocity of `v` (`(vx, vy)` pairs) certainly has the same key (module
/// docs); false when not certain (or `v` is empty, or `sectors < 3`, or `ratio <= 1`).
pub fn one_velocity_group(v: &[[f64; 2]], sectors: u32, ratio: f64) -> bool {
    if v.is_empty() || sectors < 3 || ratio.is_nan() || ratio <= 1.0 {
        return false;
    }
    one_sector(v, sectors) && one_size(v, ratio)
}

fn one_sector(v: &[[f64; 2]], sectors: u32) -> bool {
    // along +x exactly: the angle is +-0
    if v.iter().all(|&[x, y]| y == 0.0 && x > 0.0) {
        return true;
    }
    let [x0, y0] = v[0];
    if !(x0.is_finite() && y0.is_finite()) || (x0 == 0.0 && y0 == 0.0) {
        return false;
    }
    let s = sectors as f64;
    let f = (y0.atan2(x0) + std::f64::consts::PI) / std::f64::consts::TAU * s;
    let j = f.floor();
    // the wedge between the edges at angles lo and lo + 2 pi / sectors (convex: sectors >= 3)
    let lo = -std::f64::consts::PI + j * std::f64::consts::TAU / s;
    let hi = lo + std::f64::consts::TAU / s;
    let (ul, uh) = ([lo.cos(), lo.sin()], [hi.cos(), hi.sin()]);
    // (squared: no square root per pixel; n2 > 0 and finite, NaN failing every comparison)
    let m2 = MARGIN * MARGIN;
    v.iter().all(|&[x, y]| {
        let n2 = x * x + y * y;
        let (a, b) = (ul[0] * y - ul[1] * x, x * uh[1] - y * uh[0]);
        n2 > 0.0 && n2.is_finite() && a > 0.0 && b > 0.0 && a * a > m2 * n2 && b * b > m2 * n2
    })
}

fn one_size(v: &[[f64; 2]], ratio: f64) -> bool {
    // the shortest and longest squared lengths (their roots are within 1e-15 of numpy's hypot)
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for &[x, y] in v {
        let n2 = x * x + y * y;
        if !n2.is_finite() {
            return false;
        }
        lo = lo.min(n2);
        hi = hi.max(n2);
    }
    let (lo, hi) = (lo.sqrt(), hi.sqrt());
    let q = |n: f64| n.max(1.0).ln() / ratio.ln();
    let (qlo, qhi) = (q(lo), q(hi));
    let bin = qhi.floor();
    // bin 0 has no lower edge to fear: log(max(h, 1)) >= 0 (exactly 0 for h <= 1)
    qlo.floor() == bin && bin + 1.0 - qhi > MARGIN && (bin == 0.0 || qlo - bin > MARGIN)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The key of the module docs, in f64 as numpy writes it.
    fn key(v: [f64; 2], sectors: u32, ratio: f64) -> (i64, i64) {
        let s = ((v[1].atan2(v[0]) + std::f64::consts::PI) / (2.0 * std::f64::consts::PI)
            * sectors as f64)
            .floor() as i64;
        let z = (v[0].hypot(v[1]).max(1.0).ln() / ratio.ln()).floor() as i64;
        (s.rem_euclid(sectors as i64), z)
    }

    #[test]
    fn certain_only_when_the_keys_agree() {
        let mut seed = 7u64;
        let mut rnd = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut certain = 0;
        for t in 0..4000usize {
            let n = 1 + (rnd() * 50.0) as usize;
            let a0 = (rnd() - 0.5) * 7.0;
            let (spread, len) = (rnd().powi(3) * 0.6, 0.5 + rnd() * 900.0);
            let v: Vec<[f64; 2]> = (0..n)
                .map(|_| {
                    let a = a0 + (rnd() - 0.5) * spread;
                    let r = len * (1.0 + (rnd() - 0.5) * spread);
                    match t % 4 {
                        0 => [r, 0.0], // along +x
                        1 => [r * a.cos(), r * a.sin()],
                        // on an edge of the sectors, or of the size bins
                        2 => {
                            let e = -std::f64::consts::PI
                                + (t % 16) as f64 * std::f64::consts::PI / 8.0;
                            [r * (e + (rnd() - 0.5) * 1e-12).cos(), r * e.sin()]
                        }
                        _ => {
                            let r = 1.5f64.powi((t % 9) as i32) * (1.0 + (rnd() - 0.5) * 1e-13);
                            [r * a.cos(), r * a.sin()]
                        }
                    }
                })
                .collect();
            if one_velocity_group(&v, 16, 1.5) {
                certain += 1;
                let k = key(v[0], 16, 1.5);
                assert!(v.iter().all(|&p| key(p, 16, 1.5) == k), "{v:?}");
            }
        }
        assert!(certain > 1000, "{certain}: the check is too shy to help");
        // a translation along +x and along an oblique direction are certain; straddling not
        assert!(one_velocity_group(&[[579.0, 0.0], [583.5, -0.0]], 16, 1.5));
        assert!(one_velocity_group(&[[100.0, 30.0], [101.0, 30.5]], 16, 1.5));
        assert!(!one_velocity_group(
            &[[100.0, 1e-3], [100.0, -1e-3]],
            16,
            1.5
        ));
        assert!(!one_velocity_group(&[[1.5f64.powi(6), 0.0]], 16, 1.5));
        assert!(!one_velocity_group(&[[-5.0, 0.0]], 16, 1.5));
        assert!(!one_velocity_group(&[[0.0, 0.0]], 16, 1.5));
        assert!(!one_velocity_group(&[], 16, 1.5));
    }
}
