//! What `tests/lanes_match_li.rs` asks of the lanes: whether they take a
//! scene and what they built for it, and their paths against `li`'s, sample
//! for sample. A test's view, hidden from the docs: not an API.

use super::{LaneBatch, LaneLight, LaneScene};
use crate::math::Vec2;
use crate::render::lights::LightSet;
use crate::render::path::{FirstHit, SampleResult};
use crate::render::{camera_ray, camera_sample_at, RenderOptions, Setup};
use crate::scene::Scene;

/// What the lanes built for a scene they take.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Facts {
    /// Some mesh has shading normals: the kernel interpolates them.
    pub smooth: bool,
    /// A constant sky, its direction mapped in the kernel.
    pub sky_in_frame: bool,
    pub spheres: bool,
    pub mirrors: bool,
    pub lights: usize,
    /// Of them, area lights that are single triangles (not rectangles).
    pub triangle_lights: usize,
}

/// The lanes' facts about `scene`, or `None` where they do not take it
/// (`li` renders it alone).
pub fn facts(scene: &Scene) -> Option<Facts> {
    let lanes = LaneScene::build(scene, &LightSet::build(scene))?;
    Some(Facts {
        smooth: lanes.smooth,
        sky_in_frame: lanes.sky_in_frame.is_some(),
        spheres: !lanes.sphere_albedo.is_empty(),
        mirrors: lanes.mirrors,
        lights: lanes.lights.len(),
        triangle_lights: lanes
            .lights
            .iter()
            .filter(|l| matches!(l, LaneLight::Area(a) if !a.rect))
            .count(),
    })
}

/// Whether this CPU runs the kernel in AVX registers.
pub fn avx2() -> bool {
    super::avx2()
}

/// Samples of every 97th pixel of `scene` under `opts`, 13 each, through
/// `li` and through the lanes (AVX's kernel with `avx2` where the CPU has
/// it, else `wide`'s): how many agreed bit for bit in radiance, ray count and
/// first-hit AOVs, or the first that did not. Each batch is traced again
/// without first hits: the same radiance and ray counts, and no first hit.
pub fn compare_with_li(scene: &Scene, opts: &RenderOptions, avx2: bool) -> Result<usize, String> {
    let accel = crate::accel::Accel::build(&scene.meshes, &scene.spheres);
    let setup = Setup::new(scene, opts).map_err(|e| e.to_string())?;
    if setup.lanes().is_none() {
        return Err("the lanes do not take this scene under these options".into());
    }
    let tracer = setup.tracer(scene, &accel);
    let mut lanes = LaneScene::build(scene, &LightSet::build(scene)).ok_or("no lane scene")?;
    lanes.avx2 = avx2 && super::avx2();
    let (w, h) = (setup.camera.width, setup.camera.height);
    let bits = |r: &SampleResult| r.radiance.to_array().map(f32::to_bits);
    let aov =
        |f: &Option<FirstHit>| f.map(|f| (f.normal, f.depth, f.albedo, f.object_id, f.back_facing));
    let mut compared = 0;
    for pixel in (0..w * h).step_by(97) {
        let corner = Vec2::new((pixel % w) as f32, (pixel / w) as f32);
        let mut batch = LaneBatch::default();
        let mut without = LaneBatch::default();
        let mut expected = Vec::new();
        for s in 0..13 {
            expected.push(camera_sample_at(
                &tracer,
                &setup.camera,
                corner,
                pixel,
                s,
                5,
                false,
            ));
            let (ray, sampler) = camera_ray(&setup.camera, corner, pixel, s, 5);
            batch.push(ray, sampler.clone());
            without.push(ray, sampler);
        }
        lanes.trace(&tracer, &mut batch, true);
        lanes.trace(&tracer, &mut without, false);
        let got: Vec<SampleResult> = batch.results().collect();
        for (g, wo) in got.iter().zip(without.results()) {
            if bits(g) != bits(&wo) || g.rays != wo.rays || wo.first_hit.is_some() {
                return Err(format!(
                    "pixel {pixel}: traced without first hits, it differs"
                ));
            }
        }
        for (e, g) in expected.iter().zip(&got) {
            if bits(e) != bits(g) || e.rays != g.rays || aov(&e.first_hit) != aov(&g.first_hit) {
                return Err(format!(
                    "pixel {pixel}: li {} ({} rays) vs lanes {} ({} rays)",
                    e.radiance, e.rays, g.radiance, g.rays
                ));
            }
            compared += 1;
        }
    }
    Ok(compared)
}
