//! `preview shadow-field` and `preview glossy` from the command line: preview.json
//! holds the shared figures (`pipeline::preview::figures`), each a finite number or
//! `null` with `null_reason` saying why, never a placeholder; the speed-up with the
//! precompute amortised lies between the one-frame and the per-frame one; the
//! summary line says the same in words. Tiny scenes, so each run takes seconds.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn temp_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("preview_figures_{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `gradtrace preview ARGS`; returns stdout and preview.json.
fn preview(args: &[&str], out: &Path) -> (String, Value) {
    let run = Command::new(env!("CARGO_BIN_EXE_gradtrace"))
        .arg("preview")
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let json = std::fs::read_to_string(out.join("preview.json")).unwrap();
    (
        String::from_utf8_lossy(&run.stdout).into_owned(),
        serde_json::from_str(&json).unwrap(),
    )
}

/// Every number in the JSON, with its key.
fn numbers<'a>(v: &'a Value, key: &str, out: &mut Vec<(String, &'a Value)>) {
    match v {
        Value::Object(m) => m.iter().for_each(|(k, x)| numbers(x, k, out)),
        Value::Array(a) => a.iter().for_each(|x| numbers(x, key, out)),
        Value::Number(_) => out.push((key.to_string(), v)),
        _ => {}
    }
}

/// The shared figures: present, finite or null with a reason; returns whether
/// the speed-ups are numbers.
fn check_figures(j: &Value) -> bool {
    for key in [
        "precompute_s",
        "frame_s",
        "reference_spp",
        "reference_spp_max",
        "reference_s",
        "reference_noise_rmse",
        "path_tracer_noise_exponent",
    ] {
        assert!(
            j[key].as_f64().is_some_and(f64::is_finite),
            "{key}: {}",
            j[key]
        );
    }
    assert!(j["bias_resolved"].is_boolean());
    assert!(j["speedup_with_precompute"]["frames"].as_u64() == Some(100));
    let nullable = [
        &j["rmse_bias"],
        &j["path_tracer_spp_equal_error"],
        &j["path_tracer_s_equal_error"],
        &j["speedup_per_frame"],
        &j["speedup_one_frame"],
        &j["speedup_with_precompute"]["value"],
    ];
    for v in nullable {
        assert!(
            v.is_null() || v.as_f64().is_some_and(|x| x.is_finite() && x >= 0.0),
            "{v}"
        );
    }
    let any_null = nullable.iter().any(|v| v.is_null());
    assert_eq!(
        any_null,
        j["null_reason"].as_str().is_some_and(|r| !r.is_empty()),
        "a null needs its reason, a reason a null: {j:#}"
    );
    // No placeholder anywhere (the old 1e12 spp and the 1.4e11× speed-ups).
    let mut all = Vec::new();
    numbers(j, "", &mut all);
    for (k, v) in all {
        let x = v.as_f64().unwrap();
        assert!(x.is_finite() && x.abs() < 1e9, "{k} = {x}");
    }
    let speedups = j["speedup_per_frame"]
        .as_f64()
        .zip(j["speedup_one_frame"].as_f64());
    if let (Some((per_frame, one)), Some(amortised)) =
        (speedups, j["speedup_with_precompute"]["value"].as_f64())
    {
        assert!(j["precompute_s"].as_f64().unwrap() > 0.0);
        assert!(
            one < amortised && amortised < per_frame,
            "one frame {one}, amortised {amortised}, per frame {per_frame}"
        );
        return true;
    }
    false
}

const LAMBERT_BALL_ON_FLOOR: &str = r#"
[camera]
from = [0, 1.2, 3]
to = [0, 0.3, 0]
fov = 40
resolution = [24, 18]

[materials.m]
type = "lambert"
albedo = [0.6, 0.6, 0.6]

[[shapes]]
name = "ball"
type = "sphere"
center = [0, 0.5, 0]
radius = 0.5
material = "m"

[[shapes]]
name = "floor"
type = "quad"
corner = [-3, 0, 3]
edge_u = [6, 0, 0]
edge_v = [0, 0, -6]
material = "m"
"#;

#[test]
fn shadow_field_figures_hold_with_and_without_light() {
    let dir = temp_dir("shadow_field");
    // Lit by a sphere light and the sky: figures, or null with a reason.
    let lit = dir.join("lit.toml");
    std::fs::write(
        &lit,
        format!(
            "{LAMBERT_BALL_ON_FLOOR}\n[[shapes]]\nname = \"lamp\"\ntype = \"sphere\"\n\
             center = [1.5, 2.5, 1]\nradius = 0.3\nmaterial = \"m\"\nemission = [8, 8, 8]\n\
             [environment]\ntype = \"constant\"\nradiance = [0.3, 0.3, 0.3]\n"
        ),
    )
    .unwrap();
    let lit = lit.to_str().unwrap();
    let (stdout, j) = preview(
        &[
            "shadow-field",
            lit,
            "--reference-spp",
            "16",
            "--reference-spp-max",
            "256",
        ],
        &dir.join("lit"),
    );
    eprintln!("{stdout}{j:#}");
    assert_eq!(j["method"], "shadow-field");
    let numbers = check_figures(&j);
    assert_eq!(
        numbers,
        stdout.contains("the path tracer's speed per frame"),
        "{stdout}"
    );
    // Issue 54, defect 19: no light, a black image — null and a reason, and
    // words in the summary line, not 4.6e11.
    let dark = dir.join("dark.toml");
    std::fs::write(&dark, LAMBERT_BALL_ON_FLOOR).unwrap();
    let (stdout, j) = preview(&["shadow-field", dark.to_str().unwrap()], &dir.join("dark"));
    assert!(!check_figures(&j));
    assert!(j["speedup_per_frame"].is_null(), "{j:#}");
    assert!(j["null_reason"].as_str().unwrap().contains("black"));
    assert!(
        stdout.contains("no speed-up at equal error: the path-traced reference is black"),
        "{stdout}"
    );
    // A cap below what resolves the bias: unresolved, without a number.
    let (stdout, j) = preview(
        &[
            "shadow-field",
            lit,
            "--reference-spp",
            "1",
            "--reference-spp-max",
            "1",
        ],
        &dir.join("capped"),
    );
    if j["bias_resolved"] == false {
        assert!(j["rmse_bias"].is_null() && j["speedup_per_frame"].is_null());
        assert!(stdout.contains("unresolved"), "{stdout}");
    }
    check_figures(&j);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn glossy_reports_the_same_figures() {
    let dir = temp_dir("glossy");
    let scene = dir.join("cube_floor.toml");
    let sky = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/envs/sky.hdr");
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/glossy/cube_floor.toml"),
    )
    .unwrap()
    .replace("resolution = [64, 64]", "resolution = [24, 24]")
    .replace("../../../scenes/envs/sky.hdr", sky.to_str().unwrap());
    std::fs::write(&scene, text).unwrap();
    let (stdout, j) = preview(
        &[
            "glossy",
            scene.to_str().unwrap(),
            "--max-vertices",
            "600",
            "--reference-spp",
            "16",
            "--reference-spp-max",
            "256",
        ],
        &dir.join("out"),
    );
    eprintln!("{stdout}{j:#}");
    assert_eq!(j["method"], "glossy-transfer");
    let numbers = check_figures(&j);
    assert_eq!(
        numbers,
        stdout.contains("the path tracer's speed per frame"),
        "{stdout}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
