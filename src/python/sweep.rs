//! Binding for the planner's forecast: `_sweep` and its constants `SWEEP_TIMES`,
//! `SWEEP_POINTS`, `SWEEP_SHADE`.
use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use super::geometry::PyMesh;
use super::motion::PyKeyframes;
use super::segments::mat4;
use crate::{sweep, Error, MovingCamera, SweepObject, SWEEP_POINTS, SWEEP_SHADE, SWEEP_TIMES};

/// One object, the items of a dict: `mesh` (a `_Mesh`, object space), `motion` (its
/// `_Keyframes`, rigid or deforming, or None) and `rgba` (K,4) float64 straight colours: one,
/// or one a vertex.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct ObjectArg<'py> {
    mesh: Bound<'py, PyMesh>,
    motion: Option<Bound<'py, PyKeyframes>>,
    rgba: PyReadonlyArray2<'py, f64>,
}

/// The options of one `_sweep` call, the items of a dict: `objects` (a list of
/// [`ObjectArg`]), the image's `width` and `height` (pixels), the camera's `projection` and
/// `pose` (4,4) float64, `camera_motion` (its `_Keyframes` or None) and `background` (4,)
/// float64 straight RGBA.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct SweepArgs<'py> {
    objects: Vec<ObjectArg<'py>>,
    width: u32,
    height: u32,
    projection: PyReadonlyArray2<'py, f64>,
    pose: PyReadonlyArray2<'py, f64>,
    camera_motion: Option<Bound<'py, PyKeyframes>>,
    background: PyReadonlyArray1<'py, f64>,
}

/// A (4,) float64 vector; errors name `name`.
fn vec4(a: &PyReadonlyArray1<'_, f64>, name: &'static str) -> Result<[f64; 4], Error> {
    match a.as_slice() {
        Ok(&[r, g, b, al]) => Ok([r, g, b, al]),
        _ => Err(Error::shape(
            name,
            format!("expected a contiguous (4,), got {:?}", a.shape()),
        )),
    }
}

/// The rows of a contiguous (K,4) float64 array; errors name `name`.
fn rows4(a: &PyReadonlyArray2<'_, f64>, name: &'static str) -> Result<Vec<[f64; 4]>, Error> {
    match a.as_slice() {
        Ok(v) if a.shape()[1] == 4 => Ok(v
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect()),
        _ => Err(Error::shape(
            name,
            format!("expected a contiguous (K, 4), got {:?}", a.shape()),
        )),
    }
}

/// The screen sweep of `options` ([`SweepArgs`]) and the path of its outlines (`scale`,
/// `path`); see `motionblur.methods._sweep`.
#[pyfunction]
fn _sweep(options: SweepArgs<'_>) -> PyResult<(f64, f64)> {
    let o = &options;
    let colours = o
        .objects
        .iter()
        .map(|x| rows4(&x.rgba, "rgba"))
        .collect::<Result<Vec<_>, Error>>()?;
    let objects: Vec<SweepObject<'_>> = o
        .objects
        .iter()
        .zip(&colours)
        .map(|(x, rgba)| SweepObject {
            mesh: &x.mesh.get().inner,
            motion: x.motion.as_ref().map(|k| &*k.get().inner),
            rgba,
        })
        .collect();
    let camera = MovingCamera {
        width: o.width,
        height: o.height,
        projection: mat4(&o.projection, "projection")?,
        pose: mat4(&o.pose, "pose")?,
        motion: o.camera_motion.as_ref().map(|k| &*k.get().inner),
    };
    let found = sweep(&objects, &camera, vec4(&o.background, "background")?);
    Ok((found.scale, found.path))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_sweep, m)?)?;
    m.add("SWEEP_TIMES", SWEEP_TIMES)?;
    m.add("SWEEP_POINTS", SWEEP_POINTS)?;
    m.add("SWEEP_SHADE", SWEEP_SHADE)?;
    Ok(())
}
