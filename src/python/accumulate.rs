//! Bindings for the accumulation kernels: in-place on a float32 accumulation buffer, GIL released.
use super::{c_slice, to_py_err};
use crate::accumulate;
use crate::Error;
use numpy::{PyReadonlyArray2, PyReadonlyArray3, PyReadwriteArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// acc (H,W,4) f32 += weight * rgba (H,W,4) f32 where depth (H,W) < limit (H,W) (everywhere
/// when limit is None). In place; releases the GIL.
#[pyfunction]
#[pyo3(signature = (acc, rgba, depth, limit, weight))]
fn _accumulate(
    py: Python<'_>,
    mut acc: PyReadwriteArray3<'_, f32>,
    rgba: PyReadonlyArray3<'_, f32>,
    depth: PyReadonlyArray2<'_, f32>,
    limit: Option<PyReadonlyArray2<'_, f32>>,
    weight: f32,
) -> PyResult<()> {
    let shape = acc.shape().to_vec();
    if rgba.shape() != shape.as_slice() || shape[2] != 4 || depth.shape() != &shape[..2] {
        return Err(to_py_err(Error::shape(
            "rgba",
            "acc and rgba (H,W,4), depth (H,W) must match",
        )));
    }
    if let Some(l) = &limit {
        if l.shape() != &shape[..2] {
            return Err(to_py_err(Error::shape("limit", "must be (H,W) like depth")));
        }
    }
    let r = c_slice(&rgba, "rgba").map_err(to_py_err)?;
    let d = c_slice(&depth, "depth").map_err(to_py_err)?;
    let l = match &limit {
        Some(l) => Some(c_slice(l, "limit").map_err(to_py_err)?),
        None => None,
    };
    if !acc.is_c_contiguous() {
        return Err(to_py_err(Error::shape("acc", "must be C-contiguous")));
    }
    let a = acc
        .as_slice_mut()
        .map_err(|_| to_py_err(Error::shape("acc", "must be C-contiguous")))?;
    py.detach(|| accumulate::accumulate(a, r, d, l, weight))
        .map_err(to_py_err)
}

/// acc (H,W,4) f32 += under (H,W,4) f32 * (1 - acc alpha). In place; releases the GIL.
#[pyfunction]
fn _over(
    py: Python<'_>,
    mut acc: PyReadwriteArray3<'_, f32>,
    under: PyReadonlyArray3<'_, f32>,
) -> PyResult<()> {
    if under.shape() != acc.shape() {
        return Err(to_py_err(Error::shape(
            "under",
            "must have the shape of acc",
        )));
    }
    let u = c_slice(&under, "under").map_err(to_py_err)?;
    if !acc.is_c_contiguous() {
        return Err(to_py_err(Error::shape("acc", "must be C-contiguous")));
    }
    let a = acc
        .as_slice_mut()
        .map_err(|_| to_py_err(Error::shape("acc", "must be C-contiguous")))?;
    py.detach(|| accumulate::over(a, u)).map_err(to_py_err)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_accumulate, m)?)?;
    m.add_function(wrap_pyfunction!(_over, m)?)?;
    Ok(())
}
