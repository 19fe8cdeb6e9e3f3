//! The figures both previews report against the path tracer, computed once here:
//! the preview's bias with the reference's own noise taken out, the path
//! tracer's time to the same error, and the speed-up per frame, at one frame
//! and with the precompute amortised over a stated number of frames.
//!
//! The reference's noise is measured, not taken from its `variance.R/G/B`: that
//! plane is the i.i.d. estimate σ²/spp, and the Owen-scrambled Sobol samples
//! converge faster (shadowfield_bunny, 64 spp: 0.041 from the plane, 0.0090
//! between two seeds), so subtracting it hid the bias. Two renders at different
//! seeds give it exactly (E|A − B|² = 2 noise²), and a third at a lower spp the
//! rate (noise² ∝ spp^−α) at which the path tracer reaches a given error.
//!
//! A number is written only when it holds: the bias is resolved only when the
//! reference's noise is at most [`NOISE_FRACTION`] of the preview's RMSE;
//! otherwise the reference's spp is raised (up to a cap), and if the cap is
//! reached the fields are `null` with `null_reason` saying why.

use crate::math::Vec3;
use crate::output::metrics;
use crate::Result;
use serde::Serialize;

/// The reference's noise RMSE must be at most this fraction of the preview's
/// RMSE: then bias² ≥ ¾ RMSE², so the noise cannot pass for bias.
pub const NOISE_FRACTION: f64 = 0.5;

/// Default cap on the reference's spp while it is raised to resolve the bias.
pub const REFERENCE_SPP_MAX: u32 = 4096;

/// Default number of frames the precompute is amortised over.
pub const AMORTISE_FRAMES: u32 = 100;

/// The measured convergence exponent α (noise² ∝ spp^−α) is kept in
/// [1, 2]: Monte Carlo's rate at worst, and beyond what a measurement from
/// two noisy levels can claim.
const ALPHA_RANGE: (f64, f64) = (1.0, 2.0);

/// A path-traced reference with its measured noise.
#[derive(Clone, Debug)]
pub struct Reference {
    /// The render scored against (seed index 0).
    pub beauty: Vec<Vec3>,
    pub spp: u32,
    /// Wall time of that render.
    pub seconds: f64,
    /// Its noise: the expected squared RMSE against the converged image,
    /// mean over pixels and channels (half the squared RMSE between two seeds).
    pub noise_var: f64,
    /// noise² ∝ spp^−α, measured between two spp (1 where it could not be).
    pub alpha: f64,
}

fn mse(a: &[Vec3], b: &[Vec3], scored: Option<&[bool]>) -> Result<f64> {
    Ok(scored_rmse(a, b, scored)?.powi(2))
}

/// RMSE over the pixels `scored` keeps (every pixel without it).
pub fn scored_rmse(a: &[Vec3], b: &[Vec3], scored: Option<&[bool]>) -> Result<f64> {
    let Some(keep) = scored else {
        return Ok(f64::from(metrics::rmse(a, b)?));
    };
    let pick = |v: &[Vec3]| -> Vec<Vec3> {
        v.iter()
            .zip(keep)
            .filter(|(_, k)| **k)
            .map(|(c, _)| *c)
            .collect()
    };
    if keep.iter().all(|k| !k) {
        return Ok(0.0);
    }
    Ok(f64::from(metrics::rmse(&pick(a), &pick(b))?))
}

/// Whether the preview's RMSE `rmse` against a reference of noise `noise_var`
/// resolves the preview's bias.
pub fn bias_resolved(rmse: f64, noise_var: f64) -> bool {
    noise_var.sqrt() <= NOISE_FRACTION * rmse
}

