//! Paths traced together, their shading eight hits at a time (issue 16).
//!
//! [`PathTracer::li`] shades one hit at a time: ~1,200 instructions of scalar
//! and three-wide vector work per vertex, at an IPC near the core's limit, so
//! only fewer instructions make it faster. Here a batch of paths (a tile row's
//! samples) advances bounce by bounce: every live path's ray is traced with the
//! same single-ray queries, then the hits are shaded in `wide::f32x8` lanes —
//! the surface point and its error bound, the frame, the light sample, the
//! Lambertian eval, pdf and sample, MIS, both rays' offsets — then the shadow
//! rays are traced and the paths go on. Same estimator, same random numbers
//! (each path keeps its `PixelSampler`), the same operations in the same order
//! lane by lane: a path's radiance is `li`'s, whichever paths share its lanes
//! and whatever the thread count (`tests`: sample for sample).
//!
//! It takes Lambertian triangle meshes without shading normals or bump maps,
//! lit by area lights (rectangles, emitting triangles), without gradients or
//! line sampling ([`LaneScene::build`]); everything else goes through `li`.

use super::interaction::interaction;
use super::lights::AreaLight;
use super::path::{power_heuristic, FirstHit, PathTracer, SampleResult, VertexSamples};
use crate::accel::{triangle_normal, Hit, PrimRef};
use crate::brdf::Material;
use crate::math::sampler::PixelSampler;
use crate::math::{warp, Ray, Vec3};
use crate::scene::Scene;
use wide::{f32x8, f64x4};

/// Lanes per shading step: AVX's width (two SSE registers each on a build
/// without it).
const LANES: usize = 8;

/// Per-triangle data the lanes gather, indexed by the mesh's first triangle +
/// the triangle: vertices, the accel's unit normal and the sanitised albedo.
#[derive(Clone, Copy, Debug, Default)]
struct LaneTriangle {
    v: [Vec3; 3],
    n: Vec3,
    albedo: Vec3,
}

/// What the lane shading needs of a scene it can take.
#[derive(Debug)]
pub(crate) struct LaneScene {
    first: Vec<u32>,
    triangles: Vec<LaneTriangle>,
    lights: Vec<AreaLight>,
}

impl LaneScene {
    /// `None` unless every shape is a Lambertian triangle mesh without shading
    /// normals or a bump map and every light an area light.
    pub(crate) fn build(scene: &Scene, lights: &super::lights::LightSet) -> Option<Self> {
        if !scene.spheres.is_empty() || scene.environment.is_some() {
            return None;
        }
        let lights = lights.area_lights(scene)?;
        let mut first = Vec::with_capacity(scene.meshes.len());
        let mut triangles = Vec::new();
        for m in &scene.meshes {
            let Material::Lambert { albedo } = scene.materials.get(m.material as usize)? else {
                return None;
            };
            if !m.normals.is_empty() || m.bump.is_some() {
                return None;
            }
            first.push(u32::try_from(triangles.len()).ok()?);
            let keep = albedo.cmpgt(Vec3::ZERO) & albedo.cmplt(Vec3::INFINITY);
            let albedo = Vec3::select(keep, *albedo, Vec3::ZERO);
            triangles.extend(m.triangles.iter().map(|t| {
                let v = t.map(|i| m.positions[i as usize]);
                LaneTriangle {
                    v,
                    n: triangle_normal(v),
                    albedo,
                }
            }));
        }
        Some(Self {
            first,
            triangles,
            lights,
        })
    }

    /// Traces every path of `batch` and leaves in it what [`PathTracer::li`]
    /// would return for each (no gradients).
    pub(crate) fn trace(&self, tracer: &PathTracer, batch: &mut LaneBatch) {
        let LaneBatch {
            paths,
            live,
            shaded,
            gathered,
        } = batch;
        live.clear();
        live.extend(0..paths.len());
        for depth in 1..=tracer.max_depth {
            let mut kept = 0;
            for k in 0..live.len() {
                let i = live[k];
                if self.intersect(tracer, &mut paths[i], depth) {
                    live[kept] = i;
                    kept += 1;
                }
            }
            live.truncate(kept);
            if depth == tracer.max_depth || live.is_empty() {
                break;
            }
            shaded.clear();
            for chunk in live.chunks(LANES) {
                self.shade(tracer, paths, chunk, depth, gathered);
                shaded.push(shade8(gathered));
            }
            let mut kept = 0;
            for k in 0..live.len() {
                let i = live[k];
                let s = &shaded[k / LANES];
                if self.finish(tracer, &mut paths[i], s, k % LANES, depth) {
                    live[kept] = i;
                    kept += 1;
                }
            }
            live.truncate(kept);
            if live.is_empty() {
                break;
            }
        }
    }

