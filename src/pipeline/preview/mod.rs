//! Preview layers against the path-traced reference: precompute and shade with
//! `preview`, render the reference with `render`, score and write with `output`.

pub mod figures;
pub mod glossy;
pub mod shadow_field;
