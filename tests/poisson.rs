//! The gradient-domain reconstruction (`reconstruct::poisson`, `render
//! --reconstruct`): known answers on analytic images, an exact dense reference for
//! L2 and a dual certificate for L1 on a small image, masked step edges,
//! adversarial inputs, determinism over thread counts, and a render end to end.

mod common;

use common::Rng;
use glam::Vec3A as Vec3;
use gradtrace::reconstruct::poisson::{solve, trapezoid_differences, Norm, Problem, Settings};
use std::process::Command;

/// An owned problem (the solver borrows its planes).
#[derive(Clone)]
struct Owned {
    w: usize,
    h: usize,
    primal: Vec<Vec3>,
    weight: Vec<f32>,
    dx: Vec<Vec3>,
    dy: Vec<Vec3>,
    vx: Vec<bool>,
    vy: Vec<bool>,
}

impl Owned {
    fn problem(&self) -> Problem<'_> {
        Problem {
            width: self.w,
            height: self.h,
            primal: &self.primal,
            weight: &self.weight,
            dx: &self.dx,
            dy: &self.dy,
            valid_x: &self.vx,
            valid_y: &self.vy,
        }
    }

    /// Exact differences of `img`, every pair valid (the last column/row unused).
    fn exact(w: usize, h: usize, img: &[Vec3], primal: Vec<Vec3>, alpha: f32) -> Self {
        let n = w * h;
        let mut dx = vec![Vec3::ZERO; n];
        let mut dy = vec![Vec3::ZERO; n];
        for i in 0..n {
            if i % w + 1 < w {
                dx[i] = img[i + 1] - img[i];
            }
            if i / w + 1 < h {
                dy[i] = img[i + w] - img[i];
            }
        }
        Self {
            w,
            h,
            primal,
            weight: vec![alpha; n],
            dx,
            dy,
            vx: vec![true; n],
            vy: vec![true; n],
        }
    }
}

fn tight(norm: Norm) -> Settings {
    Settings {
        tolerance: 1e-12,
        max_iterations: 20_000,
        irls_max_iterations: 20_000,
        ..Settings::new(norm)
    }
}

/// A smooth analytic image, different per channel.
fn smooth(w: usize, h: usize) -> Vec<Vec3> {
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
            Vec3::new(
                0.5 + 0.4 * (3.0 * x).sin() * (2.0 * y).cos(),
                0.3 + 0.2 * x + 0.3 * y * y,
                1.0 + 0.5 * (5.0 * x + y).cos(),
            )
        })
        .collect()
}

/// Gaussian noise by Box–Muller from the tests' independent stream.
fn gauss(rng: &mut Rng) -> f32 {
    let (u1, u2) = (rng.next_f64().max(1e-300), rng.next_f64());
    ((-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()) as f32
}

fn noisy(img: &[Vec3], sigma: f32, rng: &mut Rng) -> Vec<Vec3> {
    img.iter()
        .map(|v| *v + sigma * Vec3::new(gauss(rng), gauss(rng), gauss(rng)))
        .collect()
}

fn rmse(a: &[Vec3], b: &[Vec3]) -> f64 {
    let s: f64 = a
        .iter()
        .zip(b)
        .map(|(a, b)| f64::from((*a - *b).length_squared()))
        .sum();
    (s / (3 * a.len()) as f64).sqrt()
}

fn mean(v: &[Vec3]) -> Vec3 {
    v.iter().copied().sum::<Vec3>() / v.len() as f32
}

/// (a) With exact differences and α → 0 the solve is the image up to the constant
/// the primal fixes (its mean offset); with noisy differences and primal it beats
/// the primal alone.
#[test]
fn l2_recovers_a_smooth_image_from_its_differences() {
    let (w, h) = (32, 24);
    let img = smooth(w, h);
    let mut rng = Rng::new(1);
    let primal = noisy(&img, 0.1, &mut rng);
    let p = Owned::exact(w, h, &img, primal.clone(), 1e-6);
    let out = solve(&p.problem(), &tight(Norm::L2)).unwrap().image;
    let offset = mean(&primal) - mean(&img);
    let err = out
        .iter()
        .zip(&img)
        .map(|(o, i)| (*o - *i - offset).abs().max_element())
        .fold(0.0f32, f32::max);
    assert!(err < 1e-3, "max error {err} after removing the mean offset");

    // Noisy differences (σ 0.02) and primal (σ 0.1): α = 0.05 trusts the pairs,
    // and the result must be at least 3× closer than the primal (measured: 6.0×).
    let mut q = p.clone();
    q.weight = vec![0.05; w * h];
    for d in q.dx.iter_mut().chain(q.dy.iter_mut()) {
        *d += 0.02 * Vec3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng));
    }
    let out = solve(&q.problem(), &Settings::new(Norm::L2)).unwrap().image;
    let (before, after) = (rmse(&primal, &img), rmse(&out, &img));
    println!("noisy pairs: primal RMSE {before:.4}, L2 {after:.4}");
    assert!(
        before > 3.0 * after,
        "primal RMSE {before:.4}, reconstruction {after:.4}"
    );
}

