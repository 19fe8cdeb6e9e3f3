//! Issue 54: `merge`, `diff` and `render --resume` as hard as the scene parser.
//! Every bad input is one `error:` line naming the file and what was expected,
//! status 1, no output written; nothing blocks, nothing allocates what a header
//! merely claims, and no input is ever replaced by an output.
#![cfg(unix)]

use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, ImageAttributes,
    IntegerBounds, Layer, LayerAttributes, SmallVec, Text, WritableImage,
};
use gradtrace::pipeline::diff::{self, DiffMetric, DiffOptions};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_gradtrace");

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gradtrace-in54-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs the binary in `dir`, killed after `limit`: a hang is a failure.
fn run_in(dir: &Path, args: &[&str], limit: Duration) -> Output {
    let mut child = Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("gradtrace {} hung for {limit:?}", args.join(" "));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    println!(
        "$ gradtrace {}\n-> {:?} {}",
        args.join(" "),
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn run(dir: &Path, args: &[&str]) -> Output {
    run_in(dir, args, Duration::from_secs(30))
}

/// Status 1 and one `error:` line holding every needle.
fn assert_refused(o: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "one line: {err:?}");
    assert!(err.starts_with("error: "), "{err:?}");
    assert!(!err.contains("internal error"), "{err:?}");
    for n in needles {
        assert!(err.contains(n), "{err:?} should say {n:?}");
    }
}

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(path.to_str().unwrap()).unwrap();
    // SAFETY: a NUL-terminated path that outlives the call.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
}

fn is_fifo(path: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_fifo())
}

/// The provenance `merge` checks; any values, equal across the parts.
const PROVENANCE: [(&str, &str); 4] = [
    ("gradtrace.scene_sha256", "00"),
    ("gradtrace.settings", "test"),
    ("gradtrace.seed", "1"),
    ("gradtrace.spp_range", "0:4"),
];

/// A part written with the `exr` crate, uncompressed (so that its bytes can be
/// patched, and so that it may hold what gradtrace's writer refuses): the
/// `w`×`h` data window at `origin` of a `display` image, channels R, G, B.
fn write_part(
    path: &Path,
    (w, h): (usize, usize),
    origin: (i32, i32),
    display: (usize, usize),
    rgb: &[[f32; 3]],
) {
    let mut list = SmallVec::new();
    for (k, name) in ["R", "G", "B"].iter().enumerate() {
        let data: Vec<f32> = rgb.iter().map(|p| p[k]).collect();
        list.push(AnyChannel::new(*name, FlatSamples::F32(data)));
    }
    let mut attrs = LayerAttributes {
        layer_position: exr::math::Vec2(origin.0, origin.1),
        ..LayerAttributes::default()
    };
    for (k, v) in PROVENANCE {
        attrs
            .other
            .insert(Text::from(k), AttributeValue::Text(Text::from(v)));
    }
    let layer = Layer::new(
        (w, h),
        attrs,
        Encoding::UNCOMPRESSED,
        AnyChannels::sort(list),
    );
    let image = Image::new(
        ImageAttributes::new(IntegerBounds::from_dimensions(display)),
        layer,
    );
    image.write().to_file(path).unwrap();
}

fn gray(n: usize, v: f32) -> Vec<[f32; 3]> {
    vec![[v, 0.5 * v, 0.25 * v]; n]
}

/// The two halves (8×4 each) of an 8×8 image: t0.exr (top), t1.exr (bottom).
fn two_tiles(dir: &Path) {
    write_part(&dir.join("t0.exr"), (8, 4), (0, 0), (8, 8), &gray(32, 1.0));
    write_part(&dir.join("t1.exr"), (8, 4), (0, 4), (8, 8), &gray(32, 2.0));
}

/// The byte offset of the value of the header attribute `name` (of type `kind`).
fn attribute_at(bytes: &[u8], name: &str, kind: &str) -> usize {
    let key = [name.as_bytes(), b"\0", kind.as_bytes(), b"\0"].concat();
    bytes
        .windows(key.len())
        .position(|w| w == key)
        .expect("attribute present")
        + key.len()
        + 4 // the attribute's byte size
}