/// The spp to render the reference at next, or `None` when `spp` resolves the
/// bias or is already the cap. Aims at a noise² of a third of the estimated
/// bias² by the 1/spp law (the slowest rate, so with margin), with 1.5× for
/// the estimates' own error, at least doubling and at most ×16.
pub fn next_reference_spp(rmse: f64, noise_var: f64, spp: u32, max: u32) -> Option<u32> {
    if bias_resolved(rmse, noise_var) || spp >= max {
        return None;
    }
    let bias2 = rmse * rmse - noise_var;
    let spp_f = f64::from(spp);
    let wanted = if bias2 > 0.0 {
        4.5 * noise_var * spp_f / bias2
    } else {
        // No bias seen over the noise yet: quadruple.
        4.0 * spp_f
    };
    let next = wanted
        .clamp(2.0 * spp_f, 16.0 * spp_f)
        .ceil()
        .min(f64::from(max));
    Some(next as u32)
}

/// Renders the reference at `start` spp (`render(spp, seed_index)` gives the
/// image and its wall time; seed indices 0 and 1 at each spp measure the
/// noise), then at more spp (see [`next_reference_spp`]) until it resolves
/// `preview`'s bias or reaches `max`; α comes from the first and last spp, or,
/// when the first one resolved it, from one more render at a quarter of it.
/// Every error is taken over the pixels `scored` keeps (all without it).
pub fn converge_reference(
    preview: &[Vec3],
    scored: Option<&[bool]>,
    start: u32,
    max: u32,
    mut render: impl FnMut(u32, u32) -> Result<(Vec<Vec3>, f64)>,
) -> Result<Reference> {
    let max = max.max(start);
    let mut spp = start.max(1);
    let mut first: Option<(u32, f64)> = None;
    loop {
        let (beauty, seconds) = render(spp, 0)?;
        let (other, _) = render(spp, 1)?;
        let noise_var = mse(&beauty, &other, scored)? / 2.0;
        let rmse = mse(preview, &beauty, scored)?.sqrt();
        let next = next_reference_spp(rmse, noise_var, spp, max);
        if next.is_none() {
            let low = match first {
                Some(level) => Some(level),
                None if spp >= 4 => {
                    // E|C − A|² = noise²(spp/4) + noise²(spp).
                    let (c, _) = render(spp / 4, 2)?;
                    Some((spp / 4, mse(&c, &beauty, scored)? - noise_var))
                }
                None => None,
            };
            let alpha = match low {
                Some((low_spp, low_var)) if low_var > 0.0 && noise_var > 0.0 => {
                    let a = (low_var / noise_var).ln() / (f64::from(spp) / f64::from(low_spp)).ln();
                    if a.is_finite() {
                        a.clamp(ALPHA_RANGE.0, ALPHA_RANGE.1)
                    } else {
                        1.0
                    }
                }
                _ => 1.0,
            };
            return Ok(Reference {
                beauty,
                spp,
                seconds,
                noise_var,
                alpha,
            });
        }
        first.get_or_insert((spp, noise_var));
        spp = next.unwrap_or(spp);
    }
}

/// The precompute amortised over `frames` frames.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Amortised {
    pub frames: u32,
    /// Path tracer's time for `frames` frames at equal error over the preview's
    /// precompute plus `frames` frames.
    pub value: Option<f64>,
}

/// The preview's figures against the path tracer (flattened into preview.json).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Figures {
    /// spp of the reference scored against (raised from the requested one until
    /// the bias is resolved, up to `reference_spp_max`).
    pub reference_spp: u32,
    pub reference_spp_max: u32,
    /// Wall time of that reference.
    pub reference_s: f64,
    /// The reference's own noise RMSE, measured between two seeds.
    pub reference_noise_rmse: f64,
    /// α of the path tracer's noise² ∝ spp^−α, measured between two spp
    /// (1 for plain Monte Carlo; kept in [1, 2]).
    pub path_tracer_noise_exponent: f64,
    /// Whether `reference_noise_rmse` ≤ ½ RMSE, so that the bias is measured.
    pub bias_resolved: bool,
    /// The preview's error against the converged image, √(RMSE² − noise²).
    pub rmse_bias: Option<f64>,
    /// spp and time the path tracer needs for an RMSE of `rmse_bias`:
    /// noise²(reference_spp) × (reference_spp / spp)^α = bias², at least 1 spp.
    pub path_tracer_spp_equal_error: Option<f64>,
    pub path_tracer_s_equal_error: Option<f64>,
    /// Wall time of the preview's scored frame, precompute left out.
    pub frame_s: f64,
    /// path_tracer_s_equal_error / frame_s.
    pub speedup_per_frame: Option<f64>,
    /// path_tracer_s_equal_error / (precompute_s + frame_s).
    pub speedup_one_frame: Option<f64>,
    pub speedup_with_precompute: Amortised,
    /// Why the fields above are null (absent when none is).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub null_reason: Option<String>,
}

