//! Triangles + exact spheres → one obvhs CWBVH answering closest-hit and any-hit
//! (shadow) queries.
//!
//! One BVH holds every primitive of the scene: the build only sees per-primitive
//! AABBs (a mix of triangle and sphere boxes), and traversal calls our own
//! intersection routine per primitive (`primitive.rs`), so spheres stay exact
//! analytic spheres and triangles use the watertight test.
//!
//! obvhs 0.4 pitfalls and where they are handled:
//! 1. `Triangle::compute_barycentric` is scaled wrongly, 2. its triangle test is
//!    not watertight → neither is used; see `primitive::WatertightRay`.
//! 3. Node culling ignores the ray's `tmin` (it clamps the entry distance to a
//!    fixed 1e-4 instead) → every primitive test filters by `t_min` itself, and
//!    the traversal ray is backed up so the 1e-4 clamp cannot cull nodes that
//!    hold hits at t < 1e-4 (`TraversalRay`).
//! 4. The traversal stack is 32 entries and silently clamps in release → the
//!    depth of the built tree is measured after every build, and deeper trees are
//!    traversed with a heap stack sized to the depth ([`Accel::needs_heap_stack`]).
//!    The depth is a conservative bound (a stack entry is only pushed where a node
//!    has two or more inner children still to visit), so some deep trees that the
//!    fixed stack would survive take the slower path; correctness first.
//!
//! 5. The build overflows (panics) for boxes wider than ~1e19 and is quadratic
//!    for coincident boxes → `build.rs` builds in a power-of-two-scaled frame
//!    and deduplicates boxes first.
//!
//! Robustness of the ray/box test itself: `obvhs::ray::Ray::new` replaces
//! direction components below `f32::EPSILON` by ±1/EPSILON in the inverse, which
//! culls valid boxes for axis-parallel rays; we build the obvhs ray ourselves.
//! Primitive boxes are padded by a scene-relative epsilon so that the rounding
//! errors of the quantised slab test can never cull a box a ray touches at an
//! edge or vertex (Ize 2013, "Robust BVH Ray Traversal", makes the same point).

mod build;
mod offset;
mod primitive;

#[doc(hidden)]
pub use build::BuildPreset;
pub use offset::{offset_ray_origin, offset_ray_origin_with_error, SurfacePoint};

use crate::math::{Ray, Vec2, Vec3};
use crate::scene::{Mesh, Sphere};
use glam::{UVec2, Vec3A};
use obvhs::aabb::Aabb;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::cwbvh::CwBvh;
use obvhs::faststack::{FastStack, HeapStack, StackStack};
use primitive::{intersect_sphere, with_axes, WatertightRay};
use std::time::{Duration, Instant};

/// Which primitive a ray hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimRef {
    Triangle { mesh: u32, tri: u32 },
    Sphere(u32),
}

/// The closest hit along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub prim: PrimRef,
    /// Barycentrics (b1, b2) of vertices 1 and 2 for triangles; unused for spheres.
    pub bary: Vec2,
}

/// One primitive, stored in BVH leaf order so that the traversal callback reads
/// memory sequentially instead of going through `primitive_indices`.
#[derive(Clone, Copy, Debug)]
enum Prim {
    Triangle { v: [Vec3; 3], mesh: u32, tri: u32 },
    Sphere { center: Vec3, radius: f32, id: u32 },
}

impl Prim {
    /// The exact intersection with `t` in `[t_min, t_max]`; `KX, KY, KZ` are
    /// `wr`'s axis permutation.
    #[inline(always)]
    fn intersect<const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        t_max: f32,
    ) -> Option<Hit> {
        match *self {
            Prim::Triangle { v, mesh, tri } => wr
                .intersect::<KX, KY, KZ>(v[0], v[1], v[2], ray.t_min, t_max)
                .map(|(t, b1, b2)| Hit {
                    t,
                    prim: PrimRef::Triangle { mesh, tri },
                    bary: Vec2::new(b1, b2),
                }),
            Prim::Sphere { center, radius, id } => {
                intersect_sphere(ray.origin, ray.dir, center, radius, ray.t_min, t_max).map(|t| {
                    Hit {
                        t,
                        prim: PrimRef::Sphere(id),
                        bary: Vec2::ZERO,
                    }
                })
            }
        }
    }
}

