//! Robust spawning of secondary and shadow rays (pbrt-v4, §6.8.6 "Robust Spawned
//! Ray Origins", Pharr, Jakob & Humphreys).
//!
//! How callers should do it: never start a continuation or shadow ray at the raw
//! hit point with a fixed `t_min = 1e-4`. Instead recompute the point from the
//! primitive ([`crate::accel::Accel::surface_point`]), carry a conservative
//! absolute error bound `p_error` with it, and move the origin along the
//! *geometric* normal by `dot(|n|, p_error)` to the side the new ray leaves to,
//! then round it one more ulp away from the surface. The origin is then provably
//! on the correct side of the surface, so `t_min = 0` works with no self-hits and
//! no light leaks through thin geometry, at any scene scale. For shadow rays to a
//! light sample, offset both ends and stop just short of the target
//! ([`SurfacePoint::spawn_ray_to`]).

use crate::math::{Ray, Vec2, Vec3};

/// Unit roundoff of f32 (2^-24).
const UNIT_ROUNDOFF: f32 = f32::EPSILON * 0.5;

/// γ(n) = n·u / (1 − n·u), the bound on the relative error of n rounded operations
/// (pbrt-v4 eq. 6.25 / Higham).
fn gamma(n: i32) -> f32 {
    let nu = n as f32 * UNIT_ROUNDOFF;
    nu / (1.0 - nu)
}

/// Relative error assumed by [`offset_ray_origin`] when the caller has no error
/// bound: 2^-18 ≈ 64 ulps of the largest coordinate — covers a point interpolated
/// from vertices (pbrt's γ₇) or computed as `ray.at(t)` from an origin of similar
/// magnitude, with a wide margin.
const DEFAULT_REL_ERROR: f32 = 1.0 / 262_144.0;

/// Offsets `p` along the geometric normal `n_geo` to the side `dir` points to, far
/// enough that a ray from the result cannot re-hit the surface `p` lies on.
///
/// Uses a default error bound of 2^-18 · max|pᵢ| (plus a tiny absolute floor);
/// prefer [`SurfacePoint::spawn_ray`] when a [`SurfacePoint`] is available, which
/// carries an exact bound. `n_geo` need not face `dir`, nor be normalised.
pub fn offset_ray_origin(p: Vec3, n_geo: Vec3, dir: Vec3) -> Vec3 {
    let err = p.abs().max_element() * DEFAULT_REL_ERROR + 1.0e-30;
    offset_ray_origin_with_error(p, Vec3::splat(err), n_geo, dir)
}

/// pbrt-v4's `OffsetRayOrigin`: `d = dot(|n|, p_error)`, move `p` by `d·n` towards
/// the side of `dir`, then round every moved component one ulp further away.
pub fn offset_ray_origin_with_error(p: Vec3, p_error: Vec3, n_geo: Vec3, dir: Vec3) -> Vec3 {
    let d = n_geo.abs().dot(p_error);
    let mut offset = d * n_geo;
    if dir.dot(n_geo) < 0.0 {
        offset = -offset;
    }
    let po = p + offset;
    // Round away from p so that the rounding of `p + offset` cannot pull the
    // origin back onto the surface.
    let round = |x: f32, o: f32| {
        if o > 0.0 {
            next_float_up(x)
        } else if o < 0.0 {
            next_float_down(x)
        } else {
            x
        }
    };
    Vec3::new(
        round(po.x, offset.x),
        round(po.y, offset.y),
        round(po.z, offset.z),
    )
}

fn next_float_up(x: f32) -> f32 {
    if x.is_infinite() && x > 0.0 || x.is_nan() {
        return x;
    }
    let x = if x == -0.0 { 0.0 } else { x };
    let bits = x.to_bits();
    f32::from_bits(if x >= 0.0 { bits + 1 } else { bits - 1 })
}

fn next_float_down(x: f32) -> f32 {
    -next_float_up(-x)
}

/// A hit point recomputed from its primitive, with an absolute error bound and
/// the unit geometric normal (CCW winding for triangles, outward for spheres).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    pub p: Vec3,
    pub p_error: Vec3,
    pub n_geo: Vec3,
}

