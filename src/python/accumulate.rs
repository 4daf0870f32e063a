//! Bindings for the accumulation kernels: in-place on a float32 accumulation buffer, and the
//! facing-face selection (`crate::facing`); GIL released.
use super::{c_slice, c_slice_mut, to_py_err};
use crate::accumulate;
use crate::Error;
use numpy::ndarray::Array2;
use numpy::{
    PyArray2, PyReadonlyArray2, PyReadonlyArray3, PyReadwriteArray2, PyReadwriteArray3,
    PyUntypedArrayMethods,
};
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
    let r = c_slice(&rgba, "rgba").map_err(to_py_err)?;
    let d = c_slice(&depth, "depth").map_err(to_py_err)?;
    let l = match &limit {
        Some(l) => Some(c_slice(l, "limit").map_err(to_py_err)?),
        None => None,
    };
    let a = c_slice_mut(&mut acc, "acc").map_err(to_py_err)?;
    let rect = accumulate::Rect {
        x0,
        y0,
        width: sub[1],
        height: sub[0],
        stride: shape[1],
    };
    py.detach(|| super::in_pool(|| accumulate::accumulate(a, r, d, l, weight, rect)))
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
    let a = c_slice_mut(&mut acc, "acc").map_err(to_py_err)?;
    py.detach(|| super::in_pool(|| accumulate::over(a, u)))
        .map_err(to_py_err)
}

/// In place into b (b_rgba (H,W,4) f32, b_depth (H,W) f32, b_ids (H,W) i32): layer a (a_rgba
/// (h,w,4), a_depth (h,w), a_ids (h,w), at (x0, y0) of b) composited by depth, the nearer over
/// the farther. Releases the GIL.
#[pyfunction]
#[pyo3(signature = (a_rgba, a_depth, a_ids, b_rgba, b_depth, b_ids, x0=0, y0=0))]
#[allow(clippy::too_many_arguments)]
fn _composite(
    py: Python<'_>,
    a_rgba: PyReadonlyArray3<'_, f32>,
    a_depth: PyReadonlyArray2<'_, f32>,
    a_ids: PyReadonlyArray2<'_, i32>,
    mut b_rgba: PyReadwriteArray3<'_, f32>,
    mut b_depth: PyReadwriteArray2<'_, f32>,
    mut b_ids: PyReadwriteArray2<'_, i32>,
    x0: usize,
    y0: usize,
) -> PyResult<()> {
    let sub = a_rgba.shape().to_vec();
    let full = b_rgba.shape().to_vec();
    if sub[2] != 4 || full[2] != 4 || a_depth.shape() != &sub[..2] || a_ids.shape() != &sub[..2] {
        return Err(to_py_err(Error::shape(
            "a_rgba",
            "a: rgba (h,w,4), depth and ids (h,w) expected",
        )));
    }
    if b_depth.shape() != &full[..2] || b_ids.shape() != &full[..2] {
        return Err(to_py_err(Error::shape(
            "b_rgba",
            "b: rgba (H,W,4), depth and ids (H,W) expected",
        )));
    }
    if y0 + sub[0] > full[0] || x0 + sub[1] > full[1] {
        return Err(to_py_err(Error::shape(
            "a_rgba",
            "the rectangle must lie inside b",
        )));
    }
    let ar = c_slice(&a_rgba, "a_rgba").map_err(to_py_err)?;
    let ad = c_slice(&a_depth, "a_depth").map_err(to_py_err)?;
    let ai = c_slice(&a_ids, "a_ids").map_err(to_py_err)?;
    let br = c_slice_mut(&mut b_rgba, "b_rgba").map_err(to_py_err)?;
    let bd = c_slice_mut(&mut b_depth, "b_depth").map_err(to_py_err)?;
    let bi = c_slice_mut(&mut b_ids, "b_ids").map_err(to_py_err)?;
    let rect = accumulate::Rect {
        x0,
        y0,
        width: sub[1],
        height: sub[0],
        stride: full[1],
    };
    py.detach(|| super::in_pool(|| accumulate::composite(ar, ad, ai, br, bd, bi, rect)))
        .map_err(to_py_err)
}

/// In place into out (out_rgba (H,W,4) f32, out_depth (H,W) f32, out_ids (H,W) i32) at pixel
/// (x0, y0): the supersampled layer rgba (h*s,w*s,4) f32, depth (h*s,w*s) f32, ids (h*s,w*s)
/// i32 resolved to (h,w) pixels (mean colour, nearest depth and its id). Releases the GIL.
#[pyfunction]
#[pyo3(signature = (rgba, depth, ids, samples, out_rgba, out_depth, out_ids, x0=0, y0=0))]
#[allow(clippy::too_many_arguments)]
fn _resolve(
    py: Python<'_>,
    rgba: PyReadonlyArray3<'_, f32>,
    depth: PyReadonlyArray2<'_, f32>,
    ids: PyReadonlyArray2<'_, i32>,
    samples: usize,
    mut out_rgba: PyReadwriteArray3<'_, f32>,
    mut out_depth: PyReadwriteArray2<'_, f32>,
    mut out_ids: PyReadwriteArray2<'_, i32>,
    x0: usize,
    y0: usize,
) -> PyResult<()> {
    let sub = rgba.shape().to_vec();
    let full = out_rgba.shape().to_vec();
    if samples == 0 || sub[0] % samples != 0 || sub[1] % samples != 0 {
        return Err(to_py_err(Error::shape(
            "samples",
            "must be >= 1 and divide the layer's height and width",
        )));
    }
    if sub[2] != 4 || full[2] != 4 || depth.shape() != &sub[..2] || ids.shape() != &sub[..2] {
        return Err(to_py_err(Error::shape(
            "rgba",
            "rgba (h,w,4), depth and ids (h,w) expected",
        )));
    }
    if out_depth.shape() != &full[..2] || out_ids.shape() != &full[..2] {
        return Err(to_py_err(Error::shape(
            "out_rgba",
            "out: rgba (H,W,4), depth and ids (H,W) expected",
        )));
    }
    let rect = accumulate::Rect {
        x0,
        y0,
        width: sub[1] / samples,
        height: sub[0] / samples,
        stride: full[1],
    };
    let r = c_slice(&rgba, "rgba").map_err(to_py_err)?;
    let d = c_slice(&depth, "depth").map_err(to_py_err)?;
    let i = c_slice(&ids, "ids").map_err(to_py_err)?;
    let or = c_slice_mut(&mut out_rgba, "out_rgba").map_err(to_py_err)?;
    let od = c_slice_mut(&mut out_depth, "out_depth").map_err(to_py_err)?;
    let oi = c_slice_mut(&mut out_ids, "out_ids").map_err(to_py_err)?;
    py.detach(|| super::in_pool(|| accumulate::resolve(r, d, i, samples, or, od, oi, rect)))
        .map_err(to_py_err)
}

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
        .detach(|| super::in_pool(|| accumulate::facing_faces(v, f, e)))
        .map_err(to_py_err)?;
    let arr = Array2::from_shape_vec((kept.len() / 3, 3), kept).expect("rows of 3");
    Ok(PyArray2::from_owned_array(py, arr))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_resolve, m)?)?;
    m.add_function(wrap_pyfunction!(_composite, m)?)?;
    m.add_function(wrap_pyfunction!(_accumulate, m)?)?;
    m.add_function(wrap_pyfunction!(_over, m)?)?;
    m.add_function(wrap_pyfunction!(_facing_faces, m)?)?;
    Ok(())
}
