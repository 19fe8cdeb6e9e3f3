//! scene → every sampling strategy at several budgets, a cached reference and
//! honest baselines → `out/<scene>/report.{html,json,md}`.
//!
//! What is compared, per the adaptive-sampling issue and the first-order paper's
//! Sec. 8–9: each strategy of `adaptive` at each budget (equal sample counts,
//! reconstructed by gradient-aware C1 interpolation); a full render at the same
//! samples per evaluated point (whose wall time is the speed-up baseline); full
//! renders with fewer samples per pixel at the wall time of the `gradient`
//! strategy (equal-time baselines); and Sec. 8's 1%-of-pixels experiment, gradient
//! against linear interpolation.

use crate::accel::Accel;
use crate::adaptive::{Settings, Strategy};
use crate::output::report::{self, ReportInput, ReportRow, Run, RunKind};
use crate::reconstruct::Interpolation;
use crate::render::adaptive::render_adaptive;
use crate::render::{render, RenderOptions};
use crate::scene::Scene;
use crate::{Error, Result};
use glam::{Vec2, Vec3};
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
            vis_samples: Some(8),
            gradient_spp: None,
            seed: None,
            out_dir,
        }
    }
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
    let t = Instant::now();
    let full = render(scene, accel, &base, &|_, _| {})?;
    let full_time = t.elapsed().as_secs_f64();
    progress(&format!("full render: {spp} spp, {full_time:.2} s"));
    let mut runs = vec![Run {
        label: "full".into(),
        kind: RunKind::EqualTime { spp },
        samples: full.width * full.height * spp as usize,
        wall_time_s: full_time,
        overhead_s: 0.0,
        image: full.beauty,
        sample_positions: Vec::new(),
    }];

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
            runs.push(Run {
                label: strategy.name().into(),
                kind: RunKind::Adaptive { budget },
                samples: out.samples.samples.len(),
                wall_time_s: st.wall_s,
                overhead_s: st.quadtree_s + st.reconstruct_s,
                image: out.reconstruction.image,
                sample_positions: out.samples.samples.iter().map(|s| s.pos).collect(),
            });
        }
    }

    // Equal wall time: every pixel rendered, with as many samples as the gradient
    // strategy's time buys.
    for (budget, t_grad) in gradient_times {
        let spp_eq = ((spp as f64 * t_grad / full_time).round() as u32).max(1);
        let t = Instant::now();
        let out = render(
            scene,
            accel,
            &RenderOptions {
                spp: Some(spp_eq),
                ..base.clone()
            },
            &|_, _| {},
        )?;
        let secs = t.elapsed().as_secs_f64();
        progress(&format!(
            "equal time as gradient at {:.0}%: {spp_eq} spp, {secs:.2} s",
            budget * 100.0
        ));
        runs.push(Run {
            label: "uniform-all-pixels".into(),
            kind: RunKind::EqualTime { spp: spp_eq },
            samples: out.width * out.height * spp_eq as usize,
            wall_time_s: secs,
            overhead_s: 0.0,
            image: out.beauty,
            sample_positions: Vec::new(),
        });
    }

    // Sec. 8: 1% of the pixels on a regular grid, gradient vs linear interpolation.
    for interp in [Interpolation::Linear, Interpolation::Gradient] {
        let settings = Settings::new(Strategy::Uniform, 0.01);
        let out = render_adaptive(scene, accel, &base, &settings, interp, &|_, _| {})?;
        runs.push(Run {
            label: format!("1% grid, {} interpolation", interp.name()),
            kind: RunKind::Interpolation { budget: 0.01 },
            samples: out.samples.samples.len(),
            wall_time_s: out.stats.wall_s,
            overhead_s: out.stats.quadtree_s + out.stats.reconstruct_s,
            image: out.reconstruction.image,
            sample_positions: out
                .samples
                .samples
                .iter()
                .map(|s| s.pos)
                .collect::<Vec<Vec2>>(),
        });
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
        notes: vec![
            format!(
                "Reference: every pixel at {ref_spp} spp ({reference_time:.1} s when rendered). Speed-ups are against the full render at {spp} spp per pixel ({full_time:.2} s), \
                 the same number of samples per evaluated point as the adaptive runs."
            ),
            "Adaptive runs evaluate the renderer (path tracing with analytic gradients of the direct light) at the quadtree's \
             samples and reconstruct the pixels by Sibson C1 interpolation with those gradients; overhead = quadtree + reconstruction."
                .into(),
        ],
    };
    report::write_report(&opts.out_dir, &input)
}

/// The reference image, rendered once and cached as `reference-<spp>spp-<w>x<h>.exr`
/// with its render time in a `.txt` sidecar.
fn cached_reference(
    scene: &Scene,
    accel: &Accel,
    base: &RenderOptions,
    spp: u32,
    (w, h): (u32, u32),
    dir: &Path,
) -> Result<(Vec<Vec3>, f64)> {
    let stem = format!("reference-{spp}spp-{w}x{h}");
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
    let t = Instant::now();
    let out = render(
        scene,
        accel,
        &RenderOptions {
            spp: Some(spp),
            ..base.clone()
        },
        &|_, _| {},
    )?;
    let secs = t.elapsed().as_secs_f64();
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    crate::output::write_exr(&exr, &crate::output::image_from_render(&out))?;
    crate::output::write_atomic(&meta, |f| {
        use std::io::Write;
        writeln!(f, "{secs}").map_err(|e| e.to_string())
    })?;
    Ok((out.beauty, secs))
}
