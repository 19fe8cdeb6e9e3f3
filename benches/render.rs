//! End-to-end throughput: camera samples per second on the bundled Cornell box
//! (path tracing, max depth 8), and the direct-lighting mode for comparison.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use gradtrace::accel::Accel;
use gradtrace::render::{render, RenderOptions};
use gradtrace::scene::{self, Integrator};
use std::path::Path;

fn cornell(c: &mut Criterion) {
    let scene = scene::load(Path::new("scenes/cornell.toml")).expect("bundled scene loads");
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let (w, h, spp) = (128u32, 128u32, 4u32);
    let mut group = c.benchmark_group("cornell_128x128_4spp");
    group.sample_size(10);
    group.throughput(Throughput::Elements((w * h * spp) as u64));
    for (name, integrator) in [("path_depth8", Integrator::Path), ("direct", Integrator::Direct)] {
        let opts = RenderOptions {
            spp: Some(spp),
            max_depth: Some(8),
            resolution: Some((w, h)),
            integrator: Some(integrator),
            ..Default::default()
        };
        group.bench_function(name, |b| {
            b.iter(|| render(&scene, &accel, &opts, &|_, _| {}).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, cornell);
criterion_main!(benches);
