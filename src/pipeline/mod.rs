//! scene file + settings → output sets: the one place that joins the stages
//! (`scene`, `accel`, `render`, `adaptive`, `reconstruct`, `preview`, `output`).
//! Each command is a short function that calls the stages in order:
//! [`render::run`] (full or adaptive render), [`compare::run`], [`info`], and
//! the previews in [`preview`].

pub mod adaptive;
pub mod cache;
pub mod compare;
pub mod diff;
pub mod gdomain;
pub mod memory;
pub mod merge;
pub mod output_set;
pub mod preview;
pub mod progress;
pub mod render;

use crate::accel::Accel;
use crate::scene::{self, Scene};
use crate::{Error, Result};
use std::path::Path;
use std::time::Instant;

/// The most worker threads a run starts: a few per core is enough to hide any
/// imbalance, and far more only costs start-up time and memory.
pub const MAX_THREADS_PER_CORE: usize = 8;

/// Loads the scene and builds its BVH: what every command starts from.
pub fn load(path: &Path) -> Result<(Scene, Accel)> {
    let scene = scene::load(path)?;
    memory::check_scene(&scene, "a comparison")?;
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    Ok((scene, accel))
}

/// Runs `f` on a pool of `threads` workers (default: rayon's global pool, one per
/// core), capped at [`MAX_THREADS_PER_CORE`] per core. The thread count never
/// changes an image.
pub fn with_threads<R: Send>(threads: Option<u32>, f: impl FnOnce() -> R + Send) -> Result<R> {
    let Some(t) = threads else {
        return Ok(f());
    };
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let t = (t as usize).clamp(1, cores * MAX_THREADS_PER_CORE);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(t)
        .build()
        .map_err(|e| Error::Option {
            option: "--threads".into(),
            message: format!("cannot start {t} worker threads: {e}"),
        })?;
    Ok(pool.install(f))
}

/// The `info` report: what the scene holds, what the renderer builds for it and
/// how long the BVH takes to build.
pub fn info(path: &Path) -> Result<String> {
    let scene = scene::load(path)?;
    memory::check_scene(&scene, "the BVH")?;
    let t0 = Instant::now();
    // Kept alive until after the timing so that its drop is not measured.
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let build = t0.elapsed();
    let primitives = scene.stats.triangles + scene.spheres.len();
    let queries = if accel.streams() {
        "ray streams (a small tree)"
    } else {
        "one ray at a time"
    };
    Ok(format!(
        "{}renderer: {}\nbvh: built in {:.3} ms ({primitives} primitives, {} inner nodes); lane queries: {queries}\n",
        scene.describe(),
        crate::render::describe(&scene),
        build.as_secs_f64() * 1e3,
        accel.node_count(),
    ))
}

/// The renderer's version: the crate version and the git commit it was built
/// from (`build.rs`), e.g. `0.1.0 (4342f2c)`, as `--version` prints it and every
/// EXR header and report records it.
pub const VERSION: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " (",
    env!("GRADTRACE_GIT_COMMIT"),
    ")"
);

/// What cached references are keyed on: the crate version and the hash of the
/// pinned-pixel table (`build.rs`). The table must be rewritten whenever the path
/// tracer's pixels change, so a commit that leaves them alone (docs, tests, a
/// faster traversal) reuses its references and one that moves them re-renders.
pub const PIXEL_EPOCH: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " ",
    env!("GRADTRACE_PIXEL_EPOCH")
);

/// What cached precomputations (shadow fields, glossy transfer) are keyed on: the
/// crate version and a hash of every source file. They are not pinned, so any
/// change of the code recomputes them rather than risk a stale cache.
pub const SOURCE_EPOCH: &str = concat!(
    env!("CARGO_PKG_VERSION"),
    " ",
    env!("GRADTRACE_SOURCE_HASH")
);

/// This process's command line, for the headers and reports that record it
/// (arguments with spaces quoted).
pub fn command_line() -> String {
    std::env::args()
        .map(|a| {
            if a.is_empty() || a.contains(char::is_whitespace) {
                format!("{a:?}")
            } else {
                a
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}
