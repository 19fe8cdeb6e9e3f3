//! The `gradtrace` binary: help text, one-line errors with status 1, outputs left
//! untouched by failed runs, and end-to-end renders of a tiny inline scene.

mod common;
use common::{run_in, temp_dir};
use gradtrace::output::read_exr;
use std::path::Path;
use std::process::Output;

/// A 16x12 white sphere in a uniform white environment, 2 spp.
const TINY_SCENE: &str = r#"
[camera]
from = [0, 0, 5]
to = [0, 0, 0]
up = [0, 1, 0]
fov = 40
resolution = [16, 12]
[render]
spp = 2
[materials.white]
type = "lambert"
albedo = [0.8, 0.8, 0.8]
[[shapes]]
type = "sphere"
center = [0, 0, 0]
radius = 1
material = "white"
[environment]
type = "constant"
radiance = [1, 1, 1]
"#;

/// Every entry below `dir`, relative and sorted.
fn tree(dir: &Path) -> Vec<String> {
    fn walk(base: &Path, d: &Path, out: &mut Vec<String>) {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            out.push(p.strip_prefix(base).unwrap().to_string_lossy().into_owned());
            if p.is_dir() {
                walk(base, &p, out);
            }
        }
    }
    let mut v = Vec::new();
    walk(dir, dir, &mut v);
    v.sort();
    v
}

/// A failed run: status 1, nothing on stdout, exactly one `error:` line on stderr
/// that contains `needle`.
fn assert_failed_with(out: &Output, needle: &str) {
    assert_eq!(out.status.code(), Some(1), "exit status");
    assert!(out.stdout.is_empty(), "nothing on stdout");
    let err = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "exactly one line on stderr: {err:?}");
    assert!(lines[0].starts_with("error: "), "{err:?}");
    assert!(
        lines[0].contains(needle),
        "{err:?} should mention {needle:?}"
    );
}

