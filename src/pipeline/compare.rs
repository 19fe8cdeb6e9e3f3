//! scene → every sampling strategy at several budgets, repeated over seeds, against
//! a content-keyed cached reference and the baselines a user would pick instead →
//! `<out>/report.{html,json,md}`.
//!
//! Per the first-order paper's Sec. 8–9: each strategy of `adaptive` at each budget
//! (equal sample counts, reconstructed by gradient-aware C1 interpolation); a full
//! render at the same samples per evaluated point; the baselines — every pixel
//! rendered with as many samples as the `gradient` strategy's wall or CPU time
//! buys (`--equal`) — at equal cost; Sec. 8's 1%-of-pixels experiment, gradient
//! against linear interpolation, also scored on the largest surface away from
//! silhouettes; and the previews that suit the scene (`previews`).

use super::adaptive::{render_adaptive, AdaptiveRender};
use super::output_set::image_of_render;
use crate::accel::Accel;
use crate::adaptive::{Settings, Strategy};
use crate::math::sampler::hash2;
use crate::math::Vec3;
use crate::output::report::{self, EqualCost, ReferenceInfo, ReportInput, ReportRow, Run, RunKind};
use crate::reconstruct::Interpolation;
use crate::render::{render, RenderOptions, RenderOutput};
use crate::scene::Scene;
use crate::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

mod previews;

/// What `compare` runs.
#[derive(Clone, Debug)]
pub struct CompareOptions {
    pub strategies: Vec<Strategy>,
    /// Samples per pixel, as the user wrote them (f64, so that the report prints
    /// 0.17 and not 0.17000000178813934); the quadtree gets them as f32.
    pub budgets: Vec<f64>,
    /// Samples per evaluated point (adaptive samples and full-render pixels);
    /// default: the scene's spp.
    pub spp: Option<u32>,
    /// Samples per pixel of the reference; default 8 × spp.
    pub reference_spp: Option<u32>,
    pub resolution: Option<(u32, u32)>,
    /// Shadow rays per line for the visibility gradients of the samples.
    pub vis_samples: Option<u32>,
    /// Camera samples per adaptive sample that carry the gradient (see
    /// [`RenderOptions::gradient_spp`]).
    pub gradient_spp: Option<u32>,
    pub seed: Option<u32>,
    /// Repetitions of every run with independent random numbers (≥ 1; the
    /// report gives means and 95 % intervals).
    pub seeds: u32,
    /// Keep every run's image as an EXR under `<out_dir>/runs/`.
    pub keep_exr: bool,
    /// Images of every budget in the report, not only the headline budget's.
    pub all_images: bool,
    /// Directory of the report; the reference is cached there.
    pub out_dir: PathBuf,
    /// The command line, recorded in `report.json`.
    pub command: String,
    /// What the baselines are matched on (`--equal`): wall time or process CPU time.
    pub equal: EqualCost,
    /// The previews (shadow-field, glossy) as rows where the scene suits them
    /// (`--no-previews`: false).
    pub previews: bool,
    /// The shadow-field preview's precompute settings (tests make them cheap).
    pub shadow_field: crate::preview::shadow_field::Settings,
    /// The glossy preview's precompute settings.
    pub glossy: crate::preview::glossy::Settings,
}

impl CompareOptions {
    /// Every strategy at 5, 10, 17, 25 and 50 % of the pixels, one seed.
    pub fn new(out_dir: PathBuf) -> Self {
        Self {
            strategies: Strategy::ALL.to_vec(),
            budgets: vec![0.05, 0.10, 0.17, 0.25, 0.50],
            spp: None,
            reference_spp: None,
            resolution: None,
            vis_samples: Some(4),
            gradient_spp: None,
            seed: None,
            seeds: 1,
            keep_exr: false,
            all_images: false,
            out_dir,
            command: String::new(),
            equal: EqualCost::Wall,
            previews: true,
            shadow_field: Default::default(),
            glossy: Default::default(),
        }
    }

    /// Every option checked before any work: a bad list must not cost a
    /// reference render (nor leave one behind).
    pub fn validate(&self) -> Result<()> {
        let bad = |option: &str, message: String| {
            Err(Error::Option {
                option: option.into(),
                message,
            })
        };
        if self.strategies.is_empty() {
            return bad("--strategies", "needs at least one strategy".into());
        }
        if self.budgets.is_empty() {
            return bad("--budgets", "needs at least one budget".into());
        }
        // Also > 0 as the f32 the quadtree takes.
        if let Some(b) = self
            .budgets
            .iter()
            .find(|b| !(**b > 0.0 && **b <= 16.0 && (**b as f32) > 0.0))
        {
            return bad(
                "--budgets",
                format!("{b}: a budget is samples per pixel in (0, 16], e.g. 0.17"),
            );
        }
        if self.seeds == 0 {
            return bad("--seeds", "must be at least 1".into());
        }
        if self.equal == EqualCost::Cpu && crate::cpu_time::process_s().is_none() {
            return bad(
                "--equal",
                "cpu: this system does not report the process's CPU time; use --equal wall".into(),
            );
        }
        if self.out_dir.exists() && !self.out_dir.is_dir() {
            return bad(
                "--out",
                format!("{}: exists and is not a folder", self.out_dir.display()),
            );
        }
        Ok(())
    }
}

/// `out/<scene path>`: derived from the whole path, so that two scenes never share a
/// folder (`scenes/cornell.toml` → `out/cornell`, `scenes/validation/cornell.toml` →
/// `out/validation-cornell`; a scene outside the working folder gets its stem and a
/// hash of its absolute path).
pub fn default_dir(scene: &Path) -> PathBuf {
    let stem = scene
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let cwd = std::env::current_dir().unwrap_or_default();
    let abs = std::fs::canonicalize(scene).unwrap_or_else(|_| cwd.join(scene));
    let name = match abs.strip_prefix(&cwd) {
        Ok(rel) => {
            let mut parts: Vec<String> = rel
                .with_extension("")
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if parts.len() > 1 && parts[0] == "scenes" {
                parts.remove(0);
            }
            parts.join("-")
        }
        Err(_) => {
            let key = hash2(
                abs.to_string_lossy()
                    .bytes()
                    .fold(0u32, |h, b| hash2(h, b as u32)),
                0,
            );
            format!("{stem}-{key:08x}")
        }
    };
    Path::new("out").join(name)
}

