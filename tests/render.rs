//! End-to-end checks of the path tracer on scenes built in code: known answers
//! (furnace), light-sampling densities against their own integrals, determinism
//! across thread counts, and finiteness on hard configurations.

use gradtrace::accel::Accel;
use gradtrace::brdf::Material;
use gradtrace::math::sampler::PixelSampler;
use gradtrace::math::{Frame, Vec2, Vec3};
use gradtrace::render::lights::LightSet;
use gradtrace::render::path::PathTracer;
use gradtrace::render::{render, RenderOptions};
use gradtrace::scene::{Camera, Environment, Integrator, Rect, Scene};
use std::f32::consts::PI;

mod scenes;
use scenes::*;

fn render_scene(s: &Scene, spp: u32, aovs: bool) -> gradtrace::render::RenderOutput {
    let accel = Accel::build(&s.meshes, &s.spheres);
    let opts = RenderOptions {
        spp: Some(spp),
        aovs,
        ..Default::default()
    };
    render(s, &accel, &opts, &|_, _| {}).unwrap()
}

/// White furnace: a convex object inside a uniform environment. A path leaving a
/// convex surface never returns to it, so a pixel covering a fraction f of the
/// object sees L_env·(1 − f + f·ρ) for a reflector of albedo ρ; with ρ = 1 that is
/// L_env whatever f, for any BRDF that conserves energy. The albedo AOV averages
/// ρ over the same samples, which gives f per pixel.
#[test]
fn furnace_sphere_in_constant_environment() {
    let env = Vec3::new(0.5, 1.0, 2.0);
    for (material, rho) in [
        (Material::Lambert { albedo: Vec3::ONE }, 1.0),
        (
            Material::Lambert {
                albedo: Vec3::splat(0.5),
            },
            0.5,
        ),
        (
            Material::Mirror {
                reflectance: Vec3::splat(0.8),
            },
            0.8,
        ),
    ] {
        let mut s = empty_scene(camera(24, 16));
        let m = add_material(&mut s, material.clone());
        add_sphere(&mut s, Vec3::new(0.0, 0.5, 0.0), 1.0, m, Vec3::ZERO);
        s.environment = Some(Environment::Constant { radiance: env });
        let out = render_scene(&s, 64, true);
        let albedo = out.albedo.as_ref().unwrap();
        let (mut got, mut want) = (Vec3::ZERO, Vec3::ZERO);
        for (c, a) in out.beauty.iter().zip(albedo) {
            let f = a.x / rho;
            got += *c;
            want += env * (1.0 - f + f * rho);
            // Per pixel: the noise of 64 MIS samples of a constant is small.
            let expect = env * (1.0 - f + f * rho);
            assert!(
                (*c - expect).abs().max_element() < 0.05 * expect.max_element(),
                "{material:?}: {c} vs {expect}"
            );
        }
        assert!(
            (got - want).abs().max_element() < 2e-3 * want.max_element(),
            "{material:?}: sum {got} want {want}"
        );
    }
}

/// A diffuse plane lit by a small sphere light far away follows the inverse-square
/// law: irradiance E = Φ-free closed form L_e · π (r/d)² cos θ for a sphere of radius r at
/// distance d (exact for a sphere: the subtended cap gives π sin²α cos θ).
#[test]
fn sphere_light_irradiance_matches_closed_form() {
    // The camera looks at the origin from the side, below the light.
    let mut s =
        empty_scene(Camera::new(Vec3::new(1.5, 0.5, 0.0), Vec3::ZERO, Vec3::Y, 1.0, 8, 8).unwrap());
    let white = add_material(&mut s, Material::Lambert { albedo: Vec3::ONE });
    let black = add_material(&mut s, Material::Lambert { albedo: Vec3::ZERO });
    add_quad(&mut s, ground(50.0), white, Vec3::ZERO);
    let (r, d) = (0.25f32, 2.0f32);
    add_sphere(&mut s, Vec3::new(0.0, d, 0.0), r, black, Vec3::splat(10.0));
    s.settings.integrator = Integrator::Direct;
    let out = render_scene(&s, 256, false);
    // The camera sees a small patch straight below the light: cos θ ≈ 1.
    let _ = Camera::new;
    let sin2 = (r / d) * (r / d);
    let radiance = 10.0 * PI * sin2 / PI; // Lambert albedo 1: L = E / π.
    let centre = out.beauty[4 * 8 + 4];
    assert!(
        (centre.x - radiance).abs() < 0.02 * radiance,
        "{} vs {radiance}",
        centre.x
    );
}

