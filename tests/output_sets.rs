//! Output sets (issue 54, defects 11 and 12): a preview's images and
//! `preview.json`, a report's pages, assets and `--keep-exr` EXRs all carry one
//! render id, every EXR the provenance `render` writes; `check_set` confirms a
//! complete set and catches one split by an interruption between the members'
//! renames and the index's; two compares into one folder never mix assets.
#![cfg(target_os = "linux")]

use gradtrace::accel::Accel;
use gradtrace::adaptive::Strategy;
use gradtrace::output::atomic::{check_set, SetState, RENDER_ID_KEY, STOP_BEFORE_INDEX_ENV};
use gradtrace::output::read_exr_with_header;
use gradtrace::output::report::ASSET_DIR;
use gradtrace::pipeline::compare::{compare, CompareOptions};
use gradtrace::pipeline::merge::attr;
use gradtrace::pipeline::preview::glossy::GlossyOptions;
use gradtrace::pipeline::preview::shadow_field::{self, ShadowFieldOptions};
use gradtrace::preview::glossy::Settings as GlossySettings;
use gradtrace::preview::shadow_field::Settings;
use std::path::{Path, PathBuf};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gradtrace-sets-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn index(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The index is consistent, and every EXR it lists carries its id and the
/// provenance attributes; returns the id.
fn assert_consistent(index_path: &Path) -> String {
    let id = match check_set(index_path).unwrap() {
        SetState::Consistent(id) => id,
        other => panic!("{}: {other:?}", index_path.display()),
    };
    let json = index(index_path);
    assert_eq!(json["render_id"], id.as_str());
    let dir = index_path.parent().unwrap();
    let files: Vec<&str> = json["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    assert!(!files.is_empty());
    let exrs: Vec<&&str> = files.iter().filter(|f| f.ends_with(".exr")).collect();
    assert!(!exrs.is_empty(), "no EXR in {files:?}");
    for f in exrs {
        assert_provenance(&dir.join(f), Some(&id));
    }
    id
}

/// The EXR's header has the render id (`want`, or any) and the provenance.
fn assert_provenance(exr: &Path, want: Option<&str>) {
    let (_, header) = read_exr_with_header(exr).unwrap();
    let id = header
        .get(RENDER_ID_KEY)
        .unwrap_or_else(|| panic!("{}: no id", exr.display()));
    if let Some(w) = want {
        assert_eq!(id, w, "{}", exr.display());
    }
    for key in [
        attr::VERSION,
        attr::COMMAND,
        attr::SCENE_SHA256,
        attr::SPP,
        attr::RENDER_TIME_S,
    ] {
        assert!(
            header.get(key).is_some_and(|v| !v.is_empty()),
            "{}: no {key}",
            exr.display()
        );
    }
}

fn shadow_opts(dir: &Path, frames: Option<u32>, size: (u32, u32)) -> ShadowFieldOptions {
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/shadowfield_deform.toml"
    );
    let mut opts = ShadowFieldOptions::new(scene);
    opts.out_dir = dir.to_path_buf();
    opts.quiet = true;
    opts.frames = frames;
    opts.resolution = Some(size);
    opts.reference_spp = Some(16);
    opts.reference_spp_max = Some(32);
    opts.settings = Settings {
        rays: 12,
        self_rays: 6,
        ..Settings::default()
    };
    opts
}

#[test]
fn shadow_field_preview_is_one_set() {
    let dir = temp_dir("sf");
    let s = shadow_field::run(&shadow_opts(&dir, Some(2), (48, 36))).unwrap();
    assert_eq!(s.frames, Some(2));
    let json = dir.join("preview.json");
    let id = assert_consistent(&json);
    // Two frames, an EXR and a PNG each.
    assert_eq!(index(&json)["files"].as_array().unwrap().len(), 4);
    // A file of another run under a listed name is caught.
    let other = temp_dir("sf-other");
    shadow_field::run(&shadow_opts(&other, None, (40, 30))).unwrap();
    std::fs::copy(
        other.join("shadowfield_deform.png"),
        dir.join("shadowfield_deform-f001.png"),
    )
    .unwrap();
    match check_set(&json).unwrap() {
        SetState::Mismatched { id: i, file, found } => {
            assert_eq!(i, id);
            assert!(file.ends_with("shadowfield_deform-f001.png"));
            assert!(found.is_some_and(|f| f != id));
        }
        s => panic!("not detected: {s:?}"),
    }
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&other);
}

