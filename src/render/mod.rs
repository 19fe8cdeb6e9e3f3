//! scene + BVH → per-pixel estimates (radiance, AOVs, analytic gradients) by
//! path tracing; `point` evaluates the same estimator at arbitrary image points
//! (the pipeline's adaptive renders ask it for their samples).

pub mod gradients;
pub mod interaction;
pub mod lights;
pub mod path;
pub mod point;

use crate::accel::Accel;
use crate::math::sampler::PixelSampler;
use crate::math::{finite_or_zero, Vec2, Vec3};
use crate::scene::{Integrator, Scene};
use gradients::geometry::unit_direction_derivatives;
use gradients::GradientSample;
use lights::LightSet;
use path::{PathTracer, SampleResult};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

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
    /// With gradients: shadow rays per φ-line for the first hit's direct light
    /// (visibility gradients need a line; default 32). 0: point sampling and no
    /// visibility term, the cheapest gradients.
    pub vis_samples: Option<u32>,
    /// With gradients: bisection steps that refine each visibility jump (default 0).
    pub vis_refine: Option<u32>,
    /// With gradients: treat near lights as distant where 2|n_x|·d exceeds this
    /// factor (the far-light criterion of Sec. 5.2), dropping their SV term.
    pub far_light: Option<f32>,
    /// Adaptive renders: how many of each sample's `spp` camera samples carry the
    /// analytic gradient (dual lanes, and line sampling for the visibility term);
    /// the rest are plain path samples that only refine the radiance. The gradient
    /// steers placement and interpolation and needs far fewer samples than a
    /// converged radiance, so this bounds its cost (default: all of them, up to 16).
    pub gradient_spp: Option<u32>,
}

impl RenderOptions {
    /// The image size this render will have: the override, else the camera's.
    pub fn resolution_of(&self, scene: &Scene) -> (u32, u32) {
        self.resolution
            .unwrap_or((scene.camera.width, scene.camera.height))
    }
}

/// What a render produced: row-major planes, top row first.
#[derive(Clone, Debug)]
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
        }
    }

    /// Stores the mean gradient of one pixel's samples.
    fn set(&mut self, i: usize, g: &GradientSample) {
        let t = g.total();
        self.grad_u[i] = finite_or_zero(t[0]);
        self.grad_v[i] = finite_or_zero(t[1]);
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
}

/// Progress callback: called with (pixels done, pixels total) from worker threads
/// (full renders), or (samples evaluated, samples in the budget) (adaptive renders).
pub type Progress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// Side length of the square tiles that rayon distributes.
const TILE: usize = 16;

