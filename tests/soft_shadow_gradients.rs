//! Image gradients of the direct light on a floor against independent closed forms
//! (issue 12), rendered end to end (`render`, `--integrator direct --gradients`):
//!
//! * under a constant environment L with polygonal blockers, the floor irradiance is
//!   E(x) = L (π − Σ_faces ∫_face cos θ dω) over the blockers' faces seen from x, each
//!   term by Lambert's contour formula ½ Σ_edges β_i n·(r_i × r_{i+1})/|r_i × r_{i+1}|;
//! * under a sphere light (radius r, radiance L, centre at height h, distance d) the
//!   cap is always fully above the floor's horizon and E = π L sin²α cos θ =
//!   π L r² h / d³.
//!
//! The reference pixel gradient is the pixel average (4 × 4 points) of central
//! differences of I = ρ/π E along the image axes, through the camera's own rays to
//! the floor: noise-free and independent of the renderer. Each render is two
//! half-renders with different seeds, whose difference measures the noise, so a
//! test can say "within noise": the RMS error over the compared pixels divided by
//! the RMS noise of the mean is ≈ 1 for an unbiased gradient and grows with a bias.

use glam::DVec3;
use gradtrace::accel::{Accel, PrimRef};
use gradtrace::brdf::Material;
use gradtrace::math::{Vec2, Vec3};
use gradtrace::render::{render, RenderOptions, RenderOutput};
use gradtrace::scene::{Camera, Environment, Integrator, Mesh, Scene};
use std::f64::consts::PI;

mod scenes;
use scenes::*;

const ALBEDO: f32 = 0.5;

/// A planar convex blocker face; `two_sided` for a card (seen from either side),
/// otherwise seen only from the side its counter-clockwise normal points to.
#[derive(Clone, Debug)]
struct Face {
    verts: Vec<DVec3>,
    two_sided: bool,
}

/// ∫_P cos θ dω of the polygon `verts` seen from the floor point x (normal +y),
/// by Lambert's contour integral; exact for polygons above the horizon.
fn polygon_cos_solid_angle(x: DVec3, verts: &[DVec3]) -> f64 {
    let n = verts.len();
    let mut s = 0.0;
    for i in 0..n {
        let a = (verts[i] - x).normalize();
        let b = (verts[(i + 1) % n] - x).normalize();
        let g = a.cross(b);
        let len = g.length();
        if len < 1e-15 {
            continue;
        }
        s += a.dot(b).clamp(-1.0, 1.0).acos() * g.y / len;
    }
    0.5 * s.abs()
}

/// Exact irradiance on the floor at x under a constant environment `l` with the
/// convex faces `faces` (faces of one convex solid do not overlap as seen from x).
fn sky_irradiance(x: DVec3, faces: &[Face], l: f64) -> f64 {
    let mut blocked = 0.0;
    for f in faces {
        let nf = (f.verts[1] - f.verts[0]).cross(f.verts[2] - f.verts[0]);
        let side = (x - f.verts[0]).dot(nf);
        if side.abs() < 1e-12 || (!f.two_sided && side < 0.0) {
            continue;
        }
        blocked += polygon_cos_solid_angle(x, &f.verts);
    }
    l * (PI - blocked)
}

/// Exact irradiance on the floor at x from a sphere light: π L r² h / d³.
fn sphere_irradiance(x: DVec3, centre: DVec3, radius: f64, l: f64) -> f64 {
    let q = centre - x;
    let d = q.length();
    PI * l * radius * radius * q.y / (d * d * d)
}

fn camera(w: u32, h: u32) -> Camera {
    Camera::new(
        Vec3::new(0.0, 3.6, 3.4),
        Vec3::new(0.0, 0.0, 0.1),
        Vec3::Y,
        45.0,
        w,
        h,
    )
    .unwrap()
}

