//! Shadow fields (Zhou et al. 2005; deformable extension): per-entity occlusion and source radiance fields in order-4 spherical harmonics, combined per receiver point.
//!
//! scene → [`precompute`](fn@precompute) (one OOF per occluder, SRF + OOF per light, self-occlusion
//! at mesh vertices; rays traced with our BVH, in parallel) → [`Fields`] →
//! [`Fields::combiner`] for a frame's poses → [`shade_image`] (first hit per pixel
//! sample) or [`shade_vertices`]. Glossy receivers (BlinnPhong, CookTorrance) add
//! their lobe, seen from the camera ([`glossy`]). Rigid fields are rotated in SH; deforming entities
//! (a procedural `deform` or an `obj_sequence`: both are just a frame's posed
//! geometry here) are rebuilt each frame from their base-sphere visibility ([`deform`]).

// Index loops mirror the coefficient subscripts of the formulas.
#![allow(clippy::needless_range_loop)]

pub mod cache;
pub mod combine;
pub mod deform;
pub mod field;
pub mod glossy;
pub mod peak;
pub mod precompute;

use crate::accel::{Accel, PrimRef};
use crate::math::sh::{self, Rotation, ShF, COEFFS};
use crate::math::{Vec2, Vec3};
use crate::scene::{Environment, Scene};
use combine::{Combiner, Placed};
use glam::Mat3;
use precompute::{Entity, EntityFields, EntityKind, Ticker};
use rayon::prelude::*;

/// Precomputation settings; every field enters the cache key.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Angular samples of each field sphere (θ including both poles × φ): 12 × 20
    /// as in the paper.
    pub n_theta: usize,
    pub n_phi: usize,
    /// Concentric spheres, geometric from `r_min` to `r_max` bounding radii.
    pub n_radii: usize,
    pub r_min: f32,
    pub r_max: f32,
    /// Rays per field sample: `rays²` stratified directions in the entity's cone.
    pub rays: usize,
    /// Rays per vertex for self-occlusion: `self_rays²` over the hemisphere.
    pub self_rays: usize,
    /// Rays per side of a pixel on an edge (`pixel_samples²` first hits, box
    /// filter); elsewhere one ray through the pixel's centre ([`shade_image`]).
    pub pixel_samples: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            n_theta: 12,
            n_phi: 20,
            n_radii: 16,
            r_min: 0.25,
            r_max: 8.0,
            rays: 32,
            self_rays: 16,
            pixel_samples: 4,
        }
    }
}

impl Settings {
    /// The text of every setting, for the cache key.
    pub fn key(&self) -> String {
        format!("{self:?}")
    }
}

/// The precomputed fields of a scene, rest pose.
#[derive(Clone, Debug)]
pub struct Fields {
    pub entities: Vec<Entity>,
    pub fields: Vec<EntityFields>,
}

