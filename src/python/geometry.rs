//! Bindings for the geometry stage: `_Mesh`, `contour_edges`, `motion_volume`, `_ContourTable`.
//!
//! Thin: copy the (already dtype-converted, C-contiguous) inputs into owned Rust data while
//! attached, then detach for the kernels. Shapes are checked here again and named in errors.
use std::sync::Arc;

use numpy::ndarray::Array2;
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

use super::to_py_err;
use crate::contour::contour_pairs as core_contour_pairs;
use crate::contour::ContourTable;
use crate::mesh::Mesh;
use crate::motion::Path;
use crate::volume::{
    motion_volume as core_motion_volume, spin_volume as core_spin_volume, Colors, Filter, Spin,
    VolumeOptions,
};
use crate::Error;

fn rows<const N: usize, T: numpy::Element + Copy + Default>(
    a: &PyReadonlyArray2<'_, T>,
    name: &'static str,
) -> PyResult<Vec<[T; N]>> {
    let view = a.as_array();
    if view.ncols() != N {
        return Err(to_py_err(Error::shape(
            name,
            format!("expected shape (N,{N}), got {:?}", view.shape()),
        )));
    }
    let mut out = vec![[T::default(); N]; view.nrows()];
    match super::c_slice(a, name) {
        Ok(s) => {
            for (o, c) in out.iter_mut().zip(s.chunks_exact(N)) {
                o.copy_from_slice(c);
            }
        }
        Err(_) => {
            for (o, r) in out.iter_mut().zip(view.rows()) {
                for (x, y) in o.iter_mut().zip(r.iter()) {
                    *x = *y;
                }
            }
        }
    }
    Ok(out)
}

/// (F,3) int64 faces to owned `u32` triples, in parallel, checking every index is in [0, nv).
fn face_rows(a: &PyReadonlyArray2<'_, i64>, nv: usize) -> PyResult<Vec<[u32; 3]>> {
    if a.as_array().ncols() != 3 {
        let shape = a.as_array().shape().to_vec();
        return Err(to_py_err(Error::shape(
            "faces",
            format!("expected shape (N,3), got {shape:?}"),
        )));
    }
    let owned;
    let flat: &[i64] = match super::c_slice(a, "faces") {
        Ok(s) => s,
        Err(_) => {
            owned = rows::<3, i64>(a, "faces")?
                .into_iter()
                .flatten()
                .collect::<Vec<_>>();
            &owned
        }
    };
    let nv = nv as i64;
    let out: Vec<[u32; 3]> = flat
        .par_chunks_exact(3)
        .with_min_len(8192)
        .map(|t| {
            if t.iter().all(|&x| (0..nv).contains(&x)) {
                [t[0] as u32, t[1] as u32, t[2] as u32]
            } else {
                [u32::MAX; 3]
            }
        })
        .collect();
    if !out.par_iter().with_min_len(8192).all(|t| t[0] != u32::MAX) {
        let i = out.iter().position(|t| t[0] == u32::MAX).unwrap_or(0);
        return Err(to_py_err(Error::value(
            "faces",
            format!("face {i} has an index out of range [0, {nv})"),
        )));
    }
    Ok(out)
}

fn vec3(a: &PyReadonlyArray1<'_, f64>, name: &'static str) -> PyResult<[f64; 3]> {
    let v = a.as_array();
    if v.len() != 3 {
        return Err(to_py_err(Error::shape(
            name,
            format!("expected shape (3,), got {:?}", v.shape()),
        )));
    }
    Ok([v[0], v[1], v[2]])
}

fn array2<'py, T: numpy::Element + Copy, const N: usize>(
    py: Python<'py>,
    v: &[[T; N]],
) -> Bound<'py, PyArray2<T>> {
    let flat: Vec<T> = v.iter().flatten().copied().collect();
    let arr = Array2::from_shape_vec((v.len(), N), flat).expect("length matches");
    PyArray2::from_owned_array(py, arr)
}

