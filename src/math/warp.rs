//! Warps from the unit square to directions and points, each with its density.
//! Densities are with respect to solid angle (directions) or area (points).

use super::lanes::{Lanes, V3};
use super::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, PI};

/// Concentric (Shirley–Chiu) map from the square to the unit disk: low distortion,
/// so stratification of the input survives.
pub fn square_to_disk_concentric(u: Vec2) -> Vec2 {
    let (x, y, _) = concentric(u.x, u.y);
    Vec2::new(x, y)
}

/// The concentric map's point (x, y) and its radius r (the major
/// coordinate's magnitude), over any [`Lanes`]: the one formula for the
/// path tracer and the lane kernel.
#[inline(always)]
pub fn concentric<L: Lanes>(u0: L, u1: L) -> (L, L, L) {
    let zero = L::splat(0.0);
    let one = L::splat(1.0);
    let ox = L::splat(2.0) * u0 - one;
    let oy = L::splat(2.0) * u1 - one;
    let centre = ox.eq(zero).and(oy.eq(zero));
    // Which wedge is a coin flip per sample: selects, not a branch the CPU
    // would mispredict half the time. θ = π/4 · ratio in the x wedges and
    // π/2 − π/4 · ratio in the y wedges, whose cosine and sine are the sine
    // and cosine of π/4 · ratio: one short polynomial instead of a libm call
    // (`sincosf` was 4 % of a cornell render).
    let x_major = ox.abs().gt(oy.abs());
    let r = x_major.select(ox, oy);
    let other = x_major.select(oy, ox);
    let (s, c) = sin_cos_quarter(L::splat(std::f32::consts::FRAC_PI_4) * (other / r));
    let (cos, sin) = (x_major.select(c, s), x_major.select(s, c));
    let r = centre.select(zero, r);
    (
        centre.select(zero, r * cos),
        centre.select(zero, r * sin),
        r.abs(),
    )
}

/// (sin x, cos x) for |x| ≤ π/4 within 2 ulp: Cephes' `sinf`/`cosf`
/// minimax polynomials on that interval (S. Moshier), which is all the
/// concentric map needs (no range reduction).
#[inline(always)]
fn sin_cos_quarter<L: Lanes>(x: L) -> (L, L) {
    let k = L::splat;
    let z = x * x;
    let sin = ((k(-1.951_529_6e-4) * z + k(8.332_161e-3)) * z - k(1.666_665_5e-1)) * z * x + x;
    let cos = ((k(2.443_315_7e-5) * z - k(1.388_731_6e-3)) * z + k(4.166_664_6e-2)) * z * z
        - k(0.5) * z
        + k(1.0);
    (sin, cos)
}

/// Cosine-weighted hemisphere around +z (Malley's method).
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    cosine_hemisphere(u.x, u.y).to_vec3()
}

/// [`square_to_cosine_hemisphere`] over any [`Lanes`]. z from the radius, not
/// from |d|²: the same value to a few ulp, but its square root no longer
/// waits for the division and the polynomial.
#[inline(always)]
pub fn cosine_hemisphere<L: Lanes>(u0: L, u1: L) -> V3<L> {
    let (x, y, r) = concentric(u0, u1);
    let z = (L::splat(1.0) - r * r).max(L::splat(0.0)).sqrt();
    V3 { x, y, z }
}

pub fn cosine_hemisphere_pdf(v: Vec3) -> f32 {
    cosine_hemisphere_pdf_z(v.z)
}

/// [`cosine_hemisphere_pdf`] from the direction's z, over any [`Lanes`].
#[inline(always)]
pub fn cosine_hemisphere_pdf_z<L: Lanes>(z: L) -> L {
    z.gt(L::splat(0.0))
        .select(z * L::splat(FRAC_1_PI), L::splat(0.0))
}

pub fn square_to_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

pub const UNIFORM_SPHERE_PDF: f32 = 0.25 * FRAC_1_PI;

/// Uniform direction in the cone of half-angle acos(cos_max) around +z.
pub fn square_to_uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_t = 1.0 - u.x * (1.0 - cos_max);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

pub fn uniform_cone_pdf(cos_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_max))
}