/// Precomputes every entity's fields (in parallel); `progress(done, total)`.
pub fn precompute(
    scene: &Scene,
    settings: &Settings,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Fields {
    let entities = precompute::entities(scene);
    let total = entities
        .iter()
        .map(|e| precompute::work_units(scene, e, settings))
        .sum();
    let ticker = Ticker::new(total, progress);
    let tick = || ticker.tick();
    let fields = entities
        .iter()
        .map(|e| precompute::compute_fields(scene, e, settings, &tick))
        .collect();
    Fields { entities, fields }
}

/// Whether the method models `scene` (what `compare` asks before adding the
/// preview as a row): diffuse or glossy surfaces (no mirror: a delta lobe is
/// neither in an order-4 transfer nor at a light's few directions), emitters
/// that are spheres or rectangles (the light entities it integrates), and some
/// light or an environment. Returns why not.
pub fn check_scene(scene: &Scene) -> Result<(), String> {
    check_shapes(scene)?;
    if scene.emitter_count() == 0 && scene.environment.is_none() {
        return Err("nothing lights the scene (no light, no environment)".into());
    }
    Ok(())
}

/// What `preview shadow-field` refuses: a shape the method cannot shade (a
/// mirror) or an emitter that is not a light entity. (An unlit scene it renders
/// black, scored against a black reference.)
pub fn check_shapes(scene: &Scene) -> Result<(), String> {
    let shaded = |m: u32, name: &str| match scene.materials.get(m as usize) {
        Some(m) if m.preview_parts().is_ok() => Ok(()),
        Some(_) => Err(format!(
            "shape `{name}` is a mirror (a delta lobe: shadow fields shade smooth lobes only)"
        )),
        None => Err(format!("shape `{name}` has no material")),
    };
    for m in &scene.meshes {
        if m.emission != Vec3::ZERO {
            if m.rect.is_none() {
                return Err(format!(
                    "emitter `{}` is neither a sphere nor a rectangle",
                    m.name
                ));
            }
        } else {
            shaded(m.material, &m.name)?;
        }
    }
    for s in scene.spheres.iter().filter(|s| s.emission == Vec3::ZERO) {
        shaded(s.material, &s.name)?;
    }
    Ok(())
}

/// A rigid pose of an entity relative to its rest pose: x ↦ c + t + R (x − c)
/// about the rest bounding centre c.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub rotation: Mat3,
    pub translation: Vec3,
}

impl Default for Pose {
    fn default() -> Self {
        Self {
            rotation: Mat3::IDENTITY,
            translation: Vec3::ZERO,
        }
    }
}

/// The order-4 RGB projection of the environment (zero without one).
pub fn environment_sh(env: Option<&Environment>) -> [ShF; 3] {
    let Some(env) = env else {
        return [[0.0; COEFFS]; 3];
    };
    if let Environment::Constant { radiance } = env {
        let one = sh::one();
        return std::array::from_fn(|c| one.map(|x| (x * f64::from(radiance[c])) as f32));
    }
    let (rule, values) = environment_samples(env);
    project_rgb(&rule, &values)
}

/// The environment's radiance on the projection's quadrature rule.
pub(crate) fn environment_samples(env: &Environment) -> (Vec<(glam::DVec3, f64)>, Vec<Vec3>) {
    let rule = sh::sphere_quadrature(96, 192);
    let values = rule.iter().map(|(d, _)| env.eval(d.as_vec3a())).collect();
    (rule, values)
}

/// The order-4 RGB projection of radiance `values` sampled on `rule`.
pub(crate) fn project_rgb(rule: &[(glam::DVec3, f64)], values: &[Vec3]) -> [ShF; 3] {
    let mut out = [[0.0f64; COEFFS]; 3];
    for ((d, w), v) in rule.iter().zip(values) {
        let y = sh::eval(*d);
        for c in 0..3 {
            for k in 0..COEFFS {
                out[c][k] += w * f64::from(v[c]) * y[k];
            }
        }
    }
    out.map(|c| c.map(|x| x as f32))
}

/// Lat-long image of the lighting the method can represent, for the
/// low-frequency reference: the order-4 projection (negative lobes clamped to
/// zero) plus the split-off peak of `env`, if any.
pub fn environment_lowfreq(
    light: &peak::EnvironmentLight,
    env: Option<&Environment>,
    width: usize,
    height: usize,
) -> Environment {
    let peak = light.peak.as_ref().zip(env);
    lowfreq_image(width, height, |d| {
        let low = sh_radiance(&light.sh, d);
        peak.map_or(low, |(pk, env)| low + pk.part(d, env.eval(d)))
    })
}

/// Lat-long image of an order-4 projection (negative lobes clamped to zero).
pub fn lowfreq_sh(env_sh: &[ShF; 3], width: usize, height: usize) -> Environment {
    lowfreq_image(width, height, |d| sh_radiance(env_sh, d))
}

