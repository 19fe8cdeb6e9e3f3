//! Robust spawning of secondary and shadow rays (pbrt-v4, §6.8.6 "Robust Spawned
//! Ray Origins", Pharr, Jakob & Humphreys).
//!
//! This is the renderer's one ray-offset mechanism: the path tracer's
//! `Interaction` carries the same point and bound, the previews spawn from
//! [`SurfacePoint`]s, and code that has no bound uses [`offset_ray_origin`]'s
//! conservative default. It relies on the triangle test rejecting hits with
//! t ≤ δt (its own rounding bound, `primitive.rs`), as pbrt-v4's does.
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

use crate::math::lanes::{Lanes, Vector3};
use crate::math::{cross, Ray, Vec2, Vec3};

use super::primitive::gamma;

/// Relative error assumed by [`offset_ray_origin`] when the caller has no error
/// bound: 2^-18 ≈ 64 ulps of the largest coordinate — covers a point interpolated
/// from vertices (pbrt's γ₇) or computed as `ray.at(t)` from an origin of similar
/// magnitude, with a wide margin.
pub(crate) const DEFAULT_REL_ERROR: f32 = 1.0 / 262_144.0;

/// Offsets `p` along the geometric normal `n_geo` to the side `dir` points to, far
/// enough that a ray from the result cannot re-hit the surface `p` lies on.
///
/// Uses a default error bound of 2^-18 · max|pᵢ| (plus a tiny absolute floor);
/// prefer [`SurfacePoint::spawn_ray`] when a [`SurfacePoint`] is available, which
/// carries an exact bound. `n_geo` need not face `dir`, nor be normalised.
pub fn offset_ray_origin(p: Vec3, n_geo: Vec3, dir: Vec3) -> Vec3 {
    offset_ray_origin_with_error(p, default_error(p), n_geo, dir)
}

/// [`DEFAULT_REL_ERROR`] of the largest coordinate, on every axis.
fn default_error(p: Vec3) -> Vec3 {
    default_error_of(p)
}

/// [`default_error`] on one vector or on the lane kernel's eight (its light
/// points): the largest |coordinate| in glam's `max_element` order,
/// (x max z) max (y max z), so that a NaN coordinate gives the bits it gave
/// (SSE's `max` returns its second operand where either is NaN).
#[inline(always)]
pub(crate) fn default_error_of<V: Vector3>(p: V) -> V {
    let [x, y, z] = p.abs_each().components();
    let e = x.max(z).max(y.max(z)) * V::L::splat(DEFAULT_REL_ERROR) + V::L::splat(1.0e-30);
    p.map(
        #[inline(always)]
        |_| e,
    )
}

