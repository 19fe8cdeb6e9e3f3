//! Emitters and the environment as light sources for next-event estimation:
//! choosing a light in proportion to its power, sampling a point or direction on
//! it, and the solid-angle density of that choice (needed again when a BSDF-sampled
//! ray hits the same light, for multiple importance sampling).

use crate::accel::PrimRef;
use crate::math::distribution::{Distribution1D, Distribution2D};
use crate::math::lanes::{Lanes, Vector3};
use crate::math::{cross, luminance, warp, Frame, Vec2, Vec3};
use crate::scene::environment::{self, direction_to_latlong, latlong_to_direction};
use crate::scene::{Environment, Scene};
use std::f32::consts::PI;

/// One light source.
#[derive(Clone, Copy, Debug)]
enum Light {
    /// An emitting triangle of mesh `mesh` (quads are two of these), with its
    /// vertices and unit normal copied here: light sampling runs at every
    /// path vertex and need not go through the mesh's index buffer or
    /// renormalise the cross product each time.
    Triangle {
        mesh: u32,
        area: f32,
        v: [Vec3; 3],
        n: Vec3,
    },
    /// A rectangle emitter (a quad mesh with `rect`) as one light, sampled
    /// uniformly over its area by (u, v) ↦ corner + u·edge_u + v·edge_v. Picking
    /// one of its two triangles and warping the square onto it scattered a
    /// pixel's stratified light samples over the rectangle; this map keeps them
    /// stratified, as Mitsuba's `rectangle` does. The density is the two
    /// triangles' (area-proportional pick × 1/area), so MIS weights are unchanged.
    Rect {
        mesh: u32,
        area: f32,
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        n: Vec3,
    },
    Sphere(u32),
    Environment,
}

/// One light as the lane shading reads it ([`LightSet::lane_lights`]).
#[derive(Clone, Copy, Debug)]
pub(crate) enum LaneLight {
    Area(AreaLight),
    /// The environment, picked with probability `pick`.
    Environment {
        pick: f32,
    },
    /// A sphere: its sample depends on the receiving point alone
    /// ([`LightSet::sample_without_frame`]).
    Sphere,
}

/// An area light for the lane shading.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AreaLight {
    pub a: Vec3,
    pub b: Vec3,
    pub c: Vec3,
    pub n: Vec3,
    pub area: f32,
    pub emission: Vec3,
    /// (u, v) ↦ a + u·b + v·c; otherwise a triangle sampled uniformly.
    pub rect: bool,
    /// The probability of picking it.
    pub pick: f32,
}

/// A light whose whole angular domain the gradient stage can march (see
/// `gradients::visibility`), with the probability of choosing it.
#[derive(Clone, Copy, Debug)]
pub enum LineLight {
    Environment,
    Sphere(u32),
    /// A rectangle light: the mesh with `rect` set (both its triangles).
    Rect(u32),
}

/// A sampled light direction as seen from a shading point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    pub wi: Vec3,
    /// Emitted radiance arriving along `-wi` (before visibility).
    pub radiance: Vec3,
    /// Density in solid angle at the shading point, including the light choice.
    pub pdf: f32,
    /// Point on the light and its normal; `None` for the environment (at infinity).
    pub point: Option<(Vec3, Vec3)>,
    /// For a sphere light sampled in the cone it subtends: its (centre, radius), so
    /// the gradient stage can hold the sample's cone coordinates fixed
    /// (`gradients::sphere_light`, law `Uniform`).
    pub cone: Option<(Vec3, f32)>,
}

/// How the environment is importance-sampled: built only for scenes that have one.
#[derive(Clone, Debug)]
pub enum EnvSampler {
    /// Constant radiance: cosine-weighted about the receiving point's shading
    /// normal. A constant sky sends the same radiance from every direction, so the
    /// direct light's integrand is cos θ times the BSDF: sampling the cosine makes it
    /// exact for a diffuse receiver (bar visibility), where the uniform sphere (what
    /// Mitsuba's `constant` emitter does) wastes half its samples below the horizon.
    CosineAboutNormal,
    /// Lat-long image: a 2D piecewise-constant distribution over texels with
    /// weights luminance · sin θ (the Jacobian of the lat-long map).
    Image(Distribution2D),
    /// Gaussian sky: the vMF lobe with probability `lobe_prob`, else uniform.
    GaussianSky { lobe_prob: f32 },
}

