//! triangles + spheres → BVH (obvhs CWBVH) answering closest-hit and any-hit
//! (shadow) queries.
//!
//! OWNED BY THE ACCEL WORK ITEM — the bodies below are placeholders to be replaced.

use crate::math::{Ray, Vec2};
use crate::scene::{Mesh, Sphere};
use std::time::Duration;

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

/// The acceleration structure over all shapes of a scene.
pub struct Accel {
    build_time: Duration,
}

impl Accel {
    pub fn build(_meshes: &[Mesh], _spheres: &[Sphere]) -> Self {
        Self {
            build_time: Duration::ZERO,
        }
    }
    /// Closest hit with t in [ray.t_min, ray.t_max].
    pub fn intersect(&self, _ray: &Ray) -> Option<Hit> {
        None
    }
    /// True if anything is hit with t in [ray.t_min, ray.t_max].
    pub fn occluded(&self, _ray: &Ray) -> bool {
        false
    }
    pub fn build_time(&self) -> Duration {
        self.build_time
    }
}
