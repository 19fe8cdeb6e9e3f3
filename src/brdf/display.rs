//! One line per material, as `info` prints it.

use super::Material;
use std::fmt;

/// `[x, y, z]`, as the scene file writes a colour.
pub(crate) struct V3(pub crate::math::Vec3);

impl fmt::Display for V3 {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "[{}, {}, {}]", self.0.x, self.0.y, self.0.z)
    }
}

impl fmt::Display for Material {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            Material::Lambert { albedo } => write!(f, "lambert albedo={}", V3(*albedo)),
            Material::BlinnPhong { kd, ks, exponent } => write!(
                f,
                "blinn_phong kd={} ks={} exponent={exponent}",
                V3(*kd),
                V3(*ks)
            ),
            Material::CookTorrance { kd, ks, exponent } => write!(
                f,
                "cook_torrance kd={} ks={} exponent={exponent}",
                V3(*kd),
                V3(*ks)
            ),
            Material::Mirror { reflectance } => {
                write!(f, "mirror reflectance={}", V3(*reflectance))
            }
        }
    }
}
