//! `gradtrace render`: scene file → BVH → full or adaptive render → EXR + PNG.

use super::adaptive::render_adaptive;
use super::output_set::{image_of_reconstruction, image_of_render, output_paths, write_output_set};
use super::progress::{Phase, ProgressMode};
use super::{memory, with_threads};
use crate::adaptive::Settings;
use crate::denoise;
use crate::math::Vec3;
use crate::output::{names::RGB, OutputImage};
use crate::reconstruct::Interpolation;
use crate::render::{self, RenderOptions, RenderOutput};
use crate::{Error, Result};
use std::borrow::Cow;
use std::fmt;
use std::path::PathBuf;
use std::time::Instant;

/// One `render` run as the command line describes it.
#[derive(Clone, Debug)]
pub struct RenderJob {
    pub scene: PathBuf,
    /// The EXR path; the PNG shares its stem (default `out/<scene-stem>.exr`).
    pub out: Option<PathBuf>,
    pub options: RenderOptions,
    /// Adaptive sampling: where the samples go and how pixels are rebuilt.
    pub adaptive: Option<(Settings, Interpolation)>,
    /// Full renders: denoise the beauty with OIDN (`denoise::denoise`).
    pub denoise: bool,
    /// Worker threads (default: all cores); never changes the image.
    pub threads: Option<u32>,
    /// Refuse runs estimated to need more bytes than this (default: 90 % of the
    /// memory available).
    pub max_memory: Option<u64>,
    pub progress: ProgressMode,
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
        /// Wall time of the denoiser, when it ran.
        denoise_s: Option<f64>,
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
            SummaryKind::Full {
                spp,
                seconds,
                rays,
                denoise_s,
            } => {
                let rate = if *seconds > 0.0 {
                    format!("{:.2} Mrays/s", *rays as f64 / seconds / 1e6)
                } else {
                    "- Mrays/s".into()
                };
                write!(f, "{spp} spp, {seconds:.3} s, {rate}")?;
                if let Some(d) = denoise_s {
                    write!(f, ", denoised in {d:.3} s")?;
                }
            }
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

/// Renders `job.scene` and writes the EXR + PNG set. The output paths are settled
/// before any work, so a bad `--out` costs nothing.
pub fn run(job: &RenderJob) -> Result<RenderSummary> {
    let stem = job
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let (exr, png) = output_paths(job.out.as_deref(), &stem)?;
    if job.adaptive.is_some() && job.options.gradients {
        return Err(Error::Option {
            option: "--gradients".into(),
            message: "adaptive renders (--strategy) compute the gradient at their samples and \
                      reconstruct with it; the per-pixel grad.* layers come from full renders: \
                      drop --gradients or --strategy"
                .into(),
        });
    }
    if job.denoise {
        check_denoise(job)?;
    }
    let scene = crate::scene::load(&job.scene)?;
    let (w, h) = job.options.resolution_of(&scene);
    let pixels = u64::from(w) * u64::from(h);
    let bytes = match &job.adaptive {
        None => memory::full_render_bytes(pixels, &job.options),
        Some((s, _)) => memory::adaptive_render_bytes(pixels, s.budget, &job.options),
    };
    let what = format!("a {w}x{h} render");
    memory::check(bytes, job.max_memory, &what, "--width/--height/--budget")?;
    let accel = crate::accel::Accel::build(&scene.meshes, &scene.spheres);
    with_threads(job.threads, || match &job.adaptive {
        None => {
            let phase = Phase::new(job.progress, "render", w as u64 * h as u64, "pixels");
            let out = render::render(&scene, &accel, &job.options, &phase.callback())?;
            drop(phase);
            let (image, beauty, denoise_s) = full_image(&out, job.denoise)?;
            write_output_set(&image, &beauty, &exr, &png)?;
            Ok(RenderSummary {
                width: out.width,
                height: out.height,
                exr,
                png,
                kind: SummaryKind::Full {
                    spp: out.spp,
                    seconds: out.stats.wall_time.as_secs_f64(),
                    rays: out.stats.rays,
                    denoise_s,
                },
            })
        }
        Some((settings, interpolation)) => {
            let phase = Phase::new(job.progress, settings.strategy.name(), 0, "samples");
            let out = render_adaptive(
                &scene,
                &accel,
                &job.options,
                settings,
                *interpolation,
                &phase.callback(),
            )?;
            drop(phase);
            let rec = &out.reconstruction;
            let mut image = image_of_reconstruction(rec);
            if job.options.aovs {
                add_aovs(&mut image, &scene, &accel, &job.options)?;
            }
            write_output_set(&image, &rec.image, &exr, &png)?;
            Ok(RenderSummary {
                width: rec.width,
                height: rec.height,
                exr,
                png,
                kind: SummaryKind::Adaptive {
                    settings: *settings,
                    samples: out.samples.samples.len(),
                    seconds: out.stats.wall_s,
                    quadtree_s: out.stats.quadtree_s,
                    reconstruct_s: out.stats.reconstruct_s,
                },
            })
        }
    })?
}

/// The AOV layers of an adaptive render (normal, depth, albedo, object id), from
/// one camera ray per pixel: what the reconstructed radiance sits on, at a cost of
/// one primary ray and hit per pixel (a 256-spp adaptive sample costs hundreds).
fn add_aovs(
    image: &mut crate::output::OutputImage,
    scene: &crate::scene::Scene,
    accel: &crate::accel::Accel,
    opts: &RenderOptions,
) -> Result<()> {
    let gbuffer = render::render(
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
    )?;
    // Every layer but the beauty (`R,G,B`) and the one-sample variance.
    let aovs = image_of_render(&gbuffer)
        .channels
        .into_iter()
        .filter(|c| c.name.contains('.') && !c.name.starts_with(crate::output::names::VARIANCE));
    image.channels.extend(aovs);
    Ok(())
}

/// Fails before any work where `--denoise` cannot run.
fn check_denoise(job: &RenderJob) -> Result<()> {
    let message = if job.adaptive.is_some() {
        "denoises full renders only, not --strategy reconstructions"
    } else if !denoise::available() {
        denoise::unavailable_reason()
    } else {
        return Ok(());
    };
    Err(Error::Option {
        option: "--denoise".into(),
        message: message.into(),
    })
}

/// The render's planes; with `denoise` the OIDN-denoised beauty (guided by the
/// albedo and normal AOVs when rendered) becomes `R,G,B`, the noisy one stays
/// as `noisy.R/G/B`; returns the planes, the beauty for the PNG and the
/// denoiser's wall time.
fn full_image(
    out: &RenderOutput,
    denoise: bool,
) -> Result<(OutputImage, Cow<'_, [Vec3]>, Option<f64>)> {
    let mut image = image_of_render(out);
    if !denoise {
        return Ok((image, Cow::Borrowed(&out.beauty), None));
    }
    let t0 = Instant::now();
    let (albedo, normal) = (out.albedo.as_deref(), out.normal.as_deref());
    let clean: Vec<Vec3> = denoise::denoise(&out.beauty, albedo, normal, out.width, out.height)?;
    let seconds = t0.elapsed().as_secs_f64();
    for ch in image
        .channels
        .iter_mut()
        .filter(|c| RGB.contains(&c.name.as_str()))
    {
        ch.name = format!("noisy.{}", ch.name);
    }
    image.push_vec3("", RGB, &clean);
    Ok((image, Cow::Owned(clean), Some(seconds)))
}
