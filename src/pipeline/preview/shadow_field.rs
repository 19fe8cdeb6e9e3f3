//! `gradtrace preview shadow-field`: precompute (cached) → shade → reference → preview.json.
//!
//! Writes `DIR/<scene>.exr` (`R,G,B` = preview, `reference.R/G/B`, `error.Y`),
//! `DIR/<scene>.png` and `DIR/preview.json`; with `--frames N` one EXR/PNG per frame
//! (`<scene>-fNNN`), all as one set under one render id, `preview.json` (its
//! index) last. Fields are cached under `DIR/cache/` (`pipeline::cache`), keyed
//! by the scene's content hash, every precompute setting and the source's hash.

use crate::accel::Accel;
use crate::math::Vec3;
use crate::output::{self, metrics, OutputImage};
use crate::pipeline::preview::figures::{self, Figures, Reference, Timing};
use crate::pipeline::preview::PreviewSet;
use crate::pipeline::progress::{Phase, ProgressMode};
use crate::preview::shadow_field::{self as sf, deform, Fields, Pose, Receivers, Settings};
use crate::render::{render, RenderOptions};
use crate::scene::{Integrator, Scene};
use crate::{Error, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What `gradtrace preview shadow-field` needs.
#[derive(Clone, Debug)]
pub struct ShadowFieldOptions {
    pub scene: PathBuf,
    /// Output folder (default `out/`).
    pub out_dir: PathBuf,
    /// Render this many frames of the scene's `[animation]` (`Some(0)`: the block's
    /// own `frames`); `None`: the still scene, animation ignored.
    pub frames: Option<u32>,
    /// Samples per pixel the path-traced direct-lighting reference starts at
    /// (default 256); raised until it resolves the preview's bias, up to
    /// `reference_spp_max` (default [`figures::REFERENCE_SPP_MAX`]).
    pub reference_spp: Option<u32>,
    pub reference_spp_max: Option<u32>,
    /// Frames the precompute is amortised over (default [`figures::AMORTISE_FRAMES`]).
    pub amortise_frames: Option<u32>,
    /// Override of the camera resolution.
    pub resolution: Option<(u32, u32)>,
    pub quiet: bool,
    pub settings: Settings,
    /// Read and write the field cache (default true).
    pub cache: bool,
}

impl ShadowFieldOptions {
    pub fn new(scene: impl Into<PathBuf>) -> Self {
        Self {
            scene: scene.into(),
            out_dir: PathBuf::from("out"),
            frames: None,
            reference_spp: None,
            reference_spp_max: None,
            amortise_frames: None,
            resolution: None,
            quiet: false,
            settings: Settings::default(),
            cache: true,
        }
    }
}

/// `preview.json`: see the fields' docs (README).
#[derive(Clone, Debug, Serialize)]
pub struct ShadowFieldSummary {
    pub method: String,
    pub scene: String,
    pub entities: usize,
    /// Receiver points shaded (first hits on lit surfaces, all pixel samples).
    pub points: usize,
    /// Fields precomputation (when cached: the time it took when it was computed).
    pub precompute_s: f64,
    pub precompute_cached: bool,
    /// Shading the image, without precomputation (all threads).
    pub render_s: f64,
    /// The frame's process CPU time (render_s × threads where the OS does not
    /// report it) / (points × entities): CPU µs per point and entity, first-hit
    /// tracing included.
    pub us_per_point_entity: f64,
    pub threads: usize,
    /// Mean of the reference over the scored pixels and channels.
    pub image_mean: f64,
    /// Pixels the RMSE and the figures are taken over: those that neither see
    /// an emitter directly nor touch one that does (`Shaded::scored`).
    pub scored_pixels: usize,
    pub pixels: usize,
    /// Against the converged path-traced direct-lighting reference, over the
    /// scored pixels.
    pub rmse: f64,
    /// The same over every pixel, directly seen lights included.
    pub rmse_all_pixels: f64,
    pub rmse_relative: f64,
    /// Against the reference with the environment replaced by its order-4 projection.
    pub rmse_lowfreq: f64,
    pub rmse_lowfreq_relative: f64,
    /// Bias, equal-error time and speed-ups (`figures`); `frame_s` is `render_s`
    /// plus, with `--frames`, the deforming entities' base-sphere updates.
    #[serde(flatten)]
    pub figures: Figures,
    pub exr: PathBuf,
    pub png: PathBuf,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frames: Option<u32>,
    /// Per frame and deforming entity: base-sphere visibility + extrapolation.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bsv_update_s: Option<f64>,
    /// The full direct precomputation of that entity's field.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub full_field_s: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rmse_worst_frame: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rmse_worst_frame_relative: Option<f64>,
}

/// The command's one summary line.
impl std::fmt::Display for ShadowFieldSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(
            f,
            "shadow-field: {} entities, precompute {:.2} s{}, shading {:.3} s, RMSE {:.3e} ({:.1}% of the mean{}), {}; wrote {}",
            self.entities,
            self.precompute_s,
            if self.precompute_cached { " (cached)" } else { "" },
            self.render_s,
            self.rmse,
            100.0 * self.rmse_relative,
            if self.scored_pixels < self.pixels {
                format!(
                    ", over the {:.0}% of pixels that see no light; {:.3e} over all",
                    100.0 * self.scored_pixels as f64 / self.pixels.max(1) as f64,
                    self.rmse_all_pixels
                )
            } else {
                String::new()
            },
            self.figures.summary(),
            self.exr.display()
        )
    }
}

