//! Materials: `eval`, importance `sample` and `pdf` in the local shading frame
//! (+z = shading normal; `wo` and `wi` both point away from the surface).
//!
//! Conventions shared by every material:
//! * `eval` returns the BRDF f (no cosine); `pdf` is a density w.r.t. solid angle;
//!   `sample` returns `weight = f · cos θi / pdf`, with `pdf` exactly the value
//!   [`Material::pdf`] returns for the sampled direction (MIS relies on it).
//! * A direction on or below the horizon (`z <= 0`) gives f = 0, pdf = 0 and no sample.
//! * Inputs are re-normalised in f64; NaN/negative colours count as 0 and exponents are
//!   clamped to `[0, MAX_EXPONENT]`, so no input can produce NaN or Inf.
//! * Each material's f is written once, in [`Material::f`], generic over
//!   [`Scalar`] and fed the half-vector sum ([`HalfSum`]):
//!   `eval` runs it at f64 in the local frame, the gradient stage over dual numbers in
//!   world space ([`Material::f_cos_world`]), so both share the guards above. Every
//!   `match` on a material's variants lives in this module.
//!
//! Adding a material: a variant here, its formulas in a file of this folder (f generic
//! over `Scalar`, plus pdf and sampling), an arm in each method of [`Material`], and its
//! TOML form in `scene/parse.rs`; render/ needs no change.
//!
//! Formulas are from "The Blinn-Phong Normalization Zoo" (Schüler 2011,
//! `papers/blinn-phong-normalization-zoo.md`, "the zoo" below):
//!
//! * **Lambert**: f = albedo/π, cosine-weighted sampling.
//! * **BlinnPhong**: f = kd/π + ks · N(n) · (N·H)^n with the zoo's *exact* "Blinn-Phong
//!   (modified)" RDF factor N(n) = (n+2)(n+4) / (8π (2^{−n/2} + n))
//!   ([`normalization::blinn_phong_modified_rdf`]). Why this form: (N·H)^n with no extra
//!   cosine *is* the modified (cosine-carrying) RDF, and the exact factor makes the
//!   specular albedo exactly `ks` at normal incidence (the zoo's normalization
//!   condition). Away from the normal the albedo falls (roughly like cos²θo for large n,
//!   since part of the lobe leaves the hemisphere and the (N·H)^n lobe gets squeezed),
//!   so energy ≤ 1 holds for every wo when ks ≤ 1 (and kd + ks ≤ 1 for the sum); the
//!   test file verifies this over a sweep down to θo = 90° − 1e−7. At grazing angles
//!   the highlight therefore *dims* (no Fresnel brightening), and f stays bounded
//!   by N(n), so there are no fireflies. The popular (n+8)/(8π) upper bound gains up
//!   to ~2/n energy at normal incidence and (n+2)/(8π) loses up to half at n = 0; the
//!   exact form costs one `exp2` per material evaluation. At n = 0 it is Lambert.
//! * **CookTorrance**: the zoo's "minimalist Cook-Torrance",
//!   f = kd/π + ks · (n+1)(N·H)^n / (8π (L·H)^3) = kd/π + ks·D·FV with the NDF-normalised
//!   D = (n+1)/(2π) (N·H)^n and FV = 1/(4 (L·H)^3). This model is **not energy
//!   conserving away from the normal**: for large n its specular albedo is ≈ ks/cos θo
//!   (FV mimics Fresnel brightening, with no cap), and it diverges at grazing
//!   incidence. It is implemented as published; (L·H) is floored at [`MIN_LH`] so
//!   values stay finite (≤ ~1e25 for n ≤ 1e5). Use it with dielectric-like ks
//!   (0.02–0.05, as the zoo intends) and expect bright silhouettes.
//! * **Mirror**: a Dirac delta: eval/pdf are 0, `sample` returns the reflection with
//!   `weight = reflectance`, `pdf = 1` and `is_delta`.
//!
//! Glossy sampling (BlinnPhong, CookTorrance): the lobe is chosen with probability
//! proportional to luminance(ks) vs luminance(kd) using `u_lobe`; the specular lobe
//! samples the half vector with `pdf_h = (n+1)/(2π) cos^n θh` (cos θh = (1−u)^{1/(n+1)})
//! and reflects `wo`, so `pdf_wi = pdf_h / (4 wo·h)`. Samples whose reflection falls
//! below the horizon are returned as `None` (their mass is missing from `pdf`, which
//! is therefore exactly the density of the returned directions).

