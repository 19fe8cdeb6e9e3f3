//! Ray streams for small trees: a batch of rays traced together, node by
//! node, each leaf's triangles tested against eight rays at a time.
//!
//! Why: on a scene of a few dozen triangles (the Cornell box: three nodes,
//! leaves of one face) a single-ray query is its fixed costs — the set-up, a
//! root test, one leaf of two triangles in a four- or eight-lane test, the
//! stack — about 750 instructions per closest hit (benches/README.md, levers).
//! A stream pays a node test per ray and node, and tests each leaf triangle
//! against eight rays in the lanes (`primitive::avx::intersect_rays8`) instead
//! of one ray against a half-empty block. Deeper trees fragment a batch's
//! rays over many nodes, where single rays are as fast: [`super::Accel::streams`]
//! says where a stream is used.
//!
//! Every ray gets exactly the single-ray query's answer: the node test is the
//! single-ray one (with the interval's first upper end, which only visits
//! more leaves), each lane of the triangle test runs the scalar test's
//! operations, edge fallbacks go through the scalar test, and the closest hit
//! is the least (t, input index) over all tested hits, the tie rule that makes
//! the single-ray answer independent of visit order.

#[cfg(target_arch = "x86_64")]
use super::bvh8::Bvh8;
use super::bvh8::NodeRay;
#[cfg(target_arch = "x86_64")]
use super::leaf::{nearer, LeafCode, Leaves, EMPTY_LANE};
#[cfg(target_arch = "x86_64")]
use super::primitive::avx::{intersect_rays8, Hits8, Rays8, F8};
#[cfg(target_arch = "x86_64")]
use super::primitive::WatertightRay;
#[cfg(target_arch = "x86_64")]
use super::tree::{decode_leaf, LEAF_BIT, WIDEN, WIDEN_INV};
use super::tree::{Tree, EMPTY};
use crate::math::{Ray, Vec2};

/// Trees with at most this many inner nodes take stream queries. Measured
/// (cornell 256² with n boxes added, 16 spp, two threads, streams against
/// single rays): 3 nodes −15 %, 13 −10 %, 31 −6 %, 59 −4 %, 117 +0.4 %,
/// 281 (a teapot) +1 %; the bunny (69k triangles) +32 %.
const STREAM_MAX_NODES: usize = 64;

/// No hit yet (plane [`BEST_ID`]).
const NONE: u32 = u32::MAX;

// The planes of a stream, one f32 (or the bits of an i32/u32) per ray. The
// triangle test's, gathered eight rays at a time: the origin along each ray's
// permuted axes, the shear constants, the permutation, `t_min`; then the
// nearest hit so far (at first the ray's `t_max`), its primitive's input index
// (`NONE`: none), barycentrics and leaf slot; then the node test's view
// ([`NodeRay`]'s fields; `NEAR`: its three row indices a byte each).
const ORG: usize = 0;
const SHEAR: usize = 3;
const AXIS: usize = 6;
const T_MIN: usize = 9;
const BEST_T: usize = 10;
const BEST_ID: usize = 11;
const BEST_B1: usize = 12;
const BEST_B2: usize = 13;
const BEST_SLOT: usize = 14;
const NODE_ORG: usize = 15;
const NODE_INV: usize = 18;
const NODE_INV_FAR: usize = 21;
const NEAR: usize = 24;
const T_LO: usize = 25;
const HI: usize = 26;
const PLANES: usize = 27;

/// The scratch of stream queries, reused from batch to batch.
#[derive(Default)]
pub struct RayStream {
    /// [`PLANES`] planes of `cap` values each (the stream's length rounded
    /// up to eight); grown, never shrunk.
    planes: Vec<f32>,
    cap: usize,
    /// Ray indices, one list per pending node (`stack` holds their ranges);
    /// grown, never shrunk, so that its cells are not zeroed per query.
    ids: Vec<u32>,
    stack: Vec<(u32, u32, u32)>,
}

impl RayStream {
    /// Planes for `n` rays (`cap`: `n` rounded up to the eight lanes).
    fn reserve(&mut self, n: usize) {
        self.cap = n.next_multiple_of(8);
        if self.planes.len() < PLANES * self.cap {
            self.planes.resize(PLANES * self.cap, 0.0);
        }
    }