/// (b) A step the differences do not see (the point derivative is zero across it)
/// survives when its pairs are masked, and is smeared when they are not (the
/// control: the mask is what keeps it).
#[test]
fn a_masked_step_edge_is_not_smeared() {
    let (w, h) = (32, 16);
    let smooth_part = smooth(w, h);
    let step = |i: usize| if i % w >= 16 { 1.0 } else { 0.0 };
    let img: Vec<Vec3> = (0..w * h)
        .map(|i| smooth_part[i] + Vec3::splat(step(i)))
        .collect();
    let mut rng = Rng::new(2);
    let primal = noisy(&img, 0.05, &mut rng);
    // The differences of the smooth part only: what point derivatives report.
    let mut p = Owned::exact(w, h, &smooth_part, primal, 0.05);
    let jump = |out: &[Vec3]| -> f32 {
        (0..h)
            .map(|y| (out[y * w + 16] - out[y * w + 15]).x)
            .sum::<f32>()
            / h as f32
    };
    let unmasked = solve(&p.problem(), &tight(Norm::L2)).unwrap().image;
    for y in 0..h {
        p.vx[y * w + 15] = false;
    }
    for norm in [Norm::L2, Norm::L1] {
        let out = solve(&p.problem(), &tight(norm)).unwrap().image;
        let j = jump(&out);
        let true_jump = jump(&img);
        assert!(
            (j - true_jump).abs() < 0.1,
            "{norm:?}: jump {j}, expected {true_jump}"
        );
        // Beside the edge the levels hold: columns 14 and 17 within 0.1.
        for c in [14, 17] {
            let e = (0..h)
                .map(|y| (out[y * w + c] - img[y * w + c]).x.abs())
                .fold(0.0f32, f32::max);
            assert!(e < 0.1, "{norm:?}: column {c} off by {e}");
        }
    }
    let j = jump(&unmasked);
    assert!(
        j < 0.5,
        "control: unmasked, the zero differences should flatten the step (jump {j})"
    );
}

/// A random small problem: random primal, weights in [0.05, 1], differences, and
/// about one pair in five invalid.
fn random_problem(w: usize, h: usize, seed: u64) -> Owned {
    let mut rng = Rng::new(seed);
    let n = w * h;
    let v = |rng: &mut Rng| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    Owned {
        w,
        h,
        primal: (0..n).map(|_| v(&mut rng)).collect(),
        weight: (0..n).map(|_| 0.05 + 0.95 * rng.next_f32()).collect(),
        dx: (0..n).map(|_| v(&mut rng) - Vec3::splat(0.5)).collect(),
        dy: (0..n).map(|_| v(&mut rng) - Vec3::splat(0.5)).collect(),
        vx: (0..n)
            .map(|i| i % w + 1 < w && rng.next_f32() > 0.2)
            .collect(),
        vy: (0..n)
            .map(|i| i / w + 1 < h && rng.next_f32() > 0.2)
            .collect(),
    }
}

