//! Refuse up front what the machine cannot hold: a run's memory estimated from its
//! image size, planes and samples, against the memory available (or a limit).
//! A 1,000,000² render must fail in a millisecond with a clear line, not abort
//! after minutes with "memory allocation failed".

use crate::math::Vec3;
use crate::memory::size;
use crate::render::gradients::GradientSum;
use crate::render::{PixelAccumulator, RenderOptions};
use crate::scene::Scene;
use crate::{Error, Result};

/// Bytes per pixel of a full render: the film's running sums, its planes, the
/// output image and the EXR encoder's copy of that, and the PNG.
/// `several_passes`: the render adds its samples in several passes
/// (`--time-limit`, the noise-adaptive rounds), each after the first working
/// on a copy of the film's sums (all or nothing), so that they are held twice.
pub fn full_render_bytes(pixels: u64, opts: &RenderOptions, several_passes: bool) -> u64 {
    // Planes hold `Vec3`s (16 bytes, SIMD-aligned); the output image and the EXR
    // encoder three f32 channels each.
    let vec3 = std::mem::size_of::<Vec3>() as u64;
    let mut sums = std::mem::size_of::<PixelAccumulator>() as u64;
    if opts.gradients {
        sums += std::mem::size_of::<GradientSum>() as u64;
    }
    let mut per_pixel = sums * (1 + u64::from(several_passes)) + vec3 + 2 * 12 + 3;
    if opts.aovs {
        // variance, normal, albedo, depth, id: planes, then image and encoder.
        per_pixel += 3 * vec3 + 8 + 2 * 44;
    }
    if opts.gradients {
        // The planes and the three in-memory ones of a gradient-domain solve.
        per_pixel += 52 * 3 + 3 * vec3;
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
            false,
        ) * u64::from(opts.aovs)
}

/// Bytes of what a render builds from a loaded scene of `primitives` triangles
/// and spheres: the BVH (obvhs' build at its peak, then the blocks, lane
/// records and nodes) and the lane shading's per-triangle table. Measured as
/// the peak RSS of rendering a 2×2 image of a grid mesh above the peak of
/// loading it alone (2026-12-05, `--max-memory` tiny to stop after the load):
/// 0.5 M triangles 92 → 207 MB, 2 M triangles 354 → 693 MB, i.e. 320–400 bytes
/// per triangle above the loaded scene; 400 here.
pub fn scene_structures_bytes(primitives: u64) -> u64 {
    primitives * 400
}

/// An error when `bytes` exceed 90 % of the memory available (or `limit`, when
/// given): `what` names the run, `hint` the options that shrink it.
fn check(bytes: u64, limit: Option<u64>, what: &str, hint: &str) -> Result<()> {
    let Some(message) = crate::memory::exceeds(bytes, limit, what) else {
        return Ok(());
    };
    Err(Error::Option {
        option: hint.into(),
        message: format!("{message}; make it smaller"),
    })
}

/// `check` for a render of `scene`, `image_bytes` for its image: when what
/// the scene builds (its triangles and spheres) is the larger part, the error
/// names the scene file rather than the image's options.
pub fn check_render(
    image_bytes: u64,
    scene: &Scene,
    limit: Option<u64>,
    what: &str,
    hint: &str,
) -> Result<()> {
    let (triangles, spheres) = (scene.stats.triangles as u64, scene.spheres.len() as u64);
    let scene_bytes = scene_structures_bytes(triangles + spheres);
    if scene_bytes <= image_bytes {
        return check(image_bytes + scene_bytes, limit, what, hint);
    }
    let what = match spheres {
        0 => format!("{what} of {triangles} triangles"),
        _ => format!("{what} of {triangles} triangles and {spheres} spheres"),
    };
    let Some(message) = crate::memory::exceeds(image_bytes + scene_bytes, limit, &what) else {
        return Ok(());
    };
    Err(Error::Asset {
        path: scene.path.clone(),
        message: format!(
            "{message} ({} of it for the BVH and the shading tables); split or simplify the meshes",
            size(scene_bytes)
        ),
    })
}

/// [`check_render`] for a run whose images are small beside its scene (a
/// comparison's or a preview's): the BVH and shading tables of `scene` against
/// the memory available.
pub fn check_scene(scene: &Scene, what: &str) -> Result<()> {
    check_render(0, scene, None, what, "")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A render in several passes holds the film's sums twice (the copy a
    /// later pass adds to), gradient sums included; one pass holds them once.
    #[test]
    fn several_passes_count_the_film_sums_twice() {
        let accumulator = std::mem::size_of::<PixelAccumulator>() as u64;
        let gradient = std::mem::size_of::<GradientSum>() as u64;
        for gradients in [false, true] {
            let opts = RenderOptions {
                gradients,
                ..RenderOptions::default()
            };
            let sums = accumulator + if gradients { gradient } else { 0 };
            let one = full_render_bytes(1000, &opts, false);
            let several = full_render_bytes(1000, &opts, true);
            assert_eq!(several - one, 1000 * sums, "gradients: {gradients}");
            assert!(one > 1000 * sums, "one pass counts the sums and more");
        }
    }
}
