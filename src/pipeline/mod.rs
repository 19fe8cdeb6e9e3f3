//! scene file + settings → output sets: the one place that joins the stages
//! (`scene`, `accel`, `render`, `adaptive`, `reconstruct`, `preview`, `output`).
//! Each entry point is a short function that calls the stages in order.

pub mod preview;
