//! noisy beauty (+ albedo and normal AOVs) → denoised beauty, with Intel Open
//! Image Denoise: the "denoised uniform" baseline that adaptive sampling is
//! judged against.
//!
//! Optional: only a build with the cargo feature `oidn` links the native
//! library (installed from the PyPI wheel `pyoidn` by `scripts/setup_oidn.sh`,
//! see README.md); without it [`denoise`] returns an [`Error::Option`] saying
//! how to enable it, and the default build and `cargo test` need nothing new.
//!
//! OIDN's `RT` filter runs on the CPU device in HDR mode on linear radiance,
//! with its default ("high") quality. The AOVs are first-hit averages over the
//! pixel's camera samples, so they carry anti-aliasing noise at edges: they are
//! *not* flagged `cleanAux` (OIDN's advice for aux images that are not
//! prefiltered or noise-free).

use crate::math::Vec3;
use crate::{Error, Result};

/// The option name every denoiser error is reported under.
const OPTION: &str = "--denoise";

/// Denoises `beauty` (linear radiance, row-major, `width × height`), guided by
/// the albedo (clamped to [0, 1], as OIDN expects) and the shading normal when
/// given. OIDN uses a normal only together with an albedo, so a normal without
/// an albedo is an error rather than silently dropped.
pub fn denoise(
    beauty: &[Vec3],
    albedo: Option<&[Vec3]>,
    normal: Option<&[Vec3]>,
    width: usize,
    height: usize,
) -> Result<Vec<Vec3>> {
    check_planes(beauty, albedo, normal, width, height)?;
    backend::denoise(beauty, albedo, normal, width, height)
}

/// Whether this build can denoise (built with the `oidn` feature, and the
/// library creates a CPU device). Checked once; cheap afterwards.
pub fn available() -> bool {
    backend::unavailable().is_none()
}

/// Why [`available`] is false, in one line that says how to fix it; empty when
/// it is true.
pub fn unavailable_reason() -> &'static str {
    backend::unavailable().unwrap_or("")
}

fn option_error(message: String) -> Error {
    Error::Option {
        option: OPTION.into(),
        message,
    }
}

/// Same resolution everywhere, a non-empty image, finite inputs: OIDN would
/// read out of bounds on a short plane and spread one NaN over its receptive
/// field.
fn check_planes(
    beauty: &[Vec3],
    albedo: Option<&[Vec3]>,
    normal: Option<&[Vec3]>,
    width: usize,
    height: usize,
) -> Result<()> {
    let n = width
        .checked_mul(height)
        .filter(|&n| n > 0)
        .ok_or_else(|| option_error(format!("cannot denoise a {width}x{height} image")))?;
    if normal.is_some() && albedo.is_none() {
        return Err(option_error(
            "a normal AOV needs an albedo AOV too (OIDN's RT filter)".into(),
        ));
    }
    let planes = [
        ("beauty", Some(beauty)),
        ("albedo", albedo),
        ("normal", normal),
    ];
    for (name, plane) in planes {
        let Some(plane) = plane else { continue };
        if plane.len() != n {
            return Err(option_error(format!(
                "the {name} plane has {} pixels, expected {width}x{height} = {n}",
                plane.len()
            )));
        }
        if let Some(i) = plane.iter().position(|p| !p.is_finite()) {
            return Err(option_error(format!(
                "the {name} plane holds a non-finite pixel {} at ({}, {})",
                plane[i],
                i % width,
                i / width
            )));
        }
    }
    Ok(())
}

#[cfg(not(feature = "oidn"))]
mod backend {
    use crate::math::Vec3;
    use crate::Result;

    pub const DISABLED: &str = "this gradtrace was built without Intel Open Image Denoise; \
        run scripts/setup_oidn.sh and rebuild with `cargo build --release --features oidn` \
        (README.md, \"Optional: denoiser\")";

    pub fn unavailable() -> Option<&'static str> {
        Some(DISABLED)
    }

    pub fn denoise(
        _beauty: &[Vec3],
        _albedo: Option<&[Vec3]>,
        _normal: Option<&[Vec3]>,
        _width: usize,
        _height: usize,
    ) -> Result<Vec<Vec3>> {
        Err(super::option_error(DISABLED.into()))
    }
}

