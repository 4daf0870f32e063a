//! Bindings for the image stage: shape and contiguity checks naming the argument, the GIL
//! released around every kernel, numpy out. The Python layer (`motionblur.image`) converts
//! dtypes and checks parameters first; these checks are the second line.
use numpy::{
    PyArray3, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
    PyReadonlyArray4, PyReadwriteArray3, PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use super::convert::{c_slice, c_slice_mut, detached_in_pool, matrix, rows, shaped};
use crate::{
    CameraBlur, CameraMatrices, Composite, CoverageObject, CoveragePart, CoverageSource, DofParams,
    Error, Layer, LensParams, Piece, ReconstructParams,
};

type PyOut<'py> = PyResult<Bound<'py, PyAny>>;

/// A window (y0, y1, x0, x1) of an image.
type Window = (usize, usize, usize, usize);

/// `(h, w, channels)` float32 C-contiguous image: its data, width and height.
fn img3<'a>(
    a: &'a PyReadonlyArray3<'_, f32>,
    name: &'static str,
    channels: usize,
) -> PyResult<(&'a [f32], usize, usize)> {
    let s = a.shape();
    if s[2] != channels {
        return Err(
            Error::shape(name, format!("expected shape (H,W,{channels}), got {s:?}")).into(),
        );
    }
    let data = c_slice(a, name)?;
    Ok((data, s[1], s[0]))
}

fn img2<'a>(
    a: &'a PyReadonlyArray2<'_, f32>,
    name: &'static str,
) -> PyResult<(&'a [f32], usize, usize)> {
    let s = a.shape();
    let data = c_slice(a, name)?;
    Ok((data, s[1], s[0]))
}

fn same_size(name: &'static str, got: (usize, usize), want: (usize, usize)) -> PyResult<()> {
    if got != want {
        return Err(Error::shape(
            name,
            format!(
                "expected {}x{} pixels like rgba, got {}x{}",
                want.1, want.0, got.1, got.0
            ),
        )
        .into());
    }
    Ok(())
}

/// A row-major (4,4) f64 matrix as 16 numbers.
fn map16(a: &PyReadonlyArray2<'_, f64>, name: &'static str) -> PyResult<[f64; 16]> {
    if a.shape() != [4, 4] {
        return Err(Error::shape(name, "expected shape (4,4)").into());
    }
    let mut m = [0.0f64; 16];
    m.copy_from_slice(c_slice(a, name)?);
    Ok(m)
}

/// A camera, read off the attributes `view` and `projection` (4,4) f64 of a
/// `motionblur.Camera`.
#[derive(FromPyObject)]
struct CameraArg<'py> {
    view: PyReadonlyArray2<'py, f64>,
    projection: PyReadonlyArray2<'py, f64>,
}

impl CameraArg<'_> {
    /// The core's matrices; errors name `name`.
    fn matrices(&self, name: &'static str) -> PyResult<CameraMatrices> {
        Ok(CameraMatrices::new(
            matrix(&self.view, name)?,
            matrix(&self.projection, name)?,
            name,
        )?)
    }
}

/// The parameters of `_depth_of_field`, the items of a dict: the core's [`DofParams`].
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct DofArgs {
    focal_depth: f64,
    focal_length: f64,
    f_number: f64,
    yfov: f64,
    layers: usize,
}

/// Eq. 10 glow of alpha (H,W) f32 along direction over width pixels.
#[pyfunction]
fn _glow<'py>(
    py: Python<'py>,
    alpha: PyReadonlyArray2<'py, f32>,
    direction: [f32; 2],
    width: f32,
) -> PyOut<'py> {
    let (a, w, h) = img2(&alpha, "alpha")?;
    let out = detached_in_pool(py, || crate::glow(a, w, h, direction, width))?;
    shaped(py, out, [h, w])
}

