//! Deforming entities (the deformable paper, Sec. 4 and App. A–B): the base-sphere
//! visibility (BSV) is traced at run time on the entity's bounding sphere only, in
//! each sample's local frame (z towards the centre), and extrapolated to the other
//! radii d by the angular rescaling f_k, k = r/d, applied in SH by precomputed
//! matrices M_k (Sec. 4.2), which are non-zero only where m = m′ (App. B).
//!
//! Direction of the rescaling: f_k maps the angle θ_r at which a silhouette point
//! is seen from the base sphere to the angle θ_d seen from distance d (Sec. 4.1's
//! construction: tan θ_d = k tan θ_r / (1 + tan θ_r − k tan θ_r)); the visibility
//! at d is therefore V_d(θ) = V_r(f_k⁻¹(θ)) (App. B), and f_k⁻¹ = f_{1/k}.

use super::field::{Field, Grid};
use super::precompute::EntityGeometry;
use crate::math::sh::{self, Rotation, ShF, BANDS, COEFFS};
use crate::math::{warp, Frame, Ray, Vec2, Vec3};
use glam::{DVec3, Mat3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Sec. 4.1: the silhouette angle seen from distance d = r/k, for the angle θ seen
/// from r. Written with atan2 so that the paper's "+π when θ′ < 0" branch is built in.
pub fn f_k(theta: f64, k: f64) -> f64 {
    let (s, c) = theta.sin_cos();
    (k * s).atan2(c + (1.0 - k) * s)
}

/// d f_k / dθ (by the quotient rule on tan θ_d; Sec. 4.1's f′_k).
pub fn f_k_derivative(theta: f64, k: f64) -> f64 {
    let (s, c) = theta.sin_cos();
    let den = c + (1.0 - k) * s;
    // θ_d = atan2(k s, den): dθ_d = (den·k c − k s·(−s + (1 − k) c)) / (k² s² + den²).
    (den * k * c - k * s * ((1.0 - k) * c - s)) / (k * k * s * s + den * den)
}

/// Which extrapolation: plain visibility (OOFs) or radiance with the paper's
/// solid-angle factor f′·sin f / sin θ (SRFs, App. A; it keeps ∫ V dω, i.e. the
/// DC coefficient, unchanged).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Extrapolation {
    Visibility,
    Radiance,
}

/// Dense M_k by quadrature over the sphere (Sec. 4.2): M_ij = ∫ Y_j(f_k⁻¹(θ), φ) Y_i(θ, φ) dω
/// (times the factor for radiance). Gauss–Legendre in θ (the warp is smooth but
/// not polynomial), the trapezoid rule in φ (exact: the integrand's φ-degree ≤ 6).
pub fn matrix_dense(k: f64, kind: Extrapolation) -> [[f64; COEFFS]; COEFFS] {
    let mut m = [[0.0; COEFFS]; COEFFS];
    let n_phi = 16;
    for (x, w) in sh::gauss_legendre(200) {
        let theta = 0.5 * PI * (x + 1.0);
        let w = w * 0.5 * PI * theta.sin() * 2.0 * PI / n_phi as f64;
        let src = f_k(theta, 1.0 / k);
        let factor = match kind {
            Extrapolation::Visibility => 1.0,
            Extrapolation::Radiance => {
                let s = theta.sin();
                if s < 1e-12 {
                    // The limit at the poles: f′(0)², since sin f ≈ f′ θ.
                    f_k_derivative(theta, 1.0 / k).powi(2)
                } else {
                    f_k_derivative(theta, 1.0 / k) * src.sin() / s
                }
            }
        };
        for j in 0..n_phi {
            let phi = (j as f64 + 0.5) * 2.0 * PI / n_phi as f64;
            let at = |t: f64| DVec3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos());
            let (yd, yr) = (sh::eval(at(theta)), sh::eval(at(src)));
            for a in 0..COEFFS {
                for b in 0..COEFFS {
                    m[a][b] += w * factor * yd[a] * yr[b];
                }
            }
        }
    }
    m
}

