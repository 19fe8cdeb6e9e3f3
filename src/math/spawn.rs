//! The ray-spawning rule (pbrt-v4 §6.8.6, "Robust Spawned Ray Origins"),
//! written once over [`Vector3`]: `accel::offset_ray_origin_with_error` runs
//! it on one vector, the lane kernel on eight.

use super::lanes::{Lanes, Vector3};

/// pbrt-v4's `OffsetRayOrigin`: `d = dot(|n|, p_error)`, `p` moved by `d·n`
/// towards the side of `dir`, then every moved component at least one ulp
/// further away, so that the rounding of `p + offset` cannot pull the origin
/// back onto the surface. pbrt steps exactly one ulp with `NextFloatUp`/`Down`;
/// here the step is |x|·2⁻²³ (one to two ulps, at least the smallest normal
/// float), which needs no branch per component.
#[inline(always)]
pub fn offset_ray_origin<V: Vector3>(p: V, p_error: V, n: V, dir: V) -> V {
    let zero = V::L::splat(0.0);
    let one = V::L::splat(1.0);
    let d = n
        .map(
            #[inline(always)]
            |c| c.abs(),
        )
        .dot(p_error);
    let flip = dir.dot(n).lt(zero);
    p.zip(
        n,
        #[inline(always)]
        |p, n| {
            let offset = n * d;
            let offset = flip.select(-offset, offset);
            let po = p + offset;
            // The offset's direction: 0 where it is 0, else its sign.
            let away = offset
                .eq(zero)
                .select(zero, offset.is_sign_negative().select(-one, one));
            po + away * (po.abs() * V::L::splat(f32::EPSILON)).max(V::L::splat(f32::MIN_POSITIVE))
        },
    )
}
