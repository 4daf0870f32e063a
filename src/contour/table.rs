//! Precomputed contour edges (Wloka and Zeleznik, section 4.4).
//!
//! For `K` motion directions the face split and the oriented contour edges are computed once;
//! a motion vector is then matched to the stored direction with the largest cosine (ties: the
//! lowest index) and the lookup reports the angle between them (radians), the error the
//! approximation makes. Directions are unit vectors drawn uniformly on the sphere from a seeded
//! generator (splitmix64), as the paper recommends stochastic directions, or given by the caller
//! (for example clustered around a preferred direction of motion).
use rayon::prelude::*;

use std::sync::atomic::{AtomicU64, Ordering};

use super::edges::{classify_faces, contour_from_sides};
use crate::budget::{memory_budget, Need};
use crate::error::check_vector;
use crate::error::{Error, Result};
use crate::mesh::{dot, normalize, Mesh};

/// Largest number of directions accepted.
const MAX_DIRECTIONS: usize = 1 << 16;

/// One stored contour set.
#[derive(Debug, Clone, PartialEq)]
pub struct ContourSet {
    /// Oriented contour edges `(a, b)` in adjacency order, as [`contour_edges`](crate::contour_edges).
    pub edges: Vec<[u32; 2]>,
    /// Front (`true`) or back per face.
    pub front: Vec<bool>,
}

/// Contour sets for a fixed set of directions.
#[derive(Debug, Clone)]
pub struct ContourTable {
    /// Unit motion directions, one per set.
    pub directions: Vec<[f64; 3]>,
    /// The contour set of each direction.
    pub sets: Vec<ContourSet>,
}

struct SplitMix64(u64);