    /// Ray `r`'s value in `plane` (below [`PLANES`], `r` below `cap`).
    #[inline(always)]
    fn get(&self, plane: usize, r: usize) -> f32 {
        debug_assert!(plane < PLANES && r < self.cap);
        // SAFETY: `planes` holds `PLANES` planes of `cap` values (`prepare`).
        unsafe { *self.planes.get_unchecked(plane * self.cap + r) }
    }

    #[inline(always)]
    fn set(&mut self, plane: usize, r: usize, v: f32) {
        debug_assert!(plane < PLANES && r < self.cap);
        // SAFETY: as in `get`.
        unsafe { *self.planes.get_unchecked_mut(plane * self.cap + r) = v };
    }

    #[inline(always)]
    fn id(&self, plane: usize, r: usize) -> u32 {
        self.get(plane, r).to_bits()
    }

    /// Ray `r`'s node test view.
    #[inline(always)]
    fn node_ray(&self, r: usize) -> NodeRay {
        let v3 = |p: usize| [self.get(p, r), self.get(p + 1, r), self.get(p + 2, r)];
        let near = self.id(NEAR, r);
        NodeRay {
            org: v3(NODE_ORG),
            inv: v3(NODE_INV),
            inv_far: v3(NODE_INV_FAR),
            near: [near & 0xff, (near >> 8) & 0xff, near >> 16],
            t_lo: self.get(T_LO, r),
            hi: self.get(HI, r),
        }
    }

    /// Ray `k`'s closest hit after a closest-hit query, as (input index,
    /// t, barycentrics, leaf slot): `RayStream::hit` (with the front end)
    /// makes the [`super::Hit`].
    pub(super) fn answer(&self, k: usize) -> Option<(u32, f32, Vec2, u32)> {
        let id = self.id(BEST_ID, k);
        (id != NONE).then(|| {
            (
                id,
                self.get(BEST_T, k),
                Vec2::new(self.get(BEST_B1, k), self.get(BEST_B2, k)),
                self.id(BEST_SLOT, k),
            )
        })
    }

    /// Whether ray `k` is blocked, after an any-hit query.
    pub fn occluded(&self, k: usize) -> bool {
        self.id(BEST_ID, k) != NONE
    }
}

/// Whether stream queries pay on `tree`: an 8-wide one (AVX2) of at most
/// [`STREAM_MAX_NODES`] inner nodes, where streams stop paying.
pub(super) fn takes(tree: &Tree) -> bool {
    cfg!(target_arch = "x86_64")
        && matches!(tree, Tree::Eight(t) if t.nodes.len() <= STREAM_MAX_NODES && t.root != EMPTY)
}

impl RayStream {
    /// Writes the answers of `n` rays asked one at a time (`answer(k)`: as
    /// [`RayStream::answer`]), where the tree takes no streams.
    pub(super) fn set_answers(
        &mut self,
        n: usize,
        answer: impl Fn(usize) -> Option<(u32, f32, Vec2, u32)>,
    ) {
        self.reserve(n);
        for k in 0..n {
            let (id, t, bary, slot) = answer(k).unwrap_or((NONE, 0.0, Vec2::ZERO, 0));
            self.set(BEST_T, k, t);
            self.set(BEST_ID, k, f32::from_bits(id));
            self.set(BEST_B1, k, bary.x);
            self.set(BEST_B2, k, bary.y);
            self.set(BEST_SLOT, k, f32::from_bits(slot));
        }
    }
}

