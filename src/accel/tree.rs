//! The wide tree's layout, shared by both widths: child references (inner
//! node or leaf), the nodes' build-side interface ([`WideNode`]), the tree
//! itself ([`Bvh`]) and the width chosen at build time ([`Tree`]). The node
//! tests live with each node type (`bvh4.rs`, `bvh8.rs`), the loop that
//! visits them in `traverse.rs`, the collapse that builds them in
//! `collapse.rs`.

use super::bvh4::Bvh4;
use super::bvh8::Bvh8;
use super::prefetch::prefetch_lines;

/// Child reference: an inner node's index, or `LEAF_BIT | (count − 1) << 28 |
/// first` for a leaf of `count` ≤ [`MAX_LEAF`] consecutive primitives, or
/// [`EMPTY`].
pub(super) const LEAF_BIT: u32 = 1 << 31;
pub(super) const COUNT_SHIFT: u32 = 28;
pub(super) const FIRST_MASK: u32 = (1 << COUNT_SHIFT) - 1;
pub(super) const EMPTY: u32 = u32::MAX;
/// Most primitives a leaf can reference (3 bits of count).
pub(super) const MAX_LEAF: u32 = 8;
/// Most primitives the tree can hold (28 bits of leaf offset, `EMPTY` excluded).
pub(super) const MAX_PRIMITIVES: usize = FIRST_MASK as usize;

/// Ize 2013's `1 + 2γ₃` widening of exit distances, rounded up generously.
pub(super) const WIDEN: f32 = 1.0 + 4.0 * f32::EPSILON;

/// The widening of the reciprocal direction the exit distances are computed
/// with (Ize 2013, §3.3: pad the reciprocal instead of each distance, one
/// multiply fewer on every node test's dependency chain). An exit distance
/// then carries four roundings (the difference, the reciprocal, its padding,
/// the product; ≥ (1 − u)⁴ of the exact one) and an entry distance three
/// (≤ (1 + u)³), so the pad must exceed (1 + u)³ / (1 − u)⁴ ≈ 1 + 7u; this is
/// 1 + 16u (u = 2⁻²⁴).
pub(super) const WIDEN_INV: f32 = 1.0 + 8.0 * f32::EPSILON;

/// A node of [`Bvh`]: `WIDTH` child slots with their boxes.
pub(super) trait WideNode: Copy {
    const WIDTH: usize;
    fn empty() -> Self;
    fn set_child(&mut self, slot: usize, lo: [f32; 3], hi: [f32; 3]);
    fn child_box(&self, slot: usize) -> ([f32; 3], [f32; 3]);
    /// The child references, `WIDTH` of them (read by the traversal: inline).
    fn children(&self) -> &[u32];
    fn children_mut(&mut self) -> &mut [u32];
}

/// The `N::WIDTH`-wide tree; leaf offsets index the primitives in `leaf_order`.
#[derive(Debug)]
pub(super) struct Bvh<N> {
    pub(super) nodes: Vec<N>,
    pub(super) root: u32,
    /// For every leaf slot, the index of its primitive in the build's input.
    pub(super) leaf_order: Vec<u32>,
    /// Inner levels below the root (root alone = 0).
    pub(super) depth: u32,
}

impl<N: WideNode> Bvh<N> {
    /// Rewrites every leaf reference `(first, count)` to `f(first, count)`
    /// (both kept in the encoding's ranges: `first` ≤ [`MAX_PRIMITIVES`],
    /// `count` in 1..=[`MAX_LEAF`]), so that the leaf callback of
    /// the traversal can address another layout of the primitives.
    pub(super) fn remap_leaves(&mut self, mut f: impl FnMut(usize, usize) -> (usize, usize)) {
        let mut remap = |c: &mut u32| {
            if *c == EMPTY || *c & LEAF_BIT == 0 {
                return;
            }
            let (first, count) = decode_leaf(*c);
            let (first, count) = f(first, count);
            debug_assert!(first <= MAX_PRIMITIVES && (1..=MAX_LEAF as usize).contains(&count));
            *c = LEAF_BIT | (count as u32 - 1) << COUNT_SHIFT | first as u32;
        };
        remap(&mut self.root);
        for node in &mut self.nodes {
            node.children_mut().iter_mut().for_each(&mut remap);
        }
    }

    /// The traversal stack's worst case: each inner node on the path leaves at
    /// most `WIDTH − 1` siblings behind.
    pub(super) fn stack_size(&self) -> usize {
        (N::WIDTH - 1) * (self.depth as usize + 1) + 1
    }

    /// Starts loading inner node `child` into the cache (a hint; no-op for
    /// leaves and on other architectures).
    #[inline(always)]
    pub(super) fn prefetch(&self, child: u32) {
        if child & LEAF_BIT == 0 {
            // SAFETY: inner references index `nodes`, so the node is in bounds.
            unsafe {
                prefetch_lines(self.nodes.as_ptr().add(child as usize), 1);
            }
        }
    }

