//! Delaunay reconstruction on analytic images: exactness on linear functions,
//! agreement with spade's own Sibson C1 interpolant, C1 beating linear on a smooth image,
//! no blending across silhouettes, and the density plane.

mod common;

use common::perspective_floor;
use gradtrace::adaptive::{refine, Sample, SampleSet, SampleValue, Settings, Strategy};
use gradtrace::math::{Vec2, Vec3};
use gradtrace::reconstruct::{reconstruct, reconstruct_with, Interpolation, Options};
use spade::{DelaunayTriangulation, HasPosition, Point2, Triangulation};

/// A per-channel linear image `a + b·u + c·v`.
fn linear(p: Vec2) -> SampleValue {
    let b = Vec3::new(0.013, -0.021, 0.004);
    let c = Vec3::new(-0.007, 0.011, 0.019);
    let a = Vec3::new(0.5, 2.0, -1.0);
    SampleValue::new(a + b * p.x + c * p.y, b, c)
}

/// A smooth image: sin(u/9)·cos(v/7) (+ channel offsets), with its exact gradient.
fn sincos(p: Vec2) -> SampleValue {
    let (sx, cx) = (p.x / 9.0).sin_cos();
    let (sy, cy) = (p.y / 7.0).sin_cos();
    let v = sx * cy;
    let gu = cx * cy / 9.0;
    let gv = -sx * sy / 7.0;
    SampleValue::new(
        Vec3::new(v, 0.5 * v + 1.0, 2.0 - v),
        Vec3::new(gu, 0.5 * gu, -gu),
        Vec3::new(gv, 0.5 * gv, -gv),
    )
}

fn rmse(set: &SampleSet, mode: Interpolation, truth: impl Fn(Vec2) -> SampleValue) -> f64 {
    let r = reconstruct(set, mode).unwrap();
    let mut sum = 0.0f64;
    for y in 0..r.height {
        for x in 0..r.width {
            let t = truth(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)).radiance;
            let d = (r.image[y * r.width + x] - t).as_dvec3();
            sum += d.length_squared() / 3.0;
        }
    }
    (sum / (r.width * r.height) as f64).sqrt()
}

/// Point-sized samples of `f` at `positions` (no quadtree cells, so no border ghosts).
fn point_samples(
    width: u32,
    height: u32,
    positions: impl IntoIterator<Item = Vec2>,
    f: impl Fn(Vec2) -> SampleValue,
) -> SampleSet {
    let samples = positions
        .into_iter()
        .map(|pos| Sample {
            pos,
            cell_min: pos,
            cell_max: pos,
            split: 0,
            value: f(pos),
        })
        .collect();
    SampleSet {
        width,
        height,
        samples,
        depth_tolerance: 0.1,
    }
}

/// Samples at arbitrary positions (no quadtree), e.g. a jittered lattice.
fn scattered(width: u32, height: u32, n: usize, f: impl Fn(Vec2) -> SampleValue) -> SampleSet {
    // Rank-1 lattice (Fibonacci-like), deterministic and well spread.
    let positions = (0..n).map(|k| {
        let u = (k as f32 + 0.5) / n as f32;
        let v = (k as f32 * 0.618_034).fract();
        Vec2::new(u * width as f32, v * height as f32)
    });
    point_samples(width, height, positions, f)
}

#[test]
fn linear_and_c1_are_exact_on_linear_images() {
    let sets = [
        refine(&linear, 96, 64, &Settings::new(Strategy::Gradient, 0.1)).unwrap(),
        refine(&linear, 96, 64, &Settings::new(Strategy::Uniform, 0.07)).unwrap(),
        refine(&linear, 37, 53, &Settings::new(Strategy::Variance, 0.3)).unwrap(),
        scattered(80, 50, 211, linear),
    ];
    for (k, set) in sets.iter().enumerate() {
        for mode in [Interpolation::Linear, Interpolation::Gradient] {
            let r = reconstruct(set, mode).unwrap();
            let mut worst = 0.0f32;
            for y in 0..r.height {
                for x in 0..r.width {
                    let t = linear(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)).radiance;
                    worst = worst.max((r.image[y * r.width + x] - t).abs().max_element());
                }
            }
            println!("set {k} {:?}: max error {worst:.2e}", mode);
            assert!(worst < 1e-4, "set {k} {mode:?}: max error {worst}");
        }
    }
}

