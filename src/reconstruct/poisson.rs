//! primal image + pixel-pair differences → screened Poisson reconstruction (the
//! dense gradient-domain step of Kettunen et al. 2015, "Gradient-domain path
//! tracing"), in L2 and in L1 by iteratively reweighted least squares.
//!
//! For each colour channel separately, with P the primal (a pixel's mean), α_p ≥ 0
//! its weight, and for every valid pair e = (p, q) — q the right or lower
//! neighbour of p — a difference G_e standing for I_q − I_p and the residual
//! r_e = (I_q − I_p) − G_e, the solution minimises
//!
//! ```text
//!   E_k(I) = Σ_p α_p (I_p − P_p)²  +  s_k Σ_valid |r_e|^k        k = 2 (L2), 1 (L1)
//! ```
//!
//! (s_2 = 1; s_1 below). L2: the normal equations (diag α + Dᵀ W D) I = α P + Dᵀ W G,
//! W = diag(w_e), w_e = 1, by conjugate gradients with a Jacobi preconditioner,
//! started from P. L1: IRLS — the same solve with w_e = s_1 / (2 max(|r_e|, ε)), r_e
//! from the previous solution (the quadratic that touches s_1|r| at r_e), a few
//! times, each started from the last; ε smooths |r| below it (a Huber-like
//! objective). s_1 makes |r| comparable with the squared primal term: by default
//! the mean |r_e| of the L2 solution, so that a typical pair weighs as in L2.
//!
//! Where a pair is invalid the pixels keep only their primal term and the valid
//! pairs around them: a dropped edge lets the image jump there. A pixel with
//! α = 0 and no valid pair keeps P (its row of the system is zero and CG never
//! moves it). Inputs are sanitised (non-finite primal → 0 with α = 0, non-finite
//! difference → invalid pair, weights clamped), so the result is finite for any
//! input. The solve is deterministic: every sum runs in a fixed order and only
//! whole channels run in parallel.

use crate::math::Vec3;
use rayon::prelude::*;

/// The data term's exponent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Norm {
    L2,
    L1,
}

impl Norm {
    pub const ALL: [Norm; 2] = [Norm::L1, Norm::L2];

    pub fn name(self) -> &'static str {
        match self {
            Norm::L2 => "poisson-l2",
            Norm::L1 => "poisson-l1",
        }
    }
}

/// A screened Poisson problem on a `width`×`height` image; planes are row-major.
#[derive(Clone, Copy, Debug)]
pub struct Problem<'a> {
    pub width: usize,
    pub height: usize,
    pub primal: &'a [Vec3],
    /// α_p, per pixel (one for all channels).
    pub weight: &'a [f32],
    /// G for the pair (x, y)–(x+1, y) at index (x, y); the last column is unused.
    pub dx: &'a [Vec3],
    /// G for the pair (x, y)–(x, y+1) at index (x, y); the last row is unused.
    pub dy: &'a [Vec3],
    pub valid_x: &'a [bool],
    pub valid_y: &'a [bool],
}

#[derive(Clone, Copy, Debug)]
pub struct Settings {
    pub norm: Norm,
    /// CG stops at ‖residual‖ ≤ tolerance · ‖right-hand side‖ (preconditioned).
    pub tolerance: f64,
    pub max_iterations: usize,
    /// L1: reweighted solves after the first (L2) one.
    pub irls_iterations: usize,
    /// L1: CG iterations per reweighted solve (each starts from the last
    /// solution, so a few refine it; IRLS needs no exact inner solves).
    pub irls_max_iterations: usize,
    /// L1: ε as a fraction of the channel's mean |P| (floor 1e-8 absolute).
    pub epsilon: f64,
    /// L1: s_1 of the objective; `None`: the mean |r_e| of the L2 solution.
    pub l1_scale: Option<f64>,
}

impl Settings {
    pub fn new(norm: Norm) -> Self {
        Self {
            norm,
            tolerance: 1e-4,
            max_iterations: 400,
            irls_iterations: 4,
            irls_max_iterations: 25,
            epsilon: 1e-3,
            l1_scale: None,
        }
    }
}

/// Largest weight (α or w_e) the solve accepts: keeps the system's scale finite.
const MAX_WEIGHT: f64 = 1e12;

/// A solve's result.
#[derive(Clone, Debug)]
pub struct Solution {
    pub image: Vec<Vec3>,
    /// CG iterations, summed over the channels and the IRLS solves.
    pub iterations: usize,
}

