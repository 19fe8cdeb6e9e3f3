//! Tests of the glossy-transfer preview (`gradtrace::preview::glossy` and
//! `gradtrace::pipeline::preview::glossy`): subdivision invariants (neighbour
//! levels differ by ≤ 1, watertight after T-vertex resolution, the lookup
//! reproduces surface points), the BRDF fit against the material's known albedo,
//! a furnace-like known answer, and `run` end to end on a small scene.
//!
//! `cargo test --release --test glossy -- --ignored --nocapture` also runs the
//! teapot against the path tracer (a few minutes on 2 cores).

use gradtrace::brdf::Material;
use gradtrace::math::{cross, Frame, Vec2, Vec3};
use gradtrace::pipeline::preview::glossy::{run, GlossyOptions};
use gradtrace::preview::glossy::fit::{MaterialFit, FIT_LEVEL};
use gradtrace::preview::glossy::icosphere::Icosphere;
use gradtrace::preview::glossy::mesh::{AdaptiveMesh, Vertex};
use gradtrace::preview::glossy::{self, PrefilteredEnv, Settings};
use gradtrace::scene::Mesh;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// An octahedron with shared vertices and smooth normals: closed, 8 faces.
fn octahedron() -> Mesh {
    let positions = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let triangles = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    Mesh {
        name: "octahedron".into(),
        normals: positions.clone(),
        positions,
        triangles,
        ..Default::default()
    }
}

fn interp(m: &Mesh) -> impl Fn(u32, u32, Vec3) -> Vertex + '_ {
    move |_, tri, b| {
        let t = m.triangles[tri as usize];
        let p = t.map(|i| m.positions[i as usize]);
        let position = p[0] * b.x + p[1] * b.y + p[2] * b.z;
        Vertex {
            position,
            normal: position.normalize(),
            geometric_normal: cross(p[1] - p[0], p[2] - p[0]).normalize(),
            material: 0,
        }
    }
}