/// Samples all on one line (a row, a diagonal) span no triangle; the pixels on that
/// line lie on the hull and are interpolated along it, exactly on a linear image.
/// (The triangulation nudges its vertices off exact cocircularity, which turns the
/// line into slivers; a pixel on the line must still count as on it.)
#[test]
fn collinear_samples_interpolate_along_their_line() {
    let lines: [(&str, Vec<Vec2>); 2] = [
        (
            "row",
            (0..6)
                .map(|k| Vec2::new(2.0 * k as f32 + 0.5, 4.5))
                .collect(),
        ),
        (
            "diagonal",
            (0..6).map(|k| Vec2::splat(2.0 * k as f32 + 0.5)).collect(),
        ),
    ];
    for (name, points) in lines {
        let set = point_samples(14, 12, points.iter().copied(), linear);
        let (first, last) = (points[0], points[points.len() - 1]);
        for mode in [Interpolation::Linear, Interpolation::Gradient] {
            let r = reconstruct(&set, mode).unwrap();
            let mut on_line = 0;
            for y in 0..r.height {
                for x in 0..r.width {
                    let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    let t = (p - first).dot(last - first) / (last - first).length_squared();
                    if !(0.0..=1.0).contains(&t) || (first + (last - first) * t).distance(p) > 1e-4
                    {
                        continue;
                    }
                    on_line += 1;
                    let err = (r.image[y * r.width + x] - linear(p).radiance)
                        .abs()
                        .max_element();
                    assert!(err < 1e-4, "{name} {mode:?}: error {err} at ({x}, {y})");
                }
            }
            assert_eq!(on_line, 11, "{name}: pixels on the line");
        }
    }
}

struct Pt {
    pos: Point2<f64>,
    h: f64,
    g: [f64; 2],
}

impl HasPosition for Pt {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.pos
    }
}

/// Our per-channel Sibson C1 (written out to allow neighbour filtering) must equal
/// spade's `interpolate_gradient` with flatness 0.5 inside the hull, when the
/// gradients are used as sampled (no slope limiter; the point-sized cells of
/// `scattered` touch no border, so no mirror samples are added).
#[test]
fn c1_matches_spade_interpolate_gradient() {
    let (w, h) = (64u32, 48u32);
    let set = scattered(w, h, 160, sincos);
    let raw = Options {
        slope_limiter: false,
    };
    let r = reconstruct_with(&set, Interpolation::Gradient, &raw).unwrap();
    for (ch, pick) in [|v: Vec3| v.x, |v: Vec3| v.y, |v: Vec3| v.z]
        .into_iter()
        .enumerate()
    {
        let pts: Vec<Pt> = set
            .samples
            .iter()
            .map(|s| Pt {
                pos: Point2::new(s.pos.x as f64, s.pos.y as f64),
                h: pick(s.value.radiance) as f64,
                g: [pick(s.value.grad_u) as f64, pick(s.value.grad_v) as f64],
            })
            .collect();
        let dt = DelaunayTriangulation::<Pt>::bulk_load(pts).unwrap();
        let nn = dt.natural_neighbor();
        let mut compared = 0;
        for y in 0..h as usize {
            for x in 0..w as usize {
                let p = Point2::new(x as f64 + 0.5, y as f64 + 0.5);
                if let Some(v) = nn.interpolate_gradient(|v| v.data().h, |v| v.data().g, 0.5, p) {
                    let ours = pick(r.image[y * w as usize + x]) as f64;
                    assert!(
                        (ours - v).abs() < 1e-5,
                        "channel {ch} at ({x},{y}): {ours} vs {v}"
                    );
                    compared += 1;
                }
            }
        }
        assert!(
            compared > (w * h) as usize / 2,
            "only {compared} pixels inside the hull"
        );
    }
}

#[test]
fn c1_beats_linear_on_smooth_image() {
    for strategy in [Strategy::Uniform, Strategy::Gradient] {
        let set = refine(&sincos, 128, 128, &Settings::new(strategy, 0.05)).unwrap();
        let lin = rmse(&set, Interpolation::Linear, sincos);
        let c1 = rmse(&set, Interpolation::Gradient, sincos);
        println!(
            "sin·cos 128x128, {} samples ({:?}): RMSE linear {lin:.3e}, C1 {c1:.3e} (ratio {:.2})",
            set.samples.len(),
            strategy,
            lin / c1
        );
        assert!(c1 < 0.5 * lin, "C1 {c1} not clearly below linear {lin}");
    }
}