/// An owned `(n, N)` array handed to numpy without copying its data.
fn owned2<'py, T: numpy::Element, const N: usize>(
    py: Python<'py>,
    v: Vec<[T; N]>,
) -> Bound<'py, PyArray2<T>> {
    let n = v.len();
    let arr = Array2::from_shape_vec((n, N), v.into_flattened()).expect("length matches");
    PyArray2::from_owned_array(py, arr)
}

fn index_pairs<'py>(
    py: Python<'py>,
    e: impl Iterator<Item = [u32; 2]>,
) -> Bound<'py, PyArray2<i64>> {
    let v: Vec<[i64; 2]> = e.map(|[a, b]| [a as i64, b as i64]).collect();
    array2(py, &v)
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
        let v = rows::<3, f64>(&vertices, "vertices")?;
        let f = face_rows(&faces, v.len())?;
        let mesh = py.detach(move || Mesh::new(v, f));
        Ok(PyMesh {
            inner: Arc::new(mesh.map_err(to_py_err)?),
        })
    }

    /// Same faces and adjacency, new vertex positions.
    fn with_vertices(&self, py: Python<'_>, vertices: PyReadonlyArray2<'_, f64>) -> PyResult<Self> {
        let v = rows::<3, f64>(&vertices, "vertices")?;
        let inner = self.inner.clone();
        let mesh = py
            .detach(move || inner.with_vertices(v))
            .map_err(to_py_err)?;
        Ok(PyMesh {
            inner: Arc::new(mesh),
        })
    }

    fn has_adjacency(&self) -> bool {
        self.inner.has_adjacency()
    }

    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let inner = self.inner.clone();
        let s = py.detach(move || inner.stats());
        let d = PyDict::new(py);
        d.set_item("faces", s.faces)?;
        d.set_item("vertices", s.vertices)?;
        d.set_item("edges", s.edges)?;
        d.set_item("degenerate_faces", s.degenerate_faces)?;
        d.set_item("boundary_edges", s.boundary_edges)?;
        d.set_item("nonmanifold_edges", s.nonmanifold_edges)?;
        d.set_item("inconsistent_edges", s.inconsistent_edges)?;
        d.set_item("unreferenced_vertices", s.unreferenced_vertices)?;
        d.set_item("closed", s.is_closed())?;
        Ok(d)
    }

    /// (F,3) float64 face normals, unit (zero for degenerate faces) or raw `(b-a) x (c-a)`.
    #[pyo3(signature = (unit = true))]
    fn face_normals<'py>(&self, py: Python<'py>, unit: bool) -> Bound<'py, PyArray2<f64>> {
        let inner = self.inner.clone();
        let n = py.detach(move || {
            if unit {
                inner.face_normals()
            } else {
                inner.face_normals_raw()
            }
        });
        array2(py, &n)
    }

    /// (V,3) float64 area-weighted unit vertex normals.
    fn vertex_normals<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let inner = self.inner.clone();
        let n = py.detach(move || inner.vertex_normals());
        array2(py, &n)
    }

    /// (E,2) int64 undirected edges `a < b`, sorted; builds the adjacency if needed.
    fn edges<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let inner = self.inner.clone();
        let e = py.detach(move || inner.adjacency().edges.clone());
        index_pairs(py, e.into_iter())
    }

    /// (E,) int64 number of faces on each edge of `edges()`.
    fn edge_face_counts<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let inner = self.inner.clone();
        let c: Vec<i64> = py.detach(move || {
            let adj = inner.adjacency();
            adj.offsets
                .windows(2)
                .map(|w| (w[1] - w[0]) as i64)
                .collect()
        });
        PyArray1::from_vec(py, c)
    }

    /// Build the adjacency now (it is otherwise built on first use).
    fn build_adjacency(&self, py: Python<'_>) {
        let inner = self.inner.clone();
        py.detach(move || {
            inner.adjacency();
        });
    }
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
    let flat = py
        .detach(move || super::in_pool(|| core_contour_pairs(&inner, m, cam)))
        .map_err(to_py_err)?;
    let n = flat.len() / 2;
    let arr = Array2::from_shape_vec((n, 2), flat).expect("pairs");
    Ok(PyArray2::from_owned_array(py, arr))
}

