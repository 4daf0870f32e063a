//! volume: see the crate docs.
