//! The direct-lighting integrand at one fixed light sample, over duals:
//! f(ω_o, ω_i; n) (n·ω_i)₊ L_e G / p, whose lanes are the gradient terms.

use super::geometry::HitDuals;
use super::{GDual, GVec3, CAM, CDV};
use crate::brdf::Material;
use crate::math::Vec3;
use crate::scene::Environment;

/// A light sample as the gradient stage sees it.
#[derive(Clone, Copy, Debug)]
pub enum LightPoint {
    /// A point y on an emitter with normal n_y; `pdf_area` is the density of
    /// choosing y in area measure (light choice included).
    Area {
        y: Vec3,
        ny: Vec3,
        radiance: Vec3,
        pdf_area: f32,
    },
    /// A direction at infinity with solid-angle density `pdf`.
    Direction { wi: Vec3, radiance: Vec3, pdf: f32 },
}

/// f·(n·ω_i)₊ L_e G / p and its derivatives. The light point is held fixed (in
/// area measure for emitters), so the derivatives are those of the integrand of
/// a fixed-domain integral: an unbiased estimate of ∂B (Eq. 25's terms).
pub fn direct_sample(material: &Material, h: &HitDuals, light: &LightPoint) -> [GDual; 3] {
    let (wi, radiance, scale) = match *light {
        LightPoint::Area {
            y,
            ny,
            radiance,
            pdf_area,
        } => {
            let to = GVec3::constant(y) - h.x;
            let r2 = to.length_squared();
            let wi = to * r2.sqrt().recip();
            // Geometry term of the emitter side: cos θ_y / r².
            let cos_y = -wi.dot_const(ny);
            (wi, radiance, cos_y.max0() / r2 * (1.0 / pdf_area))
        }
        LightPoint::Direction { wi, radiance, pdf } => {
            (GVec3::constant(wi), radiance, GDual::constant(1.0 / pdf))
        }
    };
    let f_cos = brdf_cos(material, h.n, h.wo, wi);
    [0, 1, 2].map(|c| f_cos[c] * scale * radiance[c])
}

/// The indirect part of ∂I/∂u, ∂I/∂v from one continuation of the path: the path
/// left the first hit along `wi` (world space, density `pdf` in solid angle) and
/// brought back `l_in`, the radiance arriving along `wi` (everything the path
/// gathered beyond the first hit except emitters seen directly, which the direct
/// term covers). Differentiating f·(n·ω_i)₊ through the normal (CDV lanes:
/// curvature and bump maps) and the view direction (CAM lanes) at fixed `wi`
/// is unbiased for those terms of the indirect integral (its domain does not move;
/// the cosine vanishes at the horizon). Not included: the spatial variation of the
/// incident indirect field (∂L_in/∂x, the SV term of indirect light) — indirect
/// light is treated as distant, the far-field case of Sec. 5.2 — and, on bump maps,
/// the moving boundary of the geometric hemisphere (paths below it end), where the
/// tilted shading cosine is small but not zero. Per sample the estimate is
/// heavy-tailed near the horizon (∝ (∂n·ω_i)/(n·ω_i) under cosine sampling); the
/// sampler subtracts the gradient's variance and the reconstruction slope-limits, so
/// outliers neither draw samples nor paint blobs.
pub fn indirect_sample(
    material: &Material,
    h: &HitDuals,
    wi: Vec3,
    pdf: f32,
    l_in: Vec3,
) -> [Vec3; 2] {
    // A path that brought nothing back (it escaped into a black sky, or ended)
    // has no indirect gradient: skip the dual evaluation.
    if !(pdf > 0.0 && pdf.is_finite()) || l_in == Vec3::ZERO {
        return [Vec3::ZERO; 2];
    }
    let f_cos = brdf_cos(material, h.n, h.wo, GVec3::constant(wi));
    let scale = l_in / pdf;
    [0, 1].map(|k| {
        let lane = |l: usize| Vec3::new(f_cos[0].d[l], f_cos[1].d[l], f_cos[2].d[l]);
        (lane(CDV + k) + lane(CAM + k)) * scale
    })
}

/// f(ω_o, ω_i; n) · (n·ω_i)₊ in world space, per RGB channel, over duals: the
/// materials' own implementation ([`Material::f_cos_world`]); zero for delta lobes.
pub fn brdf_cos(material: &Material, n: GVec3, wo: GVec3, wi: GVec3) -> [GDual; 3] {
    material.f_cos_world(components(n), components(wo), components(wi))
}

/// Radiance of the environment seen along the dual direction `d` (for camera
/// rays that escape: the view-direction lanes then carry ∂L_env/∂u, ∂L_env/∂v).
pub fn environment(env: &Environment, d: GVec3) -> [GDual; 3] {
    env.radiance(components(d))
}

fn components(v: GVec3) -> [GDual; 3] {
    [v.x, v.y, v.z]
}
