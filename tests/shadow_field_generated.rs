//! Issue 57, item 2: `preview shadow-field` on seeded generated diffuse scenes
//! (`scene::generate` with `diffuse_only`: 1–3 sphere lights anywhere from a few
//! hundredths above an object to high up, radius 0.01–0.3, constant, image or no
//! sky, spheres, cubes and the bundled models): every preview finite, and its
//! RMSE against the path tracer's direct light within the stated bound.

use gradtrace::pipeline::preview::shadow_field::{run, ShadowFieldOptions};
use gradtrace::preview::shadow_field::Settings;
use gradtrace::scene::generate::{scene_toml, Options};

const SCENES: u64 = 24;

#[test]
fn generated_diffuse_scenes_preview_finite_and_close_to_the_path_tracer() {
    let dir = scratch("sfgen");
    let mut failures = Vec::new();
    let mut worst = (0.0f64, 0u64);
    let mut all = Vec::new();
    for seed in 0..SCENES {
        let (path, mut o) = generated(&dir, seed, [48, 36]);
        o.reference_spp = Some(64);
        o.reference_spp_max = Some(256);
        o.settings = Settings {
            rays: 16,
            self_rays: 8,
            ..Settings::default()
        };
        let s = match run(&o) {
            Ok(s) => s,
            Err(e) => {
                failures.push(format!("seed {seed}: {e}"));
                continue;
            }
        };
        let exr = gradtrace::output::read_exr(&s.exr).unwrap();
        if let Some(c) = exr
            .channels
            .iter()
            .find(|c| !c.data.iter().all(|x| x.is_finite()))
        {
            failures.push(format!("seed {seed}: {} not finite", c.name));
        }
        let scene = gradtrace::scene::load(&path).unwrap();
        let rel = masked_rmse(&scene, &exr);
        eprintln!(
            "seed {seed}: RMSE {:.1}% of the mean away from seen emitters ({:.1}% with them)",
            100.0 * rel,
            100.0 * s.rmse_relative
        );
        if !rel.is_finite() || rel > BOUND {
            failures.push(format!("seed {seed}: RMSE {:.1}% of the mean", 100.0 * rel));
        }
        all.push(rel);
        if rel > worst.0 {
            worst = (rel, seed);
        }
        let _ = std::fs::remove_dir_all(&o.out_dir);
    }
    eprintln!("worst: seed {} at {:.1}%", worst.1, 100.0 * worst.0);
    all.sort_by(f64::total_cmp);
    let median = all.get(all.len() / 2).copied().unwrap_or(f64::INFINITY);
    eprintln!("median {:.1}%", 100.0 * median);
    if median > MEDIAN_BOUND {
        failures.push(format!("median RMSE {:.1}% of the mean", 100.0 * median));
    }
    if failures.is_empty() {
        let _ = std::fs::remove_dir_all(&dir);
    }
    assert!(
        failures.is_empty(),
        "scenes kept in {}: {failures:#?}",
        dir.display()
    );
}

/// Issue 57, item 3 (a benchmark, not a timed test): speed-up at equal error
/// and CPU µs per point and entity over `GRADTRACE_SF_SCENES` (default 20)
/// generated scenes at 160 × 120, their distribution printed.
/// `cargo test --release --test shadow_field_generated speed -- --ignored --nocapture`
#[test]
#[ignore]
fn speed_over_generated_scenes() {
    let n: u64 = std::env::var("GRADTRACE_SF_SCENES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20);
    let dir = scratch("sfspeed");
    let (mut speed, mut us, mut rmse) = (Vec::new(), Vec::new(), Vec::new());
    for seed in 0..n {
        let (path, o) = generated(&dir, seed, [160, 120]);
        let s = run(&o).unwrap();
        let exr = gradtrace::output::read_exr(&s.exr).unwrap();
        let scene = gradtrace::scene::load(&path).unwrap();
        let rel = masked_rmse(&scene, &exr);
        // None where the bias is not resolved (the reference's cap reached).
        let x = s.figures.speedup_per_frame.unwrap_or(f64::NAN);
        println!(
            "seed {seed:2}: {} entities, {:.3} µs per point-entity, frame {:.4} s, RMSE {:.1}% ({:.1}% away from emitters), {:.1}× the path tracer at equal error per frame",
            s.entities,
            s.us_per_point_entity,
            s.figures.frame_s,
            100.0 * s.rmse_relative,
            100.0 * rel,
            x
        );
        if x.is_finite() {
            speed.push(x);
        }
        us.push(s.us_per_point_entity);
        rmse.push(rel);
        let _ = std::fs::remove_dir_all(&o.out_dir);
    }
    let _ = std::fs::remove_dir_all(&dir);
    let show = |name: &str, v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let q = |f: f64| v[((v.len() - 1) as f64 * f).round() as usize];
        println!(
            "{name}: min {:.3}, quartile {:.3}, median {:.3}, quartile {:.3}, max {:.3}",
            q(0.0),
            q(0.25),
            q(0.5),
            q(0.75),
            q(1.0)
        );
    };
    println!("{} of {n} scenes with the bias resolved", speed.len());
    show("speed-up per frame at equal error", &mut speed);
    show("CPU µs per point and entity", &mut us);
    show("RMSE / mean away from emitters", &mut rmse);
}

