//! The per-sample estimator: unidirectional path tracing with next-event
//! estimation, multiple importance sampling (power heuristic) between light and
//! BSDF sampling for area lights and the environment, and Russian roulette.

use super::gradients::geometry::{hit_duals, HitDuals};
use super::gradients::shading::{self, LightPoint};
use super::gradients::sphere_light::{self, ConeLaw};
use super::gradients::visibility::{trace_line_and_ring, Domain, LinePoint};
use super::gradients::{GradientSample, SV};
use super::interaction::{interaction, offset_origin, segment_between, Interaction};
use super::lights::{LightSet, LineLight};
use crate::accel::Accel;
use crate::brdf::Material;
use crate::math::sampler::PixelSampler;
use crate::math::{finite_or_zero, Frame, Ray, Vec3};
use crate::scene::Scene;

/// Sampler dimensions used per path vertex; fixed so that vertex k always reads
/// the same dimensions whatever happened at earlier vertices.
const DIMS_PER_BOUNCE: u32 = 8;
/// The first two dimensions jitter the position in the pixel; bounces start at a
/// multiple of four so that each reads whole 4D Sobol sets.
const FIRST_BOUNCE_DIM: u32 = 4;

/// Configuration shared by all samples of a render.
pub struct PathTracer<'a> {
    pub scene: &'a Scene,
    pub accel: &'a Accel,
    pub lights: &'a LightSet,
    pub max_depth: u32,
    pub rr_depth: u32,
    /// With gradients: how the first hit's direct light is sampled (see
    /// `gradients::visibility`); `None` keeps point sampling everywhere.
    pub lines: Option<LineConfig>,
    /// Far-light criterion factor for the gradient terms (Sec. 5.2); `None`
    /// keeps every near light's SV term.
    pub far_light: Option<f32>,
}

/// Line sampling of the first hit's direct light: `n_theta` shadow rays along one
/// azimuth per camera sample, bisection `refine` steps per visibility jump.
#[derive(Clone, Copy, Debug)]
pub struct LineConfig {
    pub n_theta: u32,
    pub refine: u32,
}

/// What one camera sample returns: radiance plus first-hit data for the AOVs.
#[derive(Clone, Copy, Debug, Default)]
pub struct SampleResult {
    pub radiance: Vec3,
    pub first_hit: Option<FirstHit>,
    /// Analytic image gradient (direct illumination, plus the indirect term), when
    /// asked for.
    pub gradient: Option<GradientSample>,
    pub rays: u32,
}

#[derive(Clone, Copy, Debug)]
pub struct FirstHit {
    pub normal: Vec3,
    pub depth: f32,
    pub albedo: Vec3,
    pub object_id: u32,
    /// The shading normal faces away from the camera (a bump map's terminator): the
    /// path ends at this hit.
    pub back_facing: bool,
}

/// Power heuristic with β = 2 (Veach 1997), written to stay finite when one
/// density is infinite or both are zero.
pub fn power_heuristic(f: f32, g: f32) -> f32 {
    let (f2, g2) = (f * f, g * g);
    if f2.is_infinite() {
        return 1.0;
    }
    if f2 + g2 <= 0.0 {
        return 0.0;
    }
    f2 / (f2 + g2)
}