/// A disc (value 1) on a background (value 0), constant per surface; the disc is
/// another object, or the same object at a fifth of the depth, or a fold of a
/// receding floor (raised 3% towards the camera, where the floor's own depth changes
/// 5% per 8 pixels), or a facet of a flat-shaded surface tilted by 10° (a crease), or
/// the background is the same object's back-facing side (a bump map's terminator,
/// black). No pixel may be a blend of the two (0 < v < 1), whatever the sample
/// layout; once the quadtree has refined the silhouette to pixel size, every pixel
/// also gets its own surface. The uniform layout leaves pixel centres between
/// samples of both surfaces, which is where a missing silhouette rule would blend.
#[test]
fn never_interpolates_across_silhouettes() {
    for by in ["object id", "depth", "fold", "crease", "terminator"] {
        let disc = move |p: Vec2| {
            let inside = p.distance(Vec2::new(50.3, 41.7)) < 23.0;
            let mut v = SampleValue::new(Vec3::splat(inside as u32 as f32), Vec3::ZERO, Vec3::ZERO);
            match by {
                "object id" => v.object_id = inside as u32,
                "depth" if inside => v.depth = 0.2,
                "fold" => {
                    let lift = if inside { 0.03 } else { 0.0 };
                    (v.depth, v.inv_depth_grad) = perspective_floor(p, lift);
                }
                "crease" => {
                    let tilt = if inside { 10f32.to_radians() } else { 0.0 };
                    v.facet_normal = Some(Vec3::new(tilt.sin(), 0.0, tilt.cos()));
                }
                "terminator" => v.back_facing = !inside,
                _ => {}
            }
            v
        };
        for strategy in [Strategy::Gradient, Strategy::Uniform] {
            // The whole budget may go to the boundary: what is tested is the
            // reconstruction's rule once the silhouette is refined.
            let settings = Settings {
                boundary_share: 1.0,
                ..Settings::new(strategy, 0.25)
            };
            let set = refine(&disc, 100, 90, &settings).unwrap();
            for mode in [Interpolation::Linear, Interpolation::Gradient] {
                let r = reconstruct(&set, mode).unwrap();
                let mut wrong = 0;
                let mut blended = 0;
                for y in 0..r.height {
                    for x in 0..r.width {
                        let v = r.image[y * r.width + x].x;
                        let t = disc(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)).radiance.x;
                        if v > 1e-5 && v < 1.0 - 1e-5 {
                            blended += 1;
                        } else if (v - t).abs() > 1e-5 {
                            wrong += 1;
                        }
                    }
                }
                println!(
                    "disc by {by}, {strategy:?} samples, {mode:?}: {blended} blended pixels, \
                     {wrong} pixels of the wrong surface"
                );
                assert_eq!(blended, 0);
                if strategy != Strategy::Uniform {
                    assert_eq!(wrong, 0);
                }
            }
        }
    }
}

#[test]
fn density_plane_counts_samples() {
    let set = refine(&sincos, 70, 45, &Settings::new(Strategy::Gradient, 0.2)).unwrap();
    let r = reconstruct(&set, Interpolation::Linear).unwrap();
    let total: f32 = r.density.iter().sum();
    assert_eq!(total as usize, set.samples.len());
    assert_eq!(r.density.len(), 70 * 45);
    let img = gradtrace::pipeline::output_set::image_of_reconstruction(&r);
    let names: Vec<&str> = img.channels.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["R", "G", "B", "samples.density", "samples.Y"]);
}

#[test]
fn degenerate_inputs() {
    // No samples: an error, not a panic.
    let empty = SampleSet {
        width: 8,
        height: 8,
        samples: vec![],
        depth_tolerance: 0.1,
    };
    assert!(reconstruct(&empty, Interpolation::Linear).is_err());
    // One sample, or collinear samples: constant / Taylor extrapolation everywhere.
    for n in [1usize, 5] {
        let positions = (0..n).map(|k| Vec2::new(2.0 + 3.0 * k as f32, 4.0));
        let set = point_samples(20, 9, positions, linear);
        for mode in [Interpolation::Linear, Interpolation::Gradient] {
            let r = reconstruct(&set, mode).unwrap();
            assert!(
                r.image.iter().all(|c| c.is_finite()),
                "{n} samples, {mode:?}"
            );
        }
        // C1 extrapolates with the analytic gradient, so it stays exact.
        let r = reconstruct(&set, Interpolation::Gradient).unwrap();
        let t = linear(Vec2::new(10.5, 7.5)).radiance;
        assert!((r.image[7 * 20 + 10] - t).abs().max_element() < 1e-4);
    }
    // Non-finite positions are rejected.
    let mut bad = scattered(10, 10, 20, linear);
    bad.samples[3].pos.x = f32::NAN;
    assert!(reconstruct(&bad, Interpolation::Gradient).is_err());
}

