//! Contours of moving meshes: the contour edges of a rigid motion (Wloka and Zeleznik,
//! section 3.2) and their precomputed tables (section 4.4), and the per-vertex silhouette of
//! motion of a deforming mesh (Jones and Keyser, section 3.2).
mod edges;
mod silhouette;
mod table;

pub use edges::{
    classify_faces, classify_faces_seen, contour_edges, contour_from_sides, contour_line,
    contour_pairs, ContourEdge,
};
pub(crate) use silhouette::check_values;
pub use silhouette::{
    face_edge, face_normals_into, facing, motion_silhouette, MAX_COORD, MAX_NORMAL, NEUTRAL,
    NO_EDGE,
};
#[cfg(test)]
pub(crate) use silhouette::{BACK, FRONT};
pub use table::{ContourSet, ContourTable};
