//! One rigid keyframe split into translation, rotation and scale, and the interpolation
//! between two of them: translation and scale linear, rotation spherical on the shorter arc.
//!
//! A keyframe is a similarity `p' = s R p + t`: a rotation `R` times a positive uniform scale
//! `s`, plus a translation `t`. It is validated and split once, when it is made; interpolation
//! works on the parts and builds the matrix of the result from them. The arithmetic is that of
//! the same formulas written in numpy, operation for operation (the products and the
//! determinant in [`numeric`](super::numeric)'s fixed order), so the tests' numpy twin
//! (`tests/_helpers/motion_twin.py`) gives the same transforms.
// Index loops over 3- and 4-vectors read better than iterator chains here.
#![allow(clippy::needless_range_loop)]
use super::numeric::{
    det3, dot, gram, linear_part, norm, row_times, translation_part, Mat3, Mat4, IDENTITY4,
};
use crate::error::{Error, Result};
use crate::mesh::MAX_COORD;

/// Largest deviation of `R^T R` from the identity accepted for a rotation (the 3x3 part
/// divided by the cube root of its determinant).
pub const RIGID_TOLERANCE: f64 = 1e-6;

/// Smallest and largest accepted uniform scale of a keyframe: `1 / MAX_COORD` to `MAX_COORD`.
/// A unit object scaled by them stays within the coordinate range (and is not shrunk below its
/// rounding), and the determinant `s^3` that splits the scale off stays a normal float64.
pub const MIN_SCALE: f64 = 1.0 / MAX_COORD;
/// See [`MIN_SCALE`].
pub const MAX_SCALE: f64 = MAX_COORD;

/// Above this cosine between two unit quaternions (half-angles below 1.4e-6 rad, equal
/// rotations among them) the interpolation is the normalised linear one: it equals the slerp
/// there to rounding (they differ by the cube of the angle), while the slerp's weights would
/// divide by a vanishing sine.
const NEARLY_EQUAL: f64 = 1.0 - 1e-12;

/// A rigid keyframe: its matrix and that matrix split into parts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Similarity {
    /// The 4x4 matrix, row-major (as given, or built from the parts when interpolated).
    pub matrix: Mat4,
    /// The translation `t`.
    pub translation: [f64; 3],
    /// The rotation `R` as a unit quaternion `(w, x, y, z)`.
    pub rotation: [f64; 4],
    /// The uniform scale `s > 0`.
    pub scale: f64,
}

/// The allowed deviation of a last-row entry from its target (numpy's `allclose` defaults).
fn near(x: f64, target: f64) -> bool {
    (x - target).abs() <= 1e-12 + 1e-5 * target.abs()
}

/// `x` as `printf("%g")` writes it: 6 significant digits, exponent form outside [1e-4, 1e6).
pub(crate) fn general(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let sci = format!("{x:.5e}");
    let (mantissa, exp) = sci.split_once('e').expect("exponent form");
    let exp: i32 = exp.parse().expect("integer exponent");
    let trim = |s: &str| -> String {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s.to_string()
        }
    };
    if (-4..6).contains(&exp) {
        trim(&format!("{x:.*}", (5 - exp) as usize))
    } else {
        let sign = if exp < 0 { '-' } else { '+' };
        format!("{}e{sign}{:02}", trim(mantissa), exp.abs())
    }
}

