//! The quadtree refiner on analytic images: exact budgets, silhouettes refined to pixel
//! size, samples following the gradient, lower error than uniform at budget 0.17, the
//! renderer-filled strategies, bad input, and determinism across thread counts.

mod common;

use common::perspective_floor;
use glam::{DVec2, DVec3, Vec2};
use gradtrace::adaptive::{refine, surfaces_differ, SampleSet, SampleValue, Settings, Strategy};
use gradtrace::math::Vec3;
use gradtrace::reconstruct::{reconstruct, Interpolation};

/// A gentle ramp plus a sharp Gaussian bump (σ = 3 px) at `(40, 80)`.
fn bump(p: Vec2) -> SampleValue {
    let c = Vec2::new(40.0, 80.0);
    let d = p - c;
    let s2 = 9.0;
    let g = 4.0 * (-d.length_squared() / (2.0 * s2)).exp();
    let gu = -g * d.x / s2;
    let gv = -g * d.y / s2;
    let base = 0.2 + 0.001 * p.x;
    SampleValue::new(
        Vec3::splat(base + g),
        Vec3::splat(0.001 + gu),
        Vec3::splat(gv),
    )
}

/// Smooth, low-frequency background plus a localized high-frequency patch: a
/// Gaussian-windowed ripple (wavelength ≈ 9 px, σ = 18 px) around `(170, 90)`.
fn detail(p: Vec2) -> SampleValue {
    let c = Vec2::new(170.0, 90.0);
    let d = p - c;
    let s2 = 18.0f32 * 18.0;
    let win = (-d.length_squared() / (2.0 * s2)).exp();
    let k = 0.7f32;
    let (sn, cs) = (k * (p.x + 0.6 * p.y)).sin_cos();
    let bg = 0.5 + 0.3 * (p.x / 80.0).sin() * (p.y / 60.0).cos();
    let bg_u = 0.3 / 80.0 * (p.x / 80.0).cos() * (p.y / 60.0).cos();
    let bg_v = -0.3 / 60.0 * (p.x / 80.0).sin() * (p.y / 60.0).sin();
    let v = bg + win * sn;
    // d/du (win·sin) = win·(−d.x/s2)·sin + win·k·cos
    let gu = bg_u + win * (-d.x / s2) * sn + win * k * cs;
    let gv = bg_v + win * (-d.y / s2) * sn + win * k * 0.6 * cs;
    SampleValue::new(
        Vec3::new(v, 0.8 * v, 1.0 - 0.5 * v),
        Vec3::new(gu, 0.8 * gu, -0.5 * gu),
        Vec3::new(gv, 0.8 * gv, -0.5 * gv),
    )
}

/// What separates the disc from the ramp around it.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Boundary {
    ObjectId,
    Depth,
    /// Same object and depth, but the shading normal faces away (a bump map's
    /// terminator): the disc is black.
    BackFacing,
    /// A fold: the disc is a part of a receding floor raised 3% towards the camera,
    /// with the same radiance. Only the tangent-plane depth test sees it (the floor's
    /// own depth changes by 5% per 8-pixel block).
    Fold,
    /// A crease: the disc is a facet of a flat-shaded surface tilted by 10°, at the
    /// same depth as the facet around it.
    Crease,
}

fn disc(by: Boundary) -> impl Fn(Vec2) -> SampleValue + Sync {
    move |p: Vec2| {
        let inside = p.distance(Vec2::new(61.3, 66.7)) < 30.0;
        let mut v = SampleValue::new(
            Vec3::splat(0.3 + 0.002 * p.y),
            Vec3::ZERO,
            Vec3::new(0.0, 0.002, 0.0),
        );
        if by == Boundary::Fold {
            (v.depth, v.inv_depth_grad) = perspective_floor(p, if inside { 0.03 } else { 0.0 });
        }
        if by == Boundary::Crease {
            let tilt = if inside { 10f32.to_radians() } else { 0.0 };
            v.facet_normal = Some(Vec3::new(tilt.sin(), 0.0, tilt.cos()));
        }
        if inside {
            match by {
                Boundary::Fold | Boundary::Crease => {}
                Boundary::Depth => v.depth = 0.2,
                Boundary::ObjectId => v.object_id = 7,
                Boundary::BackFacing => {
                    v = SampleValue::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
                    v.back_facing = true;
                }
            }
        }
        v
    }
}

