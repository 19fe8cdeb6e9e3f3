//! Piecewise-constant 1D and 2D distributions, used for environment-map importance
//! sampling and for choosing emitting triangles in proportion to their power.

use super::Vec2;

/// A piecewise-constant density on [0, 1) with `n` equal cells.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    func: Vec<f32>,
    cdf: Vec<f32>,
    integral: f32,
}

impl Distribution1D {
    /// Builds from non-negative cell weights; an all-zero input becomes uniform so
    /// that sampling never divides by zero.
    pub fn new(weights: &[f32]) -> Self {
        assert!(
            !weights.is_empty(),
            "a distribution needs at least one cell"
        );
        let n = weights.len();
        let func: Vec<f32> = weights
            .iter()
            .map(|&w| if w.is_finite() && w > 0.0 { w } else { 0.0 })
            .collect();
        let mut cdf = Vec::with_capacity(n + 1);
        cdf.push(0.0f32);
        let mut acc = 0.0f64;
        for &f in &func {
            acc += f as f64 / n as f64;
            cdf.push(acc as f32);
        }
        let integral = acc as f32;
        if integral > 0.0 {
            for c in cdf.iter_mut() {
                *c /= integral;
            }
        } else {
            for (i, c) in cdf.iter_mut().enumerate() {
                *c = i as f32 / n as f32;
            }
        }
        *cdf.last_mut().unwrap() = 1.0;
        Self {
            func,
            cdf,
            integral,
        }
    }

    pub fn len(&self) -> usize {
        self.func.len()
    }

    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// ∫ f over [0, 1).
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// Samples a continuous position in [0, 1); returns (x, density at x, cell).
    pub fn sample_continuous(&self, u: f32) -> (f32, f32, usize) {
        let cell = self.sample_discrete(u);
        let lo = self.cdf[cell];
        let hi = self.cdf[cell + 1];
        let du = if hi > lo { (u - lo) / (hi - lo) } else { 0.5 };
        let x = ((cell as f32 + du.clamp(0.0, 1.0)) / self.len() as f32).min(1.0 - f32::EPSILON);
        (x, self.pdf_cell(cell), cell)
    }

    /// The cell whose CDF interval contains `u`.
    pub fn sample_discrete(&self, u: f32) -> usize {
        // First index with cdf > u, minus one; skips zero-width cells.
        let i = self.cdf.partition_point(|&c| c <= u);
        i.saturating_sub(1).min(self.len() - 1)
    }

    /// Probability of choosing `cell` with [`Self::sample_discrete`].
    pub fn discrete_pmf(&self, cell: usize) -> f32 {
        self.cdf[cell + 1] - self.cdf[cell]
    }

    /// Density (w.r.t. [0,1) measure) of the continuous sample in `cell`.
    pub fn pdf_cell(&self, cell: usize) -> f32 {
        if self.integral > 0.0 {
            self.func[cell] / self.integral
        } else {
            1.0
        }
    }
}

/// A piecewise-constant density on [0,1)², sampled as a marginal over rows (v) and
/// a conditional over columns (u).
#[derive(Clone, Debug)]
pub struct Distribution2D {
    conditional: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// `weights` is row-major with `width` columns.
    pub fn new(weights: &[f32], width: usize, height: usize) -> Self {
        assert_eq!(weights.len(), width * height);
        let conditional: Vec<Distribution1D> = (0..height)
            .map(|y| Distribution1D::new(&weights[y * width..(y + 1) * width]))
            .collect();
        let row_integrals: Vec<f32> = conditional.iter().map(|c| c.integral()).collect();
        Self {
            marginal: Distribution1D::new(&row_integrals),
            conditional,
        }
    }

    /// Returns a point in [0,1)² and its density.
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (y, pdf_y, row) = self.marginal.sample_continuous(u.y);
        let (x, pdf_x, _) = self.conditional[row].sample_continuous(u.x);
        (Vec2::new(x, y), pdf_x * pdf_y)
    }

    pub fn pdf(&self, p: Vec2) -> f32 {
        let h = self.conditional.len();
        let w = self.conditional[0].len();
        let row = ((p.y * h as f32) as usize).min(h - 1);
        let col = ((p.x * w as f32) as usize).min(w - 1);
        self.marginal.pdf_cell(row) * self.conditional[row].pdf_cell(col)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn discrete_sampling_matches_weights() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]);
        assert!((d.discrete_pmf(0) - 0.25).abs() < 1e-6);
        assert_eq!(d.discrete_pmf(1), 0.0);
        assert_eq!(d.sample_discrete(0.2), 0);
        assert_eq!(d.sample_discrete(0.25), 2);
        assert_eq!(d.sample_discrete(0.9999), 2);
    }

    #[test]
    fn pdf_2d_agrees_with_sample() {
        let w = [1.0, 2.0, 0.0, 4.0, 0.5, 0.5];
        let d = Distribution2D::new(&w, 3, 2);
        for i in 0..64u32 {
            let u = Vec2::new((i % 8) as f32 / 8.0 + 0.01, (i / 8) as f32 / 8.0 + 0.01);
            let (p, pdf) = d.sample(u);
            assert!((d.pdf(p) - pdf).abs() < 1e-4 * pdf.max(1.0), "{p:?}");
            assert!(pdf > 0.0);
        }
        // Density integrates to 1 over the square: sum of cell pdfs / cells.
        let mut s = 0.0;
        for y in 0..2 {
            for x in 0..3 {
                s += d.pdf(Vec2::new((x as f32 + 0.5) / 3.0, (y as f32 + 0.5) / 2.0)) / 6.0;
            }
        }
        assert!((s - 1.0).abs() < 1e-5);
    }
}
