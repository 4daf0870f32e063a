//! Indexed triangle meshes: validation, face normals, statistics and the cached edge adjacency.
//!
//! Vertices are `[f64; 3]` in scene units, faces are `[u32; 3]` counter-clockwise seen from the
//! front. The edge adjacency is built once (counting sort by the lower vertex, then a short sort
//! per vertex bucket) and kept in a `OnceLock`, so a mesh can be classified against many motion
//! vectors, or given new vertex positions with [`Mesh::with_vertices`], without rebuilding it.
//!
//! Edge rules (documented in the Python API too):
//! - an undirected edge is the set of half-edges `(a, b)` / `(b, a)` of the faces that use it;
//!   a face with a repeated index has a zero-length half-edge `(a, a)`, which is not an edge;
//! - a *boundary* edge has one incident face, a *non-manifold* edge three or more, an
//!   *inconsistent* edge two faces that run it in the same direction;
//! - a *degenerate* face has a zero cross product `(b - a) x (c - a)` (repeated index,
//!   collinear or coincident vertices). It keeps its place in the adjacency; its normal is zero.
use std::sync::OnceLock;

use rayon::prelude::*;

use crate::{Error, Result};

/// Largest number of faces or vertices accepted (indices are stored as `u32`).
pub const MAX_ELEMENTS: usize = (u32::MAX as usize) / 4;

/// The edge adjacency of a mesh.
///
/// `edges[e] = [a, b]` with `a < b`, sorted lexicographically. The half-edges of edge `e` are
/// `half_edges[offsets[e]..offsets[e + 1]]`, each `3 * face + k` for the face's edge
/// `faces[face][k] -> faces[face][(k + 1) % 3]`, in increasing order.
#[derive(Debug, Clone, PartialEq)]
pub struct Adjacency {
    pub edges: Vec<[u32; 2]>,
    pub offsets: Vec<u32>,
    pub half_edges: Vec<u32>,
}

impl Adjacency {
    /// Number of undirected edges.
    pub fn len(&self) -> usize {
        self.edges.len()
    }
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }
    /// The half-edges (`3 * face + k`) of edge `e`.
    pub fn incident(&self, e: usize) -> &[u32] {
        &self.half_edges[self.offsets[e] as usize..self.offsets[e + 1] as usize]
    }
}

/// Counts describing a mesh's health.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MeshStats {
    pub faces: usize,
    pub vertices: usize,
    pub edges: usize,
    pub degenerate_faces: usize,
    pub boundary_edges: usize,
    pub nonmanifold_edges: usize,
    pub inconsistent_edges: usize,
    pub unreferenced_vertices: usize,
}

impl MeshStats {
    /// Closed: every edge has exactly two faces running it in opposite directions.
    pub fn is_closed(&self) -> bool {
        self.boundary_edges == 0 && self.nonmanifold_edges == 0 && self.inconsistent_edges == 0
    }
}

/// An indexed triangle mesh with a lazily built, cached edge adjacency.
#[derive(Debug)]
pub struct Mesh {
    vertices: Vec<[f64; 3]>,
    faces: Vec<[u32; 3]>,
    adjacency: std::sync::Arc<OnceLock<Adjacency>>,
}

impl Mesh {
    /// A mesh from owned data. Errors name `vertices` or `faces`: empty arrays, non-finite
    /// coordinates, indices out of range, absurd sizes.
    pub fn new(vertices: Vec<[f64; 3]>, faces: Vec<[u32; 3]>) -> Result<Self> {
        check_vertices(&vertices)?;
        if faces.is_empty() {
            return Err(Error::shape("faces", "is empty"));
        }
        if faces.len() > MAX_ELEMENTS {
            return Err(Error::shape("faces", format!("too many faces ({})", faces.len())));
        }
        let nv = vertices.len() as u32;
        if let Some(bad) = faces.par_iter().position_first(|f| f.iter().any(|&i| i >= nv)) {
            return Err(Error::value(
                "faces",
                format!("face {bad} has an index out of range [0, {nv})"),
            ));
        }
        Ok(Mesh {
            vertices,
            faces,
            adjacency: Default::default(),
        })
    }

    /// The same faces (and the same cached adjacency) with new vertex positions, as after a
    /// deformation. `vertices` must have the same length.
    pub fn with_vertices(&self, vertices: Vec<[f64; 3]>) -> Result<Self> {
        check_vertices(&vertices)?;
        if vertices.len() != self.vertices.len() {
            return Err(Error::shape(
                "vertices",
                format!("expected {} vertices, got {}", self.vertices.len(), vertices.len()),
            ));
        }
        Ok(Mesh {
            vertices,
            faces: self.faces.clone(),
            adjacency: self.adjacency.clone(),
        })
    }

