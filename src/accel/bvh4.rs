//! The traversal tree: obvhs' BVH2 collapsed into a 4-wide BVH with
//! uncompressed f32 child boxes in SoA layout, tested four at a time with
//! `wide::f32x4` slab tests and visited nearest-first.
//!
//! Why not obvhs' CWBVH (issue 16): its 8-wide nodes are quantised (u8 child
//! boxes decoded on every visit), visited in octant order rather than by
//! distance, and its entry distance is clamped to a fixed 1e-4, which forced a
//! backed-off traversal ray. Here a node test is 6 subtractions, 6
//! multiplications and 8 min/max on four children at once, and the box test is
//! Ize's conservative one (2013, "Robust BVH Ray Traversal": exit distances
//! widened by `1 + 2γ₃`, here generously `1 + 4ε`), on boxes padded by the
//! build (`build.rs`), so no box a ray touches at an edge or vertex is culled.

use crate::math::Vec3;
use obvhs::bvh2::Bvh2;
use wide::f32x4;

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

/// Four child boxes: `bounds[2·axis]` the minima, `bounds[2·axis + 1]` the
/// maxima along `axis`. Empty slots hold the inverted box (+∞, −∞), which the
/// ordered slab test always misses.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(super) struct Node4 {
    bounds: [f32x4; 6],
    children: [u32; 4],
}

/// A node of [`Bvh`]: `WIDTH` child slots with their boxes.
pub(super) trait WideNode: Copy {
    const WIDTH: usize;
    fn empty() -> Self;
    fn set_child(&mut self, slot: usize, lo: [f32; 3], hi: [f32; 3]);
    fn child_box(&self, slot: usize) -> ([f32; 3], [f32; 3]);
    fn children(&self) -> &[u32];
    fn children_mut(&mut self) -> &mut [u32];
}

impl WideNode for Node4 {
    const WIDTH: usize = 4;

    fn empty() -> Self {
        let (inf, ninf) = (f32x4::splat(f32::INFINITY), f32x4::splat(f32::NEG_INFINITY));
        Self {
            bounds: [inf, ninf, inf, ninf, inf, ninf],
            children: [EMPTY; 4],
        }
    }

    fn set_child(&mut self, slot: usize, lo: [f32; 3], hi: [f32; 3]) {
        for axis in 0..3 {
            let mut min = self.bounds[2 * axis].to_array();
            let mut max = self.bounds[2 * axis + 1].to_array();
            min[slot] = lo[axis];
            max[slot] = hi[axis];
            self.bounds[2 * axis] = f32x4::new(min);
            self.bounds[2 * axis + 1] = f32x4::new(max);
        }
    }

    fn child_box(&self, slot: usize) -> ([f32; 3], [f32; 3]) {
        let c = |i: usize| self.bounds[i].to_array()[slot];
        ([c(0), c(2), c(4)], [c(1), c(3), c(5)])
    }

    fn children(&self) -> &[u32] {
        &self.children
    }

    fn children_mut(&mut self) -> &mut [u32] {
        &mut self.children
    }
}

impl Node4 {
    /// Entry distances of the four children and the mask of those whose box
    /// overlaps `[t_lo, hi_w]` along the ray (`hi_w` already widened).
    #[inline(always)]
    fn hit(&self, r: &BoxRay, hi_w: f32x4) -> (f32x4, u32) {
        let b = &self.bounds;
        // near[a] & 1 is the ray's sign bit on axis a: the slab's entry plane is
        // the minimum for a positive direction, the maximum for a negative one.
        let (nx, ny, nz) = (r.near[0] & 1, 2 + (r.near[1] & 1), 4 + (r.near[2] & 1));
        let tnx = (b[nx] - r.org[0]) * r.inv[0];
        let tny = (b[ny] - r.org[1]) * r.inv[1];
        let tnz = (b[nz] - r.org[2]) * r.inv[2];
        let tfx = (b[nx ^ 1] - r.org[0]) * r.inv_far[0];
        let tfy = (b[ny ^ 1] - r.org[1]) * r.inv_far[1];
        let tfz = (b[nz ^ 1] - r.org[2]) * r.inv_far[2];
        let t_near = tnx.fast_max(tny).fast_max(tnz.fast_max(r.t_lo));
        let t_far = tfx.fast_min(tfy).fast_min(tfz).fast_min(hi_w);
        (t_near, t_near.simd_le(t_far).to_bitmask())
    }
}

