//! Small matrix arithmetic in one fixed order of operations.
//!
//! The placements of the keyframe engine and of the accumulation buffer are products of 3x3
//! and 4x4 matrices, determinants and dot products. numpy computes these through BLAS and
//! LAPACK, whose results depend on the order in which each kernel sums its products and on
//! whether it fuses a multiplication with the following addition. The functions here fix one
//! order: the one numpy's OpenBLAS kernels use on x86-64 with fused multiply-adds (FMA), so a
//! placement computed here equals the numpy expression named in each function's doc bit for
//! bit on such a machine, and the tests of the Python layer can compare against numpy exactly.
//! `f64::mul_add` is exactly rounded on every platform (in hardware or in software), so the
//! results themselves do not depend on the machine.
//!
//! Matrices are row-major arrays of rows.
// Index loops over 3- and 4-vectors read better than iterator chains here.
#![allow(clippy::needless_range_loop)]

/// A 4x4 matrix, row-major (acting on column vectors: `p' = M p`).
pub type Mat4 = [[f64; 4]; 4];
/// A 3x3 matrix, row-major.
pub type Mat3 = [[f64; 3]; 3];

/// The 4x4 identity.
pub const IDENTITY4: Mat4 = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// `sum_i a[i] b[i]` as a chain of fused multiply-adds from 0, first index first
/// (`numpy.dot` of two float64 vectors).
#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0, |s, (x, y)| x.mul_add(*y, s))
}

/// The Euclidean length of `v` (`numpy.linalg.norm` of a float64 vector): the square root of
/// [`dot`]`(v, v)`.
#[inline]
pub fn norm(v: &[f64]) -> f64 {
    dot(v, v).sqrt()
}

/// `a @ b` of two 4x4 matrices (numpy's `matmul`): each entry a [`dot`] of a row and a column.
pub fn mat4_mul(a: &Mat4, b: &Mat4) -> Mat4 {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| (0..4).fold(0.0, |s, k| a[i][k].mul_add(b[k][j], s)))
    })
}

/// The 3x3 part of `m`.
pub fn linear_part(m: &Mat4) -> Mat3 {
    std::array::from_fn(|r| [m[r][0], m[r][1], m[r][2]])
}

/// The translation column of `m`.
pub fn translation_part(m: &Mat4) -> [f64; 3] {
    [m[0][3], m[1][3], m[2][3]]
}

/// `p @ l.T + t` for one point `p` (numpy's `points @ l.T + t`): per coordinate a [`dot`] of
/// the row of `l` with `p`, then `t` added.
#[inline]
pub fn place(l: &Mat3, t: &[f64; 3], p: &[f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| dot(&l[r], p) + t[r])
}

/// `p @ l.T` for one direction `p` (numpy's `directions @ l.T`).
#[inline]
pub fn turn(l: &Mat3, p: &[f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| dot(&l[r], p))
}

/// `l.T @ d` (numpy's `matmul` of a transposed 3x3 matrix and a vector): per coordinate a
/// [`dot`] of a column of `l` with `d`.
pub fn transpose_times(l: &Mat3, d: &[f64; 3]) -> [f64; 3] {
    std::array::from_fn(|j| dot(&[l[0][j], l[1][j], l[2][j]], d))
}

/// `p @ v` for one 3-vector row `p` of a row-major matrix (numpy's `matmul` of an (N,3)
/// matrix and a (3,) vector): the second product first, then the first and the third fused.
#[inline]
pub fn row_times(p: &[f64; 3], v: &[f64; 3]) -> f64 {
    p[2].mul_add(v[2], p[0].mul_add(v[0], p[1] * v[1]))
}

/// `a.T @ a` of a 3x3 matrix (numpy's `matmul`).
pub fn gram(a: &Mat3) -> Mat3 {
    std::array::from_fn(|i| {
        std::array::from_fn(|j| (0..3).fold(0.0, |s, k| a[k][i].mul_add(a[k][j], s)))
    })
}

