//! The 8-wide tree for CPUs with AVX2 (chosen at run time, see
//! `BuildPreset::node_width`): the same collapse as the BVH4 (`bvh4.rs`) with eight
//! slots, the same conservative slab test on eight children at once with
//! 256-bit `std::arch` intrinsics. Half the levels of the BVH4, so an
//! incoherent ray waits on fewer dependent node loads.

#[cfg(target_arch = "x86_64")]
use super::bvh4::BoxRay;
#[cfg(target_arch = "x86_64")]
use super::traverse::NodeTest;
use super::tree::{Bvh, WideNode, EMPTY};

/// Eight child boxes: `bounds[2·axis]` the minima, `bounds[2·axis + 1]` the
/// maxima along `axis`; empty slots hold the inverted box (+∞, −∞).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(super) struct Node8 {
    bounds: [[f32; 8]; 6],
    children: [u32; 8],
}

impl WideNode for Node8 {
    const WIDTH: usize = 8;

    fn empty() -> Self {
        let (inf, ninf) = ([f32::INFINITY; 8], [f32::NEG_INFINITY; 8]);
        Self {
            bounds: [inf, ninf, inf, ninf, inf, ninf],
            children: [EMPTY; 8],
        }
    }

    fn set_child(&mut self, slot: usize, lo: [f32; 3], hi: [f32; 3]) {
        for axis in 0..3 {
            self.bounds[2 * axis][slot] = lo[axis];
            self.bounds[2 * axis + 1][slot] = hi[axis];
        }
    }

    fn child_box(&self, slot: usize) -> ([f32; 3], [f32; 3]) {
        let c = |i: usize| self.bounds[i][slot];
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

#[cfg(target_arch = "x86_64")]
impl Node8 {
    /// The conservative slab test of the eight children against one ray
    /// splatted (`near`: each axis's near-plane row, 0/1, 2/3, 4/5): the
    /// children entered within [`t_lo`, `hi`], and their entry distances.
    /// The one copy of the test, for [`Bvh8::traverse`] and the ray
    /// streams' [`Bvh8::child_mask`], whose answers must be the same bits.
    ///
    /// # Safety
    /// AVX2; the caller must be an AVX2 function (this inlines into it).
    #[inline(always)]
    unsafe fn slab_test(
        &self,
        org: &[std::arch::x86_64::__m256; 3],
        inv: &[std::arch::x86_64::__m256; 3],
        inv_far: &[std::arch::x86_64::__m256; 3],
        [nx, ny, nz]: [usize; 3],
        t_lo: std::arch::x86_64::__m256,
        hi: std::arch::x86_64::__m256,
    ) -> (u32, std::arch::x86_64::__m256) {
        use std::arch::x86_64::*;
        let b = &self.bounds;
        // SAFETY: `Node8` is 32-byte aligned and each bounds row is 32 bytes
        // at a multiple of 32.
        let slab = |i: usize, a: usize, inv: &[__m256; 3]| {
            _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(b[i].as_ptr()), org[a]), inv[a])
        };
        let (tnx, tny, tnz) = (slab(nx, 0, inv), slab(ny, 1, inv), slab(nz, 2, inv));
        let (tfx, tfy, tfz) = (
            slab(nx ^ 1, 0, inv_far),
            slab(ny ^ 1, 1, inv_far),
            slab(nz ^ 1, 2, inv_far),
        );
        // Same operand order as the BVH4's `fast_max`/`fast_min`.
        let t_near = _mm256_max_ps(_mm256_max_ps(tnx, tny), _mm256_max_ps(tnz, t_lo));
        let t_far = _mm256_min_ps(_mm256_min_ps(_mm256_min_ps(tfx, tfy), tfz), hi);
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far)) as u32;
        (mask, t_near)
    }
}

/// The 8-wide tree.
pub(super) type Bvh8 = Bvh<Node8>;

/// Whether this CPU runs the 8-wide traversal.
pub(super) fn supported() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// The ray as the 8-wide node test reads it: the [`BoxRay`]'s origin,
/// reciprocals and lower end splatted into AVX registers once per query,
/// and each axis's near-plane row.
#[cfg(target_arch = "x86_64")]
pub(super) struct Ray8 {
    org: [std::arch::x86_64::__m256; 3],
    inv: [std::arch::x86_64::__m256; 3],
    inv_far: [std::arch::x86_64::__m256; 3],
    near: [usize; 3],
    t_lo: std::arch::x86_64::__m256,
}

