//! Bindings for the keyframe engine: `_Keyframes`, validated once when made and sampled at
//! any time (many times in one call), and `_check_times`. The engine (`src/motion/`) is
//! sequential, no rayon call in it: its calls release the GIL but need no thread pool.
use std::sync::Arc;

use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;

use super::convert::{c_slice, rows_array, shaped, vec3};
use crate::{axis_angle, check_times, Error, Keyframes, Mat4, Similarity};

/// The argument names a caller may give the matrices (errors name it).
fn matrices_name(name: &str) -> Result<&'static str, Error> {
    match name {
        "transforms" => Ok("transforms"),
        "motion" => Ok("motion"),
        "camera_motion" => Ok("camera_motion"),
        _ => Err(Error::value(
            "name",
            format!("expected 'transforms', 'motion' or 'camera_motion', got {name:?}"),
        )),
    }
}

/// (K,4,4) float64 matrices of any layout.
fn matrices(a: &PyReadonlyArray3<'_, f64>, name: &'static str) -> Result<Vec<Mat4>, Error> {
    let v = a.as_array();
    if v.shape()[1] != 4 || v.shape()[2] != 4 {
        return Err(Error::shape(
            name,
            format!("expected shape (K,4,4), got {:?}", v.shape()),
        ));
    }
    Ok(v.outer_iter()
        .map(|m| std::array::from_fn(|r| std::array::from_fn(|c| m[[r, c]])))
        .collect())
}

/// A finite time, named `name` in the error.
fn finite(t: f64, name: &'static str) -> Result<f64, Error> {
    if t.is_finite() {
        Ok(t)
    } else {
        Err(Error::value(name, format!("must be finite, got {t}")))
    }
}

/// 4x4 matrices as an (N,4,4) float64 array.
fn matrix_array<'py>(py: Python<'py>, mats: Vec<Mat4>) -> PyResult<Bound<'py, PyAny>> {
    let n = mats.len();
    let flat: Vec<f64> = mats.into_iter().flatten().flatten().collect();
    shaped(py, flat, [n, 4, 4])
}

/// Keyframes at sorted shutter times: rigid (K,4,4) transforms or deforming (K,V,3) vertex
/// positions, validated and split once (see `src/motion/`).
#[pyclass(frozen, name = "_Keyframes", module = "motionblur._core")]
pub struct PyKeyframes {
    pub(crate) inner: Arc<Keyframes>,
}

#[pymethods]
impl PyKeyframes {
    /// `times` (K,) float64 and exactly one of `transforms` (K,4,4) float64 (errors name
    /// `name`) or `vertices` (K,V,3) float64.
    #[new]
    #[pyo3(signature = (times, transforms = None, vertices = None, name = "transforms"))]
    fn new(
        py: Python<'_>,
        times: PyReadonlyArray1<'_, f64>,
        transforms: Option<PyReadonlyArray3<'_, f64>>,
        vertices: Option<PyReadonlyArray3<'_, f64>>,
        name: &str,
    ) -> PyResult<Self> {
        let name = matrices_name(name)?;
        let t = times.as_array().to_vec();
        let keys = match (transforms, vertices) {
            (Some(m), None) => {
                let mats = matrices(&m, name)?;
                py.detach(move || Keyframes::rigid(t, &mats, name))?
            }
            (None, Some(v)) => {
                let shape = v.shape().to_vec();
                if shape[2] != 3 {
                    return Err(Error::shape(
                        "vertices",
                        format!("expected shape (K,V,3), got {shape:?}"),
                    )
                    .into());
                }
                if shape[0] != t.len() {
                    return Err(Error::shape(
                        "vertices",
                        format!(
                            "expected {} keyframes (one per time), got {}",
                            t.len(),
                            shape[0]
                        ),
                    )
                    .into());
                }
                let flat = c_slice(&v, "vertices")?;
                let rows: Vec<[f64; 3]> =
                    flat.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
                py.detach(move || Keyframes::deforming(t, rows))?
            }
            _ => {
                return Err(Error::value(
                    "transforms",
                    "give exactly one of transforms and vertices",
                )
                .into())
            }
        };
        Ok(PyKeyframes {
            inner: Arc::new(keys),
        })
    }

