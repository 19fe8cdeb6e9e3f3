//! scene + BVH + image point → a converged estimate there: radiance, analytic
//! gradient, and the surface seen at the point (object, planar depth and its
//! tangent plane, facet normal, the Durand metric). The pipeline turns it into the
//! quadtree's samples; `render` does not know who asks.

use super::gradients::geometry::base_curvature;
use super::gradients::magnitude;
use super::interaction::{interaction, Interaction};
use super::path::PathTracer;
use super::{add_timing, camera_sample_at, gradient_share, traced_sample, Setup};
use crate::accel::{Accel, PrimRef};
use crate::math::sampler::hash2;
use crate::math::{Vec2, Vec3};
use crate::scene::{Camera, Scene};
use std::sync::Mutex;

/// One estimate at an image point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointEstimate {
    /// Mean radiance of all `spp` camera samples.
    pub radiance: Vec3,
    /// Mean ∂I/∂u, ∂I/∂v of the first `gradient_spp` samples (pixel units).
    pub grad_u: Vec3,
    pub grad_v: Vec3,
    /// Mean magnitude of their visibility (soft-shadow) term.
    pub vis_gradient: f32,
    /// Variance of the mean gradient (summed over components), from the samples'
    /// spread; `None` with a single gradient sample.
    pub gradient_variance: Option<f32>,
    /// Variance of the mean radiance (summed over R, G, B), from the `spp` samples'
    /// spread; `None` with a single sample. Lets the quadtree tell a firefly (one
    /// path carrying the estimate) from a real contrast.
    pub radiance_variance: Option<f32>,
    /// The surface exactly at the point; `None` for the background.
    pub surface: Option<SurfaceAt>,
    /// The first camera sample's path ended on the far side of a bump map's
    /// terminator (black), on the same object as `surface`.
    pub back_facing: bool,
}

/// The surface seen exactly at an estimate's position (the camera samples are
/// jittered over a pixel around it): what the boundary tests and the Durand metric
/// read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceAt {
    pub object_id: u32,
    /// Planar depth along the view axis (its inverse is affine across a plane).
    pub depth: f32,
    /// ∇(1/depth) in pixel units: the tangent plane.
    pub inv_depth_grad: Vec2,
    /// The geometric normal where the surface is flat shaded (a crease can show).
    pub facet_normal: Option<Vec3>,
    /// The Durand et al. 2005 bandwidth metric (Sec. 9.1).
    pub durand: f32,
}

/// The path tracer evaluated at arbitrary image points.
pub struct PointEstimator<'a> {
    pub tracer: PathTracer<'a>,
    pub camera: &'a Camera,
    /// Camera samples averaged per estimate.
    pub spp: u32,
    /// The first `gradient_spp` of them carry the gradient (1 ≤ it ≤ spp).
    pub gradient_spp: u32,
    pub seed: u32,
    /// Seconds of the timed samples with and without their gradient, summed over
    /// every estimate so far (`gradient_share`).
    pub timing: Mutex<[f64; 2]>,
}

impl<'a> PointEstimator<'a> {
    /// The estimator of a render setup: `spp` camera samples per estimate, the first
    /// `gradient_spp` of them (clamped to 1..=spp) carrying the gradient.
    pub(crate) fn new(
        setup: &'a Setup,
        scene: &'a Scene,
        accel: &'a Accel,
        gradient_spp: u32,
    ) -> Self {
        Self {
            tracer: setup.tracer(scene, accel),
            camera: &setup.camera,
            spp: setup.spp,
            gradient_spp: gradient_spp.clamp(1, setup.spp),
            seed: setup.seed,
            timing: Mutex::new([0.0; 2]),
        }
    }

    /// The gradients' share of the tracing time of the estimates so far (only the
    /// first `gradient_spp` of each estimate's samples carry one).
    pub fn gradient_share(&self) -> Option<f64> {
        let carried = f64::from(self.gradient_spp) / f64::from(self.spp.max(1));
        gradient_share(
            *self.timing.lock().unwrap_or_else(|e| e.into_inner()),
            carried,
        )
    }

