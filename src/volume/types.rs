//! The motion volume's options and result, shared by its construction, assembly and
//! subdivision.
use rayon::prelude::*;

use std::sync::Arc;

use super::filter::Filter;
use crate::contour::ContourTable;
use crate::error::check_vector;
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::motion::Path;

/// [`MotionVolume::part`] of a leading face (front faces placed at shutter close).
pub const LEADING: u8 = 0;
/// [`MotionVolume::part`] of a trailing face (back faces placed at shutter open).
pub const TRAILING: u8 = 1;
/// [`MotionVolume::part`] of a joining face (the swept contour).
pub const JOINING: u8 = 2;

/// Largest number of segments accepted (joining segments of a volume, sweep steps of a spin).
pub const MAX_SEGMENTS: usize = 4096;

/// Checks a number of segments: in `1..=MAX_SEGMENTS` (for a volume: in total, keyframe
/// intervals times the segments each is cut into). Errors name `segments`.
pub fn check_segments(n: usize) -> Result<()> {
    if n == 0 || n > MAX_SEGMENTS {
        return Err(Error::value(
            "segments",
            format!("must be in 1..={MAX_SEGMENTS} (in total), got {n}"),
        ));
    }
    Ok(())
}

/// `path` with every interval cut into `segments` joining segments, checked first
/// ([`check_segments`] of the total) so that nothing is allocated for an absurd count.
pub fn subdivided(path: &Path, segments: usize) -> Result<Path> {
    check_segments(path.segments().saturating_mul(segments))?;
    Ok(path.subdivide(segments))
}

/// Colours: one straight RGBA for all, one per mesh vertex, or one per mesh face.
///
/// With per-face colours every leading and trailing face has its own three vertices and every
/// joining strip its own vertices, coloured from the strip's front face (leading end) to its back
/// face (trailing end), or with the visible side's colour only when the camera sees one side
/// (section 4.1); the volume is then closed geometrically but not as an indexed mesh.
#[derive(Debug, Clone)]
pub enum Colors {
    /// One straight RGBA for every vertex.
    Uniform([f32; 4]),
    /// One straight RGBA per mesh vertex.
    PerVertex(Vec<[f32; 4]>),
    /// One straight RGBA per mesh face.
    PerFace(Vec<[f32; 4]>),
}

/// Options of [`motion_volume`](crate::motion_volume).
#[derive(Debug, Clone)]
pub struct VolumeOptions {
    /// The shutter filter of the alphas.
    pub filter: Filter,
    /// The colours of the volume's vertices.
    pub colors: Colors,
    /// Per-vertex normals in object space; `None`: area-weighted vertex normals.
    pub normals: Option<Vec<[f64; 3]>>,
    /// The camera position (world units), for the contour line, the section 4.1 normal rule
    /// and the coverage model's view.
    pub camera: Option<[f64; 3]>,
    /// With a camera: sweep only the contour line (section 3.2) and apply the section 4.1
    /// normal rule (`true`), or sweep every contour edge and use the camera for the coverage
    /// alphas only (`false`).
    pub contour_line: bool,
    /// With a camera and `contour_line`: leave out the leading faces that face away from the
    /// camera at shutter close and the trailing faces that face away at open (a renderer that
    /// culls back faces draws the same image from fewer faces; the volume is then open).
    pub visible_only: bool,
    /// Precomputed contour sets of the mesh (section 4.4): the face split and contour edges of
    /// the stored direction nearest the summed motion replace the ones computed for it
    /// ([`MotionVolume::contour_error`] is the angle between the two).
    pub contours: Option<Arc<ContourTable>>,
    /// The part `(a, b)` of the shutter the path stands for (`0 <= a < b <= 1`): its keyframe
    /// times `i / n` are the shutter times `a + (b - a) i / n`, and the coverage alphas weigh the
    /// time by the filter over `[a, b]`, normalised to unit weight (a piece of a shutter cut into
    /// several volumes; `(0, 1)`: the whole shutter). The ramp ignores it.
    pub window: (f64, f64),
}

impl Default for VolumeOptions {
    fn default() -> Self {
        VolumeOptions {
            filter: Filter::Ramp,
            colors: Colors::Uniform([1.0; 4]),
            normals: None,
            camera: None,
            contour_line: true,
            visible_only: false,
            contours: None,
            window: (0.0, 1.0),
        }
    }
}

/// The assembled motion volume.
#[derive(Debug, Clone, PartialEq)]
pub struct MotionVolume {
    /// World positions (V,3).
    pub vertices: Vec<[f64; 3]>,
    /// Counter-clockwise triangles (F,3) over `vertices`.
    pub faces: Vec<[u32; 3]>,
    /// Straight (non-premultiplied) linear RGBA per vertex.
    pub rgba: Vec<[f32; 4]>,
    /// Unit normals per vertex (zero where the mesh normal is undefined).
    pub normals: Vec<[f32; 3]>,
    /// `LEADING`, `TRAILING` or `JOINING` per face.
    pub part: Vec<u8>,
    /// Opacity of each contour ring, open (index 0) to close (index n).
    pub ring_alpha: Vec<f64>,
    /// Number of contour edges swept.
    pub contour_edges: usize,
    /// With [`VolumeOptions::contours`], the angle (radians) between the summed motion and the
    /// stored direction whose contour was swept; 0 otherwise.
    pub contour_error: f64,
}

/// Checks the colours, normals and camera of `opts` against `mesh`, naming the argument.
pub(crate) fn check_options(mesh: &Mesh, opts: &VolumeOptions) -> Result<()> {
    let nv = mesh.vertices().len();
    let check_rgba = |c: &[f32; 4]| {
        c.iter().all(|x| x.is_finite())
            && c[..3].iter().all(|x| *x >= 0.0)
            && (0.0..=1.0).contains(&c[3])
    };
    match &opts.colors {
        Colors::Uniform(c) if !check_rgba(c) => {
            return Err(Error::value(
                "colors",
                "must be finite, RGB >= 0 and alpha in [0, 1]",
            ));
        }
        Colors::PerFace(c) => {
            let nf = mesh.faces().len();
            if c.len() != nf {
                return Err(Error::shape(
                    "face_colors",
                    format!("expected {nf} colours, got {}", c.len()),
                ));
            }
            if !c.par_iter().all(check_rgba) {
                return Err(Error::value(
                    "face_colors",
                    "must be finite, RGB >= 0 and alpha in [0, 1]",
                ));
            }
        }
        Colors::PerVertex(c) => {
            if c.len() != nv {
                return Err(Error::shape(
                    "colors",
                    format!("expected {nv} colours, got {}", c.len()),
                ));
            }
            if !c.par_iter().all(check_rgba) {
                return Err(Error::value(
                    "colors",
                    "must be finite, RGB >= 0 and alpha in [0, 1]",
                ));
            }
        }
        _ => {}
    }
    if let Some(n) = &opts.normals {
        if n.len() != nv {
            return Err(Error::shape(
                "normals",
                format!("expected {nv} normals, got {}", n.len()),
            ));
        }
        if !n.par_iter().all(|x| x.iter().all(|c| c.is_finite())) {
            return Err(Error::value("normals", "is NaN or inf"));
        }
    }
    if let Some(eye) = opts.camera {
        check_vector(eye, "camera_position")?;
    }
    let (a, b) = opts.window;
    if !(0.0 <= a && a < b && b <= 1.0) || opts.filter.weight(a, b) <= 0.0 {
        return Err(Error::value(
            "window",
            format!("must be 0 <= a < b <= 1 with a positive filter weight, got ({a}, {b})"),
        ));
    }
    Ok(())
}
