//! gradtrace: a CPU path tracer that renders a scene file to a multi-layer EXR.
//!
//! The pipeline, one module per stage (see `ARCHITECTURE.md`):
//! `scene` (TOML + OBJ → plain data) → `accel` (obvhs BVH + analytic spheres) →
//! `render` (path tracer, per-pixel estimates) → `output` (EXR layers, PNG).
//! `brdf` holds the materials, `math` the shared numerics (frames, warps, samplers).

pub mod accel;
pub mod adaptive;
pub mod brdf;
pub mod cpu_time;
pub mod denoise;
pub mod error;
pub mod flatland;
pub mod math;
pub mod memory;
pub mod output;
pub mod pipeline;
pub mod preview;
pub mod reconstruct;
pub mod render;
pub mod scene;

pub use error::{Error, Result};

/// Lower-case hex of a digest's bytes: the one spelling of every cache key,
/// content hash and render id.
pub(crate) fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}
