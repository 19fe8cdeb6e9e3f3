//! `gradtrace render`: scene file → BVH → full (whole, a tile, a sample range,
//! time-limited, resumed), noise-adaptive or adaptive render → EXR + PNG with the
//! run's provenance in the EXR header.

use super::adaptive::render_adaptive;
use super::merge::{attr, merge_sample_ranges, Part};
use super::output_set::{
    image_of_reconstruction, image_of_render, output_paths, write_output_set_with_header,
};
use super::progress::{Phase, ProgressMode};
use super::{load, with_threads};
use crate::adaptive::Settings;
use crate::output::names::RGB;
use crate::output::ExrHeader;
use crate::reconstruct::Interpolation;
use crate::render::noise_adaptive::{render_noise_adaptive, NoiseAdaptive};
use crate::render::{self, Crop, Passes, RenderOptions, RenderOutput};
use crate::scene::Scene;
use crate::{Error, Result};
use std::fmt;
use std::path::{Path, PathBuf};

/// The crate version and the git commit it was built from (`build.rs`).
pub const VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (",
    env!("GRADTRACE_GIT_COMMIT"),
    ")"
);

/// The sample cap of a `--time-limit` render without `--spp`.
pub const TIME_LIMIT_MAX_SPP: u32 = 1 << 20;

/// One `render` run as the command line describes it.
#[derive(Clone, Debug)]
pub struct RenderJob {
    pub scene: PathBuf,
    /// The EXR path; the PNG shares its stem (default `out/<scene-stem>.exr`).
    pub out: Option<PathBuf>,
    pub options: RenderOptions,
    /// Adaptive sampling: where the samples go and how pixels are rebuilt.
    pub adaptive: Option<(Settings, Interpolation)>,
    /// Worker threads (default: all cores); never changes the image.
    pub threads: Option<u32>,
    pub progress: ProgressMode,
    /// Time limit and cancel flag (Ctrl-C) of a render in passes.
    pub passes: Passes,
    /// Continue the render in this EXR (a `--time-limit` or `--spp-range` output)
    /// up to `--spp` or the time limit; the default `--out`.
    pub resume: Option<PathBuf>,
    /// Per-pixel adaptive sample counts (Cycles' sampler) instead of a fixed spp.
    pub noise_adaptive: Option<NoiseAdaptive>,
    /// Render only tile K of N (bands of rows, [`Crop::tile`]).
    pub tile: Option<(u32, u32)>,
    /// The command line, recorded in the EXR header.
    pub command: String,
}

/// What a run did, for the one summary line.
#[derive(Clone, Debug)]
pub struct RenderSummary {
    pub width: usize,
    pub height: usize,
    pub exr: PathBuf,
    pub png: PathBuf,
    pub kind: SummaryKind,
}

#[derive(Clone, Debug)]
pub enum SummaryKind {
    Full {
        spp: u32,
        seconds: f64,
        rays: u64,
    },
    NoiseAdaptive {
        mean_spp: f64,
        max_spp: u32,
        seconds: f64,
        rays: u64,
    },
    Adaptive {
        settings: Settings,
        samples: usize,
        seconds: f64,
        quadtree_s: f64,
        reconstruct_s: f64,
    },
}

impl fmt::Display for RenderSummary {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}x{}, ", self.width, self.height)?;
        match &self.kind {
            SummaryKind::Full { spp, seconds, rays } => {
                write!(f, "{spp} spp, {seconds:.3} s, {}", rate(*rays, *seconds))?;
            }
            SummaryKind::NoiseAdaptive {
                mean_spp,
                max_spp,
                seconds,
                rays,
            } => write!(
                f,
                "noise-adaptive: mean {mean_spp:.1} spp (at most {max_spp}), {seconds:.3} s, {}",
                rate(*rays, *seconds)
            )?,
            SummaryKind::Adaptive {
                settings,
                samples,
                seconds,
                quadtree_s,
                reconstruct_s,
            } => write!(
                f,
                "{} at budget {}: {samples} samples, {seconds:.3} s (quadtree {quadtree_s:.3} s, reconstruction {reconstruct_s:.3} s)",
                settings.strategy.name(),
                settings.budget
            )?,
        }
        write!(
            f,
            ", wrote {} and {}",
            self.exr.display(),
            self.png.display()
        )
    }
}

fn rate(rays: u64, seconds: f64) -> String {
    if seconds > 0.0 {
        format!("{:.2} Mrays/s", rays as f64 / seconds / 1e6)
    } else {
        "- Mrays/s".into()
    }
}