fn rmse(set: &SampleSet, mode: Interpolation, truth: impl Fn(Vec2) -> SampleValue) -> f64 {
    let r = reconstruct(set, mode).unwrap();
    let mut sum = 0.0f64;
    for y in 0..r.height {
        for x in 0..r.width {
            let t = truth(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)).radiance;
            sum += (r.image[y * r.width + x] - t).as_dvec3().length_squared() / 3.0;
        }
    }
    (sum / (r.width * r.height) as f64).sqrt()
}

const QUADTREE: [Strategy; 3] = [
    Strategy::Gradient,
    Strategy::Variance,
    Strategy::SecondOrder,
];

#[test]
fn budget_is_honoured_exactly() {
    let mut checked = 0;
    for (w, h) in [(64u32, 64u32), (100, 37), (13, 200), (5, 3), (256, 256)] {
        for budget in [0.01f32, 0.03, 0.0713, 0.17, 0.5, 1.0, 2.3] {
            let n = (budget as f64 * w as f64 * h as f64).round() as usize;
            if n == 0 {
                assert!(refine(&bump, w, h, &Settings::new(Strategy::Gradient, budget)).is_err());
                continue;
            }
            for strategy in QUADTREE.into_iter().chain([Strategy::Uniform]) {
                let set = refine(&bump, w, h, &Settings::new(strategy, budget)).unwrap();
                assert_eq!(set.samples.len(), n, "{w}x{h} budget {budget} {strategy:?}");
                // Inside the image, no duplicates, and the leaves tile the image.
                let mut keys: Vec<(u32, u32)> = set
                    .samples
                    .iter()
                    .map(|s| {
                        assert!(s.pos.x > 0.0 && s.pos.y > 0.0);
                        assert!(s.pos.x < w as f32 && s.pos.y < h as f32);
                        (s.pos.x.to_bits(), s.pos.y.to_bits())
                    })
                    .collect();
                keys.sort_unstable();
                keys.dedup();
                assert_eq!(keys.len(), n, "duplicate sample positions");
                let area: f64 = set
                    .leaf_regions()
                    .iter()
                    .map(|(a, b)| ((b.x - a.x) * (b.y - a.y)) as f64)
                    .sum();
                assert!(
                    (area - (w * h) as f64).abs() < 1e-3 * (w * h) as f64,
                    "leaves cover {area}"
                );
                checked += 1;
            }
        }
    }
    println!("{checked} (size, budget, strategy) combinations hit their budget exactly");
}

#[test]
fn object_boundaries_are_refined_to_pixel_size() {
    let (w, h) = (128u32, 128u32);
    let centre = Vec2::new(61.3, 66.7);
    for by in [
        Boundary::ObjectId,
        Boundary::Depth,
        Boundary::BackFacing,
        Boundary::Fold,
        Boundary::Crease,
    ] {
        let f = disc(by);
        for strategy in QUADTREE {
            let set = refine(&f, w, h, &Settings::new(strategy, 0.3)).unwrap();
            let mut crossing = 0;
            for (a, b) in set.leaf_regions() {
                // Nearest and farthest points of the rectangle from the disc centre.
                let near = centre.clamp(a, b).distance(centre);
                let far = [a, b, Vec2::new(a.x, b.y), Vec2::new(b.x, a.y)]
                    .iter()
                    .map(|c| c.distance(centre))
                    .fold(0.0f32, f32::max);
                if near < 30.0 && far > 30.0 {
                    crossing += 1;
                    let size = (b.x - a.x).max(b.y - a.y);
                    assert!(
                        size <= 1.0,
                        "{strategy:?} by {by:?}: cell {a}..{b} crosses the silhouette at size {size}"
                    );
                }
            }
            println!(
                "{strategy:?} (boundary by {by:?}): {crossing} boundary-crossing cells, all at pixel size"
            );
            assert!(
                crossing > 150,
                "a 30 px circle crosses at least ~190 pixel cells"
            );
        }
    }
}

