//! The single-ray queries: closest hit and any hit, each the one traversal
//! loop (`traverse.rs`) with its leaf test over the blocks (`leaf.rs`): a
//! leaf's four- or eight-lane triangle test, the scalar test for spheres and
//! edge fallbacks, and the tie rule ([`nearer`]).

use super::bvh4::BoxRay;
use super::leaf::{nearer, LeafBlock, LeafCode, Leaves};
#[cfg(target_arch = "x86_64")]
use super::primitive;
use super::primitive::{WatertightRay, WatertightRay4};
use super::traverse::{Entry, LeafTest};
use super::tree::Tree;
use super::Hit;
use crate::math::{Ray, Vec2, Vec3};
use std::cell::RefCell;

/// The node test's view of a ray, and the shift `back_off` between its
/// distances and the primitive tests' (node distance = t + back_off).
///
/// Rays with `t_min ≥ 0` are tested as they are. For `t_min < 0` (hits behind
/// the origin are legal) the node ray's origin is moved back by |t_min| plus a
/// margin (2e-4 plus enough ulps of the origin that the shift survives
/// rounding), so that its interval starts at 0, where the slab distances keep
/// their sign.
#[inline(always)]
pub(super) fn node_ray(ray: &Ray) -> (BoxRay, f32) {
    // |d| is clamped to 1e-20 (inverse ±1e20: finite, no NaN from 0·∞), with
    // the sign kept (−0.0 counts as positive, like `d < 0.0` in the node test).
    // Lane-wise selects rather than a branch per component.
    let d = ray.dir;
    let tiny = Vec3::select(
        d.cmplt(Vec3::ZERO),
        Vec3::splat(-1.0e-20),
        Vec3::splat(1.0e-20),
    );
    let dir = Vec3::select(d.abs().cmplt(Vec3::splat(1.0e-20)), tiny, d);
    if ray.t_min >= 0.0 {
        return (BoxRay::new(ray.origin, dir, ray.t_min), 0.0);
    }
    let back_off = 2.0e-4 + ray.origin.abs().max_element() * (1.0 / 262_144.0) - ray.t_min;
    let origin = ray.origin - dir * back_off;
    (BoxRay::new(origin, dir, 0.0), back_off)
}

/// Closest hit; `work` counts (node tests, primitive tests), the latter
/// only with `count_prims` (counting reads each block's ids, a cache line
/// a query without a hit need not load).
#[inline(always)]
pub(super) fn closest(
    tree: &Tree,
    leaves: &Leaves,
    ray: &Ray,
    wr: &WatertightRay,
    stack: &mut [Entry],
    work: &mut (u32, u32),
    count_prims: bool,
) -> Option<Hit> {
    let (node_ray, back_off) = node_ray(ray);
    let wr4 = WatertightRay4::new(wr);
    let (mut best, mut t_max, mut prims_tested) = (None, ray.t_max, 0);
    let leaf = Closest {
        leaves,
        ray,
        wr,
        wr4: &wr4,
        #[cfg(target_arch = "x86_64")]
        eight_lanes: tree.eight_lane_leaves(),
        count_prims,
        back_off,
        best: &mut best,
        t_max: &mut t_max,
        prims_tested: &mut prims_tested,
    };
    tree.traverse::<true>(&node_ray, ray.t_max + back_off, stack, &mut work.0, leaf);
    work.1 += prims_tested;
    best.map(|(id, t, bary, slot)| Hit {
        t,
        prim: leaves.prim_ref_at(id, slot),
        bary,
        slot,
    })
}

/// The closest-hit query's leaf test: the query's set-up, and its state by
/// `&mut` (see [`LeafTest`]).
struct Closest<'a> {
    leaves: &'a Leaves,
    ray: &'a Ray,
    wr: &'a WatertightRay,
    wr4: &'a WatertightRay4,
    #[cfg(target_arch = "x86_64")]
    eight_lanes: bool,
    count_prims: bool,
    back_off: f32,
    /// (input index, t, (b1, b2), slot) of the nearest hit so far.
    best: &'a mut Option<(u32, f32, Vec2, u32)>,
    t_max: &'a mut f32,
    prims_tested: &'a mut u32,
}

