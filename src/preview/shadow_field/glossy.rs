//! Glossy receivers (Zhou et al. 2005, Sec. 5: a glossy receiver's transfer is the
//! BRDF's SH projection, multiplied with the occluders' visibility in the triple
//! product like the diffuse transfer). Per material, the order-4 projection of
//! f_s(ω_i, ω_o)·max(n·ω_i, 0) over ω_i, tabulated over θ_o in the frame where
//! n = +z and ω_o lies in the +x half of the xz-plane; at a receiver the entry of
//! its θ_o is rotated to world space. Sphere lights do not use it: they evaluate
//! the lobe itself at their cap's directions ([`super::combine`]).
//!
//! Why a table and not a zonal lobe around the reflected direction: an isotropic
//! BRDF times the cosine depends on θ_o alone in that frame, so a table over θ_o is
//! exact up to its interpolation, for any lobe shape (the cosine, the horizon's
//! cut, Blinn-Phong's off-specular stretch, Cook-Torrance's grazing gain), and
//! it is filled by the renderer's own [`Material::eval`], so the lobe's formula is
//! written once. Its cost: one SH rotation per receiver (~1 µs) and 33 × 64²
//! evaluations per material and frame (a few ms).
//!
//! **Bound.** Order 4 (bands l ≤ 3) holds the transfer of a lobe whose energy
//! lies in those bands. A Blinn-Phong lobe of exponent e is about a Phong lobe
//! cos^s of the reflected direction with s ≈ e/4, whose band-l coefficients fall
//! as exp(−l²/2s) (Ramamoorthi & Hanrahan 2001): band 4 keeps exp(−32/e) of it,
//! 2 % at e = 8, 14 % at e = 16, 37 % at e = 32. So e ≤ 8 is held (the tests'
//! bound), and beyond e ≈ 16 an environment's highlight comes out blurred and too
//! dim at its peak — and so does an occluder seen in the lobe (its visibility
//! enters by the same order-4 triple product). Unoccluded under order-4
//! lighting (a constant sky, the projected environment, an SRF) it is exact
//! whatever e. Measured (`tests/shadow_field_glossy.rs`' Gaussian sky, a ball on
//! a Blinn-Phong floor): RMSE 1.4, 2.1, 3.4, 5.4, 8.6 % of the mean at
//! e = 2, 8, 16, 32, 100. Sphere lights are not bounded by it.

use super::combine::GlossyReceiver;
use crate::brdf::Material;
use crate::math::sh::{self, Rotation, Sh, ShF, COEFFS};
use crate::math::{Frame, Vec3};
use glam::DMat3;
use rayon::prelude::*;

/// θ_o entries from 0 to 90° (the last just above the horizon).
const THETA_STEPS: usize = 33;
/// Quadrature over ω_i: Gauss–Legendre nodes in s ∈ [0, 1], θ' = π s² from the
/// reflected direction (dense where a lobe is), times a uniform φ' rule.
const S_NODES: usize = 64;
const PHI_NODES: usize = 64;

/// A glossy material's lobe as the shadow field shades it.
#[derive(Clone, Debug)]
pub struct GlossyLobe {
    /// The lobe alone, kd zeroed: what a sphere light's directions evaluate.
    pub lobe: Material,
    /// ks, by which the unit-colour table is scaled.
    pub ks: Vec3,
    /// Per θ_o step, cos θ_o times the transfer of the lobe with ks = 1 in the
    /// local frame: Cook-Torrance's albedo grows as 1/cos θ_o towards grazing,
    /// which the product keeps smooth enough to interpolate linearly.
    table: Vec<ShF>,
}

impl GlossyLobe {
    /// The table of `material`'s glossy lobe; `None` for a material without one
    /// (or with a black one).
    pub fn new(material: &Material) -> Option<Self> {
        let parts = material.preview_parts().ok()?;
        let lobe = parts.glossy?;
        let (ks, unit) = material.glossy_lobe_unit()?;
        if ks == Vec3::ZERO {
            return None;
        }
        let gl = sh::gauss_legendre(S_NODES);
        let table = (0..THETA_STEPS)
            .into_par_iter()
            .map(|k| {
                let theta = theta_of(k);
                project_local(&unit, theta, &gl).map(|c| c * theta.cos() as f32)
            })
            .collect();
        Some(Self { lobe, ks, table })
    }

