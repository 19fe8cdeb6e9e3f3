//! scene + BVH → per-pixel estimates (radiance, AOVs, analytic gradients) by
//! path tracing; `point` evaluates the same estimator at arbitrary image points
//! (the pipeline's adaptive renders ask it for their samples).

pub mod gradients;
pub mod interaction;
mod lanes;
#[doc(hidden)]
pub use lanes::check as lane_check;
pub mod lights;
pub mod noise_adaptive;
pub mod path;
pub mod point;
pub mod two_pass;

use crate::accel::Accel;
use crate::math::sampler::PixelSampler;
use crate::math::{finite_or_zero, luminance, Vec2, Vec3};
use crate::scene::{Integrator, Scene};
use gradients::geometry::unit_direction_derivatives;
use gradients::{GradientSample, GradientSum};
use lights::LightSet;
use path::{PathTracer, SampleResult};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Shadow rays per visibility line. Polygon crossings are solved exactly on the
/// blocker's edges, so more rays mostly find thinner blockers: on spheres_table
/// 4 rays per line reach a visibility-gradient error 1.1× that of 32 at 0.2× the
/// line cost (issue 53; benches/README.md, gradients).
pub const DEFAULT_VIS_SAMPLES: u32 = 4;

/// Probability of marching the ring where the penumbra probes agree
/// (`visibility::Gate`): the ring is ~70 % of the line-and-ring rays.
pub const DEFAULT_VIS_GATE: f32 = 0.25;

/// Options for one render; `None` fields fall back to the scene's `[render]` table.
/// The thread count is the caller's rayon pool (the CLI's `--threads`); it never
/// changes the image.
#[derive(Clone, Debug, Default)]
pub struct RenderOptions {
    pub spp: Option<u32>,
    pub max_depth: Option<u32>,
    pub seed: Option<u32>,
    pub integrator: Option<Integrator>,
    /// Override of the camera resolution.
    pub resolution: Option<(u32, u32)>,
    /// Compute the AOV planes (normal, depth, albedo, object id, variance).
    pub aovs: bool,
    /// Compute the analytic image gradient planes (`grad.*` layers).
    pub gradients: bool,
    /// With gradients: shadow rays per φ-line for the first hit's visibility
    /// gradient (default [`DEFAULT_VIS_SAMPLES`]). 0: no visibility term, the
    /// cheapest gradients.
    pub vis_samples: Option<u32>,
    /// With gradients: bisection steps that refine each visibility jump (default 0).
    pub vis_refine: Option<u32>,
    /// With gradients: the probability of marching a sample's ring where its
    /// penumbra probes agree (`visibility::Gate`; default [`DEFAULT_VIS_GATE`]).
    pub vis_gate: Option<f32>,
    /// With gradients: treat near lights as distant where 2|n_x|·d exceeds this
    /// factor (the far-light criterion of Sec. 5.2), dropping their SV term.
    pub far_light: Option<f32>,
    /// Adaptive renders: how many of each sample's `spp` camera samples carry the
    /// analytic gradient (dual lanes, and line sampling for the visibility term);
    /// the rest are plain path samples that only refine the radiance. The gradient
    /// steers placement and interpolation and needs far fewer samples than a
    /// converged radiance, so this bounds its cost (default: all of them, up to 16).
    pub gradient_spp: Option<u32>,
    /// Full renders: trace only these pixels; the planes cover the crop, and every
    /// pixel gets the random numbers it has in the whole image.
    pub crop: Option<Crop>,
    /// Full renders: trace only sample indices A..B of every pixel's `spp` (the
    /// sampler is addressed by index, so disjoint ranges are pieces of one render).
    pub sample_range: Option<(u32, u32)>,
    /// Keep what an exact merge of sample ranges needs ([`MergePlanes`]).
    pub merge_planes: bool,
    /// Trace every path through `PathTracer::li` alone, never the lane
    /// shading (`render::lanes`): the same image, for comparing the two.
    pub no_lanes: bool,
}

impl RenderOptions {
    /// Whether the film keeps the camera rays' first hits: for the AOV planes,
    /// or for the merge planes (hit counts, normal lengths). Without either the
    /// lane shading makes none (cornell: −0.8 % of the render).
    pub(crate) fn keeps_first_hits(&self) -> bool {
        self.aovs || self.merge_planes
    }

    /// Every setting that changes what a pixel's samples are, resolved against the
    /// scene (but not `spp`, the crop or the sample range): parts of one render
    /// share it, so `merge` compares it.
    pub fn settings_key(&self, scene: &Scene) -> crate::Result<String> {
        let setup = Setup::new(scene, self)?;
        let integrator = self.integrator.unwrap_or(scene.settings.integrator);
        Ok(format!(
            "integrator={} max_depth={} rr_depth={} resolution={}x{} aovs={} gradients={} lines={:?} far_light={:?}",
            integrator.name(),
            setup.max_depth,
            setup.rr_depth,
            setup.camera.width,
            setup.camera.height,
            self.aovs,
            self.gradients,
            setup.lines.map(|l| (l.n_theta, l.refine, l.gate)),
            self.far_light,
        ))
    }

    /// The image size this render will have: the override, else the camera's.
    pub fn resolution_of(&self, scene: &Scene) -> (u32, u32) {
        self.resolution
            .unwrap_or((scene.camera.width, scene.camera.height))
    }
}