    /// The path's closest hit and the emission found there (MIS-weighted as
    /// `li` weighs it); `false` when the ray leaves the scene.
    fn intersect(&self, tracer: &PathTracer, p: &mut LanePath, depth: u32) -> bool {
        p.rays += 1;
        let Some(hit) = tracer.accel.intersect(&p.ray) else {
            return false;
        };
        let PrimRef::Triangle { mesh, .. } = hit.prim else {
            unreachable!("a lane scene has triangles only");
        };
        let m = &tracer.scene.meshes[mesh as usize];
        // The first hit's AOVs come from the lanes (`finish`), unless no
        // bounce is shaded at all.
        let aovs = depth == 1 && tracer.max_depth == 1;
        if m.emission != Vec3::ZERO || aovs {
            // Rare: the scalar set-up, which gives the same point and normals.
            let si = interaction(tracer.scene, tracer.accel, &p.ray, &hit);
            if aovs {
                p.first_hit = Some(FirstHit {
                    normal: si.frame.n,
                    depth: hit.t,
                    albedo: tracer.scene.materials[si.material as usize].albedo(),
                    object_id: si.object_id,
                    back_facing: si.frame.n.dot(p.ray.dir) >= 0.0,
                });
            }
            if si.emission != Vec3::ZERO {
                let w = if p.prev_pdf.is_infinite() {
                    1.0
                } else {
                    let light_pdf =
                        tracer
                            .lights
                            .pdf_emitter(tracer.scene, si.prim, p.prev_p, si.p, si.ng);
                    power_heuristic(p.prev_pdf, light_pdf)
                };
                p.radiance += p.beta * si.emission * w;
            }
        }
        p.hit = Some(hit);
        true
    }

    /// Gathers the hits of the paths `chunk` (at most [`LANES`]) and their
    /// random numbers into lanes.
    fn shade(
        &self,
        tracer: &PathTracer,
        paths: &mut [LanePath],
        chunk: &[usize],
        depth: u32,
        g: &mut Gathered,
    ) {
        for (l, &i) in chunk.iter().enumerate() {
            let p = &mut paths[i];
            let u = VertexSamples::draw(&mut p.sampler, depth);
            let hit = p.hit.expect("a live path has a hit");
            let PrimRef::Triangle { mesh, tri } = hit.prim else {
                unreachable!("a lane scene has triangles only");
            };
            let t = &self.triangles[(self.first[mesh as usize] + tri) as usize];
            let light = tracer.lights.pick(u.pick).map(|k| &self.lights[k]);
            g.set(l, p, &hit, t, &u, light);
        }
        // Unused lanes repeat lane 0: finite inputs, results dropped.
        for l in chunk.len()..LANES {
            g.copy_lane(0, l);
        }
    }

    /// Direct light through the shadow ray, then the continuation (throughput,
    /// MIS state, Russian roulette), as `li` does; `false` when the path ends.
    /// `s`'s lane `l` is this path's.
    fn finish(
        &self,
        tracer: &PathTracer,
        p: &mut LanePath,
        s: &Shaded8,
        l: usize,
        depth: u32,
    ) -> bool {
        let bit = |m: u32| m & (1 << l) != 0;
        if depth == 1 {
            // `li`'s `visible_surface`: the frame's normal is the flipped
            // geometric one here.
            let hit = p.hit.expect("a shaded path has a hit");
            let PrimRef::Triangle { mesh, .. } = hit.prim else {
                unreachable!("a lane scene has triangles only");
            };
            let m = &tracer.scene.meshes[mesh as usize];
            let normal = s.ng.lane(l);
            p.first_hit = Some(FirstHit {
                normal,
                depth: hit.t,
                albedo: tracer.scene.materials[m.material as usize].albedo(),
                object_id: m.object_id,
                back_facing: normal.dot(p.ray.dir) >= 0.0,
            });
        }
        if !bit(s.alive) {
            return false;
        }
        if bit(s.direct) {
            p.rays += 1;
            let shadow = segment(s.shadow_o.lane(l), s.shadow_end.lane(l));
            if !tracer.accel.occluded(&shadow) {
                p.radiance += s.ld.lane(l);
            }
        }
        if !bit(s.next) {
            return false;
        }
        p.beta *= s.weight.lane(l);
        p.prev_pdf = s.pdf.as_array()[l];
        p.prev_p = s.p.lane(l);
        p.ray = Ray::new(s.next_o.lane(l), s.next_d.lane(l));
        if depth >= tracer.rr_depth {
            let q = p.beta.max_element().min(0.95);
            if q <= 0.0 || s.u_rr[l] >= q {
                return false;
            }
            p.beta /= q;
        }
        p.beta != Vec3::ZERO
    }
}