impl LeafTest for Closest<'_> {
    #[inline(always)]
    fn test(&mut self, first: usize, code: usize) -> Option<f32> {
        let (leaves, ray, wr) = (self.leaves, self.ray, self.wr);
        let (count, spheres) = LeafCode::decode(code);
        let blocks = &leaves.blocks[first..first + count];
        #[cfg(target_arch = "x86_64")]
        if self.eight_lanes && count == 2 {
            if self.count_prims {
                *self.prims_tested += blocks[0].primitive_count() + blocks[1].primitive_count();
            }
            // SAFETY: eight-lane leaves only in an 8-wide (AVX2) tree.
            let (h, scalar) =
                unsafe { leaves.leaf8::<false>(wr, blocks, spheres, ray.t_min, *self.t_max) };
            leaves.take_lanes(
                ray,
                wr,
                (h.hits | scalar, h.hits),
                (&h.t, &h.b1, &h.b2),
                |lane| blocks[lane >> 2].ids[lane & 3],
                4 * first as u32,
                self.t_max,
                self.best,
            );
            return Some(*self.t_max + self.back_off);
        }
        for (i, block) in blocks.iter().enumerate() {
            if self.count_prims {
                *self.prims_tested += block.primitive_count();
            }
            let h = self
                .wr4
                .intersect::<false>(&block.tris, ray.t_min, *self.t_max);
            let mut lanes = h.hits | h.fallback;
            if spheres {
                lanes |= block.sphere_lanes(leaves.first_sphere);
            }
            if lanes == 0 {
                continue;
            }
            let (ts, b1, b2) = (h.t.to_array(), h.b1.to_array(), h.b2.to_array());
            let id = |lane: usize| block.ids[lane];
            leaves.take_lanes(
                ray,
                wr,
                (lanes, h.hits),
                (&ts, &b1, &b2),
                id,
                4 * (first + i) as u32,
                self.t_max,
                self.best,
            );
        }
        Some(*self.t_max + self.back_off)
    }

    #[inline(always)]
    fn prefetch(&self, first: usize, code: usize) {
        self.leaves.prefetch_leaf(first, code)
    }
}

/// Any hit. The triangle test's set-up ([`WatertightRay`] and its splats)
/// is made when the traversal opens its first leaf: most shadow rays open
/// none (0.46 leaves per ray on cornell; −1 to −3 % render time there). A
/// closest-hit query nearly always opens one, and made lazily there it
/// bought nothing (benches/README.md, levers).
#[inline(always)]
pub(super) fn any(
    tree: &Tree,
    leaves: &Leaves,
    ray: &Ray,
    stack: &mut [Entry],
    nodes: &mut u32,
) -> bool {
    let (node_ray, back_off) = node_ray(ray);
    let (mut leaf_ray, mut hit) = (None, false);
    let leaf = Any {
        leaves,
        ray,
        leaf_ray: &mut leaf_ray,
        #[cfg(target_arch = "x86_64")]
        eight_lanes: tree.eight_lane_leaves(),
        hit: &mut hit,
    };
    tree.traverse::<false>(&node_ray, ray.t_max + back_off, stack, nodes, leaf);
    hit
}

/// The any-hit query's leaf test, as [`Closest`].
struct Any<'a> {
    leaves: &'a Leaves,
    ray: &'a Ray,
    /// The triangle tests' set-up, made at the first leaf.
    leaf_ray: &'a mut Option<(WatertightRay, WatertightRay4)>,
    #[cfg(target_arch = "x86_64")]
    eight_lanes: bool,
    hit: &'a mut bool,
}

impl LeafTest for Any<'_> {
    #[inline(always)]
    fn test(&mut self, first: usize, code: usize) -> Option<f32> {
        let (leaves, ray) = (self.leaves, self.ray);
        let (count, spheres) = LeafCode::decode(code);
        let blocks = &leaves.blocks[first..first + count];
        let (wr, wr4) = &*self.leaf_ray.get_or_insert_with(|| {
            let wr = WatertightRay::new(ray.origin, ray.dir);
            let wr4 = WatertightRay4::new(&wr);
            (wr, wr4)
        });
        #[cfg(target_arch = "x86_64")]
        if self.eight_lanes && count == 2 {
            // SAFETY: eight-lane leaves only in an 8-wide (AVX2) tree.
            let (h, scalar) =
                unsafe { leaves.leaf8::<true>(wr, blocks, spheres, ray.t_min, ray.t_max) };
            *self.hit = h.hits != 0
                || leaves.scalar_hit(ray, wr, scalar, |lane| blocks[lane >> 2].ids[lane & 3]);
            return (!*self.hit).then_some(f32::INFINITY);
        }
        for block in blocks {
            let h = wr4.intersect::<true>(&block.tris, ray.t_min, ray.t_max);
            let mut lanes = h.fallback;
            if spheres {
                lanes |= block.sphere_lanes(leaves.first_sphere);
            }
            *self.hit = h.hits != 0 || leaves.scalar_hit(ray, wr, lanes, |lane| block.ids[lane]);
            if *self.hit {
                return None;
            }
        }
        Some(f32::INFINITY)
    }

    #[inline(always)]
    fn prefetch(&self, first: usize, code: usize) {
        self.leaves.prefetch_leaf(first, code)
    }
}

