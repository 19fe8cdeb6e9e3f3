//! Mutation fuzzing of the EXR inputs of `merge`, `diff` and `render --resume`
//! (issue 54), beside `fuzz_scene.rs`'s fuzzing of the scene parser.
//!
//! Two tiles of an 8×8 image (gradtrace's own ZIP files and uncompressed ones
//! from the `exr` crate) are mutated where a hostile header bites — the data
//! and display windows, the chunk offset table, the file's length — and by
//! random byte changes in the header. The oracle, for every input:
//! - no panic and no hang (each read well under two seconds);
//! - an input that must be invalid (a window beyond 2^28 pixels, a data window
//!   outside the display window, an offset outside the file, a truncated file)
//!   is an error; an error is one line naming the mutated file;
//! - what is accepted holds only finite values, and merges and diffs without
//!   a panic;
//! - for a sample of inputs, the binary (`merge`, `diff`, `render --resume`)
//!   exits 0 or 1, never 0 on an invalid input, with one `error:` line that is
//!   not an internal error.
//!
//! `cargo test --release --test fuzz_scene_exr` runs a few seconds of it; the
//! long run is `FUZZ_EXR_COUNT=100000 cargo test --release --test fuzz_scene_exr
//! -- --ignored --nocapture`.
#![cfg(unix)]

use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, ImageAttributes,
    IntegerBounds, Layer, LayerAttributes, SmallVec, Text, WritableImage,
};
use gradtrace::output::{self, ExrHeader, OutputImage};
use gradtrace::pipeline::diff::{self, DiffMetric, DiffOptions};
use gradtrace::pipeline::merge::{merge_parts, Part};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_gradtrace");

/// splitmix64, as `fuzz_scene/mutate.rs`.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
    fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[self.below(items.len())]
    }
}

const PROVENANCE: [(&str, &str); 4] = [
    ("gradtrace.scene_sha256", "00"),
    ("gradtrace.settings", "fuzz"),
    ("gradtrace.seed", "1"),
    ("gradtrace.spp_range", "0:4"),
];

fn pixels(n: usize, v: f32) -> Vec<[f32; 3]> {
    (0..n).map(|i| [v, 0.01 * i as f32, 0.5]).collect()
}

/// Tile `k` (0: top, 1: bottom) of an 8×8 image by gradtrace's writer (ZIP).
fn write_ours(path: &Path, k: usize) {
    let mut img = OutputImage::new(8, 4);
    let rgb = pixels(32, 1.0 + k as f32);
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        img.push_scalar(name, rgb.iter().map(|p| p[c]).collect());
    }
    let header = ExrHeader {
        display: (8, 8),
        origin: (0, 4 * k),
        attributes: PROVENANCE
            .iter()
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .collect(),
    };
    output::stage_exr_with_header(path, &img, &header)
        .unwrap()
        .commit()
        .unwrap();
}

/// The same tile uncompressed, by the `exr` crate.
fn write_plain(path: &Path, k: usize) {
    let rgb = pixels(32, 1.0 + k as f32);
    let mut list = SmallVec::new();
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        let data: Vec<f32> = rgb.iter().map(|p| p[c]).collect();
        list.push(AnyChannel::new(*name, FlatSamples::F32(data)));
    }
    let mut attrs = LayerAttributes {
        layer_position: exr::math::Vec2(0, 4 * k as i32),
        ..LayerAttributes::default()
    };
    for (a, b) in PROVENANCE {
        attrs
            .other
            .insert(Text::from(a), AttributeValue::Text(Text::from(b)));
    }
    let layer = Layer::new(
        (8, 4),
        attrs,
        Encoding::UNCOMPRESSED,
        AnyChannels::sort(list),
    );
    Image::new(
        ImageAttributes::new(IntegerBounds::from_dimensions((8, 8))),
        layer,
    )
    .write()
    .to_file(path)
    .unwrap();
}

/// Where the value of box2i attribute `name` starts.
fn box_at(bytes: &[u8], name: &str) -> usize {
    let key = [name.as_bytes(), b"\0box2i\0"].concat();
    bytes
        .windows(key.len())
        .position(|w| w == key)
        .expect("attribute present")
        + key.len()
        + 4
}

