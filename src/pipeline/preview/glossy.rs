//! `gradtrace preview glossy`: precompute transfer (cached) → render views → reference → preview.json.
//!
//! `preview.json`: `render_ms` is the wall time of one frame at the scene's
//! resolution from the cached transfer (the fastest of several warm frames),
//! `render_median_ms` their median (what a shared machine gives in practice),
//! `render_cpu_ms` their mean process CPU time over `render_threads` threads;
//! the speed-ups (`figures`) time the scored image itself (`frame_s`:
//! `subpixels`² positions per pixel).
//!
//! The reference is the path tracer with `max_depth = 3` (camera, first surface,
//! one bounce, then the environment): exactly the light paths the transfer holds
//! (direct and one-bounce interreflections), under the same environment.

use crate::accel::Accel;
use crate::math::{luminance, Vec2, Vec3};
use crate::output::{self, OutputImage};
use crate::pipeline::cache::{Cache, Entry, Epoch};
use crate::pipeline::preview::figures::{self, Figures, Timing};
use crate::pipeline::preview::PreviewSet;
use crate::pipeline::progress::{Phase, ProgressMode};
use crate::preview::glossy::{self, PrefilteredEnv, Settings, Transfer};
use crate::render::{self, RenderOptions};
use crate::scene::{Camera, Integrator, Scene};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of one `preview glossy` run.
#[derive(Clone, Debug)]
pub struct GlossyOptions {
    pub scene: PathBuf,
    pub out_dir: PathBuf,
    /// Also render N views on a circle around the scene (`orbit_NNN.png`).
    pub orbit: Option<u32>,
    /// Samples per pixel the path-traced reference starts at (default 256);
    /// raised until it resolves the preview's bias, up to `reference_spp_max`
    /// (default [`figures::REFERENCE_SPP_MAX`]).
    pub reference_spp: Option<u32>,
    pub reference_spp_max: Option<u32>,
    /// Frames the precompute is amortised over (default [`figures::AMORTISE_FRAMES`]).
    pub amortise_frames: Option<u32>,
    /// Override of the camera resolution (width, height).
    pub resolution: Option<(u32, u32)>,
    pub quiet: bool,
    /// Written preview: n × n positions per pixel (a box filter like the path
    /// tracer's, so silhouettes do not alias into the error); `render_ms` is the
    /// one-position frame.
    pub subpixels: u32,
    pub settings: Settings,
}

impl GlossyOptions {
    pub fn new(scene: impl Into<PathBuf>) -> Self {
        Self {
            scene: scene.into(),
            out_dir: PathBuf::from("out"),
            orbit: None,
            reference_spp: None,
            reference_spp_max: None,
            amortise_frames: None,
            resolution: None,
            quiet: false,
            subpixels: 2,
            settings: Settings::default(),
        }
    }
}

/// What a run wrote and measured.
#[derive(Clone, Debug)]
pub struct GlossySummary {
    pub exr: PathBuf,
    pub png: PathBuf,
    pub json: PathBuf,
    pub stats_page: PathBuf,
    pub cached: bool,
    pub precompute_s: f64,
    /// Wall time of one frame: the fastest of several warm frames (`time_frame`).
    pub render_ms: f64,
    /// The median of those warm frames.
    pub render_median_ms: f64,
    /// Process CPU time per frame (all threads), where the OS reports it.
    pub render_cpu_ms: Option<f64>,
    pub vertices_initial: usize,
    pub vertices_final: usize,
    pub angular_levels: Vec<usize>,
    /// The transfer in memory.
    pub bytes: usize,
    /// The transfer's cache entry (empty lobes left out, see `preview::glossy::store`).
    pub cache_bytes: usize,
    pub image_mean: f64,
    pub reference_mean: f64,
    pub rmse: f64,
    /// RMSE over pixels whose corners and centre see the same object (no edge).
    pub rmse_interior: f64,
    pub reference_s: f64,
    /// Bias, equal-error time and speed-ups against the path tracer.
    pub figures: Figures,
}

/// The command's one summary line.
impl std::fmt::Display for GlossySummary {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(
            f,
            "glossy: {} → {} vertices, precompute {:.1} s{}, frame {:.1} ms, RMSE {:.3e} ({:.1}% of the mean), {}; wrote {} and {}",
            self.vertices_initial,
            self.vertices_final,
            self.precompute_s,
            if self.cached { " (cached)" } else { "" },
            self.render_ms,
            self.rmse,
            100.0 * self.rmse / self.reference_mean.max(1e-12),
            self.figures.summary(),
            self.exr.display(),
            self.stats_page.display()
        )
    }
}

