//! Analytic motion blur: for every sample, the exact set of shutter times during which each
//! moving triangle covers it, visibility resolved over time, colour integrated with the
//! shutter filter.
//!
//! This is Korein and Badler's continuous algorithm (1983) in the rasterizer form of Gribel,
//! Doggett and Akenine-Möller (2010). The shutter is cut into segments (`times`); within each
//! every vertex moves linearly in clip space, so each edge function of a triangle at a sample
//! is a quadratic in time and the covered times are found from its roots (`prim.rs`, `poly.rs`).
//! Rigid keyframes, deforming meshes and camera motion all reduce to this: the caller gives the
//! world positions at the segment boundaries and the camera's view-projection at each.
//!
//! Pipeline of one frame ([`render`]):
//! 1. clip positions of every vertex at every boundary (camera of that instant);
//! 2. prims: each face over each segment, set up once (orientation cubic, swept hull, bounds);
//!    faces back-facing throughout a segment (with culling) or outside the view are dropped;
//! 3. binning into tiles of 32 x 32 samples by the swept hull (`hull.rs`);
//! 4. tiles in parallel: each prim's covered spans at the tile's samples become fragments; per
//!    sample, the sweep (`visibility.rs`) orders them in depth over time (linear depth per
//!    triangle, split where two cross) over the static backdrop, and [`resolve`] shades the
//!    visible pieces at Gauss points in time;
//! 5. the box resolve of each pixel's samples (colour mean; depth, id and velocity of the
//!    nearest sample);
//! 6. on request ([`Input::exposure`]), the exposure channel: per sample, the object in front
//!    on each piece of the sweep with the filter's weight of its time and its first and last
//!    instant; per pixel, the mean weight and the extreme instants over its samples.
//!
//! The segments' boundaries come from the caller; [`segment_times`] is the method's own rule
//! for them (`segments.rs`).
//!
//! Depth, ids and velocity describe the surface in front at the reference time. Every step is
//! deterministic per sample, so the output does not depend on the thread count.
// Numeric kernels: index loops over corners and coefficients read like the formulas, and
// `!(a > b)` deliberately counts NaN as failing (as in raster/).
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

mod chain;
mod clip;
mod frame;
mod hull;
mod input;
mod poly;
mod prim;
mod quadrature;
mod resolve;
mod segments;
mod shade;
mod strips;
mod tiles;
mod transform;
mod visibility;

#[cfg(test)]
mod tests;

pub use frame::{render, Stats};
pub use input::{Input, MovingDraw, Rolling, DEFAULT_TILE_BUDGET};
pub use quadrature::Quadrature;
pub use segments::{
    segment_times, SegmentCamera, SegmentObject, DEFORMING_POINTS, MAX_SEGMENTS, MIN_PIECE,
    NORMAL_TOLERANCE,
};
pub use transform::transform_points;
