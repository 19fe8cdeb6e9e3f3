//! Transfer slices (Sec. 5): for one surface point and view direction, paths from
//! the point traced with the BVH until they escape to the environment, binned by
//! path type — direct, indirect diffuse, indirect glossy (the lobe sampled at the
//! second surface) — and each bin reduced to one weighted vMF lobe (Eq. 13–15),
//! the direct bin of the glossy part to the two lobes of its BRDF's mixture, both
//! estimated as the known unoccluded lobe minus what occluders block.
//! The diffuse part of the first reflection is view-independent (Eq. 3's Td) and
//! gets one slice per vertex; the glossy part (Tg) one per view direction.

use super::fit::{responsibilities, KnownLobe, MaterialFit, DIRECT_LOBES};
use super::icosphere::Icosphere;
use crate::accel::{offset_ray_origin_with_error, Accel, PrimRef};
use crate::math::vmf::{l2_distance_sq, LobeAccumulator, Vmf, WeightedVmf};
use crate::math::{luminance, Frame, Ray, Vec3};
use crate::scene::Scene;
use glam::DVec3;

/// One weighted lobe α γ(μ, κ) with an RGB weight; α = 0: no path of this type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lobe {
    pub mu: Vec3,
    pub kappa: f32,
    pub alpha: Vec3,
}

impl Default for Lobe {
    fn default() -> Self {
        Self {
            mu: Vec3::Z,
            kappa: 1.0,
            alpha: Vec3::ZERO,
        }
    }
}

/// Direct, indirect diffuse, indirect glossy, and the direct path's second lobe
/// (the glossy component's two-lobe mixture, [`super::fit::KnownLobe`]; empty in Td).
pub type Slice = [Lobe; 4];

pub const PATH_TYPES: [&str; 4] = [
    "direct",
    "indirect diffuse",
    "indirect glossy",
    "direct, second lobe",
];

/// Where the direct path's second lobe sits in a [`Slice`].
pub const DIRECT_SECOND: usize = 3;

/// `walk`'s path type for a first direction that did not escape.
const FIRST_BLOCKED: usize = 3;

/// A surface point the transfer is computed at.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceSample {
    pub position: Vec3,
    pub geometric_normal: Vec3,
    pub frame: Frame,
    pub material: u32,
}

/// What tracing a slice needs from the scene.
pub struct TraceContext<'a> {
    pub scene: &'a Scene,
    pub accel: &'a Accel,
    pub fits: &'a [MaterialFit],
    pub ico: &'a Icosphere,
}

fn rng(index: u32, dim: u32, seed: u32) -> f64 {
    sobol_burley::sample(index, dim, seed) as f64
}

