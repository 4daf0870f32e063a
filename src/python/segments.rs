//! Binding for the analytic method's segment rule: `_segment_times` (GIL released) and its
//! limits `ANALYTIC_MAX_SEGMENTS`, `ANALYTIC_MIN_PIECE`, `ANALYTIC_NORMAL_TOLERANCE`.
use numpy::{PyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use super::convert::detached_in_pool;
use super::geometry::PyMesh;
use super::motion::PyKeyframes;
use crate::{
    segment_times, Error, Mat4, MovingCamera, SegmentCamera, SegmentObject, ANALYTIC_MAX_SEGMENTS,
    ANALYTIC_MIN_PIECE, ANALYTIC_NORMAL_TOLERANCE,
};

/// One object, the items of a dict: `mesh` (a `_Mesh`, object space), `motion` (its
/// `_Keyframes`, rigid or deforming, or None) and `lambert` (lambert shaded).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct ObjectArg<'py> {
    mesh: Bound<'py, PyMesh>,
    motion: Option<Bound<'py, PyKeyframes>>,
    lambert: bool,
}

/// The options of one `_segment_times` call, the items of a dict: `objects` (a list of
/// [`ObjectArg`]), the image's `width`, `height` (pixels) and `znear`, the scene camera's
/// `view_projection`, `projection` and `pose` (4,4) float64, `camera_motion` (its
/// `_Keyframes` or None) and `tolerance` (pixels).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct SegmentArgs<'py> {
    objects: Vec<ObjectArg<'py>>,
    width: u32,
    height: u32,
    znear: f64,
    view_projection: PyReadonlyArray2<'py, f64>,
    projection: PyReadonlyArray2<'py, f64>,
    pose: PyReadonlyArray2<'py, f64>,
    camera_motion: Option<Bound<'py, PyKeyframes>>,
    tolerance: f64,
}

/// A (4,4) float64 matrix of any layout, rows first; errors name `name`.
pub(super) fn mat4(a: &PyReadonlyArray2<'_, f64>, name: &'static str) -> Result<Mat4, Error> {
    if a.shape() != [4, 4] {
        return Err(Error::shape(
            name,
            format!("expected shape (4,4), got {:?}", a.shape()),
        ));
    }
    let v = a.as_array();
    Ok(std::array::from_fn(|r| std::array::from_fn(|c| v[[r, c]])))
}

/// (K+1,) float64 segment boundaries from 0 to 1 of the analytic method's rule for `options`
/// ([`SegmentArgs`]); see `motionblur.methods.analytic.segment_times`.
#[pyfunction]
fn _segment_times<'py>(
    py: Python<'py>,
    options: SegmentArgs<'py>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let o = &options;
    // The pyclasses are frozen: their cores are borrowed for the call, never copied.
    let objects: Vec<SegmentObject> = o
        .objects
        .iter()
        .map(|x| SegmentObject {
            mesh: &x.mesh.get().inner,
            motion: x.motion.as_ref().map(|k| &*k.get().inner),
            lambert: x.lambert,
        })
        .collect();
    let camera = SegmentCamera {
        view: MovingCamera {
            width: o.width,
            height: o.height,
            projection: mat4(&o.projection, "projection")?,
            pose: mat4(&o.pose, "pose")?,
            motion: o.camera_motion.as_ref().map(|k| &*k.get().inner),
        },
        znear: o.znear,
        view_projection: mat4(&o.view_projection, "view_projection")?,
    };
    let tolerance = o.tolerance;
    let times = detached_in_pool(py, || segment_times(&objects, &camera, tolerance))?;
    Ok(PyArray1::from_vec(py, times))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_segment_times, m)?)?;
    m.add("ANALYTIC_MAX_SEGMENTS", ANALYTIC_MAX_SEGMENTS)?;
    m.add("ANALYTIC_MIN_PIECE", ANALYTIC_MIN_PIECE)?;
    m.add("ANALYTIC_NORMAL_TOLERANCE", ANALYTIC_NORMAL_TOLERANCE)?;
    Ok(())
}
