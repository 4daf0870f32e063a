//! A camera moved by rigid keyframes ([`MovingCamera`]): its image, its projection and its
//! camera-to-world pose at rest, `pose(t) = motion(t) @ pose`.
use glam::DMat4;

use crate::motion::{mat4_mul, Keyframes, Mat4};

/// A camera moved over the shutter by rigid keyframes (or still). Matrices row-major.
#[derive(Clone, Copy)]
pub struct MovingCamera<'a> {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The projection.
    pub projection: Mat4,
    /// Camera-to-world pose at rest.
    pub pose: Mat4,
    /// The camera's rigid motion, or None.
    pub motion: Option<&'a Keyframes>,
}

impl MovingCamera<'_> {
    /// The view-projection at shutter time `t`: `projection @ inverse(motion(t) @ pose)` (the
    /// inverse glam's, which may differ from numpy's LAPACK one in the last bits).
    pub fn view_projection_at(&self, t: f64) -> Mat4 {
        let pose = match self.motion {
            Some(m) => mat4_mul(&m.transform_at(t), &self.pose),
            None => self.pose,
        };
        // Rows of the inverse: glam's matrices are column-major.
        let view = DMat4::from_cols_array_2d(&pose)
            .transpose()
            .inverse()
            .transpose()
            .to_cols_array_2d();
        mat4_mul(&self.projection, &view)
    }
}