    /// The estimate at image point `p` (continuous pixel coordinates).
    pub fn estimate(&self, p: Vec2) -> PointEstimate {
        // Random numbers are addressed by the sample position, so the estimate is
        // the same whatever order or thread evaluates it.
        let key = hash2(p.x.to_bits(), p.y.to_bits());
        let (mut radiance, mut gu, mut gv, mut vis) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, 0.0f32);
        let (mut sq, mut radiance_sq) = (0.0f32, 0.0f32);
        let mut first = None;
        let mut timing = [0.0; 2];
        for s in 0..self.spp {
            // A pixel-sized box footprint around p, as the full render's pixels have.
            let sample = |gradients| {
                camera_sample_at(
                    &self.tracer,
                    self.camera,
                    p - Vec2::splat(0.5),
                    key,
                    s,
                    self.seed,
                    gradients,
                )
            };
            let r = traced_sample(key, s, s < self.gradient_spp, &mut timing, sample);
            radiance += r.radiance;
            radiance_sq += r.radiance.length_squared();
            if let Some(g) = r.gradient {
                let t = g.total();
                gu += t[0];
                gv += t[1];
                sq += t[0].length_squared() + t[1].length_squared();
                vis += magnitude(&g.vis);
            }
            if s == 0 {
                first = Some(r);
            }
        }
        if timing[0] > 0.0 {
            let mut sum = self.timing.lock().unwrap_or_else(|e| e.into_inner());
            *sum = add_timing(*sum, timing);
        }
        let n = self.spp as f32;
        let ng = self.gradient_spp as f32;
        let (grad_u, grad_v) = (gu / ng, gv / ng);
        let gradient_variance =
            variance_of_mean(sq, grad_u.length_squared() + grad_v.length_squared(), ng);
        let radiance_variance = variance_of_mean(radiance_sq, (radiance / n).length_squared(), n);
        let surface = self.surface_at(p);
        let back_facing = surface.is_some_and(|c| {
            first
                .and_then(|r| r.first_hit)
                .is_some_and(|fh| fh.back_facing && fh.object_id == c.object_id)
        });
        PointEstimate {
            radiance: radiance / n,
            grad_u,
            grad_v,
            vis_gradient: vis / ng,
            gradient_variance,
            radiance_variance,
            surface,
            back_facing,
        }
    }
    /// Object id, planar depth, tangent plane and (where flat-shaded) facet normal of
    /// the first hit of the ray through `p`, and the Durand metric there; `None` for
    /// the background.
    ///
    /// The depth is `z = t (d·f)`, along the view axis `f`: on the plane through the
    /// hit point `x` with geometric normal `n`, the ray `o + s D(p)` (unnormalised
    /// direction, `D·f = 1`, affine in `p`) meets it at `z = n·(x − o) / n·D`, so
    /// `1/z` is affine in the image and `∇(1/z) = (n·∂D/∂u, n·∂D/∂v) / n·(x − o)`
    /// with `n·(x − o) = t n·d`. (The distance `t` along the unit ray has no affine
    /// inverse: `1/t` carries a factor `1/|D|`.)
    pub fn surface_at(&self, p: Vec2) -> Option<SurfaceAt> {
        let scene = self.tracer.scene;
        let ray = self.camera.generate_ray(p);
        let hit = self.tracer.accel.intersect(&ray)?;
        let si = interaction(scene, self.tracer.accel, &ray, &hit);
        let d = ray.dir;
        let [du, dv] = self.camera.direction_derivatives();
        let g = Vec2::new(si.ng.dot(du), si.ng.dot(dv)) / (hit.t * si.ng.dot(d));
        Some(SurfaceAt {
            object_id: si.object_id,
            depth: hit.t * d.dot(self.camera.forward()),
            inv_depth_grad: if g.is_finite() { g } else { Vec2::ZERO },
            facet_normal: flat_shaded(scene, &si).then_some(si.ng),
            durand: self.durand(&si, hit.t, d),
        })
    }

    /// The Durand et al. 2005 metric as written in Sec. 9.1 of the first-order
    /// paper: I ∼ (1/γ) · 2kz / (n₀·v) · Ω_ρ, Ω_ρ = √(6s), with γ the focal length
    /// in pixels, k the base curvature (no bump maps), z the distance, n₀·v the
    /// cosine between the geometric normal and the view ray and s the Phong
    /// exponent (1 for Lambert, a large value for mirrors).
    fn durand(&self, si: &Interaction, z: f32, dir: Vec3) -> f32 {
        let scene = self.tracer.scene;
        let k = base_curvature(scene, si);
        let gamma =
            self.camera.height as f32 / (2.0 * (self.camera.fov_y.to_radians() * 0.5).tan());
        let cos = si.ng.dot(-dir).abs().max(1e-3);
        let omega = scene.materials[si.material as usize].angular_bandwidth();
        let m = (1.0 / gamma) * 2.0 * k * z / cos * omega;
        if m.is_finite() {
            m
        } else {
            0.0
        }
    }
}