/// What `gradtrace compare` prints: the report's table and where it went.
#[derive(Clone, Debug)]
pub struct CompareSummary {
    pub rows: Vec<ReportRow>,
    pub report: PathBuf,
}

impl std::fmt::Display for CompareSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        writeln!(f, "{}", report::markdown_table(&self.rows))?;
        write!(f, "wrote {}", self.report.display())
    }
}

/// `gradtrace compare`: checks the options, loads the scene, runs [`compare`] with
/// one progress line per step, and returns what the command prints.
pub fn run(
    scene_path: &Path,
    threads: Option<u32>,
    opts: &CompareOptions,
    mode: super::progress::ProgressMode,
) -> Result<CompareSummary> {
    opts.validate()?;
    let (scene, accel) = super::load(scene_path)?;
    let oidn = crate::denoise::available();
    let baselines = 4 + 2 * usize::from(oidn);
    let gradient_oidn = usize::from(oidn && opts.strategies.contains(&Strategy::Gradient));
    let per_budget = opts.strategies.len() + gradient_oidn + baselines;
    let per_seed = 1 + per_budget * opts.budgets.len();
    let previews = if opts.previews {
        previews::suited(&scene).len()
    } else {
        0
    };
    // The reference, every seed's runs, the interpolation grid, the previews and
    // the report.
    let steps = 1 + per_seed * opts.seeds as usize + 2 + previews;
    let phase = super::progress::Phase::new(mode, "compare", steps as u64, "runs");
    // One step per finished run; warnings are messages, not steps.
    let progress = |msg: &str| {
        if !msg.starts_with("warning") {
            phase.inc(1);
        }
        phase.message(msg);
    };
    let rows = super::with_threads(threads, || compare(&scene, &accel, opts, &progress))??;
    Ok(CompareSummary {
        rows,
        report: opts.out_dir.join("report.html"),
    })
}

/// The run settings shared by every render of a comparison.
struct Plan<'a> {
    scene: &'a Scene,
    accel: &'a Accel,
    opts: &'a CompareOptions,
    base: RenderOptions,
    spp: u32,
    reference_spp: u32,
    size: (u32, u32),
}

/// Runs the comparison and writes the report; returns its rows.
/// `progress` receives one line per finished step.
pub fn compare(
    scene: &Scene,
    accel: &Accel,
    opts: &CompareOptions,
    progress: &dyn Fn(&str),
) -> Result<Vec<ReportRow>> {
    opts.validate()?;
    let start = Instant::now();
    let spp = opts.spp.unwrap_or(scene.settings.spp).max(1);
    let base = RenderOptions {
        spp: Some(spp),
        resolution: opts.resolution,
        seed: opts.seed,
        vis_samples: opts.vis_samples,
        gradient_spp: opts.gradient_spp,
        ..Default::default()
    };
    let plan = Plan {
        scene,
        accel,
        opts,
        size: base.resolution_of(scene),
        reference_spp: opts.reference_spp.unwrap_or(8 * spp).max(spp),
        spp,
        base,
    };
    let scene_hash = scene.content_hash()?;
    let (reference, info) = cached_reference(&plan, &scene_hash)?;
    progress(&format!(
        "reference: {} spp, {} ({:.1} s when rendered)",
        info.spp,
        if info.reused { "reused" } else { "rendered" },
        info.time_s
    ));
    let mut rendering_s = if info.reused { 0.0 } else { info.time_s };

    let mut runs = Vec::new();
    let mut shares = Vec::new();
    for k in 0..opts.seeds {
        let (seed_runs, seconds) = seed_runs(&plan, k, progress, &mut shares)?;
        rendering_s += seconds;
        runs.extend(seed_runs);
    }
    warn_identical_sample_sets(&runs, progress);
    let (grid, sec8_note) = interpolation_runs(&plan, &reference)?;
    rendering_s += grid.iter().map(|r| r.wall_time_s).sum::<f64>();
    progress("Sec. 8 interpolation grid");
    runs.extend(grid);
    let mut preview_notes = Vec::new();
    if opts.previews {
        let p = previews::runs(&plan, progress)?;
        rendering_s += p.seconds;
        runs.extend(p.runs);
        preview_notes = p.notes;
    }

    let outside_s = (start.elapsed().as_secs_f64() - rendering_s).max(0.0);
    let mut notes = notes(
        &plan,
        &info,
        sec8_note,
        outside_s,
        start.elapsed().as_secs_f64(),
    );
    notes.extend(gradient_share_note(&shares));
    notes.extend(preview_notes);
    let (w, h) = plan.size;
    let input = ReportInput {
        scene: scene.name(),
        scene_hash,
        command: opts.command.clone(),
        version: super::VERSION.into(),
        threads: rayon::current_num_threads(),
        equal_cost: opts.equal,
        width: w as usize,
        height: h as usize,
        reference,
        reference_info: info,
        exposure: 0.0,
        runs,
        all_images: opts.all_images,
        notes,
    };
    let t = Instant::now();
    // `--keep-exr`'s EXRs are members of the report's set: one id, renamed
    // before the pages, listed in report.json.
    let rows = report::write_report_with(&opts.out_dir, &input, |set| {
        if opts.keep_exr {
            keep_exrs(&plan, &input, set)?;
        }
        Ok(())
    })?;
    let total = start.elapsed().as_secs_f64();
    let outside = outside_s + t.elapsed().as_secs_f64();
    progress(&format!(
        "report written; outside rendering (cache, metrics, report) {outside:.2} s of {total:.1} s: {:.1}%",
        100.0 * outside / total.max(1e-9)
    ));
    Ok(rows)
}