pub(crate) mod display;
mod glossy;
mod lambert;
mod mirror;
pub mod normalization;
mod preview;

use crate::math::lanes::{Lanes, Vector3};
use crate::math::scalar::{dot, Scalar};
use crate::math::{Vec2, Vec3};
use glam::DVec3;

pub use glossy::MIN_LH;
pub use preview::PreviewParts;

/// Largest exponent honoured; larger (or infinite) exponents are clamped to it. At 1e7
/// the lobe is ~6e-4 rad wide, still resolvable with f32 directions.
pub const MAX_EXPONENT: f32 = 1e7;

/// The closed set of materials.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// f = albedo / π.
    Lambert { albedo: Vec3 },
    /// Diffuse plus normalised Blinn-Phong lobe: f = kd/π + ks · N(n) (N·H)^n.
    BlinnPhong { kd: Vec3, ks: Vec3, exponent: f32 },
    /// Minimalist Cook-Torrance: f = kd/π + ks·(n+1)(N·H)^n / (8π (L·H)^3).
    CookTorrance { kd: Vec3, ks: Vec3, exponent: f32 },
    /// Perfect specular reflection (a Dirac delta).
    Mirror { reflectance: Vec3 },
}

/// A direction drawn by [`Material::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    pub wi: Vec3,
    /// f · cos θ_i / pdf (for a delta lobe: the reflectance).
    pub weight: Vec3,
    /// Solid-angle density (for a delta lobe: 1, not a density; see `is_delta`).
    pub pdf: f32,
    pub is_delta: bool,
}

