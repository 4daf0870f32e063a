//! The indexed triangle mesh: validation, the cached adjacency, normals and planes, statistics.
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::OnceLock;

use rayon::prelude::*;

use super::adjacency::{build_adjacency, Adjacency, FaceNeighbors};
use super::normals::{self, dot, face_normal, FacePlanes};
use crate::error::{Error, Result};

/// The one coordinate range of every entry point: the largest accepted |component| of any
/// position, translation or point, in scene units. Face normals multiply two coordinate
/// differences and `n . d` a third, which stays below `f32::MAX` (3.4e38) at this bound (the
/// blur shell's facing test runs in float32); the rasterizer's f64 transforms keep every
/// fractional bit a pixel needs; float32 positions near it are 64 units apart anyway.
pub const MAX_COORD: f64 = 1e9;

/// Largest number of faces or vertices accepted (indices are stored as `u32`).
pub const MAX_ELEMENTS: usize = (u32::MAX as usize) / 8;

/// Counts describing a mesh's health.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MeshStats {
    /// Number of faces.
    pub faces: usize,
    /// Number of vertices.
    pub vertices: usize,
    /// Number of undirected edges.
    pub edges: usize,
    /// Faces with a zero cross product.
    pub degenerate_faces: usize,
    /// Edges with one face.
    pub boundary_edges: usize,
    /// Edges with three or more faces.
    pub nonmanifold_edges: usize,
    /// Edges whose two faces run them in the same direction.
    pub inconsistent_edges: usize,
    /// Vertices no face uses.
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
    /// Per face, the face across each of its edges and that edge's index, when every edge has
    /// exactly two faces that run it in opposite directions (built from the adjacency on first
    /// use).
    neighbors: std::sync::Arc<OnceLock<Option<FaceNeighbors>>>,
    /// [`Mesh::face_planes`], built on first use (not shared with deformed copies).
    planes: OnceLock<FacePlanes>,
    /// [`Mesh::vertex_normals`], kept by [`Mesh::cached_vertex_normals`].
    normals: OnceLock<Vec<[f64; 3]>>,
    /// [`Mesh::face_normals_raw`], kept by [`Mesh::repeated_face_normals_raw`].
    face_normals: OnceLock<Vec<[f64; 3]>>,
    /// Whether [`Mesh::repeated_face_normals_raw`] has been asked before.
    asked_normals: AtomicBool,
    /// [`Mesh::longest_edge`], computed on first use.
    longest: OnceLock<f64>,
}

impl Mesh {
    /// Unnormalised face normals `(b - a) x (c - a)` (twice the area), in vertex units squared.
    pub fn face_normals_raw(&self) -> Vec<[f64; 3]> {
        normals::face_normals_raw(self.vertices(), self.faces())
    }

    /// Unit face normals; degenerate faces get `[0, 0, 0]`.
    pub fn face_normals(&self) -> Vec<[f64; 3]> {
        normals::face_normals(self.vertices(), self.faces())
    }

    /// Area-weighted vertex normals (sum of the raw normals of the faces around the vertex),
    /// normalised; a vertex with no non-degenerate face gets `[0, 0, 0]`.
    pub fn vertex_normals(&self) -> Vec<[f64; 3]> {
        normals::vertex_normals(self.vertices(), self.faces())
    }

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
            face_normals: Default::default(),
            asked_normals: Default::default(),
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
            face_normals: Default::default(),
            asked_normals: Default::default(),
            longest: Default::default(),
        })
    }

    /// Vertex positions (scene units).
    pub fn vertices(&self) -> &[[f64; 3]] {
        &self.vertices
    }
    /// Counter-clockwise triangles over `vertices`.
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
            .get_or_init(|| self.adjacency().face_neighbors(self.faces.len()))
            .as_ref()
    }

    /// The per-face planes ([`FacePlanes`]), built on first use.
    pub(crate) fn face_planes(&self) -> &FacePlanes {
        self.planes
            .get_or_init(|| FacePlanes::new(&self.vertices, &self.faces))
    }

    /// [`Mesh::face_normals_raw`] kept for a mesh whose faces are classified again and again (a
    /// rigid object against a new motion every frame): `None` on the first call, when the
    /// caller computes what it needs from the corners (a deformed mesh, used once, stores
    /// nothing); from the second call on, the normals, computed then and kept (the same values,
    /// 24 bytes a face; not shared with deformed copies).
    pub fn repeated_face_normals_raw(&self) -> Option<&[[f64; 3]]> {
        if let Some(n) = self.face_normals.get() {
            return Some(n);
        }
        if !self.asked_normals.swap(true, Ordering::Relaxed) {
            return None;
        }
        Some(self.face_normals.get_or_init(|| self.face_normals_raw()))
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
    let bad_vertex = |v: &[f64; 3]| v.iter().any(|x| x.is_nan() || x.abs() > MAX_COORD);
    if !vertices
        .par_iter()
        .with_min_len(8192)
        .all(|v| !bad_vertex(v))
    {
        let bad = vertices.iter().position(bad_vertex).unwrap_or(0);
        let row = vertices[bad];
        if row.iter().all(|x| x.is_finite()) {
            return Err(Error::value(
                "vertices",
                format!(
                    "vertex {bad} ({row:?}) is beyond the coordinate range +-{MAX_COORD:e} \
                     (MAX_COORD)"
                ),
            ));
        }
        return Err(Error::value(
            "vertices",
            format!("vertex {bad} is NaN or inf"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coordinates_past_the_range_are_refused_naming_the_vertex() {
        let f = vec![[0, 1, 2]];
        let at = |y: f64| vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, y, 0.0]];
        Mesh::new(at(MAX_COORD), f.clone()).unwrap();
        Mesh::new(at(-MAX_COORD), f.clone()).unwrap();
        let e = Mesh::new(at(MAX_COORD * 1.5), f.clone())
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("vertices: vertex 2") && e.contains("coordinate range"),
            "{e}"
        );
        let e = Mesh::new(at(f64::NAN), f).unwrap_err().to_string();
        assert_eq!(e, "vertices: vertex 2 is NaN or inf");
    }

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
}