    /// Starts loading a child pushed for later: an inner node itself, a leaf
    /// through `leaf_prefetch(first, count)` (the leaves' primitives live
    /// with the caller). Prefetching pushed leaves too: +6–10 % incoherent
    /// rays/s on the bunny (best and median of 7 interleaved runs).
    #[inline(always)]
    pub(super) fn prefetch_child(&self, child: u32, leaf_prefetch: &impl Fn(usize, usize)) {
        if child & LEAF_BIT == 0 {
            self.prefetch(child);
        } else if child != EMPTY {
            let (first, count) = decode_leaf(child);
            leaf_prefetch(first, count);
        }
    }

    /// Surface-area-heuristic cost relative to the root's box: 1 + Σ over child
    /// boxes of area(child)/area(root) × (1 per inner child, `leaf(count)` per
    /// leaf of `count` primitives).
    pub(super) fn sah_cost_with(&self, leaf: impl Fn(u32) -> f64) -> f64 {
        if self.nodes.is_empty() {
            return 0.0;
        }
        let half_area = |(lo, hi): ([f32; 3], [f32; 3])| {
            let d = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]].map(|x| x.max(0.0) as f64);
            d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
        };
        let root = &self.nodes[0];
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for k in 0..N::WIDTH {
            if root.children()[k] != EMPTY {
                let (l, h) = root.child_box(k);
                for a in 0..3 {
                    lo[a] = lo[a].min(l[a]);
                    hi[a] = hi[a].max(h[a]);
                }
            }
        }
        let root_area = half_area((lo, hi));
        let mut cost = 1.0;
        for node in &self.nodes {
            for k in 0..N::WIDTH {
                let c = node.children()[k];
                if c == EMPTY {
                    continue;
                }
                let weight = if c & LEAF_BIT == 0 {
                    1.0
                } else {
                    leaf(decode_leaf(c).1 as u32)
                };
                cost += weight * half_area(node.child_box(k)) / root_area;
            }
        }
        cost
    }

    /// [`Self::sah_cost_with`] under the collapse's own model: a leaf priced by
    /// [`leaf_test_cost`] with a triangle4 block costing `block` node tests, the
    /// cost `collapse::SahCollapse` minimises.
    pub(super) fn sah_cost(&self, block: f32) -> f64 {
        self.sah_cost_with(|count| leaf_test_cost::<N>(block, count))
    }
}

/// What testing a leaf of `count` primitives costs, in wide node tests, when
/// one triangle4 block costs `block`: one test per block, except that the
/// 8-wide tree tests two blocks as one eight-lane test (half again as dear).
pub(super) fn leaf_test_cost<N: WideNode>(block: f32, count: u32) -> f64 {
    let block = block as f64;
    if N::WIDTH == 8 && count > 4 {
        1.5 * block
    } else {
        block * count.div_ceil(4) as f64
    }
}

/// A leaf code's primitives: (first, count).
#[inline(always)]
pub(super) fn decode_leaf(code: u32) -> (usize, usize) {
    (
        (code & FIRST_MASK) as usize,
        ((code >> COUNT_SHIFT) & (MAX_LEAF - 1)) as usize + 1,
    )
}

/// The traversal tree: 8-wide where the CPU has AVX2 (`bvh8.rs`), else 4-wide.
pub(super) enum Tree {
    Four(Bvh4),
    Eight(Bvh8),
}

impl Tree {
    pub(super) fn root(&self) -> u32 {
        match self {
            Tree::Four(t) => t.root,
            Tree::Eight(t) => t.root,
        }
    }

    pub(super) fn depth(&self) -> u32 {
        match self {
            Tree::Four(t) => t.depth,
            Tree::Eight(t) => t.depth,
        }
    }

    pub(super) fn node_count(&self) -> usize {
        match self {
            Tree::Four(t) => t.nodes.len(),
            Tree::Eight(t) => t.nodes.len(),
        }
    }

    pub(super) fn stack_size(&self) -> usize {
        match self {
            Tree::Four(t) => t.stack_size(),
            Tree::Eight(t) => t.stack_size(),
        }
    }

    pub(super) fn leaf_order(&self) -> &[u32] {
        match self {
            Tree::Four(t) => &t.leaf_order,
            Tree::Eight(t) => &t.leaf_order,
        }
    }

    /// The SAH cost under the collapse's own model (`leaf_test_cost`, one
    /// block of four primitives = `leaf_cost` node tests), so that trees built
    /// with different collapses compare by the cost the builder minimised.
    pub(super) fn sah_cost(&self, leaf_cost: f32) -> f32 {
        (match self {
            Tree::Four(t) => t.sah_cost(leaf_cost),
            Tree::Eight(t) => t.sah_cost(leaf_cost),
        }) as f32
    }

    /// Whether leaves of two blocks are tested as one eight-lane block
    /// (`primitive::avx`): in the 8-wide tree, which is only built with AVX2.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub(super) fn eight_lane_leaves(&self) -> bool {
        matches!(self, Tree::Eight(_))
    }

    /// [`Bvh::remap_leaves`] on either width.
    pub(super) fn remap_leaves(&mut self, f: impl FnMut(usize, usize) -> (usize, usize)) {
        match self {
            Tree::Four(t) => t.remap_leaves(f),
            Tree::Eight(t) => t.remap_leaves(f),
        }
    }
}