/// Renders `job.scene` and writes the EXR + PNG set. The output paths are settled
/// before any work, so a bad `--out` costs nothing; so are the resume file and the
/// crop and sample range (checked against the scene before tracing).
pub fn run(job: &RenderJob) -> Result<RenderSummary> {
    let stem = job
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let out = job.out.as_deref().or(job.resume.as_deref());
    let (exr, png) = output_paths(out, &stem)?;
    let resume = job.resume.as_deref().map(Part::read).transpose()?;
    let (scene, accel) = load(&job.scene)?;
    with_threads(job.threads, || {
        if let Some((settings, interpolation)) = &job.adaptive {
            return run_adaptive(job, &scene, &accel, settings, *interpolation, &exr, &png);
        }
        if let Some(settings) = &job.noise_adaptive {
            return run_noise_adaptive(job, &scene, &accel, settings, &exr, &png);
        }
        run_full(job, &scene, &accel, resume.as_ref(), &exr, &png)
    })?
}

/// A full render (or a tile, a sample range, a time-limited or resumed one).
fn run_full(
    job: &RenderJob,
    scene: &Scene,
    accel: &crate::accel::Accel,
    resume: Option<&Part>,
    exr: &Path,
    png: &Path,
) -> Result<RenderSummary> {
    let mut opts = job.options.clone();
    let progressive = job.passes.time_limit.is_some() || resume.is_some();
    if progressive || opts.sample_range.is_some() {
        opts.merge_planes = true;
    }
    if job.passes.time_limit.is_some() && opts.spp.is_none() {
        opts.spp = Some(TIME_LIMIT_MAX_SPP);
    }
    let (w, h) = opts.resolution_of(scene);
    if let Some((k, n)) = job.tile {
        let crop = Crop::tile(k, n, w, h).map_err(|message| Error::Option {
            option: "--tile".into(),
            message,
        })?;
        opts.crop = Some(crop);
    }
    if let Some(prev) = resume {
        opts.sample_range = Some(resume_range(scene, &opts, prev)?);
        opts.crop = Some(prev.window());
    }
    let phase = match job.passes.time_limit {
        Some(_) => Phase::new(job.progress, "render", 0, "ms"),
        None => Phase::new(job.progress, "render", w as u64 * h as u64, "pixels"),
    };
    let out = render::render_passes(scene, accel, &opts, &job.passes, &phase.callback())?;
    drop(phase);
    let header = provenance(scene, &opts, &job.command, &out)?;
    let image = image_of_render(&out);
    let (image, header) = match resume {
        None => (image, header),
        Some(prev) => {
            let new = Part {
                path: PathBuf::from("(this render)"),
                image,
                header,
            };
            let merged = merge_sample_ranges(&[prev.clone(), new], exr, &job.command)?;
            (merged.image, merged.header)
        }
    };
    let beauty = image.vec3("", RGB).unwrap_or_default();
    write_output_set_with_header(&image, &header, &beauty, exr, png)?;
    let spp = header
        .get(attr::SPP)
        .and_then(|s| s.parse().ok())
        .unwrap_or(out.spp);
    Ok(RenderSummary {
        width: image.width,
        height: image.height,
        exr: exr.to_path_buf(),
        png: png.to_path_buf(),
        kind: SummaryKind::Full {
            spp,
            seconds: out.stats.wall_time.as_secs_f64(),
            rays: out.stats.rays,
        },
    })
}

/// The samples a resumed render adds: from where `prev` ends up to `--spp`, after
/// checking that `prev` is a render of this scene with these settings.
fn resume_range(scene: &Scene, opts: &RenderOptions, prev: &Part) -> Result<(u32, u32)> {
    let err = |message: String| Error::Asset {
        path: prev.path.clone(),
        message,
    };
    let hash = scene.content_hash()?;
    if prev.attr(attr::SCENE_SHA256)? != hash {
        return Err(err(format!(
            "cannot resume: rendered from a different scene than {} (scene or assets changed)",
            scene.path.display()
        )));
    }
    let key = opts.settings_key(scene)?;
    if prev.attr(attr::SETTINGS)? != key {
        return Err(err(format!(
            "cannot resume: rendered with other settings ({:?}, now {key:?})",
            prev.attr(attr::SETTINGS)?
        )));
    }
    let seed = opts.seed.unwrap_or(scene.settings.seed).to_string();
    if prev.attr(attr::SEED)? != seed {
        return Err(err(format!(
            "cannot resume: rendered with seed {}, now {seed}",
            prev.attr(attr::SEED)?
        )));
    }
    let (_, end) = prev.range()?;
    let spp = opts.spp.unwrap_or(scene.settings.spp);
    if end >= spp {
        return Err(err(format!(
            "already holds samples up to {end}, and --spp is {spp}: raise --spp (or add --time-limit) to continue"
        )));
    }
    Ok((end, spp))
}

