//! Paths traced together, their shading eight hits at a time (issue 16).
//!
//! [`PathTracer::li`] shades one hit at a time: ~1,200 instructions of scalar
//! and three-wide vector work per vertex, at an IPC near the core's limit, so
//! only fewer instructions make it faster. Here a batch of paths (up to
//! `render::LANE_BATCH` of a tile row's samples) advances bounce by bounce:
//! every live path's ray is traced (as one ray stream where the tree is
//! small, `accel::stream`; else with the same single-ray queries), then
//! the hits are shaded eight at a time in SIMD lanes (`kernel`: AVX
//! registers where the CPU has AVX2, `wide::f32x8` else) —
//! the surface point and its error bound, the frame, the light sample, the
//! Lambertian eval, pdf and sample, MIS, both rays' offsets — then the shadow
//! rays are traced and the paths go on. Same estimator, same random numbers
//! (each path keeps its `PixelSampler`), the same operations in the same order
//! lane by lane: a path's radiance is `li`'s, whichever paths share its lanes
//! and whatever the thread count (`tests`: sample for sample).
//!
//! It takes triangle meshes (with or without shading normals) and spheres,
//! Lambertian or mirrors, without bump maps, under any light, without
//! gradients or line sampling ([`refusal`]); everything else (glossy
//! materials, bump maps) goes through `li`. A sphere hit's surface point is
//! computed while the lanes are gathered (`sphere_point`, as `interaction`
//! does), a triangle's in the kernel. A constant sky's cosine-weighted
//! sample needs the shading frame, so the kernel maps it; an image's or a
//! Gaussian sky's, and a sphere light's (from the hit point), are drawn
//! while gathering (`LightSet::sample_without_frame`).

use super::interaction::interaction;
use super::lights::{AreaLight, LaneLight, LightSample};
use super::path::{FirstHit, PathState, PathTracer, SampleResult, VertexSamples};
use crate::accel::{
    sphere_point, triangle_normal, triangle_point_with_normal, Hit, PrimRef, RayStream,
    SurfacePoint,
};
use crate::brdf::{LaneBsdf, Material};
use crate::math::sampler::PixelSampler;
use crate::math::{warp, Ray, Vec2, Vec3};
use crate::scene::Scene;
use kernel::Shaded8;

pub mod check;
mod kernel;

/// Lanes per shading step: AVX's width (two SSE registers each on a build
/// without it).
const LANES: usize = 8;

/// Per-triangle data the lanes gather, indexed by the mesh's first triangle +
/// the triangle: vertices, the accel's unit normal and the sanitised albedo.
/// A copy of what `Accel::hit_triangle` and the mesh give (80 bytes per
/// triangle): read through those instead, one lane at a time, cornell's render
/// took 4–6 % longer.
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
    lights: Vec<LaneLight>,
    /// A constant sky's radiance when the kernel maps its sample (cosine-
    /// weighted about the shading frame); `None` when there is no
    /// environment or its sample reads no frame and is drawn before the
    /// kernel (`LightSet::sample_without_frame`).
    sky_in_frame: Option<Vec3>,
    /// Some light's sample is drawn before the kernel (a sphere's, or an
    /// environment's), or mapped in it (a constant sky's).
    other_lights: bool,
    /// Each sphere's sanitised albedo (a mirror's reflectance).
    sphere_albedo: Vec<Vec3>,
    /// Whether each mesh, each sphere is a mirror (else Lambertian), and
    /// whether any is.
    mesh_mirror: Vec<bool>,
    sphere_mirror: Vec<bool>,
    mirrors: bool,
    /// The kernel in AVX's registers (the CPU has AVX2), else in `wide`'s.
    #[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
    avx2: bool,
    /// Each triangle's vertex normals, when some mesh has shading normals
    /// (empty otherwise); zero on a mesh without them, which the interpolation
    /// turns into the geometric normal, as `interaction` does.
    vertex_normals: Vec<[Vec3; 3]>,
    smooth: bool,
}

