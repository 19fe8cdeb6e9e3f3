//! scene → every sampling strategy at several budgets, a cached reference and
//! honest baselines → `out/<scene>/report.{html,json,md}`.
//!
//! What is compared, per the adaptive-sampling issue and the first-order paper's
//! Sec. 8–9: each strategy of `adaptive` at each budget (equal sample counts,
//! reconstructed by gradient-aware C1 interpolation); a full render at the same
//! samples per evaluated point (whose wall time is the speed-up baseline); full
//! renders with fewer samples per pixel at the wall time of the `gradient`
//! strategy (equal-time baselines); and Sec. 8's 1%-of-pixels experiment, gradient
//! against linear interpolation, at the reference's samples per point and also scored
//! on the largest surface away from silhouettes (the ground plane of Fig. 13).

use super::adaptive::{render_adaptive, AdaptiveRender};
use crate::accel::Accel;
use crate::adaptive::{Settings, Strategy};
use crate::output::report::{self, ReportInput, ReportRow, Run, RunKind};
use crate::reconstruct::Interpolation;
use crate::render::{render, RenderOptions, RenderOutput};
use crate::scene::Scene;
use crate::{Error, Result};
use glam::Vec3;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What `compare` runs.
#[derive(Clone, Debug)]
pub struct CompareOptions {
    pub strategies: Vec<Strategy>,
    pub budgets: Vec<f32>,
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
    /// Directory of the report (default `out/<scene>`); the reference is cached there.
    pub out_dir: PathBuf,
}

impl CompareOptions {
    /// Every strategy at 5, 10, 17, 25 and 50 % of the pixels.
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
            out_dir,
        }
    }
}

/// `gradtrace compare`: loads the scene, runs [`compare`] with one progress line
/// per step, and returns the report's rows.
pub fn run(
    scene_path: &Path,
    threads: Option<u32>,
    opts: &CompareOptions,
    mode: super::progress::ProgressMode,
) -> Result<Vec<ReportRow>> {
    let (scene, accel) = super::load(scene_path)?;
    let steps = 3 + opts.strategies.len() * opts.budgets.len() + 2 + opts.budgets.len();
    let phase = super::progress::Phase::new(mode, "compare", steps as u64, "steps");
    let progress = |msg: &str| {
        phase.inc(1);
        phase.message(msg);
    };
    super::with_threads(threads, || compare(&scene, &accel, opts, &progress))?
}