impl Similarity {
    /// Validates and splits a 4x4 matrix: finite, last row `[0, 0, 0, 1]` (within 1e-12, and
    /// 1e-5 relative for the 1), a positive determinant, and the 3x3 part divided by the cube
    /// root of its determinant a rotation within `RIGID_TOLERANCE` (1e-6). Errors name `name` and
    /// the keyframe `index`.
    pub fn from_matrix(m: &Mat4, name: &'static str, index: usize) -> Result<Self> {
        if m.iter().flatten().any(|x| !x.is_finite()) {
            return Err(Error::value(
                name,
                format!("keyframe {index} is NaN or inf"),
            ));
        }
        if !(0..4).all(|c| near(m[3][c], if c == 3 { 1.0 } else { 0.0 })) {
            return Err(Error::value(
                name,
                format!("keyframe {index}: last row must be [0, 0, 0, 1]"),
            ));
        }
        let lin = linear_part(m);
        // The range first, from the columns' lengths (a rigid keyframe's are all the scale): a
        // scale past it would make the determinant overflow or underflow and the messages below
        // speak of shear or mirrors.
        let lengths = (0..3).map(|c| (0..3).map(|r| lin[r][c] * lin[r][c]).sum::<f64>().sqrt());
        let (lo, hi) = lengths.fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
        let slack = 1.0 + RIGID_TOLERANCE;
        if lo > 0.0 && (hi > MAX_SCALE * slack || lo < MIN_SCALE / slack) {
            let s = if hi > MAX_SCALE * slack { hi } else { lo };
            return Err(Error::value(
                name,
                format!(
                    "keyframe {index} scales by about {}, outside the accepted uniform scales \
                     [{}, {}] (1/MAX_COORD to MAX_COORD: scaled coordinates must stay in the \
                     coordinate range +-{}, and the scale is split off through the determinant)",
                    general(s),
                    general(MIN_SCALE),
                    general(MAX_SCALE),
                    general(MAX_COORD)
                ),
            ));
        }
        let t = translation_part(m);
        if t.iter().any(|x| x.abs() > MAX_COORD) {
            return Err(Error::value(
                name,
                format!(
                    "keyframe {index} translates by {t:?}, beyond the coordinate range +-{} \
                     (MAX_COORD)",
                    general(MAX_COORD)
                ),
            ));
        }
        let det = det3(&lin);
        if det <= 0.0 {
            return Err(Error::value(
                name,
                format!(
                    "keyframe {index} is not rigid (determinant {} <= 0: mirror or singular)",
                    general(det)
                ),
            ));
        }
        let scale = det.powf(1.0 / 3.0);
        let r: Mat3 = lin.map(|row| row.map(|x| x / scale));
        let g = gram(&r);
        let deviation = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| (g[i][j] - if i == j { 1.0 } else { 0.0 }).abs())
            .fold(0.0, f64::max);
        if deviation > RIGID_TOLERANCE {
            return Err(Error::value(
                name,
                format!(
                    "keyframe {index} is not rigid (rotation times a positive uniform scale); \
                     shear and non-uniform scale are not supported"
                ),
            ));
        }
        Ok(Similarity {
            matrix: *m,
            translation: translation_part(m),
            rotation: quaternion(&r),
            scale,
        })
    }

    /// The pure translation by `t` (identity rotation, scale 1).
    pub fn translate(t: [f64; 3]) -> Self {
        let mut matrix = IDENTITY4;
        for r in 0..3 {
            matrix[r][3] = t[r];
        }
        Similarity {
            matrix,
            translation: t,
            rotation: [1.0, 0.0, 0.0, 0.0],
            scale: 1.0,
        }
    }

    /// The keyframe a fraction `u` of the way to `other`: translation and scale
    /// `(1 - u) a + u b`, rotation spherically interpolated on the shorter arc (normalised
    /// linear interpolation, equal to it to rounding, for rotations within `NEARLY_EQUAL` (1 - 1e-12) in
    /// cosine). `u = 0` gives this keyframe itself.
    pub fn interpolate(&self, other: &Similarity, u: f64) -> Similarity {
        if u == 0.0 {
            return *self;
        }
        let v = 1.0 - u;
        let scale = v * self.scale + u * other.scale;
        let q = slerp(&self.rotation, &other.rotation, u);
        let n = norm(&q);
        let rotation = q.map(|x| x / n);
        let translation: [f64; 3] =
            std::array::from_fn(|i| v * self.translation[i] + u * other.translation[i]);
        let r = rotation_matrix(&rotation);
        let mut matrix = IDENTITY4;
        for i in 0..3 {
            for j in 0..3 {
                matrix[i][j] = scale * r[i][j];
            }
            matrix[i][3] = translation[i];
        }
        Similarity {
            matrix,
            translation,
            rotation,
            scale,
        }
    }
}

/// The rotation by `angle` radians (right hand) about `axis` (non-zero, any length) through
/// `center`, as a 4x4 matrix: the axis normalised, the half-angle quaternion normalised and
/// turned into a matrix, the translation `center - R center`.
pub fn axis_angle(angle: f64, axis: [f64; 3], center: [f64; 3]) -> Mat4 {
    let n = norm(&axis);
    let a = axis.map(|x| x / n);
    let (s, c) = ((angle / 2.0).sin(), (angle / 2.0).cos());
    let q = [c, s * a[0], s * a[1], s * a[2]];
    let nq = norm(&q);
    let r = rotation_matrix(&q.map(|x| x / nq));
    let mut m = IDENTITY4;
    for i in 0..3 {
        m[i][..3].copy_from_slice(&r[i]);
        m[i][3] = center[i] - row_times(&r[i], &center);
    }
    m
}

