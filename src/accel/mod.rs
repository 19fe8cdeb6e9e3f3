//! Triangles + exact spheres → one wide BVH answering closest-hit and any-hit
//! (shadow) queries.
//!
//! One BVH holds every primitive of the scene: the build only sees per-primitive
//! AABBs (a mix of triangle and sphere boxes), and traversal calls our own
//! intersection routine per primitive (`primitive.rs`), so spheres stay exact
//! analytic spheres and triangles use the watertight test.
//!
//! obvhs builds the tree (PLOC + reinsertion, `build.rs`); we collapse it into
//! our own uncompressed wide BVH at least SAH cost (`bvh4::SahCollapse`, the
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

mod build;
mod bvh4;
mod bvh8;
mod offset;
mod primitive;
mod stream;

#[doc(hidden)]
pub use build::BuildPreset;
pub use offset::{
    offset_ray_origin, offset_ray_origin_with_error, sphere_point, triangle_normal, triangle_point,
    triangle_point_with_normal, SurfacePoint,
};

pub(crate) use offset::{DEFAULT_REL_ERROR, SHADOW_EPSILON};
/// pbrt's γ(n), the bound on n rounded f32 operations (the error bounds'
/// constant, for the lane shading's copy of `triangle_point_with_normal`).
pub(crate) use primitive::gamma as gamma_bound;
pub use stream::RayStream;

use crate::math::{Ray, Vec2, Vec3};
use crate::scene::{Mesh, Sphere};
use bvh4::{BoxRay, Bvh, Bvh4, Entry, WideNode};
use bvh8::Bvh8;
use glam::Vec4;
use obvhs::aabb::Aabb;
use primitive::{intersect_sphere, Tri4, WatertightRay, WatertightRay4};
use std::cell::RefCell;
use std::time::{Duration, Instant};

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

/// The one mesh with triangles, if only one has any (`mesh_first`: each
/// mesh's first input index, then the first sphere's).
fn only_mesh(mesh_first: &[u32]) -> Option<u32> {
    let mut with_triangles = mesh_first
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[1] > w[0]);
    match (with_triangles.next(), with_triangles.next()) {
        (Some((m, _)), None) => Some(m as u32),
        _ => None,
    }
}

/// A block lane's triangle as a hit needs it beyond its vertices, in one
/// 16-byte record: its unit geometric normal (instead of a cross product,
/// square root and division per hit, on the path's critical chain) and its
/// mesh (instead of a binary search of `mesh_first` per closest hit), which
/// the interaction reads moments after the hit is formed: one cache line for
/// both.
#[derive(Clone, Copy, Debug)]
struct LaneRecord(Vec4);

impl LaneRecord {
    fn new(n: Vec3, mesh: u32) -> Self {
        Self(n.extend(f32::from_bits(mesh)))
    }

    /// The normal with w zeroed: the mesh's bits read as a float are a
    /// denormal, and one in a `Vec3A`'s hidden lane made every vector
    /// operation on it take a microcode assist (+26 % on cornell).
    #[inline(always)]
    fn normal(self) -> Vec3 {
        Vec3::from_vec4(self.0.with_w(0.0))
    }

    #[inline(always)]
    fn mesh(self) -> u32 {
        self.0.w.to_bits()
    }
}

/// [`Hit::slot`] of a hit found outside the leaf blocks.
pub(crate) const NO_SLOT: u32 = u32::MAX;

impl PartialEq for Hit {
    fn eq(&self, o: &Self) -> bool {
        self.t == o.t && self.prim == o.prim && self.bary == o.bary
    }
}

/// One primitive, stored in BVH leaf order so that the traversal callback reads
/// memory sequentially instead of going through `primitive_indices`.
#[derive(Clone, Copy, Debug)]
enum Prim {
    Triangle { v: [Vec3; 3], mesh: u32, tri: u32 },
    Sphere { center: Vec3, radius: f32, id: u32 },
}

impl Prim {
    fn prim_ref(&self) -> PrimRef {
        match *self {
            Prim::Triangle { mesh, tri, .. } => PrimRef::Triangle { mesh, tri },
            Prim::Sphere { id, .. } => PrimRef::Sphere(id),
        }
    }

    /// The exact intersection with `t` in `[t_min, t_max]`.
    #[inline(always)]
    fn intersect(&self, ray: &Ray, wr: &WatertightRay, t_max: f32) -> Option<Hit> {
        match *self {
            Prim::Triangle { v, mesh, tri } => wr
                .intersect(v[0], v[1], v[2], ray.t_min, t_max)
                .map(|(t, b1, b2)| Hit {
                    t,
                    prim: PrimRef::Triangle { mesh, tri },
                    bary: Vec2::new(b1, b2),
                    slot: NO_SLOT,
                }),
            Prim::Sphere { center, radius, id } => {
                intersect_sphere(ray.origin, ray.dir, center, radius, ray.t_min, t_max).map(|t| {
                    Hit {
                        t,
                        prim: PrimRef::Sphere(id),
                        bary: Vec2::ZERO,
                        slot: NO_SLOT,
                    }
                })
            }
        }
    }
}

