//! contour: see the crate docs.
