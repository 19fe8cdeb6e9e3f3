//! scalar in [0, 1] → perceptual colour (viridis), for the report's error maps.
//!
//! Viridis is perceptually uniform and ordered in lightness, so equal error steps
//! look equally different and the maps survive grey-scale printing, which a
//! rainbow map does not.

use crate::math::Vec3;

/// Polynomial fit (degree 6, per channel) to matplotlib's viridis; max deviation
/// from the 256-entry table is below one 8-bit level. Coefficients c0…c6.
const VIRIDIS: [[f32; 3]; 7] = [
    [0.277_727_33, 0.005_407_345, 0.334_099_8],
    [0.105_093_04, 1.404_613_5, 1.384_590_2],
    [-0.330_861_83, 0.214_847_56, 0.095_095_16],
    [-4.634_230_5, -5.799_101, -19.332_441],
    [6.228_27, 14.179_933, 56.690_55],
    [4.776_385, -13.745_145, -65.353_03],
    [-5.435_456, 4.645_852_6, 26.312_435],
];

/// Viridis colour of `t` (clamped to [0, 1]; NaN maps to 0), as *display* sRGB in
/// [0, 1] — not linear radiance.
pub fn viridis(t: f32) -> Vec3 {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let mut c = Vec3::from(VIRIDIS[6]);
    for k in (0..6).rev() {
        c = c * t + Vec3::from(VIRIDIS[k]);
    }
    c.clamp(Vec3::ZERO, Vec3::ONE)
}

/// Viridis as 8-bit sRGB.
pub fn viridis8(t: f32) -> [u8; 3] {
    viridis(t).to_array().map(|v| (v * 255.0).round() as u8)
}

/// `#rrggbb` of viridis at `t`, for SVG gradients and legends.
pub fn viridis_hex(t: f32) -> String {
    let [r, g, b] = viridis8(t);
    format!("#{r:02x}{g:02x}{b:02x}")
}
