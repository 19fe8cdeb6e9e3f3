//! The one traversal loop, for both node widths: nearest-first (or any-order)
//! descent with a stack ([`traverse`]), generic over the node's slab test
//! ([`NodeTest`]: four children with `wide::f32x4`, eight with AVX2
//! intrinsics). Everything it calls is `#[inline(always)]`, so each width's
//! instance compiles to the loop it had when written out twice.

use super::bvh4::{BoxRay, Bvh4, Node4};
#[cfg(target_arch = "x86_64")]
use super::bvh8::{Bvh8, Node8, Ray8};
use super::tree::{decode_leaf, Bvh, Tree, WideNode, EMPTY, LEAF_BIT, WIDEN};
use std::ops::IndexMut;

/// A node width's slab test, as the loop needs it.
///
/// # Safety
/// The methods may use instructions the CPU must have (the 8-wide node's:
/// AVX2), and must then be called from a function compiled with them.
pub(super) trait NodeTest: WideNode {
    /// The ray as this width's test reads it, made once per query.
    type Ray;
    /// The interval's upper end, splatted for the test.
    type Hi: Copy;
    /// The children's entry distances as the test leaves them (a register).
    type Near: Copy;
    /// `WIDTH` child references and entry distances: the loop's scratch.
    type Ids: Copy + Default + IndexMut<usize, Output = u32>;
    type Ts: Copy + Default + IndexMut<usize, Output = f32>;

    unsafe fn splat(hi: f32) -> Self::Hi;
    /// The mask of children entered within the ray's interval (upper end
    /// `hi`, already widened) and their entry distances.
    unsafe fn test(&self, ray: &Self::Ray, hi: Self::Hi) -> (u32, Self::Near);
    /// [`Self::test`]'s distances in memory, read only where two or more
    /// children were entered.
    unsafe fn spill(near: Self::Near) -> Self::Ts;
}

/// What the loop does at a leaf. A trait rather than closures: LLVM did not
/// inline the closest-hit leaf test, as a closure, into the 8-wide loop
/// once the loop and its callers moved apart (+2.6 % instructions on
/// cornell, callgrind); `#[inline(always)]` on these methods makes it. Taken
/// by value as a closure would be, its mutable state behind `&mut` fields:
/// a test behind one `&mut` had its read-only fields reloaded at every leaf
/// (+1.5 %).
pub(super) trait LeafTest {
    /// Tests the primitives `first..first + count`: the new upper end of the
    /// ray interval in the node test's distances, or `None` to stop.
    fn test(&mut self, first: usize, count: usize) -> Option<f32>;
    /// Starts loading those primitives (a hint).
    fn prefetch(&self, first: usize, count: usize);
}

/// A pending subtree on the traversal stack, with its entry distance.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Entry {
    pub(super) node: u32,
    pub(super) t: f32,
}