impl PathTracer<'_> {
    /// Radiance arriving at the camera along `ray`. With `dd` (the image
    /// derivatives ∂d/∂u, ∂d/∂v of the ray's unit direction) the result also
    /// carries the analytic gradient of the direct illumination at the first hit,
    /// computed from the same light sample and shadow ray as the radiance, plus the
    /// curvature/bump and camera terms of the indirect light from the path's own
    /// continuation (`GradientSample::indirect`).
    pub fn li(
        &self,
        mut ray: Ray,
        sampler: &mut PixelSampler,
        dd: Option<[Vec3; 2]>,
    ) -> SampleResult {
        let scene = self.scene;
        let mut out = SampleResult::default();
        let mut grad: Option<(GradientSample, HitDuals)> = None;
        let mut radiance = Vec3::ZERO;
        let mut beta = Vec3::ONE;
        // Density of the BSDF sample that produced `ray`; infinite for camera rays
        // and delta lobes (emitters they hit are counted with full weight).
        let mut prev_pdf = f32::INFINITY;
        let mut prev_p = ray.origin;
        // The previous vertex sampled its direct light by lines: emitters that
        // lines cover are not counted again when the path hits them.
        let mut prev_line = false;
        // With gradients: the first hit's material and continuation (direction,
        // density, BSDF weight), and the radiance once emitters seen directly from
        // the first hit are counted — what the path adds after that is indirect.
        let mut continuation: Option<(&Material, Vec3, f32, Vec3)> = None;
        let mut direct_done: Option<Vec3> = None;
        for depth in 1..=self.max_depth {
            sampler.set_dimension(FIRST_BOUNCE_DIM + (depth - 1) * DIMS_PER_BOUNCE);
            out.rays += 1;
            let Some(hit) = self.accel.intersect(&ray) else {
                if let (Some(env), Some(dd), 1) = (&scene.environment, dd, depth) {
                    out.gradient = Some(escaped_ray_gradient(env, ray.dir, dd));
                }
                if let Some(env) = &scene.environment {
                    let le = env.eval(ray.dir);
                    let w = if prev_line {
                        0.0
                    } else if prev_pdf.is_infinite() {
                        1.0
                    } else {
                        power_heuristic(prev_pdf, self.lights.pdf_env(scene, ray.dir))
                    };
                    radiance += beta * le * w;
                }
                if depth == 2 {
                    direct_done = Some(radiance);
                }
                break;
            };
            let si = interaction(scene, &ray, &hit);
            if let (Some(dd), 1) = (dd, depth) {
                let hd = hit_duals(scene, &si, &ray, dd);
                let g = GradientSample {
                    cv: hd.cv,
                    ..Default::default()
                };
                grad = Some((g, hd));
            }
            if depth == 1 {
                out.first_hit = Some(FirstHit {
                    normal: si.frame.n,
                    depth: hit.t,
                    albedo: scene.materials[si.material as usize].albedo(),
                    object_id: si.object_id,
                    back_facing: si.frame.n.dot(ray.dir) >= 0.0,
                });
            }
            if si.emission != Vec3::ZERO {
                let w = if prev_line && self.lights.is_line_light(scene, si.prim) {
                    0.0
                } else if prev_pdf.is_infinite() {
                    1.0
                } else {
                    let light_pdf = self.lights.pdf_emitter(scene, si.prim, prev_p, si.p, si.ng);
                    power_heuristic(prev_pdf, light_pdf)
                };
                radiance += beta * si.emission * w;
            }
            if depth == 2 {
                direct_done = Some(radiance);
            }
            if depth == self.max_depth {
                break;
            }
            let material = &scene.materials[si.material as usize];
            let wo = si.frame.to_local(-ray.dir);
            if wo.z <= 0.0 {
                break;
            }
            // Next-event estimation (one light sample per vertex).
            let u_pick = sampler.next_1d();
            let u_light = sampler.next_2d();
            // In line mode every line-coverable light is accounted for by the lines
            // in expectation over the pick, whichever light this sample picked, so the
            // continuation must not count them again even when the pick fell on a
            // (point-sampled) mesh emitter.
            prev_line =
                grad.is_some() && self.lines.is_some() && depth == 1 && !material.is_delta();
            let line = match (&mut grad, self.lines) {
                (Some((g, hd)), Some(cfg)) if prev_line => self
                    .lights
                    .pick_line(scene, u_pick)
                    .map(|(ll, pmf)| (ll, pmf, g, *hd, cfg)),
                _ => None,
            };
            if let Some((ll, pmf, g, hd, cfg)) = line {
                let (l, rays) = self.line_direct(&si, wo, material, &hd, ll, pmf, u_light, cfg, g);
                radiance += l;
                out.rays += rays;
            } else if !material.is_delta() {
                if let Some(ls) = self.lights.sample(scene, si.p, u_pick, u_light) {
                    let wi_local = si.frame.to_local(ls.wi);
                    let f = material.eval(wo, wi_local);
                    // Both sides must agree: the shading and the geometric normal.
                    if wi_local.z > 0.0 && ls.wi.dot(si.ng) > 0.0 && f != Vec3::ZERO {
                        out.rays += 1;
                        if self.unoccluded(&si, ls.wi, ls.point) {
                            let bsdf_pdf = material.pdf(wo, wi_local);
                            let w = power_heuristic(ls.pdf, bsdf_pdf);
                            radiance += beta * f * wi_local.z * ls.radiance * (w / ls.pdf);
                            // The gradient uses this light sample alone (weight 1):
                            // an unbiased estimate of ∂(direct light) on its own.
                            if let (Some((g, hd)), 1) = (grad.as_mut(), depth) {
                                let far = self.far_light.map(|k| (hd.cv, k));
                                let c = if let Some((centre, radius)) = ls.cone {
                                    sphere_light::direct_sample(
                                        material,
                                        hd,
                                        centre,
                                        radius,
                                        ls.wi,
                                        ls.radiance,
                                        1.0 / ls.pdf,
                                        ConeLaw::Uniform,
                                        far,
                                    )
                                } else {
                                    let lp = light_point(
                                        si.p,
                                        ls.point,
                                        ls.wi,
                                        ls.radiance,
                                        ls.pdf,
                                        far,
                                    );
                                    shading::direct_sample(material, hd, &lp)
                                };
                                g.add_lanes(&c, 1.0);
                            }
                        }
                    }
                }
            }
            // BSDF sampling continues the path.
            let u_lobe = sampler.next_1d();
            let u_dir = sampler.next_2d();
            let Some(bs) = material.sample(wo, u_lobe, u_dir) else {
                break;
            };
            let wi = si.frame.to_world(bs.wi);
            if wi.dot(si.ng) <= 0.0 || !bs.weight.is_finite() {
                break;
            }
            if grad.is_some() && depth == 1 && !bs.is_delta {
                continuation = Some((material, wi, bs.pdf, bs.weight));
            }
            beta *= bs.weight;
            prev_pdf = if bs.is_delta { f32::INFINITY } else { bs.pdf };
            prev_p = si.p;
            ray = Ray::new(offset_origin(si.p, si.ng, wi), wi);
            // Russian roulette on the throughput, once paths are long enough.
            let u_rr = sampler.next_1d();
            if depth >= self.rr_depth {
                let q = beta.max_element().min(0.95);
                if q <= 0.0 || u_rr >= q {
                    break;
                }
                beta /= q;
            }
            if beta == Vec3::ZERO {
                break;
            }
        }
        out.radiance = radiance;
        if let (Some((g, hd)), Some((material, wi, pdf, weight)), Some(done)) =
            (grad.as_mut(), continuation, direct_done)
        {
            // The path's indirect contribution is weight × L_in (Russian roulette's
            // 1/q stays in L_in, keeping it unbiased).
            // A non-finite deeper bounce must not poison the gradient (the radiance
            // itself is cleaned when it is accumulated).
            let gathered = finite_or_zero(radiance - done);
            let l_in = Vec3::select(weight.cmpgt(Vec3::ZERO), gathered / weight, Vec3::ZERO);
            g.indirect = shading::indirect_sample(material, hd, wi, pdf, l_in);
        }
        if let Some((g, _)) = grad {
            out.gradient = Some(g);
        }
        out
    }

    /// Direct light at the first hit from one light, by one φ-line of shadow rays
    /// (radiance, gradient lanes and the visibility term from the same rays).
    #[allow(clippy::too_many_arguments)]
    fn line_direct(
        &self,
        si: &Interaction,
        wo: Vec3,
        material: &crate::brdf::Material,
        hd: &HitDuals,
        light: LineLight,
        pmf: f32,
        u: crate::math::Vec2,
        cfg: LineConfig,
        g: &mut GradientSample,
    ) -> (Vec3, u32) {
        let scene = self.scene;
        let p = si.p;
        let (domain, le): (Domain, Vec3) = match light {
            LineLight::Environment => (
                Domain::Cone {
                    frame: Frame::from_normal(si.ng),
                    theta_max: std::f32::consts::FRAC_PI_2,
                    sphere: None,
                },
                Vec3::ZERO,
            ),
            LineLight::Sphere(i) => {
                let s = &scene.spheres[i as usize];
                let to_c = s.center - p;
                let d = to_c.length();
                if d <= s.radius * 1.0001 {
                    return (Vec3::ZERO, 0);
                }
                (
                    Domain::Cone {
                        frame: Frame::from_normal(to_c / d),
                        theta_max: (s.radius / d).asin(),
                        sphere: Some((s.center, s.radius)),
                    },
                    s.emission,
                )
            }
            LineLight::Rect(m) => {
                let mesh = &scene.meshes[m as usize];
                let Some(r) = mesh.rect else {
                    return (Vec3::ZERO, 0);
                };
                // One-sided: a rectangle facing away sends nothing.
                if r.normal().dot(p - r.corner) <= 0.0 {
                    return (Vec3::ZERO, 0);
                }
                let centre = r.corner + 0.5 * (r.edge_u + r.edge_v);
                (
                    Domain::Rect {
                        frame: Frame::from_normal((centre - p).normalize()),
                        corner: r.corner,
                        edge_u: r.edge_u,
                        edge_v: r.edge_v,
                    },
                    mesh.emission,
                )
            }
        };
        let env = scene.environment.as_ref();
        let radiance_from = |w: Vec3| match light {
            LineLight::Environment => env.map_or(Vec3::ZERO, |e| e.eval(w)),
            _ => le,
        };
        let transport = |w: Vec3| {
            let wl = si.frame.to_local(w);
            if wl.z <= 0.0 {
                return Vec3::ZERO;
            }
            material.eval(wo, wl) * wl.z * radiance_from(w) / pmf
        };
        let mut radiance = Vec3::ZERO;
        let mut on_point = |pt: &LinePoint| {
            if !pt.visible {
                return;
            }
            let wl = si.frame.to_local(pt.wi);
            if wl.z <= 0.0 || pt.wi.dot(si.ng) <= 0.0 {
                return;
            }
            let le = radiance_from(pt.wi);
            radiance += material.eval(wo, wl) * wl.z * le / (pt.pdf * pmf);
            let far = self.far_light.map(|k| (hd.cv, k));
            let c = if let Domain::Cone {
                sphere: Some((centre, radius)),
                ..
            } = domain
            {
                let w = 1.0 / pt.pdf;
                sphere_light::direct_sample(
                    material,
                    hd,
                    centre,
                    radius,
                    pt.wi,
                    le,
                    w,
                    ConeLaw::Line,
                    far,
                )
            } else {
                let lp = light_point(p, pt.light_point, pt.wi, le, pt.pdf, far);
                shading::direct_sample(material, hd, &lp)
            };
            g.add_lanes(&c, 1.0 / pmf);
        };
        let dx = [hd.x.lane(SV), hd.x.lane(SV + 1)];
        let est = trace_line_and_ring(
            scene,
            self.accel,
            p,
            si.ng,
            &domain,
            u.x * std::f32::consts::TAU,
            u.y,
            cfg.n_theta,
            cfg.refine,
            dx,
            &transport,
            &mut on_point,
        );
        for k in 0..2 {
            g.vis[k] += est.vis[k];
        }
        (finite_or_zero(radiance), est.rays)
    }

    fn unoccluded(&self, si: &Interaction, wi: Vec3, point: Option<(Vec3, Vec3)>) -> bool {
        let ray = match point {
            Some((q, nq)) => segment_between(si.p, si.ng, q, Some(nq)),
            None => Ray::new(offset_origin(si.p, si.ng, wi), wi),
        };
        !self.accel.occluded(&ray)
    }
}

