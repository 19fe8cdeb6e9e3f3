//! Shadow fields: the OOF of a sphere against its closed-form visibility cap, the
//! SRF of a sphere light against its radiance cap, field interpolation, and the
//! preview against the path tracer end to end (`pipeline::preview::shadow_field::run`).

use glam::{DVec3, Vec3};
use gradtrace::math::sh::{self, COEFFS};
use gradtrace::pipeline::preview::shadow_field::{run, ShadowFieldOptions};
use gradtrace::preview::shadow_field::precompute::EntityGeometry;
use gradtrace::preview::shadow_field::Settings;
use gradtrace::scene::Sphere;
use std::path::PathBuf;

fn sphere(center: Vec3, radius: f32, emission: Vec3) -> Sphere {
    Sphere {
        name: "s".into(),
        center,
        radius,
        material: 0,
        emission,
        bump: None,
        object_id: 1,
    }
}

/// L2 norm of the difference of two SH functions over the sphere, relative to the
/// norm of the reference (Parseval: the coefficient vectors' distance).
fn rel_l2(a: &[f32; COEFFS], b: &sh::Sh) -> f64 {
    let d: f64 = (0..COEFFS).map(|k| (a[k] as f64 - b[k]).powi(2)).sum();
    let n: f64 = b.iter().map(|x| x * x).sum();
    (d / n).sqrt()
}

#[test]
fn sphere_occlusion_field_matches_the_closed_form_cap() {
    let (c, r) = (Vec3::new(0.3, -0.2, 0.5), 0.7);
    let geo = EntityGeometry::from_shapes(&[], &[sphere(c, r, Vec3::ZERO)]);
    for (k, d) in [1.05f32, 1.5, 3.0, 8.0].into_iter().enumerate() {
        let dir = Vec3::new(0.3, 0.8, -0.52 + 0.1 * k as f32).normalize();
        let p = c + dir * d * r;
        let got = geo.sample(p, c, r, 32, false).occlusion;
        let sin = 1.0 / d as f64;
        let want = sh::cap(-dir.as_dvec3(), (1.0 - sin * sin).sqrt());
        let err = rel_l2(&got, &want);
        // 32² stratified rays over the cone the sphere fills: the cap is resolved
        // to well under 1% (a bound a wrong cone or weight misses by far).
        assert!(err < 5e-3, "d = {d} R: relative L2 error {err}");
    }
}

#[test]
fn sphere_light_radiance_field_matches_its_cap() {
    let (c, r, le) = (Vec3::ZERO, 0.3, Vec3::new(2.0, 1.0, 0.5));
    let geo = EntityGeometry::from_shapes(&[], &[sphere(c, r, le)]);
    let p = Vec3::new(0.4, 1.1, -0.3);
    let s = geo.sample(p, c, r, 32, true);
    let d = p.length() as f64;
    let sin = r as f64 / d;
    let cap = sh::cap((c - p).normalize().as_dvec3(), (1.0 - sin * sin).sqrt());
    for ch in 0..3 {
        let want = cap.map(|x| x * le[ch] as f64);
        assert!(rel_l2(&s.radiance[ch], &want) < 5e-3);
    }
}

#[test]
fn interpolated_field_stays_close_to_direct_samples() {
    use gradtrace::preview::shadow_field::field::{Field, Grid};
    let (c, r) = (Vec3::ZERO, 0.5);
    let geo = EntityGeometry::from_shapes(&[], &[sphere(c, r, Vec3::ZERO)]);
    let grid = Grid {
        n_theta: 12,
        n_phi: 20,
        n_radii: 16,
        r_min: 0.25 * r,
        r_max: 8.0 * r,
    };
    let field = Field {
        grid,
        data: (0..grid.len())
            .map(|i| geo.sample(c + grid.position(i), c, r, 24, false).occlusion)
            .collect(),
    };
    // Points between the samples: the trilinear lookup against the exact cap.
    let mut worst: f64 = 0.0;
    for (k, d) in [1.3f32, 2.2, 3.7, 6.1].into_iter().enumerate() {
        let dir = Vec3::new(0.37 * k as f32 - 0.5, 0.61, 0.29).normalize();
        let got = field.lookup(dir * d * r);
        let sin = 1.0 / d as f64;
        let want = sh::cap(-dir.as_dvec3(), (1.0 - sin * sin).sqrt());
        let err = rel_l2(&got, &want);
        eprintln!("d = {d} R: relative L2 error of the interpolated field {err:.4}");
        worst = worst.max(err);
    }
    // 12 × 20 angular samples are 15–18° apart: far out, where the cap is a small
    // lobe whose coefficients follow its direction, linear interpolation between
    // neighbours loses a few per cent (measured 5.1%, 4.2%, 2.7%, 7.4% at the four
    // distances); a wrong grid, weight or axis gives errors of order 1.
    assert!(worst < 0.1, "worst relative L2 error {worst}");
    // Beyond the outermost sphere the occlusion falls as 1/d².
    let far = field.lookup(Vec3::new(0.0, 40.0 * r, 0.0));
    let want = sh::cap(-DVec3::Y, (1.0 - 1.0 / 1600f64).sqrt());
    assert!((far[0] as f64 - want[0]).abs() / want[0] < 0.02);
}

fn out_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gradtrace-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn preview_agrees_with_the_path_tracer_on_the_bunny_scene() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/shadowfield_bunny.toml");
    let mut opts = ShadowFieldOptions::new(scene);
    opts.out_dir = out_dir("bunny");
    opts.quiet = true;
    opts.resolution = Some((96, 72));
    opts.reference_spp = Some(64);
    opts.settings = Settings {
        rays: 16,
        self_rays: 8,
        ..Settings::default()
    };
    let first = run(&opts).unwrap();
    eprintln!("{}", serde_json::to_string_pretty(&first).unwrap());
    assert_eq!(first.method, "shadow-field");
    assert_eq!(first.entities, 4, "floor, bunny, ball, light");
    assert!(!first.precompute_cached);
    assert!(
        first.points >= 96 * 72 * 4 / 2,
        "most pixels see a lit surface"
    );
    assert!(first.rmse.is_finite() && first.rmse_lowfreq.is_finite());
    assert!(
        first.rmse_relative < 0.15,
        "RMSE {}% of the mean",
        first.rmse_relative * 100.0
    );
    let exr = gradtrace::output::read_exr(&first.exr).unwrap();
    for ch in [
        "R",
        "G",
        "B",
        "reference.R",
        "reference.G",
        "reference.B",
        "error.Y",
    ] {
        let c = exr.channel(ch).unwrap_or_else(|| panic!("missing {ch}"));
        assert!(c.data.iter().all(|x| x.is_finite()));
    }
    assert!(first.png.is_file());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(opts.out_dir.join("preview.json")).unwrap())
            .unwrap();
    for key in [
        "method",
        "entities",
        "points",
        "precompute_s",
        "render_s",
        "us_per_point_entity",
        "image_mean",
        "rmse",
        "rmse_lowfreq",
        "reference_spp_equal_error",
        "reference_s_equal_error",
        "speedup_equal_error",
    ] {
        assert!(json.get(key).is_some(), "preview.json lacks {key}");
    }
    // A second run reads the cached fields and shades the same image.
    let second = run(&opts).unwrap();
    assert!(second.precompute_cached);
    let again = gradtrace::output::read_exr(&second.exr).unwrap();
    assert_eq!(again.channel("R"), exr.channel("R"));
    let _ = std::fs::remove_dir_all(&opts.out_dir);
}