/// What a render produced: row-major planes, top row first, covering the crop
/// at `origin` of the `display`-sized image (all of it unless cropped).
#[derive(Clone, Debug, Default)]
pub struct RenderOutput {
    pub width: usize,
    pub height: usize,
    pub spp: u32,
    pub beauty: Vec<Vec3>,
    /// Per-pixel variance of the mean (sample variance / spp), when AOVs are on.
    pub variance: Option<Vec<Vec3>>,
    pub normal: Option<Vec<Vec3>>,
    pub depth: Option<Vec<f32>>,
    pub albedo: Option<Vec<Vec3>>,
    pub object_id: Option<Vec<f32>>,
    pub gradients: Option<GradientPlanes>,
    pub stats: RenderStats,
    /// The planes' top-left pixel in the full image.
    pub origin: (usize, usize),
    /// The full image's size; (0, 0) means the planes' own (`width`, `height`).
    pub display: (usize, usize),
    /// The samples rendered are indices `first_sample..first_sample + spp`.
    pub first_sample: u32,
    /// Present when asked for ([`RenderOptions::merge_planes`]).
    pub merge: Option<MergePlanes>,
    /// Samples per pixel where they differ (noise-adaptive renders): `samples.spp`.
    pub spp_map: Option<Vec<f32>>,
}

/// Per-pixel analytic image gradients (direct illumination and the indirect term; pixel units; u to
/// the right, v downwards) and the magnitudes of the first-order paper's terms.
#[derive(Clone, Debug, Default)]
pub struct GradientPlanes {
    /// ∂I/∂u, ∂I/∂v: all terms, including visibility.
    pub grad_u: Vec<Vec3>,
    pub grad_v: Vec<Vec3>,
    /// |SV| = |L_x ⊗ ρ| projected to the image (luminance magnitude over u, v).
    pub sv: Vec<f32>,
    /// |DV| = |L_θ ⊗ ρ|: angular gradient of the reflected radiance, per radian.
    pub dv: Vec<f32>,
    /// CV = 2|n_x|, per unit length on the surface.
    pub cv: Vec<f32>,
    /// |CDV| = |2 n_x (L_θ ⊗ ρ)| projected to the image.
    pub cdv: Vec<f32>,
    /// |visibility term| projected to the image.
    pub vis: Vec<f32>,
    /// |indirect term| (curvature/bump and camera terms of indirect light).
    pub indirect: Vec<f32>,
    /// CDV / SV (the paper's Fig. 5e), 0 where both vanish.
    pub ratio: Vec<f32>,
    /// The mean of [`GradientSample::value`] (the direct light the gradient
    /// describes) and ∂/∂u, ∂/∂v of it alone (all terms but the indirect one):
    /// what a gradient-domain reconstruction solves for. Not written to files.
    pub direct: Vec<Vec3>,
    pub direct_u: Vec<Vec3>,
    pub direct_v: Vec<Vec3>,
}

impl GradientPlanes {
    fn new(n: usize) -> Self {
        Self {
            grad_u: vec![Vec3::ZERO; n],
            grad_v: vec![Vec3::ZERO; n],
            sv: vec![0.0; n],
            dv: vec![0.0; n],
            cv: vec![0.0; n],
            cdv: vec![0.0; n],
            vis: vec![0.0; n],
            indirect: vec![0.0; n],
            ratio: vec![0.0; n],
            direct: vec![Vec3::ZERO; n],
            direct_u: vec![Vec3::ZERO; n],
            direct_v: vec![Vec3::ZERO; n],
        }
    }

    /// Stores the mean gradient of one pixel's samples.
    fn set(&mut self, i: usize, g: &GradientSample) {
        let t = g.total();
        self.grad_u[i] = finite_or_zero(t[0]);
        self.grad_v[i] = finite_or_zero(t[1]);
        self.direct[i] = finite_or_zero(g.value);
        self.direct_u[i] = finite_or_zero(t[0] - g.indirect[0]);
        self.direct_v[i] = finite_or_zero(t[1] - g.indirect[1]);
        let fin = |x: f32| if x.is_finite() { x } else { 0.0 };
        let sv = fin(gradients::magnitude(&g.sv));
        let cdv = fin(gradients::magnitude(&g.cdv));
        self.sv[i] = sv;
        self.cdv[i] = cdv;
        self.dv[i] = fin(gradients::magnitude(&g.dv));
        self.cv[i] = fin(g.cv);
        self.vis[i] = fin(gradients::magnitude(&g.vis));
        self.indirect[i] = fin(gradients::magnitude(&g.indirect));
        self.ratio[i] = if cdv <= 0.0 {
            0.0
        } else {
            (cdv / sv.max(1e-12)).min(1e12)
        };
    }
}

#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub wall_time: Duration,
    /// Rays traced (camera, bounce and shadow rays together).
    pub rays: u64,
    /// With gradients: the share of the tracing time they took, measured on one
    /// sample in 64 traced with and without them.
    pub gradient_share: Option<f64>,
}

/// Progress callback: called with (pixels done, pixels total) from worker threads
/// (full renders), or (samples evaluated, samples in the budget) (adaptive renders).
pub type Progress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// Side length of the square tiles that rayon distributes.
const TILE: usize = 16;