impl Leaves {
    /// Takes the `lanes` of a leaf test into `best` (`hits`: the lanes the
    /// SIMD test decided, with their `t`, `b1`, `b2`; the rest go to the scalar
    /// test), the lane's primitive being input index `id(lane)` and its
    /// [`Hit::slot`] `slot_base + lane`. A hit at the
    /// same distance as the best so far (a ray through a shared edge) wins by
    /// input order, not by visit order, which depends on the node width: the
    /// same image on every CPU.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn take_lanes(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        (mut lanes, hits): (u32, u32),
        (ts, b1, b2): (&[f32], &[f32], &[f32]),
        id: impl Fn(usize) -> u32,
        slot_base: u32,
        t_max: &mut f32,
        best: &mut Option<(u32, f32, Vec2, u32)>,
    ) {
        while lanes != 0 {
            let lane = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let id = id(lane);
            let found = if hits & (1 << lane) != 0 {
                (ts[lane] <= *t_max).then(|| (ts[lane], Vec2::new(b1[lane], b2[lane])))
            } else {
                self.prim_of_input(id)
                    .intersect(ray, wr, *t_max)
                    .map(|hit| (hit.t, hit.bary))
            };
            if let Some((t, bary)) = found {
                if nearer(t, id, best.map(|(b, bt, ..)| (bt, b))) {
                    *t_max = t;
                    *best = Some((id, t, bary, slot_base + lane as u32));
                }
            }
        }
    }

    /// A leaf of two blocks through the eight-lane test: its result, and the
    /// lanes the scalar test must decide (edge fallbacks and spheres).
    ///
    /// # Safety
    /// As [`primitive::avx::intersect8`]: only from the 8-wide (AVX2) traversal.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn leaf8<const ANY: bool>(
        &self,
        wr: &WatertightRay,
        blocks: &[LeafBlock],
        spheres: bool,
        t_min: f32,
        t_max: f32,
    ) -> (primitive::avx::Hits8, u32) {
        let h =
            primitive::avx::intersect8::<ANY>(wr, &blocks[0].tris, &blocks[1].tris, t_min, t_max);
        let mut scalar = h.fallback;
        if spheres {
            scalar |= blocks[0].sphere_lanes(self.first_sphere)
                | blocks[1].sphere_lanes(self.first_sphere) << 4;
        }
        (h, scalar)
    }

    /// Whether one of the `lanes` left to the scalar test (primitive: input
    /// index `id(lane)`) is hit.
    #[inline(always)]
    fn scalar_hit(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        mut lanes: u32,
        id: impl Fn(usize) -> u32,
    ) -> bool {
        while lanes != 0 {
            let id = id(lanes.trailing_zeros() as usize);
            lanes &= lanes - 1;
            if self
                .prim_of_input(id)
                .intersect(ray, wr, ray.t_max)
                .is_some()
            {
                return true;
            }
        }
        false
    }
}

thread_local! {
    /// Each thread's traversal stack, grown to the deepest tree it has
    /// traversed: no per-query allocation or zeroing (a 64-entry array on the
    /// call stack cost a 512-byte memset per query, ~5% of a query's instructions).
    static STACK: RefCell<Vec<Entry>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` on this thread's traversal stack with at least `size` entries.
#[inline(always)]
pub(super) fn with_stack<R>(size: usize, f: impl FnOnce(&mut [Entry]) -> R) -> R {
    STACK.with_borrow_mut(|stack| {
        if stack.len() < size {
            stack.resize(size, Entry::default());
        }
        f(stack)
    })
}
