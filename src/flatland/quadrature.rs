//! Composite Gauss–Legendre quadrature for the smooth lighting term over one
//! visible angular interval. The integrand `L(θ) cos θ` (Gaussian lobe times cosine)
//! has no elementary antiderivative, but it is entire, so a 16-point rule on panels of
//! at most 0.1 rad integrates it to rounding error: the "exact" shading of Sec. 6.3
//! only has error at the level of f64 round-off, which is what lets the finite
//! differences of `B(x)` be compared with a tight tolerance.

/// Nodes and weights of the `N`-point Gauss–Legendre rule on `[-1, 1]`.
#[derive(Clone, Debug)]
pub struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

/// Largest panel width (radians) of the composite rule.
const PANEL: f64 = 0.1;

impl GaussLegendre {
    /// Computes the rule by Newton iteration on the Legendre polynomial `P_n`
    /// from the Chebyshev-like initial guesses `cos(π (i − 1/4) / (n + 1/2))`.
    pub fn new(n: usize) -> Self {
        let n = n.max(1);
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        for i in 0..n.div_ceil(2) {
            let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                // Three-term recurrence for P_n(z) and its derivative.
                let (mut p0, mut p1) = (1.0f64, z);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                let pn = if n == 1 { z } else { p1 };
                let pnm1 = if n == 1 { 1.0 } else { p0 };
                dp = n as f64 * (z * pn - pnm1) / (z * z - 1.0);
                let dz = pn / dp;
                z -= dz;
                if dz.abs() < 1e-16 {
                    break;
                }
            }
            let w = 2.0 / ((1.0 - z * z) * dp * dp);
            nodes[i] = -z;
            nodes[n - 1 - i] = z;
            weights[i] = w;
            weights[n - 1 - i] = w;
        }
        Self { nodes, weights }
    }

    /// `∫_a^b f(θ) dθ` with the composite rule (panels of at most `PANEL` rad).
    pub fn integrate(&self, a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
        if b <= a {
            return 0.0;
        }
        let panels = ((b - a) / PANEL).ceil().max(1.0) as usize;
        let h = (b - a) / panels as f64;
        let mut sum = 0.0;
        for p in 0..panels {
            let mid = a + (p as f64 + 0.5) * h;
            let half = 0.5 * h;
            let mut s = 0.0;
            for (z, w) in self.nodes.iter().zip(&self.weights) {
                s += w * f(mid + half * z);
            }
            sum += s * half;
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_polynomials_and_cosine_exactly() {
        let gl = GaussLegendre::new(16);
        let w: f64 = gl.weights.iter().sum();
        assert!((w - 2.0).abs() < 1e-14, "weights sum {w}");
        // Degree 31 is exact for 16 points.
        let v = gl.integrate(0.0, 1.0, |t| t.powi(31));
        assert!((v - 1.0 / 32.0).abs() < 1e-15, "{v}");
        let c = gl.integrate(-1.3, 0.4, f64::cos);
        assert!((c - (0.4f64.sin() + 1.3f64.sin())).abs() < 1e-15, "{c}");
    }
}