/// Paths traced together: [`LaneBatch::push`] each camera sample, then
/// [`LaneScene::trace`], then [`LaneBatch::results`]; reused from batch to
/// batch, so that a tile allocates once.
#[derive(Default)]
pub(crate) struct LaneBatch {
    paths: Vec<LanePath>,
    live: Vec<usize>,
    shaded: Vec<Shaded8>,
    gathered: Gathered,
}

impl LaneBatch {
    /// A path from the camera ray `ray`, drawing from `sampler`.
    pub(crate) fn push(&mut self, ray: Ray, sampler: PixelSampler) {
        self.paths.push(LanePath {
            ray,
            sampler,
            beta: Vec3::ONE,
            radiance: Vec3::ZERO,
            prev_pdf: f32::INFINITY,
            prev_p: ray.origin,
            hit: None,
            first_hit: None,
            rays: 0,
        });
    }

    pub(crate) fn len(&self) -> usize {
        self.paths.len()
    }

    /// Each path's result, in the order they were pushed; the batch is then empty.
    pub(crate) fn results(&mut self) -> impl Iterator<Item = SampleResult> + '_ {
        self.paths.drain(..).map(|p| SampleResult {
            radiance: p.radiance,
            first_hit: p.first_hit,
            gradient: None,
            rays: p.rays,
        })
    }
}

/// One path's state between bounces.
struct LanePath {
    ray: Ray,
    sampler: PixelSampler,
    beta: Vec3,
    radiance: Vec3,
    prev_pdf: f32,
    prev_p: Vec3,
    hit: Option<Hit>,
    first_hit: Option<FirstHit>,
    rays: u32,
}

/// The inputs of [`shade8`], one array per scalar, one entry per lane.
#[derive(Default)]
struct Gathered {
    dir: [[f32; LANES]; 3],
    bary: [[f32; LANES]; 2],
    v: [[[f32; LANES]; 3]; 3],
    n: [[f32; LANES]; 3],
    albedo: [[f32; LANES]; 3],
    beta: [[f32; LANES]; 3],
    u_dir: [[f32; LANES]; 2],
    u_rr: [f32; LANES],
    /// The picked light: its point's three terms and weights, its normal, area,
    /// pick probability and emission; `has_light` 0 without one.
    light: [[[f32; LANES]; 3]; 3],
    light_w: [[f32; LANES]; 3],
    light_n: [[f32; LANES]; 3],
    light_area: [f32; LANES],
    light_pick: [f32; LANES],
    light_le: [[f32; LANES]; 3],
    has_light: [f32; LANES],
}

