//! Bindings for the raster stage: numpy in, owned Rust data, GIL released, numpy out.
use glam::DMat4;
use numpy::{PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use super::convert::{c_slice, detached_in_pool, rows, shaped, ToDict};
use crate::{
    faces_from_i64, rasterize_over, Background, Blend, Camera, Draw, Error, Layer, Light,
    RasterOptions, Shading, FRAGMENT_CAP, MAX_INTERNAL_SIDE, MAX_PIXELS, MAX_SIDE, SAMPLES,
};

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
        layer: Layer {
            width: cols,
            height: rows,
            rgba: c_slice(&b.0, "background")?,
            depth: c_slice(&b.1, "background")?,
            ids: c_slice(&b.2, "background")?,
        },
        x0: b.3,
        y0: b.4,
    })
}

fn matrix(a: &PyReadonlyArray2<'_, f64>, name: &'static str) -> Result<DMat4, Error> {
    let m = rows::<f64, 4>(a, name)?;
    if m.len() != 4 {
        return Err(Error::shape(name, "expected shape (4,4)"));
    }
    // numpy rows -> glam columns.
    Ok(DMat4::from_cols_array_2d(&[m[0], m[1], m[2], m[3]]).transpose())
}

fn owned_draw(d: &DrawArgs<'_>) -> Result<Draw, Error> {
    let vertices = rows::<f64, 3>(&d.0, "vertices")?.to_vec();
    let faces = faces_from_i64(
        rows::<i64, 3>(&d.1, "faces")?.as_flattened(),
        vertices.len(),
    )?;
    let rgba = rows::<f32, 4>(&d.2, "rgba")?.to_vec();
    let normals =
        d.3.as_ref()
            .map(|n| rows::<f32, 3>(n, "normals").map(<[_]>::to_vec))
            .transpose()?;
    let previous =
        d.6.as_ref()
            .map(|p| rows::<f64, 3>(p, "previous_vertices").map(<[_]>::to_vec))
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
/// ids (H,W) i32, velocity (H,W,2) f32 or None when no draw has previous positions (zero
/// motion), stats dict). The GIL is released while rendering.
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
        matrix(&view, "view")?,
        matrix(&projection, "projection")?,
        width,
        height,
    )?;
    let opts = RasterOptions {
        samples,
        blend: Blend::parse(blend)?,
        shading: Shading::parse(shading)?,
        lights: lights
            .iter()
            .map(|(d, i)| Light::new(*d, *i))
            .collect::<Result<_, _>>()?,
        ambient: ambient.map(|a| a as f32),
    };
    let owned: Vec<Draw> = draws.iter().map(owned_draw).collect::<Result<_, _>>()?;
    drop(draws);
    let bg = background.as_ref().map(self::background).transpose()?;
    let (frame, stats) =
        detached_in_pool(py, || rasterize_over(&camera, &owned, &opts, bg.as_ref()))?;
    let (h, w) = (frame.height as usize, frame.width as usize);
    let stats = stats.to_dict(py)?;
    Ok((
        shaped(py, frame.rgba, [h, w, 4])?,
        shaped(py, frame.depth, [h, w])?,
        shaped(py, frame.ids, [h, w])?,
        match frame.velocity {
            None => py.None().into_bound(py),
            Some(v) => shaped(py, v, [h, w, 2])?,
        },
        stats,
    ))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_rasterize, m)?)?;
    m.add("MAX_SIDE", MAX_SIDE)?;
    m.add("MAX_PIXELS", MAX_PIXELS)?;
    m.add("FRAGMENT_CAP", FRAGMENT_CAP)?;
    m.add("MAX_INTERNAL_SIDE", MAX_INTERNAL_SIDE)?;
    m.add("SAMPLES", PyTuple::new(m.py(), SAMPLES)?)?;
    m.add("SHADINGS", PyTuple::new(m.py(), Shading::NAMES)?)?;
    m.add("BLENDS", PyTuple::new(m.py(), Blend::NAMES)?)?;
    Ok(())
}