/// The density each light-sampling routine reports must be the one it realises:
/// E[1/pdf] over samples equals the solid angle covered, and `pdf_emitter`
/// recomputes the same value from the sampled point.
#[test]
fn light_sample_densities_are_consistent() {
    let mut s = empty_scene(camera(4, 4));
    let black = add_material(&mut s, Material::Lambert { albedo: Vec3::ZERO });
    add_sphere(&mut s, Vec3::new(0.0, 3.0, 0.0), 0.5, black, Vec3::ONE);
    let lights = LightSet::build(&s);
    let p = Vec3::ZERO;
    let n = 40_000u32;
    let mut inv_pdf = 0.0f64;
    for i in 0..n {
        let mut smp = PixelSampler::new(0, i, 3);
        let ls = lights
            .sample(
                &s,
                p,
                &Frame::from_normal(Vec3::Y),
                smp.next_1d(),
                smp.next_2d(),
            )
            .unwrap();
        let (q, nq) = ls.point.unwrap();
        let again = lights.pdf_emitter(&s, gradtrace::accel::PrimRef::Sphere(0), p, q, nq);
        assert!(
            (again - ls.pdf).abs() < 1e-3 * ls.pdf,
            "{again} vs {}",
            ls.pdf
        );
        inv_pdf += 1.0 / ls.pdf as f64;
    }
    let cos_max = (1.0f64 - 0.25 / 9.0).sqrt();
    let solid_angle = 2.0 * std::f64::consts::PI * (1.0 - cos_max);
    assert!(((inv_pdf / n as f64) - solid_angle).abs() < 1e-3 * solid_angle);

    // A rectangle light: E[1/pdf] = its solid angle, estimated by brute force.
    let mut s2 = empty_scene(camera(4, 4));
    let black = add_material(&mut s2, Material::Lambert { albedo: Vec3::ZERO });
    let rect = Rect {
        corner: Vec3::new(-0.5, 2.0, -0.5),
        edge_u: Vec3::new(1.0, 0.0, 0.0),
        edge_v: Vec3::new(0.0, 0.0, 1.0),
    };
    assert!(rect.normal().y < 0.0, "light faces down");
    add_quad(&mut s2, rect, black, Vec3::ONE);
    let lights = LightSet::build(&s2);
    let mut est = 0.0f64;
    for i in 0..n {
        let mut smp = PixelSampler::new(1, i, 3);
        if let Some(ls) = lights.sample(
            &s2,
            p,
            &Frame::from_normal(Vec3::Y),
            smp.next_1d(),
            smp.next_2d(),
        ) {
            let (_, nq) = ls.point.unwrap();
            est += 1.0 / ls.pdf as f64;
            assert!(nq.y < 0.0);
        }
    }
    // Closed form: solid angle of a centred a×b rectangle at height h
    // Ω = 4 asin(ab / sqrt((a²+4h²)(b²+4h²))).
    let (a, b, h) = (1.0f64, 1.0f64, 2.0f64);
    let omega = 4.0 * (a * b / ((a * a + 4.0 * h * h) * (b * b + 4.0 * h * h)).sqrt()).asin();
    assert!(
        ((est / n as f64) - omega).abs() < 5e-3 * omega,
        "{} vs {omega}",
        est / n as f64
    );
}