impl SplitMix64 {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn uniform(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `count` unit vectors uniform on the sphere (Archimedes: z uniform in [-1, 1], angle uniform).
pub fn random_directions(count: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = SplitMix64(seed);
    (0..count)
        .map(|_| {
            let z = 2.0 * rng.uniform() - 1.0;
            let phi = 2.0 * std::f64::consts::PI * rng.uniform();
            let r = (1.0 - z * z).max(0.0).sqrt();
            [r * phi.cos(), r * phi.sin(), z]
        })
        .collect()
}

/// What a table of `directions` sets of `faces` faces holds before its contour edges: a front
/// flag per face and direction, and each set's own fields.
fn table_need(faces: usize, directions: usize) -> Result<Need> {
    Need::new("ContourTable")
        .add(
            &[("faces", faces as u64), ("directions", directions as u64)],
            1,
        )?
        .add(
            &[("directions", directions as u64)],
            (std::mem::size_of::<ContourSet>() + 24) as u64,
        )
}

impl ContourTable {
    /// Precompute the contour sets of `mesh` for the given directions (normalised here).
    ///
    /// Memory: a byte per face and direction and 8 bytes per contour edge of each direction,
    /// checked against the memory budget: the flags before anything is computed, the edges as
    /// the sets are made (the call stops at the first set past the budget).
    pub fn new(mesh: &Mesh, directions: Vec<[f64; 3]>) -> Result<Self> {
        if directions.is_empty() || directions.len() > MAX_DIRECTIONS {
            return Err(Error::value(
                "directions",
                format!(
                    "must hold 1..={MAX_DIRECTIONS} directions, got {}",
                    directions.len()
                ),
            ));
        }
        let need = table_need(mesh.faces().len(), directions.len())?;
        need.check()?;
        let mut unit = Vec::with_capacity(directions.len());
        for d in directions {
            check_vector(d, "directions")?;
            let u = normalize(d);
            if u == [0.0; 3] {
                return Err(Error::value("directions", "a direction is zero"));
            }
            unit.push(u);
        }
        mesh.adjacency();
        // The edges' bytes are known set by set: their running total with the flags is checked
        // as each set is made.
        let budget = memory_budget();
        let held = AtomicU64::new(need.bytes());
        let sets = unit
            .par_iter()
            .map(|&d| {
                let front = classify_faces(mesh, d);
                let edges: Vec<[u32; 2]> = contour_from_sides(mesh, &front)
                    .into_iter()
                    .map(|c| [c.a, c.b])
                    .collect();
                let bytes = 8 * edges.len() as u64;
                let total = held.fetch_add(bytes, Ordering::Relaxed) + bytes;
                if total > budget {
                    return Err(Error::Memory {
                        name: "faces x directions".into(),
                        reason: format!(
                            "ContourTable of {} faces and {} directions: the contour edges take \
                             over the memory budget of {} with the face flags (8 bytes an edge, \
                             a byte a face and direction); motionblur.set_memory_budget raises it",
                            mesh.faces().len(),
                            unit.len(),
                            crate::budget::human(budget)
                        ),
                    });
                }
                Ok(ContourSet { edges, front })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(ContourTable {
            directions: unit,
            sets,
        })
    }

    /// `count` stochastic directions from `seed`.
    pub fn random(mesh: &Mesh, count: usize, seed: u64) -> Result<Self> {
        if count == 0 || count > MAX_DIRECTIONS {
            return Err(Error::value(
                "directions",
                format!("must be in 1..={MAX_DIRECTIONS}, got {count}"),
            ));
        }
        Self::new(mesh, random_directions(count, seed))
    }

    /// The index of the nearest stored direction to `motion` and the angle to it (radians).
    pub fn nearest(&self, motion: [f64; 3]) -> Result<(usize, f64)> {
        check_vector(motion, "motion")?;
        let m = normalize(motion);
        if m == [0.0; 3] {
            return Err(Error::value(
                "motion",
                "is zero; a contour needs a direction",
            ));
        }
        let (mut best, mut cos) = (0usize, f64::NEG_INFINITY);
        for (i, d) in self.directions.iter().enumerate() {
            let c = dot(*d, m);
            if c > cos {
                best = i;
                cos = c;
            }
        }
        Ok((best, cos.clamp(-1.0, 1.0).acos()))
    }

    /// Bytes held by the stored sets (edges as two u32, one byte per face flag).
    pub fn storage_bytes(&self) -> usize {
        self.sets
            .iter()
            .map(|s| s.edges.len() * 8 + s.front.len())
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_past_the_memory_budget_fails_before_it_is_computed() {
        let (v, f) = crate::mesh::uv_sphere(200, 205);
        let mesh = Mesh::new(v, f).unwrap();
        assert!(mesh.faces().len() * MAX_DIRECTIONS > 4 << 30);
        let _lock = crate::budget::tests::BUDGET_LOCK.lock().unwrap();
        let t = std::time::Instant::now();
        let e = ContourTable::random(&mesh, MAX_DIRECTIONS, 1).unwrap_err();
        assert!(t.elapsed().as_secs_f64() < 1.0, "checked before computing");
        let Error::Memory { name, reason } = &e else {
            panic!("{e:?}")
        };
        assert_eq!(name, "faces x directions");
        assert!(reason.contains(&format!("{} x {MAX_DIRECTIONS}", mesh.faces().len())));
        // within the budget the same mesh gets its table
        assert_eq!(ContourTable::random(&mesh, 8, 1).unwrap().sets.len(), 8);
    }

    #[test]
    fn directions_are_unit_and_seeded() {
        let a = random_directions(100, 7);
        assert_eq!(a, random_directions(100, 7));
        assert_ne!(a, random_directions(100, 8));
        assert!(a.iter().all(|d| (dot(*d, *d) - 1.0).abs() < 1e-12));
    }

    #[test]
    fn lookup_of_a_stored_direction_is_exact() {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let f = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let mesh = Mesh::new(v, f).unwrap();
        let t = ContourTable::random(&mesh, 32, 1).unwrap();
        let (i, err) = t.nearest(t.directions[5]).unwrap();
        assert_eq!(i, 5);
        assert!(err < 1e-7);
        assert!(t.nearest([0.0; 3]).is_err());
        let t1 = crate::on_threads(1, || ContourTable::random(&mesh, 32, 1).unwrap());
        assert_eq!(t1.sets, t.sets);
    }
}
