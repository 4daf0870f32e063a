//! Rigid keyframes over the shutter: validation, point and normal transforms, subdivision.
//!
//! A [`Path`] holds `n + 1` keyframes at the equally spaced shutter times `i / n`. Each keyframe
//! maps the mesh's given vertices to their placement at that time, `p' = L p + t`, where `L` is
//! a rotation times a positive uniform scale (a similarity; mirrors and shear are rejected).
//! A translation `m` is the path `[identity, translate(m)]`: the given vertices sit at shutter
//! open and arrive at `v + m` at shutter close.
use glam::{DMat3, DQuat, DVec3};

use crate::error::{Error, Result};

/// One rigid placement `p' = linear * p + translation` (`linear` row-major).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Keyframe {
    /// Rotation times uniform scale, row-major.
    pub linear: [[f64; 3]; 3],
    /// Translation (scene units).
    pub translation: [f64; 3],
}

const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

impl Keyframe {
    /// The pure translation by `t`.
    pub fn translate(t: [f64; 3]) -> Self {
        Keyframe {
            linear: IDENTITY,
            translation: t,
        }
    }

    /// From a row-major 4x4 matrix: finite, last row `[0, 0, 0, 1]`, and a similarity with a
    /// positive determinant. `index` names the keyframe in errors about `motion`.
    pub fn from_matrix(m: &[[f64; 4]; 4], index: usize) -> Result<Self> {
        if m.iter().flatten().any(|x| !x.is_finite()) {
            return Err(Error::value(
                "motion",
                format!("keyframe {index} is NaN or inf"),
            ));
        }
        if m[3] != [0.0, 0.0, 0.0, 1.0] {
            return Err(Error::value(
                "motion",
                format!("keyframe {index}: last row must be [0, 0, 0, 1]"),
            ));
        }
        let linear = [
            [m[0][0], m[0][1], m[0][2]],
            [m[1][0], m[1][1], m[1][2]],
            [m[2][0], m[2][1], m[2][2]],
        ];
        let k = Keyframe {
            linear,
            translation: [m[0][3], m[1][3], m[2][3]],
        };
        let det = k.mat3().determinant();
        if det.is_nan() || det <= 0.0 {
            return Err(Error::value(
                "motion",
                format!(
                    "keyframe {index}: the 3x3 part must have a positive determinant (no mirror)"
                ),
            ));
        }
        // Similarity: L^T L = s^2 I.
        let ltl = k.mat3().transpose() * k.mat3();
        let s2 = (ltl.x_axis.x + ltl.y_axis.y + ltl.z_axis.z) / 3.0;
        let off = (ltl - DMat3::from_diagonal(DVec3::splat(s2))).to_cols_array();
        if off.iter().any(|x| x.abs() > 1e-6 * s2) {
            return Err(Error::value(
                "motion",
                format!("keyframe {index}: must be rigid (rotation, uniform scale, translation)"),
            ));
        }
        Ok(k)
    }

    /// The 3x3 part as a glam matrix (column-major storage).
    pub fn mat3(&self) -> DMat3 {
        DMat3::from_cols_array_2d(&self.linear).transpose()
    }

    /// Whether `linear` is exactly the identity.
    pub fn has_identity_linear(&self) -> bool {
        self.linear == IDENTITY
    }

    /// The placement of a point. With an identity 3x3 part this is exactly `p + t`.
    #[inline]
    pub fn point(&self, p: [f64; 3]) -> [f64; 3] {
        let t = self.translation;
        if self.has_identity_linear() {
            return [p[0] + t[0], p[1] + t[1], p[2] + t[2]];
        }
        let l = &self.linear;
        [
            l[0][0] * p[0] + l[0][1] * p[1] + l[0][2] * p[2] + t[0],
            l[1][0] * p[0] + l[1][1] * p[1] + l[1][2] * p[2] + t[1],
            l[2][0] * p[0] + l[2][1] * p[1] + l[2][2] * p[2] + t[2],
        ]
    }

    /// The linear part applied to a direction.
    #[inline]
    pub fn vector(&self, p: [f64; 3]) -> [f64; 3] {
        if self.has_identity_linear() {
            return p;
        }
        let l = &self.linear;
        [
            l[0][0] * p[0] + l[0][1] * p[1] + l[0][2] * p[2],
            l[1][0] * p[0] + l[1][1] * p[1] + l[1][2] * p[2],
            l[2][0] * p[0] + l[2][1] * p[1] + l[2][2] * p[2],
        ]
    }

    /// A direction given in world space, brought back to object space (`L^-1 d`).
    pub fn inverse_vector(&self, d: [f64; 3]) -> [f64; 3] {
        if self.has_identity_linear() {
            return d;
        }
        self.mat3()
            .inverse()
            .mul_vec3(DVec3::from_array(d))
            .to_array()
    }