/// The unit quaternion `(w, x, y, z)` of a rotation matrix (Shepperd's method: the largest of
/// the trace and the diagonal entries chooses the formula), normalised.
fn quaternion(r: &Mat3) -> [f64; 4] {
    let tr = r[0][0] + r[1][1] + r[2][2];
    let q = if tr > 0.0 {
        let s = (tr + 1.0).sqrt() * 2.0;
        [
            0.25 * s,
            (r[2][1] - r[1][2]) / s,
            (r[0][2] - r[2][0]) / s,
            (r[1][0] - r[0][1]) / s,
        ]
    } else if r[0][0] > r[1][1] && r[0][0] > r[2][2] {
        let s = (1.0 + r[0][0] - r[1][1] - r[2][2]).sqrt() * 2.0;
        [
            (r[2][1] - r[1][2]) / s,
            0.25 * s,
            (r[0][1] + r[1][0]) / s,
            (r[0][2] + r[2][0]) / s,
        ]
    } else if r[1][1] > r[2][2] {
        let s = (1.0 + r[1][1] - r[0][0] - r[2][2]).sqrt() * 2.0;
        [
            (r[0][2] - r[2][0]) / s,
            (r[0][1] + r[1][0]) / s,
            0.25 * s,
            (r[1][2] + r[2][1]) / s,
        ]
    } else {
        let s = (1.0 + r[2][2] - r[0][0] - r[1][1]).sqrt() * 2.0;
        [
            (r[1][0] - r[0][1]) / s,
            (r[0][2] + r[2][0]) / s,
            (r[1][2] + r[2][1]) / s,
            0.25 * s,
        ]
    };
    let n = norm(&q);
    q.map(|x| x / n)
}

/// Spherical interpolation of unit quaternions on the shorter arc (not normalised).
fn slerp(q0: &[f64; 4], q1: &[f64; 4], u: f64) -> [f64; 4] {
    let mut d = dot(q0, q1);
    let mut q1 = *q1;
    if d < 0.0 {
        q1 = q1.map(|x| -x);
        d = -d;
    }
    if d > NEARLY_EQUAL {
        let q: [f64; 4] = std::array::from_fn(|i| q0[i] + u * (q1[i] - q0[i]));
        let n = norm(&q);
        return q.map(|x| x / n);
    }
    let theta = if d < 1.0 { d } else { 1.0 }.acos();
    let s = theta.sin();
    let (a, b) = (((1.0 - u) * theta).sin(), (u * theta).sin());
    std::array::from_fn(|i| (a * q0[i] + b * q1[i]) / s)
}

