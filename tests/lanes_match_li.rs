//! The lane shading (`render::lanes`) against `PathTracer::li`, sample for
//! sample: the same radiance bit for bit, the same first-hit AOVs and ray
//! counts, on every kind of surface, normal, light and path end the lanes
//! take; and the lanes refuse what they do not shade as `li` does. The
//! kernel calls the scalar code's own formulas, so these guard the gathering,
//! the masks and the order of the operations.

use gradtrace::brdf::Material;
use gradtrace::math::Vec3;
use gradtrace::render::lane_check::{avx2, compare_with_li, facts};
use gradtrace::render::RenderOptions;
use gradtrace::scene::{Environment, Scene, Sphere};

fn load(path: &str) -> Scene {
    gradtrace::scene::load(std::path::Path::new(path)).expect("bundled scene")
}

/// How many samples of `scene` the lanes traced as `li` did (panics on the
/// first that differs), with the CPU's kernel.
fn compared(scene: &Scene, opts: &RenderOptions) -> usize {
    compare_with_li(scene, opts, avx2()).unwrap_or_else(|e| panic!("{e}"))
}

/// Every sample of a cornell render, traced by `li` and by the lanes with
/// the same sampler: the same radiance bit for bit, the same AOVs, the
/// same ray count.
#[test]
fn lanes_trace_the_paths_li_traces() {
    let scene = load("scenes/validation/cornell_256.toml");
    let opts = RenderOptions::default();
    let mut n = 0;
    // Both kernels: `wide`'s, and AVX's where this CPU has it.
    for avx2 in [false, avx2()] {
        n += compare_with_li(&scene, &opts, avx2).unwrap_or_else(|e| panic!("{e}"));
    }
    assert!(n > 16_000, "{n}");
}

/// Paths cut short: no bounce shaded (the first hit's AOVs from the
/// scalar set-up), one bounce, and Russian roulette from the second.
#[test]
fn lanes_stop_where_li_stops() {
    let mut scene = load("scenes/validation/cornell_256.toml");
    scene.settings.rr_depth = 2;
    for max_depth in [1, 2, 6] {
        let opts = RenderOptions {
            max_depth: Some(max_depth),
            ..Default::default()
        };
        assert!(compared(&scene, &opts) > 8000, "{max_depth}");
    }
}

/// Shading normals: interpolated, one of zero length (the geometric
/// normal instead) and some below the surface (folded back), bit for bit.
#[test]
fn lanes_interpolate_shading_normals_as_li_does() {
    let mut scene = load("scenes/validation/cornell_256.toml");
    for (k, m) in scene.meshes.iter_mut().enumerate() {
        m.normals = (0..m.positions.len())
            .map(|i| match (k + i) % 5 {
                0 => Vec3::ZERO,
                1 => Vec3::new(0.3, -0.8, 0.5).normalize(),
                _ => Vec3::new(0.2 * i as f32, 1.0, -0.1 * k as f32).normalize(),
            })
            .collect();
    }
    assert!(facts(&scene).expect("a lane scene").smooth);
    assert!(compared(&scene, &RenderOptions::default()) > 8000);
}

/// Emitting triangles (the light's rectangle dropped, so it is two
/// triangle lights) and a second emitter, a wall, picked by power: the
/// triangle map, the pick and the MIS weights of emitter hits, bit for bit.
#[test]
fn lanes_trace_triangle_lights_as_li_does() {
    let mut scene = load("scenes/validation/cornell_256.toml");
    let light = scene
        .meshes
        .iter()
        .position(|m| m.emission != Vec3::ZERO)
        .expect("an emitter");
    scene.meshes[light].rect = None;
    let wall = (0..scene.meshes.len())
        .find(|&i| i != light)
        .expect("a wall");
    scene.meshes[wall].emission = Vec3::new(0.4, 0.2, 0.1);
    scene.meshes[wall].rect = None;
    let f = facts(&scene).expect("a lane scene");
    assert!(f.lights > 3 && f.triangle_lights == f.lights, "{f:?}");
    assert!(compared(&scene, &RenderOptions::default()) > 8000);
}

/// Environments: the constant sky's cosine map in the kernel, the image's
/// and the Gaussian sky's directions drawn before it, alone and beside an
/// area light (the pick between them), with rays that leave the scene
/// (the escaped light's MIS weight), bit for bit.
#[test]
fn lanes_trace_environments_as_li_does() {
    let load = |p: &str| {
        let mut s = load(p);
        s.spheres.clear();
        s
    };
    let sky = Environment::GaussianSky {
        direction: Vec3::new(0.3, 0.8, -0.2).normalize(),
        sharpness: 12.0,
        peak: Vec3::new(4.0, 3.0, 2.0),
        ambient: Vec3::new(0.1, 0.2, 0.3),
    };
    let mut cornell = load("scenes/validation/cornell_256.toml");
    cornell.environment = Some(Environment::Constant {
        radiance: Vec3::new(0.5, 0.6, 0.7),
    });
    // The Cornell box's open side faces the camera: escaped rays, and a
    // pick between the sky and the rectangle light.
    let mut cornell_sky = cornell.clone();
    cornell_sky.environment = Some(sky.clone());
    let mut floor_sky = load("scenes/validation/env_constant.toml");
    floor_sky.environment = Some(sky);
    for (name, scene, in_frame) in [
        (
            "constant",
            load("scenes/validation/env_constant.toml"),
            true,
        ),
        ("image", load("scenes/validation/env_image.toml"), false),
        ("gaussian sky", floor_sky, false),
        ("cornell + constant", cornell, true),
        ("cornell + gaussian sky", cornell_sky, false),
    ] {
        let f = facts(&scene).expect("a lane scene");
        assert_eq!(f.sky_in_frame, in_frame, "{name}");
        assert!(compared(&scene, &RenderOptions::default()) > 400, "{name}");
    }
}