    /// A normal (up to length) in world space: for a similarity, `L n` has the right direction.
    #[inline]
    pub fn normal(&self, n: [f64; 3]) -> [f64; 3] {
        self.vector(n)
    }

    fn decompose(&self) -> (f64, DQuat) {
        let m = self.mat3();
        let s = m.determinant().cbrt();
        (s, DQuat::from_mat3(&(m * (1.0 / s))).normalize())
    }

    /// Interpolation between two keyframes at `u` in [0, 1]: translation and scale linear,
    /// rotation by spherical linear interpolation. `u = 0` and `u = 1` return the ends exactly.
    pub fn interpolate(&self, other: &Keyframe, u: f64) -> Keyframe {
        if u <= 0.0 {
            return *self;
        }
        if u >= 1.0 {
            return *other;
        }
        let t0 = DVec3::from_array(self.translation);
        let t1 = DVec3::from_array(other.translation);
        let translation = t0.lerp(t1, u).to_array();
        if self.linear == other.linear {
            return Keyframe {
                linear: self.linear,
                translation,
            };
        }
        let (s0, q0) = self.decompose();
        let (s1, q1) = other.decompose();
        let m = DMat3::from_quat(q0.slerp(q1, u)) * (s0 + (s1 - s0) * u);
        Keyframe {
            linear: m.transpose().to_cols_array_2d(),
            translation,
        }
    }
}

/// A keyframe with its identity test made once: [`Placer::point`] gives exactly
/// [`Keyframe::point`]'s values without comparing the 3x3 part at every point.
#[derive(Debug, Clone, Copy)]
pub struct Placer {
    key: Keyframe,
    identity: bool,
}

impl Placer {
    #[inline]
    pub fn point(&self, p: [f64; 3]) -> [f64; 3] {
        let t = self.key.translation;
        if self.identity {
            return [p[0] + t[0], p[1] + t[1], p[2] + t[2]];
        }
        let l = &self.key.linear;
        [
            l[0][0] * p[0] + l[0][1] * p[1] + l[0][2] * p[2] + t[0],
            l[1][0] * p[0] + l[1][1] * p[1] + l[1][2] * p[2] + t[1],
            l[2][0] * p[0] + l[2][1] * p[1] + l[2][2] * p[2] + t[2],
        ]
    }
}

impl Placer {
    /// Exactly [`Keyframe::normal`].
    #[inline]
    pub fn normal(&self, p: [f64; 3]) -> [f64; 3] {
        if self.identity {
            return p;
        }
        let l = &self.key.linear;
        [
            l[0][0] * p[0] + l[0][1] * p[1] + l[0][2] * p[2],
            l[1][0] * p[0] + l[1][1] * p[1] + l[1][2] * p[2],
            l[2][0] * p[0] + l[2][1] * p[1] + l[2][2] * p[2],
        ]
    }
}

impl Keyframe {
    /// This keyframe as a [`Placer`].
    pub(crate) fn placer(&self) -> Placer {
        Placer {
            key: *self,
            identity: self.has_identity_linear(),
        }
    }
}

/// Keyframes at the equally spaced shutter times `i / (len - 1)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Path {
    /// The keyframes, shutter open to close (at least two).
    pub frames: Vec<Keyframe>,
}

impl Path {
    /// The translation `m` over the shutter: `[identity, translate(m)]`.
    pub fn translation(m: [f64; 3]) -> Result<Self> {
        if m.iter().any(|x| !x.is_finite()) {
            return Err(Error::value("motion", "is NaN or inf"));
        }
        Ok(Path {
            frames: vec![Keyframe::translate([0.0; 3]), Keyframe::translate(m)],
        })
    }

    /// From `n + 1 >= 2` row-major 4x4 matrices.
    pub fn from_matrices(mats: &[[[f64; 4]; 4]]) -> Result<Self> {
        if mats.len() < 2 {
            return Err(Error::shape("motion", "needs at least 2 keyframes"));
        }
        let frames = mats
            .iter()
            .enumerate()
            .map(|(i, m)| Keyframe::from_matrix(m, i))
            .collect::<Result<Vec<_>>>()?;
        Ok(Path { frames })
    }

    /// Number of segments (keyframe intervals).
    pub fn segments(&self) -> usize {
        self.frames.len() - 1
    }

    /// Every interval cut into `parts` equal sub-intervals (interpolated keyframes).
    pub fn subdivide(&self, parts: usize) -> Path {
        if parts <= 1 {
            return self.clone();
        }
        let mut frames = Vec::with_capacity(self.segments() * parts + 1);
        for w in self.frames.windows(2) {
            frames.push(w[0]);
            for j in 1..parts {
                frames.push(w[0].interpolate(&w[1], j as f64 / parts as f64));
            }
        }
        frames.push(*self.frames.last().expect("at least two keyframes"));
        Path { frames }
    }

