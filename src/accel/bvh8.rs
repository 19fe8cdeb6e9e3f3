//! The 8-wide tree for CPUs with AVX2 (chosen at run time, see
//! `BuildPreset::node_width`): the same collapse as the BVH4 (`bvh4.rs`) with eight
//! slots, the same conservative slab test on eight children at once with
//! 256-bit `std::arch` intrinsics. Half the levels of the BVH4, so an
//! incoherent ray waits on fewer dependent node loads.

use super::bvh4::{decode_leaf, BoxRay, Bvh, Entry, WideNode, EMPTY, LEAF_BIT, WIDEN};

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

#[cfg(target_arch = "x86_64")]
impl Bvh8 {
    /// [`super::bvh4::Bvh4::traverse`] on eight children per node.
    ///
    /// # Safety
    /// The CPU must support AVX2 ([`supported`]).
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn traverse<const SORTED: bool>(
        &self,
        ray: &BoxRay,
        t_hi: f32,
        stack: &mut [Entry],
        nodes_visited: &mut u32,
        mut leaf: impl FnMut(usize, usize) -> Option<f32>,
        leaf_prefetch: impl Fn(usize, usize),
    ) {
        use std::arch::x86_64::*;
        let prefetch = |c: u32| self.prefetch_child(c, &leaf_prefetch);
        let (org, inv) = (ray.org_scalar(), ray.inv_scalar());
        let org = org.map(|o| _mm256_set1_ps(o));
        let inv = inv.map(|i| _mm256_set1_ps(i));
        let inv_far = ray.inv_far_scalar().map(|i| _mm256_set1_ps(i));
        let near = ray.near;
        let (nx, ny, nz) = (near[0] & 1, 2 + (near[1] & 1), 4 + (near[2] & 1));
        let t_lo = _mm256_set1_ps(ray.t_lo_scalar());
        let mut hi = t_hi * WIDEN;
        let mut hi_w = _mm256_set1_ps(hi);
        let mut sp = 0usize;
        let mut cur = self.root;
        loop {
            while cur & LEAF_BIT == 0 {
                *nodes_visited += 1;
                let node = &self.nodes[cur as usize];
                let (mask, t_near) = node.slab_test(&org, &inv, &inv_far, [nx, ny, nz], t_lo, hi_w);
                if mask == 0 {
                    cur = EMPTY;
                    break;
                }
                // From here the step is the BVH4's, written out again: one shared
                // `#[inline(always)]` helper for both widths cost 1–3.5 % more
                // instructions per ray (callgrind, `GRADTRACE_ACCEL_ONCE`).
                if mask & (mask - 1) == 0 {
                    cur = node.children[mask.trailing_zeros() as usize];
                    continue;
                }
                let mut t_near_arr = [0f32; 8];
                _mm256_storeu_ps(t_near_arr.as_mut_ptr(), t_near);
                let t_near = t_near_arr;
                let rest = mask & (mask - 1);
                if rest & (rest - 1) == 0 {
                    let (i, j) = (
                        mask.trailing_zeros() as usize,
                        rest.trailing_zeros() as usize,
                    );
                    let (near, far) = if !SORTED || t_near[i] <= t_near[j] {
                        (i, j)
                    } else {
                        (j, i)
                    };
                    stack[sp] = Entry::new(node.children[far], t_near[far]);
                    sp += 1;
                    prefetch(node.children[far]);
                    cur = node.children[near];
                    continue;
                }
                let (mut ids, mut ts, mut k) = ([0u32; 8], [0f32; 8], 0usize);
                let mut m = mask;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    ids[k] = node.children[i];
                    ts[k] = t_near[i];
                    k += 1;
                    m &= m - 1;
                }
                if SORTED {
                    // Insertion sort, farthest first, stable.
                    for i in 1..k {
                        let (t, id) = (ts[i], ids[i]);
                        let mut j = i;
                        while j > 0 && ts[j - 1] < t {
                            ts[j] = ts[j - 1];
                            ids[j] = ids[j - 1];
                            j -= 1;
                        }
                        ts[j] = t;
                        ids[j] = id;
                    }
                }
                for i in 0..k - 1 {
                    stack[sp] = Entry::new(ids[i], ts[i]);
                    sp += 1;
                    prefetch(ids[i]);
                }
                cur = ids[k - 1];
            }
            if cur != EMPTY {
                let (first, count) = decode_leaf(cur);
                match leaf(first, count) {
                    None => return,
                    Some(t) => {
                        hi = hi.min(t * WIDEN);
                        hi_w = _mm256_set1_ps(hi);
                    }
                }
            }
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                let e = stack[sp];
                if e.t <= hi {
                    cur = e.node;
                    break;
                }
            }
        }
    }
}

/// One ray's view for [`Bvh8::child_mask`]: what [`Bvh8::traverse`] splats
/// from its [`BoxRay`], and its fixed upper bound (made by the ray streams'
/// set-up, `accel::stream`, with [`BoxRay::new`]'s operations).
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