/// A rectangle light is one light, sampled by (u, v) ↦ corner + u·edge_u + v·edge_v:
/// a k×k stratified pattern of (u, v) puts exactly one point in each cell of the
/// rectangle's k×k grid (picking one of its two triangles and warping the square
/// onto it does not), whatever `u_pick` is, and `pdf_emitter` on either of its
/// triangles returns the sample's own density (the MIS weight of a BSDF ray that
/// hits it).
#[test]
fn rectangle_light_samples_keep_their_strata_and_density() {
    let mut s = empty_scene(camera(4, 4));
    let black = add_material(&mut s, Material::Lambert { albedo: Vec3::ZERO });
    let rect = Rect {
        corner: Vec3::new(-0.3, 2.0, -0.2),
        edge_u: Vec3::new(0.6, 0.0, 0.0),
        edge_v: Vec3::new(0.0, 0.0, 0.4),
    };
    add_quad(&mut s, rect, black, Vec3::ONE);
    let lights = LightSet::build(&s);
    let p = Vec3::new(0.1, 0.0, 0.05);
    let k = 8;
    for u_pick in [0.0, 0.3, 0.99] {
        let mut cells = vec![0u32; k * k];
        for i in 0..k {
            for j in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                let ls = lights
                    .sample(&s, p, &Frame::from_normal(Vec3::Y), u_pick, u)
                    .unwrap();
                let (q, nq) = ls.point.unwrap();
                let d = q - rect.corner;
                let a = d.dot(rect.edge_u) / rect.edge_u.length_squared();
                let b = d.dot(rect.edge_v) / rect.edge_v.length_squared();
                assert!(d.dot(rect.normal()).abs() < 1e-6, "{q} off the plane");
                cells[(a * k as f32) as usize * k + (b * k as f32) as usize] += 1;
                for tri in 0..2 {
                    let prim = gradtrace::accel::PrimRef::Triangle { mesh: 0, tri };
                    let again = lights.pdf_emitter(&s, prim, p, q, nq);
                    assert!(
                        (again - ls.pdf).abs() <= 1e-5 * ls.pdf,
                        "triangle {tri}: {again} vs {}",
                        ls.pdf
                    );
                }
            }
        }
        assert!(cells.iter().all(|&c| c == 1), "{cells:?}");
    }
}

/// Gaussian-sky importance sampling: E[L/pdf] = ∫ L dω = 4π·ambient + peak·2π(1−e^{−2κ})/κ.
#[test]
fn gaussian_sky_sampling_integrates_the_sky() {
    for kappa in [2.0f32, 50.0, 2000.0] {
        let mut s = empty_scene(camera(4, 4));
        s.environment = Some(Environment::GaussianSky {
            direction: Vec3::new(0.2, 1.0, 0.1).normalize(),
            sharpness: kappa,
            peak: Vec3::splat(5.0),
            ambient: Vec3::splat(0.1),
        });
        let lights = LightSet::build(&s);
        let n = 50_000u32;
        let mut est = 0.0f64;
        for i in 0..n {
            let mut smp = PixelSampler::new(2, i, 9);
            let ls = lights
                .sample(
                    &s,
                    Vec3::ZERO,
                    &Frame::from_normal(Vec3::Y),
                    smp.next_1d(),
                    smp.next_2d(),
                )
                .unwrap();
            assert!((lights.pdf_env(&s, ls.wi, Vec3::Y) - ls.pdf).abs() < 1e-3 * ls.pdf);
            est += (ls.radiance.x / ls.pdf) as f64;
        }
        let k = kappa as f64;
        let exact = 4.0 * std::f64::consts::PI * 0.1
            + 5.0 * 2.0 * std::f64::consts::PI * (1.0 - (-2.0 * k).exp()) / k;
        let got = est / n as f64;
        assert!(
            (got - exact).abs() < 0.01 * exact,
            "kappa {kappa}: {got} vs {exact}"
        );
    }
}

/// The shading frame is a continuous function of the shading normal: two hits a
/// hair apart on either side of a mesh edge get nearly the same tangents, so that a
/// pixel's stratified BSDF and sky samples stay stratified across the triangles it
/// covers. A frame aligned with each triangle's dpdu fails this: neighbouring
/// triangles' parametrisations differ by tens of degrees.
#[test]
fn shading_frames_are_continuous_across_mesh_edges() {
    let mut s = empty_scene(camera(8, 8));
    let m = add_material(&mut s, Material::Lambert { albedo: Vec3::ONE });
    add_icosphere(&mut s, Vec3::ZERO, 1.0, 3, m);
    let accel = Accel::build(&s.meshes, &s.spheres);
    let (mut crossings, mut worst) = (0, 0.0f32);
    for i in 0..4000u32 {
        // Fibonacci directions over the sphere; each ray and a twin 2e-3 rad away.
        let z = 1.0 - (i as f32 + 0.5) / 2000.0;
        let phi = i as f32 * 2.399_963;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
        let side = Frame::from_normal(d).s;
        let hits = [d, (d + 2e-3 * side).normalize()].map(|d| {
            let ray = gradtrace::math::Ray::new(3.0 * d, -d);
            let hit = accel.intersect(&ray).expect("the sphere is hit");
            (
                hit.prim,
                gradtrace::render::interaction::interaction(&s, &accel, &ray, &hit).frame,
            )
        });
        let [(p1, f1), (p2, f2)] = hits;
        // Duff et al.'s frame flips with the sign of n.z, by design.
        if p1 == p2 || f1.n.z.abs() < 0.05 || f2.n.z.abs() < 0.05 || f1.n.z * f2.n.z < 0.0 {
            continue;
        }
        crossings += 1;
        let dn = (f1.n - f2.n).length();
        let ds = (f1.s - f2.s).length().max((f1.t - f2.t).length());
        worst = worst.max(ds / dn);
        assert!(
            ds <= 4.0 * dn + 1e-5,
            "ray {i}: |Δn| {dn:e}, |Δs|, |Δt| up to {ds:e}"
        );
    }
    assert!(crossings > 40, "only {crossings} edge crossings");
    println!("{crossings} crossings, |Δframe| / |Δn| up to {worst}");
}

