//! Exact ray/primitive intersection routines used as the per-primitive callback of
//! the BVH traversal (and by the brute-force reference).
//!
//! Neither routine comes from obvhs on purpose:
//! - obvhs' `Triangle::intersect` is a Möller–Trumbore test, which is *not*
//!   watertight: rays through a shared edge or vertex can slip between the two
//!   triangles. We implement the watertight test of Woop, Benthin & Wald 2013
//!   ("Watertight Ray/Triangle Intersection", JCGT 2(1)) instead.
//! - obvhs' `Triangle::compute_barycentric` returns barycentrics with the wrong
//!   scale; our barycentrics come straight out of the watertight test (U, V, W
//!   divided by their sum), so they are exact and sum to one.

use crate::math::lanes::Lanes;
use crate::math::Vec3;
use wide::f32x4;

/// γ(n) = n·u / (1 − n·u) with u = 2⁻²⁴, the relative error bound of n rounded
/// f32 operations (pbrt-v4 eq. 6.25; Higham).
pub(crate) const fn gamma(n: i32) -> f32 {
    let nu = n as f32 * (f32::EPSILON * 0.5);
    nu / (1.0 - nu)
}

/// pbrt-v4's bound on the rounding error of the watertight test's `t`
/// (Pharr, Jakob & Humphreys, §6.8.4, "Triangle t error bounds"), from the
/// sheared vertices' largest |x|, |y|, |z|, the largest |edge function| and
/// 1/det. A hit with `t ≤ δt` may be behind the origin: it is rejected, which
/// is what lets a ray spawned with [`crate::accel::SurfacePoint`]'s tight origin
/// offset start at `t_min = 0` without re-hitting the triangle it leaves, even
/// at grazing angles where 1/det is large. Generic so that the scalar test and
/// each lane of the 4-wide one compute the same bits (no FMA contraction):
/// `x`, `y`, `z` are the three sheared (and, for z, scaled) vertices' coordinates,
/// `e` the edge functions.
#[inline(always)]
fn t_error_bound<F: Lanes>(x: [F; 3], y: [F; 3], z: [F; 3], e: [F; 3], abs_rcp_det: F) -> F {
    let max3 = |p: [F; 3]| p[0].abs().max(p[1].abs()).max(p[2].abs());
    let (max_x, max_y, max_z, max_e) = (max3(x), max3(y), max3(z), max3(e));
    let g = |n: i32| F::splat(gamma(n));
    let delta_z = g(3) * max_z;
    let delta_x = g(5) * (max_x + max_z);
    let delta_y = g(5) * (max_y + max_z);
    let delta_e = F::splat(2.0) * (g(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    F::splat(3.0) * (g(3) * max_e * max_z + delta_e * max_z + delta_z * max_e) * abs_rcp_det
}

/// The watertight test's arithmetic on SIMD lanes, one triangle per lane:
/// the sheared vertices, the edge functions, the hit distance and 1/det.
struct LaneTest<F> {
    x: [F; 3],
    y: [F; 3],
    z: [F; 3],
    /// U, V, W (paper eq. 3).
    e: [F; 3],
    det: F,
    rcp_det: F,
    t: F,
}

/// [`WatertightRay::intersect`]'s operations in its order, on lanes: the one
/// sequence the 4- and 8-lane tests share, so that each lane's bits are the
/// scalar test's. `rel(k, i)` is vertex k relative to the ray origin along
/// the permuted axis i (kx, ky, kz); `s` the shear constants (Sx, Sy, Sz).
#[inline(always)]
fn lane_test<F: Lanes>(rel: impl Fn(usize, usize) -> F, [sx, sy, sz]: [F; 3]) -> LaneTest<F> {
    let vertex = |k: usize| [rel(k, 0), rel(k, 1), rel(k, 2)];
    let (a, b, c) = (vertex(0), vertex(1), vertex(2));
    // Shear and scale (paper §3, Listing 1).
    let (ax, ay) = (a[0] - sx * a[2], a[1] - sy * a[2]);
    let (bx, by) = (b[0] - sx * b[2], b[1] - sy * b[2]);
    let (cx, cy) = (c[0] - sx * c[2], c[1] - sy * c[2]);
    // Edge functions (paper eq. 3).
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    let det = u + v + w;
    // Scaled hit distance (paper eq. 5).
    let (az, bz, cz) = (sz * a[2], sz * b[2], sz * c[2]);
    let t_scaled = u * az + v * bz + w * cz;
    let rcp_det = F::splat(1.0) / det;
    LaneTest {
        x: [ax, bx, cx],
        y: [ay, by, cy],
        z: [az, bz, cz],
        e: [u, v, w],
        det,
        rcp_det,
        t: t_scaled * rcp_det,
    }
}

impl<F: Lanes> LaneTest<F> {
    /// The barycentrics (b1, b2) = (V, W) / det, as the scalar test returns them.
    #[inline(always)]
    fn barycentrics(&self) -> (F, F) {
        (self.e[1] * self.rcp_det, self.e[2] * self.rcp_det)
    }

    /// pbrt-v4's δt for these lanes ([`t_error_bound`]).
    #[inline(always)]
    fn t_error_bound(&self) -> F {
        t_error_bound(self.x, self.y, self.z, self.e, self.rcp_det.abs())
    }
}

impl<F: Lanes> LaneTest<F> {
    /// The scalar test's decisions on every lane, as bit masks: `(hits,
    /// on_edge)`, the lanes hit with t in [t_min, t_max] (and t > δt on
    /// forward rays), and those with an edge function exactly zero, which the
    /// scalar test must decide (its double-precision path).
    #[inline(always)]
    fn decide(&self, t_min: f32, t_max: f32) -> (u32, u32) {
        let forward = if t_min >= 0.0 { u32::MAX } else { 0 };
        self.decide_in(F::splat(t_min), F::splat(t_max), forward)
    }

    /// [`LaneTest::decide`] with each lane's own interval (one ray per lane,
    /// [`avx::intersect_rays8`]); `forward`: the lanes whose ray has
    /// `t_min ≥ 0`, which the δt test applies to.
    #[inline(always)]
    fn decide_in(&self, t_min: F, t_max: F, forward: u32) -> (u32, u32) {
        let [u, v, w] = self.e;
        let zero = F::splat(0.0);
        let on_edge = u.eq(zero).or(v.eq(zero)).or(w.eq(zero)).bitmask();
        let negative = u.lt(zero).or(v.lt(zero)).or(w.lt(zero));
        let positive = u.gt(zero).or(v.gt(zero)).or(w.gt(zero));
        let in_range = self.t.ge(t_min).and(self.t.le(t_max));
        // `ne` is true for a NaN det, as the scalar test's `det == 0` is false.
        let mut hits = in_range.and(self.det.ne(zero)).bitmask()
            & !negative.and(positive).bitmask()
            & !on_edge;
        // The scalar test's t > δt for forward rays, on the (few) blocks with a hit.
        if hits & forward != 0 {
            hits &= !(self.t.le(self.t_error_bound()).bitmask() & forward);
        }
        (hits, on_edge)
    }
}

/// Per-ray precomputation of the watertight test (Woop, Benthin & Wald 2013, §3,
/// "Ray transformation"): the permutation that makes `kz` the dominant direction
/// axis, and the shear constants that map the ray to the +z axis of a unit space.
///
/// The permutation is a run-time value: the SIMD leaf tests read their triangles
/// in SoA rows, so `A[kx]` is a row picked by index, as cheap as a fixed one, and
/// the traversal is one instance instead of one per permutation (six copies of
/// the closest-hit and any-hit loops did not fit the instruction cache).
#[derive(Clone, Copy, Debug)]
pub(crate) struct WatertightRay {
    org: Vec3,
    /// (Sx, Sy, Sz) in one register: the SIMD tests splat them from one
    /// 16-byte store, which forwards (three f32 fields were read 16 bytes at
    /// a time across separate stores, a store-forwarding stall per query).
    shear: Vec3,
    /// (kx, ky, kz): `kz` the dominant axis, kx and ky swapped when
    /// `dir[kz] < 0` to keep the winding.
    axes: Axes,
}

/// A permutation (kx, ky, kz) packed in one `u32`, a byte each, so that the
/// SIMD tests' copy of it is one 4-byte load of one 4-byte store (as
/// `[usize; 3]` it was copied 16 bytes at a time across separate 8-byte
/// stores: a store-forwarding stall per query). Each axis is below 3 (built
/// only by [`Axes::new`]), which is what makes [`pick`] safe.
#[derive(Clone, Copy, Debug)]
struct Axes(u32);

impl Axes {
    fn new(kx: usize, ky: usize, kz: usize) -> Self {
        debug_assert!(kx < 3 && ky < 3 && kz < 3);
        Self(kx as u32 | (ky as u32) << 8 | (kz as u32) << 16)
    }

    #[inline(always)]
    fn get(self) -> [usize; 3] {
        [0, 8, 16].map(|shift| ((self.0 >> shift) & 0xff) as usize)
    }
}

/// `row[axis]` for an axis of a [`WatertightRay`]'s permutation, without a
/// bounds check in the leaf tests' inner loop.
#[inline(always)]
fn pick<T: Copy>(row: &[T; 3], axis: usize) -> T {
    debug_assert!(axis < 3);
    // SAFETY: every axis of a permutation is 0, 1 or 2 (`Axes::new`, called
    // only by `WatertightRay::new`).
    unsafe { *row.get_unchecked(axis) }
}

impl WatertightRay {
    pub(crate) fn new(org: Vec3, dir: Vec3) -> Self {
        let a = dir.abs();
        // kz = index of the largest |dir| component (paper: max_dim(abs(dir))),
        // kx, ky the next two, swapped when dir[kz] < 0 to preserve the winding.
        // Selects rather than branches: for a bounce's random direction each
        // comparison is a coin toss.
        let (xy, xz, yz) = (a.x > a.y, a.x > a.z, a.y > a.z);
        let kz = if xy {
            2 * usize::from(!xz)
        } else {
            1 + usize::from(!yz)
        };
        let d = [dir.x, dir.y, dir.z];
        let flip = usize::from(d[kz] < 0.0);
        // (kz + 1, kz + 2) mod 3, in that order or swapped.
        let kx = (kz + 1 + flip) % 3;
        let ky = (kz + 2 - flip) % 3;
        // Shear constants (paper §3: Sx = dx/dz, Sy = dy/dz, Sz = 1/dz).
        let sz = 1.0 / d[kz];
        Self {
            org,
            shear: Vec3::new(d[kx] * sz, d[ky] * sz, sz),
            axes: Axes::new(kx, ky, kz),
        }
    }

    /// Returns `(t, b1, b2)` for a hit with `t_min <= t <= t_max`, where b1, b2 are
    /// the barycentric weights of `v1` and `v2`. Two-sided (no back-face culling).
    #[inline(always)]
    pub(crate) fn intersect(
        &self,
        v0: Vec3,
        v1: Vec3,
        v2: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, f32, f32)> {
        // Vertices relative to the ray origin.
        let a = (v0 - self.org).to_array();
        let b = (v1 - self.org).to_array();
        let c = (v2 - self.org).to_array();
        // Shear and scale of the vertices (paper §3, Listing 1).
        let [kx, ky, kz] = self.axes.get();
        let shear = |v: &[f32; 3]| {
            let z = pick(v, kz);
            (
                pick(v, kx) - self.shear.x * z,
                pick(v, ky) - self.shear.y * z,
            )
        };
        let ((ax, ay), (bx, by), (cx, cy)) = (shear(&a), shear(&b), shear(&c));
        // Scaled barycentric coordinates = 2D edge functions (paper §3, eq. 3).
        // Rust never contracts `a*b - c*d` into an FMA, which is what makes the
        // edge function of a shared edge exactly anti-symmetric between the two
        // triangles that share it (the watertightness argument of §3.1).
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        // Fall back to double precision when an edge function is exactly zero
        // (ray through an edge or vertex): the f32 result is then not reliable to
        // decide the side, the f64 product of f32 inputs is exact (§3.1).
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (
                ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
            );
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        // Edge tests, no back-face culling: all the same sign (zeros allowed).
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        // det == 0: the ray is parallel to the triangle's plane or the triangle is
        // degenerate (zero area): never a hit.
        if det == 0.0 {
            return None;
        }
        // Scaled hit distance (paper eq. 5): T = U·Az + V·Bz + W·Cz.
        let (az, bz, cz) = (
            self.shear.z * pick(&a, kz),
            self.shear.z * pick(&b, kz),
            self.shear.z * pick(&c, kz),
        );
        let t_scaled = u * az + v * bz + w * cz;
        let rcp_det = 1.0 / det;
        let t = t_scaled * rcp_det;
        // Range test in [t_min, t_max]. This is where `t_min` is honoured: node
        // culling only drops boxes that end before it, so a visited leaf can still
        // hold primitives hit before t_min.
        if !(t >= t_min && t <= t_max) {
            return None;
        }
        // A ray that may only go forward (t_min ≥ 0) must be conservatively in
        // front: t > δt (pbrt-v4 §6.8.4).
        if t_min >= 0.0 {
            let bound = t_error_bound(
                [ax, bx, cx],
                [ay, by, cy],
                [az, bz, cz],
                [u, v, w],
                rcp_det.abs(),
            );
            if t <= bound {
                return None;
            }
        }
        Some((t, v * rcp_det, w * rcp_det))
    }
}

/// Up to four triangles in SoA layout (`v[k][axis]`: vertex k's coordinate
/// along `axis`, one lane per triangle), tested at once by
/// [`WatertightRay4::intersect`]. Lanes without a triangle hold NaN vertices,
/// for which every edge and range comparison is false: never a hit, never a
/// fallback.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(crate) struct Tri4 {
    pub(crate) v: [[f32x4; 3]; 3],
}

impl Tri4 {
    pub(crate) fn new(lanes: [Option<[Vec3; 3]>; 4]) -> Self {
        let mut v = [[[f32::NAN; 4]; 3]; 3];
        for (lane, tri) in lanes.iter().enumerate() {
            let Some(tri) = tri else { continue };
            for k in 0..3 {
                for axis in 0..3 {
                    v[k][axis][lane] = tri[k][axis];
                }
            }
        }
        Self {
            v: v.map(|vk| vk.map(f32x4::new)),
        }
    }

    /// The triangle of `lane` (< 4), as [`Tri4::new`] took it.
    #[inline(always)]
    pub(crate) fn lane(&self, lane: usize) -> [Vec3; 3] {
        let at = |k: usize, axis: usize| self.v[k][axis].as_array()[lane];
        [0, 1, 2].map(|k| Vec3::new(at(k, 0), at(k, 1), at(k, 2)))
    }
}

/// [`WatertightRay`] splatted for [`Tri4`]: each lane runs exactly the scalar
/// test's operations in the same order (Rust never contracts them into FMAs),
/// so a lane's `t` and barycentrics are bit-identical to
/// [`WatertightRay::intersect`]'s, which keeps the brute-force agreement.
pub(crate) struct WatertightRay4 {
    org: [f32x4; 3],
    sx: f32x4,
    sy: f32x4,
    sz: f32x4,
    axes: Axes,
}

/// The four lanes' results: `hits` the lanes with a hit in range; `fallback`
/// those with an edge function exactly zero, which the scalar test must decide
/// (its double-precision path); `t`, `b1`, `b2` valid in `hits` lanes.
pub(crate) struct Hits4 {
    pub(crate) hits: u32,
    pub(crate) fallback: u32,
    pub(crate) t: f32x4,
    pub(crate) b1: f32x4,
    pub(crate) b2: f32x4,
}

impl WatertightRay4 {
    pub(crate) fn new(wr: &WatertightRay) -> Self {
        let (o, s) = (wr.org, wr.shear);
        Self {
            org: [f32x4::splat(o.x), f32x4::splat(o.y), f32x4::splat(o.z)],
            sx: f32x4::splat(s.x),
            sy: f32x4::splat(s.y),
            sz: f32x4::splat(s.z),
            axes: wr.axes,
        }
    }

    /// [`WatertightRay::intersect`] on four triangles. Barycentrics are only
    /// computed when some lane hits (`ANY` false) — an any-hit query needs only
    /// the masks.
    #[inline(always)]
    pub(crate) fn intersect<const ANY: bool>(&self, tri: &Tri4, t_min: f32, t_max: f32) -> Hits4 {
        let axes = self.axes.get();
        let lt = lane_test(
            |k, i| pick(&tri.v[k], axes[i]) - pick(&self.org, axes[i]),
            [self.sx, self.sy, self.sz],
        );
        let (hits, on_edge) = lt.decide(t_min, t_max);
        let zero = f32x4::splat(0.0);
        let (b1, b2) = if ANY || hits == 0 {
            (zero, zero)
        } else {
            lt.barycentrics()
        };
        Hits4 {
            hits,
            fallback: on_edge,
            t: lt.t,
            b1,
            b2,
        }
    }
}

/// Two [`Tri4`] blocks (a leaf of five to eight triangles) tested at once
/// with 256-bit AVX: lane `i < 4` is `lo`'s lane `i`, lane `4 + i` is `hi`'s.
/// Each lane runs [`WatertightRay4::intersect`]'s operations in the same order,
/// so its bits are the scalar test's. For the 8-wide tree (`bvh8.rs`), which
/// only runs where AVX2 is: one test instead of two halves the leaf work of
/// the blocks that fill both.
#[cfg(target_arch = "x86_64")]
pub(crate) mod avx {
    use super::{lane_test, LaneTest, Tri4, WatertightRay};
    use crate::math::lanes::{Lanes, Lanes8};
    use std::arch::x86_64::*;

    /// Eight f32 lanes (`math::lanes`' AVX type); its operations must only
    /// run inside an AVX function (they are `#[inline(always)]` so that they
    /// inline into one).
    pub(crate) use crate::math::lanes::Avx as F8;

    /// [`super::Hits4`] for eight lanes.
    #[derive(Default)]
    pub(crate) struct Hits8 {
        pub(crate) hits: u32,
        pub(crate) fallback: u32,
        pub(crate) t: [f32; 8],
        pub(crate) b1: [f32; 8],
        pub(crate) b2: [f32; 8],
    }

    impl Hits8 {
        /// The lanes of `lt` with its decisions `(hits, on_edge)`; the
        /// barycentrics only where some lane hits and not for `ANY`.
        #[inline(always)]
        fn new<const ANY: bool>(lt: &LaneTest<F8>, (hits, on_edge): (u32, u32)) -> Self {
            let (b1, b2) = if ANY || hits == 0 {
                ([0.0; 8], [0.0; 8])
            } else {
                let (b1, b2) = lt.barycentrics();
                (b1.store(), b2.store())
            };
            Hits8 {
                hits,
                fallback: on_edge,
                t: lt.t.store(),
                b1,
                b2,
            }
        }
    }

    /// [`super::WatertightRay4::intersect`] on the eight lanes of `lo` and `hi`.
    ///
    /// # Safety
    /// The CPU must support AVX2, and the caller must be an AVX2 function
    /// (the 8-wide traversal): this is `#[inline(always)]` rather than
    /// `#[target_feature]` so that it inlines into the traversal loop (a
    /// target-feature function is called out of line, which cost ~4 % of closest-hit rays/s), and
    /// its intrinsics inline once it sits in an AVX2 body.
    #[inline(always)]
    pub(crate) unsafe fn intersect8<const ANY: bool>(
        wr: &WatertightRay,
        lo: &Tri4,
        hi: &Tri4,
        t_min: f32,
        t_max: f32,
    ) -> Hits8 {
        let org = wr.org.to_array().map(F8::splat);
        // SAFETY: a `wide::f32x4` is four f32 in 16 aligned bytes; `axis` is
        // below 3 (see `pick`).
        let load = |k: usize, axis: usize| {
            let p = |t: &Tri4| t.v[k].as_ptr().add(axis) as *const f32;
            F8(_mm256_loadu2_m128(p(hi), p(lo)))
        };
        let axes = wr.axes.get();
        let lt = lane_test(
            |k, i| load(k, axes[i]) - super::pick(&org, axes[i]),
            wr.shear.to_array().map(F8::splat),
        );
        let decided = lt.decide(t_min, t_max);
        Hits8::new::<ANY>(&lt, decided)
    }

    /// Eight rays in lanes for [`intersect_rays8`]: each lane's
    /// [`WatertightRay`] (origin along the permuted axes, shear, permutation)
    /// and interval start, gathered once per leaf and tested against each of
    /// its triangles.
    pub(crate) struct Rays8 {
        /// The origin along each lane's permuted axes.
        org: [F8; 3],
        shear: [F8; 3],
        /// Per permuted axis i, the lanes whose axis is 1 and those whose axis is 2.
        is_y: [F8; 3],
        is_z: [F8; 3],
        t_min: F8,
        /// The lanes with `t_min ≥ 0` (the δt test's).
        forward: u32,
    }

    impl Rays8 {
        /// The lanes' origins along their permuted axes, shear constants,
        /// permutations (each axis 0, 1 or 2 in an i32 lane) and `t_min`.
        ///
        /// # Safety
        /// AVX2, as [`intersect8`].
        #[inline(always)]
        pub(crate) unsafe fn new(
            org: [F8; 3],
            shear: [F8; 3],
            axis: [__m256i; 3],
            t_min: F8,
        ) -> Self {
            let is = |k: i32| {
                let eq = |a: __m256i| {
                    F8(_mm256_castsi256_ps(_mm256_cmpeq_epi32(
                        a,
                        _mm256_set1_epi32(k),
                    )))
                };
                [eq(axis[0]), eq(axis[1]), eq(axis[2])]
            };
            Self {
                org,
                shear,
                is_y: is(1),
                is_z: is(2),
                forward: t_min.ge(F8::splat(0.0)).bitmask(),
                t_min,
            }
        }
    }

    /// [`WatertightRay::intersect`] of eight rays (one per lane) with one
    /// triangle `v` (`v[k][axis]`), each lane's interval [t_min, `t_max`]:
    /// every lane runs the scalar test's operations in its order, its axes
    /// picked by blends, so its bits are the scalar test's (the ray streams
    /// of `accel::stream`).
    ///
    /// # Safety
    /// AVX2, as [`intersect8`].
    #[inline(always)]
    pub(crate) unsafe fn intersect_rays8<const ANY: bool>(
        rays: &Rays8,
        v: &[[f32; 3]; 3],
        t_max: F8,
    ) -> Hits8 {
        // Each vertex splatted once, then its coordinate along each lane's
        // axis i picked by two blends.
        let splat = |p: [f32; 3]| p.map(F8::splat);
        let vertices = [splat(v[0]), splat(v[1]), splat(v[2])];
        let pick = |k: usize, i: usize| {
            let [x, y, z] = vertices[k];
            let xy = _mm256_blendv_ps(x.0, y.0, rays.is_y[i].0);
            F8(_mm256_blendv_ps(xy, z.0, rays.is_z[i].0))
        };
        let lt = lane_test(|k, i| pick(k, i) - rays.org[i], rays.shear);
        let decided = lt.decide_in(rays.t_min, t_max, rays.forward);
        Hits8::new::<ANY>(&lt, decided)
    }
}

/// Both roots of the ray/sphere quadratic, smallest first, computed with the
/// precision-improved formulation of Haines et al., "Precision Improvements for
/// Ray/Sphere Intersection" (Ray Tracing Gems, ch. 7), as also used by pbrt-v4:
///
/// - the discriminant is evaluated as `r² − |f − (f·d/d·d) d|²` (RTG eq. 7.5/7.6,
///   Hearn & Baker) instead of `b² − 4ac`, which avoids the catastrophic
///   cancellation for rays far from the sphere, and the difference of squares is
///   factored as `(r − l)(r + l)`;
/// - the roots are `t0 = c/q`, `t1 = q/a` with `q = −(b + sign(b)√Δ)` (RTG eq. 7.8,
///   Press et al.), which avoids cancellation between `−b` and `√Δ`.
///
/// Returns `None` when the line misses the sphere.
#[inline(always)]
pub(crate) fn sphere_roots(org: Vec3, dir: Vec3, center: Vec3, radius: f32) -> Option<(f32, f32)> {
    let f = org - center;
    let a = dir.length_squared();
    // Half-b form: a t² + 2 b' t + c = 0, b' = f·d.
    let b = f.dot(dir);
    // Vector from the centre to the point of the line closest to it.
    let l = f - (b / a) * dir;
    let l_len = l.length();
    // Δ/4 = a (r² − |l|²) (RTG eq. 7.6 in half-b form).
    let disc = a * (radius - l_len) * (radius + l_len);
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    // c = |f|² − r², factored to reduce cancellation for origins near the surface.
    let f_len = f.length();
    let c = (f_len - radius) * (f_len + radius);
    let q = -(b + disc.sqrt().copysign(b));
    if q == 0.0 {
        // b == 0 and Δ == 0: a tangent ray whose closest point is the origin.
        return Some((0.0, 0.0));
    }
    let (t0, t1) = (c / q, q / a);
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
}

/// The nearest root of the sphere quadratic inside `[t_min, t_max]`: the near root
/// for rays from outside, the far root for rays starting inside the sphere (or
/// when the near one is before `t_min`).
#[inline(always)]
pub(crate) fn intersect_sphere(
    org: Vec3,
    dir: Vec3,
    center: Vec3,
    radius: f32,
    t_min: f32,
    t_max: f32,
) -> Option<f32> {
    let (t0, t1) = sphere_roots(org, dir, center, radius)?;
    // Filter by t_min here (node culling is coarser, see `intersect`).
    if t0 >= t_min && t0 <= t_max {
        Some(t0)
    } else if t1 >= t_min && t1 <= t_max {
        Some(t1)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_known_answer_and_barycentrics() {
        let (v0, v1, v2) = (
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        );
        let o = Vec3::new(0.25, 0.5, 2.0);
        let wr = WatertightRay::new(o, -Vec3::Z);
        let (t, b1, b2) = wr.intersect(v0, v1, v2, 0.0, f32::INFINITY).unwrap();
        assert!((t - 2.0).abs() < 1e-6);
        assert!((b1 - 0.25).abs() < 1e-6 && (b2 - 0.5).abs() < 1e-6);
        // Same from below (other winding relative to the ray).
        let wr = WatertightRay::new(Vec3::new(0.25, 0.5, -3.0), Vec3::Z);
        let (t, b1, b2) = wr.intersect(v0, v1, v2, 0.0, f32::INFINITY).unwrap();
        assert!((t - 3.0).abs() < 1e-6);
        assert!((b1 - 0.25).abs() < 1e-6 && (b2 - 0.5).abs() < 1e-6);
        // Range limits.
        assert!(wr.intersect(v0, v1, v2, 0.0, 2.9).is_none());
        assert!(wr.intersect(v0, v1, v2, 3.1, 9.0).is_none());
        // Miss.
        let wr = WatertightRay::new(Vec3::new(0.8, 0.8, 1.0), -Vec3::Z);
        assert!(wr.intersect(v0, v1, v2, 0.0, f32::INFINITY).is_none());
    }

    #[test]
    fn sphere_roots_are_precise_far_away() {
        // Ray from 1e4 away toward a unit sphere: the naive b² − 4ac loses the
        // roots almost entirely in f32; the improved form keeps them to ~1e-3.
        let c = Vec3::new(0.0, 0.0, 1.0e4);
        let (t0, t1) = sphere_roots(Vec3::ZERO, Vec3::Z, c, 1.0).unwrap();
        assert!((t0 - 9999.0).abs() < 2e-3, "{t0}");
        assert!((t1 - 10001.0).abs() < 2e-3, "{t1}");
        // Inside: far side only.
        let t = intersect_sphere(c, Vec3::X, c, 1.0, 0.0, f32::INFINITY).unwrap();
        assert!((t - 1.0).abs() < 1e-3);
        // Tiny sphere, grazing miss.
        assert!(sphere_roots(Vec3::ZERO, Vec3::X, Vec3::new(5.0, 0.0011, 0.0), 0.001).is_none());
    }
}
