//! Spherical harmonics (order 4): normalisation, the paper's Appendix-B definition,
//! rotation against closed forms and against re-projection, zonal functions, and the
//! triple product against numerical integration.

mod common;

use common::Rng;
use glam::{DMat3, DVec3};
use gradtrace::math::sh::{self, Rotation, Sh, COEFFS};
use std::f64::consts::PI;

fn random_dir(rng: &mut Rng) -> DVec3 {
    let z = 2.0 * rng.next_f64() - 1.0;
    let phi = 2.0 * PI * rng.next_f64();
    let s = (1.0 - z * z).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), z)
}

fn random_sh(rng: &mut Rng) -> Sh {
    std::array::from_fn(|_| 2.0 * rng.next_f64() - 1.0)
}

fn random_rotation(rng: &mut Rng) -> DMat3 {
    let axis = random_dir(rng);
    DMat3::from_axis_angle(axis, 2.0 * PI * rng.next_f64())
}

fn max_diff(a: &Sh, b: &Sh) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

#[test]
fn basis_is_orthonormal_without_hidden_factors() {
    // Exact for degree ≤ 2·6 − 1 = 11 in z: every product of two l ≤ 3 functions.
    let rule = sh::sphere_quadrature(6, 12);
    let total: f64 = rule.iter().map(|p| p.1).sum();
    assert!(
        (total - 4.0 * PI).abs() < 1e-12,
        "the rule integrates 1 to 4π"
    );
    for i in 0..COEFFS {
        for j in 0..COEFFS {
            let g: f64 = rule
                .iter()
                .map(|&(d, w)| w * sh::eval(d)[i] * sh::eval(d)[j])
                .sum();
            let want = if i == j { 1.0 } else { 0.0 };
            assert!((g - want).abs() < 1e-12, "<Y{i}, Y{j}> = {g}");
        }
    }
}

/// Appendix B: Y_l^m = √2 K cos(mφ) P_l^m(cos θ) (m > 0), √2 K sin(|m|φ) P_l^|m| (m < 0),
/// K P_l^0 (m = 0), K = √((2l+1)/4π · (l−|m|)!/(l+|m|)!), P without the
/// Condon–Shortley phase.
fn appendix_b(l: usize, m: i32, d: DVec3) -> f64 {
    let theta = d.z.clamp(-1.0, 1.0).acos();
    let phi = d.y.atan2(d.x);
    let am = m.unsigned_abs() as usize;
    let x = theta.cos();
    let s = theta.sin();
    // P_m^m = (2m−1)!! s^m, then the three-term recurrence in l.
    let mut pmm = 1.0;
    for k in 0..am {
        pmm *= (2 * k + 1) as f64 * s;
    }
    let p = if l == am {
        pmm
    } else {
        let mut p0 = pmm;
        let mut p1 = x * (2 * am + 1) as f64 * pmm;
        for ll in am + 2..=l {
            let p2 = ((2 * ll - 1) as f64 * x * p1 - (ll + am - 1) as f64 * p0) / (ll - am) as f64;
            p0 = p1;
            p1 = p2;
        }
        p1
    };
    let fact = |n: usize| (1..=n).map(|k| k as f64).product::<f64>();
    let k = ((2 * l + 1) as f64 / (4.0 * PI) * fact(l - am) / fact(l + am)).sqrt();
    match m.cmp(&0) {
        std::cmp::Ordering::Greater => 2f64.sqrt() * k * (am as f64 * phi).cos() * p,
        std::cmp::Ordering::Less => 2f64.sqrt() * k * (am as f64 * phi).sin() * p,
        std::cmp::Ordering::Equal => k * p,
    }
}

#[test]
fn cartesian_basis_matches_the_papers_definition() {
    let mut rng = Rng::new(1);
    for _ in 0..200 {
        let d = random_dir(&mut rng);
        let y = sh::eval(d);
        for (i, yi) in y.iter().enumerate() {
            let (l, m) = sh::band_of(i);
            assert_eq!(sh::index(l, m), i);
            let want = appendix_b(l, m, d);
            assert!(
                (yi - want).abs() < 1e-12,
                "Y({l},{m}) at {d}: {yi} vs {want}"
            );
        }
    }
}