/// The valid pairs (p, q, G_e) of channel `c`.
fn edges(p: &Owned, c: usize) -> Vec<(usize, usize, f64)> {
    let mut e = Vec::new();
    for i in 0..p.w * p.h {
        if p.vx[i] {
            e.push((i, i + 1, f64::from(p.dx[i][c])));
        }
        if p.vy[i] {
            e.push((i, i + p.w, f64::from(p.dy[i][c])));
        }
    }
    e
}

/// Dense least squares: (diag α + Σ_e d_e d_eᵀ) x = α P + Σ_e d_e G_e, by Gaussian
/// elimination with partial pivoting (indices, as the textbook writes it).
#[allow(clippy::needless_range_loop)]
fn dense_l2(p: &Owned, c: usize) -> Vec<f64> {
    let n = p.w * p.h;
    let mut a = vec![vec![0.0f64; n + 1]; n];
    for i in 0..n {
        let al = f64::from(p.weight[i]);
        a[i][i] += al;
        a[i][n] += al * f64::from(p.primal[i][c]);
    }
    for (i, j, g) in edges(p, c) {
        a[i][i] += 1.0;
        a[j][j] += 1.0;
        a[i][j] -= 1.0;
        a[j][i] -= 1.0;
        a[i][n] -= g;
        a[j][n] += g;
    }
    for k in 0..n {
        let piv = (k..n)
            .max_by(|&x, &y| a[x][k].abs().total_cmp(&a[y][k].abs()))
            .unwrap();
        a.swap(k, piv);
        for r in k + 1..n {
            let f = a[r][k] / a[k][k];
            for col in k..=n {
                a[r][col] -= f * a[k][col];
            }
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|j| a[k][j] * x[j]).sum();
        x[k] = (a[k][n] - s) / a[k][k];
    }
    x
}

/// E_1(x) = Σ α (x − P)² + s Σ |x_q − x_p − G|.
fn l1_objective(p: &Owned, c: usize, s: f64, x: &[f64]) -> f64 {
    let data: f64 = (0..x.len())
        .map(|i| f64::from(p.weight[i]) * (x[i] - f64::from(p.primal[i][c])).powi(2))
        .sum();
    data + s * edges(p, c)
        .iter()
        .map(|&(i, j, g)| (x[j] - x[i] - g).abs())
        .sum::<f64>()
}

/// The L1 problem's dual, maximised by projected gradient ascent: with
/// s|t| = max_{|λ| ≤ s} λt, the inner minimum over x is at x = P − Dᵀλ / (2α), and
/// g(λ) = λᵀ(DP − G) − ¼ Σ (Dᵀλ)²/α is a smooth concave function on a box. Returns
/// (x(λ), g(λ)); weak duality makes g a lower bound of E_1 at every x.
fn dual_l1(p: &Owned, c: usize, s: f64) -> (Vec<f64>, f64) {
    let n = p.w * p.h;
    let e = edges(p, c);
    let al: Vec<f64> = p.weight.iter().map(|&a| f64::from(a)).collect();
    let pr: Vec<f64> = p.primal.iter().map(|v| f64::from(v[c])).collect();
    let mut lam = vec![0.0f64; e.len()];
    let x_of = |lam: &[f64]| -> Vec<f64> {
        let mut dtl = vec![0.0; n];
        for (k, &(i, j, _)) in e.iter().enumerate() {
            dtl[j] += lam[k];
            dtl[i] -= lam[k];
        }
        (0..n).map(|i| pr[i] - dtl[i] / (2.0 * al[i])).collect()
    };
    // ∇g(λ)_e = (D x(λ) − G)_e; its Lipschitz constant is ≤ ‖D‖² / (2 min α) ≤ 8 / (2 min α).
    let min_a = al.iter().cloned().fold(f64::INFINITY, f64::min);
    let step = 2.0 * min_a / 8.0;
    for _ in 0..200_000 {
        let x = x_of(&lam);
        for (k, &(i, j, g)) in e.iter().enumerate() {
            lam[k] = (lam[k] + step * (x[j] - x[i] - g)).clamp(-s, s);
        }
    }
    let x = x_of(&lam);
    let g: f64 = (0..n).map(|i| al[i] * (x[i] - pr[i]).powi(2)).sum::<f64>()
        + e.iter()
            .zip(&lam)
            .map(|(&(i, j, g), l)| l * (x[j] - x[i] - g))
            .sum::<f64>();
    (x, g)
}

