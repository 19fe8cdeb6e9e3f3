//! `--gradients` adds layers and changes no other pixel: its radiance is the plain
//! render's light-sampled estimate, and the gradient stage reads its own random
//! numbers (a hashed dimension set past the path's, `render::path::GATE_DIM`), so
//! with the same seed every plain layer — R, G, B, the variance and the AOVs — is
//! the plain render's, bit for bit. On every bundled scene and on generated scenes
//! (`scene::generate`: random geometry, lights of every size, tilt and distance,
//! every material, with and without a sky), at several line lengths and gates.
//!
//! Until issue 53 the lines also estimated the radiance; this test then was a
//! z-test of the two estimates, and caught a 0.84× radiance on spheres_table
//! (the lines' shadow rays re-hit the radius-100 table).

use gradtrace::output::read_exr;
use gradtrace::scene::generate::{scene_toml, Options};
use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_gradtrace");

/// Every bundled scene that `--gradients` takes (the previews' scenes too: they
/// are path-traceable scenes like any other).
const SCENES: &[&str] = &[
    "scenes/cornell.toml",
    "scenes/spheres_table.toml",
    "scenes/spheres_table_far.toml",
    "scenes/three_spheres_env.toml",
    "scenes/objects_bumpy.toml",
    "scenes/bunny_env.toml",
    "scenes/glossy_bunny.toml",
    "scenes/glossy_teapot.toml",
    "scenes/shadowfield_bunny.toml",
    "scenes/shadowfield_deform.toml",
    "scenes/validation/cornell.toml",
    "scenes/validation/env_constant.toml",
    "scenes/validation/env_image.toml",
    "scenes/validation/spheres.toml",
];

/// The gradient settings each scene is rendered with besides the plain render.
const GRADIENTS: [&[&str]; 3] = [
    &["--gradients", "--vis-samples", "0"],
    &["--gradients"],
    &[
        "--gradients",
        "--vis-samples",
        "16",
        "--vis-gate",
        "1",
        "--vis-refine",
        "2",
    ],
];

/// Renders `scene` small with `extra` flags; its channels by name.
fn render(scene: &Path, dir: &Path, extra: &[&str]) -> Vec<(String, Vec<f32>)> {
    let exr = dir.join("render.exr");
    let out = Command::new(BIN)
        .arg("render")
        .arg(scene)
        .args([
            "--width", "40", "--height", "30", "--spp", "4", "--seed", "5",
        ])
        .arg("--quiet")
        .args(extra)
        .arg("--out")
        .arg(&exr)
        .output()
        .expect("the binary runs");
    assert!(
        out.status.success(),
        "{}: {}",
        scene.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let img = read_exr(&exr).unwrap();
    img.channels.into_iter().map(|c| (c.name, c.data)).collect()
}

/// Every way the gradient renders of `path` differ from its plain render.
fn differences(path: &Path, dir: &Path, label: &str) -> Vec<String> {
    let plain = render(path, dir, &[]);
    let mut failures = Vec::new();
    for extra in GRADIENTS {
        let grad = render(path, dir, extra);
        let has_gradients = grad.iter().any(|(n, _)| n == "grad.u.R");
        if !has_gradients {
            failures.push(format!("{label} {extra:?}: no gradient layers"));
        }
        for (name, data) in &plain {
            match grad.iter().find(|(n, _)| n == name) {
                None => failures.push(format!("{label} {extra:?}: no {name}")),
                Some((_, g)) => {
                    let differ = data
                        .iter()
                        .zip(g)
                        .filter(|(a, b)| a.to_bits() != b.to_bits())
                        .count();
                    if differ > 0 {
                        failures.push(format!(
                            "{label} {extra:?}: {name} differs in {differ} of {} pixels",
                            data.len()
                        ));
                    }
                }
            }
        }
    }
    failures
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gradtrace-gradrad-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn gradient_renders_have_the_plain_pixels_on_every_bundled_scene() {
    let dir = temp_dir("bundled");
    let mut failures = Vec::new();
    for scene in SCENES {
        failures.extend(differences(&root().join(scene), &dir, scene));
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Generated scenes the test renders.
const GENERATED: u64 = 24;

#[test]
fn gradient_renders_have_the_plain_pixels_on_generated_scenes() {
    let dir = temp_dir("generated");
    let opts = Options {
        asset_dir: Some(root().join("scenes").to_string_lossy().into_owned()),
        ..Options::default()
    };
    let mut failures = Vec::new();
    for seed in 0..GENERATED {
        let path = dir.join(format!("scene-{seed}.toml"));
        std::fs::write(&path, scene_toml(seed, &opts)).unwrap();
        failures.extend(differences(&path, &dir, &format!("generated seed {seed}")));
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "{failures:#?}");
}
