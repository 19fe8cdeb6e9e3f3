//! The per-sample estimator: unidirectional path tracing with next-event
//! estimation, multiple importance sampling (power heuristic) between light and
//! BSDF sampling for area lights and the environment, and Russian roulette.

use super::gradients::geometry::{hit_duals, HitDuals};
use super::gradients::shading::{self, LightPoint};
use super::gradients::sphere_light::{self, ConeLaw};
use super::gradients::visibility::{trace_gated, Domain, Gate};
use super::gradients::{GradientSample, SV};
use super::interaction::{interaction, Interaction};
use super::lights::{LightSet, LineLight};
use crate::accel::{Accel, PrimRef};
use crate::brdf::{BsdfSample, Material};
use crate::math::lanes::Lanes;
use crate::math::sampler::PixelSampler;
use crate::math::{finite_or_zero, Frame, Ray, Vec2, Vec3};
use crate::scene::Scene;

/// Sampler dimensions used per path vertex; fixed so that vertex k always reads
/// the same dimensions whatever happened at earlier vertices.
const DIMS_PER_BOUNCE: u32 = 8;
/// The first two dimensions jitter the position in the pixel; bounces start at a
/// multiple of four so that each reads whole 4D Sobol sets.
const FIRST_BOUNCE_DIM: u32 = 4;
/// The first vertex's BSDF direction reads dimensions 2–3, the pair of the camera
/// set that the pixel jitter leaves free, instead of its slot in the bounce's set
/// (Sobol dimensions 8–9): with the jitter that is Sobol's best 4D set, and the
/// first bounce's direction carries most of an indirectly lit image's variance
/// (cornell MSE −6.8 %, bunny −2.3 %; benches/README, levers table).
const FIRST_DIRECTION_DIM: u32 = 2;

/// The random numbers of one path vertex, read as one block of its
/// [`DIMS_PER_BOUNCE`] dimensions (`PixelSampler::block8`): the light pick and
/// point of next-event estimation, the BSDF lobe and direction, Russian roulette
/// (the eighth is unused). Fixed slots, so vertex k reads the same dimensions
/// whatever happened at earlier vertices.
pub(super) struct VertexSamples {
    pub pick: f32,
    pub light: Vec2,
    pub lobe: f32,
    pub dir: Vec2,
    /// Russian roulette's number; 0 and unread where roulette does not apply.
    pub rr: f32,
}

impl VertexSamples {
    /// `roulette`: whether Russian roulette reads `rr` at this vertex; where
    /// it does not, `rr` is 0 and unread. The first vertex then needs only the
    /// block's first set (its direction comes from the camera set): one Sobol
    /// set instead of two, the same values where they are read.
    pub(super) fn draw(sampler: &mut PixelSampler, depth: u32, roulette: bool) -> Self {
        let dim = FIRST_BOUNCE_DIM + (depth - 1) * DIMS_PER_BOUNCE;
        if depth == 1 && !roulette {
            let u = sampler.block4(dim);
            return Self {
                pick: u[0],
                light: Vec2::new(u[1], u[2]),
                lobe: u[3],
                dir: sampler.next_2d_at(FIRST_DIRECTION_DIM),
                rr: 0.0,
            };
        }
        let u = sampler.block8(dim);
        // The first vertex's direction from the camera set (its own slot unread).
        let dir = if depth == 1 {
            sampler.next_2d_at(FIRST_DIRECTION_DIM)
        } else {
            Vec2::new(u[4], u[5])
        };
        Self {
            pick: u[0],
            light: Vec2::new(u[1], u[2]),
            lobe: u[3],
            dir,
            rr: u[6],
        }
    }
}

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

/// The visibility gradient at the first hit: one φ-line of `n_theta` shadow rays
/// and its ring per camera sample, bisection `refine` steps per visibility jump,
/// marched with probability `gate` where the penumbra probes all agree
/// ([`Gate`]; 1 marches every sample).
#[derive(Clone, Copy, Debug)]
pub struct LineConfig {
    pub n_theta: u32,
    pub refine: u32,
    pub gate: f32,
}