/// (c) On a 6×5 image: L2 equals the dense least-squares solution; L1 (IRLS with
/// a tiny ε) reaches the optimum certified by the dual — its objective within
/// 2e-5 of the dual's lower bound (and so, by strong convexity, within 0.005 of
/// the optimum in the α-weighted norm).
#[test]
fn small_problem_matches_exact_references() {
    let p = random_problem(6, 5, 3);
    let l2 = solve(&p.problem(), &tight(Norm::L2)).unwrap().image;
    let s = 0.7;
    let settings = Settings {
        irls_iterations: 300,
        epsilon: 1e-9,
        l1_scale: Some(s),
        ..tight(Norm::L1)
    };
    let l1 = solve(&p.problem(), &settings).unwrap().image;
    for c in 0..3 {
        let exact = dense_l2(&p, c);
        for (i, e) in exact.iter().enumerate() {
            let d = (f64::from(l2[i][c]) - e).abs();
            assert!(d < 1e-5, "L2 channel {c} pixel {i}: {} vs {e}", l2[i][c]);
        }
        let x: Vec<f64> = l1.iter().map(|v| f64::from(v[c])).collect();
        let (xd, lower) = dual_l1(&p, c, s);
        let e_irls = l1_objective(&p, c, s, &x);
        let e_dual = l1_objective(&p, c, s, &xd);
        assert!(
            e_dual - lower < 1e-6,
            "channel {c}: the dual did not converge (gap {})",
            e_dual - lower
        );
        assert!(
            e_irls - lower < 2e-5,
            "channel {c}: IRLS objective {e_irls} above the dual bound {lower}"
        );
        // E_1 is 1-strongly convex in the α-norm (Σ α d²), so each point lies within
        // √(its gap) of the optimum in that norm.
        let d = x
            .iter()
            .zip(&xd)
            .zip(&p.weight)
            .map(|((a, b), w)| f64::from(*w) * (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        let bound = (e_irls - lower).max(0.0).sqrt() + (e_dual - lower).max(0.0).sqrt();
        println!(
            "channel {c}: IRLS gap {:.2e}, dual gap {:.2e}, α-distance {d:.2e} ≤ {bound:.2e}",
            e_irls - lower,
            e_dual - lower
        );
        assert!(
            d <= bound + 1e-6,
            "channel {c}: IRLS and dual optima {d} apart"
        );
        // The L2 solution is not the L1 one: the check can tell them apart.
        let x2: Vec<f64> = l2.iter().map(|v| f64::from(v[c])).collect();
        assert!(l1_objective(&p, c, s, &x2) > e_irls + 1e-3);
    }
}

/// (d) Zero weights, non-finite primal and differences, huge values, a 1×1 and an
/// empty image: finite output; mismatched planes are an error, not a panic.
#[test]
fn adversarial_inputs_give_finite_images() {
    let check = |p: &Owned, what: &str| {
        for norm in [Norm::L2, Norm::L1] {
            let out = solve(&p.problem(), &Settings::new(norm)).unwrap().image;
            assert_eq!(out.len(), p.w * p.h);
            assert!(
                out.iter().all(|v| v.is_finite()),
                "{what} {norm:?}: {out:?}"
            );
        }
    };
    let mut p = random_problem(7, 6, 4);
    p.weight = vec![0.0; 42];
    check(&p, "zero weights");
    p.vx = vec![false; 42];
    p.vy = vec![false; 42];
    check(&p, "zero weights, no pairs");
    let mut p = random_problem(7, 6, 5);
    p.primal[3] = Vec3::splat(f32::NAN);
    p.primal[9] = Vec3::splat(f32::INFINITY);
    p.dx[5] = Vec3::splat(f32::INFINITY);
    p.dy[8] = Vec3::new(f32::NAN, f32::NEG_INFINITY, 1.0);
    p.weight[10] = f32::INFINITY;
    p.weight[11] = f32::NAN;
    p.weight[12] = -3.0;
    p.dx[20] = Vec3::splat(1e30);
    p.primal[21] = Vec3::splat(-1e30);
    check(&p, "non-finite and huge entries");
    let one = Owned::exact(1, 1, &[Vec3::ONE], vec![Vec3::splat(0.25)], 0.0);
    check(&one, "1x1");
    let out = solve(&one.problem(), &Settings::new(Norm::L1))
        .unwrap()
        .image;
    assert_eq!(
        out,
        vec![Vec3::splat(0.25)],
        "a lone pixel keeps its primal"
    );
    let empty = Owned::exact(0, 0, &[], vec![], 1.0);
    check(&empty, "0x0");
    let mut bad = random_problem(4, 4, 6);
    bad.dy.pop();
    let err = solve(&bad.problem(), &Settings::new(Norm::L2)).unwrap_err();
    assert!(err.contains("dy"), "{err}");
    // The trapezoid rule's planes are finite where its inputs are.
    let (dx, dy) = trapezoid_differences(1, 1, &[Vec3::ONE], &[Vec3::ONE]);
    assert_eq!((dx, dy), (vec![Vec3::ZERO], vec![Vec3::ZERO]));
}

/// (e) The same bits for 1, 2 and 7 worker threads, on an image larger than one
/// parallel chunk.
#[test]
fn deterministic_for_any_thread_count() {
    let p = random_problem(97, 61, 7);
    for norm in [Norm::L2, Norm::L1] {
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| solve(&p.problem(), &Settings::new(norm)).unwrap())
        };
        let first = run(1);
        for t in [2, 7] {
            let other = run(t);
            assert_eq!(first.iterations, other.iterations, "{norm:?}, {t} threads");
            let same = first
                .image
                .iter()
                .zip(&other.image)
                .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits));
            assert!(same, "{norm:?}: {t} threads changed the image");
        }
    }
}

