//! Pins the pixels: every bundled scene, in every mode (path, direct, `--gradients`,
//! `--strategy` with both interpolations), rendered small by the `gradtrace` binary,
//! with a checksum per EXR channel compared against the table below. A refactor
//! that changes any bit of any layer fails here.
//!
//! When a change is *meant* to change pixels, rewrite the table with
//! `GRADTRACE_PIN_WRITE=1 cargo test --release --test pixels_pinned` and say in the
//! commit which layers moved and why. The table's hash keys cached references
//! (`build.rs`), so rewriting it re-renders them.

use gradtrace::output::read_exr;
use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_gradtrace");

const SCENES: &[&str] = &[
    "scenes/cornell.toml",
    "scenes/spheres_table.toml",
    "scenes/spheres_table_far.toml",
    "scenes/three_spheres_env.toml",
    "scenes/objects_bumpy.toml",
    "scenes/bunny_env.toml",
    "scenes/validation/cornell.toml",
    "scenes/validation/env_constant.toml",
    "scenes/validation/env_image.toml",
    "scenes/validation/spheres.toml",
];

/// (mode name, extra flags). Small images and few samples keep the whole table
/// under a minute; every code path of the renderer still runs.
const MODES: &[(&str, &[&str])] = &[
    ("path", &["--integrator", "path", "--spp", "4"]),
    ("direct", &["--integrator", "direct", "--spp", "4"]),
    (
        "gradients",
        &["--gradients", "--vis-samples", "4", "--spp", "4"],
    ),
    (
        "strategy-gradient",
        &["--strategy", "gradient", "--budget", "0.3", "--spp", "4"],
    ),
    (
        "strategy-variance-linear",
        &[
            "--strategy",
            "variance",
            "--budget",
            "0.2",
            "--interpolation",
            "linear",
            "--spp",
            "4",
        ],
    ),
];

/// FNV-1a over the f32 bit patterns: any change of any bit changes it.
fn fnv1a(data: &[f32]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for v in data {
        for b in v.to_bits().to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Renders one scene in one mode and returns "scene mode channel=hash" lines.
fn checksums(scene: &str, mode: &str, flags: &[&str], dir: &Path) -> Vec<String> {
    let exr = dir.join(format!("{}-{mode}.exr", scene.replace(['/', '.'], "_")));
    let out = Command::new(BIN)
        .arg("render")
        .arg(root().join(scene))
        .args(["--width", "40", "--height", "30", "--seed", "7", "--quiet"])
        .args(flags)
        .arg("--out")
        .arg(&exr)
        .output()
        .expect("the binary runs");
    assert!(
        out.status.success(),
        "{scene} {mode}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = read_exr(&exr).unwrap();
    let mut lines: Vec<String> = img
        .channels
        .iter()
        .map(|c| format!("{scene} {mode} {}={:016x}", c.name, fnv1a(&c.data)))
        .collect();
    lines.sort();
    lines
}

#[test]
fn every_scene_and_mode_renders_the_pinned_pixels() {
    let dir = std::env::temp_dir().join(format!("gradtrace-pins-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut got = Vec::new();
    for scene in SCENES {
        for (mode, flags) in MODES {
            got.extend(checksums(scene, mode, flags, &dir));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    if std::env::var_os("GRADTRACE_PIN_WRITE").is_some() {
        let table = root().join("tests/pixels_pinned.txt");
        std::fs::write(&table, format!("{}\n", got.join("\n"))).unwrap();
        println!("wrote {} checksums to {}", got.len(), table.display());
        return;
    }
    let want: Vec<&str> = PINNED.lines().filter(|l| !l.trim().is_empty()).collect();
    let mismatched: Vec<String> = got
        .iter()
        .filter(|g| !want.contains(&g.as_str()))
        .cloned()
        .collect();
    assert!(
        mismatched.is_empty() && got.len() == want.len(),
        "{} of {} channel checksums differ from the pinned table ({} pinned); first: {:?}",
        mismatched.len(),
        got.len(),
        want.len(),
        mismatched.iter().take(8).collect::<Vec<_>>()
    );
}

/// Cached references are keyed on the table's hash (`build.rs`): the key must be
/// this very table's, or an edited table would leave stale references in use.
#[test]
fn the_reference_cache_epoch_is_the_hash_of_this_table() {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in PINNED.as_bytes() {
        h ^= *b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    let want = format!("{} pins-{h:016x}", env!("CARGO_PKG_VERSION"));
    assert_eq!(gradtrace::pipeline::PIXEL_EPOCH, want);
}

/// The pinned table. `build.rs` hashes this file into the pixel epoch that keys
/// cached references, so it lives apart from the code.
const PINNED: &str = include_str!("pixels_pinned.txt");