#[test]
fn render_help_documents_every_option() {
    let out = run_in(&std::env::temp_dir(), &["render", "--help"]);
    assert_eq!(out.status.code(), Some(0));
    let help = String::from_utf8_lossy(&out.stdout);
    for opt in [
        "<SCENE>",
        "--spp",
        "--max-depth",
        "--width",
        "--height",
        "--seed",
        "--threads",
        "--out",
        "--integrator",
        "path",
        "direct",
        "--no-aovs",
        "--gradients",
        "--quiet",
        "out/<scene-stem>.exr",
    ] {
        assert!(help.contains(opt), "render --help lacks {opt}");
    }
    let out = run_in(&std::env::temp_dir(), &["--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(help.contains("render") && help.contains("info"));
    let out = run_in(&std::env::temp_dir(), &["info", "--help"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stdout).contains("<SCENE>"));
}

/// No option's help states its default twice (clap adds `[default: …]` for a
/// `default_value`; a doc comment that says it too doubles it: issue 54, 20).
#[test]
fn no_help_states_a_default_twice() {
    let commands: [&[&str]; 7] = [
        &["render"],
        &["compare"],
        &["preview", "shadow-field"],
        &["preview", "glossy"],
        &["merge"],
        &["diff"],
        &["info"],
    ];
    for cmd in commands {
        let out = run_in(&std::env::temp_dir(), &[cmd, &["--help"]].concat());
        for line in String::from_utf8_lossy(&out.stdout).lines() {
            assert!(
                line.matches("[default:").count() <= 1,
                "{cmd:?} --help: {line}"
            );
        }
    }
}

#[test]
fn missing_scene_file_is_one_error_line_and_creates_nothing() {
    let dir = temp_dir("missing");
    let out = run_in(&dir, &["render", "no_such_scene.toml"]);
    assert_failed_with(&out, "no_such_scene.toml");
    assert!(tree(&dir).is_empty(), "nothing created: {:?}", tree(&dir));

    let out = run_in(&dir, &["info", "no_such_scene.toml"]);
    assert_failed_with(&out, "no_such_scene.toml");
    assert!(tree(&dir).is_empty());
}

#[test]
fn bad_arguments_are_one_error_line_with_status_1() {
    let dir = temp_dir("badargs");
    std::fs::write(dir.join("tiny.toml"), TINY_SCENE).unwrap();
    for (args, needle) in [
        (&["render", "tiny.toml", "--spp", "0"][..], "--spp"),
        (&["render", "tiny.toml", "--width", "8"][..], "--height"),
        (
            &["render", "tiny.toml", "--integrator", "bidir"][..],
            "bidir",
        ),
        (&["render", "tiny.toml", "--threads", "0"][..], "--threads"),
        (&["render", "tiny.toml", "--bogus"][..], "--bogus"),
        // Counts are bounded up front, options of the other preview refused and
        // negative tiles reach their own parser (issue 54, defects 3, 18, 19).
        (
            &["render", "tiny.toml", "--tile", "-1/2"][..],
            "expected K/N",
        ),
        (
            &["render", "tiny.toml", "--crop", "-1,0,4,4"][..],
            "x0,y0,x1,y1",
        ),
        (
            &["render", "tiny.toml", "--time-limit", "1e9"][..],
            "(0, 1e9)",
        ),
        (
            &["render", "tiny.toml", "--max-memory", "1e-9"][..],
            "1 MiB",
        ),
        (
            &[
                "render",
                "tiny.toml",
                "--gradients",
                "--vis-samples",
                "4294967295",
            ][..],
            "0..=1024",
        ),
        (
            &[
                "render",
                "tiny.toml",
                "--gradients",
                "--vis-refine",
                "4294967295",
            ][..],
            "0..=24",
        ),
        (
            &["compare", "tiny.toml", "--seeds", "1000000"][..],
            "1..=1000",
        ),
        (
            &[
                "preview",
                "shadow-field",
                "tiny.toml",
                "--frames",
                "4294967295",
            ][..],
            "0..=10000",
        ),
        (
            &["preview", "glossy", "tiny.toml", "--orbit", "4294967295"][..],
            "0..=3600",
        ),
        (
            &["preview", "glossy", "tiny.toml", "--frames", "2"][..],
            "--frames is an option of `preview shadow-field` only",
        ),
        (
            &["preview", "shadow-field", "tiny.toml", "--orbit", "2"][..],
            "--orbit is an option of `preview glossy` only",
        ),
        (&["render", "tiny.toml", "--out", "img.png"][..], "img.png"),
        // Every numeric flag is checked like its scene key (issue 18, defect 7 and 12).
        (
            &[
                "render",
                "tiny.toml",
                "--strategy",
                "gradient",
                "--budget",
                "-1",
            ][..],
            "--budget",
        ),
        (
            &[
                "render",
                "tiny.toml",
                "--strategy",
                "gradient",
                "--budget",
                "17",
            ][..],
            "(0, 16]",
        ),
        (
            &["render", "tiny.toml", "--far-light", "nan"][..],
            "--far-light",
        ),
        (
            &["render", "tiny.toml", "--max-depth", "0"][..],
            "--max-depth",
        ),
        (
            &["render", "tiny.toml", "--max-memory", "-2"][..],
            "--max-memory",
        ),
        (
            &[
                "render",
                "tiny.toml",
                "--strategy",
                "gradient",
                "--gradients",
            ][..],
            "--gradients",
        ),
        (
            &["compare", "tiny.toml", "--budgets", "0.1,-0.5"][..],
            "--budgets",
        ),
        // Defect 3: a run that cannot fit is refused before any work.
        (
            &[
                "render",
                "tiny.toml",
                "--width",
                "1000000",
                "--height",
                "1000000",
            ][..],
            "GiB",
        ),
        (
            &[
                "render",
                "tiny.toml",
                "--max-memory",
                "0.001",
                "--width",
                "2000",
                "--height",
                "2000",
            ][..],
            "--max-memory",
        ),
        (
            &[
                "render",
                "tiny.toml",
                "--strategy",
                "gradient",
                "--budget",
                "16",
                "--width",
                "2000",
                "--height",
                "2000",
                "--max-memory",
                "4",
            ][..],
            "GiB",
        ),
    ] {
        let out = run_in(&dir, args);
        assert_failed_with(&out, needle);
    }
    assert_eq!(tree(&dir), vec!["tiny.toml"]);
}

/// A scene whose BVH and shading tables would not fit is refused after it is
/// loaded and before they are built, naming the scene file; with the memory
/// they need it renders.
#[test]
fn a_scene_too_large_to_build_names_its_file() {
    let dir = temp_dir("bigmesh");
    // A 224 × 224 grid: 100,352 triangles, about 40 MB to build.
    write_grid_scene(&dir, 224);
    let small = ["--width", "2", "--height", "2", "--out", "out/big.exr"];
    let out = run_in(
        &dir,
        &[&["render", "big.toml", "--max-memory", "0.03"][..], &small].concat(),
    );
    assert_failed_with(
        &out,
        "big.toml: a 2x2 render of 100352 triangles needs about",
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("BVH"));
    assert_eq!(tree(&dir), vec!["big.toml", "grid.obj"]);
    let out = run_in(
        &dir,
        &[
            &["render", "big.toml", "--max-memory", "0.2", "--quiet"][..],
            &small,
        ]
        .concat(),
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A glossy preview whose transfer could not fit (here a vertex budget of four
/// billion: ~70 TB of view-dependent slices) is refused before its mesh is
/// split, naming the scene and the options that shrink it, and writes nothing.
/// Without the check it would split and trace until the allocator gave up.
#[test]
fn a_glossy_transfer_too_large_is_refused_up_front() {
    let dir = temp_dir("glossybig");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/glossy_teapot.toml");
    let start = std::time::Instant::now();
    let out = run_in(
        &dir,
        &[
            "preview",
            "glossy",
            scene,
            "--max-vertices",
            "4000000000",
            "--quiet",
            "--out",
            "preview",
        ],
    );
    assert_failed_with(
        &out,
        "glossy_teapot.toml: glossy preview: the transfer of up to",
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("view directions needs about"), "{err}");
    assert!(err.contains("lower --uniform or --max-vertices"), "{err}");
    assert!(start.elapsed().as_secs() < 30, "refused up front");
    assert!(tree(&dir).is_empty(), "{:?}", tree(&dir));
}

/// Writes `grid.obj` (an `n` × `n` grid, [`grid_obj`]) and `big.toml`, the
/// tiny scene with the grid in place of its sphere, into `dir`; returns the
/// OBJ's size in bytes.
fn write_grid_scene(dir: &Path, n: usize) -> usize {
    let obj = grid_obj(n);
    std::fs::write(dir.join("grid.obj"), &obj).unwrap();
    let scene = TINY_SCENE.replace(
        "type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1",
        "type = \"mesh\"\nfile = \"grid.obj\"",
    );
    assert!(scene.contains("grid.obj"));
    std::fs::write(dir.join("big.toml"), scene).unwrap();
    obj.len()
}

/// An OBJ of an `n` × `n` grid of quads (2n² triangles) in the plane y = 0.
fn grid_obj(n: usize) -> String {
    let mut obj = String::new();
    for j in 0..=n {
        for i in 0..=n {
            obj += &format!(
                "v {} 0 {}\n",
                i as f32 / n as f32 - 0.5,
                j as f32 / n as f32 - 0.5
            );
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i + 1;
            let (b, c) = (a + 1, a + n + 1);
            obj += &format!("f {a} {c} {b}\nf {b} {c} {}\n", c + 1);
        }
    }
    obj
}

/// `gradtrace ARGS` in `dir` under an address-space limit of `kib` KiB
/// (`ulimit -v`): past it every allocation fails, whatever memory is free.
#[cfg(target_os = "linux")]
fn run_limited(dir: &Path, kib: u64, args: &[&str]) -> Output {
    std::process::Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {kib} && exec \"$0\" \"$@\""))
        .arg(common::BIN)
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

/// An OBJ whose load would not fit is refused before it is read, naming the
/// scene's key and the OBJ: the memory available counts the address-space
/// limit, which `MemAvailable` does not show. Without the check, the load ran
/// out of memory halfway (before this check existed, an abort, status 134).
#[test]
#[cfg(target_os = "linux")]
fn an_obj_too_large_to_load_names_it() {
    let dir = temp_dir("bigobj");
    // 605,000 triangles: about 20 MB of text, ~120 MB to load; 100 MB allowed.
    let obj_bytes = write_grid_scene(&dir, 550);
    assert!(obj_bytes > 18 << 20, "{obj_bytes}");
    let out = run_limited(
        &dir,
        100_000,
        &["render", "big.toml", "--out", "out/big.exr"],
    );
    assert_failed_with(&out, "big.toml: shapes[0].file (line ");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("grid.obj: loading this 2"), "{err}");
    assert!(err.contains("MiB OBJ needs about 1"), "{err}");
    assert!(err.contains(" MiB available; simplify the mesh"), "{err}");
    assert_eq!(tree(&dir), vec!["big.toml", "grid.obj"]);
    // `--max-memory` counts for the load too (it reaches the loader through
    // `memory::limited`): refused under 50 MiB without any address-space limit.
    let out = run_in(
        &dir,
        &[
            "render",
            "big.toml",
            "--max-memory",
            "0.05",
            "--out",
            "out/big.exr",
        ],
    );
    assert_failed_with(&out, "big.toml: shapes[0].file (line ");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("more than the 51 MiB allowed by --max-memory"),
        "{err}"
    );
    assert_eq!(tree(&dir), vec!["big.toml", "grid.obj"]);
}

/// An allocation that fails anyway (here `--max-memory` lets through a render
/// the address-space limit cannot hold) ends the run with one line naming the
/// scene and status 1, not an abort, and leaves no file. `--quiet`: on a slow
/// machine the render runs past the progress log's first 5 s before the
/// allocation fails, and that log line is not what this test is about.
#[test]
#[cfg(target_os = "linux")]
fn running_out_of_memory_is_one_line_not_an_abort() {
    let dir = temp_dir("oom");
    std::fs::write(dir.join("tiny.toml"), TINY_SCENE).unwrap();
    let args = [
        "render",
        "tiny.toml",
        "--quiet",
        "--width",
        "20000",
        "--height",
        "20000",
        "--max-memory",
        "1000",
        "--out",
        "out/huge.exr",
    ];
    let out = run_limited(&dir, 1_000_000, &args);
    assert_failed_with(
        &out,
        "error: tiny.toml: out of memory while rendering (an allocation of ",
    );
    assert_eq!(tree(&dir), vec!["tiny.toml"]);
    // The same render within --max-memory's default (the memory available,
    // which the limit caps) is refused before it starts.
    let out = run_limited(&dir, 1_000_000, &args[..7]);
    assert_failed_with(&out, "a 20000x20000 render needs about");
}

/// An `--out` inside a regular file names that file (not "File exists").
#[test]
fn out_under_a_regular_file_names_the_file() {
    let dir = temp_dir("outfile");
    std::fs::write(dir.join("tiny.toml"), TINY_SCENE).unwrap();
    std::fs::write(dir.join("plain"), b"x").unwrap();
    let out = run_in(&dir, &["render", "tiny.toml", "--out", "plain/sub/img.exr"]);
    assert_failed_with(&out, "plain: cannot write output: is a file, not a folder");
    assert_eq!(tree(&dir), vec!["plain", "tiny.toml"]);
}

#[test]
fn failed_run_does_not_overwrite_existing_outputs() {
    let dir = temp_dir("keep");
    std::fs::create_dir(dir.join("out")).unwrap();
    std::fs::write(dir.join("out/broken.exr"), b"old exr").unwrap();
    std::fs::write(dir.join("out/broken.png"), b"old png").unwrap();
    // Not TOML at all: fails in the parser, whatever its final form.
    std::fs::write(dir.join("broken.toml"), "[camera\nfrom = ").unwrap();
    let out = run_in(&dir, &["render", "broken.toml"]);
    assert_failed_with(&out, "broken.toml");
    assert_eq!(
        std::fs::read(dir.join("out/broken.exr")).unwrap(),
        b"old exr"
    );
    assert_eq!(
        std::fs::read(dir.join("out/broken.png")).unwrap(),
        b"old png"
    );
    assert_eq!(
        tree(&dir),
        vec!["broken.toml", "out", "out/broken.exr", "out/broken.png"],
        "no temporary file left"
    );
}

#[test]
fn unwritable_png_target_keeps_the_existing_exr() {
    // The PNG path is a directory, so the run must fail and must not replace the
    // EXR either (both are staged before either is committed).
    let dir = temp_dir("pngdir");
    std::fs::write(dir.join("tiny.toml"), TINY_SCENE).unwrap();
    std::fs::write(dir.join("img.exr"), b"old exr").unwrap();
    std::fs::create_dir(dir.join("img.png")).unwrap();
    let out = run_in(
        &dir,
        &["render", "tiny.toml", "--out", "img.exr", "--quiet"],
    );
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(std::fs::read(dir.join("img.exr")).unwrap(), b"old exr");
    assert_eq!(tree(&dir), vec!["img.exr", "img.png", "tiny.toml"]);
}

// ---- End-to-end: these need the scene parser (and pass once it has landed). ----

#[test]
fn render_tiny_scene_writes_exr_png_and_summary() {
    let dir = temp_dir("tiny");
    std::fs::write(dir.join("tiny.toml"), TINY_SCENE).unwrap();
    let out = run_in(
        &dir,
        &[
            "render",
            "tiny.toml",
            "--out",
            "res/img.exr",
            "--spp",
            "3",
            "--seed",
            "7",
            "--threads",
            "2",
            "--max-depth",
            "4",
            "--integrator",
            "path",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "render succeeds");
    assert!(out.stderr.is_empty(), "no progress bar off a terminal");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 1, "one summary line: {stdout:?}");
    for part in ["16x12", "3 spp", "Mrays/s", "res/img.exr", "res/img.png"] {
        assert!(lines[0].contains(part), "summary lacks {part}: {stdout:?}");
    }

    let img = read_exr(&dir.join("res/img.exr")).unwrap();
    assert_eq!((img.width, img.height), (16, 12));
    for name in [
        "R",
        "G",
        "B",
        "normal.X",
        "normal.Y",
        "normal.Z",
        "depth.Z",
        "albedo.R",
        "albedo.G",
        "albedo.B",
        "object.id",
        "variance.R",
        "variance.G",
        "variance.B",
    ] {
        let ch = img
            .channel(name)
            .unwrap_or_else(|| panic!("{name} missing"));
        assert!(ch.data.iter().all(|v| v.is_finite()));
    }
    // Radiance is non-negative, and a white sphere under a white sky is not black.
    let r = &img.channel("R").unwrap().data;
    assert!(r.iter().all(|v| *v >= 0.0));
    let png = image::open(dir.join("res/img.png")).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (16, 12));
    assert_eq!(
        tree(&dir),
        vec!["res", "res/img.exr", "res/img.png", "tiny.toml"]
    );
}

#[test]
fn render_tiny_scene_default_paths_and_overrides() {
    let dir = temp_dir("defaults");
    std::fs::write(dir.join("tiny.toml"), TINY_SCENE).unwrap();
    std::fs::create_dir(dir.join("out")).unwrap();
    std::fs::write(dir.join("out/tiny.exr"), b"previous").unwrap();
    let out = run_in(
        &dir,
        &[
            "render",
            "tiny.toml",
            "--width",
            "8",
            "--height",
            "6",
            "--no-aovs",
            "--quiet",
        ],
    );
    assert_eq!(out.status.code(), Some(0), "render succeeds");
    assert!(
        out.stdout.is_empty() && out.stderr.is_empty(),
        "--quiet is quiet"
    );
    let img = read_exr(&dir.join("out/tiny.exr")).unwrap();
    assert_eq!((img.width, img.height), (8, 6));
    let names: Vec<&str> = img.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["B", "G", "R"], "--no-aovs writes the beauty only");
    let png = image::open(dir.join("out/tiny.png")).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (8, 6));
    assert_eq!(
        tree(&dir),
        vec!["out", "out/tiny.exr", "out/tiny.png", "tiny.toml"]
    );
}

