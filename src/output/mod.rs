//! rendered planes → files: one multi-layer EXR (linear, `layer.channel` names that
//! tev groups) and a tone-mapped sRGB PNG, each written to a temporary file and
//! renamed so that a failed run never leaves a broken or half-overwritten output.

pub mod atomic;
pub mod colormap;
mod exr;
pub mod input;
pub mod metrics;
pub mod plot;
mod png;
pub mod report;

use crate::math::Vec3;

pub use self::exr::{
    read_exr, read_exr_input, read_exr_with_header, stage_exr, stage_exr_with_header, write_exr,
    ExrHeader,
};
pub use self::png::{
    srgb_oetf, stage_png, stage_png_rgb8, to_srgb8, write_png, write_png_exposure,
};
pub use atomic::{write_atomic, Staged};

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

impl OutputImage {
    /// An image with no channels yet.
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            channels: Vec::new(),
        }
    }

    /// The channel called `name`, if present.
    pub fn channel(&self, name: &str) -> Option<&Channel> {
        self.channels.iter().find(|c| c.name == name)
    }

    /// Adds one scalar plane.
    pub fn push_scalar(&mut self, name: &str, data: Vec<f32>) {
        self.channels.push(Channel {
            name: name.into(),
            data,
        });
    }

    /// Adds a three-component plane as `prefix` + each of `names` (e.g. prefix
    /// `normal.` and names `["X", "Y", "Z"]`; prefix `""` for the beauty `R,G,B`).
    pub fn push_vec3(&mut self, prefix: &str, names: [&str; 3], data: &[Vec3]) {
        for (k, n) in names.iter().enumerate() {
            self.push_scalar(&format!("{prefix}{n}"), data.iter().map(|v| v[k]).collect());
        }
    }

    /// Reassembles a three-component plane from `prefix` + `names`; `None` when any
    /// of the three channels is missing.
    pub fn vec3(&self, prefix: &str, names: [&str; 3]) -> Option<Vec<Vec3>> {
        let [a, b, c] = names.map(|n| self.channel(&format!("{prefix}{n}")));
        let (a, b, c) = (a?, b?, c?);
        Some(
            a.data
                .iter()
                .zip(&b.data)
                .zip(&c.data)
                .map(|((x, y), z)| Vec3::new(*x, *y, *z))
                .collect(),
        )
    }
}

/// Channel names of the beauty and AOV planes, in one place so that the writer,
/// the tests and the validation scripts agree.
pub mod names {
    pub const RGB: [&str; 3] = ["R", "G", "B"];
    pub const XYZ: [&str; 3] = ["X", "Y", "Z"];
    pub const NORMAL: &str = "normal.";
    pub const DEPTH: &str = "depth.Z";
    pub const ALBEDO: &str = "albedo.";
    pub const OBJECT_ID: &str = "object.id";
    pub const VARIANCE: &str = "variance.";
    pub const GRAD_U: &str = "grad.u.";
    pub const GRAD_V: &str = "grad.v.";
    pub const SAMPLES_DENSITY: &str = "samples.density";
    pub const SAMPLES_Y: &str = "samples.Y";
    /// Scalar gradient-term planes: SV, DV, CV, CDV, visibility, indirect and the
    /// CDV/SV ratio.
    pub const GRAD_TERMS: [&str; 7] = [
        "grad.sv.Y",
        "grad.dv.Y",
        "grad.cv.Y",
        "grad.cdv.Y",
        "grad.vis.Y",
        "grad.indirect.Y",
        "grad.ratio.Y",
    ];
}