/// The reconstructed image. Errors only when the planes' lengths do not match the size.
pub fn solve(problem: &Problem, settings: &Settings) -> Result<Solution, String> {
    let n = problem.width * problem.height;
    let lens = [
        ("primal", problem.primal.len()),
        ("weight", problem.weight.len()),
        ("dx", problem.dx.len()),
        ("dy", problem.dy.len()),
        ("valid_x", problem.valid_x.len()),
        ("valid_y", problem.valid_y.len()),
    ];
    if let Some((name, len)) = lens.iter().find(|(_, l)| *l != n) {
        return Err(format!(
            "poisson: the {name} plane has {len} entries, expected {}x{} = {n}",
            problem.width, problem.height
        ));
    }
    let channels: Vec<(Vec<f64>, usize)> = (0..3)
        .into_par_iter()
        .map(|c| Channel::new(problem, c).solve(settings))
        .collect();
    let iterations = channels.iter().map(|c| c.1).sum();
    let channels: Vec<&Vec<f64>> = channels.iter().map(|c| &c.0).collect();
    let image = (0..n)
        .map(|i| {
            let v = Vec3::new(
                channels[0][i] as f32,
                channels[1][i] as f32,
                channels[2][i] as f32,
            );
            crate::math::finite_or_zero(v)
        })
        .collect();
    Ok(Solution { image, iterations })
}

/// One channel's sanitised problem, f64.
struct Channel {
    w: usize,
    h: usize,
    p: Vec<f64>,
    alpha: Vec<f64>,
    /// Differences, 0 where the pair is invalid or outside the image.
    gx: Vec<f64>,
    gy: Vec<f64>,
    /// Pair validity as 1/0: the L2 solve's base pair weights.
    vx: Vec<f64>,
    vy: Vec<f64>,
}

fn clamp_weight(x: f64) -> f64 {
    if x.is_finite() {
        x.clamp(0.0, MAX_WEIGHT)
    } else if x > 0.0 {
        MAX_WEIGHT
    } else {
        0.0
    }
}

impl Channel {
    fn new(pr: &Problem, c: usize) -> Self {
        let (w, h) = (pr.width, pr.height);
        let n = w * h;
        let mut p = vec![0.0; n];
        let mut alpha = vec![0.0; n];
        let (mut gx, mut gy) = (vec![0.0; n], vec![0.0; n]);
        let (mut vx, mut vy) = (vec![0.0; n], vec![0.0; n]);
        for i in 0..n {
            let (x, y) = (i % w, i / w);
            let v = f64::from(pr.primal[i][c]);
            if v.is_finite() {
                p[i] = v;
                alpha[i] = clamp_weight(f64::from(pr.weight[i]));
            }
            let d = f64::from(pr.dx[i][c]);
            if x + 1 < w && pr.valid_x[i] && d.is_finite() {
                gx[i] = d;
                vx[i] = 1.0;
            }
            let d = f64::from(pr.dy[i][c]);
            if y + 1 < h && pr.valid_y[i] && d.is_finite() {
                gy[i] = d;
                vy[i] = 1.0;
            }
        }
        Self {
            w,
            h,
            p,
            alpha,
            gx,
            gy,
            vx,
            vy,
        }
    }

    /// The channel's solution and the CG iterations it took.
    fn solve(&self, s: &Settings) -> (Vec<f64>, usize) {
        let mut x = self.p.clone();
        let mut iterations = self.cg(&self.vx, &self.vy, &mut x, s);
        if s.norm == Norm::L2 {
            return (x, iterations);
        }
        let (rx, ry) = self.residuals(&x);
        let count = self.vx.iter().chain(&self.vy).sum::<f64>().max(1.0);
        let mean_r = rx.iter().chain(&ry).map(|r| r.abs()).sum::<f64>() / count;
        let scale = clamp_weight(s.l1_scale.unwrap_or(mean_r));
        let mean_p = self.p.iter().map(|v| v.abs()).sum::<f64>() / self.p.len().max(1) as f64;
        let eps = (s.epsilon * mean_p).max(1e-8);
        for _ in 0..s.irls_iterations {
            let (rx, ry) = self.residuals(&x);
            let reweight = |r: &[f64], v: &[f64]| -> Vec<f64> {
                r.iter()
                    .zip(v)
                    .map(|(r, v)| clamp_weight(v * scale / (2.0 * r.abs().max(eps))))
                    .collect()
            };
            let (wx, wy) = (reweight(&rx, &self.vx), reweight(&ry, &self.vy));
            let inner = Settings {
                max_iterations: s.irls_max_iterations,
                ..*s
            };
            iterations += self.cg(&wx, &wy, &mut x, &inner);
        }
        (x, iterations)
    }

