//! von Mises–Fisher lobes on the unit sphere, in f64: density, sampling,
//! single-lobe estimates from weighted samples and the L2 distance between two
//! weighted lobes (glossy-interreflections paper, Eq. 5, 7–8, 10, 13–15, App. A).
//!
//! Stability (as Open PGL's mixture and Tokuyoshi's vMF notes do it): the exponent is
//! always written `κ(μ·s − 1) ≤ 0` and the normaliser `c(κ) = κ / (4π sinh κ)` as
//! `κ / (2π (1 − e^{−2κ}))` times that exponential, with `expm1`, so κ from 1e-6 to
//! 1e6 neither overflows nor cancels.

use glam::DVec3;
use std::f64::consts::PI;

/// Smallest and largest concentration a lobe may have.
pub const KAPPA_MIN: f64 = 1e-6;
pub const KAPPA_MAX: f64 = 1e6;

/// A unit-mass vMF lobe γ(s) = c(κ) exp(κ μ·s) (Eq. 5).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vmf {
    pub mu: DVec3,
    pub kappa: f64,
}

/// `κ / sinh κ`'s logarithm, stable from 0 to 1e6 (the normaliser is `e^this / 4π`).
pub fn ln_kappa_over_sinh(kappa: f64) -> f64 {
    if kappa < 1e-4 {
        // κ/sinh κ = 1 − κ²/6 + …
        return -kappa * kappa / 6.0;
    }
    // ln sinh κ = κ + ln(1 − e^{−2κ}) − ln 2
    kappa.ln() - (kappa + (-(-2.0 * kappa).exp_m1()).ln() - std::f64::consts::LN_2)
}

/// The normaliser c(κ) = κ / (4π sinh κ) (Eq. 16); underflows to 0 gracefully.
pub fn normaliser(kappa: f64) -> f64 {
    ln_kappa_over_sinh(kappa).exp() / (4.0 * PI)
}

/// `κ / (2π (1 − e^{−2κ}))`: the density at the mode, c(κ) e^κ, without overflow.
pub fn peak_density(kappa: f64) -> f64 {
    if kappa < 1e-8 {
        return 1.0 / (4.0 * PI) * (1.0 + kappa);
    }
    kappa / (2.0 * PI * -(-2.0 * kappa).exp_m1())
}

/// Mean cosine A(κ) = E[μ·s] = coth κ − 1/κ (the length of the mean resultant).
pub fn mean_cosine(kappa: f64) -> f64 {
    if kappa < 1e-3 {
        // coth κ − 1/κ = κ/3 − κ³/45 + …
        return kappa / 3.0 - kappa.powi(3) / 45.0;
    }
    // coth κ = (1 + e^{−2κ}) / (1 − e^{−2κ})
    let e = (-2.0 * kappa).exp();
    (1.0 + e) / -(-2.0 * kappa).exp_m1() - 1.0 / kappa
}

impl Vmf {
    /// A lobe with μ normalised and κ clamped to [KAPPA_MIN, KAPPA_MAX]; a zero or
    /// non-finite μ becomes +z with κ = KAPPA_MIN (uniform).
    pub fn new(mu: DVec3, kappa: f64) -> Self {
        let len = mu.length();
        if !(len > 0.0 && len.is_finite()) || kappa.is_nan() {
            return Self {
                mu: DVec3::Z,
                kappa: KAPPA_MIN,
            };
        }
        Self {
            mu: mu / len,
            kappa: kappa.clamp(KAPPA_MIN, KAPPA_MAX),
        }
    }

    /// Density (w.r.t. solid angle) at unit direction `s`:
    /// κ / (2π (1 − e^{−2κ})) · exp(κ(μ·s − 1)), written with ‖s − μ‖² = 2(1 − μ·s)
    /// so that directions close to μ keep their precision.
    pub fn pdf(&self, s: DVec3) -> f64 {
        let half_d2 = 0.5 * (s - self.mu).length_squared();
        peak_density(self.kappa) * (-self.kappa * half_d2).exp()
    }

