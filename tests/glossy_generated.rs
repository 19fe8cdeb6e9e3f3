//! Issue 57, item 2 (glossy half): `preview glossy` on seeded generated scenes
//! (`scene::generate` with `glossy_only`: 1–3 cubes, cows and teapots of lambert,
//! Blinn-Phong and Cook-Torrance materials of exponent 2–128 on a lambert floor,
//! a lambert wall half the time, under a constant or image sky): every layer finite, and the
//! RMSE against the path tracer's direct + one bounce within what the method holds.
//!
//! The bound: one vMF lobe per path type and view direction holds low-frequency
//! transfer, interpolated between vertices. At these cheap settings (8 paths a
//! slice, angular level ≤ 1, 400 vertices added, the floor tessellated to an
//! eighth of the scene) and 40 × 30 pixels, seeds 0–19 measured a median RMSE of
//! 9.0 % of the mean, 1.6 % at best and 28.4 % at worst (seed 17; 12.1 % and 35.6 %
//! before Td's direct light read the cosine-convolved sky); 274 s on 2 shared cores
//! (load 4). The test asks for a median within 20 % and every
//! scene within 50 %. Glossy floors are left out: a large glossy plane's
//! highlight moves within faces the criterion does not split (132 % on one).

use gradtrace::pipeline::preview::glossy::{run, GlossyOptions};
use gradtrace::preview::glossy::Settings;
use gradtrace::scene::generate::{scene_toml, Options};

const SCENES: u64 = 20;
const BOUND: f64 = 0.5;
const MEDIAN_BOUND: f64 = 0.2;

#[test]
fn generated_glossy_scenes_preview_finite_and_close_to_the_path_tracer() {
    let dir = std::env::temp_dir().join(format!("gradtrace-glgen-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let opts = Options {
        glossy_only: true,
        asset_dir: Some(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes").into()),
        resolution: [40, 30],
        spp: 4,
        max_depth: 3,
        ..Options::default()
    };
    let mut failures = Vec::new();
    let mut all = Vec::new();
    for seed in 0..SCENES {
        let start = std::time::Instant::now();
        let path = dir.join(format!("gl-{seed}.toml"));
        std::fs::write(&path, scene_toml(seed, &opts)).unwrap();
        let mut o = GlossyOptions::new(&path);
        o.out_dir = dir.join(format!("out-{seed}"));
        o.quiet = true;
        o.reference_spp = Some(64);
        o.reference_spp_max = Some(256);
        o.settings = Settings {
            samples: 8,
            diffuse_samples: 32,
            fit_samples: 512,
            max_angular_level: 1,
            initial_edge_fraction: 0.125,
            batch: 40,
            max_vertices: 400,
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
        let rel = s.rmse / s.reference_mean;
        eprintln!(
            "seed {seed}: RMSE {:.1}% of the mean ({:.1}% away from silhouettes), {} → {} vertices, {:.1} s",
            100.0 * rel,
            100.0 * s.rmse_interior / s.reference_mean,
            s.vertices_initial,
            s.vertices_final,
            start.elapsed().as_secs_f64()
        );
        if !rel.is_finite() || rel > BOUND {
            failures.push(format!("seed {seed}: RMSE {:.1}% of the mean", 100.0 * rel));
        }
        all.push((rel, seed));
        let _ = std::fs::remove_dir_all(&o.out_dir);
    }
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    let median = all.get(all.len() / 2).map_or(f64::INFINITY, |x| x.0);
    if let Some((worst, seed)) = all.last() {
        eprintln!(
            "median {:.1}%, worst seed {seed} at {:.1}%",
            100.0 * median,
            100.0 * worst
        );
    }
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
