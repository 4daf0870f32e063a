//! Keyframes over the shutter [0, 1]: rigid transforms or vertex positions at sorted times,
//! validated once and sampled at any time.
//!
//! Between two keyframes a rigid motion interpolates its [`Similarity`] parts (translation and
//! scale linear, rotation on the shorter arc) and a deforming one its vertex positions
//! linearly; before the first and after the last keyframe the motion holds still. A time equal
//! to a keyframe's gives that keyframe exactly.
use super::numeric::{Mat4, IDENTITY4};
use super::similarity::Similarity;
use crate::error::{Error, Result};

/// What the keyframes hold.
#[derive(Debug, Clone, PartialEq)]
pub enum Keys {
    /// One rigid transform per keyframe.
    Rigid(Vec<Similarity>),
    /// `count` vertex positions per keyframe, keyframe after keyframe.
    Deforming {
        /// Positions, `times.len() * count` rows.
        vertices: Vec<[f64; 3]>,
        /// Vertices per keyframe.
        count: usize,
    },
}

/// Keyframes at sorted shutter times.
#[derive(Debug, Clone, PartialEq)]
pub struct Keyframes {
    times: Vec<f64>,
    keys: Keys,
}

/// Checks keyframe or sample times: at least one, finite, in [0, 1], strictly increasing.
/// Errors name `name`.
pub fn check_times(times: &[f64], name: &'static str) -> Result<()> {
    if times.is_empty() {
        return Err(Error::shape(name, "is empty"));
    }
    if times.iter().any(|t| !t.is_finite()) {
        return Err(Error::value(name, "contains NaN or inf"));
    }
    let (lo, hi) = times
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &t| {
            (a.min(t), b.max(t))
        });
    if lo < 0.0 || hi > 1.0 {
        return Err(Error::value(
            name,
            format!(
                "must lie in the shutter interval [0, 1], got [{}, {}]",
                super::similarity::general(lo),
                super::similarity::general(hi)
            ),
        ));
    }
    if times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(Error::value(name, "must be strictly increasing"));
    }
    Ok(())
}

/// The times `i / n`, i = 0..=n, as `numpy.linspace(0, 1, n + 1)` gives them (`i * (1 / n)`,
/// the last exactly 1).
pub fn uniform_times(n: usize) -> Vec<f64> {
    if n == 0 {
        return vec![0.0];
    }
    let step = 1.0 / n as f64;
    let mut t: Vec<f64> = (0..=n).map(|i| i as f64 * step + 0.0).collect();
    t[n] = 1.0;
    t
}

impl Keyframes {
    /// Rigid keyframes: `times` (K,) and one 4x4 matrix per time, each validated and split
    /// ([`Similarity::from_matrix`]); errors name `name` (the matrices' argument) or "times".
    pub fn rigid(times: Vec<f64>, matrices: &[Mat4], name: &'static str) -> Result<Self> {
        check_times(&times, "times")?;
        if matrices.len() != times.len() {
            return Err(Error::shape(
                name,
                format!(
                    "expected {} keyframes (one per time), got {}",
                    times.len(),
                    matrices.len()
                ),
            ));
        }
        let keys = matrices
            .iter()
            .enumerate()
            .map(|(i, m)| Similarity::from_matrix(m, name, i))
            .collect::<Result<Vec<_>>>()?;
        Ok(Keyframes {
            times,
            keys: Keys::Rigid(keys),
        })
    }

    /// Rigid keyframes already split (made by this engine), at checked `times`.
    pub fn from_parts(times: Vec<f64>, keys: Vec<Similarity>) -> Result<Self> {
        check_times(&times, "times")?;
        if keys.len() != times.len() {
            return Err(Error::shape("keys", "one keyframe per time expected"));
        }
        Ok(Keyframes {
            times,
            keys: Keys::Rigid(keys),
        })
    }