impl TraceContext<'_> {
    /// Where a ray lands and how it is shaded there (shading frame facing the
    /// ray), or `None` if it escapes.
    pub fn hit(&self, ray: &Ray) -> Option<Option<SurfaceSample>> {
        let hit = self.accel.intersect(ray)?;
        let Some(sp) = self.accel.surface_point(ray, &hit) else {
            return Some(None);
        };
        let (normal, material) = match hit.prim {
            PrimRef::Triangle { mesh, tri } => {
                let m = &self.scene.meshes[mesh as usize];
                let n = if m.normals.is_empty() {
                    sp.n_geo
                } else {
                    let t = m.triangles[tri as usize];
                    let b = hit.bary;
                    (m.normals[t[0] as usize] * (1.0 - b.x - b.y)
                        + m.normals[t[1] as usize] * b.x
                        + m.normals[t[2] as usize] * b.y)
                        .normalize_or(sp.n_geo)
                };
                (n, m.material)
            }
            PrimRef::Sphere(s) => {
                let s = &self.scene.spheres[s as usize];
                ((sp.p - s.center).normalize_or(sp.n_geo), s.material)
            }
        };
        // Two-sided shading: face the arriving ray.
        let n = if normal.dot(ray.dir) > 0.0 {
            -normal
        } else {
            normal
        };
        Some(Some(SurfaceSample {
            position: sp.p,
            geometric_normal: sp.n_geo,
            frame: Frame::from_normal(n),
            material,
        }))
    }

    fn spawn(&self, at: &SurfaceSample, dir: Vec3) -> Ray {
        let err = self.accel.spawn_error(Vec3::splat(
            at.position.abs().max_element().max(1.0) * 32.0 * f32::EPSILON,
        ));
        Ray::new(
            offset_ray_origin_with_error(at.position, err, at.geometric_normal, dir),
            dir,
        )
    }

    /// Traces `samples` paths from `at`: `wo = None` starts with the diffuse
    /// component (Td), `Some(wo)` (local frame) with the glossy one (Tg). Also
    /// returns the slice's noise: half the relative distance between the estimates
    /// from the even and the odd paths, i.e. the expected distance between two
    /// independent estimates of `samples` paths each (variance halves with twice
    /// the paths). The subdivision criteria discount it, so that Monte Carlo noise
    /// alone does not refine.
    ///
    /// The direct lobes depart from the paper's plain Eq. 13–15 sums: what an
    /// unoccluded point would receive is known from the BRDF ([`KnownLobe`]), so
    /// the paths estimate only the part occluders remove and subtract it (a control
    /// variate: the same expectation, no noise where nothing occludes; 32 paths
    /// gave 6.7 % of the image mean of slice noise on the e = 128 teapot). Where
    /// more is blocked than escapes, the escaped paths are summed directly instead.
    pub fn trace(
        &self,
        at: &SurfaceSample,
        wo: Option<Vec3>,
        samples: u32,
        seed: u32,
    ) -> (Slice, f32) {
        let known = self.known_direct(at, wo);
        let mut halves = [[Bin::default(); 3]; 2];
        // [half][mixture lobe][escaped, blocked]
        let mut direct = [[[Bin::default(); 2]; DIRECT_LOBES]; 2];
        self.walk(at, wo, samples, seed, |i, k, dir, w| {
            let h = (i % 2) as usize;
            if k == 0 || k == FIRST_BLOCKED {
                let rho = responsibilities(&known, dir.as_dvec3());
                for (j, bins) in direct[h].iter_mut().enumerate() {
                    bins[usize::from(k != 0)].add(dir, w * rho[j] as f32);
                }
            } else {
                halves[h][k].add(dir, w);
            }
        });
        let slice = |bins: &[Bin; 3], direct: &[[Bin; 2]; DIRECT_LOBES], m: u32| -> Slice {
            let d = |j: usize| direct_lobe(&direct[j], known.get(j), m);
            [d(0), bins[1].lobe(m), bins[2].lobe(m), d(1)]
        };
        let even = slice(&halves[0], &direct[0], samples.div_ceil(2).max(1));
        let odd = slice(&halves[1], &direct[1], (samples / 2).max(1));
        let mut all = halves[0];
        for (a, b) in all.iter_mut().zip(&halves[1]) {
            a.merge(b);
        }
        let mut all_direct = direct[0];
        for (a, b) in all_direct.iter_mut().zip(&direct[1]) {
            a[0].merge(&b[0]);
            a[1].merge(&b[1]);
        }
        let full = slice(&all, &all_direct, samples.max(1));
        (full, (0.5 * relative_distance(&even, &odd)) as f32)
    }

    /// The unoccluded direct lobes at `at` (world space): Td's one, Tg's mixture.
    fn known_direct(&self, at: &SurfaceSample, wo: Option<Vec3>) -> Vec<KnownLobe> {
        let fit = &self.fits[at.material as usize];
        match wo {
            None if fit.diffuse.is_some() => vec![fit.known_diffuse().to_world(&at.frame)],
            None => Vec::new(),
            Some(wo) => fit.glossy_at(self.ico, wo).map_or(Vec::new(), |e| {
                e.direct.iter().map(|k| k.to_world(&at.frame)).collect()
            }),
        }
    }

    /// The radiance the same paths carry, per path type, with the environment
    /// evaluated where each escapes instead of binned into a lobe: the value a
    /// slice stands for, without the lobe fit (for measuring the fit's error).
    pub fn radiance(
        &self,
        at: &SurfaceSample,
        wo: Option<Vec3>,
        samples: u32,
        seed: u32,
        env: &crate::scene::environment::Environment,
    ) -> [Vec3; 3] {
        let mut sum = [DVec3::ZERO; 3];
        self.walk(at, wo, samples, seed, |_, k, dir, w| {
            if k < 3 {
                sum[k] += (w * env.eval(dir)).as_dvec3()
            }
        });
        sum.map(|s| (s / samples.max(1) as f64).as_vec3a())
    }

    /// The paths of one slice: calls `visit(path, type, escape direction,
    /// throughput)` for every path that escapes (types 0–2 as [`PATH_TYPES`]), and
    /// with type 3 and its first direction for every path whose first ray is blocked.
    pub fn walk(
        &self,
        at: &SurfaceSample,
        wo: Option<Vec3>,
        samples: u32,
        seed: u32,
        mut visit: impl FnMut(u32, usize, Vec3, Vec3),
    ) {
        let fit = &self.fits[at.material as usize];
        let entry = wo.and_then(|wo| fit.glossy_at(self.ico, wo));
        for i in 0..samples {
            let u = |d: u32| rng(i, d, seed);
            let first = match (wo, &entry) {
                (None, _) => fit.sample_diffuse([u(0), u(1)]),
                (Some(wo), Some(e)) => fit.sample_glossy(e, wo, u(2), [u(0), u(1)]),
                (Some(_), None) => None,
            };
            let Some((wi, w1)) = first else { continue };
            let dir = at.frame.to_world(wi);
            match self.hit(&self.spawn(at, dir)) {
                None => visit(i, 0, dir, w1),
                Some(None) => visit(i, FIRST_BLOCKED, dir, w1),
                Some(Some(y)) => {
                    visit(i, FIRST_BLOCKED, dir, w1);
                    self.second_bounce(
                        &y,
                        -dir,
                        w1,
                        &mut |k, d, w| visit(i, k, d, w),
                        [u(3), u(4), u(5), u(6), u(7)],
                    )
                }
            }
        }
    }

    /// At the second surface y: one diffuse and one glossy sample (Sec. 5.1), each
    /// counted when it escapes (direct + one bounce, as the paper computes).
    fn second_bounce(
        &self,
        y: &SurfaceSample,
        to_x: Vec3,
        w1: Vec3,
        visit: &mut dyn FnMut(usize, Vec3, Vec3),
        u: [f64; 5],
    ) {
        let fit = &self.fits[y.material as usize];
        let wo = y.frame.to_local(to_x);
        if wo.z <= 0.0 {
            return;
        }
        if let Some((wi, w2)) = fit.sample_diffuse([u[0], u[1]]) {
            let dir = y.frame.to_world(wi);
            if self.hit(&self.spawn(y, dir)).is_none() {
                visit(1, dir, w1 * w2);
            }
        }
        let wo = super::fit::clamp_view(wo);
        if let Some(e) = fit.glossy_at(self.ico, wo) {
            if let Some((wi, w2)) = fit.sample_glossy(&e, wo, u[4], [u[2], u[3]]) {
                let dir = y.frame.to_world(wi);
                if self.hit(&self.spawn(y, dir)).is_none() {
                    visit(2, dir, w1 * w2);
                }
            }
        }
    }
}

