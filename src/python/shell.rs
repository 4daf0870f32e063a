//! Bindings for the blur-shell stage: `_BlurShell` and `_motion_silhouette`.
//!
//! Inputs arrive from the Python layer already converted to C-contiguous float64 / int64; the
//! kernels borrow them (no copy) with the GIL released. Shapes are checked again here and every
//! error names the argument.
use numpy::ndarray::{Array1, Array2, ArrayView1, ArrayView2};
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use super::convert::{c_slice, detached_in_pool, face_indices, in_pool, rows};
use crate::budget::try_vec;
use crate::{
    motion_silhouette, BlurShell, Error, ShellColor, ShellOptions, ShellOut, ON_SILHOUETTE,
};

/// (F,3) C-contiguous int64 faces, F > 0, to `u32` triples, every index in [0, nv).
fn faces(a: &PyReadonlyArray2<'_, i64>, nv: usize) -> PyResult<Vec<[u32; 3]>> {
    let shape = a.shape();
    if shape[1] != 3 || shape[0] == 0 {
        return Err(Error::shape(
            "faces",
            format!("expected shape (F,3), F > 0, got {shape:?}"),
        )
        .into());
    }
    Ok(face_indices(c_slice(a, "faces")?, nv)?)
}

type I8Pair<'py> = (Bound<'py, PyArray1<i8>>, Bound<'py, PyArray1<i8>>);

type ShellArrays<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<i64>>,
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<i32>>,
);

/// Numpy views of one shell build, all over a single buffer: one allocation per build (the
/// kernel writes numpy's int64 / int32 indices directly) instead of a page-faulting
/// allocation per output.
struct OneBuffer {
    words: Vec<u64>,
    nv: usize,
    nt: usize,
}

/// Word offsets in [`OneBuffer`]: 8-byte values (vertices, faces, face) then 4-byte ones
/// (rgba, normals, step).
fn layout(nv: usize, nt: usize) -> [usize; 7] {
    let o_faces = 3 * nv;
    let o_face = o_faces + 3 * nt;
    let o_rgba = o_face + nv;
    let o_nrm = o_rgba + 2 * nv;
    let o_step = o_nrm + (3 * nv).div_ceil(2);
    let end = o_step + nv.div_ceil(2);
    [0, o_faces, o_face, o_rgba, o_nrm, o_step, end]
}

impl OneBuffer {
    /// The buffer, or a `MemoryError` when the system refuses it (the plan checked its size
    /// against the budget).
    fn new(nv: usize, nt: usize) -> Result<Self, Error> {
        Ok(OneBuffer {
            words: try_vec(layout(nv, nt)[6], 0u64, "vertices")?,
            nv,
            nt,
        })
    }

    #[allow(clippy::type_complexity)]
    fn slices(&mut self) -> ShellOut<'_, i64, i64, i32> {
        let (nv, nt) = (self.nv, self.nt);
        let o = layout(nv, nt);
        let base = self.words.as_mut_ptr();
        // SAFETY: the regions [o[k], o[k+1]) are disjoint and inside `words` (layout's end is
        // its length); every type has alignment <= 8 (u64) and no invalid bit patterns, and
        // each region holds at least the bytes of its slice.
        unsafe {
            ShellOut {
                vertices: std::slice::from_raw_parts_mut(base.add(o[0]).cast(), nv),
                faces: std::slice::from_raw_parts_mut(base.add(o[1]).cast(), nt),
                face: std::slice::from_raw_parts_mut(base.add(o[2]).cast(), nv),
                rgba: std::slice::from_raw_parts_mut(base.add(o[3]).cast(), nv),
                normals: std::slice::from_raw_parts_mut(base.add(o[4]).cast(), nv),
                step: std::slice::from_raw_parts_mut(base.add(o[5]).cast(), nv),
            }
        }
    }

    fn into_arrays(self, py: Python<'_>) -> ShellArrays<'_> {
        let (nv, nt) = (self.nv, self.nt);
        if self.words.is_empty() {
            return (
                Array2::zeros((0, 3)).into_pyarray(py),
                Array2::zeros((0, 3)).into_pyarray(py),
                Array2::zeros((0, 4)).into_pyarray(py),
                Array2::zeros((0, 3)).into_pyarray(py),
                Array1::zeros(0).into_pyarray(py),
                Array1::zeros(0).into_pyarray(py),
            );
        }
        let o = layout(nv, nt);
        let owner = PyArray1::from_vec(py, self.words);
        let base = owner.data();
        // SAFETY: `owner` keeps the buffer (never reallocated) alive as the base object of
        // every view; the views cover the disjoint, aligned regions of `layout`.
        unsafe {
            let p = |k: usize| base.add(o[k]);
            (
                PyArray2::borrow_from_array(
                    &ArrayView2::<f64>::from_shape_ptr((nv, 3), p(0).cast()),
                    owner.clone().into_any(),
                ),
                PyArray2::borrow_from_array(
                    &ArrayView2::<i64>::from_shape_ptr((nt, 3), p(1).cast()),
                    owner.clone().into_any(),
                ),
                PyArray2::borrow_from_array(
                    &ArrayView2::<f32>::from_shape_ptr((nv, 4), p(3).cast()),
                    owner.clone().into_any(),
                ),
                PyArray2::borrow_from_array(
                    &ArrayView2::<f32>::from_shape_ptr((nv, 3), p(4).cast()),
                    owner.clone().into_any(),
                ),
                PyArray1::borrow_from_array(
                    &ArrayView1::<i64>::from_shape_ptr(nv, p(2).cast()),
                    owner.clone().into_any(),
                ),
                PyArray1::borrow_from_array(
                    &ArrayView1::<i32>::from_shape_ptr(nv, p(5).cast()),
                    owner.into_any(),
                ),
            )
        }
    }
}

