//! Bindings for the painter and the accumulation frame: `_Painter` (objects drawn at any
//! shutter time) with `layer` (one time), `accumulate_still` and `accumulate_moving` (a whole
//! frame's samples in one call). The GIL is released while they draw.
use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;

use super::convert::{c_slice, detached_in_pool, face_indices, rows, shaped};
use super::motion::PyKeyframes;
use crate::{
    accumulate_moving, accumulate_still, Accumulated, Error, Frame, Layer, Mat4, PaintObject,
    Painter, Samples, Shading, StillCamera,
};

/// One object as the Python layer passes it: (object id, shading name, vertices f64 (V,3),
/// faces i64 (F,3), rgba f32 (1|V,4), normals f32 (V,3) | None, keyframes | None).
type ObjectArgs<'py> = (
    i32,
    String,
    PyReadonlyArray2<'py, f64>,
    PyReadonlyArray2<'py, i64>,
    PyReadonlyArray2<'py, f32>,
    Option<PyReadonlyArray2<'py, f32>>,
    Option<PyRef<'py, PyKeyframes>>,
);

/// The static layer as the Python layer passes it: rgba f32 (H,W,4), depth f32 (H,W), ids i32
/// (H,W), one entry per sample.
type StaticArgs<'py> = (
    PyReadonlyArray3<'py, f32>,
    PyReadonlyArray2<'py, f32>,
    PyReadonlyArray2<'py, i32>,
);

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

fn object(o: &ObjectArgs<'_>) -> Result<PaintObject, Error> {
    let vertices = rows::<f64, 3>(&o.2, "vertices")?.to_vec();
    let faces = face_indices(
        rows::<i64, 3>(&o.3, "faces")?.as_flattened(),
        vertices.len(),
    )?;
    let rgba = rows::<f32, 4>(&o.4, "rgba")?.to_vec();
    if rgba.len() != 1 && rgba.len() != vertices.len() {
        return Err(Error::shape(
            "rgba",
            "expected one colour or one per vertex",
        ));
    }
    let normals =
        o.5.as_ref()
            .map(|n| rows::<f32, 3>(n, "normals").map(<[_]>::to_vec))
            .transpose()?;
    if normals.as_ref().is_some_and(|n| n.len() != vertices.len()) {
        return Err(Error::shape("normals", "expected one normal per vertex"));
    }
    Ok(PaintObject {
        id: o.0,
        shading: Shading::parse(&o.1)?,
        vertices,
        faces,
        rgba,
        normals,
        motion: o.6.as_ref().map(|k| k.inner.clone()),
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

/// Objects drawn at any shutter time (see `src/accumulate/painter.rs`).
#[pyclass(name = "_Painter", module = "motionblur._core")]
pub struct PyPainter {
    inner: Painter,
}

#[pymethods]
impl PyPainter {
    /// `objects`: list of (id, shading, vertices, faces, rgba, normals, keyframes); `lights`:
    /// (direction, intensity) pairs; `ambient` RGB.
    #[new]
    fn new(
        objects: Vec<ObjectArgs<'_>>,
        lights: Vec<([f64; 3], [f64; 3])>,
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

    /// The still-camera accumulation frame: `times`, `weights` (N,) float64, `reference`
    /// sample; the supersampled camera's `view`, `projection`, `view_projection` (4,4),
    /// `width` x `height` samples, `aa`; the static layer (rgba, depth, ids) of that size and
    /// whether it is opaque. Returns None (nothing on the image) or ((x0, y0, x1, y1) window,
    /// rgba (h,w,4) f32, depth (h,w) f32, ids (h,w) i32, draw calls).
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (times, weights, reference, view, projection, view_projection, width, height, aa, background, opaque))]
    fn accumulate_still<'py>(
        &self,
        py: Python<'py>,
        times: PyReadonlyArray1<'_, f64>,
        weights: PyReadonlyArray1<'_, f64>,
        reference: usize,
        view: PyReadonlyArray2<'_, f64>,
        projection: PyReadonlyArray2<'_, f64>,
        view_projection: PyReadonlyArray2<'_, f64>,
        width: usize,
        height: usize,
        aa: usize,
        background: StaticArgs<'_>,
        opaque: bool,
    ) -> PyResult<Option<StillFrame<'py>>> {
        let camera = StillCamera {
            view: matrix(&view, "view")?,
            projection: matrix(&projection, "projection")?,
            view_projection: matrix(&view_projection, "view_projection")?,
            width,
            height,
            aa,
        };
        if background.0.shape() != [height, width, 4] {
            return Err(Error::shape("background", "rgba must be (height, width, 4)").into());
        }
        let bg = Layer {
            width,
            height,
            rgba: c_slice(&background.0, "background")?,
            depth: c_slice(&background.1, "background")?,
            ids: c_slice(&background.2, "background")?,
        };
        let (ts, ws) = (c_slice(&times, "times")?, c_slice(&weights, "weights")?);
        let samples = Samples {
            times: ts,
            weights: ws,
            reference,
        };
        let inner = &self.inner;
        let out = detached_in_pool(py, || accumulate_still(inner, &camera, samples, bg, opaque))?;
        let Some(Accumulated {
            frame: Frame {
                rgba, depth, ids, ..
            },
            window: w,
            draw_calls,
        }) = out
        else {
            return Ok(None);
        };
        let win = (w[0], w[1], w[2], w[3]).into_pyobject(py)?.into_any();
        let (r, d, i) = arrays(py, rgba, depth, ids, w[2] - w[0], w[3] - w[1])?;
        Ok(Some((win, r, d, i, draw_calls)))
    }

    /// The moving-camera accumulation frame: `times`, `weights` (N,) float64, `reference`
    /// sample, one view (N,4,4) float64 per sample, the `projection` (4,4), `width` x `height`
    /// samples. Returns (rgba (height,width,4) f32, depth, ids of the reference sample).
    #[allow(clippy::too_many_arguments)]
    fn accumulate_moving<'py>(
        &self,
        py: Python<'py>,
        times: PyReadonlyArray1<'_, f64>,
        weights: PyReadonlyArray1<'_, f64>,
        reference: usize,
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
        let (ts, ws) = (c_slice(&times, "times")?, c_slice(&weights, "weights")?);
        let samples = Samples {
            times: ts,
            weights: ws,
            reference,
        };
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