/// Box blur of rgba (H,W,4) f32 along direction over length pixels.
#[pyfunction]
fn _box_blur<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArray3<'py, f32>,
    direction: [f32; 2],
    length: f32,
) -> PyOut<'py> {
    let (a, w, h) = img3(&rgba, "rgba", 4)?;
    let out = detached_in_pool(py, || crate::box_blur(a, w, h, direction, length))?;
    shaped(py, out, [h, w, 4])
}

/// Splat colors (N,4) f32 along paths (N,P,2) f32 into a (height, width, 4) f32 image.
#[pyfunction]
fn _splat_paths<'py>(
    py: Python<'py>,
    colors: PyReadonlyArray2<'py, f32>,
    paths: PyReadonlyArray3<'py, f32>,
    width: usize,
    height: usize,
) -> PyOut<'py> {
    let (cs, ps) = (colors.shape(), paths.shape());
    if cs[1] != 4 {
        return Err(Error::shape("colors", format!("expected shape (N,4), got {cs:?}")).into());
    }
    if ps[2] != 2 || ps[0] != cs[0] {
        return Err(Error::shape(
            "paths",
            format!("expected shape ({},P,2) like colors, got {ps:?}", cs[0]),
        )
        .into());
    }
    let c = c_slice(&colors, "colors")?;
    let p = c_slice(&paths, "paths")?;
    let c4: Vec<[f32; 4]> = c
        .chunks_exact(4)
        .map(|x| [x[0], x[1], x[2], x[3]])
        .collect();
    let p2: Vec<[f32; 2]> = p.chunks_exact(2).map(|x| [x[0], x[1]]).collect();
    let out = detached_in_pool(py, || crate::splat_paths(width, height, &c4, &p2, ps[1]))?;
    shaped(py, out, [height, width, 4])
}

/// One piece of `_scatter_pieces`, the items of a dict: its layer `rgba` (H,W,4) f32, `depth`
/// (H,W) f32, `ids` (H,W) i32, the camera `ray` (4,) f64, its shutter `weight`, the `objects`
/// (M,) i32 and their `maps` (M,P,4,4) f64 (the core's [`Piece`]).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct PieceArg<'py> {
    rgba: PyReadonlyArray3<'py, f32>,
    depth: PyReadonlyArray2<'py, f32>,
    ids: PyReadonlyArray2<'py, i32>,
    ray: [f64; 4],
    weight: f32,
    objects: PyReadonlyArray1<'py, i32>,
    maps: PyReadonlyArray4<'py, f64>,
}

/// Splat the pieces' covered pixels along their paths into a (height, width, 4) f32 image.
#[pyfunction]
fn _scatter_pieces<'py>(
    py: Python<'py>,
    pieces: Vec<PieceArg<'py>>,
    points: usize,
    width: usize,
    height: usize,
) -> PyOut<'py> {
    let mut views = Vec::with_capacity(pieces.len());
    for PieceArg {
        rgba,
        depth,
        ids,
        ray,
        weight,
        objects,
        maps,
    } in &pieces
    {
        let (c, w, h) = img3(rgba, "rgba", 4)?;
        let (d, dw, dh) = img2(depth, "depth")?;
        same_size("depth", (dh, dw), (h, w))?;
        let s = ids.shape();
        same_size("ids", (s[0], s[1]), (h, w))?;
        let ms = maps.shape();
        if ms[0] != objects.len() || ms[1] != points || ms[2] != 4 || ms[3] != 4 {
            return Err(Error::shape(
                "maps",
                format!(
                    "expected shape ({},{points},4,4) (objects, points), got {ms:?}",
                    objects.len()
                ),
            )
            .into());
        }
        views.push(Piece {
            layer: Layer {
                rgba: c,
                depth: d,
                ids: c_slice(ids, "ids")?,
                width: w,
                height: h,
            },
            ray: *ray,
            weight: *weight,
            objects: c_slice(objects, "objects")?,
            maps: c_slice(maps, "maps")?,
        });
    }
    let out = detached_in_pool(py, || crate::scatter_pieces(width, height, &views, points))?;
    shaped(py, out, [height, width, 4])
}

