//! The renderer as the quadtree's estimator: budgets are honoured, every
//! reconstructed pixel is finite, results do not depend on the thread count,
//! and the CLI writes the sample layers.

use gradtrace::accel::Accel;
use gradtrace::adaptive::{Settings, Strategy};
use gradtrace::pipeline::adaptive::render_adaptive;
use gradtrace::reconstruct::Interpolation;
use gradtrace::render::RenderOptions;
use std::path::Path;

fn small() -> RenderOptions {
    RenderOptions {
        spp: Some(4),
        resolution: Some((64, 48)),
        vis_samples: Some(4),
        ..Default::default()
    }
}

#[test]
fn every_strategy_renders_the_bundled_scene_within_budget() {
    let scene = gradtrace::scene::load(Path::new("scenes/spheres_table.toml")).unwrap();
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    for strategy in Strategy::ALL {
        let settings = Settings::new(strategy, 0.17);
        let out = render_adaptive(
            &scene,
            &accel,
            &small(),
            &settings,
            Interpolation::Gradient,
            &|_, _| {},
        )
        .unwrap();
        let expected = (0.17f32 * 64.0 * 48.0).round() as usize;
        assert_eq!(out.samples.samples.len(), expected, "{}", strategy.name());
        assert!(
            out.reconstruction.image.iter().all(|c| c.is_finite()),
            "{}",
            strategy.name()
        );
        assert_eq!(
            out.reconstruction.density.iter().sum::<f32>() as usize,
            expected
        );
    }
}

#[test]
fn adaptive_render_is_identical_for_any_thread_count() {
    let scene = gradtrace::scene::load(Path::new("scenes/three_spheres_env.toml")).unwrap();
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let settings = Settings::new(Strategy::Gradient, 0.1);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                render_adaptive(
                    &scene,
                    &accel,
                    &small(),
                    &settings,
                    Interpolation::Gradient,
                    &|_, _| {},
                )
                .unwrap()
            })
    };
    let (a, b) = (run(1), run(3));
    assert_eq!(a.samples.samples.len(), b.samples.samples.len());
    assert!(a
        .reconstruction
        .image
        .iter()
        .zip(&b.reconstruction.image)
        .all(|(x, y)| x.to_array() == y.to_array()));
}

