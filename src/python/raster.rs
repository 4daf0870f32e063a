//! Bindings for the raster stage: numpy in, owned Rust data, GIL released, numpy out.
use super::{c_slice, to_py_err};
use crate::raster::{self, Background, Blend, Camera, Draw, Light, Options, Shading};
use crate::Error;
use glam::DMat4;
use numpy::{
    IntoPyArray, PyArrayMethods, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// One draw as the Python layer passes it: (vertices f64 (V,3), faces i64 (F,3), rgba f32 (1|V,4),
/// normals f32 (V,3) | None, object_id, cull_back, previous_vertices f64 (V,3) | None).
type DrawArgs<'py> = (
    PyReadonlyArray2<'py, f64>,
    PyReadonlyArray2<'py, i64>,
    PyReadonlyArray2<'py, f32>,
    Option<PyReadonlyArray2<'py, f32>>,
    i32,
    bool,
    Option<PyReadonlyArray2<'py, f64>>,
);

/// Copies a C-contiguous (N, K) array into owned rows, checking the column count.
fn rows<T: numpy::Element + Copy + Default, const K: usize>(
    a: &PyReadonlyArray2<'_, T>,
    name: &'static str,
) -> Result<Vec<[T; K]>, Error> {
    let shape = a.shape();
    if shape[1] != K {
        return Err(Error::shape(
            name,
            format!("expected shape (N,{K}), got {shape:?}"),
        ));
    }
    let flat = c_slice(a, name)?;
    Ok(flat
        .chunks_exact(K)
        .map(|c| {
            let mut r = [T::default(); K];
            r.copy_from_slice(c);
            r
        })
        .collect())
}

/// The background as the Python layer passes it: (rgba f32 (R,S,4), depth f32 (R,S), ids i32
/// (R,S), x0, y0), one entry per sample; the frame reads the window from sample (x0, y0).
type BackgroundArgs<'py> = (
    PyReadonlyArray3<'py, f32>,
    PyReadonlyArray2<'py, f32>,
    PyReadonlyArray2<'py, i32>,
    usize,
    usize,
);

/// Borrows the background's data after checking its shapes (the window of `hs` x `ws` samples
/// is checked by the core).
fn background<'a>(b: &'a BackgroundArgs<'_>) -> Result<Background<'a>, Error> {
    let [rows, cols] = [b.1.shape()[0], b.1.shape()[1]];
    if b.0.shape() != [rows, cols, 4] || b.2.shape() != [rows, cols] {
        return Err(Error::shape(
            "background",
            format!(
                "rgba (R,S,4) and ids (R,S) must match depth {:?}, got {:?} and {:?}",
                b.1.shape(),
                b.0.shape(),
                b.2.shape()
            ),
        ));
    }
    Ok(Background {
        rgba: c_slice(&b.0, "background")?,
        depth: c_slice(&b.1, "background")?,
        ids: c_slice(&b.2, "background")?,
        stride: cols,
        x0: b.3,
        y0: b.4,
    })
}

fn matrix(a: &PyReadonlyArray2<'_, f64>, name: &'static str) -> Result<DMat4, Error> {
    let m: Vec<[f64; 4]> = rows(a, name)?;
    if m.len() != 4 {
        return Err(Error::shape(name, "expected shape (4,4)"));
    }
    // numpy rows -> glam columns.
    Ok(DMat4::from_cols_array_2d(&[m[0], m[1], m[2], m[3]]).transpose())
}

fn owned_draw(d: &DrawArgs<'_>) -> Result<Draw, Error> {
    let vertices: Vec<[f64; 3]> = rows(&d.0, "vertices")?;
    let faces_i: Vec<[i64; 3]> = rows(&d.1, "faces")?;
    let flat: Vec<i64> = faces_i.iter().flatten().copied().collect();
    let faces = raster::faces_from_i64(&flat, vertices.len())?;
    let rgba: Vec<[f32; 4]> = rows(&d.2, "rgba")?;
    let normals = d.3.as_ref().map(|n| rows(n, "normals")).transpose()?;
    let previous =
        d.6.as_ref()
            .map(|p| rows(p, "previous_vertices"))
            .transpose()?;
    Ok(Draw {
        vertices,
        faces,
        rgba,
        normals,
        object_id: d.4,
        cull_back: d.5,
        previous,
    })
}

/// Renders draws, over `background` when given; returns (rgba (H,W,4) f32, depth (H,W) f32,
/// ids (H,W) i32, velocity (H,W,2) f32, stats dict). The GIL is released while rendering.
#[pyfunction]
#[pyo3(signature = (view, projection, width, height, draws, samples, blend, shading, lights, ambient, background=None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn _rasterize<'py>(
    py: Python<'py>,
    view: PyReadonlyArray2<'py, f64>,
    projection: PyReadonlyArray2<'py, f64>,
    width: u32,
    height: u32,
    draws: Vec<DrawArgs<'py>>,
    samples: u32,
    blend: &str,
    shading: &str,
    lights: Vec<([f64; 3], [f64; 3])>,
    ambient: [f64; 3],
    background: Option<BackgroundArgs<'py>>,
) -> PyResult<(
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyDict>,
)> {
    let camera = Camera::from_matrices(
        matrix(&view, "view").map_err(to_py_err)?,
        matrix(&projection, "projection").map_err(to_py_err)?,
        width,
        height,
    )
    .map_err(to_py_err)?;
    let opts = Options {
        samples,
        blend: Blend::parse(blend).map_err(to_py_err)?,
        shading: Shading::parse(shading).map_err(to_py_err)?,
        lights: lights
            .iter()
            .map(|(d, i)| Light::new(*d, *i))
            .collect::<Result<_, _>>()
            .map_err(to_py_err)?,
        ambient: ambient.map(|a| a as f32),
    };
    let owned: Vec<Draw> = draws
        .iter()
        .map(owned_draw)
        .collect::<Result<_, _>>()
        .map_err(to_py_err)?;
    drop(draws);
    let bg = background
        .as_ref()
        .map(self::background)
        .transpose()
        .map_err(to_py_err)?;
    let frame = py
        .detach(|| super::in_pool(|| raster::rasterize_over(&camera, &owned, &opts, bg.as_ref())))
        .map_err(to_py_err)?;
    let (h, w) = (frame.height as usize, frame.width as usize);
    let stats = PyDict::new(py);
    let s = &frame.stats;
    stats.set_item("triangles", s.triangles)?;
    stats.set_item("fragments", s.fragments)?;
    stats.set_item("culled", s.culled)?;
    stats.set_item("clipped", s.clipped)?;
    stats.set_item("ms_transform", s.ms_transform)?;
    stats.set_item("ms_setup", s.ms_setup)?;
    stats.set_item("ms_bin", s.ms_bin)?;
    stats.set_item("ms_raster", s.ms_raster)?;
    stats.set_item("ms_total", s.ms_total)?;
    let rgba = frame.rgba.into_pyarray(py).reshape([h, w, 4])?.into_any();
    let depth = frame.depth.into_pyarray(py).reshape([h, w])?.into_any();
    let ids = frame.ids.into_pyarray(py).reshape([h, w])?.into_any();
    let velocity = frame
        .velocity
        .into_pyarray(py)
        .reshape([h, w, 2])?
        .into_any();
    Ok((rgba, depth, ids, velocity, stats))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_rasterize, m)?)?;
    Ok(())
}
