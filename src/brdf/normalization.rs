//! Normalization factors of the Phong / Blinn-Phong family, one pure function per
//! row of the table in "The Blinn-Phong Normalization Zoo" (Schüler 2011,
//! `papers/blinn-phong-normalization-zoo.md`, section "The Normalization Zoo").
//!
//! Each factor `N(n)` makes the named integrand integrate to one:
//!
//! * RDF rows (reflection density = BRDF · cos θ): with the viewer on the normal
//!   (V = N, so R = N and the angle between N and H is θ/2),
//!   `N(n) · 2π ∫_0^{π/2} integrand(θ) dθ = 1`.
//! * NDF rows (micro-facet normal density): `N(n) · 2π ∫_0^{π/2} integrand(α) dα = 1`,
//!   α being the angle between N and H.
//!
//! All functions take the exponent `n` in f64 (exact up to 1e5 and beyond) and clamp
//! a negative or NaN `n` to 0, where every form is still finite. The test file
//! `tests/brdf.rs` checks each factor, and the zoo's bounds, against quadrature.

use std::f64::consts::PI;

/// Sanitises an exponent: NaN and negatives become 0 (the forms are defined for n ≥ 0).
fn clamp_n(n: f64) -> f64 {
    if n >= 0.0 {
        n
    } else {
        0.0
    }
}

/// Phong RDF `(R·L)^n`, integrand `cos^n θ sin θ`: `N = (n+1) / (2π)`.
pub fn phong_rdf(n: f64) -> f64 {
    (clamp_n(n) + 1.0) / (2.0 * PI)
}

/// Modified Phong RDF `(R·L)^n (N·L)`, integrand `cos^n θ cos θ sin θ`:
/// `N = (n+2) / (2π)` (Lafortune & Willems; Lewis 1994).
pub fn phong_modified_rdf(n: f64) -> f64 {
    (clamp_n(n) + 2.0) / (2.0 * PI)
}

/// Blinn-Phong RDF `(N·H)^n` (no cosine in the shader), integrand
/// `cos^n(θ/2) sin θ`, exact factor `N = (n+2) / (4π (2 − 2^{−n/2}))`.
///
/// Derivation: with `c = cos(θ/2)`, `sin θ dθ = −4c dc`, so the integral is
/// `8π (1 − 2^{−(n+2)/2}) / (n+2)`.
pub fn blinn_phong_rdf(n: f64) -> f64 {
    let n = clamp_n(n);
    (n + 2.0) / (4.0 * PI * (2.0 - (-n / 2.0).exp2()))
}

/// The zoo's bounds on [`blinn_phong_rdf`]: `(n+2)/(8π) < N < (n+4)/(8π)`.
/// The upper bound is attained at n = 0 (strict for n > 0).
pub fn blinn_phong_rdf_bounds(n: f64) -> (f64, f64) {
    let n = clamp_n(n);
    ((n + 2.0) / (8.0 * PI), (n + 4.0) / (8.0 * PI))
}

/// Modified Blinn-Phong RDF `(N·H)^n (N·L)` — i.e. the BRDF `(N·H)^n` — with
/// integrand `cos^n(θ/2) cos θ sin θ`, exact factor
/// `N = (n+2)(n+4) / (8π (2^{−n/2} + n))`.
///
/// This is the normalization [`crate::brdf::Material::BlinnPhong`] ships: it makes the
/// directional albedo of the specular lobe exactly `ks` at normal incidence.
pub fn blinn_phong_modified_rdf(n: f64) -> f64 {
    let n = clamp_n(n);
    (n + 2.0) * (n + 4.0) / (8.0 * PI * ((-n / 2.0).exp2() + n))
}

/// The zoo's bounds on [`blinn_phong_modified_rdf`]: `(n+6)/(8π) < N < (n+8)/(8π)`.
/// The upper bound (the popular "(n+8)/8π" of Real-Time Rendering) is attained at
/// n = 0 and overshoots the exact factor for n > 0, i.e. it gains energy.
pub fn blinn_phong_modified_rdf_bounds(n: f64) -> (f64, f64) {
    let n = clamp_n(n);
    ((n + 6.0) / (8.0 * PI), (n + 8.0) / (8.0 * PI))
}

/// Blinn-Phong NDF `(N·H)^n`, integrand `cos^n α sin α`: `N = (n+1) / (2π)`.
/// This is `D` of the minimalist Cook-Torrance model and the half-vector sampling
/// density of the glossy lobes.
pub fn blinn_phong_ndf(n: f64) -> f64 {
    (clamp_n(n) + 1.0) / (2.0 * PI)
}

/// Blinn-Phong height-field NDF (projected micro-facet area normalised to the
/// ground plane), integrand `cos^n α cos α sin α`: `N = (n+2) / (2π)` (PBRT).
pub fn blinn_phong_heightfield_ndf(n: f64) -> f64 {
    (clamp_n(n) + 2.0) / (2.0 * PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closed_forms_at_zero_and_large_n() {
        // n = 0: the modified Blinn-Phong BRDF is constant, i.e. Lambert: 1/π.
        assert!((blinn_phong_modified_rdf(0.0) - 1.0 / PI).abs() < 1e-15);
        // Large n: both exact RDF factors approach their lower bounds' slope.
        let n = 1e5;
        assert!(blinn_phong_modified_rdf(n).is_finite());
        assert!((blinn_phong_rdf(n) / blinn_phong_rdf_bounds(n).0 - 1.0).abs() < 1e-12);
        assert_eq!(blinn_phong_rdf(f64::NAN), blinn_phong_rdf(0.0));
    }
}