impl Gathered {
    fn set(
        &mut self,
        l: usize,
        p: &LanePath,
        hit: &Hit,
        t: &LaneTriangle,
        u: &VertexSamples,
        light: Option<&AreaLight>,
    ) {
        for c in 0..3 {
            self.dir[c][l] = p.ray.dir[c];
            self.n[c][l] = t.n[c];
            self.albedo[c][l] = t.albedo[c];
            self.beta[c][l] = p.beta[c];
            for k in 0..3 {
                self.v[k][c][l] = t.v[k][c];
            }
        }
        self.bary[0][l] = hit.bary.x;
        self.bary[1][l] = hit.bary.y;
        self.u_dir[0][l] = u.dir.x;
        self.u_dir[1][l] = u.dir.y;
        self.u_rr[l] = u.rr;
        let Some(a) = light else {
            self.has_light[l] = 0.0;
            return;
        };
        self.has_light[l] = 1.0;
        // `LightSet::sample`'s point: corner + u·edge_u + v·edge_v, or the
        // triangle's vertices weighted by a uniform barycentric sample.
        let w = if a.rect {
            [1.0, u.light.x, u.light.y]
        } else {
            let b = warp::square_to_uniform_triangle(u.light);
            [1.0 - b.x - b.y, b.x, b.y]
        };
        for (c, w) in w.into_iter().enumerate() {
            self.light[0][c][l] = a.a[c];
            self.light[1][c][l] = a.b[c];
            self.light[2][c][l] = a.c[c];
            self.light_w[c][l] = w;
            self.light_n[c][l] = a.n[c];
            self.light_le[c][l] = a.emission[c];
        }
        self.light_area[l] = a.area;
        self.light_pick[l] = a.pick;
    }

    fn copy_lane(&mut self, from: usize, to: usize) {
        fn lane<const N: usize>(planes: &mut [[f32; LANES]; N], from: usize, to: usize) {
            for p in planes {
                p[to] = p[from];
            }
        }
        lane(&mut self.dir, from, to);
        lane(&mut self.bary, from, to);
        for v in &mut self.v {
            lane(v, from, to);
        }
        lane(&mut self.n, from, to);
        lane(&mut self.albedo, from, to);
        lane(&mut self.beta, from, to);
        lane(&mut self.u_dir, from, to);
        for v in &mut self.light {
            lane(v, from, to);
        }
        lane(&mut self.light_w, from, to);
        lane(&mut self.light_n, from, to);
        lane(&mut self.light_le, from, to);
        for p in [
            &mut self.u_rr,
            &mut self.light_area,
            &mut self.light_pick,
            &mut self.has_light,
        ] {
            p[to] = p[from];
        }
    }
}

/// Three planes of lanes: eight vectors.
#[derive(Clone, Copy)]
struct V8 {
    x: f32x8,
    y: f32x8,
    z: f32x8,
}

