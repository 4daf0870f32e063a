//! How many points in time a visible piece of a sample is shaded at, and where: Gauss-Legendre
//! rules of 1 to 8 points, chosen by the piece's length and by how much its triangles' shading
//! varies across them ([`Quadrature::points`]). A piece is shaded by one triangle per layer
//! (`resolve.rs` cuts it where a chain changes triangle).

/// [`Quadrature::Auto`] shades triangles whose corner normals are further apart than this at 2
/// points at least.
pub const BEND_2: f32 = 0.1;
/// ... further apart than this at 3.
pub const BEND_3: f32 = 0.5;
/// ... and further apart than this at 4.
pub const BEND_4: f32 = 1.0;

/// How many points in time each visible piece is shaded at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quadrature {
    /// 1 to 4 points, the most of two rules. By the piece's length: below 1/32 of the
    /// shutter 1, below 1/4 2, else 3. By the bend of its triangles (the largest distance
    /// between two unit corner normals of a smooth-shaded triangle, about the angle between
    /// them; 0 for flat shading): above 0.1 (`BEND_2`) 2, above 0.5 (`BEND_3`) 3, above 1.0
    /// (`BEND_4`) 4. A sample
    /// crossed by a triangle sweeps the whole triangle within a short piece, so how much the
    /// shading varies over the piece depends on the triangle's normals as much as on the
    /// piece's length: lambert of a normal interpolated linearly and normalised is linear up to
    /// terms in the square of the bend, which a single midpoint misses.
    Auto,
    /// A fixed number of Gauss-Legendre points, 1 to 4.
    Points(u8),
}

impl Quadrature {
    /// Points for a piece of length `len` shaded by one triangle per layer whose shading
    /// varies by `bend` across it: `Auto` takes 1, 2 or 3 by length, or up to 4 by `bend`.
    pub fn points(self, len: f64, bend: f32) -> usize {
        match self {
            Quadrature::Points(n) => n as usize,
            Quadrature::Auto => {
                let by_len = if len < 1.0 / 32.0 {
                    1
                } else if len < 0.25 {
                    2
                } else {
                    3
                };
                let by_bend = if bend > BEND_4 {
                    4
                } else if bend > BEND_3 {
                    3
                } else if bend > BEND_2 {
                    2
                } else {
                    1
                };
                by_len.max(by_bend)
            }
        }
    }
}

/// Gauss-Legendre nodes on [-1, 1] and weights, for 1 to 8 points.
pub fn gauss(n: usize) -> (&'static [f64], &'static [f64]) {
    const X6: [f64; 6] = [
        -0.932_469_514_203_152,
        -0.661_209_386_466_264_5,
        -0.238_619_186_083_196_9,
        0.238_619_186_083_196_9,
        0.661_209_386_466_264_5,
        0.932_469_514_203_152,
    ];
    const W6: [f64; 6] = [
        0.171_324_492_379_170_3,
        0.360_761_573_048_138_6,
        0.467_913_934_572_691_1,
        0.467_913_934_572_691_1,
        0.360_761_573_048_138_6,
        0.171_324_492_379_170_3,
    ];
    const X8: [f64; 8] = [
        -0.960_289_856_497_536_3,
        -0.796_666_477_413_626_7,
        -0.525_532_409_916_329,
        -0.183_434_642_495_649_8,
        0.183_434_642_495_649_8,
        0.525_532_409_916_329,
        0.796_666_477_413_626_7,
        0.960_289_856_497_536_3,
    ];
    const W8: [f64; 8] = [
        0.101_228_536_290_376_3,
        0.222_381_034_453_374_5,
        0.313_706_645_877_887_3,
        0.362_683_783_378_362,
        0.362_683_783_378_362,
        0.313_706_645_877_887_3,
        0.222_381_034_453_374_5,
        0.101_228_536_290_376_3,
    ];
    if n >= 7 {
        return (&X8, &W8);
    }
    if n >= 5 {
        return (&X6, &W6);
    }
    const X1: [f64; 1] = [0.0];
    const W1: [f64; 1] = [2.0];
    const X2: [f64; 2] = [-0.577_350_269_189_625_8, 0.577_350_269_189_625_8];
    const W2: [f64; 2] = [1.0, 1.0];
    const X3: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
    const W3: [f64; 3] = [
        0.555_555_555_555_555_6,
        0.888_888_888_888_889,
        0.555_555_555_555_555_6,
    ];
    const X4: [f64; 4] = [
        -0.861_136_311_594_052_6,
        -0.339_981_043_584_856_3,
        0.339_981_043_584_856_3,
        0.861_136_311_594_052_6,
    ];
    const W4: [f64; 4] = [
        0.347_854_845_137_453_9,
        0.652_145_154_862_546_1,
        0.652_145_154_862_546_1,
        0.347_854_845_137_453_9,
    ];
    match n {
        1 => (&X1, &W1),
        2 => (&X2, &W2),
        3 => (&X3, &W3),
        4 => (&X4, &W4),
        _ => (&X1, &W1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_rule_integrates_polynomials_of_its_degree_exactly() {
        for n in [1, 2, 3, 4, 6, 8] {
            let (xs, ws) = gauss(n);
            assert_eq!(xs.len(), n);
            // x^k over [-1, 1]: 0 for odd k, 2 / (k + 1) for even k, exact up to degree 2n - 1
            for k in 0..2 * n as i32 {
                let got: f64 = xs.iter().zip(ws).map(|(x, w)| w * x.powi(k)).sum();
                let want = if k % 2 == 1 {
                    0.0
                } else {
                    2.0 / f64::from(k + 1)
                };
                assert!((got - want).abs() < 1e-14, "n {n}, x^{k}: {got} {want}");
            }
        }
    }

    #[test]
    fn auto_takes_points_by_length_and_bend() {
        let q = Quadrature::Auto;
        assert_eq!(q.points(0.01, 0.0), 1);
        assert_eq!(q.points(0.1, 0.0), 2);
        assert_eq!(q.points(0.5, 0.0), 3);
        assert_eq!(Quadrature::Points(2).points(0.5, 0.0), 2);
        // a bent triangle takes more points however short the piece; a long piece keeps its 3
        assert_eq!(q.points(0.01, 0.02), 1);
        assert_eq!(q.points(0.01, 0.3), 2);
        assert_eq!(q.points(0.01, 0.7), 3);
        assert_eq!(q.points(0.01, 1.5), 4);
        assert_eq!(q.points(0.5, 0.3), 3);
        assert_eq!(q.points(0.5, 1.5), 4);
        assert_eq!(Quadrature::Points(1).points(0.01, 1.5), 1);
        assert_eq!(Quadrature::Points(4).points(0.001, 0.0), 4);
        // 5 and 7 points take the next even rule
        assert_eq!(gauss(5).0.len(), 6);
        assert_eq!(gauss(7).0.len(), 8);
    }
}
