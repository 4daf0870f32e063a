//! Bindings of the memory budget: read and set the one process-wide number every kernel checks.
use pyo3::prelude::*;

use crate::{DEFAULT_MEMORY_BUDGET, MIN_MEMORY_BUDGET};

/// The most bytes one call may allocate.
#[pyfunction]
fn memory_budget() -> u64 {
    crate::memory_budget()
}

/// Sets the memory budget (bytes); returns the previous one.
#[pyfunction]
fn set_memory_budget(bytes: u64) -> PyResult<u64> {
    Ok(crate::set_memory_budget(bytes)?)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(memory_budget, m)?)?;
    m.add_function(wrap_pyfunction!(set_memory_budget, m)?)?;
    m.add("DEFAULT_MEMORY_BUDGET", DEFAULT_MEMORY_BUDGET)?;
    m.add("MIN_MEMORY_BUDGET", MIN_MEMORY_BUDGET)?;
    Ok(())
}