/// All lights of a scene plus the distribution that picks one.
#[derive(Clone, Debug)]
pub struct LightSet {
    lights: Vec<Light>,
    choose: Option<Distribution1D>,
    /// Index into `lights` of each emitting mesh's rectangle light or first
    /// emitting triangle (u32::MAX if none).
    mesh_first_light: Vec<u32>,
    sphere_light: Vec<u32>,
    env_light: Option<u32>,
    pub env_sampler: Option<EnvSampler>,
}

impl LightSet {
    pub fn build(scene: &Scene) -> Self {
        let mut lights = Vec::new();
        let mut power = Vec::new();
        let mut mesh_first_light = vec![u32::MAX; scene.meshes.len()];
        for (mi, m) in scene.meshes.iter().enumerate() {
            if m.emission == Vec3::ZERO {
                continue;
            }
            mesh_first_light[mi] = lights.len() as u32;
            if let Some(r) = m.rect {
                let area = r.area();
                lights.push(Light::Rect {
                    mesh: mi as u32,
                    area,
                    corner: r.corner,
                    edge_u: r.edge_u,
                    edge_v: r.edge_v,
                    n: r.normal(),
                });
                power.push(luminance(m.emission) * area * PI);
                continue;
            }
            for t in &m.triangles {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                let normal = cross(b - a, c - a);
                let area = 0.5 * normal.length();
                lights.push(Light::Triangle {
                    mesh: mi as u32,
                    area,
                    v: [a, b, c],
                    n: normal.normalize_or_zero(),
                });
                power.push(luminance(m.emission) * area * PI);
            }
        }
        let mut sphere_light = vec![u32::MAX; scene.spheres.len()];
        for (si, s) in scene.spheres.iter().enumerate() {
            if s.emission == Vec3::ZERO {
                continue;
            }
            sphere_light[si] = lights.len() as u32;
            lights.push(Light::Sphere(si as u32));
            power.push(luminance(s.emission) * 4.0 * PI * s.radius * s.radius * PI);
        }
        let (env_light, env_sampler) = match &scene.environment {
            None => (None, None),
            Some(env) => {
                let r = scene_radius(scene);
                // Power through a disk the size of the scene (pbrt's Φ of an infinite light).
                power.push(env.mean_luminance() * 4.0 * PI * PI * r * r);
                lights.push(Light::Environment);
                (Some(lights.len() as u32 - 1), Some(build_env_sampler(env)))
            }
        };
        let choose = (!lights.is_empty()).then(|| Distribution1D::new(&power));
        Self {
            lights,
            choose,
            mesh_first_light,
            sphere_light,
            env_light,
            env_sampler,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    /// Counts for `info`: (rectangle lights, other emitting triangles, emitting
    /// spheres, environment?).
    pub fn counts(&self) -> (usize, usize, usize, bool) {
        let rects = self
            .lights
            .iter()
            .filter(|l| matches!(l, Light::Rect { .. }))
            .count();
        let tris = self
            .lights
            .iter()
            .filter(|l| matches!(l, Light::Triangle { .. }))
            .count();
        let spheres = self
            .lights
            .iter()
            .filter(|l| matches!(l, Light::Sphere(_)))
            .count();
        (rects, tris, spheres, self.env_light.is_some())
    }

    /// Picks a light with `u_pick` and samples a direction toward it from `p`, a
    /// point whose shading frame is `frame` (its normal bounds the hemisphere that
    /// receives light). The cosine-weighted sky is sampled in that very frame, a
    /// continuous function of the normal, so that its stratified samples stay
    /// stratified across the triangles of a pixel (a frame built per sample from
    /// the normal alone would do too, at ~250 instructions a call).
    pub fn sample(
        &self,
        scene: &Scene,
        p: Vec3,
        frame: &Frame,
        u_pick: f32,
        u: Vec2,
    ) -> Option<LightSample> {
        let choose = self.choose.as_ref()?;
        let idx = choose.sample_discrete(u_pick);
        let pick = choose.discrete_pmf(idx);
        let mut s = match self.lights[idx] {
            Light::Triangle { mesh, area, v, n } => {
                let bary = warp::square_to_uniform_triangle(u);
                let q = v[0] * (1.0 - bary.x - bary.y) + v[1] * bary.x + v[2] * bary.y;
                sample_area_point(q, n, area, scene.meshes[mesh as usize].emission, p)?
            }
            Light::Rect {
                mesh,
                area,
                corner,
                edge_u,
                edge_v,
                n,
            } => {
                let q = corner + u.x * edge_u + u.y * edge_v;
                sample_area_point(q, n, area, scene.meshes[mesh as usize].emission, p)?
            }
            Light::Sphere(i) => sample_sphere(scene, i, p, u)?,
            Light::Environment => self.sample_env(scene.environment.as_ref()?, frame, u)?,
        };
        s.pdf *= pick;
        (s.pdf > 0.0 && s.pdf.is_finite()).then_some(s)
    }

    /// Every light as the lane shading (`render::lanes`) reads it. An area
    /// light's sample lands on `a·w0 + b·w1 + c·w2`: the corner and edges of a
    /// rectangle with weights (1, u, v), the vertices of a triangle with its
    /// barycentrics, in the order [`Self::sample`] sums them.
    pub(crate) fn lane_lights(&self, scene: &Scene) -> Vec<LaneLight> {
        // Without a distribution (no light has power) nothing is ever picked.
        let pick = |i: usize| self.choose.as_ref().map_or(0.0, |c| c.discrete_pmf(i));
        self.lights
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let (mesh, area, [a, b, c], n, rect) = match *l {
                    Light::Triangle { mesh, area, v, n } => (mesh, area, v, n, false),
                    Light::Rect {
                        mesh,
                        area,
                        corner,
                        edge_u,
                        edge_v,
                        n,
                    } => (mesh, area, [corner, edge_u, edge_v], n, true),
                    Light::Environment => return LaneLight::Environment { pick: pick(i) },
                    Light::Sphere(_) => return LaneLight::Sphere,
                };
                LaneLight::Area(AreaLight {
                    a,
                    b,
                    c,
                    n,
                    area,
                    emission: scene.meshes[mesh as usize].emission,
                    rect,
                    pick: pick(i),
                })
            })
            .collect()
    }