/// An empty folder of this process under the system's temporary one.
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("gradtrace-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Generated diffuse scene `seed` at `resolution`, written into `dir`, and the
/// preview's options for it (quiet, no cache, output under `dir`).
fn generated(
    dir: &std::path::Path,
    seed: u64,
    resolution: [u32; 2],
) -> (std::path::PathBuf, ShadowFieldOptions) {
    let opts = Options {
        diffuse_only: true,
        asset_dir: Some(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes").into()),
        resolution,
        spp: 4,
        ..Options::default()
    };
    let path = dir.join(format!("sf-{seed}.toml"));
    std::fs::write(&path, scene_toml(seed, &opts)).unwrap();
    let mut o = ShadowFieldOptions::new(&path);
    o.out_dir = dir.join(format!("out-{seed}"));
    o.quiet = true;
    o.cache = false;
    (path, o)
}

/// What the method holds on these scenes, at 48 × 36 (one shading per pixel facet)
/// (measured: median 5.0%, worst 94%; 6.3% before the sun was split off the
/// sky's SH, 16% before the per-facet shading and the finite quads): the median
/// within 10% of the mean and every
/// scene within 100%. The worst are lights a few centimetres from a
/// flat-shaded or thin-legged model (the cow): hard shadows of features smaller
/// than the field's 12 × 20 × 16 samples resolve, and facets aliased at this size.
const BOUND: f64 = 1.0;
const MEDIAN_BOUND: f64 = 0.1;

/// RMSE of the preview against its `reference` layers over the pixels that see no
/// emitter (4 × 4 rays a pixel) and touch none that does, over the reference's
/// mean there. A light a few pixels wide, thousands of times brighter than what
/// it lights, is box-filtered from 2 × 2 receivers by the preview: its pixels
/// alone would make the RMSE, as the README says of the denoiser.
fn masked_rmse(scene: &gradtrace::scene::Scene, exr: &gradtrace::output::OutputImage) -> f64 {
    use gradtrace::accel::{Accel, PrimRef};
    use gradtrace::math::{Vec2, Vec3};
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let mut lit = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            for k in 0..16 {
                let p = Vec2::new(
                    x as f32 + (k % 4) as f32 / 4.0 + 0.125,
                    y as f32 + (k / 4) as f32 / 4.0 + 0.125,
                );
                let emits =
                    accel
                        .intersect(&cam.generate_ray(p))
                        .is_some_and(|hit| match hit.prim {
                            PrimRef::Sphere(s) => scene.spheres[s as usize].emission != Vec3::ZERO,
                            PrimRef::Triangle { mesh, .. } => {
                                scene.meshes[mesh as usize].emission != Vec3::ZERO
                            }
                        });
                lit[y * w + x] |= emits;
            }
        }
    }
    let ch = |n: &str| &exr.channel(n).unwrap().data;
    let (pre, refs) = (
        [ch("R"), ch("G"), ch("B")],
        [ch("reference.R"), ch("reference.G"), ch("reference.B")],
    );
    let (mut se, mut sum, mut n) = (0.0f64, 0.0f64, 0usize);
    for y in 0..h {
        for x in 0..w {
            let near = (y.saturating_sub(1)..(y + 2).min(h))
                .any(|j| (x.saturating_sub(1)..(x + 2).min(w)).any(|i| lit[j * w + i]));
            if near {
                continue;
            }
            for c in 0..3 {
                let i = y * w + x;
                se += f64::from(pre[c][i] - refs[c][i]).powi(2);
                sum += f64::from(refs[c][i]);
                n += 1;
            }
        }
    }
    (se / n.max(1) as f64).sqrt() / (sum / n.max(1) as f64)
}