impl LaneScene {
    /// `None` unless every shape is Lambertian or a mirror, without a bump
    /// map ([`refusal`]).
    pub(crate) fn build(scene: &Scene, light_set: &super::lights::LightSet) -> Option<Self> {
        if refusal(scene).is_some() {
            return None;
        }
        let lights = light_set.lane_lights(scene);
        let other_lights = lights.iter().any(|l| !matches!(l, LaneLight::Area(_)));
        // As a Lambertian or mirror sample's weight is; whether a mirror.
        let bsdf = |m: u32| {
            scene
                .materials
                .get(m as usize)
                .and_then(Material::lane_bsdf)
        };
        let albedo = |m: u32| bsdf(m).map(LaneBsdf::weight);
        let mirror = |m: u32| bsdf(m).is_some_and(LaneBsdf::is_mirror);
        let sphere_albedo = scene
            .spheres
            .iter()
            .map(|s| albedo(s.material))
            .collect::<Option<_>>()?;
        let sphere_mirror: Vec<bool> = scene.spheres.iter().map(|s| mirror(s.material)).collect();
        let mesh_mirror: Vec<bool> = scene.meshes.iter().map(|m| mirror(m.material)).collect();
        let mirrors = mesh_mirror.iter().chain(&sphere_mirror).any(|&m| m);
        // The cosine-weighted sampler is built for a constant sky only: its
        // radiance is the same in every direction.
        let sky_in_frame = scene
            .environment
            .as_ref()
            .filter(|_| light_set.env_sample_in_frame())
            .map(|env| env.eval(Vec3::Z));
        let mut first = Vec::with_capacity(scene.meshes.len());
        let mut triangles = Vec::new();
        let smooth = scene.meshes.iter().any(|m| !m.normals.is_empty());
        let mut vertex_normals = Vec::new();
        for m in &scene.meshes {
            let albedo = albedo(m.material)?;
            first.push(u32::try_from(triangles.len()).ok()?);
            triangles.extend(m.triangles.iter().map(|t| {
                let v = t.map(|i| m.positions[i as usize]);
                LaneTriangle {
                    v,
                    n: triangle_normal(v),
                    albedo,
                }
            }));
            if smooth {
                vertex_normals.extend(
                    m.triangles.iter().map(|t| {
                        t.map(|i| m.normals.get(i as usize).copied().unwrap_or(Vec3::ZERO))
                    }),
                );
            }
        }
        Some(Self {
            first,
            triangles,
            lights,
            sky_in_frame,
            other_lights,
            sphere_albedo,
            mesh_mirror,
            sphere_mirror,
            mirrors,
            avx2: avx2(),
            vertex_normals,
            smooth,
        })
    }

