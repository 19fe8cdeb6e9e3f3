//! Our own overhead in adaptive sampling at the paper's setting (512×512, budget 0.17):
//! quadtree construction per strategy and Delaunay reconstruction per interpolation,
//! with a trivial analytic estimator so that almost no time goes into "rendering";
//! then the reconstruction of a rendered sample set (spheres_table at 17%).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use gradtrace::adaptive::{refine, SampleValue, Settings, Strategy};
use gradtrace::math::{Vec2, Vec3};
use gradtrace::reconstruct::{reconstruct, Interpolation};

/// A Gaussian bump on a ramp, and a disc that is another object (so that the forced
/// silhouette refinement is part of what is measured).
fn image(p: Vec2) -> SampleValue {
    let d = p - Vec2::new(300.0, 200.0);
    let g = (-d.length_squared() / 800.0).exp();
    let mut v = SampleValue::new(
        Vec3::splat(0.2 + 0.001 * p.x + g),
        Vec3::splat(0.001 - g * d.x / 400.0),
        Vec3::splat(-g * d.y / 400.0),
    );
    if p.distance(Vec2::new(150.0, 330.0)) < 90.0 {
        v.object_id = 1;
    }
    v
}

fn adaptive(c: &mut Criterion) {
    let (w, h, budget) = (512u32, 512u32, 0.17f32);
    let n = (budget * (w * h) as f32).round() as u64;
    let mut group = c.benchmark_group("adaptive_512x512_b0.17");
    group.sample_size(10);
    group.throughput(Throughput::Elements(n));
    for strategy in [
        Strategy::Uniform,
        Strategy::Gradient,
        Strategy::Variance,
        Strategy::SecondOrder,
    ] {
        let settings = Settings::new(strategy, budget);
        group.bench_function(format!("quadtree_{}", strategy.name()), |b| {
            b.iter(|| refine(&image, w, h, &settings).unwrap())
        });
    }
    let set = refine(&image, w, h, &Settings::new(Strategy::Gradient, budget)).unwrap();
    group.throughput(Throughput::Elements((w * h) as u64));
    for mode in [Interpolation::Linear, Interpolation::Gradient] {
        group.bench_function(format!("reconstruct_{}", mode.name()), |b| {
            b.iter(|| reconstruct(&set, mode).unwrap())
        });
    }
    group.finish();

    // The same on a real sample set: spheres_table's quadtree at 17% (16 spp per
    // sample, enough for the same placement structure), with its silhouettes,
    // folds and terminators.
    let scene = gradtrace::scene::load(std::path::Path::new("scenes/spheres_table.toml")).unwrap();
    let accel = gradtrace::accel::Accel::build(&scene.meshes, &scene.spheres);
    let opts = gradtrace::render::RenderOptions {
        spp: Some(16),
        ..Default::default()
    };
    let settings = Settings::new(Strategy::Gradient, budget);
    let run = gradtrace::pipeline::adaptive::render_adaptive(
        &scene,
        &accel,
        &opts,
        &settings,
        Interpolation::Gradient,
        &|_, _| {},
    )
    .unwrap();
    let (w, h) = (run.samples.width, run.samples.height);
    let mut group = c.benchmark_group(format!("spheres_table_{w}x{h}_b0.17"));
    group.sample_size(20);
    group.throughput(Throughput::Elements((w * h) as u64));
    for mode in [Interpolation::Linear, Interpolation::Gradient] {
        group.bench_function(format!("reconstruct_{}", mode.name()), |b| {
            b.iter(|| reconstruct(&run.samples, mode).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, adaptive);
criterion_main!(benches);