/// Up to four consecutive primitives of one leaf: their triangles in SoA
/// layout for the 4-wide watertight test, and each lane's primitive by its
/// input index (triangles of mesh 0, mesh 1, …, then spheres; [`EMPTY_LANE`]
/// for none). The input index is all a hit needs — its [`PrimRef`] and the
/// tie-break order — so the closest hit never reads `prims`, a cache miss
/// that was 13 % of an incoherent closest-hit query (perf, bunny); spheres
/// and edge fallbacks, which the scalar test decides, look their slot up.
/// A leaf of up to 8 primitives is one or two blocks; its tree reference holds
/// the first block and a [`LeafCode`].
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
struct LeafBlock {
    tris: Tri4,
    ids: [u32; 4],
}

const EMPTY_LANE: u32 = u32::MAX;

/// Leaf blocks from this many bytes on are prefetched when pushed (about an L2
/// cache): on the bunny (megabytes of blocks) +6–10 % incoherent rays/s; on
/// the Cornell box (36 triangles, all in L1) the prefetches were 5.5 % more
/// instructions per closest-hit query and bought nothing.
const PREFETCH_LEAVES_FROM: usize = 1 << 20;

/// A leaf's `count` field once it refers to blocks: 1 + (blocks − 1) + 2 ×
/// (some lane is a sphere), in the 1..=8 the BVH4 encoding holds.
struct LeafCode;

impl LeafCode {
    fn encode(blocks: usize, spheres: bool) -> usize {
        blocks + 2 * spheres as usize
    }

    #[inline(always)]
    fn decode(code: usize) -> (usize, bool) {
        (1 + ((code - 1) & 1), (code - 1) & 2 != 0)
    }
}

impl LeafBlock {
    /// The lanes holding a sphere, i.e. an input index from `first_sphere`
    /// on (only looked at in leaves that have one).
    #[inline(always)]
    fn sphere_lanes(&self, first_sphere: u32) -> u32 {
        let mut mask = 0;
        for (lane, &id) in self.ids.iter().enumerate() {
            if id != EMPTY_LANE && id >= first_sphere {
                mask |= 1 << lane;
            }
        }
        mask
    }

    fn primitive_count(&self) -> u32 {
        self.ids.iter().filter(|&&s| s != EMPTY_LANE).count() as u32
    }
}

/// Packs each leaf's primitives (`prims[first..first + count]`, whose input
/// indices are `input_of_slot[first..first + count]`) into blocks and points
/// the leaf at them.
fn pack_leaves<N: WideNode>(
    bvh: &mut Bvh<N>,
    prims: &[Prim],
    input_of_slot: &[u32],
) -> Vec<LeafBlock> {
    let mut blocks = Vec::new();
    bvh.remap_leaves(|first, count| {
        let start = blocks.len();
        let mut spheres = false;
        for chunk in (first..first + count).collect::<Vec<_>>().chunks(4) {
            let mut lanes = [None; 4];
            let mut ids = [EMPTY_LANE; 4];
            for (lane, &slot) in chunk.iter().enumerate() {
                ids[lane] = input_of_slot[slot];
                match prims[slot] {
                    Prim::Triangle { v, .. } => lanes[lane] = Some(v),
                    Prim::Sphere { .. } => spheres = true,
                }
            }
            blocks.push(LeafBlock {
                tris: Tri4::new(lanes),
                ids,
            });
        }
        (start, LeafCode::encode(blocks.len() - start, spheres))
    });
    blocks
}

/// The traversal tree: 8-wide where the CPU has AVX2 (`bvh8.rs`), else 4-wide.
enum Tree {
    Four(Bvh4),
    Eight(Bvh8),
}

/// `tree.traverse::<SORTED>(args)` on either width.
macro_rules! traverse {
    ($tree:expr, $sorted:literal, $($arg:expr),* $(,)?) => {
        match $tree {
            Tree::Four(t) => t.traverse::<$sorted>($($arg),*),
            #[cfg(target_arch = "x86_64")]
            // SAFETY: an 8-wide tree is only built when `bvh8::supported()`.
            // (The leaf callback's own `unsafe` blocks are needed in the 4-wide
            // arm, and redundant here.)
            Tree::Eight(t) => {
                #[allow(unused_unsafe)]
                unsafe { t.traverse::<$sorted>($($arg),*) }
            }
            #[cfg(not(target_arch = "x86_64"))]
            Tree::Eight(_) => unreachable!("8-wide trees need x86_64"),
        }
    };
}