/// (x_min, y_min, x_max, y_max) of points (N,3) f64 under map (4,4) f64, or None (one behind).
#[pyfunction]
fn _pixel_bounds(
    py: Python<'_>,
    map: PyReadonlyArray2<'_, f64>,
    points: PyReadonlyArray2<'_, f64>,
) -> PyResult<Option<[f64; 4]>> {
    let m = map16(&map, "map")?;
    let p = rows::<f64, 3>(&points, "points")?.as_flattened();
    Ok(detached_in_pool(py, || crate::pixel_bounds(&m, p))?)
}

/// rgba (N,4) f32 with the colours sampled from img (H,W,4) f32 at points (N,3) f64 under map.
#[pyfunction]
fn _sample_colors<'py>(
    py: Python<'py>,
    img: PyReadonlyArray3<'py, f32>,
    map: PyReadonlyArray2<'py, f64>,
    points: PyReadonlyArray2<'py, f64>,
    rgba: PyReadonlyArray2<'py, f32>,
) -> PyOut<'py> {
    let (a, w, h) = img3(&img, "img", 4)?;
    let m = map16(&map, "map")?;
    let p = rows::<f64, 3>(&points, "points")?.as_flattened();
    let c = rows::<f32, 4>(&rgba, "rgba")?.as_flattened();
    let n = p.len() / 3;
    let out = detached_in_pool(py, || crate::sample_colors(a, w, h, &m, p, c))?;
    shaped(py, out, [n, 4])
}

/// Coverage alpha of rgba (H,W,4) f32 times the colour of averaged (H,W,4) f32, over static_rgba.
#[pyfunction]
#[pyo3(signature = (rgba, averaged, static_rgba=None))]
fn _colored<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArray3<'py, f32>,
    averaged: PyReadonlyArray3<'py, f32>,
    static_rgba: Option<PyReadonlyArray3<'py, f32>>,
) -> PyOut<'py> {
    let (r, w, h) = img3(&rgba, "rgba", 4)?;
    let (s, sw, sh) = img3(&averaged, "averaged", 4)?;
    same_size("averaged", (sh, sw), (h, w))?;
    let u = match &static_rgba {
        Some(u) => {
            let (u, uw, uh) = img3(u, "static_rgba", 4)?;
            same_size("static_rgba", (uh, uw), (h, w))?;
            Some(u)
        }
        None => None,
    };
    let out = detached_in_pool(py, || crate::colored(r, s, u))?;
    shaped(py, out, [h, w, 4])
}

/// Opaque blur (box, glow, eq. 7) of rgba (H,W,4) f32.
#[pyfunction]
fn _opaque_blur<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArray3<'py, f32>,
    direction: [f32; 2],
    length: f32,
) -> PyOut<'py> {
    let (a, w, h) = img3(&rgba, "rgba", 4)?;
    let out = detached_in_pool(py, || crate::opaque_blur(a, w, h, direction, length))?;
    shaped(py, out, [h, w, 4])
}

/// Opaque motion blur of rgba (H,W,4) f32 composited `mode` base (H,W,4) f32 or rgba itself;
/// written into `out` (H,W,4) f32 and returned as it when given, else a new array.
#[pyfunction]
#[pyo3(signature = (rgba, base, direction, length, mode, out=None))]
fn _opaque_motion_blur<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArray3<'py, f32>,
    base: Option<PyReadonlyArray3<'py, f32>>,
    direction: [f32; 2],
    length: f32,
    mode: &str,
    out: Option<Bound<'py, PyArray3<f32>>>,
) -> PyOut<'py> {
    let (a, w, h) = img3(&rgba, "rgba", 4)?;
    let mode = Composite::parse(mode)?;
    let b = match &base {
        Some(b) => {
            let (b, bw, bh) = img3(b, "base", 4)?;
            same_size("base", (bh, bw), (h, w))?;
            Some(b)
        }
        None => None,
    };
    let Some(out) = out else {
        let out = detached_in_pool(py, || {
            crate::opaque_motion_blur(a, b, w, h, direction, length, mode)
        })?;
        return shaped(py, out, [h, w, 4]);
    };
    // a read-write borrow: numpy's borrow checker refuses an `out` that shares memory with
    // rgba or base (borrowed read-only above)
    let mut o = out.try_readwrite().map_err(|_| {
        Error::value(
            "out",
            "must be a writable array sharing no memory with rgba or base",
        )
    })?;
    if o.shape() != [h, w, 4] {
        return Err(Error::shape(
            "out",
            format!("expected shape ({h}, {w}, 4), got {:?}", o.shape()),
        )
        .into());
    }
    let dst = c_slice_mut(&mut o, "out")?;
    detached_in_pool(py, || {
        crate::opaque_motion_blur_into(a, b, w, h, direction, length, mode, dst)
    })?;
    drop(o);
    Ok(out.into_any())
}

