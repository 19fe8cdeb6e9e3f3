//! Refuse up front what the machine cannot hold: a run's memory estimated from its
//! image size, planes and samples, against the memory available (or a limit).
//! A 1,000,000² render must fail in a millisecond with a clear line, not abort
//! after minutes with "memory allocation failed".

use crate::math::Vec3;
use crate::render::gradients::GradientSum;
use crate::render::{PixelAccumulator, RenderOptions};
use crate::{Error, Result};

/// Bytes per pixel of a full render: the film's running sums, its planes, the
/// output image and the EXR encoder's copy of that, and the PNG.
pub fn full_render_bytes(pixels: u64, opts: &RenderOptions) -> u64 {
    // Planes hold `Vec3`s (16 bytes, SIMD-aligned); the output image and the EXR
    // encoder three f32 channels each.
    let vec3 = std::mem::size_of::<Vec3>() as u64;
    let mut per_pixel = std::mem::size_of::<PixelAccumulator>() as u64 + vec3 + 2 * 12 + 3;
    if opts.aovs {
        // variance, normal, albedo, depth, id: planes, then image and encoder.
        per_pixel += 3 * vec3 + 8 + 2 * 44;
    }
    if opts.gradients {
        per_pixel += std::mem::size_of::<GradientSum>() as u64 + 52 * 3;
    }
    pixels * per_pixel
}

/// Bytes of an adaptive render: the samples (cell, value, quadtree bookkeeping and
/// the triangulation's vertex, edges and weights: ~560 bytes each, measured as the
/// growth of the peak RSS of a cornell render at 800×600 from budget 0.25 to 2,
/// 456 MB for 840k samples; 600 here) and the reconstructed planes.
pub fn adaptive_render_bytes(pixels: u64, budget: f32, opts: &RenderOptions) -> u64 {
    let samples = (pixels as f64 * f64::from(budget.max(0.0))).ceil() as u64;
    samples * 600
        + pixels * (12 * 4 + 8 + 3)
        + full_render_bytes(
            pixels,
            &RenderOptions {
                gradients: false,
                ..opts.clone()
            },
        ) * u64::from(opts.aovs)
}

/// Memory the system can give this process now (`MemAvailable`), if known.
fn available_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// An error when `bytes` exceed 90 % of the memory available (or `limit`, when
/// given): `what` names the run, `hint` the options that shrink it.
pub fn check(bytes: u64, limit: Option<u64>, what: &str, hint: &str) -> Result<()> {
    let Some(cap) = limit.or_else(|| available_bytes().map(|a| a / 10 * 9)) else {
        return Ok(());
    };
    if bytes <= cap {
        return Ok(());
    }
    let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
    Err(Error::Option {
        option: hint.into(),
        message: format!(
            "{what} needs about {:.1} GiB of memory, more than the {:.1} GiB {}; make it smaller",
            gib(bytes),
            gib(cap),
            if limit.is_some() {
                "allowed by --max-memory"
            } else {
                "available"
            }
        ),
    })
}