    /// Whether the keyframes are vertex positions.
    #[getter]
    fn is_deforming(&self) -> bool {
        self.inner.is_deforming()
    }

    /// (K,) float64 keyframe times.
    fn times<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.times())
    }

    /// (K,4,4) float64 rigid keyframes ((0,4,4) for a deforming motion).
    fn transforms<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mats = self.inner.rigid_keys().iter().map(|k| k.matrix).collect();
        matrix_array(py, mats)
    }

    /// (K,) float64 uniform scales of the rigid keyframes.
    fn scales<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let s: Vec<f64> = self.inner.rigid_keys().iter().map(|k| k.scale).collect();
        PyArray1::from_vec(py, s)
    }

    /// (4,4) float64 transform at shutter time `t` (the identity for a deforming motion).
    fn transform_at<'py>(&self, py: Python<'py>, t: f64) -> PyResult<Bound<'py, PyAny>> {
        let t = finite(t, "t")?;
        let m = self.inner.transform_at(t);
        shaped(py, m.into_iter().flatten().collect(), [4, 4])
    }

    /// (N,4,4) float64 transforms at the shutter times `times` (N,) float64 (any order).
    fn transforms_at<'py>(
        &self,
        py: Python<'py>,
        times: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let ts = times.as_array();
        let mats = ts
            .iter()
            .map(|&t| finite(t, "times").map(|t| self.inner.transform_at(t)))
            .collect::<Result<Vec<_>, _>>()?;
        matrix_array(py, mats)
    }

    /// (V,3) float64 vertex positions at shutter time `t` of a deforming motion.
    fn vertices_at<'py>(
        &self,
        py: Python<'py>,
        t: f64,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let t = finite(t, "t")?;
        let inner = self.inner.clone();
        let v = py
            .detach(move || inner.vertices_at(t))
            .ok_or_else(|| Error::value("motion", "vertices_at needs a deforming motion"))?;
        Ok(rows_array(py, v))
    }

    /// The rigid keyframes at the `segments + 1` times `i / segments` (numpy's linspace),
    /// interpolated from these keyframes' parts (not split again).
    fn resampled(&self, segments: usize) -> PyResult<Self> {
        if segments == 0 || segments > crate::MAX_SEGMENTS {
            return Err(Error::value(
                "segments",
                format!("must be in 1..={}, got {segments}", crate::MAX_SEGMENTS),
            )
            .into());
        }
        let keys = self
            .inner
            .resampled(segments)
            .ok_or_else(|| Error::value("motion", "resampling needs rigid keyframes"))?;
        Ok(PyKeyframes {
            inner: Arc::new(keys),
        })
    }
}

impl PyKeyframes {
    /// The split rigid keyframes (empty for a deforming motion).
    pub(crate) fn rigid(&self) -> &[Similarity] {
        self.inner.rigid_keys()
    }
}

/// Checks sample times `times` (N,) float64: finite, in [0, 1], strictly increasing (errors
/// name `times`).
#[pyfunction]
fn _check_times(times: PyReadonlyArray1<'_, f64>) -> PyResult<()> {
    Ok(check_times(&times.as_array().to_vec(), "times")?)
}

/// (4,4) float64 rotation by `angle` radians about `axis` (3,) (non-zero) through `center` (3,).
#[pyfunction]
fn _rotate<'py>(
    py: Python<'py>,
    angle: f64,
    axis: PyReadonlyArray1<'_, f64>,
    center: PyReadonlyArray1<'_, f64>,
) -> PyResult<Bound<'py, PyAny>> {
    let a = vec3(&axis, "axis")?;
    if a.iter().any(|x| !x.is_finite()) || a == [0.0; 3] {
        return Err(Error::value("axis", "must be finite and not zero").into());
    }
    let m = axis_angle(finite(angle, "angle")?, a, vec3(&center, "center")?);
    shaped(py, m.into_iter().flatten().collect(), [4, 4])
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyKeyframes>()?;
    m.add_function(wrap_pyfunction!(_check_times, m)?)?;
    m.add_function(wrap_pyfunction!(_rotate, m)?)?;
    Ok(())
}