#[derive(Clone, Copy, Default)]
struct Bin {
    acc: LobeAccumulator,
    rgb: DVec3,
}

impl Bin {
    fn merge(&mut self, other: &Bin) {
        self.acc.merge(&other.acc);
        self.rgb += other.rgb;
    }

    fn add(&mut self, dir: Vec3, w: Vec3) {
        let lum = luminance(w) as f64;
        if lum > 0.0 && w.is_finite() {
            self.acc.add(dir.as_dvec3().normalize(), lum);
            self.rgb += w.as_dvec3();
        }
    }

    /// Eq. 15: α = Σ throughput / M; μ, κ from the luminance-weighted mean (Eq. 13–14).
    fn lobe(&self, samples: u32) -> Lobe {
        match self.acc.estimate(samples as u64) {
            Some(e) => Lobe {
                mu: e.lobe.mu.as_vec3a(),
                kappa: e.lobe.kappa as f32,
                alpha: (self.rgb / samples as f64).as_vec3a(),
            },
            None => Lobe::default(),
        }
    }
}

/// One direct lobe from its escaped and blocked paths (`bins`) and, when known,
/// its unoccluded expectations: known − blocked while at most half is blocked,
/// else the escaped paths alone (whichever sum has the smaller variance).
fn direct_lobe(bins: &[Bin; 2], known: Option<&KnownLobe>, samples: u32) -> Lobe {
    let [escaped, blocked] = bins;
    let Some(k) = known.filter(|_| blocked.acc.weight_sum <= escaped.acc.weight_sum) else {
        return escaped.lobe(samples);
    };
    let m = samples.max(1) as f64;
    let weight = k.weight - blocked.acc.weight_sum / m;
    let rgb = (k.rgb - blocked.rgb / m).max(DVec3::ZERO);
    if weight.is_nan() || weight <= 0.0 || luminance(rgb.as_vec3a()) <= 0.0 {
        return Lobe::default();
    }
    let lobe =
        Vmf::from_mean_resultant((k.resultant_vector() - blocked.acc.direction_sum / m) / weight);
    // Cutting at most half of a lobe away sharpens what is left by well under 4×;
    // more is noise in the difference (its r can even reach 1, κ = ∞).
    let kappa_max = 4.0 * Vmf::from_mean_resultant(k.mean_dir * k.resultant).kappa;
    Lobe {
        mu: lobe.mu.as_vec3a(),
        kappa: lobe.kappa.min(kappa_max) as f32,
        alpha: rgb.as_vec3a(),
    }
}