/// The floor (mesh 0, 8 × 8, albedo `ALBEDO`) and nothing else yet.
fn floor_scene(w: u32, h: u32) -> Scene {
    let mut s = empty_scene(camera(w, h));
    let white = add_material(
        &mut s,
        Material::Lambert {
            albedo: Vec3::splat(ALBEDO),
        },
    );
    add_material(&mut s, Material::Lambert { albedo: Vec3::ZERO });
    add_quad(&mut s, ground(4.0), white, Vec3::ZERO);
    s
}

/// Adds the faces as one black mesh (a fan of triangles per face).
fn add_blocker(s: &mut Scene, faces: &[Face]) {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for f in faces {
        let base = positions.len() as u32;
        positions.extend(f.verts.iter().map(|v| v.as_vec3a()));
        for k in 1..f.verts.len() as u32 - 1 {
            triangles.push([base, base + k, base + k + 1]);
        }
    }
    s.object_names.push(format!("blocker{}", s.meshes.len()));
    s.meshes.push(Mesh {
        name: String::new(),
        positions,
        normals: vec![],
        uvs: vec![],
        triangles,
        material: 1,
        emission: Vec3::ZERO,
        bump: None,
        rect: None,
        object_id: s.object_names.len() as u32,
    });
}

/// The 0.8 × 0.6 card centred at (0, 0.6, 0), first tilted by `tilt` degrees about
/// its horizontal axis (x), then turned by `yaw` degrees about the vertical, and
/// sheared so its sides lean by `shear` (horizontal offset of the top edge).
fn card(yaw: f64, tilt: f64, shear: f64) -> Vec<Face> {
    let (sy, cy) = yaw.to_radians().sin_cos();
    let (st, ct) = tilt.to_radians().sin_cos();
    let place = |u: f64, v: f64| {
        // Card plane: u along x, v up; tilt about x, then yaw about y.
        let p = DVec3::new(u + shear * (v / 0.3), v * ct, -v * st);
        DVec3::new(cy * p.x + sy * p.z, p.y + 0.6, -sy * p.x + cy * p.z)
    };
    vec![Face {
        verts: vec![
            place(-0.4, -0.3),
            place(0.4, -0.3),
            place(0.4, 0.3),
            place(-0.4, 0.3),
        ],
        two_sided: true,
    }]
}

/// A cube of side `a` standing on the floor, centred on the y axis, turned by `yaw`.
fn standing_cube(a: f64, yaw: f64) -> Vec<Face> {
    let (sy, cy) = yaw.to_radians().sin_cos();
    let h = 0.5 * a;
    let p = |x: f64, y: f64, z: f64| DVec3::new(cy * x + sy * z, y, -sy * x + cy * z);
    let c = [
        p(-h, 0.0, -h),
        p(h, 0.0, -h),
        p(h, 0.0, h),
        p(-h, 0.0, h),
        p(-h, a, -h),
        p(h, a, -h),
        p(h, a, h),
        p(-h, a, h),
    ];
    // Counter-clockwise seen from outside.
    [
        [0, 1, 2, 3], // bottom (−y)
        [4, 7, 6, 5], // top
        [0, 4, 5, 1], // −z
        [2, 6, 7, 3], // +z
        [1, 5, 6, 2], // +x
        [3, 7, 4, 0], // −x
    ]
    .iter()
    .map(|q| Face {
        verts: q.iter().map(|&i| c[i]).collect(),
        two_sided: false,
    })
    .collect()
}

/// The floor point seen through image point p, if the camera sees the floor there.
fn floor_point(s: &Scene, accel: &Accel, p: Vec2) -> Option<DVec3> {
    let ray = s.camera.generate_ray(p);
    let hit = accel.intersect(&ray)?;
    if !matches!(hit.prim, PrimRef::Triangle { mesh: 0, .. }) {
        return None;
    }
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    Some(o + d * (-o.y / d.y))
}