/// RGB radiance of an order-4 projection in direction `d`, negative lobes clamped.
fn sh_radiance(env_sh: &[ShF; 3], d: Vec3) -> Vec3 {
    let y = sh::eval_f32(d);
    Vec3::new(
        sh::dot_f32(&env_sh[0], &y).max(0.0),
        sh::dot_f32(&env_sh[1], &y).max(0.0),
        sh::dot_f32(&env_sh[2], &y).max(0.0),
    )
}

/// A `width × height` lat-long image of `radiance` at its texels' directions
/// (rows from pole to pole).
fn lowfreq_image(width: usize, height: usize, radiance: impl Fn(Vec3) -> Vec3) -> Environment {
    let mut texels = Vec::with_capacity(width * height);
    for j in 0..height {
        for i in 0..width {
            let uv = Vec2::new(
                (i as f32 + 0.5) / width as f32,
                j as f32 / (height - 1) as f32,
            );
            texels.push(radiance(crate::scene::environment::latlong_to_direction(
                uv,
            )));
        }
    }
    Environment::Image {
        width,
        height,
        texels,
        scale: 1.0,
    }
}

impl Fields {
    /// The combiner for one frame: each entity at `poses[i]` (rest when missing),
    /// its fields' coefficients rotated once (not per receiver), and per-mesh
    /// self-visibility rotated likewise.
    pub fn combiner(
        &self,
        poses: &[Pose],
        env: peak::EnvironmentLight,
    ) -> (Combiner, Vec<Option<Vec<ShF>>>) {
        let mut placed = Vec::with_capacity(self.entities.len());
        let mut mesh_self: Vec<Option<Vec<ShF>>> = Vec::new();
        for (i, (e, f)) in self.entities.iter().zip(&self.fields).enumerate() {
            let pose = poses.get(i).copied().unwrap_or_default();
            let identity = pose.rotation == Mat3::IDENTITY;
            let rot = Rotation::new(pose.rotation.as_dmat3());
            let turn = |fd: &field::Field| {
                if identity {
                    fd.clone()
                } else {
                    fd.rotated(&rot)
                }
            };
            let kind = match e.kind {
                EntityKind::Quad(r) => EntityKind::Quad(crate::scene::Rect {
                    corner: e.center + pose.translation + pose.rotation * (r.corner - e.center),
                    edge_u: pose.rotation * r.edge_u,
                    edge_v: pose.rotation * r.edge_v,
                }),
                k => k,
            };
            placed.push(Placed {
                kind,
                center: e.center + pose.translation,
                radius: e.radius,
                to_rest: pose.rotation.transpose(),
                occlusion: f.occlusion.as_ref().map(turn),
                radiance: f
                    .radiance
                    .as_ref()
                    .map(|r| [turn(&r[0]), turn(&r[1]), turn(&r[2])]),
                self_from_field: e.deforming,
                sphere_light: e.sphere_light,
                visibility: f.visibility.clone(),
            });
            for (k, &m) in e.meshes.iter().enumerate() {
                if mesh_self.len() <= m {
                    mesh_self.resize(m + 1, None);
                }
                mesh_self[m] = f.self_occlusion.get(k).map(|occ| {
                    occ.iter()
                        .map(|o| {
                            let o = if identity { *o } else { rot.apply_f32(o) };
                            let mut v = o.map(|x| -x);
                            v[0] += sh::one()[0] as f32;
                            v
                        })
                        .collect()
                });
            }
        }
        (Combiner::new(placed, env), mesh_self)
    }
}

/// A shaded image and how many receiver points it took.
#[derive(Clone, Debug)]
pub struct Shaded {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<Vec3>,
    /// Receiver points shaded (first hits on a non-emitting surface).
    pub points: usize,
    /// Sum over points of the entities combined there (the cost unit).
    pub point_entities: usize,
    /// Per pixel: whether a ray saw an emitter's face directly.
    pub sees_emitter: Vec<bool>,
}