/// Barycentric blend of lobes (Eq. 6): α and κ interpolated, μ interpolated and
/// renormalised. μ and κ are weighted by each lobe's luminance as well, so a corner
/// where no path of this type arrived (α = 0, shape undefined) does not bend it.
pub fn blend(lobes: &[(Lobe, f32)]) -> Lobe {
    let mut alpha = Vec3::ZERO;
    let mut mu = Vec3::ZERO;
    let mut kappa = 0.0;
    let mut shape_w = 0.0;
    for (l, w) in lobes {
        alpha += l.alpha * *w;
        let sw = w * luminance(l.alpha);
        mu += l.mu * sw;
        kappa += l.kappa * sw;
        shape_w += sw;
    }
    if shape_w <= 0.0 {
        return Lobe::default();
    }
    Lobe {
        mu: mu.normalize_or(Vec3::Z),
        kappa: kappa / shape_w,
        alpha,
    }
}

pub fn blend_slices(slices: &[(&Slice, f32); 3]) -> Slice {
    std::array::from_fn(|k| blend(&slices.map(|(s, w)| (s[k], w))))
}

fn weighted(l: &Lobe) -> WeightedVmf {
    WeightedVmf {
        weight: luminance(l.alpha) as f64,
        lobe: Vmf::new(l.mu.as_dvec3(), l.kappa as f64),
    }
}

/// Squared L2 distance of two slices over their lobes (App. A, exact), and the
/// sum of their squared norms: their ratio, in [0, 2], is the relative difference
/// the subdivision thresholds compare.
pub fn distance(a: &Slice, b: &Slice) -> (f64, f64) {
    let mut d = 0.0;
    let mut norm = 0.0;
    for (la, lb) in a.iter().zip(b) {
        let (wa, wb) = (weighted(la), weighted(lb));
        d += l2_distance_sq(&wa, &wb);
        norm += wa.weight * wa.weight * wa.lobe.self_product()
            + wb.weight * wb.weight * wb.lobe.self_product();
    }
    (d, norm)
}

/// `distance` as a ratio (0 when both slices are empty).
pub fn relative_distance(a: &Slice, b: &Slice) -> f64 {
    let (d, n) = distance(a, b);
    if n > 0.0 {
        d / n
    } else {
        0.0
    }
}