/// Splits pseudo-random leaves, the deeper ones near +x more often (a hot spot, so
/// that neighbours of very different levels would arise without the constraint).
fn refined_octahedron(splits: usize) -> (Mesh, AdaptiveMesh) {
    let m = octahedron();
    let mut mesh = AdaptiveMesh::new(std::slice::from_ref(&m));
    let f = interp(&m);
    let mut state = 12345u64;
    for _ in 0..splits {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let leaves: Vec<u32> = mesh.leaves().collect();
        // Prefer the leaf nearest the hot spot among a few random ones.
        let pick = (0..4)
            .map(|k| leaves[((state >> (8 + 8 * k)) as usize) % leaves.len()])
            .min_by(|&a, &b| {
                let d = |x: u32| {
                    let v = mesh.face_vertices(x);
                    -mesh.vertices[v[0] as usize].position.x
                };
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        if mesh.face_level(pick) < 6 {
            mesh.split(pick, &f);
        }
    }
    mesh.resolve();
    drop(f);
    (m, mesh)
}

#[test]
fn neighbour_levels_differ_by_at_most_one() {
    let (_, mesh) = refined_octahedron(300);
    let deepest = mesh.leaves().map(|f| mesh.face_level(f)).max().unwrap();
    println!(
        "{} faces, {} vertices, deepest level {deepest}",
        mesh.face_count(),
        mesh.vertices.len()
    );
    assert!(
        deepest >= 4,
        "the test must reach deep levels to mean anything"
    );
    assert_eq!(mesh.max_neighbour_level_difference(), 1);
}

#[test]
fn resolved_mesh_is_watertight_and_consistently_oriented() {
    let (_, mesh) = refined_octahedron(300);
    let mut directed: HashMap<(u32, u32), u32> = HashMap::new();
    let mut area = 0.0;
    for t in mesh.resolved_triangles() {
        let p = t.map(|i| mesh.vertices[i as usize].position);
        let a = 0.5 * cross(p[1] - p[0], p[2] - p[0]).length();
        assert!(a > 0.0, "degenerate resolved triangle {t:?}");
        area += a;
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "directed edge {a}->{b} used {n} times");
        assert_eq!(
            directed.get(&(b, a)),
            Some(&1),
            "edge {a}-{b} has no twin: a crack"
        );
    }
    // The flat octahedron's area, 8 · (√3/2), exactly tiled.
    assert!((area - 4.0 * 3f32.sqrt()).abs() < 1e-4, "area {area}");
}

#[test]
fn lookup_reproduces_points_on_the_original_triangles() {
    let (m, mesh) = refined_octahedron(300);
    for tri in 0..8u32 {
        let t = m.triangles[tri as usize];
        let p = t.map(|i| m.positions[i as usize]);
        for k in 0..400 {
            let u = (
                (k as f32 * 0.618_034) % 1.0,
                (k as f32 * 0.414_214 + 0.1) % 1.0,
            );
            let (b1, b2) = if u.0 + u.1 > 1.0 {
                (1.0 - u.0, 1.0 - u.1)
            } else {
                u
            };
            let x = p[0] * (1.0 - b1 - b2) + p[1] * b1 + p[2] * b2;
            let (ids, w) = mesh.locate(0, tri, Vec2::new(b1, b2)).unwrap();
            let y: Vec3 = (0..3)
                .map(|i| mesh.vertices[ids[i] as usize].position * w[i])
                .sum();
            assert!(
                (x - y).length() < 1e-5,
                "tri {tri} at ({b1}, {b2}): {x} vs {y}"
            );
        }
    }
}

#[test]
fn brdf_fit_keeps_the_albedo_and_centres_on_the_reflection() {
    let ico = Icosphere::new(FIT_LEVEL);
    let ks = Vec3::new(0.7, 0.5, 0.3);
    for exponent in [16.0, 128.0] {
        let m = Material::BlinnPhong {
            kd: Vec3::splat(0.1),
            ks,
            exponent,
        };
        let fit = MaterialFit::new(&m, &ico, 4096).unwrap();
        // At normal incidence the modified Blinn-Phong's specular albedo is ks exactly.
        let e = fit.glossy_at(&ico, Vec3::Z).unwrap();
        println!(
            "n = {exponent}: βg = {} κ = {:.1} μ = {}",
            e.albedo, e.lobe.kappa, e.lobe.mu
        );
        assert!((e.albedo - ks).abs().max_element() < 0.01 * ks.max_element());
        assert!(e.lobe.mu.z > 0.999);
        // Sharper lobes give larger κ; a lobe of (N·H)^n is about n·2 wide in ωi's κ... just monotone here.
        // Off the normal, μ leans away from the view like the mirror direction.
        let wo = Vec3::new(0.5, 0.0, 0.75f32.sqrt());
        let e = fit.glossy_at(&ico, wo).unwrap();
        assert!(e.lobe.mu.x < -0.3 && e.lobe.mu.z > 0.5, "μ {}", e.lobe.mu);
    }
    let k16 = MaterialFit::new(
        &Material::BlinnPhong {
            kd: Vec3::ZERO,
            ks,
            exponent: 16.0,
        },
        &ico,
        4096,
    )
    .unwrap();
    let k128 = MaterialFit::new(
        &Material::BlinnPhong {
            kd: Vec3::ZERO,
            ks,
            exponent: 128.0,
        },
        &ico,
        4096,
    )
    .unwrap();
    let (a, b) = (
        k16.glossy_at(&ico, Vec3::Z).unwrap(),
        k128.glossy_at(&ico, Vec3::Z).unwrap(),
    );
    assert!(
        b.lobe.kappa > 4.0 * a.lobe.kappa,
        "κ {} vs {}",
        a.lobe.kappa,
        b.lobe.kappa
    );
    assert!(MaterialFit::new(
        &Material::Mirror {
            reflectance: Vec3::ONE
        },
        &ico,
        16
    )
    .is_err());
}

fn temp_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// An unoccluded Lambert floor under a constant environment reflects albedo × L
/// (the direct lobe's α is the albedo, and a constant prefilters to itself).
#[test]
fn lambert_floor_under_constant_sky_reflects_albedo() {
    let dir = temp_dir("glossy_furnace");
    let scene_path = dir.join("floor.toml");
    std::fs::write(
        &scene_path,
        r#"
[camera]
from = [0, 2, 2]
to = [0, 0, 0]
fov = 30
resolution = [32, 32]

[materials.floor]
type = "lambert"
albedo = [0.6, 0.4, 0.2]

[[shapes]]
type = "quad"
corner = [-5, 0, 5]
edge_u = [10, 0, 0]
edge_v = [0, 0, -10]
material = "floor"

[environment]
type = "constant"
radiance = [1.5, 1.5, 1.5]
"#,
    )
    .unwrap();
    let scene = gradtrace::scene::load(&scene_path).unwrap();
    let accel = gradtrace::accel::Accel::build(&scene.meshes, &scene.spheres);
    let settings = Settings {
        spatial: false,
        ..Settings::default()
    };
    let t = glossy::precompute(&scene, &accel, &settings, &|_, _, _| {}).unwrap();
    let env = PrefilteredEnv::new(scene.environment.as_ref().unwrap());
    let img = glossy::render(&t, &env, &scene, &accel, &scene.camera);
    let expected = Vec3::new(0.6, 0.4, 0.2) * 1.5;
    for (i, c) in img.iter().enumerate() {
        assert!(
            (*c - expected).abs().max_element() < 0.01 * 1.5,
            "pixel {i}: {c} vs {expected}"
        );
    }
    // Every frame is one Frame per vertex; sanity of the public pieces.
    assert_eq!(t.frames.len(), t.vertices.len());
    let _ = Frame::from_normal(Vec3::Y);
}

/// An unoccluded Lambert floor under the bundled sky image (sun at 55°, the
/// ground below the horizon at a fifth of the sky) reflects albedo × ∫ L cos/π
/// over the upper hemisphere, here by a 512 × 1024 midpoint quadrature of the
/// environment. A constant sky cannot see it: Td's open direct lobe, a vMF of
/// mean cosine 2/3 (κ = 46/15), read the sky's vMF convolution, 0.84 / 0.86 /
/// 0.91 of the truth per channel here (issue 57's dark floor); within 1 % now.
#[test]
fn lambert_floor_under_the_sky_image_reflects_albedo_times_irradiance() {
    let dir = temp_dir("glossy_furnace_sky");
    let scene_path = dir.join("floor.toml");
    let sky = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/envs/sky.hdr");
    std::fs::write(
        &scene_path,
        format!(
            r#"
[camera]
from = [0, 2, 2]
to = [0, 0, 0]
fov = 30
resolution = [24, 24]

[materials.floor]
type = "lambert"
albedo = [0.6, 0.4, 0.2]

[[shapes]]
type = "quad"
corner = [-50, 0, 50]
edge_u = [100, 0, 0]
edge_v = [0, 0, -100]
material = "floor"

[environment]
type = "image"
file = "{}"
"#,
            sky.display()
        ),
    )
    .unwrap();
    let scene = gradtrace::scene::load(&scene_path).unwrap();
    let env_src = scene.environment.as_ref().unwrap();
    // ∫ L cos θ/π dω = (1/π) ∫∫ L cos θ d(cos θ) dφ, midpoints in cos θ and φ.
    let (nu, nphi) = (512, 1024);
    let mut irradiance = glam::DVec3::ZERO;
    for i in 0..nu {
        let ct = (i as f64 + 0.5) / nu as f64;
        let st = (1.0 - ct * ct).sqrt();
        for j in 0..nphi {
            let phi = std::f64::consts::TAU * (j as f64 + 0.5) / nphi as f64;
            let d = Vec3::new((st * phi.cos()) as f32, ct as f32, (st * phi.sin()) as f32);
            irradiance += env_src.eval(d).as_dvec3() * ct;
        }
    }
    irradiance *= std::f64::consts::TAU / (nu * nphi) as f64 / std::f64::consts::PI;
    let expected = Vec3::new(0.6, 0.4, 0.2) * irradiance.as_vec3a();
    let accel = gradtrace::accel::Accel::build(&scene.meshes, &scene.spheres);
    let settings = Settings {
        spatial: false,
        ..Settings::default()
    };
    let t = glossy::precompute(&scene, &accel, &settings, &|_, _, _| {}).unwrap();
    let env = PrefilteredEnv::new(env_src);
    let img = glossy::render(&t, &env, &scene, &accel, &scene.camera);
    let floor: Vec<&Vec3> = img.iter().filter(|c| c.max_element() > 0.0).collect();
    assert!(floor.len() > img.len() / 2, "the floor fills the view");
    for (i, c) in floor.iter().enumerate() {
        let ratio = **c / expected;
        assert!(
            (ratio - Vec3::ONE).abs().max_element() < 0.01,
            "floor pixel {i}: {c} vs {expected} (ratio {ratio})"
        );
    }
}

/// In a black card's shadow on a Lambert floor under the sky image (the card
/// 1 m up towards the sky's bright band: 4 % of the cosine-weighted hemisphere,
/// 47 % of the light), the preview's pixel is the floor point's direct light
/// traced with 2^16 paths within 15 %. A vMF of what is open cannot hold the
/// hole around the band: the stored lobe alone read 1.38 / 1.25 / 1.11 of it,
/// plus its open error scaled by the open fraction 1.72 / 1.49 / 1.23; the open
/// lobe minus the blocked one 0.91 / 0.94 / 0.97 (one vMF for a square card over
/// the band's peak: the bound).
#[test]
fn lambert_floor_in_a_cards_shadow_under_the_sky_image_matches_traced_light() {
    use gradtrace::preview::glossy::slice::{SurfaceSample, TraceContext};
    let dir = temp_dir("glossy_card_shadow");
    let scene_path = dir.join("card.toml");
    let sky = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/envs/sky.hdr");
    // The sky's brightest texel is at θ = 55°, φ = 54° (u = atan2(x, −z)/2π):
    // direction (0.67, 0.57, −0.48); the card, 0.6 m square, 1 m along it.
    std::fs::write(
        &scene_path,
        format!(
            r#"
[camera]
from = [0, 1.5, 1.0]
to = [0, 0, 0]
fov = 4
resolution = [9, 9]

[materials.floor]
type = "lambert"
albedo = [0.5, 0.5, 0.5]

[materials.card]
type = "lambert"
albedo = [0, 0, 0]

[[shapes]]
type = "quad"
corner = [-1.5, 0, 1.5]
edge_u = [3, 0, 0]
edge_v = [0, 0, -3]
material = "floor"

[[shapes]]
type = "quad"
corner = [0.37, 0.57, -0.18]
edge_u = [0.6, 0, 0]
edge_v = [0, 0, -0.6]
material = "card"

[environment]
type = "image"
file = "{}"
"#,
            sky.display()
        ),
    )
    .unwrap();
    let scene = gradtrace::scene::load(&scene_path).unwrap();
    let accel = gradtrace::accel::Accel::build(&scene.meshes, &scene.spheres);
    let settings = Settings {
        spatial: false,
        initial_edge_fraction: 1.0 / 48.0,
        diffuse_samples: 1024,
        ..Settings::default()
    };
    let t = glossy::precompute(&scene, &accel, &settings, &|_, _, _| {}).unwrap();
    let env = PrefilteredEnv::new(scene.environment.as_ref().unwrap());
    let img = glossy::render(&t, &env, &scene, &accel, &scene.camera);
    // The centre pixel's floor point, its direct light traced (Td's paths, the
    // environment evaluated where each escapes).
    let ray = scene.camera.generate_ray(Vec2::new(4.5, 4.5));
    let p = ray.origin + ray.dir * (-ray.origin.y / ray.dir.y);
    let ico = Icosphere::new(FIT_LEVEL);
    let fits: Vec<MaterialFit> = scene
        .materials
        .iter()
        .map(|m| MaterialFit::new(m, &ico, 512).unwrap())
        .collect();
    let ctx = TraceContext {
        scene: &scene,
        accel: &accel,
        fits: &fits,
        ico: &ico,
    };
    let at = SurfaceSample {
        position: p,
        geometric_normal: Vec3::Y,
        frame: Frame::from_normal(Vec3::Y),
        material: scene
            .material_names
            .iter()
            .position(|n| n == "floor")
            .unwrap() as u32,
    };
    let env_src = scene.environment.as_ref().unwrap();
    let traced = ctx.radiance(&at, None, 1 << 16, 7, env_src)[0];
    let (open, _) = ctx.trace(&at, None, 4096, 7);
    let blocked = 1.0 - open[0].alpha.x / 0.5;
    let got = img[4 * 9 + 4];
    println!("at {p}: preview {got}, traced {traced}, blocked fraction {blocked:.3}");
    assert!(
        (0.02..0.15).contains(&blocked),
        "the card blocks a small part of the hemisphere: {blocked}"
    );
    let ratio = got / traced;
    assert!(
        (ratio - Vec3::ONE).abs().max_element() < 0.15,
        "shadowed floor: preview {got} vs traced {traced} (ratio {ratio})"
    );
}

#[test]
fn run_end_to_end_on_a_small_scene() {
    let out = temp_dir("glossy_run");
    let mut opts = GlossyOptions::new(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/glossy/cube_floor.toml"),
    );
    opts.out_dir = out.clone();
    opts.quiet = true;
    opts.orbit = Some(2);
    opts.reference_spp = Some(64);
    opts.reference_spp_max = Some(256);
    opts.settings = Settings {
        samples: 32,
        diffuse_samples: 128,
        max_angular_level: 3,
        initial_edge_fraction: 0.25,
        batch: 20,
        max_vertices: 3000,
        ..Settings::default()
    };
    let s = run(&opts).unwrap();
    println!("{s:#?}");
    for p in [&s.exr, &s.png, &s.json, &s.stats_page] {
        assert!(p.is_file(), "{} missing", p.display());
    }
    assert!(out.join("orbit_001.png").is_file());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&s.json).unwrap()).unwrap();
    assert_eq!(json["method"], "glossy-transfer");
    for key in [
        "precompute_s",
        "render_ms",
        "render_median_ms",
        "vertices_initial",
        "vertices_final",
        "bytes",
        "image_mean",
        "rmse",
        "reference_s",
    ] {
        assert!(
            json[key].as_f64().is_some_and(f64::is_finite),
            "{key}: {}",
            json[key]
        );
    }
    assert!(
        s.vertices_final > s.vertices_initial,
        "spatial refinement added no vertex"
    );
    let img = gradtrace::output::read_exr(&s.exr).unwrap();
    for name in [
        "R",
        "G",
        "B",
        "reference.R",
        "reference.G",
        "reference.B",
        "error.Y",
    ] {
        let c = img
            .channel(name)
            .unwrap_or_else(|| panic!("channel {name}"));
        assert!(c.data.iter().all(|x| x.is_finite()));
    }
    let rel = s.rmse / s.reference_mean;
    println!("RMSE {:.4} = {:.1} % of the mean", s.rmse, 100.0 * rel);
    assert!(
        rel < 0.2,
        "preview too far from the path tracer: {:.1} %",
        100.0 * rel
    );
    // A second run reads the cache: same image, no precomputation.
    let again = run(&opts).unwrap();
    assert!(again.cached);
    assert_eq!(again.vertices_final, s.vertices_final);
    assert!((again.rmse - s.rmse).abs() < 1e-9);
}

