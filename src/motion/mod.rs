//! The one keyframe interpolation engine: rigid and deforming keyframes over the shutter,
//! validated and split once, sampled at any time; the motion volume's paths built on it.
//!
//! - `numeric`: small matrix arithmetic in one fixed order (numpy's, see the module);
//! - `similarity`: one rigid keyframe split into translation, rotation and scale, and the
//!   interpolation of two;
//! - `keyframes`: keyframes at sorted times in [0, 1], rigid or deforming, sampled at any time;
//! - `camera`: a camera moved by rigid keyframes, its view-projection at any time;
//! - `path`: equally spaced keyframes of a motion volume and the placements applied to points;
//! - `sweep`: how far moving outlines travel on screen, the planner's forecast of accumulation's
//!   error.
mod camera;
mod keyframes;
mod numeric;
mod path;
mod similarity;
mod sweep;

pub use camera::MovingCamera;
pub use keyframes::{check_times, uniform_times, Keyframes, Keys};
pub use numeric::{
    det3, dot, linear_part, mat4_mul, norm, place, row_times, translation_part, transpose_times,
    turn, Mat3, Mat4, IDENTITY4,
};
pub(crate) use path::Placer;
pub use path::{Keyframe, Path};
pub use similarity::{axis_angle, Similarity};
pub use sweep::{sweep, Sweep, SweepObject, SWEEP_POINTS, SWEEP_SHADE, SWEEP_TIMES};