#[test]
fn rotation_about_z_is_the_closed_form() {
    // f(R⁻¹ω) with R = rotation by α about z: (c_{l,m}, c_{l,−m}) turn by mα.
    let mut rng = Rng::new(2);
    let c = random_sh(&mut rng);
    let alpha = 0.7316;
    let r = Rotation::new(DMat3::from_rotation_z(alpha));
    let got = r.apply(&c);
    for l in 0..4usize {
        assert!((got[sh::index(l, 0)] - c[sh::index(l, 0)]).abs() < 1e-12);
        for m in 1..=l as i32 {
            let (cp, cn) = (c[sh::index(l, m)], c[sh::index(l, -m)]);
            let (ca, sa) = ((m as f64 * alpha).cos(), (m as f64 * alpha).sin());
            assert!((got[sh::index(l, m)] - (ca * cp - sa * cn)).abs() < 1e-10);
            assert!((got[sh::index(l, -m)] - (sa * cp + ca * cn)).abs() < 1e-10);
        }
    }
}

#[test]
fn rotating_a_basis_function_gives_its_rotated_polynomial() {
    // Rotation by 90° about y maps z → x: Y_2^0 ∝ 3z² − 1 becomes 3x² − 1 =
    // −½(3z² − 1)·… written in the basis: 3x² − 1 = (3/2)(x² − y²) − ½(3z² − 1).
    let r = Rotation::new(DMat3::from_rotation_y(PI / 2.0));
    let mut c = [0.0; COEFFS];
    c[sh::index(2, 0)] = 1.0;
    let got = r.apply(&c);
    let k20 = 0.315_391_565_252_520_05;
    let k22 = 0.546_274_215_296_039_6;
    let mut want = [0.0; COEFFS];
    want[sh::index(2, 0)] = -0.5;
    want[sh::index(2, 2)] = 1.5 * k20 / k22;
    assert!(max_diff(&got, &want) < 1e-12, "{got:?}");
    // Y_3^0 ∝ z(5z² − 3) about y by 90° becomes x(5x² − 3): check pointwise.
    let mut c = [0.0; COEFFS];
    c[sh::index(3, 0)] = 1.0;
    let got = r.apply(&c);
    let mut rng = Rng::new(3);
    for _ in 0..50 {
        let d = random_dir(&mut rng);
        let want = 0.373_176_332_590_115_4 * d.x * (5.0 * d.x * d.x - 3.0);
        assert!((sh::eval_sum(&got, d) - want).abs() < 1e-10);
    }
}

#[test]
fn rotate_then_project_equals_project_then_rotate() {
    let mut rng = Rng::new(4);
    let rule = sh::sphere_quadrature(8, 16);
    for _ in 0..20 {
        let c = random_sh(&mut rng);
        let r = random_rotation(&mut rng);
        let inv = r.transpose();
        let reprojected = sh::project_with(|d| sh::eval_sum(&c, inv * d), &rule);
        let rotated = Rotation::new(r).apply(&c);
        assert!(max_diff(&reprojected, &rotated) < 1e-10);
        // Orthogonal, and composing rotations composes their SH matrices.
        let back = Rotation::new(inv).apply(&rotated);
        assert!(max_diff(&back, &c) < 1e-10);
        let r2 = random_rotation(&mut rng);
        let two = Rotation::new(r2).apply(&rotated);
        let once = Rotation::new(r2 * r).apply(&c);
        assert!(max_diff(&two, &once) < 1e-10);
    }
}

#[test]
fn clamped_cosine_and_cap_match_exact_quadrature() {
    let mut rng = Rng::new(5);
    for _ in 0..10 {
        let n = random_dir(&mut rng);
        let cos_alpha = 2.0 * rng.next_f64() - 1.0;
        // Exact projections around +z: Gauss–Legendre on the cap's z-range only.
        let exact = |z0: f64, f: &dyn Fn(f64) -> f64| -> Sh {
            let mut c = [0.0; COEFFS];
            for (x, w) in sh::gauss_legendre(8) {
                let z = z0 + (1.0 - z0) * 0.5 * (x + 1.0);
                let w = w * 0.5 * (1.0 - z0);
                let s = (1.0 - z * z).sqrt();
                for j in 0..16 {
                    let phi = (j as f64 + 0.5) * 2.0 * PI / 16.0;
                    let d = DVec3::new(s * phi.cos(), s * phi.sin(), z);
                    let y = sh::eval(d);
                    for i in 0..COEFFS {
                        c[i] += w * 2.0 * PI / 16.0 * f(z) * y[i];
                    }
                }
            }
            c
        };
        // Rotate the z-axis results to n with an independent rotation (z → n).
        let axis = DVec3::Z.cross(n);
        let rot = if axis.length() < 1e-9 {
            DMat3::IDENTITY
        } else {
            DMat3::from_axis_angle(axis.normalize(), n.z.clamp(-1.0, 1.0).acos())
        };
        let r = Rotation::new(rot);
        let cap = r.apply(&exact(cos_alpha, &|_| 1.0));
        assert!(max_diff(&cap, &sh::cap(n, cos_alpha)) < 1e-10);
        let cosine = r.apply(&exact(0.0, &|z| z));
        assert!(max_diff(&cosine, &sh::clamped_cosine(n)) < 1e-10);
    }
    // ∫ max(cos, 0) dω = π.
    let c = sh::clamped_cosine(DVec3::Y);
    assert!((sh::dot(&c, &sh::one()) - PI).abs() < 1e-12);
}