/// Constant-environment sampling is cosine-weighted about the receiver's normal:
/// every sample lies in its hemisphere, `pdf_env` reproduces the density, and
/// E[cos θ · L / pdf] is the irradiance π·L, with zero variance (the estimator is
/// constant), for normals in every orientation.
#[test]
fn constant_environment_sampling_is_cosine_weighted_about_the_normal() {
    let mut s = empty_scene(camera(4, 4));
    s.environment = Some(Environment::Constant {
        radiance: Vec3::new(0.5, 1.0, 2.0),
    });
    let lights = LightSet::build(&s);
    for n in [
        Vec3::Y,
        Vec3::NEG_Z,
        Vec3::new(0.3, -0.8, 0.52).normalize(),
        Vec3::new(-1.0, 1e-4, 0.0).normalize(),
    ] {
        let count = 20_000u32;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for i in 0..count {
            let mut smp = PixelSampler::new(4, i, 2);
            let Some(ls) = lights.sample(
                &s,
                Vec3::ZERO,
                &Frame::from_normal(n),
                smp.next_1d(),
                smp.next_2d(),
            ) else {
                continue;
            };
            let cos = ls.wi.dot(n);
            assert!(cos > 0.0, "{n}: {ls:?} below the horizon");
            let again = lights.pdf_env(&s, ls.wi, n);
            assert!(
                (again - ls.pdf).abs() <= 1e-6 * ls.pdf,
                "{again} vs {}",
                ls.pdf
            );
            let e = (cos * ls.radiance.y / ls.pdf) as f64;
            sum += e;
            sum2 += e * e;
        }
        let mean = sum / count as f64;
        let var = sum2 / count as f64 - mean * mean;
        let exact = std::f64::consts::PI;
        assert!(
            (mean - exact).abs() < 2e-3 * exact,
            "{n}: {mean} vs {exact}"
        );
        assert!(var < 1e-6, "{n}: variance {var}");
        // Directions below the horizon have no density (BSDF samples there get
        // the full MIS weight).
        assert_eq!(lights.pdf_env(&s, -n, n), 0.0);
    }
}

/// Image environment sampling: E[L/pdf] over importance samples equals the
/// integral of the (bilinear) map computed by dense quadrature.
#[test]
fn image_environment_sampling_integrates_the_map() {
    let (w, h) = (32usize, 16usize);
    let mut texels = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let bright = if (x / 4 + y / 4) % 3 == 0 { 20.0 } else { 0.2 };
            texels.push(Vec3::new(bright, bright * 0.5, 1.0) * (1.0 + y as f32 / h as f32));
        }
    }
    let env = Environment::Image {
        width: w,
        height: h,
        texels,
        scale: 1.5,
    };
    let mut s = empty_scene(camera(4, 4));
    s.environment = Some(env.clone());
    let lights = LightSet::build(&s);
    // Quadrature on a fine lat-long grid.
    let (qw, qh) = (1024usize, 512usize);
    let mut exact = 0.0f64;
    for y in 0..qh {
        for x in 0..qw {
            let uv = Vec2::new((x as f32 + 0.5) / qw as f32, (y as f32 + 0.5) / qh as f32);
            let d = gradtrace::scene::environment::latlong_to_direction(uv);
            let st = (uv.y * PI).sin() as f64;
            exact += env.eval(d).x as f64 * st;
        }
    }
    exact *= 2.0 * std::f64::consts::PI * std::f64::consts::PI / (qw * qh) as f64;
    let n = 100_000u32;
    let mut est = 0.0f64;
    for i in 0..n {
        let mut smp = PixelSampler::new(5, i, 1);
        let (u1, u2) = (smp.next_1d(), smp.next_2d());
        let ls = lights
            .sample(&s, Vec3::ZERO, &Frame::from_normal(Vec3::Y), u1, u2)
            .unwrap_or_else(|| panic!("{u1} {u2}"));
        assert!((lights.pdf_env(&s, ls.wi, Vec3::Y) - ls.pdf).abs() < 1e-3 * ls.pdf.max(1e-3));
        // The radiance comes from the sampled (u, v), not from the direction:
        // the same lookup up to the round trip's rounding.
        let le = env.eval(ls.wi);
        assert!(
            (ls.radiance - le).abs().max_element() <= 1e-4 * le.max_element().max(1e-3),
            "{} vs {le}",
            ls.radiance
        );
        est += (ls.radiance.x / ls.pdf) as f64;
    }
    let got = est / n as f64;
    assert!((got - exact).abs() < 0.01 * exact, "{got} vs {exact}");
}

