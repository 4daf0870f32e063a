//! motionblur core: object-space motion volumes, blur shells, a CPU rasterizer and
//! image-space blur, in pure Rust. The Python binding lives in `python/` behind the
//! `python` feature and is the only place that knows about PyO3.
//!
//! One private module per pipeline stage, its API re-exported here:
//! - `mesh`: indexed triangle meshes, their adjacency, normals and face planes;
//! - `motion`: the one keyframe interpolation engine (rigid and deforming keyframes over the
//!   shutter, the motion volume's paths);
//! - `contour`: contour edges of a rigid motion and the silhouette of motion of a deforming
//!   mesh;
//! - `volume`: motion volumes (Wloka and Zeleznik);
//! - `shell`: blur shells (Jones and Keyser);
//! - `accumulate`: the accumulation buffer's kernels;
//! - `raster`: the software rasterizer;
//! - `image`: image-space blur;
//! - `frame`: the one owned frame type and the one borrowed layer view every stage shares;
//! - `budget`: the memory budget every kernel checks before it allocates;
//! - `analytic`: analytic motion blur, exact covered time per sample, and its segment rule;
//! - `shutter`: the shutter filters;
//! - `simd`: the switch over the kernels' vector forms;
//! - `threads`: the per-process thread pool every parallel kernel runs in (safe after `fork`).
#![warn(missing_docs)]

mod accumulate;
mod analytic;
mod budget;
mod contour;
mod error;
mod frame;
mod image;
mod mesh;
mod motion;
mod raster;
mod shell;
mod shutter;
mod simd;
mod threads;
mod volume;

#[cfg(feature = "python")]
mod python;

pub use accumulate::{
    accumulate, accumulate_moving, accumulate_still, accumulate_still_parts, composite,
    facing_faces, halves, over, pixel_rect, resolve, sample_rects, window_projection, Accumulated,
    BuffersMut, HalfPart, Halves, PaintObject, Painter, Rect, Samples, StillCamera, SERIAL_PIXELS,
};
pub use analytic::{
    render as render_analytic, segment_times, transform_points, Input as AnalyticInput, MovingDraw,
    Quadrature, Rolling, SegmentCamera, SegmentObject, Stats as AnalyticStats,
    DEFAULT_TILE_BUDGET as ANALYTIC_TILE_BUDGET, DEFORMING_POINTS as ANALYTIC_DEFORMING_POINTS,
    MAX_SEGMENTS as ANALYTIC_MAX_SEGMENTS, MIN_PIECE as ANALYTIC_MIN_PIECE,
    NORMAL_TOLERANCE as ANALYTIC_NORMAL_TOLERANCE,
};
pub use budget::{
    memory_budget, set_memory_budget, Need, DEFAULT_MEMORY_BUDGET, MIN_MEMORY_BUDGET,
};
pub use contour::{
    contour_edges, contour_pairs, motion_silhouette, ContourEdge, ContourSet, ContourTable,
};
pub use error::{Error, Result};
pub use frame::{Exposure, Frame, Layer};
pub use image::{
    box_blur, camera_frame_blur, camera_motion_blur, camera_velocity, colored, coverage_blur,
    coverage_composite, depth_of_field, glow, lens_blur, max_speed, max_speed_in, object_pixels,
    one_velocity_group, opaque_blur, opaque_motion_blur, opaque_motion_blur_into, pixel_bounds,
    pyramid_blur, pyramid_glow, pyramid_opaque_blur, reconstruct, reconstruct_moving,
    sample_colors, scatter_pieces, splat_paths, velocity_blur, CameraBlur, CameraMatrices,
    Composite, CoverageObject, CoveragePart, CoverageSource, DofParams, FrameMotion, LensParams,
    ObjectPixels, Piece, ReconstructParams, MAX_FPS_RATIO, MAX_LAYERS, MAX_LENGTH, MAX_LENS_LEVELS,
    MAX_LEVELS, MAX_SAMPLES, MAX_TAPS, MAX_VELOCITY, MIN_ALPHA,
};
pub use mesh::{Adjacency, FaceNeighbors, Mesh, MeshStats, MAX_COORD};
pub use motion::{
    axis_angle, check_times, det3, dot, mat4_mul, norm, place, row_times, transpose_times, turn,
    uniform_times, Keyframe, Keyframes, Keys, Mat3, Mat4, Path, Similarity, IDENTITY4,
};
pub use motion::{sweep, MovingCamera, Sweep, SweepObject, SWEEP_POINTS, SWEEP_SHADE, SWEEP_TIMES};
pub use raster::{
    faces_from_i64, on_sample_grid, rasterize, rasterize_over, Background, Blend, Camera, Draw,
    Light, Options as RasterOptions, Shading, Stats as RasterStats, FRAGMENT_CAP,
    MAX_INTERNAL_SIDE, MAX_PIXELS, MAX_SIDE, SAMPLES,
};
pub use shell::{
    BlurShell, BuildPlan, FaceState, ShellColor, ShellMesh, ShellOptions, ShellOut, MAX_HYSTERESIS,
    MAX_SUBDIVISIONS, ON_SILHOUETTE,
};
pub use shutter::Shutter;
pub use simd::{set_simd, simd_enabled};
pub use threads::{install, num_threads, set_num_threads, MAX_THREADS, NUM_THREADS_ENV};
pub use volume::{
    check_segments, motion_volume, spin_volume, subdivided, Colors, Filter, MotionVolume, Spin,
    VolumeOptions, JOINING, LEADING, MAX_SEGMENTS, TRAILING,
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