/// A light sample in the form the gradient stage differentiates: emitter points
/// in area measure (so they stay fixed while the shading point moves), from a
/// solid-angle density `pdf`.
///
/// With the far-light criterion (Sec. 5.2) a near light is treated as distant —
/// its direction held fixed, which drops its SV term — where the surface is curved
/// enough that |L_x| ≪ 2|n_x||L_θ|: for an isotropic source at distance d,
/// L_x ≈ L_θ/d, so the test is 2|n_x|·d > `far_factor` (CV = 2|n_x|).
fn light_point(
    p: Vec3,
    point: Option<(Vec3, Vec3)>,
    wi: Vec3,
    radiance: Vec3,
    pdf: f32,
    far: Option<(f32, f32)>,
) -> LightPoint {
    match point {
        Some((y, ny)) => {
            let d = y - p;
            let r2 = d.length_squared();
            if let Some((cv, far_factor)) = far {
                if cv * r2.sqrt() > far_factor {
                    return LightPoint::Direction { wi, radiance, pdf };
                }
            }
            let cos_y = (ny.dot(d) / r2.sqrt()).abs();
            LightPoint::Area {
                y,
                ny,
                radiance,
                pdf_area: pdf * cos_y / r2,
            }
        }
        None => LightPoint::Direction { wi, radiance, pdf },
    }
}

/// Gradient of the environment radiance seen by a camera ray that hits nothing.
fn escaped_ray_gradient(env: &crate::scene::Environment, d: Vec3, dd: [Vec3; 2]) -> GradientSample {
    let mut lanes = [Vec3::ZERO; super::gradients::LANES];
    lanes[super::gradients::CAM] = dd[0];
    lanes[super::gradients::CAM + 1] = dd[1];
    let l = shading::environment(env, super::gradients::GVec3::with_lanes(d, lanes));
    let mut g = GradientSample::default();
    g.add_lanes(&l, 1.0);
    g.dv = [Vec3::ZERO; 2];
    g
}