fn hard_scene() -> Scene {
    let mut s = empty_scene(camera(48, 32));
    let white = add_material(
        &mut s,
        Material::Lambert {
            albedo: Vec3::splat(0.8),
        },
    );
    let glossy = add_material(
        &mut s,
        Material::BlinnPhong {
            kd: Vec3::splat(0.2),
            ks: Vec3::splat(0.7),
            exponent: 1e5,
        },
    );
    let ct = add_material(
        &mut s,
        Material::CookTorrance {
            kd: Vec3::splat(0.3),
            ks: Vec3::splat(0.6),
            exponent: 3000.0,
        },
    );
    let mirror = add_material(
        &mut s,
        Material::Mirror {
            reflectance: Vec3::ONE,
        },
    );
    let black = add_material(&mut s, Material::Lambert { albedo: Vec3::ZERO });
    add_quad(&mut s, ground(4.0), white, Vec3::ZERO);
    // Spheres resting exactly on the ground (tangent contact), a light touching it.
    add_sphere(&mut s, Vec3::new(-1.2, 0.5, 0.0), 0.5, glossy, Vec3::ZERO);
    add_sphere(&mut s, Vec3::new(0.0, 0.5, 0.0), 0.5, ct, Vec3::ZERO);
    add_sphere(&mut s, Vec3::new(1.2, 0.5, 0.0), 0.5, mirror, Vec3::ZERO);
    add_sphere(
        &mut s,
        Vec3::new(0.0, 0.2, 1.2),
        0.2,
        black,
        Vec3::splat(50.0),
    );
    // A light grazing the ground: a rect standing on it, edge on the surface.
    add_quad(
        &mut s,
        Rect {
            corner: Vec3::new(-2.0, 0.0, -1.5),
            edge_u: Vec3::new(0.0, 1.0, 0.0),
            edge_v: Vec3::new(1.0, 0.0, 0.0),
        },
        black,
        Vec3::splat(5.0),
    );
    s.environment = Some(Environment::GaussianSky {
        direction: Vec3::Y,
        sharpness: 1e4,
        peak: Vec3::splat(100.0),
        ambient: Vec3::splat(0.05),
    });
    s
}

/// No sample of the estimator itself (before the accumulation guard) is NaN or Inf
/// on a scene of tangent contacts, touching and grazing lights, exponents up to
/// 10^5 and a near-delta sky.
#[test]
fn estimator_is_finite_on_hard_configurations() {
    let s = hard_scene();
    let traced = Traceable::new(&s);
    let tracer = traced.tracer(&s, 8, 3);
    let (w, h) = (s.camera.width, s.camera.height);
    let mut bad = 0;
    let mut nonzero = 0;
    for y in 0..h {
        for x in 0..w {
            for i in 0..4 {
                let mut smp = PixelSampler::new(y * w + x, i, 0);
                let p = Vec2::new(x as f32, y as f32) + smp.next_2d();
                let r = tracer.li(s.camera.generate_ray(p), &mut smp, None);
                if !r.radiance.is_finite() || r.radiance.min_element() < 0.0 {
                    bad += 1;
                }
                if r.radiance.max_element() > 0.0 {
                    nonzero += 1;
                }
            }
        }
    }
    assert_eq!(bad, 0, "non-finite or negative samples");
    assert!(nonzero > (w * h) as usize, "the scene is lit");
}