    /// r_e = (x_q − x_p) − G_e (0 where the pair is invalid).
    fn residuals(&self, x: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let w = self.w;
        let n = x.len();
        let mut rx = vec![0.0; n];
        let mut ry = vec![0.0; n];
        for i in 0..n {
            if self.vx[i] > 0.0 {
                rx[i] = x[i + 1] - x[i] - self.gx[i];
            }
            if self.vy[i] > 0.0 {
                ry[i] = x[i + w] - x[i] - self.gy[i];
            }
        }
        (rx, ry)
    }

    /// (diag α + Dᵀ W D) x, W = diag(wx, wy); in bands of whole rows, so that
    /// no pixel needs a division to find its neighbours.
    fn apply(&self, wx: &[f64], wy: &[f64], x: &[f64], out: &mut [f64]) {
        let (w, h) = (self.w, self.h);
        if w == 0 {
            return;
        }
        let rows = (CHUNK / w).max(1);
        out.par_chunks_mut(rows * w)
            .enumerate()
            .for_each(|(k, band)| {
                for (r, o) in band.chunks_mut(w).enumerate() {
                    let y = k * rows + r;
                    let row = y * w;
                    for (px, o) in o.iter_mut().enumerate() {
                        let i = row + px;
                        let xi = x[i];
                        let mut v = self.alpha[i] * xi;
                        if px + 1 < w {
                            v += wx[i] * (xi - x[i + 1]);
                        }
                        if px > 0 {
                            v += wx[i - 1] * (xi - x[i - 1]);
                        }
                        if y + 1 < h {
                            v += wy[i] * (xi - x[i + w]);
                        }
                        if y > 0 {
                            v += wy[i - w] * (xi - x[i - w]);
                        }
                        *o = v;
                    }
                }
            });
    }

    /// Preconditioned CG on the normal equations with pair weights (wx, wy), from
    /// `x`; returns the iterations it ran.
    fn cg(&self, wx: &[f64], wy: &[f64], x: &mut [f64], s: &Settings) -> usize {
        let (w, n) = (self.w, x.len());
        // b = α P + Dᵀ W G, and the Jacobi diagonal.
        let mut b = vec![0.0; n];
        let mut diag = vec![0.0; n];
        for i in 0..n {
            b[i] += self.alpha[i] * self.p[i];
            diag[i] += self.alpha[i];
            if i % w + 1 < w {
                let f = wx[i] * self.gx[i];
                b[i] -= f;
                b[i + 1] += f;
                diag[i] += wx[i];
                diag[i + 1] += wx[i];
            }
            if i / w + 1 < self.h {
                let f = wy[i] * self.gy[i];
                b[i] -= f;
                b[i + w] += f;
                diag[i] += wy[i];
                diag[i + w] += wy[i];
            }
        }
        let inv: Vec<f64> = diag
            .iter()
            .map(|&d| if d > 0.0 { 1.0 / d } else { 0.0 })
            .collect();
        let mut ax = vec![0.0; n];
        self.apply(wx, wy, x, &mut ax);
        let mut r: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
        let mut z: Vec<f64> = r.iter().zip(&inv).map(|(r, m)| r * m).collect();
        let mut d = z.clone();
        let mut rz = dot(&r, &z);
        let bb: f64 = b.iter().zip(&inv).map(|(b, m)| b * b * m).sum();
        let stop = s.tolerance * s.tolerance * bb.max(1e-300);
        let mut q = ax;
        let mut iterations = 0;
        while iterations < s.max_iterations && rz > stop {
            self.apply(wx, wy, &d, &mut q);
            let dq = dot(&d, &q);
            if !(dq > 0.0 && dq.is_finite()) {
                break;
            }
            let a = rz / dq;
            let rz_new: f64 = x
                .par_chunks_mut(CHUNK)
                .zip(r.par_chunks_mut(CHUNK))
                .zip(z.par_chunks_mut(CHUNK))
                .enumerate()
                .map(|(k, ((x, r), z))| {
                    let o = k * CHUNK;
                    let mut sum = 0.0;
                    for j in 0..x.len() {
                        x[j] += a * d[o + j];
                        r[j] -= a * q[o + j];
                        z[j] = r[j] * inv[o + j];
                        sum += r[j] * z[j];
                    }
                    sum
                })
                .collect::<Vec<f64>>()
                .iter()
                .sum();
            let beta = rz_new / rz;
            rz = rz_new;
            d.par_chunks_mut(CHUNK)
                .zip(z.par_chunks(CHUNK))
                .for_each(|(d, z)| {
                    for (d, z) in d.iter_mut().zip(z) {
                        *d = z + beta * *d;
                    }
                });
            iterations += 1;
        }
        // A breakdown (only possible through overflow) keeps the primal.
        if x.iter().any(|v| !v.is_finite()) {
            x.copy_from_slice(&self.p);
        }
        iterations
    }
}

