//! The brute-force reference the trees are tested against (the unit tests and
//! `tests/accel.rs`): no tree, every primitive through the traversal's own
//! exact test. Test support, so hidden from the docs.

use super::{Accel, Hit, PrimRef};
use crate::math::Ray;
use crate::scene::{Mesh, Sphere};

/// The reference closest and any hit: every primitive tested with
/// [`Accel::intersect_primitive`] (the traversal's own exact tests), no
/// tree; ties go to the first in input order, as the traversal's do.
pub struct BruteForce<'a> {
    accel: &'a Accel,
    /// Every primitive in input order.
    prims: Vec<PrimRef>,
}

impl<'a> BruteForce<'a> {
    pub fn new(accel: &'a Accel, meshes: &[Mesh], spheres: &[Sphere]) -> Self {
        let triangles = meshes.iter().enumerate().flat_map(|(m, mesh)| {
            (0..mesh.triangles.len() as u32).map(move |tri| PrimRef::Triangle {
                mesh: m as u32,
                tri,
            })
        });
        let spheres = (0..spheres.len() as u32).map(PrimRef::Sphere);
        Self {
            accel,
            prims: triangles.chain(spheres).collect(),
        }
    }

    /// The accel whose primitives this tests.
    pub fn accel(&self) -> &'a Accel {
        self.accel
    }

    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        for &prim in &self.prims {
            if let Some(h) = self.accel.intersect_primitive(ray, prim) {
                if best.is_none_or(|b| h.t < b.t) {
                    best = Some(h);
                }
            }
        }
        best
    }

    pub fn occluded(&self, ray: &Ray) -> bool {
        self.prims
            .iter()
            .any(|&prim| self.accel.intersect_primitive(ray, prim).is_some())
    }
}
