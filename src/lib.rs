//! motionblur core: object-space motion volumes, blur shells, a CPU rasterizer and
//! image-space blur, in pure Rust. The Python binding lives in `python/` behind the
//! `python` feature and is the only place that knows about PyO3.
//!
//! One module per pipeline stage: `mesh` (indexed triangle meshes, adjacency), `motion`
//! (keyframes), `contour` (contour edges, silhouette of motion), `volume` (motion volumes), `shell` (blur shells),
//! `raster` (the software rasterizer), `image` (image-space blur).
//!
//! The motion volume is split into `volume` (construction), `volume_filter` (the paper's ramp),
//! `volume_alpha` (coverage alphas), `hull` (projected hulls), `volume_assemble` (surfaces and attributes), `subdivide`
//! and `spin` (section 4.3's spinning objects); `adjacency` builds the mesh adjacency.
#![allow(dead_code)]

pub mod accumulate;
pub mod contour;
mod error;
pub mod image;
pub mod mesh;
pub mod motion;
pub mod raster;
pub mod shell;
pub mod volume;

/// `f` run on a rayon pool of `n` threads (tests of thread-count independence).
#[cfg(test)]
pub(crate) fn on_threads<T: Send>(n: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
        .install(f)
}

pub use error::{Error, Result};

#[cfg(feature = "python")]
mod python;
