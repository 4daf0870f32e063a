//! Bindings for the painter and the accumulation frame: `_Painter` (objects drawn at any
//! shutter time) with `layer` (one time), `accumulate_still` and `accumulate_moving` (a whole
//! frame's samples in one call). The GIL is released while they draw.
use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::prelude::*;

use super::args::{LayerArg, LightArg};
use super::convert::{c_slice, detached_in_pool, face_indices_u32, rows, shaped};
use super::motion::PyKeyframes;
use crate::{
    accumulate_moving, accumulate_still, accumulate_still_parts, Accumulated, Error, Frame, Layer,
    Mat4, PaintObject, Painter, Samples, Shading, StillCamera,
};

/// One object, the items of a dict: `id`, `shading` name, `vertices` f64 (V,3), `faces` i64
/// (F,3), `rgba` f32 (1|V,4), `normals` f32 (V,3) | None, `keyframes` | None.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct ObjectArg<'py> {
    id: i32,
    shading: String,
    vertices: PyReadonlyArray2<'py, f64>,
    faces: PyReadonlyArray2<'py, i64>,
    rgba: PyReadonlyArray2<'py, f32>,
    normals: Option<PyReadonlyArray2<'py, f32>>,
    keyframes: Option<PyRef<'py, PyKeyframes>>,
}

/// The time samples of an accumulation frame, the items of a dict: `times` and `weights` (N,)
/// f64, `reference` (the sample whose depth and ids the frame keeps).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct SamplesArg<'py> {
    times: PyReadonlyArray1<'py, f64>,
    weights: PyReadonlyArray1<'py, f64>,
    reference: usize,
}

impl SamplesArg<'_> {
    fn samples(&self) -> Result<Samples<'_>, Error> {
        Ok(Samples {
            times: c_slice(&self.times, "times")?,
            weights: c_slice(&self.weights, "weights")?,
            reference: self.reference,
        })
    }
}

/// The supersampled still camera, the items of a dict: `view`, `projection`, `view_projection`
/// (4,4) f64, `width` x `height` samples, `aa` samples a pixel along each axis.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct StillCameraArg<'py> {
    view: PyReadonlyArray2<'py, f64>,
    projection: PyReadonlyArray2<'py, f64>,
    view_projection: PyReadonlyArray2<'py, f64>,
    width: usize,
    height: usize,
    aa: usize,
}

impl StillCameraArg<'_> {
    fn camera(&self) -> Result<StillCamera, Error> {
        Ok(StillCamera {
            view: matrix(&self.view, "view")?,
            projection: matrix(&self.projection, "projection")?,
            view_projection: matrix(&self.view_projection, "view_projection")?,
            width: self.width,
            height: self.height,
            aa: self.aa,
        })
    }
}

/// A (4,4) float64 matrix, row-major.
fn matrix(a: &PyReadonlyArray2<'_, f64>, name: &'static str) -> Result<Mat4, Error> {
    let v = a.as_array();
    if v.shape() != [4, 4] {
        return Err(Error::shape(
            name,
            format!("expected shape (4,4), got {:?}", v.shape()),
        ));
    }
    Ok(std::array::from_fn(|r| std::array::from_fn(|c| v[[r, c]])))
}

fn object(o: &ObjectArg<'_>) -> Result<PaintObject, Error> {
    let vertices = rows::<f64, 3>(&o.vertices, "vertices")?.to_vec();
    // converted only: the rasterizer's `Draw::validate` checks the range of every draw it is given
    let faces = face_indices_u32(rows::<i64, 3>(&o.faces, "faces")?);
    let rgba = rows::<f32, 4>(&o.rgba, "rgba")?.to_vec();
    if rgba.len() != 1 && rgba.len() != vertices.len() {
        return Err(Error::shape(
            "rgba",
            "expected one colour or one per vertex",
        ));
    }
    let normals = o
        .normals
        .as_ref()
        .map(|n| rows::<f32, 3>(n, "normals").map(<[_]>::to_vec))
        .transpose()?;
    if normals.as_ref().is_some_and(|n| n.len() != vertices.len()) {
        return Err(Error::shape("normals", "expected one normal per vertex"));
    }
    Ok(PaintObject {
        id: o.id,
        shading: Shading::parse(&o.shading)?,
        vertices,
        faces,
        rgba,
        normals,
        motion: o.keyframes.as_ref().map(|k| k.inner.clone()),
    })
}

