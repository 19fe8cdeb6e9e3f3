//! `--gradients` estimates the first hit's direct light by φ-lines of shadow rays
//! instead of the plain light samples; its radiance must be the plain render's
//! within noise, on every bundled scene and at every line length. A z-test on the
//! means of each channel over the whole image and over horizontal bands, with
//! each render's own `variance` layer (the variance of the pixel mean; pixels are
//! independent, so a band mean's variance is their sum over N²).
//!
//! This caught a 0.84× (0.36× in the band under the light) radiance on
//! spheres_table, whose table is a radius-100 sphere: the lines' shadow rays left
//! it by a default error bound smaller than the sphere's own and re-hit it.

use gradtrace::output::read_exr;
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

#[test]
fn gradient_renders_have_the_plain_radiance_on_every_bundled_scene() {
    let dir = std::env::temp_dir().join(format!("gradtrace-gradrad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut failures = Vec::new();
    for scene in SCENES {
        let path = root().join(scene);
        let plain = render(&path, &dir, "plain", "3", &["--spp", "64"]);
        for n in ["1", "4", "32"] {
            let spp = if n == "32" { "16" } else { "64" };
            let grad = render(
                &path,
                &dir,
                "grad",
                "11",
                &["--gradients", "--vis-samples", n, "--spp", spp],
            );
            let (z, at) = worst_z(&grad, &plain);
            println!("{scene} --vis-samples {n}: worst |z| {z:.2} ({at})");
            if z > Z_MAX {
                failures.push(format!("{scene} --vis-samples {n}: |z| {z:.1} at {at}"));
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(failures.is_empty(), "biased radiance: {failures:#?}");
}