/// What `render` builds for a scene before tracing: reported by `info`.
pub fn describe(scene: &Scene) -> String {
    let lights = LightSet::build(scene);
    let (rects, tris, spheres, env) = lights.counts();
    let env_sampler = match &lights.env_sampler {
        None => "none".to_string(),
        Some(lights::EnvSampler::CosineAboutNormal) => {
            "cosine-weighted about the shading normal".to_string()
        }
        Some(lights::EnvSampler::Image(_)) => "2D piecewise-constant (lat-long texels)".to_string(),
        Some(lights::EnvSampler::GaussianSky { lobe_prob }) => {
            format!("vMF lobe (p = {lobe_prob:.3}) + uniform")
        }
    };
    let bumped = scene.meshes.iter().filter(|m| m.bump.is_some()).count()
        + scene.spheres.iter().filter(|s| s.bump.is_some()).count();
    let shadows = if gradients::visibility::scene_can_cast_shadows(scene) {
        "line sampling with visibility jumps"
    } else {
        "skipped (nothing can cast a shadow)"
    };
    let shading = match lanes::refusal(scene) {
        None if lanes::avx2() => "eight hits at a time (AVX2 lanes)".to_string(),
        None => "eight hits at a time (SSE lanes)".to_string(),
        Some(why) => format!("one hit at a time ({why})"),
    };
    format!(
        "light sampling: {rects} rectangle lights, {tris} emitting triangles, {spheres} sphere lights{}; environment sampler: {env_sampler}; bump-mapped shapes: {bumped}; with --gradients, visibility term: {shadows}; path shading without --gradients: {shading}",
        if env { ", environment" } else { "" }
    )
}

/// The options resolved against the scene's `[render]` table, and the lights: what
/// every render path (full image or adaptive samples) starts from.
pub(crate) struct Setup {
    pub spp: u32,
    pub seed: u32,
    pub camera: crate::scene::Camera,
    max_depth: u32,
    rr_depth: u32,
    lights: LightSet,
    lines: Option<path::LineConfig>,
    far_light: Option<f32>,
    lanes: Option<lanes::LaneScene>,
}

impl Setup {
    pub fn new(scene: &Scene, opts: &RenderOptions) -> crate::Result<Self> {
        let settings = &scene.settings;
        let spp = opts.spp.unwrap_or(settings.spp);
        if spp == 0 {
            return Err(crate::Error::Option {
                option: "--spp".into(),
                message: "must be at least 1".into(),
            });
        }
        // 0 would never march a ring: its crossings' density would vanish (Inf).
        if let Some(q) = opts.vis_gate.filter(|q| !(*q > 0.0 && *q <= 1.0)) {
            return Err(crate::Error::Option {
                option: "--vis-gate".into(),
                message: format!("expected a probability in (0, 1], got {q}"),
            });
        }
        let integrator = opts.integrator.unwrap_or(settings.integrator);
        let max_depth = match integrator {
            Integrator::Path => opts.max_depth.unwrap_or(settings.max_depth),
            // Emitters seen directly plus one bounce of emitted light.
            Integrator::Direct => opts.max_depth.unwrap_or(2).min(2),
        };
        let camera = match opts.resolution {
            Some((w, h)) => {
                scene
                    .camera
                    .with_resolution(w, h)
                    .map_err(|message| crate::Error::Option {
                        option: "--width/--height".into(),
                        message,
                    })?
            }
            None => scene.camera.clone(),
        };
        let lights = LightSet::build(scene);
        Ok(Self {
            spp,
            seed: opts.seed.unwrap_or(settings.seed),
            camera,
            max_depth,
            rr_depth: settings.rr_depth,
            lanes: (!opts.gradients && !opts.no_lanes)
                .then(|| lanes::LaneScene::build(scene, &lights))
                .flatten(),
            lights,
            // Lines exist to find visibility jumps: none where nothing casts shadows,
            // and none when asked for 0 rays per line (shading terms only).
            lines: (opts.gradients
                && opts.vis_samples != Some(0)
                && gradients::visibility::scene_can_cast_shadows(scene))
            .then(|| path::LineConfig {
                n_theta: opts.vis_samples.unwrap_or(DEFAULT_VIS_SAMPLES),
                refine: opts.vis_refine.unwrap_or(0),
                gate: opts.vis_gate.unwrap_or(DEFAULT_VIS_GATE),
            }),
            far_light: opts.far_light,
        })
    }

    /// The lane shading's data, when the scene is one it takes and the render
    /// asks for no gradients (`render::lanes`).
    pub(crate) fn lanes(&self) -> Option<&lanes::LaneScene> {
        self.lanes.as_ref()
    }

    /// What every sample of a render reads; `first` is its first sample index.
    pub(crate) fn context<'a>(
        &'a self,
        scene: &'a Scene,
        accel: &'a Accel,
        opts: &RenderOptions,
        first: u32,
    ) -> SampleContext<'a> {
        SampleContext {
            tracer: self.tracer(scene, accel),
            camera: &self.camera,
            seed: self.seed,
            gradients: opts.gradients,
            first,
            lanes: self.lanes(),
            first_hits: opts.keeps_first_hits(),
        }
    }

    pub fn tracer<'a>(&'a self, scene: &'a Scene, accel: &'a Accel) -> PathTracer<'a> {
        PathTracer {
            scene,
            accel,
            lights: &self.lights,
            max_depth: self.max_depth,
            rr_depth: self.rr_depth,
            lines: self.lines,
            far_light: self.far_light,
        }
    }
}