/// A floor receding in perspective is one surface, although its depth changes by 5%
/// per initial block: the tangent planes predict that change. With the planes dropped
/// (zero ∇(1/depth)), the same depths read as steps — the rule the planes replace.
#[test]
fn a_receding_floor_is_one_surface() {
    for with_planes in [true, false] {
        let point = |p: Vec2| {
            let (depth, g) = perspective_floor(p, 0.0);
            let mut v = SampleValue::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
            v.depth = depth;
            v.inv_depth_grad = if with_planes { g } else { Vec2::ZERO };
            v.surface_point(p)
        };
        let mut split = 0;
        for j in 0..16 {
            for i in 0..16 {
                let p = Vec2::new(4.0 + 8.0 * i as f32, 4.0 + 8.0 * j as f32);
                for step in [
                    Vec2::new(8.0, 0.0),
                    Vec2::new(8.0, 8.0),
                    Vec2::new(0.0, 8.0),
                ] {
                    let tol = Settings::new(Strategy::Gradient, 0.1).depth_tolerance;
                    split += surfaces_differ(&point(p), &point(p + step), tol) as u32;
                }
            }
        }
        println!("tangent planes {with_planes}: {split} of 768 neighbour pairs read as a step");
        if with_planes {
            assert_eq!(split, 0);
        } else {
            assert!(
                split >= 512,
                "the vertical and diagonal pairs step by 2.7–4.8%"
            );
        }
    }
}