impl Tree {
    fn root(&self) -> u32 {
        match self {
            Tree::Four(t) => t.root,
            Tree::Eight(t) => t.root,
        }
    }

    fn depth(&self) -> u32 {
        match self {
            Tree::Four(t) => t.depth,
            Tree::Eight(t) => t.depth,
        }
    }

    fn node_count(&self) -> usize {
        match self {
            Tree::Four(t) => t.nodes.len(),
            Tree::Eight(t) => t.nodes.len(),
        }
    }

    fn stack_size(&self) -> usize {
        match self {
            Tree::Four(t) => t.stack_size(),
            Tree::Eight(t) => t.stack_size(),
        }
    }

    fn leaf_order(&self) -> &[u32] {
        match self {
            Tree::Four(t) => &t.leaf_order,
            Tree::Eight(t) => &t.leaf_order,
        }
    }

    /// The SAH cost under the collapse's own model (`bvh4::leaf_test_cost`, one
    /// block of four primitives = `leaf_cost` node tests), so that trees built
    /// with different collapses compare by the cost the builder minimised.
    fn sah_cost(&self, leaf_cost: f32) -> f32 {
        (match self {
            Tree::Four(t) => t.sah_cost(leaf_cost),
            Tree::Eight(t) => t.sah_cost(leaf_cost),
        }) as f32
    }

    /// Whether leaves of two blocks are tested as one eight-lane block
    /// (`primitive::avx`): in the 8-wide tree, which is only built with AVX2.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn eight_lane_leaves(&self) -> bool {
        matches!(self, Tree::Eight(_))
    }

    fn pack_leaves(&mut self, prims: &[Prim], input_of_slot: &[u32]) -> Vec<LeafBlock> {
        match self {
            Tree::Four(t) => pack_leaves(t, prims, input_of_slot),
            Tree::Eight(t) => pack_leaves(t, prims, input_of_slot),
        }
    }
}