    /// The placement at shutter time `t` in [0, 1]: keyframe interpolation inside its interval.
    pub fn at(&self, t: f64) -> Keyframe {
        let n = self.segments();
        let x = t.clamp(0.0, 1.0) * n as f64;
        let j = (x.floor() as usize).min(n - 1);
        self.frames[j].interpolate(&self.frames[j + 1], x - j as f64)
    }

    /// Whether every keyframe equals the first (no motion at all).
    pub fn is_static(&self) -> bool {
        self.frames.iter().all(|k| *k == self.frames[0])
    }

    /// Whether every keyframe has the same 3x3 part (a pure translation path).
    pub fn is_translation(&self) -> bool {
        self.frames
            .iter()
            .all(|k| k.linear == self.frames[0].linear)
    }

    /// Motion vectors of the segments, in world units: the difference of the translations for a
    /// translation path (exact for `[identity, translate(m)]`), else the displacement of `pivot`.
    pub fn segment_vectors(&self, pivot: [f64; 3]) -> Vec<[f64; 3]> {
        let pure = self.is_translation();
        self.frames
            .windows(2)
            .map(|w| {
                let (p, q) = if pure {
                    (w[0].translation, w[1].translation)
                } else {
                    (w[0].point(pivot), w[1].point(pivot))
                };
                [q[0] - p[0], q[1] - p[1], q[2] - p[2]]
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rot_z(a: f64, t: [f64; 3]) -> [[f64; 4]; 4] {
        let (s, c) = a.sin_cos();
        [
            [c, -s, 0.0, t[0]],
            [s, c, 0.0, t[1]],
            [0.0, 0.0, 1.0, t[2]],
            [0.0, 0.0, 0.0, 1.0],
        ]
    }

    #[test]
    fn translation_points_are_exact() {
        let p = Path::translation([0.1, 0.2, 0.3]).unwrap();
        assert_eq!(
            p.frames[1].point([1.0, 2.0, 3.0]),
            [1.0 + 0.1, 2.0 + 0.2, 3.0 + 0.3]
        );
        assert_eq!(p.segment_vectors([5.0; 3]), vec![[0.1, 0.2, 0.3]]);
    }

    #[test]
    fn rejects_mirrors_shear_and_nan() {
        let mut m = rot_z(0.3, [0.0; 3]);
        m[0][0] = -m[0][0];
        m[0][1] = -m[0][1];
        m[0][2] = -m[0][2];
        assert!(Path::from_matrices(&[rot_z(0.0, [0.0; 3]), m]).is_err());
        let mut s = rot_z(0.0, [0.0; 3]);
        s[0][1] = 0.5;
        assert!(Path::from_matrices(&[rot_z(0.0, [0.0; 3]), s]).is_err());
        let mut n = rot_z(0.0, [0.0; 3]);
        n[1][3] = f64::NAN;
        assert!(Path::from_matrices(&[rot_z(0.0, [0.0; 3]), n]).is_err());
        assert!(Path::from_matrices(&[rot_z(0.0, [0.0; 3])]).is_err());
    }

    #[test]
    fn placers_place_as_their_keyframes() {
        let keys = [
            Keyframe::translate([0.1, -2.0, 3.5]),
            Keyframe::from_matrix(&rot_z(0.7, [1.0, 2.0, -0.5]), 0).unwrap(),
        ];
        for k in keys {
            let pl = k.placer();
            for p in [[0.3, -0.1, 7.0], [-1e5, 2.5e-3, 0.0], [0.0, -0.0, 1.0]] {
                assert_eq!(pl.point(p), k.point(p));
                assert_eq!(pl.normal(p), k.normal(p));
            }
        }
    }

    #[test]
    fn subdivision_slerps_the_rotation() {
        let p = Path::from_matrices(&[rot_z(0.0, [0.0; 3]), rot_z(1.0, [2.0, 0.0, 0.0])]).unwrap();
        let q = p.subdivide(4);
        assert_eq!(q.frames.len(), 5);
        assert_eq!(q.frames[4], p.frames[1]);
        let half = q.frames[2];
        let expect = Keyframe::from_matrix(&rot_z(0.5, [1.0, 0.0, 0.0]), 0).unwrap();
        for r in 0..3 {
            for c in 0..3 {
                assert!((half.linear[r][c] - expect.linear[r][c]).abs() < 1e-12);
            }
        }
        assert!((half.translation[0] - 1.0).abs() < 1e-15);
    }
}
