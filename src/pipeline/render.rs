//! `gradtrace render`: scene file → BVH → full (whole, a tile, a sample range,
//! time-limited, resumed), noise-adaptive or adaptive render → EXR + PNG with the
//! run's provenance in the EXR header.

use super::adaptive::render_adaptive;
use super::gdomain::GradientDomain;
use super::merge::{attr, merge_sample_ranges, Part};
use super::output_set::{
    image_of_reconstruction, image_of_render, output_paths, write_output_set_with_header,
};
use super::progress::{Phase, ProgressMode};
use super::{memory, with_threads};
use crate::adaptive::Settings;
use crate::denoise;
use crate::math::Vec3;
use crate::output::names::RGB;
use crate::output::{ExrHeader, OutputImage};
use crate::reconstruct::poisson::Norm;
use crate::reconstruct::Interpolation;
use crate::render::noise_adaptive::{render_noise_adaptive, NoiseAdaptive};
use crate::render::{self, Crop, Passes, RenderOptions, RenderOutput};
use crate::scene::Scene;
use crate::{Error, Result};
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Instant;

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
    /// Refuse runs estimated to need more bytes than this (default: 90 % of the
    /// memory available).
    pub max_memory: Option<u64>,
    /// Full renders: denoise the beauty with OIDN (`denoise::denoise`).
    pub denoise: bool,
    /// Full renders: with gradients, reconstruct in the gradient domain
    /// (`gdomain::reconstruct`) with this norm.
    pub reconstruct: Option<Norm>,
    /// With `reconstruct`: place the samples by `gdomain::metric` (a uniform
    /// quarter of `--spp`, the rest where noise, gradient and unexplained contrast
    /// are) instead of `--spp` in every pixel.
    pub dense_adaptive: bool,
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
        /// The denoiser's wall time, with `--denoise`.
        denoise_s: Option<f64>,
        /// With `--gradients`: their share of the tracing time (`RenderStats`).
        gradient_share: Option<f64>,
        /// The gradient-domain solve's norm and wall time, with `--reconstruct`.
        reconstruct: Option<(Norm, f64)>,
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
        /// The G-buffer pass and the denoiser's wall time, with `--denoise`.
        denoise_s: Option<f64>,
        /// The gradients' share of the estimates' tracing time.
        gradient_share: Option<f64>,
    },
}