/// Runs the whole command. See the module doc for what it writes.
pub fn run(opts: &ShadowFieldOptions) -> Result<ShadowFieldSummary> {
    let mut scene = crate::scene::load(&opts.scene)?;
    crate::pipeline::memory::check_scene(&scene, "a shadow-field preview")?;
    // What the method cannot shade (a mirror, an emitting mesh) would come out
    // black or unlit without a word.
    sf::check_shapes(&scene).map_err(|message| Error::Scene {
        path: scene.path.clone(),
        location: "shadow-field preview".into(),
        message,
    })?;
    if let Some((w, h)) = opts.resolution {
        scene.camera = scene
            .camera
            .with_resolution(w, h)
            .map_err(|message| Error::Option {
                option: "--resolution".into(),
                message,
            })?;
    }
    let name = scene.name();
    create_dir(&opts.out_dir)?;
    let frames = match (opts.frames, scene.animation.as_ref()) {
        (None, _) => None,
        (Some(0), Some(a)) => Some(a.frames),
        (Some(n), Some(_)) => Some(n),
        (Some(_), None) => {
            return Err(Error::Option {
                option: "--frames".into(),
                message: format!("{} has no [animation] block", opts.scene.display()),
            })
        }
    };
    let (fields, precompute_s, cached) = cached_fields(&scene, opts)?;
    // Set up once per run, as the BVH is: in neither the precompute nor a frame.
    let shading = sf::Shading::new(&scene);
    match frames {
        None => {
            let accel = Accel::build(&scene.meshes, &scene.spheres);
            let frame = shade_frame(&scene, &accel, &fields, &[], &shading, &opts.settings);
            let refs = references(&scene, &accel, &shading.env, &frame.shaded, opts)?;
            let stem = opts.out_dir.join(&name);
            let mut set = PreviewSet::default();
            add_images(&mut set, &stem, &frame.shaded, &refs.reference.beauty);
            let timing = timing(opts, precompute_s, frame.render_s);
            let summary = summarise(&scene, &fields, &frame, &refs, timing, cached, &stem, opts);
            let header = super::provenance(&scene, refs.reference.spp, frame.render_s)?;
            write_set(set, &opts.out_dir.join("preview.json"), &summary, &header)?;
            Ok(summary)
        }
        Some(n) => run_frames(&scene, opts, &fields, &shading, n, (precompute_s, cached)),
    }
}

/// One shaded frame and its timing.
pub(crate) struct Frame {
    pub(crate) shaded: sf::Shaded,
    pub(crate) render_s: f64,
    /// Process CPU seconds of the frame (None where the OS does not say): what
    /// the µs per point and entity are read from, so other jobs on the machine
    /// do not inflate them.
    pub(crate) cpu_s: Option<f64>,
}

pub(crate) fn shade_frame(
    scene: &Scene,
    accel: &Accel,
    fields: &Fields,
    poses: &[Pose],
    shading: &sf::Shading,
    settings: &Settings,
) -> Frame {
    let (start, cpu) = (Instant::now(), crate::cpu_time::process_s());
    let (combiner, mesh_self) = fields.combiner(poses, shading.env.clone());
    let receivers = Receivers::new(scene, accel, fields, &mesh_self, &shading.glossy);
    let shaded = sf::shade_image(&receivers, &combiner, settings.pixel_samples);
    Frame {
        shaded,
        render_s: start.elapsed().as_secs_f64(),
        cpu_s: cpu.zip(crate::cpu_time::process_s()).map(|(a, b)| b - a),
    }
}

