//! scene + BVH → per-pixel estimates (radiance and AOVs) by path tracing.
//!
//! OWNED BY THE RENDER WORK ITEM (lead) — the API below is stable; bodies change.

use crate::accel::Accel;
use crate::math::Vec3;
use crate::scene::{Integrator, Scene};
use std::time::Duration;

/// Options for one render; `None` fields fall back to the scene's `[render]` table.
#[derive(Clone, Debug, Default)]
pub struct RenderOptions {
    pub spp: Option<u32>,
    pub max_depth: Option<u32>,
    pub seed: Option<u32>,
    pub integrator: Option<Integrator>,
    /// Worker threads (None: rayon's default, all cores). Never changes the image.
    pub threads: Option<usize>,
    /// Override of the camera resolution.
    pub resolution: Option<(u32, u32)>,
    /// Compute the AOV planes (normal, depth, albedo, object id, variance).
    pub aovs: bool,
}

/// What a render produced: row-major planes, top row first.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    pub width: usize,
    pub height: usize,
    pub spp: u32,
    pub beauty: Vec<Vec3>,
    /// Per-pixel variance of the mean (sample variance / spp), when AOVs are on.
    pub variance: Option<Vec<Vec3>>,
    pub normal: Option<Vec<Vec3>>,
    pub depth: Option<Vec<f32>>,
    pub albedo: Option<Vec<Vec3>>,
    pub object_id: Option<Vec<f32>>,
    pub stats: RenderStats,
}

#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub wall_time: Duration,
    /// Rays traced (camera, bounce and shadow rays together).
    pub rays: u64,
}

/// Progress callback: called with (tiles done, tiles total) from worker threads.
pub type Progress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// Renders the scene. Deterministic for a fixed seed, whatever the thread count.
pub fn render(
    scene: &Scene,
    _accel: &Accel,
    _opts: &RenderOptions,
    _progress: Progress,
) -> crate::Result<RenderOutput> {
    let w = scene.camera.width as usize;
    let h = scene.camera.height as usize;
    Ok(RenderOutput {
        width: w,
        height: h,
        spp: 0,
        beauty: vec![Vec3::ZERO; w * h],
        variance: None,
        normal: None,
        depth: None,
        albedo: None,
        object_id: None,
        stats: RenderStats::default(),
    })
}