/// The node test's view of a ray, and the shift `back_off` between its
/// distances and the primitive tests' (node distance = t + back_off).
///
/// Rays with `t_min ≥ 0` are tested as they are. For `t_min < 0` (hits behind
/// the origin are legal) the node ray's origin is moved back by |t_min| plus a
/// margin (2e-4 plus enough ulps of the origin that the shift survives
/// rounding), so that its interval starts at 0, where the slab distances keep
/// their sign.
#[inline(always)]
fn node_ray(ray: &Ray) -> (BoxRay, f32) {
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

/// The acceleration structure over all shapes of a scene.
pub struct Accel {
    bvh: Tree,
    /// The leaves' primitives as the traversal tests them (see [`LeafBlock`]).
    blocks: Vec<LeafBlock>,
    /// Each block lane's [`LaneRecord`], index block × 4 + lane like [`Hit::slot`].
    lanes: Vec<LaneRecord>,
    /// Whether the traversal prefetches the leaves it pushes (`blocks` larger
    /// than [`PREFETCH_LEAVES_FROM`]).
    prefetch_leaves: bool,
    /// SAH cost of the tree, taken before its leaves were packed into blocks.
    sah: f32,
    /// Primitives in BVH leaf order (`prims[i]` is leaf slot `i`).
    prims: Vec<Prim>,
    /// For a primitive in input order (triangles of mesh 0, mesh 1, …, then spheres),
    /// its slot in `prims`, or `u32::MAX` when it was rejected at build time.
    slot_of_input: Vec<u32>,
    /// Index in input order of the first triangle of each mesh; one extra entry
    /// gives the index of the first sphere.
    mesh_first: Vec<u32>,
    /// `mesh_first`'s last entry: input indices from here on are spheres.
    first_sphere: u32,
    /// The mesh holding every triangle, when one does: its closest hits skip
    /// the lane record's read, which costs a query that is not followed by an
    /// interaction (the `accel` bench's incoherent rays on the bunny: −9 %).
    only_mesh: Option<u32>,
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
        let mut inputs: Vec<(Prim, Aabb)> = Vec::new();
        let mut mesh_first = Vec::with_capacity(meshes.len() + 1);
        let mut input_count: u32 = 0;
        let mut input_index: Vec<u32> = Vec::new();
        let mut rejected = 0usize;
        for (mi, mesh) in meshes.iter().enumerate() {
            mesh_first.push(input_count);
            for (ti, idx) in mesh.triangles.iter().enumerate() {
                let this = input_count;
                input_count += 1;
                let v = idx.map(|i| mesh.positions.get(i as usize).copied());
                let (Some(a), Some(b), Some(c)) = (v[0], v[1], v[2]) else {
                    rejected += 1;
                    continue;
                };
                let aabb = Aabb::new(a.min(b).min(c), a.max(b).max(c));
                if !(a.is_finite() && b.is_finite() && c.is_finite() && box_is_buildable(&aabb)) {
                    rejected += 1;
                    continue;
                }
                inputs.push((
                    Prim::Triangle {
                        v: [a, b, c],
                        mesh: mi as u32,
                        tri: ti as u32,
                    },
                    aabb,
                ));
                input_index.push(this);
            }
        }
        mesh_first.push(input_count);
        for (si, s) in spheres.iter().enumerate() {
            let this = input_count;
            input_count += 1;
            let r = Vec3::splat(s.radius);
            let aabb = Aabb::new(s.center - r, s.center + r);
            if !(s.center.is_finite() && s.radius > 0.0 && box_is_buildable(&aabb)) {
                rejected += 1;
                continue;
            }
            inputs.push((
                Prim::Sphere {
                    center: s.center,
                    radius: s.radius,
                    id: si as u32,
                },
                aabb,
            ));
            input_index.push(this);
        }

        if inputs.len() > bvh4::MAX_PRIMITIVES {
            rejected += inputs.len() - bvh4::MAX_PRIMITIVES;
            inputs.truncate(bvh4::MAX_PRIMITIVES);
            input_index.truncate(bvh4::MAX_PRIMITIVES);
        }
        let triangle_count = inputs
            .iter()
            .filter(|(p, _)| matches!(p, Prim::Triangle { .. }))
            .count();
        let sphere_count = inputs.len() - triangle_count;

        let mut bounds_box = Aabb::empty();
        for (_, b) in &inputs {
            bounds_box = bounds_box.union(b);
        }
        let bounds = (!inputs.is_empty()).then_some((bounds_box.min, bounds_box.max));
        let aabbs: Vec<Aabb> = inputs.iter().map(|(_, b)| *b).collect();
        let mut bvh = if preset.node_width == 8 && bvh8::supported() {
            Tree::Eight(build::build_tree(&aabbs, preset))
        } else {
            Tree::Four(build::build_tree(&aabbs, preset))
        };

        // Reorder primitives to leaf order and build the input → slot table.
        let mut slot_of_input = vec![u32::MAX; input_count as usize];
        let prims: Vec<Prim> = bvh
            .leaf_order()
            .iter()
            .enumerate()
            .map(|(slot, &pi)| {
                slot_of_input[input_index[pi as usize] as usize] = slot as u32;
                inputs[pi as usize].0
            })
            .collect();
        let input_of_slot: Vec<u32> = bvh
            .leaf_order()
            .iter()
            .map(|&pi| input_index[pi as usize])
            .collect();
        let sah = bvh.sah_cost(preset.leaf_cost.unwrap_or(1.0));
        let blocks = bvh.pack_leaves(&prims, &input_of_slot);
        let lanes = blocks
            .iter()
            .flat_map(|b| {
                // A lane's primitive as `prim_of_input` finds it (none for an empty lane).
                let prim = |id: u32| prims.get(*slot_of_input.get(id as usize)? as usize);
                b.ids.map(|id| match prim(id) {
                    Some(&Prim::Triangle { v, mesh, .. }) => {
                        LaneRecord::new(offset::triangle_normal(v), mesh)
                    }
                    _ => LaneRecord::new(Vec3::ZERO, 0),
                })
            })
            .collect();

        Self {
            bvh,
            prefetch_leaves: std::mem::size_of_val(blocks.as_slice()) >= PREFETCH_LEAVES_FROM,
            blocks,
            lanes,
            sah,
            prims,
            slot_of_input,
            first_sphere: *mesh_first.last().unwrap_or(&0),
            only_mesh: only_mesh(&mesh_first),
            mesh_first,
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
        with_stack(self.bvh.stack_size(), |stack| {
            self.closest_with(ray, &wr, stack, &mut (0, 0), false)
        })
    }

    /// True if anything is hit with t in [ray.t_min, ray.t_max]. Stops at the first
    /// hit found.
    pub fn occluded(&self, ray: &Ray) -> bool {
        if !self.traversable(ray) {
            return false;
        }
        with_stack(self.bvh.stack_size(), |stack| {
            self.any_with(ray, stack, &mut 0)
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
        self.prims.len()
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
        self.bvh.depth()
    }

    /// SAH cost of the tree relative to its root box, under the collapse's cost
    /// model (see `Tree::sah_cost`).
    #[doc(hidden)]
    pub fn sah_cost(&self) -> f32 {
        self.sah
    }

    /// Number of inner nodes (4- or 8-wide).
    pub fn node_count(&self) -> usize {
        self.bvh.node_count()
    }

    /// Entries of the traversal stack this tree needs: each inner node on the
    /// current path leaves at most W − 1 siblings on it (W = 4 or 8), so a tree of
    /// depth d needs (W − 1)(d + 1) + 1.
    pub fn stack_size(&self) -> usize {
        self.bvh.stack_size()
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
        let mut stack = vec![Entry::default(); self.bvh.stack_size()];
        let mut work = (0, 0);
        self.closest_with(ray, &wr, &mut stack, &mut work, true);
        work
    }

    /// Any-hit traversal that counts BVH4 node tests (see [`Accel::closest_hit_work`]).
    #[doc(hidden)]
    pub fn occluded_work(&self, ray: &Ray) -> u32 {
        if !self.traversable(ray) {
            return 0;
        }
        let mut stack = vec![Entry::default(); self.bvh.stack_size()];
        let mut nodes = 0;
        self.any_with(ray, &mut stack, &mut nodes);
        nodes
    }

    /// Reference closest hit: every primitive is tested, no BVH. For tests and
    /// debugging; uses the same primitive routines as [`Accel::intersect`].
    pub fn intersect_brute_force(&self, ray: &Ray) -> Option<Hit> {
        if !ray_is_valid(ray) {
            return None;
        }
        let wr = WatertightRay::new(ray.origin, ray.dir);
        self.closest_brute_force(ray, &wr)
    }

    fn closest_brute_force(&self, ray: &Ray, wr: &WatertightRay) -> Option<Hit> {
        let mut best: Option<(u32, Hit)> = None;
        for p in &self.prims {
            let t_max = best.map_or(ray.t_max, |(_, h)| h.t);
            if let Some(h) = p.intersect(ray, wr, t_max) {
                let id = self.input_of(p.prim_ref());
                if nearer(h.t, id, best.map(|(b, bh)| (bh.t, b))) {
                    best = Some((id, h));
                }
            }
        }
        best.map(|(_, h)| h)
    }

    /// Starts loading the blocks of the leaf `(first, code)` (a hint), when
    /// the blocks are too many to stay in cache ([`PREFETCH_LEAVES_FROM`]).
    #[inline(always)]
    fn prefetch_leaf(&self, first: usize, code: usize) {
        if !self.prefetch_leaves {
            return;
        }
        let (count, _) = LeafCode::decode(code);
        // SAFETY: the leaf's blocks are `blocks[first..first + count]`.
        unsafe { prefetch_lines(self.blocks.as_ptr().add(first), count) }
    }

    /// The input index of a primitive: triangles of mesh 0, mesh 1, …, then
    /// spheres (`prim` must be in this BVH).
    fn input_of(&self, prim: PrimRef) -> u32 {
        match prim {
            PrimRef::Triangle { mesh, tri } => self.mesh_first[mesh as usize] + tri,
            PrimRef::Sphere(s) => self.first_sphere + s,
        }
    }

    /// [`Accel::input_of`] inverted, for the primitive in block lane `slot`:
    /// a triangle's mesh read from the lane's record.
    #[inline(always)]
    fn prim_ref_at(&self, id: u32, slot: u32) -> PrimRef {
        if id >= self.first_sphere {
            return PrimRef::Sphere(id - self.first_sphere);
        }
        let mesh = self
            .only_mesh
            .unwrap_or_else(|| self.lanes[slot as usize].mesh());
        PrimRef::Triangle {
            mesh,
            tri: id - self.mesh_first[mesh as usize],
        }
    }

    /// The stored primitive with input index `id` (one in a leaf block).
    #[inline(always)]
    fn prim_of_input(&self, id: u32) -> &Prim {
        &self.prims[self.slot_of_input[id as usize] as usize]
    }

    /// Reference any-hit: every primitive is tested, no BVH.
    pub fn occluded_brute_force(&self, ray: &Ray) -> bool {
        if !ray_is_valid(ray) {
            return false;
        }
        let wr = WatertightRay::new(ray.origin, ray.dir);
        self.any_brute_force(ray, &wr)
    }

    fn any_brute_force(&self, ray: &Ray, wr: &WatertightRay) -> bool {
        self.prims
            .iter()
            .any(|p| p.intersect(ray, wr, ray.t_max).is_some())
    }

    /// The geometric data of a hit needed to continue a path robustly: the hit
    /// point recomputed from the primitive (barycentric interpolation of the
    /// vertices for triangles, re-projection onto the surface for spheres), its
    /// conservative absolute error bound, and the unit geometric normal
    /// (counter-clockwise winding for triangles, outward for spheres). `None` if the
    /// hit does not refer to a primitive of this BVH.
    pub fn surface_point(&self, ray: &Ray, hit: &Hit) -> Option<SurfacePoint> {
        let mut sp = match *self.prim(hit.prim)? {
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
        if !matches!(hit.prim, PrimRef::Triangle { .. }) {
            return None;
        }
        let block = self.blocks.get((hit.slot / 4) as usize)?;
        let lane = (hit.slot % 4) as usize;
        (block.ids[lane] == self.checked_input_of(hit.prim)?).then(|| {
            (
                block.tris.lane(lane),
                self.lanes[hit.slot as usize].normal(),
            )
        })
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
        let p = self.prim(prim)?;
        let wr = WatertightRay::new(ray.origin, ray.dir);
        p.intersect(ray, &wr, ray.t_max)
    }

    /// The stored primitive of a [`PrimRef`], `None` when out of range or rejected.
    fn prim(&self, prim: PrimRef) -> Option<&Prim> {
        let input = self.checked_input_of(prim)?;
        let slot = *self.slot_of_input.get(input as usize)?;
        self.prims.get(slot as usize)
    }

    /// [`Accel::input_of`] for a `PrimRef` that may not be of this BVH:
    /// `None` when its mesh or index is out of range.
    #[inline]
    fn checked_input_of(&self, prim: PrimRef) -> Option<u32> {
        match prim {
            PrimRef::Triangle { mesh, tri } => {
                let first = *self.mesh_first.get(mesh as usize)?;
                let end = *self.mesh_first.get(mesh as usize + 1)?;
                let i = first.checked_add(tri)?;
                (i < end).then_some(i)
            }
            PrimRef::Sphere(s) => self.mesh_first.last()?.checked_add(s),
        }
    }

    fn traversable(&self, ray: &Ray) -> bool {
        self.bvh.root() != bvh4::EMPTY && ray_is_valid(ray)
    }

    /// Closest hit; `work` counts (node tests, primitive tests), the latter
    /// only with `count_prims` (counting reads each block's ids, a cache line
    /// a query without a hit need not load).
    #[inline(always)]
    fn closest_with(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        stack: &mut [Entry],
        work: &mut (u32, u32),
        count_prims: bool,
    ) -> Option<Hit> {
        let (node_ray, back_off) = node_ray(ray);
        let wr4 = WatertightRay4::new(wr);
        #[cfg(target_arch = "x86_64")]
        let eight_lanes = self.bvh.eight_lane_leaves();
        // (input index, t, (b1, b2), slot) of the nearest hit so far.
        let mut best: Option<(u32, f32, Vec2, u32)> = None;
        let mut t_max = ray.t_max;
        let mut prims_tested = 0;
        traverse!(
            &self.bvh,
            true,
            &node_ray,
            t_max + back_off,
            stack,
            &mut work.0,
            |first, code| {
                let (count, spheres) = LeafCode::decode(code);
                let blocks = &self.blocks[first..first + count];
                #[cfg(target_arch = "x86_64")]
                if eight_lanes && count == 2 {
                    if count_prims {
                        prims_tested += blocks[0].primitive_count() + blocks[1].primitive_count();
                    }
                    // SAFETY: eight-lane leaves only in an 8-wide (AVX2) tree.
                    let (h, scalar) =
                        unsafe { self.leaf8::<false>(wr, blocks, spheres, ray.t_min, t_max) };
                    self.take_lanes(
                        ray,
                        wr,
                        (h.hits | scalar, h.hits),
                        (&h.t, &h.b1, &h.b2),
                        |lane| blocks[lane >> 2].ids[lane & 3],
                        4 * first as u32,
                        &mut t_max,
                        &mut best,
                    );
                    return Some(t_max + back_off);
                }
                for (i, block) in blocks.iter().enumerate() {
                    if count_prims {
                        prims_tested += block.primitive_count();
                    }
                    let h = wr4.intersect::<false>(&block.tris, ray.t_min, t_max);
                    let mut lanes = h.hits | h.fallback;
                    if spheres {
                        lanes |= block.sphere_lanes(self.first_sphere);
                    }
                    if lanes == 0 {
                        continue;
                    }
                    let (ts, b1, b2) = (h.t.to_array(), h.b1.to_array(), h.b2.to_array());
                    let id = |lane: usize| block.ids[lane];
                    self.take_lanes(
                        ray,
                        wr,
                        (lanes, h.hits),
                        (&ts, &b1, &b2),
                        id,
                        4 * (first + i) as u32,
                        &mut t_max,
                        &mut best,
                    );
                }
                Some(t_max + back_off)
            },
            |first, code| self.prefetch_leaf(first, code),
        );
        work.1 += prims_tested;
        best.map(|(id, t, bary, slot)| Hit {
            t,
            prim: self.prim_ref_at(id, slot),
            bary,
            slot,
        })
    }

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

    /// Any hit. The triangle test's set-up ([`WatertightRay`] and its splats)
    /// is made when the traversal opens its first leaf: most shadow rays open
    /// none (0.46 leaves per ray on cornell; −1 to −3 % render time there). A
    /// closest-hit query nearly always opens one, and made lazily there it
    /// bought nothing (benches/README.md, levers).
    #[inline(always)]
    fn any_with(&self, ray: &Ray, stack: &mut [Entry], nodes: &mut u32) -> bool {
        let (node_ray, back_off) = node_ray(ray);
        let mut leaf_ray: Option<(WatertightRay, WatertightRay4)> = None;
        #[cfg(target_arch = "x86_64")]
        let eight_lanes = self.bvh.eight_lane_leaves();
        let mut hit = false;
        traverse!(
            &self.bvh,
            false,
            &node_ray,
            ray.t_max + back_off,
            stack,
            nodes,
            |first, code| {
                let (count, spheres) = LeafCode::decode(code);
                let blocks = &self.blocks[first..first + count];
                let (wr, wr4) = &*leaf_ray.get_or_insert_with(|| {
                    let wr = WatertightRay::new(ray.origin, ray.dir);
                    let wr4 = WatertightRay4::new(&wr);
                    (wr, wr4)
                });
                #[cfg(target_arch = "x86_64")]
                if eight_lanes && count == 2 {
                    // SAFETY: eight-lane leaves only in an 8-wide (AVX2) tree.
                    let (h, scalar) =
                        unsafe { self.leaf8::<true>(wr, blocks, spheres, ray.t_min, ray.t_max) };
                    hit = h.hits != 0
                        || self.scalar_hit(ray, wr, scalar, |lane| blocks[lane >> 2].ids[lane & 3]);
                    return (!hit).then_some(f32::INFINITY);
                }
                for block in blocks {
                    let h = wr4.intersect::<true>(&block.tris, ray.t_min, ray.t_max);
                    let mut lanes = h.fallback;
                    if spheres {
                        lanes |= block.sphere_lanes(self.first_sphere);
                    }
                    hit = h.hits != 0 || self.scalar_hit(ray, wr, lanes, |lane| block.ids[lane]);
                    if hit {
                        return None;
                    }
                }
                Some(f32::INFINITY)
            },
            |first, code| self.prefetch_leaf(first, code),
        );
        hit
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

/// Whether a hit at distance `t` on the primitive with input index `id`
/// replaces `best` (its distance and input index; the caller has already
/// bounded `t` by it): nearer, or as near and earlier in input order
/// (triangles of mesh 0, mesh 1, …, then spheres), so that ties do not depend
/// on the order the tree visits leaves.
#[inline(always)]
fn nearer(t: f32, id: u32, best: Option<(f32, u32)>) -> bool {
    best.is_none_or(|(best_t, best_id)| t < best_t || (t == best_t && id < best_id))
}

thread_local! {
    /// Each thread's traversal stack, grown to the deepest tree it has
    /// traversed: no per-query allocation or zeroing (a 64-entry array on the
    /// call stack cost a 512-byte memset per query, ~5% of a query's instructions).
    static STACK: RefCell<Vec<Entry>> = const { RefCell::new(Vec::new()) };
}

/// Runs `f` on this thread's traversal stack with at least `size` entries.
#[inline(always)]
fn with_stack<R>(size: usize, f: impl FnOnce(&mut [Entry]) -> R) -> R {
    STACK.with_borrow_mut(|stack| {
        if stack.len() < size {
            stack.resize(size, Entry::default());
        }
        f(stack)
    })
}

/// Whether a primitive's box is finite and within [`build::MAX_BUILD_MAGNITUDE`]
/// (the box of finite inputs: glam's min/max skip NaN, so check those first).
fn box_is_buildable(b: &Aabb) -> bool {
    let m = b.min.abs().max(b.max.abs()).max_element();
    m.is_finite() && m <= build::MAX_BUILD_MAGNITUDE
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

/// Starts loading every cache line of `items[0..n]` (a hint; a no-op on other
/// architectures). A plain counted loop: `step_by` costs a division per call.
///
/// # Safety
/// `p..p + n` must lie inside one allocation (a prefetch never faults, but the
/// pointer arithmetic must stay in bounds).
#[inline(always)]
unsafe fn prefetch_lines<T>(p: *const T, n: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let (p, bytes) = (p as *const i8, n * std::mem::size_of::<T>());
        let mut line = 0;
        while line < bytes {
            _mm_prefetch::<_MM_HINT_T0>(p.add(line));
            line += 64;
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (p, n);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Uniform f32s in [0, 1) from a 64-bit LCG: test data reproducible without a
    /// dependency.
    pub(super) fn lcg(mut seed: u64) -> impl FnMut() -> f32 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / 16_777_216.0
        }
    }

    /// A closed, finely tessellated sphere (shared edges and vertices), a
    /// heap of small overlapping quads, and analytic spheres.
    fn scene() -> (Vec<Mesh>, Vec<Sphere>) {
        let globe = globe(40, 60);
        let mut next = lcg(7);
        let mut quads = Mesh {
            name: "quads".into(),
            ..Default::default()
        };
        add_quads(&mut quads, 500, 0.3, &mut next);
        let spheres = (0..20)
            .map(|k| Sphere {
                name: format!("s{k}"),
                center: Vec3::new(next() * 4.0 - 2.0, next() * 4.0 - 2.0, next() * 4.0 - 2.0),
                radius: 0.05 + 0.2 * next(),
                material: 0,
                emission: Vec3::ZERO,
                bump: None,
                object_id: 0,
            })
            .collect();
        (vec![globe, quads], spheres)
    }

    /// The 8-wide and 4-wide trees (leaves of 1 to 8 primitives, so one or
    /// two triangle4 blocks with sphere lanes; greedy and SAH collapse) find
    /// closest hits bit-identical in distances and barycentrics and the same
    /// occlusion as brute force.
    #[test]
    fn node_widths_and_leaf_sizes_agree_with_brute_force() {
        let (meshes, spheres) = scene();
        let mut next = lcg(11);
        let rays: Vec<Ray> = (0..3000)
            .map(|_| {
                let o = Vec3::new(next(), next(), next()) * 6.0 - 3.0;
                let d = Vec3::new(next(), next(), next()) * 2.0 - 1.0;
                Ray::new(o, d.normalize_or(Vec3::X))
            })
            .collect();
        let widths: &[usize] = if bvh8::supported() { &[4, 8] } else { &[4] };
        let mut hits = 0;
        for &node_width in widths {
            for (max_prims_per_leaf, leaf_cost) in [1, 4, 8]
                .into_iter()
                .flat_map(|m| [(m, None), (m, Some(1.0))])
            {
                let preset = BuildPreset {
                    node_width,
                    max_prims_per_leaf,
                    leaf_cost,
                    ..BuildPreset::default()
                };
                let accel = Accel::build_with_preset(&meshes, &spheres, &preset);
                assert_eq!(matches!(accel.bvh, Tree::Eight(_)), node_width == 8);
                for ray in &rays {
                    let (a, b) = (accel.intersect(ray), accel.intersect_brute_force(ray));
                    assert_eq!(
                        a.map(|h| h.t.to_bits()),
                        b.map(|h| h.t.to_bits()),
                        "{ray:?}"
                    );
                    if let (Some(a), Some(b)) = (a, b) {
                        // Another primitive only on an exact tie (a shared edge).
                        if a.prim == b.prim {
                            assert_eq!(a.bary, b.bary, "{ray:?}");
                        }
                        hits += 1;
                    }
                    assert_eq!(
                        accel.occluded(ray),
                        accel.occluded_brute_force(ray),
                        "{ray:?}"
                    );
                }
            }
        }
        assert!(hits > 1000, "{hits}");
    }

    /// A closed unit sphere of `rings` × `segments` quads, each two
    /// triangles sharing their edges and vertices with their neighbours.
    pub(super) fn globe(rings: u32, segments: u32) -> Mesh {
        let mut positions = Vec::new();
        for i in 0..=rings {
            let theta = std::f32::consts::PI * i as f32 / rings as f32;
            for j in 0..segments {
                let phi = std::f32::consts::TAU * j as f32 / segments as f32;
                positions.push(Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                ));
            }
        }
        let mut triangles = Vec::new();
        for i in 0..rings {
            for j in 0..segments {
                let (a, b) = (i * segments + j, i * segments + (j + 1) % segments);
                let (c, d) = (a + segments, b + segments);
                triangles.push([a, b, d]);
                triangles.push([a, d, c]);
            }
        }
        Mesh {
            name: "globe".into(),
            positions,
            triangles,
            ..Default::default()
        }
    }

    /// `count` quads (two triangles each) of edges up to `size` at random
    /// in [−2, 2]³.
    pub(super) fn add_quads(
        mesh: &mut Mesh,
        count: usize,
        size: f32,
        next: &mut impl FnMut() -> f32,
    ) {
        for _ in 0..count {
            let o = Vec3::new(next() * 4.0 - 2.0, next() * 4.0 - 2.0, next() * 4.0 - 2.0);
            let (u, v) = (
                Vec3::new(next(), 0.0, next()) * size,
                Vec3::new(0.0, next(), next()) * size,
            );
            let base = mesh.positions.len() as u32;
            mesh.positions.extend([o, o + u, o + u + v, o + v]);
            mesh.triangles.push([base, base + 1, base + 2]);
            mesh.triangles.push([base, base + 2, base + 3]);
        }
    }
}
