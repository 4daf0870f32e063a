//! motion: see the crate docs.