impl Shaded {
    /// The pixels the figures are scored on: those that neither see an emitter
    /// nor touch one that does. There the camera rays of the preview and of the
    /// path tracer are alike and only the light's tiny, bright edge separates
    /// them, which a few pixels of a light thousands of times brighter than
    /// what it lights would turn into the whole RMSE.
    pub fn scored(&self) -> Vec<bool> {
        let (w, h) = (self.width, self.height);
        (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                !(y.saturating_sub(1)..(y + 2).min(h)).any(|j| {
                    (x.saturating_sub(1)..(x + 2).min(w)).any(|k| self.sees_emitter[j * w + k])
                })
            })
            .collect()
    }
}

/// Everything a receiver needs about the scene's geometry.
pub struct Receivers<'a> {
    pub scene: &'a Scene,
    pub accel: &'a Accel,
    /// Entity index of each object id (index = object id).
    pub entity_of_object: Vec<Option<usize>>,
    /// Per scene mesh: visibility SH at each vertex (self-shadowing), if any.
    pub mesh_self: &'a [Option<Vec<ShF>>],
    /// Per scene material: its glossy lobe's transfer table, if it has one.
    pub glossy: &'a [Option<glossy::GlossyLobe>],
}

/// What every frame shades with and no pose changes, built once per run: the
/// environment (its SH and its sun) and each material's glossy transfer table
/// (milliseconds per glossy material: precomputation, not frame time).
#[derive(Clone, Debug)]
pub struct Shading {
    pub env: peak::EnvironmentLight,
    pub glossy: Vec<Option<glossy::GlossyLobe>>,
}

impl Shading {
    pub fn new(scene: &Scene) -> Self {
        Self {
            env: peak::EnvironmentLight::new(scene.environment.as_ref()),
            glossy: scene
                .materials
                .iter()
                .map(glossy::GlossyLobe::new)
                .collect(),
        }
    }
}

impl<'a> Receivers<'a> {
    pub fn new(
        scene: &'a Scene,
        accel: &'a Accel,
        fields: &Fields,
        mesh_self: &'a [Option<Vec<ShF>>],
        glossy: &'a [Option<glossy::GlossyLobe>],
    ) -> Self {
        let max_id = fields
            .entities
            .iter()
            .map(|e| e.object_id)
            .max()
            .unwrap_or(0);
        let mut entity_of_object = vec![None; max_id as usize + 1];
        for (i, e) in fields.entities.iter().enumerate() {
            entity_of_object[e.object_id as usize] = Some(i);
        }
        Self {
            scene,
            accel,
            entity_of_object,
            mesh_self,
            glossy,
        }
    }

    /// Radiance along one camera ray: emission seen directly, or the shadow-field
    /// estimate of the direct light reflected at the first hit (its glossy lobe
    /// towards the camera included), or the environment.
    /// The bool says whether a receiver was shaded; the usize how many entities.
    pub fn radiance(&self, combiner: &Combiner, ray: &crate::math::Ray) -> (Vec3, bool, usize) {
        match self.first_hit(ray) {
            FirstHit::Seen(v, _) => (v, false, 0),
            FirstHit::Receiver(r) => {
                let (v, n) = self.shade(combiner, &r);
                (v, true, n)
            }
        }
    }

