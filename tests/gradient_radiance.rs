//! `--gradients` estimates the first hit's direct light by φ-lines of shadow rays
//! instead of the plain light samples; its radiance must be the plain render's
//! within noise, on every bundled scene and at every line length. A z-test on the
//! means of each channel over the whole image and over horizontal bands, with
//! each render's own `variance` layer (the variance of the pixel mean; pixels are
//! independent, so a band mean's variance is their sum over N²).
//!
//! The same on generated scenes (`scene::generate`): random geometry, lights of
//! every size, tilt and distance, every material, with and without a sky.
//!
//! This caught a 0.84× (0.36× in the band under the light) radiance on
//! spheres_table, whose table is a radius-100 sphere: the lines' shadow rays left
//! it by a default error bound smaller than the sphere's own and re-hit it.

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

/// (rays per line, spp) of the gradient renders; the plain render takes 256 spp.
/// Enough samples that the heavy tails of the generated scenes (mirrors,
/// exponents up to 10⁴, sphere lights of radius 0.02) are in the means and
/// variances: one ray per line has no MIS with the BSDF, and on generated seed
/// 14 (exponent 5,061 reflecting a tiny sphere light) its variance is ~5,000×
/// the plain render's: |z| 21 at 64 spp, 0.6 at 1,024 (two seeds: 1.94 ± 0.13,
/// 1.85 ± 0.12 against 1.866). Every |z| above 2.2 at fewer spp was checked
/// unbiased at 1,024–2,048 spp.
const LINES: [(&str, &str); 3] = [("1", "512"), ("4", "128"), ("32", "64")];

/// Horizontal bands the image is cut into, besides the whole image: a bias
/// confined to one region (a shadow, the area under a light) shows there.
const BANDS: usize = 4;

/// |z| above this fails. The renders are deterministic (fixed seeds), so the
/// test cannot flake; 5 leaves room for the heavy tails of a few hundred
/// statistics at low spp while a real bias of a few per cent is far beyond it.
const Z_MAX: f64 = 5.0;

struct Planes {
    width: usize,
    height: usize,
    /// (mean, variance of the mean) per channel R, G, B.
    rgb: [(Vec<f32>, Vec<f32>); 3],
}

/// Renders `scene` small with `extra` flags. The plain and the gradient renders
/// take different seeds: with the same one they would share their indirect
/// light's random numbers, correlate, and make every z too small.
fn render(scene: &Path, dir: &Path, name: &str, seed: &str, extra: &[&str]) -> Planes {
    let exr = dir.join(format!("{name}.exr"));
    let out = Command::new(BIN)
        .arg("render")
        .arg(scene)
        .args(["--width", "48", "--height", "32", "--seed", seed, "--quiet"])
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
    let plane = |name: &str| {
        img.channels
            .iter()
            .find(|c| c.name == name)
            .unwrap_or_else(|| panic!("{}: no channel {name}", exr.display()))
            .data
            .clone()
    };
    Planes {
        width: img.width,
        height: img.height,
        rgb: ["R", "G", "B"].map(|c| (plane(c), plane(&format!("variance.{c}")))),
    }
}

/// The largest |z| of (a − b) over channels × (whole image, bands), with where.
fn worst_z(a: &Planes, b: &Planes) -> (f64, String) {
    let mut worst = (0.0, String::new());
    let rows = |band: Option<usize>| match band {
        None => 0..a.height,
        Some(k) => k * a.height / BANDS..(k + 1) * a.height / BANDS,
    };
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        for band in std::iter::once(None).chain((0..BANDS).map(Some)) {
            let (mut sa, mut sb, mut va, mut vb, mut n) = (0.0, 0.0, 0.0, 0.0, 0.0f64);
            for y in rows(band) {
                for x in 0..a.width {
                    let i = y * a.width + x;
                    sa += a.rgb[c].0[i] as f64;
                    sb += b.rgb[c].0[i] as f64;
                    va += a.rgb[c].1[i] as f64;
                    vb += b.rgb[c].1[i] as f64;
                    n += 1.0;
                }
            }
            let sd = (va + vb).sqrt() / n;
            if sd == 0.0 {
                assert_eq!(sa, sb, "{name} {band:?}: noise-free yet different");
                continue;
            }
            let z = (sa - sb) / n / sd;
            if z.abs() > worst.0 {
                worst = (
                    z.abs(),
                    format!(
                        "{name} {}: means {:.5} vs {:.5}",
                        band.map_or("whole image".into(), |k| format!("band {}/{BANDS}", k + 1)),
                        sa / n,
                        sb / n
                    ),
                );
            }
        }
    }
    worst
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Renders `scene` plainly and with `--gradients` at each line length, and
/// names each comparison whose worst |z| is above [`Z_MAX`].
fn biased_line_lengths(path: &Path, dir: &Path, label: &str) -> Vec<String> {
    let mut failures = Vec::new();
    let plain = render(path, dir, "plain", "3", &["--spp", "256"]);
    for (n, spp) in LINES {
        let grad = render(
            path,
            dir,
            "grad",
            "11",
            &["--gradients", "--vis-samples", n, "--spp", spp],
        );
        let (z, at) = worst_z(&grad, &plain);
        println!("{label} --vis-samples {n}: worst |z| {z:.2} ({at})");
        if z > Z_MAX {
            failures.push(format!("{label} --vis-samples {n}: |z| {z:.1} at {at}"));
        }
    }
    failures
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gradtrace-gradrad-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn gradient_renders_have_the_plain_radiance_on_every_bundled_scene() {
    let dir = temp_dir("bundled");
    let mut failures = Vec::new();
    for scene in SCENES {
        failures.extend(biased_line_lengths(&root().join(scene), &dir, scene));
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "biased radiance: {failures:#?}");
}

/// Generated scenes the test renders (each three times with `--gradients`).
const GENERATED: u64 = 24;

#[test]
fn gradient_renders_have_the_plain_radiance_on_generated_scenes() {
    let dir = temp_dir("generated");
    let opts = Options {
        asset_dir: Some(root().join("scenes").to_string_lossy().into_owned()),
        ..Options::default()
    };
    let mut failures = Vec::new();
    for seed in 0..GENERATED {
        let path = dir.join(format!("scene-{seed}.toml"));
        std::fs::write(&path, scene_toml(seed, &opts)).unwrap();
        failures.extend(biased_line_lengths(
            &path,
            &dir,
            &format!("generated seed {seed}"),
        ));
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "biased radiance: {failures:#?}");
}