/// The teapot (e = 128) against the path tracer: RMSE ≤ 8 % of the image mean.
#[test]
#[ignore = "minutes on 2 cores; run with --ignored"]
fn teapot_preview_matches_path_tracer() {
    let out = temp_dir("glossy_teapot");
    let mut opts =
        GlossyOptions::new(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/glossy_teapot.toml"));
    opts.out_dir = out;
    opts.quiet = true;
    opts.resolution = Some((256, 256));
    opts.reference_spp = Some(256);
    let s = run(&opts).unwrap();
    let rel = s.rmse / s.reference_mean;
    println!("{s:#?}\nRMSE = {:.2} % of the mean", 100.0 * rel);
    assert!(rel <= 0.08, "RMSE {:.2} % of the mean", 100.0 * rel);
}

/// Process CPU seconds (user + system), Linux only: the machine is shared, so
/// precompute cost is quoted in CPU time as well as wall time.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|x| x.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / 100.0
}

fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The benchmark figures of the issue: `GLOSSY_SCENE` (default the e = 128 teapot),
/// `GLOSSY_LEVEL`, `GLOSSY_SAMPLES`, `GLOSSY_SPATIAL` (0/1), `GLOSSY_UNIFORM`
/// (uniform levels), `GLOSSY_RES`, `GLOSSY_SPP`, `GLOSSY_OUT`; prints progress with
/// wall and CPU time, then runs the pipeline on the cached transfer.
#[test]
#[ignore = "benchmark; run with --ignored --nocapture"]
fn glossy_benchmark() {
    let scene_path: String = env_or("GLOSSY_SCENE", "scenes/glossy_teapot.toml".to_string());
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join(scene_path);
    let res: u32 = env_or("GLOSSY_RES", 512);
    let mut opts = GlossyOptions::new(&scene_path);
    opts.out_dir = PathBuf::from(env_or(
        "GLOSSY_OUT",
        format!("{}/glossy_bench", env!("CARGO_TARGET_TMPDIR")),
    ));
    opts.quiet = true;
    opts.resolution = Some((res, res));
    opts.reference_spp = Some(env_or("GLOSSY_SPP", 256));
    opts.orbit = Some(env_or("GLOSSY_ORBIT", 0));
    opts.settings = Settings {
        max_angular_level: env_or("GLOSSY_LEVEL", 3),
        samples: env_or("GLOSSY_SAMPLES", 32),
        spatial: env_or("GLOSSY_SPATIAL", 1) == 1,
        uniform_levels: env_or("GLOSSY_UNIFORM", 0),
        max_vertices: env_or("GLOSSY_MAXV", 60_000),
        spatial_threshold: env_or("GLOSSY_TAU", 0.05),
        ..Settings::default()
    };
    let scene = gradtrace::scene::load(&scene_path).unwrap();
    let accel = gradtrace::accel::Accel::build(&scene.meshes, &scene.spheres);
    // Where `run` looks for the cache; an existing one is reused.
    let entry =
        gradtrace::pipeline::preview::glossy::transfer_entry(&scene, &opts.out_dir, &opts.settings)
            .unwrap();
    let cache = entry.path().to_path_buf();
    let mut cpu_s = f64::NAN;
    if !cache.is_file() {
        let (wall, cpu) = (std::time::Instant::now(), cpu_seconds());
        let last = std::sync::Mutex::new((String::new(), 0u64));
        let progress = |phase: &str, done: u64, total: u64| {
            let mut l = last.lock().unwrap();
            let step = 10 * done / total.max(1);
            if l.0 != phase || l.1 != step {
                *l = (phase.to_string(), step);
                let (w, c) = (wall.elapsed().as_secs_f64(), cpu_seconds() - cpu);
                eprintln!("[{w:7.1} s wall, {c:7.1} s cpu] {phase}: {done}/{total}");
            }
        };
        let t = glossy::precompute(&scene, &accel, &opts.settings, &progress).unwrap();
        cpu_s = cpu_seconds() - cpu;
        eprintln!(
            "precompute: {:.1} s wall, {cpu_s:.1} s cpu; {:?}",
            wall.elapsed().as_secs_f64(),
            t.stats
        );
        entry
            .write_bytes(&t.encode(entry.key()), t.stats.precompute_s)
            .unwrap();
    }
    let s = run(&opts).unwrap();
    assert!(
        s.cached,
        "the benchmark's cache key must match the pipeline's"
    );
    println!(
        "RESULT scene={} res={res} precompute_wall_s={:.1} precompute_cpu_s={cpu_s:.1} vertices={}→{} levels={:?} bytes={} render_ms={:.1} rmse={:.5} mean={:.5} rmse/mean={:.2}% interior={:.2}% reference_s={:.1}",
        scene.name(),
        s.precompute_s,
        s.vertices_initial,
        s.vertices_final,
        s.angular_levels,
        s.bytes,
        s.render_ms,
        s.rmse,
        s.reference_mean,
        100.0 * s.rmse / s.reference_mean,
        100.0 * s.rmse_interior / s.reference_mean,
        s.reference_s
    );
}