/// Depth steps on one object, read off the tangent planes (`surfaces_differ`).
/// A sphere seen in perspective is one surface: near its rim the tangent planes of
/// samples 8 px apart miss each other's depth by far more than the tolerance, but
/// both misses put the sphere behind the plane, which is curvature, not a step.
/// Half the sphere raised 3% towards the camera is a step all along the cut (misses
/// of opposite sign), and so is the sphere's silhouette against a wall of the same
/// object 3% behind its rim, where the sphere's plane is seen edge-on (both samples
/// in front of the other's plane). Where the curvature between two samples is as
/// large as the step, one plane's miss cancels and the pair reads as one surface:
/// a third of the pairs straddling a 3% step may be missed that way, never more.
#[test]
fn steps_on_one_surface_are_told_from_its_curvature() {
    // Pinhole at the origin looking down +z, focal length 200 px, image centre
    // (64, 64); a sphere of radius 1 at distance 5 covers a disc of ~41 px radius,
    // its rim at depth √24 ≈ 4.9.
    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Case {
        Sphere,
        RightHalfRaised,
        WallBehind,
    }
    let scene = |p: DVec2, case: Case| -> Option<f64> {
        let d = DVec3::new((p.x - 64.0) / 200.0, (p.y - 64.0) / 200.0, 1.0).normalize();
        let c = DVec3::new(0.0, 0.0, 5.0);
        let b = d.dot(c);
        let disc = b * b - (c.length_squared() - 1.0);
        let lift = if case == Case::RightHalfRaised && p.x > 64.0 {
            1.03
        } else {
            1.0
        };
        if disc >= 0.0 {
            Some(lift / (b - disc.sqrt()))
        } else {
            // The wall z = 1.03 √24 (inverse depth along the ray: d.z / z).
            (case == Case::WallBehind).then(|| d.z / (1.03 * 24f64.sqrt()))
        }
    };
    let tol = Settings::new(Strategy::Gradient, 0.1).depth_tolerance;
    let on_sphere = |p: Vec2| p.distance(Vec2::splat(64.0)) < 40.8;
    for case in [Case::Sphere, Case::RightHalfRaised, Case::WallBehind] {
        let point = |p: Vec2| {
            let at = |p: DVec2| scene(p, case);
            let (pd, h) = (p.as_dvec2(), 1e-4);
            // The side of p's own surface for the difference quotient.
            let side = |e: DVec2| {
                if on_sphere((pd + e).as_vec2()) == on_sphere(p) {
                    e
                } else {
                    -e
                }
            };
            let (ex, ey) = (side(DVec2::X * h), side(DVec2::Y * h));
            let q = at(pd)?;
            let g = DVec2::new((at(pd + ex)? - q) / ex.x, (at(pd + ey)? - q) / ey.y);
            let mut v = SampleValue::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
            v.depth = (1.0 / q) as f32;
            v.inv_depth_grad = g.as_vec2();
            Some((v.surface_point(p), q, g))
        };
        let (mut pairs, mut curved, mut split, mut split_at_step, mut steps) = (0, 0, 0, 0, 0);
        for j in 0..32 {
            for i in 0..32 {
                let p = Vec2::new(4.0 * i as f32 + 1.3, 4.0 * j as f32 + 1.7);
                for step in [
                    Vec2::new(8.0, 0.0),
                    Vec2::new(0.0, 8.0),
                    Vec2::new(8.0, 8.0),
                ] {
                    let (Some((a, qa, ga)), Some((b, qb, gb))) = (point(p), point(p + step)) else {
                        continue;
                    };
                    pairs += 1;
                    let d = step.as_dvec2();
                    let limit = tol as f64 * qa.max(qb);
                    let (miss_b, miss_a) = (qb - qa - ga.dot(d), qa - qb + gb.dot(d));
                    curved += (miss_b.abs().min(miss_a.abs()) > limit) as u32;
                    let differ = surfaces_differ(&a, &b, tol);
                    split += differ as u32;
                    let at_step = match case {
                        Case::Sphere => false,
                        Case::RightHalfRaised => (p.x > 64.0) != (p.x + step.x > 64.0),
                        Case::WallBehind => on_sphere(p) != on_sphere(p + step),
                    };
                    split_at_step += (differ && at_step) as u32;
                    steps += at_step as u32;
                    assert!(!differ || at_step, "{case:?}: split at {p} + {step}");
                }
            }
        }
        println!(
            "{case:?}: {pairs} pairs, {curved} with both planes missing beyond the \
             tolerance, {split} split, all at the step, which {steps} pairs straddle"
        );
        match case {
            Case::Sphere => assert!(curved >= 10, "the rim should defeat the planes: {curved}"),
            _ => assert!(
                3 * split_at_step >= 2 * steps,
                "{case:?}: {split_at_step} of {steps} pairs across the 3% step"
            ),
        }
    }
}

#[test]
fn gradient_strategy_samples_where_the_image_varies() {
    let (w, h) = (128u32, 128u32);
    let near = |p: Vec2| p.distance(Vec2::new(40.0, 80.0)) < 9.0;
    let area_near = std::f32::consts::PI * 81.0 / (w * h) as f32;
    for strategy in [Strategy::Gradient, Strategy::Uniform] {
        let set = refine(&bump, w, h, &Settings::new(strategy, 0.1)).unwrap();
        let frac =
            set.samples.iter().filter(|s| near(s.pos)).count() as f32 / set.samples.len() as f32;
        println!(
            "{strategy:?}: {:.1}% of the samples within 9 px of the bump ({:.1}% of the area)",
            100.0 * frac,
            100.0 * area_near
        );
        if strategy == Strategy::Gradient {
            assert!(
                frac > 8.0 * area_near,
                "gradient strategy did not concentrate: {frac}"
            );
        } else {
            assert!(frac < 2.0 * area_near);
        }
    }
}

