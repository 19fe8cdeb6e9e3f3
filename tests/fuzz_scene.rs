//! Mutation fuzzing of the scene parser (`scene::load_from_str`) on stable Rust.
//!
//! Every bundled scene is mutated (see `fuzz_scene/mutate.rs`) and loaded; the
//! oracle requires, for every input:
//! - no panic and no hang (each load well under a second);
//! - an error is one line that starts with the scene file's name;
//! - a mutation that must invalidate the file (an extra or missing array
//!   element, NaN/inf/wrong type for a number, an unknown key, a position
//!   beyond `scene::MAX_MAGNITUDE`, a bogus reference, a duplicate key) is
//!   rejected — "garbage" never loads;
//! - a scene that loads holds no NaN or infinity anywhere and every position
//!   within ±MAX_MAGNITUDE.
//!
//! Mesh and image assets are replaced by tiny inline files, so that a million
//! inputs do not reparse the 70k-triangle bunny; a short run at the end uses the
//! real bundled assets.
//!
//! `cargo test --release --test fuzz_scene` runs a few seconds of it. The long
//! run (10⁶ inputs by default) is
//! `FUZZ_SCENE_COUNT=1000000 cargo test --release --test fuzz_scene -- --ignored --nocapture`.

#[path = "fuzz_scene/mutate.rs"]
mod mutate;

