//! Bindings for the analytic method: numpy in, the frame out, GIL released.
use glam::DMat4;
use numpy::{PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use super::convert::{c_slice, detached_in_pool, face_indices, shaped, ToDict};
use crate::{
    render_analytic, AnalyticInput, AnalyticStats, Error, Layer, Light, MovingDraw, Quadrature,
    Shading, Shutter, ANALYTIC_TILE_BUDGET,
};

/// One moving draw: (positions f64 (K+1,V,3), faces i64 (F,3), rgba f32 (1|V,4), normals f32
/// (K+1,V,3) | None, object_id, cull_back, shading name).
type DrawArgs<'py> = (
    PyReadonlyArray3<'py, f64>,
    PyReadonlyArray2<'py, i64>,
    PyReadonlyArray2<'py, f32>,
    Option<PyReadonlyArray3<'py, f32>>,
    i32,
    bool,
    String,
);

/// The backdrop: (rgba f32 (HS,WS,4), depth f32 (HS,WS), ids i32 (HS,WS)), one entry a sample.
type BackdropArgs<'py> = (
    PyReadonlyArray3<'py, f32>,
    PyReadonlyArray2<'py, f32>,
    PyReadonlyArray2<'py, i32>,
);

struct Owned {
    positions: Vec<[f64; 3]>,
    faces: Vec<[u32; 3]>,
    rgba: Vec<[f32; 4]>,
    normals: Option<Vec<[f32; 3]>>,
    object_id: i32,
    cull_back: bool,
    shading: Shading,
}

fn as_rows<T: Copy + Default, const K: usize>(flat: &[T]) -> Vec<[T; K]> {
    flat.chunks_exact(K)
        .map(|c| {
            let mut r = [T::default(); K];
            r.copy_from_slice(c);
            r
        })
        .collect()
}

fn owned(d: &DrawArgs<'_>, k1: usize) -> Result<Owned, Error> {
    let s = d.0.shape();
    if s[0] != k1 || s[2] != 3 {
        return Err(Error::shape(
            "positions",
            format!("expected ({k1},V,3) (one (V,3) per boundary), got {s:?}"),
        ));
    }
    let nv = s[1];
    let positions = as_rows::<f64, 3>(c_slice(&d.0, "positions")?);
    if d.1.shape()[1] != 3 {
        return Err(Error::shape("faces", "expected (F,3)"));
    }
    let faces = face_indices(c_slice(&d.1, "faces")?, nv)?;
    if d.2.shape()[1] != 4 {
        return Err(Error::shape("rgba", "expected (1,4) or (V,4)"));
    }
    let rgba = as_rows::<f32, 4>(c_slice(&d.2, "rgba")?);
    let normals = match &d.3 {
        None => None,
        Some(n) => {
            if n.shape() != s {
                return Err(Error::shape("normals", "must have the shape of positions"));
            }
            Some(as_rows::<f32, 3>(c_slice(n, "normals")?))
        }
    };
    Ok(Owned {
        positions,
        faces,
        rgba,
        normals,
        object_id: d.4,
        cull_back: d.5,
        shading: Shading::parse(&d.6)?,
    })
}

/// Renders moving draws analytically; returns (rgba (H,W,4) f32, depth (H,W) f32, ids (H,W)
/// i32, velocity (H,W,2) f32, stats dict). `shutter` is a filter name or (M,) f64 weights;
/// `gauss` 0 means auto; `tile_budget` is [`AnalyticInput::tile_budget`] in bytes. The GIL is
/// released while rendering.
#[pyfunction]
#[pyo3(signature = (width, height, samples, times, view_projections, draws, shutter, lights, ambient, gauss, reference_time, shade, backdrop=None, tile_budget=ANALYTIC_TILE_BUDGET))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn _analytic<'py>(
    py: Python<'py>,
    width: u32,
    height: u32,
    samples: u32,
    times: PyReadonlyArray1<'py, f64>,
    view_projections: PyReadonlyArray3<'py, f64>,
    draws: Vec<DrawArgs<'py>>,
    shutter: &Bound<'py, PyAny>,
    lights: Vec<([f64; 3], [f64; 3])>,
    ambient: [f64; 3],
    gauss: u8,
    reference_time: f64,
    shade: bool,
    backdrop: Option<BackdropArgs<'py>>,
    tile_budget: usize,
) -> PyResult<(
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyAny>,
    Bound<'py, PyDict>,
)> {
    let times_v = c_slice(&times, "times")?.to_vec();
    let k1 = times_v.len();
    let vs = view_projections.shape();
    if vs[1] != 4 || vs[2] != 4 {
        return Err(Error::shape("view_projections", "expected (N,4,4)").into());
    }
    let vps: Vec<DMat4> = c_slice(&view_projections, "view_projections")?
        .chunks_exact(16)
        .map(|m| DMat4::from_cols_slice(m).transpose())
        .collect();
    let shutter = if let Ok(name) = shutter.extract::<String>() {
        Shutter::parse(&name)?
    } else {
        let w: PyReadonlyArray1<f64> = shutter.extract()?;
        Shutter::weights(c_slice(&w, "shutter")?)?
    };
    let lights: Vec<Light> = lights
        .iter()
        .map(|(d, i)| Light::new(*d, *i))
        .collect::<Result<_, _>>()?;
    let owned: Vec<Owned> = draws
        .iter()
        .map(|d| owned(d, k1))
        .collect::<Result<_, _>>()?;
    drop(draws);
    let moving: Vec<MovingDraw> = owned
        .iter()
        .map(|o| MovingDraw {
            positions: &o.positions,
            faces: &o.faces,
            rgba: &o.rgba,
            normals: o.normals.as_deref(),
            object_id: o.object_id,
            cull_back: o.cull_back,
            shading: o.shading,
        })
        .collect();
    let backdrop = match &backdrop {
        None => None,
        Some(b) => Some(Layer {
            width: b.1.shape()[1],
            height: b.1.shape()[0],
            rgba: c_slice(&b.0, "backdrop")?,
            depth: c_slice(&b.1, "backdrop")?,
            ids: c_slice(&b.2, "backdrop")?,
        }),
    };
    let input = AnalyticInput {
        width,
        height,
        samples,
        times: &times_v,
        view_projections: &vps,
        draws: &moving,
        backdrop,
        shutter: &shutter,
        lights: &lights,
        ambient: ambient.map(|a| a as f32),
        quadrature: if gauss == 0 {
            Quadrature::Auto
        } else {
            Quadrature::Points(gauss)
        },
        reference_time,
        shade,
        tile_budget,
    };
    let (frame, stats) = detached_in_pool(py, || render_analytic(&input))?;
    let (h, w) = (frame.height as usize, frame.width as usize);
    let velocity = frame.velocity.unwrap_or_else(|| vec![0.0; 2 * h * w]);
    Ok((
        shaped(py, frame.rgba, [h, w, 4])?,
        shaped(py, frame.depth, [h, w])?,
        shaped(py, frame.ids, [h, w])?,
        shaped(py, velocity, [h, w, 2])?,
        stats.to_dict(py)?,
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
        d.set_item("ms_prepare", self.ms_prepare)?;
        d.set_item("ms_setup", self.ms_setup)?;
        d.set_item("ms_bin", self.ms_bin)?;
        d.set_item("ms_tiles", self.ms_tiles)?;
        d.set_item("ms_total", self.ms_total)?;
        Ok(d)
    }
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_analytic, m)?)?;
    Ok(())
}