/// Traversal state for the `obvhs::traverse!` macro, generic over the stack so
/// that shallow trees use obvhs' fixed 32-entry stack and deep trees a heap stack.
struct TraversalState<S> {
    stack: S,
    current_group: UVec2,
    primitive_group: UVec2,
    oct_inv4: u32,
    primitive_id: u32,
    hitmask: u32,
}

/// Size of obvhs' fixed traversal stack (`cwbvh::TRAVERSAL_STACK_SIZE`, private).
const OBVHS_STACK_SIZE: usize = 32;

/// The ray handed to obvhs' node test.
///
/// obvhs' `CwBvhNode::intersect_ray` computes the box entry as
/// `max(entry, 1e-4)` — it ignores `ray.tmin` and culls every box whose exit
/// distance is below 1e-4. A hit at t < 1e-4 (legal for `t_min = 0`) would be lost.
/// We therefore move the traversal ray's origin back by `back_off` along the
/// direction (and extend `tmax` by the same amount): every node distance grows by
/// `back_off` ≥ 2e-4, so no box holding a hit at t ≥ 0 is culled by the clamp.
/// The exact primitive tests still use the caller's un-moved ray.
struct TraversalRay {
    ray: obvhs::ray::Ray,
    back_off: f32,
}

impl TraversalRay {
    fn new(ray: &Ray) -> Self {
        // Back-off: 2e-4 plus enough ulps of the origin that the shift survives
        // rounding even for origins far from the world origin, plus |t_min| when
        // t_min is negative (hits behind the origin are then legal too).
        let back_off =
            2.0e-4 + ray.origin.abs().max_element() * (1.0 / 262_144.0) + (-ray.t_min).max(0.0);
        // obvhs' `Ray::new` maps |d| <= f32::EPSILON to ±1/EPSILON in the inverse,
        // which for axis-parallel rays turns the "inside the slab" interval into a
        // short finite one and culls valid boxes. We clamp |d| to 1e-20 instead
        // (inverse ±1e20: finite, no NaN from 0·∞) and keep the sign consistent
        // with obvhs' octant test (`d < 0.0`, so −0.0 counts as positive).
        let fix = |d: f32| {
            if d.abs() >= 1.0e-20 {
                d
            } else if d < 0.0 {
                -1.0e-20
            } else {
                1.0e-20
            }
        };
        let dir = Vec3A::new(fix(ray.dir.x), fix(ray.dir.y), fix(ray.dir.z));
        let origin = Vec3A::from(ray.origin) - dir * back_off;
        Self {
            ray: obvhs::ray::Ray {
                origin,
                direction: dir,
                inv_direction: dir.recip(),
                tmin: 0.0,
                tmax: Self::node_t_max(ray.t_max, back_off),
            },
            back_off,
        }
    }

    /// The node-culling distance for a primitive distance `t`: shifted by the
    /// back-off and widened by a few ulps (Ize 2013's `1 + 2γ₃` factor, generous).
    #[inline(always)]
    fn node_t_max(t: f32, back_off: f32) -> f32 {
        (t + back_off) * (1.0 + 4.0 * f32::EPSILON)
    }
}

/// The acceleration structure over all shapes of a scene.
pub struct Accel {
    bvh: CwBvh,
    /// Primitives in BVH leaf order (`prims[i]` is leaf slot `i`).
    prims: Vec<Prim>,
    /// For a primitive in input order (triangles of mesh 0, mesh 1, …, then spheres),
    /// its slot in `prims`, or `u32::MAX` when it was rejected at build time.
    slot_of_input: Vec<u32>,
    /// Index in input order of the first triangle of each mesh; one extra entry
    /// gives the index of the first sphere.
    mesh_first: Vec<u32>,
    triangle_count: usize,
    sphere_count: usize,
    rejected: usize,
    depth: u32,
    bounds: Option<(Vec3, Vec3)>,
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
                let aabb = Aabb::new(a.min(b).min(c).into(), a.max(b).max(c).into());
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
            let aabb = Aabb::new((s.center - r).into(), (s.center + r).into());
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

        let triangle_count = inputs
            .iter()
            .filter(|(p, _)| matches!(p, Prim::Triangle { .. }))
            .count();
        let sphere_count = inputs.len() - triangle_count;