#[test]
fn gradient_beats_uniform_at_budget_017() {
    let (w, h) = (256u32, 256u32);
    let mut table = Vec::new();
    for strategy in [
        Strategy::Uniform,
        Strategy::Gradient,
        Strategy::Variance,
        Strategy::SecondOrder,
    ] {
        let set = refine(&detail, w, h, &Settings::new(strategy, 0.17)).unwrap();
        let lin = rmse(&set, Interpolation::Linear, detail);
        let c1 = rmse(&set, Interpolation::Gradient, detail);
        println!(
            "budget 0.17 ({} samples), {strategy:?}: RMSE linear {lin:.4e}, C1 {c1:.4e}",
            set.samples.len()
        );
        table.push((strategy, lin, c1));
    }
    let (_, uni_lin, uni_c1) = table[0];
    let (_, grad_lin, grad_c1) = table[1];
    assert!(
        grad_c1 < uni_c1,
        "gradient C1 {grad_c1} vs uniform C1 {uni_c1}"
    );
    assert!(
        grad_lin < uni_lin,
        "gradient linear {grad_lin} vs uniform linear {uni_lin}"
    );
}

#[test]
fn renderer_filled_strategies() {
    // Without the fields they need, Durand and GradientVis refuse clearly.
    for strategy in [Strategy::Durand, Strategy::GradientVis] {
        let err = refine(&bump, 32, 32, &Settings::new(strategy, 0.2)).unwrap_err();
        assert!(err.to_string().contains(strategy.name()), "{err}");
    }
    // With them, they follow the field: put all the "durand" weight on the left half.
    let left = |p: Vec2| {
        let mut v = bump(p);
        v.durand = Some(if p.x < 32.0 { 1.0 } else { 0.0 });
        v.vis_gradient = Some(if p.x < 32.0 { 0.0 } else { 5.0 });
        v
    };
    let set = refine(&left, 64, 64, &Settings::new(Strategy::Durand, 0.2)).unwrap();
    let frac =
        set.samples.iter().filter(|s| s.pos.x < 32.0).count() as f32 / set.samples.len() as f32;
    println!(
        "Durand: {:.0}% of samples in the weighted half",
        100.0 * frac
    );
    assert!(frac > 0.85);
    let set = refine(&left, 64, 64, &Settings::new(Strategy::GradientVis, 0.2)).unwrap();
    let frac =
        set.samples.iter().filter(|s| s.pos.x >= 32.0).count() as f32 / set.samples.len() as f32;
    println!(
        "GradientVis: {:.0}% of samples in the shadow-gradient half",
        100.0 * frac
    );
    assert!(frac > 0.75);
    // The optional importance weight scales every metric: zero it on the right half.
    let weighted = |p: Vec2| {
        let mut v = SampleValue::new(Vec3::ONE, Vec3::splat(0.1), Vec3::ZERO);
        v.importance = Some(if p.x < 32.0 { 1.0 } else { 0.0 });
        v
    };
    let set = refine(&weighted, 64, 64, &Settings::new(Strategy::Gradient, 0.2)).unwrap();
    let right = set.samples.iter().filter(|s| s.pos.x >= 32.0).count();
    assert_eq!(right, 32, "only the 32 initial samples of the right half");
}

#[test]
fn bad_input_is_an_error() {
    let s = |b| Settings::new(Strategy::Gradient, b);
    assert!(refine(&bump, 0, 10, &s(0.2)).is_err());
    assert!(refine(&bump, 10, 0, &s(0.2)).is_err());
    for b in [0.0, -1.0, f32::NAN, f32::INFINITY, 16.5] {
        assert!(refine(&bump, 16, 16, &s(b)).is_err(), "budget {b}");
    }
    let mut t = s(0.2);
    t.depth_tolerance = f32::NAN;
    assert!(refine(&bump, 16, 16, &t).is_err());
    t = s(0.2);
    t.block_size = 0;
    assert!(refine(&bump, 16, 16, &t).is_err());
    assert!(Strategy::from_name("gradientt")
        .unwrap_err()
        .to_string()
        .contains("second_order"));
    for st in Strategy::ALL {
        assert_eq!(Strategy::from_name(st.name()).unwrap(), st);
    }
    // The spellings, as the CLI help lists them.
    assert_eq!(
        Strategy::from_name("gradient+vis").unwrap(),
        Strategy::GradientVis
    );
    assert_eq!(
        Strategy::from_name("second-order").unwrap(),
        Strategy::SecondOrder
    );
}

