//! The two glossy materials, which share everything except the specular term:
//! a Lambertian lobe kd/π plus a half-vector lobe in (N·H)^n, sampled as a
//! luminance-weighted mixture of cosine sampling and Blinn-Phong NDF sampling.
//!
//! Everything is computed in f64 from the half-vector *sum* `s = wo + wi`:
//! `sin²θh = (s.x² + s.y²)/|s|²` has no cancellation, so `(N·H)^n = exp(n/2 · ln cos²θh)`
//! is accurate (and finite) for exponents up to 1e7 and directions grazing to 1e-7,
//! where `powf` on an f32 cosine would lose ~n·6e-8 relative precision. And
//! `L·H = V·H = |s|/2` is symmetric in `wo`, `wi` to the last bit (reciprocity).

use super::normalization::{blinn_phong_modified_rdf, blinn_phong_ndf};
use super::{sanitize, HalfSum, MAX_EXPONENT};
use crate::math::scalar::Scalar;
use crate::math::{warp, Vec2, Vec3};
use glam::DVec3;
use std::f64::consts::{FRAC_1_PI, PI};

/// Floor on L·H in the Cook-Torrance `1/(L·H)^3` and in the `1/(4 wo·h)` Jacobian.
/// L·H < 1e-8 needs `wi` within ~2e-8 rad of `−wo` mirrored through the horizon (a
/// set of negligible measure); the floor keeps f ≤ (n+1)/(8π)·1e24, finite in f32.
pub const MIN_LH: f64 = 1e-8;

/// Which specular term a [`Glossy`] evaluates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum SpecularForm {
    /// ks · N(n) (N·H)^n with N = [`blinn_phong_modified_rdf`] (zoo, "Blinn-Phong (modified)").
    BlinnPhong,
    /// ks · (n+1)(N·H)^n / (8π (L·H)^3) (zoo, "Minimalist Cook-Torrance").
    CookTorrance,
}

/// Sanitised parameters of a glossy material plus its precomputed constants.
#[derive(Clone, Copy, Debug)]
pub(super) struct Glossy {
    kd: DVec3,
    ks: DVec3,
    /// Specular exponent n, clamped to [0, MAX_EXPONENT].
    n: f64,
    /// Probability of choosing the specular lobe: lum(ks) / (lum(kd) + lum(ks)).
    p_spec: f64,
    /// Constant factor of the specular term: N(n) or (n+1)/(8π).
    spec_norm: f64,
    /// (n+1)/(2π): the half-vector sampling density's normalization.
    ndf_norm: f64,
    form: SpecularForm,
}

/// Rec.709 luminance in f64 (same weights as `math::luminance`).
fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Half-vector quantities of a pair of unit directions above the horizon: the
/// numerical guards of both glossy lobes, for every scalar type.
struct Half<T> {
    /// (N·H)^n.
    cos_n: T,
    /// L·H = V·H, floored at [`MIN_LH`].
    lh: T,
}

impl<T: Scalar> Half<T> {
    fn new(s: &HalfSum<T>, n: f64) -> Self {
        // |s| ≥ n·s = cos θo + cos θi > 0: no division by zero.
        let sin2 = s.perp2 / s.len2;
        let ln_cos2 = if sin2.value() < 0.5 {
            (-sin2).ln_1p()
        } else {
            (s.along * s.along / s.len2).ln()
        };
        let cos_n = if n == 0.0 {
            T::constant(1.0)
        } else {
            ln_cos2.mul_const(0.5 * n).exp()
        };
        Self {
            cos_n,
            lh: s.len2.sqrt().mul_const(0.5).max_const(MIN_LH),
        }
    }
}

