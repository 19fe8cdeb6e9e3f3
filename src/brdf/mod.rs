//! Materials: `eval`, importance `sample` and `pdf` in the local shading frame
//! (+z = shading normal; `wo` and `wi` both point away from the surface).
//!
//! OWNED BY THE BRDF WORK ITEM — the bodies below are placeholders to be replaced.

use crate::math::{Vec2, Vec3};

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
    pub fn eval(&self, _wo: Vec3, _wi: Vec3) -> Vec3 {
        Vec3::ZERO
    }
    /// Solid-angle density of sampling `wi` given `wo`; zero for delta lobes.
    pub fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }
    /// Importance-samples `wi`; `u_lobe` chooses the lobe, `u` the direction.
    pub fn sample(&self, _wo: Vec3, _u_lobe: f32, _u: Vec2) -> Option<BsdfSample> {
        None
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
    /// True when the material is a pure delta (no light sampling is useful).
    pub fn is_delta(&self) -> bool {
        matches!(self, Material::Mirror { .. })
    }
}

/// Placeholder until the BRDF work lands: the modified Blinn-Phong RDF factor.
pub mod normalization {
    pub fn blinn_phong_modified_rdf(n: f64) -> f64 {
        (n + 2.0) * (n + 4.0) / (8.0 * std::f64::consts::PI * ((-n / 2.0).exp2() + n))
    }
}