#[test]
fn identical_for_any_thread_count() {
    let f = |p: Vec2| {
        let mut v = detail(p);
        let d = disc(Boundary::ObjectId)(p);
        v.object_id = d.object_id;
        v
    };
    let run = |threads: usize, strategy: Strategy| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let set = refine(&f, 160, 120, &Settings::new(strategy, 0.17)).unwrap();
            let lin = reconstruct(&set, Interpolation::Linear).unwrap();
            let c1 = reconstruct(&set, Interpolation::Gradient).unwrap();
            let bits = |v: &[Vec3]| {
                v.iter()
                    .flat_map(|c| c.to_array().map(f32::to_bits))
                    .collect::<Vec<u32>>()
            };
            let pos: Vec<(u32, u32)> = set
                .samples
                .iter()
                .map(|s| (s.pos.x.to_bits(), s.pos.y.to_bits()))
                .collect();
            (pos, bits(&lin.image), bits(&c1.image))
        })
    };
    for strategy in [Strategy::Gradient, Strategy::Variance] {
        let one = run(1, strategy);
        for threads in [2, 3, 8] {
            assert!(
                one == run(threads, strategy),
                "{strategy:?}: {threads} threads differ from 1"
            );
        }
    }
}

/// Fig. 16/17: a ripple whose period (8 px) equals the initial sample spacing is
/// invisible to numerical contrast (every initial sample sits on a zero crossing), so
/// `Variance` spends the budget on a harmless smooth blob, while the analytic gradient
/// (maximal at the zero crossings) finds the ripple at once. (At larger budgets the
/// contrast refinement creeps outwards from the blob and eventually exposes the ripple
/// too; at 0.05 it has not.)
#[test]
fn analytic_gradient_sees_what_contrast_aliases_away() {
    let tau = std::f32::consts::TAU;
    let f = |p: Vec2| {
        let d = p - Vec2::new(40.0, 64.0);
        let win = 0.5 * (-d.length_squared() / (2.0 * 256.0)).exp();
        let (s, c) = (tau * p.x / 8.0).sin_cos();
        let e = p - Vec2::new(108.0, 20.0);
        let blob = 0.5 * (-e.length_squared() / (2.0 * 64.0)).exp();
        let v = 0.3 + win * s + blob;
        let gu = win * (-d.x / 256.0) * s + win * c * tau / 8.0 - blob * e.x / 64.0;
        let gv = win * (-d.y / 256.0) * s - blob * e.y / 64.0;
        SampleValue::new(Vec3::splat(v), Vec3::splat(gu), Vec3::splat(gv))
    };
    let in_ripple = |p: Vec2| p.distance(Vec2::new(40.0, 64.0)) < 32.0;
    let mut results = Vec::new();
    for strategy in [Strategy::Gradient, Strategy::Variance] {
        let set = refine(&f, 128, 128, &Settings::new(strategy, 0.05)).unwrap();
        let frac = set.samples.iter().filter(|s| in_ripple(s.pos)).count() as f32
            / set.samples.len() as f32;
        let lin = rmse(&set, Interpolation::Linear, f);
        let c1 = rmse(&set, Interpolation::Gradient, f);
        println!(
            "{strategy:?}: {:.0}% of samples on the ripple, RMSE linear {lin:.4e}, C1 {c1:.4e}",
            100.0 * frac
        );
        results.push((frac, lin, c1));
    }
    let (g, v) = (results[0], results[1]);
    assert!(
        g.0 > 2.0 * v.0,
        "gradient {} vs variance {} on the ripple",
        g.0,
        v.0
    );
    assert!(
        g.1 < 0.5 * v.1,
        "linear RMSE: gradient {} vs variance {}",
        g.1,
        v.1
    );
}

