//! Paths of the motion volume: rigid keyframes at the equally spaced shutter times `i / n`,
//! and the placement type the volume's construction applies to points.
//!
//! A [`Path`] holds `n + 1` keyframes. Each maps the mesh's given vertices to their placement
//! at that time, `p' = L p + t`, where `L` is a rotation times a positive uniform scale (a
//! similarity; mirrors and shear are rejected). A translation `m` is the path
//! `[identity, translate(m)]`: the given vertices sit at shutter open and arrive at `v + m` at
//! shutter close. The keyframes are split into their parts once ([`Similarity`]); subdividing
//! a path and placing at a fraction of a segment interpolate those parts, as every other
//! sampling of rigid keyframes does ([`Keyframes`](super::keyframes::Keyframes)).
use glam::{DMat3, DVec3};

use super::numeric::Mat4;
use super::similarity::Similarity;
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

    /// From a row-major 4x4 matrix, validated as a rigid keyframe
    /// ([`Similarity::from_matrix`]); `index` names the keyframe in errors about `motion`.
    pub fn from_matrix(m: &Mat4, index: usize) -> Result<Self> {
        Ok(Keyframe::of(&Similarity::from_matrix(m, "motion", index)?))
    }

    /// The placement of a split keyframe.
    pub fn of(k: &Similarity) -> Self {
        let m = &k.matrix;
        Keyframe {
            linear: std::array::from_fn(|r| [m[r][0], m[r][1], m[r][2]]),
            translation: k.translation,
        }
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
    /// The keyframes' placements, shutter open to close (at least two).
    pub frames: Vec<Keyframe>,
    /// The same keyframes split into their parts.
    keys: Vec<Similarity>,
}

impl Path {
    /// The path of keyframes already split (at least two).
    pub fn from_keys(keys: Vec<Similarity>) -> Result<Self> {
        if keys.len() < 2 {
            return Err(Error::shape("motion", "needs at least 2 keyframes"));
        }
        Ok(Path {
            frames: keys.iter().map(Keyframe::of).collect(),
            keys,
        })
    }

    /// The translation `m` over the shutter: `[identity, translate(m)]`.
    pub fn translation(m: [f64; 3]) -> Result<Self> {
        if m.iter().any(|x| !x.is_finite()) {
            return Err(Error::value("motion", "is NaN or inf"));
        }
        Path::from_keys(vec![
            Similarity::translate([0.0; 3]),
            Similarity::translate(m),
        ])
    }

    /// From `n + 1 >= 2` row-major 4x4 matrices, each validated and split; errors name `motion`.
    pub fn from_matrices(mats: &[Mat4]) -> Result<Self> {
        if mats.len() < 2 {
            return Err(Error::shape("motion", "needs at least 2 keyframes"));
        }
        let keys = mats
            .iter()
            .enumerate()
            .map(|(i, m)| Similarity::from_matrix(m, "motion", i))
            .collect::<Result<Vec<_>>>()?;
        Path::from_keys(keys)
    }

    /// From placements made in Rust (`n + 1 >= 2`), each validated and split.
    pub fn from_frames(frames: &[Keyframe]) -> Result<Self> {
        let mats: Vec<Mat4> = frames
            .iter()
            .map(|f| {
                let (l, t) = (&f.linear, &f.translation);
                [
                    [l[0][0], l[0][1], l[0][2], t[0]],
                    [l[1][0], l[1][1], l[1][2], t[1]],
                    [l[2][0], l[2][1], l[2][2], t[2]],
                    [0.0, 0.0, 0.0, 1.0],
                ]
            })
            .collect();
        Path::from_matrices(&mats)
    }

    /// The keyframes split into their parts.
    pub fn keys(&self) -> &[Similarity] {
        &self.keys
    }

    /// Number of segments (keyframe intervals).
    pub fn segments(&self) -> usize {
        self.frames.len() - 1
    }

    /// The placement the fraction `u` of the way through segment `j` (keyframes `j` and
    /// `j + 1`): its ends exactly at `u <= 0` and `u >= 1`, else the interpolated parts
    /// ([`Similarity::interpolate`]).
    pub fn between(&self, j: usize, u: f64) -> Keyframe {
        if u <= 0.0 {
            return self.frames[j];
        }
        if u >= 1.0 {
            return self.frames[j + 1];
        }
        Keyframe::of(&self.keys[j].interpolate(&self.keys[j + 1], u))
    }

    /// The placement at shutter time `t` in [0, 1]: [`Path::between`] in its segment.
    pub fn at(&self, t: f64) -> Keyframe {
        let n = self.segments();
        let x = t.clamp(0.0, 1.0) * n as f64;
        let j = (x.floor() as usize).min(n - 1);
        self.between(j, x - j as f64)
    }

    /// Every interval cut into `parts` equal sub-intervals (interpolated keyframes).
    pub fn subdivide(&self, parts: usize) -> Path {
        if parts <= 1 {
            return self.clone();
        }
        let mut keys = Vec::with_capacity(self.segments() * parts + 1);
        for w in self.keys.windows(2) {
            keys.push(w[0]);
            for j in 1..parts {
                keys.push(w[0].interpolate(&w[1], j as f64 / parts as f64));
            }
        }
        keys.push(*self.keys.last().expect("at least two keyframes"));
        Path::from_keys(keys).expect("at least two keyframes")
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

    #[test]
    fn between_places_as_subdivision_and_hits_the_ends() {
        let p = Path::from_matrices(&[rot_z(0.2, [0.0; 3]), rot_z(1.4, [2.0, 1.0, 0.0])]).unwrap();
        let q = p.subdivide(3);
        assert_eq!(p.between(0, 1.0 / 3.0), q.frames[1]);
        assert_eq!(p.between(0, 0.0), p.frames[0]);
        assert_eq!(p.between(0, 1.0), p.frames[1]);
        // the translation path stays exact: identity 3x3 parts, lerped translations
        let t = Path::translation([3.0, 0.0, -1.5]).unwrap().subdivide(2);
        assert!(t.frames[1].has_identity_linear());
        assert_eq!(t.frames[1].translation, [1.5, 0.0, -0.75]);
    }
}