/// Barycentric coordinates (b1, b2) uniform over a triangle (Heitz 2019, low distortion).
pub fn square_to_uniform_triangle(u: Vec2) -> Vec2 {
    let (b0, b1);
    if u.x < u.y {
        b0 = u.x / 2.0;
        b1 = u.y - b0;
    } else {
        b1 = u.y / 2.0;
        b0 = u.x - b1;
    }
    Vec2::new(b0, b1)
}

/// Samples a von Mises–Fisher lobe around +z with concentration `kappa`
/// (Wenzel Jakob, "Numerically stable sampling of the vMF distribution", 2012),
/// stable for kappa up to 1e6 and down to 0.
pub fn square_to_vmf(u: Vec2, kappa: f32) -> Vec3 {
    if kappa < 1e-4 {
        return square_to_uniform_sphere(u);
    }
    // cos θ = 1 + log(u + (1-u) e^{-2κ}) / κ, written stably.
    let w = 1.0 + (u.x + (1.0 - u.x) * (-2.0 * kappa).exp()).max(1e-30).ln() / kappa;
    let w = w.clamp(-1.0, 1.0);
    let r = (1.0 - w * w).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), w)
}

/// Density of [`square_to_vmf`] for a direction with `cos θ = cos_theta` to +z.
pub fn vmf_pdf(cos_theta: f32, kappa: f32) -> f32 {
    if kappa < 1e-4 {
        return UNIFORM_SPHERE_PDF;
    }
    // κ / (2π (1 - e^{-2κ})) · e^{κ (cos θ - 1)}
    kappa / (2.0 * PI * (-(-2.0 * kappa).exp_m1())) * (kappa * (cos_theta - 1.0)).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Monte Carlo check that a warp's density integrates to one over its image: a
    /// uniform-sphere estimate of ∫ pdf dω must be 1.
    fn integrates_to_one(pdf: impl Fn(Vec3) -> f32) -> f32 {
        let n = 200_000;
        let mut sum = 0.0f64;
        for i in 0..n {
            let u = Vec2::new(sobol_burley::sample(i, 0, 7), sobol_burley::sample(i, 1, 7));
            sum += (pdf(square_to_uniform_sphere(u)) / UNIFORM_SPHERE_PDF) as f64;
        }
        (sum / n as f64) as f32
    }

    #[test]
    fn densities_are_normalised() {
        assert!((integrates_to_one(cosine_hemisphere_pdf) - 1.0).abs() < 5e-3);
        for kappa in [0.5f32, 5.0, 50.0] {
            let s = integrates_to_one(|v| vmf_pdf(v.z, kappa));
            assert!((s - 1.0).abs() < 2e-2, "kappa {kappa}: {s}");
        }
        let cos_max = 0.8;
        let s = integrates_to_one(|v| {
            if v.z >= cos_max {
                uniform_cone_pdf(cos_max)
            } else {
                0.0
            }
        });
        assert!((s - 1.0).abs() < 1e-2);
    }

    #[test]
    fn quarter_sin_cos_is_within_two_ulp() {
        // A dense grid over [−π/4, π/4] plus its ends, against libm.
        let n = 200_000;
        for i in 0..=n {
            let x = std::f32::consts::FRAC_PI_4 * (2.0 * i as f32 / n as f32 - 1.0);
            let (s, c): (f32, f32) = sin_cos_quarter(x);
            let (ws, wc) = x.sin_cos();
            assert!(
                (s - ws).abs() <= 2.0 * f32::EPSILON * ws.abs().max(f32::MIN_POSITIVE),
                "sin {x}: {s} vs {ws}"
            );
            assert!(
                (c - wc).abs() <= 2.0 * f32::EPSILON * wc,
                "cos {x}: {c} vs {wc}"
            );
        }
        assert_eq!(sin_cos_quarter(0.0f32), (0.0, 1.0));
    }

    #[test]
    fn warps_land_in_their_domain() {
        for i in 0..1000u32 {
            let u = Vec2::new(sobol_burley::sample(i, 0, 1), sobol_burley::sample(i, 1, 1));
            assert!(square_to_disk_concentric(u).length() <= 1.0 + 1e-6);
            let h = square_to_cosine_hemisphere(u);
            assert!(h.z >= 0.0 && (h.length() - 1.0).abs() < 1e-5);
            let b = square_to_uniform_triangle(u);
            assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
            let v = square_to_vmf(u, 1e5);
            assert!(v.is_finite() && (v.length() - 1.0).abs() < 1e-4);
        }
    }
}
