//! The binding toolkit: numpy arrays in (checked, named after the Python argument), numpy
//! arrays and dicts out, the core's errors as Python exceptions, and the GIL released around
//! the kernels.
use glam::DMat4;
use std::borrow::Cow;

use numpy::ndarray::{Array2, Dimension, IntoDimension};
use numpy::{
    Element, IntoPyArray, PyArray2, PyArrayMethods, PyReadonlyArray, PyReadonlyArray1,
    PyReadonlyArray2, PyReadwriteArray, PyUntypedArrayMethods,
};
use pyo3::exceptions::{PyMemoryError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

use crate::{Error, MeshStats, RasterStats};

/// Every core error names the argument (`"name: reason"`): a `MemoryError` when the call is
/// over the memory budget or an allocation was refused, a `ValueError` otherwise, so `?` maps
/// it.
impl From<Error> for PyErr {
    fn from(e: Error) -> PyErr {
        match e {
            Error::Memory { .. } => PyMemoryError::new_err(e.to_string()),
            _ => PyValueError::new_err(e.to_string()),
        }
    }
}

/// Runs `f` in this process's thread pool ([`crate::install`], never rayon's global pool, whose
/// threads a forked child does not have): the parallel loops inside it then start from a
/// worker instead of handing every loop over from a foreign thread (a futex wake-up and wait
/// each). Results do not depend on where `f` runs. Every binding that reaches a parallel
/// kernel goes through here. Fails without running `f` when `MOTIONBLUR_NUM_THREADS` is
/// invalid (and `set_num_threads` was not called).
pub(crate) fn in_pool<T: Send>(f: impl FnOnce() -> Result<T, Error> + Send) -> Result<T, Error> {
    crate::num_threads()?;
    crate::install(f)
}

/// [`in_pool`] with the GIL released.
pub(crate) fn detached_in_pool<T: Send>(
    py: Python<'_>,
    f: impl FnOnce() -> Result<T, Error> + Send,
) -> Result<T, Error> {
    py.detach(|| in_pool(f))
}

// ---- numpy in ----

/// The data of `a` in C (row-major) order, or an error naming the argument.
///
/// rust-numpy's `as_slice` also accepts Fortran-ordered arrays and hands their memory over in
/// column order, which silently scrambles (N,3) rows; every binding reads arrays through this.
pub(crate) fn c_slice<'a, T: Element, D: Dimension>(
    a: &'a PyReadonlyArray<'_, T, D>,
    name: &'static str,
) -> Result<&'a [T], Error> {
    if !a.is_c_contiguous() {
        return Err(Error::shape(
            name,
            "must be C-contiguous (numpy.ascontiguousarray)",
        ));
    }
    a.as_slice()
        .map_err(|_| Error::shape(name, "must be C-contiguous"))
}

/// The mutable data of `a` in C order, or an error naming the argument (see [`c_slice`]).
pub(crate) fn c_slice_mut<'a, T: Element, D: Dimension>(
    a: &'a mut PyReadwriteArray<'_, T, D>,
    name: &'static str,
) -> Result<&'a mut [T], Error> {
    if !a.is_c_contiguous() {
        return Err(Error::shape(
            name,
            "must be C-contiguous (numpy.ascontiguousarray)",
        ));
    }
    a.as_slice_mut()
        .map_err(|_| Error::shape(name, "must be C-contiguous"))
}

/// The error of an array `name` that should have `K` columns.
fn columns_error<const K: usize>(name: &'static str, shape: &[usize]) -> Error {
    Error::shape(name, format!("expected shape (N,{K}), got {shape:?}"))
}

/// The rows of a C-contiguous (N,K) array, borrowed.
pub(crate) fn rows<'a, T: Element, const K: usize>(
    a: &'a PyReadonlyArray2<'_, T>,
    name: &'static str,
) -> Result<&'a [[T; K]], Error> {
    let shape = a.shape();
    if shape[1] != K {
        return Err(columns_error::<K>(name, shape));
    }
    let flat = c_slice(a, name)?;
    // SAFETY: `[T; K]` has the size of K values of `T` and the alignment of one; `flat` holds
    // exactly `shape[0] * K` values, so the rows cover it and nothing more.
    Ok(unsafe { std::slice::from_raw_parts(flat.as_ptr().cast::<[T; K]>(), shape[0]) })
}

/// A (4,4) f64 numpy matrix (row-major) as glam's, or an error naming the argument.
pub(crate) fn matrix(a: &PyReadonlyArray2<'_, f64>, name: &'static str) -> Result<DMat4, Error> {
    if a.shape() != [4, 4] {
        return Err(Error::shape(name, "expected shape (4,4)"));
    }
    let m = rows::<f64, 4>(a, name)?;
    // numpy rows -> glam columns.
    Ok(DMat4::from_cols_array_2d(&[m[0], m[1], m[2], m[3]]).transpose())
}