    /// Deforming keyframes: `times` (K,) and `vertices` (K*V rows, keyframe after keyframe),
    /// finite; errors name "vertices" or "times".
    pub fn deforming(times: Vec<f64>, vertices: Vec<[f64; 3]>) -> Result<Self> {
        check_times(&times, "times")?;
        if vertices.is_empty() || vertices.len() % times.len() != 0 {
            return Err(Error::shape(
                "vertices",
                format!("expected {} keyframes of V >= 1 vertices", times.len()),
            ));
        }
        if vertices.iter().flatten().any(|x| !x.is_finite()) {
            return Err(Error::value("vertices", "contains NaN or inf"));
        }
        if vertices
            .iter()
            .flatten()
            .any(|x| x.abs() > crate::mesh::MAX_COORD)
        {
            return Err(Error::value(
                "vertices",
                format!(
                    "positions beyond the coordinate range +-{:e} (MAX_COORD)",
                    crate::mesh::MAX_COORD
                ),
            ));
        }
        let count = vertices.len() / times.len();
        Ok(Keyframes {
            times,
            keys: Keys::Deforming { vertices, count },
        })
    }

    /// The keyframe times.
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// What the keyframes hold.
    pub fn keys(&self) -> &Keys {
        &self.keys
    }

    /// The rigid keyframes (empty for a deforming motion).
    pub fn rigid_keys(&self) -> &[Similarity] {
        match &self.keys {
            Keys::Rigid(k) => k,
            Keys::Deforming { .. } => &[],
        }
    }

    /// Whether the keyframes are vertex positions.
    pub fn is_deforming(&self) -> bool {
        matches!(self.keys, Keys::Deforming { .. })
    }

    /// `(i, j, u)`: time `t` lies the fraction `u` of the way from keyframe `i` to `j`
    /// (`u = 0` and `i = j` at or outside the ends).
    pub fn segment(&self, t: f64) -> (usize, usize, f64) {
        let ts = &self.times;
        let last = ts.len() - 1;
        if t <= ts[0] || last == 0 {
            return (0, 0, 0.0);
        }
        if t >= ts[last] {
            return (last, last, 0.0);
        }
        let j = ts.partition_point(|&x| x <= t);
        let i = j - 1;
        (i, j, (t - ts[i]) / (ts[j] - ts[i]))
    }

    /// The rigid keyframe at shutter time `t` (None for a deforming motion).
    pub fn similarity_at(&self, t: f64) -> Option<Similarity> {
        let keys = match &self.keys {
            Keys::Rigid(k) => k,
            Keys::Deforming { .. } => return None,
        };
        let (i, j, u) = self.segment(t);
        Some(keys[i].interpolate(&keys[j], u))
    }

    /// The 4x4 transform at shutter time `t` (the identity for a deforming motion).
    pub fn transform_at(&self, t: f64) -> Mat4 {
        self.similarity_at(t).map_or(IDENTITY4, |k| k.matrix)
    }

    /// The vertex positions at shutter time `t` of a deforming motion, `(1 - u) a + u b`
    /// between keyframes (None for a rigid one).
    pub fn vertices_at(&self, t: f64) -> Option<Vec<[f64; 3]>> {
        let (vertices, n) = match &self.keys {
            Keys::Deforming { vertices, count } => (vertices, *count),
            Keys::Rigid(_) => return None,
        };
        let (i, j, u) = self.segment(t);
        let a = &vertices[i * n..(i + 1) * n];
        if u == 0.0 {
            return Some(a.to_vec());
        }
        let b = &vertices[j * n..(j + 1) * n];
        let v = 1.0 - u;
        Some(
            a.iter()
                .zip(b)
                .map(|(p, q)| std::array::from_fn(|k| v * p[k] + u * q[k]))
                .collect(),
        )
    }