/// The reference (at the spp that resolves the preview's bias, or the cap) and
/// the low-frequency one at the same spp.
struct References {
    reference: Reference,
    lowfreq: Vec<Vec3>,
    /// The pixels both were scored on ([`sf::Shaded::scored`]).
    scored: Vec<bool>,
}

fn timing(opts: &ShadowFieldOptions, precompute_s: f64, frame_s: f64) -> Timing {
    Timing {
        precompute_s,
        frame_s,
        frames: opts.amortise_frames.unwrap_or(figures::AMORTISE_FRAMES),
    }
}

fn direct(spp: u32, seed: u32) -> RenderOptions {
    RenderOptions {
        spp: Some(spp),
        seed: Some(seed),
        integrator: Some(Integrator::Direct),
        ..RenderOptions::default()
    }
}

fn references(
    scene: &Scene,
    accel: &Accel,
    env: &sf::peak::EnvironmentLight,
    preview: &sf::Shaded,
    opts: &ShadowFieldOptions,
) -> Result<References> {
    let scored = preview.scored();
    let mode = ProgressMode::detect(opts.quiet);
    let start = opts.reference_spp.unwrap_or(256);
    let max = opts.reference_spp_max.unwrap_or(figures::REFERENCE_SPP_MAX);
    // Seed index 0 is the reference written (the seed it always had); 1 and 2
    // only measure its noise and the rate.
    let seeds = [0x5eed_0001, 0x5eed_0003, 0x5eed_0004];
    let reference =
        figures::converge_reference(&preview.rgb, Some(&scored), start, max, |spp, k| {
            let phase = Phase::new(mode, &format!("reference at {spp} spp"), 0, "pixels");
            let out = render(
                scene,
                accel,
                &direct(spp, seeds[k as usize % 3]),
                &phase.callback(),
            )?;
            Ok((out.beauty, out.stats.wall_time.as_secs_f64()))
        })?;
    let lowfreq = match &scene.environment {
        Some(crate::scene::Environment::Constant { .. }) | None => reference.beauty.clone(),
        Some(_) => {
            let mut low = scene.clone();
            low.environment = Some(sf::environment_lowfreq(
                env,
                scene.environment.as_ref(),
                256,
                128,
            ));
            render(&low, accel, &direct(reference.spp, 0x5eed_0002), &|_, _| {})?.beauty
        }
    };
    Ok(References {
        reference,
        lowfreq,
        scored,
    })
}

#[allow(clippy::too_many_arguments)]
fn summarise(
    scene: &Scene,
    fields: &Fields,
    frame: &Frame,
    refs: &References,
    timing: Timing,
    cached: bool,
    stem: &Path,
    opts: &ShadowFieldOptions,
) -> ShadowFieldSummary {
    let img = &frame.shaded.rgb;
    let scored = &refs.scored;
    let kept = scored.iter().filter(|k| **k).count();
    let mean = refs
        .reference
        .beauty
        .iter()
        .zip(scored)
        .filter(|(_, k)| **k)
        .map(|(c, _)| f64::from(c.x + c.y + c.z))
        .sum::<f64>()
        / (3 * kept.max(1)) as f64;
    // Same-sized planes of one camera: the metric cannot fail.
    let rmse = figures::scored_rmse(img, &refs.reference.beauty, Some(scored)).unwrap_or(0.0);
    let rmse_low = figures::scored_rmse(img, &refs.lowfreq, Some(scored)).unwrap_or(0.0);
    let rmse_all = metrics::rmse(img, &refs.reference.beauty).unwrap_or(0.0) as f64;
    let max = opts.reference_spp_max.unwrap_or(figures::REFERENCE_SPP_MAX);
    let threads = rayon::current_num_threads();
    let entities = fields.entities.len();
    let points = frame.shaded.points;
    ShadowFieldSummary {
        method: "shadow-field".into(),
        scene: scene.name(),
        entities,
        points,
        precompute_s: timing.precompute_s,
        precompute_cached: cached,
        render_s: frame.render_s,
        us_per_point_entity: frame.cpu_s.unwrap_or(frame.render_s * threads as f64) * 1e6
            / (points * entities).max(1) as f64,
        threads,
        image_mean: mean,
        scored_pixels: kept,
        pixels: scored.len(),
        rmse,
        rmse_all_pixels: rmse_all,
        rmse_relative: rmse / mean.max(1e-30),
        rmse_lowfreq: rmse_low,
        rmse_lowfreq_relative: rmse_low / mean.max(1e-30),
        figures: figures::figures(rmse, &refs.reference, max, timing),
        exr: stem.with_extension("exr"),
        png: stem.with_extension("png"),
        frames: None,
        bsv_update_s: None,
        full_field_s: None,
        rmse_worst_frame: None,
        rmse_worst_frame_relative: None,
    }
}