/// Pyramid blur of rgba (H,W,4) f32 over `levels` levels.
#[pyfunction]
fn _pyramid_blur<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArray3<'py, f32>,
    levels: usize,
) -> PyOut<'py> {
    let (a, w, h) = img3(&rgba, "rgba", 4)?;
    let out = detached_in_pool(py, || crate::pyramid_blur(a, w, h, levels))?;
    shaped(py, out, [h, w, 4])
}

/// Pyramid glow (eqs. 8-9) of alpha (H,W) f32 over `levels` levels.
#[pyfunction]
fn _pyramid_glow<'py>(
    py: Python<'py>,
    alpha: PyReadonlyArray2<'py, f32>,
    levels: usize,
) -> PyOut<'py> {
    let (a, w, h) = img2(&alpha, "alpha")?;
    let out = detached_in_pool(py, || crate::pyramid_glow(a, w, h, levels))?;
    shaped(py, out, [h, w])
}

/// Opaque pyramid blur of rgba (H,W,4) f32 over `levels` levels.
#[pyfunction]
fn _pyramid_opaque_blur<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArray3<'py, f32>,
    levels: usize,
) -> PyOut<'py> {
    let (a, w, h) = img3(&rgba, "rgba", 4)?;
    let out = detached_in_pool(py, || crate::pyramid_opaque_blur(a, w, h, levels))?;
    shaped(py, out, [h, w, 4])
}

/// Depth of field of rgba (H,W,4) f32 with depth (H,W) f32 ([`DofArgs`]).
#[pyfunction]
fn _depth_of_field<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArray3<'py, f32>,
    depth: PyReadonlyArray2<'py, f32>,
    params: DofArgs,
) -> PyOut<'py> {
    let (a, w, h) = img3(&rgba, "rgba", 4)?;
    let (d, dw, dh) = img2(&depth, "depth")?;
    same_size("depth", (dh, dw), (h, w))?;
    let p = DofParams {
        focal_depth: params.focal_depth,
        focal_length: params.focal_length,
        f_number: params.f_number,
        yfov: params.yfov,
        layers: params.layers,
    };
    let out = detached_in_pool(py, || crate::depth_of_field(a, d, w, h, &p))?;
    shaped(py, out, [h, w, 4])
}

/// Thin-lens depth of field of rgba (H,W,4) f32 with depth (H,W) f32.
#[pyfunction]
fn _lens_blur<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArray3<'py, f32>,
    depth: PyReadonlyArray2<'py, f32>,
    aperture: f64,
    focus_distance: f64,
    yfov: f64,
) -> PyOut<'py> {
    let (a, w, h) = img3(&rgba, "rgba", 4)?;
    let (d, dw, dh) = img2(&depth, "depth")?;
    same_size("depth", (dh, dw), (h, w))?;
    let p = LensParams {
        aperture,
        focus_distance,
        yfov,
    };
    let out = detached_in_pool(py, || crate::lens_blur(a, d, w, h, &p))?;
    shaped(py, out, [h, w, 4])
}