/// Rewrites the box2i attribute `name` of the EXR at `path`.
fn patch_box(path: &Path, name: &str, b: [i32; 4]) {
    let mut bytes = std::fs::read(path).unwrap();
    let at = attribute_at(&bytes, name, "box2i");
    for (k, v) in b.iter().enumerate() {
        bytes[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn fifo_inputs_are_refused_before_opening() {
    let dir = scratch("fifo-in");
    two_tiles(&dir);
    mkfifo(&dir.join("fifo"));
    for args in [
        &["merge", "t0.exr", "fifo", "--out", "m.exr"][..],
        &["diff", "fifo", "t0.exr"],
        &["diff", "t0.exr", "fifo"],
        &[
            "render",
            root().join("scenes/cornell.toml").to_str().unwrap(),
            "--resume",
            "fifo",
            "--out",
            "r.exr",
        ],
    ] {
        let o = run_in(&dir, args, Duration::from_secs(10));
        assert_refused(
            &o,
            &["fifo", "FIFO", "not a regular file", "expected an EXR file"],
        );
    }
    assert!(!dir.join("m.exr").exists() && !dir.join("r.exr").exists());
    assert!(!dir.join("t0.diff.png").exists() && !dir.join("fifo.diff.png").exists());
}

#[test]
fn a_display_window_beyond_the_pixel_limit_is_refused_before_allocating() {
    let dir = scratch("huge");
    two_tiles(&dir);
    for side in [65536, 999_999_999] {
        // Both parts agree, so only the limit stops the merge from allocating.
        for t in ["t0.exr", "t1.exr"] {
            patch_box(&dir.join(t), "displayWindow", [0, 0, side - 1, side - 1]);
        }
        let t0 = Instant::now();
        let o = run(&dir, &["merge", "t0.exr", "t1.exr", "--out", "m.exr"]);
        assert_refused(
            &o,
            &[
                "t0.exr",
                &format!("display window of {side}×{side}"),
                "268435456",
            ],
        );
        assert!(
            t0.elapsed() < Duration::from_secs(5),
            "refused from the header"
        );
        assert!(!dir.join("m.exr").exists());
    }
    // At the limit (16384² = 2^28) the header passes, and the missing pixels are
    // found from the tiles' rectangles, not from a 2^28-entry map.
    patch_box(&dir.join("t0.exr"), "displayWindow", [0, 0, 16383, 16383]);
    patch_box(&dir.join("t1.exr"), "displayWindow", [0, 0, 16383, 16383]);
    let o = run(&dir, &["merge", "t0.exr", "t1.exr", "--out", "m.exr"]);
    assert_refused(
        &o,
        &[
            "m.exr",
            "268435392 of the 16384x16384 pixels uncovered, the first at (8, 0)",
        ],
    );
}

#[test]
fn an_output_that_is_an_input_under_another_name_is_refused() {
    let dir = scratch("same");
    two_tiles(&dir);
    let before = std::fs::read(dir.join("t0.exr")).unwrap();
    for out in ["t0.exr", "./t0.exr"] {
        let o = run(&dir, &["merge", "t0.exr", "t1.exr", "--out", out]);
        assert_refused(
            &o,
            &[
                "t0.exr",
                "is also the output",
                "expected an output path other than the inputs",
            ],
        );
    }
    let t1 = dir.join("t1.exr");
    for map in ["./t0.exr", t1.to_str().unwrap()] {
        let o = run(&dir, &["diff", "t0.exr", "t1.exr", "--error-map", map]);
        assert_refused(&o, &["is also the output", map]);
    }
    assert_eq!(
        std::fs::read(dir.join("t0.exr")).unwrap(),
        before,
        "t0.exr intact"
    );
    assert!(!dir.join("t0.png").exists() && !dir.join("t1.png").exists());
    // A hard link is the same file too.
    std::fs::hard_link(dir.join("t0.exr"), dir.join("alias.exr")).unwrap();
    let o = run(&dir, &["merge", "t0.exr", "t1.exr", "--out", "alias.exr"]);
    assert_refused(&o, &["t0.exr", "is also the output alias.exr"]);
    // A new path merges.
    let o = run(&dir, &["merge", "t0.exr", "t1.exr", "--out", "m.exr", "-q"]);
    assert_eq!(o.status.code(), Some(0));
}

#[test]
fn an_output_that_is_a_fifo_or_a_device_is_refused_and_left_alone() {
    let dir = scratch("fifo-out");
    two_tiles(&dir);
    mkfifo(&dir.join("fifo.exr"));
    std::os::unix::fs::symlink("/dev/null", dir.join("null.exr")).unwrap();
    let scene = root().join("scenes/cornell.toml");
    let scene = scene.to_str().unwrap();
    for out in ["fifo.exr", "null.exr"] {
        let what = if out == "fifo.exr" {
            "FIFO"
        } else {
            "character device"
        };
        let o = run_in(
            &dir,
            &["merge", "t0.exr", "t1.exr", "--out", out],
            Duration::from_secs(10),
        );
        assert_refused(
            &o,
            &[
                out,
                what,
                "expected --out to name a regular file or a new path",
            ],
        );
        let o = run_in(
            &dir,
            &[
                "render", scene, "--width", "8", "--height", "8", "--spp", "1", "--out", out,
            ],
            Duration::from_secs(10),
        );
        assert_refused(&o, &[out, what, "--out"]);
        let o = run_in(
            &dir,
            &["diff", "t0.exr", "t1.exr", "--error-map", out],
            Duration::from_secs(10),
        );
        assert_refused(&o, &[out, what, "--error-map"]);
    }
    assert!(is_fifo(&dir.join("fifo.exr")), "still a FIFO");
    assert_eq!(
        std::fs::read_link(dir.join("null.exr")).unwrap(),
        Path::new("/dev/null"),
        "still the link"
    );
    assert!(!dir.join("fifo.png").exists() && !dir.join("null.png").exists());
}

#[test]
fn a_data_window_outside_the_display_window_is_refused_not_clamped() {
    let dir = scratch("negative");
    two_tiles(&dir);
    // t1 moved to x = -3: its data window starts left of the image.
    patch_box(&dir.join("t1.exr"), "dataWindow", [-3, 4, 4, 7]);
    let o = run(&dir, &["merge", "t0.exr", "t1.exr", "--out", "m.exr"]);
    assert_refused(
        &o,
        &[
            "t1.exr",
            "data window (-3, 4)–(5, 8) does not lie inside the display window (0, 0)–(8, 8)",
        ],
    );
    let o = run(
        &dir,
        &[
            "render",
            root().join("scenes/cornell.toml").to_str().unwrap(),
            "--resume",
            "t1.exr",
            "--out",
            "r.exr",
        ],
    );
    assert_refused(&o, &["t1.exr", "does not lie inside the display window"]);
    assert!(!dir.join("m.exr").exists() && !dir.join("r.exr").exists());
}

#[test]
fn diff_of_finite_values_near_1e20_is_finite() {
    let dir = scratch("big-values");
    let (w, h) = (8usize, 4usize);
    let reference = gray(w * h, 1.0);
    let mut image = reference.clone();
    image[5] = [1e20, 1.0, 0.5];
    write_part(&dir.join("a.exr"), (w, h), (0, 0), (w, h), &image);
    write_part(&dir.join("b.exr"), (w, h), (0, 0), (w, h), &reference);
    for metric in [DiffMetric::Rmse, DiffMetric::Relmse] {
        let report = diff::run(
            &dir.join("a.exr"),
            &dir.join("b.exr"),
            &DiffOptions {
                metric,
                threshold: None,
                error_map: None,
            },
        )
        .unwrap();
        // One channel of one pixel off by 1e20: rmse = 1e20 / sqrt(3N).
        let want = 1e20 / ((3 * w * h) as f64).sqrt();
        let got = f64::from(report.rmse);
        assert!((got - want).abs() <= 1e-5 * want, "rmse {got} vs {want}");
        assert!(report.relmse.is_finite() && report.error_map_scale.is_finite());
        println!("{report}");
    }
    let o = run(&dir, &["diff", "a.exr", "b.exr"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        !stdout.contains("inf") && !stdout.contains("NaN"),
        "{stdout}"
    );
}

#[test]
fn diff_compares_data_windows_not_just_sizes() {
    let dir = scratch("windows");
    two_tiles(&dir);
    let o = run(&dir, &["diff", "t0.exr", "t1.exr"]);
    assert_refused(
        &o,
        &[
            "t1.exr: covers pixels 0,4,8,8 of a 8x8 image but t0.exr covers pixels 0,0,8,4",
            "one data window",
        ],
    );
    assert!(!dir.join("t0.diff.png").exists());
}

#[test]
fn a_non_finite_value_in_a_part_is_blamed_on_the_part_and_its_pixel() {
    let dir = scratch("nan");
    two_tiles(&dir);
    let mut rgb = gray(32, 2.0);
    rgb[8 + 3][1] = f32::NAN; // (3, 1) of the tile: (3, 5) of the image
    write_part(&dir.join("t1.exr"), (8, 4), (0, 4), (8, 8), &rgb);
    let o = run(&dir, &["merge", "t0.exr", "t1.exr", "--out", "m.exr"]);
    assert_refused(
        &o,
        &[
            "t1.exr",
            "channel \"G\" holds NaN at pixel (3, 5)",
            "expected finite values",
        ],
    );
    let o = run(
        &dir,
        &[
            "render",
            root().join("scenes/cornell.toml").to_str().unwrap(),
            "--resume",
            "t1.exr",
            "--out",
            "r.exr",
        ],
    );
    assert_refused(&o, &["t1.exr", "holds NaN at pixel (3, 5)"]);
    assert!(!dir.join("m.exr").exists() && !dir.join("r.exr").exists());
}

#[test]
fn a_chunk_offset_beyond_the_file_is_named_as_such() {
    let dir = scratch("offset");
    two_tiles(&dir);
    let path = dir.join("t1.exr");
    let mut bytes = std::fs::read(&path).unwrap();
    // Uncompressed scan lines, one per chunk: 4 chunks of (y, size, 8 px × 3 f32),
    // after a table of 4 offsets.
    let (chunks, chunk) = (4usize, 8 + 8 * 3 * 4);
    let table = bytes.len() - chunks * chunk - 8 * chunks;
    let first = u64::from_le_bytes(bytes[table..table + 8].try_into().unwrap());
    assert_eq!(first as usize, table + 8 * chunks, "found the offset table");
    bytes[table + 8..table + 16].copy_from_slice(&(1u64 << 63).to_le_bytes());
    std::fs::write(&path, &bytes).unwrap();
    for args in [
        &["merge", "t0.exr", "t1.exr", "--out", "m.exr"][..],
        &["diff", "t1.exr", "t0.exr"],
    ] {
        let o = run(&dir, args);
        assert_refused(
            &o,
            &[
                "t1.exr",
                "chunk 1's offset is 9223372036854775808",
                "expected an offset inside the file",
            ],
        );
    }
    // A truncated file: the table points past its end.
    std::fs::write(&path, &bytes[..table + 8 * chunks + chunk]).unwrap();
    let o = run(&dir, &["merge", "t0.exr", "t1.exr", "--out", "m.exr"]);
    assert_refused(&o, &["t1.exr", "expected an offset inside the file"]);
    assert!(!dir.join("m.exr").exists());
}

fn render(dir: &Path, extra: &[&str]) -> Output {
    let scene = root().join("scenes/cornell.toml");
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "--width",
        "40",
        "--height",
        "30",
        "--seed",
        "5",
        "-q",
    ];
    args.extend_from_slice(extra);
    run_in(dir, &args, Duration::from_secs(120))
}

#[test]
fn a_resume_file_that_cannot_continue_this_render_is_refused_before_rendering() {
    let dir = scratch("resume");
    // A plain render has no merge.* planes: it cannot be continued.
    assert!(render(&dir, &["--spp", "2", "--out", "plain.exr"])
        .status
        .success());
    for extra in [&[][..], &["--gradients"]] {
        let t0 = Instant::now();
        let o = render(
            &dir,
            &[
                &["--spp", "100000", "--resume", "plain.exr", "--out", "r.exr"],
                extra,
            ]
            .concat(),
        );
        let err = String::from_utf8_lossy(&o.stderr);
        if extra.is_empty() {
            assert_refused(
                &o,
                &[
                    "plain.exr",
                    "cannot resume",
                    "merge.hits",
                    "--time-limit or --spp-range",
                ],
            );
        } else {
            // The settings differ first (gradients=true).
            assert_refused(&o, &["plain.exr", "cannot resume"]);
        }
        assert!(!err.contains("(this render)"), "{err}");
        assert!(
            t0.elapsed() < Duration::from_secs(20),
            "refused before rendering: {:?}",
            t0.elapsed()
        );
    }
    assert!(!dir.join("r.exr").exists());
    // A resumable file's data window placed outside the 40x30 image it claims:
    // the file is blamed, not --crop/--tile (which were not given).
    assert!(render(
        &dir,
        &[
            "--spp",
            "2",
            "--time-limit",
            "60",
            "--crop",
            "8,4,40,28",
            "--out",
            "c.exr"
        ]
    )
    .status
    .success());
    patch_box(&dir.join("c.exr"), "dataWindow", [10, 10, 41, 33]);
    let o = render(&dir, &["--spp", "8", "--resume", "c.exr", "--out", "r.exr"]);
    assert_refused(
        &o,
        &[
            "c.exr",
            "(10, 10)–(42, 34)",
            "display window (0, 0)–(40, 30)",
        ],
    );
    assert!(!String::from_utf8_lossy(&o.stderr).contains("--crop"));
    // Inside, but of another image size than this render's.
    patch_box(&dir.join("c.exr"), "dataWindow", [8, 4, 39, 27]);
    patch_box(&dir.join("c.exr"), "displayWindow", [0, 0, 63, 47]);
    let o = render(&dir, &["--spp", "8", "--resume", "c.exr", "--out", "r.exr"]);
    assert_refused(&o, &["c.exr", "cannot resume", "64x48", "40x30"]);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("--crop"));
    // The same file, unpatched, resumes (the checks are not over-eager).
    patch_box(&dir.join("c.exr"), "displayWindow", [0, 0, 39, 29]);
    let o = render(&dir, &["--spp", "4", "--resume", "c.exr", "--out", "r.exr"]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(dir.join("r.exr").exists());
}