/// Exact pixel means of I and of ∂I/∂u, ∂I/∂v (4 × 4 points, central differences of
/// step 0.01 px), or `None` if any point of the pixel does not see the floor.
fn exact_pixel(
    s: &Scene,
    accel: &Accel,
    px: u32,
    py: u32,
    radiance: &dyn Fn(DVec3) -> f64,
) -> Option<(f64, [f64; 2])> {
    let corner = Vec2::new(px as f32, py as f32);
    for i in 0..=4 {
        for j in 0..=4 {
            floor_point(s, accel, corner + Vec2::new(i as f32, j as f32) * 0.25)?;
        }
    }
    let at = |p: glam::DVec2| {
        let ray = s.camera.generate_ray(p.as_vec2());
        // In f64 from the f32 ray: the step is far above its rounding.
        let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
        let x = o + d * (-o.y / d.y);
        ALBEDO as f64 / PI * radiance(x)
    };
    let h = 0.01;
    let (mut value, mut grad) = (0.0, [0.0; 2]);
    for i in 0..4 {
        for j in 0..4 {
            let p = glam::DVec2::new(
                px as f64 + (i as f64 + 0.5) / 4.0,
                py as f64 + (j as f64 + 0.5) / 4.0,
            );
            value += at(p) / 16.0;
            for (k, e) in [glam::DVec2::X, glam::DVec2::Y].iter().enumerate() {
                grad[k] += (at(p + *e * h) - at(p - *e * h)) / (2.0 * h) / 16.0;
            }
        }
    }
    Some((value, grad))
}

/// Figures of one comparison of rendered against exact pixel gradients.
#[derive(Clone, Copy, Debug)]
struct Figures {
    pixels: usize,
    /// Regression slope through the origin, Σ a e / Σ e², per axis.
    slope: [f64; 2],
    /// Median and largest |a − e| / |e| over pixels with |e| ≥ 10% of the largest.
    median_rel: f64,
    max_rel: f64,
    /// Largest |a − e| over all compared pixels / largest |e|.
    max_abs: f64,
    /// RMS error / RMS noise of the mean (≈ 1 when unbiased).
    error_to_noise: f64,
    /// Mean radiance error over the compared pixels / mean radiance, and its noise.
    radiance_bias: f64,
}

impl std::fmt::Display for Figures {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(
            f,
            "{} px: slope u {:.3} v {:.3}; |a−e|/|e| median {:.3} max {:.3}; max |a−e|/max|e| {:.3}; error/noise {:.2}; radiance bias {:+.1e}",
            self.pixels,
            self.slope[0],
            self.slope[1],
            self.median_rel,
            self.max_rel,
            self.max_abs,
            self.error_to_noise,
            self.radiance_bias
        )
    }
}

/// Renders `s` as two half-renders of `spp / 2` (seeds 1, 2) and compares the mean
/// gradient of every floor pixel with the exact one.
fn compare(s: &Scene, spp: u32, radiance: &dyn Fn(DVec3) -> f64, vis: u32) -> Figures {
    compare_gated(s, spp, radiance, vis, None)
}

