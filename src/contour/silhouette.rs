//! The silhouette of motion (Jones and Keyser, section 3.2): per-vertex facing and the
//! back-facing edge of each triangle.
//!
//! - The facing of a vertex that moves (`d = p - p_prev != 0`) is `FRONT` when `n . d >= 0`
//!   (`n` its normal; the `>= 0` convention of `contour_edges`, so a vertex moving in its
//!   tangent plane is front) and `BACK` when `n . d < 0`. A vertex that does not move is
//!   `NEUTRAL`, neither front nor back, so a static polygon never has an edge. (Were `n . d == 0`
//!   neutral too, a symmetric mesh moving along an axis would lose most of its silhouette: the
//!   equator vertices of an icosphere moving along x have `n . d` exactly 0.)
//! - A triangle has a silhouette edge when exactly one corner is front and the other two are
//!   back: the edge between the two back corners, as the face runs it. It is stored as the
//!   local index `k` of the edge `face[k] -> face[(k + 1) % 3]`, or `NO_EDGE`.
//! - Without given normals, the vertex normal is the *unnormalised* sum of the raw face normals
//!   `(b - a) x (c - a)` of the faces around it, added in increasing face order starting from
//!   zero (numpy's `np.add.at` order).
//! - Everything is float32: positions are rounded to float32 first, and the displacement, the
//!   normals and the dot product are float32 operations in a fixed order (no fused
//!   multiply-add), so the facing signs equal a numpy float32 twin's bit for bit, and a vertex
//!   whose float32 position does not change is neutral.
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::mesh::{face_normal, VertexFaces};

/// Vertex facing values.
pub const FRONT: i8 = 1;
pub const BACK: i8 = -1;
pub const NEUTRAL: i8 = 0;
/// "No silhouette edge" in a face's edge code.
pub const NO_EDGE: u8 = 3;

/// Work items per rayon task: fixed, so the split does not depend on the thread count.
const CHUNK: usize = 8192;

/// Largest accepted |coordinate| of positions (scene units): the one coordinate range. Everything
/// runs in float32: a face normal is a product of two coordinate differences (up to
/// `8 MAX_COORD^2` per component), a vertex sums at most 2^32 of them and `n . d` multiplies by
/// another difference, which stays below `f32::MAX` (3.4e38) at this bound.
pub use crate::mesh::MAX_COORD;
/// Largest accepted |component| of given normals (`3 MAX_NORMAL 2 MAX_COORD` fits in float32).
pub const MAX_NORMAL: f64 = 1e18;

/// The bound of the rows called `name`: `MAX_NORMAL` for normals, else `MAX_COORD`.
fn limit_of(name: &str) -> f64 {
    if name == "normals" {
        MAX_NORMAL
    } else {
        MAX_COORD
    }
}

/// Fails naming `name` at the first row with a NaN, an inf or a value beyond `limit_of(name)`.
/// `par`: scan on rayon's current pool, else in order on this thread (the same row either way).
pub(crate) fn check_values(a: &[[f64; 3]], name: &'static str, par: bool) -> Result<()> {
    let lim = limit_of(name);
    let is_bad = |v: &[f64; 3]| v.iter().any(|x| x.is_nan() || x.abs() > lim);
    let first = if par {
        a.par_iter().position_first(is_bad)
    } else {
        a.iter().position(is_bad)
    };
    if let Some(bad) = first {
        let row = a[bad];
        if row.iter().all(|x| x.is_finite()) {
            return Err(Error::value(
                name,
                format!(
                    "row {bad} has a value beyond +-{lim:e} ({row:?}): float32 normals or \
                     dot products would overflow"
                ),
            ));
        }
        return Err(Error::value(name, format!("row {bad} is NaN or inf")));
    }
    Ok(())
}

