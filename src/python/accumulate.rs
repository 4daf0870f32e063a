//! Bindings for the accumulation kernels: in-place on a float32 accumulation buffer, and the
//! facing-face selection; GIL released.
use numpy::{
    PyArray2, PyReadonlyArray2, PyReadonlyArray3, PyReadwriteArray3, PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use super::args::{LayerArg, LayerMutArg};
use super::convert::{c_slice, c_slice_mut, detached_in_pool, flat_rows_array, rows, shaped};
use crate::{
    accumulate, composite, facing_faces, halves, over, resolve, BuffersMut, Error, HalfPart, Rect,
    SERIAL_PIXELS,
};

/// acc[y0:y0+h, x0:x0+w] (H,W,4) f32 += weight * rgba (h,w,4) f32 where depth (h,w) <
/// limit[y0:y0+h, x0:x0+w] (limit (H,W), or everywhere when None), `origin` = (x0, y0). In
/// place; releases the GIL.
#[pyfunction]
#[pyo3(signature = (acc, rgba, depth, limit, weight, origin=[0, 0]))]
fn _accumulate(
    py: Python<'_>,
    mut acc: PyReadwriteArray3<'_, f32>,
    rgba: PyReadonlyArray3<'_, f32>,
    depth: PyReadonlyArray2<'_, f32>,
    limit: Option<PyReadonlyArray2<'_, f32>>,
    weight: f32,
    origin: [usize; 2],
) -> PyResult<()> {
    let [x0, y0] = origin;
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

/// In place into layer `b` (rgba (H,W,4) f32, depth (H,W) f32, ids (H,W) i32 attributes):
/// layer `a` (rgba (h,w,4), depth (h,w), ids (h,w)) at `origin` (x0, y0) of b composited by
/// depth, the nearer over the farther. Releases the GIL.
#[pyfunction]
#[pyo3(signature = (a, b, origin=[0, 0]))]
fn _composite(
    py: Python<'_>,
    a: LayerArg<'_>,
    mut b: LayerMutArg<'_>,
    origin: [usize; 2],
) -> PyResult<()> {
    let [h, w] = a.size("a")?;
    let [_, stride] = b.size("b")?;
    let rect = Rect {
        x0: origin[0],
        y0: origin[1],
        width: w,
        height: h,
        stride,
    };
    let (ar, ad, ai) = a.planes("a")?;
    let (br, bd, bi) = b.planes("b")?;
    Ok(detached_in_pool(py, || {
        composite(ar, ad, ai, br, bd, bi, rect)
    })?)
}

/// In place into layer `out` (rgba (H,W,4) f32, depth (H,W) f32, ids (H,W) i32 attributes) at
/// pixel `origin` (x0, y0): the supersampled `layer` (rgba (h*s,w*s,4), depth and ids
/// (h*s,w*s)) resolved to (h,w) pixels (mean colour, nearest depth and its id). Releases the
/// GIL.
#[pyfunction]
#[pyo3(signature = (layer, samples, out, origin=[0, 0]))]
fn _resolve(
    py: Python<'_>,
    layer: LayerArg<'_>,
    samples: usize,
    mut out: LayerMutArg<'_>,
    origin: [usize; 2],
) -> PyResult<()> {
    let [h, w] = layer.size("layer")?;
    if samples == 0 || h % samples != 0 || w % samples != 0 {
        return Err(Error::shape(
            "samples",
            "must be >= 1 and divide the layer's height and width",
        )
        .into());
    }
    let [_, stride] = out.size("out")?;
    let rect = Rect {
        x0: origin[0],
        y0: origin[1],
        width: w / samples,
        height: h / samples,
        stride,
    };
    let (r, d, i) = layer.planes("layer")?;
    let (or, od, oi) = out.planes("out")?;
    Ok(detached_in_pool(py, || {
        let out = BuffersMut {
            rgba: or,
            depth: od,
            ids: oi,
        };
        resolve(r, d, i, samples, out, rect)
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

/// One part of [`_halves`]: (half 0 or 1, its mass, base (H,W,4) f32, its window
/// (x0, y0, x1, y1) or None, the window's drawn pixels (h,w,4) f32 or None, its sub-half 0 or
/// 1 within its half or None, its end coefficient).
type HalfPartArg<'py> = (
    usize,
    f64,
    PyReadonlyArray3<'py, f32>,
    Option<[usize; 4]>,
    Option<PyReadonlyArray3<'py, f32>>,
    Option<usize>,
    f64,
);

/// [`_halves`]' result: ((sum of the difference's squares, the sub-halves' or None, the plain
/// difference's or None), frame, (mass of half 0, mass of half 1)).
type HalvesOut<'py> = (
    (f64, Option<f64>, Option<f64>),
    Bound<'py, PyAny>,
    (f64, f64),
);

/// The halves of an accumulation over `window` (x0, y0, x1, y1) of its image (`parts`: each a
/// [`HalfPartArg`]), their difference composited over `pre` (premultiplied RGBA): ((the sum of
/// its squares, the same of the sub-halves within each half when every part has one, else
/// None, the same without the end term when a part has an end coefficient, else None), frame
/// (h,w,4) f32, (mass of half 0, mass of half 1)). A window under
/// `SERIAL_PIXELS` pixels is made on the calling thread; releases the GIL.
#[pyfunction]
fn _halves<'py>(
    py: Python<'py>,
    parts: Vec<HalfPartArg<'py>>,
    window: [usize; 4],
    pre: [f64; 4],
) -> PyResult<HalvesOut<'py>> {
    let Some(first) = parts.first() else {
        return Err(Error::value("parts", "at least one part expected").into());
    };
    let (h, w) = (first.2.shape()[0], first.2.shape()[1]);
    let mut views = Vec::with_capacity(parts.len());
    for (half, mass, base, win, drawn, sub, end) in &parts {
        if base.shape() != [h, w, 4] {
            return Err(Error::shape("base", "every part's base must be (H, W, 4)").into());
        }
        let drawn = match (win, drawn) {
            (Some(r), Some(d)) => Some((*r, c_slice(d, "drawn")?)),
            (None, None) => None,
            _ => return Err(Error::value("window", "a window goes with its drawn pixels").into()),
        };
        views.push(HalfPart {
            half: *half,
            mass: *mass,
            base: c_slice(base, "base")?,
            window: drawn,
            sub: *sub,
            end: *end,
        });
    }
    let [x0, y0, x1, y1] = window;
    let run = || halves(&views, (w, h), window, pre);
    let out = if (x1.saturating_sub(x0)) * (y1.saturating_sub(y0)) < SERIAL_PIXELS {
        py.detach(run)?
    } else {
        detached_in_pool(py, run)?
    };
    let dims = [y1 - y0, x1 - x0, 4];
    Ok((
        (out.square_sum, out.sub_square_sum, out.plain_square_sum),
        shaped(py, out.frame, dims)?,
        (out.masses[0], out.masses[1]),
    ))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_halves, m)?)?;
    m.add_function(wrap_pyfunction!(_resolve, m)?)?;
    m.add_function(wrap_pyfunction!(_composite, m)?)?;
    m.add_function(wrap_pyfunction!(_accumulate, m)?)?;
    m.add_function(wrap_pyfunction!(_over, m)?)?;
    m.add_function(wrap_pyfunction!(_facing_faces, m)?)?;
    Ok(())
}