#[test]
fn progress_is_monotone_and_ends_at_the_total() {
    use std::sync::Mutex;
    for strategy in [Strategy::Gradient, Strategy::Uniform] {
        let seen = Mutex::new(Vec::new());
        let set = gradtrace::adaptive::refine_with_progress(
            &bump,
            96,
            80,
            &Settings::new(strategy, 0.3),
            &|done, total| seen.lock().unwrap().push((done, total)),
        )
        .unwrap();
        let seen = seen.into_inner().unwrap();
        let n = set.samples.len();
        assert!(seen.windows(2).all(|w| w[0].0 <= w[1].0));
        assert!(seen.iter().all(|&(_, t)| t == n));
        assert_eq!(seen.last().unwrap().0, n);
    }
}

/// A Monte Carlo estimator's gradient carries noise: on a flat half of the image the
/// estimate is pure noise (true gradient 0), on the other half sits the bump. The
/// estimator reports its variance, and the gradient strategy subtracts it from |∇I|²,
/// so the noise no longer draws samples away from the bump.
#[test]
fn gradient_noise_does_not_draw_samples() {
    let (w, h) = (128u32, 128u32);
    // Deterministic pseudo-noise of fixed power: a gradient of length 0.5 per
    // channel in a random direction, so E|Ĵ|² − Var is exactly the true |J|² = 0.
    let angle = |p: Vec2| {
        let x = (p.x * 12.9898 + p.y * 78.233).sin() * 43758.547;
        x.fract() * std::f32::consts::TAU
    };
    let noisy = |report: bool| {
        move |p: Vec2| {
            let mut v = bump(p);
            if p.x > 64.0 {
                let (s, c) = angle(p).sin_cos();
                v.grad_u += Vec3::splat(0.5 * c);
                v.grad_v += Vec3::splat(0.5 * s);
            }
            if report {
                v.gradient_variance = Some(if p.x > 64.0 { 3.0 * 0.25 } else { 0.0 });
            }
            v
        }
    };
    let near = |p: Vec2| p.distance(Vec2::new(40.0, 80.0)) < 9.0;
    let mut fracs = Vec::new();
    for report in [false, true] {
        let set = refine(
            &noisy(report),
            w,
            h,
            &Settings::new(Strategy::Gradient, 0.1),
        )
        .unwrap();
        let frac =
            set.samples.iter().filter(|s| near(s.pos)).count() as f32 / set.samples.len() as f32;
        println!(
            "noise variance {}: {:.1}% of the samples within 9 px of the bump",
            if report { "reported" } else { "unknown" },
            100.0 * frac
        );
        fracs.push(frac);
    }
    assert!(
        fracs[1] > 2.0 * fracs[0],
        "denoised metric should concentrate on the bump: {fracs:?}"
    );
}