/// Loads the fields from the cache or precomputes (and stores) them.
pub(crate) fn cached_fields(
    scene: &Scene,
    opts: &ShadowFieldOptions,
) -> Result<(Fields, f64, bool)> {
    use crate::pipeline::cache::{Cache, Epoch};
    let settings = &opts.settings;
    let entry = Cache::under(&opts.out_dir).entry(
        &format!("shadow_field-{}", scene.name()),
        "bin",
        Epoch::Source,
        &scene.content_hash()?,
        &settings.key(),
    );
    let entities = sf::precompute::entities(scene);
    if opts.cache {
        if let Some(hit) = entry.read_bytes() {
            if let Some(f) = sf::cache::from_bytes(&hit.value, scene, &entities, settings) {
                return Ok((f, hit.seconds, true));
            }
        }
    }
    let phase = Phase::new(
        ProgressMode::detect(opts.quiet),
        "shadow-field precompute",
        0,
        "field samples",
    );
    let start = Instant::now();
    let fields = sf::precompute(scene, settings, &phase.callback());
    let secs = start.elapsed().as_secs_f64();
    drop(phase);
    if opts.cache {
        entry.write_bytes(&sf::cache::to_bytes(&fields), secs)?;
    }
    Ok((fields, secs, false))
}

/// EXR (`R,G,B` preview, `reference.R/G/B`, `error.Y` = |luminance difference|)
/// and the preview's PNG, added to the run's set (written at its end).
fn add_images(set: &mut PreviewSet, stem: &Path, shaded: &sf::Shaded, reference: &[Vec3]) {
    let (w, h) = (shaded.width, shaded.height);
    let mut img = OutputImage::new(w, h);
    img.push_vec3("", output::names::RGB, &shaded.rgb);
    img.push_vec3("reference.", output::names::RGB, reference);
    img.push_scalar(
        "error.Y",
        shaded
            .rgb
            .iter()
            .zip(reference)
            .map(|(a, b)| (metrics::luminance(*a) - metrics::luminance(*b)).abs())
            .collect(),
    );
    set.exr(stem.with_extension("exr"), img);
    set.png(stem.with_extension("png"), shaded.rgb.clone(), w, h);
}

/// Every image, then `preview.json` (with the set's `render_id` and `files`).
fn write_set(
    set: PreviewSet,
    path: &Path,
    summary: &impl Serialize,
    header: &output::ExrHeader,
) -> Result<()> {
    let json = serde_json::to_value(summary).map_err(|e| Error::Output {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    set.write(path, json, header).map(|_| ())
}

fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.to_path_buf(),
        source,
    })
}