/// The rotation matrix of a unit quaternion `(w, x, y, z)`.
fn rotation_matrix(q: &[f64; 4]) -> Mat3 {
    let [w, x, y, z] = *q;
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_and_translations_outside_the_range_say_which_range() {
        let scaled = |s: f64| {
            let mut m = IDENTITY4;
            (0..3).for_each(|i| m[i][i] = s);
            m
        };
        for s in [1e-120, 1e-10, 2e9, 1e120] {
            let e = Similarity::from_matrix(&scaled(s), "m", 1)
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("m: keyframe 1 scales by about"), "{e}");
            assert!(e.contains("[1e-09, 1e+09]"), "{e}");
        }
        for s in [MIN_SCALE, 1e-3, 1e3, MAX_SCALE] {
            let k = Similarity::from_matrix(&scaled(s), "m", 0).unwrap();
            assert!((k.scale / s - 1.0).abs() < 1e-12);
        }
        let mut far = IDENTITY4;
        far[1][3] = -2.0 * MAX_COORD;
        let e = Similarity::from_matrix(&far, "m", 2)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("m: keyframe 2 translates by") && e.contains("coordinate range"),
            "{e}"
        );
        // a mirror inside the range is still a mirror
        let e = Similarity::from_matrix(&scaled(-2.0), "m", 0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("mirror or singular"), "{e}");
    }

    fn rot_z(a: f64, s: f64, t: [f64; 3]) -> Mat4 {
        let (sn, c) = a.sin_cos();
        [
            [s * c, -s * sn, 0.0, t[0]],
            [s * sn, s * c, 0.0, t[1]],
            [0.0, 0.0, s, t[2]],
            [0.0, 0.0, 0.0, 1.0],
        ]
    }

    #[test]
    fn splits_a_similarity_into_its_parts() {
        let k = Similarity::from_matrix(&rot_z(0.8, 2.0, [1.0, -2.0, 3.0]), "m", 0).unwrap();
        assert!((k.scale - 2.0).abs() < 1e-15);
        assert_eq!(k.translation, [1.0, -2.0, 3.0]);
        let half = [(0.4f64).cos(), 0.0, 0.0, (0.4f64).sin()];
        for i in 0..4 {
            assert!((k.rotation[i] - half[i]).abs() < 1e-15);
        }
        let id = Similarity::from_matrix(&super::IDENTITY4, "m", 0).unwrap();
        assert_eq!(id, Similarity::translate([0.0; 3]));
    }

    #[test]
    fn interpolates_on_the_shorter_arc_and_lerps_scale_and_translation() {
        let a = Similarity::from_matrix(&rot_z(0.0, 1.0, [0.0; 3]), "m", 0).unwrap();
        let b = Similarity::from_matrix(&rot_z(2.0, 3.0, [4.0, 0.0, 0.0]), "m", 1).unwrap();
        let m = a.interpolate(&b, 0.25);
        let want = rot_z(0.5, 1.5, [1.0, 0.0, 0.0]);
        for i in 0..4 {
            for j in 0..4 {
                assert!((m.matrix[i][j] - want[i][j]).abs() < 1e-14, "{i} {j}");
            }
        }
        // 350 degrees one way is 10 degrees the other way
        let c =
            Similarity::from_matrix(&rot_z(-10f64.to_radians(), 1.0, [0.0; 3]), "m", 1).unwrap();
        let d =
            Similarity::from_matrix(&rot_z(340f64.to_radians(), 1.0, [0.0; 3]), "m", 1).unwrap();
        let half = c.interpolate(&d, 0.5).matrix;
        let want = rot_z(-15f64.to_radians(), 1.0, [0.0; 3]);
        assert!((half[0][1] - want[0][1]).abs() < 1e-14);
        assert_eq!(a.interpolate(&b, 0.0), a);
        // small rotations are slerped: the angle is linear in u (a normalised lerp would be
        // 1e-6 rad off here)
        let e = Similarity::from_matrix(&rot_z(0.06, 1.0, [0.0; 3]), "m", 1).unwrap();
        let m = a.interpolate(&e, 0.2).matrix;
        assert!(
            (m[1][0] - (0.012f64).sin()).abs() < 1e-15,
            "{}",
            m[1][0] - (0.012f64).sin()
        );
        // equal rotations interpolate to themselves
        let r = Similarity::from_matrix(&rot_z(0.3, 1.0, [0.0; 3]), "m", 0).unwrap();
        let s = Similarity::from_matrix(&rot_z(0.3, 1.0, [1.0, 0.0, 0.0]), "m", 1).unwrap();
        let h = r.interpolate(&s, 0.5);
        for i in 0..3 {
            for j in 0..3 {
                assert!((h.matrix[i][j] - r.matrix[i][j]).abs() < 1e-15);
            }
        }
        // translations stay exact where the parts are exact
        let t = Similarity::translate([0.0; 3])
            .interpolate(&Similarity::translate([3.0, 0.0, 0.0]), 0.5);
        assert_eq!(t, Similarity::translate([1.5, 0.0, 0.0]));
    }

    #[test]
    fn rejects_mirrors_shear_bad_rows_and_nan_naming_the_keyframe() {
        let mut m = rot_z(0.3, 1.0, [0.0; 3]);
        m[0] = m[0].map(|x| -x);
        let e = Similarity::from_matrix(&m, "transforms", 2).unwrap_err();
        assert!(e
            .to_string()
            .starts_with("transforms: keyframe 2 is not rigid (determinant -1"));
        let mut s = rot_z(0.0, 1.0, [0.0; 3]);
        s[0][1] = 0.5;
        assert!(Similarity::from_matrix(&s, "m", 0)
            .unwrap_err()
            .to_string()
            .contains("shear"));
        let mut r = rot_z(0.0, 1.0, [0.0; 3]);
        r[3][0] = 1e-9;
        assert!(Similarity::from_matrix(&r, "m", 0)
            .unwrap_err()
            .to_string()
            .contains("last row"));
        r[3][0] = 1e-13; // within numpy's allclose
        assert!(Similarity::from_matrix(&r, "m", 0).is_ok());
        let mut n = rot_z(0.0, 1.0, [0.0; 3]);
        n[1][3] = f64::NAN;
        assert!(Similarity::from_matrix(&n, "m", 0)
            .unwrap_err()
            .to_string()
            .contains("NaN"));
        let zero = [[0.0; 4], [0.0; 4], [0.0; 4], [0.0, 0.0, 0.0, 1.0]];
        assert!(Similarity::from_matrix(&zero, "m", 0)
            .unwrap_err()
            .to_string()
            .contains("determinant 0 <= 0"));
    }

    #[test]
    fn general_format_matches_printf() {
        assert_eq!(general(-1.0), "-1");
        assert_eq!(general(0.0), "0");
        assert_eq!(general(-0.125), "-0.125");
        assert_eq!(general(-1234567.0), "-1.23457e+06");
        assert_eq!(general(-2.5e-7), "-2.5e-07");
        assert_eq!(general(-0.999999999), "-1");
    }
}