const BIN: &str = env!("CARGO_BIN_EXE_gradtrace");

fn render(args: &[&str], out: &std::path::Path) -> gradtrace::output::OutputImage {
    let status = Command::new(BIN)
        .args([
            "render",
            "scenes/bunny_env.toml",
            "--width",
            "48",
            "--height",
            "48",
            "-q",
        ])
        .args(args)
        .arg("--out")
        .arg(out)
        .status()
        .unwrap();
    assert!(status.success(), "{args:?}");
    gradtrace::output::read_exr(out).unwrap()
}

/// (f) `render --reconstruct` on the bunny at 48×48, 8 spp: R,G,B closer to a
/// 256-spp render than the primal it keeps as `noisy.R/G/B`, by at least 1.2×
/// (measured: L1 1.32×, L2 1.31×).
#[test]
fn render_reconstruct_beats_the_primal() {
    let dir = std::env::temp_dir().join(format!("gradtrace-poisson-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let rgb = ["R", "G", "B"];
    let reference = render(&["--spp", "256"], &dir.join("ref.exr"))
        .vec3("", rgb)
        .unwrap();
    for kind in ["poisson-l1", "poisson-l2"] {
        let img = render(
            &["--spp", "8", "--vis-samples", "4", "--reconstruct", kind],
            &dir.join(format!("{kind}.exr")),
        );
        let rec = img.vec3("", rgb).unwrap();
        let primal = img.vec3("noisy.", rgb).unwrap();
        let (before, after) = (rmse(&primal, &reference), rmse(&rec, &reference));
        println!("{kind}: primal RMSE {before:.5}, reconstruction {after:.5}");
        assert!(
            before > 1.2 * after,
            "{kind}: primal RMSE {before:.5}, reconstruction {after:.5}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}
