//! Bindings for the analytic method: numpy in, the frame out, GIL released.
use glam::DMat4;
use numpy::{
    PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3, PyReadwriteArray2, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::args::{lights, LayerArg, LightArg};
use super::convert::{
    c_slice, c_slice_mut, detached_in_pool, face_indices_u32, matrix, rows, shaped, ToDict,
};
use crate::{
    render_analytic, transform_points, AnalyticInput, AnalyticStats, Error, MovingDraw, Quadrature,
    Rolling, Shading, Shutter,
};

/// One moving draw, read off the attributes of a `motionblur.MovingDraw`: `positions` f64
/// (K+1,V,3), `faces` i64 (F,3), `rgba` f32 (1|V,4), `normals` f32 (K+1,V,3) | None,
/// `object_id`, `cull_back`, `shading` name.
#[derive(FromPyObject)]
struct MovingDrawArg<'py> {
    positions: PyReadonlyArray3<'py, f64>,
    faces: PyReadonlyArray2<'py, i64>,
    rgba: PyReadonlyArray2<'py, f32>,
    normals: Option<PyReadonlyArray3<'py, f32>>,
    object_id: i32,
    cull_back: bool,
    shading: String,
}

/// The shutter: a filter name, a `motionblur.Trapezoid` (its `open` and `close` ramps) or (M,)
/// f64 weights of M equal strata.
#[derive(FromPyObject)]
enum ShutterArg<'py> {
    Name(String),
    Trapezoid { open: f64, close: f64 },
    Weights(PyReadonlyArray1<'py, f64>),
}

/// Gauss points in time per visible piece: a count or `"auto"`.
#[derive(FromPyObject)]
enum GaussArg {
    Points(i64),
    Name(String),
}

impl GaussArg {
    /// The core's quadrature (a count that fits a `u8`; its range is the core's `validate`'s
    /// to check).
    fn quadrature(&self) -> Result<Quadrature, Error> {
        match self {
            GaussArg::Name(n) if n == "auto" => Ok(Quadrature::Auto),
            GaussArg::Name(n) => Err(Error::value(
                "gauss",
                format!("expected 'auto' or 1 to 4, got {n:?}"),
            )),
            GaussArg::Points(n) => u8::try_from(*n)
                .map(Quadrature::Points)
                .map_err(|_| Error::value("gauss", "must be 1 to 4 points (or auto)")),
        }
    }
}

/// The options of one `_analytic` call, the items of a dict: the fields of the core's
/// [`AnalyticInput`] but the draws and the backdrop: `width`, `height`, `samples`, `times` (K+1,)
/// f64, `view_projections` (1|K+1,4,4) f64, `shutter`, `lights`, `ambient`, `gauss`,
/// `reference_time`, `shade`, `tile_budget` bytes, and (optional) `exposure`: the number of
/// object ids of the exposure channel, or None (off); (optional) `rolling`: the readout
/// fraction of a rolling shutter (0: global) and `rolling_bottom_to_top`.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct AnalyticArgs<'py> {
    width: u32,
    height: u32,
    samples: u32,
    times: PyReadonlyArray1<'py, f64>,
    view_projections: PyReadonlyArray3<'py, f64>,
    shutter: ShutterArg<'py>,
    lights: Vec<LightArg>,
    ambient: [f64; 3],
    gauss: GaussArg,
    reference_time: f64,
    shade: bool,
    tile_budget: usize,
    #[pyo3(default)]
    exposure: Option<u32>,
    #[pyo3(default)]
    rolling: f64,
    #[pyo3(default)]
    rolling_bottom_to_top: bool,
}

/// A draw's arrays borrowed from numpy (no copy: at 4K with a hundred segments the positions
/// and normals are hundreds of MB), but the face indices (converted to `u32`).
struct Borrowed<'a> {
    positions: &'a [[f64; 3]],
    faces: Vec<[u32; 3]>,
    rgba: &'a [[f32; 4]],
    normals: Option<&'a [[f32; 3]]>,
    object_id: i32,
    cull_back: bool,
    shading: Shading,
}