/// The positions of M_k's non-zero entries (App. B): same m, l, l′ ≥ |m|;
/// (q+1)(2q²+4q+3)/3 of them for bands up to q, 44 for q = 3 (16 coefficients).
pub fn sparsity_pattern() -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for a in 0..COEFFS {
        for b in 0..COEFFS {
            if sh::band_of(a).1 == sh::band_of(b).1 {
                out.push((a, b));
            }
        }
    }
    out
}

/// M_k stored as its 44 non-zero entries.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseMatrix {
    pub k: f64,
    pub entries: Vec<(u8, u8, f32)>,
}

impl SparseMatrix {
    pub fn new(k: f64, kind: Extrapolation) -> Self {
        let dense = matrix_dense(k, kind);
        let entries = sparsity_pattern()
            .into_iter()
            .map(|(a, b)| (a as u8, b as u8, dense[a][b] as f32))
            .collect();
        Self { k, entries }
    }

    pub fn apply(&self, c: &ShF) -> ShF {
        let mut out = [0.0f32; COEFFS];
        for &(a, b, v) in &self.entries {
            out[a as usize] += v * c[b as usize];
        }
        out
    }
}

/// M_k at a set of ratios, linearly interpolated in between (Sec. 4.2); beyond the
/// table's range the nearest matrix is used (the field's own far-field rule then
/// applies).
#[derive(Clone, Debug)]
pub struct MatrixTable {
    pub matrices: Vec<SparseMatrix>,
}

impl MatrixTable {
    /// One matrix per ratio, ascending.
    pub fn new(mut ks: Vec<f64>, kind: Extrapolation) -> Self {
        ks.sort_by(f64::total_cmp);
        Self {
            matrices: ks
                .into_par_iter()
                .map(|k| SparseMatrix::new(k, kind))
                .collect(),
        }
    }

    /// The ratios R/r_j of a field grid's radii to the base sphere R.
    pub fn for_grid(grid: &Grid, base_radius: f32, kind: Extrapolation) -> Self {
        Self::new(
            (0..grid.n_radii)
                .map(|j| f64::from(base_radius) / f64::from(grid.radius(j)))
                .collect(),
            kind,
        )
    }

    /// M at ratio k.
    pub fn at(&self, k: f64) -> SparseMatrix {
        let ms = &self.matrices;
        let i = ms.partition_point(|m| m.k <= k);
        if i == 0 || i == ms.len() {
            let m = &ms[if i == 0 { 0 } else { ms.len() - 1 }];
            return SparseMatrix { k, ..m.clone() };
        }
        let (a, b) = (&ms[i - 1], &ms[i]);
        let s = ((k - a.k) / (b.k - a.k)) as f32;
        SparseMatrix {
            k,
            entries: a
                .entries
                .iter()
                .zip(&b.entries)
                .map(|(x, y)| (x.0, x.1, x.2 + s * (y.2 - x.2)))
                .collect(),
        }
    }
}

/// The base-sphere visibility: occlusion at every angular sample of the bounding
/// sphere, in the sample's local frame (z towards the centre), traced over the
/// hemisphere facing the entity (`rays²` stratified directions; the other half
/// cannot see it).
#[derive(Clone, Debug)]
pub struct BaseSphere {
    pub center: Vec3,
    pub radius: f32,
    pub n_theta: usize,
    pub n_phi: usize,
    /// Local-frame occlusion per angular sample (θ-major).
    pub occlusion: Vec<ShF>,
    /// Local → world rotation of each sample's frame, and its SH rotation.
    pub frames: Vec<Mat3>,
    rotations: Vec<Rotation>,
}

