//! Camera ray differentials → derivatives of the first hit's position, shading
//! normal (curvature, bump maps) and view direction with respect to the image
//! coordinates (the camera terms C of Eq. 26–27, for any camera ray).

use super::{GVec3, CAM, CDV, DV, SV};
use crate::accel::PrimRef;
use crate::math::dual::{DVec3, Dual};
use crate::math::{cross, Frame, Ray, Vec3};
use crate::render::interaction::Interaction;
use crate::scene::Scene;
use std::f32::consts::{PI, TAU};

/// Derivative lanes of the normal evaluation: ∂/∂u, ∂/∂v of the image, then two
/// unit tangent directions on the surface (for the curvature magnitude).
type N4 = DVec3<4>;

/// The first hit's x, n and ω_o as duals (lanes as in the module doc of
/// `gradients`), and the CV term.
#[derive(Clone, Copy, Debug)]
pub struct HitDuals {
    pub x: GVec3,
    pub n: GVec3,
    pub wo: GVec3,
    pub cv: f32,
}

/// Derivatives of the unit ray direction d = D/|D| given those of the
/// unnormalised direction D (the camera's `direction_derivatives`).
pub fn unit_direction_derivatives(d: Vec3, d_len: f32, dd_raw: [Vec3; 2]) -> [Vec3; 2] {
    dd_raw.map(|v| (v - d * d.dot(v)) / d_len)
}

/// Builds [`HitDuals`] for the hit `si` of the camera ray `ray` whose unit direction
/// has image derivatives `dd` (∂d/∂u, ∂d/∂v).
pub fn hit_duals(scene: &Scene, si: &Interaction, ray: &Ray, dd: [Vec3; 2]) -> HitDuals {
    let d = ray.dir;
    let t = si.t;
    let ng = si.ng;
    let dn = d.dot(ng);
    // Transfer of a ray differential to the tangent plane at the hit (Igehy 1999):
    // dx = t·dd − (t·dd·n / d·n) d.
    let dx = dd.map(|v| {
        if dn.abs() < 1e-8 {
            Vec3::ZERO
        } else {
            t * v - (t * v.dot(ng) / dn) * d
        }
    });
    let tangents = Frame::from_normal(ng);
    let xn = N4::with_lanes(si.p, [dx[0], dx[1], tangents.s, tangents.t]);
    let n4 = shading_normal(scene, si, xn, true);
    let n_lanes = [n4.lane(0), n4.lane(1)];
    let cv = 2.0 * (n4.lane(2).length_squared() + n4.lane(3).length_squared()).sqrt();

    let mut x_l = [Vec3::ZERO; super::LANES];
    x_l[SV] = dx[0];
    x_l[SV + 1] = dx[1];
    let mut n_l = [Vec3::ZERO; super::LANES];
    n_l[CDV] = n_lanes[0];
    n_l[CDV + 1] = n_lanes[1];
    let wo = -d;
    let wf = Frame::from_normal(wo);
    let mut w_l = [Vec3::ZERO; super::LANES];
    w_l[CAM] = -dd[0];
    w_l[CAM + 1] = -dd[1];
    w_l[DV] = wf.s;
    w_l[DV + 1] = wf.t;
    HitDuals {
        x: GVec3::with_lanes(si.p, x_l),
        n: GVec3::with_lanes(n4.value(), n_l),
        wo: GVec3::with_lanes(wo, w_l),
        cv: if cv.is_finite() { cv } else { 0.0 },
    }
}

