//! Seeded generated scenes (`gradtrace::scene::generate`): every one parses, and
//! every output the renderer makes of them is finite — every `--strategy` × both
//! interpolations × two budgets through the library, and a plain, a `--gradients`
//! and one adaptive render of each through the binary, every EXR layer read back.
//! Issue 54 (a NaN on a scene nobody had tried) is the kind of failure this catches:
//! with its fix reverted, 7 of these 96 scenes fail (non-finite samples, NaN pixels,
//! and the binary's `cannot write output … (NaN)`). A failing seed's scene is kept
//! on disk, so it is its own reproducer.

use gradtrace::accel::Accel;
use gradtrace::adaptive::{Settings, Strategy};
use gradtrace::output::read_exr;
use gradtrace::pipeline::adaptive::render_adaptive;
use gradtrace::reconstruct::{reconstruct, Interpolation};
use gradtrace::render::RenderOptions;
use gradtrace::scene::generate::{scene_toml, Options};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_gradtrace");

/// Scenes each render test runs (seeds 0..SCENES): about 15 s in all on 2 cores.
const SCENES: u64 = 96;
const BUDGETS: [f32; 2] = [0.1, 0.17];

fn options() -> Options {
    Options {
        // Absolute, so that the scene files may live in a temporary folder.
        asset_dir: Some(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes").into()),
        resolution: [48, 36],
        spp: 4,
        ..Options::default()
    }
}

fn temp_dir(what: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gradtrace-{what}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Writes the scene of `seed` to `dir` and returns its path.
fn write_scene(dir: &Path, seed: u64) -> PathBuf {
    let path = dir.join(format!("generated-{seed}.toml"));
    std::fs::write(&path, scene_toml(seed, &options())).unwrap();
    path
}

/// Fails listing every failure, with the scene text of the first.
fn report(failures: &[String], dir: &Path) {
    if failures.is_empty() {
        let _ = std::fs::remove_dir_all(dir);
        return;
    }
    panic!(
        "{} failures (scenes kept in {}):\n{}",
        failures.len(),
        dir.display(),
        failures.join("\n")
    );
}

#[test]
fn generated_scenes_parse_and_are_deterministic() {
    let diffuse = Options {
        diffuse_only: true,
        ..options()
    };
    for seed in 0..100 {
        for opts in [&options(), &diffuse] {
            let text = scene_toml(seed, opts);
            assert_eq!(text, scene_toml(seed, opts), "seed {seed}");
            if let Err(e) = gradtrace::scene::load_from_str(&text, Path::new("generated.toml")) {
                panic!("seed {seed}: {e}\n{text}");
            }
        }
    }
    assert_ne!(scene_toml(0, &options()), scene_toml(1, &options()));
}

/// What the generator promises: the close, tiny, grazing and edge-on lights, the
/// models, bumps and skies do turn up within the seeds the render tests use.
#[test]
fn generated_scenes_cover_what_the_generator_promises() {
    let texts: Vec<String> = (0..SCENES).map(|s| scene_toml(s, &options())).collect();
    let count = |needle: &str| texts.iter().filter(|t| t.contains(needle)).count();
    for needle in [
        "type = \"rect\"",
        "type = \"sphere\"\ncenter",
        "type = \"quad\"\nsize",
        "cow.obj",
        "teapot.obj",
        "type = \"blinn_phong\"",
        "type = \"cook_torrance\"",
        "type = \"mirror\"",
        "[bumps.",
        "type = \"constant\"",
        "type = \"gaussian_sky\"",
        "type = \"image\"",
        "90.0]], translate",
    ] {
        assert!(
            count(needle) > 0,
            "no scene of the first {SCENES} has {needle}"
        );
    }
    assert!(
        count("[environment]") < texts.len(),
        "every scene has a sky"
    );
}

/// The diffuse option keeps to lambert materials and sphere lights, no bumps.
#[test]
fn diffuse_only_has_lambert_materials_and_sphere_lights() {
    let opts = Options {
        diffuse_only: true,
        ..options()
    };
    for seed in 0..50 {
        let text = scene_toml(seed, &opts);
        let scene = gradtrace::scene::load_from_str(&text, Path::new("g.toml")).unwrap();
        assert!(scene
            .materials
            .iter()
            .all(|m| matches!(m, gradtrace::brdf::Material::Lambert { .. })));
        assert!(scene
            .meshes
            .iter()
            .all(|m| m.emission == gradtrace::math::Vec3::ZERO));
        assert!(scene
            .spheres
            .iter()
            .any(|s| s.emission != gradtrace::math::Vec3::ZERO));
        assert!(scene.bumps.is_empty());
    }
}

/// Every strategy × both interpolations × two budgets on every scene: the
/// reconstruction, the density plane and the samples themselves are finite, and no
/// run panics. (Both interpolations are rebuilt from one sample set, as the
/// pipeline's reconstruction sees the same samples for either.)
#[test]
fn every_adaptive_mode_is_finite_on_generated_scenes() {
    let dir = temp_dir("generated-lib");
    let mut failures = Vec::new();
    for seed in 0..SCENES {
        let path = write_scene(&dir, seed);
        let scene = match gradtrace::scene::load(&path) {
            Ok(s) => s,
            Err(e) => {
                failures.push(format!("seed {seed}: {e}"));
                continue;
            }
        };
        let accel = Accel::build(&scene.meshes, &scene.spheres);
        let opts = RenderOptions::default();
        for strategy in Strategy::ALL {
            for budget in BUDGETS {
                let what = format!("seed {seed} {} {budget}", strategy.name());
                let run = catch_unwind(AssertUnwindSafe(|| {
                    let settings = Settings::new(strategy, budget);
                    let out = render_adaptive(
                        &scene,
                        &accel,
                        &opts,
                        &settings,
                        Interpolation::Gradient,
                        &|_, _| {},
                    )
                    .map_err(|e| e.to_string())?;
                    let linear = reconstruct(&out.samples, Interpolation::Linear)
                        .map_err(|e| e.to_string())?;
                    let mut bad = Vec::new();
                    for (name, rec) in [("gradient", &out.reconstruction), ("linear", &linear)] {
                        let n = rec.image.iter().filter(|c| !c.is_finite()).count();
                        if n > 0 {
                            bad.push(format!("{name}: {n} non-finite pixels"));
                        }
                        if rec.density.iter().any(|d| !d.is_finite()) {
                            bad.push(format!("{name}: non-finite density"));
                        }
                    }
                    let samples = out
                        .samples
                        .samples
                        .iter()
                        .filter(|s| {
                            let v = &s.value;
                            !(v.radiance.is_finite()
                                && v.grad_u.is_finite()
                                && v.grad_v.is_finite()
                                && s.pos.is_finite())
                        })
                        .count();
                    if samples > 0 {
                        bad.push(format!("{samples} non-finite samples"));
                    }
                    if bad.is_empty() {
                        Ok(())
                    } else {
                        Err(bad.join(", "))
                    }
                }));
                match run {
                    Ok(Ok(())) => {}
                    Ok(Err(e)) => failures.push(format!("{what}: {e}")),
                    Err(_) => failures.push(format!("{what}: panicked")),
                }
            }
        }
    }
    report(&failures, &dir);
}

/// Runs the binary on `scene` with `flags`; an error line, or any non-finite
/// value in any layer of the EXR it wrote.
fn binary_render(scene: &Path, flags: &[&str], exr: &Path) -> Result<(), String> {
    let out = Command::new(BIN)
        .arg("render")
        .arg(scene)
        .args(["--quiet", "--threads", "2"])
        .args(flags)
        .arg("--out")
        .arg(exr)
        .output()
        .map_err(|e| e.to_string())?;
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).trim().to_string());
    }
    let img = read_exr(exr).map_err(|e| e.to_string())?;
    let bad: Vec<String> = img
        .channels
        .iter()
        .filter(|c| c.data.iter().any(|x| !x.is_finite()))
        .map(|c| c.name.clone())
        .collect();
    if bad.is_empty() {
        Ok(())
    } else {
        Err(format!("non-finite layers {bad:?}"))
    }
}

