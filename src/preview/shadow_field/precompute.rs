//! Scene shapes → entities, and their precomputed fields: object occlusion fields
//! (OOFs), source radiance fields (SRFs) and per-vertex self-occlusion, each sample
//! a set of rays traced against the entity alone with our BVH and projected to SH.
//!
//! Each sample traces only the cone the entity's bounding sphere subtends (outside
//! the sphere nothing of the entity can be seen elsewhere): the paper's
//! "hemisphere oriented towards the centre", tightened, so that a small light far
//! away is not missed by a coarse map. What is stored is the *occlusion*
//! O = 1 − V, which is zero outside that cone and vanishes far away.

use super::field::{cone_cos, cone_frame, ConeMap, Field, Grid};
use super::Settings;
use crate::accel::{Accel, PrimRef};
use crate::math::sh::{self, ShF, COEFFS};
use crate::math::{cross, warp, Frame, Ray, Vec2, Vec3};
use crate::scene::{Mesh, Rect, Scene, Sphere};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// What an entity does in the combination.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EntityKind {
    /// A non-emitting object: an OOF (and self-occlusion at its mesh vertices).
    Occluder,
    /// An emitter: an SRF, plus an OOF for what it hides behind it.
    Light,
    /// A single non-emitting quad (a floor, a wall): its occlusion is
    /// integrated over its exact spherical rectangle at each receiver
    /// (`combine::quad_visibility`) — a field on spheres around a floor's
    /// bounding sphere would be far too coarse, and a half-space hides the sky
    /// above a wall of finite height (issue 57's generated scenes).
    Quad(Rect),
}

/// One scene-file shape (all meshes and spheres of one object id).
#[derive(Clone, Debug)]
pub struct Entity {
    pub object_id: u32,
    pub name: String,
    pub meshes: Vec<usize>,
    pub spheres: Vec<usize>,
    pub kind: EntityKind,
    /// Bounding sphere at rest (for a deforming entity: in the current frame).
    pub center: Vec3,
    pub radius: f32,
    /// Rebuilt each frame from its base-sphere visibility; it then shadows itself
    /// through its own field (k > 1 inside the bounding sphere) instead of
    /// per-vertex self-occlusion.
    pub deforming: bool,
    /// The radiance of an entity that is one emitting sphere and nothing else:
    /// its light is integrated over its exact cap, not through its SH field.
    pub sphere_light: Option<Vec3>,
}

/// Groups the scene's meshes and spheres by object id, in id order.
pub fn entities(scene: &Scene) -> Vec<Entity> {
    let mut ids: Vec<u32> = scene
        .meshes
        .iter()
        .map(|m| m.object_id)
        .chain(scene.spheres.iter().map(|s| s.object_id))
        .collect();
    ids.sort_unstable();
    ids.dedup();
    ids.into_iter()
        .filter_map(|id| {
            let meshes: Vec<usize> = (0..scene.meshes.len())
                .filter(|&m| {
                    scene.meshes[m].object_id == id && !scene.meshes[m].triangles.is_empty()
                })
                .collect();
            let spheres: Vec<usize> = (0..scene.spheres.len())
                .filter(|&s| scene.spheres[s].object_id == id)
                .collect();
            let emits = meshes
                .iter()
                .any(|&m| scene.meshes[m].emission != Vec3::ZERO)
                || spheres
                    .iter()
                    .any(|&s| scene.spheres[s].emission != Vec3::ZERO);
            let (center, radius) = bounding_sphere(
                meshes.iter().map(|&m| &scene.meshes[m]),
                spheres.iter().map(|&s| &scene.spheres[s]),
            )?;
            let kind = match (emits, meshes.as_slice(), spheres.is_empty()) {
                (false, [m], true) if scene.meshes[*m].rect.is_some() => {
                    EntityKind::Quad(scene.meshes[*m].rect.unwrap_or_else(|| unreachable!()))
                }
                (true, _, _) => EntityKind::Light,
                _ => EntityKind::Occluder,
            };
            let name = scene
                .object_names
                .get(id as usize - 1)
                .cloned()
                .unwrap_or_else(|| format!("object{id}"));
            let sphere_light = match (meshes.as_slice(), spheres.as_slice()) {
                ([], [s]) if kind == EntityKind::Light => Some(scene.spheres[*s].emission),
                _ => None,
            };
            Some(Entity {
                object_id: id,
                name,
                meshes,
                spheres,
                kind,
                center,
                radius,
                deforming: false,
                sphere_light,
            })
        })
        .collect()
}