    /// Whether the environment's sample direction depends on the receiving
    /// point's frame (the cosine-weighted sampler of a constant sky): the lane
    /// kernel then maps it itself; the other samplers' are drawn before it
    /// ([`Self::sample_without_frame`]).
    pub(crate) fn env_sample_in_frame(&self) -> bool {
        matches!(self.env_sampler, Some(EnvSampler::CosineAboutNormal))
    }

    /// [`Self::sample`] from `p` where `u_pick` picks a light whose sample
    /// does not read the receiving point's frame (a sphere, or the environment
    /// unless [`Self::env_sample_in_frame`]): the same sample, bit for bit.
    pub(crate) fn sample_without_frame(
        &self,
        scene: &Scene,
        p: Vec3,
        u_pick: f32,
        u: Vec2,
    ) -> Option<LightSample> {
        self.sample(scene, p, &Frame::from_normal(Vec3::Z), u_pick, u)
    }

    /// The index [`Self::sample`] picks with `u_pick` (the lights exist).
    pub(crate) fn pick(&self, u_pick: f32) -> Option<usize> {
        Some(self.choose.as_ref()?.sample_discrete(u_pick))
    }

    /// Picks a light as [`Self::sample`] does (same `u_pick`) and, when it is one
    /// whose domain can be marched line by line, returns it with the probability of
    /// choosing it.
    pub fn pick_line(&self, u_pick: f32) -> Option<(LineLight, f32)> {
        let choose = self.choose.as_ref()?;
        let idx = choose.sample_discrete(u_pick);
        match self.lights[idx] {
            Light::Environment => Some((LineLight::Environment, choose.discrete_pmf(idx))),
            Light::Sphere(i) => Some((LineLight::Sphere(i), choose.discrete_pmf(idx))),
            Light::Rect { mesh, .. } => Some((LineLight::Rect(mesh), choose.discrete_pmf(idx))),
            Light::Triangle { .. } => None,
        }
    }

