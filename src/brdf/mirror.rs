//! Perfect specular reflection, a Dirac delta: it has no density, so `eval` and `pdf`
//! return 0 and only `sample` transports light, with `weight = reflectance` and the
//! conventional `pdf = 1` (flagged by `is_delta`; never used for MIS).

use super::{sanitize, BsdfSample};
use crate::math::Vec3;

/// Mirror reflection about +z: wi = (−wo.x, −wo.y, wo.z) (the caller has checked
/// that `wo` is a finite direction above the horizon).
pub(super) fn sample(reflectance: Vec3, wo: Vec3) -> Option<BsdfSample> {
    let wi = Vec3::new(-wo.x, -wo.y, wo.z).normalize_or_zero();
    if wi.z <= 0.0 {
        return None;
    }
    Some(BsdfSample {
        wi,
        weight: sanitize(reflectance),
        pdf: 1.0,
        is_delta: true,
    })
}