/// Pixels per parallel work item. Sums add the items' partial sums in item
/// order, so the result does not depend on the thread count.
const CHUNK: usize = 4096;

/// Σ a_i b_i, deterministic (see [`CHUNK`]).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.par_chunks(CHUNK)
        .zip(b.par_chunks(CHUNK))
        .map(|(a, b)| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>())
        .collect::<Vec<f64>>()
        .iter()
        .sum()
}

/// Trapezoid pixel-pair differences from per-pixel derivatives: the box-filtered
/// image's difference I(p+1) − I(p) is the integral of its derivative between the
/// two centres, which the mean of the end points' derivatives approximates to
/// second order. Returns (dx, dy) in [`Problem`]'s layout.
pub fn trapezoid_differences(
    width: usize,
    height: usize,
    grad_u: &[Vec3],
    grad_v: &[Vec3],
) -> (Vec<Vec3>, Vec<Vec3>) {
    let n = width * height;
    let mut dx = vec![Vec3::ZERO; n];
    let mut dy = vec![Vec3::ZERO; n];
    for i in 0..n.min(grad_u.len()).min(grad_v.len()) {
        if i % width + 1 < width {
            dx[i] = 0.5 * (grad_u[i] + grad_u[i + 1]);
        }
        if i / width + 1 < height && i + width < grad_v.len() {
            dy[i] = 0.5 * (grad_v[i] + grad_v[i + width]);
        }
    }
    (dx, dy)
}

/// The G-buffer a discontinuity test reads (the render's AOVs, per pixel).
#[derive(Clone, Copy, Debug)]
pub struct Guides<'a> {
    pub object_id: &'a [f32],
    pub depth: &'a [f32],
    pub normal: &'a [Vec3],
}

/// A neighbour's depth further than this fraction from a pixel's is a step. A
/// plane seen at incidence θ changes depth by ≈ δ tan θ per pixel (δ: a pixel's
/// angle, ≤ 0.02 rad at 64 pixels across a 70° view), so 0.1 passes planes up to
/// ≈ 79° at that size and ≈ 89° at 512 pixels, and flags occlusion steps.
pub const DEPTH_JUMP: f32 = 0.1;

/// Neighbouring mean normals further apart than this cosine (≈ 26°) straddle a
/// crease: a smooth surface turns that much between two pixel centres only near
/// its silhouette, where the pair is unreliable anyway.
pub const NORMAL_COS: f32 = 0.9;