/// The prefiltered levels against the closed form: a vMF-shaped sky
/// L(s) = e^{σ(s·d − 1)} convolved with γ_{μ,κ} is c(κ)/c(κc) · e^{−σ},
/// κc = ‖κμ + σd‖ (the same identity as App. A's cross term).
#[test]
fn prefiltered_levels_match_the_vmf_convolution_closed_form() {
    use gradtrace::math::vmf::normaliser;
    let d = Vec3::new(0.3, 0.8, -0.52).normalize();
    let sigma = 20.0f64;
    let env = gradtrace::scene::environment::Environment::GaussianSky {
        direction: d,
        sharpness: sigma as f32,
        peak: Vec3::ONE,
        ambient: Vec3::ZERO,
    };
    let pre = PrefilteredEnv::new(&env);
    let mut worst = 0.0f64;
    for level in [0, 2, 4, 6, 8, 10] {
        let mut level_worst = 0.0f64;
        let kappa = 0.25f64 * 2f64.powi(level);
        for k in 0..40 {
            let a = k as f32 * 0.7;
            let mu =
                (d + Vec3::new(a.cos(), 0.3 * a.sin(), a.sin()) * (k as f32 / 40.0)).normalize();
            let kc = (mu.as_dvec3() * kappa + d.as_dvec3() * sigma).length();
            let exact = normaliser(kappa) / normaliser(kc) * (-sigma).exp();
            let got = pre.lookup(mu, kappa as f32).x as f64;
            let peak = normaliser(kappa) / normaliser(kappa + sigma) * (-sigma).exp();
            level_worst = level_worst.max((got - exact).abs() / peak);
        }
        println!("κ = {kappa}: worst error {level_worst:.4} of the peak");
        worst = worst.max(level_worst);
    }
    println!("worst error relative to the peak: {worst:.4}");
    assert!(
        worst < 0.02,
        "prefiltered levels off by {worst} of the peak"
    );
}