    /// What a camera ray sees first: radiance that needs no shading, or a
    /// receiver point.
    pub fn first_hit(&self, ray: &crate::math::Ray) -> FirstHit {
        let Some(hit) = self.accel.intersect(ray) else {
            let env = self
                .scene
                .environment
                .as_ref()
                .map_or(Vec3::ZERO, |e| e.eval(ray.dir));
            return FirstHit::Seen(env, MISS);
        };
        let Some(sp) = self.accel.surface_point(ray, &hit) else {
            return FirstHit::Seen(Vec3::ZERO, MISS);
        };
        let front = sp.n_geo.dot(ray.dir) < 0.0;
        let (object_id, material, emission, shading_n, self_vis) = match hit.prim {
            PrimRef::Triangle { mesh, tri } => {
                let m = &self.scene.meshes[mesh as usize];
                let t = m.triangles[tri as usize];
                let b = [1.0 - hit.bary.x - hit.bary.y, hit.bary.x, hit.bary.y];
                let n = if m.normals.len() == m.positions.len() {
                    (0..3)
                        .map(|k| m.normals[t[k] as usize] * b[k])
                        .sum::<Vec3>()
                        .normalize_or_zero()
                } else {
                    sp.n_geo
                };
                let sv = self
                    .mesh_self
                    .get(mesh as usize)
                    .and_then(|s| s.as_ref())
                    .map(|s| {
                        let mut v = [0.0f32; COEFFS];
                        for k in 0..3 {
                            let sk = &s[t[k] as usize];
                            for c in 0..COEFFS {
                                v[c] += b[k] * sk[c];
                            }
                        }
                        v
                    });
                (
                    m.object_id,
                    m.material,
                    if front { m.emission } else { Vec3::ZERO },
                    n,
                    sv,
                )
            }
            PrimRef::Sphere(s) => {
                let s = &self.scene.spheres[s as usize];
                (
                    s.object_id,
                    s.material,
                    if front { s.emission } else { Vec3::ZERO },
                    sp.n_geo,
                    None,
                )
            }
        };
        // Two-sided shading: the normal faces the viewer; self-visibility was
        // computed for the front side only.
        let back = shading_n.dot(ray.dir) > 0.0;
        let (n, self_vis) = if back {
            (-shading_n, None)
        } else {
            (shading_n, self_vis)
        };
        let albedo = self.scene.materials[material as usize].diffuse_albedo();
        let glossy = self
            .glossy
            .get(material as usize)
            .is_some_and(|g| g.is_some());
        if (albedo == Vec3::ZERO && !glossy) || n == Vec3::ZERO {
            return FirstHit::Seen(emission, object_id);
        }
        FirstHit::Receiver(Receiver {
            key: object_id.wrapping_mul(2) | u32::from(back),
            p: sp.p,
            n,
            wo: -ray.dir,
            self_vis,
            material,
            albedo,
            emission,
            own: self
                .entity_of_object
                .get(object_id as usize)
                .copied()
                .flatten(),
        })
    }

    /// The receiver's reflected radiance (plus its own emission) and the
    /// number of entities combined.
    pub fn shade(&self, combiner: &Combiner, r: &Receiver) -> (Vec3, usize) {
        let glossy = self
            .glossy
            .get(r.material as usize)
            .and_then(|g| g.as_ref())
            .and_then(|g| g.receiver(r.n, r.wo));
        let s = combiner.shade_parts(r.p, r.n, r.own, r.self_vis.as_ref(), glossy.as_ref());
        let mut value = r.emission + r.albedo * s.diffuse.max(Vec3::ZERO);
        if glossy.is_some() {
            value += s.glossy.max(Vec3::ZERO);
        }
        (crate::math::finite_or_zero(value), s.count)
    }
}

/// The id [`FirstHit::Seen`] gives a ray that hit nothing.
pub const MISS: u32 = u32::MAX;

/// [`Receivers::first_hit`]'s answer.
#[derive(Clone, Copy, Debug)]
pub enum FirstHit {
    /// The environment ([`MISS`]), or the object id of an emitter's face or a
    /// black surface: radiance as seen.
    Seen(Vec3, u32),
    Receiver(Receiver),
}

