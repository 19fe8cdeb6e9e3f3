//! Triangles + exact spheres → one wide BVH answering closest-hit and any-hit
//! (shadow) queries.
//!
//! One BVH holds every primitive of the scene: the build only sees per-primitive
//! AABBs (a mix of triangle and sphere boxes), and traversal calls our own
//! intersection routine per primitive (`primitive.rs`), so spheres stay exact
//! analytic spheres and triangles use the watertight test.
//!
//! obvhs builds the tree (PLOC + reinsertion, `build.rs`); we collapse it into
//! our own uncompressed wide BVH at least SAH cost (`collapse::SahCollapse`, the
//! collapse obvhs does only for its CWBVH) and traverse that: 8-wide with AVX2
//! where the CPU has it (`bvh8.rs`, detected at run time), else 4-wide (`bvh4.rs`);
//! leaves hold triangle4 blocks (`LeafBlock`), and the 8-wide tree tests a
//! leaf of two blocks as one eight-lane AVX block (`primitive::avx`). On small
//! trees the lane shading's rays go through as ray streams instead
//! (`stream.rs`: a batch node by node, each triangle against eight rays). obvhs 0.4
//! pitfalls and where they are handled:
//! 1. `Triangle::compute_barycentric` is scaled wrongly, 2. its triangle test is
//!    not watertight → neither is used; see `primitive::WatertightRay`.
//! 3. Its CWBVH traversal clamps the entry distance to a fixed 1e-4, decodes
//!    u8-quantised boxes on every visit, visits children in octant order and has
//!    a 32-entry stack that silently clamps in release → not used: our BVH4/BVH8 is
//!    traversed nearest-first with a stack sized from the measured depth
//!    ([`Accel::stack_size`]).
//! 4. The build overflows (panics) for boxes wider than ~1e19 and is quadratic
//!    for coincident boxes → `build.rs` builds in a power-of-two-scaled frame
//!    and deduplicates boxes first.
//!
//! Robustness of the ray/box test itself: direction components are clamped
//! away from zero (±1e-20) so the reciprocal is finite and `0 · ∞` cannot occur,
//! exit distances are widened (Ize 2013, "Robust BVH Ray Traversal"), and
//! primitive boxes are padded by a scene-relative epsilon so that rounding can
//! never cull a box a ray touches at an edge or vertex.
//!
//! Files by concern: this front end ([`Accel`], its queries and statistics);
//! `leaf.rs` the primitives packed per leaf; `tree.rs` the wide tree's
//! layout, `bvh4.rs`/`bvh8.rs` its two node types and their slab tests,
//! `collapse.rs` the BVH2 → wide tree collapse, `build.rs` the obvhs build;
//! `traverse.rs` the one traversal loop, generic over the node width;
//! `query.rs` the closest-hit and any-hit queries on it; `stream.rs` the ray
//! streams; `primitive.rs` the ray/primitive tests; `offset.rs` the
//! ray-spawning rule.

#[doc(hidden)]
pub mod brute_force;
mod build;
mod bvh4;
mod bvh8;
mod collapse;
mod leaf;
mod offset;
mod prefetch;
mod primitive;
mod query;
mod stream;
#[cfg(test)]
mod tests;
mod traverse;
mod tree;

#[doc(hidden)]
pub use build::BuildPreset;
pub use offset::{
    offset_ray_origin, offset_ray_origin_with_error, sphere_point, triangle_normal, triangle_point,
    triangle_point_with_normal, SurfacePoint,
};

/// The spawning rules written once over `math::lanes::Vector3`, which the
/// lane kernel runs on eight hits.
pub(crate) use offset::{default_error_of, segment_to, triangle_point_error};
pub use stream::RayStream;

use crate::math::{Ray, Vec2, Vec3};
use crate::scene::{Mesh, Sphere};
use leaf::{Inputs, Leaves, Prim};
use primitive::WatertightRay;
use std::time::{Duration, Instant};
use traverse::Entry;
use tree::Tree;

/// Which primitive a ray hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimRef {
    Triangle { mesh: u32, tri: u32 },
    Sphere(u32),
}

/// The closest hit along a ray.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    pub prim: PrimRef,
    /// Barycentrics (b1, b2) of vertices 1 and 2 for triangles; unused for spheres.
    pub bary: Vec2,
    /// Where the traversal found the triangle: leaf block × 4 + lane, or
    /// [`NO_SLOT`]. A hint, not part of the hit's identity (`==` ignores it):
    /// [`Accel::hit_triangle`] reads the vertices from the block the leaf
    /// test has just loaded instead of through the mesh's index buffer, and
    /// the unit normal and mesh from the lane's build-time record.
    pub(crate) slot: u32,
}

