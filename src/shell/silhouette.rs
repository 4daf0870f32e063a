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

/// Vertex facing values.
pub const FRONT: i8 = 1;
pub const BACK: i8 = -1;
pub const NEUTRAL: i8 = 0;
/// "No silhouette edge" in a face's edge code.
pub const NO_EDGE: u8 = 3;

/// Work items per rayon task: fixed, so the split does not depend on the thread count.
pub(crate) const CHUNK: usize = 8192;

/// The faces around each vertex (a CSR table), in increasing face order; a face that repeats a
/// vertex is listed once per corner, as `np.add.at` would add it.
#[derive(Debug, Clone)]
pub struct VertexFaces {
    offsets: Vec<u32>,
    faces: Vec<u32>,
}

impl VertexFaces {
    pub fn new(faces: &[[u32; 3]], n_vertices: usize) -> Self {
        let mut offsets = vec![0u32; n_vertices + 1];
        for f in faces {
            for &i in f {
                offsets[i as usize + 1] += 1;
            }
        }
        for i in 0..n_vertices {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut out = vec![0u32; 3 * faces.len()];
        for (fi, f) in faces.iter().enumerate() {
            for &i in f {
                out[fill[i as usize] as usize] = fi as u32;
                fill[i as usize] += 1;
            }
        }
        VertexFaces {
            offsets,
            faces: out,
        }
    }

    /// The faces of vertex `v`, in order.
    #[inline]
    pub fn faces_of(&self, v: usize) -> &[u32] {
        &self.faces[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }

    /// Unnormalised vertex normal of `v`: the sum of `face_n` over its faces, in order, from 0.
    #[inline]
    pub fn normal(&self, v: usize, face_n: &[[f32; 3]]) -> [f32; 3] {
        let mut acc = [0.0f32; 3];
        for &f in &self.faces[self.offsets[v] as usize..self.offsets[v + 1] as usize] {
            let n = face_n[f as usize];
            acc[0] += n[0];
            acc[1] += n[1];
            acc[2] += n[2];
        }
        acc
    }
}

/// Raw float32 face normals into `out` (same length as `faces`), in parallel.
pub fn face_normals_into(vertices: &[[f32; 3]], faces: &[[u32; 3]], out: &mut [[f32; 3]]) {
    out.par_chunks_mut(CHUNK)
        .zip(faces.par_chunks(CHUNK))
        .for_each(|(o, f)| {
            for (o, f) in o.iter_mut().zip(f) {
                *o = crate::mesh::face_normal(vertices, f);
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
/// area-weighted ones, all in float32 as in [`crate::shell::BlurShell::update`]. Returns the
/// facing per vertex and the edge code per face. Fails naming `vertices`, `previous_vertices`
/// or `normals` for NaN, inf or values beyond [`super::MAX_COORD`] / [`super::MAX_NORMAL`].
pub fn motion_silhouette(
    vertices: &[[f64; 3]],
    previous: &[[f64; 3]],
    faces: &[[u32; 3]],
    normals: Option<&[[f64; 3]]>,
) -> crate::Result<(Vec<i8>, Vec<u8>)> {
    super::check_values(vertices, "vertices")?;
    super::check_values(previous, "previous_vertices")?;
    if let Some(n) = normals {
        super::check_values(n, "normals")?;
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

/// A cache-friendly internal order for the per-update passes: vertices renumbered in
/// breadth-first order over the mesh (neighbours get nearby numbers), faces sorted by their
/// lowest renumbered vertex. Positions are gathered into this order once per update, so the
/// face-normal and vertex-normal passes stream through memory whatever the caller's order.
/// Results do not depend on it: every vertex still sums its faces in original face order.
#[derive(Debug, Clone)]
pub struct Locality {
    /// Internal vertex `i` is the caller's vertex `perm[i]`.
    pub perm: Vec<u32>,
    /// The caller's vertex `v` is internal vertex `inv[v]`.
    pub inv: Vec<u32>,
    /// Faces in the caller's order, with internal vertex numbers.
    pub ifaces: Vec<[u32; 3]>,
    /// Faces in internal order (sorted by lowest internal vertex), with internal vertex numbers.
    pub bfaces: Vec<[u32; 3]>,
    /// Per internal vertex, its faces as indices into `bfaces`, in original face order.
    pub vf: VertexFaces,
}

impl Locality {
    pub fn new(faces: &[[u32; 3]], n_vertices: usize) -> Self {
        let by_vertex = VertexFaces::new(faces, n_vertices);
        // Breadth-first order over vertices sharing a face; components in original order.
        let mut inv = vec![u32::MAX; n_vertices];
        let mut perm = Vec::with_capacity(n_vertices);
        let mut head = 0;
        for seed in 0..n_vertices {
            if inv[seed] != u32::MAX {
                continue;
            }
            inv[seed] = perm.len() as u32;
            perm.push(seed as u32);
            while head < perm.len() {
                let v = perm[head] as usize;
                head += 1;
                let (a, b) = (
                    by_vertex.offsets[v] as usize,
                    by_vertex.offsets[v + 1] as usize,
                );
                for &f in &by_vertex.faces[a..b] {
                    for &w in &faces[f as usize] {
                        if inv[w as usize] == u32::MAX {
                            inv[w as usize] = perm.len() as u32;
                            perm.push(w);
                        }
                    }
                }
            }
        }
        let ifaces: Vec<[u32; 3]> = faces
            .iter()
            .map(|f| [inv[f[0] as usize], inv[f[1] as usize], inv[f[2] as usize]])
            .collect();
        // Faces sorted (stably) by their lowest internal vertex: a counting sort.
        let mut start = vec![0u32; n_vertices + 1];
        for f in &ifaces {
            start[*f.iter().min().unwrap_or(&0) as usize + 1] += 1;
        }
        for i in 0..n_vertices {
            start[i + 1] += start[i];
        }
        let mut slot_of = vec![0u32; faces.len()];
        let mut bfaces = vec![[0u32; 3]; faces.len()];
        for (fi, f) in ifaces.iter().enumerate() {
            let s = &mut start[*f.iter().min().unwrap_or(&0) as usize];
            slot_of[fi] = *s;
            bfaces[*s as usize] = *f;
            *s += 1;
        }
        // Per internal vertex, its faces' internal slots, in original face order.
        let mut offsets = vec![0u32; n_vertices + 1];
        for f in &ifaces {
            for &i in f {
                offsets[i as usize + 1] += 1;
            }
        }
        for i in 0..n_vertices {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut list = vec![0u32; 3 * faces.len()];
        for (fi, f) in ifaces.iter().enumerate() {
            for &i in f {
                list[fill[i as usize] as usize] = slot_of[fi];
                fill[i as usize] += 1;
            }
        }
        Locality {
            perm,
            inv,
            ifaces,
            bfaces,
            vf: VertexFaces {
                offsets,
                faces: list,
            },
        }
    }
}