/// The preview's timings.
#[derive(Clone, Copy, Debug)]
pub struct Timing {
    /// Precomputation (when cached: the time it took when computed).
    pub precompute_s: f64,
    /// One frame, precompute left out.
    pub frame_s: f64,
    /// Frames to amortise the precompute over.
    pub frames: u32,
}

/// The figures of a preview whose RMSE against `reference` is `rmse`.
pub fn figures(rmse: f64, reference: &Reference, spp_max: u32, timing: Timing) -> Figures {
    let noise_var = reference.noise_var.max(0.0);
    let resolved = bias_resolved(rmse, noise_var);
    let mut f = Figures {
        reference_spp: reference.spp,
        reference_spp_max: spp_max.max(reference.spp),
        reference_s: reference.seconds,
        reference_noise_rmse: noise_var.sqrt(),
        path_tracer_noise_exponent: reference.alpha,
        bias_resolved: resolved,
        rmse_bias: None,
        path_tracer_spp_equal_error: None,
        path_tracer_s_equal_error: None,
        frame_s: timing.frame_s,
        speedup_per_frame: None,
        speedup_one_frame: None,
        speedup_with_precompute: Amortised {
            frames: timing.frames,
            value: None,
        },
        null_reason: None,
    };
    if reference.beauty.iter().all(|c| *c == Vec3::ZERO) {
        // Exact and noiseless: the preview's RMSE is its bias.
        f.rmse_bias = Some(rmse);
        f.null_reason = Some(
            "the path-traced reference is black (no light reaches the camera): \
             there is no error to match"
                .into(),
        );
        return f;
    }
    if !resolved {
        f.null_reason = Some(format!(
            "unresolved: the reference's noise (RMSE {:.3e} at {} spp, the cap) is above \
             {NOISE_FRACTION} of the preview's RMSE {rmse:.3e}, so the preview's bias cannot \
             be told from it; raise --reference-spp-max",
            noise_var.sqrt(),
            reference.spp
        ));
        return f;
    }
    let bias2 = (rmse * rmse - noise_var).max(0.0);
    // A noiseless path tracer is exact at 1 spp.
    let spp_eq = if noise_var > 0.0 {
        (f64::from(reference.spp) * (noise_var / bias2).powf(1.0 / reference.alpha)).max(1.0)
    } else {
        1.0
    };
    let pt_s = spp_eq * reference.seconds / f64::from(reference.spp.max(1));
    let n = f64::from(timing.frames.max(1));
    let values = [
        bias2.sqrt(),
        spp_eq,
        pt_s,
        pt_s / timing.frame_s,
        pt_s / (timing.precompute_s + timing.frame_s),
        n * pt_s / (timing.precompute_s + n * timing.frame_s),
    ];
    if let Some(bad) = values.iter().position(|v| !v.is_finite()) {
        f.null_reason = Some(format!(
            "not finite (term {bad}): frame time {} s, precompute {} s, reference {} s",
            timing.frame_s, timing.precompute_s, reference.seconds
        ));
        return f;
    }
    let [bias, spp_eq, pt_s, per_frame, one_frame, amortised] = values;
    f.rmse_bias = Some(bias);
    f.path_tracer_spp_equal_error = Some(spp_eq);
    f.path_tracer_s_equal_error = Some(pt_s);
    f.speedup_per_frame = Some(per_frame);
    f.speedup_one_frame = Some(one_frame);
    f.speedup_with_precompute.value = Some(amortised);
    f
}