        let mut bounds_box = Aabb::empty();
        for (_, b) in &inputs {
            bounds_box = bounds_box.union(b);
        }
        let bounds = (!inputs.is_empty()).then(|| (bounds_box.min.into(), bounds_box.max.into()));
        let aabbs: Vec<Aabb> = inputs.iter().map(|(_, b)| *b).collect();
        let bvh = build::build_cwbvh(&aabbs, preset);

        // Reorder primitives to leaf order and build the input → slot table.
        let mut slot_of_input = vec![u32::MAX; input_count as usize];
        let prims: Vec<Prim> = bvh
            .primitive_indices
            .iter()
            .enumerate()
            .map(|(slot, &pi)| {
                slot_of_input[input_index[pi as usize] as usize] = slot as u32;
                inputs[pi as usize].0
            })
            .collect();

        let depth = cwbvh_depth(&bvh.nodes);
        Self {
            bvh,
            prims,
            slot_of_input,
            mesh_first,
            triangle_count,
            sphere_count,
            rejected,
            depth,
            bounds,
            build_time: start.elapsed(),
        }
    }

    /// Closest hit with t in [ray.t_min, ray.t_max].
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if !self.traversable(ray) {
            return None;
        }
        let wr = WatertightRay::new(ray.origin, ray.dir);
        if self.needs_heap_stack() {
            let stack = HeapStack::new_with_capacity(self.depth as usize + 2);
            with_axes!(wr.axes, self.closest_with(ray, &wr, stack))
        } else {
            let stack = StackStack::<UVec2, OBVHS_STACK_SIZE>::default();
            with_axes!(wr.axes, self.closest_with(ray, &wr, stack))
        }
    }

    /// True if anything is hit with t in [ray.t_min, ray.t_max]. Stops at the first
    /// hit found.
    pub fn occluded(&self, ray: &Ray) -> bool {
        if !self.traversable(ray) {
            return false;
        }
        let wr = WatertightRay::new(ray.origin, ray.dir);
        if self.needs_heap_stack() {
            let stack = HeapStack::new_with_capacity(self.depth as usize + 2);
            with_axes!(wr.axes, self.any_with(ray, &wr, stack))
        } else {
            let stack = StackStack::<UVec2, OBVHS_STACK_SIZE>::default();
            with_axes!(wr.axes, self.any_with(ray, &wr, stack))
        }
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

    /// Depth of the deepest inner node of the CWBVH (root = 0). The traversal
    /// stack never holds more than this many entries.
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// SAH cost of the tree relative to its root box (see `build::sah_cost`).
    #[doc(hidden)]
    pub fn sah_cost(&self) -> f32 {
        build::sah_cost(&self.bvh)
    }

    /// Number of CWBVH nodes.
    pub fn node_count(&self) -> usize {
        self.bvh.nodes.len()
    }

    /// Whether the tree is too deep for obvhs' fixed 32-entry stack.
    ///
    /// The stack holds at most one entry per level (the remaining siblings of each
    /// node on the current path), so a depth ≤ 30 is safe with the fixed stack.
    /// obvhs' `StackStack::push` clamps its index at 31 in release builds, so a
    /// deeper tree would silently overwrite pending subtrees and *miss* hits. For
    /// such (pathological) trees we traverse with a heap stack of depth + 2
    /// entries instead, allocated per query; correct, merely slower.
    pub fn needs_heap_stack(&self) -> bool {
        self.depth as usize > OBVHS_STACK_SIZE - 2
    }

    /// Closest hit forced through obvhs' fixed 32-entry stack even when the tree is
    /// deeper — i.e. what `CwBvh::ray_traverse` would do. Only for the test that
    /// shows why [`Accel::needs_heap_stack`] exists; never use it for rendering.
    #[doc(hidden)]
    pub fn intersect_with_fixed_stack(&self, ray: &Ray) -> Option<Hit> {
        if !self.traversable(ray) {
            return None;
        }
        let wr = WatertightRay::new(ray.origin, ray.dir);
        let stack = StackStack::<UVec2, OBVHS_STACK_SIZE>::default();
        with_axes!(wr.axes, self.closest_with(ray, &wr, stack))
    }

    /// Closest-hit traversal that counts its work: (CWBVH nodes tested, primitives
    /// tested). A load-independent measure of tree quality for comparing builds on
    /// a shared machine.
    #[doc(hidden)]
    pub fn closest_hit_work(&self, ray: &Ray) -> (u32, u32) {
        if !self.traversable(ray) {
            return (0, 0);
        }
        let wr = WatertightRay::new(ray.origin, ray.dir);
        let stack = HeapStack::new_with_capacity(self.depth as usize + 2);
        with_axes!(wr.axes, self.closest_work(ray, &wr, stack))
    }

    fn closest_work<const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        stack: impl FastStack<UVec2>,
    ) -> (u32, u32) {
        let mut tray = TraversalRay::new(ray);
        let mut state = self.new_state(stack, tray.ray.direction);
        let (mut nodes, mut prims) = (1u32, 0u32);
        let mut t_max = ray.t_max;
        let mut node: &CwBvhNode;
        obvhs::traverse!(
            self.bvh,
            node,
            state,
            {
                nodes += 1;
                node.intersect_ray(&tray.ray, state.oct_inv4)
            },
            {
                prims += 1;
                let prim = &self.prims[state.primitive_id as usize];
                if let Some(h) = prim.intersect::<KX, KY, KZ>(ray, wr, t_max) {
                    t_max = h.t;
                    tray.ray.tmax = TraversalRay::node_t_max(h.t, tray.back_off);
                }
            }
        );
        (nodes, prims)
    }

    /// Reference closest hit: every primitive is tested, no BVH. For tests and
    /// debugging; uses the same primitive routines as [`Accel::intersect`].
    pub fn intersect_brute_force(&self, ray: &Ray) -> Option<Hit> {
        if !ray_is_valid(ray) {
            return None;
        }
        let wr = WatertightRay::new(ray.origin, ray.dir);
        with_axes!(wr.axes, self.closest_brute_force(ray, &wr))
    }

    fn closest_brute_force<const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
    ) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        for p in &self.prims {
            let t_max = best.map_or(ray.t_max, |h| h.t);
            if let Some(h) = p.intersect::<KX, KY, KZ>(ray, wr, t_max) {
                if best.is_none_or(|b| h.t < b.t) {
                    best = Some(h);
                }
            }
        }
        best
    }

    /// Reference any-hit: every primitive is tested, no BVH.
    pub fn occluded_brute_force(&self, ray: &Ray) -> bool {
        if !ray_is_valid(ray) {
            return false;
        }
        let wr = WatertightRay::new(ray.origin, ray.dir);
        with_axes!(wr.axes, self.any_brute_force(ray, &wr))
    }

    fn any_brute_force<const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
    ) -> bool {
        self.prims
            .iter()
            .any(|p| p.intersect::<KX, KY, KZ>(ray, wr, ray.t_max).is_some())
    }

    /// The geometric data of a hit needed to continue a path robustly: the hit
    /// point recomputed from the primitive (barycentric interpolation of the
    /// vertices for triangles, re-projection onto the surface for spheres), its
    /// conservative absolute error bound, and the unit geometric normal
    /// (counter-clockwise winding for triangles, outward for spheres). `None` if the
    /// hit does not refer to a primitive of this BVH.
    pub fn surface_point(&self, ray: &Ray, hit: &Hit) -> Option<SurfacePoint> {
        let input = match hit.prim {
            PrimRef::Triangle { mesh, tri } => {
                let first = *self.mesh_first.get(mesh as usize)?;
                let end = *self.mesh_first.get(mesh as usize + 1)?;
                let i = first.checked_add(tri)?;
                (i < end).then_some(i)?
            }
            PrimRef::Sphere(s) => self.mesh_first.last()?.checked_add(s)?,
        };
        let slot = *self.slot_of_input.get(input as usize)?;
        let prim = self.prims.get(slot as usize)?;
        match *prim {
            Prim::Triangle { v, .. } => Some(offset::triangle_point(v, hit.bary)),
            Prim::Sphere { center, radius, .. } => {
                Some(offset::sphere_point(center, radius, ray.at(hit.t)))
            }
        }
    }

    fn traversable(&self, ray: &Ray) -> bool {
        !self.bvh.nodes.is_empty() && ray_is_valid(ray)
    }

    fn new_state<S: FastStack<UVec2>>(&self, stack: S, dir: Vec3A) -> TraversalState<S> {
        TraversalState {
            stack,
            current_group: UVec2::new(0, 0x8000_0000),
            primitive_group: UVec2::ZERO,
            oct_inv4: ray_octant_inv4(dir),
            primitive_id: 0,
            hitmask: 0,
        }
    }

    #[inline(always)]
    fn closest_with<const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        stack: impl FastStack<UVec2>,
    ) -> Option<Hit> {
        let mut tray = TraversalRay::new(ray);
        let mut state = self.new_state(stack, tray.ray.direction);
        let mut best: Option<Hit> = None;
        let mut t_max = ray.t_max;
        let mut node: &CwBvhNode;
        obvhs::traverse!(
            self.bvh,
            node,
            state,
            node.intersect_ray(&tray.ray, state.oct_inv4),
            {
                let prim = &self.prims[state.primitive_id as usize];
                if let Some(h) = prim.intersect::<KX, KY, KZ>(ray, wr, t_max) {
                    t_max = h.t;
                    tray.ray.tmax = TraversalRay::node_t_max(h.t, tray.back_off);
                    best = Some(h);
                }
            }
        );
        best
    }

    #[inline(always)]
    fn any_with<const KX: usize, const KY: usize, const KZ: usize>(
        &self,
        ray: &Ray,
        wr: &WatertightRay,
        stack: impl FastStack<UVec2>,
    ) -> bool {
        let tray = TraversalRay::new(ray);
        let mut state = self.new_state(stack, tray.ray.direction);
        let mut hit = false;
        let mut node: &CwBvhNode;
        // The primitive block runs inside the macro's inner `while` loop: a plain
        // `break` would only leave that loop and traversal would go on, so we leave
        // the labelled block instead (as obvhs' `ray_traverse_miss` does).
        'traversal: {
            obvhs::traverse!(
                self.bvh,
                node,
                state,
                node.intersect_ray(&tray.ray, state.oct_inv4),
                {
                    let prim = &self.prims[state.primitive_id as usize];
                    if prim.intersect::<KX, KY, KZ>(ray, wr, ray.t_max).is_some() {
                        hit = true;
                        break 'traversal;
                    }
                }
            );
        }
        hit
    }
}