/// The first hit's gate and line numbers: a hashed dimension set of their own, the
/// last the sampler addresses (a path would need ~5·10⁸ vertices to reach it), so
/// that `--gradients` leaves every number the radiance reads (and with it the
/// radiance) as a plain render has them.
const GATE_DIM: u32 = u32::MAX - 7;

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

impl FirstHit {
    /// The AOVs of a camera ray's hit: the shading `normal`, the distance `t`,
    /// the material's albedo and the object id; `dir` is the ray's direction.
    pub(super) fn new(
        scene: &Scene,
        normal: Vec3,
        t: f32,
        material: u32,
        object_id: u32,
        dir: Vec3,
    ) -> Self {
        Self {
            normal,
            depth: t,
            albedo: scene.materials[material as usize].albedo(),
            object_id,
            back_facing: normal.dot(dir) >= 0.0,
        }
    }
}

/// Power heuristic with β = 2 (Veach 1997), written to stay finite when one
/// density is infinite or both are zero.
/// Generic over [`Lanes`]: `li` runs it at `f32`, the lane kernel on eight.
#[inline(always)]
pub fn power_heuristic<L: Lanes>(f: L, g: L) -> L {
    let (f2, g2) = (f * f, g * g);
    let sum = f2 + g2;
    f2.is_inf().select(
        L::splat(1.0),
        sum.le(L::splat(0.0)).select(L::splat(0.0), f2 / sum),
    )
}

/// The state a path carries from bounce to bounce.
pub(super) struct PathState {
    pub radiance: Vec3,
    pub beta: Vec3,
    /// Density of the BSDF sample that produced the current ray; infinite for
    /// camera rays and delta lobes (emitters they hit count with full weight).
    pub prev_pdf: f32,
    pub prev_p: Vec3,
    /// The previous vertex's shading normal: the environment's light-sampling
    /// density depends on it (`LightSet::pdf_env`).
    pub prev_n: Vec3,
}

impl PathState {
    /// A camera ray's state: no radiance yet, unit throughput, and an infinite
    /// density, so that what it hits counts with full weight.
    pub(super) fn camera(origin: Vec3) -> Self {
        Self {
            radiance: Vec3::ZERO,
            beta: Vec3::ONE,
            prev_pdf: f32::INFINITY,
            prev_p: origin,
            prev_n: Vec3::ZERO,
        }
    }
}

/// What the first hit records besides radiance (pbrt-v4's `VisibleSurface`): the
/// AOVs and, with gradients, the gradient capture (boxed: it is ~1 KB, and a
/// plain render would otherwise copy that much per sample for a `None`).
struct VisibleSurface<'a> {
    aovs: FirstHit,
    gradient: Option<Box<GradientCapture<'a>>>,
}

/// The gradient stage's view of the first hit: its duals, the gradient gathered so
/// far, the path's continuation from it, and the radiance once the emitters it sees
/// directly are counted (what the path adds after that is indirect).
struct GradientCapture<'a> {
    hd: HitDuals,
    g: GradientSample,
    continuation: Option<Continuation<'a>>,
    direct_done: Option<Vec3>,
}

/// The BSDF sample that continued the path from the first hit.
#[derive(Clone, Copy)]
struct Continuation<'a> {
    material: &'a Material,
    wi: Vec3,
    pdf: f32,
    weight: Vec3,
}