/// Through the binary users run: a plain render, a `--gradients` render (4 rays
/// per line, as the adaptive pipeline uses), a gradient-domain render (L1 or L2,
/// with or without `--dense-adaptive`) and one adaptive render per scene, the
/// adaptive runs cycling through every strategy × interpolation × budget.
#[test]
fn the_binary_writes_finite_layers_for_generated_scenes() {
    let dir = temp_dir("generated-bin");
    let mut failures = Vec::new();
    let combos: Vec<(Strategy, &str, f32)> = Strategy::ALL
        .iter()
        .flat_map(|&s| {
            ["gradient", "linear"]
                .into_iter()
                .flat_map(move |i| BUDGETS.map(|b| (s, i, b)))
        })
        .collect();
    for seed in 0..SCENES {
        let path = write_scene(&dir, seed);
        let (s, interp, budget) = combos[seed as usize % combos.len()];
        let budget = budget.to_string();
        // The gradient-domain solves, each with and without dense adaptive sampling.
        let solve = ["poisson-l1", "poisson-l2"][seed as usize % 2];
        let mut domain = vec!["--reconstruct", solve];
        if seed % 4 >= 2 {
            domain.push("--dense-adaptive");
        }
        let runs: [(&str, Vec<&str>); 4] = [
            ("plain", vec![]),
            ("gradients", vec!["--gradients", "--vis-samples", "4"]),
            ("gradient-domain", domain),
            (
                "adaptive",
                vec![
                    "--strategy",
                    s.name(),
                    "--interpolation",
                    interp,
                    "--budget",
                    &budget,
                ],
            ),
        ];
        for (name, flags) in runs {
            let exr = dir.join(format!("generated-{seed}-{name}.exr"));
            if let Err(e) = binary_render(&path, &flags, &exr) {
                failures.push(format!("seed {seed} {name} {flags:?}: {e}"));
            }
        }
    }
    assert!(combos.len() as u64 <= SCENES, "every combination runs");
    report(&failures, &dir);
}