fn out_err(path: &Path, e: impl std::fmt::Display) -> crate::Error {
    crate::Error::Output {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// The transfer's cache entry: the scene's content, every precompute setting,
/// the source (public for the benchmark, which fills the cache the run reads).
pub fn transfer_entry(scene: &Scene, out_dir: &Path, settings: &Settings) -> crate::Result<Entry> {
    Ok(Cache::under(out_dir).entry(
        "glossy",
        "bin",
        Epoch::Source,
        &scene.content_hash()?,
        &format!("{settings:?}"),
    ))
}

/// The transfer from the cache, or precomputed (and cached) with a progress bar;
/// and the bytes of its cache entry.
pub(crate) fn transfer(
    scene: &Scene,
    accel: &Accel,
    opts: &GlossyOptions,
) -> crate::Result<(Transfer, usize)> {
    let entry = transfer_entry(scene, &opts.out_dir, &opts.settings)?;
    if let Some(hit) = entry.read_bytes() {
        if let Some(t) = Transfer::decode(&hit.value, entry.key(), scene, &opts.settings) {
            return Ok((t, hit.value.len()));
        }
    }
    // One phase over every refinement step's vertices.
    let phase = Phase::new(
        ProgressMode::detect(opts.quiet),
        "glossy precompute",
        0,
        "vertices",
    );
    let t = glossy::precompute(scene, accel, &opts.settings, &phase.steps())?;
    drop(phase);
    let bytes = t.encode(entry.key());
    entry.write_bytes(&bytes, t.stats.precompute_s)?;
    Ok((t, bytes.len()))
}

/// The path-traced reference (direct + one bounce) at `spp` and the seed of
/// index `seed` (0: the renderer's default, the image written; 1, 2: the noise
/// measurement's), cached as an EXR.
fn reference(
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
    opts: &GlossyOptions,
    spp: u32,
    seed: u32,
) -> crate::Result<(Vec<Vec3>, f64)> {
    let seed = (seed > 0).then_some(0x6c05_5000 + seed);
    let ropts = RenderOptions {
        spp: Some(spp),
        seed,
        max_depth: Some(3),
        integrator: Some(Integrator::Path),
        resolution: Some((camera.width, camera.height)),
        ..Default::default()
    };
    let entry = Cache::under(&opts.out_dir).entry(
        "reference",
        "exr",
        Epoch::Pixels,
        &scene.content_hash()?,
        &format!("{ropts:?}"),
    );
    let size = (camera.width as usize, camera.height as usize);
    if let Some(hit) = entry.read_exr(|img| (img.width, img.height) == size) {
        if let Some(rgb) = hit.value.vec3("", ["R", "G", "B"]) {
            return Ok((rgb, hit.seconds));
        }
    }
    let phase = Phase::new(
        ProgressMode::detect(opts.quiet),
        &format!("reference at {spp} spp"),
        0,
        "pixels",
    );
    let start = Instant::now();
    let out = render::render(scene, accel, &ropts, &phase.callback())?;
    let secs = start.elapsed().as_secs_f64();
    drop(phase);
    let mut img = OutputImage::new(out.width, out.height);
    img.push_vec3("", ["R", "G", "B"], &out.beauty);
    let header =
        crate::pipeline::render::provenance(scene, &ropts, &crate::pipeline::command_line(), &out)?;
    entry.write_exr(&img, &header, &out.beauty, secs)?;
    Ok((out.beauty, secs))
}

/// How long one frame takes: the wall time is the fastest (and the median) of `FRAMES` warm frames
/// (one frame first, untimed, pays the first touch of the transfer and the
/// environment levels and rayon's thread start); the CPU time is their mean
/// process CPU time per frame, which a machine shared with other jobs inflates
/// far less than the wall time (divided by the thread count it estimates the
/// wall time on idle cores).
struct FrameTime {
    wall_ms: f64,
    median_ms: f64,
    cpu_ms: Option<f64>,
}

const FRAMES: usize = 15;

fn time_frame(
    t: &Transfer,
    env: &PrefilteredEnv,
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
) -> FrameTime {
    let _ = glossy::render(t, env, scene, accel, camera);
    let cpu0 = crate::cpu_time::process_s();
    let mut walls: Vec<f64> = (0..FRAMES)
        .map(|_| {
            let start = Instant::now();
            let _ = glossy::render(t, env, scene, accel, camera);
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    walls.sort_by(f64::total_cmp);
    let cpu_ms = cpu0
        .zip(crate::cpu_time::process_s())
        .map(|(a, b)| (b - a) * 1e3 / FRAMES as f64);
    FrameTime {
        wall_ms: walls[0],
        median_ms: walls[FRAMES / 2],
        cpu_ms,
    }
}

fn mean_luminance(img: &[Vec3]) -> f64 {
    img.iter().map(|c| luminance(*c) as f64).sum::<f64>() / img.len().max(1) as f64
}

/// Runs `preview glossy` end to end.
pub fn run(opts: &GlossyOptions) -> crate::Result<GlossySummary> {
    let scene = crate::scene::load(&opts.scene)?;
    crate::pipeline::memory::check_scene(&scene, "a glossy preview")?;
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let camera = match opts.resolution {
        Some((w, h)) => {
            scene
                .camera
                .with_resolution(w, h)
                .map_err(|message| crate::Error::Option {
                    option: "--resolution".into(),
                    message,
                })?
        }
        None => scene.camera.clone(),
    };
    let (transfer, cache_bytes) = transfer(&scene, &accel, opts)?;
    let env = scene
        .environment
        .as_ref()
        .ok_or_else(|| crate::Error::Scene {
            path: scene.path.clone(),
            location: "environment".into(),
            message: "the glossy preview needs an [environment]".into(),
        })?;
    let env = PrefilteredEnv::new(env);
    let frame = time_frame(&transfer, &env, &scene, &accel, &camera);
    // The scored image's own time (its subpixel positions), for the speed-ups:
    // the fastest of three, as `render_ms` is of its frames.
    let mut frame_s = f64::INFINITY;
    let mut image = Vec::new();
    for _ in 0..3 {
        let start = Instant::now();
        image =
            glossy::render_supersampled(&transfer, &env, &scene, &accel, &camera, opts.subpixels);
        frame_s = frame_s.min(start.elapsed().as_secs_f64());
    }
    let spp_max = opts.reference_spp_max.unwrap_or(figures::REFERENCE_SPP_MAX);
    let refs = figures::converge_reference(
        &image,
        None,
        opts.reference_spp.unwrap_or(256),
        spp_max,
        |spp, seed| reference(&scene, &accel, &camera, opts, spp, seed),
    )?;
    let reference = refs.beauty.clone();
    std::fs::create_dir_all(&opts.out_dir).map_err(|e| out_err(&opts.out_dir, e))?;
    let name = scene.name();
    let (w, h) = (camera.width as usize, camera.height as usize);
    let error: Vec<f32> = image
        .iter()
        .zip(&reference)
        .map(|(a, b)| (luminance(*a) - luminance(*b)).abs())
        .collect();
    let rmse = output::metrics::rmse(&image, &reference)? as f64;
    let interior = interior_pixels(&accel, &camera);
    let pick = |img: &[Vec3]| -> Vec<Vec3> {
        img.iter()
            .zip(&interior)
            .filter(|(_, &k)| k)
            .map(|(c, _)| *c)
            .collect()
    };
    let rmse_interior = output::metrics::rmse(&pick(&image), &pick(&reference))? as f64;
    let scale = 4.0 / mean_luminance(&reference).max(1e-12) as f32;
    let error_rgb: Vec<Vec3> = error
        .iter()
        .map(|e| output::colormap::viridis((e * scale).min(1.0)))
        .collect();
    // Everything goes into one set, written at the end under one render id.
    let mut set = PreviewSet::default();
    set.png(
        opts.out_dir.join(format!("{name}_error.png")),
        error_rgb,
        w,
        h,
    );
    let mut exr = OutputImage::new(w, h);
    exr.push_vec3("", ["R", "G", "B"], &image);
    exr.push_vec3("reference.", ["R", "G", "B"], &reference);
    exr.push_scalar("error.Y", error);
    let exr_path = opts.out_dir.join(format!("{name}.exr"));
    set.exr(exr_path.clone(), exr);
    let png = opts.out_dir.join(format!("{name}.png"));
    set.png(png.clone(), image.clone(), w, h);
    set.png(
        opts.out_dir.join(format!("{name}_reference.png")),
        reference.clone(),
        w,
        h,
    );
    let orbit = orbit_views(&mut set, &transfer, &env, &scene, &accel, &camera, opts)?;
    let levels_png = opts.out_dir.join(format!("{name}_levels.png"));
    let levels = level_image(&transfer, &accel, &camera);
    set.png(levels_png.clone(), levels, w, h);
    let s = &transfer.stats;
    let timing = Timing {
        precompute_s: s.precompute_s,
        frame_s,
        frames: opts.amortise_frames.unwrap_or(figures::AMORTISE_FRAMES),
    };
    let summary = GlossySummary {
        json: opts.out_dir.join("preview.json"),
        stats_page: opts.out_dir.join(format!("{name}_stats.md")),
        exr: exr_path,
        png,
        cached: s.cached,
        precompute_s: s.precompute_s,
        render_ms: frame.wall_ms,
        render_median_ms: frame.median_ms,
        render_cpu_ms: frame.cpu_ms,
        vertices_initial: s.vertices_initial,
        vertices_final: s.vertices_final,
        angular_levels: s.angular_levels.clone(),
        bytes: transfer.bytes(),
        cache_bytes,
        image_mean: mean_luminance(&image),
        reference_mean: mean_luminance(&reference),
        rmse,
        rmse_interior,
        reference_s: refs.seconds,
        figures: figures::figures(rmse, &refs, spp_max, timing),
    };
    set.page(
        summary.stats_page.clone(),
        stats_page(&summary, &levels_png, &transfer),
    );
    let header = super::provenance(&scene, refs.spp, frame_s)?;
    set.write(
        &summary.json,
        index(&summary, opts, &scene, &orbit),
        &header,
    )?;
    Ok(summary)
}

/// Pixels whose centre and four corners hit the same mesh (or all miss).
fn interior_pixels(accel: &Accel, camera: &Camera) -> Vec<bool> {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let id = |x: f32, y: f32| -> i64 {
        match accel
            .intersect(&camera.generate_ray(Vec2::new(x, y)))
            .map(|hit| hit.prim)
        {
            None => -1,
            Some(crate::accel::PrimRef::Triangle { mesh, .. }) => mesh as i64,
            Some(crate::accel::PrimRef::Sphere(s)) => 1 << 40 | s as i64,
        }
    };
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            let c = id(x + 0.5, y + 0.5);
            [(x, y), (x + 1.0, y), (x, y + 1.0), (x + 1.0, y + 1.0)]
                .iter()
                .all(|&(a, b)| id(a, b) == c)
        })
        .collect()
}

fn orbit_views(
    set: &mut PreviewSet,
    t: &Transfer,
    env: &PrefilteredEnv,
    scene: &Scene,
    accel: &Accel,
    camera: &Camera,
    opts: &GlossyOptions,
) -> crate::Result<Vec<(String, f64)>> {
    let n = opts.orbit.unwrap_or(0);
    let mut out = Vec::new();
    for k in 0..n {
        let angle = std::f32::consts::TAU * k as f32 / n as f32;
        let rel = camera.from - camera.to;
        let (s, c) = angle.sin_cos();
        let from = camera.to + Vec3::new(c * rel.x + s * rel.z, rel.y, -s * rel.x + c * rel.z);
        let cam = Camera::new(
            from,
            camera.to,
            camera.up,
            camera.fov_y,
            camera.width,
            camera.height,
        )
        .map_err(|message| crate::Error::Option {
            option: "--orbit".into(),
            message,
        })?;
        let start = Instant::now();
        let img = glossy::render(t, env, scene, accel, &cam);
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let file = format!("orbit_{k:03}.png");
        set.png(
            opts.out_dir.join(&file),
            img,
            cam.width as usize,
            cam.height as usize,
        );
        out.push((file, ms));
    }
    Ok(out)
}

/// The mesh seen from the camera, each point coloured by the angular level of its
/// nearest vertex (viridis, level 0 dark), resolved triangle edges darkened.
fn level_image(t: &Transfer, accel: &Accel, camera: &Camera) -> Vec<Vec3> {
    let levels = t.vertex_levels();
    let top = (levels.iter().copied().max().unwrap_or(0)).max(1) as f32;
    let (w, h) = (camera.width as usize, camera.height as usize);
    let mut img = vec![Vec3::splat(1.0); w * h];
    for (i, px) in img.iter_mut().enumerate() {
        let ray = camera.generate_ray(Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5));
        let Some(hit) = accel.intersect(&ray) else {
            continue;
        };
        let crate::accel::PrimRef::Triangle { mesh, tri } = hit.prim else {
            continue;
        };
        if let Some((ids, wts)) = t.mesh.locate(mesh, tri, hit.bary) {
            let k = (0..3)
                .max_by(|&a, &b| wts[a].total_cmp(&wts[b]))
                .unwrap_or(0);
            let c = output::colormap::viridis(levels[ids[k] as usize] as f32 / top);
            let edge = wts.iter().copied().fold(f32::INFINITY, f32::min) < 0.03;
            *px = if edge { c * 0.35 } else { c };
        }
    }
    img
}

/// `preview.json` before the set adds its `render_id` and `files`.
fn index(
    s: &GlossySummary,
    opts: &GlossyOptions,
    scene: &Scene,
    orbit: &[(String, f64)],
) -> serde_json::Value {
    let json = serde_json::json!({
        "method": "glossy-transfer",
        "scene": scene.name(),
        "precompute_s": s.precompute_s,
        "cached": s.cached,
        "render_ms": s.render_ms,
        "render_median_ms": s.render_median_ms,
        "render_cpu_ms": s.render_cpu_ms,
        "render_threads": rayon::current_num_threads(),
        "vertices_initial": s.vertices_initial,
        "vertices_final": s.vertices_final,
        "angular_levels": s.angular_levels,
        "bytes": s.bytes,
        "cache_bytes": s.cache_bytes,
        "image_mean": s.image_mean,
        "reference_mean": s.reference_mean,
        "rmse": s.rmse,
        "rmse_interior": s.rmse_interior,
        "subpixels": opts.subpixels,
        "rmse_over_mean": s.rmse / s.reference_mean.max(1e-12),
        "reference_max_depth": 3,
        "orbit": orbit.iter().map(|(f, ms)| serde_json::json!({"file": f, "render_ms": ms})).collect::<Vec<_>>(),
        "settings": format!("{:?}", opts.settings),
    });
    // The shared figures (reference_spp, reference_s, speedup_*, …) at the top level.
    let mut json = json;
    if let (Some(map), Ok(serde_json::Value::Object(figures))) =
        (json.as_object_mut(), serde_json::to_value(&s.figures))
    {
        map.extend(figures);
    }
    json
}

fn stats_page(s: &GlossySummary, levels_png: &Path, t: &Transfer) -> String {
    let mut md = String::from(
        "# Glossy transfer: precomputation statistics\n\n| quantity | value |\n|---|---|\n",
    );
    let rows = [
        ("vertices, initial", s.vertices_initial.to_string()),
        ("vertices, final", s.vertices_final.to_string()),
        ("spatial iterations", t.stats.iterations.to_string()),
        ("slices", t.stats.slices.to_string()),
        (
            "precompute",
            format!(
                "{:.1} s{}",
                s.precompute_s,
                if s.cached { " (cached)" } else { "" }
            ),
        ),
        ("memory", format!("{:.1} MB", s.bytes as f64 / 1e6)),
        ("cache", format!("{:.1} MB", s.cache_bytes as f64 / 1e6)),
        (
            "render",
            format!(
                "{:.1} ms / frame (fastest warm frame, median {:.1} ms; {} CPU ms on {} threads)",
                s.render_ms,
                s.render_median_ms,
                s.render_cpu_ms.map_or("n/a".into(), |c| format!("{c:.1}")),
                rayon::current_num_threads()
            ),
        ),
        (
            "RMSE vs path tracer",
            format!(
                "{:.4} ({:.1} % of the mean {:.4})",
                s.rmse,
                100.0 * s.rmse / s.reference_mean.max(1e-12),
                s.reference_mean
            ),
        ),
        (
            "RMSE away from silhouettes",
            format!(
                "{:.4} ({:.1} % of the mean)",
                s.rmse_interior,
                100.0 * s.rmse_interior / s.reference_mean.max(1e-12)
            ),
        ),
        ("reference", format!("{:.1} s", s.reference_s)),
    ];
    for (k, v) in rows {
        md += &format!("| {k} | {v} |\n");
    }
    md +=
        "\n## Angular levels per vertex (the paper's Fig. 8)\n\n| level | vertices |\n|---|---|\n";
    for (l, n) in s.angular_levels.iter().enumerate() {
        md += &format!("| {l} | {n} |\n");
    }
    let file = levels_png
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_default();
    md += &format!("\n![mesh coloured by angular level (viridis, dark = level 0), resolved edges dark]({file})\n");
    let name = file.trim_end_matches("_levels.png");
    md += &format!("\n| preview | path tracer (direct + one bounce) |\n|---|---|\n| ![]({name}.png) | ![]({name}_reference.png) |\n");
    md
}