/// (rgba (h,w,4) f32, depth (h,w) f32, ids (h,w) i32) of `h` x `w` samples.
type Arrays<'py> = (Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>);

fn arrays(
    py: Python<'_>,
    rgba: Vec<f32>,
    depth: Vec<f32>,
    ids: Vec<i32>,
    w: usize,
    h: usize,
) -> PyResult<Arrays<'_>> {
    Ok((
        shaped(py, rgba, [h, w, 4])?,
        shaped(py, depth, [h, w])?,
        shaped(py, ids, [h, w])?,
    ))
}

/// A still frame: ((x0, y0, x1, y1) window, rgba, depth, ids, draw calls).
type StillFrame<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    usize,
);

/// The still camera and its static layer of the camera's size, checked (errors name
/// `background` and the camera's matrices).
fn still_inputs<'a>(
    camera: &StillCameraArg<'_>,
    background: &'a LayerArg<'_>,
) -> Result<(StillCamera, Layer<'a>), Error> {
    let camera = camera.camera()?;
    if background.size("background")? != [camera.height, camera.width] {
        return Err(Error::shape(
            "background",
            "rgba must be (height, width, 4)",
        ));
    }
    Ok((camera, background.layer("background")?))
}

/// An accumulation taken apart: its window (x0, y0, x1, y1) as a Python tuple, its frame,
/// the window's width and height and the draw calls; None when nothing was drawn.
type Taken<'py> = (Bound<'py, PyAny>, Frame, [usize; 2], usize);

/// [`Taken`] of `out`.
fn taken(py: Python<'_>, out: Option<Accumulated>) -> PyResult<Option<Taken<'_>>> {
    let Some(Accumulated {
        frame,
        window: w,
        draw_calls,
    }) = out
    else {
        return Ok(None);
    };
    let win = (w[0], w[1], w[2], w[3]).into_pyobject(py)?.into_any();
    Ok(Some((win, frame, [w[2] - w[0], w[3] - w[1]], draw_calls)))
}

/// A still-camera accumulation as Python values ([`StillFrame`]), None when nothing was drawn.
fn still_frame(py: Python<'_>, out: Option<Accumulated>) -> PyResult<Option<StillFrame<'_>>> {
    let Some((win, f, [w, h], draw_calls)) = taken(py, out)? else {
        return Ok(None);
    };
    let (r, d, i) = arrays(py, f.rgba, f.depth, f.ids, w, h)?;
    Ok(Some((win, r, d, i, draw_calls)))
}

/// A part of a still frame: [`StillFrame`] with depth and ids None when not kept.
type PartFrame<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Option<Bound<'py, PyAny>>,
    Option<Bound<'py, PyAny>>,
    usize,
);

/// A part's frame as Python values ([`PartFrame`]): [`still_frame`]'s when `kept`, else its
/// rgba alone (depth and ids None).
fn part_frame(
    py: Python<'_>,
    out: Option<Accumulated>,
    kept: bool,
) -> PyResult<Option<PartFrame<'_>>> {
    if kept {
        return Ok(still_frame(py, out)?.map(|(w, r, d, i, n)| (w, r, Some(d), Some(i), n)));
    }
    let Some((win, f, [w, h], draw_calls)) = taken(py, out)? else {
        return Ok(None);
    };
    Ok(Some((
        win,
        shaped(py, f.rgba, [h, w, 4])?,
        None,
        None,
        draw_calls,
    )))
}

/// Objects drawn at any shutter time (see `src/accumulate/painter.rs`).
#[pyclass(name = "_Painter", module = "motionblur._core")]
pub struct PyPainter {
    inner: Painter,
}

#[pymethods]
impl PyPainter {
    /// `objects`: list of dicts ([`ObjectArg`]); `lights`: (direction, intensity) pairs;
    /// `ambient` RGB.
    #[new]
    fn new(
        objects: Vec<ObjectArg<'_>>,
        lights: Vec<LightArg>,
        ambient: [f64; 3],
    ) -> PyResult<Self> {
        let objects = objects.iter().map(object).collect::<Result<Vec<_>, _>>()?;
        Ok(PyPainter {
            inner: Painter::new(objects, lights, ambient)?,
        })
    }