/// Fireflies: at about 3% of the positions one path of a 256-path estimate carries
/// 256× the pixel's value (+1.0 on a 0.2 background); where it is one of the 16
/// gradient paths, its gradient too. The estimator reports the variances such a
/// path gives its estimate (≈ X²/N² per channel), as the renderer's point
/// estimator does. A firefly must not draw samples away from the real feature (the
/// bump): with the variances reported, both the `variance` and the `gradient`
/// strategy keep at least 90% of the share of samples they put near the bump on the
/// clean image, and without them (the check that this test can fail) `variance`
/// loses it.
#[test]
fn fireflies_do_not_draw_samples() {
    let (w, h) = (128u32, 128u32);
    let hash = |p: Vec2| {
        ((p.x * 12.9898 + p.y * 78.233).sin() * 43758.547)
            .fract()
            .abs()
    };
    let bump_at = Vec2::new(40.0, 80.0);
    let is_firefly = move |p: Vec2| hash(p) < 0.03 && p.distance(bump_at) > 12.0;
    let image = |fireflies: bool, report: bool| {
        move |p: Vec2| {
            let mut v = bump(p);
            if report {
                v.radiance_variance = Some(0.0);
                v.gradient_variance = Some(0.0);
            }
            if fireflies && is_firefly(p) {
                let x = 1.0; // X / N: the one path's share of the mean
                v.radiance += Vec3::splat(x);
                let g = 40.0 / 16.0; // the same path's gradient over 16 gradient paths
                let in_gradient = hash(p + Vec2::splat(0.5)) < 0.5;
                if in_gradient {
                    v.grad_u += Vec3::splat(g);
                }
                if report {
                    v.radiance_variance = Some(3.0 * x * x);
                    v.gradient_variance = Some(if in_gradient { 3.0 * g * g } else { 0.0 });
                }
            }
            v
        }
    };
    let near_bump = |s: &gradtrace::adaptive::Sample| s.pos.distance(bump_at) < 9.0;
    for strategy in [Strategy::Variance, Strategy::Gradient] {
        let share = |fireflies: bool, report: bool| {
            let settings = Settings::new(strategy, 0.1);
            let set = refine(&image(fireflies, report), w, h, &settings).unwrap();
            let near = set.samples.iter().filter(|s| near_bump(s)).count();
            let on_fireflies = set.samples.iter().filter(|s| is_firefly(s.pos)).count();
            let frac = near as f32 / set.samples.len() as f32;
            println!(
                "{}: fireflies {fireflies}, variances reported {report}: {:.1}% of the \
                 samples within 9 px of the bump, {on_fireflies} firefly samples",
                strategy.name(),
                100.0 * frac
            );
            frac
        };
        let clean = share(false, true);
        let unreported = share(true, false);
        let reported = share(true, true);
        assert!(
            reported >= 0.9 * clean,
            "{}: fireflies drew samples away from the bump: {reported} vs {clean} clean",
            strategy.name()
        );
        if strategy == Strategy::Variance {
            assert!(
                unreported < 0.8 * clean,
                "the unreported fireflies should have drawn samples (test power): \
                 {unreported} vs {clean}"
            );
        }
    }
}

/// When the budget cannot refine every object boundary to pixel size, the boundaries
/// with the larger radiance jump go first, whatever the strategy: two discs, one in
/// strong contrast with the background and one barely different from it.
#[test]
fn forced_refinement_takes_the_largest_jumps_first() {
    let (w, h) = (160u32, 80u32);
    let (ca, cb, r) = (Vec2::new(40.0, 40.0), Vec2::new(120.0, 40.0), 25.0);
    let img = move |p: Vec2| {
        let (a, b) = (p.distance(ca) < r, p.distance(cb) < r);
        let value = if a {
            1.0
        } else if b {
            0.21
        } else {
            0.2
        };
        let mut v = SampleValue::new(Vec3::splat(value), Vec3::ZERO, Vec3::ZERO);
        v.object_id = if a {
            1
        } else if b {
            2
        } else {
            0
        };
        v
    };
    let near_rim = |p: Vec2, c: Vec2| (p.distance(c) - r).abs() < 2.0;
    for strategy in [
        Strategy::Gradient,
        Strategy::Variance,
        Strategy::SecondOrder,
    ] {
        let set = refine(&img, w, h, &Settings::new(strategy, 0.08)).unwrap();
        let count = |c: Vec2| set.samples.iter().filter(|s| near_rim(s.pos, c)).count();
        let (na, nb) = (count(ca), count(cb));
        println!("{strategy:?}: {na} samples on the strong rim, {nb} on the faint one");
        assert!(na > 3 * nb, "{strategy:?}: {na} vs {nb}");
    }
}