/// Where the offset table starts: after the header's closing NUL, found as the
/// first position whose first u64 is the table's own end (chunks follow it).
fn table_at(bytes: &[u8]) -> (usize, usize) {
    let meta = exr::meta::MetaData::read_from_buffered(bytes, false).unwrap();
    let n: usize = meta.headers.iter().map(|h| h.chunk_count).sum();
    let start = (0..bytes.len() - 8)
        .find(|&p| u64::from_le_bytes(bytes[p..p + 8].try_into().unwrap()) == (p + 8 * n) as u64)
        .expect("offset table");
    (start, n)
}

fn set_i32(bytes: &mut [u8], at: usize, v: i32) {
    bytes[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

/// A mutant of `seed` and whether it must be refused.
fn mutate(seed: &[u8], rng: &mut Rng) -> (Vec<u8>, bool, String) {
    let mut b = seed.to_vec();
    let interesting = [
        -1,
        0,
        1,
        3,
        4,
        7,
        8,
        9,
        -100,
        4095,
        65535,
        1 << 20,
        i32::MAX,
        i32::MIN,
        i32::MAX - 1,
    ];
    match rng.below(6) {
        0 => {
            // Display window beyond 2^28 pixels.
            let side = rng.pick(&[16385, 65536, 1 << 20, 999_999_999, i32::MAX]);
            let at = box_at(&b, "displayWindow");
            set_i32(&mut b, at + 8, side - 1);
            set_i32(&mut b, at + 12, side - 1);
            (b, true, format!("display {side}²"))
        }
        1 => {
            // The data window moved (same size) partly outside the display window.
            let at = box_at(&b, "dataWindow");
            let (dx, dy) = rng.pick(&[(-1, 0), (0, -5), (1, 0), (0, 5), (-100, 0), (0, 1 << 20)]);
            let v: Vec<i32> = (0..4)
                .map(|k| i32::from_le_bytes(b[at + 4 * k..at + 4 * k + 4].try_into().unwrap()))
                .collect();
            for (k, d) in [dx, dy, dx, dy].iter().enumerate() {
                set_i32(&mut b, at + 4 * k, v[k] + d);
            }
            (b, true, format!("data window moved by ({dx}, {dy})"))
        }
        2 => {
            // One chunk offset outside the file.
            let (start, n) = table_at(&b);
            let k = rng.below(n);
            let len = b.len() as u64;
            let v = rng.pick(&[0, 1, len, len + 7, 1 << 63, u64::MAX, start as u64]);
            b[start + 8 * k..start + 8 * k + 8].copy_from_slice(&v.to_le_bytes());
            (b, true, format!("offset {k} = {v}"))
        }
        3 => {
            // Truncated anywhere.
            let cut = rng.below(b.len());
            b.truncate(cut);
            (b, true, format!("truncated at {cut}"))
        }
        4 => {
            // Any window coordinate set to an interesting value: may be valid.
            let at = box_at(&b, rng.pick(&["dataWindow", "displayWindow"])) + 4 * rng.below(4);
            let v = rng.pick(&interesting);
            set_i32(&mut b, at, v);
            (b, false, format!("window int at {at} = {v}"))
        }
        _ => {
            // A few random bytes of the header and offset table changed.
            let (start, n) = table_at(&b);
            let end = start + 8 * n;
            let k = 1 + rng.below(4);
            for _ in 0..k {
                let at = rng.below(end);
                b[at] = rng.next_u64() as u8;
            }
            (b, false, format!("{k} header bytes"))
        }
    }
}

/// `f` under a time limit; a panic is caught and reported.
fn timed<T>(what: &str, f: impl FnOnce() -> T + std::panic::UnwindSafe) -> T {
    let t0 = Instant::now();
    let r = std::panic::catch_unwind(f).unwrap_or_else(|_| panic!("{what}: panicked"));
    assert!(
        t0.elapsed() < Duration::from_secs(2),
        "{what}: took {:?}",
        t0.elapsed()
    );
    r
}

/// The binary on `args` in `dir`, killed after 10 s: its exit code and stderr.
fn binary(dir: &Path, args: &[&str]) -> (i32, String) {
    let mut child = Command::new(BIN)
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed() > Duration::from_secs(10) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("gradtrace {} hung", args.join(" "));
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[derive(Default, Debug)]
struct Tally {
    inputs: usize,
    refused: usize,
    accepted: usize,
    binary_runs: usize,
}

fn fuzz(count: usize, seed: u64, binary_every: usize) -> Tally {
    let dir =
        std::env::temp_dir().join(format!("gradtrace-fuzz-exr-{}-{seed}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    write_ours(&dir.join("ours0.exr"), 0);
    write_ours(&dir.join("ours1.exr"), 1);
    write_plain(&dir.join("plain0.exr"), 0);
    write_plain(&dir.join("plain1.exr"), 1);
    let seeds: Vec<(PathBuf, Vec<u8>)> = ["ours", "plain"]
        .iter()
        .map(|s| {
            let other = dir.join(format!("{s}0.exr"));
            (other, std::fs::read(dir.join(format!("{s}1.exr"))).unwrap())
        })
        .collect();
    // The seeds themselves are valid and merge.
    for (other, bytes) in &seeds {
        std::fs::write(dir.join("m.exr"), bytes).unwrap();
        let parts = [
            Part::read(other).unwrap(),
            Part::read(&dir.join("m.exr")).unwrap(),
        ];
        merge_parts(&parts, &dir.join("out.exr"), "fuzz").unwrap();
    }
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.toml");
    let mut rng = Rng(seed);
    let mut tally = Tally::default();
    for i in 0..count {
        let (other, bytes) = &seeds[rng.below(seeds.len())];
        let (mutant, invalid, what) = mutate(bytes, &mut rng);
        let path = dir.join("m.exr");
        std::fs::write(&path, &mutant).unwrap();
        let what = format!("input {i} ({what})");
        tally.inputs += 1;
        let read = timed(&what, || Part::read(&path));
        match read {
            Err(e) => {
                tally.refused += 1;
                let msg = e.to_string();
                assert!(!msg.contains('\n'), "{what}: one line: {msg}");
                assert!(
                    msg.starts_with(path.to_str().unwrap()),
                    "{what}: names the file: {msg}"
                );
            }
            Ok(part) => {
                assert!(!invalid, "{what}: an invalid input was accepted");
                tally.accepted += 1;
                for ch in &part.image.channels {
                    assert!(ch.data.iter().all(|v| v.is_finite()), "{what}: {}", ch.name);
                }
                let first = Part::read(other).unwrap();
                let _ = timed(&what, || {
                    merge_parts(&[first, part], &dir.join("out.exr"), "fuzz")
                });
                let opts = DiffOptions {
                    metric: DiffMetric::Rmse,
                    threshold: None,
                    error_map: Some(dir.join("map.png")),
                };
                if let Ok(r) = timed(&what, || diff::run(&path, other, &opts)) {
                    assert!(r.rmse.is_finite() && r.relmse.is_finite(), "{what}: {r}");
                }
            }
        }
        if binary_every > 0 && i % binary_every == 0 {
            tally.binary_runs += 1;
            let other = other.to_str().unwrap();
            let runs: [&[&str]; 3] = [
                &["merge", other, "m.exr", "--out", "merged.exr", "-q"],
                &["diff", "m.exr", other, "--error-map", "map.png"],
                &[
                    "render",
                    scene.to_str().unwrap(),
                    "--resume",
                    "m.exr",
                    "--out",
                    "r.exr",
                    "-q",
                ],
            ];
            for args in runs {
                let (code, err) = binary(&dir, args);
                let cmd = args[0];
                assert!(code == 0 || code == 1, "{what}: {cmd} exited {code}: {err}");
                if invalid || cmd == "render" {
                    // A resume of a fuzz file always fails (not this scene).
                    assert_eq!(code, 1, "{what}: {cmd} accepted an invalid input");
                }
                if code == 1 {
                    assert_eq!(err.lines().count(), 1, "{what}: {cmd}: {err}");
                    assert!(err.starts_with("error: "), "{what}: {cmd}: {err}");
                    assert!(!err.contains("internal error"), "{what}: {cmd}: {err}");
                }
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    tally
}

#[test]
fn mutated_exr_inputs_are_refused_cleanly_or_read_sanely() {
    let t = fuzz(600, 54, 20);
    println!("{t:?}");
    assert!(
        t.refused > 300 && t.accepted > 10,
        "both outcomes exercised: {t:?}"
    );
}

/// The long run: `FUZZ_EXR_COUNT` inputs (default 10⁵) from seed `FUZZ_EXR_SEED`.
#[test]
#[ignore]
fn mutated_exr_inputs_long_run() {
    let env = |k: &str, d: u64| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let t = fuzz(
        env("FUZZ_EXR_COUNT", 100_000) as usize,
        env("FUZZ_EXR_SEED", 1),
        env("FUZZ_EXR_BINARY_EVERY", 200) as usize,
    );
    println!("{t:?}");
}