/// [`compare`] with the ring's penumbra gate `gate` (default: the renderer's).
fn compare_gated(
    s: &Scene,
    spp: u32,
    radiance: &dyn Fn(DVec3) -> f64,
    vis: u32,
    gate: Option<f32>,
) -> Figures {
    let accel = Accel::build(&s.meshes, &s.spheres);
    let half = |seed: u32| -> RenderOutput {
        let opts = RenderOptions {
            spp: Some(spp / 2),
            seed: Some(seed),
            integrator: Some(Integrator::Direct),
            gradients: true,
            vis_samples: Some(vis),
            vis_gate: gate,
            ..Default::default()
        };
        render(s, &accel, &opts, &|_, _| {}).unwrap()
    };
    let (r1, r2) = (half(1), half(2));
    let (g1, g2) = (r1.gradients.unwrap(), r2.gradients.unwrap());
    let (w, h) = (s.camera.width, s.camera.height);
    let mut rows = Vec::new();
    for py in 0..h {
        for px in 0..w {
            let Some((value, exact)) = exact_pixel(s, &accel, px, py, radiance) else {
                continue;
            };
            let i = (py * w + px) as usize;
            let a1 = [g1.grad_u[i].x as f64, g1.grad_v[i].x as f64];
            let a2 = [g2.grad_u[i].x as f64, g2.grad_v[i].x as f64];
            let l = 0.5 * (r1.beauty[i].x + r2.beauty[i].x) as f64;
            rows.push((a1, a2, exact, value, l));
        }
    }
    assert!(rows.len() > 200, "only {} floor pixels", rows.len());
    let mean = |a: [f64; 2], b: [f64; 2]| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    let norm = |v: [f64; 2]| v[0].hypot(v[1]);
    let e_max = rows.iter().map(|r| norm(r.2)).fold(0.0, f64::max);
    let (mut num, mut den) = ([0.0; 2], [0.0; 2]);
    let (mut err2, mut noise2, mut max_abs) = (0.0, 0.0, 0.0f64);
    let mut rel = Vec::new();
    let (mut dl, mut lsum) = (0.0, 0.0);
    for (a1, a2, e, value, l) in &rows {
        let a = mean(*a1, *a2);
        for k in 0..2 {
            num[k] += a[k] * e[k];
            den[k] += e[k] * e[k];
            err2 += (a[k] - e[k]).powi(2);
            noise2 += 0.25 * (a1[k] - a2[k]).powi(2);
        }
        let diff = norm([a[0] - e[0], a[1] - e[1]]);
        max_abs = max_abs.max(diff);
        if norm(*e) >= 0.1 * e_max {
            rel.push(diff / norm(*e));
        }
        dl += l - value;
        lsum += value;
    }
    rel.sort_by(|a, b| a.total_cmp(b));
    Figures {
        pixels: rows.len(),
        slope: [num[0] / den[0], num[1] / den[1]],
        median_rel: rel[rel.len() / 2],
        max_rel: *rel.last().unwrap(),
        max_abs: max_abs / e_max,
        error_to_noise: (err2 / noise2.max(1e-300)).sqrt(),
        radiance_bias: dl / lsum,
    }
}

fn sky_scene(faces: &[Face]) -> Scene {
    let mut s = floor_scene(64, 48);
    add_blocker(&mut s, faces);
    s.environment = Some(Environment::Constant {
        radiance: Vec3::ONE,
    });
    s
}

fn check_sky(name: &str, faces: Vec<Face>, spp: u32) -> Figures {
    check_sky_gated(name, faces, spp, None)
}

fn check_sky_gated(name: &str, faces: Vec<Face>, spp: u32, gate: Option<f32>) -> Figures {
    let s = sky_scene(&faces);
    let exact = move |x: DVec3| sky_irradiance(x, &faces, 1.0);
    let f = compare_gated(&s, spp, &exact, 32, gate);
    println!("{name}: {f}");
    f
}

/// Asserts an unbiased gradient: slopes within 10% of 1, the error at the noise.
fn assert_unbiased(name: &str, f: &Figures) {
    assert_no_bias(name, f);
    assert!(f.median_rel < 0.15, "{name}: {f}");
    assert!(f.radiance_bias.abs() < 5e-3, "{name}: {f}");
}

/// [`assert_unbiased`]'s bias criteria alone: the slopes and the error at the noise.
fn assert_no_bias(name: &str, f: &Figures) {
    assert!(
        f.slope.iter().all(|s| (s - 1.0).abs() < 0.1),
        "{name}: slopes {:?}",
        f.slope
    );
    // Residual bias at the rays' spacing (blockers seen narrower than it, jump
    // positions on curved parts) stays below 3.5× the noise of 256 spp.
    assert!(f.error_to_noise < 3.5, "{name}: {f}");
}

/// A blocker under the sky, twice: every ring marched (`--vis-gate 1`), the gradient
/// meets all of [`assert_unbiased`]; with the default penumbra gate, which skips
/// rings where its probes agree and so adds noise where only rings cross an edge
/// (median relative error 0.15–0.17 at 256 spp against ≤ 0.15 ungated), its bias
/// criteria.
fn assert_sky(name: &str, faces: Vec<Face>, spp: u32) {
    let f = check_sky_gated(name, faces.clone(), spp, Some(1.0));
    assert_unbiased(name, &f);
    let gated = format!("{name}, gated rings");
    assert_no_bias(&gated, &check_sky(&gated, faces, spp));
}