/// Centre of the bounding box and the largest distance of any point from it.
pub fn bounding_sphere<'a>(
    meshes: impl Iterator<Item = &'a Mesh> + Clone,
    spheres: impl Iterator<Item = &'a Sphere> + Clone,
) -> Option<(Vec3, f32)> {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for m in meshes.clone() {
        for t in &m.triangles {
            for &v in t {
                lo = lo.min(m.positions[v as usize]);
                hi = hi.max(m.positions[v as usize]);
            }
        }
    }
    for s in spheres.clone() {
        lo = lo.min(s.center - Vec3::splat(s.radius));
        hi = hi.max(s.center + Vec3::splat(s.radius));
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let c = 0.5 * (lo + hi);
    let mut r: f32 = 0.0;
    for m in meshes {
        for t in &m.triangles {
            for &v in t {
                r = r.max((m.positions[v as usize] - c).length());
            }
        }
    }
    for s in spheres {
        r = r.max((s.center - c).length() + s.radius);
    }
    Some((c, r.max(1e-6)))
}

/// An entity's geometry alone, for tracing its fields.
pub struct EntityGeometry {
    accel: Accel,
    mesh_emission: Vec<Vec3>,
    sphere_emission: Vec<Vec3>,
}

impl EntityGeometry {
    pub fn new(scene: &Scene, e: &Entity) -> Self {
        let meshes: Vec<Mesh> = e.meshes.iter().map(|&m| scene.meshes[m].clone()).collect();
        let spheres: Vec<Sphere> = e
            .spheres
            .iter()
            .map(|&s| scene.spheres[s].clone())
            .collect();
        Self::from_shapes(&meshes, &spheres)
    }

    pub fn from_shapes(meshes: &[Mesh], spheres: &[Sphere]) -> Self {
        Self {
            accel: Accel::build(meshes, spheres),
            mesh_emission: meshes.iter().map(|m| m.emission).collect(),
            sphere_emission: spheres.iter().map(|s| s.emission).collect(),
        }
    }

    /// Whether a ray hits the entity at all.
    pub fn hits(&self, ray: &Ray) -> bool {
        self.accel.occluded(ray)
    }

    /// Whether a ray hits the entity, and the radiance it sees there (emission is
    /// one-sided, on the geometric normal's side, as in the renderer).
    fn trace(&self, ray: &Ray) -> Option<Vec3> {
        let hit = self.accel.intersect(ray)?;
        let emission = match hit.prim {
            PrimRef::Triangle { mesh, .. } => self.mesh_emission[mesh as usize],
            PrimRef::Sphere(s) => self.sphere_emission[s as usize],
        };
        if emission == Vec3::ZERO {
            return Some(Vec3::ZERO);
        }
        let front = self
            .accel
            .surface_point(ray, &hit)
            .is_some_and(|sp| sp.n_geo.dot(ray.dir) < 0.0);
        Some(if front { emission } else { Vec3::ZERO })
    }

    /// Occlusion and (for lights) RGB radiance in SH at point `p`, seen towards an
    /// entity bounded by the sphere (`center`, `radius`): `n × n` stratified
    /// directions in the cone it subtends, or the whole sphere from inside it.
    pub fn sample(&self, p: Vec3, center: Vec3, radius: f32, n: usize, radiance: bool) -> Sample {
        let to_c = center - p;
        let d = to_c.length();
        let cos_max = cone_cos(d, radius);
        let frame = if cos_max > -1.0 {
            Frame::from_normal(to_c / d)
        } else {
            Frame::from_normal(Vec3::Z)
        };
        self.sample_in(p, &frame, cos_max, n, radiance, None)
    }

    /// [`sample`](Self::sample) with the cone laid out in `frame` (z the cone's
    /// axis); `bits`, if given, gets bit a·n + b set where ray (a, b) hits.
    pub fn sample_in(
        &self,
        p: Vec3,
        frame: &Frame,
        cos_max: f32,
        n: usize,
        radiance: bool,
        mut bits: Option<&mut [u64]>,
    ) -> Sample {
        let weight = std::f32::consts::TAU * (1.0 - cos_max) / (n * n) as f32;
        let mut s = Sample::default();
        for a in 0..n {
            for b in 0..n {
                let u = Vec2::new((a as f32 + 0.5) / n as f32, (b as f32 + 0.5) / n as f32);
                let dir = frame.to_world(warp::square_to_uniform_cone(u, cos_max));
                let Some(le) = self.trace(&Ray::new(p, dir)) else {
                    continue;
                };
                if let Some(bits) = bits.as_deref_mut() {
                    let k = a * n + b;
                    bits[k / 64] |= 1 << (k % 64);
                }
                let y = sh::eval_f32(dir);
                for k in 0..COEFFS {
                    s.occlusion[k] += weight * y[k];
                }
                if radiance && le != Vec3::ZERO {
                    for c in 0..3 {
                        for k in 0..COEFFS {
                            s.radiance[c][k] += weight * le[c] * y[k];
                        }
                    }
                }
            }
        }
        s
    }

    /// Occlusion over the hemisphere above `n` at surface point `x` (zero below
    /// it, where the receiver's cosine is zero: V = 1 there keeps an unoccluded
    /// vertex exactly the constant 1).
    pub fn self_occlusion(&self, x: Vec3, n: Vec3, n_side: usize, eps: f32) -> ShF {
        let frame = Frame::from_normal(n);
        let origin = x + n * eps;
        let weight = std::f32::consts::TAU / (n_side * n_side) as f32;
        let mut o = [0.0; COEFFS];
        for a in 0..n_side {
            for b in 0..n_side {
                let u = Vec2::new(
                    (a as f32 + 0.5) / n_side as f32,
                    (b as f32 + 0.5) / n_side as f32,
                );
                let dir = frame.to_world(warp::square_to_uniform_cone(u, 0.0));
                if self.accel.occluded(&Ray::new(origin, dir)) {
                    let y = sh::eval_f32(dir);
                    for k in 0..COEFFS {
                        o[k] += weight * y[k];
                    }
                }
            }
        }
        o
    }
}

/// Occlusion and radiance at one sample point.
#[derive(Clone, Copy, Debug, Default)]
pub struct Sample {
    pub occlusion: ShF,
    pub radiance: [ShF; 3],
}

/// The precomputed fields of one entity (rest pose, world-aligned SH).
#[derive(Clone, Debug, PartialEq)]
pub struct EntityFields {
    pub occlusion: Option<Field>,
    /// RGB source radiance field (lights only).
    pub radiance: Option<[Field; 3]>,
    /// Self-occlusion at every vertex of each of the entity's meshes (occluders
    /// with meshes; empty otherwise).
    pub self_occlusion: Vec<Vec<ShF>>,
    /// The occlusion unblurred, for sphere lights (rigid entities; `None` for
    /// quads and for fields rebuilt each frame).
    pub visibility: Option<ConeMap>,
}

/// The grid of an entity's fields under `settings`.
pub fn grid_for(e: &Entity, settings: &Settings) -> Grid {
    Grid {
        n_theta: settings.n_theta,
        n_phi: settings.n_phi,
        n_radii: settings.n_radii,
        r_min: settings.r_min * e.radius,
        r_max: settings.r_max * e.radius,
    }
}

/// Units of work of [`compute_fields`] for an entity, for progress.
pub fn work_units(scene: &Scene, e: &Entity, settings: &Settings) -> usize {
    match e.kind {
        EntityKind::Quad(_) => 0,
        EntityKind::Light => grid_for(e, settings).len(),
        EntityKind::Occluder => {
            grid_for(e, settings).len()
                + e.meshes
                    .iter()
                    .map(|&m| scene.meshes[m].positions.len())
                    .sum::<usize>()
        }
    }
}

/// The occlusion field alone, every grid sample traced directly (in parallel).
pub fn occlusion_field(geo: &EntityGeometry, e: &Entity, grid: &Grid, rays: usize) -> Field {
    Field {
        grid: *grid,
        data: (0..grid.len())
            .into_par_iter()
            .map(|i| {
                geo.sample(e.center + grid.position(i), e.center, e.radius, rays, false)
                    .occlusion
            })
            .collect(),
    }
}

/// Traces every sample of an entity's fields, in parallel; `tick` is called
/// once per sample point and vertex.
pub fn compute_fields(
    scene: &Scene,
    e: &Entity,
    settings: &Settings,
    tick: &(dyn Fn() + Sync),
) -> EntityFields {
    if let EntityKind::Quad(_) = e.kind {
        return EntityFields {
            occlusion: None,
            radiance: None,
            self_occlusion: Vec::new(),
            visibility: None,
        };
    }
    let geo = EntityGeometry::new(scene, e);
    let grid = grid_for(e, settings);
    let is_light = e.kind == EntityKind::Light;
    let words = ConeMap::words(settings.rays);
    let samples: Vec<(Sample, Vec<u64>)> = (0..grid.len())
        .into_par_iter()
        .map(|i| {
            let (t, p) = ((i / grid.n_phi) % grid.n_theta, i % grid.n_phi);
            let dir = grid.direction(t, p);
            let phi = std::f32::consts::TAU * p as f32 / grid.n_phi as f32;
            let mut bits = vec![0u64; words];
            let s = geo.sample_in(
                e.center + grid.position(i),
                &cone_frame(dir, phi),
                cone_cos(grid.radius(i / (grid.n_phi * grid.n_theta)), e.radius),
                settings.rays,
                is_light,
                Some(&mut bits),
            );
            tick();
            (s, bits)
        })
        .collect();
    let visibility = Some(ConeMap {
        grid,
        side: settings.rays,
        bits: samples
            .iter()
            .flat_map(|(_, b)| b.iter().copied())
            .collect(),
    });
    let samples: Vec<Sample> = samples.into_iter().map(|(s, _)| s).collect();
    let occlusion = Field {
        grid,
        data: samples.iter().map(|s| s.occlusion).collect(),
    };
    let radiance = is_light.then(|| {
        std::array::from_fn(|c| Field {
            grid,
            data: samples.iter().map(|s| s.radiance[c]).collect(),
        })
    });
    let self_occlusion = if e.kind == EntityKind::Occluder && !e.deforming {
        e.meshes
            .iter()
            .map(|&m| mesh_self_occlusion(&geo, &scene.meshes[m], e.radius, settings, tick))
            .collect()
    } else {
        Vec::new()
    };
    EntityFields {
        occlusion: Some(occlusion),
        radiance,
        self_occlusion,
        visibility,
    }
}

fn mesh_self_occlusion(
    geo: &EntityGeometry,
    mesh: &Mesh,
    radius: f32,
    settings: &Settings,
    tick: &(dyn Fn() + Sync),
) -> Vec<ShF> {
    let normals = vertex_normals(mesh);
    (0..mesh.positions.len())
        .into_par_iter()
        .map(|v| {
            let o = if normals[v] == Vec3::ZERO {
                [0.0; COEFFS]
            } else {
                geo.self_occlusion(
                    mesh.positions[v],
                    normals[v],
                    settings.self_rays,
                    1e-4 * radius,
                )
            };
            tick();
            o
        })
        .collect()
}

/// The mesh's own vertex normals, or area-weighted ones when it has none (zero
/// for unused vertices).
pub fn vertex_normals(mesh: &Mesh) -> Vec<Vec3> {
    if mesh.normals.len() == mesh.positions.len() {
        return mesh.normals.clone();
    }
    let mut n = vec![Vec3::ZERO; mesh.positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        let f = cross(b - a, c - a);
        for &i in t {
            n[i as usize] += f;
        }
    }
    n.iter().map(|v| v.normalize_or_zero()).collect()
}

/// A counter for [`compute_fields`]' ticks that reports (done, total).
pub struct Ticker<'a> {
    done: AtomicUsize,
    total: usize,
    progress: &'a (dyn Fn(usize, usize) + Sync),
}

impl<'a> Ticker<'a> {
    pub fn new(total: usize, progress: &'a (dyn Fn(usize, usize) + Sync)) -> Self {
        Self {
            done: AtomicUsize::new(0),
            total,
            progress,
        }
    }

    pub fn tick(&self) {
        let n = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        if n.is_multiple_of(256) || n == self.total {
            (self.progress)(n, self.total);
        }
    }
}