    /// Traces every path of `batch` and leaves in it what [`PathTracer::li`]
    /// would return for each (no gradients); the camera rays' first hits only
    /// with `first_hits` (else `None`, where the film would drop them).
    pub(crate) fn trace(&self, tracer: &PathTracer, batch: &mut LaneBatch, first_hits: bool) {
        let LaneBatch {
            paths,
            live,
            shaded,
            gathered,
            queries: q,
        } = batch;
        let streams = tracer.accel.streams();
        live.clear();
        live.extend(0..paths.len());
        for depth in 1..=tracer.max_depth {
            if streams {
                let n = live.len();
                tracer
                    .accel
                    .intersect_stream(n, |k| &paths[live[k]].ray, &mut q.stream);
            }
            let mut kept = 0;
            for k in 0..live.len() {
                let i = live[k];
                let p = &mut paths[i];
                let hit = if streams {
                    q.stream.hit(tracer.accel, k)
                } else {
                    tracer.accel.intersect(&p.ray)
                };
                if self.intersect(tracer, p, hit, depth, first_hits) {
                    live[kept] = i;
                    kept += 1;
                }
            }
            live.truncate(kept);
            if depth == tracer.max_depth || live.is_empty() {
                break;
            }
            // Slots reused from bounce to bounce (grown, never cleared): the
            // kernel writes each in place.
            let chunks = live.len().div_ceil(LANES);
            if shaded.len() < chunks {
                shaded.resize(chunks, Shaded8::default());
            }
            for (chunk, out) in live.chunks(LANES).zip(shaded.iter_mut()) {
                self.gather(tracer, paths, chunk, depth, gathered);
                self.kernel(gathered, out);
            }
            if streams {
                // The shadow rays of the lanes that have one, in live order.
                q.shadow.clear();
                for k in 0..live.len() {
                    let (s, l) = (&shaded[k / LANES], k % LANES);
                    if casts_shadow_ray(s, l) {
                        q.shadow.push(shadow_ray(s, l));
                    }
                }
                let shadow = &q.shadow;
                tracer
                    .accel
                    .occluded_stream(shadow.len(), |k| &shadow[k], &mut q.stream);
            }
            let mut kept = 0;
            let mut shadow = 0;
            for k in 0..live.len() {
                let i = live[k];
                let (s, l) = (&shaded[k / LANES], k % LANES);
                let occluded = if !streams || !casts_shadow_ray(s, l) {
                    None
                } else {
                    shadow += 1;
                    Some(q.stream.occluded(shadow - 1))
                };
                if self.finish(tracer, &mut paths[i], s, l, occluded, depth, first_hits) {
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
    /// `li` weighs it); `false` when the ray leaves the scene, with the
    /// environment's light.
    fn intersect(
        &self,
        tracer: &PathTracer,
        p: &mut LanePath,
        hit: Option<Hit>,
        depth: u32,
        first_hits: bool,
    ) -> bool {
        p.rays += 1;
        let Some(hit) = hit else {
            p.st.radiance += tracer.escaped(&p.ray, &p.st);
            return false;
        };
        let surface = Surface::of(tracer.scene, &hit);
        // The first hit's AOVs come from the lanes (`finish`), unless no
        // bounce is shaded at all.
        let aovs = first_hits && depth == 1 && tracer.max_depth == 1;
        if surface.emission != Vec3::ZERO || aovs {
            // Rare: the scalar set-up, which gives the same point and normals.
            let si = interaction(tracer.scene, tracer.accel, &p.ray, &hit);
            if aovs {
                p.first_hit = Some(FirstHit::new(
                    tracer.scene,
                    si.frame.n,
                    hit.t,
                    si.material,
                    si.object_id,
                    p.ray.dir,
                ));
            }
            if si.emission != Vec3::ZERO {
                let w = tracer.emitter_weight(&si, p.st.prev_pdf, p.st.prev_p);
                p.st.radiance += p.st.beta * si.emission * w;
            }
        }
        // The triangle's record is read when the lanes are gathered, after
        // the batch's other queries: on a large mesh a cache miss unless its
        // load starts now.
        if let PrimRef::Triangle { mesh, tri } = hit.prim {
            let index = (self.first[mesh as usize] + tri) as usize;
            prefetch(&self.triangles[index]);
            if self.smooth {
                prefetch(&self.vertex_normals[index]);
            }
        }
        p.hit = Some(hit);
        true
    }

    /// Gathers the hits of the paths `chunk` (at most [`LANES`]) and their
    /// random numbers into lanes.
    fn gather(
        &self,
        tracer: &PathTracer,
        paths: &mut [LanePath],
        chunk: &[usize],
        depth: u32,
        g: &mut Gathered,
    ) {
        g.smooth = self.smooth;
        g.spawn_floor = tracer.accel.spawn_floor();
        for (l, &i) in chunk.iter().enumerate() {
            let p = &mut paths[i];
            let u = VertexSamples::draw(&mut p.sampler, depth, tracer.roulette_at(depth));
            let hit = p.hit.expect("a live path has a hit");
            p.u_rr = u.rr;
            // The hit point, computed here only where a light's sample needs it
            // before the kernel (a sphere light's), the kernel's bits.
            let point = match hit.prim {
                PrimRef::Triangle { mesh, tri } => {
                    let index = (self.first[mesh as usize] + tri) as usize;
                    let t = &self.triangles[index];
                    if self.smooth {
                        for (k, n) in self.vertex_normals[index].into_iter().enumerate() {
                            g.vn[k][l] = n;
                        }
                    }
                    g.set_triangle(l, &hit, t);
                    g.mirror[l] = f32::from(u8::from(self.mesh_mirror[mesh as usize]));
                    Point::Triangle(t, hit.bary)
                }
                PrimRef::Sphere(k) => {
                    let s = &tracer.scene.spheres[k as usize];
                    let sp = sphere_point(s.center, s.radius, p.ray.at(hit.t));
                    g.set_sphere(l, &sp, self.sphere_albedo[k as usize]);
                    g.mirror[l] = f32::from(u8::from(self.sphere_mirror[k as usize]));
                    Point::Known(sp.p)
                }
            };
            g.set(l, p, &u);
            let light = tracer.lights.pick(u.pick).map(|k| &self.lights[k]);
            let kind = match (light, self.sky_in_frame) {
                (None, _) => LightKind::None,
                (Some(LaneLight::Area(a)), _) => g.set_area_light(l, a, &u),
                (Some(&LaneLight::Environment { pick }), Some(radiance)) => {
                    g.set_env_in_frame(l, pick, radiance)
                }
                (Some(light @ (LaneLight::Environment { .. } | LaneLight::Sphere)), _) => {
                    // A sky's sample reads no point: the hit point is computed
                    // only for a sphere light's.
                    let at = match light {
                        LaneLight::Sphere => point.at(),
                        _ => Vec3::ZERO,
                    };
                    let ls = tracer
                        .lights
                        .sample_without_frame(tracer.scene, at, u.pick, u.light);
                    g.set_drawn_light(l, ls)
                }
            };
            g.kind[l] = kind as u32 as f32;
        }
        g.other_lights = self.other_lights;
        g.spheres = !self.sphere_albedo.is_empty();
        g.mirrors = self.mirrors;
        // Unused lanes repeat lane 0: finite inputs, results dropped.
        for l in chunk.len()..LANES {
            g.copy_lane(0, l);
        }
    }

    /// The kernel over the gathered lanes, in the widest registers the CPU has.
    fn kernel(&self, g: &Gathered, out: &mut Shaded8) {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is true only where AVX2 was detected on this CPU
            // (`LaneScene::build`).
            return unsafe { kernel::shade8_avx2(g, out) };
        }
        kernel::shade8_wide(g, out)
    }

    /// Direct light through the shadow ray, then the continuation (throughput,
    /// MIS state, Russian roulette), as `li` does; `false` when the path ends.
    /// `s`'s lane `l` is this path's; the first hit is recorded with `first_hits`.
    /// `occluded`: the shadow ray's answer where a stream has traced it.
    #[allow(clippy::too_many_arguments)]
    fn finish(
        &self,
        tracer: &PathTracer,
        p: &mut LanePath,
        s: &Shaded8,
        l: usize,
        occluded: Option<bool>,
        depth: u32,
        first_hits: bool,
    ) -> bool {
        let bit = |m: u32| m & (1 << l) != 0;
        if depth == 1 && first_hits {
            // `li`'s `visible_surface`, with the lanes' shading normal.
            let hit = p.hit.expect("a shaded path has a hit");
            let surface = Surface::of(tracer.scene, &hit);
            p.first_hit = Some(FirstHit::new(
                tracer.scene,
                s.normal[l],
                hit.t,
                surface.material,
                surface.object_id,
                p.ray.dir,
            ));
        }
        if !bit(s.alive) {
            return false;
        }
        if bit(s.direct) {
            p.rays += 1;
            if !occluded.unwrap_or_else(|| tracer.accel.occluded(&shadow_ray(s, l))) {
                p.st.radiance += s.ld[l];
            }
        }
        if !bit(s.next) {
            return false;
        }
        p.st.beta *= s.weight[l];
        p.st.prev_pdf = s.pdf[l];
        p.st.prev_p = s.p[l];
        p.st.prev_n = s.normal[l];
        p.ray = Ray::new(s.next_o[l], s.next_d[l]);
        tracer.survives(&mut p.st.beta, p.u_rr, depth)
    }
}

/// Whether lane `l`'s path traces its shadow ray (`finish`: alive, with direct light).
fn casts_shadow_ray(s: &Shaded8, l: usize) -> bool {
    (s.alive & s.direct) & (1 << l) != 0
}

/// Lane `l`'s shadow ray.
fn shadow_ray(s: &Shaded8, l: usize) -> Ray {
    Ray::segment(s.shadow_o[l], s.shadow_d[l], s.shadow_t[l])
}

/// Why the lanes do not take `scene` (what `li` handles and they do not), or
/// `None` when they do.
pub(crate) fn refusal(scene: &Scene) -> Option<&'static str> {
    let lambert = |m: u32| {
        scene
            .materials
            .get(m as usize)
            .and_then(Material::lane_bsdf)
            .is_some()
    };
    let materials = scene.meshes.iter().map(|m| m.material);
    let bumps = scene.meshes.iter().map(|m| m.bump);
    if !materials
        .chain(scene.spheres.iter().map(|s| s.material))
        .all(lambert)
    {
        Some("a glossy material")
    } else if bumps
        .chain(scene.spheres.iter().map(|s| s.bump))
        .any(|b| b.is_some())
    {
        Some("bump maps")
    } else {
        None
    }
}

/// What a hit's surface is, beside its geometry.
struct Surface {
    material: u32,
    emission: Vec3,
    object_id: u32,
}

impl Surface {
    fn of(scene: &Scene, hit: &Hit) -> Self {
        let (material, emission, object_id) = match hit.prim {
            PrimRef::Triangle { mesh, .. } => {
                let m = &scene.meshes[mesh as usize];
                (m.material, m.emission, m.object_id)
            }
            PrimRef::Sphere(i) => {
                let s = &scene.spheres[i as usize];
                (s.material, s.emission, s.object_id)
            }
        };
        Self {
            material,
            emission,
            object_id,
        }
    }
}

/// A lane's hit point, for a light sample drawn before the kernel: a
/// sphere's is known, a triangle's is computed on demand as the kernel
/// computes it (`triangle_point_with_normal`).
enum Point<'a> {
    Known(Vec3),
    Triangle(&'a LaneTriangle, Vec2),
}

impl Point<'_> {
    fn at(&self) -> Vec3 {
        match *self {
            Point::Known(p) => p,
            Point::Triangle(t, bary) => triangle_point_with_normal(t.v, bary, t.n).p,
        }
    }
}

/// Starts loading every cache line `r` lies on (a hint; nothing on other
/// architectures): its first byte's line and on to its last byte's, for the
/// 60-byte triangle records that straddle two lines more often than not. The
/// traversal's `prefetch_lines` steps from the start alone, for its aligned
/// nodes and blocks; one helper for both (the exact line range, or a
/// prefetch of the last byte added to the traversal's) cost cornell and the
/// bunny 1–1.7 % (benches/README.md, levers).
#[inline(always)]
fn prefetch<T>(r: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let (p, size) = (r as *const T as *const i8, std::mem::size_of::<T>());
        // Points at most 64 bytes apart from the first byte to the last: one
        // on every line.
        let mut at = 0;
        while at + 1 < size {
            // SAFETY: `at` < `size`, inside `*r`; a prefetch never faults.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p.add(at)) };
            at += 64;
        }
        // SAFETY: the last byte of `*r`.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(p.add(size.max(1) - 1)) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = r;
}

/// Whether this CPU runs the kernel in AVX registers.
pub(crate) fn avx2() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
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
    /// Where the tree takes ray streams (`Accel::streams`): the stream's
    /// scratch and each bounce's shadow rays.
    queries: Queries,
}