impl GradientCapture<'_> {
    /// The finished gradient: adds the indirect term once the path's radiance is known.
    fn finish(mut self, radiance: Vec3) -> GradientSample {
        if let (Some(c), Some(done)) = (self.continuation, self.direct_done) {
            // The path's indirect contribution is weight × L_in (Russian roulette's
            // 1/q stays in L_in, keeping it unbiased).
            // A non-finite deeper bounce must not poison the gradient (the radiance
            // itself is cleaned when it is accumulated).
            let gathered = finite_or_zero(radiance - done);
            let l_in = Vec3::select(c.weight.cmpgt(Vec3::ZERO), gathered / c.weight, Vec3::ZERO);
            self.g.indirect = shading::indirect_sample(c.material, &self.hd, c.wi, c.pdf, l_in);
        }
        self.g
    }
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
        let mut visible: Option<VisibleSurface> = None;
        let mut st = PathState::camera(ray.origin);
        for depth in 1..=self.max_depth {
            out.rays += 1;
            let Some(hit) = self.accel.intersect(&ray) else {
                if let (Some(env), Some(dd), 1) = (&scene.environment, dd, depth) {
                    out.gradient = Some(escaped_ray_gradient(env, ray.dir, dd));
                }
                st.radiance += self.escaped(&ray, &st);
                mark_direct_done(&mut visible, depth, st.radiance);
                break;
            };
            let si = interaction(scene, self.accel, &ray, &hit);
            if depth == 1 {
                visible = Some(self.visible_surface(&si, &ray, hit.t, dd));
            }
            st.radiance += self.emitted(&si, &st);
            mark_direct_done(&mut visible, depth, st.radiance);
            if depth == self.max_depth {
                break;
            }
            let material = &scene.materials[si.material as usize];
            let wo = si.frame.to_local(-ray.dir);
            if wo.z <= 0.0 {
                break;
            }
            let u = VertexSamples::draw(sampler, depth, self.roulette_at(depth));
            // The BSDF sample that continues the path, taken before the light's
            // shadow ray: the two samples are independent chains of square roots
            // and divisions, which the CPU overlaps when they sit side by side
            // (bunny render −3 %, cornell within the noise; same bits).
            let bsdf_sample = material.sample(wo, u.lobe, u.dir);
            let capture = first_hit_capture(&mut visible, depth);
            let gate_u =
                (capture.is_some() && self.lines.is_some()).then(|| sampler.block8(GATE_DIM));
            let (ld, rays) =
                self.sample_ld(&si, wo, material, st.beta, u.pick, u.light, capture, gate_u);
            st.radiance += ld;
            out.rays += rays;
            let capture = first_hit_capture(&mut visible, depth);
            let Some(next) =
                self.continue_path(&si, material, bsdf_sample, u.rr, &mut st, depth, capture)
            else {
                break;
            };
            ray = next;
        }
        out.radiance = st.radiance;
        if let Some(v) = visible {
            out.first_hit = Some(v.aovs);
            if let Some(c) = v.gradient {
                out.gradient = Some(c.finish(st.radiance));
            }
        }
        out
    }

    /// The AOVs of the first hit and, when `dd` asks for gradients, its capture.
    fn visible_surface<'m>(
        &self,
        si: &Interaction,
        ray: &Ray,
        t: f32,
        dd: Option<[Vec3; 2]>,
    ) -> VisibleSurface<'m> {
        let gradient = dd.map(|dd| {
            let hd = hit_duals(self.scene, si, ray, dd);
            Box::new(GradientCapture {
                hd,
                g: GradientSample {
                    cv: hd.cv,
                    ..Default::default()
                },
                continuation: None,
                direct_done: None,
            })
        });
        VisibleSurface {
            aovs: FirstHit::new(
                self.scene,
                si.frame.n,
                t,
                si.material,
                si.object_id,
                ray.dir,
            ),
            gradient,
        }
    }

    /// The environment's contribution to a ray that leaves the scene, MIS-weighted
    /// against the light sample that could have produced its direction.
    pub(super) fn escaped(&self, ray: &Ray, st: &PathState) -> Vec3 {
        let Some(env) = &self.scene.environment else {
            return Vec3::ZERO;
        };
        // The light-sampling density only where MIS weighs this ray: not after
        // a camera ray or a delta lobe (weight 1).
        let mis = !st.prev_pdf.is_infinite();
        let (le, pdf_env) = self
            .lights
            .escaped(self.scene, env, ray.dir, st.prev_n, mis);
        let w = if mis {
            power_heuristic(st.prev_pdf, pdf_env)
        } else {
            1.0
        };
        st.beta * le * w
    }

    /// Emission of the surface the path hit, MIS-weighted against light sampling.
    fn emitted(&self, si: &Interaction, st: &PathState) -> Vec3 {
        if si.emission == Vec3::ZERO {
            return Vec3::ZERO;
        }
        st.beta * si.emission * self.emitter_weight(si, st.prev_pdf, st.prev_p)
    }

    /// The MIS weight of an emitter the path hit at `si`, against the light
    /// sample that could have found it from `prev_p` (`prev_pdf`: the BSDF
    /// sample's density, infinite for camera rays and delta lobes).
    pub(super) fn emitter_weight(&self, si: &Interaction, prev_pdf: f32, prev_p: Vec3) -> f32 {
        if prev_pdf.is_infinite() {
            return 1.0;
        }
        let light_pdf = self
            .lights
            .pdf_emitter(self.scene, si.prim, prev_p, si.p, si.ng);
        power_heuristic(prev_pdf, light_pdf)
    }

    /// Direct light at a vertex from one light sample (pbrt's `SampleLd`),
    /// MIS-weighted, and the shadow rays it traced. With `capture` (first hit,
    /// gradients) the sample's gradient lanes are added, and with `gate_u` the
    /// picked light's visibility gradient ([`Self::visibility_gradient`]).
    #[allow(clippy::too_many_arguments)]
    fn sample_ld(
        &self,
        si: &Interaction,
        wo: Vec3,
        material: &Material,
        beta: Vec3,
        u_pick: f32,
        u_light: Vec2,
        mut capture: Option<&mut GradientCapture>,
        gate_u: Option<[f32; 8]>,
    ) -> (Vec3, u32) {
        let (ld, rays, seen) = self.point_ld(
            si,
            wo,
            material,
            beta,
            u_pick,
            u_light,
            capture.as_deref_mut(),
        );
        let (Some(cfg), Some(c), Some(u)) = (self.lines, capture, gate_u) else {
            return (ld, rays);
        };
        match self.lights.pick_line(u_pick) {
            Some((ll, pmf)) if !material.is_delta() => {
                let vis_rays = self.visibility_gradient(si, wo, material, ll, pmf, seen, u, cfg, c);
                (ld, rays + vis_rays)
            }
            _ => (ld, rays),
        }
    }

    /// [`Self::sample_ld`]'s light sample, and whether its shadow ray found the
    /// light visible (`None` where it cast none).
    #[allow(clippy::too_many_arguments)]
    fn point_ld(
        &self,
        si: &Interaction,
        wo: Vec3,
        material: &Material,
        beta: Vec3,
        u_pick: f32,
        u_light: Vec2,
        capture: Option<&mut GradientCapture>,
    ) -> (Vec3, u32, Option<bool>) {
        if material.is_delta() {
            return (Vec3::ZERO, 0, None);
        }
        let Some(ls) = self
            .lights
            .sample(self.scene, si.p, &si.frame, u_pick, u_light)
        else {
            return (Vec3::ZERO, 0, None);
        };
        let wi_local = si.frame.to_local(ls.wi);
        let f = material.eval(wo, wi_local);
        // Both sides must agree: the shading and the geometric normal.
        if !(wi_local.z > 0.0 && ls.wi.dot(si.ng) > 0.0 && f != Vec3::ZERO) {
            return (Vec3::ZERO, 0, None);
        }
        if !self.unoccluded(si, ls.wi, ls.point) {
            return (Vec3::ZERO, 1, Some(false));
        }
        let bsdf_pdf = material.pdf(wo, wi_local);
        let w = power_heuristic(ls.pdf, bsdf_pdf);
        // The gradient uses this light sample alone (weight 1): an unbiased
        // estimate of ∂(direct light) on its own.
        // A sphere light's sample is held fixed in its cone's coordinates, whose
        // flow keeps the variance bounded at the rim (issue 12, D2).
        if let Some(c) = capture {
            let far = self.far_light.map(|k| (c.hd.cv, k));
            let lanes = match ls.cone {
                Some((centre, radius)) => Some(sphere_light::direct_sample(
                    material,
                    &c.hd,
                    centre,
                    radius,
                    ls.wi,
                    ls.radiance,
                    1.0 / ls.pdf,
                    ConeLaw::Uniform,
                    far,
                )),
                None => light_point(si.p, ls.point, ls.wi, ls.radiance, ls.pdf, far)
                    .map(|lp| shading::direct_sample(material, &c.hd, &lp)),
            };
            if let Some(lanes) = lanes {
                c.g.add_lanes(&lanes, 1.0);
            }
        }
        (
            beta * f * wi_local.z * ls.radiance * (w / ls.pdf),
            1,
            Some(true),
        )
    }

    /// The BSDF sample `bs` of `material` continues the path (throughput, MIS
    /// state, Russian roulette): the next ray, or `None` when the path ends.
    #[allow(clippy::too_many_arguments)]
    fn continue_path<'m>(
        &self,
        si: &Interaction,
        material: &'m Material,
        bs: Option<BsdfSample>,
        u_rr: f32,
        st: &mut PathState,
        depth: u32,
        capture: Option<&mut GradientCapture<'m>>,
    ) -> Option<Ray> {
        let bs = bs?;
        let wi = si.frame.to_world(bs.wi);
        if wi.dot(si.ng) <= 0.0 || !bs.weight.is_finite() {
            return None;
        }
        if let (Some(c), false) = (capture, bs.is_delta) {
            c.continuation = Some(Continuation {
                material,
                wi,
                pdf: bs.pdf,
                weight: bs.weight,
            });
        }
        st.beta *= bs.weight;
        st.prev_pdf = if bs.is_delta { f32::INFINITY } else { bs.pdf };
        st.prev_p = si.p;
        st.prev_n = si.frame.n;
        let ray = si.spawn_ray(wi);
        self.survives(&mut st.beta, u_rr, depth).then_some(ray)
    }

    /// Whether Russian roulette applies at path vertex `depth` (and reads the
    /// vertex's `rr` number).
    pub(super) fn roulette_at(&self, depth: u32) -> bool {
        depth >= self.rr_depth
    }

    /// Russian roulette on the throughput `beta` at `depth`, once paths are long
    /// enough (the survivor's `beta` divided by its probability); `false`
    /// when the path ends here, by the roulette or with zero throughput.
    pub(super) fn survives(&self, beta: &mut Vec3, u_rr: f32, depth: u32) -> bool {
        if self.roulette_at(depth) {
            let q = beta.max_element().min(0.95);
            if q <= 0.0 || u_rr >= q {
                return false;
            }
            *beta /= q;
        }
        *beta != Vec3::ZERO
    }

    /// The visibility (soft-shadow) gradient of the first hit's picked light: one
    /// φ-line and ring behind the penumbra gate, whose probes start from the
    /// radiance's own shadow ray (`seen`). The radiance is the light sample's; the
    /// line adds only the `vis` term. Returns the shadow rays it traced.
    #[allow(clippy::too_many_arguments)]
    fn visibility_gradient(
        &self,
        si: &Interaction,
        wo: Vec3,
        material: &Material,
        light: LineLight,
        pmf: f32,
        seen: Option<bool>,
        u: [f32; 8],
        cfg: LineConfig,
        c: &mut GradientCapture,
    ) -> u32 {
        let scene = self.scene;
        let Some((domain, le)) = line_domain(scene, light, si) else {
            return 0;
        };
        let env = scene.environment.as_ref();
        let transport = |w: Vec3| {
            let wl = si.frame.to_local(w);
            if wl.z <= 0.0 {
                return Vec3::ZERO;
            }
            let le = match light {
                LineLight::Environment => env.map_or(Vec3::ZERO, |e| e.eval(w)),
                _ => le,
            };
            material.eval(wo, wl) * wl.z * le / pmf
        };
        let gate = Gate {
            q_agree: cfg.gate,
            seen,
            u: [u[0], u[1], u[2], u[3], u[4]],
        };
        let est = trace_gated(
            scene,
            self.accel,
            si.surface(),
            &domain,
            u[5] * std::f32::consts::TAU,
            u[6],
            cfg.n_theta,
            cfg.refine,
            [c.hd.x.lane(SV), c.hd.x.lane(SV + 1)],
            &transport,
            gate,
        );
        for k in 0..2 {
            c.g.vis[k] += est.vis[k];
        }
        est.rays
    }

    fn unoccluded(&self, si: &Interaction, wi: Vec3, point: Option<(Vec3, Vec3)>) -> bool {
        let ray = match point {
            Some((q, nq)) => si.spawn_ray_to(q, nq),
            None => si.spawn_ray(wi),
        };
        !self.accel.occluded(&ray)
    }
}