/// A rectangle of pixels of the full image, half-open (x0 ≤ x < x1, y0 ≤ y < y1),
/// like pbrt-v4's `--pixelbounds`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Crop {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl Crop {
    /// The whole `w`×`h` image.
    pub fn full(w: u32, h: u32) -> Self {
        Self {
            x0: 0,
            y0: 0,
            x1: w,
            y1: h,
        }
    }

    pub fn width(&self) -> u32 {
        self.x1.saturating_sub(self.x0)
    }

    pub fn height(&self) -> u32 {
        self.y1.saturating_sub(self.y0)
    }

    /// Tile `k` of `n` (0-based) of a `w`×`h` image: `n` bands of whole rows, of
    /// heights differing by at most one, so that the tiles cover the image exactly
    /// once whatever `n` is (up to the image height).
    pub fn tile(k: u32, n: u32, w: u32, h: u32) -> Result<Self, String> {
        if n == 0 || k >= n {
            return Err(format!("{k}/{n}: expected K/N with 0 ≤ K < N"));
        }
        if n > h {
            return Err(format!(
                "{k}/{n}: the image has only {h} rows, so at most {h} tiles"
            ));
        }
        let row = |i: u32| (i as u64 * h as u64 / n as u64) as u32;
        Ok(Self {
            x0: 0,
            y0: row(k),
            x1: w,
            y1: row(k + 1),
        })
    }

    /// Ok when the crop is non-empty and lies inside a `w`×`h` image.
    pub fn check_inside(&self, w: u32, h: u32) -> Result<(), String> {
        if self.x0 >= self.x1 || self.y0 >= self.y1 {
            return Err(format!("{self}: empty (expected x0 < x1 and y0 < y1)"));
        }
        if self.x1 > w || self.y1 > h {
            return Err(format!("{self}: outside the {w}x{h} image"));
        }
        Ok(())
    }
}

impl std::fmt::Display for Crop {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "{},{},{},{}", self.x0, self.y0, self.x1, self.y1)
    }
}

/// What merging sample ranges needs beyond the planes a viewer sees: each is a
/// statistic from which the full render's value follows exactly (up to rounding).
#[derive(Clone, Debug, Default)]
pub struct MergePlanes {
    /// Samples whose camera ray hit a surface (the depth mean's denominator).
    pub hits: Vec<f32>,
    /// |Σ normal| / n: the length of the mean normal before it was normalised.
    pub normal_len: Vec<f32>,
    /// Luminance of the mean ∂/∂u and ∂/∂v of each gradient term, in the order of
    /// [`GRAD_TERM_LUMINANCES`] (the term magnitudes are not linear in the samples).
    pub grad_terms: Option<Vec<[f32; 10]>>,
}

/// Names of [`MergePlanes::grad_terms`]' entries: (term, u or v).
pub const GRAD_TERM_LUMINANCES: [&str; 10] = [
    "sv.u",
    "sv.v",
    "dv.u",
    "dv.v",
    "cdv.u",
    "cdv.v",
    "vis.u",
    "vis.v",
    "indirect.u",
    "indirect.v",
];

/// How a render is split in time: by default one pass of all samples; with a
/// `time_limit`, passes of doubling sample counts (sized to the time left) until
/// the time is up. Setting `cancel` (Ctrl-C) abandons the pass under way and keeps
/// the finished ones. A render in passes gives the same bits as one pass of the
/// sample count it reached: each pixel's sums run over its samples in order.
#[derive(Clone, Debug, Default)]
pub struct Passes {
    pub time_limit: Option<Duration>,
    pub cancel: Option<Arc<AtomicBool>>,
}

impl Passes {
    /// Whether Ctrl-C set the cancel flag: the render then holds the passes
    /// finished before it, not the samples asked for.
    pub fn interrupted(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|c| c.load(std::sync::atomic::Ordering::SeqCst))
    }
}

/// Renders the scene (or the crop and sample range `opts` asks for) in one pass.
/// Deterministic for a fixed seed, whatever the thread count: every random number
/// is addressed by (pixel, sample, dimension, seed).
pub fn render(
    scene: &Scene,
    accel: &Accel,
    opts: &RenderOptions,
    progress: Progress,
) -> crate::Result<RenderOutput> {
    render_passes(scene, accel, opts, &Passes::default(), progress)
}

/// The crop and the sample range a render covers, checked against the image and
/// `spp`: one clear error each, before anything is traced.
pub(crate) fn extent(setup: &Setup, opts: &RenderOptions) -> crate::Result<(Crop, Range<u32>)> {
    let (w, h) = (setup.camera.width, setup.camera.height);
    let crop = opts.crop.unwrap_or(Crop::full(w, h));
    crop.check_inside(w, h)
        .map_err(|message| crate::Error::Option {
            option: "--crop/--tile".into(),
            message,
        })?;
    let (a, b) = opts.sample_range.unwrap_or((0, setup.spp));
    if a >= b || b > setup.spp {
        return Err(crate::Error::Option {
            option: "--spp-range".into(),
            message: format!(
                "{a}:{b}: expected A:B with A < B ≤ the render's spp ({})",
                setup.spp
            ),
        });
    }
    Ok((crop, a..b))
}

/// [`render`] split into [`Passes`]. With a time limit, `progress` gets
/// (milliseconds elapsed, milliseconds allowed); otherwise (pixels done, pixels).
pub fn render_passes(
    scene: &Scene,
    accel: &Accel,
    opts: &RenderOptions,
    passes: &Passes,
    progress: Progress,
) -> crate::Result<RenderOutput> {
    let start = Instant::now();
    let setup = Setup::new(scene, opts)?;
    let (crop, range) = extent(&setup, opts)?;
    let ctx = setup.context(scene, accel, opts, range.start);
    let mut film = Film::new(crop, setup.camera.width as usize, ctx.gradients);
    let cancelled = || {
        passes
            .cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
    };
    match passes.time_limit {
        None => {
            let total = film.pixels();
            let done = AtomicUsize::new(0);
            let report = |n: usize| progress(done.fetch_add(n, Ordering::Relaxed) + n, total);
            let plan = |_: usize| range.clone();
            if !film.add_samples(&ctx, &plan, &cancelled, &report) {
                return Err(interrupted());
            }
        }
        Some(limit) => {
            let reached = timed_passes(&ctx, &mut film, range.clone(), limit, &cancelled, progress);
            if reached == range.start {
                return Err(interrupted());
            }
        }
    }
    let mut out = film.output(opts, range.start, (setup.camera.width, setup.camera.height));
    out.stats.wall_time = start.elapsed();
    Ok(out)
}

