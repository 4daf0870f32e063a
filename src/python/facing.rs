//! Binding for the accumulation buffer's facing-face selection: borrowed C-contiguous arrays,
//! the kernel run with the GIL released.
use numpy::ndarray::Array2;
use numpy::{PyArray2, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use super::{c_slice, to_py_err};
use crate::facing;
use crate::Error;

/// The data of the (N,3) array `a`, row-major (C-contiguous only).
fn rows3<'a, T: numpy::Element>(
    a: &'a PyReadonlyArray2<'_, T>,
    name: &'static str,
) -> PyResult<&'a [T]> {
    if a.shape()[1] != 3 {
        return Err(to_py_err(Error::shape(
            name,
            format!("expected shape (N,3), got {:?}", a.shape()),
        )));
    }
    c_slice(a, name).map_err(to_py_err)
}

/// The faces (F',3) int64 of vertices (V,3) f64 / faces (F,3) int64 that face one of the
/// object-space eye positions eyes (K,3) f64, in order. Releases the GIL.
#[pyfunction]
fn _facing_faces<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f64>,
    faces: PyReadonlyArray2<'py, i64>,
    eyes: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let v = rows3(&vertices, "vertices")?;
    let f = rows3(&faces, "faces")?;
    let e = rows3(&eyes, "eyes")?;
    let kept = py
        .detach(|| super::in_pool(|| facing::facing_faces(v, f, e)))
        .map_err(to_py_err)?;
    let arr = Array2::from_shape_vec((kept.len() / 3, 3), kept).expect("rows of 3");
    Ok(PyArray2::from_owned_array(py, arr))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_facing_faces, m)?)?;
    Ok(())
}
