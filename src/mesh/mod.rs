//! Indexed triangle meshes: validation, edge and vertex adjacency, face normals and face planes.
//!
//! Vertices are `[f64; 3]` in scene units, faces are `[u32; 3]` counter-clockwise seen from the
//! front. The edge adjacency is built once (counting sort by the lower vertex, then a short sort
//! per vertex bucket) and cached by the [`Mesh`], so a mesh can be classified against many
//! motion vectors, or given new vertex positions with [`Mesh::with_vertices`], without
//! rebuilding it.
//!
//! Edge rules (documented in the Python API too):
//! - an undirected edge is the set of half-edges `(a, b)` / `(b, a)` of the faces that use it;
//!   a face with a repeated index has a zero-length half-edge `(a, a)`, which is not an edge;
//! - a *boundary* edge has one incident face, a *non-manifold* edge three or more, an
//!   *inconsistent* edge two faces that run it in the same direction;
//! - a *degenerate* face has a zero cross product `(b - a) x (c - a)` (repeated index,
//!   collinear or coincident vertices). It keeps its place in the adjacency; its normal is zero.
mod adjacency;
mod indexed;
mod normals;
#[cfg(test)]
mod test_meshes;

pub use adjacency::{Adjacency, FaceNeighbors, VertexFaces};
pub use indexed::{Mesh, MeshStats, MAX_COORD, MAX_ELEMENTS};
pub use normals::{dot, face_normal, normalize, FacePlanes, SLIVER};
#[cfg(test)]
pub(crate) use test_meshes::{grid_faces, uv_sphere};