/// The determinant of a 3x3 matrix as `numpy.linalg.det` computes it: LAPACK's LU
/// factorisation with partial pivoting (OpenBLAS's left-looking `getf2`: each column updated
/// by fused dot products of the columns before it, the pivot the first entry of largest
/// magnitude, the entries below it scaled by its reciprocal), then `sign * exp(sum of the logs
/// of |u_ii|)`. Singular matrices give 0. (So `det(2 I)` is `7.999999999999998`, as numpy.)
pub fn det3(a: &Mat3) -> f64 {
    let mut lu = *a;
    let mut pivots = [0usize; 3];
    for j in 0..3 {
        let mut b = [lu[0][j], lu[1][j], lu[2][j]];
        for (i, &p) in pivots.iter().enumerate().take(j) {
            b.swap(i, p);
        }
        // Solve with the unit lower factor above the diagonal, then update the rest.
        for i in 1..j {
            b[i] -= (0..i).fold(0.0, |s, k| lu[i][k].mul_add(b[k], s));
        }
        for r in j..3 {
            b[r] -= (0..j).fold(0.0, |s, k| lu[r][k].mul_add(b[k], s));
        }
        let mut p = j;
        for r in j + 1..3 {
            if b[r].abs() > b[p].abs() {
                p = r;
            }
        }
        pivots[j] = p;
        for r in 0..3 {
            lu[r][j] = b[r];
        }
        let pivot = lu[p][j];
        if pivot == 0.0 {
            return 0.0;
        }
        if p != j {
            for c in 0..=j {
                let tmp = lu[j][c];
                lu[j][c] = lu[p][c];
                lu[p][c] = tmp;
            }
        }
        if pivot.abs() >= f64::MIN_POSITIVE {
            let reciprocal = 1.0 / pivot;
            for r in j + 1..3 {
                lu[r][j] *= reciprocal;
            }
        } else {
            for r in j + 1..3 {
                lu[r][j] /= pivot;
            }
        }
    }
    let mut sign = 1.0;
    let mut log = 0.0;
    for i in 0..3 {
        if pivots[i] != i {
            sign = -sign;
        }
        let mut u = lu[i][i];
        if u < 0.0 {
            sign = -sign;
            u = -u;
        }
        log += u.ln();
    }
    sign * log.exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact 3x3 determinant by cofactors of small integers (no rounding below 2^53).
    fn exact(a: &Mat3) -> f64 {
        a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
    }

    #[test]
    fn det_is_numpys_exp_of_log_sum() {
        let two = [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]];
        assert_eq!(det3(&two), 7.999999999999998); // numpy.linalg.det(2 * eye(3))
        let id = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(det3(&id), 1.0);
        assert_eq!(
            det3(&[[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 1.0, 1.0]]),
            0.0
        );
        // integer matrices: within a few ulps of the exact value, with its sign
        let mut seed = 7u64;
        for _ in 0..500 {
            let m: Mat3 = std::array::from_fn(|_| {
                std::array::from_fn(|_| {
                    seed = seed
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    ((seed >> 33) % 19) as f64 - 9.0
                })
            });
            let (got, want) = (det3(&m), exact(&m));
            assert!(
                (got - want).abs() <= 1e-13 * want.abs(),
                "{m:?}: {got} vs {want}"
            );
        }
        // a row swap changes the sign only
        let a = [[0.0, 2.0, 1.0], [3.0, 0.5, 0.0], [1.0, 1.0, 4.0]];
        let b = [a[1], a[0], a[2]];
        assert_eq!(det3(&a), -det3(&b));
    }

    #[test]
    fn products_follow_their_definitions() {
        let a: Mat4 = std::array::from_fn(|i| std::array::from_fn(|j| (i * 4 + j) as f64 - 5.0));
        let b: Mat4 = std::array::from_fn(|i| std::array::from_fn(|j| (j * 3 + i) as f64 * 0.5));
        let c = mat4_mul(&a, &b);
        for i in 0..4 {
            for j in 0..4 {
                let want: f64 = (0..4).map(|k| a[i][k] * b[k][j]).sum();
                assert_eq!(c[i][j], want); // small integers and halves: exact
            }
        }
        assert_eq!(mat4_mul(&IDENTITY4, &a), a);
        let l = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 10.0]];
        assert_eq!(
            place(&l, &[1.0, 0.0, -1.0], &[1.0, 1.0, 1.0]),
            [7.0, 15.0, 24.0]
        );
        assert_eq!(turn(&l, &[1.0, 0.0, 0.0]), [1.0, 4.0, 7.0]);
        assert_eq!(transpose_times(&l, &[1.0, 0.0, 0.0]), [1.0, 2.0, 3.0]);
        assert_eq!(row_times(&[1.0, 2.0, 3.0], &[1.0, 1.0, 2.0]), 9.0);
        let g = gram(&l);
        assert_eq!(g[0][1], 1.0 * 2.0 + 4.0 * 5.0 + 7.0 * 8.0);
        assert_eq!(g[1][0], g[0][1]);
        assert_eq!(norm(&[3.0, 4.0, 0.0, 12.0]), 13.0);
    }

    #[test]
    fn a_dot_fuses_each_product_with_the_running_sum() {
        // 1 + e and 1 - e multiply to 1 - e^2: added to -1 in one fused step the e^2 stays,
        // where a rounded product (1) would lose it; the first product is rounded alone.
        let e = f64::EPSILON;
        assert_eq!(dot(&[-1.0, 1.0 + e], &[1.0, 1.0 - e]), -e * e);
        assert_eq!(dot(&[1.0 + e, -1.0], &[1.0 - e, 1.0]), 0.0);
    }
}