fn interrupted() -> crate::Error {
    crate::Error::Interrupted("before the first pass finished; nothing was written".into())
}

/// Passes of doubling sample counts from `range.start`, each sized to the time
/// left at the rate measured so far, until `limit` or `range.end`; returns the
/// first sample index not rendered. Only the first pass runs regardless of the
/// clock (so that there is an image); a pass overtaken by the limit or by a
/// cancel is abandoned.
fn timed_passes(
    ctx: &SampleContext,
    film: &mut Film,
    range: Range<u32>,
    limit: Duration,
    cancelled: &(dyn Fn() -> bool + Sync),
    progress: Progress,
) -> u32 {
    let start = Instant::now();
    let limit_ms = limit.as_millis().max(1) as usize;
    let report = |_: usize| progress(start.elapsed().as_millis() as usize, limit_ms);
    let mut next = range.start;
    while next < range.end && !cancelled() {
        let done = next - range.start;
        let size = if done == 0 {
            1
        } else {
            // Samples per pixel that fit in the time left at the rate so far.
            let per_sample = start.elapsed().as_secs_f64() / done as f64;
            let left = limit.as_secs_f64() - start.elapsed().as_secs_f64();
            let fit = (left / per_sample.max(1e-9)).floor().min(u32::MAX as f64) as u32;
            fit.min(done).min(range.end - next)
        };
        if size == 0 {
            break;
        }
        let over = || cancelled() || (done > 0 && start.elapsed() > limit);
        let pass = next..next + size;
        if !film.add_samples(ctx, &|_| pass.clone(), &over, &report) {
            break;
        }
        next += size;
    }
    next
}

/// What tracing one camera sample of a full-image pixel needs.
pub(crate) struct SampleContext<'a> {
    pub tracer: PathTracer<'a>,
    pub camera: &'a crate::scene::Camera,
    pub seed: u32,
    pub gradients: bool,
    /// The render's first sample index: its sample gives the object id.
    pub first: u32,
    /// Paths traced together and shaded in lanes, where the scene allows.
    pub lanes: Option<&'a lanes::LaneScene>,
    /// [`RenderOptions::keeps_first_hits`]: whether the lanes record them.
    pub first_hits: bool,
}

/// The running sums of every pixel of a crop, tile by tile (tiles in a scrambled
/// order, so that the pixels done so far are a fair sample of the image's cost:
/// in index order the cheap sky rows come first and the ETA is 2–3× optimistic).
#[derive(Clone)]
pub(crate) struct Film {
    crop: Crop,
    full_width: usize,
    /// Whether the tiles keep gradient sums.
    gradients: bool,
    tiles: Vec<FilmTile>,
}

#[derive(Clone)]
struct FilmTile {
    x0: usize,
    y0: usize,
    x1: usize,
    y1: usize,
    /// Empty until the film's first pass, which allocates it in the worker
    /// that renders the tile ([`FilmTile::working_copy`]).
    pixels: Vec<PixelAccumulator>,
    /// Each pixel's gradient sums, with `--gradients` only (empty otherwise: at
    /// 160 bytes a pixel they would be most of the film).
    gradients: Vec<GradientSum>,
}

impl FilmTile {
    fn pixel_count(&self) -> usize {
        (self.x1 - self.x0) * (self.y1 - self.y0)
    }

    /// The sums a pass adds to, leaving `self` as it was until the pass is
    /// done (all or nothing): a copy, or on the film's first pass fresh zeros.
    /// Why not zeros up front in `Film::new`: 128 bytes a pixel (8 MB at 256²)
    /// that one thread wrote before the render and the pass then copied.
    fn working_copy(&self, gradients: bool) -> FilmTile {
        if !self.pixels.is_empty() {
            return self.clone();
        }
        let n = self.pixel_count();
        FilmTile {
            pixels: vec![PixelAccumulator::default(); n],
            gradients: vec![GradientSum::default(); if gradients { n } else { 0 }],
            ..*self
        }
    }
}

impl Film {
    pub fn new(crop: Crop, full_width: usize, gradients: bool) -> Self {
        let (cx0, cy0) = (crop.x0 as usize, crop.y0 as usize);
        let (cx1, cy1) = (crop.x1 as usize, crop.y1 as usize);
        let tiles_x = (cx1 - cx0).div_ceil(TILE);
        let tiles_y = (cy1 - cy0).div_ceil(TILE);
        let tiles = scrambled_order(tiles_x * tiles_y)
            .into_iter()
            .map(|t| {
                let (x0, y0) = (cx0 + t % tiles_x * TILE, cy0 + t / tiles_x * TILE);
                let (x1, y1) = ((x0 + TILE).min(cx1), (y0 + TILE).min(cy1));
                FilmTile {
                    x0,
                    y0,
                    x1,
                    y1,
                    pixels: Vec::new(),
                    gradients: Vec::new(),
                }
            })
            .collect();
        Self {
            crop,
            full_width,
            gradients,
            tiles,
        }
    }