/// Two-lobe EM (fit::fit_mixture) recovers a known mixture of two vMF lobes from
/// samples of it: shares, μ and κ; lobe 0 is the one nearer the normal.
#[test]
fn two_lobe_em_recovers_a_known_mixture() {
    use glam::DVec3;
    use gradtrace::math::vmf::Vmf;
    let tilt = |deg: f64| DVec3::new(deg.to_radians().sin(), 0.0, deg.to_radians().cos());
    let (a, b) = (Vmf::new(tilt(15.0), 200.0), Vmf::new(tilt(35.0), 120.0));
    let n = 16384u32;
    let share_a = 0.6;
    let samples: Vec<(DVec3, DVec3)> = (0..n)
        .map(|i| {
            let u = [
                sobol_burley::sample(i, 0, 7) as f64,
                sobol_burley::sample(i, 1, 7) as f64,
            ];
            let lobe = if (i as f64 + 0.5) / (n as f64) < share_a {
                a
            } else {
                b
            };
            (lobe.sample(u), DVec3::ONE)
        })
        .collect();
    let fit = gradtrace::preview::glossy::fit::fit_mixture(&samples, n as u64);
    for (got, (want, share)) in fit.iter().zip([(a, share_a), (b, 1.0 - share_a)]) {
        let lobe = Vmf::from_mean_resultant(got.mean_dir * got.resultant);
        let angle = lobe.mu.dot(want.mu).clamp(-1.0, 1.0).acos().to_degrees();
        println!(
            "share {:.3} (want {share}), μ off by {angle:.2}°, κ {:.1} (want {})",
            got.weight, lobe.kappa, want.kappa
        );
        assert!((got.weight - share).abs() < 0.02, "share {}", got.weight);
        assert!(angle < 1.0, "μ off by {angle}°");
        assert!(
            (lobe.kappa / want.kappa - 1.0).abs() < 0.1,
            "κ {}",
            lobe.kappa
        );
    }
}

