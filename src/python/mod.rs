//! The binding layer: the only PyO3 code. Each file binds one stage of the core's public API;
//! `convert.rs` is their shared toolkit (numpy in and out, error mapping, GIL release), `args.rs`
//! the typed arguments several of them read. Arguments cross as objects read by attribute (a
//! `Draw`, a `Camera`, a layer) or dicts read by item, each through a `#[derive(FromPyObject)]`
//! struct: one options struct per kernel, never a positional tuple. Extraction only converts
//! types; shapes are checked here and values by the core's `validate`, naming the argument.
use pyo3::prelude::*;

mod accumulate;
mod analytic;
mod args;
mod budget;
mod convert;
mod geometry;
mod image;
mod motion;
mod painter;
mod raster;
mod segments;
mod shell;
mod sweep;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    budget::register(m)?;
    motion::register(m)?;
    geometry::register(m)?;
    raster::register(m)?;
    image::register(m)?;
    shell::register(m)?;
    accumulate::register(m)?;
    painter::register(m)?;
    analytic::register(m)?;
    segments::register(m)?;
    sweep::register(m)?;
    Ok(())
}
