//! Bindings for the raster stage: numpy in, owned Rust data, GIL released, numpy out.
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use super::args::{lights, LayerArg, LightArg};
use super::convert::{
    detached_in_pool, face_indices_u32, matrix, rows, rows_array, shaped, ToDict,
};
use crate::{
    rasterize_over, Background, Blend, Camera, Draw, Error, RasterOptions, Shading, FRAGMENT_CAP,
    MAX_INTERNAL_SIDE, MAX_PIXELS, MAX_SIDE, SAMPLES,
};

/// One draw, read off the attributes of a `motionblur.Draw` (or any object that has them):
/// `vertices` f64 (V,3), `faces` i64 (F,3), `rgba` f32 (1|V,4), `normals` f32 (V,3) | None,
/// `object_id`, `cull_back`, `previous_vertices` f64 (V,3) | None, `shading` name | None (the
/// call's shading when None).
#[derive(FromPyObject)]
struct DrawArg<'py> {
    vertices: PyReadonlyArray2<'py, f64>,
    faces: PyReadonlyArray2<'py, i64>,
    rgba: PyReadonlyArray2<'py, f32>,
    normals: Option<PyReadonlyArray2<'py, f32>>,
    object_id: i32,
    cull_back: bool,
    previous_vertices: Option<PyReadonlyArray2<'py, f64>>,
    #[pyo3(default)]
    shading: Option<String>,
}

/// The options of one `_rasterize` call, the items of a dict: the camera's `view` and
/// `projection` (4,4) f64 and image size, then the core's [`RasterOptions`] (`samples`, `blend`
/// and `shading` names, `lights`, `ambient`), and `origin`, the background's sample (x0, y0)
/// under the frame's sample (0, 0).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct RasterArgs<'py> {
    view: PyReadonlyArray2<'py, f64>,
    projection: PyReadonlyArray2<'py, f64>,
    width: u32,
    height: u32,
    samples: u32,
    blend: String,
    shading: String,
    lights: Vec<LightArg>,
    ambient: [f64; 3],
    origin: [usize; 2],
}

/// The core's draw, owned (the GIL is released while it renders). Face indices are converted
/// to `u32` only ([`face_indices_u32`]): the core's [`Draw::validate`] checks their range.
fn owned_draw(d: &DrawArg<'_>) -> Result<Draw, Error> {
    let vertices = rows::<f64, 3>(&d.vertices, "vertices")?.to_vec();
    let faces = face_indices_u32(rows::<i64, 3>(&d.faces, "faces")?);
    let rgba = rows::<f32, 4>(&d.rgba, "rgba")?.to_vec();
    let normals = d
        .normals
        .as_ref()
        .map(|n| rows::<f32, 3>(n, "normals").map(<[_]>::to_vec))
        .transpose()?;
    let previous = d
        .previous_vertices
        .as_ref()
        .map(|p| rows::<f64, 3>(p, "previous_vertices").map(<[_]>::to_vec))
        .transpose()?;
    Ok(Draw {
        vertices,
        faces,
        rgba,
        normals,
        object_id: d.object_id,
        cull_back: d.cull_back,
        previous,
        shading: d.shading.as_deref().map(Shading::parse).transpose()?,
    })
}

/// The background's data after checking its shapes (the window of the frame's samples is
/// checked by the core).
fn background<'a>(b: &'a LayerArg<'_>, origin: [usize; 2]) -> Result<Background<'a>, Error> {
    Ok(Background {
        layer: b.layer("background")?,
        x0: origin[0],
        y0: origin[1],
    })
}

/// The image arrays of a frame: rgba (H,W,4) f32, depth (H,W) f32, ids (H,W) i32, velocity
/// (H,W,2) f32 or None, stats.
type FrameOut<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyDict>,
);

/// Renders `draws` (`motionblur.Draw` objects) with `options` ([`RasterArgs`]), over
/// `background` (an object with `rgba`, `depth`, `ids`) when given; returns (rgba (H,W,4) f32,
/// depth (H,W) f32, ids (H,W) i32, velocity (H,W,2) f32 or None when no draw has previous
/// positions (zero motion), stats dict). The GIL is released while rendering.
#[pyfunction]
#[pyo3(signature = (draws, options, background=None))]
fn _rasterize<'py>(
    py: Python<'py>,
    draws: Vec<DrawArg<'py>>,
    options: RasterArgs<'py>,
    background: Option<LayerArg<'py>>,
) -> PyResult<FrameOut<'py>> {
    let camera = Camera::from_matrices(
        matrix(&options.view, "view")?,
        matrix(&options.projection, "projection")?,
        options.width,
        options.height,
    )?;
    let opts = RasterOptions {
        samples: options.samples,
        blend: Blend::parse(&options.blend)?,
        shading: Shading::parse(&options.shading)?,
        lights: lights(&options.lights)?,
        ambient: options.ambient.map(|a| a as f32),
    };
    let owned: Vec<Draw> = draws.iter().map(owned_draw).collect::<Result<_, _>>()?;
    drop(draws);
    let bg = background
        .as_ref()
        .map(|b| self::background(b, options.origin))
        .transpose()?;
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

/// World points (V,3) f64 moved, at their clip depth, onto the fixed-point grid the rasterizer
/// snaps corners to for the camera (`view`, `projection` (4,4) f64, `width` x `height` pixels)
/// at `samples` a pixel side ([`crate::on_sample_grid`]); returns (V,3) f64.
#[pyfunction]
fn _on_sample_grid<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    view: PyReadonlyArray2<'py, f64>,
    projection: PyReadonlyArray2<'py, f64>,
    width: u32,
    height: u32,
    samples: u32,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let camera = Camera::from_matrices(
        matrix(&view, "view")?,
        matrix(&projection, "projection")?,
        width,
        height,
    )?;
    if !SAMPLES.contains(&samples) {
        return Err(Error::value("samples", format!("must be one of {SAMPLES:?}")).into());
    }
    let pts = rows::<f64, 3>(&points, "points")?;
    let out = py.detach(|| crate::on_sample_grid(&camera, samples, pts));
    Ok(rows_array(py, out))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_rasterize, m)?)?;
    m.add_function(wrap_pyfunction!(_on_sample_grid, m)?)?;
    m.add("MAX_SIDE", MAX_SIDE)?;
    m.add("MAX_PIXELS", MAX_PIXELS)?;
    m.add("FRAGMENT_CAP", FRAGMENT_CAP)?;
    m.add("MAX_INTERNAL_SIDE", MAX_INTERNAL_SIDE)?;
    m.add("SAMPLES", PyTuple::new(m.py(), SAMPLES)?)?;
    m.add("SHADINGS", PyTuple::new(m.py(), Shading::NAMES)?)?;
    m.add("BLENDS", PyTuple::new(m.py(), Blend::NAMES)?)?;
    Ok(())
}
