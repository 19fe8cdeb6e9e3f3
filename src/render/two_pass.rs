//! scene + BVH → a render in two passes: `base` samples in every pixel, then
//! per-pixel extra samples that the caller chooses from the base pass's planes
//! (the gradient-domain strategy's dense adaptive sampling, `pipeline::gdomain`).
//! The metric lives with its caller: this module only traces the plan.

use super::{extent, Crop, Film, RenderOptions, RenderOutput, Setup};
use crate::accel::Accel;
use crate::scene::Scene;
use crate::{Error, Result};
use std::time::Instant;

/// Renders samples `0..base` of every pixel, hands those planes to `extra`, and
/// adds samples `base..base + extra[p]` to pixel p (row-major, the full image).
/// A pixel's samples are a prefix of its own sequence and its sums run in sample
/// order, so the image is the same for any thread count. The output's `spp` is the
/// most any pixel took, `spp_map` each pixel's count; `opts.spp`, `crop` and
/// `sample_range` are ignored.
pub fn render_two_pass(
    scene: &Scene,
    accel: &Accel,
    opts: &RenderOptions,
    base: u32,
    extra: &dyn Fn(&RenderOutput) -> Result<Vec<u32>>,
) -> Result<RenderOutput> {
    let start = Instant::now();
    let bad = |message: String| Error::Option {
        option: "--spp".into(),
        message,
    };
    if base == 0 {
        return Err(bad("the base pass needs at least 1 sample per pixel".into()));
    }
    let opts = RenderOptions {
        spp: Some(base),
        crop: None,
        sample_range: None,
        ..opts.clone()
    };
    let setup = Setup::new(scene, &opts)?;
    extent(&setup, &opts)?;
    let (w, h) = (setup.camera.width as usize, setup.camera.height as usize);
    let ctx = setup.context(scene, accel, &opts, 0);
    let mut film = Film::new(Crop::full(w as u32, h as u32), w, ctx.gradients);
    let never = || false;
    let quiet = |_: usize| {};
    film.add_samples(&ctx, &|_| 0..base, &never, &quiet);
    let first = film.output(&opts, 0, (w as u32, h as u32));
    let more = extra(&first)?;
    if more.len() != w * h {
        return Err(bad(format!(
            "the extra samples name {} pixels, the image has {}",
            more.len(),
            w * h
        )));
    }
    let counts: Vec<u32> = more.iter().map(|&e| base.saturating_add(e)).collect();
    film.add_samples(&ctx, &|p| base..counts[p], &never, &quiet);
    let mut out = film.output(&opts, 0, (w as u32, h as u32));
    out.spp_map = Some(counts.iter().map(|&c| c as f32).collect());
    out.stats.wall_time = start.elapsed();
    Ok(out)
}