impl Material {
    /// f(wo, wi), without the cosine; zero for delta lobes.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if let Material::Lambert { albedo } = self {
            // f does not depend on the directions, only on both being above the
            // horizon, which normalising cannot change: skip the two f64 square
            // roots `upper_pair` takes (same result bit for bit).
            let upper = wo.is_finite() && wi.is_finite() && wo.z > 0.0 && wi.z > 0.0;
            return if upper {
                lambert::eval(*albedo)
            } else {
                Vec3::ZERO
            };
        }
        let Some((wo, wi)) = upper_pair(wo, wi) else {
            return Vec3::ZERO;
        };
        to_f32(DVec3::from_array(self.f(&HalfSum::local(wo, wi))))
    }

    /// f for a pair of directions strictly above the horizon (checked by the
    /// caller), from their half-vector sum: the one implementation of every
    /// material, at f64 for [`eval`](Self::eval) and over duals for the gradients
    /// ([`f_cos_world`](Self::f_cos_world)). Zero for delta lobes.
    pub fn f<T: Scalar>(&self, h: &HalfSum<T>) -> [T; 3] {
        match self {
            Material::Lambert { albedo } => lambert::eval(*albedo)
                .to_array()
                .map(|c| T::constant(c as f64)),
            Material::BlinnPhong { .. } | Material::CookTorrance { .. } => {
                self.glossy().map_or([T::constant(0.0); 3], |g| g.f(h))
            }
            Material::Mirror { .. } => [T::constant(0.0); 3],
        }
    }

    /// f(ω_o, ω_i; n) · (n·ω_i)₊ for world-space unit vectors given as components
    /// (the gradient stage passes duals, whose lanes then carry the derivatives);
    /// zero unless both directions are strictly above the shading normal's horizon.
    pub fn f_cos_world<T: Scalar>(&self, n: [T; 3], wo: [T; 3], wi: [T; 3]) -> [T; 3] {
        let cos_i = dot(n, wi);
        let cos_o = dot(n, wo);
        if cos_i.value() <= 0.0 || cos_o.value() <= 0.0 {
            return [T::constant(0.0); 3];
        }
        self.f(&HalfSum::world(n, wo, wi)).map(|f| f * cos_i)
    }

    /// Solid-angle density of sampling `wi` given `wo`; zero for delta lobes.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let p = match self {
            // cos θi / π needs only wi's normalised z, and wo only its side: the
            // same bits as normalising both at f64, without five of the divisions.
            Material::Lambert { .. } => {
                return if upper(wo) { lambert_pdf(wi) } else { 0.0 };
            }
            Material::BlinnPhong { .. } | Material::CookTorrance { .. } => upper_pair(wo, wi)
                .map_or(0.0, |(wo, wi)| self.glossy().map_or(0.0, |g| g.pdf(wo, wi))),
            Material::Mirror { .. } => 0.0,
        };
        finite_nonneg(p as f32)
    }

    /// Importance-samples `wi`; `u_lobe` chooses the lobe, `u` the direction.
    /// `None` when `wo` is below the horizon, the material is black, or the sampled
    /// direction is unusable (below the horizon or of zero density).
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            // Only wo's side matters to a Lambertian or mirror sample: no f64
            // normalisation.
            Material::Lambert { albedo } => upper(wo).then(|| lambert::sample(*albedo, u))?,
            Material::Mirror { reflectance } => {
                upper(wo).then(|| mirror::sample(*reflectance, wo))?
            }
            Material::BlinnPhong { .. } | Material::CookTorrance { .. } => {
                let wo64 = unit(wo)?;
                if wo64.z <= 0.0 {
                    return None;
                }
                let g = self.glossy()?;
                let wi = g.sample_direction(wo64, u_lobe, u)?;
                // Evaluate f and pdf through exactly the path `eval`/`pdf` take, from
                // the f32 direction handed out, so that `pdf(wo, s.wi) == s.pdf`.
                let wi64 = unit(wi)?;
                if wi64.z <= 0.0 {
                    return None;
                }
                let (f, pdf) = g.eval_pdf(wo64, wi64);
                let pdf32 = pdf as f32;
                if !(pdf32 > 0.0 && pdf32.is_finite()) {
                    return None;
                }
                let weight = to_f32(f * (wi64.z / pdf));
                Some(BsdfSample {
                    wi,
                    weight,
                    pdf: pdf32,
                    is_delta: false,
                })
            }
        }
    }

    /// Directional albedo proxy for the `albedo` AOV (kd + ks, or reflectance).
    pub fn albedo(&self) -> Vec3 {
        match self {
            Material::Lambert { albedo } => *albedo,
            Material::BlinnPhong { kd, ks, .. } | Material::CookTorrance { kd, ks, .. } => {
                *kd + *ks
            }
            Material::Mirror { reflectance } => *reflectance,
        }
    }

    /// Ω_ρ = √(6s), the BRDF's angular bandwidth in the Durand et al. 2005 frequency
    /// analysis (first-order paper Sec. 9.1), with s the Phong exponent of an
    /// equivalent lobe: 1 for Lambert, the exponent (at least 1) for the glossy
    /// lobes and a large 1e4 for a mirror.
    pub fn angular_bandwidth(&self) -> f32 {
        let s = match self {
            Material::Lambert { .. } => 1.0,
            Material::BlinnPhong { exponent, .. } | Material::CookTorrance { exponent, .. } => {
                exponent.max(1.0)
            }
            Material::Mirror { .. } => 1e4,
        };
        (6.0 * s).sqrt()
    }

    /// True when the material is a pure delta (no light sampling is useful).
    pub fn is_delta(&self) -> bool {
        matches!(self, Material::Mirror { .. })
    }

    /// The shared glossy implementation for BlinnPhong / CookTorrance; `None` for
    /// other materials and for black glossy materials (nothing to sample).
    fn glossy(&self) -> Option<glossy::Glossy> {
        let g = match self {
            Material::BlinnPhong { kd, ks, exponent } => {
                glossy::Glossy::new(*kd, *ks, *exponent, glossy::SpecularForm::BlinnPhong)
            }
            Material::CookTorrance { kd, ks, exponent } => {
                glossy::Glossy::new(*kd, *ks, *exponent, glossy::SpecularForm::CookTorrance)
            }
            _ => return None,
        };
        (!g.is_black()).then_some(g)
    }
}

/// The half-vector *sum* s = ω_o + ω_i of two unit directions, seen from the
/// shading normal n: everything an isotropic half-vector lobe needs, without
/// cancellation (sin²θh = |n×s|²/|s|², L·H = |s|/2).
#[derive(Clone, Copy, Debug)]
pub struct HalfSum<T> {
    /// |s|².
    pub len2: T,
    /// |n × s|², the squared length of s's component in the tangent plane.
    pub perp2: T,
    /// n · s.
    pub along: T,
}