    pub fn pixels(&self) -> usize {
        self.crop.width() as usize * self.crop.height() as usize
    }

    /// Adds to every pixel the samples `plan(pixel)` names (pixel: linear index in
    /// the full image); `report(n)` after each tile of `n` pixels. All or nothing:
    /// when `cancelled()` turns true the film is left as it was and `false` returned.
    pub fn add_samples(
        &mut self,
        ctx: &SampleContext,
        plan: &(dyn Fn(usize) -> Range<u32> + Sync),
        cancelled: &(dyn Fn() -> bool + Sync),
        report: &(dyn Fn(usize) + Sync),
    ) -> bool {
        let w = self.full_width;
        let tiles: Option<Vec<FilmTile>> = self
            .tiles
            .par_iter()
            .map(|tile| {
                let mut t = tile.working_copy(self.gradients);
                let tw = t.x1 - t.x0;
                let mut batch = lanes::LaneBatch::default();
                let mut keys = Vec::new();
                for y in t.y0..t.y1 {
                    if cancelled() {
                        return None;
                    }
                    if let Some(lanes) = ctx.lanes {
                        // The row's samples traced together, `LANE_BATCH` at
                        // a time, and added in the order the loop below adds them.
                        let mut flush =
                            |batch: &mut lanes::LaneBatch, keys: &mut Vec<(usize, u32)>| {
                                lanes.trace(&ctx.tracer, batch, ctx.first_hits);
                                for ((i, s), r) in keys.drain(..).zip(batch.results()) {
                                    t.pixels[i].add(&r, s, s == ctx.first);
                                }
                            };
                        for x in t.x0..t.x1 {
                            let pixel = y * w + x;
                            let i = (y - t.y0) * tw + x - t.x0;
                            let corner = Vec2::new(x as f32, y as f32);
                            for s in plan(pixel) {
                                let (ray, sampler) =
                                    camera_ray(ctx.camera, corner, pixel as u32, s, ctx.seed);
                                batch.push(ray, sampler);
                                keys.push((i, s));
                                if batch.len() == LANE_BATCH {
                                    flush(&mut batch, &mut keys);
                                }
                            }
                        }
                        flush(&mut batch, &mut keys);
                        continue;
                    }
                    for x in t.x0..t.x1 {
                        let pixel = y * w + x;
                        let i = (y - t.y0) * tw + x - t.x0;
                        let acc = &mut t.pixels[i];
                        for s in plan(pixel) {
                            let sample = |gradients| {
                                camera_sample(
                                    &ctx.tracer,
                                    ctx.camera,
                                    pixel as u32,
                                    s,
                                    ctx.seed,
                                    gradients,
                                    Vec2::ZERO,
                                )
                            };
                            let r = traced_sample(
                                pixel as u32,
                                s,
                                ctx.gradients,
                                &mut acc.timing,
                                sample,
                            );
                            acc.add(&r, s, s == ctx.first);
                            if let (Some(g), Some(sum)) = (&r.gradient, t.gradients.get_mut(i)) {
                                sum.add(g);
                            }
                        }
                    }
                }
                report(tw * (t.y1 - t.y0));
                Some(t)
            })
            .collect();
        match tiles {
            Some(t) if !cancelled() => {
                self.tiles = t;
                true
            }
            _ => false,
        }
    }

    /// Calls `f(pixel, accumulator, gradient sums)` for every pixel (linear index
    /// in the full image); the gradient sums are there when the film keeps them.
    /// Before the first pass every pixel reads as empty, without sums.
    pub fn for_each(&self, mut f: impl FnMut(usize, &PixelAccumulator, Option<&GradientSum>)) {
        let empty = PixelAccumulator::default();
        for t in &self.tiles {
            let tw = t.x1 - t.x0;
            for i in 0..t.pixel_count() {
                f(
                    (t.y0 + i / tw) * self.full_width + t.x0 + i % tw,
                    t.pixels.get(i).unwrap_or(&empty),
                    t.gradients.get(i),
                );
            }
        }
    }

    /// The planes of the crop from each pixel's sums; `spp` is the most samples any
    /// pixel has.
    pub fn output(
        &self,
        opts: &RenderOptions,
        first_sample: u32,
        full: (u32, u32),
    ) -> RenderOutput {
        let (cw, ch) = (self.crop.width() as usize, self.crop.height() as usize);
        let n = cw * ch;
        let mut out = RenderOutput {
            width: cw,
            height: ch,
            beauty: vec![Vec3::ZERO; n],
            variance: opts.aovs.then(|| vec![Vec3::ZERO; n]),
            normal: opts.aovs.then(|| vec![Vec3::ZERO; n]),
            depth: opts.aovs.then(|| vec![0.0; n]),
            albedo: opts.aovs.then(|| vec![Vec3::ZERO; n]),
            object_id: opts.aovs.then(|| vec![0.0; n]),
            gradients: opts.gradients.then(|| GradientPlanes::new(n)),
            origin: (self.crop.x0 as usize, self.crop.y0 as usize),
            display: (full.0 as usize, full.1 as usize),
            first_sample,
            merge: opts.merge_planes.then(|| MergePlanes {
                hits: vec![0.0; n],
                normal_len: vec![0.0; n],
                grad_terms: opts.gradients.then(|| vec![[0.0; 10]; n]),
            }),
            ..Default::default()
        };
        let (cx0, cy0) = out.origin;
        let mut rays = 0;
        let mut spp = 0;
        let mut timing = [0.0; 2];
        self.for_each(|pixel, acc, gradient| {
            let (x, y) = (pixel % self.full_width, pixel / self.full_width);
            let i = (y - cy0) * cw + x - cx0;
            rays += acc.rays;
            timing = add_timing(timing, acc.timing);
            spp = spp.max(acc.count);
            acc.store(&mut out, i, gradient);
        });
        out.spp = spp;
        out.stats.rays = rays;
        out.stats.gradient_share = gradient_share(timing, 1.0);
        out
    }
}