/// Per-pixel velocity (H,W,2) f32 from depth (H,W) f32 and two cameras ([`CameraArg`]).
#[pyfunction]
fn _camera_velocity<'py>(
    py: Python<'py>,
    depth: PyReadonlyArray2<'py, f32>,
    camera: CameraArg<'py>,
    previous_camera: CameraArg<'py>,
) -> PyOut<'py> {
    let (d, w, h) = img2(&depth, "depth")?;
    let cur = camera.matrices("camera")?;
    let prev = previous_camera.matrices("previous_camera")?;
    let out = detached_in_pool(py, || crate::camera_velocity(d, w, h, &cur, &prev))?;
    shaped(py, out, [h, w, 2])
}

/// Centred N-sample blur of rgba (H,W,4) f32 along velocity (H,W,2) f32.
#[pyfunction]
fn _velocity_blur<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArray3<'py, f32>,
    velocity: PyReadonlyArray3<'py, f32>,
    samples: usize,
) -> PyOut<'py> {
    let (a, w, h) = img3(&rgba, "rgba", 4)?;
    let (v, vw, vh) = img3(&velocity, "velocity", 2)?;
    same_size("velocity", (vh, vw), (h, w))?;
    let out = detached_in_pool(py, || crate::velocity_blur(a, v, w, h, samples))?;
    shaped(py, out, [h, w, 4])
}

/// Chapman's camera motion blur of rgba (H,W,4) f32 with depth (H,W) f32 seen by two cameras
/// ([`CameraArg`]): `samples` taps, the velocity times `scale`.
#[pyfunction]
fn _camera_motion_blur<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArray3<'py, f32>,
    depth: PyReadonlyArray2<'py, f32>,
    camera: CameraArg<'py>,
    previous_camera: CameraArg<'py>,
    samples: usize,
    scale: f64,
) -> PyOut<'py> {
    let (a, w, h) = img3(&rgba, "rgba", 4)?;
    let (d, dw, dh) = img2(&depth, "depth")?;
    same_size("depth", (dh, dw), (h, w))?;
    let blur = CameraBlur {
        current: camera.matrices("camera")?,
        previous: previous_camera.matrices("previous_camera")?,
        samples,
        scale,
    };
    let out = detached_in_pool(py, || crate::camera_motion_blur(a, d, w, h, &blur))?;
    shaped(py, out, [h, w, 4])
}

/// McGuire/Guertin reconstruction filter of rgba (H,W,4) f32 with depth (H,W) f32 and
/// velocity (H,W,2) f32; `moving` (y0, y1, x0, x1): the window outside which every velocity
/// is 0 (the caller's promise), None for the whole image.
#[pyfunction]
#[pyo3(signature = (rgba, depth, velocity, samples, tile, soft_depth, moving = None))]
#[allow(clippy::too_many_arguments)] // (the Python signature's)
fn _reconstruct<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArray3<'py, f32>,
    depth: PyReadonlyArray2<'py, f32>,
    velocity: PyReadonlyArray3<'py, f32>,
    samples: usize,
    tile: usize,
    soft_depth: f32,
    moving: Option<(usize, usize, usize, usize)>,
) -> PyOut<'py> {
    let (a, w, h) = img3(&rgba, "rgba", 4)?;
    let (d, dw, dh) = img2(&depth, "depth")?;
    same_size("depth", (dh, dw), (h, w))?;
    let (v, vw, vh) = img3(&velocity, "velocity", 2)?;
    same_size("velocity", (vh, vw), (h, w))?;
    let params = ReconstructParams {
        samples,
        tile,
        soft_depth,
    };
    let moving = moving.unwrap_or((0, h, 0, w));
    let out = detached_in_pool(py, || {
        crate::reconstruct_moving(a, d, v, (w, h), params, moving)
    })?;
    shaped(py, out, [h, w, 4])
}

