//! `compare`'s cost modes, its cycles-adaptive+oidn baseline and its preview rows
//! (issues 56 and 57): `report.json` records the mode and both costs of every
//! run, the preview of a scene that suits it is a row scored against compare's
//! reference, and a scene that suits none gets no preview row and no error.

mod common;
use common::{temp_dir, BIN};
use gradtrace::accel::Accel;
use gradtrace::adaptive::Strategy;
use gradtrace::output::report::EqualCost;
use gradtrace::pipeline::compare::{compare, CompareOptions};
use std::path::Path;

fn compare_cli(dir: &Path, scene: &str, extra: &[&str]) -> serde_json::Value {
    let out = std::process::Command::new(BIN)
        .args(["compare", scene, "--width", "64", "--height", "48"])
        .args([
            "--spp",
            "4",
            "--reference-spp",
            "8",
            "--strategies",
            "gradient",
        ])
        .args(["--budgets", "0.25", "--quiet", "--out"])
        .arg(dir)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap()
}

/// A mirror ball on a diffuse floor under a rectangle light, no environment.
const MIRROR_BALL: &str = r#"
[camera]
from = [0, 1.5, 4]
to = [0, 0.4, 0]
fov = 40
resolution = [64, 48]

[materials.floor]
type = "lambert"
albedo = [0.6, 0.6, 0.6]

[materials.ball]
type = "mirror"
reflectance = [0.9, 0.9, 0.9]

[[shapes]]
type = "quad"
corner = [-3, 0, 3]
edge_u = [6, 0, 0]
edge_v = [0, 0, -6]
material = "floor"

[[shapes]]
type = "sphere"
center = [0, 0.5, 0]
radius = 0.5
material = "ball"

[[lights]]
type = "rect"
corner = [-0.5, 2.5, -0.5]
edge_u = [1, 0, 0]
edge_v = [0, 0, 1]
radiance = [20, 20, 20]
"#;

fn runs(json: &serde_json::Value) -> &Vec<serde_json::Value> {
    json["runs"].as_array().unwrap()
}

fn num(run: &serde_json::Value, key: &str) -> f64 {
    run[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} not a number: {run}"))
}

/// One thread, `--equal cpu`: the mode is recorded, every run has wall and CPU
/// seconds, CPU time is positive and (one thread) at most the wall time and not
/// far below it; a mirror sphere under a rectangle light (a delta lobe, no
/// environment) suits neither preview: no preview row, a note each, no error.
#[test]
fn cpu_mode_records_both_costs_and_unsuited_scenes_get_no_preview_row() {
    let dir = temp_dir("cpu-one-thread");
    let scene_dir = temp_dir("mirror-ball-scene");
    let scene = scene_dir.join("mirror_ball.toml");
    std::fs::write(&scene, MIRROR_BALL).unwrap();
    let json = compare_cli(
        &dir,
        scene.to_str().unwrap(),
        &["--equal", "cpu", "--threads", "1"],
    );
    assert_eq!(json["equal_cost"], "cpu");
    let (mut wall, mut cpu) = (0.0, 0.0);
    for run in runs(&json) {
        let (w, c) = (num(run, "wall_s"), num(run, "cpu_s"));
        assert!(c > 0.0 && w > 0.0, "{run}");
        // One worker thread: a run's CPU time cannot exceed its wall time (10 %
        // and 5 ms for the main thread's share and the clocks' readings).
        assert!(c <= 1.1 * w + 0.005, "CPU {c} s > wall {w} s: {run}");
        wall += w;
        cpu += c;
    }
    // And it is most of it on an idle machine; the lower bound is loose because
    // the test machine may run at a load of 10 on 2 cores (a thread then gets a
    // fifth of the wall time): a twentieth.
    println!("one thread: {cpu:.3} s CPU over {wall:.3} s wall");
    assert!(cpu >= wall / 20.0, "CPU {cpu} s ≪ wall {wall} s");
    assert!(runs(&json).iter().all(|r| r["kind"] != "preview"));
    let notes = json["notes"].to_string();
    for method in ["shadow-field", "glossy"] {
        assert!(
            notes.contains(&format!("No {method} preview row")),
            "{notes}"
        );
    }
    // The shadow field's reason: the mirror, not the (accepted) diffuse floor.
    assert!(notes.contains("is a mirror"), "{notes}");
    #[cfg(not(feature = "oidn"))]
    assert!(
        notes.contains("cycles-adaptive+oidn") && notes.contains("not in this report"),
        "{notes}"
    );
    #[cfg(feature = "oidn")]
    {
        let run = runs(&json)
            .iter()
            .find(|r| r["name"] == "cycles-adaptive+oidn")
            .expect("cycles-adaptive+oidn in an OIDN build");
        assert!(num(run, "rmse").is_finite() && num(run, "cpu_s") > 0.0);
    }
    std::fs::remove_dir_all(&dir).ok();
    std::fs::remove_dir_all(&scene_dir).ok();
}