use gradtrace::math::Vec3;
use gradtrace::scene::{self, Scene, MAX_MAGNITUDE};
use mutate::{Expect, Rng};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const BUNDLED: &[&str] = &[
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

/// Two triangles with texture coordinates (so bump maps apply) and normals.
const SMALL_OBJ: &str = "o small\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n\
vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 1 0\nf 1/1/1 4/4/1 3/3/1\nf 1/1/1 3/3/1 2/2/1\n";

/// A 2×1 Radiance image.
fn small_hdr() -> Vec<u8> {
    let mut b = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 2\n".to_vec();
    b.extend_from_slice(&[128, 128, 128, 129, 128, 64, 32, 130]);
    b
}

/// The corpus: (scene path for messages and assets, text), with every asset the
/// scenes name created small under `dir`.
fn corpus(dir: &Path) -> Vec<(PathBuf, String)> {
    let mut out = Vec::new();
    for p in BUNDLED {
        let text = std::fs::read_to_string(p).unwrap();
        let sub = Path::new(p)
            .parent()
            .unwrap()
            .strip_prefix("scenes")
            .unwrap();
        let base = dir.join(sub);
        for line in text.lines() {
            let Some(rest) = line.trim().strip_prefix("file = \"") else {
                continue;
            };
            let asset = base.join(rest.trim_end_matches('"'));
            std::fs::create_dir_all(asset.parent().unwrap()).unwrap();
            if asset.extension().is_some_and(|e| e == "obj") {
                std::fs::write(&asset, SMALL_OBJ).unwrap();
            } else {
                std::fs::write(&asset, small_hdr()).unwrap();
            }
        }
        let name = Path::new(p).file_name().unwrap();
        out.push((base.join(name), text));
    }
    out
}

/// No NaN or infinity anywhere, every used position within range, every index
/// valid.
fn sane(s: &Scene) -> Result<(), String> {
    let debug = format!("{s:?}");
    let mut tokens = debug.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'));
    if tokens.any(|w| w == "NaN" || w == "inf") {
        return Err("a NaN or infinity in the loaded scene".into());
    }
    let in_range = |p: Vec3| p.abs().max_element() <= MAX_MAGNITUDE;
    let c = &s.camera;
    if !(in_range(c.from) && in_range(c.to)) || c.width == 0 || c.height == 0 {
        return Err(format!("bad camera {c:?}"));
    }
    for sp in &s.spheres {
        let r = Vec3::splat(sp.radius);
        if !(sp.radius > 0.0 && in_range(sp.center - r) && in_range(sp.center + r)) {
            return Err(format!("bad sphere {sp:?}"));
        }
        if sp.material as usize >= s.materials.len() {
            return Err("sphere material out of range".into());
        }
    }
    for m in &s.meshes {
        for t in &m.triangles {
            for &i in t {
                let p = m.positions.get(i as usize).ok_or("index out of range")?;
                if !in_range(*p) {
                    return Err(format!("mesh {} vertex {p} out of range", m.name));
                }
            }
        }
        if m.material as usize >= s.materials.len() || m.object_id as usize > s.object_names.len() {
            return Err(format!("mesh {} has a bad material or object id", m.name));
        }
        if let Some(r) = &m.rect {
            if r.area().is_nan() || r.area() <= 0.0 {
                return Err(format!("rect {} without area", m.name));
            }
        }
    }
    Ok(())
}

#[derive(Default, Debug)]
struct Tally {
    inputs: u64,
    loaded: u64,
    rejected: u64,
    must_reject: u64,
    panics: Vec<String>,
    hangs: Vec<String>,
    garbage_loaded: Vec<String>,
    bad_messages: Vec<String>,
    insane: Vec<String>,
    slowest: Duration,
}

fn report(what: &str, text: &str, log: &[String]) -> String {
    format!("{what}\nmutations: {log:?}\n--- text ---\n{text}")
}

/// Loads one mutant and checks it against the oracle.
fn check(path: &Path, m: &mutate::Mutant, t: &mut Tally) {
    let start = Instant::now();
    LOADING.with(|l| l.set(true));
    let r = std::panic::catch_unwind(|| scene::load_from_str(&m.text, path));
    LOADING.with(|l| l.set(false));
    let took = start.elapsed();
    t.inputs += 1;
    t.slowest = t.slowest.max(took);
    if took > Duration::from_secs(1) {
        t.hangs
            .push(report(&format!("took {took:?}"), &m.text, &m.log));
    }
    // A triple-quoted string can hide the scanner's sites: no certainty then.
    let certain = !(m.text.contains("\"\"\"") || m.text.contains("'''"));
    let must_reject = m.expect == Expect::Reject && certain;
    t.must_reject += must_reject as u64;
    match r {
        Err(p) => {
            let msg = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            t.panics
                .push(report(&format!("panic: {msg}"), &m.text, &m.log));
        }
        Ok(Ok(s)) => {
            t.loaded += 1;
            if must_reject {
                t.garbage_loaded
                    .push(report("garbage loaded", &m.text, &m.log));
            }
            if let Err(e) = sane(&s) {
                t.insane.push(report(&e, &m.text, &m.log));
            }
        }
        Ok(Err(e)) => {
            t.rejected += 1;
            let msg = e.to_string();
            let prefix = format!("{}: ", path.display());
            let body_ok = msg
                .rsplit(": ")
                .next()
                .is_some_and(|b| !b.trim().is_empty());
            if !msg.starts_with(&prefix) || msg.contains('\n') || !body_ok {
                t.bad_messages
                    .push(report(&format!("message: {msg}"), &m.text, &m.log));
            }
        }
    }
}

/// Runs `count` mutants (or until `budget` has passed), seeds from `seed`.
fn fuzz(corpus: &[(PathBuf, String)], seed: u64, count: u64, budget: Duration) -> Tally {
    quiet_panics();
    let mut t = Tally::default();
    let start = Instant::now();
    for k in 0..count {
        if start.elapsed() > budget {
            break;
        }
        let mut rng = Rng(seed.wrapping_add(k).wrapping_mul(0x2545_F491_4F6C_DD1D));
        let (path, base) = &corpus[rng.below(corpus.len())];
        let m = mutate::mutate(base, &mut rng);
        check(path, &m, &mut t);
    }
    t
}

thread_local! {
    /// Set while a mutant loads: its panics are counted, not printed.
    static LOADING: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Silences the panic message of a loading mutant (panics are counted and the
/// first one is reported with its input); every other panic prints as usual.
fn quiet_panics() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !LOADING.with(|l| l.get()) {
                default(info);
            }
        }));
    });
}

