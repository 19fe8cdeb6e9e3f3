//! Issue 57: the shadow-field preview against the path tracer's direct light for a
//! sphere occluder between a floor and a sphere light, at light radii 0.1–1 and
//! distances 2–10 occluder radii. The order-4 SH product alone blurs a small
//! light's shadow to about half its depth and spreads it (before the fix the
//! shadow region held 1.7–2.5× the reference's mean); sphere lights are now
//! integrated over their cap against the occluders' unblurred cone maps.

use gradtrace::math::{Vec2, Vec3};
use gradtrace::pipeline::preview::shadow_field::{run, ShadowFieldOptions};
use gradtrace::preview::shadow_field::Settings;
use std::path::PathBuf;

/// One configuration: light radius, light centre's distance from the occluder's
/// centre in occluder radii.
struct Case {
    light_radius: f32,
    distance: f32,
}

const OCCLUDER_RADIUS: f32 = 0.3;
const OCCLUDER_CENTER: [f32; 3] = [0.0, 0.5, 0.0];

fn light_center(c: &Case) -> Vec3 {
    // Above and behind the occluder (away from the camera), tilted sideways.
    let dir = Vec3::new(0.25, 1.0, -0.6).normalize();
    Vec3::from(OCCLUDER_CENTER) + dir * (c.distance * OCCLUDER_RADIUS)
}

fn scene_text(c: &Case) -> String {
    let l = light_center(c);
    // Radiance for about the same irradiance on the floor whatever the size.
    let le = 1.2 * (l.y / c.light_radius).powi(2);
    let [ox, oy, oz] = OCCLUDER_CENTER;
    format!(
        r#"
[camera]
from = [0.0, 1.6, 2.6]
to = [0.0, 0.0, 0.5]
fov = 40
resolution = [96, 72]

[render]
spp = 16
integrator = "direct"

[materials.floor]
type = "lambert"
albedo = [0.6, 0.6, 0.6]

[materials.ball]
type = "lambert"
albedo = [0.5, 0.5, 0.5]

[[shapes]]
name = "floor"
type = "quad"
corner = [-8, 0, 8]
edge_u = [16, 0, 0]
edge_v = [0, 0, -16]
material = "floor"

[[shapes]]
name = "ball"
type = "sphere"
center = [{ox}, {oy}, {oz}]
radius = {OCCLUDER_RADIUS}
material = "ball"

[[lights]]
name = "bulb"
type = "sphere"
center = [{}, {}, {}]
radius = {}
radiance = [{le}, {le}, {le}]

[environment]
type = "constant"
radiance = [0.1, 0.1, 0.1]
"#,
        l.x, l.y, l.z, c.light_radius
    )
}

/// Whether the segment from floor point `p` to the light's centre passes through
/// the occluder: the core of its shadow.
fn in_shadow(p: Vec3, light: Vec3) -> bool {
    let (o, r) = (Vec3::from(OCCLUDER_CENTER), OCCLUDER_RADIUS);
    let d = light - p;
    let t = ((o - p).dot(d) / d.length_squared()).clamp(0.0, 1.0);
    (p + d * t - o).length() < r
}

struct Scored {
    rmse_relative: f64,
    shadow_preview: f64,
    shadow_reference: f64,
    shadow_pixels: usize,
}

fn score(name: &str, c: &Case) -> Scored {
    let dir = std::env::temp_dir().join(format!(
        "gradtrace-test-sflights-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let path: PathBuf = dir.join(format!("{name}.toml"));
    let text = scene_text(c);
    std::fs::write(&path, &text).unwrap();
    let mut opts = ShadowFieldOptions::new(&path);
    opts.out_dir = dir.join("out");
    opts.quiet = true;
    opts.cache = false;
    opts.reference_spp = Some(128);
    opts.reference_spp_max = Some(512);
    opts.settings = Settings {
        rays: 16,
        self_rays: 8,
        ..Settings::default()
    };
    let summary = run(&opts).unwrap();
    let exr = gradtrace::output::read_exr(&summary.exr).unwrap();
    let scene = gradtrace::scene::load_from_str(&text, &path).unwrap();
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let light = light_center(c);
    let (mut sp, mut sr, mut n) = (0.0f64, 0.0f64, 0usize);
    for y in 0..h {
        for x in 0..w {
            let ray = cam.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            if ray.dir.y >= 0.0 {
                continue;
            }
            let p = ray.origin + ray.dir * (-ray.origin.y / ray.dir.y);
            // Pixels that see the occluder itself are not floor.
            let to_o = Vec3::from(OCCLUDER_CENTER) - ray.origin;
            let b = to_o.dot(ray.dir);
            if (to_o - ray.dir * b).length() < OCCLUDER_RADIUS * 1.05 {
                continue;
            }
            if !in_shadow(p, light) {
                continue;
            }
            let i = y * w + x;
            for ch in ["R", "G", "B"] {
                sp += exr.channel(ch).unwrap().data[i] as f64;
                sr += exr.channel(&format!("reference.{ch}")).unwrap().data[i] as f64;
            }
            n += 1;
        }
    }
    for ch in exr.channels.iter() {
        assert!(
            ch.data.iter().all(|v| v.is_finite()),
            "{}: non-finite",
            ch.name
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    let k = (3 * n.max(1)) as f64;
    Scored {
        rmse_relative: summary.rmse_relative,
        shadow_preview: sp / k,
        shadow_reference: sr / k,
        shadow_pixels: n,
    }
}

#[test]
fn sphere_light_shadows_of_a_sphere_match_the_path_tracer() {
    let cases = [
        Case {
            light_radius: 0.1,
            distance: 2.0,
        },
        Case {
            light_radius: 0.3,
            distance: 5.0,
        },
        Case {
            light_radius: 0.5,
            distance: 4.0,
        },
        Case {
            light_radius: 1.0,
            distance: 10.0,
        },
    ];
    let mut failures = Vec::new();
    for (k, c) in cases.iter().enumerate() {
        let s = score(&format!("case{k}"), c);
        let rel = (s.shadow_preview - s.shadow_reference).abs() / s.shadow_reference;
        eprintln!(
            "light radius {} at {} occluder radii: shadow mean {:.4} vs {:.4} ({} px, {:+.1}%), RMSE {:.1}% of the mean",
            c.light_radius,
            c.distance,
            s.shadow_preview,
            s.shadow_reference,
            s.shadow_pixels,
            100.0 * (s.shadow_preview / s.shadow_reference - 1.0),
            100.0 * s.rmse_relative
        );
        assert!(s.shadow_pixels >= 20, "case {k}: the shadow is in view");
        // The shadow's core sees the sky and a penumbra edge only: the preview's
        // mean there within 10% of the path tracer's (measured within 2%; the
        // order-4 SH product alone left 70–150% too much light in it).
        if rel > 0.10 {
            failures.push(format!("case {k}: shadow mean off by {:.1}%", 100.0 * rel));
        }
        // Low-frequency sky, the light's cap integrated against unblurred
        // occlusion: the whole image within 8% RMSE of its mean. What is left is
        // the 2 × 2 receivers per pixel on hard edges (case 0, the sharpest:
        // 6.8% at 96 × 72, 3.6% at 192 × 144; the others 2–3%).
        if s.rmse_relative > 0.08 {
            failures.push(format!(
                "case {k}: RMSE {:.1}% of the mean",
                100.0 * s.rmse_relative
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