#[test]
fn triple_product_matches_numerical_integration() {
    let tensor = sh::triple_tensor();
    // Symmetric and sparse: only triples whose bands satisfy the triangle rule.
    for e in &tensor {
        let (li, lj, lk) = (sh::band_of(e.i).0, sh::band_of(e.j).0, sh::band_of(e.k).0);
        assert!(lk <= li + lj && li <= lj + lk && lj <= li + lk);
        assert!((li + lj + lk) % 2 == 0, "parity");
    }
    let unordered = tensor.iter().filter(|e| e.i <= e.j && e.j <= e.k).count();
    eprintln!(
        "triple tensor: {} ordered non-zeros, {} with i ≤ j ≤ k",
        tensor.len(),
        unordered
    );
    let mut rng = Rng::new(6);
    let rule = sh::sphere_quadrature(8, 16);
    for _ in 0..20 {
        let (a, b) = (random_sh(&mut rng), random_sh(&mut rng));
        // Numerical projection of the pointwise product (degree ≤ 6 · 3: exact rule).
        let numeric = sh::project_with(|d| sh::eval_sum(&a, d) * sh::eval_sum(&b, d), &rule);
        assert!(max_diff(&numeric, &sh::product_sparse(&a, &b, &tensor)) < 1e-12);
        assert!(max_diff(&numeric, &sh::product_f64(&a, &b)) < 1e-12);
        let af = a.map(|x| x as f32);
        let bf = b.map(|x| x as f32);
        let p32 = sh::product(&af, &bf);
        for k in 0..COEFFS {
            assert!(
                (p32[k] as f64 - numeric[k]).abs() < 2e-5,
                "f32 product coefficient {k}"
            );
        }
    }
    // Multiplying by the constant 1 is the identity.
    let a = random_sh(&mut rng);
    assert!(max_diff(&sh::product_f64(&a, &sh::one()), &a) < 1e-12);
}

#[test]
fn generated_product_is_up_to_date() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/src/math/sh/product.rs");
    let want = sh::product_source();
    if std::env::var_os("GRADTRACE_REGENERATE").is_some() {
        std::fs::write(path, &want).unwrap();
    }
    let have = std::fs::read_to_string(path).unwrap();
    assert!(
        have == want,
        "src/math/sh/product.rs is stale: GRADTRACE_REGENERATE=1 cargo test --release --test sh"
    );
}

/// ∫ Y_i dω over the directions a parallelogram (corner `c`, edges `eu`, `ev`)
/// subtends from `p`, by an independent route: the area integral
/// ∫ Y(x̂) |n·(x − p)| / |x − p|³ dA, 4 × 4 Gauss–Legendre on sub-parallelograms
/// split while they are larger than a tenth of their distance (f64). With
/// `triangle`, the triangle c, c + eu, c + eu + ev instead.
fn area_projection(c: DVec3, eu: DVec3, ev: DVec3, p: DVec3, triangle: bool) -> Sh {
    let gl = sh::gauss_legendre(4);
    let n = eu.cross(ev);
    let extent = eu.length().max(ev.length());
    let mut out = [0.0; COEFFS];
    let mut stack = vec![(0.0f64, 0.0f64, 1.0f64, 0u32)];
    while let Some((u0, v0, size, depth)) = stack.pop() {
        let mid = c + eu * (u0 + 0.5 * size) + ev * (v0 + 0.5 * size);
        if extent * size > 0.1 * (mid - p).length() && depth < 16 {
            let h = 0.5 * size;
            stack.extend([
                (u0, v0, h, depth + 1),
                (u0 + h, v0, h, depth + 1),
                (u0, v0 + h, h, depth + 1),
                (u0 + h, v0 + h, h, depth + 1),
            ]);
            continue;
        }
        for &(a, wa) in &gl {
            for &(b, wb) in &gl {
                let (u, v) = (u0 + size * 0.5 * (a + 1.0), v0 + size * 0.5 * (b + 1.0));
                // The triangle c, c + eu, c + eu + ev by the collapsed square
                // (u, v) ↦ (u, u·v): Jacobian u.
                let (x, jac) = if triangle {
                    (c + eu * u + ev * (u * v), u)
                } else {
                    (c + eu * u + ev * v, 1.0)
                };
                let d = x - p;
                let r = d.length();
                let w = wa * wb * 0.25 * size * size * jac * n.dot(d).abs() / (r * r * r);
                let y = sh::eval(d / r);
                for i in 0..COEFFS {
                    out[i] += w * y[i];
                }
            }
        }
    }
    out
}