/// The image is bit-identical whatever the number of threads.
#[test]
fn image_is_identical_for_any_thread_count() {
    let s = hard_scene();
    let accel = Accel::build(&s.meshes, &s.spheres);
    let opts = RenderOptions {
        spp: Some(4),
        aovs: true,
        ..Default::default()
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render(&s, &accel, &opts, &|_, _| {}).unwrap())
    };
    let a = run(1);
    let b = run(3);
    assert!(a
        .beauty
        .iter()
        .zip(&b.beauty)
        .all(|(x, y)| x.to_array() == y.to_array()));
    assert_eq!(
        a.variance.as_ref().unwrap().len(),
        b.variance.as_ref().unwrap().len()
    );
    assert!(a
        .variance
        .unwrap()
        .iter()
        .zip(b.variance.unwrap().iter())
        .all(|(x, y)| x.to_array() == y.to_array()));
    // A different seed changes the noise.
    let c = render(
        &s,
        &accel,
        &RenderOptions {
            seed: Some(7),
            ..opts.clone()
        },
        &|_, _| {},
    )
    .unwrap();
    assert!(a.beauty.iter().zip(&c.beauty).any(|(x, y)| x != y));
}

/// Every AOV plane exists when asked, has the right size and is finite; none
/// exist when not asked (no work nobody asked for).
#[test]
fn aov_planes_are_finite_and_only_when_asked() {
    let s = hard_scene();
    let out = render_scene(&s, 2, true);
    let n = out.width * out.height;
    for v in [
        out.variance.as_ref().unwrap(),
        out.normal.as_ref().unwrap(),
        out.albedo.as_ref().unwrap(),
    ] {
        assert_eq!(v.len(), n);
        assert!(v.iter().all(|c| c.is_finite()));
    }
    assert!(out
        .depth
        .as_ref()
        .unwrap()
        .iter()
        .all(|d| d.is_finite() && *d >= 0.0));
    let ids = out.object_id.as_ref().unwrap();
    assert!(ids.contains(&1.0), "the ground is visible");
    let plain = render_scene(&s, 1, false);
    assert!(plain.normal.is_none() && plain.variance.is_none() && plain.object_id.is_none());
}

/// With gradients on (line sampling, visibility jumps, dual-number terms), no
/// per-sample value — radiance or any gradient term — is NaN or Inf on the hard
/// scene: tangent contacts, a light touching the ground, grazing rays, a
/// near-delta sky, exponents up to 10^5, silhouettes everywhere.
#[test]
fn gradients_are_finite_on_hard_configurations() {
    use gradtrace::render::camera_sample;
    use gradtrace::render::path::LineConfig;
    let s = hard_scene();
    let traced = Traceable::new(&s);
    for refine in [0, 6] {
        let tracer = PathTracer {
            lines: Some(LineConfig {
                n_theta: 16,
                refine,
                gate: 0.25,
            }),
            far_light: Some(4.0),
            ..traced.tracer(&s, 4, 3)
        };
        let (mut bad, mut with_vis) = (0, 0);
        for pixel in 0..s.camera.width * s.camera.height {
            for i in 0..2 {
                let r = camera_sample(&tracer, &s.camera, pixel, i, 3, true, Vec2::ZERO);
                let g = r.gradient.unwrap_or_default();
                let all = [r.radiance, g.value]
                    .into_iter()
                    .chain(g.sv)
                    .chain(g.cdv)
                    .chain(g.cam)
                    .chain(g.dv)
                    .chain(g.vis);
                if !all.into_iter().all(|v| v.is_finite()) || !g.cv.is_finite() {
                    bad += 1;
                }
                if g.vis[0] != Vec3::ZERO {
                    with_vis += 1;
                }
            }
        }
        assert_eq!(bad, 0, "refine {refine}: non-finite samples");
        assert!(
            with_vis > 50,
            "the scene has soft shadows ({with_vis} samples)"
        );
    }
}

