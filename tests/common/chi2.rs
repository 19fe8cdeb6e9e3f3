//! Pearson chi-square goodness-of-fit test of a direction sampler against its claimed
//! density, after Mitsuba 3's `chi2.py`:
//!
//! 1. draw N independent samples and histogram them over a partition of the sphere
//!    into (θ, φ) cells (a sampler may also *fail*; failures get their own cell);
//! 2. integrate the density over every cell numerically (Gauss-Legendre) to get the
//!    expected counts; the failure cell expects N·(1 − ∫pdf);
//! 3. sort cells by expected count, pool those below 5 until the pool reaches 5,
//!    and compute Pearson's statistic and its p-value from the chi-square
//!    distribution (regularized upper incomplete gamma Q(dof/2, χ²/2));
//! 4. compare with a significance level Šidák-corrected for the number of tests.
//!
//! Any partition gives a valid test; [`SphereBins::from_cdfs`] builds one whose cells
//! carry similar probability (so that sharp lobes are resolved and the test has power),
//! from rough CDFs in θ and φ such as [`cauchy_cdf`] around the lobe's centre.

use glam::DVec3;
use std::f64::consts::PI;

/// The outcome of a pooled Pearson test.
#[derive(Clone, Debug)]
pub struct Chi2Outcome {
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    /// Cells with expected count < 5 that were pooled, and the pooled cells they made.
    pub pooled_in: usize,
    pub pooled_out: usize,
    /// Sum of the expected cell probabilities (the density's integral, ≤ 1).
    pub pdf_integral: f64,
    /// Fraction of samples that were failures (`None`).
    pub failure_rate: f64,
}

/// ln Γ(x) for x > 0 (Lanczos, g = 7, 9 terms; relative error ~1e-15).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection formula.
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularized lower incomplete gamma P(a, x) by its series (use for x < a + 1).
fn gamma_p_series(a: f64, x: f64) -> f64 {
    let mut sum = 1.0 / a;
    let mut term = sum;
    let mut ap = a;
    for _ in 0..100_000 {
        ap += 1.0;
        term *= x / ap;
        sum += term;
        if term.abs() < sum.abs() * 1e-16 {
            break;
        }
    }
    (sum.ln() - x + a * x.ln() - ln_gamma(a)).exp()
}

/// Regularized upper incomplete gamma Q(a, x) by Lentz's continued fraction
/// (use for x ≥ a + 1).
fn gamma_q_cf(a: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / TINY;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..100_000 {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < TINY {
            d = TINY;
        }
        c = b + an / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < 1e-16 {
            break;
        }
    }
    (h.ln() - x + a * x.ln() - ln_gamma(a)).exp()
}

/// Regularized upper incomplete gamma Q(a, x) = Γ(a, x)/Γ(a), a > 0, x ≥ 0.
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        1.0
    } else if x < a + 1.0 {
        1.0 - gamma_p_series(a, x)
    } else {
        gamma_q_cf(a, x)
    }
}

/// Survival function of the chi-square distribution: P[X ≥ stat] for `dof` degrees.
pub fn chi2_sf(stat: f64, dof: usize) -> f64 {
    gamma_q(0.5 * dof as f64, 0.5 * stat)
}

/// Šidák-corrected per-test significance so that `tests` independent tests together
/// have family-wise significance `alpha`.
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / tests as f64)
}

/// Pearson's chi-square test with Mitsuba-style pooling of low-expectation cells.
/// Fails outright (Err) when a cell with expected count 0 holds samples, or when
/// fewer than two cells remain.
pub fn pearson_pooled(
    observed: &[f64],
    expected: &[f64],
    min_expected: f64,
) -> Result<(f64, usize, usize, usize), String> {
    assert_eq!(observed.len(), expected.len());
    let mut idx: Vec<usize> = (0..expected.len()).collect();
    idx.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut stat, mut cells) = (0.0, 0usize);
    let (mut pool_obs, mut pool_exp) = (0.0, 0.0);
    let (mut pooled_in, mut pooled_out) = (0usize, 0usize);
    for &i in &idx {
        let (o, e) = (observed[i], expected[i]);
        if e <= 0.0 && o > 0.0 {
            return Err(format!(
                "{o} samples in cell {i} whose expected frequency is {e}"
            ));
        }
        // Sorted ascending: small cells accumulate in the pool, and a pool still short
        // of `min_expected` also swallows the next (larger) cell before it is emitted.
        if e < min_expected || pool_exp > 0.0 {
            pool_obs += o;
            pool_exp += e;
            pooled_in += 1;
            if pool_exp >= min_expected {
                stat += (pool_obs - pool_exp).powi(2) / pool_exp;
                cells += 1;
                pooled_out += 1;
                pool_obs = 0.0;
                pool_exp = 0.0;
            }
        } else {
            stat += (o - e).powi(2) / e;
            cells += 1;
        }
    }
    if pool_exp > 0.0 {
        stat += (pool_obs - pool_exp).powi(2) / pool_exp;
        cells += 1;
        pooled_out += 1;
    }
    if cells < 2 {
        return Err(format!(
            "only {cells} cell(s) after pooling: no degrees of freedom"
        ));
    }
    Ok((stat, cells - 1, pooled_in, pooled_out))
}

