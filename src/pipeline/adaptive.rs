//! Adaptive render: the renderer's point estimates as the quadtree's samples
//! (`render::point` → `adaptive::Estimator`), then the Delaunay reconstruction.
//! The adapter lives here so that `adaptive` stays renderer-agnostic (it is tested
//! on analytic images) and `render` does not know who asks for its samples.

use crate::accel::Accel;
use crate::adaptive::{self, Estimator, SampleSet, SampleValue, Settings, NO_OBJECT};
use crate::math::Vec2;
use crate::reconstruct::{self, Interpolation, Reconstruction};
use crate::render::point::{PointEstimate, PointEstimator};
use crate::render::{Progress, RenderOptions, Setup};
use crate::scene::Scene;
use std::time::Instant;

/// The renderer's estimator, as the quadtree sees it.
pub struct RenderedSamples<'a>(pub PointEstimator<'a>);

impl Estimator for RenderedSamples<'_> {
    fn estimate(&self, p: Vec2) -> SampleValue {
        sample_value(&self.0.estimate(p))
    }
}

/// A point estimate in the quadtree's terms. The background has no object, an
/// infinite depth and a Durand metric of 0.
pub fn sample_value(e: &PointEstimate) -> SampleValue {
    let mut v = SampleValue::new(e.radiance, e.grad_u, e.grad_v);
    v.vis_gradient = Some(e.vis_gradient);
    v.gradient_variance = e.gradient_variance;
    v.radiance_variance = e.radiance_variance;
    v.object_id = NO_OBJECT;
    v.depth = f32::INFINITY;
    v.durand = Some(0.0);
    if let Some(c) = &e.surface {
        v.object_id = c.object_id;
        v.depth = c.depth;
        v.inv_depth_grad = c.inv_depth_grad;
        v.facet_normal = c.facet_normal;
        v.durand = Some(c.durand);
        v.back_facing = e.back_facing;
    }
    v
}

/// Timings of one adaptive render, in seconds.
#[derive(Clone, Copy, Debug, Default)]
pub struct AdaptiveStats {
    pub wall_s: f64,
    /// The quadtree's own work, excluding the estimate batches it asked for (idle
    /// threads at a batch's end count as estimating, as a full render's last tile does).
    pub quadtree_s: f64,
    pub reconstruct_s: f64,
    /// Wall time of the estimate batches (the rendering itself).
    pub estimate_s: f64,
    /// The analytic gradients' share of the estimates' tracing time
    /// (`PointEstimator::gradient_share`).
    pub gradient_share: Option<f64>,
}

/// What an adaptive render produced.
pub struct AdaptiveRender {
    pub reconstruction: Reconstruction,
    pub samples: SampleSet,
    pub stats: AdaptiveStats,
}

/// Renders with `settings.strategy` at `settings.budget` samples per pixel, each a
/// `spp`-sample estimate with analytic gradients, then reconstructs every pixel.
pub fn render_adaptive(
    scene: &Scene,
    accel: &Accel,
    opts: &RenderOptions,
    settings: &Settings,
    interpolation: Interpolation,
    progress: Progress,
) -> crate::Result<AdaptiveRender> {
    let start = Instant::now();
    // Gradients are what the strategies and the C1 reconstruction feed on. Many
    // short lines (16 camera samples × 4 shadow rays) give a less noisy gradient
    // than few long ones for the same rays.
    let opts = RenderOptions {
        gradients: true,
        vis_samples: opts.vis_samples.or(Some(4)),
        ..opts.clone()
    };
    let setup = Setup::new(scene, &opts)?;
    let est = RenderedSamples(PointEstimator::new(
        &setup,
        scene,
        accel,
        opts.gradient_spp.unwrap_or(16),
    ));
    let (w, h) = (setup.camera.width, setup.camera.height);
    let (samples, refine) = adaptive::refine_with_stats(&est, w, h, settings, progress)?;
    let t = Instant::now();
    let reconstruction = reconstruct::reconstruct(&samples, interpolation)?;
    let reconstruct_s = t.elapsed().as_secs_f64();
    Ok(AdaptiveRender {
        reconstruction,
        samples,
        stats: AdaptiveStats {
            wall_s: start.elapsed().as_secs_f64(),
            quadtree_s: refine.quadtree_s,
            reconstruct_s,
            estimate_s: refine.evaluate_s,
            gradient_share: est.0.gradient_share(),
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use std::path::Path;

    /// A plane seen at a 90° field of view is one surface for the step test, at the
    /// sample spacings of coarse budgets (16 and 32 px): the planar depth's inverse is
    /// affine in the image. (With the distance along the unit ray, whose inverse is
    /// not, 2–3% misses read as steps across the ground.)
    #[test]
    fn a_plane_at_a_wide_field_of_view_is_one_surface() {
        let scene = crate::scene::load(Path::new("scenes/three_spheres_env.toml")).unwrap();
        let accel = Accel::build(&scene.meshes, &scene.spheres);
        let opts = RenderOptions {
            resolution: Some((480, 320)),
            ..Default::default()
        };
        let setup = Setup::new(&scene, &opts).unwrap();
        let c = &setup.camera;
        let wide = crate::scene::Camera::new(c.from, c.to, c.up, 90.0, 480, 320).unwrap();
        let est = PointEstimator {
            camera: &wide,
            ..PointEstimator::new(&setup, &scene, &accel, 1)
        };
        {
            {
                let ground = scene
                    .object_names
                    .iter()
                    .position(|n| n == "ground")
                    .unwrap() as u32
                    + 1;
                let tol = crate::adaptive::Settings::new(crate::adaptive::Strategy::Gradient, 0.1)
                    .depth_tolerance;
                let on_ground = |p: Vec2| {
                    let surface = Some(est.surface_at(p)?);
                    let v = sample_value(&PointEstimate {
                        radiance: Vec3::ZERO,
                        grad_u: Vec3::ZERO,
                        grad_v: Vec3::ZERO,
                        vis_gradient: 0.0,
                        gradient_variance: None,
                        radiance_variance: None,
                        surface,
                        back_facing: false,
                    });
                    (v.object_id == ground).then(|| v.surface_point(p))
                };
                let (mut pairs, mut split) = (0, 0);
                for j in 0..80 {
                    for i in 0..120 {
                        let p = Vec2::new(2.0 + 4.0 * i as f32, 2.0 + 4.0 * j as f32);
                        let Some(a) = on_ground(p) else { continue };
                        for s in [16.0, 32.0] {
                            for step in [Vec2::new(s, 0.0), Vec2::new(0.0, s), Vec2::splat(s)] {
                                if let Some(b) = on_ground(p + step) {
                                    pairs += 1;
                                    split += crate::adaptive::surfaces_differ(&a, &b, tol) as u32;
                                }
                            }
                        }
                    }
                }
                println!("ground at 90°: {split} of {pairs} pairs 16–32 px apart read as a step");
                assert!(pairs > 10_000);
                assert_eq!(split, 0);
            }
        }
    }
}
