//! scene + BVH → fast approximate images: shadow fields (rigid and deforming
//! occluders, spherical harmonics) and glossy transfer (von Mises–Fisher lobes).
//! Uses `scene`, `accel`, `brdf` and `math`, never `render`: the pipeline compares
//! each preview against the path tracer.

pub mod glossy;
pub mod raster;
pub mod shadow_field;
