//! Issue 57, item 5: glossy receivers in the shadow-field preview, against the
//! path tracer's direct-lighting reference (the pipeline's own). A glossy floor
//! under a sphere light with a sphere occluder (the highlight and the shadow both
//! in view: diffuse-only shading missed the highlight), and glossy surfaces at low
//! exponents under a constant and a Gaussian sky (the order-4 glossy transfer).

use gradtrace::math::{Vec2, Vec3};
use gradtrace::pipeline::preview::shadow_field::{run, ShadowFieldOptions, ShadowFieldSummary};
use gradtrace::preview::shadow_field::Settings;

const OCCLUDER: [f32; 3] = [0.0, 0.5, 0.0];
const OCCLUDER_RADIUS: f32 = 0.3;
const LIGHT: [f32; 3] = [1.0, 1.2, -0.5];
const LIGHT_RADIUS: f32 = 0.2;
const EXPONENT: f32 = 100.0;
const CAMERA: [f32; 3] = [0.0, 1.6, 2.6];

fn light_scene(floor: &str) -> String {
    let [ox, oy, oz] = OCCLUDER;
    let [lx, ly, lz] = LIGHT;
    format!(
        r#"
[camera]
from = [{}, {}, {}]
to = [0.0, 0.0, 0.5]
fov = 40
resolution = [96, 72]

[render]
spp = 16
integrator = "direct"

[materials.floor]
{floor}

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
center = [{lx}, {ly}, {lz}]
radius = {LIGHT_RADIUS}
radiance = [40, 40, 40]

[environment]
type = "constant"
radiance = [0.1, 0.1, 0.1]
"#,
        CAMERA[0], CAMERA[1], CAMERA[2]
    )
}