/// The longest velocity (float64 pixels) of a velocity buffer (H,W,2) f32, or of its window
/// `within` (y0, y1, x0, x1), read in place.
#[pyfunction]
#[pyo3(signature = (velocity, within = None))]
fn _max_speed(
    py: Python<'_>,
    velocity: PyReadonlyArray3<'_, f32>,
    within: Option<(usize, usize, usize, usize)>,
) -> PyResult<f64> {
    let (v, w, h) = img3(&velocity, "velocity", 2)?;
    match within {
        None => Ok(py.detach(|| crate::max_speed(v))),
        Some((y0, y1, x0, x1)) => {
            if !(y0 <= y1 && y1 <= h && x0 <= x1 && x1 <= w) {
                let msg =
                    format!("({y0}, {y1}, {x0}, {x1}) is not a window of the ({h}, {w}) image");
                return Err(Error::value("within", msg).into());
            }
            Ok(py.detach(|| crate::max_speed_in(v, w, (y0, y1, x0, x1))))
        }
    }
}

/// The options of `_camera_frame_blur`, the items of a dict: the two cameras
/// ([`CameraArg`]), the f32 velocity `scale` and the `samples` taps (None: the line integral).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct CameraFrameArgs<'py> {
    camera: CameraArg<'py>,
    previous_camera: CameraArg<'py>,
    scale: f32,
    samples: Option<usize>,
}

/// The `camera_velocity` method's blur of a frame: rgba (H,W,4) f32, depth (H,W) f32, ids
/// (H,W) i32, velocity (H,W,2) f32, `moving[id]` and the options ([`CameraFrameArgs`]).
/// Returns (the blurred rgba (H,W,4) f32, pixels blurred as a line integral).
#[pyfunction]
fn _camera_frame_blur<'py>(
    py: Python<'py>,
    rgba: PyReadonlyArray3<'py, f32>,
    depth: PyReadonlyArray2<'py, f32>,
    ids: PyReadonlyArray2<'py, i32>,
    velocity: PyReadonlyArray3<'py, f32>,
    moving: Vec<bool>,
    options: CameraFrameArgs<'py>,
) -> PyResult<(Bound<'py, PyAny>, usize)> {
    let (a, w, h) = img3(&rgba, "rgba", 4)?;
    let (d, dw, dh) = img2(&depth, "depth")?;
    same_size("depth", (dh, dw), (h, w))?;
    let (v, vw, vh) = img3(&velocity, "velocity", 2)?;
    same_size("velocity", (vh, vw), (h, w))?;
    if ids.shape() != [h, w] {
        return Err(Error::shape("ids", format!("expected shape ({h},{w})")).into());
    }
    let ids = c_slice(&ids, "ids")?;
    let cur = options.camera.matrices("camera")?;
    let prev = options.previous_camera.matrices("previous_camera")?;
    let frame = crate::FrameMotion {
        velocity: v,
        ids,
        moving: &moving,
    };
    let taps = (options.scale, options.samples);
    let (out, lines) = detached_in_pool(py, || {
        crate::camera_frame_blur(a, d, (w, h), frame, (&cur, &prev), taps)
    })?;
    Ok((shaped(py, out, [h, w, 4])?, lines))
}

/// The coverage glow's composite of the `opaque_image` method over a window (y0, y1, x0, x1)
/// of the static colour back (H,W,4) f32 and depth back_depth (H,W) f32: blurred and depth
/// (y1 - y0, x1 - x0, 4) f32. Returns (the window's colour, pixels kept in front).
#[pyfunction]
fn _coverage_composite<'py>(
    py: Python<'py>,
    back: PyReadonlyArray3<'py, f32>,
    back_depth: PyReadonlyArray2<'py, f32>,
    window: (usize, usize, usize, usize),
    blurred: PyReadonlyArray3<'py, f32>,
    depth: PyReadonlyArray3<'py, f32>,
    layers: bool,
) -> PyResult<(Bound<'py, PyAny>, u64)> {
    let (b, w, h) = img3(&back, "back", 4)?;
    let (z, zw, zh) = img2(&back_depth, "back_depth")?;
    same_size("back_depth", (zh, zw), (h, w))?;
    let (bl, bw, bh) = img3(&blurred, "blurred", 4)?;
    let (d, dw, dh) = img3(&depth, "depth", 4)?;
    same_size("depth", (dh, dw), (bh, bw))?;
    let (out, front) = detached_in_pool(py, || {
        crate::coverage_composite((b, z), (w, h), window, (bl, d), layers)
    })?;
    Ok((shaped(py, out, [bh, bw, 4])?, front))
}

