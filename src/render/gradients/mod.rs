//! first hit + light samples → analytic image gradients ∂I/∂u, ∂I/∂v and the
//! first-order paper's terms (SV, DV, CV, CDV): the shading terms from the same
//! light sample and shadow ray as the radiance, the visibility term from a φ-line
//! and ring of shadow rays of its own (`visibility`).
//!
//! How: the direct-lighting integrand at a fixed light sample (a point y on an
//! emitter, in area measure, or a direction at infinity) is evaluated over dual
//! numbers whose lanes carry the derivatives of the shading point x, the shading
//! normal n and the view direction ω_o with respect to the image coordinates
//! (ray differentials, Eq. 26–27 generalised to any camera ray):
//!
//! * lanes 0,1 — ∂x/∂u, ∂x/∂v with n and ω_o fixed: the spatial variation of
//!   the incident light, SV = L_x ⊗ ρ (Eq. 25);
//! * lanes 2,3 — ∂n/∂u, ∂n/∂v (curvature, including bump maps, Sec. 4.2) with x and
//!   ω_o fixed: CDV = 2 n_x (L_θ ⊗ ρ) — the general-BRDF form of that product;
//! * lanes 4,5 — ∂ω_o/∂u, ∂ω_o/∂v: the camera term B_θ ∂θ/∂u of Eq. 26;
//! * lanes 6,7 — ω_o rotated along two unit tangents: the directional variation
//!   DV = L_θ ⊗ ρ as an angular gradient magnitude (per radian).
//!
//! Differentiating at a fixed area sample is unbiased for the derivative of the
//! unshadowed-boundary part of the integral, because the light's domain does not
//! move with x; the moving visibility boundary is the separate visibility term.
//! Sphere lights are the exception: held fixed in area measure their samples'
//! derivative grows as 1/cos θ_y at the silhouette (unbounded variance), so they
//! are held fixed in the coordinates of the cone they subtend instead
//! (`sphere_light`), which maps that cone onto itself for every x.
//!
//! Indirect light: the path's continuation from the first hit is a direction
//! sample of the same kind, so f·(n·ω_i)₊ at that fixed direction, over the same
//! duals, times the radiance the path brought back, gives the curvature/bump and
//! camera terms of the indirect light (`shading::indirect_sample`). Without it a
//! bumpy surface in shadow, lit only by bounced light, would have zero gradient.

pub mod geometry;
pub mod shading;
pub mod sphere_light;
pub mod visibility;

use crate::math::dual::{DVec3, Dual};
use crate::math::{luminance, Vec3};

/// Number of derivative lanes (see the module doc for their meaning).
pub const LANES: usize = 8;
pub type GDual = Dual<LANES>;
pub type GVec3 = DVec3<LANES>;

pub const SV: usize = 0;
pub const CDV: usize = 2;
pub const CAM: usize = 4;
pub const DV: usize = 6;

/// Per-sample gradient of the radiance, split into the paper's terms. All image
/// quantities are per pixel (u to the right, v downwards).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GradientSample {
    /// The value whose derivative the lanes are: the light-sampled direct
    /// illumination at the first hit (or the environment seen directly). Equal in
    /// expectation to the direct part of the radiance; the tests difference it.
    pub value: Vec3,
    pub sv: [Vec3; 2],
    pub cdv: [Vec3; 2],
    pub cam: [Vec3; 2],
    /// Angular gradient of the reflected radiance along two tangents of ω_o.
    pub dv: [Vec3; 2],
    /// Visibility (soft shadow) term of ∂I/∂u, ∂I/∂v.
    pub vis: [Vec3; 2],
    /// Indirect term: the first hit's BRDF × cosine differentiated through n and
    /// ω_o at the path's own continuation direction, times the radiance that path
    /// brought back (see [`indirect_sample`](shading::indirect_sample)).
    pub indirect: [Vec3; 2],
    /// 2·|∂n/∂x|: twice the Frobenius norm of the shading normal's derivative per
    /// unit length on the surface (the CV term; 0 on flat unbumped surfaces).
    pub cv: f32,
}

impl GradientSample {
    /// ∂I/∂u and ∂I/∂v: the sum of all terms.
    pub fn total(&self) -> [Vec3; 2] {
        [0, 1].map(|i| self.sv[i] + self.cdv[i] + self.cam[i] + self.vis[i] + self.indirect[i])
    }

