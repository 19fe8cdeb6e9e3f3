//! The previews as rows of `compare` (issue 57): where a scene suits a preview,
//! one frame of it at compare's resolution, scored by the report against
//! compare's own reference (not the preview's, which is direct light or one
//! bounce only), its cost that frame and its precompute apart (cached under
//! `<out>/cache/`, so a second compare or seed reads it).

use super::{Clock, Plan};
use crate::output::report::{Run, RunKind};
use crate::pipeline::preview::glossy::{self as glossy_cmd, GlossyOptions};
use crate::pipeline::preview::shadow_field::{self as sf_cmd, ShadowFieldOptions};
use crate::preview::{glossy, shadow_field as sf};
use crate::scene::{Camera, Scene};
use crate::{Error, Result};
use std::borrow::Cow;
use std::time::Instant;

/// A preview method compare can add.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Method {
    ShadowField,
    Glossy,
}

impl Method {
    const ALL: [Method; 2] = [Method::ShadowField, Method::Glossy];

    pub(super) fn name(self) -> &'static str {
        match self {
            Method::ShadowField => "shadow-field",
            Method::Glossy => "glossy",
        }
    }

    /// Why the method does not model `scene`, by the preview's own check.
    fn unsuited(self, scene: &Scene) -> Option<String> {
        match self {
            Method::ShadowField => sf::check_scene(scene).err(),
            Method::Glossy => glossy::check_suits(scene).err().map(|e| match e {
                Error::Scene { message, .. } => message,
                e => e.to_string(),
            }),
        }
    }
}

/// The methods that suit `scene`.
pub(super) fn suited(scene: &Scene) -> Vec<Method> {
    Method::ALL
        .into_iter()
        .filter(|m| m.unsuited(scene).is_none())
        .collect()
}

/// What the previews add: their runs, the wall seconds they spent (the frames,
/// and the precomputes this run computed), and a note per preview left out.
pub(super) struct Previews {
    pub(super) runs: Vec<Run>,
    pub(super) seconds: f64,
    pub(super) notes: Vec<String>,
}

/// One run per suited preview (seed 0: a preview has no random numbers to vary).
pub(super) fn runs(plan: &Plan, progress: &dyn Fn(&str)) -> Result<Previews> {
    let mut out = Previews {
        runs: Vec::new(),
        seconds: 0.0,
        notes: Vec::new(),
    };
    for method in Method::ALL {
        if let Some(why) = method.unsuited(plan.scene) {
            out.notes.push(format!(
                "No {} preview row: the scene does not suit it ({why}).",
                method.name()
            ));
            continue;
        }
        let run = match method {
            Method::ShadowField => shadow_field(plan)?,
            Method::Glossy => glossy_frame(plan)?,
        };
        let (precompute_s, cached) = match run.kind {
            RunKind::Preview {
                precompute_s,
                cached,
            } => (precompute_s, cached),
            _ => (0.0, false),
        };
        progress(&format!(
            "{} preview: precompute {precompute_s:.2} s{}, frame {:.3} s",
            method.name(),
            if cached { " (cached)" } else { "" },
            run.wall_time_s
        ));
        out.seconds += run.wall_time_s + if cached { 0.0 } else { precompute_s };
        out.runs.push(run);
    }
    Ok(out)
}

/// The scene's camera at compare's image size.
fn camera_at(scene: &Scene, (w, h): (u32, u32)) -> Result<Camera> {
    scene
        .camera
        .with_resolution(w, h)
        .map_err(|message| Error::Option {
            option: "--width/--height".into(),
            message,
        })
}

/// `scene` with compare's image size (a clone only when it differs).
fn at_size(scene: &Scene, size: (u32, u32)) -> Result<Cow<'_, Scene>> {
    if (scene.camera.width, scene.camera.height) == size {
        return Ok(Cow::Borrowed(scene));
    }
    let mut sized = scene.clone();
    sized.camera = camera_at(scene, size)?;
    Ok(Cow::Owned(sized))
}

fn preview_run(
    method: Method,
    image: Vec<crate::math::Vec3>,
    frame: super::Cost,
    precompute_s: f64,
    cached: bool,
) -> Run {
    Run {
        name: method.name().into(),
        kind: RunKind::Preview {
            precompute_s,
            cached,
        },
        seed: 0,
        samples: 0,
        wall_time_s: frame.wall_s,
        cpu_time_s: frame.cpu_s,
        overhead_s: 0.0,
        target_s: None,
        image,
        sample_positions: Vec::new(),
    }
}

/// The shadow-field preview: fields from the cache (or precomputed and stored),
/// the environment's split and the glossy tables ([`sf::Shading`]) counted with
/// them, one shaded frame.
fn shadow_field(plan: &Plan) -> Result<Run> {
    let scene = at_size(plan.scene, plan.size)?;
    let opts = ShadowFieldOptions {
        out_dir: plan.opts.out_dir.clone(),
        quiet: true,
        settings: plan.opts.shadow_field.clone(),
        ..ShadowFieldOptions::new(scene.path.clone())
    };
    let (fields, precompute_s, cached) = sf_cmd::cached_fields(&scene, &opts)?;
    let start = Instant::now();
    let shading = sf::Shading::new(&scene);
    let shading_s = start.elapsed().as_secs_f64();
    let clock = Clock::start();
    let frame = sf_cmd::shade_frame(&scene, plan.accel, &fields, &[], &shading, &opts.settings);
    let cost = clock.cost();
    Ok(preview_run(
        Method::ShadowField,
        frame.shaded.rgb,
        cost,
        precompute_s + shading_s,
        cached,
    ))
}

/// The glossy preview: the transfer from the cache (or precomputed and stored),
/// the prefiltered environment counted with it, one frame at the preview's own
/// subpixel positions.
fn glossy_frame(plan: &Plan) -> Result<Run> {
    let scene = plan.scene;
    let opts = GlossyOptions {
        out_dir: plan.opts.out_dir.clone(),
        quiet: true,
        settings: plan.opts.glossy.clone(),
        ..GlossyOptions::new(scene.path.clone())
    };
    let (transfer, _) = glossy_cmd::transfer(scene, plan.accel, &opts)?;
    let environment = scene.environment.as_ref().ok_or_else(|| Error::Scene {
        path: scene.path.clone(),
        location: "glossy preview".into(),
        message: "needs an [environment]".into(),
    })?;
    let start = Instant::now();
    let env = glossy::PrefilteredEnv::new(environment);
    let env_s = start.elapsed().as_secs_f64();
    let camera = camera_at(scene, plan.size)?;
    let clock = Clock::start();
    let image =
        glossy::render_supersampled(&transfer, &env, scene, plan.accel, &camera, opts.subpixels);
    let cost = clock.cost();
    Ok(preview_run(
        Method::Glossy,
        image,
        cost,
        transfer.stats.precompute_s + env_s,
        transfer.stats.cached,
    ))
}