/// The indices `0..n` in a fixed pseudo-random order (sorted by a hash).
fn scrambled_order(n: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&i| crate::math::sampler::hash2(i as u32, 0x7469_6c65));
    order
}

/// One camera sample of pixel `pixel` (linear index): jittered position inside
/// the pixel (box filter), shifted by `shift` pixels. Tests shift it to take
/// finite differences with the very same random numbers.
pub fn camera_sample(
    tracer: &PathTracer,
    camera: &crate::scene::Camera,
    pixel: u32,
    sample: u32,
    seed: u32,
    gradients: bool,
    shift: Vec2,
) -> SampleResult {
    let w = camera.width;
    let corner = Vec2::new((pixel % w) as f32, (pixel / w) as f32) + shift;
    camera_sample_at(tracer, camera, corner, pixel, sample, seed, gradients)
}

/// One camera sample jittered over the unit square at `corner` (image
/// coordinates); `key` addresses the random numbers (the pixel index for full
/// renders, a hash of the position for adaptive samples).
pub fn camera_sample_at(
    tracer: &PathTracer,
    camera: &crate::scene::Camera,
    corner: Vec2,
    key: u32,
    sample: u32,
    seed: u32,
    gradients: bool,
) -> SampleResult {
    let (ray, mut sampler) = camera_ray(camera, corner, key, sample, seed);
    let dd = gradients.then(|| {
        let d_len = 1.0 / ray.dir.dot(camera.forward());
        unit_direction_derivatives(ray.dir, d_len, camera.direction_derivatives())
    });
    tracer.li(ray, &mut sampler, dd)
}

/// Paths the lane shading traces together: enough for full lanes at the deep
/// bounces, few enough that their state stays in the L2 cache. 256 against 64:
/// cornell −1.8 % / −3.3 %, the bunny −2.7 % (benches/README.md, levers); 1,024
/// loses it again.
const LANE_BATCH: usize = 256;

/// A camera sample's ray and the sampler its path goes on drawing from: the
/// pixel jitter is its first two dimensions.
pub(crate) fn camera_ray(
    camera: &crate::scene::Camera,
    corner: Vec2,
    key: u32,
    sample: u32,
    seed: u32,
) -> (crate::math::Ray, PixelSampler) {
    let mut sampler = PixelSampler::new(key, sample, seed);
    let jitter = sampler.next_2d();
    (camera.generate_ray(corner + jitter), sampler)
}

/// Running sums of one pixel's samples (f64, so thousands of samples add exactly
/// enough for the variance estimate).
#[derive(Clone, Default)]
pub(crate) struct PixelAccumulator {
    pub count: u32,
    sum: [f64; 3],
    sum_sq: [f64; 3],
    /// Radiance sum of the samples of class A alone (half of them, see
    /// [`is_class_a`]): the noise-adaptive sampler's second estimate.
    class_a: [f64; 3],
    normal: Vec3,
    depth: f32,
    albedo: Vec3,
    object_id: u32,
    hits: u32,
    rays: u64,
    /// Seconds of the [`is_timed`] samples with and without their gradient.
    timing: [f64; 2],
}

/// The samples whose gradient cost is measured (one in 64, spread by a hash): each
/// is traced once more without gradients and both are timed, so that the summary
/// and `compare` can say what share of the render the gradients took (~1.5 % extra
/// work; no pixel changes).
fn is_timed(key: u32, sample: u32) -> bool {
    crate::math::sampler::hash2(key, sample ^ 0x6772_6164).is_multiple_of(64)
}

/// `sample(gradients)`; where it carries a gradient and [`is_timed`], also timed
/// against the same sample without one, the times added to `timing`.
pub(crate) fn traced_sample(
    key: u32,
    index: u32,
    gradients: bool,
    timing: &mut [f64; 2],
    sample: impl Fn(bool) -> SampleResult,
) -> SampleResult {
    if gradients && is_timed(key, index) {
        let (r, t) = timed_gradient_sample(key, index, sample);
        *timing = add_timing(*timing, t);
        r
    } else {
        sample(gradients)
    }
}

/// Traces `sample(true)`, the sample with gradients, and times it against the same
/// sample without them (the scalar tracer's: a plain render's lane kernel, where
/// the scene takes it, is faster still, so the share is a lower bound there): (its result, [seconds with, seconds without]). Which goes
/// first alternates (the second finds the caches warm), and a pair that took over
/// a millisecond (the thread was preempted) counts as zero.
fn timed_gradient_sample(
    key: u32,
    index: u32,
    sample: impl Fn(bool) -> SampleResult,
) -> (SampleResult, [f64; 2]) {
    let timed = |gradients| {
        let start = Instant::now();
        let r = std::hint::black_box(sample(gradients));
        (r, start.elapsed().as_secs_f64())
    };
    let ((r, with), (_, without)) = if crate::math::sampler::hash2(index, key) & 1 == 0 {
        (timed(true), timed(false))
    } else {
        let plain = timed(false);
        (timed(true), plain)
    };
    let kept = if with.max(without) < 1e-3 {
        [with, without]
    } else {
        [0.0; 2]
    };
    (r, kept)
}