/// A first hit to shade.
#[derive(Clone, Copy, Debug)]
pub struct Receiver {
    /// Object id and side (two-sided shading): hits of one pixel are shaded
    /// together only within one key.
    pub key: u32,
    pub p: Vec3,
    /// Shading normal, facing the viewer.
    pub n: Vec3,
    /// Towards the viewer (a glossy lobe's ω_o).
    pub wo: Vec3,
    /// Self-visibility SH, interpolated from the mesh's vertices.
    pub self_vis: Option<ShF>,
    pub material: u32,
    pub albedo: Vec3,
    pub emission: Vec3,
    /// The receiver's own entity (its field is skipped in the combination).
    pub own: Option<usize>,
}

/// Hits of one pixel whose normals are within this cosine (about 18°) of the
/// group's first are shaded once, at their mean point: a crease splits them.
const GROUP_COS: f32 = 0.95;

/// The receivers of one pixel that are shaded together: one object, one side,
/// one facet (normals within [`GROUP_COS`]); their sums, for the mean point.
#[derive(Clone, Copy, Debug)]
struct Group {
    first: Receiver,
    p: Vec3,
    n: Vec3,
    wo: Vec3,
    self_vis: Option<ShF>,
    hits: u32,
}

impl Group {
    fn new(r: Receiver) -> Self {
        Self {
            first: r,
            p: r.p,
            n: r.n,
            wo: r.wo,
            self_vis: r.self_vis,
            hits: 1,
        }
    }

    fn takes(&self, r: &Receiver) -> bool {
        self.first.key == r.key && self.first.n.dot(r.n) >= GROUP_COS
    }

    fn add(&mut self, r: &Receiver) {
        self.p += r.p;
        self.n += r.n;
        self.wo += r.wo;
        if let (Some(a), Some(b)) = (self.self_vis.as_mut(), r.self_vis.as_ref()) {
            for (a, b) in a.iter_mut().zip(b) {
                *a += b;
            }
        }
        self.hits += 1;
    }

    /// The receiver at the group's mean point, normal and self-visibility.
    fn mean(&self) -> Receiver {
        let k = self.hits as f32;
        let n = self.n.normalize_or_zero();
        let wo = self.wo.normalize_or_zero();
        Receiver {
            p: self.p / k,
            n: if n == Vec3::ZERO { self.first.n } else { n },
            wo: if wo == Vec3::ZERO { self.first.wo } else { wo },
            self_vis: self.self_vis.map(|v| v.map(|x| x / k)),
            ..self.first
        }
    }
}

/// An edge pixel's hits: the radiance seen without shading, and the facets.
#[derive(Default)]
struct PixelHits {
    seen: Vec3,
    groups: Vec<Group>,
    rays: u32,
    emitter: bool,
    /// Shade every hit on its own (the light changes across the pixel).
    each: bool,
}

impl PixelHits {
    fn add(&mut self, hit: FirstHit) {
        self.rays += 1;
        match hit {
            FirstHit::Seen(v, id) => {
                self.seen += v;
                self.emitter |= sees_emitter(v, id);
            }
            FirstHit::Receiver(r) => {
                self.emitter |= r.emission != Vec3::ZERO;
                match self.groups.iter_mut().find(|g| !self.each && g.takes(&r)) {
                    Some(g) => g.add(&r),
                    None => self.groups.push(Group::new(r)),
                }
            }
        }
    }
}

/// Whether an unshaded ray's radiance `v` came from an emitter (not the sky).
fn sees_emitter(v: Vec3, id: u32) -> bool {
    id != MISS && v != Vec3::ZERO
}

/// Whether two first hits are the same thing to shade: the same unshaded
/// object (or both the environment), or the same facet of a receiver.
fn same_facet(a: &FirstHit, b: &FirstHit) -> bool {
    match (a, b) {
        (FirstHit::Seen(_, i), FirstHit::Seen(_, j)) => i == j,
        (FirstHit::Receiver(r), FirstHit::Receiver(q)) => Group::new(*r).takes(q),
        _ => false,
    }
}