    pub fn vertices(&self) -> &[[f64; 3]] {
        &self.vertices
    }
    pub fn faces(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// The cached edge adjacency, built on first use.
    pub fn adjacency(&self) -> &Adjacency {
        self.adjacency.get_or_init(|| build_adjacency(&self.faces, self.vertices.len()))
    }

    /// Whether the adjacency has been built already.
    pub fn has_adjacency(&self) -> bool {
        self.adjacency.get().is_some()
    }

    /// Unnormalised face normals `(b - a) x (c - a)` (twice the area), in vertex units squared.
    pub fn face_normals_raw(&self) -> Vec<[f64; 3]> {
        self.faces
            .par_iter()
            .map(|f| face_normal(&self.vertices, f))
            .collect()
    }

    /// Unit face normals; degenerate faces get `[0, 0, 0]`.
    pub fn face_normals(&self) -> Vec<[f64; 3]> {
        self.faces
            .par_iter()
            .map(|f| normalize(face_normal(&self.vertices, f)))
            .collect()
    }

    /// Area-weighted vertex normals (sum of the raw normals of the faces around the vertex),
    /// normalised; a vertex with no non-degenerate face gets `[0, 0, 0]`.
    pub fn vertex_normals(&self) -> Vec<[f64; 3]> {
        let mut acc = vec![[0.0f64; 3]; self.vertices.len()];
        for f in &self.faces {
            let n = face_normal(&self.vertices, f);
            for &i in f {
                let a = &mut acc[i as usize];
                a[0] += n[0];
                a[1] += n[1];
                a[2] += n[2];
            }
        }
        acc.into_par_iter().map(normalize).collect()
    }

    /// Face, vertex and edge counts, degenerate faces and the edge classes of the module docs.
    pub fn stats(&self) -> MeshStats {
        let adj = self.adjacency();
        let degenerate_faces = self
            .faces
            .par_iter()
            .filter(|f| face_normal(&self.vertices, f) == [0.0; 3])
            .count();
        let (boundary, nonmanifold, inconsistent) = (0..adj.len())
            .into_par_iter()
            .map(|e| {
                let inc = adj.incident(e);
                match inc.len() {
                    1 => (1, 0, 0),
                    2 => {
                        let same = half_edge_forward(&self.faces, inc[0])
                            == half_edge_forward(&self.faces, inc[1]);
                        (0, 0, usize::from(same))
                    }
                    _ => (0, 1, 0),
                }
            })
            .reduce(|| (0, 0, 0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2));
        let mut used = vec![false; self.vertices.len()];
        for f in &self.faces {
            for &i in f {
                used[i as usize] = true;
            }
        }
        MeshStats {
            faces: self.faces.len(),
            vertices: self.vertices.len(),
            edges: adj.len(),
            degenerate_faces,
            boundary_edges: boundary,
            nonmanifold_edges: nonmanifold,
            inconsistent_edges: inconsistent,
            unreferenced_vertices: used.iter().filter(|u| !**u).count(),
        }
    }
}

fn check_vertices(vertices: &[[f64; 3]]) -> Result<()> {
    if vertices.is_empty() {
        return Err(Error::shape("vertices", "is empty"));
    }
    if vertices.len() > MAX_ELEMENTS {
        return Err(Error::shape("vertices", format!("too many vertices ({})", vertices.len())));
    }
    if let Some(bad) = vertices
        .par_iter()
        .position_first(|v| v.iter().any(|x| !x.is_finite()))
    {
        return Err(Error::value("vertices", format!("vertex {bad} is NaN or inf")));
    }
    Ok(())
}

/// `(b - a) x (c - a)`, evaluated exactly as numpy's `np.cross(b - a, c - a)`.
#[inline]
pub fn face_normal(v: &[[f64; 3]], f: &[u32; 3]) -> [f64; 3] {
    let a = v[f[0] as usize];
    let b = v[f[1] as usize];
    let c = v[f[2] as usize];
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let w = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    [
        u[1] * w[2] - u[2] * w[1],
        u[2] * w[0] - u[0] * w[2],
        u[0] * w[1] - u[1] * w[0],
    ]
}

/// `x0*y0 + x1*y1 + x2*y2`, left to right (no fused multiply-add), as the numpy twin computes it.
#[inline]
pub fn dot(x: [f64; 3], y: [f64; 3]) -> f64 {
    x[0] * y[0] + x[1] * y[1] + x[2] * y[2]
}

#[inline]
pub fn normalize(n: [f64; 3]) -> [f64; 3] {
    let l = dot(n, n).sqrt();
    if l > 0.0 && l.is_finite() {
        [n[0] / l, n[1] / l, n[2] / l]
    } else {
        [0.0; 3]
    }
}

/// Whether half-edge `h = 3 * face + k` runs from the lower to the higher vertex index.
#[inline]
pub fn half_edge_forward(faces: &[[u32; 3]], h: u32) -> bool {
    let (a, b) = half_edge(faces, h);
    a < b
}

/// The vertices `(from, to)` of half-edge `h = 3 * face + k`.
#[inline]
pub fn half_edge(faces: &[[u32; 3]], h: u32) -> (u32, u32) {
    let f = &faces[(h / 3) as usize];
    let k = (h % 3) as usize;
    (f[k], f[(k + 1) % 3])
}

/// Build the adjacency: counting sort of the half-edges by their lower vertex, a sort of each
/// (small) bucket by (higher vertex, half-edge id) in parallel, then runs of equal keys. The
/// result does not depend on the thread count.
pub fn build_adjacency(faces: &[[u32; 3]], n_vertices: usize) -> Adjacency {
    let mut start = vec![0u32; n_vertices + 1];
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            if a != b {
                start[a.min(b) as usize + 1] += 1;
            }
        }
    }
    for i in 0..n_vertices {
        start[i + 1] += start[i];
    }
    let total = start[n_vertices] as usize;
    // (higher vertex, half-edge id) bucketed by lower vertex.
    let mut entries = vec![(0u32, 0u32); total];
    let mut fill = start.clone();
    for (fi, f) in faces.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            if a != b {
                let slot = &mut fill[a.min(b) as usize];
                entries[*slot as usize] = (a.max(b), 3 * fi as u32 + k as u32);
                *slot += 1;
            }
        }
    }
    // Sort every bucket; split the buffer into per-vertex slices first.
    {
        let mut buckets: Vec<&mut [(u32, u32)]> = Vec::with_capacity(n_vertices);
        let mut rest: &mut [(u32, u32)] = &mut entries;
        for i in 0..n_vertices {
            let len = (start[i + 1] - start[i]) as usize;
            let (head, tail) = rest.split_at_mut(len);
            if len > 1 {
                buckets.push(head);
            }
            rest = tail;
        }
        buckets.par_iter_mut().with_min_len(1024).for_each(|b| b.sort_unstable());
    }
    let mut edges = Vec::with_capacity(total / 2 + 1);
    let mut offsets = Vec::with_capacity(total / 2 + 2);
    let mut half_edges = Vec::with_capacity(total);
    for a in 0..n_vertices {
        let bucket = &entries[start[a] as usize..start[a + 1] as usize];
        let mut prev = u32::MAX;
        for &(b, h) in bucket {
            if b != prev {
                edges.push([a as u32, b]);
                offsets.push(half_edges.len() as u32);
                prev = b;
            }
            half_edges.push(h);
        }
    }
    offsets.push(half_edges.len() as u32);
    Adjacency {
        edges,
        offsets,
        half_edges,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> Mesh {
        let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let f = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        Mesh::new(v, f).unwrap()
    }

    #[test]
    fn tetra_is_closed() {
        let m = tetra();
        let s = m.stats();
        assert_eq!(s.edges, 6);
        assert!(s.is_closed(), "{s:?}");
        assert_eq!(s.degenerate_faces, 0);
        let adj = m.adjacency();
        assert!(adj.edges.windows(2).all(|w| w[0] < w[1]));
        assert!((0..adj.len()).all(|e| adj.incident(e).len() == 2));
    }

    #[test]
    fn open_and_nonmanifold_edges_are_counted() {
        let v = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]];
        // Three faces on edge (0, 1), one degenerate face with a repeated index.
        let f = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4], [2, 2, 3]];
        let s = Mesh::new(v, f).unwrap().stats();
        assert_eq!(s.nonmanifold_edges, 1);
        assert_eq!(s.degenerate_faces, 1);
        assert!(s.boundary_edges > 0);
    }

    #[test]
    fn bad_input_names_the_argument() {
        let e = Mesh::new(vec![[0.0, f64::NAN, 0.0]], vec![[0, 0, 0]]).unwrap_err();
        assert!(e.to_string().starts_with("vertices"));
        let e = Mesh::new(vec![[0.0; 3]; 3], vec![[0, 1, 3]]).unwrap_err();
        assert!(e.to_string().starts_with("faces"));
        assert!(Mesh::new(vec![], vec![[0, 1, 2]]).is_err());
        assert!(Mesh::new(vec![[0.0; 3]], vec![]).is_err());
    }

    #[test]
    fn adjacency_is_thread_count_independent() {
        let m = tetra();
        let faces: Vec<[u32; 3]> = (0..5000u32).map(|i| [i % 97, (i * 7 + 1) % 97, (i * 13 + 5) % 97]).collect();
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let two = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let a = one.install(|| build_adjacency(&faces, 97));
        let b = two.install(|| build_adjacency(&faces, 97));
        assert_eq!(a, b);
        drop(m);
    }
}
