//! The accumulation buffer's kernels: the weighted, depth-tested sum of a moving layer, the
//! composite and resolve of layers, and the conservative back-face selection of a translating
//! mesh.
mod facing;
mod kernels;

pub use facing::facing_faces;
pub use kernels::{accumulate, composite, over, resolve, Rect};