/// What `render` builds for a scene before tracing: reported by `info`.
pub fn describe(scene: &Scene) -> String {
    let lights = LightSet::build(scene);
    let (tris, spheres, env) = lights.counts();
    let env_sampler = match &lights.env_sampler {
        None => "none".to_string(),
        Some(lights::EnvSampler::Uniform) => "uniform sphere".to_string(),
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
    format!(
        "light sampling: {tris} emitting triangles, {spheres} sphere lights{}; environment sampler: {env_sampler}; bump-mapped shapes: {bumped}; with --gradients, visibility term: {shadows}",
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
        Ok(Self {
            spp,
            seed: opts.seed.unwrap_or(settings.seed),
            camera,
            max_depth,
            rr_depth: settings.rr_depth,
            lights: LightSet::build(scene),
            // Lines exist to find visibility jumps: none where nothing casts shadows,
            // and none when asked for 0 rays per line (shading terms only).
            lines: (opts.gradients
                && opts.vis_samples != Some(0)
                && gradients::visibility::scene_can_cast_shadows(scene))
            .then(|| path::LineConfig {
                n_theta: opts.vis_samples.unwrap_or(32),
                refine: opts.vis_refine.unwrap_or(0),
            }),
            far_light: opts.far_light,
        })
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

/// Renders the scene. Deterministic for a fixed seed, whatever the thread count:
/// every random number is addressed by (pixel, sample, dimension, seed).
pub fn render(
    scene: &Scene,
    accel: &Accel,
    opts: &RenderOptions,
    progress: Progress,
) -> crate::Result<RenderOutput> {
    let start = Instant::now();
    let setup = Setup::new(scene, opts)?;
    let (spp, seed, camera) = (setup.spp, setup.seed, setup.camera.clone());
    let (w, h) = (camera.width as usize, camera.height as usize);
    let tracer = setup.tracer(scene, accel);

    let tiles_x = w.div_ceil(TILE);
    let tiles_y = h.div_ceil(TILE);
    let total = tiles_x * tiles_y;
    let done = AtomicUsize::new(0);
    // Tiles are rendered in a scrambled order so that the pixels done so far are a
    // fair sample of the image's cost (in index order the cheap sky rows come first
    // and the ETA is 2–3× optimistic). The image does not depend on the order.
    let order = scrambled_order(total);
    let render_tile = |tile: usize| -> TileResult {
        let (tx, ty) = (tile % tiles_x, tile / tiles_x);
        let x0 = tx * TILE;
        let y0 = ty * TILE;
        let x1 = (x0 + TILE).min(w);
        let y1 = (y0 + TILE).min(h);
        let mut res = TileResult::new(x0, y0, x1 - x0, y1 - y0, opts.aovs, opts.gradients);
        for y in y0..y1 {
            for x in x0..x1 {
                let pixel = (y * w + x) as u32;
                let mut acc = PixelAccumulator::default();
                for s in 0..spp {
                    let r =
                        camera_sample(&tracer, &camera, pixel, s, seed, opts.gradients, Vec2::ZERO);
                    acc.add(&r, s == 0);
                }
                res.store(x - x0, y - y0, &acc, spp);
            }
        }
        let n = done.fetch_add((x1 - x0) * (y1 - y0), Ordering::Relaxed) + (x1 - x0) * (y1 - y0);
        progress(n, w * h);
        res
    };
    let tiles: Vec<TileResult> = order.into_par_iter().map(render_tile).collect();

    let mut out = RenderOutput {
        width: w,
        height: h,
        spp,
        beauty: vec![Vec3::ZERO; w * h],
        variance: opts.aovs.then(|| vec![Vec3::ZERO; w * h]),
        normal: opts.aovs.then(|| vec![Vec3::ZERO; w * h]),
        depth: opts.aovs.then(|| vec![0.0; w * h]),
        albedo: opts.aovs.then(|| vec![Vec3::ZERO; w * h]),
        object_id: opts.aovs.then(|| vec![0.0; w * h]),
        gradients: opts.gradients.then(|| GradientPlanes::new(w * h)),
        stats: RenderStats::default(),
    };
    let mut rays = 0u64;
    for t in &tiles {
        rays += t.rays;
        t.scatter(&mut out, w);
    }
    out.stats = RenderStats {
        wall_time: start.elapsed(),
        rays,
    };
    Ok(out)
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
    let mut sampler = PixelSampler::new(key, sample, seed);
    let jitter = sampler.next_2d();
    let p = corner + jitter;
    let ray = camera.generate_ray(p);
    let dd = gradients.then(|| {
        let d_len = 1.0 / ray.dir.dot(camera.forward());
        unit_direction_derivatives(ray.dir, d_len, camera.direction_derivatives())
    });
    tracer.li(ray, &mut sampler, dd)
}

/// Running sums of one pixel's samples (f64, so thousands of samples add exactly
/// enough for the variance estimate).
#[derive(Default)]
struct PixelAccumulator {
    sum: [f64; 3],
    sum_sq: [f64; 3],
    normal: Vec3,
    depth: f32,
    albedo: Vec3,
    object_id: u32,
    hits: u32,
    rays: u64,
    gradient: GradientSample,
}

impl PixelAccumulator {
    fn add(&mut self, r: &SampleResult, first: bool) {
        let l = finite_or_zero(r.radiance);
        for (c, v) in l.to_array().into_iter().enumerate() {
            self.sum[c] += v as f64;
            self.sum_sq[c] += (v as f64) * (v as f64);
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
        if let Some(g) = &r.gradient {
            self.gradient.add_scaled(g, 1.0);
        }
    }
}

struct TileResult {
    x0: usize,
    y0: usize,
    w: usize,
    beauty: Vec<Vec3>,
    aovs: Option<Vec<[f32; 11]>>,
    gradients: Option<Vec<GradientSample>>,
    rays: u64,
}

impl TileResult {
    fn new(x0: usize, y0: usize, w: usize, h: usize, aovs: bool, gradients: bool) -> Self {
        Self {
            x0,
            y0,
            w,
            beauty: vec![Vec3::ZERO; w * h],
            aovs: aovs.then(|| vec![[0.0; 11]; w * h]),
            gradients: gradients.then(|| vec![GradientSample::default(); w * h]),
            rays: 0,
        }
    }

    fn store(&mut self, x: usize, y: usize, acc: &PixelAccumulator, spp: u32) {
        let n = spp as f64;
        let i = y * self.w + x;
        let mean = [acc.sum[0] / n, acc.sum[1] / n, acc.sum[2] / n];
        self.beauty[i] = Vec3::new(mean[0] as f32, mean[1] as f32, mean[2] as f32);
        self.rays += acc.rays;
        if let Some(g) = &mut self.gradients {
            let mut mean = GradientSample::default();
            mean.add_scaled(&acc.gradient, 1.0 / spp as f32);
            g[i] = mean;
        }
        if let Some(a) = &mut self.aovs {
            // Variance of the pixel mean: unbiased sample variance / n.
            let var = |c: usize| -> f32 {
                if spp < 2 {
                    return 0.0;
                }
                let v = (acc.sum_sq[c] - acc.sum[c] * acc.sum[c] / n) / (n - 1.0);
                (v.max(0.0) / n) as f32
            };
            let nrm = acc.normal.normalize_or_zero();
            let inv = 1.0 / spp as f32;
            a[i] = [
                var(0),
                var(1),
                var(2),
                nrm.x,
                nrm.y,
                nrm.z,
                // Mean distance over the samples that hit something.
                acc.depth / acc.hits.max(1) as f32,
                acc.albedo.x * inv,
                acc.albedo.y * inv,
                acc.albedo.z * inv,
                acc.object_id as f32,
            ];
        }
    }

    fn scatter(&self, out: &mut RenderOutput, width: usize) {
        let h = self.beauty.len() / self.w;
        for y in 0..h {
            for x in 0..self.w {
                let src = y * self.w + x;
                let dst = (self.y0 + y) * width + self.x0 + x;
                out.beauty[dst] = self.beauty[src];
                if let (Some(g), Some(planes)) = (&self.gradients, &mut out.gradients) {
                    planes.set(dst, &g[src]);
                }
                if let Some(a) = &self.aovs {
                    let a = &a[src];
                    if let Some(v) = &mut out.variance {
                        v[dst] = Vec3::new(a[0], a[1], a[2]);
                    }
                    if let Some(v) = &mut out.normal {
                        v[dst] = Vec3::new(a[3], a[4], a[5]);
                    }
                    if let Some(v) = &mut out.depth {
                        v[dst] = a[6];
                    }
                    if let Some(v) = &mut out.albedo {
                        v[dst] = Vec3::new(a[7], a[8], a[9]);
                    }
                    if let Some(v) = &mut out.object_id {
                        v[dst] = a[10];
                    }
                }
            }
        }
    }
}