#[cfg(feature = "oidn")]
mod backend {
    use super::option_error;
    use crate::math::Vec3;
    use crate::Result;
    use std::sync::OnceLock;

    /// Creating a device loads OIDN's CPU module from beside the library; a
    /// failure there (module missing, CPU unsupported) is the one thing that
    /// can make a linked build unable to denoise.
    pub fn unavailable() -> Option<&'static str> {
        static PROBE: OnceLock<Option<String>> = OnceLock::new();
        PROBE
            .get_or_init(|| {
                oidn::Device::cpu()
                    .err()
                    .map(|e| format!("Intel Open Image Denoise cannot create a CPU device: {e}"))
            })
            .as_deref()
    }

    fn flat(plane: &[Vec3]) -> Vec<f32> {
        plane.iter().flat_map(|p| p.to_array()).collect()
    }

    pub fn denoise(
        beauty: &[Vec3],
        albedo: Option<&[Vec3]>,
        normal: Option<&[Vec3]>,
        width: usize,
        height: usize,
    ) -> Result<Vec<Vec3>> {
        let fail = |what: &str, e: oidn::Error| option_error(format!("OIDN {what}: {e}"));
        let device = oidn::Device::cpu().map_err(|e| fail("device", e))?;
        let mut filter = oidn::RayTracing::try_new(&device).map_err(|e| fail("filter", e))?;
        filter.hdr(true).image_dimensions(width, height);
        // OIDN expects albedo in [0, 1]; a glossy lobe's may exceed it.
        let albedo = albedo.map(|a| {
            let clamped: Vec<Vec3> = a.iter().map(|c| c.clamp(Vec3::ZERO, Vec3::ONE)).collect();
            flat(&clamped)
        });
        let buffer = |data: &[f32]| device.create_buffer(data).map_err(|e| fail("buffer", e));
        match (albedo, normal) {
            (Some(a), Some(n)) => {
                let (a, n) = (buffer(&a)?, buffer(&flat(n))?);
                filter
                    .albedo_normal_buffer(a, n)
                    .map_err(|e| fail("albedo/normal", e))?;
            }
            (Some(a), None) => {
                filter
                    .albedo_buffer(buffer(&a)?)
                    .map_err(|e| fail("albedo", e))?;
            }
            // `check_planes` rejected a normal without an albedo.
            (None, _) => {}
        }
        let mut out = vec![0.0f32; 3 * width * height];
        filter
            .filter(&flat(beauty), &mut out)
            .map_err(|e| fail("filter", e))?;
        let pixels: Vec<Vec3> = out.chunks_exact(3).map(Vec3::from_slice).collect();
        if let Some(i) = pixels.iter().position(|p| !p.is_finite()) {
            return Err(option_error(format!(
                "OIDN returned a non-finite pixel {} at ({}, {})",
                pixels[i],
                i % width,
                i / width
            )));
        }
        Ok(pixels)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_mismatched_and_non_finite_planes() {
        let one = vec![Vec3::ONE; 4];
        let err = |r: Result<Vec<Vec3>>| r.unwrap_err().to_string();
        assert!(err(denoise(&one, None, None, 3, 2)).contains("expected 3x2 = 6"));
        assert!(err(denoise(&one, None, None, 0, 4)).contains("0x4"));
        assert!(err(denoise(&one, None, Some(&one), 2, 2)).contains("needs an albedo"));
        let short = vec![Vec3::ONE; 3];
        assert!(err(denoise(&one, Some(&short), None, 2, 2)).contains("albedo plane"));
        let mut nan = one.clone();
        nan[3].y = f32::NAN;
        assert!(err(denoise(&nan, None, None, 2, 2)).contains("at (1, 1)"));
    }

    #[cfg(not(feature = "oidn"))]
    #[test]
    fn without_the_feature_says_how_to_enable_it() {
        assert!(!available());
        assert!(unavailable_reason().contains("--features oidn"));
        let one = vec![Vec3::ONE; 4];
        let msg = denoise(&one, Some(&one), Some(&one), 2, 2)
            .unwrap_err()
            .to_string();
        assert!(msg.starts_with("invalid option --denoise:"), "{msg}");
        assert!(msg.contains("scripts/setup_oidn.sh"), "{msg}");
        assert!(
            msg.contains("cargo build --release --features oidn"),
            "{msg}"
        );
    }
}