/// The exact projection of a spherical polygon (boundary recurrences over
/// zonal harmonics) against the area integral: random parallelograms and
/// triangles, seen from far, from just above them, beside an edge and from
/// behind; and additivity: a quad is the sum of its four quarters.
#[test]
fn polygon_projection_matches_the_area_integral() {
    let mut rng = Rng::new(57);
    let mut worst = 0.0f64;
    for case in 0..40 {
        let c = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5;
        let eu = random_dir(&mut rng) * (0.2 + 2.0 * rng.next_f64());
        let ev = (random_dir(&mut rng) * (0.2 + 2.0 * rng.next_f64())).reject_from(eu)
            + eu * (0.3 * rng.next_f64());
        let n = eu.cross(ev).normalize();
        // Heights from 10⁻³ to 10 of the quad's size, above a point inside or
        // outside it, on either side.
        let height = 10f64.powf(-3.0 + 4.0 * rng.next_f64()) * eu.length();
        let (a, b) = (1.6 * rng.next_f64() - 0.3, 1.6 * rng.next_f64() - 0.3);
        let side = if case % 2 == 0 { 1.0 } else { -1.0 };
        let p = c + eu * a + ev * b + n * (side * height);
        let triangle = case % 4 == 3;
        let want = area_projection(c, eu, ev, p, triangle);
        let f = |v: DVec3| (v - p).as_vec3a();
        let got: [f32; COEFFS] = if triangle {
            sh::polygon_projection([f(c), f(c + eu), f(c + eu + ev)])
        } else {
            sh::polygon_projection([f(c), f(c + eu), f(c + eu + ev), f(c + ev)])
        };
        let err = (0..COEFFS)
            .map(|i| (f64::from(got[i]) - want[i]).abs())
            .fold(0.0, f64::max);
        let scale = want.iter().map(|x| x.abs()).fold(0.0, f64::max).max(1e-3);
        worst = worst.max(err / scale);
        assert!(
            err < 2e-5 * scale + 1e-6,
            "case {case} (height {height:.3e}, {a:.2}, {b:.2}, triangle {triangle}): error {err:.3e} of {scale:.3e}\n{got:?}\n{want:?}"
        );
        if !triangle {
            let q = |u: f64, v: f64| {
                let (e, g) = (eu * 0.5, ev * 0.5);
                let o = c + eu * u + ev * v;
                sh::polygon_projection([f(o), f(o + e), f(o + e + g), f(o + g)])
            };
            let parts = [q(0.0, 0.0), q(0.5, 0.0), q(0.0, 0.5), q(0.5, 0.5)];
            for i in 0..COEFFS {
                let sum: f32 = parts.iter().map(|x| x[i]).sum();
                assert!(
                    (sum - got[i]).abs() < 2e-5 * scale as f32 + 1e-6,
                    "case {case}: quarters {sum} vs {}",
                    got[i]
                );
            }
        }
    }
    eprintln!("worst relative error {worst:.2e}");
}

/// The basis in f32 is the f64 basis rounded.
#[test]
fn f32_basis_is_the_f64_basis() {
    let mut rng = Rng::new(9);
    for _ in 0..100 {
        let d = random_dir(&mut rng);
        let (a, b) = (sh::eval(d), sh::eval_f32(d.as_vec3a()));
        for i in 0..COEFFS {
            assert!(
                (f64::from(b[i]) - a[i]).abs() < 1e-6,
                "{i}: {} vs {}",
                b[i],
                a[i]
            );
        }
    }
}