    /// The positions at shutter time `t` of the vertices `rows` of a deforming motion: those of
    /// [`Keyframes::vertices_at`], for these rows only (None for a rigid motion). Every row must
    /// be under the motion's vertex count.
    pub fn rows_at(&self, t: f64, rows: &[usize]) -> Option<Vec<[f64; 3]>> {
        let Keys::Deforming { vertices, count } = &self.keys else {
            return None;
        };
        let (i, j, u) = self.segment(t);
        let (a, b) = (&vertices[i * count..], &vertices[j * count..]);
        let v = 1.0 - u;
        Some(
            rows.iter()
                .map(|&r| match u == 0.0 {
                    true => a[r],
                    false => std::array::from_fn(|c| v * a[r][c] + u * b[r][c]),
                })
                .collect(),
        )
    }

    /// The rigid keyframes at the `n + 1` times `i / n` ([`uniform_times`]), interpolated from
    /// the parts of these (None for a deforming motion).
    pub fn resampled(&self, n: usize) -> Option<Keyframes> {
        let times = uniform_times(n);
        let keys: Vec<Similarity> = times
            .iter()
            .map(|&t| self.similarity_at(t))
            .collect::<Option<_>>()?;
        Some(Keyframes {
            times,
            keys: Keys::Rigid(keys),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shift(x: f64) -> Mat4 {
        let mut m = IDENTITY4;
        m[0][3] = x;
        m
    }

    #[test]
    fn holds_outside_and_hits_keyframes_exactly() {
        let k =
            Keyframes::rigid(vec![0.25, 0.75], &[shift(0.0), shift(2.0)], "transforms").unwrap();
        assert_eq!(k.transform_at(0.0)[0][3], 0.0);
        assert_eq!(k.transform_at(0.5)[0][3], 1.0);
        assert_eq!(k.transform_at(0.75), shift(2.0));
        assert_eq!(k.transform_at(1.0), shift(2.0));
        assert_eq!(k.segment(0.5), (0, 1, 0.5));
        let one = Keyframes::rigid(vec![0.4], &[shift(3.0)], "transforms").unwrap();
        assert_eq!(one.transform_at(0.9), shift(3.0));
    }

    #[test]
    fn deforming_positions_are_lerped() {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 1.0],
            [2.0, 0.0, 0.0],
            [3.0, 1.0, 1.0],
        ];
        let k = Keyframes::deforming(vec![0.0, 1.0], v).unwrap();
        assert_eq!(
            k.vertices_at(0.5).unwrap(),
            vec![[1.0, 0.0, 0.0], [2.0, 1.0, 1.0]]
        );
        assert_eq!(
            k.vertices_at(1.0).unwrap(),
            vec![[2.0, 0.0, 0.0], [3.0, 1.0, 1.0]]
        );
        assert_eq!(k.transform_at(0.3), IDENTITY4);
        assert!(Keyframes::deforming(vec![0.0, 1.0], vec![[0.0; 3]; 3]).is_err());
    }

    #[test]
    fn times_are_checked_and_named() {
        let m = [shift(0.0), shift(1.0)];
        let err = |t: Vec<f64>| {
            Keyframes::rigid(t, &m, "transforms")
                .unwrap_err()
                .to_string()
        };
        assert!(err(vec![0.5, 0.2]).contains("increasing"));
        assert!(err(vec![0.0, 1.5]).contains("[0, 1]"));
        assert!(err(vec![0.0, f64::NAN]).contains("NaN"));
        assert!(err(vec![0.0, 0.5, 1.0]).starts_with("transforms: expected 3 keyframes"));
    }

    #[test]
    fn uniform_times_are_linspace() {
        assert_eq!(uniform_times(1), vec![0.0, 1.0]);
        let t = uniform_times(10);
        assert_eq!(t[3], 3.0 * 0.1); // 0.30000000000000004, as numpy.linspace
        assert_eq!(t[10], 1.0);
        let k = Keyframes::rigid(vec![0.0, 1.0], &[shift(0.0), shift(1.0)], "m").unwrap();
        let r = k.resampled(4).unwrap();
        assert_eq!(r.rigid_keys()[1].matrix, k.transform_at(0.25));
        assert_eq!(r.times(), &uniform_times(4)[..]);
    }
}
