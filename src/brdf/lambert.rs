//! Lambertian reflection: f = albedo/π with cosine-weighted sampling, for which
//! `f · cos θi / pdf = albedo` exactly (no division is performed).

use super::{sanitize, BsdfSample};
use crate::math::{warp, Vec2, Vec3};

/// f = albedo/π (the caller has checked both directions are above the horizon).
pub(super) fn eval(albedo: Vec3) -> Vec3 {
    super::lambert_f(sanitize(albedo))
}

/// Cosine-weighted density cos θi / π, from the normalised cos θi (the caller
/// has checked it is positive).
pub(super) fn pdf(cos: f64) -> f64 {
    cos * std::f64::consts::FRAC_1_PI
}

/// [`pdf`] of `wi`, its cos θi normalised at f64, as an f32 made finite: zero
/// below the horizon and for a zero, NaN or infinite `wi` (whose z over its
/// length is then NaN, infinite or zero). Components, not a `Vec3`: the lane
/// kernel calls it lane by lane.
#[inline(always)]
pub(super) fn pdf_wi(x: f32, y: f32, z: f32) -> f32 {
    let (x, y, z) = (f64::from(x), f64::from(y), f64::from(z));
    let len2 = x * x + y * y + z * z;
    super::finite_nonneg(pdf(z / len2.sqrt()) as f32)
}

/// Malley's method via [`warp::square_to_cosine_hemisphere`]; `wo` is above the
/// horizon (checked by the caller). A direction on the horizon (the rim of the disk)
/// has zero density and is rejected. The map's direction is of unit length to a few
/// ulp (z = √(1 − r²)), so the warp's own density applies as it stands:
/// `Material::pdf`'s f64 normalisation (kept there, for directions from elsewhere)
/// would move it by ~1e-7 and cost a square root and a division on the path's
/// critical chain.
pub(super) fn sample(albedo: Vec3, u: Vec2) -> Option<BsdfSample> {
    let wi = warp::square_to_cosine_hemisphere(u);
    let pdf = warp::cosine_hemisphere_pdf(wi);
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
