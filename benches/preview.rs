//! Shadow-field preview speed: the SH triple product (generated straight-line vs the
//! generic sparse loop), one receiver's combination (per point and entity, one
//! core), and a deforming entity's base-sphere update against its full field.
//! `cargo bench --bench preview`.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use gradtrace::math::sh;
use gradtrace::math::Vec3;
use gradtrace::preview::shadow_field::{self as sf, deform, precompute, Settings};
use std::path::Path;

fn products(c: &mut Criterion) {
    let a: sh::Sh = std::array::from_fn(|i| 0.3 + 0.05 * i as f64);
    let b: sh::Sh = std::array::from_fn(|i| 0.7 - 0.03 * i as f64);
    let (af, bf) = (a.map(|x| x as f32), b.map(|x| x as f32));
    let tensor = sh::triple_tensor();
    c.bench_function("sh product f32 generated", |bn| {
        bn.iter(|| sh::product(black_box(&af), black_box(&bf)))
    });
    c.bench_function("sh product f64 generic sparse loop", |bn| {
        bn.iter(|| sh::product_sparse(black_box(&a), black_box(&b), &tensor))
    });
}

fn bunny_scene() -> gradtrace::scene::Scene {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/shadowfield_bunny.toml");
    gradtrace::scene::load(Path::new(path)).unwrap()
}

fn combination(c: &mut Criterion) {
    let scene = bunny_scene();
    let settings = Settings {
        rays: 12,
        self_rays: 6,
        ..Settings::default()
    };
    let fields = sf::precompute(&scene, &settings, &|_, _| {});
    let env = sf::peak::EnvironmentLight::new(scene.environment.as_ref());
    let (combiner, _) = fields.combiner(&[], env);
    // Receivers on the floor around the bunny and the ball (every entity in play).
    let points: Vec<Vec3> = (0..64)
        .map(|i| Vec3::new(-1.5 + 0.05 * i as f32, 0.0, 0.6 - 0.02 * i as f32))
        .collect();
    let entities = fields.entities.len() - 1; // the floor receiver skips itself
    let floor = fields.entities.iter().position(|e| e.name == "floor");
    let mut group = c.benchmark_group("shadow-field combination");
    group.bench_function(format!("64 floor points x {entities} entities"), |bn| {
        bn.iter(|| {
            let mut acc = Vec3::ZERO;
            for &p in &points {
                acc += combiner.shade(black_box(p), Vec3::Y, floor, None).0;
            }
            acc
        })
    });
    group.finish();
}

fn deforming(c: &mut Criterion) {
    let scene = bunny_scene();
    let settings = Settings::default();
    let e = precompute::entities(&scene)
        .into_iter()
        .find(|e| e.name == "bunny")
        .unwrap();
    let geo = precompute::EntityGeometry::new(&scene, &e);
    let grid = precompute::grid_for(&e, &settings);
    let unit = sf::field::Grid {
        r_min: settings.r_min,
        r_max: settings.r_max,
        ..grid
    };
    let table = deform::MatrixTable::for_grid(&unit, 1.0, deform::Extrapolation::Visibility);
    let mut group = c.benchmark_group("deforming bunny field");
    group.sample_size(10);
    group.bench_function("base-sphere update (BSV + M_k)", |bn| {
        bn.iter(|| {
            let bsv = deform::BaseSphere::trace(&geo, e.center, e.radius, 12, 20, settings.rays);
            bsv.extrapolate(&grid, &table)
        })
    });
    group.bench_function("full field (all 3840 samples)", |bn| {
        bn.iter(|| precompute::occlusion_field(&geo, &e, &grid, settings.rays))
    });
    group.finish();
}

criterion_group!(benches, products, combination, deforming);
criterion_main!(benches);