impl HalfSum<f64> {
    /// In the local shading frame (n = +z), in f64.
    pub fn local(wo: DVec3, wi: DVec3) -> Self {
        let s = wo + wi;
        Self {
            len2: s.length_squared(),
            perp2: s.x * s.x + s.y * s.y,
            along: s.z,
        }
    }
}

impl<T: Scalar> HalfSum<T> {
    /// In world space, for a unit normal `n`.
    pub fn world(n: [T; 3], wo: [T; 3], wi: [T; 3]) -> Self {
        let s = [0, 1, 2].map(|k| wo[k] + wi[k]);
        let c = [
            n[1] * s[2] - n[2] * s[1],
            n[2] * s[0] - n[0] * s[2],
            n[0] * s[1] - n[1] * s[0],
        ];
        Self {
            len2: dot(s, s),
            perp2: dot(c, c),
            along: dot(n, s),
        }
    }
}

/// `v` normalised in f64, or `None` for a zero, NaN or infinite vector.
fn unit(v: Vec3) -> Option<DVec3> {
    let d = v.as_dvec3();
    let len2 = d.length_squared();
    if !(len2 > 0.0 && len2.is_finite()) {
        return None;
    }
    Some(d / len2.sqrt())
}

/// Whether `v` normalised (by [`unit`]) is strictly above the horizon: only the
/// sign of its z matters, so no square root.
fn upper(v: Vec3) -> bool {
    let len2 = v.as_dvec3().length_squared();
    len2 > 0.0 && len2.is_finite() && v.z > 0.0
}

/// Both directions normalised and strictly above the horizon, or `None`.
fn upper_pair(wo: Vec3, wi: Vec3) -> Option<(DVec3, DVec3)> {
    let (wo, wi) = (unit(wo)?, unit(wi)?);
    (wo.z > 0.0 && wi.z > 0.0).then_some((wo, wi))
}

/// A colour parameter made usable: NaN, infinite and negative components become 0.
pub(crate) fn sanitize(c: Vec3) -> Vec3 {
    // Lane-wise compares (NaN fails both): no branch per channel; this runs on
    // every Lambertian sample and evaluation.
    let keep = c.cmpgt(Vec3::ZERO) & c.cmplt(Vec3::INFINITY);
    Vec3::select(keep, c, Vec3::ZERO)
}

fn finite_nonneg(x: f32) -> f32 {
    if x > 0.0 && x.is_finite() {
        x
    } else {
        0.0
    }
}

/// f64 → f32 colour; anything that would not be a finite non-negative f32 becomes 0
/// (cannot happen for sanitised parameters, kept as the last guard).
fn to_f32(c: DVec3) -> Vec3 {
    let v = c.as_vec3a();
    Vec3::new(finite_nonneg(v.x), finite_nonneg(v.y), finite_nonneg(v.z))
}

/// What the lane kernel (`render::lanes`) shades a material as: the
/// materials it takes, with the colour it reads (sanitised, as a sample's
/// weight is).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LaneBsdf {
    /// f = albedo/π ([`lambert_f`]), pdf [`lambert_pdf`], cosine-weighted
    /// samples ([`crate::math::warp::cosine_hemisphere`]).
    Lambert { albedo: Vec3 },
    /// The reflection about the normal, its weight the reflectance.
    Mirror { reflectance: Vec3 },
}

impl LaneBsdf {
    /// The colour a sample's weight carries: the albedo or the reflectance.
    pub fn weight(self) -> Vec3 {
        match self {
            LaneBsdf::Lambert { albedo } => albedo,
            LaneBsdf::Mirror { reflectance } => reflectance,
        }
    }

    pub fn is_mirror(self) -> bool {
        matches!(self, LaneBsdf::Mirror { .. })
    }
}

// The lanes' view of the materials, kept apart from the methods above.
impl Material {
    /// How the lanes shade this material; `None` for those only the path
    /// tracer's `li` shades (the glossy ones).
    pub fn lane_bsdf(&self) -> Option<LaneBsdf> {
        match self {
            Material::Lambert { albedo } => Some(LaneBsdf::Lambert {
                albedo: sanitize(*albedo),
            }),
            Material::Mirror { reflectance } => Some(LaneBsdf::Mirror {
                reflectance: sanitize(*reflectance),
            }),
            Material::BlinnPhong { .. } | Material::CookTorrance { .. } => None,
        }
    }
}

