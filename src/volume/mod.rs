//! Motion volumes (Wloka and Zeleznik, sections 3.3-3.4 and 4.1-4.3).
//!
//! For keyframes `T_0 .. T_n` (shutter open to close, see [`Path`](crate::motion::Path)) and the summed
//! motion vector `M` (displacement from `T_0` to `T_n`; for a translation path exactly the
//! difference of the translations), faces are split in object space into front (`n . m >= 0`,
//! `m = L_n^-1 M`) and back. The volume is:
//! - the *leading* surface: the front faces placed by `T_n` (shutter close), part 0;
//! - the *trailing* surface: the back faces placed by `T_0` (shutter open), part 1;
//! - the *joining* surface, part 2: for every contour edge `(a, b)` and segment `j`, the quad
//!   `a_{j-1} b_{j-1} b_j a_j` between the contour placed by `T_{j-1}` and by `T_j` (two
//!   triangles), so the contour is oriented at every keyframe time (section 4.3).
//!
//! Without a camera, joining vertices at the first and last ring are the trailing and leading
//! vertices themselves, so a closed, consistently wound mesh gives a closed, consistently wound
//! volume. With a camera, only the contour line is swept (edges with an adjacent face that faces
//! the camera: front faces placed at close, back faces at open) and every joining quad strip has
//! its own vertices, so that section 4.1's rule can apply per edge: when only the trailing
//! (leading) side is visible, all joining vertices of the edge take the trailing (leading)
//! normal. Colours are uniform, per mesh vertex (so leading and trailing colours of an edge
//! agree) or per face (see [`Colors`]).
//!
//! Normals are rotated by each ring's keyframe. Alpha comes from the shutter [`Filter`] and
//! multiplies the colour's own (straight) alpha. If every keyframe is the same, the result is the
//! mesh itself placed by `T_0`, all leading and opaque (colour alpha only).
//!
//! Files: `types.rs` (options and result), `build.rs` (the construction), `select.rs` (the
//! contour edges swept), `assemble.rs` (surfaces and attributes) with `sides.rs` (its leading
//! and trailing faces) and `refine.rs` (faces cut where linear alphas miss the coverage),
//! `filter.rs` (shutter filters), `coverage.rs` (coverage alphas), `hulls.rs` and `rim.rs` (the
//! coverage model's projected hulls), `subdivide.rs` (finer meshes for the alphas), `spin.rs`
//! (section 4.3's spinning objects) and `polar.rs` (their occupancy seen along the axis).
mod assemble;
mod build;
mod coverage;
mod filter;
mod hulls;
mod polar;
mod refine;
mod rim;
mod select;
mod sides;
mod spin;
mod subdivide;
mod types;

pub use build::motion_volume;
pub use filter::Filter;
pub use spin::{spin_volume, Spin};
pub use types::{
    check_segments, subdivided, Colors, MotionVolume, VolumeOptions, JOINING, LEADING,
    MAX_SEGMENTS, TRAILING,
};