/// Raw float32 face normals into `out` (same length as `faces`), in parallel.
pub fn face_normals_into(vertices: &[[f32; 3]], faces: &[[u32; 3]], out: &mut [[f32; 3]]) {
    out.par_chunks_mut(CHUNK)
        .zip(faces.par_chunks(CHUNK))
        .for_each(|(o, f)| {
            for (o, f) in o.iter_mut().zip(f) {
                *o = face_normal(vertices, f);
            }
        });
}

/// Facing of one vertex with normal `n` moving from `prev` to `p` (float32, left to right):
/// `NEUTRAL` when it does not move, else `BACK` when `n . d < 0` and `FRONT` otherwise.
#[inline]
pub fn facing(n: [f32; 3], p: [f32; 3], prev: [f32; 3]) -> i8 {
    let d = [p[0] - prev[0], p[1] - prev[1], p[2] - prev[2]];
    if d == [0.0; 3] {
        return NEUTRAL;
    }
    let s = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
    if s < 0.0 {
        BACK
    } else {
        FRONT
    }
}

/// The silhouette edge code of a face from its corners' facing: `k` (edge
/// `face[k] -> face[(k + 1) % 3]`) when one corner is front and two are back, else `NO_EDGE`.
#[inline]
pub fn face_edge(facing: &[i8], f: &[u32; 3]) -> u8 {
    let s = [
        facing[f[0] as usize],
        facing[f[1] as usize],
        facing[f[2] as usize],
    ];
    // Sum of facings is -1 with one front and two back (or with one back and two neutral: a
    // polygon with a corner that does not move has no edge).
    if s[0] + s[1] + s[2] != -1 || s.contains(&NEUTRAL) {
        return NO_EDGE;
    }
    // The edge opposite the front corner j runs from corner j + 1 to corner j + 2.
    let j = s.iter().position(|&x| x == FRONT).unwrap_or(0);
    ((j + 1) % 3) as u8
}

/// Float32 copies of float64 rows (the shell compares positions in float32).
pub fn to_f32(v: &[[f64; 3]]) -> Vec<[f32; 3]> {
    v.par_iter()
        .with_min_len(CHUNK)
        .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32])
        .collect()
}

/// The silhouette of motion of a mesh moving from `previous` to `vertices` (both (V,3), row
/// counts checked by the caller), with the given vertex normals or the unnormalised
/// area-weighted ones, all in float32 as in [`BlurShell::update`](crate::shell::BlurShell::update). Returns the
/// facing per vertex and the edge code per face. Fails naming `vertices`, `previous_vertices`
/// or `normals` for NaN, inf or values beyond `MAX_COORD` (1e9) / `MAX_NORMAL` (1e18).
pub fn motion_silhouette(
    vertices: &[[f64; 3]],
    previous: &[[f64; 3]],
    faces: &[[u32; 3]],
    normals: Option<&[[f64; 3]]>,
) -> Result<(Vec<i8>, Vec<u8>)> {
    check_values(vertices, "vertices", true)?;
    check_values(previous, "previous_vertices", true)?;
    if let Some(n) = normals {
        check_values(n, "normals", true)?;
    }
    let (v, p) = (to_f32(vertices), to_f32(previous));
    let mut fac = vec![NEUTRAL; vertices.len()];
    match normals {
        Some(n) => {
            let n = to_f32(n);
            fac.par_iter_mut()
                .enumerate()
                .with_min_len(CHUNK)
                .for_each(|(i, s)| {
                    *s = facing(n[i], v[i], p[i]);
                })
        }
        None => {
            let vf = VertexFaces::new(faces, vertices.len());
            let mut fnr = vec![[0.0; 3]; faces.len()];
            face_normals_into(&v, faces, &mut fnr);
            fac.par_iter_mut()
                .enumerate()
                .with_min_len(CHUNK)
                .for_each(|(i, s)| {
                    *s = facing(vf.normal(i, &fnr), v[i], p[i]);
                });
        }
    }
    let edges = faces
        .par_iter()
        .with_min_len(CHUNK)
        .map(|f| face_edge(&fac, f))
        .collect();
    Ok((fac, edges))
}
