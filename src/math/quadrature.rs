//! Gauss–Legendre quadrature, the one implementation shared by flatland's exact
//! shading, the object-space visibility gradient and the tests: nodes and weights
//! on [−1, 1], and composite rules on equal panels of [a, b]. Hand-written (a few
//! lines of Newton iteration) rather than a crate: nothing else in the build needs
//! special functions.

/// Nodes and weights of the `n`-point Gauss–Legendre rule on `[−1, 1]` (exact for
/// polynomials of degree 2n − 1; accurate to ~1e-15 for n up to a few hundred).
#[derive(Clone, Debug)]
pub struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussLegendre {
    /// Computes the rule by Newton iteration on the Legendre polynomial `P_n`
    /// from the Chebyshev-like initial guesses `cos(π (i + 3/4) / (n + 1/2))`.
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

    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// (node, weight) pairs of the composite rule on `panels` equal panels of
    /// `[a, b]`, so that Σ w f(x) ≈ ∫_a^b f.
    pub fn composite(&self, a: f64, b: f64, panels: usize) -> Vec<(f64, f64)> {
        let panels = panels.max(1);
        let h = (b - a) / panels as f64;
        let mut out = Vec::with_capacity(panels * self.nodes.len());
        for p in 0..panels {
            let mid = a + (p as f64 + 0.5) * h;
            for (z, w) in self.nodes.iter().zip(&self.weights) {
                out.push((mid + 0.5 * h * z, 0.5 * h * w));
            }
        }
        out
    }

    /// `∫_a^b f` by the composite rule on panels no wider than `max_panel`.
    pub fn integrate(&self, a: f64, b: f64, max_panel: f64, f: impl Fn(f64) -> f64) -> f64 {
        if b <= a {
            return 0.0;
        }
        let panels = ((b - a) / max_panel).ceil().max(1.0) as usize;
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
        let w: f64 = gl.weights().iter().sum();
        assert!((w - 2.0).abs() < 1e-14, "weights sum {w}");
        // Degree 31 is exact for 16 points.
        let v = gl.integrate(0.0, 1.0, 0.1, |t| t.powi(31));
        assert!((v - 1.0 / 32.0).abs() < 1e-15, "{v}");
        let c = gl.integrate(-1.3, 0.4, 0.1, f64::cos);
        assert!((c - (0.4f64.sin() + 1.3f64.sin())).abs() < 1e-15, "{c}");
        let s: f64 = gl
            .composite(0.0, 2.0, 3)
            .iter()
            .map(|(x, w)| w * x.powi(5))
            .sum();
        assert!((s - 64.0 / 6.0).abs() < 1e-12, "{s}");
        // The 16-point nodes as tabulated (Abramowitz & Stegun 25.4).
        assert!((gl.nodes()[15] - 0.989_400_934_991_649_9).abs() < 1e-15);
        assert!((gl.weights()[15] - 0.027_152_459_411_754_1).abs() < 1e-15);
        let one = GaussLegendre::new(1);
        assert_eq!((one.nodes()[0], one.weights()[0]), (0.0, 2.0));
    }
}