    /// The local-frame transfer (unit ks) at θ_o: cos θ_o × transfer linear
    /// between table entries, over cos θ_o (at most the last entry's 1/cos).
    pub fn local(&self, cos_o: f32) -> ShF {
        let theta = cos_o.clamp(0.0, 1.0).acos() as f64;
        let x = (theta / std::f64::consts::FRAC_PI_2 * (THETA_STEPS - 1) as f64)
            .clamp(0.0, (THETA_STEPS - 1) as f64);
        let i = (x.floor() as usize).min(THETA_STEPS - 2);
        let f = (x - i as f64) as f32;
        let (a, b) = (&self.table[i], &self.table[i + 1]);
        let inv = 1.0 / cos_o.max(theta_of(THETA_STEPS - 1).cos() as f32);
        std::array::from_fn(|c| (a[c] + f * (b[c] - a[c])) * inv)
    }

    /// What the combiner needs of this lobe at a receiver with unit shading normal
    /// `n` (facing the viewer) seen from `wo`: `None` where `wo` is on or below
    /// the horizon (no glossy reflection there).
    pub fn receiver(&self, n: Vec3, wo: Vec3) -> Option<GlossyReceiver<'_>> {
        let cos_o = n.dot(wo);
        if cos_o.is_nan() || cos_o <= 0.0 || !wo.is_finite() {
            return None;
        }
        let frame = Frame::from_normal(n);
        let tangent = wo - n * cos_o;
        let len = tangent.length();
        let t = if len > 1e-6 { tangent / len } else { frame.s };
        let b = crate::math::cross(n, t);
        let rot = Rotation::new(DMat3::from_cols(t.as_dvec3(), b.as_dvec3(), n.as_dvec3()));
        let transfer = rot.apply_f32(&self.local(cos_o));
        Some(GlossyReceiver {
            lobe: &self.lobe,
            ks: self.ks,
            frame,
            wo_local: frame.to_local(wo),
            transfer,
        })
    }
}

/// θ_o of table entry `k`: evenly from 0 to 90° less 0.06° (at 90° f is zero).
fn theta_of(k: usize) -> f64 {
    let top = std::f64::consts::FRAC_PI_2 - 1e-3;
    top * k as f64 / (THETA_STEPS - 1) as f64
}