/// The EXR header of a render: the provenance attributes and, for a tile, its
/// place in the full image.
pub fn provenance(
    scene: &Scene,
    opts: &RenderOptions,
    command: &str,
    out: &RenderOutput,
) -> Result<ExrHeader> {
    let seed = opts.seed.unwrap_or(scene.settings.seed);
    let range = (out.first_sample, out.first_sample + out.spp);
    let mut attributes: Vec<(String, String)> = vec![
        (attr::VERSION.into(), VERSION.into()),
        (attr::COMMAND.into(), command.into()),
        (attr::SCENE_SHA256.into(), scene.content_hash()?),
        (attr::SPP.into(), out.spp.to_string()),
        (attr::SPP_RANGE.into(), format!("{}:{}", range.0, range.1)),
        (attr::SEED.into(), seed.to_string()),
        (
            attr::RENDER_TIME_S.into(),
            format!("{:.3}", out.stats.wall_time.as_secs_f64()),
        ),
        (attr::SETTINGS.into(), opts.settings_key(scene)?),
    ];
    attributes.sort();
    Ok(ExrHeader {
        display: out.display,
        origin: out.origin,
        attributes,
    })
}

fn run_noise_adaptive(
    job: &RenderJob,
    scene: &Scene,
    accel: &crate::accel::Accel,
    settings: &NoiseAdaptive,
    exr: &Path,
    png: &Path,
) -> Result<RenderSummary> {
    let (w, h) = job.options.resolution_of(scene);
    let total = w as u64 * h as u64 * settings.max_spp as u64;
    let phase = Phase::new(job.progress, "noise-adaptive", total, "samples");
    let out = render_noise_adaptive(scene, accel, &job.options, settings, &phase.callback())?;
    drop(phase);
    let opts = RenderOptions {
        spp: Some(settings.max_spp),
        ..job.options.clone()
    };
    let header = provenance(scene, &opts, &job.command, &out)?;
    write_output_set_with_header(&image_of_render(&out), &header, &out.beauty, exr, png)?;
    let counts = out.spp_map.as_deref().unwrap_or(&[]);
    let mean_spp = counts.iter().map(|&c| c as f64).sum::<f64>() / counts.len().max(1) as f64;
    Ok(RenderSummary {
        width: out.width,
        height: out.height,
        exr: exr.to_path_buf(),
        png: png.to_path_buf(),
        kind: SummaryKind::NoiseAdaptive {
            mean_spp,
            max_spp: out.spp,
            seconds: out.stats.wall_time.as_secs_f64(),
            rays: out.stats.rays,
        },
    })
}

fn run_adaptive(
    job: &RenderJob,
    scene: &Scene,
    accel: &crate::accel::Accel,
    settings: &Settings,
    interpolation: Interpolation,
    exr: &Path,
    png: &Path,
) -> Result<RenderSummary> {
    let phase = Phase::new(job.progress, settings.strategy.name(), 0, "samples");
    let out = render_adaptive(
        scene,
        accel,
        &job.options,
        settings,
        interpolation,
        &phase.callback(),
    )?;
    drop(phase);
    let rec = &out.reconstruction;
    let mut attributes = vec![
        (attr::VERSION.into(), VERSION.into()),
        (attr::COMMAND.into(), job.command.clone()),
        (attr::SCENE_SHA256.into(), scene.content_hash()?),
        (
            attr::SEED.into(),
            job.options.seed.unwrap_or(scene.settings.seed).to_string(),
        ),
        (
            attr::RENDER_TIME_S.into(),
            format!("{:.3}", out.stats.wall_s),
        ),
    ];
    attributes.sort();
    let header = ExrHeader {
        attributes,
        ..ExrHeader::default()
    };
    write_output_set_with_header(&image_of_reconstruction(rec), &header, &rec.image, exr, png)?;
    Ok(RenderSummary {
        width: rec.width,
        height: rec.height,
        exr: exr.to_path_buf(),
        png: png.to_path_buf(),
        kind: SummaryKind::Adaptive {
            settings: *settings,
            samples: out.samples.samples.len(),
            seconds: out.stats.wall_s,
            quadtree_s: out.stats.quadtree_s,
            reconstruct_s: out.stats.reconstruct_s,
        },
    })
}
