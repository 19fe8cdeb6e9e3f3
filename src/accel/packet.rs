//! Ray packets: eight rays traced together through the 8-wide tree
//! (`Bvh8::traverse_packet`), for callers that have eight rays at once — a
//! pixel's samples advanced in step (`render::path`'s wavefront). Each node's
//! boxes and each leaf's triangles are loaded once for the eight rays, and the
//! traversal's branches are taken once per packet instead of once per ray;
//! every lane runs the single-ray tests' very operations, so a lane's hit is
//! [`Accel::intersect`]'s (or [`Accel::occluded`]'s) bit for bit. Where the
//! tree is 4-wide (no AVX2) the packet is traced ray by ray.

use super::bvh8::{BoxRays8, PacketEntry};
use super::primitive::avx::Rays8;
use super::primitive::WatertightRay;
use super::{bvh4, nearer, node_ray_parts, Accel, Hit, LeafCode, Tree, EMPTY_LANE};
use crate::math::{Ray, Vec2, Vec3};
use std::cell::RefCell;

/// The rays of a packet as the traversal and the leaf tests need them.
struct Packet<'r> {
    rays: &'r [Ray; 8],
    /// Lanes with a ray to trace.
    active: u32,
    wr: [WatertightRay; 8],
    boxes: BoxRays8,
    /// How far each lane's node ray starts behind its origin (`node_ray`).
    back_off: [f32; 8],
    /// Lanes with t_min ≥ 0 (the triangle test's t > δt applies).
    forward: u32,
    t_min: [f32; 8],
}

impl<'r> Packet<'r> {
    fn new(accel: &Accel, rays: &'r [Ray; 8], active: u32) -> Self {
        let mut p = Self {
            rays,
            active: 0,
            wr: [WatertightRay::new(Vec3::ZERO, Vec3::Z); 8],
            boxes: BoxRays8::default(),
            back_off: [0.0; 8],
            forward: 0,
            t_min: [0.0; 8],
        };
        // Unused lanes keep a harmless ray (+z from the origin); their results
        // are masked out.
        let negative = f32::from_bits(u32::MAX);
        for (l, ray) in rays.iter().enumerate() {
            if active >> l & 1 == 0 || !accel.traversable(ray) {
                p.boxes.inv[2][l] = 1.0;
                continue;
            }
            p.active |= 1 << l;
            // Each lane as `node_ray` and `BoxRay::new` set up a single ray.
            let (origin, dir, t_lo, back_off) = node_ray_parts(ray);
            let (o, inv, d) = (
                origin.to_array(),
                (Vec3::ONE / dir).to_array(),
                dir.to_array(),
            );
            for a in 0..3 {
                p.boxes.org[a][l] = o[a];
                p.boxes.inv[a][l] = inv[a];
                p.boxes.negative[a][l] = if d[a] < 0.0 { negative } else { 0.0 };
            }
            p.boxes.t_lo[l] = t_lo;
            p.back_off[l] = back_off;
            p.wr[l] = WatertightRay::new(ray.origin, ray.dir);
            p.forward |= ((ray.t_min >= 0.0) as u32) << l;
            p.t_min[l] = ray.t_min;
        }
        p
    }

    /// Each lane's widened far distance at the start ([`bvh4::WIDEN`]).
    fn hi(&self) -> [f32; 8] {
        std::array::from_fn(|i| (self.rays[i].t_max + self.back_off[i]) * bvh4::WIDEN)
    }

    fn lanes(mut m: u32) -> impl Iterator<Item = usize> {
        std::iter::from_fn(move || {
            (m != 0).then(|| {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                l
            })
        })
    }
}

thread_local! {
    /// Each thread's packet traversal stack (as `STACK` for single rays).
    static PACKET_STACK: RefCell<Vec<PacketEntry>> = const { RefCell::new(Vec::new()) };
}

impl Accel {
    /// [`Accel::intersect`] for the rays of the `active` lanes (bit i: `rays[i]`),
    /// traced as one packet; lanes outside `active` get `None`.
    pub fn intersect8(&self, rays: &[Ray; 8], active: u32) -> [Option<Hit>; 8] {
        #[cfg(target_arch = "x86_64")]
        if let Tree::Eight(_) = self.bvh {
            // SAFETY: an 8-wide tree is only built where AVX2 is.
            return unsafe { self.closest8(&Packet::new(self, rays, active)) };
        }
        std::array::from_fn(|i| {
            (active >> i & 1 == 1)
                .then(|| self.intersect(&rays[i]))
                .flatten()
        })
    }

