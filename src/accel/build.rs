//! Primitive boxes → obvhs BVH2 → our wide tree (`collapse.rs`), built so that it cannot fail on any finite input
//! and stays O(n log n) when many boxes coincide.
//!
//! Two defects of building directly with obvhs 0.4 in world space (issue 18):
//! 1. **Overflow.** The build compares surface areas in f32; a box wider than
//!    ~1.8e19 has an infinite area (obvhs' CWBVH collapse then indexed out of
//!    bounds, and PLOC's costs stop ordering). We build in a frame scaled by a power of two `2^-e` that
//!    brings the largest coordinate into [1, 2): every area is finite, and since
//!    scaling by a power of two is exact, every comparison — Morton codes, PLOC
//!    costs, reinsertion, collapse — gives the same result as in world space
//!    would. The wide tree's boxes are brought back to world space exactly (`· 2^e`).
//! 2. **Coincident boxes.** PLOC pairs mutual nearest neighbours, and obvhs
//!    breaks cost ties towards the *farthest* candidate (`cost <= best`), so among
//!    identical boxes (every triangle of a mesh whose vertices collapsed to a few
//!    f32 values far from the origin) only the last pair agrees: one merge per
//!    pass, O(n²) time and a chain n deep (a 20k-triangle grid at 1e8: 21 s, depth
//!    2,856). Boxes are therefore deduplicated before PLOC, which only sees one
//!    box per distinct value, and each duplicate group becomes a balanced subtree
//!    under its representative's leaf.

use super::tree::{Bvh, Tree, WideNode};
use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::bvh2::Bvh2;
use obvhs::ploc::{PlocBuilder, PlocSearchDistance, SortPrecision};
use std::collections::HashMap;

/// Largest coordinate magnitude (2^120 ≈ 1.3e36) of a primitive box the BVH
/// accepts; farther primitives are rejected at build time. Padded boxes, the
/// node origins brought back to world space and their quantised extents then
/// stay far from f32 overflow. (Scenes themselves stop at `scene::MAX_MAGNITUDE`.)
pub(super) const MAX_BUILD_MAGNITUDE: f32 = 1.329_228e36;

/// The obvhs build parameters (PLOC, reinsertion, CWBVH collapse).
#[doc(hidden)]
#[derive(Clone, Copy, Debug)]
pub struct BuildPreset {
    pub search_distance: PlocSearchDistance,
    /// Below this PLOC depth a search distance of 1 is used.
    pub search_depth_threshold: usize,
    pub sort_precision: SortPrecision,
    /// Share of the nodes reinserted per pass (obvhs' `reinsertion_batch_ratio`).
    pub reinsertion_ratio: f32,
    /// Most primitives per leaf (1..=8): two triangle4 blocks. Eight rather
    /// than four: +8–12 % closest-hit rays/s on the bunny at either width,
    /// fewer node visits for a second 4-wide test on a block already in cache
    /// (`benches/README.md`).
    pub max_prims_per_leaf: u32,
    /// Children per node: 8 (taken only where the CPU has AVX2) or 4.
    pub node_width: usize,
    /// `Some(c)`: the SAH-optimal collapse (`collapse::SahCollapse`) with a leaf's
    /// triangle4 block costing `c` wide node tests; `None`: the greedy collapse
    /// (fill every slot, largest box first). `Some(1.0)` against greedy on the
    /// bunny, 8-wide: +10 % / +23 % closest-hit and +10 % / +25 % any-hit rays/s
    /// (coherent / incoherent); 0.5–1.0 alike (`benches/README.md`).
    pub leaf_cost: Option<f32>,
}

impl Default for BuildPreset {
    /// obvhs' `medium_build` (what [`crate::accel::Accel::build`] uses).
    fn default() -> Self {
        Self {
            search_distance: PlocSearchDistance::Medium,
            search_depth_threshold: 3,
            sort_precision: SortPrecision::U64,
            reinsertion_ratio: 0.05,
            max_prims_per_leaf: 8,
            node_width: if super::bvh8::supported() { 8 } else { 4 },
            leaf_cost: Some(1.0),
        }
    }
}