/// Whether a primitive's box is finite and within [`build::MAX_BUILD_MAGNITUDE`]
/// (the box of finite inputs: glam's min/max skip NaN, so check those first).
fn box_is_buildable(b: &Aabb) -> bool {
    let m = b.min.abs().max(b.max.abs()).max_element();
    m.is_finite() && m <= build::MAX_BUILD_MAGNITUDE
}

/// Rays with NaN/∞ origin or direction, a zero direction, a non-finite `t_min` or
/// an empty/NaN interval hit nothing (instead of tripping obvhs' debug assertions).
fn ray_is_valid(ray: &Ray) -> bool {
    ray.origin.is_finite()
        && ray.dir.is_finite()
        && ray.dir != Vec3::ZERO
        && ray.t_min.is_finite()
        && !ray.t_max.is_nan()
        && ray.t_min <= ray.t_max
}

/// Same encoding as obvhs' private `ray_get_octant_inv4`: one byte per child slot,
/// bit set for a non-negative direction component.
fn ray_octant_inv4(dir: Vec3A) -> u32 {
    (if dir.x < 0.0 { 0 } else { 0x0404_0404 })
        | (if dir.y < 0.0 { 0 } else { 0x0202_0202 })
        | (if dir.z < 0.0 { 0 } else { 0x0101_0101 })
}

/// Depth of the deepest inner node (root = 0), iteratively so that even a
/// degenerate chain cannot overflow the call stack. The inner children of node
/// `n` are the `popcount(imask)` consecutive nodes starting at `child_base_idx`.
fn cwbvh_depth(nodes: &[CwBvhNode]) -> u32 {
    if nodes.is_empty() {
        return 0;
    }
    let mut max_depth = 0;
    let mut todo = vec![(0usize, 0u32)];
    while let Some((n, d)) = todo.pop() {
        max_depth = max_depth.max(d);
        let node = &nodes[n];
        let base = node.child_base_idx as usize;
        for k in 0..node.imask.count_ones() as usize {
            if base + k < nodes.len() {
                todo.push((base + k, d + 1));
            }
        }
    }
    max_depth
}
