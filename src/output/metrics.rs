//! reference + test image → error figures (RMSE, relMSE, FLIP) for the comparison report.
//!
//! All three are computed against the same reference and, for FLIP, on the same
//! display tone mapping (the PNG writer's path, `output::png`: linear × 2^exposure, clamp,
//! sRGB OETF, 8 bits), so every strategy is judged on exactly what the viewer sees.

use super::png::to_srgb8;
use crate::math::Vec3;
use crate::{Error, Result};

/// The ε in relMSE's denominator. Why 1e-2: it keeps near-black reference pixels
/// (where any noise would give an unbounded ratio) from dominating the mean, while
/// leaving pixels brighter than ~0.1 essentially unregularised. A common choice
/// in the adaptive-sampling and denoising literature; report it with the numbers,
/// since relMSE values computed with different ε do not compare.
pub const RELMSE_EPS: f32 = 1e-2;

/// Viewing condition for FLIP: the FLIP tool's default of about 67 pixels per
/// degree (a 0.7 m wide 4K monitor seen from 0.7 m).
pub const FLIP_PPD: f32 = flip_rs::DEFAULT_PPD;

/// Rec. 709 / sRGB relative luminance of linear RGB.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// |x − r|² in f64: in f32 the square of a difference near 1e20 is infinite.
pub fn sq_dist_f64(x: Vec3, r: Vec3) -> f64 {
    (0..3)
        .map(|k| {
            let d = f64::from(x[k]) - f64::from(r[k]);
            d * d
        })
        .sum()
}

/// Root-mean-square error over all pixels and all three channels:
/// `sqrt( Σ (x − r)² / (3N) )`, accumulated in f64.
pub fn rmse(img: &[Vec3], reference: &[Vec3]) -> Result<f32> {
    check_pair(img, reference)?;
    let sum: f64 = img
        .iter()
        .zip(reference)
        .map(|(x, r)| sq_dist_f64(*x, *r))
        .sum();
    Ok((sum / (3 * img.len()) as f64).sqrt() as f32)
}

/// Relative mean-square error over all pixels and channels:
/// `mean( (x − r)² / (r² + ε) )` with ε = [`RELMSE_EPS`] = 1e-2.
pub fn relmse(img: &[Vec3], reference: &[Vec3]) -> Result<f32> {
    check_pair(img, reference)?;
    let eps = f64::from(RELMSE_EPS);
    let sum: f64 = img
        .iter()
        .zip(reference)
        .flat_map(|(x, r)| (0..3).map(move |k| (f64::from(x[k]), f64::from(r[k]))))
        .map(|(x, r)| (x - r) * (x - r) / (r * r + eps))
        .sum();
    Ok((sum / (3 * img.len()) as f64) as f32)
}

/// The share of pixels with the highest error that [`relmse_trimmed`] leaves out
/// by default: 0.01 %, the convention of recent sampling papers, so that a handful
/// of fireflies cannot decide a comparison.
pub const TRIM_FRACTION: f64 = 1e-4;

/// relMSE with the `fraction` of pixels with the highest per-pixel relMSE (mean
/// over the three channels) left out; `fraction = 0` is [`relmse`].
pub fn relmse_trimmed(img: &[Vec3], reference: &[Vec3], fraction: f64) -> Result<f32> {
    check_pair(img, reference)?;
    if !(0.0..1.0).contains(&fraction) {
        return Err(metric_error(format!(
            "trim fraction must lie in [0, 1), got {fraction}"
        )));
    }
    let eps = f64::from(RELMSE_EPS);
    let mut per_pixel: Vec<f64> = img
        .iter()
        .zip(reference)
        .map(|(x, r)| {
            (0..3)
                .map(|k| {
                    let (x, r) = (f64::from(x[k]), f64::from(r[k]));
                    (x - r) * (x - r) / (r * r + eps)
                })
                .sum::<f64>()
                / 3.0
        })
        .collect();
    let drop = (per_pixel.len() as f64 * fraction).floor() as usize;
    let keep = per_pixel.len() - drop;
    if drop > 0 {
        per_pixel.select_nth_unstable_by(keep - 1, f64::total_cmp);
    }
    Ok((per_pixel[..keep].iter().sum::<f64>() / keep as f64) as f32)
}

/// Mean LDR-FLIP (Andersson et al. 2020) of `img` against `reference`, both
/// tone-mapped at exposure 0 (see [`flip_exposure`]).
pub fn flip(img: &[Vec3], reference: &[Vec3], w: usize, h: usize) -> Result<f32> {
    flip_exposure(img, reference, w, h, 0.0)
}