type VolumeTuple<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<i64>>,
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray1<u8>>,
    Bound<'py, PyArray1<f64>>,
    usize,
);

#[pyfunction]
#[pyo3(signature = (mesh, keyframes, segments, filter, colors, normals = None, camera_position = None, face_colors = false, contour_line = true, visible_only = false))]
#[allow(clippy::too_many_arguments)]
fn motion_volume<'py>(
    py: Python<'py>,
    mesh: &PyMesh,
    keyframes: PyReadonlyArray3<'_, f64>,
    segments: usize,
    filter: &str,
    colors: PyReadonlyArray2<'_, f32>,
    normals: Option<PyReadonlyArray2<'_, f64>>,
    camera_position: Option<PyReadonlyArray1<'_, f64>>,
    face_colors: bool,
    contour_line: bool,
    visible_only: bool,
) -> PyResult<VolumeTuple<'py>> {
    let filter = Filter::parse(filter).map_err(to_py_err)?;
    let kv = keyframes.as_array();
    if kv.shape()[1] != 4 || kv.shape()[2] != 4 {
        return Err(to_py_err(Error::shape(
            "motion",
            format!("expected shape (K,4,4), got {:?}", kv.shape()),
        )));
    }
    let mats: Vec<[[f64; 4]; 4]> = kv
        .outer_iter()
        .map(|m| {
            let mut out = [[0.0; 4]; 4];
            for (r, row) in out.iter_mut().enumerate() {
                for (c, x) in row.iter_mut().enumerate() {
                    *x = m[[r, c]];
                }
            }
            out
        })
        .collect();
    let mut opts = volume_options(
        filter,
        &colors,
        face_colors,
        normals.as_ref(),
        camera_position.as_ref(),
        contour_line,
    )?;
    opts.visible_only = visible_only;
    if segments == 0 {
        return Err(to_py_err(Error::value("segments", "must be >= 1")));
    }
    let inner = mesh.inner.clone();
    let vol = py
        .detach(move || {
            let path = Path::from_matrices(&mats)?;
            if path.segments().saturating_mul(segments) > crate::volume::MAX_SEGMENTS {
                return Err(Error::value(
                    "segments",
                    format!(
                        "too many segments in total (at most {})",
                        crate::volume::MAX_SEGMENTS
                    ),
                ));
            }
            super::in_pool(|| core_motion_volume(&inner, &path.subdivide(segments), &opts))
        })
        .map_err(to_py_err)?;
    Ok(volume_tuple(py, vol))
}

#[pyfunction]
#[pyo3(signature = (mesh, axis, angle, center, translation, segments, filter, colors, normals = None, camera_position = None, face_colors = false, contour_line = true))]
#[allow(clippy::too_many_arguments)]
fn spin_volume<'py>(
    py: Python<'py>,
    mesh: &PyMesh,
    axis: PyReadonlyArray1<'_, f64>,
    angle: f64,
    center: PyReadonlyArray1<'_, f64>,
    translation: PyReadonlyArray1<'_, f64>,
    segments: Option<usize>,
    filter: &str,
    colors: PyReadonlyArray2<'_, f32>,
    normals: Option<PyReadonlyArray2<'_, f64>>,
    camera_position: Option<PyReadonlyArray1<'_, f64>>,
    face_colors: bool,
    contour_line: bool,
) -> PyResult<VolumeTuple<'py>> {
    let filter = Filter::parse(filter).map_err(to_py_err)?;
    let spin = Spin {
        axis: vec3(&axis, "axis")?,
        angle,
        center: vec3(&center, "center")?,
        translation: vec3(&translation, "translation")?,
        segments,
    };
    let opts = volume_options(
        filter,
        &colors,
        face_colors,
        normals.as_ref(),
        camera_position.as_ref(),
        contour_line,
    )?;
    let inner = mesh.inner.clone();
    let vol = py
        .detach(move || super::in_pool(|| core_spin_volume(&inner, &spin, &opts)))
        .map_err(to_py_err)?;
    Ok(volume_tuple(py, vol))
}

