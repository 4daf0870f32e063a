//! Bindings of the process-wide settings: the memory budget every kernel checks, the number of
//! threads the parallel kernels run on, and (for tests) the switch over the kernels' vector
//! forms.
use pyo3::prelude::*;

use crate::{DEFAULT_MEMORY_BUDGET, MAX_THREADS, MIN_MEMORY_BUDGET};

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

/// The number of threads the parallel kernels of this process run on (the first call reads
/// MOTIONBLUR_NUM_THREADS unless set_num_threads was called).
#[pyfunction]
fn get_num_threads() -> PyResult<usize> {
    Ok(crate::num_threads()?)
}

/// Sets the number of threads the parallel kernels run on (1..=MAX_THREADS); returns the
/// previous count.
#[pyfunction]
fn set_num_threads(n: usize) -> PyResult<usize> {
    Ok(crate::set_num_threads(n)?)
}

/// Allows or forbids the kernels' vector forms (`crate::simd`); returns whether they were
/// allowed. Results are the same bits either way: tests compare the two forms with it.
#[pyfunction]
fn _set_simd(enabled: bool) -> bool {
    crate::set_simd(enabled)
}

/// Whether the kernels run their vector forms (AVX2 detected and not switched off).
#[pyfunction]
fn _simd_enabled() -> bool {
    crate::simd_enabled()
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(memory_budget, m)?)?;
    m.add_function(wrap_pyfunction!(set_memory_budget, m)?)?;
    m.add_function(wrap_pyfunction!(get_num_threads, m)?)?;
    m.add_function(wrap_pyfunction!(set_num_threads, m)?)?;
    m.add_function(wrap_pyfunction!(_set_simd, m)?)?;
    m.add_function(wrap_pyfunction!(_simd_enabled, m)?)?;
    m.add("DEFAULT_MEMORY_BUDGET", DEFAULT_MEMORY_BUDGET)?;
    m.add("MIN_MEMORY_BUDGET", MIN_MEMORY_BUDGET)?;
    m.add("MAX_THREADS", MAX_THREADS)?;
    Ok(())
}