/// Line sampling (with --gradients) estimates the same image as point sampling,
/// also when the scene mixes line-covered lights (a rectangle, a sphere, the sky)
/// with a mesh emitter that only point sampling handles.
#[test]
fn line_sampling_renders_the_same_image_as_point_sampling() {
    let mut s = empty_scene(camera(32, 24));
    let (_, black) = add_sphere_under_square_light(&mut s, 0.7, 0.5, 0.5, 0.5, 4.0);
    // The same shape as a plain mesh emitter (no `rect`): point-sampled only.
    add_quad(
        &mut s,
        Rect {
            corner: Vec3::new(1.0, 1.5, -0.5),
            edge_u: Vec3::new(0.8, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.0, 0.8),
        },
        black,
        Vec3::splat(3.0),
    );
    s.meshes.last_mut().unwrap().rect = None;
    add_sphere(
        &mut s,
        Vec3::new(-1.2, 1.2, 0.3),
        0.2,
        black,
        Vec3::splat(10.0),
    );
    s.environment = Some(Environment::Constant {
        radiance: Vec3::splat(0.2),
    });
    let accel = Accel::build(&s.meshes, &s.spheres);
    let mean = |gradients: bool| {
        let opts = RenderOptions {
            spp: Some(256),
            gradients,
            vis_samples: Some(8),
            ..Default::default()
        };
        let out = render(&s, &accel, &opts, &|_, _| {}).unwrap();
        out.beauty.iter().fold(Vec3::ZERO, |a, &b| a + b) / out.beauty.len() as f32
    };
    let (points, lines) = (mean(false), mean(true));
    assert!(
        (points - lines).abs().max_element() < 0.01 * points.max_element(),
        "point sampling {points} vs line sampling {lines}"
    );
}

/// A bump map tilts the shading normal away from the camera near a sphere's
/// silhouette: there the path ends at the first hit (the terminator's black dots),
/// and the first hit says so (`back_facing`), which the adaptive sampler treats as a
/// boundary. Every such sample must be black; the others near the rim must not all be.
#[test]
fn back_facing_shading_normals_are_flagged_and_black() {
    let mut s = empty_scene(camera(48, 36));
    let m = add_material(
        &mut s,
        Material::Lambert {
            albedo: Vec3::splat(0.7),
        },
    );
    add_sphere(&mut s, Vec3::new(0.0, 0.5, 0.0), 1.0, m, Vec3::ZERO);
    let b = add_bump(&mut s, &[(0.03, [16.0, 0.0], 0.0), (0.03, [0.0, 8.0], 0.5)]);
    s.spheres[0].bump = Some(b);
    s.environment = Some(Environment::Constant {
        radiance: Vec3::ONE,
    });
    let traced = Traceable::new(&s);
    let tracer = traced.tracer(&s, 4, 5);
    let (mut back, mut front) = (0, 0);
    for pixel in 0..s.camera.width * s.camera.height {
        for i in 0..4 {
            let r = gradtrace::render::camera_sample(
                &tracer,
                &s.camera,
                pixel,
                i,
                0,
                false,
                Vec2::ZERO,
            );
            let Some(fh) = r.first_hit else { continue };
            if fh.back_facing {
                back += 1;
                assert_eq!(
                    r.radiance,
                    Vec3::ZERO,
                    "pixel {pixel}: a back-facing hit is black"
                );
            } else {
                front += 1;
            }
        }
    }
    println!("{back} back-facing and {front} front-facing first hits");
    assert!(back > 10 && front > 3 * back);
    // The adaptive sampler's estimator passes the flag on (one camera sample per
    // estimate, so a flagged estimate is black too).
    let est = gradtrace::render::point::PointEstimator {
        tracer,
        camera: &s.camera,
        spp: 1,
        gradient_spp: 1,
        timing: Default::default(),
        seed: 0,
    };
    let mut flagged = 0;
    for j in 0..72 {
        for i in 0..96 {
            let v = est.estimate(Vec2::new(i as f32 * 0.5 + 0.25, j as f32 * 0.5 + 0.25));
            if v.back_facing {
                flagged += 1;
                assert_eq!(v.radiance, Vec3::ZERO);
            }
        }
    }
    println!("{flagged} flagged estimates");
    assert!(flagged > 10);
}