/// The points of a C-contiguous (..., 3) array, borrowed.
fn points<'a, T: numpy::Element>(
    a: &'a PyReadonlyArray3<'_, T>,
    name: &'static str,
) -> Result<&'a [[T; 3]], Error> {
    let flat = c_slice(a, name)?;
    // SAFETY: `[T; 3]` has the size of 3 values of `T` and the alignment of one; the caller
    // checked the last axis is 3, so `flat` holds exactly `len / 3` whole points.
    Ok(unsafe { std::slice::from_raw_parts(flat.as_ptr().cast::<[T; 3]>(), flat.len() / 3) })
}

/// The core's draw, borrowed. Face indices are converted to `u32` only: the core's `validate`
/// checks their range.
fn borrowed<'a>(d: &'a MovingDrawArg<'_>, k1: usize) -> Result<Borrowed<'a>, Error> {
    let s = d.positions.shape();
    if s[0] != k1 || s[2] != 3 {
        return Err(Error::shape(
            "positions",
            format!("expected ({k1},V,3) (one (V,3) per boundary), got {s:?}"),
        ));
    }
    let positions = points(&d.positions, "positions")?;
    let faces = face_indices_u32(rows::<i64, 3>(&d.faces, "faces")?);
    let rgba = rows::<f32, 4>(&d.rgba, "rgba")?;
    let normals = match &d.normals {
        None => None,
        Some(n) => {
            if n.shape() != s {
                return Err(Error::shape("normals", "must have the shape of positions"));
            }
            Some(points(n, "normals")?)
        }
    };
    Ok(Borrowed {
        positions,
        faces,
        rgba,
        normals,
        object_id: d.object_id,
        cull_back: d.cull_back,
        shading: Shading::parse(&d.shading)?,
    })
}

fn view_projections(a: &PyReadonlyArray3<'_, f64>) -> Result<Vec<DMat4>, Error> {
    let vs = a.shape();
    if vs[1] != 4 || vs[2] != 4 {
        return Err(Error::shape("view_projections", "expected (N,4,4)"));
    }
    Ok(c_slice(a, "view_projections")?
        .chunks_exact(16)
        .map(|m| DMat4::from_cols_slice(m).transpose())
        .collect())
}

/// The image arrays of a frame: rgba (H,W,4) f32, depth (H,W) f32, ids (H,W) i32, velocity
/// (H,W,2) f32, stats, and the exposure channel's (fraction, first, last) (H,W,P) f32 or None.
type FrameOut<'py> = (
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyDict>,
    Option<ExposureOut<'py>>,
);

/// The exposure channel's fraction, first and last (H,W,P) f32.
type ExposureOut<'py> = (Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>);