/// pbrt-v4's `OffsetRayOrigin` ([`crate::math::spawn::offset_ray_origin`],
/// the lane kernel's rule) on one vector, in three-wide instructions: this
/// runs for every ray the path tracer spawns.
#[inline]
pub fn offset_ray_origin_with_error(p: Vec3, p_error: Vec3, n_geo: Vec3, dir: Vec3) -> Vec3 {
    crate::math::spawn::offset_ray_origin(p, p_error, n_geo, dir)
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
pub(crate) const SHADOW_EPSILON: f32 = 1.0e-4;

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

    /// A point with no error bound of its own (a light sample, say): the default
    /// relative bound of [`offset_ray_origin`].
    pub fn with_default_error(p: Vec3, n_geo: Vec3) -> Self {
        Self {
            p,
            p_error: default_error(p),
            n_geo,
        }
    }

    /// [`Self::spawn_ray`] for a direction that is already unit length.
    /// Inlined: the path tracer spawns every bounce's ray through it.
    #[inline]
    pub fn spawn_ray_unit(&self, dir: Vec3) -> Ray {
        Ray::new(
            offset_ray_origin_with_error(self.p, self.p_error, self.n_geo, dir),
            dir,
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
        let (dir, t_max, empty) = segment_to(o, end);
        if empty.bitmask() & 1 != 0 {
            // Coincident ends: an empty segment that hits nothing.
            return Ray {
                origin: o,
                dir: Vec3::Z,
                t_min: 0.0,
                t_max: 0.0,
            };
        }
        Ray::segment(o, dir, t_max.to_array()[0])
    }
}

/// The shadow segment from `o` to `end` ([`SurfacePoint::segment`] and the
/// lane kernel's): its unit direction, its length less [`SHADOW_EPSILON`],
/// and a mask where it is empty (a length not positive, NaN or infinite).
/// Each caller makes its empty segment itself: a branch on one ray, a
/// select on eight.
#[inline(always)]
pub(crate) fn segment_to<V: Vector3>(o: V, end: V) -> (V, V::L, V::L) {
    let zero = V::L::splat(0.0);
    let d = end.diff(o);
    let len = d.dot(d).sqrt();
    let empty = len.gt(zero).select(len.is_inf(), zero.eq(zero));
    (
        d.map(
            #[inline(always)]
            |c| c / len,
        ),
        len * V::L::splat(1.0 - SHADOW_EPSILON),
        empty,
    )
}

/// pbrt-v4 triangle hit point: `p = b0 p0 + b1 p1 + b2 p2` with error bound
/// γ₇ · Σ|bᵢ pᵢ| (pbrt-v4 eq. 6.31).
pub fn triangle_point(v: [Vec3; 3], bary: Vec2) -> SurfacePoint {
    triangle_point_with_normal(v, bary, triangle_normal(v))
}

/// The unit geometric normal of a triangle (counter-clockwise winding), zero
/// for a degenerate one: the one formula for it, so that a normal computed at
/// build time ([`super::Accel::hit_triangle`]) has the bits of one computed per hit.
#[inline]
pub fn triangle_normal(v: [Vec3; 3]) -> Vec3 {
    cross(v[1] - v[0], v[2] - v[0]).normalize_or_zero()
}

/// [`triangle_point`] with the triangle's [`triangle_normal`] already known.
#[inline]
pub fn triangle_point_with_normal(v: [Vec3; 3], bary: Vec2, n: Vec3) -> SurfacePoint {
    let (p, p_error) =
        triangle_point_error(v, wide::f32x4::splat(bary.x), wide::f32x4::splat(bary.y));
    SurfacePoint {
        p,
        p_error,
        n_geo: n,
    }
}

/// The point and bound of [`triangle_point_with_normal`] on one hit or on
/// the lane kernel's eight, from the barycentrics b1, b2 of vertices 1, 2.
#[inline(always)]
pub(crate) fn triangle_point_error<V: Vector3>(v: [V; 3], b1: V::L, b2: V::L) -> (V, V) {
    let b0 = V::L::splat(1.0) - b1 - b2;
    let (t0, t1, t2) = (v[0].scale(b0), v[1].scale(b1), v[2].scale(b2));
    let p = t0.sum(t1).sum(t2);
    let abs_sum = t0.abs_each().sum(t1.abs_each()).sum(t2.abs_each());
    (p, abs_sum.scale(V::L::splat(gamma(7))))
}

/// pbrt-v4 sphere hit point: re-project onto the surface, error γ₅·|p − c|
/// (pbrt-v4 eq. 6.32), plus the rounding of adding the centre back.
///
/// The bound is widened by γ₈·|p − c| for the sphere test itself: pbrt's test
/// carries interval bounds on t, ours (`primitive::sphere_roots`) decides the
/// side of the surface by the sign of |f| − r, where |f| = |o − c| has a
/// relative error of up to γ₆ (a subtraction, three products, two sums, a
/// square root). An origin offset by this bound is therefore seen on its own
/// side, and a ray leaving the surface cannot re-hit it.
pub fn sphere_point(center: Vec3, radius: f32, p_hit: Vec3) -> SurfacePoint {
    let local = p_hit - center;
    let len = local.length();
    let n = if len > 0.0 { local / len } else { Vec3::Z };
    let local = n * radius;
    let p = center + local;
    SurfacePoint {
        p,
        p_error: (gamma(5) + gamma(8)) * local.abs() + gamma(1) * (center.abs() + local.abs()),
        n_geo: n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::lanes::{Lanes8, V3};

    /// Edge points: zeros of both signs, NaN, ∞, tiny, huge, mixed.
    fn edge_points() -> Vec<Vec3> {
        let (n, i) = (f32::NAN, f32::INFINITY);
        vec![
            Vec3::new(0.0, -0.0, 0.0),
            Vec3::new(1.0, -3.0, 2.0),
            Vec3::new(n, 1.0, 2.0),
            Vec3::new(1.0, n, -5.0),
            // (x max y) max z would give 1 here, glam gives 7.
            Vec3::new(7.0, n, 1.0),
            Vec3::new(7.0, 1.0, n),
            Vec3::new(-i, 1.0, 1.0),
            Vec3::new(1e-40, -1e-38, 3e-39),
            Vec3::new(3e38, -2e38, 1e30),
            Vec3::new(-100.0, 250.5, -0.001),
        ]
    }

    fn same(a: Vec3, b: Vec3) -> bool {
        (0..3).all(|c| a[c].to_bits() == b[c].to_bits())
    }

    /// The three folded rules give each lane of eight the one-vector bits
    /// (NaN coordinates included: the lanes read glam's `max_element` order).
    #[test]
    fn folded_rules_give_the_lanes_the_scalar_bits() {
        let pts = edge_points();
        for k in 0..pts.len() {
            let rows: [Vec3; 8] = std::array::from_fn(|l| pts[(k + l) % pts.len()]);
            let ends: [Vec3; 8] = std::array::from_fn(|l| pts[(k + 3 * l + 1) % pts.len()]);
            let lanes = V3::<wide::f32x8>::load(&rows);
            let err = default_error_of(lanes).store();
            let (dir, t, empty) = segment_to(lanes, V3::load(&ends));
            let (dir, t, empty) = (dir.store(), t.store(), empty.bitmask());
            let b: [f32; 8] = std::array::from_fn(|l| 0.1 * l as f32);
            let (tp, te) = triangle_point_error(
                [lanes, V3::load(&ends), lanes],
                wide::f32x8::load(b),
                wide::f32x8::load(b.map(|x| 0.5 - x)),
            );
            let (tp, te) = (tp.store(), te.store());
            for l in 0..8 {
                let old = Vec3::splat(rows[l].abs().max_element() * DEFAULT_REL_ERROR + 1.0e-30);
                assert!(same(err[l], old), "{} {} {}", rows[l], err[l], old);
                let ray = SurfacePoint::segment(rows[l], ends[l]);
                assert_eq!(empty >> l & 1 == 1, ray.t_max == 0.0 && ray.dir == Vec3::Z);
                if empty >> l & 1 == 0 {
                    assert!(same(dir[l], ray.dir) && t[l].to_bits() == ray.t_max.to_bits());
                }
                let sp = triangle_point_with_normal(
                    [rows[l], ends[l], rows[l]],
                    Vec2::new(b[l], 0.5 - b[l]),
                    Vec3::Z,
                );
                assert!(same(tp[l], sp.p) && same(te[l], sp.p_error));
            }
        }
    }

    #[test]
    fn offset_moves_to_the_requested_side() {
        let p = Vec3::new(100.0, 3.0, -7.0);
        let n = Vec3::new(0.0, 0.0, 1.0);
        let up = offset_ray_origin(p, n, Vec3::new(0.3, 0.0, 0.5));
        let down = offset_ray_origin(p, n, Vec3::new(0.3, 0.0, -0.5));
        assert!(up.z > p.z && down.z < p.z);
        assert_eq!((up.x, up.y), (p.x, p.y));
        // At least one ulp beyond p + offset, also from zero.
        let e = Vec3::splat(1.0e-30);
        let z = offset_ray_origin_with_error(Vec3::new(0.0, 0.0, -0.0), e, n, -n);
        assert!(z.z < 0.0 && z.x == 0.0, "{z}");
        let q = offset_ray_origin_with_error(Vec3::new(1.0, -1.0, 1.0), e, n, n);
        assert!(q.z > 1.0 && q.x == 1.0 && q.y == -1.0, "{q}");
    }
}