/// The traversal: each pending node's rays tested against its children
/// (a list per child entered), each leaf's against its triangles. With
/// `ANY`, a ray leaves the lists at its first hit.
///
/// # Safety
/// The CPU must support AVX2 (`bvh8::supported`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn trace<'r, const ANY: bool>(
    tree: &Bvh8,
    leaves: &Leaves,
    n: usize,
    ray: &impl Fn(usize) -> &'r Ray,
    s: &mut RayStream,
) {
    let mut top = s.prepare(n, ray);
    if top > 0 {
        s.stack.push((tree.root, 0, top as u32));
    }
    while let Some((node, start, end)) = s.stack.pop() {
        let (start, end) = (start as usize, end as usize);
        if node & LEAF_BIT != 0 {
            stream_leaf::<ANY>(leaves, node, start..end, ray, s);
            continue;
        }
        // Each child's list in a region of its own, written without a
        // branch per ray and child (a scan per child mispredicted half
        // its tests).
        let len = end - start;
        if s.ids.len() < top + 8 * len {
            s.ids.resize(top + 8 * len, 0);
        }
        let mut counts = [0usize; 8];
        let ids = s.ids.as_mut_ptr();
        for k in start..end {
            // SAFETY: `k` < `end` ≤ `top`, and each child's region
            // `top + c·len ..` holds at most `len` ids; `ids` has
            // `top + 8·len` cells (resized above), and nothing else
            // touches `s.ids` in this loop.
            let r = *ids.add(k);
            let m = if ANY && s.id(BEST_ID, r as usize) != NONE {
                0
            } else {
                tree.child_mask(node, &s.node_ray(r as usize))
            };
            for (c, count) in counts.iter_mut().enumerate() {
                *ids.add(top + c * len + *count) = r;
                *count += ((m >> c) & 1) as usize;
            }
        }
        let children = tree.children_of(node);
        for (c, &count) in counts.iter().enumerate() {
            if count > 0 {
                let first = (top + c * len) as u32;
                s.stack.push((children[c], first, first + count as u32));
            }
        }
        top += 8 * len;
    }
}