#[test]
fn cli_writes_sample_layers() {
    let dir = std::env::temp_dir().join(format!("gradtrace-adaptive-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let exr = dir.join("a.exr");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_gradtrace"))
        .args([
            "render",
            "scenes/three_spheres_env.toml",
            "--strategy",
            "gradient",
            "--budget",
            "0.1",
        ])
        .args([
            "--width", "48", "--height", "36", "--spp", "2", "--quiet", "--out",
        ])
        .arg(&exr)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = gradtrace::output::read_exr(&exr).unwrap();
    let density = img.channel("samples.density").unwrap();
    let mask = img.channel("samples.Y").unwrap();
    let n: f32 = density.data.iter().sum();
    assert_eq!(n as usize, (0.1f32 * 48.0 * 36.0).round() as usize);
    assert!(mask.data.iter().all(|&m| m == 0.0 || m == 1.0));
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_gradtrace"))
        .args([
            "render",
            "scenes/three_spheres_env.toml",
            "--strategy",
            "gradiant",
            "--quiet",
            "--out",
        ])
        .arg(dir.join("b.exr"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        !bad.status.success() && err.contains("gradient") && err.lines().count() == 1,
        "{err}"
    );
    assert!(!dir.join("b.exr").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// `compare` end to end on a tiny image: the reference is cached under its content
/// key, every strategy × budget runs, the baselines and 1%-grid runs, the report
/// files; a second run reuses the reference.
#[test]
fn compare_writes_the_report_and_caches_the_reference() {
    use gradtrace::pipeline::compare::{compare, CompareOptions};
    let dir = std::env::temp_dir().join(format!("gradtrace-compare-{}", std::process::id()));
    let scene = gradtrace::scene::load(Path::new("scenes/three_spheres_env.toml")).unwrap();
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let mut opts = CompareOptions::new(dir.clone());
    opts.strategies = vec![Strategy::Uniform, Strategy::Gradient];
    opts.budgets = vec![0.1, 0.25];
    opts.spp = Some(2);
    opts.reference_spp = Some(8);
    opts.resolution = Some((96, 72));
    opts.vis_samples = Some(4);
    let rows = compare(&scene, &accel, &opts, &|_| {}).unwrap();
    // full + 2×2 adaptive + 2×(uniform-all-pixels, cycles-adaptive, gradient-domain,
    // gradient-domain-adaptive, and oidn-uniform, cycles-adaptive+oidn and gradient+oidn where the build has
    // OIDN) + 2 interpolation runs + the shadow-field preview (diffuse spheres
    // under a sky).
    let baselines = 4 + 3 * usize::from(gradtrace::denoise::available());
    assert_eq!(rows.len(), 1 + 4 + 2 * baselines + 2 + 1);
    assert_eq!(rows.last().unwrap().name, "shadow-field");
    for name in [
        "uniform-all-pixels",
        "cycles-adaptive",
        "gradient-domain",
        "gradient-domain-adaptive",
    ] {
        assert_eq!(rows.iter().filter(|r| r.name == name).count(), 2, "{name}");
    }
    assert!(rows
        .iter()
        .all(|r| r.rmse.is_finite() && r.flip.is_finite() && r.relmse_trimmed <= r.relmse));
    for f in ["report.html", "report.json", "report.md"] {
        assert!(dir.join(f).exists(), "{f}");
    }
    let json = || -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
    };
    assert_eq!(json()["reference"]["reused"], false);
    let key = json()["reference"]["cache_key"]
        .as_str()
        .unwrap()
        .to_string();
    assert!(dir.join(format!("reference-{}.exr", &key[..16])).exists());
    // Sec. 8 is also scored on the ground plane, away from the silhouettes.
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(
        md.contains("Sec. 8, 1% grid on the largest surface"),
        "{md}"
    );
    // A second run reuses the cached reference (same rows for the same seeds).
    let again = compare(&scene, &accel, &opts, &|_| {}).unwrap();
    assert_eq!(rows[1].rmse, again[1].rmse);
    assert_eq!(json()["reference"]["reused"], true);
    // The reference has random numbers of its own: at the runs' own spp it is a
    // second, independent render, not a copy of the full render (RMSE 0).
    opts.reference_spp = Some(2);
    opts.strategies = vec![Strategy::Uniform];
    opts.budgets = vec![0.25];
    let rows = compare(&scene, &accel, &opts, &|_| {}).unwrap();
    assert_eq!(rows[0].name, "full");
    assert!(rows[0].rmse > 1e-3, "full vs reference: {}", rows[0].rmse);
    std::fs::remove_dir_all(&dir).ok();
}

/// A changed scene is never scored against a stale reference: doubling the
/// environment's radiance changes the cache key, so the reference is rendered
/// anew and the full render's error stays that of noise, not of the edit.
#[test]
fn an_edited_scene_is_never_scored_against_a_stale_reference() {
    use gradtrace::pipeline::compare::{compare, CompareOptions};
    let dir = std::env::temp_dir().join(format!("gradtrace-stale-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string("scenes/validation/env_constant.toml").unwrap();
    // Its meshes, beside it as in the repository.
    std::fs::create_dir_all(dir.join("models")).unwrap();
    for e in std::fs::read_dir("scenes/validation/models").unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, dir.join("models").join(p.file_name().unwrap())).unwrap();
    }
    let scene_path = dir.join("scene.toml");
    let mut opts = CompareOptions::new(dir.join("report"));
    opts.strategies = vec![Strategy::Gradient];
    opts.budgets = vec![0.25];
    opts.spp = Some(2);
    opts.reference_spp = Some(16);
    opts.resolution = Some((48, 36));
    let run = |text: &str| {
        std::fs::write(&scene_path, text).unwrap();
        let scene = gradtrace::scene::load(&scene_path).unwrap();
        let accel = Accel::build(&scene.meshes, &scene.spheres);
        let rows = compare(&scene, &accel, &opts, &|_| {}).unwrap();
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("report/report.json")).unwrap())
                .unwrap();
        (rows[0].rmse, json["reference"]["reused"].as_bool().unwrap())
    };
    let (rmse0, reused0) = run(&text);
    assert!(!reused0);
    assert!(run(&text).1, "unchanged inputs reuse the reference");
    // Double every radiance value of the environment table.
    let edited = double_environment(&text);
    assert_ne!(
        edited, text,
        "the scene has an [environment] radiance to edit"
    );
    let (rmse1, reused1) = run(&edited);
    println!("full-render RMSE: original {rmse0:.3e}, edited {rmse1:.3e}");
    assert!(!reused1, "an edited scene must re-render its reference");
    // Against the stale reference the error would be that of the edit (the whole
    // image's brightness); against the new one it is the noise of the same samples
    // at twice the radiance: exactly twice the original's (rendering is linear in
    // the emitted radiance).
    assert!((rmse1 / rmse0 - 2.0).abs() < 1e-3, "{rmse1} vs {rmse0}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The scene text with the `[environment]` table's `radiance` doubled.
fn double_environment(text: &str) -> String {
    let mut in_env = false;
    text.lines()
        .map(|l| {
            if l.trim_start().starts_with('[') {
                in_env = l.trim() == "[environment]";
            }
            match (in_env, l.split_once('=')) {
                (true, Some((k, v))) if k.trim() == "radiance" => {
                    let nums: Vec<f32> = v
                        .trim()
                        .trim_matches(|c| c == '[' || c == ']')
                        .split(',')
                        .map(|x| x.trim().parse::<f32>().unwrap() * 2.0)
                        .collect();
                    format!("radiance = {nums:?}")
                }
                _ => l.to_string(),
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// `vis_samples = 0` keeps the shading terms but samples lights by points and
/// drops the visibility term; any other count keeps it where shadows exist.
#[test]
fn zero_vis_samples_drops_only_the_visibility_term() {
    let scene = gradtrace::scene::load(Path::new("scenes/three_spheres_env.toml")).unwrap();
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let run = |n: u32| {
        let opts = RenderOptions {
            gradients: true,
            vis_samples: Some(n),
            ..small()
        };
        gradtrace::render::render(&scene, &accel, &opts, &|_, _| {})
            .unwrap()
            .gradients
            .unwrap()
    };
    let (points, lines) = (run(0), run(8));
    assert!(points.vis.iter().all(|&v| v == 0.0));
    assert!(lines.vis.iter().filter(|&&v| v > 0.0).count() > 100);
    assert!(points.grad_u.iter().all(|g| g.is_finite()));
}

/// Issue 54: a small rect light tilted 7°, 0.3 above a floor, seen from above (the
/// camera sees its black back), a sphere under it and a wall behind. A pixel
/// sample on the light's back is a shading point on the light's own plane: its
/// φ-line reached the light at distance 0 (the one-sided test passed on rounding),
/// and the gradient lanes of that light point were 0/0, which the C1
/// reconstruction spread into NaN pixels (`--interpolation linear` ignores
/// gradients, `--vis-samples 0` samples points, whose density check rejects it).
const ISSUE_54: &str = r#"
[camera]
from = [0, 0.35, 1.2]
to = [0, 0.1, 0]
fov = 40
resolution = [128, 96]

[materials.white]
type = "lambert"
albedo = [0.7, 0.7, 0.7]

[materials.red]
type = "lambert"
albedo = [0.7, 0.2, 0.2]

[[shapes]]
type = "quad"
corner = [-2, 0, 2]
edge_u = [4, 0, 0]
edge_v = [0, 0, -4]
material = "white"

[[shapes]]
type = "quad"
corner = [-2, 0, -0.6]
edge_u = [4, 0, 0]
edge_v = [0, 2, 0]
material = "white"

[[shapes]]
type = "sphere"
center = [0.02, 0.06, 0.0]
radius = 0.06
material = "red"

[[lights]]
type = "rect"
size = [0.12, 0.12]
transform = { rotate = [[1, 0, 0, 90], [0, 0, 1, 7]], translate = [0, 0.3, 0] }
radiance = [40, 40, 40]
"#;

/// The gradients of the pixel samples on the light's back, where the line of the
/// issue met the light at distance 0: every one finite (before the fix, 14 of the
/// 121 were NaN).
#[test]
fn gradients_on_the_back_of_a_rect_light_are_finite() {
    use gradtrace::math::Vec2;
    use gradtrace::render::lights::LightSet;
    use gradtrace::render::path::{LineConfig, PathTracer};
    use gradtrace::render::point::PointEstimator;
    let scene = gradtrace::scene::load_from_str(ISSUE_54, Path::new("tests/issue54.toml")).unwrap();
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let lights = LightSet::build(&scene);
    let est = PointEstimator {
        tracer: PathTracer {
            scene: &scene,
            accel: &accel,
            lights: &lights,
            max_depth: 8,
            rr_depth: 5,
            // The adaptive pipeline's lines: 4 rays each.
            lines: Some(LineConfig {
                n_theta: 4,
                refine: 0,
                gate: 1.0,
            }),
            far_light: None,
        },
        camera: &scene.camera,
        spp: 16,
        gradient_spp: 16,
        seed: 0,
        timing: Default::default(),
    };
    let light_id = scene.object_names.len() as u32;
    let (mut on_light, mut bad) = (0, 0);
    for j in 0..96 * 4 {
        for i in 0..128 * 4 {
            let p = Vec2::new(i as f32 + 0.125, j as f32 + 0.125) * 0.25;
            if est.surface_at(p).map(|s| s.object_id) != Some(light_id) {
                continue;
            }
            on_light += 1;
            let e = est.estimate(p);
            bad += !(e.grad_u.is_finite() && e.grad_v.is_finite() && e.radiance.is_finite()) as u32;
        }
    }
    println!("{on_light} points on the light's back, {bad} of them with a non-finite gradient");
    assert!(
        on_light > 100,
        "the camera sees the light's back: {on_light}"
    );
    assert_eq!(bad, 0);
}

/// The issue's symptom, end to end: NaN pixels near the light (28 at 128×96
/// `uniform` 0.17, 4 at 96×72 `gradient` 0.1 before the fix).
#[test]
fn the_back_of_a_tilted_rect_light_reconstructs_finite() {
    let scene = gradtrace::scene::load_from_str(ISSUE_54, Path::new("tests/issue54.toml")).unwrap();
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    for ((w, h), strategy, budget) in [
        ((128, 96), Strategy::Uniform, 0.17),
        ((96, 72), Strategy::Gradient, 0.1),
    ] {
        let opts = RenderOptions {
            spp: Some(16),
            resolution: Some((w, h)),
            ..Default::default()
        };
        let settings = Settings::new(strategy, budget);
        let out = render_adaptive(
            &scene,
            &accel,
            &opts,
            &settings,
            Interpolation::Gradient,
            &|_, _| {},
        )
        .unwrap();
        let bad = out
            .reconstruction
            .image
            .iter()
            .filter(|c| !c.is_finite())
            .count();
        assert_eq!(
            bad,
            0,
            "{w}x{h} {} at {budget}: non-finite pixels",
            strategy.name()
        );
    }
}