    /// Solid-angle density with which [`Self::sample`] would produce the direction
    /// from `p` to the point `q` (normal `nq`) on the emitter `prim`.
    pub fn pdf_emitter(&self, scene: &Scene, prim: PrimRef, p: Vec3, q: Vec3, nq: Vec3) -> f32 {
        let Some(choose) = &self.choose else {
            return 0.0;
        };
        match prim {
            PrimRef::Triangle { mesh, tri } => {
                let first = self.mesh_first_light[mesh as usize];
                if first == u32::MAX {
                    return 0.0;
                }
                // A rectangle is one light; other meshes have one per triangle.
                let idx = match self.lights[first as usize] {
                    Light::Rect { .. } => first,
                    _ => first + tri,
                } as usize;
                let (Light::Rect { area, .. } | Light::Triangle { area, .. }) = self.lights[idx]
                else {
                    return 0.0;
                };
                let d = q - p;
                let dist2 = d.length_squared();
                let cos = (nq.dot(d) / dist2.sqrt()).abs();
                if cos <= 0.0 || area <= 0.0 {
                    return 0.0;
                }
                choose.discrete_pmf(idx) * dist2 / (area * cos)
            }
            PrimRef::Sphere(i) => {
                let idx = self.sphere_light[i as usize];
                if idx == u32::MAX {
                    return 0.0;
                }
                choose.discrete_pmf(idx as usize) * sphere_pdf(scene, i, p, q, nq)
            }
        }
    }

    /// Density with which [`Self::sample`] would produce the environment direction `wi`
    /// at a point of shading normal `n`.
    pub fn pdf_env(&self, scene: &Scene, wi: Vec3, n: Vec3) -> f32 {
        let (Some(idx), Some(choose), Some(env)) =
            (self.env_light, &self.choose, &scene.environment)
        else {
            return 0.0;
        };
        choose.discrete_pmf(idx as usize) * self.env_pdf(env, wi, n)
    }

    /// The radiance `env` sends along `-wi` and, when `mis` asks for it,
    /// [`Self::pdf_env`] of `wi` (else 0), for a ray that leaves the scene: a
    /// lat-long image's (u, v) is computed once for both (two `atan2`s), with
    /// the bits of the two calls.
    pub fn escaped(
        &self,
        scene: &Scene,
        env: &Environment,
        wi: Vec3,
        n: Vec3,
        mis: bool,
    ) -> (Vec3, f32) {
        if let (Some(EnvSampler::Image(dist)), Some(idx), Some(choose)) =
            (self.env_sampler.as_ref(), self.env_light, &self.choose)
        {
            let uv = direction_to_latlong(wi);
            if let Some(le) = env.eval_latlong(uv) {
                let pdf = if mis {
                    choose.discrete_pmf(idx as usize) * image_pdf(dist.pdf(uv), wi)
                } else {
                    0.0
                };
                return (le, pdf);
            }
        }
        let pdf = if mis { self.pdf_env(scene, wi, n) } else { 0.0 };
        (env.eval(wi), pdf)
    }

    fn sample_env(&self, env: &Environment, frame: &Frame, u: Vec2) -> Option<LightSample> {
        let wi = match (self.env_sampler.as_ref()?, env) {
            (EnvSampler::Image(dist), _) => {
                let (uv, pdf_uv) = dist.sample(u);
                let wi = latlong_to_direction(uv);
                // Density and radiance from the sampled (u, v) itself, as pbrt-v4's
                // `ImageInfiniteLight::SampleLi` does: going back from the
                // direction (`env_pdf`, `Environment::eval`) took four `atan2`s
                // per sample (glossy_teapot: 13 % of the render in `atan2f`).
                if let Some(radiance) = env.eval_latlong(uv) {
                    return Some(LightSample {
                        wi,
                        radiance,
                        pdf: image_pdf(pdf_uv, wi),
                        point: None,
                        cone: None,
                    });
                }
                wi
            }
            (
                EnvSampler::GaussianSky { lobe_prob },
                Environment::GaussianSky {
                    direction,
                    sharpness,
                    ..
                },
            ) => {
                if u.x < *lobe_prob {
                    let u = Vec2::new(u.x / lobe_prob, u.y);
                    Frame::from_normal(*direction).to_world(warp::square_to_vmf(u, *sharpness))
                } else {
                    let u = Vec2::new((u.x - lobe_prob) / (1.0 - lobe_prob), u.y);
                    warp::square_to_uniform_sphere(u)
                }
            }
            (EnvSampler::CosineAboutNormal, _) => {
                frame.to_world(warp::square_to_cosine_hemisphere(u))
            }
            _ => warp::square_to_uniform_sphere(u),
        };
        let pdf = self.env_pdf(env, wi, frame.n);
        Some(LightSample {
            wi,
            radiance: env.eval(wi),
            pdf,
            point: None,
            cone: None,
        })
    }

