//! The leaf layout: the scene's primitives in *input order* (triangles of
//! mesh 0, mesh 1, …, then spheres; the order that also breaks ties), copied
//! in the tree's leaf order, packed per leaf into SoA blocks of four
//! ([`LeafBlock`]) that the traversal tests, each lane's record for a hit
//! ([`LaneRecord`]), and the lookups between a primitive's input index, its
//! [`PrimRef`] and its stored copy ([`Leaves`]).

use super::offset::triangle_normal;
use super::prefetch::prefetch_lines;
use super::primitive::{intersect_sphere, Tri4, WatertightRay};
use super::tree::{Tree, MAX_PRIMITIVES};
use super::{Hit, PrimRef, NO_SLOT};
use crate::math::{Ray, Vec2, Vec3};
use crate::scene::{Mesh, Sphere};
use glam::Vec4;
use obvhs::aabb::Aabb;

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

/// One primitive, stored in BVH leaf order so that the traversal callback reads
/// memory sequentially instead of going through `primitive_indices`.
#[derive(Clone, Copy, Debug)]
pub(super) enum Prim {
    Triangle { v: [Vec3; 3], mesh: u32, tri: u32 },
    Sphere { center: Vec3, radius: f32, id: u32 },
}

impl Prim {
    /// The exact intersection with `t` in `[t_min, t_max]`.
    #[inline(always)]
    pub(super) fn intersect(&self, ray: &Ray, wr: &WatertightRay, t_max: f32) -> Option<Hit> {
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
pub(super) struct LeafBlock {
    pub(super) tris: Tri4,
    pub(super) ids: [u32; 4],
}

pub(super) const EMPTY_LANE: u32 = u32::MAX;

/// Leaf blocks from this many bytes on are prefetched when pushed (about an L2
/// cache): on the bunny (megabytes of blocks) +6–10 % incoherent rays/s; on
/// the Cornell box (36 triangles, all in L1) the prefetches were 5.5 % more
/// instructions per closest-hit query and bought nothing.
const PREFETCH_LEAVES_FROM: usize = 1 << 20;

/// A leaf's `count` field once it refers to blocks: 1 + (blocks − 1) + 2 ×
/// (some lane is a sphere), in the 1..=8 the tree's leaf encoding holds.
pub(super) struct LeafCode;

impl LeafCode {
    fn encode(blocks: usize, spheres: bool) -> usize {
        blocks + 2 * spheres as usize
    }

    #[inline(always)]
    pub(super) fn decode(code: usize) -> (usize, bool) {
        (1 + ((code - 1) & 1), (code - 1) & 2 != 0)
    }
}

impl LeafBlock {
    /// The lanes holding a sphere, i.e. an input index from `first_sphere`
    /// on (only looked at in leaves that have one).
    #[inline(always)]
    pub(super) fn sphere_lanes(&self, first_sphere: u32) -> u32 {
        let mut mask = 0;
        for (lane, &id) in self.ids.iter().enumerate() {
            if id != EMPTY_LANE && id >= first_sphere {
                mask |= 1 << lane;
            }
        }
        mask
    }

    pub(super) fn primitive_count(&self) -> u32 {
        self.ids.iter().filter(|&&s| s != EMPTY_LANE).count() as u32
    }
}

/// Whether a hit at distance `t` on the primitive with input index `id`
/// replaces `best` (its distance and input index; the caller has already
/// bounded `t` by it): nearer, or as near and earlier in input order, so
/// that ties do not depend on the order the tree visits leaves.
#[inline(always)]
pub(super) fn nearer(t: f32, id: u32, best: Option<(f32, u32)>) -> bool {
    best.is_none_or(|(best_t, best_id)| t < best_t || (t == best_t && id < best_id))
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

/// Whether a primitive's box is finite and within [`super::build::MAX_BUILD_MAGNITUDE`]
/// (the box of finite inputs: glam's min/max skip NaN, so check those first).
fn box_is_buildable(b: &Aabb) -> bool {
    let m = b.min.abs().max(b.max.abs()).max_element();
    m.is_finite() && m <= super::build::MAX_BUILD_MAGNITUDE
}

/// The scene's primitives that can be intersected meaningfully, with their
/// boxes, in input order (see [`Inputs::collect`]).
pub(super) struct Inputs {
    prims: Vec<(Prim, Aabb)>,
    /// Each kept primitive's input index.
    input_index: Vec<u32>,
    /// Index in input order of the first triangle of each mesh; one extra
    /// entry gives the index of the first sphere.
    mesh_first: Vec<u32>,
    /// Input primitives, kept or not.
    input_count: u32,
    pub(super) rejected: usize,
}

impl Inputs {
    /// Every triangle of `meshes` and every sphere, skipping (and counting
    /// in `rejected`) triangles with an out-of-range index or a non-finite
    /// vertex, spheres with a non-finite centre or a radius that is not
    /// positive and finite, any primitive whose box reaches beyond ±1.3e36,
    /// and those past the tree's [`MAX_PRIMITIVES`].
    pub(super) fn collect(meshes: &[Mesh], spheres: &[Sphere]) -> Self {
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

        if inputs.len() > MAX_PRIMITIVES {
            rejected += inputs.len() - MAX_PRIMITIVES;
            inputs.truncate(MAX_PRIMITIVES);
            input_index.truncate(MAX_PRIMITIVES);
        }
        Self {
            prims: inputs,
            input_index,
            mesh_first,
            input_count,
            rejected,
        }
    }

    /// The kept primitives' boxes, what the tree is built over.
    pub(super) fn boxes(&self) -> Vec<Aabb> {
        self.prims.iter().map(|(_, b)| *b).collect()
    }

    /// (triangles, spheres) kept.
    pub(super) fn counts(&self) -> (usize, usize) {
        let triangles = self
            .prims
            .iter()
            .filter(|(p, _)| matches!(p, Prim::Triangle { .. }))
            .count();
        (triangles, self.prims.len() - triangles)
    }

    /// The box (min, max) of every kept primitive; `None` for none.
    pub(super) fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut bounds_box = Aabb::empty();
        for (_, b) in &self.prims {
            bounds_box = bounds_box.union(b);
        }
        (!self.prims.is_empty()).then_some((bounds_box.min, bounds_box.max))
    }
}

/// The primitives as the traversal and the hits read them.
pub(super) struct Leaves {
    /// The leaves' primitives as the traversal tests them (see [`LeafBlock`]).
    pub(super) blocks: Vec<LeafBlock>,
    /// Each block lane's [`LaneRecord`], index block × 4 + lane like [`Hit::slot`].
    lanes: Vec<LaneRecord>,
    /// Whether the traversal prefetches the leaves it pushes (`blocks` larger
    /// than [`PREFETCH_LEAVES_FROM`]).
    prefetch: bool,
    /// Primitives in BVH leaf order (`prims[i]` is leaf slot `i`).
    prims: Vec<Prim>,
    /// For a primitive in input order, its slot in `prims`, or `u32::MAX`
    /// when it was rejected at build time.
    slot_of_input: Vec<u32>,
    /// As [`Inputs`]' `mesh_first`.
    mesh_first: Vec<u32>,
    /// `mesh_first`'s last entry: input indices from here on are spheres.
    pub(super) first_sphere: u32,
    /// The mesh holding every triangle, when one does: its closest hits skip
    /// the lane record's read, which costs a query that is not followed by an
    /// interaction (the `accel` bench's incoherent rays on the bunny: −9 %).
    only_mesh: Option<u32>,
}

impl Leaves {
    /// `inputs` in `tree`'s leaf order, each leaf's primitives packed into
    /// blocks and the leaf pointed at them.
    pub(super) fn pack(tree: &mut Tree, inputs: Inputs) -> Self {
        let Inputs {
            prims: inputs,
            input_index,
            mesh_first,
            input_count,
            ..
        } = inputs;
        // Reorder primitives to leaf order and build the input → slot table.
        let mut slot_of_input = vec![u32::MAX; input_count as usize];
        let prims: Vec<Prim> = tree
            .leaf_order()
            .iter()
            .enumerate()
            .map(|(slot, &pi)| {
                slot_of_input[input_index[pi as usize] as usize] = slot as u32;
                inputs[pi as usize].0
            })
            .collect();
        let input_of_slot: Vec<u32> = tree
            .leaf_order()
            .iter()
            .map(|&pi| input_index[pi as usize])
            .collect();
        let blocks = pack_leaves(tree, &prims, &input_of_slot);
        let lanes = blocks
            .iter()
            .flat_map(|b| {
                // A lane's primitive as `prim_of_input` finds it (none for an empty lane).
                let prim = |id: u32| prims.get(*slot_of_input.get(id as usize)? as usize);
                b.ids.map(|id| match prim(id) {
                    Some(&Prim::Triangle { v, mesh, .. }) => {
                        LaneRecord::new(triangle_normal(v), mesh)
                    }
                    _ => LaneRecord::new(Vec3::ZERO, 0),
                })
            })
            .collect();
        Self {
            prefetch: std::mem::size_of_val(blocks.as_slice()) >= PREFETCH_LEAVES_FROM,
            blocks,
            lanes,
            prims,
            slot_of_input,
            first_sphere: *mesh_first.last().unwrap_or(&0),
            only_mesh: only_mesh(&mesh_first),
            mesh_first,
        }
    }

    /// Number of primitives in the leaves.
    #[inline]
    pub(super) fn len(&self) -> usize {
        self.prims.len()
    }

    /// Starts loading the blocks of the leaf `(first, code)` (a hint), when
    /// the blocks are too many to stay in cache ([`PREFETCH_LEAVES_FROM`]).
    #[inline(always)]
    pub(super) fn prefetch_leaf(&self, first: usize, code: usize) {
        if !self.prefetch {
            return;
        }
        let (count, _) = LeafCode::decode(code);
        // SAFETY: the leaf's blocks are `blocks[first..first + count]`.
        unsafe { prefetch_lines(self.blocks.as_ptr().add(first), count) }
    }

    /// The input index of a primitive (`prim` must be in these leaves).
    #[inline]
    pub(super) fn input_of(&self, prim: PrimRef) -> u32 {
        match prim {
            PrimRef::Triangle { mesh, tri } => self.mesh_first[mesh as usize] + tri,
            PrimRef::Sphere(s) => self.first_sphere + s,
        }
    }

    /// [`Leaves::input_of`] inverted, for the primitive in block lane `slot`:
    /// a triangle's mesh read from the lane's record.
    #[inline(always)]
    pub(super) fn prim_ref_at(&self, id: u32, slot: u32) -> PrimRef {
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
    pub(super) fn prim_of_input(&self, id: u32) -> &Prim {
        &self.prims[self.slot_of_input[id as usize] as usize]
    }

    /// The stored primitive of a [`PrimRef`], `None` when out of range or rejected.
    #[inline]
    pub(super) fn prim(&self, prim: PrimRef) -> Option<&Prim> {
        let input = self.checked_input_of(prim)?;
        let slot = *self.slot_of_input.get(input as usize)?;
        self.prims.get(slot as usize)
    }

    /// [`Leaves::input_of`] for a `PrimRef` that may not be of these leaves:
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

    /// The vertices and unit normal of the triangle in the lane `hit.slot`
    /// names, `None` where that lane holds another primitive (see
    /// `Accel::hit_triangle`).
    #[inline]
    pub(super) fn hit_triangle(&self, hit: &Hit) -> Option<([Vec3; 3], Vec3)> {
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
}

/// Packs each leaf's primitives (`prims[first..first + count]`, whose input
/// indices are `input_of_slot[first..first + count]`) into blocks and points
/// the leaf at them.
fn pack_leaves(tree: &mut Tree, prims: &[Prim], input_of_slot: &[u32]) -> Vec<LeafBlock> {
    let mut blocks = Vec::new();
    tree.remap_leaves(|first, count| {
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