/// Sums two [`timed_gradient_sample`] timings.
pub(crate) fn add_timing(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] + b[0], a[1] + b[1]]
}

/// The gradients' share of the tracing time from summed timings, where a fraction
/// `carried` of the samples carry one; `None` where nothing was timed. With r the
/// time without over the time with: carried (1 − r) / (carried + (1 − carried) r).
pub(crate) fn gradient_share(t: [f64; 2], carried: f64) -> Option<f64> {
    (t[0] > 0.0).then(|| {
        let r = t[1] / t[0];
        (carried * (1.0 - r) / (carried + (1.0 - carried) * r)).max(0.0)
    })
}

/// Splits the sample indices into two halves whose means are two independent
/// estimates of the pixel, each of them stratified (Christensen et al. 2018,
/// Sec. 10.2.1, as Cycles does: the parity of the odd bits of the index).
pub fn is_class_a(sample: u32) -> bool {
    (sample & 0xaaaa_aaaa).count_ones() & 1 == 1
}

/// How many of samples 0..n are class A: half of every aligned block of four,
/// and of the last, partial block those [`is_class_a`] picks (so that a
/// check after any number of samples weighs the half-estimate right).
pub(crate) fn class_a_count(n: u32) -> u32 {
    let whole = n / 4 * 4;
    whole / 2 + (whole..n).filter(|&s| is_class_a(s)).count() as u32
}

impl PixelAccumulator {
    /// Adds sample `index`; `first`: it is the render's first sample (object id).
    fn add(&mut self, r: &SampleResult, index: u32, first: bool) {
        self.count += 1;
        let l = finite_or_zero(r.radiance);
        let class_a = is_class_a(index);
        for (c, v) in l.to_array().into_iter().enumerate() {
            self.sum[c] += v as f64;
            self.sum_sq[c] += (v as f64) * (v as f64);
            if class_a {
                self.class_a[c] += v as f64;
            }
        }
        if let Some(fh) = &r.first_hit {
            self.normal += finite_or_zero(fh.normal);
            if fh.depth.is_finite() {
                self.depth += fh.depth;
                self.hits += 1;
            }
            self.albedo += fh.albedo;
            if first {
                self.object_id = fh.object_id;
            }
        }
        self.rays += r.rays as u64;
    }

    /// The pixel mean I and the class-A estimate A (the class-A sum over the
    /// class-A count of samples 0..count, so that E[A] = E[I] after any number of
    /// samples), RGB.
    pub fn mean_and_half(&self) -> ([f64; 3], [f64; 3]) {
        let n = self.count.max(1) as f64;
        let a = class_a_count(self.count).max(1) as f64;
        (self.sum.map(|s| s / n), self.class_a.map(|s| s / a))
    }
}

impl PixelAccumulator {
    /// Writes this pixel's means (and those of its `gradient` sums) into pixel `i`
    /// of `out`'s planes (those present).
    fn store(&self, out: &mut RenderOutput, i: usize, gradient: Option<&GradientSum>) {
        let spp = self.count.max(1);
        let n = spp as f64;
        let mean = [self.sum[0] / n, self.sum[1] / n, self.sum[2] / n];
        out.beauty[i] = Vec3::new(mean[0] as f32, mean[1] as f32, mean[2] as f32);
        if let (Some(planes), Some(sum)) = (&mut out.gradients, gradient) {
            let mut mean = GradientSample::default();
            mean.add_scaled(&sum.sample(), 1.0 / spp as f32);
            planes.set(i, &mean);
            if let Some(terms) = out.merge.as_mut().and_then(|m| m.grad_terms.as_mut()) {
                let [sv, dv, cdv, vis, ind] =
                    [&mean.sv, &mean.dv, &mean.cdv, &mean.vis, &mean.indirect];
                let lum = |g: &[Vec3; 2], k: usize| finite_or_zero_f32(luminance(g[k]));
                terms[i] = [
                    lum(sv, 0),
                    lum(sv, 1),
                    lum(dv, 0),
                    lum(dv, 1),
                    lum(cdv, 0),
                    lum(cdv, 1),
                    lum(vis, 0),
                    lum(vis, 1),
                    lum(ind, 0),
                    lum(ind, 1),
                ];
            }
        }
        if out.variance.is_none() {
            return;
        }
        // Variance of the pixel mean: unbiased sample variance / n.
        let var = |c: usize| -> f32 {
            if spp < 2 {
                return 0.0;
            }
            let v = (self.sum_sq[c] - self.sum[c] * self.sum[c] / n) / (n - 1.0);
            (v.max(0.0) / n) as f32
        };
        let inv = 1.0 / spp as f32;
        let set3 = |p: &mut Option<Vec<Vec3>>, v: Vec3| {
            if let Some(p) = p {
                p[i] = v;
            }
        };
        set3(&mut out.variance, Vec3::new(var(0), var(1), var(2)));
        set3(&mut out.normal, self.normal.normalize_or_zero());
        set3(&mut out.albedo, self.albedo * inv);
        if let Some(d) = &mut out.depth {
            // Mean distance over the samples that hit something.
            d[i] = self.depth / self.hits.max(1) as f32;
        }
        if let Some(id) = &mut out.object_id {
            id[i] = self.object_id as f32;
        }
        if let Some(m) = &mut out.merge {
            m.hits[i] = self.hits as f32;
            m.normal_len[i] = self.normal.length() / spp as f32;
        }
    }
}

fn finite_or_zero_f32(x: f32) -> f32 {
    if x.is_finite() {
        x
    } else {
        0.0
    }
}