impl fmt::Display for RenderSummary {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}x{}, ", self.width, self.height)?;
        match &self.kind {
            SummaryKind::Full {
                spp,
                seconds,
                rays,
                denoise_s,
                gradient_share,
                reconstruct,
            } => {
                write!(f, "{spp} spp, {seconds:.3} s, {}", rate(*rays, *seconds))?;
                if let Some(g) = gradient_share {
                    write!(f, " (gradients {:.0} % of the time)", g * 100.0)?;
                }
                if let Some(d) = denoise_s {
                    write!(f, ", denoised in {d:.3} s")?;
                }
                if let Some((norm, d)) = reconstruct {
                    write!(f, ", {} reconstruction in {d:.3} s", norm.name())?;
                }
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
                denoise_s,
                gradient_share,
            } => {
                write!(
                    f,
                    "{} at budget {}: {samples} samples, {seconds:.3} s (quadtree {quadtree_s:.3} s, reconstruction {reconstruct_s:.3} s",
                    settings.strategy.name(),
                    settings.budget
                )?;
                if let Some(g) = gradient_share {
                    write!(f, "; gradients {:.0} % of the tracing", g * 100.0)?;
                }
                write!(f, ")")?;
                if let Some(d) = denoise_s {
                    write!(f, ", denoised in {d:.3} s")?;
                }
            }
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

/// The exit status of a render that Ctrl-C ended early after writing what it
/// had (the shell's 128 + SIGINT), so that a script can tell it from a render
/// that ran to its end.
pub const EXIT_INTERRUPTED: u8 = 130;

/// What such a render says on stderr.
pub fn interrupted_note() -> String {
    format!("interrupted: wrote the passes finished before Ctrl-C (exit status {EXIT_INTERRUPTED})")
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
    check_combinations(job)?;
    let scene = crate::memory::limited(job.max_memory, || crate::scene::load(&job.scene))?;
    let (w, h) = job.options.resolution_of(&scene);
    let pixels = u64::from(w) * u64::from(h);
    let bytes = match &job.adaptive {
        None => memory::full_render_bytes(
            pixels,
            &job.options,
            job.passes.time_limit.is_some() || job.noise_adaptive.is_some() || job.dense_adaptive,
        ),
        Some((s, _)) => memory::adaptive_render_bytes(pixels, s.budget, &job.options),
    };
    let what = format!("a {w}x{h} render");
    memory::check_render(
        bytes,
        &scene,
        job.max_memory,
        &what,
        "--width/--height/--budget",
    )?;
    let accel = crate::accel::Accel::build(&scene.meshes, &scene.spheres);
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
    opts.gradients |= job.reconstruct.is_some();
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
        check_resume_channels(scene, accel, &opts, prev)?;
    }
    let phase = match job.passes.time_limit {
        Some(_) => Phase::new(job.progress, "render", 0, "ms"),
        None => Phase::new(job.progress, "render", w as u64 * h as u64, "pixels"),
    };
    let out = if job.dense_adaptive {
        let spp = opts.spp.unwrap_or(scene.settings.spp);
        let dense = super::gdomain::DenseAdaptive::new(spp);
        super::gdomain::render_dense_adaptive(scene, accel, &opts, &dense)?
    } else {
        render::render_passes(scene, accel, &opts, &job.passes, &phase.callback())?
    };
    drop(phase);
    let header = provenance(scene, &opts, &job.command, &out)?;
    let (mut image, mut denoised, denoise_s) = full_image(&out, job.denoise)?;
    let mut reconstruct = None;
    if let Some(norm) = job.reconstruct {
        let t0 = Instant::now();
        let solved = super::gdomain::reconstruct(&out, &GradientDomain::new(norm))?;
        reconstruct = Some((norm, t0.elapsed().as_secs_f64()));
        swap_in_denoised(&mut image, &solved);
        denoised = Some(solved);
    }
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
    let beauty = match denoised {
        Some(clean) => clean,
        None => image.vec3("", RGB).unwrap_or_default(),
    };
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
            denoise_s,
            gradient_share: out.stats.gradient_share,
            reconstruct,
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
    let (w, h) = opts.resolution_of(scene);
    if prev.display() != (w as usize, h as usize) {
        let (pw, ph) = prev.display();
        return Err(err(format!(
            "cannot resume: it is a part of a {pw}x{ph} image, but this render is {w}x{h}; expected a file rendered at this render's size"
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

/// Refuses, before any sample is traced, a resume file whose channels differ
/// from those this render writes (a plain render's file lacks the `merge.*`
/// planes; it used to fail at the merge, after every remaining sample). The
/// channels are found by rendering one sample of one pixel: which planes a
/// render makes depends on its options in many places, and asking the renderer
/// is the one answer that cannot drift from them.
fn check_resume_channels(
    scene: &Scene,
    accel: &crate::accel::Accel,
    opts: &RenderOptions,
    prev: &Part,
) -> Result<()> {
    let mut probe = opts.clone();
    let first = opts.sample_range.map_or(0, |(a, _)| a);
    probe.sample_range = Some((first, first + 1));
    let c = prev.window();
    probe.crop = Some(Crop {
        x0: c.x0,
        y0: c.y0,
        x1: c.x0 + 1,
        y1: c.y0 + 1,
    });
    let out = render::render(scene, accel, &probe, &|_, _| {})?;
    let names = |img: &OutputImage| {
        img.channels
            .iter()
            .map(|c| c.name.clone())
            .collect::<std::collections::BTreeSet<_>>()
    };
    let (want, have) = (names(&image_of_render(&out)), names(&prev.image));
    if want == have {
        return Ok(());
    }
    let missing: Vec<&String> = want.difference(&have).collect();
    let extra: Vec<&String> = have.difference(&want).collect();
    Err(Error::Asset {
        path: prev.path.clone(),
        message: format!(
            "cannot resume: lacks the channels {missing:?} and holds {extra:?} beyond those this render writes; expected the output of a --time-limit or --spp-range render with the same options"
        ),
    })
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
        (attr::VERSION.into(), super::VERSION.into()),
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
        (attr::VERSION.into(), super::VERSION.into()),
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
    let mut image = image_of_reconstruction(rec);
    let mut denoised = None;
    let mut denoise_s = None;
    if job.options.aovs || job.denoise {
        let t0 = Instant::now();
        let gbuffer = gbuffer(scene, accel, &job.options)?;
        if job.options.aovs {
            add_aovs(&mut image, &gbuffer);
        }
        if job.denoise {
            let clean = denoise_with(&rec.image, &gbuffer)?;
            swap_in_denoised(&mut image, &clean);
            denoised = Some(clean);
            denoise_s = Some(t0.elapsed().as_secs_f64());
        }
    }
    let shown = denoised.as_deref().unwrap_or(&rec.image);
    write_output_set_with_header(&image, &header, shown, exr, png)?;
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
            denoise_s,
            gradient_share: out.stats.gradient_share,
        },
    })
}

/// The AOVs of an adaptive render (normal, depth, albedo, object id), from one
/// camera ray per pixel: what the reconstructed radiance sits on, at a cost of one
/// primary ray and hit per pixel (a 256-spp adaptive sample costs hundreds). Also
/// the denoiser's guides when a reconstruction is denoised.
pub(crate) fn gbuffer(
    scene: &crate::scene::Scene,
    accel: &crate::accel::Accel,
    opts: &RenderOptions,
) -> Result<RenderOutput> {
    render::render(
        scene,
        accel,
        &RenderOptions {
            spp: Some(1),
            max_depth: Some(1),
            aovs: true,
            gradients: false,
            ..opts.clone()
        },
        &|_, _| {},
    )
}

/// Every layer of `gbuffer` but its beauty (`R,G,B`) and its one-sample variance.
fn add_aovs(image: &mut OutputImage, gbuffer: &RenderOutput) {
    let aovs = image_of_render(gbuffer)
        .channels
        .into_iter()
        .filter(|c| c.name.contains('.') && !c.name.starts_with(crate::output::names::VARIANCE));
    image.channels.extend(aovs);
}

/// `beauty` denoised by OIDN, guided by the albedo and normal AOVs of `gbuffer`
/// (the render itself, or a one-ray-per-pixel pass for a reconstruction).
pub(crate) fn denoise_with(beauty: &[Vec3], gbuffer: &RenderOutput) -> Result<Vec<Vec3>> {
    denoise::denoise(
        beauty,
        gbuffer.albedo.as_deref(),
        gbuffer.normal.as_deref(),
        gbuffer.width,
        gbuffer.height,
    )
}

/// The denoised (or gradient-domain) beauty becomes `R,G,B`; the noisy one
/// stays as `noisy.R/G/B`.
fn swap_in_denoised(image: &mut OutputImage, clean: &[Vec3]) {
    for ch in image
        .channels
        .iter_mut()
        .filter(|c| RGB.contains(&c.name.as_str()))
    {
        ch.name = format!("noisy.{}", ch.name);
    }
    image.push_vec3("", RGB, clean);
}

/// Fails before any work on options that do not go together.
fn check_combinations(job: &RenderJob) -> Result<()> {
    let bad = |option: &str, message: &str| {
        Err(Error::Option {
            option: option.into(),
            message: message.into(),
        })
    };
    if job.adaptive.is_some() && job.options.gradients {
        return bad(
            "--gradients",
            "adaptive renders (--strategy) compute the gradient at their samples and \
             reconstruct with it; the per-pixel grad.* layers come from full renders: \
             drop --gradients or --strategy",
        );
    }
    if job.dense_adaptive && job.reconstruct.is_none() {
        return bad(
            "--dense-adaptive",
            "places the samples for a gradient-domain solve: add --reconstruct poisson-l1 or poisson-l2",
        );
    }
    if job.reconstruct.is_some() {
        let why = if job.adaptive.is_some() {
            Some("reconstructs full renders, not --strategy ones (drop one of them)")
        } else if job.denoise {
            Some("replaces R,G,B as --denoise does: use one of them")
        } else if job.noise_adaptive.is_some() {
            Some("needs every pixel at --spp, not --noise-threshold renders")
        } else if job.resume.is_some()
            || job.options.sample_range.is_some()
            || job.tile.is_some()
            || job.passes.time_limit.is_some()
        {
            Some("solves over the whole image once: not with --resume, --spp-range, --tile or --time-limit")
        } else if !job.options.aovs {
            Some("needs the AOVs (object id, depth, normal, albedo, variance): drop --no-aovs")
        } else {
            None
        };
        if let Some(why) = why {
            return bad("--reconstruct", why);
        }
    }
    if job.denoise {
        if job.noise_adaptive.is_some() {
            return bad(
                "--denoise",
                "denoises full renders and --strategy reconstructions, not \
                 --noise-threshold renders (their pixels carry unequal noise)",
            );
        }
        if job.resume.is_some() || job.options.sample_range.is_some() {
            return bad(
                "--denoise",
                "denoise the merged render, not one of its sample ranges",
            );
        }
        if !denoise::available() {
            return bad("--denoise", denoise::unavailable_reason());
        }
    }
    Ok(())
}

/// The render's planes; with `denoise` the OIDN-denoised beauty (guided by the
/// albedo and normal AOVs when rendered) becomes `R,G,B`, the noisy one stays as
/// `noisy.R/G/B`; returns the planes, the denoised beauty for the PNG and the
/// denoiser's wall time.
fn full_image(
    out: &RenderOutput,
    denoise: bool,
) -> Result<(OutputImage, Option<Vec<Vec3>>, Option<f64>)> {
    let mut image = image_of_render(out);
    if !denoise {
        return Ok((image, None, None));
    }
    let t0 = Instant::now();
    let clean = denoise_with(&out.beauty, out)?;
    let seconds = t0.elapsed().as_secs_f64();
    swap_in_denoised(&mut image, &clean);
    Ok((image, Some(clean), Some(seconds)))
}