/// The ray as the node test sees it: origin and reciprocal direction splatted,
/// the sign of each direction component, and the lower end of the interval.
pub(super) struct BoxRay {
    org: [f32x4; 3],
    inv: [f32x4; 3],
    /// `inv` widened by [`WIDEN_INV`], for the exit distances.
    inv_far: [f32x4; 3],
    pub(super) near: [usize; 3],
    t_lo: f32x4,
}

impl BoxRay {
    /// `dir` components must be nonzero (the caller clamps them away from 0, so
    /// that the reciprocal is finite and `0 · ∞` cannot occur); `t_lo ≥ 0`.
    #[inline(always)]
    pub(super) fn new(org: Vec3, dir: Vec3, t_lo: f32) -> Self {
        // One packed division for the three reciprocals; the splats lane by
        // lane from the registers (through `to_array` they were 16-byte loads
        // across separate stores: a store-forwarding stall per query).
        let inv = Vec3::ONE / dir;
        let splat = |v: Vec3| [f32x4::splat(v.x), f32x4::splat(v.y), f32x4::splat(v.z)];
        Self {
            org: splat(org),
            inv: splat(inv),
            inv_far: splat(inv * WIDEN_INV),
            near: [dir.x, dir.y, dir.z].map(|d| (d < 0.0) as usize),
            t_lo: f32x4::splat(t_lo),
        }
    }

    pub(super) fn org_scalar(&self) -> [f32; 3] {
        self.org.map(|o| o.as_array()[0])
    }

    pub(super) fn inv_scalar(&self) -> [f32; 3] {
        self.inv.map(|i| i.as_array()[0])
    }

    pub(super) fn inv_far_scalar(&self) -> [f32; 3] {
        self.inv_far.map(|i| i.as_array()[0])
    }

    pub(super) fn t_lo_scalar(&self) -> f32 {
        self.t_lo.as_array()[0]
    }
}

/// A pending subtree on the traversal stack, with its entry distance.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Entry {
    pub(super) node: u32,
    pub(super) t: f32,
}

impl Entry {
    #[inline(always)]
    pub(super) fn new(node: u32, t: f32) -> Self {
        Self { node, t }
    }
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

/// The 4-wide tree.
pub(super) type Bvh4 = Bvh<Node4>;

impl<N: WideNode> Bvh<N> {
    /// Collapses `bvh2` (boxes in a frame scaled by `1/inv_scale`, a power of
    /// two) into a wide BVH in world space. With `leaf_cost` ([`SahCollapse`]):
    /// the tree of least SAH cost, leaves of at most `max_leaf` primitives.
    /// Without (greedy): each node takes its BVH2 node's two children and keeps
    /// opening the largest-area child holding more than one primitive until its
    /// `WIDTH` slots are filled; a child with at most `max_leaf` primitives
    /// becomes a leaf. Iterative, so degenerate chains cannot
    /// overflow the call stack.
    pub(super) fn from_bvh2(
        bvh2: &Bvh2,
        inv_scale: f32,
        max_leaf: u32,
        leaf_cost: Option<f32>,
    ) -> Self {
        let max_leaf = max_leaf.clamp(1, MAX_LEAF);
        let mut out = Self {
            nodes: Vec::new(),
            root: EMPTY,
            leaf_order: Vec::new(),
            depth: 0,
        };
        if bvh2.nodes.is_empty() {
            return out;
        }
        let counts = subtree_counts(bvh2);
        let sah = leaf_cost.map(|c| {
            SahCollapse::new(bvh2, &counts, N::WIDTH, max_leaf, |n| {
                leaf_test_cost::<N>(c, n)
            })
        });
        let world = |n: usize| {
            let b = bvh2.nodes[n].aabb();
            (
                (b.min * inv_scale).to_array(),
                (b.max * inv_scale).to_array(),
            )
        };
        // (BVH2 node, parent BVH4 node or EMPTY for the root, slot, depth)
        let mut work = vec![(0usize, EMPTY, 0usize, 0u32)];
        while let Some((n, parent, slot, depth)) = work.pop() {
            let as_leaf = match &sah {
                Some(t) => t.is_leaf(bvh2, n),
                None => counts[n] <= max_leaf || bvh2.nodes[n].prim_count > 0,
            };
            let child = if as_leaf {
                let first = out.leaf_order.len() as u32;
                collect_primitives(bvh2, n, &mut out.leaf_order);
                let count = out.leaf_order.len() as u32 - first;
                LEAF_BIT | (count.clamp(1, MAX_LEAF) - 1) << COUNT_SHIFT | first
            } else {
                let index = out.nodes.len() as u32;
                let mut node = N::empty();
                let kids = match &sah {
                    Some(t) => t.slots(bvh2, n),
                    None => open_children(bvh2, n, &counts, N::WIDTH),
                };
                for (k, c) in kids.into_iter().enumerate() {
                    let Some(c) = c else { break };
                    let (lo, hi) = world(c);
                    node.set_child(k, lo, hi);
                    work.push((c, index, k, depth + 1));
                }
                out.nodes.push(node);
                out.depth = out.depth.max(depth);
                index
            };
            if parent == EMPTY {
                out.root = child;
            } else {
                out.nodes[parent as usize].children_mut()[slot] = child;
            }
        }
        out
    }