/// [`Hit::slot`] of a hit found outside the leaf blocks.
pub(crate) const NO_SLOT: u32 = u32::MAX;

impl PartialEq for Hit {
    fn eq(&self, o: &Self) -> bool {
        self.t == o.t && self.prim == o.prim && self.bary == o.bary
    }
}

/// The acceleration structure over all shapes of a scene.
pub struct Accel {
    tree: Tree,
    /// The primitives, packed per leaf.
    leaves: Leaves,
    /// SAH cost of the tree, taken before its leaves were packed into blocks.
    sah: f32,
    triangle_count: usize,
    sphere_count: usize,
    rejected: usize,
    bounds: Option<(Vec3, Vec3)>,
    /// See [`Accel::spawn_floor`].
    spawn_floor: f32,
    build_time: Duration,
}

impl Accel {
    /// Builds the BVH over every triangle of `meshes` and every sphere.
    ///
    /// Primitives that cannot be intersected meaningfully are skipped (and counted
    /// in [`Accel::rejected_count`]) instead of failing: triangles with an
    /// out-of-range index or a non-finite vertex, spheres with a non-finite centre
    /// or a radius that is not positive and finite, and any primitive whose box
    /// reaches beyond ±1.3e36 (far past the scene's own limit; see `build.rs`).
    /// Zero-area triangles are kept (the watertight test never reports a hit on
    /// them). Never panics, and stays O(n log n) for coincident boxes.
    pub fn build(meshes: &[Mesh], spheres: &[Sphere]) -> Self {
        Self::build_with_preset(meshes, spheres, &BuildPreset::default())
    }

    /// [`Accel::build`] with other obvhs build parameters (for measuring presets).
    #[doc(hidden)]
    pub fn build_with_preset(meshes: &[Mesh], spheres: &[Sphere], preset: &BuildPreset) -> Self {
        let start = Instant::now();
        let inputs = Inputs::collect(meshes, spheres);
        let (triangle_count, sphere_count) = inputs.counts();
        let bounds = inputs.bounds();
        let mut tree = build::build(&inputs.boxes(), preset);
        let sah = tree.sah_cost(preset.leaf_cost.unwrap_or(1.0));
        let rejected = inputs.rejected;
        let leaves = Leaves::pack(&mut tree, inputs);
        Self {
            tree,
            leaves,
            sah,
            triangle_count,
            sphere_count,
            rejected,
            bounds,
            spawn_floor: bounds.map_or(0.0, spawn_floor),
            build_time: start.elapsed(),
        }
    }

