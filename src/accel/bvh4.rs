//! The 4-wide node: uncompressed f32 child boxes in SoA layout, tested four
//! at a time with `wide::f32x4` slab tests (the tree where the CPU has no
//! AVX2; its loop is `traverse.rs`'s, shared with the 8-wide node).
//!
//! Why not obvhs' CWBVH (issue 16): its 8-wide nodes are quantised (u8 child
//! boxes decoded on every visit), visited in octant order rather than by
//! distance, and its entry distance is clamped to a fixed 1e-4, which forced a
//! backed-off traversal ray. Here a node test is 6 subtractions, 6
//! multiplications and 8 min/max on four children at once, and the box test is
//! Ize's conservative one (2013, "Robust BVH Ray Traversal": exit distances
//! widened by `1 + 2γ₃`, here generously `1 + 4ε`), on boxes padded by the
//! build (`build.rs`), so no box a ray touches at an edge or vertex is culled.

use super::traverse::NodeTest;
use super::tree::{Bvh, WideNode, EMPTY, WIDEN_INV};
use crate::math::Vec3;
use wide::f32x4;

/// Four child boxes: `bounds[2·axis]` the minima, `bounds[2·axis + 1]` the
/// maxima along `axis`. Empty slots hold the inverted box (+∞, −∞), which the
/// ordered slab test always misses.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(super) struct Node4 {
    bounds: [f32x4; 6],
    children: [u32; 4],
}

impl WideNode for Node4 {
    const WIDTH: usize = 4;

    fn empty() -> Self {
        let (inf, ninf) = (f32x4::splat(f32::INFINITY), f32x4::splat(f32::NEG_INFINITY));
        Self {
            bounds: [inf, ninf, inf, ninf, inf, ninf],
            children: [EMPTY; 4],
        }
    }

    fn set_child(&mut self, slot: usize, lo: [f32; 3], hi: [f32; 3]) {
        for axis in 0..3 {
            let mut min = self.bounds[2 * axis].to_array();
            let mut max = self.bounds[2 * axis + 1].to_array();
            min[slot] = lo[axis];
            max[slot] = hi[axis];
            self.bounds[2 * axis] = f32x4::new(min);
            self.bounds[2 * axis + 1] = f32x4::new(max);
        }
    }

    fn child_box(&self, slot: usize) -> ([f32; 3], [f32; 3]) {
        let c = |i: usize| self.bounds[i].to_array()[slot];
        ([c(0), c(2), c(4)], [c(1), c(3), c(5)])
    }

    #[inline(always)]
    fn children(&self) -> &[u32] {
        &self.children
    }

    fn children_mut(&mut self) -> &mut [u32] {
        &mut self.children
    }
}

impl Node4 {
    /// Entry distances of the four children and the mask of those whose box
    /// overlaps `[t_lo, hi_w]` along the ray (`hi_w` already widened).
    #[inline(always)]
    fn hit(&self, r: &BoxRay, hi_w: f32x4) -> (f32x4, u32) {
        let b = &self.bounds;
        // near[a] & 1 is the ray's sign bit on axis a: the slab's entry plane is
        // the minimum for a positive direction, the maximum for a negative one.
        let (nx, ny, nz) = (r.near[0] & 1, 2 + (r.near[1] & 1), 4 + (r.near[2] & 1));
        let tnx = (b[nx] - r.org[0]) * r.inv[0];
        let tny = (b[ny] - r.org[1]) * r.inv[1];
        let tnz = (b[nz] - r.org[2]) * r.inv[2];
        let tfx = (b[nx ^ 1] - r.org[0]) * r.inv_far[0];
        let tfy = (b[ny ^ 1] - r.org[1]) * r.inv_far[1];
        let tfz = (b[nz ^ 1] - r.org[2]) * r.inv_far[2];
        let t_near = tnx.fast_max(tny).fast_max(tnz.fast_max(r.t_lo));
        let t_far = tfx.fast_min(tfy).fast_min(tfz).fast_min(hi_w);
        (t_near, t_near.simd_le(t_far).to_bitmask())
    }
}

/// The ray as the node test sees it: origin and reciprocal direction splatted,
/// the sign of each direction component, and the lower end of the interval.
pub(super) struct BoxRay {
    org: [f32x4; 3],
    inv: [f32x4; 3],
    /// `inv` widened by [`WIDEN_INV`], for the exit distances.
    inv_far: [f32x4; 3],
    pub(super) near: [usize; 3],
    t_lo: f32x4,
}