    /// Rewrites every leaf reference `(first, count)` to `f(first, count)`
    /// (both kept in the encoding's ranges: `first` ≤ [`MAX_PRIMITIVES`],
    /// `count` in 1..=[`MAX_LEAF`]), so that the leaf callback of
    /// [`Bvh4::traverse`] can address another layout of the primitives.
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
                super::prefetch_lines(self.nodes.as_ptr().add(child as usize), 1);
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
}

impl<N: WideNode> Bvh<N> {
    /// [`Self::sah_cost_with`] under the collapse's own model: a leaf priced by
    /// [`leaf_test_cost`] with a triangle4 block costing `block` node tests, the
    /// cost [`SahCollapse`] minimises.
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

impl Bvh4 {
    /// Visits the leaves whose boxes the ray overlaps, nearest box first
    /// (`SORTED`) or in any order; `leaf(first, count)` tests the primitives
    /// `first..first + count` and returns the new upper end of the ray interval
    /// in the node test's distances, or `None` to stop; `leaf_prefetch(first,
    /// count)` starts loading a leaf's primitives. `nodes_visited` counts
    /// node tests. `stack` must hold [`Bvh4::stack_size`] entries.
    #[inline(always)]
    pub(super) fn traverse<const SORTED: bool>(
        &self,
        ray: &BoxRay,
        t_hi: f32,
        stack: &mut [Entry],
        nodes_visited: &mut u32,
        mut leaf: impl FnMut(usize, usize) -> Option<f32>,
        leaf_prefetch: impl Fn(usize, usize),
    ) {
        let prefetch = |c: u32| self.prefetch_child(c, &leaf_prefetch);
        let mut hi = t_hi * WIDEN;
        let mut hi_w = f32x4::splat(hi);
        let mut sp = 0usize;
        let mut cur = self.root;
        loop {
            while cur & LEAF_BIT == 0 {
                *nodes_visited += 1;
                let node = &self.nodes[cur as usize];
                let (t_near, mask) = node.hit(ray, hi_w);
                if mask == 0 {
                    cur = EMPTY;
                    break;
                }
                if mask & (mask - 1) == 0 {
                    cur = node.children[mask.trailing_zeros() as usize];
                    continue;
                }
                let t_near = t_near.to_array();
                let rest = mask & (mask - 1);
                if rest & (rest - 1) == 0 {
                    // Two children hit (the common case): the nearer one next.
                    let (i, j) = (
                        mask.trailing_zeros() as usize,
                        rest.trailing_zeros() as usize,
                    );
                    let (near, far) = if !SORTED || t_near[i] <= t_near[j] {
                        (i, j)
                    } else {
                        (j, i)
                    };
                    stack[sp] = Entry {
                        node: node.children[far],
                        t: t_near[far],
                    };
                    sp += 1;
                    prefetch(node.children[far]);
                    cur = node.children[near];
                    continue;
                }
                let (mut ids, mut ts, mut k) = ([0u32; 4], [0f32; 4], 0usize);
                let mut m = mask;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    ids[k] = node.children[i];
                    ts[k] = t_near[i];
                    k += 1;
                    m &= m - 1;
                }
                if SORTED {
                    // Insertion sort, farthest first (stable: equal distances
                    // keep slot order, so the traversal is deterministic).
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
                    stack[sp] = Entry {
                        node: ids[i],
                        t: ts[i],
                    };
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
                        hi_w = f32x4::splat(hi);
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

/// Primitives under every BVH2 node (post-order without recursion).
fn subtree_counts(bvh2: &Bvh2) -> Vec<u32> {
    let mut counts = vec![0u32; bvh2.nodes.len()];
    let mut todo = vec![(0usize, false)];
    while let Some((n, children_done)) = todo.pop() {
        let node = &bvh2.nodes[n];
        if node.prim_count > 0 {
            counts[n] = node.prim_count;
        } else if children_done {
            let c = node.first_index as usize;
            counts[n] = counts[c] + counts[c + 1];
        } else {
            todo.push((n, true));
            todo.push((node.first_index as usize, false));
            todo.push((node.first_index as usize + 1, false));
        }
    }
    counts
}

/// Appends the primitive indices under BVH2 node `n`, left to right.
fn collect_primitives(bvh2: &Bvh2, n: usize, out: &mut Vec<u32>) {
    let mut todo = vec![n];
    while let Some(n) = todo.pop() {
        let node = &bvh2.nodes[n];
        if node.prim_count > 0 {
            let first = node.first_index as usize;
            out.extend_from_slice(&bvh2.primitive_indices[first..first + node.prim_count as usize]);
        } else {
            todo.push(node.first_index as usize + 1);
            todo.push(node.first_index as usize);
        }
    }
}

/// Up to `width` (≤ 8) BVH2 nodes covering inner node `n`'s primitives: its
/// two children, then repeatedly the largest-area one with more than one
/// primitive replaced by its two children (the usual greedy collapse).
fn open_children(bvh2: &Bvh2, n: usize, counts: &[u32], width: usize) -> [Option<usize>; 8] {
    let first = bvh2.nodes[n].first_index as usize;
    let mut kids = [None; 8];
    kids[0] = Some(first);
    kids[1] = Some(first + 1);
    let mut len = 2;
    while len < width.min(8) {
        let best = (0..len)
            .filter(|&k| {
                let c = kids[k].unwrap_or(0);
                bvh2.nodes[c].prim_count == 0 && counts[c] > 1
            })
            .max_by(|&a, &b| {
                // Ties in area (duplicate boxes) go to the larger subtree, so
                // that those stay balanced.
                let key = |k: usize| {
                    let c = kids[k].unwrap_or(0);
                    (bvh2.nodes[c].aabb().half_area(), counts[c])
                };
                let (ka, kb) = (key(a), key(b));
                ka.0.total_cmp(&kb.0).then(ka.1.cmp(&kb.1))
            });
        let Some(k) = best else { break };
        let c = kids[k].unwrap_or(0);
        let grand = bvh2.nodes[c].first_index as usize;
        kids[k] = Some(grand);
        kids[len] = Some(grand + 1);
        len += 1;
    }
    kids
}

/// The collapse that minimises the surface-area cost of the wide tree (Ylitie
/// et al. 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed
/// Wide BVHs", §4.1): for every BVH2 node `n` and slot budget `i`, the cheapest
/// way to hang `n`'s subtree from at most `i` slots of its wide parent, by
/// dynamic programming from the leaves up. Costs are areas × (1 per wide node,
/// `leaf_cost(count)` per leaf), so a small subtree becomes a leaf or a node by
/// what its rays will pay, not by filling slots.
pub(super) struct SahCollapse {
    width: usize,
    /// Per BVH2 node, how its subtree hangs from `i` slots: `choice[n][0]` is
    /// 0 for one leaf, else (one wide node) the share `k` of the node's
    /// `width` slots its left child takes; `choice[n][i − 1]` for `i ≥ 2` is
    /// 0 for "as for `i − 1`", else the left child's share `k` of `i` slots.
    /// The costs themselves live only on a stack while the children wait for
    /// their parent: 8 bytes per BVH2 node stay, not 72.
    choice: Vec<[u8; 8]>,
    /// The root's cost with one slot (area units of the build frame).
    #[cfg_attr(not(test), allow(dead_code))]
    root_cost: f64,
}

impl SahCollapse {
    pub(super) fn new(
        bvh2: &Bvh2,
        counts: &[u32],
        width: usize,
        max_leaf: u32,
        leaf_cost: impl Fn(u32) -> f64,
    ) -> Self {
        let mut choice = vec![[0u8; 8]; bvh2.nodes.len()];
        // cost[i − 1]: the subtree in at most `i` slots, for each finished
        // subtree whose parent is still to come (right child below left).
        let mut costs: Vec<[f64; 8]> = Vec::new();
        let mut todo = vec![(0usize, false)];
        while let Some((n, children_done)) = todo.pop() {
            let node = &bvh2.nodes[n];
            let area = node.aabb().half_area() as f64;
            if node.prim_count > 0 {
                costs.push([area * leaf_cost(node.prim_count); 8]);
                continue;
            }
            if !children_done {
                // Popped right subtree first, then left, then `n`.
                let l = node.first_index as usize;
                todo.extend([(n, true), (l, false), (l + 1, false)]);
                continue;
            }
            let (Some(left), Some(right)) = (costs.pop(), costs.pop()) else {
                unreachable!("both subtrees were pushed before their parent");
            };
            // distribute[j]: both children in at most j slots (j ≥ 2).
            let mut distribute = [(f64::INFINITY, 0u8); 9];
            for (j, d) in distribute.iter_mut().enumerate().take(width + 1).skip(2) {
                for k in 1..j {
                    let c = left[k - 1] + right[j - k - 1];
                    if c < d.0 {
                        *d = (c, k as u8);
                    }
                }
            }
            let leaf = if counts[n] <= max_leaf {
                area * leaf_cost(counts[n])
            } else {
                f64::INFINITY
            };
            let (inner, split) = (area + distribute[width].0, distribute[width].1);
            let mut cost = [f64::INFINITY; 8];
            (cost[0], choice[n][0]) = if leaf <= inner {
                (leaf, 0)
            } else {
                (inner, split)
            };
            for (i, &(split, k)) in distribute.iter().enumerate().take(width + 1).skip(2) {
                (cost[i - 1], choice[n][i - 1]) = if split < cost[i - 2] {
                    (split, k)
                } else {
                    (cost[i - 2], 0)
                };
            }
            costs.push(cost);
        }
        Self {
            width,
            choice,
            root_cost: costs.pop().map_or(0.0, |c| c[0]),
        }
    }

    /// Whether BVH2 node `n`, given one slot, is a leaf.
    pub(super) fn is_leaf(&self, bvh2: &Bvh2, n: usize) -> bool {
        bvh2.nodes[n].prim_count > 0 || self.choice[n][0] == 0
    }

    /// The slots of the wide node made from inner BVH2 node `n`: its children
    /// spread over at most `width` slots as the table chose.
    pub(super) fn slots(&self, bvh2: &Bvh2, n: usize) -> [Option<usize>; 8] {
        let mut out = [None; 8];
        let mut len = 0;
        let first = bvh2.nodes[n].first_index as usize;
        // (BVH2 node, slots it may take)
        let k = self.choice[n][0] as usize;
        let mut todo = vec![(first + 1, self.width - k), (first, k)];
        while let Some((c, mut i)) = todo.pop() {
            while i > 1 && self.choice[c][i - 1] == 0 {
                i -= 1;
            }
            if i <= 1 || bvh2.nodes[c].prim_count > 0 {
                out[len] = Some(c);
                len += 1;
                continue;
            }
            let k = self.choice[c][i - 1] as usize;
            let g = bvh2.nodes[c].first_index as usize;
            todo.push((g + 1, i - k));
            todo.push((g, k));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::super::bvh8::Node8;
    use super::*;
    use obvhs::aabb::Aabb;
    use obvhs::ploc::{PlocBuilder, PlocSearchDistance, SortPrecision};

    /// PLOC over `n` random small boxes in the unit cube.
    fn random_bvh2(n: usize, mut seed: u64) -> Bvh2 {
        let mut next = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / 16_777_216.0
        };
        let boxes: Vec<Aabb> = (0..n)
            .map(|_| {
                let lo = Vec3::new(next(), next(), next());
                let size = Vec3::new(next(), next(), next()) * 0.05;
                Aabb::new(lo, lo + size)
            })
            .collect();
        PlocBuilder::with_capacity(n).build(
            PlocSearchDistance::Medium,
            &boxes,
            (0..n as u32).collect(),
            SortPrecision::U64,
            3,
        )
    }

    /// The tree `from_bvh2` builds from the SAH table costs what the table says
    /// its root costs (so the reconstruction follows the table's choices), is
    /// never dearer than the greedy collapse under the same cost, and holds every
    /// primitive once.
    fn check_sah_collapse<N: WideNode>() {
        for (n, seed) in [(300, 1), (2000, 2)] {
            let bvh2 = random_bvh2(n, seed);
            let root_area = bvh2.nodes[0].aabb().half_area() as f64;
            for max_leaf in [1, 4, 8] {
                for block in [0.5f32, 1.0, 3.0] {
                    let leaf = |count| leaf_test_cost::<N>(block, count);
                    let table =
                        SahCollapse::new(&bvh2, &subtree_counts(&bvh2), N::WIDTH, max_leaf, leaf);
                    let sah = Bvh::<N>::from_bvh2(&bvh2, 1.0, max_leaf, Some(block));
                    let greedy = Bvh::<N>::from_bvh2(&bvh2, 1.0, max_leaf, None);
                    let (c_sah, c_greedy) = (sah.sah_cost(block), greedy.sah_cost(block));
                    let expected = table.root_cost / root_area;
                    assert!(
                        (c_sah - expected).abs() <= 1e-5 * expected,
                        "width {} leaf {max_leaf} block {block}: tree {c_sah}, table {expected}",
                        N::WIDTH
                    );
                    assert!(c_sah <= c_greedy * (1.0 + 1e-6), "{c_sah} > {c_greedy}");
                    let mut seen = sah.leaf_order.clone();
                    seen.sort_unstable();
                    assert_eq!(seen, (0..n as u32).collect::<Vec<_>>());
                }
            }
        }
    }

    #[test]
    fn sah_collapse_builds_the_tree_its_table_prices_4_wide() {
        check_sah_collapse::<Node4>();
    }

    #[test]
    fn sah_collapse_builds_the_tree_its_table_prices_8_wide() {
        check_sah_collapse::<Node8>();
    }

    /// The node test keeps every box the ray touches, judged in f64 (where the
    /// differences of f32 inputs are exact and a quotient is 2⁻⁵³-close): rays
    /// aimed at points on a box's edges and corners, where the exact interval
    /// shrinks to a point and an unpadded f32 test drops some (523 of the
    /// 6,946 that touch here, with `WIDEN_INV = 1`), from origins near and far
    /// (up to 10⁴ away), along all octants.
    #[test]
    fn the_node_test_keeps_every_box_the_ray_touches() {
        let mut seed = 7u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / 16_777_216.0
        };
        let (mut touching, mut kept) = (0, 0);
        for i in 0..10_000 {
            let lo = Vec3::new(next(), next(), next()) * 2.0 - 1.0;
            let hi = lo + Vec3::new(next(), next(), next()) * 0.5 + 1e-3;
            // A point on an edge (i odd) or a corner (i even) of the box.
            let pick = |a: f32, b: f32, u: f32, free: bool| {
                if free {
                    a + (b - a) * u
                } else if u < 0.5 {
                    a
                } else {
                    b
                }
            };
            let free_axis = if i % 2 == 1 { i / 2 % 3 } else { 3 };
            let target = Vec3::new(
                pick(lo.x, hi.x, next(), free_axis == 0),
                pick(lo.y, hi.y, next(), free_axis == 1),
                pick(lo.z, hi.z, next(), free_axis == 2),
            );
            let distance = [2.0, 50.0, 1e4][i % 3];
            let away = Vec3::new(next(), next(), next()) * 2.0 - 1.0;
            let org = target + away.normalize_or(Vec3::X) * distance;
            let dir = target - org;
            if dir.abs().min_element() < 1e-20 {
                continue;
            }
            let exact = (0..3).fold((0.0f64, f64::INFINITY), |(near, far), a| {
                let (o, d) = (org[a] as f64, dir[a] as f64);
                let (t0, t1) = ((lo[a] as f64 - o) / d, (hi[a] as f64 - o) / d);
                (near.max(t0.min(t1)), far.min(t0.max(t1)))
            });
            if exact.0 > exact.1 {
                continue;
            }
            touching += 1;
            let mut node = Node4::empty();
            node.set_child(2, lo.to_array(), hi.to_array());
            let ray = BoxRay::new(org, dir, 0.0);
            let (_, mask) = node.hit(&ray, f32x4::splat(f32::INFINITY));
            if mask & 0b100 != 0 {
                kept += 1;
            }
        }
        assert!(touching > 6_500, "{touching} rays touch their box");
        assert_eq!(
            kept, touching,
            "the node test dropped boxes the ray touches"
        );
    }
}