/// The pixels around each emitter that may be narrower than a few pixels: the
/// centre rays can miss a light between them, and the edge pixels then lose
/// all of its radiance (thousands of times what it lights); they are covered
/// by the edge pixels' grid instead. From each emitter's bounding sphere,
/// projected, with a pixel and a half of margin.
fn small_light_pixels(scene: &Scene, lights: &[(Vec3, f32)]) -> Vec<bool> {
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let mut out = vec![false; w * h];
    // Pixels per unit of image plane at unit depth.
    let scale = 0.5 * h as f32 / cam.frustum_slopes().y;
    for &(c, r) in lights {
        let depth = cam.view_coordinates(c).z as f32 - r;
        let Some(at) = cam.project(c) else {
            continue;
        };
        if depth.is_nan() || depth <= 0.0 {
            continue;
        }
        let rad = r / depth * scale + 1.5;
        if rad > 4.0 {
            // Wide enough for the centre rays to find it.
            continue;
        }
        let (x0, x1) = ((at.x - rad).floor(), (at.x + rad).ceil());
        let (y0, y1) = ((at.y - rad).floor(), (at.y + rad).ceil());
        for y in (y0.max(0.0) as usize)..(y1.clamp(0.0, h as f32) as usize) {
            for x in (x0.max(0.0) as usize)..(x1.clamp(0.0, w as f32) as usize) {
                out[y * w + x] = true;
            }
        }
    }
    out
}

/// Every emitter's bounding sphere.
fn emitter_spheres(scene: &Scene) -> Vec<(Vec3, f32)> {
    let spheres = scene
        .spheres
        .iter()
        .filter(|s| s.emission != Vec3::ZERO)
        .map(|s| (s.center, s.radius));
    let meshes = scene
        .meshes
        .iter()
        .filter(|m| m.emission != Vec3::ZERO)
        .filter_map(|m| precompute::bounding_sphere(std::iter::once(m), std::iter::empty()));
    spheres.chain(meshes).collect()
}

/// A pixel is shaded at every one of its rays instead of once where its
/// footprint s is more than this fraction of its distance d to a light: there
/// the centre's value of 1/d² misses the pixel's mean by about (s/d)²/4 (the
/// linear change averages out), 2 % at this fraction ([`near_a_light`]).
const STEEP: f32 = 0.3;

/// Whether some light is within 1/[`STEEP`] footprints of the point `r` the
/// pixel's centre ray hit: the floor beside a light a few centimetres above
/// it, where the centre's value is not the pixel's mean.
fn near_a_light(r: &Receiver, cam: &crate::scene::Camera, lights: &[(Vec3, f32)]) -> bool {
    let pixel = 2.0 * cam.frustum_slopes().y / cam.height as f32;
    let footprint = (r.p - cam.from).length() * pixel / r.n.dot(r.wo).abs().max(0.05);
    lights
        .iter()
        .any(|&(c, rad)| footprint > STEEP * ((c - r.p).length() - rad).max(1e-6))
}