/// Angular sample direction (θ index, φ index), as in [`Grid::direction`].
fn grid_dir(n_theta: usize, n_phi: usize, t: usize, p: usize) -> Vec3 {
    Grid {
        n_theta,
        n_phi,
        n_radii: 1,
        r_min: 1.0,
        r_max: 1.0,
    }
    .direction(t, p)
}

impl BaseSphere {
    pub fn trace(
        geo: &EntityGeometry,
        center: Vec3,
        radius: f32,
        n_theta: usize,
        n_phi: usize,
        rays: usize,
    ) -> Self {
        let n = n_theta * n_phi;
        let per: Vec<(ShF, Mat3)> = (0..n)
            .into_par_iter()
            .map(|i| {
                let (t, p) = (i / n_phi, i % n_phi);
                let u = grid_dir(n_theta, n_phi, t, p);
                let frame = Frame::from_normal(-u);
                let m = Mat3::from_cols(frame.s.into(), frame.t.into(), frame.n.into());
                // The poles repeat one point for every φ: trace it once (p = 0).
                if (t == 0 || t == n_theta - 1) && p > 0 {
                    return ([f32::NAN; COEFFS], m);
                }
                (
                    hemisphere_occlusion(geo, center + u * radius, &frame, rays),
                    m,
                )
            })
            .collect();
        let mut occlusion: Vec<ShF> = per.iter().map(|x| x.0).collect();
        let frames = per.iter().map(|x| x.1).collect::<Vec<_>>();
        // Pole copies, re-expressed in each copy's own local frame.
        for t in [0, n_theta - 1] {
            let base_world =
                Rotation::new(frames[t * n_phi].as_dmat3()).apply_f32(&occlusion[t * n_phi]);
            for p in 1..n_phi {
                let f: Mat3 = frames[t * n_phi + p];
                occlusion[t * n_phi + p] =
                    Rotation::new(f.transpose().as_dmat3()).apply_f32(&base_world);
            }
        }
        let rotations = frames.iter().map(|f| Rotation::new(f.as_dmat3())).collect();
        Self {
            center,
            radius,
            n_theta,
            n_phi,
            occlusion,
            frames,
            rotations,
        }
    }

    /// The full occlusion field on `grid` (radii in units of this base sphere's
    /// grid), world-aligned: M_{k_j} applied to each local BSV, then rotated to
    /// the world by each sample's frame.
    pub fn extrapolate(&self, grid: &Grid, table: &MatrixTable) -> Field {
        let rotations = &self.rotations;
        let mut data = vec![[0.0f32; COEFFS]; grid.len()];
        for j in 0..grid.n_radii {
            let m = table.at(f64::from(self.radius) / f64::from(grid.radius(j)));
            for s in 0..self.occlusion.len() {
                let local = m.apply(&self.occlusion[s]);
                data[j * self.occlusion.len() + s] = rotations[s].apply_f32(&local);
            }
        }
        Field { grid: *grid, data }
    }
}

fn hemisphere_occlusion(geo: &EntityGeometry, p: Vec3, frame: &Frame, n: usize) -> ShF {
    let weight = std::f32::consts::TAU / (n * n) as f32;
    let mut o = [0.0f32; COEFFS];
    for a in 0..n {
        for b in 0..n {
            let u = Vec2::new((a as f32 + 0.5) / n as f32, (b as f32 + 0.5) / n as f32);
            let local = warp::square_to_uniform_cone(u, 0.0);
            if geo.hits(&Ray::new(p, frame.to_world(local))) {
                let y = sh::eval_f32(local);
                for k in 0..COEFFS {
                    o[k] += weight * y[k];
                }
            }
        }
    }
    o
}

/// Number of non-zero entries of M for bands 0 … q (App. B).
pub fn paper_nonzero_count(q: usize) -> usize {
    (q + 1) * (2 * q * q + 4 * q + 3) / 3
}

/// Highest band of the toolkit (q in App. B's count).
pub const Q: usize = BANDS - 1;
