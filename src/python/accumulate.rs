//! Bindings for the accumulation kernels: in-place on a float32 accumulation buffer, GIL released.
use super::to_py_err;
use crate::accumulate;
use crate::Error;
use numpy::{PyReadonlyArray2, PyReadonlyArray3, PyReadwriteArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// acc[y0:y0+h, x0:x0+w] (H,W,4) f32 += weight * rgba (h,w,4) f32 where depth (h,w) <
/// limit[y0:y0+h, x0:x0+w] (limit (H,W), or everywhere when None). In place; releases the GIL.
#[pyfunction]
#[pyo3(signature = (acc, rgba, depth, limit, weight, x0=0, y0=0))]
#[allow(clippy::too_many_arguments)]
fn _accumulate(
    py: Python<'_>,
    mut acc: PyReadwriteArray3<'_, f32>,
    rgba: PyReadonlyArray3<'_, f32>,
    depth: PyReadonlyArray2<'_, f32>,
    limit: Option<PyReadonlyArray2<'_, f32>>,
    weight: f32,
    x0: usize,
    y0: usize,
) -> PyResult<()> {
    let shape = acc.shape().to_vec();
    let sub = rgba.shape().to_vec();
    if shape[2] != 4 || sub[2] != 4 || depth.shape() != &sub[..2] {
        return Err(to_py_err(Error::shape(
            "rgba",
            "acc (H,W,4), rgba (h,w,4) and depth (h,w) expected",
        )));
    }
    if y0 + sub[0] > shape[0] || x0 + sub[1] > shape[1] {
        return Err(to_py_err(Error::shape(
            "rgba",
            "the rectangle must lie inside acc",
        )));
    }
    if let Some(l) = &limit {
        if l.shape() != &shape[..2] {
            return Err(to_py_err(Error::shape("limit", "must be (H,W) like acc")));
        }
    }
    let contiguous = |name| move |_| to_py_err(Error::shape(name, "must be C-contiguous"));
    let r = rgba.as_slice().map_err(contiguous("rgba"))?;
    let d = depth.as_slice().map_err(contiguous("depth"))?;
    let l = match &limit {
        Some(l) => Some(l.as_slice().map_err(contiguous("limit"))?),
        None => None,
    };
    let a = acc.as_slice_mut().map_err(contiguous("acc"))?;
    let rect = accumulate::Rect {
        x0,
        y0,
        width: sub[1],
        height: sub[0],
        stride: shape[1],
    };
    py.detach(|| accumulate::accumulate(a, r, d, l, weight, rect))
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
    let u = under
        .as_slice()
        .map_err(|_| to_py_err(Error::shape("under", "must be C-contiguous")))?;
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