    /// Samples the lobe (Eq. 10–11 in the stable form
    /// cos θ = 1 + log1p((1 − u) expm1(−2κ)) / κ, never Eq. 12's approximation).
    pub fn sample(&self, u: [f64; 2]) -> DVec3 {
        let local = sample_local(u, self.kappa);
        let (t, b) = self.mu.any_orthonormal_pair();
        t * local.x + b * local.y + self.mu * local.z
    }

    /// Single-lobe maximum-likelihood estimate from the weighted mean of unit
    /// directions `n` (its length r ∈ [0, 1)): κ = (3r − r³)/(1 − r²), μ = n/‖n‖
    /// (Eq. 13–14, Banerjee et al.'s approximation).
    pub fn from_mean_resultant(n: DVec3) -> Self {
        let r = n.length();
        if !r.is_finite() || r <= 0.0 {
            return Self::new(DVec3::Z, KAPPA_MIN);
        }
        let r = r.min(1.0 - 1e-12);
        Self::new(n, (3.0 * r - r * r * r) / (1.0 - r * r))
    }

    /// Integral of γ² over the sphere: c(κ)²/c(2κ) = c(κ) cosh κ = κ coth κ / 4π.
    pub fn self_product(&self) -> f64 {
        let k = self.kappa;
        let k_coth = if k < 1e-4 {
            1.0 + k * k / 3.0
        } else {
            k * (1.0 + (-2.0 * k).exp()) / -(-2.0 * k).exp_m1()
        };
        k_coth / (4.0 * PI)
    }

    /// ∫ γ_a γ_b ds = c(κa) c(κb) / c(κc), κc = ‖κa μa + κb μb‖ (Eq. 8).
    pub fn cross_product(&self, other: &Vmf) -> f64 {
        let kc = (self.mu * self.kappa + other.mu * other.kappa).length();
        (ln_kappa_over_sinh(self.kappa) + ln_kappa_over_sinh(other.kappa) - ln_kappa_over_sinh(kc))
            .exp()
            / (4.0 * PI)
    }
}

/// A direction around +z with cos θ distributed as a vMF of concentration `kappa`.
pub fn sample_local(u: [f64; 2], kappa: f64) -> DVec3 {
    let kappa = kappa.clamp(KAPPA_MIN, KAPPA_MAX);
    // 1 − cos θ = −log1p((1 − u) expm1(−2κ)) / κ ∈ [0, 2]: computed directly, so
    // sin θ keeps full precision in a sharp lobe.
    let one_minus_cos = (-((1.0 - u[0]) * (-2.0 * kappa).exp_m1()).ln_1p() / kappa).clamp(0.0, 2.0);
    let cos_t = 1.0 - one_minus_cos;
    let sin_t = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    DVec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

/// Accumulates weighted unit directions for one single-lobe estimate (Eq. 13–15).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LobeAccumulator {
    pub weight_sum: f64,
    pub direction_sum: DVec3,
    pub count: u64,
}

impl LobeAccumulator {
    /// Adds a sample direction `s` (unit) with a non-negative weight (its path
    /// throughput, Eq. 15's product of β); non-finite or negative weights are dropped.
    pub fn add(&mut self, s: DVec3, weight: f64) {
        if weight > 0.0 && weight.is_finite() && s.is_finite() {
            self.weight_sum += weight;
            self.direction_sum += s * weight;
            self.count += 1;
        }
    }

    pub fn merge(&mut self, other: &LobeAccumulator) {
        self.weight_sum += other.weight_sum;
        self.direction_sum += other.direction_sum;
        self.count += other.count;
    }

