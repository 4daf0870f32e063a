//! motionblur core: object-space motion volumes, blur shells, a CPU rasterizer and
//! image-space blur, in pure Rust. The Python binding lives in `python/` behind the
//! `python` feature and is the only place that knows about PyO3.
//!
//! One private module per pipeline stage, its API re-exported here:
//! - `mesh`: indexed triangle meshes, their adjacency, normals and face planes;
//! - `motion`: rigid keyframes over the shutter;
//! - `contour`: contour edges of a rigid motion and the silhouette of motion of a deforming
//!   mesh;
//! - `volume`: motion volumes (Wloka and Zeleznik);
//! - `shell`: blur shells (Jones and Keyser);
//! - `accumulate`: the accumulation buffer's kernels;
//! - `raster`: the software rasterizer;
//! - `image`: image-space blur;
//! - `analytic`: analytic motion blur, exact covered time per sample;
//! - `shutter`: the shutter filters.
#![warn(missing_docs)]

mod accumulate;
mod analytic;
mod contour;
mod error;
mod image;
mod mesh;
mod motion;
mod raster;
mod shell;
mod shutter;
mod volume;

#[cfg(feature = "python")]
mod python;

pub use accumulate::{accumulate, composite, facing_faces, over, resolve, Rect};
pub use analytic::{
    render as render_analytic, Backdrop, Frame as AnalyticFrame, Input as AnalyticInput,
    MovingDraw, Quadrature, Stats as AnalyticStats, DEFAULT_TILE_BUDGET as ANALYTIC_TILE_BUDGET,
};
pub use contour::{
    contour_edges, contour_pairs, motion_silhouette, ContourEdge, ContourSet, ContourTable,
};
pub use error::{Error, Result};
pub use image::{
    box_blur, camera_motion_blur, camera_velocity, colored, depth_of_field, glow, opaque_blur,
    opaque_motion_blur, pixel_bounds, pyramid_blur, pyramid_glow, pyramid_opaque_blur,
    sample_colors, scatter_pieces, splat_paths, velocity_blur, CameraMatrices, Composite,
    DofParams, Piece,
};
pub use mesh::{Adjacency, FaceNeighbors, Mesh, MeshStats};
pub use motion::{Keyframe, Path};
pub use raster::{
    faces_from_i64, rasterize, rasterize_over, Background, Blend, Camera, Draw, Frame, Light,
    Options as RasterOptions, Shading, Stats as RasterStats,
};
pub use shell::{
    BlurShell, BuildPlan, FaceState, ShellColor, ShellMesh, ShellOptions, ShellOut, ON_SILHOUETTE,
};
pub use shutter::Shutter;
pub use volume::{
    motion_volume, spin_volume, Colors, Filter, MotionVolume, Spin, VolumeOptions, JOINING,
    LEADING, MAX_SEGMENTS, TRAILING,
};

/// `f` run on a rayon pool of `n` threads (tests of thread-count independence).
#[cfg(test)]
pub(crate) fn on_threads<T: Send>(n: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
        .install(f)
}