/// A Blinn-Phong floor point with a wall beside it, traced through the
/// preview's TraceContext.
fn floor_and_wall(wall: bool) -> (gradtrace::scene::Scene, PathBuf) {
    let dir = temp_dir(if wall {
        "glossy_cv_wall"
    } else {
        "glossy_cv_open"
    });
    let path = dir.join("floor.toml");
    let wall_shape = if wall {
        r#"
[[shapes]]
type = "quad"
corner = [0.3, 0, -5]
edge_u = [0, 0, 10]
edge_v = [0, 0.36, 0]
material = "floor"
"#
    } else {
        ""
    };
    std::fs::write(
        &path,
        format!(
            r#"
[camera]
from = [0, 2, 2]
to = [0, 0, 0]
fov = 30
resolution = [8, 8]

[materials.floor]
type = "blinn_phong"
kd = [0.2, 0.2, 0.2]
ks = [0.6, 0.6, 0.6]
exponent = 32

[[shapes]]
type = "quad"
corner = [-50, 0, 50]
edge_u = [100, 0, 0]
edge_v = [0, 0, -100]
material = "floor"
{wall_shape}
[environment]
type = "constant"
radiance = [1, 1, 1]
"#
        ),
    )
    .unwrap();
    (gradtrace::scene::load(&path).unwrap(), dir)
}

/// The direct lobes' control variate: on an open floor the slice is the BRDF's
/// known lobes up to rare grazing self-hits (a fraction of the plain sum's
/// spread over seeds); beside a wall its α (a constant sky makes α the radiance)
/// agrees on average with the plain sum over escaped paths.
#[test]
fn direct_lobes_control_variate_is_exact_when_open_and_unbiased_when_blocked() {
    use gradtrace::preview::glossy::slice::{SurfaceSample, TraceContext, DIRECT_SECOND};
    let ico = Icosphere::new(FIT_LEVEL);
    for wall in [false, true] {
        let (scene, _dir) = floor_and_wall(wall);
        let accel = gradtrace::accel::Accel::build(&scene.meshes, &scene.spheres);
        let fits: Vec<MaterialFit> = scene
            .materials
            .iter()
            .map(|m| MaterialFit::new(m, &ico, 4096).unwrap())
            .collect();
        let ctx = TraceContext {
            scene: &scene,
            accel: &accel,
            fits: &fits,
            ico: &ico,
        };
        let at = SurfaceSample {
            position: Vec3::ZERO,
            geometric_normal: Vec3::Y,
            frame: Frame::from_normal(Vec3::Y),
            material: 0,
        };
        // Viewed from −x at 50° elevation: the glossy lobe leans towards +x, where
        // the wall (0.36 high at x = 0.3) cuts it about in half.
        let (s50, c50) = 50f32.to_radians().sin_cos();
        let wo = at.frame.to_local(Vec3::new(-c50, s50, 0.0));
        let env = scene.environment.as_ref().unwrap();
        for view in [None, Some(wo)] {
            let seeds = 64;
            let (mut cv, mut cv2, mut plain, mut plain2) = (0.0, 0.0, 0.0, 0.0);
            for seed in 0..seeds {
                let (s, _) = ctx.trace(&at, view, 64, seed);
                let a = (s[0].alpha.x + s[DIRECT_SECOND].alpha.x) as f64;
                let p = ctx.radiance(&at, view, 64, seed, env)[0].x as f64;
                (cv, cv2, plain, plain2) = (cv + a, cv2 + a * a, plain + p, plain2 + p * p);
            }
            let n = seeds as f64;
            let (m_cv, m_plain) = (cv / n, plain / n);
            let (v_cv, v_plain) = (cv2 / n - m_cv * m_cv, plain2 / n - m_plain * m_plain);
            let se = ((v_cv + v_plain) / n).sqrt();
            println!(
                "wall {wall} view {}: cv {m_cv:.4} (sd {:.4}), plain {m_plain:.4} (sd {:.4})",
                view.is_some(),
                v_cv.max(0.0).sqrt(),
                v_plain.max(0.0).sqrt()
            );
            assert!(
                (m_cv - m_plain).abs() <= 4.0 * se + 1e-4,
                "cv {m_cv} vs plain {m_plain} ± {se}"
            );
            // (Sobol points already make the plain diffuse sum nearly exact.)
            if !wall && view.is_some() {
                assert!(
                    v_cv.max(0.0).sqrt() <= 0.2 * v_plain.sqrt(),
                    "open floor: the control variate must remove the noise"
                );
            }
            if wall && view.is_some() {
                let open = fits[0].glossy_at(&ico, wo).unwrap().albedo.x as f64;
                assert!(m_plain < 0.9 * open, "plain {m_plain} vs open {open}");
            }
        }
    }
}

