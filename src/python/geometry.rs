//! Bindings for the geometry stage: `_Mesh`, `contour_edges`, `motion_volume`, `_ContourTable`.
//!
//! Thin: copy the (already dtype-converted, C-contiguous) inputs into owned Rust data while
//! attached, then detach for the kernels. Shapes are checked here again and named in errors.
use std::borrow::Cow;
use std::sync::Arc;

use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use super::convert::{
    detached_in_pool, face_indices, flat_rows_array, rows_any_layout, rows_array, vec3, ToDict,
};
use super::motion::PyKeyframes;
use crate::{
    contour_pairs, subdivided, Colors, ContourSet, ContourTable, Error, Filter, Mesh, MotionVolume,
    Need, Path, Spin, VolumeOptions, JOINING, LEADING, MAX_SEGMENTS, TRAILING,
};

/// Bytes a volume takes per mesh edge on the contour and segment: two joining faces and their
/// share of the ring vertices (position, colour, normal), while assembled and as returned.
const EDGE_SEGMENT_BYTES: u64 = 96;

/// Sweep steps of a spin without `segments` at most (one per `pi / 12` of a full turn).
const DEFAULT_SPIN_SEGMENTS: u64 = 24;

/// A volume's worst case, checked against the memory budget before it is built (the contour is
/// known only inside): every mesh edge on the contour, swept into two joining faces per
/// segment, and the leading and trailing faces with their vertices.
fn check_volume(call: &'static str, mesh: &Mesh, segments: u64) -> Result<(), Error> {
    let edges = mesh.adjacency().edges.len() as u64;
    Need::new(call)
        .add(
            &[("mesh edges", edges), ("segments", segments)],
            EDGE_SEGMENT_BYTES,
        )?
        .add(&[("faces", mesh.faces().len() as u64)], 2 * 64)?
        .check()
}

/// (F,3) int64 faces of any layout to `u32` triples, every index in [0, nv).
fn faces(a: &PyReadonlyArray2<'_, i64>, nv: usize) -> PyResult<Vec<[u32; 3]>> {
    let rows = rows_any_layout::<i64, 3>(a, "faces")?;
    Ok(face_indices(rows.as_flattened(), nv)?)
}

/// The Rust mesh: owned vertices and faces and the cached edge adjacency.
#[pyclass(frozen, name = "_Mesh", module = "motionblur._core")]
pub struct PyMesh {
    pub(crate) inner: Arc<Mesh>,
}

#[pymethods]
impl PyMesh {
    #[new]
    fn new(
        py: Python<'_>,
        vertices: PyReadonlyArray2<'_, f64>,
        faces: PyReadonlyArray2<'_, i64>,
    ) -> PyResult<Self> {
        let v = rows_any_layout::<f64, 3>(&vertices, "vertices")?.into_owned();
        let f = self::faces(&faces, v.len())?;
        let mesh = detached_in_pool(py, move || Mesh::new(v, f))?;
        Ok(PyMesh {
            inner: Arc::new(mesh),
        })
    }

    /// Same faces and adjacency, new vertex positions.
    fn with_vertices(&self, py: Python<'_>, vertices: PyReadonlyArray2<'_, f64>) -> PyResult<Self> {
        let v = rows_any_layout::<f64, 3>(&vertices, "vertices")?.into_owned();
        let inner = self.inner.clone();
        let mesh = detached_in_pool(py, move || inner.with_vertices(v))?;
        Ok(PyMesh {
            inner: Arc::new(mesh),
        })
    }

    fn has_adjacency(&self) -> bool {
        self.inner.has_adjacency()
    }

    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let inner = self.inner.clone();
        detached_in_pool(py, move || Ok(inner.stats()))?.to_dict(py)
    }

    /// (F,3) float64 face normals, unit (zero for degenerate faces) or raw `(b-a) x (c-a)`.
    #[pyo3(signature = (unit = true))]
    fn face_normals<'py>(
        &self,
        py: Python<'py>,
        unit: bool,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let inner = self.inner.clone();
        let n = detached_in_pool(py, move || {
            Ok(if unit {
                inner.face_normals()
            } else {
                inner.face_normals_raw()
            })
        })?;
        Ok(rows_array(py, n))
    }

    /// (V,3) float64 area-weighted unit vertex normals.
    fn vertex_normals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let inner = self.inner.clone();
        let n = detached_in_pool(py, move || Ok(inner.vertex_normals()))?;
        Ok(rows_array(py, n))
    }

    /// (E,2) int64 undirected edges `a < b`, sorted; builds the adjacency if needed.
    fn edges<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let inner = self.inner.clone();
        let e = detached_in_pool(py, move || Ok(index_pairs(&inner.adjacency().edges)))?;
        Ok(rows_array(py, e))
    }

    /// (E,) int64 number of faces on each edge of `edges()`.
    fn edge_face_counts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<i64>>> {
        let inner = self.inner.clone();
        let c: Vec<i64> = detached_in_pool(py, move || {
            let adj = inner.adjacency();
            Ok(adj
                .offsets
                .windows(2)
                .map(|w| (w[1] - w[0]) as i64)
                .collect())
        })?;
        Ok(PyArray1::from_vec(py, c))
    }

    /// Build the adjacency now (it is otherwise built on first use).
    fn build_adjacency(&self, py: Python<'_>) -> PyResult<()> {
        let inner = self.inner.clone();
        detached_in_pool(py, move || {
            inner.adjacency();
            Ok(())
        })?;
        Ok(())
    }
}

