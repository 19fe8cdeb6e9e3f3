//! rendered planes → files: one multi-layer EXR (linear, `layer.channel` names that
//! tev groups) and a tone-mapped sRGB PNG, each written to a temporary file and
//! renamed so that a failed run never leaves a broken or half-overwritten output.
//!
//! OWNED BY THE OUTPUT WORK ITEM — the bodies below are placeholders to be replaced.

use std::path::Path;

/// One named channel plane, e.g. `R`, `normal.X`, `depth.Z`; row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    pub name: String,
    pub data: Vec<f32>,
}

/// A set of channels of one resolution, as it goes into the EXR.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputImage {
    pub width: usize,
    pub height: usize,
    pub channels: Vec<Channel>,
}

pub fn write_exr(_path: &Path, _image: &OutputImage) -> crate::Result<()> {
    Ok(())
}

/// Writes `rgb` (linear, row-major) as a tone-mapped sRGB PNG.
pub fn write_png(
    _path: &Path,
    _rgb: &[glam::Vec3],
    _width: usize,
    _height: usize,
) -> crate::Result<()> {
    Ok(())
}