/// ∫ f(ω_i, ω_o)·max(ω_i.z, 0)·Y(ω_i) dω_i in the local frame, ω_o at `theta`
/// in the xz-plane, by the quadrature around the reflected direction.
fn project_local(unit: &Material, theta: f64, gl: &[(f64, f64)]) -> ShF {
    let wo = Vec3::new(theta.sin() as f32, 0.0, theta.cos() as f32);
    let r = Vec3::new(-wo.x, 0.0, wo.z);
    let frame = Frame::from_normal(r);
    let pi = std::f64::consts::PI;
    let w_phi = 2.0 * pi / PHI_NODES as f64;
    let mut c: Sh = [0.0; COEFFS];
    for &(x, w) in gl {
        let s = 0.5 * (x + 1.0);
        let th = pi * s * s;
        // dω = sin θ' dθ' dφ', dθ' = 2π s ds, ds = dx/2.
        let weight = th.sin() * 2.0 * pi * s * 0.5 * w * w_phi;
        let (st, ct) = (th.sin(), th.cos());
        for j in 0..PHI_NODES {
            let phi = (j as f64 + 0.5) * w_phi;
            let local = Vec3::new((st * phi.cos()) as f32, (st * phi.sin()) as f32, ct as f32);
            let wi = frame.to_world(local);
            if wi.z <= 0.0 {
                continue;
            }
            // The lobe is grey (ks = 1): one channel holds it.
            let f = unit.eval(wo, wi).x as f64 * wi.z as f64;
            if f == 0.0 {
                continue;
            }
            let y = sh::eval(wi.as_dvec3());
            for i in 0..COEFFS {
                c[i] += f * weight * y[i];
            }
        }
    }
    c.map(|v| v as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::preview::shadow_field::combine::diffuse_transfer;

    #[test]
    fn exponent_zero_blinn_phong_is_the_lambertian_transfer() {
        // At n = 0 the modified Blinn-Phong BRDF is 1/π: ks times the clamped
        // cosine over π, whatever the view.
        let m = Material::BlinnPhong {
            kd: Vec3::ZERO,
            ks: Vec3::splat(0.5),
            exponent: 0.0,
        };
        let g = GlossyLobe::new(&m).unwrap();
        assert_eq!(g.ks, Vec3::splat(0.5));
        let n = Vec3::new(0.3, 0.8, -0.2).normalize();
        for wo in [n, Vec3::new(0.9, 0.3, 0.1).normalize(), Vec3::Y] {
            let r = g.receiver(n, wo).unwrap();
            let want = diffuse_transfer(n);
            for k in 0..COEFFS {
                assert!(
                    (r.transfer[k] - want[k]).abs() < 2e-3,
                    "{wo} {k}: {} vs {}",
                    r.transfer[k],
                    want[k]
                );
            }
        }
    }

    #[test]
    fn degenerate_views_and_extreme_lobes_give_finite_transfers() {
        // The view on the normal (no tangent), grazing, behind, NaN; exponents
        // from 0 to the clamp; Cook-Torrance's grazing gain.
        let n = Vec3::new(0.0, 1.0, 0.0);
        let views = [
            n,
            Vec3::new(1.0, 1e-7, 0.0).normalize(),
            Vec3::new(0.6, 1e-3, 0.8).normalize(),
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(f32::NAN, 1.0, 0.0),
        ];
        for e in [0.0, 8.0, 1e4, 1e7, f32::INFINITY] {
            for m in [
                Material::BlinnPhong {
                    kd: Vec3::ZERO,
                    ks: Vec3::ONE,
                    exponent: e,
                },
                Material::CookTorrance {
                    kd: Vec3::ZERO,
                    ks: Vec3::ONE,
                    exponent: e,
                },
            ] {
                let g = GlossyLobe::new(&m).unwrap();
                for (k, wo) in views.iter().enumerate() {
                    let r = g.receiver(n, *wo);
                    assert_eq!(r.is_some(), k < 3, "{m:?} {wo}");
                    if let Some(r) = r {
                        assert!(r.transfer.iter().all(|c| c.is_finite()), "{m:?} {wo}");
                    }
                }
            }
        }
        // No glossy lobe, nothing to tabulate.
        let lambert = Material::Lambert { albedo: Vec3::ONE };
        assert!(GlossyLobe::new(&lambert).is_none());
        let black = Material::BlinnPhong {
            kd: Vec3::ONE,
            ks: Vec3::ZERO,
            exponent: 8.0,
        };
        assert!(GlossyLobe::new(&black).is_none());
    }

    #[test]
    fn a_sharp_lobe_reflects_ks_at_normal_incidence_and_matches_brute_force() {
        // The exact normalisation makes the specular albedo 1 (unit ks) at
        // normal incidence: the DC coefficient is Y₀₀ = 0.28209…, even at e = 1000.
        for e in [8.0, 100.0, 1000.0] {
            let m = Material::BlinnPhong {
                kd: Vec3::ZERO,
                ks: Vec3::ONE,
                exponent: e,
            };
            let g = GlossyLobe::new(&m).unwrap();
            let c0 = g.local(1.0)[0];
            assert!((c0 - 0.282_094_8).abs() < 2e-3, "e = {e}: {c0}");
        }
        // At 50° and e = 8, against the plain 64 × 128 product rule.
        let m = Material::CookTorrance {
            kd: Vec3::ZERO,
            ks: Vec3::ONE,
            exponent: 8.0,
        };
        let g = GlossyLobe::new(&m).unwrap();
        let theta = 50f64.to_radians();
        let wo = Vec3::new(theta.sin() as f32, 0.0, theta.cos() as f32);
        let want = sh::project(|d| {
            let wi = d.as_vec3a();
            f64::from(m.eval(wo, wi).x) * d.z.max(0.0)
        });
        let got = g.local(wo.z);
        for k in 0..COEFFS {
            assert!(
                (f64::from(got[k]) - want[k]).abs() < 3e-3,
                "{k}: {} vs {}",
                got[k],
                want[k]
            );
        }
    }
}