/// Shades every pixel (box filter) as MSAA does, because the combination, not
/// the ray, is the cost, and the light mostly varies little within a pixel: one
/// camera ray through each pixel's centre; where it sees the same facet as
/// its eight neighbours' (not a silhouette, a crease or a light's edge) it is
/// shaded once; elsewhere the pixel is covered by `pixel_samples²` stratified
/// rays and shaded once per facet they hit, at the facet's mean point, or at
/// every hit where a light's 1/d² is steep across the pixel (`near_a_light`).
/// Rows in parallel; deterministic whatever the thread count.
pub fn shade_image(receivers: &Receivers, combiner: &Combiner, pixel_samples: usize) -> Shaded {
    let cam = &receivers.scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let k = pixel_samples.max(1);
    let centres: Vec<FirstHit> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let p = Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            receivers.first_hit(&cam.generate_ray(p))
        })
        .collect();
    let lights = emitter_spheres(receivers.scene);
    let small_lights = small_light_pixels(receivers.scene, &lights);
    let near = |x: usize, y: usize| matches!(&centres[y * w + x], FirstHit::Receiver(r) if near_a_light(r, cam, &lights));
    let edge = |x: usize, y: usize| {
        if small_lights[y * w + x] {
            return true;
        }
        let c = &centres[y * w + x];
        (y.saturating_sub(1)..(y + 2).min(h)).any(|j| {
            (x.saturating_sub(1)..(x + 2).min(w)).any(|i| !same_facet(c, &centres[j * w + i]))
        })
    };
    type Row = (Vec<Vec3>, Vec<bool>, usize, usize);
    let rows: Vec<Row> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut row = Vec::with_capacity(w);
            let mut emitters = Vec::with_capacity(w);
            let (mut points, mut pe) = (0, 0);
            let mut hits = PixelHits::default();
            for x in 0..w {
                let each = k > 1 && near(x, y);
                if k == 1 || !(each || edge(x, y)) {
                    let (v, emitter) = match &centres[y * w + x] {
                        FirstHit::Seen(v, id) => (*v, sees_emitter(*v, *id)),
                        FirstHit::Receiver(r) => {
                            let (v, n) = receivers.shade(combiner, r);
                            points += 1;
                            pe += n;
                            (v, r.emission != Vec3::ZERO)
                        }
                    };
                    row.push(v);
                    emitters.push(emitter);
                    continue;
                }
                hits.seen = Vec3::ZERO;
                hits.groups.clear();
                hits.rays = 0;
                hits.emitter = false;
                hits.each = each;
                for a in 0..k {
                    for b in 0..k {
                        let p = Vec2::new(
                            x as f32 + (a as f32 + 0.5) / k as f32,
                            y as f32 + (b as f32 + 0.5) / k as f32,
                        );
                        hits.add(receivers.first_hit(&cam.generate_ray(p)));
                    }
                }
                let mut acc = hits.seen;
                for g in &hits.groups {
                    let (v, n) = receivers.shade(combiner, &g.mean());
                    acc += v * g.hits as f32;
                    points += 1;
                    pe += n;
                }
                row.push(acc / hits.rays as f32);
                emitters.push(hits.emitter);
            }
            (row, emitters, points, pe)
        })
        .collect();
    let mut out = Shaded {
        width: w,
        height: h,
        rgb: Vec::with_capacity(w * h),
        points: 0,
        point_entities: 0,
        sees_emitter: Vec::with_capacity(w * h),
    };
    for (row, emitters, p, pe) in rows {
        out.rgb.extend(row);
        out.sees_emitter.extend(emitters);
        out.points += p;
        out.point_entities += pe;
    }
    out
}

/// Shades every vertex of a mesh (the paper's per-vertex mode): reflected radiance
/// towards the vertex normal's side, self-visibility included. Diffuse part only
/// (kd): a vertex colour has no view direction, which a glossy lobe needs.
pub fn shade_vertices(receivers: &Receivers, combiner: &Combiner, mesh: usize) -> Vec<Vec3> {
    let scene = receivers.scene;
    let m = &scene.meshes[mesh];
    let normals = precompute::vertex_normals(m);
    let own = receivers
        .entity_of_object
        .get(m.object_id as usize)
        .copied()
        .flatten();
    let albedo = scene.materials[m.material as usize].diffuse_albedo();
    let self_vis = receivers.mesh_self.get(mesh).and_then(|s| s.as_ref());
    (0..m.positions.len())
        .into_par_iter()
        .map(|v| {
            if normals[v] == Vec3::ZERO {
                return Vec3::ZERO;
            }
            let sv = self_vis.map(|s| &s[v]);
            let (e, _) = combiner.shade(m.positions[v], normals[v], own, sv);
            crate::math::finite_or_zero(albedo * e.max(Vec3::ZERO))
        })
        .collect()
}