/// `--equal cpu` on two threads: the uniform baseline is matched on the gradient
/// run's CPU seconds (its `time_vs_target`, in CPU seconds, within ±50 %: loose,
/// for a render of tens of milliseconds on a shared machine), and the CPU seconds
/// of a parallel render may exceed its wall seconds. Default: wall.
#[test]
fn cpu_mode_matches_the_baselines_on_cpu_seconds() {
    let dir = temp_dir("cpu-two-threads");
    let json = compare_cli(
        &dir,
        "scenes/spheres_table.toml",
        &["--equal", "cpu", "--threads", "2", "--no-previews"],
    );
    let find = |name: &str| runs(&json).iter().find(|r| r["name"] == name).unwrap();
    let (gradient, uniform) = (find("gradient"), find("uniform-all-pixels"));
    let ratio = num(uniform, "cpu_s") / num(gradient, "cpu_s");
    println!(
        "gradient {:.3} s CPU, uniform {:.3} s CPU ({ratio:.2}×), time_vs_target {}",
        num(gradient, "cpu_s"),
        num(uniform, "cpu_s"),
        uniform["time_vs_target"]
    );
    assert!((ratio - 1.0).abs() < 0.5, "{ratio}");
    assert!(
        (num(uniform, "time_vs_target") - (ratio - 1.0)).abs() < 1e-9,
        "time_vs_target is not in CPU seconds"
    );
    let dir = temp_dir("wall-default");
    let json = compare_cli(&dir, "scenes/spheres_table.toml", &["--no-previews"]);
    assert_eq!(json["equal_cost"], "wall");
    std::fs::remove_dir_all(&dir).ok();
}