/// Visits the leaves whose boxes the ray overlaps, nearest box first
/// (`SORTED`) or in any order, and `leaf` tests them (see [`LeafTest`]);
/// the loop starts with the interval's upper end `t_hi` in the node test's
/// distances. `nodes_visited` counts node tests. `stack` must hold [`Bvh::stack_size`] entries.
///
/// # Safety
/// As [`NodeTest`]: the CPU has what `N`'s test needs, and the caller is
/// compiled with it.
#[inline(always)]
unsafe fn traverse<N: NodeTest, const SORTED: bool>(
    tree: &Bvh<N>,
    ray: &N::Ray,
    t_hi: f32,
    stack: &mut [Entry],
    nodes_visited: &mut u32,
    mut leaf: impl LeafTest,
) {
    let mut hi = t_hi * WIDEN;
    let mut hi_w = N::splat(hi);
    let mut sp = 0usize;
    let mut cur = tree.root;
    loop {
        while cur & LEAF_BIT == 0 {
            *nodes_visited += 1;
            let node = &tree.nodes[cur as usize];
            let (mask, t_near) = node.test(ray, hi_w);
            if mask == 0 {
                cur = EMPTY;
                break;
            }
            let children = node.children();
            if mask & (mask - 1) == 0 {
                cur = children[mask.trailing_zeros() as usize];
                continue;
            }
            let t_near = N::spill(t_near);
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
                    node: children[far],
                    t: t_near[far],
                };
                sp += 1;
                tree.prefetch_child(children[far], &|f, n| leaf.prefetch(f, n));
                cur = children[near];
                continue;
            }
            let (mut ids, mut ts, mut k) = (N::Ids::default(), N::Ts::default(), 0usize);
            let mut m = mask;
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                ids[k] = children[i];
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
                tree.prefetch_child(ids[i], &|f, n| leaf.prefetch(f, n));
            }
            cur = ids[k - 1];
        }
        if cur != EMPTY {
            let (first, count) = decode_leaf(cur);
            match leaf.test(first, count) {
                None => return,
                Some(t) => {
                    hi = hi.min(t * WIDEN);
                    hi_w = N::splat(hi);
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

/// A leaf test called out of line, for the 4-wide loop: inlined into it
/// (the 4-wide query then too large for LLVM to inline into
/// `Accel::intersect`), or the loop out of line instead, the accel bench's
/// 4-wide queries took 3.8 % or 1 % more instructions (callgrind).
struct OutOfLine<L>(L);

impl<L: LeafTest> LeafTest for OutOfLine<L> {
    #[inline(never)]
    fn test(&mut self, first: usize, count: usize) -> Option<f32> {
        self.0.test(first, count)
    }

    #[inline(always)]
    fn prefetch(&self, first: usize, count: usize) {
        self.0.prefetch(first, count)
    }
}

impl Bvh4 {
    /// [`traverse`] on four children per node, inline, with the leaf test
    /// out of line ([`OutOfLine`]).
    #[inline(always)]
    fn traverse<const SORTED: bool>(
        &self,
        ray: &BoxRay,
        t_hi: f32,
        stack: &mut [Entry],
        nodes_visited: &mut u32,
        leaf: impl LeafTest,
    ) {
        // SAFETY: the 4-wide test needs nothing beyond the build's target.
        unsafe { traverse::<Node4, SORTED>(self, ray, t_hi, stack, nodes_visited, OutOfLine(leaf)) }
    }
}

#[cfg(target_arch = "x86_64")]
impl Bvh8 {
    /// [`traverse`] on eight children per node, in an AVX2 function.
    ///
    /// # Safety
    /// The CPU must support AVX2 (`bvh8::supported`).
    #[target_feature(enable = "avx2")]
    unsafe fn traverse<const SORTED: bool>(
        &self,
        ray: &BoxRay,
        t_hi: f32,
        stack: &mut [Entry],
        nodes_visited: &mut u32,
        leaf: impl LeafTest,
    ) {
        let ray = Ray8::new(ray);
        traverse::<Node8, SORTED>(self, &ray, t_hi, stack, nodes_visited, leaf)
    }
}

impl Tree {
    /// [`traverse`] on either width (see there).
    #[inline(always)]
    pub(super) fn traverse<const SORTED: bool>(
        &self,
        ray: &BoxRay,
        t_hi: f32,
        stack: &mut [Entry],
        nodes_visited: &mut u32,
        leaf: impl LeafTest,
    ) {
        match self {
            Tree::Four(t) => t.traverse::<SORTED>(ray, t_hi, stack, nodes_visited, leaf),
            #[cfg(target_arch = "x86_64")]
            // SAFETY: an 8-wide tree is only built when `bvh8::supported()`.
            Tree::Eight(t) => unsafe {
                t.traverse::<SORTED>(ray, t_hi, stack, nodes_visited, leaf)
            },
            #[cfg(not(target_arch = "x86_64"))]
            Tree::Eight(_) => unreachable!("8-wide trees need x86_64"),
        }
    }
}
