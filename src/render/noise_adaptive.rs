//! scene + BVH → a render whose pixels stop sampling where their noise is below a
//! threshold: the per-pixel adaptive sampler of Blender Cycles
//! (`kernel/film/adaptive_sampling.h`, after Dammertz et al. 2009, "A
//! hierarchical automatic stopping condition for Monte Carlo global
//! illumination", Sec. 2.1, applied per pixel), the baseline that `compare` runs
//! against the gradient-driven strategies.
//!
//! Each pixel keeps a second estimate A from half of its samples (class A, a
//! stratified half: [`super::is_class_a`]); every `check_every` samples a pixel whose
//! error |I − A|₁ / √(ΣI) (see [`pixel_error`]) is below the threshold stops, and
//! the neighbours of every pixel that goes on are made to go on too (a 3×3
//! dilation, Cycles' two box-filter passes). Samples are addressed by index, so the
//! image is the same for any thread count.

use super::{extent, Film, RenderOptions, RenderOutput, Setup};
use super::{Crop, Progress};
use crate::accel::Accel;
use crate::scene::Scene;
use crate::{Error, Result};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Cycles scales the user's threshold by 5 (`scene/integrator.cpp`: "makes the
/// threshold more similar to what it was before"); kept, so that a value means
/// what it means in Blender's "Noise Threshold".
pub const THRESHOLD_SCALE: f64 = 5.0;

/// Where a limited run's noise floor starts (scaled units): Cycles' progressive
/// noise floor (`render_scheduler.cpp`, `adaptive_sampling_threshold = 0.4`,
/// halved each time every pixel is below it).
const FIRST_FLOOR: f64 = 0.4;

/// The sampler's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseAdaptive {
    /// Blender's "Noise Threshold" (e.g. 0.01); 0 never stops before `max_spp`.
    pub threshold: f32,
    /// Samples every pixel gets before its first check.
    pub min_spp: u32,
    /// Samples no pixel exceeds.
    pub max_spp: u32,
    /// Samples between two checks (Cycles: 16; fewer at small budgets).
    pub check_every: u32,
    /// Stop at this wall time: the round under way is abandoned (only the first,
    /// one sample per pixel, always completes). The image then depends on the
    /// machine's speed, no longer on the seed alone.
    pub time_limit: Option<Duration>,
    /// The same limit on this process's CPU time (`crate::cpu_time`), for
    /// `compare --equal cpu`: a loaded machine does not shorten the run's work.
    pub cpu_time_limit: Option<Duration>,
    /// Stop before a round would take the whole image past this many samples: the
    /// time limit's deterministic stand-in (equal-sample comparisons, tests).
    pub sample_limit: Option<u64>,
}

impl NoiseAdaptive {
    /// The settings for a run that may take up to `max_spp` per pixel and is
    /// expected to afford `max_spp` on average (no time limit).
    pub fn new(threshold: f32, max_spp: u32) -> Self {
        Self::with_budget(threshold, max_spp, max_spp)
    }

    /// The settings for a run that affords about `budget_spp` per pixel on
    /// average (under a time limit, the spp a uniform render fits in it) and
    /// lets a pixel take up to `max_spp`. Cycles' automatic minimum, max(4,
    /// ⌈16 / threshold^0.3⌉) ("0.1 → 32, 0.01 → 64"), and its check every 16
    /// samples assume budgets of hundreds of spp; at 16 they would spend the
    /// whole budget before the first check (Cycles then renders uniformly), so
    /// both are capped by the budget: the minimum at a quarter of it (at least 4,
    /// the first block of four samples that holds both halves), the step at an
    /// eighth (a power of two, at least 2).
    pub fn with_budget(threshold: f32, max_spp: u32, budget_spp: u32) -> Self {
        let budget = budget_spp.clamp(1, max_spp.max(1));
        let cycles = if threshold > 0.0 {
            (16.0 / threshold.powf(0.3)).ceil().min(u32::MAX as f32) as u32
        } else {
            max_spp
        };
        let min_spp = cycles.min((budget / 4).max(4)).max(4).min(max_spp.max(1));
        let step = (budget / 8).max(1);
        let check_every = (1u32 << (31 - step.leading_zeros())).clamp(2, 16);
        Self {
            threshold,
            min_spp,
            max_spp,
            check_every,
            time_limit: None,
            cpu_time_limit: None,
            sample_limit: None,
        }
    }

    fn check(&self) -> Result<()> {
        let err = |option: &str, message: String| {
            Err(Error::Option {
                option: option.into(),
                message,
            })
        };
        if !(self.threshold.is_finite() && self.threshold >= 0.0) {
            return err(
                "--noise-threshold",
                format!("{}: expected a number ≥ 0", self.threshold),
            );
        }
        if self.min_spp == 0 || self.min_spp > self.max_spp {
            return err(
                "--min-spp",
                format!(
                    "{}: expected 1 ≤ min spp ≤ --spp ({})",
                    self.min_spp, self.max_spp
                ),
            );
        }
        if self.check_every == 0 {
            return err("--check-every", "must be at least 1".into());
        }
        Ok(())
    }
}