/// `--frames N`: rigid entities reuse their fields (rotated in SH), deforming ones
/// (`Track::deforms`: a procedural deformation or an OBJ sequence) are rebuilt each
/// frame from their base-sphere visibility of the posed scene's geometry.
fn run_frames(
    scene: &Scene,
    opts: &ShadowFieldOptions,
    fields: &Fields,
    shading: &sf::Shading,
    n: u32,
    (precompute_s, cached): (f64, bool),
) -> Result<ShadowFieldSummary> {
    let Some(anim) = scene.animation.as_ref() else {
        return Err(Error::Option {
            option: "--frames".into(),
            message: "the scene has no [animation] block".into(),
        });
    };
    let settings = &opts.settings;
    let mut base = fields.clone();
    for e in &mut base.entities {
        e.deforming = anim.track(e.object_id).is_some_and(|t| t.deforms());
    }
    // k_j = R / r_j does not depend on R: one table for every deforming entity.
    let unit = sf::field::Grid {
        n_theta: settings.n_theta,
        n_phi: settings.n_phi,
        n_radii: settings.n_radii,
        r_min: settings.r_min,
        r_max: settings.r_max,
    };
    let table = deform::MatrixTable::for_grid(&unit, 1.0, deform::Extrapolation::Visibility);
    let (mut bsv_total, mut bsv_count, mut full_field_s) = (0.0, 0usize, None);
    let mut first: Option<(Frame, References, PathBuf)> = None;
    let mut set = PreviewSet::default();
    let mut worst: f64 = 0.0;
    for f in 0..n {
        let t = crate::scene::animation::frame_time(f, n);
        let posed = anim.scene_at(scene, f, n);
        let accel = Accel::build(&posed.meshes, &posed.spheres);
        let mut frame_fields = base.clone();
        let mut poses = vec![Pose::default(); base.entities.len()];
        for (i, e) in base.entities.iter().enumerate() {
            let Some(track) = anim.track(e.object_id) else {
                continue;
            };
            if !e.deforming {
                let (rotation, translation) = track.pose(t);
                poses[i] = Pose {
                    rotation,
                    translation,
                };
                continue;
            }
            let (entity, geo) = deformed_geometry(&posed, e);
            let start = Instant::now();
            let field = deformed_field(&geo, &entity, settings, &table);
            bsv_total += start.elapsed().as_secs_f64();
            bsv_count += 1;
            // The direct precomputation of the same field with the same geometry,
            // once, for the speed-up (BVH builds are left out of both).
            if full_field_s.is_none() {
                let grid = sf::precompute::grid_for(&entity, settings);
                let start = Instant::now();
                let _ = sf::precompute::occlusion_field(&geo, &entity, &grid, settings.rays);
                full_field_s = Some(start.elapsed().as_secs_f64());
            }
            frame_fields.entities[i] = entity;
            frame_fields.fields[i] = sf::precompute::EntityFields {
                occlusion: Some(field),
                radiance: None,
                self_occlusion: Vec::new(),
                visibility: None,
            };
        }
        let frame = shade_frame(&posed, &accel, &frame_fields, &poses, shading, settings);
        let stem = opts.out_dir.join(format!("{}-f{f:03}", scene.name()));
        if let Some((_, refs, _)) = &first {
            // The later frames' references at the spp the first one settled on.
            let spp = refs.reference.spp;
            let reference = render(&posed, &accel, &direct(spp, 0x5eed_0001), &|_, _| {})?;
            add_images(&mut set, &stem, &frame.shaded, &reference.beauty);
            worst = worst.max(metrics::rmse(&frame.shaded.rgb, &reference.beauty)? as f64);
        } else {
            let refs = references(&posed, &accel, &shading.env, &frame.shaded, opts)?;
            add_images(&mut set, &stem, &frame.shaded, &refs.reference.beauty);
            worst = worst.max(metrics::rmse(&frame.shaded.rgb, &refs.reference.beauty)? as f64);
            first = Some((frame, refs, stem));
        }
    }
    let (frame, refs, stem) = first.ok_or_else(|| Error::Option {
        option: "--frames".into(),
        message: "expected at least one frame".into(),
    })?;
    // A frame of the sequence costs its shading and its deforming entities' updates.
    let frame_s = frame.render_s + bsv_total / f64::from(n.max(1));
    let timing = timing(opts, precompute_s, frame_s);
    let mut summary = summarise(scene, fields, &frame, &refs, timing, cached, &stem, opts);
    summary.frames = Some(n);
    if bsv_count > 0 {
        summary.bsv_update_s = Some(bsv_total / bsv_count as f64);
        summary.full_field_s = full_field_s;
    }
    summary.rmse_worst_frame = Some(worst);
    summary.rmse_worst_frame_relative = Some(worst / summary.image_mean.max(1e-30));
    let header = super::provenance(scene, refs.reference.spp, frame_s)?;
    write_set(set, &opts.out_dir.join("preview.json"), &summary, &header)?;
    Ok(summary)
}

/// A deforming entity in the posed scene: its bounding sphere now, and its
/// geometry alone (rebuilt: the mesh has changed).
fn deformed_geometry(
    posed: &Scene,
    e: &sf::precompute::Entity,
) -> (sf::precompute::Entity, sf::precompute::EntityGeometry) {
    let mut entity = e.clone();
    if let Some((c, r)) = sf::precompute::bounding_sphere(
        e.meshes.iter().map(|&m| &posed.meshes[m]),
        e.spheres.iter().map(|&s| &posed.spheres[s]),
    ) {
        entity.center = c;
        entity.radius = r;
    }
    let geo = sf::precompute::EntityGeometry::new(posed, &entity);
    (entity, geo)
}

/// The entity's occlusion field from its base-sphere visibility (Sec. 4.3).
fn deformed_field(
    geo: &sf::precompute::EntityGeometry,
    entity: &sf::precompute::Entity,
    settings: &Settings,
    table: &deform::MatrixTable,
) -> sf::field::Field {
    let bsv = deform::BaseSphere::trace(
        geo,
        entity.center,
        entity.radius,
        settings.n_theta,
        settings.n_phi,
        settings.rays,
    );
    bsv.extrapolate(&sf::precompute::grid_for(entity, settings), table)
}