/// [`Material::pdf`] of a Lambertian for a `wo` above the horizon: `wi`'s z
/// normalised at f64, over π, made finite. The lane kernel calls it lane by
/// lane (an f64 formula has no eight-wide f32 form).
#[inline(always)]
pub fn lambert_pdf(wi: Vec3) -> f32 {
    lambert::pdf_wi(wi.x, wi.y, wi.z)
}

/// A mirror's sampled direction for `wo` in the local frame, on lanes: the
/// one formula of [`Material::sample`]'s mirror arm.
#[inline(always)]
pub fn mirror_reflect<L: Lanes>(wo: crate::math::lanes::V3<L>) -> crate::math::lanes::V3<L> {
    mirror::reflect(wo)
}

/// [`lambert_pdf`] of eight directions given by their components.
#[inline(always)]
pub fn lambert_pdf8(x: [f32; 8], y: [f32; 8], z: [f32; 8]) -> [f32; 8] {
    std::array::from_fn(|l| lambert::pdf_wi(x[l], y[l], z[l]))
}

/// A Lambertian's f = albedo/π from its sanitised albedo, on one colour
/// ([`Material::eval`]) or eight (the lane kernel).
#[inline(always)]
pub fn lambert_f<V: Vector3>(albedo: V) -> V {
    albedo.map(
        #[inline(always)]
        |a| a * V::L::splat(std::f32::consts::FRAC_1_PI),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_names_the_toml_type_and_parameters() {
        let m = Material::BlinnPhong {
            kd: Vec3::splat(0.5),
            ks: Vec3::new(0.25, 0.5, 1.0),
            exponent: 40.0,
        };
        assert_eq!(
            m.to_string(),
            "blinn_phong kd=[0.5, 0.5, 0.5] ks=[0.25, 0.5, 1] exponent=40"
        );
        let m = Material::Lambert {
            albedo: Vec3::new(0.7, 0.5, 0.3),
        };
        assert_eq!(m.to_string(), "lambert albedo=[0.7, 0.5, 0.3]");
    }

    #[test]
    fn lambert_shortcuts_give_the_bits_of_the_f64_normalisation() {
        // pdf skips normalising at f64 what only needs its sign or z, and sample
        // takes its warp's density; the reference below is the general path they
        // replace. pdf keeps its bits; a sample's density is within 1e-6 of it.
        let reference_pdf = |wo: Vec3, wi: Vec3| {
            upper_pair(wo, wi).map_or(0.0, |(_, wi)| finite_nonneg(lambert::pdf(wi.z) as f32))
        };
        let m = Material::Lambert {
            albedo: Vec3::new(0.7, f32::NAN, f32::INFINITY),
        };
        assert_eq!(
            m.eval(Vec3::Z, Vec3::Z),
            Vec3::new(0.7 * std::f32::consts::FRAC_1_PI, 0.0, 0.0)
        );
        let mut state = 0x2545_f491_u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as f32 / u32::MAX as f32
        };
        let scales = [1e-30f32, 1e-3, 1.0, 7.3, 1e18];
        let specials = [
            0.0f32,
            -0.0,
            f32::MIN_POSITIVE * 0.5,
            f32::INFINITY,
            f32::NAN,
        ];
        for i in 0..20_000 {
            let mut v = || {
                let s = scales[(next() * 5.0) as usize % 5];
                Vec3::new(next() - 0.5, next() - 0.5, next() - 0.3) * s
            };
            let (mut wo, wi) = (v(), v());
            if i % 50 == 0 {
                wo.z = specials[(i / 50) % 5];
            }
            assert_eq!(
                m.pdf(wo, wi).to_bits(),
                reference_pdf(wo, wi).to_bits(),
                "{wo} {wi}"
            );
            let u = Vec2::new(next(), next());
            let got = m.sample(wo, 0.5, u);
            let want = unit(wo)
                .filter(|w| w.z > 0.0)
                .and_then(|_| lambert::sample(Vec3::ONE, u));
            assert_eq!(got.is_some(), want.is_some(), "{wo}");
            if let (Some(g), Some(w)) = (got, want) {
                assert_eq!((g.wi, g.pdf), (w.wi, w.pdf));
                assert_eq!(g.pdf, g.wi.z * std::f32::consts::FRAC_1_PI);
                let r = reference_pdf(Vec3::Z, g.wi);
                assert!((g.pdf - r).abs() <= 1e-6 * r, "{} vs {r}", g.pdf);
            }
        }
    }
}