/// A bad `--equal` is one `error:` line.
#[test]
fn a_bad_equal_mode_is_one_error_line() {
    let out = std::process::Command::new(BIN)
        .args(["compare", "scenes/cornell.toml", "--equal", "cycles"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error:") && err.contains("--equal") && err.contains("cpu"),
        "{err}"
    );
}

/// shadowfield_bunny (diffuse, a sphere light and a constant environment) gets a
/// `shadow-field` row: finite RMSE and FLIP against compare's reference, its
/// precompute apart from its frame time, and the precompute read from the cache
/// by a second compare. Cheap fields: a
/// 6×8 grid on 4 radii, 4² rays a sample.
#[test]
fn a_diffuse_scene_gets_a_shadow_field_row() {
    let dir = temp_dir("shadow-field-row");
    let scene = gradtrace::scene::load(Path::new("scenes/shadowfield_bunny.toml")).unwrap();
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let mut opts = CompareOptions::new(dir.clone());
    opts.strategies = vec![Strategy::Gradient];
    opts.budgets = vec![0.25];
    opts.spp = Some(2);
    opts.reference_spp = Some(8);
    opts.resolution = Some((32, 24));
    opts.equal = EqualCost::Cpu;
    opts.shadow_field = gradtrace::preview::shadow_field::Settings {
        n_theta: 6,
        n_phi: 8,
        n_radii: 4,
        rays: 4,
        self_rays: 4,
        pixel_samples: 1,
        ..Default::default()
    };
    let rows = compare(&scene, &accel, &opts, &|_| {}).unwrap();
    let row = rows
        .iter()
        .find(|r| r.name == "shadow-field")
        .expect("a shadow-field row");
    assert_eq!(row.kind, "preview");
    assert!(row.rmse.is_finite() && row.rmse > 0.0, "{row:?}");
    assert!(row.flip.is_finite());
    let precompute = row.precompute_s.unwrap();
    assert!(precompute > 0.0 && precompute.is_finite());
    assert!(row.wall_s > 0.0 && row.cpu_s > 0.0 && row.wall_s.is_finite());
    assert_eq!(row.precompute_cached, Some(false));
    assert!(rows.iter().all(|r| r.name != "glossy"), "lights: no glossy");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    let j = runs(&json)
        .iter()
        .find(|r| r["name"] == "shadow-field")
        .unwrap();
    assert!(num(j, "rmse") > 0.0 && num(j, "precompute_s") > 0.0 && num(j, "wall_s") > 0.0);
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(md.contains("| shadow-field | preview |"), "{md}");
    // The second compare reads the fields: same precompute seconds, same image.
    let again = compare(&scene, &accel, &opts, &|_| {}).unwrap();
    let row2 = again.iter().find(|r| r.name == "shadow-field").unwrap();
    assert_eq!(row2.precompute_cached, Some(true));
    assert_eq!(row2.precompute_s.map(|p| p > 0.0), Some(true));
    assert_eq!(row2.rmse, row.rmse);
    // --no-previews: no row.
    opts.previews = false;
    let none = compare(&scene, &accel, &opts, &|_| {}).unwrap();
    assert!(none.iter().all(|r| r.kind != "preview"));
    std::fs::remove_dir_all(&dir).ok();
}

/// A glossy mesh under an environment alone gets a `glossy` row, and a
/// shadow-field row too (it shades glossy receivers): finite RMSE against
/// compare's reference, its precompute apart. The transfer of tests/glossy.rs's small end-to-end run (≤ 3000
/// vertices, angular level 3).
#[test]
fn a_glossy_scene_gets_a_glossy_row() {
    let dir = temp_dir("glossy-row");
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/glossy/cube_floor.toml");
    let scene = gradtrace::scene::load(&path).unwrap();
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let mut opts = CompareOptions::new(dir.clone());
    opts.strategies = vec![Strategy::Gradient];
    opts.budgets = vec![0.25];
    opts.spp = Some(2);
    opts.reference_spp = Some(8);
    opts.resolution = Some((32, 24));
    opts.glossy = gradtrace::preview::glossy::Settings {
        samples: 32,
        diffuse_samples: 128,
        max_angular_level: 3,
        initial_edge_fraction: 0.25,
        batch: 20,
        max_vertices: 3000,
        ..Default::default()
    };
    opts.shadow_field = gradtrace::preview::shadow_field::Settings {
        n_theta: 6,
        n_phi: 8,
        n_radii: 4,
        rays: 4,
        self_rays: 4,
        pixel_samples: 1,
        ..Default::default()
    };
    let rows = compare(&scene, &accel, &opts, &|_| {}).unwrap();
    let row = rows
        .iter()
        .find(|r| r.name == "glossy")
        .expect("a glossy row");
    assert_eq!(row.kind, "preview");
    assert!(row.rmse.is_finite() && row.rmse > 0.0, "{row:?}");
    assert!(row.precompute_s.unwrap() > 0.0 && row.wall_s > 0.0 && row.cpu_s > 0.0);
    let sf = rows
        .iter()
        .find(|r| r.name == "shadow-field")
        .expect("a shadow-field row on a glossy scene");
    assert!(sf.rmse.is_finite() && sf.rmse > 0.0, "{sf:?}");
    std::fs::remove_dir_all(&dir).ok();
}