/// A bounce's rays traced as one stream: the stream, and the shadow rays.
#[derive(Default)]
struct Queries {
    stream: RayStream,
    shadow: Vec<Ray>,
}

impl LaneBatch {
    /// A path from the camera ray `ray`, drawing from `sampler`.
    pub(crate) fn push(&mut self, ray: Ray, sampler: PixelSampler) {
        self.paths.push(LanePath {
            ray,
            sampler,
            st: PathState::camera(ray.origin),
            hit: None,
            first_hit: None,
            rays: 0,
            u_rr: 0.0,
        });
    }

    pub(crate) fn len(&self) -> usize {
        self.paths.len()
    }

    /// Each path's result, in the order they were pushed; the batch is then empty.
    pub(crate) fn results(&mut self) -> impl Iterator<Item = SampleResult> + '_ {
        self.paths.drain(..).map(|p| SampleResult {
            radiance: p.st.radiance,
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
    st: PathState,
    hit: Option<Hit>,
    first_hit: Option<FirstHit>,
    rays: u32,
    /// This vertex's Russian roulette number.
    u_rr: f32,
}

/// What a lane's light sample is, in the kernel's `kind` plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
enum LightKind {
    /// No light picked, or its sample came back empty.
    None = 0,
    Area = 1,
    /// The environment, its direction from the kernel's cosine map.
    EnvInFrame = 2,
    /// A direction with no point (the environment's), its density and
    /// radiance drawn already: an unbounded shadow ray.
    Drawn = 3,
    /// The same toward a drawn point and its normal (a sphere light's): a
    /// shadow segment.
    DrawnPoint = 4,
}

/// The inputs of the kernel: a vector per lane (`Rows`, transposed into
/// lanes by the kernel: a row is one 16-byte copy here), a plane per scalar.
#[derive(Default)]
struct Gathered {
    dir: Rows,
    v: [Rows; 3],
    n: Rows,
    /// The vertices' shading normals, read only when `smooth`.
    vn: [Rows; 3],
    smooth: bool,
    /// The least error bound of a spawned origin ([`Accel::spawn_floor`]).
    spawn_floor: f32,
    /// Whether the scene has spheres: the planes below, a sphere's surface
    /// point where `sphere` is 1, are read only then.
    spheres: bool,
    sphere: [f32; LANES],
    sphere_p: Rows,
    sphere_error: Rows,
    /// Whether the scene has mirrors: `mirror` (1 on a mirror's lanes) is
    /// read only then.
    mirrors: bool,
    mirror: [f32; LANES],
    /// The Lambertian albedo, or the mirror's reflectance.
    albedo: Rows,
    beta: Rows,
    /// Each lane's [`LightKind`].
    kind: [f32; LANES],
    /// An area light: its point's three terms and their weights, its normal,
    /// area and pick probability.
    light: [Rows; 3],
    light_w: Rows,
    light_n: Rows,
    light_area: [f32; LANES],
    light_pick: [f32; LANES],
    /// The picked light's radiance (every kind's).
    light_le: Rows,
    /// Whether some lane may hold a light other than an area light: the
    /// kernel's lanes for those, and the planes below, are read only then.
    other_lights: bool,
    /// The light sample's square, for [`LightKind::EnvInFrame`].
    u_light: [[f32; LANES]; 2],
    /// A drawn sample's direction and density (the pick's included), and
    /// for [`LightKind::DrawnPoint`] its point (its normal in `light_n`).
    drawn_wi: Rows,
    drawn_pdf: [f32; LANES],
    drawn_q: Rows,
    bary: [[f32; LANES]; 2],
    u_dir: [[f32; LANES]; 2],
}

/// One vector per lane.
type Rows = [Vec3; LANES];

impl Gathered {
    /// Lane `l`'s path state and random numbers.
    fn set(&mut self, l: usize, p: &LanePath, u: &VertexSamples) {
        self.dir[l] = p.ray.dir;
        self.beta[l] = p.st.beta;
        self.u_dir[0][l] = u.dir.x;
        self.u_dir[1][l] = u.dir.y;
        self.u_light[0][l] = u.light.x;
        self.u_light[1][l] = u.light.y;
    }

    /// Lane `l`'s triangle hit: the kernel computes its point.
    fn set_triangle(&mut self, l: usize, hit: &Hit, t: &LaneTriangle) {
        self.n[l] = t.n;
        self.albedo[l] = t.albedo;
        for k in 0..3 {
            self.v[k][l] = t.v[k];
        }
        self.bary[0][l] = hit.bary.x;
        self.bary[1][l] = hit.bary.y;
        self.sphere[l] = 0.0;
    }

    /// Lane `l`'s sphere hit, its surface point `sp` computed already
    /// (`sphere_point`, as `interaction` does).
    fn set_sphere(&mut self, l: usize, sp: &SurfacePoint, albedo: Vec3) {
        self.n[l] = sp.n_geo;
        self.albedo[l] = albedo;
        self.sphere_p[l] = sp.p;
        self.sphere_error[l] = sp.p_error;
        self.sphere[l] = 1.0;
        self.bary[0][l] = 0.0;
        self.bary[1][l] = 0.0;
        // Zero vertex normals: the kernel's interpolation falls back to the
        // geometric normal, a sphere's shading normal.
        for vn in &mut self.vn {
            vn[l] = Vec3::ZERO;
        }
    }

    /// Lane `l`'s picked area light `a`.
    fn set_area_light(&mut self, l: usize, a: &AreaLight, u: &VertexSamples) -> LightKind {
        // `LightSet::sample`'s point: corner + u·edge_u + v·edge_v, or the
        // triangle's vertices weighted by a uniform barycentric sample.
        self.light_w[l] = if a.rect {
            Vec3::new(1.0, u.light.x, u.light.y)
        } else {
            let b = warp::square_to_uniform_triangle(u.light);
            Vec3::new(1.0 - b.x - b.y, b.x, b.y)
        };
        self.light[0][l] = a.a;
        self.light[1][l] = a.b;
        self.light[2][l] = a.c;
        self.light_n[l] = a.n;
        self.light_le[l] = a.emission;
        self.light_area[l] = a.area;
        self.light_pick[l] = a.pick;
        LightKind::Area
    }

    /// Lane `l`'s constant sky of `radiance`, picked with probability
    /// `pick`: the kernel maps its direction.
    fn set_env_in_frame(&mut self, l: usize, pick: f32, radiance: Vec3) -> LightKind {
        self.light_pick[l] = pick;
        self.light_le[l] = radiance;
        LightKind::EnvInFrame
    }

    /// Lane `l`'s light sample drawn before the kernel.
    fn set_drawn_light(&mut self, l: usize, ls: Option<LightSample>) -> LightKind {
        let Some(ls) = ls else {
            return LightKind::None;
        };
        self.drawn_wi[l] = ls.wi;
        self.drawn_pdf[l] = ls.pdf;
        self.light_le[l] = ls.radiance;
        match ls.point {
            None => LightKind::Drawn,
            Some((q, nq)) => {
                self.drawn_q[l] = q;
                self.light_n[l] = nq;
                LightKind::DrawnPoint
            }
        }
    }

    fn copy_lane(&mut self, from: usize, to: usize) {
        for r in [
            &mut self.dir,
            &mut self.n,
            &mut self.sphere_p,
            &mut self.sphere_error,
            &mut self.albedo,
            &mut self.beta,
            &mut self.light_w,
            &mut self.light_n,
            &mut self.light_le,
            &mut self.drawn_wi,
            &mut self.drawn_q,
        ]
        .into_iter()
        .chain(&mut self.v)
        .chain(&mut self.vn)
        .chain(&mut self.light)
        {
            r[to] = r[from];
        }
        for p in [
            &mut self.kind,
            &mut self.sphere,
            &mut self.mirror,
            &mut self.light_area,
            &mut self.light_pick,
            &mut self.drawn_pdf,
        ]
        .into_iter()
        .chain(&mut self.bary)
        .chain(&mut self.u_dir)
        .chain(&mut self.u_light)
        {
            p[to] = p[from];
        }
    }
}