/// The `opaque_image` method's coverage glow of one moving object, in place on out (H,W,4) f32
/// (the colour so far) over the static depth back_depth (H,W) f32: layers cut from the sharp
/// frame rgba (H,W,4) f32 with pasted = (window, colour there) or None laid over it and depth
/// (H,W) f32, object = (window, labels (h,w) i32 there), parts = [(window, direction, length,
/// blur)]. back: None, or the colour so far (H,W,4) f32, which out (then holding nothing yet)
/// receives outside the object's windows. Returns the pixels kept in front.
#[pyfunction]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn _coverage_blur(
    py: Python<'_>,
    mut out: PyReadwriteArray3<'_, f32>,
    back_depth: PyReadonlyArray2<'_, f32>,
    rgba: PyReadonlyArray3<'_, f32>,
    pasted: Option<(Window, PyReadonlyArray3<'_, f32>)>,
    depth: PyReadonlyArray2<'_, f32>,
    object: (Window, PyReadonlyArray2<'_, i32>),
    parts: Vec<(Window, [f32; 2], f32, bool)>,
    layers: bool,
    back: Option<PyReadonlyArray3<'_, f32>>,
) -> PyResult<u64> {
    let (w, h) = (out.shape()[1], out.shape()[0]);
    if out.shape()[2] != 4 {
        return Err(Error::shape("out", "expected shape (H,W,4)").into());
    }
    let (r, rw, rh) = img3(&rgba, "rgba", 4)?;
    same_size("rgba", (rh, rw), (h, w))?;
    let (z, zw, zh) = img2(&back_depth, "back_depth")?;
    same_size("back_depth", (zh, zw), (h, w))?;
    let (d, dw, dh) = img2(&depth, "depth")?;
    same_size("depth", (dh, dw), (h, w))?;
    let pasted = match &pasted {
        Some((win, a)) => Some((*win, img3(a, "pasted", 4)?.0)),
        None => None,
    };
    let labels = c_slice(&object.1, "labels")?;
    let parts: Vec<CoveragePart> = parts
        .into_iter()
        .map(|(window, direction, length, blur)| CoveragePart {
            window,
            direction,
            length,
            blur,
        })
        .collect();
    let source = CoverageSource {
        rgba: r,
        pasted,
        depth: d,
    };
    let object = CoverageObject {
        window: object.0,
        labels,
        parts: &parts,
    };
    let back = match &back {
        Some(b) => {
            let (b, bw, bh) = img3(b, "back", 4)?;
            same_size("back", (bh, bw), (h, w))?;
            Some(b)
        }
        None => None,
    };
    let o = c_slice_mut(&mut out, "out")?;
    Ok(detached_in_pool(py, || {
        crate::coverage_blur((o, back), z, (w, h), &source, &object, layers)
    })?)
}

/// `_object_pixels`' mask, velocities, depths and mean velocity.
type ObjectOut<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    [f64; 2],
);

/// The pixels of object k in window (y0, y1, x0, x1) of a frame: ids (H,W) i32, velocity
/// (H,W,2) f32, depth (H,W) f32. Returns (mask (h,w) bool, velocities (N,2) f64 and depths (N,)
/// f32 of its pixels in row order, their mean velocity (2,) f64).
#[pyfunction]
fn _object_pixels<'py>(
    py: Python<'py>,
    ids: PyReadonlyArray2<'py, i32>,
    velocity: PyReadonlyArray3<'py, f32>,
    depth: PyReadonlyArray2<'py, f32>,
    window: Window,
    k: i32,
) -> PyResult<ObjectOut<'py>> {
    let (d, w, h) = img2(&depth, "depth")?;
    let (v, vw, vh) = img3(&velocity, "velocity", 2)?;
    same_size("velocity", (vh, vw), (h, w))?;
    if ids.shape() != [h, w] {
        return Err(Error::shape("ids", format!("expected shape ({h},{w})")).into());
    }
    let ids = c_slice(&ids, "ids")?;
    let got = detached_in_pool(py, || crate::object_pixels(ids, v, d, (w, h), window, k))?;
    let n = got.depth.len();
    let (y0, y1, x0, x1) = window;
    Ok((
        shaped(py, got.mask, [y1 - y0, x1 - x0])?,
        shaped(py, got.velocity, [n, 2])?,
        shaped(py, got.depth, [n])?,
        got.mean,
    ))
}