impl Glossy {
    pub(super) fn new(kd: Vec3, ks: Vec3, exponent: f32, form: SpecularForm) -> Self {
        let kd = sanitize(kd).as_dvec3();
        let ks = sanitize(ks).as_dvec3();
        let n = if exponent >= 0.0 {
            exponent.min(MAX_EXPONENT) as f64
        } else {
            0.0
        };
        let (ld, ls) = (luminance(kd), luminance(ks));
        let p_spec = if ld + ls > 0.0 { ls / (ld + ls) } else { 0.0 };
        let spec_norm = match form {
            SpecularForm::BlinnPhong => blinn_phong_modified_rdf(n),
            SpecularForm::CookTorrance => (n + 1.0) / (8.0 * PI),
        };
        Self {
            kd,
            ks,
            n,
            p_spec,
            spec_norm,
            ndf_norm: blinn_phong_ndf(n),
            form,
        }
    }

    /// True when both lobes are black: eval is 0 and nothing can be sampled.
    pub(super) fn is_black(&self) -> bool {
        self.kd == DVec3::ZERO && self.ks == DVec3::ZERO
    }

    /// Scalar specular term (to be multiplied by ks).
    fn specular<T: Scalar>(&self, h: &Half<T>) -> T {
        match self.form {
            SpecularForm::BlinnPhong => h.cos_n.mul_const(self.spec_norm),
            // f_s = (n+1)(N·H)^n / (8π (L·H)^3), zoo "Minimalist Cook-Torrance".
            SpecularForm::CookTorrance => h.cos_n.mul_const(self.spec_norm) / (h.lh * h.lh * h.lh),
        }
    }

    /// Density of the specular strategy in wi: pdf_h / (4 wo·h), with
    /// pdf_h = (n+1)/(2π) (N·H)^n (zoo "Blinn-Phong (NDF)").
    fn specular_pdf(&self, h: &Half<f64>) -> f64 {
        self.ndf_norm * h.cos_n / (4.0 * h.lh)
    }

    /// f = kd/π + ks · specular, per channel.
    fn f_from<T: Scalar>(&self, h: &Half<T>) -> [T; 3] {
        let spec = self.specular(h);
        let (kd, ks) = (self.kd.to_array(), self.ks.to_array());
        [0, 1, 2].map(|c| spec.mul_const(ks[c]).add_const(kd[c] * FRAC_1_PI))
    }

    /// f for directions above the horizon given by their half-vector sum.
    pub(super) fn f<T: Scalar>(&self, s: &HalfSum<T>) -> [T; 3] {
        self.f_from(&Half::new(s, self.n))
    }

    /// f and the mixture pdf for unit directions above the horizon.
    pub(super) fn eval_pdf(&self, wo: DVec3, wi: DVec3) -> (DVec3, f64) {
        let h = Half::new(&HalfSum::local(wo, wi), self.n);
        let f = DVec3::from_array(self.f_from(&h));
        let pdf = (1.0 - self.p_spec) * wi.z * FRAC_1_PI + self.p_spec * self.specular_pdf(&h);
        (f, pdf)
    }

    pub(super) fn pdf(&self, wo: DVec3, wi: DVec3) -> f64 {
        self.eval_pdf(wo, wi).1
    }

    /// Draws a direction (f32, unit length) from the mixture; `None` when the
    /// reflected direction falls on or below the horizon.
    pub(super) fn sample_direction(&self, wo: DVec3, u_lobe: f32, u: Vec2) -> Option<Vec3> {
        if (u_lobe as f64) < self.p_spec {
            // cos θh = (1−u)^{1/(n+1)} inverts the CDF of pdf_h; written with
            // ln_1p/exp_m1 so that sin θh keeps full precision for n up to 1e7.
            let e = (-(u.x as f64).clamp(0.0, 1.0)).ln_1p() / (self.n + 1.0);
            let cos_h = e.exp();
            let sin_h = (-(2.0 * e).exp_m1()).max(0.0).sqrt();
            let phi = 2.0 * PI * u.y as f64;
            let h = DVec3::new(sin_h * phi.cos(), sin_h * phi.sin(), cos_h);
            let wi = (2.0 * wo.dot(h) * h - wo).normalize_or_zero();
            let wi32 = wi.as_vec3a();
            (wi32.z > 0.0).then_some(wi32)
        } else {
            let wi = warp::square_to_cosine_hemisphere(u);
            (wi.z > 0.0).then_some(wi)
        }
    }
}
