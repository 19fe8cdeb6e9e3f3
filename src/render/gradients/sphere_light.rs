//! Sphere lights in cone coordinates: the shading lanes of a sphere-light sample
//! differentiated with the sample's *cone coordinates* held fixed, not its point on
//! the sphere.
//!
//! Why: held fixed in area measure (a point y on the sphere), the integrand carries
//! cos θ_y / |y − x|² / p_area, whose derivative has a factor ∂cos θ_y / cos θ_y that
//! grows as 1/cos θ_y at the sphere's silhouette as seen from x. Cone sampling puts
//! samples there with P(cos θ_y < ε) ∝ ε², so the estimate is unbiased but its
//! variance diverges (logarithmically): single samples with |∇I| 10⁴× the typical
//! value (issue 12, D2). In cone coordinates u ∈ \[0,1\]² the cone of directions the
//! sphere subtends is mapped onto itself for every x, so the domain of the integral
//! ∫ T(ω(x, u)) J(x, u) du does not move, and differentiating under it is unbiased;
//! ω(x, u) and J(x, u) are smooth in x up to the silhouette, so the estimate is
//! bounded. The frame around the cone's axis follows it by the minimal rotation
//! (any smooth choice is unbiased; this one needs no frame derivative). The
//! visibility term must then be taken relative to the same flow ∂ω/∂x
//! (`visibility::trace_line_and_ring` does).

use super::geometry::HitDuals;
use super::shading::brdf_cos;
use super::{GDual, GVec3, LANES, SV};
use crate::brdf::Material;
use crate::math::Vec3;

/// How a sampler places directions in the cone: what is held fixed as x moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConeLaw {
    /// Uniform in solid angle (`LightSet::sample`): cos θ = 1 − u (1 − cos θmax),
    /// weight 1/p = 2π (1 − cos θmax).
    Uniform,
    /// A φ-line's stratified θ (`visibility::trace_line`): θ = u θmax, weight
    /// 1/p = 2π sin θ · θmax / n.
    Line,
}

/// The derivatives of one cone sample along two displacements of the shading point:
/// the direction's flow ∂ω and the relative change ∂(1/p) / (1/p) of its weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeFlow {
    pub dw: [Vec3; 2],
    pub dlog_weight: [f32; 2],
}

/// ∂ω/∂x · δ and ∂ ln(1/p)/∂x · δ for the direction `w` toward the sphere light
/// (`centre`, `radius`) from `x`, for δ = each of `dx`. `None` inside the sphere.
///
/// With a = (c − x)/d the cone's axis and sin θmax = r/d: ∂a = −(δ − (δ·a) a)/d and
/// ∂θmax = tan θmax (δ·a)/d. A direction ω = a cos θ + e sin θ moves by the minimal
/// rotation of the axis, ∂a cos θ − a (∂a·e) sin θ, plus ∂θ e_θ with ∂θ from the law.
pub fn cone_flow(
    x: Vec3,
    centre: Vec3,
    radius: f32,
    w: Vec3,
    law: ConeLaw,
    dx: [Vec3; 2],
) -> Option<ConeFlow> {
    let to_c = centre - x;
    let d = to_c.length();
    if d.is_nan() || d <= radius * 1.0001 {
        return None;
    }
    let a = to_c / d;
    let sin_max = radius / d;
    let cos_max = (1.0 - sin_max * sin_max).max(0.0).sqrt();
    let theta_max = sin_max.asin();
    let cos_t = w.dot(a).clamp(-1.0, 1.0);
    let perp = w - a * cos_t;
    let sin_t = perp.length();
    let (e, e_theta) = if sin_t > 1e-7 {
        let e = perp / sin_t;
        (e, e * cos_t - a * sin_t)
    } else {
        (Vec3::ZERO, Vec3::ZERO)
    };
    let theta = sin_t.atan2(cos_t);
    let mut out = ConeFlow {
        dw: [Vec3::ZERO; 2],
        dlog_weight: [0.0; 2],
    };
    for (k, delta) in dx.iter().enumerate() {
        let da = -(*delta - a * delta.dot(a)) / d;
        let dtheta_max = sin_max / cos_max.max(1e-12) * delta.dot(a) / d;
        let (dtheta, dlog) = match law {
            ConeLaw::Uniform => {
                // d cos θ = u d cos θmax with u = (1 − cos θ)/(1 − cos θmax).
                let one_minus = (1.0 - cos_max).max(1e-12);
                let u = (1.0 - cos_t) / one_minus;
                let dtheta = if sin_t > 1e-7 {
                    u * sin_max * dtheta_max / sin_t
                } else {
                    0.0
                };
                (dtheta, sin_max * dtheta_max / one_minus)
            }
            ConeLaw::Line => {
                let dtheta = theta / theta_max.max(1e-12) * dtheta_max;
                let cot = if sin_t > 1e-7 { cos_t / sin_t } else { 0.0 };
                (dtheta, dtheta_max / theta_max.max(1e-12) + cot * dtheta)
            }
        };
        out.dw[k] = da * cos_t - a * (da.dot(e) * sin_t) + e_theta * dtheta;
        out.dlog_weight[k] = dlog;
    }
    let finite =
        out.dw.iter().all(|v| v.is_finite()) && out.dlog_weight.iter().all(|v| v.is_finite());
    finite.then_some(out)
}