    fn env_pdf(&self, env: &Environment, wi: Vec3, n: Vec3) -> f32 {
        match (self.env_sampler.as_ref(), env) {
            (Some(EnvSampler::Image(dist)), _) => image_pdf(dist.pdf(direction_to_latlong(wi)), wi),
            (
                Some(EnvSampler::GaussianSky { lobe_prob }),
                Environment::GaussianSky {
                    direction,
                    sharpness,
                    ..
                },
            ) => {
                lobe_prob * warp::vmf_pdf(wi.dot(*direction), *sharpness)
                    + (1.0 - lobe_prob) * warp::UNIFORM_SPHERE_PDF
            }
            // `square_to_cosine_hemisphere`'s density, the lane kernel's too.
            (Some(EnvSampler::CosineAboutNormal), _) => warp::cosine_hemisphere_pdf_z(wi.dot(n)),
            (Some(_), _) => warp::UNIFORM_SPHERE_PDF,
            (None, _) => 0.0,
        }
    }
}

/// The solid-angle density of direction `wi` of a lat-long image sampled with
/// density `pdf_uv` over (u, v): the map (u, v) → direction has Jacobian
/// 2π · π · sin θ; 0 at the poles.
fn image_pdf(pdf_uv: f32, wi: Vec3) -> f32 {
    // From x and z, not 1 − y²: exact near the poles where y rounds to 1.
    let sin_theta = (wi.x * wi.x + wi.z * wi.z).sqrt();
    if sin_theta <= 1e-6 {
        return 0.0;
    }
    pdf_uv / (2.0 * PI * PI * sin_theta)
}

fn build_env_sampler(env: &Environment) -> EnvSampler {
    match env {
        Environment::Constant { .. } => EnvSampler::CosineAboutNormal,
        Environment::Image {
            width,
            height,
            texels,
            ..
        } => {
            let mut w = Vec::with_capacity(width * height);
            for y in 0..*height {
                let sin_theta = ((y as f32 + 0.5) / *height as f32 * PI).sin();
                for x in 0..*width {
                    // Bilinear lookup spreads a texel into its neighbours: blur the
                    // weights by taking the max of the 3×3 neighbourhood so that no
                    // direction with radiance gets a zero density.
                    let mut m = 0.0f32;
                    for dy in -1i64..=1 {
                        let yy = (y as i64 + dy).clamp(0, *height as i64 - 1) as usize;
                        for dx in -1i64..=1 {
                            let xx = (x as i64 + dx).rem_euclid(*width as i64) as usize;
                            m = m.max(luminance(texels[yy * width + xx]));
                        }
                    }
                    w.push(m * sin_theta);
                }
            }
            EnvSampler::Image(Distribution2D::new(&w, *width, *height))
        }
        Environment::GaussianSky {
            sharpness,
            peak,
            ambient,
            ..
        } => {
            // Power of each part: the lobe integrates to peak·2π(1−e^{−2κ})/κ.
            let lobe = luminance(*peak) * environment::gaussian_lobe_integral(*sharpness);
            let flat = luminance(*ambient) * 4.0 * PI;
            let total = lobe + flat;
            let p = if total > 0.0 { lobe / total } else { 0.0 };
            // Keep some uniform sampling so the ambient part is never starved.
            EnvSampler::GaussianSky {
                lobe_prob: p.clamp(0.0, 0.95),
            }
        }
    }
}

