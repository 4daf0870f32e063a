//! The one error type of the core (the binding layer maps it to Python exceptions), and a
//! shared argument check.
use thiserror::Error;

/// Errors raised by the core. Every variant names the offending argument.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// An argument has the wrong shape, length or size. Maps to `ValueError`.
    #[error("{name}: {reason}")]
    Shape {
        /// The argument's name, as the Python API spells it.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// An argument has a value out of its domain (NaN, out of range, unknown name). Maps to `ValueError`.
    #[error("{name}: {reason}")]
    Value {
        /// The argument's name, as the Python API spells it.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// A call would allocate more than the memory budget, or the system refused an
    /// allocation (see `budget.rs`). Maps to `MemoryError`.
    #[error("{name}: {reason}")]
    Memory {
        /// The arguments whose sizes the memory is proportional to (`"faces x directions"`).
        name: String,
        /// The bytes needed and the budget, or what was refused.
        reason: String,
    },
}

impl Error {
    /// A [`Error::Shape`] naming the argument `name`.
    pub fn shape(name: &'static str, reason: impl Into<String>) -> Self {
        Error::Shape {
            name,
            reason: reason.into(),
        }
    }
    /// A [`Error::Value`] naming the argument `name`.
    pub fn value(name: &'static str, reason: impl Into<String>) -> Self {
        Error::Value {
            name,
            reason: reason.into(),
        }
    }
    /// A [`Error::Memory`] naming the argument `name`.
    pub fn memory(name: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::Memory {
            name: name.into(),
            reason: reason.into(),
        }
    }
}

/// A result whose error is the core's [`enum@Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// Fails naming `name` when a component of `v` is NaN or infinite.
pub(crate) fn check_vector(v: [f64; 3], name: &'static str) -> Result<()> {
    if v.iter().any(|x| !x.is_finite()) {
        return Err(Error::value(name, "is NaN or inf"));
    }
    Ok(())
}