/// A UV sphere of `rings` × `segments` quads as OBJ text: a dense input mesh.
fn uv_sphere_obj(center: Vec3, radius: f32, rings: u32, segments: u32) -> String {
    let mut s = String::new();
    s += &format!("v {} {} {}\n", center.x, center.y + radius, center.z);
    for i in 1..rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            let p = center + radius * d;
            s += &format!("v {} {} {}\n", p.x, p.y, p.z);
        }
    }
    s += &format!("v {} {} {}\n", center.x, center.y - radius, center.z);
    let ring = |i: u32, j: u32| 2 + (i - 1) * segments + j % segments;
    let bottom = 2 + (rings - 1) * segments;
    for j in 0..segments {
        s += &format!("f 1 {} {}\n", ring(1, j + 1), ring(1, j));
        s += &format!(
            "f {bottom} {} {}\n",
            ring(rings - 1, j),
            ring(rings - 1, j + 1)
        );
        for i in 1..rings - 1 {
            let (a, b) = (ring(i, j), ring(i, j + 1));
            let (c, d) = (ring(i + 1, j), ring(i + 1, j + 1));
            s += &format!("f {a} {b} {d}\nf {a} {d} {c}\n");
        }
    }
    s
}

/// Issue 57: a dense glossy mesh above the vertex budget before any refinement
/// (a 1,060-vertex sphere, budget 600) on a floor quad of four vertices under a
/// constant sky. The old budget counted every vertex, so the floor was neither
/// tessellated nor refined and the sphere's contact shadow was missing (before
/// the fix: 1,064 → 1,064 vertices, 0 iterations, no floor vertex in the
/// shadow, RMSE 30.0 % of the shadow's mean). The budget now counts added
/// vertices: the shadow is refined and its RMSE is within 8 % of its mean
/// (measured 3.1 %: 1,349 → 1,680 vertices, 115 floor vertices in the shadow) against the path tracer's direct + one bounce at 128 spp.
#[test]
fn a_dense_mesh_leaves_the_budget_to_the_floor_shadow() {
    let dir = temp_dir("glossy_dense");
    let (center, radius) = (Vec3::new(0.0, 0.5, 0.0), 0.5);
    std::fs::write(
        dir.join("sphere.obj"),
        uv_sphere_obj(center, radius, 24, 46),
    )
    .unwrap();
    let scene_path = dir.join("dense.toml");
    std::fs::write(
        &scene_path,
        r#"
[camera]
from = [0, 1.6, 2.4]
to = [0, 0.2, 0]
fov = 40
resolution = [48, 36]

[materials.floor]
type = "blinn_phong"
kd = [0.5, 0.5, 0.5]
ks = [0.05, 0.05, 0.05]
exponent = 4

[materials.ball]
type = "blinn_phong"
kd = [0.2, 0.18, 0.15]
ks = [0.6, 0.6, 0.6]
exponent = 48

[[shapes]]
type = "quad"
corner = [-2, 0, 2]
edge_u = [4, 0, 0]
edge_v = [0, 0, -4]
material = "floor"

[[shapes]]
type = "mesh"
file = "sphere.obj"
material = "ball"
smooth_normals = true

[environment]
type = "constant"
radiance = [1, 1, 1]
"#,
    )
    .unwrap();
    let scene = gradtrace::scene::load(&scene_path).unwrap();
    let accel = gradtrace::accel::Accel::build(&scene.meshes, &scene.spheres);
    let settings = Settings {
        samples: 16,
        diffuse_samples: 64,
        fit_samples: 1024,
        max_angular_level: 1,
        batch: 50,
        max_vertices: 600,
        ..Settings::default()
    };
    let sphere_vertices = scene.meshes[1].positions.len();
    assert!(sphere_vertices > settings.max_vertices, "{sphere_vertices}");
    let t = glossy::precompute(&scene, &accel, &settings, &|_, _, _| {}).unwrap();
    // Sky blocked by the sphere at a floor point: its cosine-weighted fraction
    // over a Fibonacci set of directions.
    let blocked = |p: Vec3| {
        let n = 256;
        let hits = (0..n)
            .filter(|&k| {
                let u = (k as f32 + 0.5) / n as f32;
                let phi = k as f32 * 2.399_963;
                let (r, y) = (u.sqrt(), (1.0 - u).sqrt());
                let d = Vec3::new(r * phi.cos(), y, r * phi.sin());
                let ray = gradtrace::math::Ray::new(p + Vec3::Y * 1e-3, d);
                accel.intersect(&ray).is_some()
            })
            .count();
        hits as f32 / n as f32
    };
    let floor = scene.meshes[0].material;
    let shadow_vertices = t
        .mesh
        .vertices
        .iter()
        .filter(|v| v.material == floor && blocked(v.position) > 0.1)
        .count();
    let floor_vertices = t
        .mesh
        .vertices
        .iter()
        .filter(|v| v.material == floor)
        .count();
    // Preview and path tracer (direct + one bounce, what the transfer holds).
    let env = PrefilteredEnv::new(scene.environment.as_ref().unwrap());
    let preview = glossy::render_supersampled(&t, &env, &scene, &accel, &scene.camera, 2);
    let ropts = gradtrace::render::RenderOptions {
        spp: Some(128),
        max_depth: Some(3),
        ..Default::default()
    };
    let reference = gradtrace::render::render(&scene, &accel, &ropts, &|_, _| {})
        .unwrap()
        .beauty;
    // The shadow region: pixels whose centre sees the floor where the sphere
    // blocks more than a tenth of the sky.
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let (mut se, mut sum, mut n) = (0.0f64, 0.0f64, 0usize);
    for i in 0..w * h {
        let ray = cam.generate_ray(Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5));
        let Some(hit) = accel.intersect(&ray) else {
            continue;
        };
        let on_floor = matches!(
            hit.prim,
            gradtrace::accel::PrimRef::Triangle { mesh: 0, .. }
        );
        if !on_floor || blocked(ray.origin + ray.dir * hit.t) <= 0.1 {
            continue;
        }
        assert!(preview[i].is_finite());
        se += f64::from((preview[i] - reference[i]).length_squared()) / 3.0;
        sum += f64::from(reference[i].element_sum()) / 3.0;
        n += 1;
    }
    let rel = (se / n as f64).sqrt() / (sum / n as f64);
    eprintln!(
        "{} → {} vertices ({} iterations), floor {floor_vertices}, in its shadow {shadow_vertices}; \
         shadow: {n} pixels, RMSE {:.1} % of its mean",
        t.stats.vertices_initial,
        t.stats.vertices_final,
        t.stats.iterations,
        100.0 * rel
    );
    assert!(n > 40, "the shadow covers {n} pixels");
    assert!(t.stats.iterations > 0, "no refinement");
    assert!(
        shadow_vertices >= 100,
        "{shadow_vertices} floor vertices in the shadow"
    );
    assert!(rel <= 0.08, "shadow RMSE {:.1} % of its mean", 100.0 * rel);
}

