//! Lambertian reflection: f = albedo/π with cosine-weighted sampling, for which
//! `f · cos θi / pdf = albedo` exactly (no division is performed).

use super::{sanitize, unit_z, BsdfSample};
use crate::math::{warp, Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// f = albedo/π (the caller has checked both directions are above the horizon).
pub(super) fn eval(albedo: Vec3) -> Vec3 {
    sanitize(albedo) * FRAC_1_PI
}

/// Cosine-weighted density cos θi / π, from the normalised cos θi (the caller
/// has checked it is positive).
pub(super) fn pdf(cos: f64) -> f64 {
    cos * std::f64::consts::FRAC_1_PI
}

/// Malley's method via [`warp::square_to_cosine_hemisphere`]; `wo` is above the
/// horizon (checked by the caller). A direction on the horizon (the rim of the disk)
/// has zero density and is rejected.
pub(super) fn sample(albedo: Vec3, u: Vec2) -> Option<BsdfSample> {
    let wi = warp::square_to_cosine_hemisphere(u);
    let z = unit_z(wi)?;
    if z <= 0.0 {
        return None;
    }
    let pdf = pdf(z) as f32;
    if pdf <= 0.0 {
        return None;
    }
    Some(BsdfSample {
        wi,
        weight: sanitize(albedo),
        pdf,
        is_delta: false,
    })
}