    /// [`Accel::occluded`] for the rays of the `active` lanes, traced as one
    /// packet: bit i set when `rays[i]` is occluded.
    pub fn occluded8(&self, rays: &[Ray; 8], active: u32) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if let Tree::Eight(_) = self.bvh {
            // SAFETY: as in `intersect8`.
            return unsafe { self.any8(&Packet::new(self, rays, active)) };
        }
        (0..8).fold(0, |m, i| {
            m | ((active >> i & 1 == 1 && self.occluded(&rays[i])) as u32) << i
        })
    }

    /// # Safety
    /// AVX2 (an 8-wide tree).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn closest8(&self, p: &Packet) -> [Option<Hit>; 8] {
        let Tree::Eight(tree) = &self.bvh else {
            unreachable!("packets traverse the 8-wide tree")
        };
        let rays8 = Rays8::new(&p.wr);
        let mut best: [Option<(u32, f32, Vec2, u32)>; 8] = [None; 8];
        let mut t_max = p.rays.map(|r| r.t_max);
        let mut hi = p.hi();
        let mut take = |l: usize,
                        id: u32,
                        t: f32,
                        bary: Vec2,
                        slot: u32,
                        t_max: &mut [f32; 8],
                        hi: &mut [f32; 8]| {
            if nearer(t, id, best[l].map(|(b, bt, ..)| (bt, b))) {
                best[l] = Some((id, t, bary, slot));
                t_max[l] = t;
                hi[l] = hi[l].min((t + p.back_off[l]) * bvh4::WIDEN);
            }
        };
        with_packet_stack(self.bvh.stack_size(), |stack| {
            tree.traverse_packet::<true>(
                &p.boxes,
                &mut hi,
                p.active,
                stack,
                |first, code, lanes, hi| {
                    let (count, spheres) = LeafCode::decode(code);
                    for (b, block) in self.blocks[first..first + count].iter().enumerate() {
                        for (j, &id) in block.ids.iter().enumerate() {
                            if id == EMPTY_LANE {
                                continue;
                            }
                            let slot = 4 * (first + b) as u32 + j as u32;
                            let prim = || self.prim_of_input(id);
                            if spheres && id >= self.first_sphere {
                                for l in Packet::lanes(lanes) {
                                    if let Some(h) =
                                        prim().intersect(&p.rays[l], &p.wr[l], t_max[l])
                                    {
                                        take(l, id, h.t, h.bary, slot, &mut t_max, hi);
                                    }
                                }
                                continue;
                            }
                            let h = rays8.intersect::<false>(
                                &block.tris.rows(j),
                                &p.t_min,
                                &t_max,
                                p.forward,
                            );
                            for l in Packet::lanes((h.hits | h.fallback) & lanes) {
                                let found = if h.hits >> l & 1 == 1 {
                                    Some((h.t[l], Vec2::new(h.b1[l], h.b2[l])))
                                } else {
                                    prim()
                                        .intersect(&p.rays[l], &p.wr[l], t_max[l])
                                        .map(|h| (h.t, h.bary))
                                };
                                if let Some((t, bary)) = found {
                                    take(l, id, t, bary, slot, &mut t_max, hi);
                                }
                            }
                        }
                    }
                    u32::MAX
                },
            )
        });
        best.map(|b| {
            b.map(|(id, t, bary, slot)| Hit {
                t,
                prim: self.prim_ref_of_input(id),
                bary,
                slot,
            })
        })
    }

    /// # Safety
    /// AVX2 (an 8-wide tree).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn any8(&self, p: &Packet) -> u32 {
        let Tree::Eight(tree) = &self.bvh else {
            unreachable!("packets traverse the 8-wide tree")
        };
        let rays8 = Rays8::new(&p.wr);
        let t_max = p.rays.map(|r| r.t_max);
        let mut hi = p.hi();
        let mut occluded = 0u32;
        with_packet_stack(self.bvh.stack_size(), |stack| {
            tree.traverse_packet::<false>(
                &p.boxes,
                &mut hi,
                p.active,
                stack,
                |first, code, lanes, _| {
                    let (count, spheres) = LeafCode::decode(code);
                    let mut open = lanes & !occluded;
                    for block in &self.blocks[first..first + count] {
                        for (j, &id) in block.ids.iter().enumerate() {
                            if id == EMPTY_LANE || open == 0 {
                                continue;
                            }
                            let prim = || self.prim_of_input(id);
                            let scalar = if spheres && id >= self.first_sphere {
                                open
                            } else {
                                let h = rays8.intersect::<true>(
                                    &block.tris.rows(j),
                                    &p.t_min,
                                    &t_max,
                                    p.forward,
                                );
                                open &= !h.hits;
                                h.fallback & open
                            };
                            for l in Packet::lanes(scalar) {
                                if prim().intersect(&p.rays[l], &p.wr[l], t_max[l]).is_some() {
                                    open &= !(1 << l);
                                }
                            }
                        }
                    }
                    occluded |= lanes & !open;
                    !occluded
                },
            )
        });
        occluded & p.active
    }
}

/// Runs `f` on this thread's packet stack with at least `size` entries.
fn with_packet_stack<R>(size: usize, f: impl FnOnce(&mut [PacketEntry]) -> R) -> R {
    PACKET_STACK.with_borrow_mut(|stack| {
        if stack.len() < size {
            stack.resize(size, PacketEntry::default());
        }
        f(stack)
    })
}