/// Cycles' per-pixel error from the pixel mean `i` and the half-sample estimate
/// `a` (RGB): |I − A|₁ / (10⁻⁴ + √ΣI), where ΣI < 1, and |I − A|₁ / (10⁻⁴ + ΣI)
/// above (bright pixels, which a display clips, need less relative precision).
pub fn pixel_error(i: [f64; 3], a: [f64; 3]) -> f64 {
    let diff: f64 = (0..3).map(|c| (i[c] - a[c]).abs()).sum();
    let intensity: f64 = i.iter().sum();
    let normalize = if intensity < 1.0 {
        intensity.max(0.0).sqrt()
    } else {
        intensity
    };
    diff / (1e-4 + normalize)
}

/// Renders the whole image with per-pixel adaptive sample counts (`opts.spp` is
/// ignored: `settings.max_spp` caps every pixel). The output's `spp` is the
/// most any pixel took and `spp_map` each pixel's count (`samples.spp`).
/// `progress` gets (samples traced, pixels × max_spp).
///
/// Every pixel first takes `min_spp` (in passes of 1, 2, 4, … under a limit, so
/// that the limit holds from the first sample on), then every `check_every`
/// samples the pixels whose error is below the floor stop. Without a limit the
/// floor is the threshold; with one it starts at 0.4 and halves, down to the
/// threshold, each time every pixel is below it (Cycles' progressive noise
/// floor), so that a budget too small to reach the threshold still goes to the
/// noisiest pixels first.
pub fn render_noise_adaptive(
    scene: &Scene,
    accel: &Accel,
    opts: &RenderOptions,
    settings: &NoiseAdaptive,
    progress: Progress,
) -> Result<RenderOutput> {
    let start = Instant::now();
    settings.check()?;
    let opts = RenderOptions {
        spp: Some(settings.max_spp),
        crop: None,
        sample_range: None,
        ..opts.clone()
    };
    let setup = Setup::new(scene, &opts)?;
    extent(&setup, &opts)?;
    let (w, h) = (setup.camera.width as usize, setup.camera.height as usize);
    let ctx = setup.context(scene, accel, &opts, 0);
    let mut film = Film::new(Crop::full(w as u32, h as u32), w, ctx.gradients);
    let max = settings.max_spp;
    let mut counts = vec![0u32; w * h];
    let mut active = vec![true; w * h];
    let step = settings.check_every;
    // The first check: the minimum rounded up to the step.
    let first = settings
        .min_spp
        .div_ceil(step)
        .saturating_mul(step)
        .min(max);
    let limited = settings.time_limit.is_some()
        || settings.cpu_time_limit.is_some()
        || settings.sample_limit.is_some();
    let mut next: Vec<u32> = vec![if limited { 1 } else { first }; w * h];
    let threshold = settings.threshold as f64 * THRESHOLD_SCALE;
    let mut floor = if limited && threshold > 0.0 {
        threshold.max(FIRST_FLOOR)
    } else {
        threshold
    };
    let traced = AtomicUsize::new(0);
    let budget = w * h * max as usize;
    let cpu_start = crate::cpu_time::process_s();
    let out_of_time = || {
        settings.time_limit.is_some_and(|t| start.elapsed() > t)
            || settings.cpu_time_limit.is_some_and(|t| {
                cpu_start
                    .zip(crate::cpu_time::process_s())
                    .is_some_and(|(a, b)| b - a > t.as_secs_f64())
            })
    };
    loop {
        let plan = |p: usize| {
            if active[p] {
                counts[p]..next[p]
            } else {
                0..0
            }
        };
        let report = |_: usize| {};
        let planned: usize = (0..w * h).map(|p| plan(p).len()).sum();
        let done = traced.load(Ordering::Relaxed);
        // The first pass (one sample per pixel, or `first` without a limit) always
        // completes; every later one is skipped or abandoned past a limit, so
        // that an equal-time (or equal-sample) comparison is one.
        let first_pass = done == 0;
        let over_samples = settings
            .sample_limit
            .is_some_and(|n| (done + planned) as u64 > n);
        if !first_pass && over_samples {
            break;
        }
        let over = || !first_pass && out_of_time();
        if !film.add_samples(&ctx, &plan, &over, &report) {
            break;
        }
        progress(
            traced.fetch_add(planned, Ordering::Relaxed) + planned,
            budget,
        );
        for p in 0..w * h {
            if active[p] {
                counts[p] = next[p];
            }
        }
        if out_of_time() {
            break;
        }
        // Before the first check every pixel has the same count: double it.
        if counts[0] < first {
            next.fill((counts[0] * 2).min(first));
            continue;
        }
        let mut unconverged = vec![false; w * h];
        film.for_each(|p, acc, _| {
            if active[p] && counts[p] < max {
                let (i, a) = acc.mean_and_half();
                unconverged[p] = pixel_error(i, a) >= floor;
            }
        });
        active = dilate(&unconverged, w, h);
        for p in 0..w * h {
            active[p] &= counts[p] < max;
        }
        if !active.contains(&true) {
            if floor <= threshold {
                break;
            }
            // Every pixel is below the floor: lower it and wake every pixel that
            // has samples left.
            floor = (floor / 2.0).max(threshold);
            for p in 0..w * h {
                active[p] = counts[p] < max;
            }
            if !active.contains(&true) {
                break;
            }
        }
        for p in 0..w * h {
            next[p] = (counts[p] + step).min(max);
        }
    }
    let mut out = film.output(&opts, 0, (w as u32, h as u32));
    out.spp_map = Some(counts.iter().map(|&c| c as f32).collect());
    out.stats.wall_time = start.elapsed();
    Ok(out)
}