/// Renders `draws` (`motionblur.MovingDraw` objects) analytically with `options`
/// ([`AnalyticArgs`]) over `backdrop` (an object with `rgba` (HS,WS,4), `depth`, `ids` (HS,WS),
/// one entry a sample) when given; returns (rgba (H,W,4) f32, depth (H,W) f32, ids (H,W) i32,
/// velocity (H,W,2) f32, stats dict, exposure (fraction, first, last) (H,W,P) f32 or None).
/// The GIL is released while rendering.
#[pyfunction]
#[pyo3(signature = (draws, options, backdrop=None))]
fn _analytic<'py>(
    py: Python<'py>,
    draws: Vec<MovingDrawArg<'py>>,
    options: AnalyticArgs<'py>,
    backdrop: Option<LayerArg<'py>>,
) -> PyResult<FrameOut<'py>> {
    let o = &options;
    let times = c_slice(&o.times, "times")?;
    let vps = view_projections(&o.view_projections)?;
    let shutter = match &o.shutter {
        ShutterArg::Name(name) => Shutter::parse(name)?,
        ShutterArg::Trapezoid { open, close } => Shutter::trapezoid(*open, *close)?,
        ShutterArg::Weights(w) => Shutter::weights(c_slice(w, "shutter")?)?,
    };
    let lights = lights(&o.lights)?;
    let borrowed: Vec<Borrowed> = draws
        .iter()
        .map(|d| borrowed(d, times.len()))
        .collect::<Result<_, _>>()?;
    let moving: Vec<MovingDraw> = borrowed
        .iter()
        .map(|o| MovingDraw {
            positions: o.positions,
            faces: &o.faces,
            rgba: o.rgba,
            normals: o.normals,
            object_id: o.object_id,
            cull_back: o.cull_back,
            shading: o.shading,
        })
        .collect();
    let backdrop = backdrop.as_ref().map(|b| b.layer("backdrop")).transpose()?;
    let input = AnalyticInput {
        width: o.width,
        height: o.height,
        samples: o.samples,
        times,
        view_projections: &vps,
        draws: &moving,
        backdrop,
        shutter: &shutter,
        lights: &lights,
        ambient: o.ambient.map(|a| a as f32),
        quadrature: o.gauss.quadrature()?,
        reference_time: o.reference_time,
        shade: o.shade,
        tile_budget: o.tile_budget,
        exposure: o.exposure,
        rolling: Rolling {
            readout: o.rolling,
            bottom_to_top: o.rolling_bottom_to_top,
        },
    };
    let (frame, stats) = detached_in_pool(py, || render_analytic(&input))?;
    let (h, w) = (frame.height as usize, frame.width as usize);
    let velocity = frame.velocity.unwrap_or_else(|| vec![0.0; 2 * h * w]);
    let exposure = match frame.exposure {
        None => None,
        Some(e) => {
            let p = e.planes as usize;
            Some((
                shaped(py, e.fraction, [h, w, p])?,
                shaped(py, e.first, [h, w, p])?,
                shaped(py, e.last, [h, w, p])?,
            ))
        }
    };
    Ok((
        shaped(py, frame.rgba, [h, w, 4])?,
        shaped(py, frame.depth, [h, w])?,
        shaped(py, frame.ids, [h, w])?,
        shaped(py, velocity, [h, w, 2])?,
        stats.to_dict(py)?,
        exposure,
    ))
}

impl ToDict for AnalyticStats {
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("prims", self.prims)?;
        d.set_item("bin_entries", self.bin_entries)?;
        d.set_item("intervals", self.intervals)?;
        d.set_item("pieces", self.pieces)?;
        d.set_item("splits", self.splits)?;
        d.set_item("tests", self.tests)?;
        d.set_item("spans", self.spans)?;
        d.set_item("ms_cover", self.ms_cover)?;
        d.set_item("ms_resolve", self.ms_resolve)?;
        d.set_item("segments", self.segments)?;
        d.set_item("strips", self.strips)?;
        d.set_item("ms_prepare", self.ms_prepare)?;
        d.set_item("ms_setup", self.ms_setup)?;
        d.set_item("ms_bin", self.ms_bin)?;
        d.set_item("ms_tiles", self.ms_tiles)?;
        d.set_item("ms_total", self.ms_total)?;
        Ok(d)
    }
}

/// `points` (V,3) or (V,4) f64 (3 columns: w = 1) under the matrix `m` (4,4) f64, written into
/// `out` (V,4) f64 in the straddle's order of sums ([`transform_points`]). The GIL is released.
#[pyfunction]
fn _transform_points(
    py: Python<'_>,
    m: PyReadonlyArray2<'_, f64>,
    points: PyReadonlyArray2<'_, f64>,
    mut out: PyReadwriteArray2<'_, f64>,
) -> PyResult<()> {
    let m = matrix(&m, "m")?;
    let [v, dim] = [points.shape()[0], points.shape()[1]];
    if dim != 3 && dim != 4 {
        let got = points.shape().to_vec();
        return Err(Error::shape(
            "points",
            format!("expected shape (V,3) or (V,4), got {got:?}"),
        )
        .into());
    }
    if out.shape() != [v, 4] {
        let got = out.shape().to_vec();
        return Err(Error::shape("out", format!("expected shape ({v}, 4), got {got:?}")).into());
    }
    let p = c_slice(&points, "points")?;
    let o = c_slice_mut(&mut out, "out")?;
    detached_in_pool(py, || {
        transform_points(&m, p, dim, o);
        Ok(())
    })?;
    Ok(())
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_analytic, m)?)?;
    m.add_function(wrap_pyfunction!(_transform_points, m)?)?;
    Ok(())
}