/// The soft-shadow scene (a sphere resting on the ground under a square light)
/// renders the same 10⁴ units from the origin as at it: the ray offsets are the
/// hit points' own rounding bounds (`accel::offset`), not a fraction of the
/// coordinates — the path tracer's earlier 1e-4·|p| offset was a whole unit
/// there, above the sphere, and lifted every shadow ray off the ground.
/// Compared 8×8-pixel block means against the seed-to-seed noise at the origin.
#[test]
fn a_scene_far_from_the_origin_renders_as_it_does_at_the_origin() {
    let build = |shift: Vec3| {
        let cam = Camera::new(
            Vec3::new(0.0, 1.5, 5.0) + shift,
            Vec3::new(0.0, 0.3, 0.0) + shift,
            Vec3::Y,
            35.0,
            48,
            32,
        )
        .unwrap();
        let mut s = empty_scene(cam);
        add_sphere_under_square_light(&mut s, 0.8, 0.5, 0.5, 0.4, 12.0);
        for m in &mut s.meshes {
            m.positions.iter_mut().for_each(|p| *p += shift);
            if let Some(r) = &mut m.rect {
                r.corner += shift;
            }
        }
        s.spheres.iter_mut().for_each(|sp| sp.center += shift);
        s.settings.max_depth = 4;
        s
    };
    let render_with = |s: &Scene, seed: u32| {
        let accel = Accel::build(&s.meshes, &s.spheres);
        let opts = RenderOptions {
            spp: Some(64),
            seed: Some(seed),
            ..Default::default()
        };
        render(s, &accel, &opts, &|_, _| {}).unwrap()
    };
    let blocks = |img: &gradtrace::render::RenderOutput| -> Vec<f32> {
        let mut out = Vec::new();
        for by in 0..img.height / 8 {
            for bx in 0..img.width / 8 {
                let mut sum = 0.0;
                for y in 0..8 {
                    for x in 0..8 {
                        let c = img.beauty[(by * 8 + y) * img.width + bx * 8 + x];
                        sum += c.x + c.y + c.z;
                    }
                }
                out.push(sum / 64.0);
            }
        }
        out
    };
    let worst = |a: &[f32], b: &[f32]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs() / x.abs().max(y.abs()).max(0.05))
            .fold(0.0f32, f32::max)
    };
    let here = build(Vec3::ZERO);
    let (a, b) = (
        blocks(&render_with(&here, 1)),
        blocks(&render_with(&here, 2)),
    );
    let far = blocks(&render_with(&build(Vec3::new(1.0e4, 0.0, -1.0e4)), 1));
    let (noise, shift) = (worst(&a, &b), worst(&a, &far));
    println!("worst block difference: seed to seed {noise:.4}, origin to 1e4 away {shift:.4}");
    assert!(shift < 2.0 * noise + 0.01, "{shift} against noise {noise}");
}

/// Scenes the lane shading takes (Lambertian meshes under a rectangle light;
/// Lambertian and mirror spheres under an image environment; Lambertian
/// spheres under a Gaussian sky): every plane of the image is `li`'s bit for
/// bit (`--no-lanes`), at any thread count.
#[test]
fn lane_shading_renders_li_image() {
    for path in [
        "scenes/validation/cornell_256.toml",
        "scenes/validation/env_image.toml",
        "scenes/three_spheres_env.toml",
    ] {
        let s = gradtrace::scene::load(std::path::Path::new(path)).expect("bundled scene");
        lane_image_is_li_image(&s);
    }
}

fn lane_image_is_li_image(s: &gradtrace::scene::Scene) {
    let accel = Accel::build(&s.meshes, &s.spheres);
    let run = |threads: usize, no_lanes: bool| {
        let opts = RenderOptions {
            spp: Some(6),
            resolution: Some((40, 36)),
            aovs: true,
            no_lanes,
            ..Default::default()
        };
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| render(s, &accel, &opts, &|_, _| {}).unwrap())
    };
    let planes = |o: &gradtrace::render::RenderOutput| -> Vec<[u32; 3]> {
        [
            Some(&o.beauty),
            o.variance.as_ref(),
            o.normal.as_ref(),
            o.albedo.as_ref(),
        ]
        .into_iter()
        .flat_map(|p| p.expect("planes asked for").iter())
        .map(|v| v.to_array().map(f32::to_bits))
        .collect()
    };
    let scalar = run(2, true);
    assert!(scalar.beauty.iter().any(|v| v.x > 0.0), "the scene is lit");
    for threads in [1, 3] {
        let lanes = run(threads, false);
        assert!(planes(&lanes) == planes(&scalar), "{threads} threads");
        assert_eq!(
            lanes
                .depth
                .as_ref()
                .map(|d| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>()),
            scalar
                .depth
                .as_ref()
                .map(|d| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
        );
    }
}
