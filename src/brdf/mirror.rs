//! Perfect specular reflection, a Dirac delta: it has no density, so `eval` and `pdf`
//! return 0 and only `sample` transports light, with `weight = reflectance` and the
//! conventional `pdf = 1` (flagged by `is_delta`; never used for MIS).

use super::{sanitize, BsdfSample};
use crate::math::lanes::{Lanes, V3};
use crate::math::Vec3;

/// Mirror reflection about +z: wi = (−wo.x, −wo.y, wo.z) (the caller has checked
/// that `wo` is a finite direction above the horizon).
pub(super) fn sample(reflectance: Vec3, wo: Vec3) -> Option<BsdfSample> {
    let wi = reflect(V3::from_vec3(wo)).to_vec3();
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

/// The reflection about +z, normalised (zero where `wo` has no length), on
/// one direction or on lanes (the lane kernel's mirrors).
#[inline(always)]
pub(super) fn reflect<L: Lanes>(wo: V3<L>) -> V3<L> {
    V3 {
        x: -wo.x,
        y: -wo.y,
        z: wo.z,
    }
    .normalize_or_zero()
}
