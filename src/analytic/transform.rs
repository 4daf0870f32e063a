//! Many points under one 4x4 matrix, summed in the order the method's straddle has always
//! summed them (`straddled` in `python/motionblur/methods/analytic.py`, once numpy's `einsum`
//! order for four terms: the even terms and the odd terms first, then their sum), so that the
//! boundaries it moves keep their bits whichever side computes them.
use glam::DMat4;
use rayon::prelude::*;

/// Points per parallel job.
const CHUNK: usize = 4096;

/// Writes into `out` (`V` rows of 4, row-major) the points `points` (`V` rows of `dim` 3 or 4 values, row-major;
/// `dim` 3 means `w = 1`) transformed by `m`: component `j` is
/// `(x m[j][0] + z m[j][2]) + (y m[j][1] + w m[j][3])` (`m[j][i]` the row-`j`, column-`i`
/// element; with `dim` 3 the last product is `m[j][3]` itself, which `1 * m[j][3]` is exactly).
/// Each point alone: the result does not depend on the thread count.
///
/// # Panics
/// When `dim` is not 3 or 4, or `points` and `out` do not hold as many rows.
pub fn transform_points(m: &DMat4, points: &[f64], dim: usize, out: &mut [f64]) {
    assert!(dim == 3 || dim == 4, "dim must be 3 or 4");
    assert!(out.len() % 4 == 0, "out must hold rows of 4");
    assert_eq!(
        points.len() / dim,
        out.len() / 4,
        "points and out must hold as many rows"
    );
    assert_eq!(points.len() % dim, 0, "points must hold rows of dim");
    let c = [m.x_axis, m.y_axis, m.z_axis, m.w_axis].map(|a| a.to_array());
    out.par_chunks_mut(CHUNK * 4)
        .zip(points.par_chunks(CHUNK * dim))
        .for_each(|(o, p)| {
            for (q, r) in o.chunks_exact_mut(4).zip(p.chunks_exact(dim)) {
                for j in 0..4 {
                    let even = r[0] * c[0][j] + r[2] * c[2][j];
                    let w = if dim == 4 { r[3] * c[3][j] } else { c[3][j] };
                    q[j] = even + (r[1] * c[1][j] + w);
                }
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The numpy steps of `_Transform.__call__`, one array operation at a time, as the oracle.
    fn numpy_steps(m: &[[f64; 4]; 4], p: &[f64], dim: usize) -> [f64; 4] {
        let mut out = [0.0; 4];
        for j in 0..4 {
            let mut o = p[0] * m[j][0];
            let tmp = p[2] * m[j][2];
            o += tmp;
            let mut odd = p[1] * m[j][1];
            if dim == 4 {
                let tmp = p[3] * m[j][3];
                odd += tmp;
            } else {
                odd += m[j][3];
            }
            o += odd;
            out[j] = o;
        }
        out
    }

    #[test]
    fn every_component_has_the_numpy_steps_bits() {
        let rows = [
            [0.31, -1.7, 2.9, 0.5],
            [1e-3, 0.77, -0.4, 3.25],
            [-2.2, 0.1, 1.0 / 3.0, -0.9],
            [0.0, 0.0, -1.0, 1e-7],
        ];
        let m = DMat4::from_cols_array_2d(&rows).transpose();
        for dim in [3, 4] {
            let n = 3 * CHUNK + 17; // several jobs and a ragged last one
            let points: Vec<f64> = (0..n * dim)
                .map(|i| ((i as f64) * 0.618_033_988_7).sin() * 10f64.powi((i % 7) as i32 - 3))
                .collect();
            let mut out = vec![0.0; 4 * n];
            transform_points(&m, &points, dim, &mut out);
            for (q, p) in out.chunks_exact(4).zip(points.chunks_exact(dim)) {
                let want = numpy_steps(&rows, p, dim);
                let got: Vec<u64> = q.iter().map(|x| x.to_bits()).collect();
                assert_eq!(got, want.map(f64::to_bits));
            }
        }
    }

    #[test]
    fn three_columns_are_points_with_w_one() {
        let m = DMat4::from_cols_array(&[
            1.5, 0.2, -0.3, 0.0, 0.1, 0.9, 0.4, 0.0, -0.7, 0.25, 1.1, 0.0, 3.0, -2.0, 0.5, 1.0,
        ]);
        let p3 = [0.3, -0.8, 2.5, 1.25, 0.5, -0.75];
        let p4 = [0.3, -0.8, 2.5, 1.0, 1.25, 0.5, -0.75, 1.0];
        let (mut a, mut b) = ([0.0; 8], [0.0; 8]);
        transform_points(&m, &p3, 3, &mut a);
        transform_points(&m, &p4, 4, &mut b);
        assert_eq!(a, b);
    }
}
