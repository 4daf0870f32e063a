//! Bindings for the accumulation kernels: in-place on a float32 accumulation buffer, and the
//! facing-face selection; GIL released.
use numpy::{
    PyArray2, PyReadonlyArray2, PyReadonlyArray3, PyReadwriteArray2, PyReadwriteArray3,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use super::convert::{c_slice, c_slice_mut, detached_in_pool, flat_rows_array, rows};
use crate::{accumulate, composite, facing_faces, over, resolve, Error, Rect};

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
        return Err(
            Error::shape("rgba", "acc (H,W,4), rgba (h,w,4) and depth (h,w) expected").into(),
        );
    }
    if y0 + sub[0] > shape[0] || x0 + sub[1] > shape[1] {
        return Err(Error::shape("rgba", "the rectangle must lie inside acc").into());
    }
    if let Some(l) = &limit {
        if l.shape() != &shape[..2] {
            return Err(Error::shape("limit", "must be (H,W) like acc").into());
        }
    }
    let r = c_slice(&rgba, "rgba")?;
    let d = c_slice(&depth, "depth")?;
    let l = match &limit {
        Some(l) => Some(c_slice(l, "limit")?),
        None => None,
    };
    let a = c_slice_mut(&mut acc, "acc")?;
    let rect = Rect {
        x0,
        y0,
        width: sub[1],
        height: sub[0],
        stride: shape[1],
    };
    Ok(detached_in_pool(py, || {
        accumulate(a, r, d, l, weight, rect)
    })?)
}

/// acc (H,W,4) f32 += under (H,W,4) f32 * (1 - acc alpha). In place; releases the GIL.
#[pyfunction]
fn _over(
    py: Python<'_>,
    mut acc: PyReadwriteArray3<'_, f32>,
    under: PyReadonlyArray3<'_, f32>,
) -> PyResult<()> {
    if under.shape() != acc.shape() {
        return Err(Error::shape("under", "must have the shape of acc").into());
    }
    let u = c_slice(&under, "under")?;
    let a = c_slice_mut(&mut acc, "acc")?;
    Ok(detached_in_pool(py, || over(a, u))?)
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
        return Err(Error::shape("a_rgba", "a: rgba (h,w,4), depth and ids (h,w) expected").into());
    }
    if b_depth.shape() != &full[..2] || b_ids.shape() != &full[..2] {
        return Err(Error::shape("b_rgba", "b: rgba (H,W,4), depth and ids (H,W) expected").into());
    }
    if y0 + sub[0] > full[0] || x0 + sub[1] > full[1] {
        return Err(Error::shape("a_rgba", "the rectangle must lie inside b").into());
    }
    let ar = c_slice(&a_rgba, "a_rgba")?;
    let ad = c_slice(&a_depth, "a_depth")?;
    let ai = c_slice(&a_ids, "a_ids")?;
    let br = c_slice_mut(&mut b_rgba, "b_rgba")?;
    let bd = c_slice_mut(&mut b_depth, "b_depth")?;
    let bi = c_slice_mut(&mut b_ids, "b_ids")?;
    let rect = Rect {
        x0,
        y0,
        width: sub[1],
        height: sub[0],
        stride: full[1],
    };
    Ok(detached_in_pool(py, || {
        composite(ar, ad, ai, br, bd, bi, rect)
    })?)
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
        return Err(Error::shape(
            "samples",
            "must be >= 1 and divide the layer's height and width",
        )
        .into());
    }
    if sub[2] != 4 || full[2] != 4 || depth.shape() != &sub[..2] || ids.shape() != &sub[..2] {
        return Err(Error::shape("rgba", "rgba (h,w,4), depth and ids (h,w) expected").into());
    }
    if out_depth.shape() != &full[..2] || out_ids.shape() != &full[..2] {
        return Err(Error::shape(
            "out_rgba",
            "out: rgba (H,W,4), depth and ids (H,W) expected",
        )
        .into());
    }
    let rect = Rect {
        x0,
        y0,
        width: sub[1] / samples,
        height: sub[0] / samples,
        stride: full[1],
    };
    let r = c_slice(&rgba, "rgba")?;
    let d = c_slice(&depth, "depth")?;
    let i = c_slice(&ids, "ids")?;
    let or = c_slice_mut(&mut out_rgba, "out_rgba")?;
    let od = c_slice_mut(&mut out_depth, "out_depth")?;
    let oi = c_slice_mut(&mut out_ids, "out_ids")?;
    Ok(detached_in_pool(py, || {
        resolve(r, d, i, samples, or, od, oi, rect)
    })?)
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
    let v = rows::<f64, 3>(&vertices, "vertices")?.as_flattened();
    let f = rows::<i64, 3>(&faces, "faces")?.as_flattened();
    let e = rows::<f64, 3>(&eyes, "eyes")?.as_flattened();
    let kept = detached_in_pool(py, || facing_faces(v, f, e))?;
    Ok(flat_rows_array(py, kept, 3))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_resolve, m)?)?;
    m.add_function(wrap_pyfunction!(_composite, m)?)?;
    m.add_function(wrap_pyfunction!(_accumulate, m)?)?;
    m.add_function(wrap_pyfunction!(_over, m)?)?;
    m.add_function(wrap_pyfunction!(_facing_faces, m)?)?;
    Ok(())
}