/// D1: a vertical card under the sky. Its sides lie in planes through the floor's
/// normal, parallel to every φ-line: before the fix their part of the gradient was
/// missing (slope of ∂I/∂u −0.03).
#[test]
fn vertical_card_under_the_sky_matches_form_factor_gradient() {
    assert_sky("vertical card", card(0.0, 0.0, 0.0), 256);
}

/// D1: the same card sheared (sides not vertical) — always right.
#[test]
fn sheared_card_under_the_sky_matches_form_factor_gradient() {
    assert_sky("sheared card", card(0.0, 0.0, 0.25), 256);
}

/// D1: a cube standing on the floor (vertical edges, faces touching the floor).
#[test]
fn standing_cube_under_the_sky_matches_form_factor_gradient() {
    for yaw in [0.0, 30.0] {
        assert_sky(
            &format!("standing cube, yaw {yaw}°"),
            standing_cube(0.7, yaw),
            256,
        );
    }
}

/// D1: every orientation of the card, turned about the vertical and tilted about
/// its horizontal axis, stays within noise (the figures are in the note).
#[test]
#[ignore = "sweep of 16 orientations, ~minutes; run with --ignored"]
fn card_orientation_sweep_stays_within_noise() {
    println!("| yaw | tilt | slope u | slope v | median rel | max |a−e|/max|e| | error/noise |");
    println!("|---|---|---|---|---|---|---|");
    let mut worst: f64 = 0.0;
    for yaw in [0.0, 30.0, 60.0, 90.0] {
        for tilt in [0.0, 30.0, 60.0, 90.0] {
            let s = sky_scene(&card(yaw, tilt, 0.0));
            let faces = card(yaw, tilt, 0.0);
            let exact = move |x: DVec3| sky_irradiance(x, &faces, 1.0);
            let f = compare(&s, 128, &exact, 32);
            println!(
                "| {yaw} | {tilt} | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} |",
                f.slope[0], f.slope[1], f.median_rel, f.max_abs, f.error_to_noise
            );
            worst = worst.max(f.error_to_noise);
            assert!(
                f.slope.iter().all(|s| (s - 1.0).abs() < 0.15),
                "yaw {yaw} tilt {tilt}: {f}"
            );
        }
    }
    assert!(worst < 3.5, "worst error/noise {worst:.2}");
}

/// The sphere light over a plain floor (radius 0.3, centre 1.5 up, L = 10). A far
/// tiny sphere below the floor, which shadows nothing, makes the scene one that can
/// cast shadows, so `line` renders it by φ-lines; otherwise by cone samples.
fn sphere_light_scene(line: bool) -> Scene {
    let mut s = floor_scene(96, 72);
    let black = 1;
    add_sphere(
        &mut s,
        Vec3::new(0.3, 1.5, -0.2),
        0.3,
        black,
        Vec3::splat(10.0),
    );
    if line {
        add_sphere(&mut s, Vec3::new(0.0, -50.0, 0.0), 0.1, black, Vec3::ZERO);
    }
    s
}

/// D2: the sphere light's gradient against the closed form, per pixel, with a bound
/// on the *largest* error: before the fix single pixel means were off by 10⁴× the
/// typical gradient (all in SV, from the 1/cos θ_y of the area measure at the
/// sphere's silhouette). Also the radiance mean against the closed form.
#[test]
fn sphere_light_gradient_matches_closed_form_everywhere() {
    for line in [false, true] {
        let s = sphere_light_scene(line);
        let exact = |x: DVec3| sphere_irradiance(x, DVec3::new(0.3, 1.5, -0.2), 0.3, 10.0);
        let f = compare(&s, 64, &exact, 8);
        let name = if line {
            "sphere light, lines"
        } else {
            "sphere light, cone samples"
        };
        println!("{name}: {f}");
        assert_unbiased(name, &f);
        assert!(f.max_abs < 0.1, "{name}: largest error {f}");
    }
}