/// Whether the hit's shading normal is its facet's (a triangle of a mesh without
/// vertex normals: quads, cubes, OBJs without `vn`), so that a crease shows.
fn flat_shaded(scene: &Scene, si: &Interaction) -> bool {
    match si.prim {
        PrimRef::Triangle { mesh, .. } => scene.meshes[mesh as usize].normals.is_empty(),
        PrimRef::Sphere(_) => false,
    }
}

/// Variance of a mean of `n` samples (summed over components), from the sum of
/// their squared lengths and the squared length of the mean: (E|x|² − |E x|²) /
/// (n − 1), which carries the unbiased n/(n − 1) factor; `None` for one sample.
fn variance_of_mean(sum_sq: f32, mean_sq: f32, n: f32) -> Option<f32> {
    (n > 1.0).then(|| ((sum_sq / n - mean_sq) / (n - 1.0)).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::RenderOptions;
    use std::path::Path;

    /// Only the first `gradient_spp` camera samples carry the gradient: with the same
    /// first two samples, the gradient is the same whether 2 or 8 samples are taken
    /// in all, while the radiance averages all of them.
    #[test]
    fn gradient_comes_from_the_first_gradient_spp_samples() {
        let scene = crate::scene::load(Path::new("scenes/three_spheres_env.toml")).unwrap();
        let accel = Accel::build(&scene.meshes, &scene.spheres);
        let opts = RenderOptions {
            resolution: Some((64, 48)),
            gradients: true,
            vis_samples: Some(4),
            ..Default::default()
        };
        let setup = Setup::new(&scene, &opts).unwrap();
        let est = |spp: u32, gradient_spp: u32| PointEstimator {
            tracer: setup.tracer(&scene, &accel),
            camera: &setup.camera,
            spp,
            gradient_spp,
            timing: Default::default(),
            seed: 7,
        };
        let mut differ = 0;
        for k in 0..40 {
            let p = Vec2::new(3.5 + 1.47 * k as f32, 30.25 + 0.3 * k as f32);
            let (a, b) = (est(2, 2).estimate(p), est(8, 2).estimate(p));
            assert_eq!((a.grad_u, a.grad_v), (b.grad_u, b.grad_v), "at {p}");
            assert_eq!(a.vis_gradient, b.vis_gradient);
            differ += (a.radiance != b.radiance) as u32;
            let c = est(8, 8).estimate(p);
            differ += (c.grad_u != b.grad_u) as u32;
        }
        assert!(
            differ > 40,
            "radiance and gradient should depend on the counts"
        );
    }

    /// `f` with the scene at `path`, its setup at `resolution` and a one-sample
    /// estimator (they borrow each other, so they live only inside the call).
    fn with_estimator<R>(
        path: &str,
        resolution: (u32, u32),
        f: impl FnOnce(&Scene, &Setup, PointEstimator) -> R,
    ) -> R {
        let scene = crate::scene::load(Path::new(path)).unwrap();
        let accel = Accel::build(&scene.meshes, &scene.spheres);
        let opts = RenderOptions {
            resolution: Some(resolution),
            ..Default::default()
        };
        let setup = Setup::new(&scene, &opts).unwrap();
        let est = PointEstimator {
            tracer: setup.tracer(&scene, &accel),
            camera: &setup.camera,
            spp: 1,
            gradient_spp: 1,
            seed: 1,
            timing: Default::default(),
        };
        f(&scene, &setup, est)
    }

    /// The tangent plane the estimator reports, ∇(1/depth), against central
    /// differences of 1/depth at ±¼ pixel, on the ground sphere and the spheres of
    /// spheres_table (O(h²)).
    #[test]
    fn inverse_depth_gradient_matches_finite_differences() {
        with_estimator("scenes/spheres_table.toml", (240, 160), |_, _, est| {
            let h = 0.25f32;
            let mut errors = Vec::new();
            for j in 0..16 {
                for i in 0..24 {
                    let p = Vec2::new(5.13 + 10.0 * i as f32, 5.37 + 10.0 * j as f32);
                    let Some(c) = est.surface_at(p) else { continue };
                    let side = |e: Vec2| {
                        let (a, b) = (est.surface_at(p + e * h)?, est.surface_at(p - e * h)?);
                        (a.object_id == c.object_id && b.object_id == c.object_id)
                            .then(|| (1.0 / a.depth - 1.0 / b.depth) / (2.0 * h))
                    };
                    let (Some(fu), Some(fv)) = (side(Vec2::X), side(Vec2::Y)) else {
                        continue;
                    };
                    let fd = Vec2::new(fu, fv);
                    // Relative to the size of 1/depth's change over one pixel at all.
                    let scale = fd
                        .length()
                        .max(c.inv_depth_grad.length())
                        .max(1e-3 / c.depth);
                    errors.push((fd - c.inv_depth_grad).length() / scale);
                }
            }
            errors.sort_by(f32::total_cmp);
            let n = errors.len();
            let (median, p99) = (errors[n / 2], errors[n * 99 / 100]);
            let max = errors[n - 1];
            println!(
                "∇(1/depth) at {n} points: relative error median {median:.1e}, \
                 99th percentile {p99:.1e}, max {max:.1e}"
            );
            assert!(n > 200, "only {n} points on one surface");
            assert!(median < 1e-3 && p99 < 1e-2, "median {median}, p99 {p99}");
        });
    }

    /// Facet normals come from flat-shaded surfaces only: in the Cornell box (quads
    /// and cubes, no vertex normals) every hit has one, and each cube shows more than
    /// one facet; on objects_bumpy's smoothed meshes and spheres none has one, while
    /// its floor quad does.
    #[test]
    fn facet_normals_mark_flat_shaded_surfaces() {
        // Object id, facet normal and whether a sphere was hit, on a 64×64 grid;
        // with the scene's object names.
        let hits = |path: &str| {
            with_estimator(path, (64, 64), |scene, setup, est| {
                let mut out = Vec::new();
                for j in 0..64 {
                    for i in 0..64 {
                        let p = Vec2::new(0.5 + i as f32, 0.5 + j as f32);
                        if let Some(c) = est.surface_at(p) {
                            let ray = setup.camera.generate_ray(p);
                            let sphere = matches!(
                                est.tracer.accel.intersect(&ray).map(|h| h.prim),
                                Some(PrimRef::Sphere(_))
                            );
                            out.push((c.object_id, c.facet_normal, sphere));
                        }
                    }
                }
                (scene.object_names.clone(), out)
            })
        };
        let (names, box_hits) = hits("scenes/cornell.toml");
        assert!(
            box_hits.iter().all(|h| h.1.is_some()),
            "a Cornell box hit without a facet"
        );
        // Object ids start at 1 (`Scene::object_names` is indexed by id − 1).
        let name = |id: u32| names[id as usize - 1].as_str();
        let cubes: Vec<u32> = (1..=names.len() as u32)
            .filter(|&id| name(id).contains("box"))
            .collect();
        assert!(!cubes.is_empty());
        for id in cubes {
            let mut normals: Vec<Vec3> = Vec::new();
            for n in box_hits.iter().filter(|h| h.0 == id).filter_map(|h| h.1) {
                if normals
                    .iter()
                    // A cube's facets are 90° apart.
                    .all(|m| m.dot(n) < 0.5)
                {
                    normals.push(n);
                }
            }
            println!("{}: {} facets in view", name(id), normals.len());
            assert!(normals.len() >= 2, "{} shows one facet", name(id));
        }
        let (_, bumpy_hits) = hits("scenes/objects_bumpy.toml");
        let flat = bumpy_hits.iter().filter(|h| h.1.is_some()).count();
        assert!(
            flat > 0 && flat < bumpy_hits.len(),
            "{flat} of {}",
            bumpy_hits.len()
        );
        assert!(bumpy_hits.iter().filter(|h| h.2).all(|h| h.1.is_none()));
    }
}
