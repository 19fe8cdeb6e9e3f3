//! Build-time identities of the renderer. Never fails the build.
//!
//! - `GRADTRACE_GIT_COMMIT`: `git rev-parse --short HEAD`, or "unknown" — what
//!   `--version` and the EXR headers' `gradtrace.version` print.
//! - `GRADTRACE_PIXEL_EPOCH`: a hash of the pinned-pixel table
//!   (`tests/pixels_pinned.txt`). Every change that moves a pixel of the path
//!   tracer must regenerate that table, so references cached under this key are
//!   re-rendered exactly when the renderer's pixels change, not at every commit.
//! - `GRADTRACE_SOURCE_HASH`: a hash of every file under `src/`. The preview
//!   layers' precomputations are not pinned, so their caches key on the source.
//!
//! It also warns when an x86-64 build misses the x86-64-v2 target of
//! `.cargo/config.toml`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).output().ok()?;
    let text = String::from_utf8(out.stdout).ok()?;
    (out.status.success() && !text.trim().is_empty()).then(|| text.trim().to_string())
}

/// FNV-1a, 64 bits: enough to tell versions apart (no adversary here), and no
/// build dependency.
fn fnv1a(h: &mut u64, bytes: &[u8]) {
    for b in bytes {
        *h ^= *b as u64;
        *h = h.wrapping_mul(0x0100_0000_01b3);
    }
}

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

fn files_under(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            files_under(&path, out);
        } else {
            out.push(path);
        }
    }
}

/// The hash of the files' relative paths and contents, in sorted order (the
/// directory order of the file system does not matter).
fn tree_hash(dir: &Path) -> String {
    let mut files = Vec::new();
    files_under(dir, &mut files);
    files.sort();
    let mut h = FNV_OFFSET;
    for f in &files {
        let name = f
            .strip_prefix(dir)
            .unwrap_or(f)
            .to_string_lossy()
            .replace('\\', "/");
        fnv1a(&mut h, name.as_bytes());
        fnv1a(&mut h, &[0]);
        fnv1a(&mut h, &std::fs::read(f).unwrap_or_default());
        fnv1a(&mut h, &[0]);
    }
    format!("{h:016x}")
}

fn main() {
    let commit = git(&["rev-parse", "--short", "HEAD"]).unwrap_or_else(|| "unknown".into());
    println!("cargo:rustc-env=GRADTRACE_GIT_COMMIT={commit}");

    // Without the table (a packaged crate), fall back to the commit: always safe.
    let pins = Path::new("tests/pixels_pinned.txt");
    let epoch = match std::fs::read(pins) {
        Ok(table) => {
            let mut h = FNV_OFFSET;
            fnv1a(&mut h, &table);
            format!("pins-{h:016x}")
        }
        Err(_) => format!("commit-{commit}"),
    };
    println!("cargo:rustc-env=GRADTRACE_PIXEL_EPOCH={epoch}");
    println!(
        "cargo:rustc-env=GRADTRACE_SOURCE_HASH={}",
        tree_hash(Path::new("src"))
    );
    println!("cargo:rerun-if-changed=tests/pixels_pinned.txt");
    println!("cargo:rerun-if-changed=src");

    // Rerun when HEAD moves: the HEAD file (a branch switch) and the branch's ref
    // (a commit). Only existing paths: a missing one would rerun every build.
    for path in [
        git(&["rev-parse", "--git-path", "HEAD"]),
        git(&["symbolic-ref", "-q", "HEAD"]).and_then(|r| git(&["rev-parse", "--git-path", &r])),
        git(&["rev-parse", "--git-path", "packed-refs"]),
    ]
    .into_iter()
    .flatten()
    {
        if Path::new(&path).exists() {
            println!("cargo:rerun-if-changed={path}");
        }
    }
    println!("cargo:rerun-if-changed=build.rs");

    // `.cargo/config.toml` (x86-64-v2) is read from the directory cargo runs
    // in: a build started elsewhere (`--manifest-path`) targets baseline x86-64
    // without a word, and renders 5–10 % slower (benches/README.md, levers).
    let features = std::env::var("CARGO_CFG_TARGET_FEATURE").unwrap_or_default();
    if std::env::var("CARGO_CFG_TARGET_ARCH").as_deref() == Ok("x86_64")
        && !features.split(',').any(|f| f == "sse4.1")
    {
        println!(
            "cargo:warning=building for baseline x86-64: .cargo/config.toml's x86-64-v2 applies \
             when cargo runs inside the repository; this build renders 5-10 % slower"
        );
    }
}