/// Fraction of the distance cut from the end of a shadow ray (pbrt's
/// `ShadowEpsilon`), on top of offsetting the target point itself.
const SHADOW_EPSILON: f32 = 1.0e-4;

impl SurfacePoint {
    /// A ray leaving the surface in direction `dir` (normalised here), with
    /// `t_min = 0`, `t_max = ∞`.
    pub fn spawn_ray(&self, dir: Vec3) -> Ray {
        let d = dir.normalize_or_zero();
        Ray::new(
            offset_ray_origin_with_error(self.p, self.p_error, self.n_geo, d),
            d,
        )
    }

    /// A shadow ray from this point to `target` (a point on another surface, with
    /// its own error bound and normal): both ends are offset, and the segment stops
    /// `SHADOW_EPSILON` short of the target so the target surface is not hit.
    pub fn spawn_ray_to(&self, target: &SurfacePoint) -> Ray {
        let towards = target.p - self.p;
        let o = offset_ray_origin_with_error(self.p, self.p_error, self.n_geo, towards);
        let end = offset_ray_origin_with_error(target.p, target.p_error, target.n_geo, -towards);
        Self::segment(o, end)
    }

    /// A shadow ray from this point to a point `target` that is not on a surface
    /// (e.g. a point light); only the origin is offset.
    pub fn spawn_ray_to_point(&self, target: Vec3) -> Ray {
        let o = offset_ray_origin_with_error(self.p, self.p_error, self.n_geo, target - self.p);
        Self::segment(o, target)
    }

    fn segment(o: Vec3, end: Vec3) -> Ray {
        let d = end - o;
        let len = d.length();
        if len.is_nan() || len <= 0.0 || len.is_infinite() {
            // Coincident ends: an empty segment that hits nothing.
            return Ray {
                origin: o,
                dir: Vec3::Z,
                t_min: 0.0,
                t_max: 0.0,
            };
        }
        Ray::segment(o, d / len, len * (1.0 - SHADOW_EPSILON))
    }
}

/// pbrt-v4 triangle hit point: `p = b0 p0 + b1 p1 + b2 p2` with error bound
/// γ₇ · Σ|bᵢ pᵢ| (pbrt-v4 eq. 6.31).
pub(crate) fn triangle_point(v: [Vec3; 3], bary: Vec2) -> SurfacePoint {
    let b0 = 1.0 - bary.x - bary.y;
    let (t0, t1, t2) = (v[0] * b0, v[1] * bary.x, v[2] * bary.y);
    let p = t0 + t1 + t2;
    let abs_sum = t0.abs() + t1.abs() + t2.abs();
    let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
    SurfacePoint {
        p,
        p_error: gamma(7) * abs_sum,
        n_geo: n,
    }
}

/// pbrt-v4 sphere hit point: re-project onto the surface, error γ₅·|p − c|
/// (pbrt-v4 eq. 6.32), plus the rounding of adding the centre back.
pub(crate) fn sphere_point(center: Vec3, radius: f32, p_hit: Vec3) -> SurfacePoint {
    let local = p_hit - center;
    let len = local.length();
    let n = if len > 0.0 { local / len } else { Vec3::Z };
    let local = n * radius;
    let p = center + local;
    SurfacePoint {
        p,
        p_error: gamma(5) * local.abs() + gamma(1) * (center.abs() + local.abs()),
        n_geo: n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_moves_to_the_requested_side() {
        let p = Vec3::new(100.0, 3.0, -7.0);
        let n = Vec3::new(0.0, 0.0, 1.0);
        let up = offset_ray_origin(p, n, Vec3::new(0.3, 0.0, 0.5));
        let down = offset_ray_origin(p, n, Vec3::new(0.3, 0.0, -0.5));
        assert!(up.z > p.z && down.z < p.z);
        assert_eq!((up.x, up.y), (p.x, p.y));
        assert!(next_float_up(1.0) > 1.0 && next_float_down(1.0) < 1.0);
        assert!(next_float_up(-0.0) > 0.0);
    }
}