    /// Closest hit with t in [ray.t_min, ray.t_max].
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if !self.traversable(ray) {
            return None;
        }
        let wr = WatertightRay::new(ray.origin, ray.dir);
        query::with_stack(self.tree.stack_size(), |stack| {
            query::closest(
                &self.tree,
                &self.leaves,
                ray,
                &wr,
                stack,
                &mut (0, 0),
                false,
            )
        })
    }

    /// True if anything is hit with t in [ray.t_min, ray.t_max]. Stops at the first
    /// hit found.
    pub fn occluded(&self, ray: &Ray) -> bool {
        if !self.traversable(ray) {
            return false;
        }
        query::with_stack(self.tree.stack_size(), |stack| {
            query::any(&self.tree, &self.leaves, ray, stack, &mut 0)
        })
    }

    /// The least error bound a spawned ray's origin is given (an absolute
    /// distance, the same on every axis), so that it is offset at least this
    /// far off its surface (`offset_ray_origin_with_error` moves it by
    /// `dot(|n|, p_error)` ≥ this for a unit normal); why: the function
    /// `spawn_floor` below.
    pub fn spawn_floor(&self) -> f32 {
        self.spawn_floor
    }

    /// `p_error` raised to [`Accel::spawn_floor`] on every axis: the bound a
    /// ray spawned from a hit of this tree is offset by.
    pub fn spawn_error(&self, p_error: Vec3) -> Vec3 {
        p_error.max(Vec3::splat(self.spawn_floor))
    }

    /// Wall-clock time of [`Accel::build`] (AABBs, BVH build, reordering).
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// Number of triangles in the BVH (rejected ones excluded).
    pub fn triangle_count(&self) -> usize {
        self.triangle_count
    }

    /// Number of spheres in the BVH (rejected ones excluded).
    pub fn sphere_count(&self) -> usize {
        self.sphere_count
    }

    /// Number of primitives in the BVH leaves (triangles + spheres).
    pub fn primitive_count(&self) -> usize {
        self.leaves.len()
    }

    /// Number of input primitives skipped at build time (bad indices, NaN/∞
    /// coordinates, non-positive radii).
    pub fn rejected_count(&self) -> usize {
        self.rejected
    }

    /// Bounding box (min, max) of all primitives; `None` for an empty scene.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.bounds
    }

    /// Depth of the deepest inner node of the tree (root = 0).
    pub fn depth(&self) -> u32 {
        self.tree.depth()
    }

    /// SAH cost of the tree relative to its root box, under the collapse's cost
    /// model (see `Tree::sah_cost`).
    #[doc(hidden)]
    pub fn sah_cost(&self) -> f32 {
        self.sah
    }

    /// Number of inner nodes (4- or 8-wide).
    pub fn node_count(&self) -> usize {
        self.tree.node_count()
    }

    /// Entries of the traversal stack this tree needs: each inner node on the
    /// current path leaves at most W − 1 siblings on it (W = 4 or 8), so a tree of
    /// depth d needs (W − 1)(d + 1) + 1.
    pub fn stack_size(&self) -> usize {
        self.tree.stack_size()
    }

    /// Closest-hit traversal that counts its work: (inner nodes tested, primitives
    /// tested). A load-independent measure of tree quality for comparing builds on
    /// a shared machine.
    #[doc(hidden)]
    pub fn closest_hit_work(&self, ray: &Ray) -> (u32, u32) {
        if !self.traversable(ray) {
            return (0, 0);
        }
        let wr = WatertightRay::new(ray.origin, ray.dir);
        let mut stack = vec![Entry::default(); self.tree.stack_size()];
        let mut work = (0, 0);
        query::closest(
            &self.tree,
            &self.leaves,
            ray,
            &wr,
            &mut stack,
            &mut work,
            true,
        );
        work
    }

    /// Any-hit traversal that counts node tests (see [`Accel::closest_hit_work`]).
    #[doc(hidden)]
    pub fn occluded_work(&self, ray: &Ray) -> u32 {
        if !self.traversable(ray) {
            return 0;
        }
        let mut stack = vec![Entry::default(); self.tree.stack_size()];
        let mut nodes = 0;
        query::any(&self.tree, &self.leaves, ray, &mut stack, &mut nodes);
        nodes
    }

    /// The geometric data of a hit needed to continue a path robustly: the hit
    /// point recomputed from the primitive (barycentric interpolation of the
    /// vertices for triangles, re-projection onto the surface for spheres), its
    /// conservative absolute error bound, and the unit geometric normal
    /// (counter-clockwise winding for triangles, outward for spheres). `None` if the
    /// hit does not refer to a primitive of this BVH.
    pub fn surface_point(&self, ray: &Ray, hit: &Hit) -> Option<SurfacePoint> {
        let mut sp = match *self.leaves.prim(hit.prim)? {
            Prim::Triangle { v, .. } => offset::triangle_point(v, hit.bary),
            Prim::Sphere { center, radius, .. } => {
                offset::sphere_point(center, radius, ray.at(hit.t))
            }
        };
        sp.p_error = self.spawn_error(sp.p_error);
        Some(sp)
    }

    /// The vertices of a triangle hit, from the leaf block where the traversal
    /// found it (the same values as the mesh's, copied at build time), and its
    /// unit geometric normal ([`offset::triangle_normal`], computed at build
    /// time: the same bits as per hit); `None` for spheres, for hits found
    /// outside the blocks (`NO_SLOT`) and for a hit whose slot holds another
    /// primitive (a hit from another `Accel`).
    #[inline]
    pub fn hit_triangle(&self, hit: &Hit) -> Option<([Vec3; 3], Vec3)> {
        self.leaves.hit_triangle(hit)
    }

    /// The hit of `ray` with the one primitive `prim`, by the exact test
    /// [`Accel::intersect`] runs (same t and barycentrics, bit for bit): for a
    /// caller that already knows which primitive the ray sees (the previews find
    /// primary visibility by rasterising, `preview::raster`). `None` when the ray
    /// misses it or `prim` is not in this BVH.
    pub fn intersect_primitive(&self, ray: &Ray, prim: PrimRef) -> Option<Hit> {
        if !ray_is_valid(ray) {
            return None;
        }
        let p = self.leaves.prim(prim)?;
        let wr = WatertightRay::new(ray.origin, ray.dir);
        p.intersect(ray, &wr, ray.t_max)
    }

    fn traversable(&self, ray: &Ray) -> bool {
        self.tree.root() != tree::EMPTY && ray_is_valid(ray)
    }

    /// Whether the stream queries run on this tree: an 8-wide one (AVX2) of
    /// at most 64 inner nodes (`stream::STREAM_MAX_NODES`: where streams stop
    /// paying).
    pub fn streams(&self) -> bool {
        stream::takes(&self.tree)
    }

    /// [`Accel::intersect`] of the `n` rays `ray(0..n)`, answers read with
    /// [`RayStream::hit`]. Where not [`Accel::streams`], the rays are asked
    /// one at a time: the answers are the same, only the speed differs.
    pub fn intersect_stream<'r>(
        &self,
        n: usize,
        ray: impl Fn(usize) -> &'r Ray,
        s: &mut RayStream,
    ) {
        self.query_stream::<false>(n, &ray, s);
    }

    /// [`Accel::occluded`] of the `n` rays `ray(0..n)`, answers read with
    /// [`RayStream::occluded`]; as [`Accel::intersect_stream`], one ray at a
    /// time where not [`Accel::streams`].
    pub fn occluded_stream<'r>(&self, n: usize, ray: impl Fn(usize) -> &'r Ray, s: &mut RayStream) {
        self.query_stream::<true>(n, &ray, s);
    }

    /// The stream traversal where the tree takes it, single-ray queries
    /// written into the stream's answer planes elsewhere.
    fn query_stream<'r, const ANY: bool>(
        &self,
        n: usize,
        ray: &impl Fn(usize) -> &'r Ray,
        s: &mut RayStream,
    ) {
        if self.streams() {
            // SAFETY: an 8-wide tree is only built where AVX2 was detected.
            #[cfg(target_arch = "x86_64")]
            if let Tree::Eight(tree) = &self.tree {
                unsafe { stream::trace::<ANY>(tree, &self.leaves, n, ray, s) };
            }
            return;
        }
        s.set_answers(n, |k| {
            if ANY {
                self.occluded(ray(k)).then_some((0, 0.0, Vec2::ZERO, 0))
            } else {
                self.intersect(ray(k))
                    .map(|h| (self.leaves.input_of(h.prim), h.t, h.bary, h.slot))
            }
        });
    }
}

