//! What analytic gradients cost: render time with and without `--gradients` at
//! the same samples per pixel, part by part, on four bundled scenes, and the
//! visibility-gradient analysis alone (jump finding + Eq. 45–46/72 per line)
//! against casting the same shadow rays without it.

use criterion::{criterion_group, criterion_main, Criterion};
use gradtrace::accel::{Accel, SurfacePoint};
use gradtrace::math::{Frame, Ray, Vec3};
use gradtrace::render::gradients::visibility::{trace_line, Domain};
use gradtrace::render::{render, RenderOptions};
use gradtrace::scene;
use std::path::Path;

/// The cost breakdown of issue 53: each variant adds one part of the gradient
/// to the one before (shading terms: the SV/CDV/camera/DV duals and the indirect
/// term; the lines; the gated rings; every ring; bisection), at the same spp.
fn overhead(c: &mut Criterion) {
    for name in [
        "spheres_table",
        "objects_bumpy",
        "three_spheres_env",
        "bunny_env",
    ] {
        let path = format!("scenes/{name}.toml");
        let scene = scene::load(Path::new(&path)).expect("bundled scene loads");
        let accel = Accel::build(&scene.meshes, &scene.spheres);
        let mut group = c.benchmark_group(format!("gradient_overhead/{name}"));
        group.sample_size(10);
        let base = RenderOptions {
            spp: Some(4),
            resolution: Some((160, 120)),
            ..Default::default()
        };
        let gradients = |vis: u32, gate: f32, refine: u32| RenderOptions {
            gradients: true,
            vis_samples: Some(vis),
            vis_gate: Some(gate),
            vis_refine: Some(refine),
            ..base.clone()
        };
        let variants = [
            ("plain", base.clone()),
            ("shading_terms", gradients(0, 1.0, 0)),
            ("lines_rare_rings", gradients(4, 1e-6, 0)),
            ("default_gated_rings", gradients(4, 0.25, 0)),
            ("every_ring", gradients(4, 1.0, 0)),
            ("every_ring_refine2", gradients(4, 1.0, 2)),
            ("every_ring_32_rays", gradients(32, 1.0, 0)),
        ];
        for (label, opts) in variants {
            group.bench_function(label, |b| {
                b.iter(|| render(&scene, &accel, &opts, &|_, _| {}).unwrap())
            });
        }
        group.finish();
    }
}

fn visibility_alone(c: &mut Criterion) {
    let scene = scene::load(Path::new("scenes/spheres_table.toml")).expect("bundled scene loads");
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    // Shading points on a grid over the ground, hemisphere lines toward +y.
    let points: Vec<Vec3> = (0..64)
        .map(|i| {
            Vec3::new(
                (i % 8) as f32 * 0.25 - 1.0,
                0.001,
                (i / 8) as f32 * 0.25 - 1.0,
            )
        })
        .collect();
    let domain = Domain::Cone {
        frame: Frame::from_normal(Vec3::Y),
        theta_max: 1.5,
        sphere: None,
    };
    let mut group = c.benchmark_group("visibility_line_32rays_x64");
    group.bench_function("rays_only", |b| {
        b.iter(|| {
            let mut n = 0u32;
            for (i, &x) in points.iter().enumerate() {
                let phi = i as f32 * 0.7;
                let f = Frame::from_normal(Vec3::Y);
                for k in 0..32 {
                    let t = (k as f32 + 0.5) / 32.0 * 1.5;
                    let w = f.n * t.cos() + (f.s * phi.cos() + f.t * phi.sin()) * t.sin();
                    n += accel.intersect(&Ray::new(x + Vec3::Y * 1e-3, w)).is_some() as u32;
                }
            }
            n
        })
    });
    group.bench_function("rays_and_visibility_gradient", |b| {
        b.iter(|| {
            let mut acc = Vec3::ZERO;
            for (i, &x) in points.iter().enumerate() {
                let est = trace_line(
                    &scene,
                    &accel,
                    SurfacePoint::with_default_error(x, Vec3::Y),
                    &domain,
                    i as f32 * 0.7,
                    0.5,
                    32,
                    0,
                    [Vec3::X, Vec3::Z],
                    &|_| Vec3::ONE,
                    &mut |_| {},
                );
                acc += est.vis[0];
            }
            acc
        })
    });
    group.finish();
}

criterion_group!(benches, overhead, visibility_alone);
criterion_main!(benches);