/// The shading normal as a function of the surface position `x` (a dual whose
/// lanes move it in the tangent plane): the same computation as
/// `interaction::interaction`, differentiated. Bump maps use the analytic second
/// derivatives of the height (Sec. 4.2: n_x of a bump-mapped surface).
pub fn shading_normal(scene: &Scene, si: &Interaction, x: N4, with_bump: bool) -> N4 {
    let (base, ng_orig, uv, dpdu, dpdv, bump) = match si.prim {
        PrimRef::Triangle { mesh, tri } => {
            let m = &scene.meshes[mesh as usize];
            let [i0, i1, i2] = m.triangles[tri as usize].map(|i| i as usize);
            let (p0, p1, p2) = (m.positions[i0], m.positions[i1], m.positions[i2]);
            let e1 = p1 - p0;
            let e2 = p2 - p0;
            let nn = cross(e1, e2);
            let inv = 1.0 / nn.length_squared();
            let a = x - N4::constant(p0);
            // Barycentrics of x: b1 = a·(e2×N)/|N|², b2 = a·(N×e1)/|N|².
            let b1 = a.dot_const(cross(e2, nn) * inv);
            let b2 = a.dot_const(cross(nn, e1) * inv);
            let b0 = Dual::constant(1.0) - b1 - b2;
            let ng_orig = nn.normalize_or_zero();
            let base = if m.normals.is_empty() {
                N4::constant(ng_orig)
            } else {
                (N4::constant(m.normals[i0]) * b0
                    + N4::constant(m.normals[i1]) * b1
                    + N4::constant(m.normals[i2]) * b2)
                    .normalize()
            };
            let uv = if m.uvs.is_empty() {
                [b1, b2]
            } else {
                let (t0, t1, t2) = (m.uvs[i0], m.uvs[i1], m.uvs[i2]);
                [
                    b0 * t0.x + b1 * t1.x + b2 * t2.x,
                    b0 * t0.y + b1 * t1.y + b2 * t2.y,
                ]
            };
            (
                base,
                ng_orig,
                uv,
                N4::constant(si.dpdu),
                N4::constant(si.dpdv),
                m.bump,
            )
        }
        PrimRef::Sphere(i) => {
            let s = &scene.spheres[i as usize];
            let n = (x - N4::constant(s.center)).normalize();
            let sin_t = (n.x * n.x + n.z * n.z).sqrt();
            let phi = n.z.atan2(n.x);
            let theta = sin_t.atan2(n.y);
            let r = s.radius;
            let dpdu = N4 {
                x: -n.z,
                y: Dual::constant(0.0),
                z: n.x,
            }
            .scale(TAU * r);
            let inv_st = sin_t.recip();
            let dpdv = N4 {
                x: n.y * n.x * inv_st,
                y: -sin_t,
                z: n.y * n.z * inv_st,
            }
            .scale(PI * r);
            let uv = [phi.scale(1.0 / TAU), theta.scale(1.0 / PI)];
            (n, n.value(), uv, dpdu, dpdv, s.bump)
        }
    };
    let mut n = base;
    if let (Some(b), true) = (bump, with_bump) {
        let j = scene.bumps[b as usize].eval(crate::math::Vec2::new(uv[0].v, uv[1].v));
        // h_u and h_v along the lanes: dh_u = h_uu du + h_uv dv, dh_v = h_uv du + h_vv dv.
        let mut h_u = Dual::constant(j.h_u);
        let mut h_v = Dual::constant(j.h_v);
        for l in 0..4 {
            h_u.d[l] = j.h_uu * uv[0].d[l] + j.h_uv * uv[1].d[l];
            h_v.d[l] = j.h_uv * uv[0].d[l] + j.h_vv * uv[1].d[l];
        }
        let pu = dpdu + base * h_u;
        let pv = dpdv + base * h_v;
        let nb = pu.cross(pv);
        if nb.value().length_squared() > 0.0 && nb.value().is_finite() {
            let nb = nb.normalize();
            n = if nb.value().dot(base.value()) < 0.0 {
                -nb
            } else {
                nb
            };
        }
    }
    let sign = if si.front_face { 1.0 } else { -1.0 };
    let n = n.scale(sign);
    // Mirrors the fold in `interaction::finish`: a normal turned away from the
    // geometric one is replaced by it (and then has no derivative).
    if n.value().dot(ng_orig * sign) <= 1e-4 {
        return N4::constant(ng_orig * sign);
    }
    n
}

/// Curvature of the base surface at the hit, without bump maps: the "global
/// curvature k" of the Durand et al. metric (first-order paper Sec. 9.1), as
/// the norm of the normal's derivative per unit length (1/r on a sphere, 0 on a
/// flat quad, from the interpolated normals on a smooth mesh).
pub fn base_curvature(scene: &Scene, si: &Interaction) -> f32 {
    let t = Frame::from_normal(si.ng);
    let xn = N4::with_lanes(si.p, [t.s, t.t, Vec3::ZERO, Vec3::ZERO]);
    let n = shading_normal(scene, si, xn, false);
    let k = (0.5 * (n.lane(0).length_squared() + n.lane(1).length_squared())).sqrt();
    if k.is_finite() {
        k
    } else {
        0.0
    }
}
