//! Piecewise-constant 1D and 2D distributions, used for environment-map importance
//! sampling and for choosing emitting triangles in proportion to their power.

use super::Vec2;

/// A piecewise-constant density on [0, 1) with `n` equal cells.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    func: Vec<f32>,
    cdf: Vec<f32>,
    integral: f32,
    /// Guide table (Chen & Asau's cut points): `guide[k]` is the cell that
    /// `u = k/n` falls in, k = 0..=n, so the cell of any u in [k/n, (k+1)/n)
    /// lies in `guide[k]..=guide[k + 1]`: a search over those few cells instead
    /// of the whole CDF, whose ~log2(n) unpredictable branches were 8–10 % of an
    /// image-sky render. The same cell as the full search, bit for bit.
    guide: Vec<u32>,
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
        let guide = (0..=n)
            .map(|k| cell_of(&cdf, k as f32 / n as f32) as u32)
            .collect();
        Self {
            func,
            cdf,
            integral,
            guide,
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

    /// The cell whose CDF interval contains `u` (`cell_of`), searched between
    /// the guide table's bounds for u's bucket. Rounding in the bucket index can
    /// put u just outside them: the answer is checked (the last cell with
    /// cdf ≤ u) and the whole CDF searched when the check fails, so the result
    /// is always the full search's.
    ///
    /// One cell (a scene with one light) needs no search: its answer is 0
    /// whatever u is. Inlined, that costs nothing; out of line, the call's
    /// dependent loads stalled the lanes' light pick (cornell −0.7 %).
    #[inline]
    pub fn sample_discrete(&self, u: f32) -> usize {
        if self.len() == 1 {
            return 0;
        }
        self.search(u)
    }

    /// [`Self::sample_discrete`] over two or more cells.
    fn search(&self, u: f32) -> usize {
        self.guided(u).unwrap_or_else(|| cell_of(&self.cdf, u))
    }

    /// The cell found between the guide table's bounds, if it passes the check.
    fn guided(&self, u: f32) -> Option<usize> {
        let n = self.len();
        // NaN and negative u give bucket 0 (`as` saturates), then fail the check.
        let k = ((u * n as f32) as usize).min(n - 1);
        let (lo, hi) = (self.guide[k] as usize, self.guide[k + 1] as usize);
        // `guide` is non-decreasing (k/n and the cell of u both are): hi ≥ lo.
        let i = lo + self.cdf[lo + 1..=hi].partition_point(|&c| c <= u);
        (self.cdf[i] <= u && (i + 1 == n || self.cdf[i + 1] > u)).then_some(i)
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

/// The cell of a CDF (`cdf[0] = 0`, one entry per cell boundary) whose interval
/// contains `u`: the last cell with cdf ≤ u, which skips zero-width cells; 0 for
/// u below 0 or NaN.
fn cell_of(cdf: &[f32], u: f32) -> usize {
    // First index with cdf > u, minus one.
    let i = cdf.partition_point(|&c| c <= u);
    i.saturating_sub(1).min(cdf.len() - 2)
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

    /// The guided search finds the full search's cell for every u: random ones,
    /// the CDF's own values and their neighbours, the buckets' edges, and
    /// out-of-range inputs, on flat, peaked and zero-run distributions.
    #[test]
    fn the_guided_search_finds_the_full_searchs_cell() {
        let peaked: Vec<f32> = (0..1000)
            .map(|i| if i == 417 { 1e6 } else { 1e-3 })
            .collect();
        let runs: Vec<f32> = (0..257)
            .map(|i| {
                if (i / 16) % 3 == 0 {
                    0.0
                } else {
                    (i % 7) as f32
                }
            })
            .collect();
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut random = || {
            x ^= x >> 12;
            x ^= x << 25;
            x ^= x >> 27;
            (x.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut checked = 0;
        for w in [
            vec![1.0; 5],
            vec![0.0; 9],
            vec![3.0],
            vec![0.0],
            peaked,
            runs,
        ] {
            let d = Distribution1D::new(&w);
            let n = d.len();
            let mut us: Vec<f32> = (0..20_000).map(|_| random()).collect();
            for &c in &d.cdf {
                us.extend([c, c.next_down(), c.next_up()]);
            }
            for k in 0..=n {
                let b = k as f32 / n as f32;
                us.extend([b, b.next_down(), b.next_up()]);
            }
            us.extend([0.0, -0.0, -1.0, 1.0, 2.0, f32::NAN, 1.0f32.next_down()]);
            for u in us {
                assert_eq!(d.sample_discrete(u), cell_of(&d.cdf, u), "u = {u}, n = {n}");
                checked += 1;
            }
            // The guide does the work: random u in [0, 1) almost never fall back.
            let missed = (0..20_000).filter(|_| d.guided(random()).is_none()).count();
            assert!(missed <= 20, "{missed} of 20000 fell back, n = {n}");
        }
        assert!(checked > 100_000);
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