/// One sample with a wild gradient (a heavy-tailed Monte Carlo visibility term, say)
/// in a coarse layout. Unlimited, Sibson's Taylor terms spread it over the cell as a
/// blob far outside the image's range; the Barth–Jespersen limiter keeps every pixel
/// within the range of the samples, and leaves the rest of the image as accurate as
/// before.
#[test]
fn slope_limiter_contains_an_outlier_gradient() {
    let (w, h) = (96u32, 64u32);
    let mut set = refine(&sincos, w, h, &Settings::new(Strategy::Uniform, 0.04)).unwrap();
    let k = set
        .samples
        .iter()
        .position(|s| s.pos.distance(Vec2::new(48.0, 32.0)) < 6.0)
        .unwrap();
    set.samples[k].value.grad_u += Vec3::splat(3.0);
    let truth = |x: usize, y: usize| sincos(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)).radiance;
    let worst = |opts: &Options| {
        let r = reconstruct_with(&set, Interpolation::Gradient, opts).unwrap();
        let mut worst = 0.0f32;
        for y in 0..r.height {
            for x in 0..r.width {
                worst = worst.max((r.image[y * r.width + x] - truth(x, y)).abs().max_element());
            }
        }
        worst
    };
    let limited = worst(&Options::default());
    let raw = worst(&Options {
        slope_limiter: false,
    });
    println!("outlier gradient: worst pixel error {raw:.3} unlimited, {limited:.3} limited");
    // sin·cos spans [-1, 1] (plus offsets); samples are ~5 px apart.
    assert!(
        raw > 1.5,
        "the outlier should show without the limiter ({raw})"
    );
    assert!(
        limited < 0.4,
        "limited reconstruction still off by {limited}"
    );
    // On the clean image the limiter costs little accuracy.
    let clean = refine(&sincos, w, h, &Settings::new(Strategy::Uniform, 0.04)).unwrap();
    let lin = rmse(&clean, Interpolation::Linear, sincos);
    let c1 = rmse(&clean, Interpolation::Gradient, sincos);
    println!("clean sin·cos: RMSE linear {lin:.3e}, limited C1 {c1:.3e}");
    assert!(c1 < 0.6 * lin);
}

/// Pixels in the strip between the image border and the outermost samples (up to
/// half a block wide) are interpolated from the samples next to them: the mirror
/// samples close the hull. Two objects meet along a horizontal line; without the
/// mirrors the Delaunay slivers along the left border handed border pixels values
/// from the far side of that line (dark columns in rendered images).
#[test]
fn border_strip_uses_its_own_surface() {
    let (w, h) = (120u32, 80u32);
    // Above the horizon: background (no object, infinite depth, black); below: a
    // ground plane receding towards it (inverse depth affine in y, as seen through a
    // pinhole), lit by a ramp.
    let img = |p: Vec2| {
        let below = p.y > 37.3;
        if !below {
            let mut v = SampleValue::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
            v.object_id = gradtrace::adaptive::NO_OBJECT;
            v.depth = f32::INFINITY;
            return v;
        }
        let mut v = SampleValue::new(Vec3::splat(2.0 + 0.01 * p.x), Vec3::splat(0.01), Vec3::ZERO);
        v.depth = 1.0 / (0.02 + 0.0005 * (p.y - 37.3));
        v.inv_depth_grad = Vec2::new(0.0, 0.0005);
        v
    };
    for strategy in [Strategy::Gradient, Strategy::Variance] {
        let set = refine(&img, w, h, &Settings::new(strategy, 0.08)).unwrap();
        for mode in [Interpolation::Linear, Interpolation::Gradient] {
            let r = reconstruct(&set, mode).unwrap();
            let mut worst = 0.0f32;
            for y in 0..r.height {
                for x in (0..4).chain(r.width - 4..r.width) {
                    let t = img(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)).radiance;
                    // Next to the horizon a pixel keeps only its own surface's
                    // samples (renormalised weights, not exact on the ramp).
                    if (y as f32 + 0.5 - 37.3).abs() < 2.0 {
                        continue;
                    }
                    worst = worst.max((r.image[y * r.width + x] - t).abs().max_element());
                }
            }
            println!("{strategy:?} {mode:?}: worst border-strip error {worst:.2e}");
            // The other surface is 2 away (without the mirrors: errors of 3.2).
            assert!(worst < 1e-3, "{strategy:?} {mode:?}: {worst}");
        }
    }
}