/// Which pairs the point derivatives describe: a pair is dropped when its pixels
/// differ in object id, in depth by more than [`DEPTH_JUMP`] (relative) or in
/// normal by more than [`NORMAL_COS`]; and, since a pixel is a box and the
/// first sample's id a point, also every pair touching a pixel that has such a
/// pair (a pixel the edge runs through mixes both sides, which no point
/// derivative sees). Returns (valid_x, valid_y).
pub fn continuous_pairs(width: usize, height: usize, g: &Guides) -> (Vec<bool>, Vec<bool>) {
    let n = width * height;
    let ok = |a: usize, b: usize| -> bool {
        if g.object_id[a] != g.object_id[b] {
            return false;
        }
        let (da, db) = (g.depth[a], g.depth[b]);
        if !(da.is_finite() && db.is_finite()) {
            return false;
        }
        if (da - db).abs() > DEPTH_JUMP * da.abs().min(db.abs()) {
            return false;
        }
        let (na, nb) = (g.normal[a], g.normal[b]);
        // Background pixels (no normal) pair with each other.
        if na == Vec3::ZERO && nb == Vec3::ZERO {
            return true;
        }
        na.dot(nb) >= NORMAL_COS
    };
    let sizes_ok = g.object_id.len() == n && g.depth.len() == n && g.normal.len() == n;
    if !sizes_ok {
        return (vec![false; n], vec![false; n]);
    }
    let raw_x: Vec<bool> = (0..n)
        .map(|i| i % width + 1 < width && ok(i, i + 1))
        .collect();
    let raw_y: Vec<bool> = (0..n)
        .map(|i| i / width + 1 < height && ok(i, i + width))
        .collect();
    // A pixel is on an edge when any pair inside the image around it is broken.
    let on_edge: Vec<bool> = (0..n)
        .map(|i| {
            let (x, y) = (i % width, i / width);
            (x + 1 < width && !raw_x[i])
                || (x > 0 && !raw_x[i - 1])
                || (y + 1 < height && !raw_y[i])
                || (y > 0 && !raw_y[i - width])
        })
        .collect();
    let vx = (0..n)
        .map(|i| raw_x[i] && !on_edge[i] && !on_edge[i + 1])
        .collect();
    let vy = (0..n)
        .map(|i| raw_y[i] && !on_edge[i] && !on_edge[i + width])
        .collect();
    (vx, vy)
}

/// α from the primal's per-pixel variance of the mean σ²_p: 2β m / (σ²_p + m), m
/// the mean σ² over the image, at least β/1000: β for a pixel of typical noise
/// (β: its weight relative to one pair), up to 2β for a noiseless one — bounded,
/// so that a dark pixel whose few samples all missed the light (σ² = 0) is not
/// pinned to its zero.
pub fn primal_weights(variance: &[f32], beta: f32) -> Vec<f32> {
    let beta = if beta.is_finite() && beta > 0.0 {
        f64::from(beta)
    } else {
        0.0
    };
    let clean = |v: f32| {
        let v = f64::from(v);
        if v.is_finite() && v > 0.0 {
            v
        } else {
            0.0
        }
    };
    let m = variance.iter().map(|&v| clean(v)).sum::<f64>() / variance.len().max(1) as f64;
    variance
        .iter()
        .map(|&v| {
            let a = if m > 0.0 {
                2.0 * beta * m / (clean(v) + m)
            } else {
                beta
            };
            a.max(beta * 1e-3) as f32
        })
        .collect()
}

/// Pairs whose difference disagrees with the primal's own, |G_e − (P_q − P_p)| >
/// `k` √(σ²_p + σ²_q) in any channel (σ²: the primal's variance of the mean, at
/// least (1e-3 |P|)²), become invalid. A correct G passes with the probability of
/// a k-sigma event (k = 4: > 99.99 % for Gaussian noise, before G's own noise);
/// a biased one (a highlight narrower than the trapezoid rule resolves) fails once
/// the primal is precise enough to tell, so the solve tends to the primal as the
/// sample count grows instead of to the bias. Pixels without variance (one sample)
/// are not tested.
pub fn drop_inconsistent(
    width: usize,
    primal: &[Vec3],
    variance: &[Vec3],
    (dx, dy): (&[Vec3], &[Vec3]),
    (valid_x, valid_y): (&mut [bool], &mut [bool]),
    k: f32,
) {
    let n = primal.len();
    if variance.len() != n || dx.len() != n || dy.len() != n || width == 0 {
        return;
    }
    let agrees = |p: usize, q: usize, g: Vec3| -> bool {
        let (vp, vq) = (variance[p], variance[q]);
        if vp == Vec3::ZERO && vq == Vec3::ZERO {
            return true;
        }
        let floor = 1e-3 * primal[p].abs().max(primal[q].abs());
        let sigma = (vp + vq).max(floor * floor).max(Vec3::splat(1e-20)).sqrt();
        let off = (g - (primal[q] - primal[p])).abs();
        // NaN compares false: a non-finite pair fails.
        off.cmple(k * sigma).all()
    };
    for i in 0..n {
        if valid_x[i] && i % width + 1 < width && !agrees(i, i + 1, dx[i]) {
            valid_x[i] = false;
        }
        if valid_y[i] && i + width < n && !agrees(i, i + width, dy[i]) {
            valid_y[i] = false;
        }
    }
}