/// How far every primitive box is padded, for a scene whose largest
/// coordinate magnitude is `magnitude` (see `build_tree`).
pub(super) fn box_pad(magnitude: f32) -> f32 {
    (magnitude * (1.0 / 65_536.0)).max(1.0e-30)
}

/// The tree over `boxes` (as [`build_tree`]): 8-wide where the preset asks
/// for it and the CPU has AVX2, else 4-wide.
pub(super) fn build(boxes: &[Aabb], preset: &BuildPreset) -> Tree {
    if preset.node_width == 8 && super::bvh8::supported() {
        Tree::Eight(build_tree(boxes, preset))
    } else {
        Tree::Four(build_tree(boxes, preset))
    }
}

/// Builds the 4- or 8-wide tree over `boxes` (unpadded, finite, within
/// [`MAX_BUILD_MAGNITUDE`]); `leaf_order` refers to `boxes`.
fn build_tree<N: WideNode>(boxes: &[Aabb], preset: &BuildPreset) -> Bvh<N> {
    if boxes.is_empty() {
        return Bvh::from_bvh2(&Bvh2::default(), 1.0, 1, None);
    }
    let mut total = Aabb::empty();
    for b in boxes {
        total = total.union(b);
    }
    // Pad every primitive box by a scene-relative epsilon (2^-16 of the largest
    // coordinate magnitude, at least 1e-30). The quantised slab test has a
    // rounding error of a few ulps of the coordinates involved; without slack a
    // ray through a vertex or edge lying exactly on a (shared) box face can be
    // rejected by *every* box containing the incident triangles, which would
    // defeat the watertight triangle test. A ray through a point of a padded box
    // stays inside it for ≥ pad along its path, which dwarfs those errors.
    let magnitude = total.min.abs().max(total.max.abs()).max_element();
    let pad = box_pad(magnitude);
    let frame = ScaledFrame::new(magnitude.max(pad));
    let scaled: Vec<Aabb> = boxes
        .iter()
        .map(|b| Aabb::new((b.min - pad) * frame.scale, (b.max + pad) * frame.scale))
        .collect();

    let groups = DuplicateGroups::new(&scaled);
    // obvhs' PLOC + reinsertion (as in its `medium_build`), then our own
    // collapse to the uncompressed wide tree that traversal uses (`collapse.rs`).
    let mut bvh2 = PlocBuilder::with_capacity(groups.unique.len()).build(
        preset.search_distance,
        &groups.unique,
        (0..groups.unique.len() as u32).collect(),
        preset.sort_precision,
        preset.search_depth_threshold,
    );
    ReinsertionOptimizer::default().run(&mut bvh2, preset.reinsertion_ratio, None);
    if groups.unique.len() < scaled.len() {
        groups.expand(&mut bvh2);
    }
    Bvh::from_bvh2(
        &bvh2,
        frame.inv_scale,
        preset.max_prims_per_leaf,
        preset.leaf_cost,
    )
}

/// The power-of-two scale `2^-e` of the build frame, with `e` such that the
/// largest coordinate lands in [1, 2).
struct ScaledFrame {
    scale: f32,
    inv_scale: f32,
}

impl ScaledFrame {
    fn new(magnitude: f32) -> Self {
        // magnitude ∈ [1e-30, 2^121): a normal float, so its biased exponent is
        // in 1..=247 and both 2^-e and 2^e are normal floats.
        let exponent = ((magnitude.to_bits() >> 23) & 0xff) as i32 - 127;
        let pow2 = |k: i32| f32::from_bits(((127 + k) as u32) << 23);
        Self {
            scale: pow2(-exponent),
            inv_scale: pow2(exponent),
        }
    }
}

/// Boxes with bit-identical coordinates, grouped: PLOC builds over `unique`, and
/// group `u` holds the input boxes `members[start[u]..start[u + 1]]`.
struct DuplicateGroups {
    unique: Vec<Aabb>,
    start: Vec<u32>,
    members: Vec<u32>,
}