/// CDF on [lo, hi] of a Cauchy distribution (truncated and renormalised) centred at
/// `center` with scale `scale`: heavy tails, so cells built from it also cover the
/// flanks of a lobe.
pub fn cauchy_cdf(x: f64, center: f64, scale: f64, lo: f64, hi: f64) -> f64 {
    let f = |t: f64| ((t - center) / scale).atan();
    ((f(x.clamp(lo, hi)) - f(lo)) / (f(hi) - f(lo))).clamp(0.0, 1.0)
}

/// A partition of the unit sphere into cells [θ_i, θ_{i+1}] × [φ_j, φ_{j+1}] with
/// θ from the +z axis and φ = atan2(y, x) ∈ [−π, π].
#[derive(Clone, Debug)]
pub struct SphereBins {
    pub theta: Vec<f64>,
    pub phi: Vec<f64>,
}

/// Inverse of a monotone CDF on [lo, hi] at level `y`, by bisection.
fn invert(cdf: &dyn Fn(f64) -> f64, lo: f64, hi: f64, y: f64) -> f64 {
    let (mut a, mut b) = (lo, hi);
    for _ in 0..100 {
        let m = 0.5 * (a + b);
        if cdf(m) < y {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

impl SphereBins {
    /// Mitsuba's `SphericalDomain` partition: uniform in cos θ and in φ.
    pub fn uniform(n_theta: usize, n_phi: usize) -> Self {
        let theta = (0..=n_theta)
            .map(|i| {
                (1.0 - 2.0 * i as f64 / n_theta as f64)
                    .clamp(-1.0, 1.0)
                    .acos()
            })
            .collect();
        let phi = (0..=n_phi)
            .map(|j| -PI + 2.0 * PI * j as f64 / n_phi as f64)
            .collect();
        Self { theta, phi }
    }

    /// Cells of roughly equal probability under the given marginal CDFs: θ edges are
    /// the `n_theta`-quantiles of `cdf_theta` on [0, theta_max] (when theta_max < π one
    /// extra band [theta_max, π] is appended, e.g. the lower hemisphere for a BRDF),
    /// φ edges the `n_phi`-quantiles of `cdf_phi` on [−π, π].
    pub fn from_cdfs(
        n_theta: usize,
        n_phi: usize,
        theta_max: f64,
        cdf_theta: &dyn Fn(f64) -> f64,
        cdf_phi: &dyn Fn(f64) -> f64,
    ) -> Self {
        let mut theta: Vec<f64> = (0..=n_theta)
            .map(|i| match i {
                0 => 0.0,
                i if i == n_theta => theta_max,
                i => invert(cdf_theta, 0.0, theta_max, i as f64 / n_theta as f64),
            })
            .collect();
        if theta_max < PI {
            theta.push(PI);
        }
        let phi = (0..=n_phi)
            .map(|j| match j {
                0 => -PI,
                j if j == n_phi => PI,
                j => invert(cdf_phi, -PI, PI, j as f64 / n_phi as f64),
            })
            .collect();
        // Quantiles of a very peaked CDF can coincide; drop empty cells.
        let dedup = |mut v: Vec<f64>| {
            v.dedup_by(|a, b| *a <= *b);
            v
        };
        Self {
            theta: dedup(theta),
            phi: dedup(phi),
        }
    }

    pub fn cell_count(&self) -> usize {
        (self.theta.len() - 1) * (self.phi.len() - 1)
    }

    /// The cell holding direction `d` (unit length).
    pub fn cell_of(&self, d: DVec3) -> usize {
        let theta = d.z.clamp(-1.0, 1.0).acos();
        let phi = d.y.atan2(d.x);
        let nt = self.theta.len() - 1;
        let np = self.phi.len() - 1;
        let i = self.theta.partition_point(|&t| t <= theta).clamp(1, nt) - 1;
        let j = self.phi.partition_point(|&p| p <= phi).clamp(1, np) - 1;
        i * np + j
    }

    /// ∫ pdf dω over every cell by adaptive Gauss-Legendre cubature in (θ, φ) with
    /// weight sin θ: an `order`×`order` rule on the cell is compared with the same rule
    /// on its four quadrants, which are refined recursively (to `max_depth`) until the
    /// two agree to `tol` (an absolute probability) or to 1e-6 relative. The refinement matters for sharp
    /// lobes whose tails reach into wide cells.
    pub fn integrate(
        &self,
        pdf: &dyn Fn(DVec3) -> f64,
        order: usize,
        tol: f64,
        max_depth: u32,
    ) -> Vec<f64> {
        let (x, w) = super::gauss_legendre(order);
        let rule = |t0: f64, t1: f64, p0: f64, p1: f64| -> f64 {
            let (ht, hp) = (0.5 * (t1 - t0), 0.5 * (p1 - p0));
            let mut sum = 0.0;
            for (xt, wt) in x.iter().zip(&w) {
                let t = t0 + ht * (xt + 1.0);
                let (st, ct) = t.sin_cos();
                for (xp, wp) in x.iter().zip(&w) {
                    let (sp, cp) = (p0 + hp * (xp + 1.0)).sin_cos();
                    sum += wt * wp * st * pdf(DVec3::new(st * cp, st * sp, ct));
                }
            }
            sum * ht * hp
        };
        #[allow(clippy::too_many_arguments)]
        fn refine(
            rule: &dyn Fn(f64, f64, f64, f64) -> f64,
            t0: f64,
            t1: f64,
            p0: f64,
            p1: f64,
            whole: f64,
            tol: f64,
            depth: u32,
        ) -> f64 {
            let (tm, pm) = (0.5 * (t0 + t1), 0.5 * (p0 + p1));
            let q = [
                (t0, tm, p0, pm),
                (t0, tm, pm, p1),
                (tm, t1, p0, pm),
                (tm, t1, pm, p1),
            ];
            let parts: Vec<f64> = q.iter().map(|&(a, b, c, d)| rule(a, b, c, d)).collect();
            let sum: f64 = parts.iter().sum();
            // Relative floor: f32 densities carry ~1e-6 noise that no refinement removes.
            if depth == 0 || (sum - whole).abs() <= tol.max(1e-6 * sum.abs()) {
                return sum;
            }
            q.iter()
                .zip(&parts)
                .map(|(&(a, b, c, d), &p)| refine(rule, a, b, c, d, p, 0.25 * tol, depth - 1))
                .sum()
        }
        let np = self.phi.len() - 1;
        let mut out = vec![0.0; self.cell_count()];
        for i in 0..self.theta.len() - 1 {
            let (t0, t1) = (self.theta[i], self.theta[i + 1]);
            for j in 0..np {
                let (p0, p1) = (self.phi[j], self.phi[j + 1]);
                let whole = rule(t0, t1, p0, p1);
                out[i * np + j] = refine(&rule, t0, t1, p0, p1, whole, tol, max_depth);
            }
        }
        out
    }
}

/// Runs the full test: `n` calls of `sample` (a `None` is a failed sample), expected
/// counts from `pdf` over `bins`. Returns Err for a hard failure (samples where the
/// density is 0, a density integrating to more than 1, no degrees of freedom).
pub fn sphere_test(
    bins: &SphereBins,
    n: usize,
    mut sample: impl FnMut() -> Option<DVec3>,
    pdf: &dyn Fn(DVec3) -> f64,
) -> Result<Chi2Outcome, String> {
    let cells = bins.cell_count();
    let mut observed = vec![0.0; cells + 1];
    for _ in 0..n {
        match sample() {
            Some(d) if d.is_finite() => observed[bins.cell_of(d)] += 1.0,
            Some(d) => return Err(format!("sampler returned a non-finite direction {d}")),
            None => observed[cells] += 1.0,
        }
    }
    let probs = bins.integrate(pdf, 8, 1e-7, 6);
    let total: f64 = probs.iter().sum();
    if total > 1.0 + 1e-3 {
        return Err(format!("pdf integrates to {total} > 1"));
    }
    let mut expected: Vec<f64> = probs.iter().map(|p| p * n as f64).collect();
    // The failure cell: quadrature cannot resolve a failure probability below its own
    // error, and measure-zero failures (e.g. a direction exactly on the horizon) do
    // occur with f32 inputs, so its expectation gets a tiny floor instead of the
    // hard "samples where pdf = 0" rejection; pooling absorbs it.
    expected.push((1.0 - total).max(1e-12) * n as f64);
    let (statistic, dof, pooled_in, pooled_out) = pearson_pooled(&observed, &expected, 5.0)?;
    Ok(Chi2Outcome {
        statistic,
        dof,
        p_value: chi2_sf(statistic, dof),
        pooled_in,
        pooled_out,
        pdf_integral: total,
        failure_rate: observed[cells] / n as f64,
    })
}