/// The core's [`ShellOptions`], the items of a dict: `subdivisions`, `hysteresis`,
/// `initial_alpha`.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct ShellArgs {
    subdivisions: u32,
    hysteresis: u32,
    initial_alpha: f32,
}

/// The Rust blur shell. See `motionblur.BlurShell`.
#[pyclass(name = "_BlurShell", module = "motionblur._core")]
pub struct PyBlurShell {
    inner: BlurShell,
}

#[pymethods]
impl PyBlurShell {
    #[new]
    #[pyo3(signature = (faces, n_vertices, options, mask=None, color=None))]
    fn new(
        py: Python<'_>,
        faces: PyReadonlyArray2<'_, i64>,
        n_vertices: usize,
        options: ShellArgs,
        mask: Option<PyReadonlyArray1<'_, bool>>,
        color: Option<PyReadonlyArray2<'_, f32>>,
    ) -> PyResult<Self> {
        let f = self::faces(&faces, n_vertices)?;
        let mask = mask.map(|m| m.as_array().to_vec());
        let color = match color {
            None => ShellColor::Uniform([1.0; 4]),
            Some(c) => {
                let view = c.as_array();
                if view.ncols() != 4 {
                    let shape = view.shape().to_vec();
                    return Err(Error::shape(
                        "color",
                        format!("expected (1,4) or (V,4) RGBA, got {shape:?}"),
                    )
                    .into());
                }
                let rows: Vec<[f32; 4]> = view
                    .rows()
                    .into_iter()
                    .map(|r| [r[0], r[1], r[2], r[3]])
                    .collect();
                if rows.len() == 1 {
                    ShellColor::Uniform(rows[0])
                } else {
                    ShellColor::PerVertex(rows)
                }
            }
        };
        let opts = ShellOptions {
            subdivisions: options.subdivisions,
            hysteresis: options.hysteresis,
            initial_alpha: options.initial_alpha,
        };
        let inner = detached_in_pool(py, move || BlurShell::new(f, n_vertices, opts, mask, color))?;
        Ok(PyBlurShell { inner })
    }

    #[pyo3(signature = (vertices, normals=None))]
    fn update(
        &mut self,
        py: Python<'_>,
        vertices: PyReadonlyArray2<'_, f64>,
        normals: Option<PyReadonlyArray2<'_, f64>>,
    ) -> PyResult<()> {
        let v = rows(&vertices, "vertices")?;
        let n = normals.as_ref().map(|n| rows(n, "normals")).transpose()?;
        let inner = &mut self.inner;
        if inner.parallel() {
            detached_in_pool(py, move || inner.update(v, n))?;
        } else {
            // Small mesh: sequential kernels on this thread (no hand-over to the pool, and no
            // rayon call: nothing that could reach rayon's global pool).
            py.detach(move || inner.update(v, n))?;
        }
        Ok(())
    }