#[test]
fn glossy_preview_is_one_set() {
    let dir = temp_dir("glossy");
    let mut opts = GlossyOptions::new(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/glossy/cube_floor.toml"),
    );
    opts.out_dir = dir.clone();
    opts.quiet = true;
    opts.orbit = Some(1);
    opts.resolution = Some((48, 36));
    opts.reference_spp = Some(16);
    opts.reference_spp_max = Some(32);
    opts.settings = GlossySettings {
        samples: 16,
        diffuse_samples: 32,
        max_angular_level: 2,
        initial_edge_fraction: 0.25,
        batch: 20,
        max_vertices: 800,
        ..GlossySettings::default()
    };
    gradtrace::pipeline::preview::glossy::run(&opts).unwrap();
    let json = dir.join("preview.json");
    let id = assert_consistent(&json);
    let files = index(&json)["files"].as_array().unwrap().clone();
    // EXR, preview, error, reference, levels, one orbit view, the stats page.
    assert_eq!(files.len(), 7, "{files:?}");
    assert!(files.iter().any(|f| f == "orbit_000.png"));
    let page = std::fs::read_to_string(dir.join("cube_floor_stats.md")).unwrap();
    assert!(page.contains(&format!("render_id: {id}")));
    // The cached reference carries an id and provenance of its own.
    let cached: Vec<PathBuf> = walk(&dir)
        .into_iter()
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("reference-"))
        })
        .collect();
    assert!(!cached.is_empty());
    for p in cached {
        assert_provenance(&p, None);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

fn compare_opts(dir: &Path, budgets: Vec<f64>) -> CompareOptions {
    let mut opts = CompareOptions::new(dir.to_path_buf());
    opts.strategies = vec![Strategy::Gradient];
    opts.budgets = budgets;
    opts.spp = Some(2);
    opts.reference_spp = Some(4);
    opts.resolution = Some((24, 16));
    opts.keep_exr = true;
    opts.command = "gradtrace compare (test)".into();
    opts
}

fn asset_folders(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir.join(ASSET_DIR))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Every `src`/`href` and Markdown link of the pages points into `id`'s folder.
fn assert_links_only(dir: &Path, id: &str) {
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    let own = format!("{ASSET_DIR}/{id}/");
    for (text, sep) in [(&html, "src=\""), (&html, "href=\""), (&md, "](")] {
        let links: Vec<&str> = text.split(sep).skip(1).collect();
        assert!(!links.is_empty());
        for l in links {
            assert!(l.starts_with(&own), "{sep}{}", &l[..l.len().min(60)]);
        }
    }
}

#[test]
fn compare_is_one_set_and_two_compares_do_not_mix_assets() {
    let dir = temp_dir("compare");
    let scene = gradtrace::scene::load(Path::new("scenes/cornell.toml")).unwrap();
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    compare(&scene, &accel, &compare_opts(&dir, vec![0.25]), &|_| {}).unwrap();
    let first = assert_consistent(&dir.join("report.json"));
    assert_eq!(asset_folders(&dir), vec![first.clone()]);
    assert_links_only(&dir, &first);
    // The cached reference: an id and provenance of its own.
    let refs: Vec<PathBuf> = walk(&dir)
        .into_iter()
        .filter(|p| {
            let n = p.file_name().unwrap().to_string_lossy().into_owned();
            n.starts_with("reference-") && n.ends_with(".exr")
        })
        .collect();
    assert_eq!(refs.len(), 1);
    assert_provenance(&refs[0], None);
    // A stale folder (a killed run's) and flat assets of the layout before ids.
    let stale = dir.join(ASSET_DIR).join("0123456789abcdef0123456789abcdef");
    std::fs::create_dir_all(&stale).unwrap();
    std::fs::write(stale.join("reference.jpg"), b"old").unwrap();
    std::fs::write(dir.join(ASSET_DIR).join("reference.jpg"), b"old").unwrap();
    // A second compare with other budgets: another id, and only its assets.
    compare(&scene, &accel, &compare_opts(&dir, vec![0.1, 0.3]), &|_| {}).unwrap();
    let second = assert_consistent(&dir.join("report.json"));
    assert_ne!(first, second);
    assert_eq!(asset_folders(&dir), vec![second.clone()]);
    assert_links_only(&dir, &second);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A compare stopped (by the test hook, as a kill would) after its members are
/// in place and before its index is: the old `report.json` now lists files of
/// the new run, and `check_set` says so.
#[test]
fn a_compare_stopped_before_its_index_is_detected() {
    let dir = temp_dir("stopped");
    let run = |budgets: &str, stop: bool| {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_gradtrace"));
        cmd.args([
            "compare",
            "scenes/cornell.toml",
            "--width",
            "24",
            "--height",
            "16",
        ])
        .args([
            "--spp",
            "2",
            "--reference-spp",
            "4",
            "--strategies",
            "gradient",
        ])
        .args(["--budgets", budgets, "--keep-exr", "--quiet", "--out"])
        .arg(&dir);
        if stop {
            cmd.env(STOP_BEFORE_INDEX_ENV, "1");
        }
        cmd.output().unwrap()
    };
    let out = run("0.25", false);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let first = assert_consistent(&dir.join("report.json"));
    let out = run("0.3", true);
    assert_eq!(
        out.status.code(),
        Some(86),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(index(&dir.join("report.json"))["render_id"], first.as_str());
    match check_set(&dir.join("report.json")).unwrap() {
        SetState::Mismatched { id, found, .. } => {
            assert_eq!(id, first);
            assert!(found.is_some_and(|f| f != first));
        }
        s => panic!("split set not detected: {s:?}"),
    }
    // The next complete compare sweeps the stopped run's folder.
    let out = run("0.3", false);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let last = assert_consistent(&dir.join("report.json"));
    assert_eq!(asset_folders(&dir), [last]);
    let _ = std::fs::remove_dir_all(&dir);
}