/// The angular domain a φ-line marches for `light` seen from the hit `si`, and the
/// light's constant radiance (zero for the environment, looked up per direction);
/// `None` when the light sends nothing there (inside a sphere light, behind a
/// one-sided rectangle).
fn line_domain(scene: &Scene, light: LineLight, si: &Interaction) -> Option<(Domain, Vec3)> {
    let p = si.p;
    Some(match light {
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
                return None;
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
            let r = mesh.rect?;
            // A rectangle does not light its own points (a camera may see its
            // back): their distances to it are zero, and issue 54's NaN came
            // from the line's 0/0 at such a point.
            if matches!(si.prim, PrimRef::Triangle { mesh, .. } if mesh == m) {
                return None;
            }
            // One-sided: a rectangle facing away sends nothing, nor one whose
            // plane x lies in within its rounding bound (its side is undecided
            // there, and cos θ_y of every light point is 0 up to rounding).
            let n = r.normal();
            let to_p = p - r.corner;
            let bound = n.abs().dot(si.p_error) + 4.0 * f32::EPSILON * to_p.abs().dot(n.abs());
            if n.dot(to_p) <= bound {
                return None;
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
    })
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
) -> Option<LightPoint> {
    Some(match point {
        Some((y, ny)) => {
            let d = y - p;
            let r2 = d.length_squared();
            if let Some((cv, far_factor)) = far {
                if cv * r2.sqrt() > far_factor {
                    return Some(LightPoint::Direction { wi, radiance, pdf });
                }
            }
            let cos_y = (ny.dot(d) / r2.sqrt()).abs();
            let pdf_area = pdf * cos_y / r2;
            // Seen edge-on (cos θ_y = 0) or from its own surface (r = 0) the point
            // has no area density; it carries no light, as the point sampler's
            // density check (`LightSet::sample`) has it.
            if !(pdf_area > 0.0 && pdf_area.is_finite()) {
                return None;
            }
            LightPoint::Area {
                y,
                ny,
                radiance,
                pdf_area,
            }
        }
        None => LightPoint::Direction { wi, radiance, pdf },
    })
}

/// Records the radiance once the emitters the first hit sees directly are counted
/// (at the second vertex): what the path adds after that is indirect.
fn mark_direct_done(visible: &mut Option<VisibleSurface>, depth: u32, radiance: Vec3) {
    if let (
        2,
        Some(VisibleSurface {
            gradient: Some(c), ..
        }),
    ) = (depth, visible.as_mut())
    {
        c.direct_done = Some(radiance);
    }
}

/// The gradient capture, at the first hit only.
fn first_hit_capture<'v, 'm>(
    visible: &'v mut Option<VisibleSurface<'m>>,
    depth: u32,
) -> Option<&'v mut GradientCapture<'m>> {
    match (depth, visible.as_mut()) {
        (1, Some(v)) => v.gradient.as_deref_mut(),
        _ => None,
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