/// Runs the comparison and writes the report; returns its table rows.
/// `progress` receives one line per finished step.
pub fn compare(
    scene: &Scene,
    accel: &Accel,
    opts: &CompareOptions,
    progress: &dyn Fn(&str),
) -> Result<Vec<ReportRow>> {
    if opts.budgets.is_empty() || opts.strategies.is_empty() {
        return Err(Error::Option {
            option: "compare".into(),
            message: "needs at least one strategy and one budget".into(),
        });
    }
    let spp = opts.spp.unwrap_or(scene.settings.spp).max(1);
    let ref_spp = opts.reference_spp.unwrap_or(8 * spp).max(spp);
    let base = RenderOptions {
        spp: Some(spp),
        resolution: opts.resolution,
        seed: opts.seed,
        vis_samples: opts.vis_samples,
        gradient_spp: opts.gradient_spp,
        ..Default::default()
    };
    let (w, h) = opts
        .resolution
        .unwrap_or((scene.camera.width, scene.camera.height));
    let (reference, reference_time) =
        cached_reference(scene, accel, &base, ref_spp, (w, h), &opts.out_dir)?;
    progress(&format!(
        "reference: {ref_spp} spp ({reference_time:.1} s when rendered)"
    ));

    // The full render every adaptive run is measured against.
    let (full, full_time) = timed_render(scene, accel, &base)?;
    progress(&format!("full render: {spp} spp, {full_time:.2} s"));
    let mut runs = vec![full_run("full", full, spp, full_time)];

    let mut gradient_times = Vec::new();
    for &strategy in &opts.strategies {
        for &budget in &opts.budgets {
            let settings = Settings::new(strategy, budget);
            let out = render_adaptive(
                scene,
                accel,
                &base,
                &settings,
                Interpolation::Gradient,
                &|_, _| {},
            )?;
            let st = out.stats;
            progress(&format!(
                "{} at {:.0}%: {} samples, {:.2} s",
                strategy.name(),
                budget * 100.0,
                out.samples.samples.len(),
                st.wall_s
            ));
            if strategy == Strategy::Gradient {
                gradient_times.push((budget, st.wall_s));
            }
            runs.push(adaptive_run(
                strategy.name().into(),
                RunKind::Adaptive { budget },
                out,
            ));
        }
    }

    // How much shorter than the reference render itself the gradient runs are.
    // (Only when the cached render time is known.)
    let against_reference = (reference_time > 0.0 && !gradient_times.is_empty()).then(|| {
        let list = gradient_times
            .iter()
            .map(|&(budget, t)| format!("{:.0}%: {:.1}×", budget * 100.0, reference_time / t))
            .collect::<Vec<_>>()
            .join(", ");
        format!("gradient's wall time against the reference render ({reference_time:.1} s): {list} shorter.")
    });
    // Equal wall time: every pixel rendered, with as many samples as the gradient
    // strategy's time buys.
    for (budget, t_grad) in gradient_times {
        let spp_eq = ((spp as f64 * t_grad / full_time).round() as u32).max(1);
        let equal_time = RenderOptions {
            spp: Some(spp_eq),
            ..base.clone()
        };
        let (out, secs) = timed_render(scene, accel, &equal_time)?;
        progress(&format!(
            "equal time as gradient at {:.0}%: {spp_eq} spp, {secs:.2} s",
            budget * 100.0
        ));
        runs.push(full_run("uniform-all-pixels", out, spp_eq, secs));
    }

    // Sec. 8: 1% of the pixels on a regular grid, gradient vs linear interpolation.
    // The paper evaluates these few pixels with dense light sampling ("we must have
    // accurate values at the image pixels"): here at the reference's spp, a quarter
    // of the camera samples carrying the gradient with 32 shadow rays per line. The
    // grid is 1% of the image, so this costs a few percent of the reference.
    let grid_opts = RenderOptions {
        spp: Some(ref_spp),
        gradient_spp: Some((ref_spp / 4).max(1)),
        vis_samples: Some(opts.vis_samples.unwrap_or(0).max(32)),
        ..base.clone()
    };
    for interp in [Interpolation::Linear, Interpolation::Gradient] {
        let settings = Settings::new(Strategy::Uniform, 0.01);
        let out = render_adaptive(scene, accel, &grid_opts, &settings, interp, &|_, _| {})?;
        runs.push(adaptive_run(
            format!("1% grid, {} interpolation", interp.name()),
            RunKind::Interpolation { budget: 0.01 },
            out,
        ));
    }

    // Sec. 8 is about soft shadows on the ground plane: also score the grid runs on
    // the surface that covers the most pixels (the ground in three_spheres_env).
    // Pixels within one grid spacing of another surface are left out: there the
    // grid cannot place the silhouette (both interpolations show the same blocky
    // outline) and Sec. 8 is about the shading and shadows in between.
    let mut notes = Vec::new();
    let spacing = (1.0f32 / 0.01).sqrt().ceil() as usize;
    let surface = largest_surface(scene, accel, &base)?
        .map(|(id, mask)| (id, erode(&mask, w as usize, h as usize, spacing)))
        .filter(|(_, mask)| mask.contains(&true));
    if let Some((id, mask)) = surface {
        let pick = |v: &[Vec3]| -> Vec<Vec3> {
            v.iter()
                .zip(&mask)
                .filter(|(_, &m)| m)
                .map(|(c, _)| *c)
                .collect()
        };
        let reference_on_mask = pick(&reference);
        let n = reference_on_mask.len();
        let masked = |img: &[Vec3]| crate::output::metrics::rmse(&pick(img), &reference_on_mask);
        // The last two runs are the grid's, linear then gradient.
        let grid = &runs[runs.len() - 2..];
        let (lin, grad) = (masked(&grid[0].image)?, masked(&grid[1].image)?);
        let line = format!(
            "Sec. 8, 1% grid on the largest surface (shape {id}, the {n} pixels more than {spacing} px from any other surface): RMSE linear {lin:.4e}, gradient {grad:.4e} ({:.2}×).",
            grad / lin.max(f32::MIN_POSITIVE)
        );
        progress(&line);
        notes.push(line);
    }

    let input = ReportInput {
        scene: scene.name(),
        width: w as usize,
        height: h as usize,
        reference,
        reference_time_s: full_time,
        reference_spp: ref_spp,
        exposure: 0.0,
        runs,
        notes: [
            Some(format!(
                "Reference: every pixel at {ref_spp} spp, with random numbers independent of every run ({reference_time:.1} s when rendered). Speed-ups are against the full render at {spp} spp per pixel ({full_time:.2} s), \
                 the same number of samples per evaluated point as the adaptive runs."
            )),
            against_reference,
            Some("Adaptive runs evaluate the renderer (path tracing with analytic gradients: direct light, soft shadows and the indirect term) at the quadtree's \
             samples and reconstruct the pixels by Sibson C1 interpolation with those gradients; overhead = quadtree + reconstruction."
                .into()),
        ]
        .into_iter()
        .flatten()
        .chain(notes)
        .collect(),
    };
    report::write_report(&opts.out_dir, &input)
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
fn largest_surface(
    scene: &Scene,
    accel: &Accel,
    base: &RenderOptions,
) -> Result<Option<(u32, Vec<bool>)>> {
    let ids = render(
        scene,
        accel,
        &RenderOptions {
            spp: Some(1),
            max_depth: Some(1),
            aovs: true,
            gradients: false,
            ..base.clone()
        },
        &|_, _| {},
    )?
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

/// Every pixel rendered with `opts`, and the wall time it took.
fn timed_render(scene: &Scene, accel: &Accel, opts: &RenderOptions) -> Result<(RenderOutput, f64)> {
    let t = Instant::now();
    let out = render(scene, accel, opts, &|_, _| {})?;
    Ok((out, t.elapsed().as_secs_f64()))
}

/// A report run of a full render at `spp` samples per pixel.
fn full_run(label: &str, out: RenderOutput, spp: u32, secs: f64) -> Run {
    Run {
        label: label.into(),
        kind: RunKind::EqualTime { spp },
        samples: out.width * out.height * spp as usize,
        wall_time_s: secs,
        overhead_s: 0.0,
        image: out.beauty,
        sample_positions: Vec::new(),
    }
}

/// A report run of an adaptive render (its overhead: quadtree + reconstruction).
fn adaptive_run(label: String, kind: RunKind, out: AdaptiveRender) -> Run {
    Run {
        label,
        kind,
        samples: out.samples.samples.len(),
        wall_time_s: out.stats.wall_s,
        overhead_s: out.stats.quadtree_s + out.stats.reconstruct_s,
        image: out.reconstruction.image,
        sample_positions: out.samples.samples.iter().map(|s| s.pos).collect(),
    }
}

/// The reference image, rendered once and cached as
/// `reference-<spp>spp-<w>x<h>-seed<s>.exr` with its render time in a `.txt` sidecar.
///
/// Its random numbers come from a seed of its own (derived from the runs' seed):
/// with the runs' seed, its first `spp` samples per pixel would be the full render's
/// very samples, and the full and equal-time renders would share a quarter or more of
/// their noise with the reference — their error would look ~25% smaller than it is.
fn cached_reference(
    scene: &Scene,
    accel: &Accel,
    base: &RenderOptions,
    spp: u32,
    (w, h): (u32, u32),
    dir: &Path,
) -> Result<(Vec<Vec3>, f64)> {
    let seed = crate::math::sampler::hash2(base.seed.unwrap_or(scene.settings.seed), 0x7265_6665);
    let stem = format!("reference-{spp}spp-{w}x{h}-seed{seed}");
    let exr = dir.join(format!("{stem}.exr"));
    let meta = dir.join(format!("{stem}.txt"));
    if let (Ok(img), Ok(text)) = (
        crate::output::read_exr(&exr),
        std::fs::read_to_string(&meta),
    ) {
        if let (Some(r), Some(g), Some(b)) = (img.channel("R"), img.channel("G"), img.channel("B"))
        {
            if img.width == w as usize && img.height == h as usize {
                let pixels = r
                    .data
                    .iter()
                    .zip(&g.data)
                    .zip(&b.data)
                    .map(|((&r, &g), &b)| Vec3::new(r, g, b))
                    .collect();
                return Ok((pixels, text.trim().parse().unwrap_or(0.0)));
            }
        }
    }
    let reference = RenderOptions {
        spp: Some(spp),
        seed: Some(seed),
        ..base.clone()
    };
    let (out, secs) = timed_render(scene, accel, &reference)?;
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    crate::output::write_exr(&exr, &super::output_set::image_of_render(&out))?;
    crate::output::write_atomic(&meta, |f| {
        use std::io::Write;
        writeln!(f, "{secs}").map_err(|e| e.to_string())
    })?;
    Ok((out.beauty, secs))
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