/// Mean LDR-FLIP after the shared display tone mapping at `exposure` stops.
pub fn flip_exposure(
    img: &[Vec3],
    reference: &[Vec3],
    w: usize,
    h: usize,
    exposure: f32,
) -> Result<f32> {
    let map = flip_map(img, reference, w, h, exposure)?;
    let sum: f64 = map.iter().map(|&e| f64::from(e)).sum();
    Ok((sum / map.len() as f64) as f32)
}

/// The per-pixel LDR-FLIP error map (values in [0, 1], row-major).
///
/// FLIP is evaluated by the `flip-rs` crate (a pure-Rust port of NVIDIA's FLIP
/// v1.7) on the *8-bit sRGB values the PNG would contain*, not on linear
/// radiance: FLIP's LDR model expects display-referred sRGB, and quantising
/// exactly as the PNG does means the number describes the picture shown.
pub fn flip_map(
    img: &[Vec3],
    reference: &[Vec3],
    w: usize,
    h: usize,
    exposure: f32,
) -> Result<Vec<f32>> {
    check_pair(img, reference)?;
    if w.checked_mul(h) != Some(img.len()) {
        return Err(metric_error(format!(
            "{} pixels given for a {w}x{h} image",
            img.len()
        )));
    }
    let r = flip_rs::RgbImage::new(w, h, tone_map_srgb8(reference, exposure)?)
        .map_err(|e| metric_error(format!("FLIP: {e}")))?;
    let t = flip_rs::RgbImage::new(w, h, tone_map_srgb8(img, exposure)?)
        .map_err(|e| metric_error(format!("FLIP: {e}")))?;
    let map =
        flip_rs::ldr_flip(&r, &t, FLIP_PPD).map_err(|e| metric_error(format!("FLIP: {e}")))?;
    Ok(map.into_pixels())
}

/// The shared display tone mapping: linear × 2^exposure → clamp → sRGB → 8 bits,
/// interleaved RGB. Identical to the PNG writer's, by construction (it calls the
/// same [`to_srgb8`]).
pub fn tone_map_srgb8(img: &[Vec3], exposure: f32) -> Result<Vec<u8>> {
    if !exposure.is_finite() {
        return Err(metric_error(format!(
            "exposure must be finite, got {exposure}"
        )));
    }
    check_finite(img)?;
    let scale = exposure.exp2();
    Ok(img
        .iter()
        .flat_map(|p| (*p * scale).to_array())
        .map(to_srgb8)
        .collect())
}

fn check_pair(img: &[Vec3], reference: &[Vec3]) -> Result<()> {
    if img.len() != reference.len() {
        return Err(metric_error(format!(
            "image has {} pixels, reference has {}",
            img.len(),
            reference.len()
        )));
    }
    if img.is_empty() {
        return Err(metric_error("empty image".into()));
    }
    check_finite(img)?;
    check_finite(reference)
}

fn check_finite(img: &[Vec3]) -> Result<()> {
    match img.iter().position(|p| !p.is_finite()) {
        Some(i) => Err(metric_error(format!(
            "non-finite pixel {} at index {i}",
            img[i]
        ))),
        None => Ok(()),
    }
}

fn metric_error(message: String) -> Error {
    Error::Option {
        option: "metrics".into(),
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// N pixels, all off by 0.1 from a reference of 0.5 except `k` outliers off
    /// by 2: trimming the k worst leaves exactly the base error, trimming fewer
    /// leaves the closed-form mix.
    #[test]
    fn relmse_trimmed_drops_exactly_the_worst_pixels() {
        let (n, k) = (1000, 3);
        let reference = vec![Vec3::splat(0.5); n];
        let mut img = vec![Vec3::splat(0.6); n];
        for i in 0..k {
            img[100 * i + 7] = Vec3::splat(2.5);
        }
        let eps = f64::from(RELMSE_EPS);
        let base = 0.01 / (0.25 + eps);
        let outlier = 4.0 / (0.25 + eps);
        let close = |got: f32, want: f64| {
            assert!(
                (f64::from(got) - want).abs() <= 1e-6 * want,
                "{got} vs {want}"
            )
        };
        // ⌊0.003 · 1000⌋ = 3 pixels left out: all the outliers.
        close(relmse_trimmed(&img, &reference, 0.003).unwrap(), base);
        // ⌊0.002 · 1000⌋ = 2: one outlier stays among 998 pixels.
        let mix = (997.0 * base + outlier) / 998.0;
        close(relmse_trimmed(&img, &reference, 0.002).unwrap(), mix);
        // Nothing left out: the plain relMSE.
        let all = (997.0 * base + 3.0 * outlier) / 1000.0;
        close(relmse_trimmed(&img, &reference, 0.0).unwrap(), all);
        close(relmse(&img, &reference).unwrap(), all);
        assert!(relmse_trimmed(&img, &reference, 1.0).is_err());
        assert!(relmse_trimmed(&img, &reference, f64::NAN).is_err());
    }
}