/// The rays `s.ids[list]` against leaf `code`'s triangles, eight rays
/// at a time, each ray's best hit (or, with `ANY`, its first) in `s`.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn stream_leaf<'r, const ANY: bool>(
    leaves: &Leaves,
    code: u32,
    list: std::ops::Range<usize>,
    ray: &impl Fn(usize) -> &'r Ray,
    s: &mut RayStream,
) {
    let (first, count) = decode_leaf(code);
    let (count, _) = LeafCode::decode(count);
    let blocks = &leaves.blocks[first..first + count];
    let mut k = list.start;
    while k < list.end {
        // The next eight rays still looking (unused lanes repeat the first).
        let mut idx = [0i32; 8];
        let mut len = 0;
        while k < list.end && len < 8 {
            let r = s.ids[k];
            k += 1;
            if !ANY || s.id(BEST_ID, r as usize) == NONE {
                idx[len] = r as i32;
                len += 1;
            }
        }
        if len == 0 {
            break;
        }
        for l in len..8 {
            idx[l] = idx[0];
        }
        let live = (1u32 << len) - 1;
        let at = Lanes::new(&idx);
        let lanes = at.rays(s);
        let mut t_max = at.plane(s, BEST_T);
        let mut done = 0u32;
        'blocks: for (b, block) in blocks.iter().enumerate() {
            for (lane, &id) in block.ids.iter().enumerate() {
                if id == EMPTY_LANE {
                    continue;
                }
                let (mut hits, mut scalar, h);
                if id >= leaves.first_sphere {
                    // A sphere: the scalar test for every ray, as a
                    // single-ray query's leaf does.
                    h = Hits8::default();
                    (hits, scalar) = (0, live & !done);
                } else {
                    let v = block.tris.lane(lane).map(|p| p.to_array());
                    h = intersect_rays8::<ANY>(&lanes, &v, t_max);
                    (hits, scalar) = (h.hits & live & !done, h.fallback & live & !done);
                }
                if hits | scalar == 0 {
                    continue;
                }
                let slot = 4 * (first + b) as u32 + lane as u32;
                while hits | scalar != 0 {
                    let l = (hits | scalar).trailing_zeros() as usize;
                    let r = idx[l] as usize;
                    let best_t = s.get(BEST_T, r);
                    let found = if hits & (1 << l) != 0 {
                        Some((h.t[l], Vec2::new(h.b1[l], h.b2[l])))
                    } else {
                        let ray = ray(r);
                        let wr = WatertightRay::new(ray.origin, ray.dir);
                        leaves
                            .prim_of_input(id)
                            .intersect(ray, &wr, best_t)
                            .map(|hit| (hit.t, hit.bary))
                    };
                    hits &= !(1 << l);
                    scalar &= !(1 << l);
                    let Some((t, bary)) = found else { continue };
                    let best_id = s.id(BEST_ID, r);
                    if nearer(t, id, (best_id != NONE).then_some((best_t, best_id))) {
                        s.set(BEST_T, r, t);
                        s.set(BEST_ID, r, f32::from_bits(id));
                        s.set(BEST_B1, r, bary.x);
                        s.set(BEST_B2, r, bary.y);
                        s.set(BEST_SLOT, r, f32::from_bits(slot));
                        if ANY {
                            done |= 1 << l;
                        }
                    }
                }
                if ANY {
                    if done == live {
                        break 'blocks;
                    }
                } else {
                    t_max = at.plane(s, BEST_T);
                }
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl RayStream {
    /// The planes of the rays `ray(0..n)`, eight at a time in AVX lanes
    /// (the single-ray set-up, `node_ray`, `BoxRay::new` and
    /// [`WatertightRay::new`], with the same operations lane by lane); the
    /// indices of the valid rays (as `Accel::traversable` has them) in `ids`
    /// from 0, their count returned.
    #[target_feature(enable = "avx2")]
    unsafe fn prepare<'r>(&mut self, n: usize, ray: &impl Fn(usize) -> &'r Ray) -> usize {
        use std::arch::x86_64::*;
        self.stack.clear();
        self.reserve(n);
        if self.ids.len() < self.cap {
            self.ids.resize(self.cap, 0);
        }
        let mut valid = 0;
        for k0 in (0..n).step_by(8) {
            // Eight rays' fields in lanes (past `n`, the last ray again).
            let mut f = [[0f32; 8]; 8];
            for l in 0..8 {
                let r = ray((k0 + l).min(n - 1));
                let v = [
                    r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, r.t_min, r.t_max,
                ];
                for (field, x) in f.iter_mut().zip(v) {
                    field[l] = x;
                }
            }
            let lane = |i: usize| _mm256_loadu_ps(f[i].as_ptr());
            let (o, d) = ([lane(0), lane(1), lane(2)], [lane(3), lane(4), lane(5)]);
            let (t_min, t_max) = (lane(6), lane(7));
            let c = _mm256_set1_ps;
            let abs = |x: __m256| _mm256_andnot_ps(c(-0.0), x);
            let lt = |a: __m256, b: __m256| _mm256_cmp_ps::<_CMP_LT_OQ>(a, b);
            let gt = |a: __m256, b: __m256| _mm256_cmp_ps::<_CMP_GT_OQ>(a, b);
            let or = |a: __m256, b: __m256| _mm256_or_ps(a, b);
            let and = |a: __m256, b: __m256| _mm256_and_ps(a, b);
            let finite = |x: __m256| lt(abs(x), c(f32::INFINITY));
            // `ray_is_valid`.
            let all3 = |v: [__m256; 3]| and(and(finite(v[0]), finite(v[1])), finite(v[2]));
            let nonzero = |x: __m256| _mm256_cmp_ps::<_CMP_NEQ_UQ>(x, c(0.0));
            let valid_lanes = and(
                and(all3(o), all3(d)),
                and(
                    or(or(nonzero(d[0]), nonzero(d[1])), nonzero(d[2])),
                    and(finite(t_min), _mm256_cmp_ps::<_CMP_LE_OQ>(t_min, t_max)),
                ),
            );
            // `node_ray`: directions clamped away from 0, origins moved
            // back for t_min < 0.
            let clamp = |x: __m256| {
                let tiny = _mm256_blendv_ps(c(1.0e-20), c(-1.0e-20), lt(x, c(0.0)));
                _mm256_blendv_ps(x, tiny, lt(abs(x), c(1.0e-20)))
            };
            let dir = [clamp(d[0]), clamp(d[1]), clamp(d[2])];
            let forward = _mm256_cmp_ps::<_CMP_GE_OQ>(t_min, c(0.0));
            let max_o = _mm256_max_ps(_mm256_max_ps(abs(o[0]), abs(o[1])), abs(o[2]));
            let back = _mm256_sub_ps(
                _mm256_add_ps(c(2.0e-4), _mm256_mul_ps(max_o, c(1.0 / 262_144.0))),
                t_min,
            );
            let back_off = _mm256_blendv_ps(back, c(0.0), forward);
            let back = |i: usize| {
                let moved = _mm256_sub_ps(o[i], _mm256_mul_ps(dir[i], back_off));
                _mm256_blendv_ps(moved, o[i], forward)
            };
            let node_org = [back(0), back(1), back(2)];
            let t_lo = _mm256_blendv_ps(c(0.0), t_min, forward);
            // `BoxRay::new`.
            let inv = [
                _mm256_div_ps(c(1.0), dir[0]),
                _mm256_div_ps(c(1.0), dir[1]),
                _mm256_div_ps(c(1.0), dir[2]),
            ];
            let far = |x: __m256| _mm256_mul_ps(x, c(WIDEN_INV));
            let inv_far = [far(inv[0]), far(inv[1]), far(inv[2])];
            let neg = |x: __m256| _mm256_srli_epi32::<31>(_mm256_castps_si256(lt(x, c(0.0))));
            let near = _mm256_or_si256(
                _mm256_or_si256(
                    neg(dir[0]),
                    _mm256_slli_epi32::<8>(_mm256_add_epi32(neg(dir[1]), _mm256_set1_epi32(2))),
                ),
                _mm256_slli_epi32::<16>(_mm256_add_epi32(neg(dir[2]), _mm256_set1_epi32(4))),
            );
            let hi = _mm256_mul_ps(_mm256_add_ps(t_max, back_off), c(WIDEN));
            // `WatertightRay::new`: kz the largest |d|, kx and ky the next
            // two (swapped when d[kz] < 0), the shear constants.
            let a = [abs(d[0]), abs(d[1]), abs(d[2])];
            let (xy, xz, yz) = (gt(a[0], a[1]), gt(a[0], a[2]), gt(a[1], a[2]));
            let i = |x: i32| _mm256_castsi256_ps(_mm256_set1_epi32(x));
            let kz = _mm256_blendv_ps(
                _mm256_blendv_ps(i(2), i(1), yz),
                _mm256_blendv_ps(i(2), i(0), xz),
                xy,
            );
            let pick = |v: &[__m256; 3], k: __m256| {
                let k = _mm256_castps_si256(k);
                let is = |x: i32| _mm256_castsi256_ps(_mm256_cmpeq_epi32(k, _mm256_set1_epi32(x)));
                _mm256_blendv_ps(_mm256_blendv_ps(v[0], v[1], is(1)), v[2], is(2))
            };
            let d_kz = pick(&d, kz);
            let flip = _mm256_srli_epi32::<31>(_mm256_castps_si256(lt(d_kz, c(0.0))));
            let mod3 = |x: __m256i| {
                let over = _mm256_cmpgt_epi32(x, _mm256_set1_epi32(2));
                _mm256_sub_epi32(x, _mm256_and_si256(over, _mm256_set1_epi32(3)))
            };
            let kzi = _mm256_castps_si256(kz);
            let kx = mod3(_mm256_add_epi32(
                _mm256_add_epi32(kzi, _mm256_set1_epi32(1)),
                flip,
            ));
            let ky = mod3(_mm256_sub_epi32(
                _mm256_add_epi32(kzi, _mm256_set1_epi32(2)),
                flip,
            ));
            let (kx, ky) = (_mm256_castsi256_ps(kx), _mm256_castsi256_ps(ky));
            let sz = _mm256_div_ps(c(1.0), d_kz);
            let out: [(usize, __m256); PLANES] = [
                (ORG, pick(&o, kx)),
                (ORG + 1, pick(&o, ky)),
                (ORG + 2, pick(&o, kz)),
                (SHEAR, _mm256_mul_ps(pick(&d, kx), sz)),
                (SHEAR + 1, _mm256_mul_ps(pick(&d, ky), sz)),
                (SHEAR + 2, sz),
                (AXIS, kx),
                (AXIS + 1, ky),
                (AXIS + 2, kz),
                (T_MIN, t_min),
                (BEST_T, t_max),
                (BEST_ID, i(NONE as i32)),
                (BEST_B1, c(0.0)),
                (BEST_B2, c(0.0)),
                (BEST_SLOT, c(0.0)),
                (NODE_ORG, node_org[0]),
                (NODE_ORG + 1, node_org[1]),
                (NODE_ORG + 2, node_org[2]),
                (NODE_INV, inv[0]),
                (NODE_INV + 1, inv[1]),
                (NODE_INV + 2, inv[2]),
                (NODE_INV_FAR, inv_far[0]),
                (NODE_INV_FAR + 1, inv_far[1]),
                (NODE_INV_FAR + 2, inv_far[2]),
                (NEAR, _mm256_castsi256_ps(near)),
                (T_LO, t_lo),
                (HI, hi),
            ];
            for (plane, v) in out {
                let at = plane * self.cap + k0;
                _mm256_storeu_ps(self.planes[at..at + 8].as_mut_ptr(), v);
            }
            let mut m = _mm256_movemask_ps(valid_lanes) as u32 & ((1u32 << (n - k0).min(8)) - 1);
            while m != 0 {
                self.ids[valid] = (k0 + m.trailing_zeros() as usize) as u32;
                valid += 1;
                m &= m - 1;
            }
        }
        valid
    }
}

/// Eight rays of a stream read into SIMD lanes, plane by plane.
#[cfg(target_arch = "x86_64")]
struct Lanes(std::arch::x86_64::__m256i);

#[cfg(target_arch = "x86_64")]
impl Lanes {
    /// Lane `l` is ray `idx[l]` (every index below the stream's length).
    #[inline(always)]
    unsafe fn new(idx: &[i32; 8]) -> Self {
        use std::arch::x86_64::*;
        Self(_mm256_loadu_si256(idx.as_ptr() as *const __m256i))
    }

    /// Each lane's value in `plane`.
    #[inline(always)]
    unsafe fn plane(&self, s: &RayStream, plane: usize) -> F8 {
        debug_assert!(plane < PLANES);
        F8::gather(s.planes.as_ptr().add(plane * s.cap), self.0)
    }

    /// The triangle test's view of the eight rays.
    #[inline(always)]
    unsafe fn rays(&self, s: &RayStream) -> Rays8 {
        use std::arch::x86_64::_mm256_castps_si256;
        let row = |p: usize| [self.plane(s, p), self.plane(s, p + 1), self.plane(s, p + 2)];
        let [x, y, z] = row(AXIS);
        Rays8::new(
            row(ORG),
            row(SHEAR),
            [
                _mm256_castps_si256(x.0),
                _mm256_castps_si256(y.0),
                _mm256_castps_si256(z.0),
            ],
            self.plane(s, T_MIN),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{add_quads, globe, lcg};
    use super::super::{Accel, Hit};
    use super::*;
    use crate::math::Vec3;
    use crate::scene::{Mesh, Sphere};

    /// A small scene: a coarse closed globe (shared edges and vertices), an
    /// axis-aligned unit quad split along its diagonal, a few tilted quads
    /// and, with `spheres`, analytic spheres.
    fn scene(spheres: bool) -> (Vec<Mesh>, Vec<Sphere>) {
        let globe = globe(6, 10);
        let mut quads = Mesh {
            name: "quads".into(),
            positions: vec![
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(3.0, 0.0, 0.0),
                Vec3::new(3.0, 1.0, 0.0),
                Vec3::new(2.0, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            ..Default::default()
        };
        let mut next = lcg(3);
        add_quads(&mut quads, 12, 0.6, &mut next);
        let spheres = if spheres {
            (0..4)
                .map(|k| Sphere {
                    name: format!("s{k}"),
                    center: Vec3::new(next() * 4.0 - 2.0, next() * 4.0 - 2.0, next() * 4.0 - 2.0),
                    radius: 0.1 + 0.3 * next(),
                    material: 0,
                    emission: Vec3::ZERO,
                    bump: None,
                    object_id: 0,
                })
                .collect()
        } else {
            Vec::new()
        };
        (vec![globe, quads], spheres)
    }

    /// Random rays, segments (t_max finite), rays that may hit behind their
    /// origin (t_min < 0), axis-aligned rays, rays through the split quad's
    /// diagonal and through globe vertices (edge functions exactly zero: the
    /// scalar fallback), and invalid rays.
    fn rays(globe: &Mesh) -> Vec<Ray> {
        let mut next = lcg(17);
        let mut rays = Vec::new();
        for i in 0..4000 {
            let o = Vec3::new(next(), next(), next()) * 6.0 - 3.0;
            let d = (Vec3::new(next(), next(), next()) * 2.0 - 1.0).normalize_or(Vec3::X);
            let mut ray = Ray::new(o, d);
            match i % 4 {
                1 => ray.t_max = next() * 4.0,
                2 => ray.t_min = -next() * 2.0,
                _ => {}
            }
            rays.push(ray);
        }
        for k in 0..200 {
            let x = 2.0 + (k as f32 + 0.5) / 200.0;
            rays.push(Ray::new(Vec3::new(x, x - 2.0, 1.0), -Vec3::Z));
            rays.push(Ray::new(Vec3::new(x, 0.5, -1.0), Vec3::Z));
        }
        for &p in globe.positions.iter().take(50) {
            let o = p * 3.0 + Vec3::new(0.0, 0.0, 1e-3);
            rays.push(Ray::new(o, (p - o).normalize()));
            rays.push(Ray::new(Vec3::ZERO, p));
        }
        // Rays leaving a point of a triangle without an offset (t_min = 0):
        // the hit on their own triangle at t ≈ 0 is the δt test's to reject.
        for (k, t) in globe.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|i| globe.positions[i as usize]);
            let (u, v) = (next() * 0.5, next() * 0.5);
            let p = a + (b - a) * u + (c - a) * v;
            let d = (Vec3::new(next(), next(), next()) * 2.0 - 1.0).normalize_or(Vec3::Y);
            rays.push(Ray::new(p, if k % 2 == 0 { d } else { -p }));
        }
        rays.push(Ray::new(Vec3::splat(f32::NAN), Vec3::X));
        rays.push(Ray::new(Vec3::ZERO, Vec3::ZERO));
        rays.push(Ray::new(Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0)));
        rays.push(Ray {
            t_min: 2.0,
            t_max: 1.0,
            ..Ray::new(Vec3::ZERO, Vec3::Y)
        });
        rays
    }

    /// Every ray of a stream gets the single-ray query's answer, bit for bit
    /// (distance, barycentrics, primitive and leaf slot; occlusion), in
    /// batches of every size around the eight lanes, with and without spheres,
    /// for leaves of one to eight primitives — and so do the 4-wide trees,
    /// whose stream queries go ray by ray.
    #[test]
    fn streams_answer_as_single_rays() {
        let mut tested = [0, 0];
        for spheres in [false, true] {
            let (meshes, spheres) = scene(spheres);
            let rays = rays(&meshes[0]);
            for (node_width, max_prims_per_leaf) in [(8, 1), (8, 4), (8, 8), (4, 4)] {
                let preset = super::super::BuildPreset {
                    node_width,
                    max_prims_per_leaf,
                    ..Default::default()
                };
                let accel = Accel::build_with_preset(&meshes, &spheres, &preset);
                let streams = node_width == 8 && super::super::bvh8::supported();
                assert_eq!(accel.streams(), streams, "{} nodes", accel.node_count());
                let mut s = RayStream::default();
                let mut start = 0;
                for batch in [1, 7, 8, 9, 256, 64, 3].into_iter().cycle() {
                    if start >= rays.len() {
                        break;
                    }
                    let rays = &rays[start..(start + batch).min(rays.len())];
                    start += batch;
                    accel.intersect_stream(rays.len(), |k| &rays[k], &mut s);
                    for (k, ray) in rays.iter().enumerate() {
                        let (a, b) = (s.hit(&accel, k), accel.intersect(ray));
                        let bits = |h: Option<Hit>| {
                            h.map(|h| {
                                (
                                    h.t.to_bits(),
                                    h.prim,
                                    h.bary.to_array().map(f32::to_bits),
                                    h.slot,
                                )
                            })
                        };
                        assert_eq!(bits(a), bits(b), "{ray:?}");
                    }
                    accel.occluded_stream(rays.len(), |k| &rays[k], &mut s);
                    for (k, ray) in rays.iter().enumerate() {
                        assert_eq!(s.occluded(k), accel.occluded(ray), "{ray:?}");
                    }
                    tested[usize::from(streams)] += rays.len();
                }
            }
        }
        let streamed = if super::super::bvh8::supported() {
            20_000
        } else {
            0
        };
        assert!(tested[1] >= streamed && tested[0] > 5_000, "{tested:?}");
    }

    /// The bunny's tree is too deep for streams; cornell's is not.
    #[test]
    fn small_trees_only() {
        let (meshes, spheres) = scene(true);
        let accel = Accel::build(&meshes, &spheres);
        assert_eq!(accel.streams(), super::super::bvh8::supported());
        let mut big = meshes[0].clone();
        big.positions = (0..30_000)
            .map(|i| Vec3::new(i as f32, (i % 7) as f32, 0.0))
            .collect();
        big.triangles = (0..29_998).map(|i| [i, i + 1, i + 2]).collect();
        assert!(!Accel::build(&[big], &[]).streams());
    }
}
