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
pub const MAX_ELEMENTS: usize = (u32::MAX as usize) / 8;

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
    /// Per half-edge (parallel to `half_edges`): runs from the lower to the higher index.
    pub forward: Vec<bool>,
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
    /// The direction flags of the half-edges of edge `e` (see `forward`).
    pub fn incident_forward(&self, e: usize) -> &[bool] {
        &self.forward[self.offsets[e] as usize..self.offsets[e + 1] as usize]
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

/// Per face `f` and edge `k` (`faces[f][k] -> faces[f][(k + 1) % 3]`): the face across it and
/// the edge's index in the adjacency.
#[derive(Debug, Clone, PartialEq)]
pub struct FaceNeighbors {
    pub faces: Vec<[u32; 3]>,
    pub edges: Vec<[u32; 3]>,
}

/// An indexed triangle mesh with a lazily built, cached edge adjacency.
#[derive(Debug)]
pub struct Mesh {
    vertices: Vec<[f64; 3]>,
    faces: Vec<[u32; 3]>,
    adjacency: std::sync::Arc<OnceLock<Adjacency>>,
    /// Per face, the face across each of its edges and that edge's index, when every edge has
    /// exactly two faces that run it in opposite directions (built from the adjacency on first
    /// use).
    neighbors: std::sync::Arc<OnceLock<Option<FaceNeighbors>>>,
    /// [`Mesh::face_planes`], built on first use (not shared with deformed copies).
    planes: OnceLock<crate::hull::FacePlanes>,
    /// [`Mesh::vertex_normals`], kept by [`Mesh::cached_vertex_normals`].
    normals: OnceLock<Vec<[f64; 3]>>,
    /// [`Mesh::longest_edge`], computed on first use.
    longest: OnceLock<f64>,
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
            return Err(Error::shape(
                "faces",
                format!("too many faces ({})", faces.len()),
            ));
        }
        let nv = vertices.len() as u32;
        // A parallel `all` first (cheap), the index of the first bad face only on failure.
        let bad_face = |f: &[u32; 3]| f.iter().any(|&i| i >= nv);
        if !faces.par_iter().with_min_len(8192).all(|f| !bad_face(f)) {
            let bad = faces.iter().position(bad_face).unwrap_or(0);
            return Err(Error::value(
                "faces",
                format!("face {bad} has an index out of range [0, {nv})"),
            ));
        }
        Ok(Mesh {
            vertices,
            faces,
            adjacency: Default::default(),
            neighbors: Default::default(),
            planes: Default::default(),
            normals: Default::default(),
            longest: Default::default(),
        })
    }

    /// The same faces (and the same cached adjacency) with new vertex positions, as after a
    /// deformation. `vertices` must have the same length.
    pub fn with_vertices(&self, vertices: Vec<[f64; 3]>) -> Result<Self> {
        check_vertices(&vertices)?;
        if vertices.len() != self.vertices.len() {
            return Err(Error::shape(
                "vertices",
                format!(
                    "expected {} vertices, got {}",
                    self.vertices.len(),
                    vertices.len()
                ),
            ));
        }
        Ok(Mesh {
            vertices,
            faces: self.faces.clone(),
            adjacency: self.adjacency.clone(),
            neighbors: self.neighbors.clone(),
            planes: Default::default(),
            normals: Default::default(),
            longest: Default::default(),
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
        self.adjacency
            .get_or_init(|| build_adjacency(&self.faces, self.vertices.len()))
    }

    /// The face across each edge of every face and the edge's index ([`FaceNeighbors`]), or
    /// `None` unless every face edge has exactly one partner running it the other way (a closed,
    /// consistently wound, 2-manifold mesh without zero-length edges). Cached, and shared by
    /// [`Mesh::with_vertices`] copies.
    pub fn face_neighbors(&self) -> Option<&FaceNeighbors> {
        self.neighbors
            .get_or_init(|| {
                use std::sync::atomic::{AtomicU32, Ordering::Relaxed};
                let adj = self.adjacency();
                let n = 3 * self.faces.len();
                let across: Vec<AtomicU32> = (0..n).map(|_| AtomicU32::new(u32::MAX)).collect();
                let edge: Vec<AtomicU32> = (0..n).map(|_| AtomicU32::new(u32::MAX)).collect();
                // Every half-edge belongs to one edge, so each slot is written at most once.
                let paired = (0..adj.len()).into_par_iter().with_min_len(4096).all(|e| {
                    let (inc, fw) = (adj.incident(e), adj.incident_forward(e));
                    if inc.len() != 2 || fw[0] == fw[1] {
                        return false;
                    }
                    for (h, other) in [(inc[0], inc[1]), (inc[1], inc[0])] {
                        across[h as usize].store(other / 3, Relaxed);
                        edge[h as usize].store(e as u32, Relaxed);
                    }
                    true
                });
                let triples = |a: &[AtomicU32]| -> Vec<[u32; 3]> {
                    a.par_chunks(3)
                        .map(|c| [c[0].load(Relaxed), c[1].load(Relaxed), c[2].load(Relaxed)])
                        .collect()
                };
                let faces = triples(&across);
                (paired && faces.par_iter().all(|n| !n.contains(&u32::MAX))).then(|| {
                    FaceNeighbors {
                        faces,
                        edges: triples(&edge),
                    }
                })
            })
            .as_ref()
    }

    /// The per-face planes of the rim pre-selection ([`crate::hull::rim_candidates`]), built
    /// on first use.
    pub fn face_planes(&self) -> &crate::hull::FacePlanes {
        self.planes
            .get_or_init(|| crate::hull::FacePlanes::new(&self.vertices, &self.faces))
    }

    /// [`Mesh::vertex_normals`], computed on first use and kept (the same values).
    pub fn cached_vertex_normals(&self) -> &[[f64; 3]] {
        self.normals.get_or_init(|| self.vertex_normals())
    }

    /// The length of the longest face edge (`|b - a|` over the three edges of every face),
    /// computed on first use and kept.
    pub fn longest_edge(&self) -> f64 {
        *self.longest.get_or_init(|| {
            let v = &self.vertices;
            self.faces
                .par_iter()
                .map(|f| {
                    (0..3)
                        .map(|k| {
                            let (a, b) = (v[f[k] as usize], v[f[(k + 1) % 3] as usize]);
                            let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                            dot(d, d).sqrt()
                        })
                        .fold(0.0, f64::max)
                })
                .reduce(|| 0.0, f64::max)
        })
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
                        let fw = adj.incident_forward(e);
                        (0, 0, usize::from(fw[0] == fw[1]))
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
        return Err(Error::shape(
            "vertices",
            format!("too many vertices ({})", vertices.len()),
        ));
    }
    let bad_vertex = |v: &[f64; 3]| v.iter().any(|x| !x.is_finite());
    if !vertices
        .par_iter()
        .with_min_len(8192)
        .all(|v| !bad_vertex(v))
    {
        let bad = vertices.iter().position(bad_vertex).unwrap_or(0);
        return Err(Error::value(
            "vertices",
            format!("vertex {bad} is NaN or inf"),
        ));
    }
    Ok(())
}

/// `(b - a) x (c - a)`, evaluated exactly as numpy's `np.cross(b - a, c - a)` in the vertices'
/// own precision (f64 for meshes, f32 for the blur shell's snapshots).
#[inline]
pub fn face_normal<T>(v: &[[T; 3]], f: &[u32; 3]) -> [T; 3]
where
    T: Copy + std::ops::Sub<Output = T> + std::ops::Mul<Output = T>,
{
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

pub use crate::adjacency::build_adjacency;

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> Mesh {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
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
        // Each face's neighbour across edge k runs that edge the other way.
        let nbr = m.face_neighbors().expect("closed");
        for (f, n) in nbr.faces.iter().enumerate() {
            for (k, &across) in n.iter().enumerate() {
                let (a, b) = (m.faces()[f][k], m.faces()[f][(k + 1) % 3]);
                let g = m.faces()[across as usize];
                assert!((0..3).any(|j| g[j] == b && g[(j + 1) % 3] == a));
                assert_eq!(adj.edges[nbr.edges[f][k] as usize], [a.min(b), a.max(b)]);
            }
        }
        // An open mesh has none; a deformed copy shares the cached table.
        let open = Mesh::new(m.vertices().to_vec(), m.faces()[..3].to_vec()).unwrap();
        assert!(open.face_neighbors().is_none());
        let moved = m.with_vertices(vec![[1.0; 3]; 4]).unwrap();
        assert!(std::ptr::eq(moved.face_neighbors().unwrap(), nbr));
    }

    #[test]
    fn open_and_nonmanifold_edges_are_counted() {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, -1.0, 0.0],
        ];
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
        let faces: Vec<[u32; 3]> = (0..50000u32)
            .map(|i| [i % 4999, (i * 7 + 1) % 4999, (i * 13 + 5) % 4999])
            .collect();
        let a = crate::on_threads(1, || build_adjacency(&faces, 4999));
        let b = crate::on_threads(3, || build_adjacency(&faces, 4999));
        assert_eq!(a, b);
        // Against a plain sort of all half-edges.
        let mut all: Vec<(u32, u32, u32)> = Vec::new();
        for (i, f) in faces.iter().enumerate() {
            for k in 0..3 {
                let (x, y) = (f[k], f[(k + 1) % 3]);
                if x != y {
                    all.push((x.min(y), x.max(y), 3 * i as u32 + k as u32));
                }
            }
        }
        all.sort_unstable();
        assert_eq!(a.half_edges, all.iter().map(|t| t.2).collect::<Vec<_>>());
        let mut keys: Vec<[u32; 2]> = all.iter().map(|t| [t.0, t.1]).collect();
        keys.dedup();
        assert_eq!(a.edges, keys);
    }
}
