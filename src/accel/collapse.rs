//! obvhs' BVH2 → our wide tree ([`Bvh`]): the greedy collapse, and the
//! SAH-optimal one ([`SahCollapse`]) the default build uses.

use super::tree::{leaf_test_cost, Bvh, WideNode, COUNT_SHIFT, EMPTY, LEAF_BIT, MAX_LEAF};
use obvhs::bvh2::Bvh2;

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
        // (BVH2 node, parent wide node or EMPTY for the root, slot, depth)
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
struct SahCollapse {
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
    fn new(
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
    fn is_leaf(&self, bvh2: &Bvh2, n: usize) -> bool {
        bvh2.nodes[n].prim_count > 0 || self.choice[n][0] == 0
    }

    /// The slots of the wide node made from inner BVH2 node `n`: its children
    /// spread over at most `width` slots as the table chose.
    fn slots(&self, bvh2: &Bvh2, n: usize) -> [Option<usize>; 8] {
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
    use super::super::bvh4::Node4;
    use super::super::bvh8::Node8;
    use super::*;
    use crate::math::Vec3;
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
}
