//! The binding layer: the only PyO3 code. Conversion, shape checks, error mapping, GIL release.
use pyo3::prelude::*;

mod accumulate;
mod geometry;
mod image;
mod raster;
mod shell;

/// Run `f` on a worker thread of rayon's global pool: the parallel loops inside it then start
/// from a worker, not one cross-thread hand-over (a futex wake-up and wait) each; on small
/// meshes those hand-overs were most of the time of a motion-volume build. The loops and
/// their results are unchanged (no dependence on the thread count).
pub(crate) fn in_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    rayon::scope(|_| f())
}

/// The data of `a` in C (row-major) order, or an error naming the argument.
///
/// rust-numpy's `as_slice` also accepts Fortran-ordered arrays and hands their memory over in
/// column order, which silently scrambles (N,3) rows; every binding reads arrays through this.
pub(crate) fn c_slice<'a, T: numpy::Element, D: numpy::ndarray::Dimension>(
    a: &'a numpy::PyReadonlyArray<'_, T, D>,
    name: &'static str,
) -> Result<&'a [T], crate::Error> {
    use numpy::PyUntypedArrayMethods;
    if !a.is_c_contiguous() {
        return Err(crate::Error::shape(
            name,
            "must be C-contiguous (numpy.ascontiguousarray)",
        ));
    }
    a.as_slice()
        .map_err(|_| crate::Error::shape(name, "must be C-contiguous"))
}

/// The mutable data of `a` in C order, or an error naming the argument (see [`c_slice`]).
pub(crate) fn c_slice_mut<'a, T: numpy::Element, D: numpy::ndarray::Dimension>(
    a: &'a mut numpy::PyReadwriteArray<'_, T, D>,
    name: &'static str,
) -> Result<&'a mut [T], crate::Error> {
    use numpy::PyUntypedArrayMethods;
    if !a.is_c_contiguous() {
        return Err(crate::Error::shape(
            name,
            "must be C-contiguous (numpy.ascontiguousarray)",
        ));
    }
    a.as_slice_mut()
        .map_err(|_| crate::Error::shape(name, "must be C-contiguous"))
}

/// The one error mapping point: core errors become `ValueError` naming the argument.
pub(crate) fn to_py_err(e: crate::Error) -> PyErr {
    pyo3::exceptions::PyValueError::new_err(e.to_string())
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    geometry::register(m)?;
    raster::register(m)?;
    image::register(m)?;
    shell::register(m)?;
    accumulate::register(m)?;
    Ok(())
}