impl RayStream {
    /// Ray `k`'s closest hit after [`Accel::intersect_stream`].
    pub fn hit(&self, accel: &Accel, k: usize) -> Option<Hit> {
        self.answer(k).map(|(id, t, bary, slot)| Hit {
            t,
            prim: accel.leaves.prim_ref_at(id, slot),
            bary,
            slot,
        })
    }
}

/// [`Accel::spawn_floor`] for a scene within `bounds`: twice the padding of
/// the tree's boxes (`build::box_pad`, 2^-16 of the largest coordinate), so
/// that a ray leaving a flat surface in a coordinate plane at the scene's edge
/// (a room's walls, floor and ceiling) starts outside that surface's padded
/// leaf box and the traversal never opens the leaf it leaves. With pbrt's
/// bound alone (~γ₇ of the coordinates) every such ray started inside it and
/// tested the wall's own triangles for nothing (cornell: −9 % render time,
/// benches/README.md). At most 2^-15 of the scene's extent: far from the
/// origin the padding grows with the coordinates, not the scene's size, and
/// the floor must not (in the render test's scene 10⁴ units away it stays
/// below pbrt's own bound there, and the image is the one at the origin).
fn spawn_floor((lo, hi): (Vec3, Vec3)) -> f32 {
    let magnitude = lo.abs().max(hi.abs()).max_element();
    let extent = (hi - lo).max_element();
    (2.0 * build::box_pad(magnitude)).min(extent * (1.0 / 32_768.0))
}

/// Rays with NaN/∞ origin or direction, a zero direction, a non-finite `t_min` or
/// an empty/NaN interval hit nothing (NaN would defeat the slab test's comparisons).
fn ray_is_valid(ray: &Ray) -> bool {
    ray.origin.is_finite()
        && ray.dir.is_finite()
        && ray.dir != Vec3::ZERO
        && ray.t_min.is_finite()
        && !ray.t_max.is_nan()
        && ray.t_min <= ray.t_max
}