impl DuplicateGroups {
    fn new(boxes: &[Aabb]) -> Self {
        let key = |b: &Aabb| {
            let (lo, hi) = (b.min.to_array(), b.max.to_array());
            [lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]].map(f32::to_bits)
        };
        // Group ids in first-occurrence order, so that without duplicates PLOC
        // sees exactly the input order.
        let mut id_of: HashMap<[u32; 6], u32> = HashMap::with_capacity(boxes.len());
        let mut group_of = Vec::with_capacity(boxes.len());
        let mut unique = Vec::new();
        for b in boxes {
            let next = unique.len() as u32;
            let id = *id_of.entry(key(b)).or_insert(next);
            if id == next {
                unique.push(*b);
            }
            group_of.push(id);
        }
        // Counting sort of the inputs by group (stable: members in input order).
        let mut start = vec![0u32; unique.len() + 1];
        for &g in &group_of {
            start[g as usize + 1] += 1;
        }
        for u in 0..unique.len() {
            start[u + 1] += start[u];
        }
        let mut fill = start.clone();
        let mut members = vec![0u32; boxes.len()];
        for (i, &g) in group_of.iter().enumerate() {
            members[fill[g as usize] as usize] = i as u32;
            fill[g as usize] += 1;
        }
        Self {
            unique,
            start,
            members,
        }
    }

    /// Replaces each leaf (one unique box) by a balanced subtree over its group's
    /// inputs, and rewrites `primitive_indices` to input indices.
    fn expand(&self, bvh: &mut Bvh2) {
        let mut indices = Vec::with_capacity(self.members.len());
        for n in 0..bvh.nodes.len() {
            let node = bvh.nodes[n];
            if node.prim_count == 0 {
                continue;
            }
            let u = bvh.primitive_indices[node.first_index as usize] as usize;
            let group = &self.members[self.start[u] as usize..self.start[u + 1] as usize];
            bvh.nodes[n] = balanced_subtree(&mut bvh.nodes, *node.aabb(), group, &mut indices);
        }
        bvh.primitive_indices = indices;
        bvh.parents.clear();
        bvh.primitives_to_nodes.clear();
        bvh.children_are_ordered_after_parents = false;
    }
}

/// A balanced binary subtree whose leaves are `group` (all with box `aabb`);
/// inner nodes' children are appended to `nodes` as adjacent pairs, as obvhs'
/// BVH2 layout requires. Returns the subtree's root node.
fn balanced_subtree(
    nodes: &mut Vec<Bvh2Node>,
    aabb: Aabb,
    group: &[u32],
    indices: &mut Vec<u32>,
) -> Bvh2Node {
    if let [only] = group {
        indices.push(*only);
        return Bvh2Node::new(aabb, 1, indices.len() as u32 - 1);
    }
    let first = nodes.len();
    nodes.push(Bvh2Node::new(aabb, 0, 0));
    nodes.push(Bvh2Node::new(aabb, 0, 0));
    let (left, right) = group.split_at(group.len() / 2);
    nodes[first] = balanced_subtree(nodes, aabb, left, indices);
    nodes[first + 1] = balanced_subtree(nodes, aabb, right, indices);
    Bvh2Node::new(aabb, 0, first as u32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    #[test]
    fn scaled_frame_is_a_power_of_two_and_its_inverse() {
        for m in [1.0e-30f32, 3.0e-7, 1.0, 1.5, 2.0, 700.0, 1.0e12, 1.3e36] {
            let f = ScaledFrame::new(m);
            let x = m * f.scale;
            assert!((1.0..2.0).contains(&x), "{m}: {x}");
            assert_eq!(f.scale * f.inv_scale, 1.0);
            assert_eq!(f.inv_scale.to_bits() & 0x7f_ffff, 0);
        }
    }

    #[test]
    fn duplicate_boxes_build_a_balanced_tree() {
        let b = Aabb::new(Vec3A::splat(1.0), Vec3A::splat(2.0));
        let mut boxes = vec![b; 5000];
        boxes.push(Aabb::new(Vec3A::splat(3.0), Vec3A::splat(4.0)));
        let groups = DuplicateGroups::new(&boxes);
        assert_eq!(groups.unique.len(), 2);
        let bvh: super::super::bvh4::Bvh4 = build_tree(&boxes, &BuildPreset::default());
        let mut seen = bvh.leaf_order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..boxes.len() as u32).collect::<Vec<_>>());
        // 5000 leaves under 4-wide nodes: a handful of levels, not 2500.
        assert!(bvh.depth < 10, "{}", bvh.depth);
    }
}
