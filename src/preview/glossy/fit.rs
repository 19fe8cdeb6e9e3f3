//! The BRDF fit (Eq. 9): a material's cosine-weighted BRDF as one diffuse and one
//! glossy vMF lobe, βd γd(si) + βg γg(si), for the view directions of an
//! icosahedral set, interpolated barycentrically in between. Precomputation draws
//! directions from the fit and weights them by the true BRDF, so the fit only
//! steers variance, never the answer.

use super::icosphere::Icosphere;
use crate::brdf::Material;
use crate::math::vmf::{self, LobeAccumulator, Vmf};
use crate::math::{luminance, Vec2, Vec3};
use glam::DVec3;

/// The icosahedral level of the fitted view directions (≈ 8° apart).
pub const FIT_LEVEL: usize = 3;

/// Fraction of glossy samples drawn from a cosine lobe instead of the fitted vMF:
/// a defensive mixture that bounds the weights where the fit is narrower than the
/// true lobe (grazing views, where a Blinn-Phong lobe in ωi is elongated).
const DEFENSIVE: f64 = 0.15;

/// The diffuse lobe: the vMF whose mean cosine is that of cos θ/π (2/3), by Eq. 13.
pub fn diffuse_lobe() -> Vmf {
    Vmf::from_mean_resultant(DVec3::Z * (2.0 / 3.0))
}

/// The fitted glossy lobe for one view direction (local frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlossyEntry {
    /// βg: the glossy component's directional albedo (RGB).
    pub albedo: Vec3,
    pub lobe: Vmf,
}

/// One material, split into its diffuse and glossy components and fitted.
pub struct MaterialFit {
    /// The diffuse component f = kd/π (None if black).
    pub diffuse: Option<Material>,
    pub kd: Vec3,
    /// The glossy component (kd = 0) and its fit per slot of `FIT_LEVEL`.
    pub glossy: Option<(Material, Vec<GlossyEntry>)>,
}

/// A material's diffuse and glossy parts, or why the preview cannot take it.
fn split(material: &Material) -> Result<(Vec3, Option<Material>), String> {
    match material {
        Material::Lambert { albedo } => Ok((*albedo, None)),
        Material::BlinnPhong { kd, ks, exponent } => Ok((
            *kd,
            Some(Material::BlinnPhong {
                kd: Vec3::ZERO,
                ks: *ks,
                exponent: *exponent,
            }),
        )),
        Material::CookTorrance { kd, ks, exponent } => Ok((
            *kd,
            Some(Material::CookTorrance {
                kd: Vec3::ZERO,
                ks: *ks,
                exponent: *exponent,
            }),
        )),
        Material::Mirror { .. } => {
            Err("a mirror is a delta lobe, which one vMF lobe per path type cannot hold".into())
        }
    }
}

impl MaterialFit {
    /// Fits `material` with `samples` BRDF samples per view direction.
    pub fn new(material: &Material, ico: &Icosphere, samples: u32) -> Result<Self, String> {
        let (kd, glossy) = split(material)?;
        let diffuse = (luminance(kd) > 0.0).then_some(Material::Lambert { albedo: kd });
        let glossy = glossy.map(|g| {
            let table = (0..ico.slot_end[FIT_LEVEL] as u32)
                .map(|slot| fit_glossy(&g, clamp_view(ico.slot_direction(slot)), samples))
                .collect();
            (g, table)
        });
        Ok(Self {
            diffuse,
            kd,
            glossy,
        })
    }

    /// The glossy fit at local view direction `wo` (z > 0), interpolated
    /// barycentrically over the three nearest fitted directions (μ renormalised).
    pub fn glossy_at(&self, ico: &Icosphere, wo: Vec3) -> Option<GlossyEntry> {
        let (_, table) = self.glossy.as_ref()?;
        let loc = ico.locate(wo, FIT_LEVEL);
        let mut albedo = Vec3::ZERO;
        let mut mu = DVec3::ZERO;
        let mut kappa = 0.0;
        for (slot, w) in loc.slots.iter().zip(loc.weights) {
            let e = &table[*slot as usize];
            albedo += e.albedo * w;
            mu += e.lobe.mu * w as f64;
            kappa += e.lobe.kappa * w as f64;
        }
        Some(GlossyEntry {
            albedo,
            lobe: Vmf::new(mu, kappa),
        })
    }

    /// Draws ωi from the diffuse lobe; returns it with f_d cos θi / γd.
    pub fn sample_diffuse(&self, u: [f64; 2]) -> Option<(Vec3, Vec3)> {
        let d = self.diffuse.as_ref()?;
        let lobe = diffuse_lobe();
        let wi = lobe.sample(u);
        if wi.z <= 0.0 {
            return None;
        }
        let f = d.eval(Vec3::Z, wi.as_vec3());
        Some((wi.as_vec3(), f * (wi.z / lobe.pdf(wi)) as f32))
    }

    /// Draws ωi from the fitted glossy lobe (with the defensive cosine part);
    /// returns it with f_g cos θi / pdf.
    pub fn sample_glossy(
        &self,
        entry: &GlossyEntry,
        wo: Vec3,
        u_select: f64,
        u: [f64; 2],
    ) -> Option<(Vec3, Vec3)> {
        let (g, _) = self.glossy.as_ref()?;
        let wi = if u_select < DEFENSIVE {
            crate::math::warp::square_to_cosine_hemisphere(Vec2::new(u[0] as f32, u[1] as f32))
                .as_dvec3()
        } else {
            entry.lobe.sample(u)
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = (1.0 - DEFENSIVE) * entry.lobe.pdf(wi) + DEFENSIVE * wi.z / std::f64::consts::PI;
        let f = g.eval(wo, wi.as_vec3());
        let weight = f * (wi.z / pdf) as f32;
        weight.is_finite().then_some((wi.as_vec3(), weight))
    }
}

/// A view direction usable by the BRDF: lifted to at least 1° above the horizon.
pub fn clamp_view(wo: Vec3) -> Vec3 {
    let h = (wo.x * wo.x + wo.y * wo.y).sqrt();
    let min_z = 1f32.to_radians().sin();
    if wo.z >= min_z || h == 0.0 {
        return wo.normalize();
    }
    let c = (1.0 - min_z * min_z).sqrt();
    Vec3::new(wo.x / h * c, wo.y / h * c, min_z)
}

/// One lobe for the glossy component at `wo`: βg is the mean of f cos/pdf over the
/// material's own importance samples, μ and κ the single-lobe estimate of the
/// luminance-weighted directions (Eq. 13–14). Sobol points make it deterministic.
fn fit_glossy(g: &Material, wo: Vec3, samples: u32) -> GlossyEntry {
    let mut acc = LobeAccumulator::default();
    let mut albedo = DVec3::ZERO;
    for i in 0..samples {
        let u = Vec2::new(
            sobol_burley::sample(i, 0, 0x5eed),
            sobol_burley::sample(i, 1, 0x5eed),
        );
        if let Some(s) = g.sample(wo, 0.5, u) {
            acc.add(s.wi.as_dvec3(), luminance(s.weight) as f64);
            albedo += s.weight.as_dvec3();
        }
    }
    let lobe = acc
        .estimate(samples as u64)
        .map_or(Vmf::new(DVec3::Z, vmf::KAPPA_MIN), |e| e.lobe);
    GlossyEntry {
        albedo: (albedo / samples.max(1) as f64).as_vec3(),
        lobe,
    }
}