#[cfg(target_arch = "x86_64")]
impl Ray8 {
    /// # Safety
    /// AVX2; the caller must be an AVX2 function (this inlines into it).
    #[inline(always)]
    pub(super) unsafe fn new(ray: &BoxRay) -> Self {
        use std::arch::x86_64::*;
        let (org, inv) = (ray.org_scalar(), ray.inv_scalar());
        let near = ray.near;
        Self {
            org: org.map(|o| _mm256_set1_ps(o)),
            inv: inv.map(|i| _mm256_set1_ps(i)),
            inv_far: ray.inv_far_scalar().map(|i| _mm256_set1_ps(i)),
            near: [near[0] & 1, 2 + (near[1] & 1), 4 + (near[2] & 1)],
            t_lo: _mm256_set1_ps(ray.t_lo_scalar()),
        }
    }
}

/// Safety of each method: AVX2, the caller an AVX2 function.
#[cfg(target_arch = "x86_64")]
impl NodeTest for Node8 {
    type Ray = Ray8;
    type Hi = std::arch::x86_64::__m256;
    type Near = std::arch::x86_64::__m256;
    type Ids = [u32; 8];
    type Ts = [f32; 8];

    #[inline(always)]
    unsafe fn splat(hi: f32) -> Self::Hi {
        std::arch::x86_64::_mm256_set1_ps(hi)
    }

    #[inline(always)]
    unsafe fn test(&self, ray: &Ray8, hi: Self::Hi) -> (u32, Self::Near) {
        self.slab_test(&ray.org, &ray.inv, &ray.inv_far, ray.near, ray.t_lo, hi)
    }

    #[inline(always)]
    unsafe fn spill(near: Self::Near) -> [f32; 8] {
        let mut t = [0f32; 8];
        std::arch::x86_64::_mm256_storeu_ps(t.as_mut_ptr(), near);
        t
    }
}

/// One ray's view for [`Bvh8::child_mask`]: what [`Bvh8::traverse`] splats
/// from its `BoxRay`, and its fixed upper bound (made by the ray streams'
/// set-up, `accel::stream`, with `BoxRay::new`'s operations).
pub(super) struct NodeRay {
    pub(super) org: [f32; 3],
    pub(super) inv: [f32; 3],
    pub(super) inv_far: [f32; 3],
    /// Index of the near plane's row per axis (0 or 1, offset by 2·axis).
    pub(super) near: [u32; 3],
    pub(super) t_lo: f32,
    pub(super) hi: f32,
}

#[cfg(target_arch = "x86_64")]
impl Bvh8 {
    /// The children of inner node `node` that `ray` enters: [`Bvh8::traverse`]'s
    /// slab test, with the same operations and the interval's first upper end
    /// (a closest hit found since would only have narrowed it). For the ray
    /// streams (`accel::stream`), which test a node once per ray of a batch.
    ///
    /// # Safety
    /// AVX2, as [`Bvh8::traverse`]; the caller must be an AVX2 function.
    #[inline(always)]
    pub(super) unsafe fn child_mask(&self, node: u32, ray: &NodeRay) -> u32 {
        use std::arch::x86_64::*;
        let splat = |v: [f32; 3]| {
            [
                _mm256_set1_ps(v[0]),
                _mm256_set1_ps(v[1]),
                _mm256_set1_ps(v[2]),
            ]
        };
        let near = [
            ray.near[0] as usize,
            ray.near[1] as usize,
            ray.near[2] as usize,
        ];
        self.nodes[node as usize]
            .slab_test(
                &splat(ray.org),
                &splat(ray.inv),
                &splat(ray.inv_far),
                near,
                _mm256_set1_ps(ray.t_lo),
                _mm256_set1_ps(ray.hi),
            )
            .0
    }

    /// The eight child references of inner node `node`.
    pub(super) fn children_of(&self, node: u32) -> &[u32; 8] {
        &self.nodes[node as usize].children
    }
}