impl Figures {
    /// The summary line's words for the speed-up.
    pub fn summary(&self) -> String {
        match (
            self.speedup_per_frame,
            self.speedup_one_frame,
            self.speedup_with_precompute.value,
        ) {
            (Some(p), Some(o), Some(a)) => format!(
                "at equal error {}× the path tracer's speed per frame, {}× over {} frames \
                 with the precompute, {}× for one frame (bias {:.3e}, reference {} spp)",
                significant(p),
                significant(a),
                self.speedup_with_precompute.frames,
                significant(o),
                self.rmse_bias.unwrap_or_default(),
                self.reference_spp
            ),
            _ => format!(
                "no speed-up at equal error: {}",
                self.null_reason.as_deref().unwrap_or("unknown")
            ),
        }
    }
}

/// Two significant digits at least, whatever the magnitude.
fn significant(x: f64) -> String {
    if x >= 10.0 {
        format!("{x:.0}")
    } else if x >= 1.0 {
        format!("{x:.1}")
    } else if x >= 1e-3 {
        let digits = (1 - x.log10().floor() as i32).max(0) as usize;
        format!("{x:.digits$}")
    } else {
        format!("{x:.1e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic standard normals (Box–Muller over a 64-bit LCG).
    fn normals(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
        let mut uniform = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let (u, v) = (uniform(), uniform());
                (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
            })
            .collect()
    }

    const PIXELS: usize = 20_000;
    const TRUTH: f32 = 0.5;

    /// A path tracer of the constant image TRUTH whose noise² at s spp is
    /// σ²/s^α (independent per seed), taking 0.01 s per spp.
    fn tracer(sigma: f64, alpha: f64) -> impl FnMut(u32, u32) -> Result<(Vec<Vec3>, f64)> {
        move |spp, seed| {
            let sd = sigma / f64::from(spp).powf(alpha / 2.0);
            let z = normals(3 * PIXELS, u64::from(spp) << 8 | u64::from(seed));
            let img = z
                .chunks(3)
                .map(|c| {
                    Vec3::new(
                        TRUTH + (sd * c[0]) as f32,
                        TRUTH + (sd * c[1]) as f32,
                        TRUTH + (sd * c[2]) as f32,
                    )
                })
                .collect();
            Ok((img, 0.01 * f64::from(spp)))
        }
    }

    /// The truth plus a bias of 0.01 in every channel.
    fn biased_preview() -> Vec<Vec3> {
        vec![Vec3::splat(TRUTH + 0.01); PIXELS]
    }

    fn rmse(preview: &[Vec3], r: &Reference) -> f64 {
        mse(preview, &r.beauty, None).unwrap().sqrt()
    }

    const TIMING: Timing = Timing {
        precompute_s: 4.0,
        frame_s: 0.1,
        frames: 100,
    };

    #[test]
    fn a_quiet_reference_resolves_the_known_bias() {
        // σ = 0.1, plain Monte Carlo, 1024 spp: noise 0.003125 ≤ ½ × 0.0105.
        let preview = biased_preview();
        let mut asked = Vec::new();
        let mut pt = tracer(0.1, 1.0);
        let r = converge_reference(&preview, None, 1024, 4096, |spp, seed| {
            asked.push((spp, seed));
            pt(spp, seed)
        })
        .unwrap();
        // Two seeds measure the noise, a quarter of the spp the rate.
        assert_eq!(asked, [(1024, 0), (1024, 1), (256, 2)]);
        let f = figures(rmse(&preview, &r), &r, 4096, TIMING);
        assert!(f.bias_resolved && f.null_reason.is_none(), "{f:?}");
        // The noise from two seeds of 60 000 values each: within 2 %.
        assert!(
            (f.reference_noise_rmse / 0.003125 - 1.0).abs() < 0.02,
            "{f:?}"
        );
        assert!((f.path_tracer_noise_exponent - 1.0).abs() < 0.05, "{f:?}");
        // The bias is 0.01 exactly; the noise's subtraction leaves well under 1 %.
        let bias = f.rmse_bias.unwrap();
        assert!((bias - 0.01).abs() < 1e-4, "bias {bias}");
        // σ²/s = bias² → s = 0.01 / 1e-4 = 100 spp (α's own error: a few %).
        let spp = f.path_tracer_spp_equal_error.unwrap();
        assert!((spp / 100.0 - 1.0).abs() < 0.06, "{spp}");
        let pt_s = f.path_tracer_s_equal_error.unwrap();
        assert!((pt_s - spp * 0.01).abs() < 1e-12);
        assert!((f.speedup_per_frame.unwrap() - pt_s / 0.1).abs() < 1e-9);
        assert!((f.speedup_one_frame.unwrap() - pt_s / 4.1).abs() < 1e-9);
        let a = f.speedup_with_precompute.value.unwrap();
        assert!((a - 100.0 * pt_s / (4.0 + 100.0 * 0.1)).abs() < 1e-9);
        assert_eq!(f.speedup_with_precompute.frames, 100);
        assert!(f.speedup_one_frame < Some(a) && Some(a) < f.speedup_per_frame);
    }

    #[test]
    fn a_faster_converging_tracer_needs_more_spp_than_the_one_over_spp_law() {
        // noise² = σ²/s² (α = 2, as stratified samples on a smooth integrand):
        // 64 spp give noise² 2.44e-6; bias² 1e-4 is reached at
        // 64 × (2.44e-6 / 1e-4)^½ = 10 spp, where the 1/spp law says 1.56.
        let preview = biased_preview();
        let r = converge_reference(&preview, None, 64, 4096, tracer(0.1, 2.0)).unwrap();
        assert_eq!(r.spp, 64);
        let f = figures(rmse(&preview, &r), &r, 4096, TIMING);
        assert!((f.path_tracer_noise_exponent - 2.0).abs() < 0.05, "{f:?}");
        let spp = f.path_tracer_spp_equal_error.unwrap();
        assert!((spp / 10.0 - 1.0).abs() < 0.06, "{spp}");
    }

    #[test]
    fn a_noisy_reference_leaves_the_bias_unresolved() {
        // 64 spp of σ = 0.1: noise 0.0125 > the bias 0.01. Subtracting it gives
        // a bias estimate, but one the noise can fake, so no number is written.
        let preview = biased_preview();
        let r = converge_reference(&preview, None, 64, 64, tracer(0.1, 1.0)).unwrap();
        let f = figures(rmse(&preview, &r), &r, 64, TIMING);
        assert!(!f.bias_resolved);
        assert_eq!(f.rmse_bias, None);
        assert_eq!(f.path_tracer_spp_equal_error, None);
        assert_eq!(f.speedup_per_frame, None);
        assert_eq!(f.speedup_one_frame, None);
        assert_eq!(f.speedup_with_precompute.value, None);
        let reason = f.null_reason.unwrap();
        assert!(reason.starts_with("unresolved") && reason.contains("64 spp"));
        // Below the cap the spp is raised: noise² × 64 / s ≤ bias² / 3 with
        // 1.5× margin: 4.5 × 1.5625e-4 × 64 / 1e-4 = 450 spp.
        let (noise_var, bias2): (f64, f64) = (1.5625e-4, 1e-4);
        let e = (noise_var + bias2).sqrt();
        let next = next_reference_spp(e, noise_var, 64, 4096).unwrap();
        assert!((449..=451).contains(&next), "{next}");
        assert_eq!(next_reference_spp(e, noise_var, 64, 256), Some(256));
        assert_eq!(next_reference_spp(e, noise_var, 64, 64), None);
        // No bias seen over the noise: quadruple.
        assert_eq!(next_reference_spp(0.01, noise_var, 64, 4096), Some(256));
    }

    #[test]
    fn converging_raises_the_spp_until_the_bias_is_resolved() {
        let preview = biased_preview();
        let mut asked = Vec::new();
        let mut pt = tracer(0.1, 1.0);
        let r = converge_reference(&preview, None, 64, 4096, |spp, seed| {
            asked.push((spp, seed));
            pt(spp, seed)
        })
        .unwrap();
        // 64 is too noisy, ≈ 450 resolves; α from those two, no third render.
        assert_eq!(asked.len(), 4, "{asked:?}");
        assert_eq!(&asked[..2], [(64, 0), (64, 1)]);
        assert!(
            (420..=480).contains(&r.spp) && asked[3] == (r.spp, 1),
            "{asked:?}"
        );
        let f = figures(rmse(&preview, &r), &r, 4096, TIMING);
        assert!(f.bias_resolved, "{f:?}");
        assert!((f.rmse_bias.unwrap() - 0.01).abs() < 2e-4);
        assert!((f.path_tracer_noise_exponent - 1.0).abs() < 0.05, "{f:?}");
        // With no bias at all it stops at the cap, unresolved.
        let exact = vec![Vec3::splat(TRUTH); PIXELS];
        let mut asked = Vec::new();
        let mut pt = tracer(0.1, 1.0);
        let r = converge_reference(&exact, None, 64, 1000, |spp, seed| {
            asked.push(spp);
            pt(spp, seed)
        })
        .unwrap();
        assert_eq!((asked[0], r.spp), (64, 1000), "{asked:?}");
        assert!(asked.windows(2).all(|w| w[0] <= w[1]), "{asked:?}");
        assert!(!figures(rmse(&exact, &r), &r, 1000, TIMING).bias_resolved);
    }

    #[test]
    fn a_black_reference_gives_null_and_a_reason_not_a_placeholder() {
        // A scene with no light: both images black, no noise, no error.
        let black = vec![Vec3::ZERO; 16];
        let r = converge_reference(&black, None, 256, 4096, |_, _| {
            Ok((vec![Vec3::ZERO; 16], 1.0))
        })
        .unwrap();
        let f = figures(0.0, &r, 4096, TIMING);
        assert_eq!(f.speedup_per_frame, None);
        assert_eq!(f.path_tracer_spp_equal_error, None);
        assert!(f.null_reason.as_deref().unwrap().contains("black"));
        assert_eq!(f.rmse_bias, Some(0.0));
        assert!(f
            .summary()
            .starts_with("no speed-up at equal error: the path-traced"));
        let json = serde_json::to_value(&f).unwrap();
        assert!(json["speedup_per_frame"].is_null());
        assert!(json["speedup_with_precompute"]["value"].is_null());
        assert!(json["null_reason"].is_string());
    }

    #[test]
    fn a_noiseless_path_tracer_matches_at_one_spp() {
        // No noise (a scene lit only by a constant sky, nothing occluded): the
        // path tracer is exact at 1 spp, whatever the bias.
        let r = Reference {
            beauty: vec![Vec3::splat(1.0); 16],
            spp: 256,
            seconds: 2.56,
            noise_var: 0.0,
            alpha: 1.0,
        };
        let f = figures(0.02, &r, 4096, TIMING);
        assert_eq!(f.path_tracer_spp_equal_error, Some(1.0));
        assert!((f.path_tracer_s_equal_error.unwrap() - 0.01).abs() < 1e-12);
        // No precompute: amortised = per frame.
        let g = figures(
            0.02,
            &r,
            4096,
            Timing {
                precompute_s: 0.0,
                ..TIMING
            },
        );
        let (a, p) = (
            g.speedup_with_precompute.value.unwrap(),
            g.speedup_per_frame.unwrap(),
        );
        assert!((a - p).abs() < 1e-12 * p, "{a} vs {p}");
        assert_eq!(
            f.summary(),
            "at equal error 0.10× the path tracer's speed per frame, 0.071× over 100 \
             frames with the precompute, 0.0024× for one frame (bias 2.000e-2, reference 256 spp)"
        );
    }
}