/// The seed of repetition `k`: the runs' seed itself first (so one repetition is
/// the single-seed comparison), then independent streams derived from it.
fn repetition_seed(base: u32, k: u32) -> u32 {
    if k == 0 {
        base
    } else {
        hash2(base, 0x5eed_0000 + k)
    }
}

/// The gradient strategy's reconstruction denoised: what a user would combine.
const GRADIENT_OIDN: &str = "gradient+oidn";

/// One repetition: the full render, every strategy × budget, and for every budget
/// the baselines at the `gradient` run's cost (wall or CPU time, `--equal`). Also
/// returns the wall seconds spent rendering (and denoising), each counted once.
/// The runs of repetition `k`; the adaptive runs' gradient shares of their tracing
/// time go to `shares` (strategy name, share).
fn seed_runs(
    plan: &Plan,
    k: u32,
    progress: &dyn Fn(&str),
    shares: &mut Vec<(&'static str, f64)>,
) -> Result<(Vec<Run>, f64)> {
    let seed = repetition_seed(plan.base.seed.unwrap_or(plan.scene.settings.seed), k);
    let base = RenderOptions {
        seed: Some(seed),
        ..plan.base.clone()
    };
    let mode = plan.opts.equal;
    let (full, full_cost) = timed_render(plan, &base)?;
    progress(&format!(
        "seed {k}: full render, {} spp, {:.2} s",
        plan.spp, full_cost.wall_s
    ));
    let mut runs = vec![full_run(
        "full",
        RunKind::Full { spp: plan.spp },
        k,
        full,
        full_cost,
    )];
    // Rendering and denoising that no run's wall time holds (the G-buffers and
    // denoisers of the derived gradient+oidn runs, discarded equal-time attempts).
    let mut extra_s = 0.0;
    for &budget in &plan.opts.budgets {
        let mut gradient_cost = None;
        let mut denoiser_cost = None;
        for &strategy in &plan.opts.strategies {
            let settings = Settings::new(strategy, budget as f32);
            let clock = Clock::start();
            let out = render_adaptive(
                plan.scene,
                plan.accel,
                &base,
                &settings,
                Interpolation::Gradient,
                &|_, _| {},
            )?;
            // Wall and CPU time over the same span.
            let cost = clock.cost();
            if let Some(g) = out.stats.gradient_share {
                shares.push((strategy.name(), g));
            }
            progress(&format!(
                "seed {k}: {} at {:.0}%, {} samples, {:.2} s",
                strategy.name(),
                budget * 100.0,
                out.samples.samples.len(),
                out.stats.wall_s
            ));
            if strategy == Strategy::Gradient {
                gradient_cost = Some(cost);
                if crate::denoise::available() {
                    let (run, gbuffer, denoiser) =
                        denoised_run(plan, &base, &out, cost, budget, k)?;
                    progress(&format!(
                        "seed {k}: {GRADIENT_OIDN} at {:.0}%, G-buffer {:.2} s + denoise {:.2} s",
                        budget * 100.0,
                        gbuffer.wall_s,
                        denoiser.wall_s
                    ));
                    extra_s += gbuffer.wall_s + denoiser.wall_s;
                    denoiser_cost = Some(denoiser);
                    runs.push(run);
                }
            }
            runs.push(adaptive_run(
                strategy.name(),
                RunKind::Adaptive {
                    budget,
                    spp: plan.spp,
                },
                k,
                out,
                cost.cpu_s,
            ));
        }
        // The baselines need the gradient run's cost; without `gradient` among the
        // strategies, the first strategy's cost stands in.
        let target = gradient_cost
            .unwrap_or_else(|| runs.last().map_or(full_cost, Cost::of_run))
            .of(mode);
        let guess =
            ((plan.spp as f64 * target / full_cost.of(mode).max(1e-9)).round() as u32).max(1);
        let uniform = equal_time_render(plan, &base, guess, target)?;
        let (out, cost, spp_eq) = (uniform.out, uniform.cost, uniform.spp);
        extra_s += uniform.discarded_s;
        progress(&format!(
            "seed {k}: uniform-all-pixels at the {} of {:.0}%: {spp_eq} spp, {:.2} s",
            mode.label(),
            budget * 100.0,
            cost.of(mode)
        ));
        let kind = RunKind::Baseline {
            budget,
            spp: spp_eq,
        };
        let mut run = full_run("uniform-all-pixels", kind, k, out, cost);
        run.target_s = Some(target);
        runs.push(run);
        let equal = EqualTime {
            budget,
            spp: spp_eq,
            target,
            denoiser_s: denoiser_cost.map(|c| c.of(mode)),
        };
        let (baselines, discarded_s) = other_baselines(plan, &base, &equal, k, progress)?;
        runs.extend(baselines.into_iter().map(|r| Run {
            target_s: Some(target),
            ..r
        }));
        extra_s += discarded_s;
        let (run, discarded_s) = gradient_domain_run(plan, &base, &equal, k, None, progress)?;
        let spp_gd = run.kind.spp();
        runs.push(run);
        extra_s += discarded_s;
        let (run, discarded_s) =
            gradient_domain_run(plan, &base, &equal, k, Some(spp_gd), progress)?;
        runs.push(run);
        extra_s += discarded_s;
    }
    let rendering_s = runs
        .iter()
        .filter(|r| r.name != GRADIENT_OIDN)
        .map(|r| r.wall_time_s)
        .sum::<f64>()
        + extra_s;
    Ok((runs, rendering_s))
}

/// `out` (the gradient strategy's reconstruction, which cost `cost`) denoised with
/// OIDN, guided by a one-ray-per-pixel G-buffer; its cost is the adaptive render's
/// plus both. Returns the run, the G-buffer's and the denoiser's cost.
fn denoised_run(
    plan: &Plan,
    base: &RenderOptions,
    out: &AdaptiveRender,
    cost: Cost,
    budget: f64,
    k: u32,
) -> Result<(Run, Cost, Cost)> {
    let clock = Clock::start();
    let gbuffer = super::render::gbuffer(plan.scene, plan.accel, base)?;
    let gbuffer_cost = clock.cost();
    let clock = Clock::start();
    let clean = super::render::denoise_with(&out.reconstruction.image, &gbuffer)?;
    let denoiser_cost = clock.cost();
    let extra = gbuffer_cost + denoiser_cost;
    let run = Run {
        name: GRADIENT_OIDN.into(),
        kind: RunKind::Adaptive {
            budget,
            spp: plan.spp,
        },
        seed: k,
        samples: out.samples.samples.len(),
        wall_time_s: out.stats.wall_s + extra.wall_s,
        cpu_time_s: cost.cpu_s + extra.cpu_s,
        overhead_s: out.stats.quadtree_s + out.stats.reconstruct_s + extra.wall_s,
        // An equal-time contender: measured against the run it denoises.
        target_s: Some(cost.of(plan.opts.equal)),
        image: clean,
        sample_positions: out.samples.samples.iter().map(|s| s.pos).collect(),
    };
    Ok((run, gbuffer_cost, denoiser_cost))
}

/// What the baselines at one budget are given: the gradient run's cost
/// (`target`, wall or CPU seconds as `--equal`), the spp a full render fits in it,
/// and the denoiser's cost on this image when it ran (the denoised baselines
/// render less to leave room for it).
struct EqualTime {
    budget: f64,
    spp: u32,
    target: f64,
    denoiser_s: Option<f64>,
}

/// Blender's per-pixel noise-threshold sampler (`render::noise_adaptive`).
const CYCLES: &str = "cycles-adaptive";

/// Blender's recommended pairing: [`CYCLES`] at equal cost, then OIDN with the
/// albedo and normal guides, the denoise counted in the cost.
const CYCLES_OIDN: &str = "cycles-adaptive+oidn";

/// The Cycles-style sampler's settings: Blender's default threshold, the minimum
/// and the step sized for the spp the time affords (a pixel may take 8 times
/// that), stopped at `limit` seconds of wall or CPU time (`--equal`).
fn cycles_settings(
    mode: EqualCost,
    spp_eq: u32,
    limit: f64,
) -> crate::render::noise_adaptive::NoiseAdaptive {
    let mut cycles = crate::render::noise_adaptive::NoiseAdaptive::with_budget(
        0.01,
        (8 * spp_eq).max(16),
        spp_eq,
    );
    let limit = Some(std::time::Duration::from_secs_f64(limit.max(0.0)));
    match mode {
        EqualCost::Wall => cycles.time_limit = limit,
        EqualCost::Cpu => cycles.cpu_time_limit = limit,
    }
    cycles
}

/// A noise-adaptive render's run: its mean spp as the kind's, its samples summed.
fn cycles_run(name: &str, budget: f64, k: u32, out: RenderOutput, cost: Cost) -> Run {
    let counts = out.spp_map.as_deref().unwrap_or(&[]);
    let total: f64 = counts.iter().map(|&c| f64::from(c)).sum();
    let mean = (total / counts.len().max(1) as f64).round() as u32;
    let mut run = full_run(name, RunKind::Baseline { budget, spp: mean }, k, out, cost);
    run.samples = total as usize;
    run
}

/// The baselines besides uniform, at the `target` cost of the gradient run at
/// `budget`: the Cycles-style per-pixel adaptive sampler and, where the build has
/// OIDN, the denoised uniform render and the denoised Cycles-style render.
fn other_baselines(
    plan: &Plan,
    base: &RenderOptions,
    equal: &EqualTime,
    k: u32,
    progress: &dyn Fn(&str),
) -> Result<(Vec<Run>, f64)> {
    let &EqualTime {
        budget,
        spp: spp_eq,
        target,
        denoiser_s,
    } = equal;
    use crate::render::noise_adaptive::render_noise_adaptive;
    let mode = plan.opts.equal;
    let mut runs = Vec::new();
    let cycles = cycles_settings(mode, spp_eq, target);
    let clock = Clock::start();
    let out = render_noise_adaptive(plan.scene, plan.accel, base, &cycles, &|_, _| {})?;
    let run = cycles_run(CYCLES, budget, k, out, clock.cost());
    progress(&format!(
        "seed {k}: {CYCLES} at the {} of {:.0}%: mean {} spp, {:.2} s",
        mode.label(),
        budget * 100.0,
        run.kind.spp(),
        mode.of(run.wall_time_s, run.cpu_time_s)
    ));
    runs.push(run);
    if !crate::denoise::available() {
        return Ok((runs, 0.0));
    }
    // Denoise time included: the render gets what the denoiser leaves of the target.
    let denoiser_s = denoiser_s.unwrap_or(0.0).clamp(0.0, 0.75 * target);
    let guess = ((f64::from(spp_eq) * (target - denoiser_s) / target).round() as u32).max(1);
    let with_aovs = RenderOptions {
        aovs: true,
        ..base.clone()
    };
    let rendered = equal_time_render(plan, &with_aovs, guess, target - denoiser_s)?;
    let (out, spp_oidn) = (rendered.out, rendered.spp);
    let clock = Clock::start();
    let clean = super::render::denoise_with(&out.beauty, &out)?;
    let denoised = clock.cost();
    let cost = rendered.cost + denoised;
    progress(&format!(
        "seed {k}: oidn-uniform, {spp_oidn} spp + denoise, {:.2} s",
        cost.of(mode)
    ));
    let mut run = full_run(
        "oidn-uniform",
        RunKind::Baseline {
            budget,
            spp: spp_oidn,
        },
        k,
        out,
        cost,
    );
    run.overhead_s = denoised.wall_s;
    run.image = clean;
    runs.push(run);
    runs.push(cycles_oidn_run(
        plan, &with_aovs, equal, denoiser_s, k, progress,
    )?);
    Ok((runs, rendered.discarded_s))
}

/// [`CYCLES_OIDN`]: the noise-adaptive render (with its albedo and normal AOVs)
/// stopped at what the denoiser leaves of the target, then denoised.
fn cycles_oidn_run(
    plan: &Plan,
    with_aovs: &RenderOptions,
    equal: &EqualTime,
    denoiser_s: f64,
    k: u32,
    progress: &dyn Fn(&str),
) -> Result<Run> {
    use crate::render::noise_adaptive::render_noise_adaptive;
    let mode = plan.opts.equal;
    let cycles = cycles_settings(mode, equal.spp, equal.target - denoiser_s);
    let clock = Clock::start();
    let out = render_noise_adaptive(plan.scene, plan.accel, with_aovs, &cycles, &|_, _| {})?;
    // The guides come with the render's first hits; a pass of their own only
    // where a render kept none.
    let clean = if out.albedo.is_some() && out.normal.is_some() {
        super::render::denoise_with(&out.beauty, &out)?
    } else {
        let gbuffer = super::render::gbuffer(plan.scene, plan.accel, with_aovs)?;
        super::render::denoise_with(&out.beauty, &gbuffer)?
    };
    let cost = clock.cost();
    let render_wall = out.stats.wall_time.as_secs_f64();
    let mut run = cycles_run(CYCLES_OIDN, equal.budget, k, out, cost);
    run.overhead_s = (cost.wall_s - render_wall).max(0.0);
    run.image = clean;
    progress(&format!(
        "seed {k}: {CYCLES_OIDN}, mean {} spp + denoise, {:.2} s",
        run.kind.spp(),
        cost.of(mode)
    ));
    Ok(run)
}

/// The `gradient-domain` row: every pixel rendered with gradients and AOVs, then
/// the L1 screened Poisson solve (`gdomain`), render + solve at the `target` cost
/// (wall or CPU seconds, as `--equal` says). A 1-spp probe (render and solve) sizes the spp; an attempt that misses the
/// target by more than 10 % is redone once at the spp its own time implies. Returns
/// the run and the discarded seconds (probe and missed attempt).
///
/// With `dense: Some(spp)`, the [`GD_ADAPTIVE`] row: the same solve on a render
/// whose samples `gdomain::render_dense_adaptive` placed, starting from the
/// `gradient-domain` row's fitted `spp` instead of a probe.
fn gradient_domain_run(
    plan: &Plan,
    base: &RenderOptions,
    equal: &EqualTime,
    k: u32,
    dense: Option<u32>,
    progress: &dyn Fn(&str),
) -> Result<(Run, f64)> {
    use super::gdomain::{reconstruct, render_dense_adaptive, DenseAdaptive, GradientDomain};
    let gd = GradientDomain::new(crate::reconstruct::poisson::Norm::L1);
    let opts = RenderOptions {
        gradients: true,
        aovs: true,
        ..base.clone()
    };
    let mode = plan.opts.equal;
    let attempt = |spp: u32| -> Result<(RenderOutput, Vec<Vec3>, Cost, Cost)> {
        let opts = RenderOptions {
            spp: Some(spp),
            ..opts.clone()
        };
        let (out, render) = match dense {
            None => timed_render(plan, &opts)?,
            Some(_) => {
                let clock = Clock::start();
                let dense = DenseAdaptive::new(spp);
                let out = render_dense_adaptive(plan.scene, plan.accel, &opts, &dense)?;
                (out, clock.cost())
            }
        };
        let clock = Clock::start();
        let image = reconstruct(&out, &gd)?;
        Ok((out, image, render, clock.cost()))
    };
    let (guess, probe_s) = match dense {
        Some(spp) => (spp, 0.0),
        None => {
            let (_, _, probe_render, probe_solve) = attempt(1)?;
            let guess = spp_for(equal.target, probe_render.of(mode), probe_solve.of(mode));
            (guess, probe_render.wall_s + probe_solve.wall_s)
        }
    };
    let fitted = at_target(mode, guess, equal.target, |spp| {
        let (out, image, render, solve) = attempt(spp)?;
        Ok(((out, image), render, solve))
    })?;
    let ((out, image), render, solve, spp) =
        (fitted.value, fitted.scaled, fitted.fixed, fitted.spp);
    let discarded = probe_s + fitted.discarded_s;
    let name = if dense.is_some() {
        GD_ADAPTIVE
    } else {
        "gradient-domain"
    };
    progress(&format!(
        "seed {k}: {name} ({}) at the time of {:.0}%: {spp} spp, render {:.2} s + solve {:.2} s",
        gd.norm.name(),
        equal.budget * 100.0,
        render.of(mode),
        solve.of(mode)
    ));
    let kind = RunKind::Baseline {
        budget: equal.budget,
        spp,
    };
    let mut run = full_run(name, kind, k, out, render + solve);
    run.overhead_s = solve.wall_s;
    run.image = image;
    run.target_s = Some(equal.target);
    Ok((run, discarded))
}

/// The gradient-domain strategy with dense adaptive sampling (issue 56, item 2).
const GD_ADAPTIVE: &str = "gradient-domain-adaptive";

/// Two strategies that placed exactly the same samples at one budget and seed
/// (forced boundary cells can take the whole budget) are one result twice. (The
/// denoised gradient run shares its samples by construction.)
fn warn_identical_sample_sets(runs: &[Run], progress: &dyn Fn(&str)) {
    let strategies: Vec<&Run> = runs.iter().filter(|r| r.name != GRADIENT_OIDN).collect();
    for (i, a) in strategies.iter().enumerate() {
        for b in &strategies[i + 1..] {
            if a.seed == b.seed
                && a.kind == b.kind
                && matches!(a.kind, RunKind::Adaptive { .. })
                && !a.sample_positions.is_empty()
                && a.sample_positions == b.sample_positions
            {
                progress(&format!(
                    "warning: {} and {} placed the same {} samples",
                    a.name,
                    b.name,
                    a.sample_positions.len()
                ));
            }
        }
    }
}

/// Sec. 8: 1% of the pixels on a regular grid, linear then gradient interpolation,
/// and the note scoring them on the largest surface away from silhouettes.
///
/// The paper evaluates these few pixels with dense light sampling ("we must have
/// accurate values at the image pixels"): here at the reference's spp, a quarter
/// of the camera samples carrying the gradient with 32 shadow rays per line.
fn interpolation_runs(plan: &Plan, reference: &[Vec3]) -> Result<(Vec<Run>, Option<String>)> {
    let grid_opts = RenderOptions {
        spp: Some(plan.reference_spp),
        gradient_spp: Some((plan.reference_spp / 4).max(1)),
        vis_samples: Some(plan.opts.vis_samples.unwrap_or(0).max(32)),
        ..plan.base.clone()
    };
    let mut runs = Vec::new();
    for interp in [Interpolation::Linear, Interpolation::Gradient] {
        let settings = Settings::new(Strategy::Uniform, 0.01);
        let clock = Clock::start();
        let out = render_adaptive(
            plan.scene,
            plan.accel,
            &grid_opts,
            &settings,
            interp,
            &|_, _| {},
        )?;
        let name = format!("1% grid, {} interpolation", interp.name());
        runs.push(adaptive_run(
            &name,
            RunKind::Interpolation {
                budget: 0.01,
                spp: plan.reference_spp,
            },
            0,
            out,
            clock.cost().cpu_s,
        ));
    }
    // Pixels within one grid spacing of another surface are left out: there the
    // grid cannot place the silhouette and Sec. 8 is about the shading in between.
    let (w, h) = plan.size;
    let spacing = (1.0f32 / 0.01).sqrt().ceil() as usize;
    let surface = largest_surface(plan)?
        .map(|(id, mask)| (id, erode(&mask, w as usize, h as usize, spacing)))
        .filter(|(_, mask)| mask.contains(&true));
    let note = match surface {
        None => None,
        Some((id, mask)) => {
            let pick = |v: &[Vec3]| -> Vec<Vec3> {
                v.iter()
                    .zip(&mask)
                    .filter(|(_, &m)| m)
                    .map(|(c, _)| *c)
                    .collect()
            };
            let reference_on_mask = pick(reference);
            let masked =
                |img: &[Vec3]| crate::output::metrics::rmse(&pick(img), &reference_on_mask);
            let (lin, grad) = (masked(&runs[0].image)?, masked(&runs[1].image)?);
            Some(format!(
                "Sec. 8, 1% grid on the largest surface (shape {id}, the {} pixels more than {spacing} px from any other surface): RMSE linear {lin:.4e}, gradient {grad:.4e} ({:.2}×).",
                reference_on_mask.len(),
                grad / lin.max(f32::MIN_POSITIVE)
            ))
        }
    };
    Ok((runs, note))
}

/// What share of the adaptive runs' tracing time the analytic gradients took, per
/// strategy (mean over budgets and seeds).
fn gradient_share_note(shares: &[(&str, f64)]) -> Option<String> {
    let mut names: Vec<&str> = shares.iter().map(|(n, _)| *n).collect();
    names.sort_unstable();
    names.dedup();
    let parts: Vec<String> = names
        .iter()
        .map(|n| {
            let of: Vec<f64> = shares
                .iter()
                .filter(|(m, _)| m == n)
                .map(|(_, g)| *g)
                .collect();
            format!(
                "{n} {:.0} %",
                100.0 * of.iter().sum::<f64>() / of.len() as f64
            )
        })
        .collect();
    (!parts.is_empty()).then(|| {
        format!(
            "Gradient share of the adaptive runs' tracing time (one camera sample in 64 traced with and without its analytic gradient and timed; --vis-samples and --gradient-spp set it): {}.",
            parts.join(", ")
        )
    })
}

fn notes(
    plan: &Plan,
    info: &ReferenceInfo,
    sec8: Option<String>,
    outside_s: f64,
    total_s: f64,
) -> Vec<String> {
    [
        Some(format!(
            "Reference: every pixel at {} spp with random numbers independent of every run, {} ({:.1} s when rendered); cache key {}.",
            info.spp,
            if info.reused { "reused from the cache" } else { "rendered for this report" },
            info.time_s,
            info.cache_key
        )),
        Some(format!(
            "Adaptive runs evaluate the renderer (path tracing with analytic gradients: direct light, soft shadows and the indirect term) at the quadtree's samples, {} spp each, and reconstruct the pixels by Sibson C1 interpolation with those gradients; overhead = quadtree + reconstruction.",
            plan.spp
        )),
        Some(format!(
            "{} repetition{} with independent random numbers; ± is the 95% Student-t interval of the mean.",
            plan.opts.seeds,
            if plan.opts.seeds == 1 { "" } else { "s" }
        )),
        sec8,
        Some(match plan.opts.equal {
            EqualCost::Wall => "Equal cost: wall time (--equal wall); every run's CPU time (user + system, all threads) is recorded beside it.".to_string(),
            EqualCost::Cpu => "Equal cost: process CPU time, user + system over all threads (--equal cpu), which other jobs on the machine inflate far less than the wall time; every run's wall time is recorded beside it.".to_string(),
        }),
        (!crate::denoise::available()).then(|| format!(
            "oidn-uniform, {GRADIENT_OIDN} and {CYCLES_OIDN} (the denoised baselines) are not in this report: {}",
            crate::denoise::unavailable_reason()
        )),
        Some(format!(
            "Before writing this report, compare spent {outside_s:.2} s of {total_s:.1} s outside rendering (cache, checks): {:.1}%; the metrics and the report's files take a few tenths of a second more (the final progress line gives the total).",
            100.0 * outside_s / total_s.max(1e-9)
        )),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// `mask` shrunk by `r` pixels: a pixel stays set only if every pixel in the
/// (2r+1)² square around it (clipped to the image) is set. Two 1D passes.
fn erode(mask: &[bool], w: usize, h: usize, r: usize) -> Vec<bool> {
    let pass = |src: &[bool], len: usize, lines: usize, at: &dyn Fn(usize, usize) -> usize| {
        let mut out = vec![false; src.len()];
        for l in 0..lines {
            for i in 0..len {
                let (a, b) = (i.saturating_sub(r), (i + r).min(len - 1));
                out[at(l, i)] = (a..=b).all(|k| src[at(l, k)]);
            }
        }
        out
    };
    let rows = pass(mask, w, h, &|y, x| y * w + x);
    pass(&rows, h, w, &|x, y| y * w + x)
}

/// The shape seen at the most pixel centres (1-based id as in the `object.id` layer)
/// and its pixel mask, from one primary ray per pixel; `None` if nothing is hit.
fn largest_surface(plan: &Plan) -> Result<Option<(u32, Vec<bool>)>> {
    let opts = RenderOptions {
        spp: Some(1),
        max_depth: Some(1),
        aovs: true,
        gradients: false,
        ..plan.base.clone()
    };
    let ids = render(plan.scene, plan.accel, &opts, &|_, _| {})?
        .object_id
        .unwrap_or_default();
    let mut counts = std::collections::BTreeMap::new();
    for &id in ids.iter().filter(|&&id| id > 0.0) {
        *counts.entry(id as u32).or_insert(0usize) += 1;
    }
    let Some((&id, _)) = counts.iter().max_by_key(|(_, &n)| n) else {
        return Ok(None);
    };
    Ok(Some((id, ids.iter().map(|&v| v as u32 == id).collect())))
}

/// A run's cost in both measures: wall seconds and process CPU seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Cost {
    wall_s: f64,
    cpu_s: f64,
}

impl Cost {
    fn of(self, mode: EqualCost) -> f64 {
        mode.of(self.wall_s, self.cpu_s)
    }

    fn of_run(run: &Run) -> Self {
        Self {
            wall_s: run.wall_time_s,
            cpu_s: run.cpu_time_s,
        }
    }
}

impl std::ops::Add for Cost {
    type Output = Cost;
    fn add(self, o: Cost) -> Cost {
        Cost {
            wall_s: self.wall_s + o.wall_s,
            cpu_s: self.cpu_s + o.cpu_s,
        }
    }
}

/// Measures a span in both: the process's CPU clock advances only by what this
/// process runs (compare runs one thing at a time, so that is the run's).
struct Clock {
    wall: Instant,
    cpu: Option<f64>,
}

impl Clock {
    fn start() -> Self {
        Self {
            cpu: crate::cpu_time::process_s(),
            wall: Instant::now(),
        }
    }

    /// The cost so far; where the OS reports no CPU time (`--equal cpu` is then
    /// refused) the CPU seconds are the wall seconds.
    fn cost(&self) -> Cost {
        let wall_s = self.wall.elapsed().as_secs_f64();
        let cpu_s = self
            .cpu
            .zip(crate::cpu_time::process_s())
            .map_or(wall_s, |(a, b)| (b - a).max(0.0));
        Cost { wall_s, cpu_s }
    }
}

/// What [`equal_time_render`] kept.
struct EqualTimeRender {
    out: RenderOutput,
    /// The kept render's cost.
    cost: Cost,
    spp: u32,
    /// The discarded first attempt's wall time (0 when it was kept): rendering too.
    discarded_s: f64,
}

/// A full render at the `target` cost (wall or CPU seconds, `--equal`): `guess`
/// spp (scaled from the full render's cost), retried as [`at_target`] says.
fn equal_time_render(
    plan: &Plan,
    base: &RenderOptions,
    guess: u32,
    target: f64,
) -> Result<EqualTimeRender> {
    let fitted = at_target(plan.opts.equal, guess, target, |spp| {
        let (out, cost) = timed_render(
            plan,
            &RenderOptions {
                spp: Some(spp),
                ..base.clone()
            },
        )?;
        Ok((out, cost, Cost::default()))
    })?;
    Ok(EqualTimeRender {
        out: fitted.value,
        cost: fitted.scaled,
        spp: fitted.spp,
        discarded_s: fitted.discarded_s,
    })
}

/// What [`at_target`] kept: the attempt's value, its cost (the part that scales
/// with spp and the fixed part) and spp, and the
/// wall seconds of a discarded first attempt (0 when it was kept).
struct Fitted<T> {
    value: T,
    scaled: Cost,
    fixed: Cost,
    spp: u32,
    discarded_s: f64,
}

/// `attempt(guess)`, whose cost is a part that grows with spp and a `fixed` part;
/// where their sum missed `target` by more than 10 %, once more at the spp its
/// own costs imply (the machine's load can change between the two, and an
/// equal-time comparison must not hand a method half the time).
fn at_target<T>(
    mode: EqualCost,
    guess: u32,
    target: f64,
    attempt: impl Fn(u32) -> Result<(T, Cost, Cost)>,
) -> Result<Fitted<T>> {
    let (value, scaled, fixed) = attempt(guess)?;
    let secs = (scaled + fixed).of(mode);
    let again = spp_for(target, scaled.of(mode) / f64::from(guess), fixed.of(mode));
    let first = Fitted {
        value,
        scaled,
        fixed,
        spp: guess,
        discarded_s: 0.0,
    };
    if (secs / target - 1.0).abs() <= 0.10 || again == guess {
        return Ok(first);
    }
    let (value, scaled, fixed) = attempt(again)?;
    Ok(Fitted {
        value,
        scaled,
        fixed,
        spp: again,
        discarded_s: (first.scaled + first.fixed).wall_s,
    })
}

/// The spp whose cost, `per_spp` each plus `fixed`, is `target` (at least 1).
fn spp_for(target: f64, per_spp: f64, fixed: f64) -> u32 {
    (((target - fixed) / per_spp.max(1e-9)).round() as u32).max(1)
}

/// Every pixel rendered with `opts`, and what it cost.
fn timed_render(plan: &Plan, opts: &RenderOptions) -> Result<(RenderOutput, Cost)> {
    let clock = Clock::start();
    let out = render(plan.scene, plan.accel, opts, &|_, _| {})?;
    Ok((out, clock.cost()))
}

/// A report run of a render of every pixel.
fn full_run(name: &str, kind: RunKind, seed: u32, out: RenderOutput, cost: Cost) -> Run {
    let spp = match kind {
        RunKind::Full { spp } | RunKind::Baseline { spp, .. } => spp,
        _ => out.spp,
    };
    Run {
        name: name.into(),
        kind,
        seed,
        samples: out.width * out.height * spp as usize,
        wall_time_s: cost.wall_s,
        cpu_time_s: cost.cpu_s,
        overhead_s: 0.0,
        target_s: None,
        image: out.beauty,
        sample_positions: Vec::new(),
    }
}

/// A report run of an adaptive render (its overhead: quadtree + reconstruction);
/// `cpu_s`: the CPU time measured around it.
fn adaptive_run(name: &str, kind: RunKind, seed: u32, out: AdaptiveRender, cpu_s: f64) -> Run {
    Run {
        name: name.into(),
        kind,
        seed,
        samples: out.samples.samples.len(),
        wall_time_s: out.stats.wall_s,
        cpu_time_s: cpu_s,
        overhead_s: out.stats.quadtree_s + out.stats.reconstruct_s,
        target_s: None,
        image: out.reconstruction.image,
        sample_positions: out.samples.samples.iter().map(|s| s.pos).collect(),
    }
}

/// `--keep-exr`: every run's image as `runs/<name>-<setting>-seed<k>.exr`, with
/// the report's id and the provenance `render` writes.
fn keep_exrs(
    plan: &Plan,
    input: &report::ReportInput,
    set: &mut crate::output::atomic::StagedSet,
) -> Result<()> {
    use super::merge::attr;
    let runs = &input.runs;
    let dir = plan.opts.out_dir.join("runs");
    std::fs::create_dir_all(&dir).map_err(|e| Error::Output {
        path: dir.clone(),
        message: format!("cannot create the folder: {e}"),
    })?;
    let (w, h) = plan.size;
    for r in runs {
        let setting = match r.kind {
            RunKind::Adaptive { budget, .. } | RunKind::Interpolation { budget, .. } => {
                format!("b{budget}")
            }
            RunKind::Baseline { budget, spp } => format!("t{budget}-{spp}spp"),
            RunKind::Full { spp } => format!("{spp}spp"),
            RunKind::Preview { .. } => "frame".into(),
        };
        let name: String = format!("{}-{setting}-seed{}", r.name, r.seed)
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        let mut img = crate::output::OutputImage::new(w as usize, h as usize);
        img.push_vec3("", crate::output::names::RGB, &r.image);
        let mut attributes: Vec<(String, String)> = vec![
            (attr::VERSION.into(), input.version.clone()),
            (attr::COMMAND.into(), input.command.clone()),
            (attr::SCENE_SHA256.into(), input.scene_hash.clone()),
            (attr::SPP.into(), r.kind.spp().to_string()),
            (attr::SEED.into(), r.seed.to_string()),
            (attr::RENDER_TIME_S.into(), format!("{:.3}", r.wall_time_s)),
        ];
        attributes.sort();
        let header = crate::output::ExrHeader {
            attributes,
            ..Default::default()
        };
        set.stage_exr(&dir.join(format!("{name}.exr")), &img, &header)?;
    }
    Ok(())
}

/// The reference image, rendered once and cached (`pipeline::cache`) as
/// `reference-<key>.exr` beside the report; reused only when its key (scene
/// content, every render setting, the pixel epoch) is the present inputs'.
///
/// Its random numbers come from a seed of its own (derived from the runs' seed):
/// with the runs' seed, its first `spp` samples per pixel would be the full render's
/// very samples, and the full and equal-time renders would share a quarter or more of
/// their noise with the reference — their error would look ~25% smaller than it is.
fn cached_reference(plan: &Plan, scene_hash: &str) -> Result<(Vec<Vec3>, ReferenceInfo)> {
    let seed = hash2(
        plan.base.seed.unwrap_or(plan.scene.settings.seed),
        0x7265_6665,
    );
    let opts = RenderOptions {
        spp: Some(plan.reference_spp),
        seed: Some(seed),
        resolution: Some(plan.size),
        gradients: false,
        aovs: false,
        ..plan.base.clone()
    };
    let entry = super::cache::Cache::beside(&plan.opts.out_dir).entry(
        "reference",
        "exr",
        super::cache::Epoch::Pixels,
        scene_hash,
        &format!("{opts:?}"),
    );
    let (w, h) = plan.size;
    // A damaged entry (a NaN written by another tool, a flipped bit) is a miss,
    // found before the runs (issue 54, defect 15), and rendered anew.
    let hit = entry
        .read_exr(|img| (img.width, img.height) == (w as usize, h as usize))
        .and_then(|hit| Some((hit.value.vec3("", crate::output::names::RGB)?, hit.seconds)));
    if let Some((pixels, time_s)) = hit {
        let info = ReferenceInfo {
            spp: plan.reference_spp,
            time_s,
            cache_key: entry.key().to_string(),
            reused: true,
        };
        return Ok((pixels, info));
    }
    let (out, cost) = timed_render(plan, &opts)?;
    let secs = cost.wall_s;
    let header = super::render::provenance(plan.scene, &opts, &plan.opts.command, &out)?;
    entry.write_exr(&image_of_render(&out), &header, &out.beauty, secs)?;
    let info = ReferenceInfo {
        spp: plan.reference_spp,
        time_s: secs,
        cache_key: entry.key().to_string(),
        reused: false,
    };
    Ok((out.beauty, info))
}

#[cfg(test)]
mod tests {
    use super::erode;

    #[test]
    fn erode_shrinks_by_the_radius() {
        // A 7×5 block inside a 11×9 image, eroded by 2, leaves its 3×1 core.
        let (w, h) = (11, 9);
        let mask: Vec<bool> = (0..w * h)
            .map(|i| (2..9).contains(&(i % w)) && (2..7).contains(&(i / w)))
            .collect();
        let e = erode(&mask, w, h, 2);
        let kept: Vec<(usize, usize)> = (0..w * h)
            .filter(|&i| e[i])
            .map(|i| (i % w, i / w))
            .collect();
        assert_eq!(kept, vec![(4, 4), (5, 4), (6, 4)]);
        // The image border does not erode.
        assert!(erode(&vec![true; w * h], w, h, 3).iter().all(|&m| m));
    }
}