/// Spheres: hit (their surface point from `sphere_point`), and lights
/// (their samples drawn from the hit point), beside triangles with and
/// without shading normals, a rectangle light and environments, bit for
/// bit.
#[test]
fn lanes_trace_spheres_as_li_does() {
    let mut cornell = load("scenes/validation/cornell_256.toml");
    let white = cornell.meshes[0].material;
    let ball = |center: Vec3, radius: f32, emission: Vec3, object_id: u32| Sphere {
        name: "ball".into(),
        center,
        radius,
        material: white,
        emission,
        bump: None,
        object_id,
    };
    cornell.spheres = vec![
        ball(Vec3::new(-0.4, -0.6, 0.3), 0.35, Vec3::ZERO, 90),
        ball(Vec3::new(0.5, 0.4, -0.2), 0.2, Vec3::new(3.0, 2.0, 1.0), 91),
    ];
    let mut smooth = cornell.clone();
    for m in &mut smooth.meshes {
        m.normals = (0..m.positions.len())
            .map(|i| Vec3::new(0.1 * i as f32, 1.0, 0.3).normalize())
            .collect();
    }
    for (name, scene) in [
        ("cornell + a ball and a sphere light", cornell),
        ("the same with shading normals", smooth),
        (
            "three spheres, Gaussian sky",
            load("scenes/three_spheres_env.toml"),
        ),
        (
            "bunny, sphere light, constant sky",
            load("scenes/shadowfield_bunny.toml"),
        ),
    ] {
        assert!(facts(&scene).expect("a lane scene").spheres, "{name}");
        assert!(compared(&scene, &RenderOptions::default()) > 400, "{name}");
    }
}

/// Mirrors: no light sample, the reflection, an infinite density for the
/// next hit's MIS; on a sphere (the Mitsuba validation scenes, under a
/// sphere light, a constant sky, an image) and on a wall of the Cornell
/// box, bit for bit.
#[test]
fn lanes_trace_mirrors_as_li_does() {
    let mut cornell = load("scenes/validation/cornell_256.toml");
    let back = cornell.meshes.len() - 1;
    let mirror = cornell.materials.len() as u32;
    cornell.materials.push(Material::Mirror {
        reflectance: Vec3::new(0.9, 0.8, 0.7),
    });
    cornell.meshes[back].material = mirror;
    for (name, scene) in [
        ("spheres", load("scenes/validation/spheres.toml")),
        ("constant sky", load("scenes/validation/env_constant.toml")),
        ("image sky", load("scenes/validation/env_image.toml")),
        ("cornell with a mirror wall", cornell),
    ] {
        assert!(facts(&scene).expect("a lane scene").mirrors, "{name}");
        assert!(compared(&scene, &RenderOptions::default()) > 400, "{name}");
    }
}

/// Only what the lanes shade exactly as `li` does gets them.
#[test]
fn lane_scenes_are_lambertian_or_mirror_without_bump_maps() {
    let lanes = |s: &Scene| facts(s).is_some();
    let mut cornell = load("scenes/cornell.toml");
    assert!(lanes(&cornell));
    for scene in [
        "scenes/three_spheres_env.toml",
        "scenes/shadowfield_bunny.toml",
        "scenes/validation/env_constant.toml",
    ] {
        assert!(lanes(&load(scene)), "{scene}");
    }
    for (scene, why) in [
        ("scenes/spheres_table.toml", "a glossy material"),
        ("scenes/glossy_teapot.toml", "a glossy material"),
        ("scenes/bunny_env.toml", "a glossy material"),
        ("scenes/objects_bumpy.toml", "bump maps"),
    ] {
        assert!(!lanes(&load(scene)), "{scene}: {why}");
    }
    // A bump map on a sphere alone.
    let mut bumpy = load("scenes/three_spheres_env.toml");
    let bumped = load("scenes/objects_bumpy.toml");
    bumpy.spheres[0].bump = Some(0);
    bumpy.bumps = bumped.bumps.clone();
    assert!(!lanes(&bumpy));
    // No light at all: still the lanes' (every light pick comes back empty).
    let mut dark = cornell.clone();
    for m in &mut dark.meshes {
        m.emission = Vec3::ZERO;
    }
    assert!(lanes(&dark));
    // A glossy material on one mesh.
    let glossy = load("scenes/glossy_teapot.toml");
    cornell.materials[cornell.meshes[0].material as usize] = glossy.materials[0].clone();
    assert!(!lanes(&cornell));
}