/// Radius of a sphere around all finite geometry (at least 1).
fn scene_radius(scene: &Scene) -> f32 {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for m in &scene.meshes {
        for &p in &m.positions {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    for s in &scene.spheres {
        lo = lo.min(s.center - Vec3::splat(s.radius));
        hi = hi.max(s.center + Vec3::splat(s.radius));
    }
    if lo.x > hi.x {
        return 1.0;
    }
    (0.5 * (hi - lo).length()).max(1.0)
}

/// The point `q`, drawn uniformly over an emitter of area `area` (unit normal
/// `n`), seen from `p`: its direction and density in solid angle; `None` from
/// behind.
fn sample_area_point(q: Vec3, n: Vec3, area: f32, emission: Vec3, p: Vec3) -> Option<LightSample> {
    let (_, wi, pdf, defined) = area_point_pdf(q, n, wide::f32x4::splat(area), p);
    if defined.bitmask() & 1 == 0 {
        return None;
    }
    Some(LightSample {
        wi,
        radiance: emission,
        pdf: pdf.to_array()[0],
        point: Some((q, n)),
        cone: None,
    })
}

/// [`sample_area_point`]'s geometry on one point or on the lane kernel's
/// eight: `d = q − p`, the unit direction, the solid-angle density, and a
/// mask where that is defined (q ≠ p, a positive area, `p` in front of the
/// emitter: one-sided emission, the back of an emitter is dark).
#[inline(always)]
pub(crate) fn area_point_pdf<V: Vector3>(q: V, n: V, area: V::L, p: V) -> (V, V, V::L, V::L) {
    let zero = V::L::splat(0.0);
    let d = q.diff(p);
    let dist2 = d.dot(d);
    let len = dist2.sqrt();
    let wi = d.map(
        #[inline(always)]
        |c| c / len,
    );
    let cos_l = -n.dot(wi);
    let defined = dist2.gt(zero).and(area.gt(zero)).and(cos_l.gt(zero));
    (d, wi, dist2 / (area * cos_l), defined)
}

/// Samples the cone of directions a sphere light subtends (uniform in solid angle:
/// zero variance in the geometry term, unlike area sampling); area sampling when
/// `p` is inside the sphere.
fn sample_sphere(scene: &Scene, i: u32, p: Vec3, u: Vec2) -> Option<LightSample> {
    let s = &scene.spheres[i as usize];
    let to_c = s.center - p;
    let dist2 = to_c.length_squared();
    let r2 = s.radius * s.radius;
    let inside = dist2 <= r2 * 1.0001;
    let (wi, q, n) = if inside {
        // Inside (or on) the light: uniform area sampling of the whole sphere.
        let n = warp::square_to_uniform_sphere(u);
        let q = s.center + s.radius * n;
        let wi = (q - p) / (q - p).length().max(1e-30);
        if -n.dot(wi) <= 0.0 {
            return None;
        }
        (wi, q, n)
    } else {
        let dist = dist2.sqrt();
        let cos_max = (1.0 - r2 / dist2).max(0.0).sqrt();
        let wi = Frame::from_normal(to_c / dist).to_world(warp::square_to_uniform_cone(u, cos_max));
        // Point on the sphere along wi: nearer root of |p + t wi − c|² = r².
        let b = to_c.dot(wi);
        let disc = (r2 - (to_c - b * wi).length_squared()).max(0.0);
        let q = p + (b - disc.sqrt()) * wi;
        (wi, q, (q - s.center).normalize_or_zero())
    };
    // One density formula for sampling and for MIS, so the two always agree.
    Some(LightSample {
        wi,
        radiance: s.emission,
        pdf: sphere_pdf(scene, i, p, q, n),
        point: Some((q, n)),
        cone: (!inside).then_some((s.center, s.radius)),
    })
}

fn sphere_pdf(scene: &Scene, i: u32, p: Vec3, q: Vec3, nq: Vec3) -> f32 {
    let s = &scene.spheres[i as usize];
    let dist2 = (s.center - p).length_squared();
    let r2 = s.radius * s.radius;
    if dist2 <= r2 * 1.0001 {
        let d = q - p;
        let d2 = d.length_squared();
        let cos_l = (nq.dot(d) / d2.sqrt()).abs();
        if cos_l <= 0.0 {
            return 0.0;
        }
        return d2 / (4.0 * PI * r2 * cos_l);
    }
    let cos_max = (1.0 - r2 / dist2).max(0.0).sqrt();
    warp::uniform_cone_pdf(cos_max)
}