/// Every pixel within one pixel (3×3) of a set one: Cycles' `filter_x` then
/// `filter_y` passes, so that the neighbours of a noisy pixel go on sampling.
fn dilate(mask: &[bool], w: usize, h: usize) -> Vec<bool> {
    let mut rows = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let lo = x.saturating_sub(1);
            let hi = (x + 1).min(w - 1);
            rows[y * w + x] = (lo..=hi).any(|k| mask[y * w + k]);
        }
    }
    let mut out = vec![false; w * h];
    for y in 0..h {
        let lo = y.saturating_sub(1);
        let hi = (y + 1).min(h - 1);
        for x in 0..w {
            out[y * w + x] = (lo..=hi).any(|k| rows[k * w + x]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::is_class_a;

    #[test]
    fn error_uses_sqrt_below_unit_intensity_and_linear_above() {
        // ΣI = 0.25: √ = 0.5; |I − A|₁ = 0.03.
        let e = pixel_error([0.1, 0.1, 0.05], [0.11, 0.09, 0.06]);
        assert!((e - 0.03 / (1e-4 + 0.5)).abs() < 1e-12, "{e}");
        // ΣI = 4: normalised by 4, not 2.
        let e = pixel_error([2.0, 1.0, 1.0], [2.1, 1.0, 1.0]);
        assert!((e - 0.1 / (1e-4 + 4.0)).abs() < 1e-12, "{e}");
        // A black pixel with a black half-estimate has no error.
        assert_eq!(pixel_error([0.0; 3], [0.0; 3]), 0.0);
    }

    #[test]
    fn class_a_is_half_of_every_aligned_block_of_four() {
        for block in 0..64u32 {
            let n = (0..4).filter(|k| is_class_a(block * 4 + k)).count();
            assert_eq!(n, 2, "block {block}");
        }
    }

    #[test]
    fn dilation_reaches_the_eight_neighbours_only() {
        let (w, h) = (5, 4);
        let mut m = vec![false; w * h];
        m[w + 2] = true;
        let d = dilate(&m, w, h);
        let set: Vec<usize> = (0..w * h).filter(|&i| d[i]).collect();
        assert_eq!(set, vec![1, 2, 3, 6, 7, 8, 11, 12, 13]);
    }

    #[test]
    fn small_budgets_check_early_and_often() {
        // At 16 spp Cycles' minimum (64 at 0.01) left nothing to adapt.
        let s = NoiseAdaptive::new(0.01, 16);
        assert_eq!((s.min_spp, s.check_every), (4, 2));
        let s = NoiseAdaptive::with_budget(0.01, 128, 16);
        assert_eq!((s.min_spp, s.max_spp, s.check_every), (4, 128, 2));
        let s = NoiseAdaptive::with_budget(0.01, 512, 64);
        assert_eq!((s.min_spp, s.check_every), (16, 8));
        // Large budgets keep Cycles' own values; tiny ones at most the budget.
        let s = NoiseAdaptive::new(0.01, 1024);
        assert_eq!((s.min_spp, s.check_every), (64, 16));
        let s = NoiseAdaptive::new(0.01, 2);
        assert_eq!((s.min_spp, s.check_every), (2, 2));
    }

    #[test]
    fn class_a_count_matches_the_samples() {
        for n in 0..200u32 {
            let direct = (0..n).filter(|&s| is_class_a(s)).count() as u32;
            assert_eq!(crate::render::class_a_count(n), direct, "n = {n}");
        }
    }

    #[test]
    fn cycles_default_min_samples() {
        assert_eq!(NoiseAdaptive::new(0.1, 1024).min_spp, 32);
        assert_eq!(NoiseAdaptive::new(0.01, 1024).min_spp, 64);
        assert_eq!(NoiseAdaptive::new(0.001, 1024).min_spp, 128);
    }
}