impl V8 {
    fn load(p: &[[f32; LANES]; 3]) -> Self {
        Self {
            x: f32x8::new(p[0]),
            y: f32x8::new(p[1]),
            z: f32x8::new(p[2]),
        }
    }
    /// glam's order: (x·x' + y·y') + z·z'.
    fn dot(self, o: Self) -> f32x8 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    fn add(self, o: Self) -> Self {
        Self {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
    fn sub(self, o: Self) -> Self {
        Self {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
    fn mul(self, s: f32x8) -> Self {
        Self {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    fn mul_v(self, o: Self) -> Self {
        Self {
            x: self.x * o.x,
            y: self.y * o.y,
            z: self.z * o.z,
        }
    }
    fn div(self, s: f32x8) -> Self {
        Self {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
    fn neg(self) -> Self {
        Self {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
    fn abs(self) -> Self {
        Self {
            x: self.x.abs(),
            y: self.y.abs(),
            z: self.z.abs(),
        }
    }
    fn is_finite(self) -> f32x8 {
        self.x.is_finite() & self.y.is_finite() & self.z.is_finite()
    }
    fn lane(self, l: usize) -> Vec3 {
        Vec3::new(
            self.x.as_array()[l],
            self.y.as_array()[l],
            self.z.as_array()[l],
        )
    }
}

/// `Frame`'s basis in lanes.
struct Frame8 {
    s: V8,
    t: V8,
    n: V8,
}

impl Frame8 {
    /// `Frame::from_normal` (Duff et al. 2017), operation for operation.
    fn from_normal(n: V8) -> Self {
        let one = f32x8::ONE;
        let sign = n.z.is_sign_negative().select(-one, one);
        let a = -one / (sign + n.z);
        let b = n.x * n.y * a;
        Self {
            s: V8 {
                x: one + sign * n.x * n.x * a,
                y: sign * b,
                z: -sign * n.x,
            },
            t: V8 {
                x: b,
                y: sign + n.y * n.y * a,
                z: -n.y,
            },
            n,
        }
    }
    fn to_local(&self, v: V8) -> V8 {
        V8 {
            x: v.dot(self.s),
            y: v.dot(self.t),
            z: v.dot(self.n),
        }
    }
    fn to_world(&self, v: V8) -> V8 {
        self.s.mul(v.x).add(self.t.mul(v.y)).add(self.n.mul(v.z))
    }
}

/// `accel::offset_ray_origin_with_error` in lanes.
fn offset8(p: V8, p_error: V8, n: V8, dir: V8) -> V8 {
    let zero = f32x8::ZERO;
    let d = n.abs().dot(p_error);
    let offset = n.mul(d);
    let offset = dir.dot(n).simd_lt(zero).select_v(offset.neg(), offset);
    let po = p.add(offset);
    let away = |o: f32x8| {
        o.simd_eq(zero)
            .select(zero, o.is_sign_negative().select(-f32x8::ONE, f32x8::ONE))
    };
    let step =
        |po: f32x8| (po.abs() * f32x8::splat(f32::EPSILON)).max(f32x8::splat(f32::MIN_POSITIVE));
    V8 {
        x: po.x + away(offset.x) * step(po.x),
        y: po.y + away(offset.y) * step(po.y),
        z: po.z + away(offset.z) * step(po.z),
    }
}

trait SelectV8 {
    fn select_v(self, t: V8, f: V8) -> V8;
}

impl SelectV8 for f32x8 {
    fn select_v(self, t: V8, f: V8) -> V8 {
        V8 {
            x: self.select(t.x, f.x),
            y: self.select(t.y, f.y),
            z: self.select(t.z, f.z),
        }
    }
}

/// The results of [`shade8`], per lane.
struct Shaded8 {
    alive: u32,
    p: V8,
    ng: V8,
    direct: u32,
    ld: V8,
    shadow_o: V8,
    shadow_end: V8,
    next: u32,
    next_o: V8,
    next_d: V8,
    weight: V8,
    pdf: f32x8,
    u_rr: [f32; LANES],
}

/// `SurfacePoint::spawn_ray_to`'s segment from its two offset ends.
fn segment(o: Vec3, end: Vec3) -> Ray {
    crate::accel::SurfacePoint::segment(o, end)
}

/// The shading of eight hits: `interaction`, the light sample, the
/// Lambertian eval, pdf and sample, MIS and both rays' offsets, as `li` and
/// the functions it calls compute them.
fn shade8(g: &Gathered) -> Shaded8 {
    let zero = f32x8::ZERO;
    let one = f32x8::ONE;
    let frac_1_pi = f32x8::splat(std::f32::consts::FRAC_1_PI);
    let dir = V8::load(&g.dir);
    let (b1, b2) = (f32x8::new(g.bary[0]), f32x8::new(g.bary[1]));
    // `triangle_point_with_normal`: the vertices weighted, and the error bound.
    let b0 = one - b1 - b2;
    let t0 = V8::load(&g.v[0]).mul(b0);
    let t1 = V8::load(&g.v[1]).mul(b1);
    let t2 = V8::load(&g.v[2]).mul(b2);
    let p = t0.add(t1).add(t2);
    let gamma7 = f32x8::splat(crate::accel::gamma_bound(7));
    let p_error = t0.abs().add(t1.abs()).add(t2.abs()).mul(gamma7);
    // `interaction::finish`: normals toward the ray, the frame.
    let n = V8::load(&g.n);
    let front = dir.dot(n).simd_lt(zero);
    let ng = n.mul(front.select(one, -one));
    let frame = Frame8::from_normal(ng);
    let wo = frame.to_local(dir.neg());
    let alive = wo.z.simd_gt(zero);
    let albedo = V8::load(&g.albedo);
    let beta = V8::load(&g.beta);

    // The light sample (`LightSet::sample` → `sample_area_point`).
    let w = V8::load(&g.light_w);
    let q = V8::load(&g.light[0])
        .mul(w.x)
        .add(V8::load(&g.light[1]).mul(w.y))
        .add(V8::load(&g.light[2]).mul(w.z));
    let d = q.sub(p);
    let dist2 = d.dot(d);
    let area = f32x8::new(g.light_area);
    let wi = d.div(dist2.sqrt());
    let ln = V8::load(&g.light_n);
    let cos_l = -ln.dot(wi);
    let light_pdf = dist2 / (area * cos_l) * f32x8::new(g.light_pick);
    let sampled = f32x8::new(g.has_light).simd_gt(zero)
        & dist2.simd_gt(zero)
        & area.simd_gt(zero)
        & cos_l.simd_gt(zero)
        & light_pdf.simd_gt(zero)
        & light_pdf.is_finite();
    // `Material::eval` (Lambert) and the checks of `sample_ld`.
    let wil = frame.to_local(wi);
    let upper = wo.is_finite() & wil.is_finite() & wo.z.simd_gt(zero) & wil.z.simd_gt(zero);
    let f = albedo.mul(frac_1_pi);
    let f_nonzero = f.x.simd_ne(zero) | f.y.simd_ne(zero) | f.z.simd_ne(zero);
    let direct = alive & sampled & upper & wi.dot(ng).simd_gt(zero) & f_nonzero;
    // `Material::pdf` (Lambert): wi's z normalised at f64, as `unit_z` does.
    let bsdf_pdf = lambert_pdf8(wil);
    let weight_mis = power_heuristic8(light_pdf, bsdf_pdf);
    let le = V8::load(&g.light_le);
    let ld = beta
        .mul_v(f)
        .mul(wil.z)
        .mul_v(le)
        .mul(weight_mis / light_pdf);
    // `spawn_ray_to`: both ends offset.
    let shadow_o = offset8(p, p_error, ng, d);
    let q_error = {
        let m = q.x.abs().max(q.y.abs()).max(q.z.abs());
        let e = m * f32x8::splat(crate::accel::DEFAULT_REL_ERROR) + f32x8::splat(1.0e-30);
        V8 { x: e, y: e, z: e }
    };
    let shadow_end = offset8(q, q_error, ln, d.neg());

    // The BSDF sample (`lambert::sample`: the concentric map, z from its radius).
    let ox = f32x8::splat(2.0) * f32x8::new(g.u_dir[0]) - one;
    let oy = f32x8::splat(2.0) * f32x8::new(g.u_dir[1]) - one;
    let centre = ox.simd_eq(zero) & oy.simd_eq(zero);
    let x_major = ox.abs().simd_gt(oy.abs());
    let r = x_major.select(ox, oy);
    let other = x_major.select(oy, ox);
    let (s, c) = sin_cos_quarter8(f32x8::splat(std::f32::consts::FRAC_PI_4) * (other / r));
    let (cos, sin) = (x_major.select(c, s), x_major.select(s, c));
    let r = centre.select(zero, r);
    let lx = centre.select(zero, r * cos);
    let ly = centre.select(zero, r * sin);
    let rr = r.abs();
    let lz = (one - rr * rr).max(zero).sqrt();
    let pdf = lz.simd_gt(zero).select(lz * frac_1_pi, zero);
    let wi_next = frame.to_world(V8 {
        x: lx,
        y: ly,
        z: lz,
    });
    let next = alive & pdf.simd_gt(zero) & wi_next.dot(ng).simd_gt(zero) & albedo.is_finite();
    let next_o = offset8(p, p_error, ng, wi_next);
    Shaded8 {
        alive: alive.to_bitmask(),
        p,
        ng,
        direct: direct.to_bitmask(),
        ld,
        shadow_o,
        shadow_end,
        next: next.to_bitmask(),
        next_o,
        next_d: wi_next,
        weight: albedo,
        pdf,
        u_rr: g.u_rr,
    }
}

/// `warp::sin_cos_quarter` in lanes, operation for operation.
fn sin_cos_quarter8(x: f32x8) -> (f32x8, f32x8) {
    let z = x * x;
    let s = ((f32x8::splat(-1.951_529_6e-4) * z + f32x8::splat(8.332_161e-3)) * z
        - f32x8::splat(1.666_665_5e-1))
        * z
        * x
        + x;
    let c = ((f32x8::splat(2.443_315_7e-5) * z - f32x8::splat(1.388_731_6e-3)) * z
        + f32x8::splat(4.166_664_6e-2))
        * z
        * z
        - f32x8::splat(0.5) * z
        + f32x8::ONE;
    (s, c)
}

/// `path::power_heuristic` in lanes.
fn power_heuristic8(f: f32x8, g: f32x8) -> f32x8 {
    let (f2, g2) = (f * f, g * g);
    let sum = f2 + g2;
    f2.is_inf().select(
        f32x8::ONE,
        sum.simd_le(f32x8::ZERO).select(f32x8::ZERO, f2 / sum),
    )
}

/// `Material::pdf` of a Lambertian for a direction above the horizon (the
/// caller masks the rest): cos θ normalised at f64, over π, made finite.
fn lambert_pdf8(v: V8) -> f32x8 {
    let half = |k: usize| {
        let f = |a: f32x8| f64x4::new(std::array::from_fn(|i| f64::from(a.as_array()[4 * k + i])));
        let (x, y, z) = (f(v.x), f(v.y), f(v.z));
        let len2 = x * x + y * y + z * z;
        z / len2.sqrt() * f64x4::splat(std::f64::consts::FRAC_1_PI)
    };
    let (lo, hi) = (half(0), half(1));
    let p = f32x8::new(std::array::from_fn(|i| {
        let h = if i < 4 { lo } else { hi };
        h.as_array()[i % 4] as f32
    }));
    (p.simd_gt(f32x8::ZERO) & p.is_finite()).select(p, f32x8::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;
    use crate::render::{camera_ray, camera_sample_at, RenderOptions, Setup};

    /// Every sample of a cornell render, traced by `li` and by the lanes with
    /// the same sampler: the same radiance bit for bit, the same AOVs, the
    /// same ray count.
    #[test]
    fn lanes_trace_the_paths_li_traces() {
        let scene = crate::scene::load(std::path::Path::new("scenes/validation/cornell_256.toml"))
            .expect("bundled scene");
        let accel = crate::accel::Accel::build(&scene.meshes, &scene.spheres);
        let setup = Setup::new(&scene, &RenderOptions::default()).expect("setup");
        let tracer = setup.tracer(&scene, &accel);
        let lanes = setup.lanes().expect("cornell is a lane scene");
        let (w, h) = (setup.camera.width, setup.camera.height);
        let mut compared = 0;
        for pixel in (0..w * h).step_by(97) {
            let corner = Vec2::new((pixel % w) as f32, (pixel / w) as f32);
            let mut batch = LaneBatch::default();
            let mut expected = Vec::new();
            for s in 0..13 {
                expected.push(camera_sample_at(
                    &tracer,
                    &setup.camera,
                    corner,
                    pixel,
                    s,
                    5,
                    false,
                ));
                let (ray, sampler) = camera_ray(&setup.camera, corner, pixel, s, 5);
                batch.push(ray, sampler);
            }
            lanes.trace(&tracer, &mut batch);
            let got: Vec<SampleResult> = batch.results().collect();
            for (e, g) in expected.iter().zip(&got) {
                assert_eq!(
                    e.radiance.to_array().map(f32::to_bits),
                    g.radiance.to_array().map(f32::to_bits),
                    "pixel {pixel}: {} vs {}",
                    e.radiance,
                    g.radiance
                );
                assert_eq!(e.rays, g.rays, "pixel {pixel}");
                let aov = |f: &Option<FirstHit>| {
                    f.map(|f| (f.normal, f.depth, f.albedo, f.object_id, f.back_facing))
                };
                assert_eq!(aov(&e.first_hit), aov(&g.first_hit), "pixel {pixel}");
                compared += 1;
            }
        }
        assert!(compared > 8000, "{compared}");
    }

    /// Only what the lanes shade exactly as `li` does gets them.
    #[test]
    fn lane_scenes_are_lambertian_meshes_under_area_lights() {
        let load = |p: &str| crate::scene::load(std::path::Path::new(p)).expect("bundled scene");
        let lanes = |s: &Scene| {
            let lights = crate::render::lights::LightSet::build(s);
            LaneScene::build(s, &lights).is_some()
        };
        let mut cornell = load("scenes/cornell.toml");
        assert!(lanes(&cornell));
        for (scene, why) in [
            ("scenes/spheres_table.toml", "spheres"),
            ("scenes/glossy_teapot.toml", "a glossy material"),
            ("scenes/validation/env_constant.toml", "an environment"),
            ("scenes/objects_bumpy.toml", "bump maps"),
        ] {
            assert!(!lanes(&load(scene)), "{scene}: {why}");
        }
        // Shading normals on one mesh.
        let m = &mut cornell.meshes[0];
        m.normals = vec![Vec3::Y; m.positions.len()];
        assert!(!lanes(&cornell));
    }
}