    #[pyo3(signature = (vertices=None, normals=None))]
    fn build<'py>(
        &self,
        py: Python<'py>,
        vertices: Option<PyReadonlyArray2<'py, f64>>,
        normals: Option<PyReadonlyArray2<'py, f64>>,
    ) -> PyResult<ShellArrays<'py>> {
        let v = vertices.as_ref().map(|v| rows(v, "vertices")).transpose()?;
        let n = normals.as_ref().map(|n| rows(n, "normals")).transpose()?;
        let inner = &self.inner;
        // A small shell runs in order on this thread, no rayon call in it (see `parallel`).
        let plan = if inner.parallel() {
            in_pool(|| inner.build_plan(v, n))?
        } else {
            inner.build_plan(v, n)?
        };
        let mut buf = OneBuffer::new(plan.n_vertices, plan.n_triangles)?;
        let out = buf.slices();
        let plan = &plan;
        if inner.parallel() {
            detached_in_pool(py, move || {
                inner.build_into(plan, out, v, n);
                Ok(())
            })?;
        } else {
            py.detach(move || inner.build_into(plan, out, v, n));
        }
        Ok(buf.into_arrays(py))
    }

    fn reset(&mut self) {
        self.inner.reset();
    }

    /// The shell's history as bytes, for pickling (`src/shell/history.rs`).
    fn _history<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        PyBytes::new(py, &self.inner.history())
    }

    /// Takes the history of a shell made with the same arguments; ValueError naming `state`
    /// otherwise (nothing changes then).
    fn _restore(&mut self, state: &[u8]) -> PyResult<()> {
        Ok(self.inner.restore(state)?)
    }

    #[getter]
    fn updates(&self) -> u64 {
        self.inner.updates()
    }

    #[getter]
    fn update_index(&self) -> Option<usize> {
        self.inner.update_index()
    }

    #[getter]
    fn n_vertices(&self) -> usize {
        self.inner.n_vertices()
    }

    #[getter]
    fn n_faces(&self) -> usize {
        self.inner.faces().len()
    }

    /// (facing i8 (V,), last edge i8 (F,) -1 none, since i64 (F,), fade i32 (F,), run i32 (F,)).
    #[allow(clippy::type_complexity)]
    fn _state<'py>(
        &self,
        py: Python<'py>,
    ) -> (
        Bound<'py, PyArray1<i8>>,
        Bound<'py, PyArray1<i8>>,
        Bound<'py, PyArray1<i64>>,
        Bound<'py, PyArray1<i32>>,
        Bound<'py, PyArray1<i32>>,
    ) {
        let st = self.inner.state();
        let last = st
            .iter()
            .map(|s| if s.last > 2 { -1 } else { s.last as i8 });
        (
            Array1::from_vec(self.inner.facing().to_vec()).into_pyarray(py),
            Array1::from_iter(last).into_pyarray(py),
            Array1::from_iter(st.iter().map(|s| i64::from(s.since))).into_pyarray(py),
            Array1::from_iter(st.iter().map(|s| i32::from(s.fade))).into_pyarray(py),
            Array1::from_iter(st.iter().map(|s| i32::from(s.run))).into_pyarray(py),
        )
    }

    /// The ring element of face `face` recorded `age` updates ago: (edge 0..2, on silhouette),
    /// or None past the strip's run.
    fn _element(&self, face: usize, age: usize) -> Option<(u8, bool)> {
        self.inner
            .element(face, age)
            .map(|c| (c & 3, c & ON_SILHOUETTE != 0))
    }
}

/// (facing i8 (V,): +1 front, -1 back, 0 neutral; edge i8 (F,): k of edge face[k] -> face[k+1],
/// -1 none). The GIL is released.
#[pyfunction]
#[pyo3(signature = (vertices, previous_vertices, faces, normals=None))]
fn _motion_silhouette<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f64>,
    previous_vertices: PyReadonlyArray2<'py, f64>,
    faces: PyReadonlyArray2<'py, i64>,
    normals: Option<PyReadonlyArray2<'py, f64>>,
) -> PyResult<I8Pair<'py>> {
    let v = rows(&vertices, "vertices")?;
    let p = rows(&previous_vertices, "previous_vertices")?;
    let n = normals.as_ref().map(|n| rows(n, "normals")).transpose()?;
    if p.len() != v.len() {
        return Err(Error::shape(
            "previous_vertices",
            format!("expected {} rows (as vertices), got {}", v.len(), p.len()),
        )
        .into());
    }
    if let Some(n) = n {
        if n.len() != v.len() {
            return Err(Error::shape(
                "normals",
                format!("expected {} rows (as vertices), got {}", v.len(), n.len()),
            )
            .into());
        }
    }
    let f = self::faces(&faces, v.len())?;
    let (fac, edge) = detached_in_pool(py, move || motion_silhouette(v, p, &f, n))?;
    let edge = edge.into_iter().map(|e| if e > 2 { -1 } else { e as i8 });
    Ok((
        Array1::from_vec(fac).into_pyarray(py),
        Array1::from_iter(edge).into_pyarray(py),
    ))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyBlurShell>()?;
    m.add_function(wrap_pyfunction!(_motion_silhouette, m)?)?;
    m.add("MAX_SUBDIVISIONS", crate::MAX_SUBDIVISIONS)?;
    m.add("MAX_HYSTERESIS", crate::MAX_HYSTERESIS)?;
    Ok(())
}