/// The cache leaves out lobes of zero weight (a 4-bit mask per slice, 12 bytes
/// per lobe written): its exact length says so, and the transfer read back
/// renders the same image bit for bit.
#[test]
fn cache_leaves_out_empty_lobes_and_renders_the_same() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/glossy/cube_floor.toml");
    let scene = gradtrace::scene::load(&path).unwrap();
    let accel = gradtrace::accel::Accel::build(&scene.meshes, &scene.spheres);
    let settings = Settings {
        samples: 8,
        diffuse_samples: 16,
        fit_samples: 512,
        max_angular_level: 1,
        initial_edge_fraction: 0.25,
        batch: 20,
        max_vertices: 100,
        ..Settings::default()
    };
    let t = glossy::precompute(&scene, &accel, &settings, &|_, _, _| {}).unwrap();
    let key = "test key";
    let bytes = t.encode(key);
    let lobes = || t.vertices.iter().flat_map(|v| v.glossy.iter().flatten());
    let empty = lobes()
        .filter(|l| l.kappa_alpha[1..].iter().all(|h| h & 0x7fff == 0))
        .count();
    let written = lobes().count() - empty;
    assert!(empty > 0 && written > 0, "{empty} empty, {written} written");
    let header = 8 + 4 + key.len() + 8 + 12 + 4 + 4 * t.stats.angular_levels.len() + 4;
    let per_vertex: usize = t
        .vertices
        .iter()
        .map(|v| 12 + 112 + v.glossy.len().div_ceil(2))
        .sum();
    assert_eq!(
        bytes.len(),
        header + 4 * t.mesh.split_log.len() + 4 + per_vertex + 12 * written
    );
    let back = glossy::Transfer::decode(&bytes, key, &scene, &settings).unwrap();
    let env = PrefilteredEnv::new(scene.environment.as_ref().unwrap());
    let a = glossy::render(&t, &env, &scene, &accel, &scene.camera);
    let b = glossy::render(&back, &env, &scene, &accel, &scene.camera);
    assert!(a == b, "the cached transfer renders another image");
    // A cut-short file is a miss, not a panic.
    assert!(glossy::Transfer::decode(&bytes[..bytes.len() - 1], key, &scene, &settings).is_none());
}