/// `u32` vertex pairs as int64 rows.
fn index_pairs(pairs: &[[u32; 2]]) -> Vec<[i64; 2]> {
    pairs.iter().map(|p| p.map(i64::from)).collect()
}

#[pyfunction]
#[pyo3(signature = (mesh, motion, camera_position = None))]
fn contour_edges<'py>(
    py: Python<'py>,
    mesh: &PyMesh,
    motion: PyReadonlyArray1<'_, f64>,
    camera_position: Option<PyReadonlyArray1<'_, f64>>,
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let m = vec3(&motion, "motion")?;
    let cam = camera_position
        .as_ref()
        .map(|c| vec3(c, "camera_position"))
        .transpose()?;
    let inner = mesh.inner.clone();
    let flat = detached_in_pool(py, move || contour_pairs(&inner, m, cam))?;
    Ok(flat_rows_array(py, flat, 2))
}

type VolumeTuple<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<i64>>,
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray1<u8>>,
    Bound<'py, PyArray1<f64>>,
    usize,
    f64,
);

/// The options of a volume, the items of a dict: the core's [`VolumeOptions`] (`filter` name,
/// `colors` f32 (1|V|F,4), `face_colors` (one colour a face), `normals` f64 (V,3) | None,
/// `camera_position` (3,) f64 | None, `contour_line`), and, for `motion_volume` only (absent:
/// the defaults), `visible_only`, `contour_table` (built for this mesh) and `window`.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct VolumeArgs<'py> {
    filter: String,
    colors: PyReadonlyArray2<'py, f32>,
    face_colors: bool,
    normals: Option<PyReadonlyArray2<'py, f64>>,
    camera_position: Option<PyReadonlyArray1<'py, f64>>,
    contour_line: bool,
    #[pyo3(default)]
    visible_only: bool,
    #[pyo3(default)]
    contour_table: Option<PyRef<'py, PyContourTable>>,
    #[pyo3(default)]
    window: Option<(f64, f64)>,
}

impl VolumeArgs<'_> {
    /// The core's options: colours (one, per vertex, or per face), normals and the camera
    /// position, each checked and named.
    fn options(&self) -> PyResult<VolumeOptions> {
        let c = rows_any_layout::<f32, 4>(&self.colors, "colors")?.into_owned();
        let colors = if self.face_colors {
            Colors::PerFace(c)
        } else if c.len() == 1 {
            Colors::Uniform(c[0])
        } else {
            Colors::PerVertex(c)
        };
        let normals = self
            .normals
            .as_ref()
            .map(|n| rows_any_layout::<f64, 3>(n, "normals").map(Cow::into_owned))
            .transpose()?;
        Ok(VolumeOptions {
            filter: Filter::parse(&self.filter)?,
            colors,
            normals,
            camera: self
                .camera_position
                .as_ref()
                .map(|c| vec3(c, "camera_position"))
                .transpose()?,
            contour_line: self.contour_line,
            visible_only: self.visible_only,
            contours: self.contour_table.as_ref().map(|t| t.inner.clone()),
            window: self.window.unwrap_or((0.0, 1.0)),
        })
    }
}

/// The motion volume of `mesh` along `keyframes` (rigid, at the equally spaced shutter times
/// `i / K`), each interval cut into `segments` joining segments, with `options`
/// ([`VolumeArgs`]); with a `contour_table` the face split and contour come from its nearest
/// stored direction; `window`: the part of the shutter the keyframes stand for (see
/// `VolumeOptions::window`; None: all of it).
#[pyfunction]
fn motion_volume<'py>(
    py: Python<'py>,
    mesh: &PyMesh,
    keyframes: &PyKeyframes,
    segments: usize,
    options: VolumeArgs<'_>,
) -> PyResult<VolumeTuple<'py>> {
    let opts = options.options()?;
    let keys = keyframes.rigid().to_vec();
    let inner = mesh.inner.clone();
    let vol = detached_in_pool(py, move || {
        let path = subdivided(&Path::from_keys(keys)?, segments)?;
        check_volume("motion_volume", &inner, path.segments() as u64)?;
        crate::motion_volume(&inner, &path, &opts)
    })?;
    Ok(volume_tuple(py, vol))
}

/// A spin, the items of a dict: the core's [`Spin`] (`axis`, `center`, `translation` (3,) f64,
/// `angle` radians, `segments` | None).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct SpinArgs<'py> {
    axis: PyReadonlyArray1<'py, f64>,
    angle: f64,
    center: PyReadonlyArray1<'py, f64>,
    translation: PyReadonlyArray1<'py, f64>,
    segments: Option<usize>,
}

