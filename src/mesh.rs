//! mesh: see the crate docs.