/// Runs the preview on `text`; returns its summary, the preview and reference
/// planes (luminance-free RGB means per pixel) and the scene's camera rays.
fn preview(name: &str, text: &str) -> (ShadowFieldSummary, Vec<Vec3>, Vec<Vec3>) {
    let dir = std::env::temp_dir().join(format!(
        "gradtrace-test-sfglossy-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
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
    for ch in exr.channels.iter() {
        assert!(
            ch.data.iter().all(|v| v.is_finite()),
            "{name}: {}: non-finite",
            ch.name
        );
    }
    let plane = |prefix: &str| -> Vec<Vec3> {
        let c = ["R", "G", "B"].map(|ch| &exr.channel(&format!("{prefix}{ch}")).unwrap().data);
        (0..c[0].len())
            .map(|i| Vec3::new(c[0][i], c[1][i], c[2][i]))
            .collect()
    };
    let (p, r) = (plane(""), plane("reference."));
    let _ = std::fs::remove_dir_all(&dir);
    (summary, p, r)
}

/// Floor pixels (not seeing the occluder) classified by `keep(point on the floor)`.
fn region_means(
    text: &str,
    p: &[Vec3],
    r: &[Vec3],
    keep: impl Fn(Vec3, Vec3) -> bool,
) -> (f64, f64, usize) {
    let scene = gradtrace::scene::load_from_str(text, std::path::Path::new("x.toml")).unwrap();
    let cam = &scene.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let (mut sp, mut sr, mut n) = (0.0f64, 0.0f64, 0usize);
    for y in 0..h {
        for x in 0..w {
            let ray = cam.generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            if ray.dir.y >= 0.0 {
                continue;
            }
            let point = ray.origin + ray.dir * (-ray.origin.y / ray.dir.y);
            let to_o = Vec3::from(OCCLUDER) - ray.origin;
            let b = to_o.dot(ray.dir);
            if (to_o - ray.dir * b).length() < OCCLUDER_RADIUS * 1.05 {
                continue;
            }
            if !keep(point, -ray.dir) {
                continue;
            }
            let i = y * w + x;
            sp += f64::from(p[i].x + p[i].y + p[i].z) / 3.0;
            sr += f64::from(r[i].x + r[i].y + r[i].z) / 3.0;
            n += 1;
        }
    }
    (sp / n.max(1) as f64, sr / n.max(1) as f64, n)
}

/// Where the light's centre is in the floor's Blinn-Phong lobe: (N·H)^e ≥ 0.5.
fn in_highlight(p: Vec3, wo: Vec3) -> bool {
    let wl = (Vec3::from(LIGHT) - p).normalize();
    let h = (wo + wl).normalize();
    h.y.max(0.0).powf(EXPONENT) >= 0.5
}

/// The segment from `p` to the light's centre passes through the occluder.
fn in_shadow(p: Vec3, _wo: Vec3) -> bool {
    let (o, r) = (Vec3::from(OCCLUDER), OCCLUDER_RADIUS);
    let d = Vec3::from(LIGHT) - p;
    let t = ((o - p).dot(d) / d.length_squared()).clamp(0.0, 1.0);
    (p + d * t - o).length() < r
}

/// Blinn-Phong and Cook-Torrance floors at e = 100 under a sphere light of 0.2
/// (about 7° seen from the highlight) with a constant sky; measured: highlight
/// mean within 0.2 %, shadow mean within 0.4 %, RMSE 3.9 % and 5.5 % of the mean
/// (diffuse-only shading: the highlight at 10 % and 3 % of the reference, the
/// shadow 29 % and 66 % too dark, RMSE 126 % and 197 %).
#[test]
fn glossy_floor_under_a_sphere_light_has_its_highlight_and_its_shadow() {
    let mut failures = Vec::new();
    for (name, floor) in [
        (
            "blinn",
            format!("type = \"blinn_phong\"\nkd = [0.3, 0.3, 0.3]\nks = [0.4, 0.4, 0.4]\nexponent = {EXPONENT}"),
        ),
        (
            "cook",
            format!("type = \"cook_torrance\"\nkd = [0.3, 0.3, 0.3]\nks = [0.4, 0.4, 0.4]\nexponent = {EXPONENT}"),
        ),
    ] {
        let text = light_scene(&floor);
        let (s, p, r) = preview(name, &text);
        let (hp, hr, hn) = region_means(&text, &p, &r, in_highlight);
        let (sp, sr, sn) = region_means(&text, &p, &r, in_shadow);
        eprintln!(
            "{name}: highlight {hp:.4} vs {hr:.4} ({hn} px, {:+.1}%), shadow {sp:.4} vs {sr:.4} ({sn} px, {:+.1}%), RMSE {:.1}% of the mean",
            100.0 * (hp / hr - 1.0),
            100.0 * (sp / sr - 1.0),
            100.0 * s.rmse_relative
        );
        assert!(hn >= 10 && sn >= 20, "{name}: highlight and shadow in view");
        // The highlight is the light's cap integrated against the renderer's own
        // BRDF: its mean within 5 %, the shadow's (the sky's glossy reflection
        // under the occluder's order-4 visibility) within 10 %.
        if (hp / hr - 1.0).abs() > 0.05 {
            failures.push(format!("{name}: highlight {hp:.4} vs {hr:.4}"));
        }
        if (sp / sr - 1.0).abs() > 0.10 {
            failures.push(format!("{name}: shadow {sp:.4} vs {sr:.4}"));
        }
        if s.rmse_relative > 0.08 {
            failures.push(format!(
                "{name}: RMSE {:.1}% of the mean",
                100.0 * s.rmse_relative
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The floor reaches past the top of the view: a far edge would put pixels half
/// floor, half sky in the image, which the preview's 2 × 2 point samples alias.
fn sky_scene(environment: &str) -> String {
    let [ox, oy, oz] = OCCLUDER;
    format!(
        r#"
[camera]
from = [0.0, 1.6, 2.6]
to = [0.0, 0.3, 0.0]
fov = 40
resolution = [80, 60]

[materials.floor]
type = "blinn_phong"
kd = [0.2, 0.2, 0.2]
ks = [0.5, 0.5, 0.5]
exponent = 8

[materials.ball]
type = "cook_torrance"
kd = [0.4, 0.3, 0.2]
ks = [0.3, 0.3, 0.3]
exponent = 4

[[shapes]]
name = "floor"
type = "quad"
corner = [-20, 0, 20]
edge_u = [40, 0, 0]
edge_v = [0, 0, -40]
material = "floor"

[[shapes]]
name = "ball"
type = "sphere"
center = [{ox}, {oy}, {oz}]
radius = {OCCLUDER_RADIUS}
material = "ball"

[environment]
{environment}
"#
    )
}

/// A Blinn-Phong floor at e = 8 and a Cook-Torrance ball at e = 4, where order 4
/// holds the lobes (`preview::shadow_field::glossy`): the whole image within 3 %
/// (constant sky) and 4 % (Gaussian sky) RMSE of its mean, against the full and
/// the order-4 sky (measured 1.2 % and 2.1 %, what is left mostly the ball's
/// silhouette; diffuse-only shading was 47 % and 60 % off).
#[test]
fn low_exponent_glossy_surfaces_under_an_environment_match_the_path_tracer() {
    let mut failures = Vec::new();
    for (name, env, bound, bound_low) in [
        (
            "constant",
            "type = \"constant\"\nradiance = [1, 1, 1]",
            0.03,
            0.03,
        ),
        (
            "sky",
            "type = \"gaussian_sky\"\ndirection = [0.4, 1.0, -0.6]\nsharpness = 3\npeak = [2, 2, 2]\nambient = [0.2, 0.2, 0.2]",
            0.04,
            0.04,
        ),
    ] {
        let text = sky_scene(env);
        let (s, _, _) = preview(name, &text);
        eprintln!(
            "{name}: RMSE {:.2}% of the mean ({:.2}% against the order-4 sky)",
            100.0 * s.rmse_relative,
            100.0 * s.rmse_lowfreq_relative
        );
        if s.rmse_relative > bound || s.rmse_lowfreq_relative > bound_low {
            failures.push(format!(
                "{name}: RMSE {:.2}% / {:.2}% of the mean, bound {:.0}% / {:.0}%",
                100.0 * s.rmse_relative,
                100.0 * s.rmse_lowfreq_relative,
                100.0 * bound,
                100.0 * bound_low
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
