//! The binding layer: the only PyO3 code. Conversion, shape checks, error mapping, GIL release.
use pyo3::prelude::*;

mod accumulate;
mod geometry;
mod image;
mod raster;
mod shell;

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