/// f·(n·ω)₊ L / p for a sphere-light sample `wi` of weight 1/p = `weight`, over the
/// gradient duals, with the sample's cone coordinates (not its point on the sphere)
/// held fixed: the SV lanes carry the flow of [`cone_flow`]. `far` is the far-light
/// criterion (CV, factor) of `path::light_point`: a light far enough for the surface's
/// curvature keeps its direction fixed (no SV term).
#[allow(clippy::too_many_arguments)]
pub fn direct_sample(
    material: &Material,
    h: &HitDuals,
    centre: Vec3,
    radius: f32,
    wi: Vec3,
    radiance: Vec3,
    weight: f32,
    law: ConeLaw,
    far: Option<(f32, f32)>,
) -> [GDual; 3] {
    let x = h.x.value();
    let dx = [h.x.lane(SV), h.x.lane(SV + 1)];
    let is_far = far.is_some_and(|(cv, factor)| cv * ((centre - x).length() - radius) > factor);
    let flow = if is_far {
        None
    } else {
        cone_flow(x, centre, radius, wi, law, dx)
    };
    let mut lanes = [Vec3::ZERO; LANES];
    let mut dw = [0.0f32; LANES];
    if let Some(f) = flow {
        for k in 0..2 {
            lanes[SV + k] = f.dw[k];
            dw[SV + k] = weight * f.dlog_weight[k];
        }
    }
    let wi = GVec3::with_lanes(wi, lanes);
    let weight = GDual::new(weight, dw);
    let f_cos = brdf_cos(material, h.n, h.wo, wi);
    [0, 1, 2].map(|c| f_cos[c] * weight * radiance[c])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{cross, warp, Frame, Vec2};

    /// The flow of each law is the derivative of the sampled direction (and of the
    /// weight) at fixed sample coordinates, against central differences of the
    /// warps themselves with the frame carried by the minimal rotation.
    #[test]
    fn cone_flow_matches_differences_of_the_warp() {
        let (centre, radius) = (Vec3::new(0.4, 2.0, -0.3), 0.5f32);
        let x0 = Vec3::new(0.1, 0.0, 0.2);
        let dx = [Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.2, 0.3, -0.9)];
        let frame0 = Frame::from_normal((centre - x0).normalize());
        // Frame at x: the minimal rotation of frame0 taking its axis to the new axis.
        let frame_at = |x: Vec3| {
            let a = (centre - x).normalize();
            let a0 = frame0.n;
            let rot = |v: Vec3| {
                let k = cross(a0, a);
                let c = a0.dot(a);
                v * c + cross(k, v) + k * (k.dot(v) / (1.0 + c))
            };
            (rot(frame0.s), rot(frame0.t), a)
        };
        let sample = |x: Vec3, u: Vec2, law: ConeLaw| -> (Vec3, f32) {
            let d = (centre - x).length();
            let sin_max = radius / d;
            let cos_max = (1.0 - sin_max * sin_max).sqrt();
            let (s, t, n) = frame_at(x);
            let (local, weight) = match law {
                ConeLaw::Uniform => (
                    warp::square_to_uniform_cone(u, cos_max),
                    1.0 / warp::uniform_cone_pdf(cos_max),
                ),
                ConeLaw::Line => {
                    let theta = u.y * sin_max.asin();
                    let phi = u.x * std::f32::consts::TAU;
                    let v = Vec3::new(
                        theta.sin() * phi.cos(),
                        theta.sin() * phi.sin(),
                        theta.cos(),
                    );
                    (
                        v,
                        std::f32::consts::TAU * theta.sin() * sin_max.asin() / 8.0,
                    )
                }
            };
            (s * local.x + t * local.y + n * local.z, weight)
        };
        for law in [ConeLaw::Uniform, ConeLaw::Line] {
            for u in [
                Vec2::new(0.13, 0.77),
                Vec2::new(0.61, 0.99),
                Vec2::new(0.9, 0.05),
            ] {
                let (w, _) = sample(x0, u, law);
                let f = cone_flow(x0, centre, radius, w, law, dx).unwrap();
                for (k, &delta) in dx.iter().enumerate() {
                    let h = 1e-3;
                    let (wp, gp) = sample(x0 + delta * h, u, law);
                    let (wm, gm) = sample(x0 - delta * h, u, law);
                    let fd_w = (wp - wm) / (2.0 * h);
                    let fd_log = (gp.ln() - gm.ln()) / (2.0 * h);
                    assert!(
                        (fd_w - f.dw[k]).length() < 2e-3 * (1.0 + fd_w.length()),
                        "{law:?} u {u} lane {k}: flow {} vs FD {fd_w}",
                        f.dw[k]
                    );
                    assert!(
                        (fd_log - f.dlog_weight[k]).abs() < 2e-3 * (1.0 + fd_log.abs()),
                        "{law:?} u {u} lane {k}: dlog {} vs FD {fd_log}",
                        f.dlog_weight[k]
                    );
                }
            }
        }
    }
}