/// Whether the velocities (N,2) f64 of an object's pixels certainly form one group of
/// `opaque_image`'s split into `sectors` directions and lengths `ratio` apart (the core's
/// `one_velocity_group`); false: not certain.
#[pyfunction]
fn _one_velocity_group(
    velocities: PyReadonlyArray2<'_, f64>,
    sectors: u32,
    ratio: f64,
) -> PyResult<bool> {
    let v = rows::<f64, 2>(&velocities, "velocities")?;
    Ok(crate::one_velocity_group(v, sectors, ratio))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_reconstruct, m)?)?;
    m.add_function(wrap_pyfunction!(_max_speed, m)?)?;
    m.add_function(wrap_pyfunction!(_camera_frame_blur, m)?)?;
    m.add_function(wrap_pyfunction!(_coverage_composite, m)?)?;
    m.add_function(wrap_pyfunction!(_coverage_blur, m)?)?;
    m.add_function(wrap_pyfunction!(_object_pixels, m)?)?;
    m.add_function(wrap_pyfunction!(_one_velocity_group, m)?)?;
    m.add_function(wrap_pyfunction!(_glow, m)?)?;
    m.add_function(wrap_pyfunction!(_box_blur, m)?)?;
    m.add_function(wrap_pyfunction!(_splat_paths, m)?)?;
    m.add_function(wrap_pyfunction!(_scatter_pieces, m)?)?;
    m.add_function(wrap_pyfunction!(_pixel_bounds, m)?)?;
    m.add_function(wrap_pyfunction!(_sample_colors, m)?)?;
    m.add_function(wrap_pyfunction!(_colored, m)?)?;
    m.add_function(wrap_pyfunction!(_opaque_blur, m)?)?;
    m.add_function(wrap_pyfunction!(_opaque_motion_blur, m)?)?;
    m.add_function(wrap_pyfunction!(_pyramid_blur, m)?)?;
    m.add_function(wrap_pyfunction!(_pyramid_glow, m)?)?;
    m.add_function(wrap_pyfunction!(_pyramid_opaque_blur, m)?)?;
    m.add_function(wrap_pyfunction!(_depth_of_field, m)?)?;
    m.add_function(wrap_pyfunction!(_lens_blur, m)?)?;
    m.add_function(wrap_pyfunction!(_camera_velocity, m)?)?;
    m.add_function(wrap_pyfunction!(_velocity_blur, m)?)?;
    m.add_function(wrap_pyfunction!(_camera_motion_blur, m)?)?;
    m.add("MAX_LENGTH", f64::from(crate::MAX_LENGTH))?;
    m.add("MAX_FPS_RATIO", crate::MAX_FPS_RATIO)?;
    m.add("MAX_VELOCITY", crate::MAX_VELOCITY)?;
    m.add("MAX_LEVELS", crate::MAX_LEVELS)?;
    m.add("MAX_LAYERS", crate::MAX_LAYERS)?;
    m.add("MAX_LENS_LEVELS", crate::MAX_LENS_LEVELS)?;
    m.add("MAX_SAMPLES", crate::MAX_SAMPLES)?;
    m.add("MAX_TAPS", crate::MAX_TAPS)?;
    m.add("MIN_ALPHA", f64::from(crate::MIN_ALPHA))?;
    Ok(())
}
