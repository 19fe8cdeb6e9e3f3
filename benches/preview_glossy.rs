//! Glossy-transfer preview: one 512 × 512 frame of the e = 128 teapot from
//! precomputed transfer (the issue's ≤ 50 ms bar), the environment prefilter, and
//! a small precomputation. The frame's cost depends on the pixel count and on the
//! mesh (every frame blends each vertex's slices for the view; deeper meshes are
//! slower to look up), not on how the slices were estimated: `GLOSSY_CACHE=FILE`
//! renders the transfer `gradtrace preview glossy` cached (default settings), the
//! mesh its `render_ms` times; without it the bench precomputes the unrefined mesh
//! with reduced settings (3,644 vertices against the adaptive run's ~20k, which is
//! most of why this figure was below the run's).

use criterion::{criterion_group, criterion_main, Criterion};
use gradtrace::accel::Accel;
use gradtrace::preview::glossy::{self, PrefilteredEnv, Settings};
use gradtrace::scene;
use std::path::Path;

fn teapot_frame(c: &mut Criterion) {
    let scene = scene::load(Path::new("scenes/glossy_teapot.toml")).expect("bundled scene loads");
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let settings = Settings {
        samples: 8,
        diffuse_samples: 16,
        max_angular_level: 2,
        spatial: false,
        ..Settings::default()
    };
    let t = match std::env::var_os("GLOSSY_CACHE") {
        Some(path) => {
            let defaults = Settings::default();
            let raw = std::fs::read(path).expect("GLOSSY_CACHE reads");
            let bytes = gradtrace::pipeline::cache::byte_entry_payload(&raw).unwrap_or(&raw);
            glossy::Transfer::stored_key(bytes)
                .and_then(|key| glossy::Transfer::decode(bytes, key, &scene, &defaults))
                .expect("GLOSSY_CACHE holds this scene's transfer at default settings")
        }
        None => glossy::precompute(&scene, &accel, &settings, &|_, _, _| {}).unwrap(),
    };
    eprintln!("frame bench: {} vertices", t.vertices.len());
    let env_src = scene.environment.as_ref().unwrap();
    let env = PrefilteredEnv::new(env_src);
    let camera = scene.camera.with_resolution(512, 512).unwrap();
    let mut group = c.benchmark_group("preview_glossy");
    group.sample_size(20);
    group.bench_function("teapot_frame_512x512", |b| {
        b.iter(|| glossy::render(&t, &env, &scene, &accel, &camera))
    });
    group.bench_function("prefilter_sky", |b| b.iter(|| PrefilteredEnv::new(env_src)));
    group.finish();
}

criterion_group!(benches, teapot_frame);
criterion_main!(benches);