fn assert_clean(t: &Tally, elapsed: Duration) {
    println!(
        "{} inputs in {elapsed:.1?}: {} loaded, {} rejected ({} had to be); \
         {} panics, {} hangs, {} garbage loaded, {} bad messages, {} insane scenes; \
         slowest input {:?}",
        t.inputs,
        t.loaded,
        t.rejected,
        t.must_reject,
        t.panics.len(),
        t.hangs.len(),
        t.garbage_loaded.len(),
        t.bad_messages.len(),
        t.insane.len(),
        t.slowest
    );
    for list in [
        &t.panics,
        &t.hangs,
        &t.garbage_loaded,
        &t.bad_messages,
        &t.insane,
    ] {
        if let Some(first) = list.first() {
            panic!("{} failure(s); the first:\n{first}", list.len());
        }
    }
    assert!(
        t.loaded > 0 && t.rejected > 0,
        "the mutants must exercise both outcomes"
    );
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gradtrace-fuzz-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The bounded run for every `cargo test`: ~3 s of mutants.
#[test]
fn fuzz_scene_parser_briefly() {
    let dir = scratch("brief");
    let corpus = corpus(&dir);
    let start = Instant::now();
    let t = fuzz(&corpus, 1, 20_000, Duration::from_secs(3));
    assert_clean(&t, start.elapsed());
    // (Release builds run ~4000; a debug build on a busy machine far fewer.)
    assert!(t.inputs >= 100, "too few inputs ({})", t.inputs);
}

/// The bundled scenes with their real assets (a few hundred mutants, the bunny
/// included), within the same oracle.
#[test]
fn fuzz_scene_parser_with_bundled_assets() {
    let corpus: Vec<(PathBuf, String)> = BUNDLED
        .iter()
        .map(|p| (PathBuf::from(p), std::fs::read_to_string(p).unwrap()))
        .collect();
    let count = std::env::var("FUZZ_SCENE_ASSET_COUNT")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(60);
    let start = Instant::now();
    let t = fuzz(&corpus, 7, count, Duration::from_secs(600));
    assert_clean(&t, start.elapsed());
}

/// The long run: `FUZZ_SCENE_COUNT` inputs (default 10⁶) from seed
/// `FUZZ_SCENE_SEED` (default 1 000 000 007).
#[test]
#[ignore]
fn fuzz_scene_parser_long() {
    let env = |k: &str, d: u64| {
        std::env::var(k)
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(d)
    };
    let dir = scratch("long");
    let corpus = corpus(&dir);
    let (seed, count) = (
        env("FUZZ_SCENE_SEED", 1_000_000_007),
        env("FUZZ_SCENE_COUNT", 1_000_000),
    );
    let threads = env("FUZZ_SCENE_THREADS", 2).max(1);
    let start = Instant::now();
    // Thread k runs seeds seed + k·share … : the inputs do not depend on the
    // thread count.
    let share = count.div_ceil(threads);
    let parts: Vec<Tally> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|k| {
                let corpus = &corpus;
                let n = share.min(count.saturating_sub(k * share));
                s.spawn(move || fuzz(corpus, seed + k * share, n, Duration::from_secs(86_400)))
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let mut t = Tally::default();
    for p in parts {
        t.inputs += p.inputs;
        t.loaded += p.loaded;
        t.rejected += p.rejected;
        t.must_reject += p.must_reject;
        t.panics.extend(p.panics);
        t.hangs.extend(p.hangs);
        t.garbage_loaded.extend(p.garbage_loaded);
        t.bad_messages.extend(p.bad_messages);
        t.insane.extend(p.insane);
        t.slowest = t.slowest.max(p.slowest);
    }
    assert_clean(&t, start.elapsed());
}
