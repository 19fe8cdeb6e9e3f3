//! Icosahedral direction sets (Sec. 4.2): level 0 is the icosahedron's 12
//! vertices, each level splits every face 1-to-4 at its normalised edge midpoints.
//! Vertex ids are nested: level ℓ's vertices are ids `0..level_end[ℓ]`. Directions
//! are located by descending the face tree and interpolated with gnomonic
//! barycentrics (planar barycentrics of the ray through the flat face).
//!
//! Only view directions in the upper hemisphere are ever asked for, so the vertices
//! that some face touching z > 0 needs get compact "slots", nested per level too.

use crate::math::{cross, Vec3};
use std::collections::HashMap;

pub struct Icosphere {
    pub vertices: Vec<Vec3>,
    /// Vertices of levels ≤ ℓ are `0..level_end[ℓ]`.
    pub level_end: Vec<usize>,
    /// Faces per level, counter-clockwise seen from outside; the children of face f
    /// of level ℓ are faces 4f..4f+4 of level ℓ + 1.
    faces: Vec<Vec<[u32; 3]>>,
    /// Per face (b × c, c × a, a × b): the gnomonic barycentrics of a direction
    /// are its dot products with them, so locating one costs no cross products.
    edge_normals: Vec<Vec<[Vec3; 3]>>,
    /// Compact index of a vertex that the upper hemisphere needs (`u32::MAX`: none).
    slot_of: Vec<u32>,
    /// Slots of levels ≤ ℓ are `0..slot_end[ℓ]`.
    pub slot_end: Vec<usize>,
    /// The vertex of each slot.
    pub slot_vertex: Vec<u32>,
}

/// A direction's enclosing face at some level: three slots and their weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Located {
    pub slots: [u32; 3],
    pub weights: [f32; 3],
}

impl Icosphere {
    /// The sets up to and including `max_level`.
    pub fn new(max_level: usize) -> Self {
        let (mut vertices, base) = crate::math::icosahedron();
        let mut faces = vec![base];
        let mut level_end = vec![vertices.len()];
        for level in 0..max_level {
            let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
            let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<Vec3>| -> u32 {
                *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    let m = (vertices[a as usize] + vertices[b as usize]).normalize();
                    vertices.push(m);
                    (vertices.len() - 1) as u32
                })
            };
            let mut next = Vec::with_capacity(faces[level].len() * 4);
            for &[a, b, c] in &faces[level] {
                let ab = midpoint(a, b, &mut vertices);
                let bc = midpoint(b, c, &mut vertices);
                let ca = midpoint(c, a, &mut vertices);
                next.extend_from_slice(&[[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
            }
            faces.push(next);
            level_end.push(vertices.len());
        }
        // Slots: corners of every face with a corner strictly above the horizon. A
        // face whose corners are all at z ≤ 0 lies in the lower hemisphere.
        let mut needed = vec![false; vertices.len()];
        for level_faces in &faces {
            for f in level_faces {
                if f.iter().any(|&v| vertices[v as usize].z > 0.0) {
                    for &v in f {
                        needed[v as usize] = true;
                    }
                }
            }
        }
        let mut slot_of = vec![u32::MAX; vertices.len()];
        let mut slot_vertex = Vec::new();
        for (v, &n) in needed.iter().enumerate() {
            if n {
                slot_of[v] = slot_vertex.len() as u32;
                slot_vertex.push(v as u32);
            }
        }
        let slot_end = level_end
            .iter()
            .map(|&end| slot_vertex.partition_point(|&v| (v as usize) < end))
            .collect();
        let edge_normals = faces
            .iter()
            .map(|level_faces| {
                level_faces
                    .iter()
                    .map(|f| {
                        let [a, b, c] = f.map(|v| vertices[v as usize]);
                        [cross(b, c), cross(c, a), cross(a, b)]
                    })
                    .collect()
            })
            .collect();
        Self {
            vertices,
            level_end,
            faces,
            edge_normals,
            slot_of,
            slot_end,
            slot_vertex,
        }
    }

    pub fn max_level(&self) -> usize {
        self.faces.len() - 1
    }

    /// The direction of a slot.
    pub fn slot_direction(&self, slot: u32) -> Vec3 {
        self.vertices[self.slot_vertex[slot as usize] as usize]
    }

    /// The level at which a slot first appears.
    pub fn slot_level(&self, slot: u32) -> usize {
        self.slot_end.partition_point(|&end| end <= slot as usize)
    }

    /// Unnormalised gnomonic barycentrics of `d` in face `f` (all ≥ 0 inside).
    fn dets(&self, level: usize, f: usize, d: Vec3) -> [f32; 3] {
        self.edge_normals[level][f].map(|n| d.dot(n))
    }

    /// The face of level `level` around unit direction `d` and its barycentric
    /// weights; `d` must be in the upper hemisphere (z ≥ 0) for the slots to exist.
    pub fn locate(&self, d: Vec3, level: usize) -> Located {
        let level = level.min(self.max_level());
        let min_det = |w: [f32; 3]| w[0].min(w[1]).min(w[2]);
        let best = |candidates: std::ops::Range<usize>, level: usize| -> usize {
            let mut best = (candidates.start, f32::NEG_INFINITY);
            for i in candidates {
                let m = min_det(self.dets(level, i, d));
                if m > best.1 {
                    best = (i, m);
                }
            }
            best.0
        };
        let mut f = best(0..20, 0);
        for l in 1..=level {
            f = best(4 * f..4 * f + 4, l);
        }
        let face = self.faces[level][f];
        let w = self.dets(level, f, d).map(|x| x.max(0.0));
        let sum = w[0] + w[1] + w[2];
        let weights = if sum > 0.0 {
            w.map(|x| x / sum)
        } else {
            [1.0 / 3.0; 3]
        };
        Located {
            slots: face.map(|v| self.slot_of[v as usize]),
            weights,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_have_the_icosphere_counts_and_nested_slots() {
        let ico = Icosphere::new(4);
        assert_eq!(ico.level_end, vec![12, 42, 162, 642, 2562]);
        for l in 0..=4 {
            for k in 0..200 {
                let u = (k as f32 + 0.5) / 200.0;
                let phi = 37.0 * u;
                let z = u;
                let r = (1.0 - z * z).sqrt();
                let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                let loc = ico.locate(d, l);
                let mut back = Vec3::ZERO;
                for i in 0..3 {
                    assert!(loc.slots[i] != u32::MAX, "level {l}: slot missing");
                    assert!((loc.slots[i] as usize) < ico.slot_end[l]);
                    back += ico.slot_direction(loc.slots[i]) * loc.weights[i];
                }
                // Gnomonic barycentrics reproduce the direction up to length.
                assert!(back.normalize().dot(d) > 1.0 - 1e-5, "level {l}");
            }
        }
    }
}
