//! What the approximate previews (`preview/`) need to know of a material, so that
//! they hold no `match` on its variants: its diffuse albedo and its split into a
//! diffuse and a glossy part.

use super::Material;
use crate::math::Vec3;

/// A material split into the parts the glossy preview fits separately.
#[derive(Clone, Debug, PartialEq)]
pub struct PreviewParts {
    /// kd of f = kd/π (zero for a purely glossy material).
    pub kd: Vec3,
    /// The glossy lobe alone (its kd zeroed); `None` for a Lambertian material.
    pub glossy: Option<Material>,
}

impl Material {
    /// The albedo of the diffuse part: what a diffuse-only preview (the shadow
    /// field) shades with. Glossy lobes are left out and a mirror is black.
    pub fn diffuse_albedo(&self) -> Vec3 {
        match self {
            Material::Lambert { albedo } => *albedo,
            Material::BlinnPhong { kd, .. } | Material::CookTorrance { kd, .. } => *kd,
            Material::Mirror { .. } => Vec3::ZERO,
        }
    }

    /// The diffuse and glossy parts, or why a preview of smooth lobes cannot hold
    /// this material (a delta lobe).
    pub fn preview_parts(&self) -> Result<PreviewParts, String> {
        let (kd, glossy) = match self {
            Material::Lambert { albedo } => (*albedo, None),
            Material::BlinnPhong { kd, ks, exponent } => (
                *kd,
                Some(Material::BlinnPhong {
                    kd: Vec3::ZERO,
                    ks: *ks,
                    exponent: *exponent,
                }),
            ),
            Material::CookTorrance { kd, ks, exponent } => (
                *kd,
                Some(Material::CookTorrance {
                    kd: Vec3::ZERO,
                    ks: *ks,
                    exponent: *exponent,
                }),
            ),
            Material::Mirror { .. } => {
                return Err(
                    "a mirror is a delta lobe, which one vMF lobe per path type cannot hold".into(),
                )
            }
        };
        Ok(PreviewParts { kd, glossy })
    }

    /// The glossy lobe's colour ks (sanitised, as `eval` reads it) and the lobe
    /// with kd = 0 and ks = 1: a preview that tabulates the lobe once in one
    /// channel scales it by ks. `None` without a smooth glossy lobe.
    pub fn glossy_lobe_unit(&self) -> Option<(Vec3, Material)> {
        match self {
            Material::BlinnPhong { ks, exponent, .. } => Some((
                super::sanitize(*ks),
                Material::BlinnPhong {
                    kd: Vec3::ZERO,
                    ks: Vec3::ONE,
                    exponent: *exponent,
                },
            )),
            Material::CookTorrance { ks, exponent, .. } => Some((
                super::sanitize(*ks),
                Material::CookTorrance {
                    kd: Vec3::ZERO,
                    ks: Vec3::ONE,
                    exponent: *exponent,
                },
            )),
            Material::Lambert { .. } | Material::Mirror { .. } => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glossy_parts_keep_the_lobe_and_drop_the_diffuse_term() {
        let (kd, ks) = (Vec3::new(0.2, 0.3, 0.4), Vec3::splat(0.5));
        let m = Material::CookTorrance {
            kd,
            ks,
            exponent: 64.0,
        };
        assert_eq!(m.diffuse_albedo(), kd);
        let parts = m.preview_parts().unwrap();
        assert_eq!(parts.kd, kd);
        assert_eq!(
            parts.glossy,
            Some(Material::CookTorrance {
                kd: Vec3::ZERO,
                ks,
                exponent: 64.0
            })
        );
        let lambert = Material::Lambert { albedo: kd };
        assert_eq!(lambert.diffuse_albedo(), kd);
        assert_eq!(lambert.preview_parts().unwrap().glossy, None);
        let mirror = Material::Mirror { reflectance: ks };
        assert_eq!(mirror.diffuse_albedo(), Vec3::ZERO);
        assert!(mirror.preview_parts().unwrap_err().contains("delta lobe"));
        let (c, unit) = m.glossy_lobe_unit().unwrap();
        assert_eq!(c, ks);
        let (wo, wi) = (Vec3::new(0.3, 0.1, 0.9), Vec3::new(-0.2, 0.0, 0.95));
        let (f, g) = (parts.glossy.unwrap().eval(wo, wi), unit.eval(wo, wi));
        assert!((f - ks * g).abs().max_element() <= 1e-6 * f.max_element());
        assert!(lambert.glossy_lobe_unit().is_none() && mirror.glossy_lobe_unit().is_none());
    }
}
