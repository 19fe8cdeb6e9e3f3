//! Scenes built in code for the integration tests (no scene file needed).
#![allow(dead_code)]

use gradtrace::accel::Accel;
use gradtrace::brdf::Material;
use gradtrace::math::Vec3;
use gradtrace::render::lights::LightSet;
use gradtrace::render::path::PathTracer;
use gradtrace::scene::{Camera, Mesh, Rect, RenderSettings, Scene, SceneStats, Sphere};

/// What tracing a scene needs besides the scene: its BVH and its light set.
pub struct Traceable {
    pub accel: Accel,
    pub lights: LightSet,
}

impl Traceable {
    pub fn new(s: &Scene) -> Self {
        Self {
            accel: Accel::build(&s.meshes, &s.spheres),
            lights: LightSet::build(s),
        }
    }

    /// A path tracer with point light sampling and no far-light approximation;
    /// tests that need lines set them with struct-update syntax.
    pub fn tracer<'a>(&'a self, s: &'a Scene, max_depth: u32, rr_depth: u32) -> PathTracer<'a> {
        PathTracer {
            scene: s,
            accel: &self.accel,
            lights: &self.lights,
            max_depth,
            rr_depth,
            lines: None,
            far_light: None,
        }
    }
}

pub fn empty_scene(camera: Camera) -> Scene {
    Scene {
        path: "test.toml".into(),
        assets: vec![],
        camera,
        settings: RenderSettings::default(),
        materials: vec![],
        material_names: vec![],
        meshes: vec![],
        spheres: vec![],
        bumps: vec![],
        environment: None,
        object_names: vec![],
        stats: SceneStats::default(),
        animation: None,
        content_hash_memo: Default::default(),
    }
}

pub fn camera(w: u32, h: u32) -> Camera {
    Camera::new(
        Vec3::new(0.0, 1.0, 6.0),
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::Y,
        35.0,
        w,
        h,
    )
    .unwrap()
}

pub fn add_material(s: &mut Scene, m: Material) -> u32 {
    s.materials.push(m);
    s.material_names.push(format!("m{}", s.materials.len()));
    s.materials.len() as u32 - 1
}

pub fn add_sphere(s: &mut Scene, center: Vec3, radius: f32, material: u32, emission: Vec3) {
    s.object_names.push(format!("sphere{}", s.spheres.len()));
    s.spheres.push(Sphere {
        name: String::new(),
        center,
        radius,
        material,
        emission,
        bump: None,
        object_id: s.object_names.len() as u32,
    });
}

pub fn add_quad(s: &mut Scene, rect: Rect, material: u32, emission: Vec3) {
    let c = rect.corner;
    s.object_names.push(format!("quad{}", s.meshes.len()));
    s.meshes.push(Mesh {
        name: String::new(),
        positions: vec![
            c,
            c + rect.edge_u,
            c + rect.edge_u + rect.edge_v,
            c + rect.edge_v,
        ],
        normals: vec![],
        uvs: vec![],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        material,
        emission,
        bump: None,
        rect: Some(rect),
        object_id: s.object_names.len() as u32,
    });
}

/// Ground quad facing +y, centred at the origin.
pub fn ground(size: f32) -> Rect {
    Rect {
        corner: Vec3::new(-size, 0.0, size),
        edge_u: Vec3::new(2.0 * size, 0.0, 0.0),
        edge_v: Vec3::new(0.0, 0.0, -2.0 * size),
    }
}

/// A Lambert sphere (albedo `albedo`, centre height `height`, `radius`) on a 6 × 6
/// ground of the same material, under a square light of half-width `half` at
/// height 2 emitting `radiance`: the soft-shadow set-up. Returns the (white, black)
/// material ids.
pub fn add_sphere_under_square_light(
    s: &mut Scene,
    albedo: f32,
    height: f32,
    radius: f32,
    half: f32,
    radiance: f32,
) -> (u32, u32) {
    let white = add_material(
        s,
        Material::Lambert {
            albedo: Vec3::splat(albedo),
        },
    );
    let black = add_material(s, Material::Lambert { albedo: Vec3::ZERO });
    add_quad(s, ground(3.0), white, Vec3::ZERO);
    add_sphere(s, Vec3::new(0.0, height, 0.0), radius, white, Vec3::ZERO);
    add_quad(
        s,
        Rect {
            corner: Vec3::new(-half, 2.0, -half),
            edge_u: Vec3::new(2.0 * half, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 2.0 * half),
        },
        black,
        Vec3::splat(radiance),
    );
    (white, black)
}

/// An icosphere of `radius` around `center`, subdivided `levels` times with shared
/// vertices (midpoint cache), with exact vertex normals (a smooth mesh whose
/// shading normals vary across every triangle). Named "icosphere", object id 0.
pub fn icosphere_mesh(levels: u32, center: Vec3, radius: f32, material: u32) -> Mesh {
    let (mut v, mut f) = gradtrace::math::icosahedron();
    for _ in 0..levels {
        let mut cache = std::collections::HashMap::new();
        let mut mid = |a: u32, b: u32, v: &mut Vec<Vec3>| -> u32 {
            let key = (a.min(b), a.max(b));
            *cache.entry(key).or_insert_with(|| {
                v.push(((v[a as usize] + v[b as usize]) * 0.5).normalize());
                v.len() as u32 - 1
            })
        };
        let mut nf = Vec::new();
        for [a, b, c] in f {
            let ab = mid(a, b, &mut v);
            let bc = mid(b, c, &mut v);
            let ca = mid(c, a, &mut v);
            nf.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = nf;
    }
    Mesh {
        name: "icosphere".into(),
        positions: v.iter().map(|&p| center + radius * p).collect(),
        normals: v,
        uvs: vec![],
        triangles: f,
        material,
        emission: Vec3::ZERO,
        bump: None,
        rect: None,
        object_id: 0,
    }
}

/// Adds [`icosphere_mesh`] to the scene as its own object.
pub fn add_icosphere(s: &mut Scene, center: Vec3, radius: f32, levels: u32, material: u32) {
    s.object_names.push(format!("icosphere{}", s.meshes.len()));
    s.meshes.push(Mesh {
        name: String::new(),
        object_id: s.object_names.len() as u32,
        ..icosphere_mesh(levels, center, radius, material)
    });
}

/// Adds a sum-of-sinusoids bump map and returns its index.
pub fn add_bump(s: &mut Scene, terms: &[(f32, [f32; 2], f32)]) -> u32 {
    use gradtrace::scene::bump::{Bump, Sinusoid};
    s.bumps.push(Bump {
        name: format!("bump{}", s.bumps.len()),
        terms: terms
            .iter()
            .map(|&(amplitude, f, phase)| Sinusoid {
                amplitude,
                frequency: gradtrace::math::Vec2::from(f),
                phase,
            })
            .collect(),
    });
    s.bumps.len() as u32 - 1
}