    /// α = (Σ weights) / M over all `total_samples` paths (Eq. 15), and the lobe of
    /// the weighted mean resultant (Eq. 13–14); `None` when no sample landed here.
    pub fn estimate(&self, total_samples: u64) -> Option<WeightedVmf> {
        if self.weight_sum <= 0.0 || total_samples == 0 {
            return None;
        }
        Some(WeightedVmf {
            weight: self.weight_sum / total_samples as f64,
            lobe: Vmf::from_mean_resultant(self.direction_sum / self.weight_sum),
        })
    }
}

/// A lobe with a weight: α γ(s). α is a scalar here; colour lives with the caller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeightedVmf {
    pub weight: f64,
    pub lobe: Vmf,
}

/// Exact squared L2 distance ‖α0 γ0 − α1 γ1‖² (App. A):
/// α0² c0 cosh κ0 + α1² c1 cosh κ1 − 2 α0 α1 c0 c1 / c(κc).
pub fn l2_distance_sq(a: &WeightedVmf, b: &WeightedVmf) -> f64 {
    let d = a.weight * a.weight * a.lobe.self_product()
        + b.weight * b.weight * b.lobe.self_product()
        - 2.0 * a.weight * b.weight * a.lobe.cross_product(&b.lobe);
    d.max(0.0)
}

/// The κ ≫ 1 form of the same distance (Eq. 7):
/// α0²κ0/4π + α1²κ1/4π − α0α1κ0κ1/(π κc) · e^{κc − κ0 − κ1}.
/// It needs κ0, κ1 *and* κc large (see [`l2_approximation_is_safe`]).
pub fn l2_distance_sq_approx(a: &WeightedVmf, b: &WeightedVmf) -> f64 {
    let (k0, k1) = (a.lobe.kappa, b.lobe.kappa);
    let kc = (a.lobe.mu * k0 + b.lobe.mu * k1).length();
    let cross = a.weight * b.weight * k0 * k1 / (PI * kc.max(1e-300)) * (kc - k0 - k1).exp();
    (a.weight * a.weight * k0 + b.weight * b.weight * k1) / (4.0 * PI) - cross
}

/// When Eq. 7 is within `rel_tol` of the exact distance (relative to the lobes'
/// own norms): it replaces coth κ by 1 and sinh κ by e^κ/2, errors of 2e^{−2κ} each,
/// so every one of κ0, κ1 and κc must exceed ½ ln(4/rel_tol) (κ ≥ 3 for 1 %: the
/// paper's "min(κ) ≈ 3", but κc is small for opposite lobes even when κ0, κ1 are not).
pub fn l2_approximation_is_safe(a: &Vmf, b: &Vmf, rel_tol: f64) -> bool {
    let kc = (a.mu * a.kappa + b.mu * b.kappa).length();
    let k_min = 0.5 * (4.0 / rel_tol).ln();
    a.kappa >= k_min && b.kappa >= k_min && kc >= k_min
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normaliser_matches_closed_form_where_it_is_representable() {
        for k in [1e-6, 1e-3, 0.1, 1.0, 10.0, 100.0, 700.0] {
            let direct = k / (4.0 * PI * f64::sinh(k));
            let ours = normaliser(k);
            assert!(
                (ours / direct - 1.0).abs() < 1e-12,
                "κ {k}: {ours} vs {direct}"
            );
        }
        // Beyond sinh's range the peak stays finite and exact: κ/(2π) for κ ≫ 1.
        assert!((peak_density(1e6) / (1e6 / (2.0 * PI)) - 1.0).abs() < 1e-15);
        assert!((mean_cosine(1e6) - (1.0 - 1e-6)).abs() < 1e-15);
    }

    #[test]
    fn estimate_inverts_mean_cosine_approximately() {
        // Banerjee's κ(r) is an approximation of A⁻¹: within 1–3 % over the range.
        for k in [0.5, 3.0, 30.0, 3000.0] {
            let est = Vmf::from_mean_resultant(DVec3::Z * mean_cosine(k)).kappa;
            assert!((est / k - 1.0).abs() < 0.05, "κ {k}: {est}");
        }
    }
}