    /// Adds `w ×` the lanes of an RGB dual contribution.
    pub fn add_lanes(&mut self, c: &[GDual; 3], w: f32) {
        self.value += Vec3::new(c[0].v, c[1].v, c[2].v) * w;
        let lane = |i: usize| Vec3::new(c[0].d[i], c[1].d[i], c[2].d[i]) * w;
        for k in 0..2 {
            self.sv[k] += lane(SV + k);
            self.cdv[k] += lane(CDV + k);
            self.cam[k] += lane(CAM + k);
            self.dv[k] += lane(DV + k);
        }
    }

    pub fn add_scaled(&mut self, o: &GradientSample, w: f32) {
        self.value += o.value * w;
        for k in 0..2 {
            self.sv[k] += o.sv[k] * w;
            self.cdv[k] += o.cdv[k] * w;
            self.cam[k] += o.cam[k] * w;
            self.dv[k] += o.dv[k] * w;
            self.vis[k] += o.vis[k] * w;
            self.indirect[k] += o.indirect[k] * w;
        }
        self.cv += o.cv * w;
    }
}

/// A pixel's running [`GradientSample`] sum as the film keeps it: the same 40
/// numbers in 12-byte vectors (160 bytes instead of the 224 of the sample's
/// SIMD-aligned ones, for every pixel of a gradient render).
#[derive(Clone, Copy, Debug, Default)]
pub struct GradientSum {
    /// `value`, then the (u, v) pairs of `sv`, `cdv`, `cam`, `dv`, `vis`, `indirect`.
    rgb: [glam::Vec3; 13],
    cv: f32,
}

impl GradientSum {
    /// Adds one sample (the bits of `GradientSample::add_scaled` with weight 1).
    pub fn add(&mut self, g: &GradientSample) {
        let mut sum = self.sample();
        sum.add_scaled(g, 1.0);
        *self = Self::from(&sum);
    }

    /// The sum as a [`GradientSample`].
    pub fn sample(&self) -> GradientSample {
        let r = |i: usize| Vec3::from(self.rgb[i]);
        let pair = |i: usize| [r(i), r(i + 1)];
        GradientSample {
            value: r(0),
            sv: pair(1),
            cdv: pair(3),
            cam: pair(5),
            dv: pair(7),
            vis: pair(9),
            indirect: pair(11),
            cv: self.cv,
        }
    }
}

impl From<&GradientSample> for GradientSum {
    fn from(g: &GradientSample) -> Self {
        let [sv, cdv, cam, dv, vis, ind] = [g.sv, g.cdv, g.cam, g.dv, g.vis, g.indirect];
        let v = [
            g.value, sv[0], sv[1], cdv[0], cdv[1], cam[0], cam[1], dv[0], dv[1], vis[0], vis[1],
            ind[0], ind[1],
        ];
        Self {
            rgb: v.map(glam::Vec3::from),
            cv: g.cv,
        }
    }
}

/// Magnitude of a (u, v) pair of RGB gradients, on luminance.
pub fn magnitude(g: &[Vec3; 2]) -> f32 {
    luminance(g[0]).hypot(luminance(g[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every field goes to its own slot and back: a swapped index would move one
    /// term's sum into another's plane.
    #[test]
    fn gradient_sum_keeps_each_term_in_its_place() {
        let mut k = 0.0f32;
        let mut next = || {
            k += 1.0;
            Vec3::new(k, k + 0.25, k + 0.5)
        };
        let mut pair = || [next(), next()];
        let g = GradientSample {
            value: Vec3::new(-1.0, -2.0, -3.0),
            sv: pair(),
            cdv: pair(),
            cam: pair(),
            dv: pair(),
            vis: pair(),
            indirect: pair(),
            cv: 0.75,
        };
        assert_eq!(GradientSum::from(&g).sample(), g);
        let mut sum = GradientSum::default();
        sum.add(&g);
        sum.add(&g);
        let mut twice = GradientSample::default();
        twice.add_scaled(&g, 1.0);
        twice.add_scaled(&g, 1.0);
        assert_eq!(sum.sample(), twice);
    }
}