#[test]
fn info_lists_the_tiny_scene() {
    let dir = temp_dir("info");
    std::fs::write(dir.join("tiny.toml"), TINY_SCENE).unwrap();
    let out = run_in(&dir, &["info", "tiny.toml"]);
    assert_eq!(out.status.code(), Some(0));
    let s = String::from_utf8_lossy(&out.stdout);
    for part in [
        "triangles: 0",
        "spheres: 1",
        "meshes: 0",
        "white: lambert",
        "emitters: 0",
        "environment: constant",
        "bump maps: 0",
        "16x12",
        "spp=2",
        "bvh: built in",
    ] {
        assert!(s.contains(part), "info lacks {part:?}:\n{s}");
    }
    assert_eq!(tree(&dir), vec!["tiny.toml"], "info writes nothing");
}

/// `info` gives each mesh's bounds in world space, after its transform: a
/// unit quad (centred, in the xy plane) scaled by 2 and moved by (10, 0, -3)
/// ends up at [9, -1, -3] to [11, 1, -3].
#[test]
fn info_gives_each_mesh_its_bounds_after_its_transform() {
    let dir = temp_dir("info-bounds");
    let scene = format!(
        "{TINY_SCENE}[[shapes]]\nname = \"panel\"\ntype = \"quad\"\nsize = [1, 1]\n\
         material = \"white\"\ntransform = {{ scale = 2, translate = [10, 0, -3] }}\n"
    );
    std::fs::write(dir.join("s.toml"), scene).unwrap();
    let out = run_in(&dir, &["info", "s.toml"]);
    let s = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{s}");
    assert!(
        s.contains("  panel: 2 triangles, bounds [9, -1, -3] to [11, 1, -3]"),
        "{s}"
    );
}

#[test]
fn thread_count_does_not_change_the_image() {
    let dir = temp_dir("threads");
    std::fs::write(dir.join("tiny.toml"), TINY_SCENE).unwrap();
    let mut images = Vec::new();
    // 100000 is capped at 8 per core (issue 18, defect 13: it used to start them all).
    for t in ["1", "3", "100000"] {
        let exr = format!("t{t}.exr");
        let out = run_in(
            &dir,
            &["render", "tiny.toml", "--threads", t, "--out", &exr, "-q"],
        );
        assert_eq!(out.status.code(), Some(0), "render succeeds");
        images.push(read_exr(&dir.join(&exr)).unwrap());
    }
    let bits = |img: &gradtrace::output::OutputImage| -> Vec<(String, Vec<u32>)> {
        img.channels
            .iter()
            .map(|c| (c.name.clone(), c.data.iter().map(|v| v.to_bits()).collect()))
            .collect()
    };
    assert_eq!(bits(&images[0]), bits(&images[1]), "bit-identical layers");
    assert_eq!(bits(&images[0]), bits(&images[2]), "bit-identical layers");
}