/// The options both volume bindings share: colours (one, per vertex, or per face), normals and
/// the camera position, each checked and named.
fn volume_options(
    filter: Filter,
    colors: &PyReadonlyArray2<'_, f32>,
    face_colors: bool,
    normals: Option<&PyReadonlyArray2<'_, f64>>,
    camera_position: Option<&PyReadonlyArray1<'_, f64>>,
    contour_line: bool,
) -> PyResult<VolumeOptions> {
    let c = rows::<4, f32>(colors, "colors")?;
    let colors = if face_colors {
        Colors::PerFace(c)
    } else if c.len() == 1 {
        Colors::Uniform(c[0])
    } else {
        Colors::PerVertex(c)
    };
    Ok(VolumeOptions {
        filter,
        colors,
        normals: normals.map(|n| rows::<3, f64>(n, "normals")).transpose()?,
        camera: camera_position
            .map(|c| vec3(c, "camera_position"))
            .transpose()?,
        contour_line,
        visible_only: false,
    })
}

fn volume_tuple(py: Python<'_>, vol: crate::volume::MotionVolume) -> VolumeTuple<'_> {
    let faces: Vec<[i64; 3]> = vol.faces.iter().map(|f| f.map(i64::from)).collect();
    (
        owned2(py, vol.vertices),
        owned2(py, faces),
        owned2(py, vol.rgba),
        owned2(py, vol.normals),
        PyArray1::from_vec(py, vol.part),
        PyArray1::from_vec(py, vol.ring_alpha),
        vol.contour_edges,
    )
}

/// Precomputed contour sets (section 4.4).
#[pyclass(frozen, name = "_ContourTable", module = "motionblur._core")]
pub struct PyContourTable {
    inner: ContourTable,
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
            .map(|d| rows::<3, f64>(d, "directions"))
            .transpose()?;
        let m = mesh.inner.clone();
        let inner = py
            .detach(move || match dirs {
                Some(d) => ContourTable::new(&m, d),
                None => ContourTable::random(&m, count, seed),
            })
            .map_err(to_py_err)?;
        Ok(PyContourTable { inner })
    }

    fn __len__(&self) -> usize {
        self.inner.directions.len()
    }

    /// (K,3) float64 unit directions.
    fn directions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        array2(py, &self.inner.directions)
    }

    /// (index, angular error in radians) of the nearest stored direction.
    fn nearest(&self, motion: PyReadonlyArray1<'_, f64>) -> PyResult<(usize, f64)> {
        let m = vec3(&motion, "motion")?;
        self.inner.nearest(m).map_err(to_py_err)
    }

    fn edges<'py>(&self, py: Python<'py>, index: usize) -> PyResult<Bound<'py, PyArray2<i64>>> {
        let set = self.set(index)?;
        Ok(index_pairs(py, set.edges.iter().copied()))
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
    fn set(&self, index: usize) -> PyResult<&crate::contour::ContourSet> {
        self.inner.sets.get(index).ok_or_else(|| {
            to_py_err(Error::value(
                "index",
                format!("must be < {}, got {index}", self.inner.sets.len()),
            ))
        })
    }
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMesh>()?;
    m.add_class::<PyContourTable>()?;
    m.add_function(wrap_pyfunction!(contour_edges, m)?)?;
    m.add_function(wrap_pyfunction!(motion_volume, m)?)?;
    m.add_function(wrap_pyfunction!(spin_volume, m)?)?;
    m.add("LEADING", crate::volume::LEADING)?;
    m.add("TRAILING", crate::volume::TRAILING)?;
    m.add("JOINING", crate::volume::JOINING)?;
    Ok(())
}