    /// The objects at shutter time `t` through `view` and `projection` (4,4) float64:
    /// (rgba (height,width,4) f32, depth (height,width) f32, ids (height,width) i32).
    fn layer<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        view: PyReadonlyArray2<'_, f64>,
        projection: PyReadonlyArray2<'_, f64>,
        width: u32,
        height: u32,
    ) -> PyResult<Arrays<'py>> {
        let (v, p) = (matrix(&view, "view")?, matrix(&projection, "projection")?);
        let inner = &self.inner;
        let l = detached_in_pool(py, || inner.layer(t, &v, &p, width, height))?;
        arrays(py, l.rgba, l.depth, l.ids, width as usize, height as usize)
    }

    /// The still-camera accumulation frame of `samples` ([`SamplesArg`]) seen by `camera`
    /// ([`StillCameraArg`]) over the static layer `background` (`rgba`, `depth`, `ids`
    /// attributes of the camera's size), `opaque` when every static object is. Returns None
    /// (nothing on the image) or ((x0, y0, x1, y1) window, rgba (h,w,4) f32, depth (h,w) f32,
    /// ids (h,w) i32, draw calls).
    fn accumulate_still<'py>(
        &self,
        py: Python<'py>,
        samples: SamplesArg<'_>,
        camera: StillCameraArg<'_>,
        background: LayerArg<'_>,
        opaque: bool,
    ) -> PyResult<Option<StillFrame<'py>>> {
        let (camera, bg) = still_inputs(&camera, &background)?;
        let samples = samples.samples()?;
        let inner = &self.inner;
        let out = detached_in_pool(py, || accumulate_still(inner, &camera, samples, bg, opaque))?;
        still_frame(py, out)
    }

    /// [`Self::accumulate_still`] of each of `parts` (each a [`SamplesArg`]) in one call: the
    /// same frames, one hand-off to the pool for all of them (an accumulation's halves), the
    /// static layer cropped once for all. With `keep` an index, only that part gets its
    /// reference sample's depth and ids (the others' are None).
    #[pyo3(signature = (parts, camera, background, opaque, keep=None))]
    fn accumulate_still_parts<'py>(
        &self,
        py: Python<'py>,
        parts: Vec<SamplesArg<'_>>,
        camera: StillCameraArg<'_>,
        background: LayerArg<'_>,
        opaque: bool,
        keep: Option<usize>,
    ) -> PyResult<Vec<Option<PartFrame<'py>>>> {
        let (camera, bg) = still_inputs(&camera, &background)?;
        let samples = parts
            .iter()
            .map(SamplesArg::samples)
            .collect::<Result<Vec<_>, _>>()?;
        if keep.is_some_and(|k| k >= samples.len()) {
            return Err(Error::value("keep", "must index one of the parts").into());
        }
        let inner = &self.inner;
        let outs = detached_in_pool(py, || {
            accumulate_still_parts(inner, &camera, &samples, bg, opaque, keep)
        })?;
        outs.into_iter()
            .enumerate()
            .map(|(p, o)| part_frame(py, o, keep.is_none_or(|k| k == p)))
            .collect()
    }

    /// The moving-camera accumulation frame of `samples` ([`SamplesArg`]): one view (N,4,4)
    /// float64 per sample, the `projection` (4,4), `width` x `height` samples. Returns (rgba
    /// (height,width,4) f32, depth, ids of the reference sample).
    fn accumulate_moving<'py>(
        &self,
        py: Python<'py>,
        samples: SamplesArg<'_>,
        views: PyReadonlyArray3<'_, f64>,
        projection: PyReadonlyArray2<'_, f64>,
        width: usize,
        height: usize,
    ) -> PyResult<Arrays<'py>> {
        let v = views.as_array();
        if v.shape()[1] != 4 || v.shape()[2] != 4 {
            return Err(Error::shape(
                "views",
                format!("expected shape (N,4,4), got {:?}", v.shape()),
            )
            .into());
        }
        let views: Vec<Mat4> = v
            .outer_iter()
            .map(|m| std::array::from_fn(|r| std::array::from_fn(|c| m[[r, c]])))
            .collect();
        let p = matrix(&projection, "projection")?;
        let samples = samples.samples()?;
        let inner = &self.inner;
        let out = detached_in_pool(py, || {
            accumulate_moving(inner, &views, &p, width, height, samples)
        })?;
        let f = out.frame;
        arrays(py, f.rgba, f.depth, f.ids, width, height)
    }
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyPainter>()?;
    Ok(())
}