/// The volume of `mesh` spun by `spin` ([`SpinArgs`]) with `options` ([`VolumeArgs`]; every
/// contour edge is swept whatever `contour_line`).
#[pyfunction]
fn spin_volume<'py>(
    py: Python<'py>,
    mesh: &PyMesh,
    spin: SpinArgs<'_>,
    options: VolumeArgs<'_>,
) -> PyResult<VolumeTuple<'py>> {
    let segments = spin.segments;
    let spin = Spin {
        axis: vec3(&spin.axis, "axis")?,
        angle: spin.angle,
        center: vec3(&spin.center, "center")?,
        translation: vec3(&spin.translation, "translation")?,
        segments,
    };
    let opts = options.options()?;
    let inner = mesh.inner.clone();
    let vol = detached_in_pool(py, move || {
        if let Some(s) = segments.filter(|&s| s <= MAX_SEGMENTS) {
            check_volume("spin_volume", &inner, s as u64)?;
        } else if segments.is_none() {
            check_volume("spin_volume", &inner, DEFAULT_SPIN_SEGMENTS)?;
        }
        crate::spin_volume(&inner, &spin, &opts)
    })?;
    Ok(volume_tuple(py, vol))
}

fn volume_tuple(py: Python<'_>, vol: MotionVolume) -> VolumeTuple<'_> {
    let faces: Vec<[i64; 3]> = vol.faces.iter().map(|f| f.map(i64::from)).collect();
    (
        rows_array(py, vol.vertices),
        rows_array(py, faces),
        rows_array(py, vol.rgba),
        rows_array(py, vol.normals),
        PyArray1::from_vec(py, vol.part),
        PyArray1::from_vec(py, vol.ring_alpha),
        vol.contour_edges,
        vol.contour_error,
    )
}

/// Precomputed contour sets (section 4.4).
#[pyclass(frozen, name = "_ContourTable", module = "motionblur._core")]
pub struct PyContourTable {
    inner: Arc<ContourTable>,
}

#[pymethods]
impl PyContourTable {
    #[new]
    #[pyo3(signature = (mesh, count, seed, directions = None))]
    fn new(
        py: Python<'_>,
        mesh: &PyMesh,
        count: usize,
        seed: u64,
        directions: Option<PyReadonlyArray2<'_, f64>>,
    ) -> PyResult<Self> {
        let dirs = directions
            .as_ref()
            .map(|d| rows_any_layout::<f64, 3>(d, "directions").map(Cow::into_owned))
            .transpose()?;
        let m = mesh.inner.clone();
        let inner = detached_in_pool(py, move || match dirs {
            Some(d) => ContourTable::new(&m, d),
            None => ContourTable::random(&m, count, seed),
        })?;
        Ok(PyContourTable {
            inner: Arc::new(inner),
        })
    }

    fn __len__(&self) -> usize {
        self.inner.directions.len()
    }

    /// (K,3) float64 unit directions.
    fn directions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows_array(py, self.inner.directions.clone())
    }

    /// (index, angular error in radians) of the nearest stored direction.
    fn nearest(&self, motion: PyReadonlyArray1<'_, f64>) -> PyResult<(usize, f64)> {
        let m = vec3(&motion, "motion")?;
        Ok(self.inner.nearest(m)?)
    }

    fn edges<'py>(&self, py: Python<'py>, index: usize) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let set = self.set(index)?;
        Ok(rows_array(py, index_pairs(&set.edges())))
    }

    fn front<'py>(&self, py: Python<'py>, index: usize) -> PyResult<Bound<'py, PyArray1<bool>>> {
        let set = self.set(index)?;
        Ok(PyArray1::from_vec(py, set.front.clone()))
    }

    fn storage_bytes(&self) -> usize {
        self.inner.storage_bytes()
    }
}

impl PyContourTable {
    fn set(&self, index: usize) -> Result<&ContourSet, Error> {
        self.inner.sets.get(index).ok_or_else(|| {
            Error::value(
                "index",
                format!("must be < {}, got {index}", self.inner.sets.len()),
            )
        })
    }
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMesh>()?;
    m.add_class::<PyContourTable>()?;
    m.add_function(wrap_pyfunction!(contour_edges, m)?)?;
    m.add_function(wrap_pyfunction!(motion_volume, m)?)?;
    m.add_function(wrap_pyfunction!(spin_volume, m)?)?;
    m.add("MAX_SEGMENTS", MAX_SEGMENTS)?;
    m.add("MAX_COORD", crate::mesh::MAX_COORD)?;
    m.add("FILTERS", PyTuple::new(m.py(), Filter::NAMES)?)?;
    m.add("LEADING", LEADING)?;
    m.add("TRAILING", TRAILING)?;
    m.add("JOINING", JOINING)?;
    Ok(())
}