impl BoxRay {
    /// `dir` components must be nonzero (the caller clamps them away from 0, so
    /// that the reciprocal is finite and `0 · ∞` cannot occur); `t_lo ≥ 0`.
    #[inline(always)]
    pub(super) fn new(org: Vec3, dir: Vec3, t_lo: f32) -> Self {
        // One packed division for the three reciprocals; the splats lane by
        // lane from the registers (through `to_array` they were 16-byte loads
        // across separate stores: a store-forwarding stall per query).
        let inv = Vec3::ONE / dir;
        let splat = |v: Vec3| [f32x4::splat(v.x), f32x4::splat(v.y), f32x4::splat(v.z)];
        Self {
            org: splat(org),
            inv: splat(inv),
            inv_far: splat(inv * WIDEN_INV),
            near: [dir.x, dir.y, dir.z].map(|d| (d < 0.0) as usize),
            t_lo: f32x4::splat(t_lo),
        }
    }

    pub(super) fn org_scalar(&self) -> [f32; 3] {
        self.org.map(|o| o.as_array()[0])
    }

    pub(super) fn inv_scalar(&self) -> [f32; 3] {
        self.inv.map(|i| i.as_array()[0])
    }

    pub(super) fn inv_far_scalar(&self) -> [f32; 3] {
        self.inv_far.map(|i| i.as_array()[0])
    }

    pub(super) fn t_lo_scalar(&self) -> f32 {
        self.t_lo.as_array()[0]
    }
}

/// The 4-wide tree.
pub(super) type Bvh4 = Bvh<Node4>;

impl NodeTest for Node4 {
    type Ray = BoxRay;
    type Hi = f32x4;
    type Near = f32x4;
    type Ids = [u32; 4];
    type Ts = [f32; 4];

    #[inline(always)]
    unsafe fn splat(hi: f32) -> f32x4 {
        f32x4::splat(hi)
    }

    #[inline(always)]
    unsafe fn test(&self, ray: &BoxRay, hi: f32x4) -> (u32, f32x4) {
        let (t_near, mask) = self.hit(ray, hi);
        (mask, t_near)
    }

    #[inline(always)]
    unsafe fn spill(near: f32x4) -> [f32; 4] {
        near.to_array()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The node test keeps every box the ray touches, judged in f64 (where the
    /// differences of f32 inputs are exact and a quotient is 2⁻⁵³-close): rays
    /// aimed at points on a box's edges and corners, where the exact interval
    /// shrinks to a point and an unpadded f32 test drops some (523 of the
    /// 6,946 that touch here, with `WIDEN_INV = 1`), from origins near and far
    /// (up to 10⁴ away), along all octants.
    #[test]
    fn the_node_test_keeps_every_box_the_ray_touches() {
        let mut seed = 7u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / 16_777_216.0
        };
        let (mut touching, mut kept) = (0, 0);
        for i in 0..10_000 {
            let lo = Vec3::new(next(), next(), next()) * 2.0 - 1.0;
            let hi = lo + Vec3::new(next(), next(), next()) * 0.5 + 1e-3;
            // A point on an edge (i odd) or a corner (i even) of the box.
            let pick = |a: f32, b: f32, u: f32, free: bool| {
                if free {
                    a + (b - a) * u
                } else if u < 0.5 {
                    a
                } else {
                    b
                }
            };
            let free_axis = if i % 2 == 1 { i / 2 % 3 } else { 3 };
            let target = Vec3::new(
                pick(lo.x, hi.x, next(), free_axis == 0),
                pick(lo.y, hi.y, next(), free_axis == 1),
                pick(lo.z, hi.z, next(), free_axis == 2),
            );
            let distance = [2.0, 50.0, 1e4][i % 3];
            let away = Vec3::new(next(), next(), next()) * 2.0 - 1.0;
            let org = target + away.normalize_or(Vec3::X) * distance;
            let dir = target - org;
            if dir.abs().min_element() < 1e-20 {
                continue;
            }
            let exact = (0..3).fold((0.0f64, f64::INFINITY), |(near, far), a| {
                let (o, d) = (org[a] as f64, dir[a] as f64);
                let (t0, t1) = ((lo[a] as f64 - o) / d, (hi[a] as f64 - o) / d);
                (near.max(t0.min(t1)), far.min(t0.max(t1)))
            });
            if exact.0 > exact.1 {
                continue;
            }
            touching += 1;
            let mut node = Node4::empty();
            node.set_child(2, lo.to_array(), hi.to_array());
            let ray = BoxRay::new(org, dir, 0.0);
            let (_, mask) = node.hit(&ray, f32x4::splat(f32::INFINITY));
            if mask & 0b100 != 0 {
                kept += 1;
            }
        }
        assert!(touching > 6_500, "{touching} rays touch their box");
        assert_eq!(
            kept, touching,
            "the node test dropped boxes the ray touches"
        );
    }
}