/// The rows of an (N,K) array of any memory layout: borrowed when C-contiguous, else copied
/// in row order.
pub(crate) fn rows_any_layout<'a, T: Element + Copy + Default, const K: usize>(
    a: &'a PyReadonlyArray2<'_, T>,
    name: &'static str,
) -> Result<Cow<'a, [[T; K]]>, Error> {
    if a.is_c_contiguous() {
        return rows(a, name).map(Cow::Borrowed);
    }
    let view = a.as_array();
    if view.ncols() != K {
        return Err(columns_error::<K>(name, view.shape()));
    }
    let mut out = vec![[T::default(); K]; view.nrows()];
    for (o, r) in out.iter_mut().zip(view.rows()) {
        for (x, y) in o.iter_mut().zip(r.iter()) {
            *x = *y;
        }
    }
    Ok(Cow::Owned(out))
}

/// A (3,) float64 vector.
pub(crate) fn vec3(a: &PyReadonlyArray1<'_, f64>, name: &'static str) -> Result<[f64; 3], Error> {
    let v = a.as_array();
    if v.len() != 3 {
        return Err(Error::shape(
            name,
            format!("expected shape (3,), got {:?}", v.shape()),
        ));
    }
    Ok([v[0], v[1], v[2]])
}

/// Face rows of int64 indices as the core's `u32` triples, converted only: an index no `u32`
/// holds (negative, or past 2^32 - 1) becomes `u32::MAX`, past every vertex the core accepts, so
/// the core's one range check (`Draw::validate`, the analytic `validate`) rejects it naming
/// `faces`.
pub(crate) fn face_indices_u32(faces: &[[i64; 3]]) -> Vec<[u32; 3]> {
    faces
        .iter()
        .map(|f| f.map(|i| u32::try_from(i).unwrap_or(u32::MAX)))
        .collect()
}

/// `faces` (flat int64 triples) as `u32` triples, every index in `[0, nv)`; else an error
/// naming `faces` and the first bad face.
pub(crate) fn face_indices(faces: &[i64], nv: usize) -> Result<Vec<[u32; 3]>, Error> {
    in_pool(|| {
        let nv = nv as i64;
        let out: Vec<[u32; 3]> = faces
            .par_chunks_exact(3)
            .with_min_len(8192)
            .map(|t| {
                if t.iter().all(|x| (0..nv).contains(x)) {
                    [t[0] as u32, t[1] as u32, t[2] as u32]
                } else {
                    [u32::MAX; 3]
                }
            })
            .collect();
        if let Some(i) = out.par_iter().position_first(|t| t[0] == u32::MAX) {
            return Err(Error::value(
                "faces",
                format!("face {i} has an index out of range [0, {nv})"),
            ));
        }
        Ok(out)
    })
}

// ---- numpy out ----

/// An owned `(n, N)` array handed to numpy without copying its data.
pub(crate) fn rows_array<T: Element, const N: usize>(
    py: Python<'_>,
    rows: Vec<[T; N]>,
) -> Bound<'_, PyArray2<T>> {
    let n = rows.len();
    let arr = Array2::from_shape_vec((n, N), rows.into_flattened()).expect("length matches");
    PyArray2::from_owned_array(py, arr)
}

/// Flat data of rows of `cols` values as an owned `(len / cols, cols)` array, not copied.
pub(crate) fn flat_rows_array<T: Element>(
    py: Python<'_>,
    flat: Vec<T>,
    cols: usize,
) -> Bound<'_, PyArray2<T>> {
    let arr = Array2::from_shape_vec((flat.len() / cols, cols), flat).expect("whole rows");
    PyArray2::from_owned_array(py, arr)
}

/// Row-major data as a numpy array of shape `dims` (an image: `[h, w]` or `[h, w, c]`).
pub(crate) fn shaped<T: Element, D: IntoDimension>(
    py: Python<'_>,
    data: Vec<T>,
    dims: D,
) -> PyResult<Bound<'_, PyAny>> {
    Ok(data.into_pyarray(py).reshape(dims)?.into_any())
}

/// A stats struct as a Python dict, one key per field.
pub(crate) trait ToDict {
    /// The dict, keys in field order.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>>;
}

impl ToDict for MeshStats {
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("faces", self.faces)?;
        d.set_item("vertices", self.vertices)?;
        d.set_item("edges", self.edges)?;
        d.set_item("degenerate_faces", self.degenerate_faces)?;
        d.set_item("boundary_edges", self.boundary_edges)?;
        d.set_item("nonmanifold_edges", self.nonmanifold_edges)?;
        d.set_item("inconsistent_edges", self.inconsistent_edges)?;
        d.set_item("unreferenced_vertices", self.unreferenced_vertices)?;
        d.set_item("closed", self.is_closed())?;
        Ok(d)
    }
}

impl ToDict for RasterStats {
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("triangles", self.triangles)?;
        d.set_item("fragments", self.fragments)?;
        d.set_item("approximated_samples", self.approximated)?;
        d.set_item("culled", self.culled)?;
        d.set_item("clipped", self.clipped)?;
        d.set_item("ms_transform", self.ms_transform)?;
        d.set_item("ms_setup", self.ms_setup)?;
        d.set_item("ms_bin", self.ms_bin)?;
        d.set_item("ms_raster", self.ms_raster)?;
        d.set_item("ms_coverage", self.ms_coverage)?;
        d.set_item("ms_shade", self.ms_shade)?;
        d.set_item("ms_transparent", self.ms_transparent)?;
        d.set_item("ms_resolve", self.ms_resolve)?;
        d.set_item("ms_total", self.ms_total)?;
        Ok(d)
    }
}
