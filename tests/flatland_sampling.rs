//! Flatland sampling demo (paper Sec. 9.2, Fig. 16–17): the bumpy receiver's
//! analytic gradient (Eq. 25) against central differences and brute force, exact
//! sample budgets, analytic- vs numerical-gradient adaptive sampling at equal
//! counts, the aliasing that defeats the numerical metric, the figure writer, and
//! bad input.

use gradtrace::flatland::sampling::{
    adaptive_samples, budget_table, coarse_count, reconstruct, rms_error, uniform_samples,
    write_sampling_figures, BumpyReceiver, Metric, PixelSample, Reconstruction, FIG16_BUDGET,
    FIG_BUDGETS, FIG_COARSE_STEP, FIG_PIXELS,
};
use gradtrace::flatland::Lighting;
use std::f64::consts::{FRAC_PI_2, PI};

const LIGHT: Lighting = Lighting {
    ambient: 0.1,
    peak: 1.0,
    sigma: 0.6,
};

/// Points that avoid any pixel grid.
fn points(n: usize, lo: f64, hi: f64) -> Vec<f64> {
    (0..n)
        .map(|i| lo + (hi - lo) * (i as f64 + 0.3712) / n as f64)
        .collect()
}

#[test]
fn bump_derivatives_and_gradient_match_central_differences() {
    let r = BumpyReceiver::paper_fig17();
    let h = 1e-6;
    let (mut worst_h1, mut worst_h2, mut worst_g, mut scale) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for x in points(400, 0.0, 1.0) {
        let [_, h1, h2] = r.height(x);
        let fd1 = (r.height(x + h)[0] - r.height(x - h)[0]) / (2.0 * h);
        let fd2 = (r.height(x + h)[1] - r.height(x - h)[1]) / (2.0 * h);
        worst_h1 = worst_h1.max((h1 - fd1).abs());
        worst_h2 = worst_h2.max((h2 - fd2).abs() / (1.0 + h2.abs()));
        let g = r.grad_analytic(x);
        let fd = r.grad_numerical(x, h).unwrap();
        worst_g = worst_g.max((g - fd).abs());
        scale = scale.max(g.abs());
    }
    println!(
        "max |h' - fd| {worst_h1:.2e}, max rel |h'' - fd| {worst_h2:.2e}, max |B_x - fd| {worst_g:.2e} (max |B_x| {scale:.2})"
    );
    assert!(worst_h1 < 1e-7, "h' vs central differences: {worst_h1}");
    assert!(worst_h2 < 1e-6, "h'' vs central differences: {worst_h2}");
    assert!(
        scale > 10.0,
        "the chirp should give steep shading, max |B_x| {scale}"
    );
    assert!(
        worst_g < 1e-6 * scale,
        "B_x (Eq. 25) vs central differences: {worst_g} of {scale}"
    );
}

#[test]
fn normal_derivative_matches_differences_and_shading_matches_brute_force() {
    let r = BumpyReceiver::paper_fig17();
    let l = r.lighting();
    let radiance = |w: f64| l.ambient + l.peak * (-0.5 * w * w / (l.sigma * l.sigma)).exp();
    for nu in [-1.2, -0.7, -0.31, -1e-3, 0.0, 2e-3, 0.25, 0.66, 1.3] {
        // ∂B/∂ν against central differences of B(ν), across ν = 0 where the clamp
        // switches from the left horizon to the right one.
        let h = 1e-6;
        let fd = (r.shading_at_normal(nu + h) - r.shading_at_normal(nu - h)) / (2.0 * h);
        let d = r.shading_normal_derivative(nu);
        assert!((d - fd).abs() < 1e-8, "nu {nu}: dB/dnu {d} vs fd {fd}");
        // B(ν) against a brute-force midpoint sum of L(ω) max(cos(ω − ν), 0) over the
        // upper half-plane: checks the clamped limits.
        let n = 200_000;
        let dw = PI / n as f64;
        let brute: f64 = (0..n)
            .map(|k| {
                let w = -FRAC_PI_2 + (k as f64 + 0.5) * dw;
                radiance(w) * (w - nu).cos().max(0.0) * dw
            })
            .sum();
        let b = r.shading_at_normal(nu);
        assert!((b - brute).abs() < 1e-8, "nu {nu}: B {b} vs brute {brute}");
    }
    // Symmetric lighting: B even in ν, so B(x) has twice the bump frequency.
    assert!((r.shading_at_normal(0.4) - r.shading_at_normal(-0.4)).abs() < 1e-14);
}

#[test]
fn equal_sample_counts_are_honoured_exactly() {
    let r = BumpyReceiver::paper_fig17();
    let xs = r.pixel_positions(1025).unwrap();
    let dx = xs[1] - xs[0];
    let step = 64;
    let coarse = coarse_count(1025, step);
    assert_eq!(coarse, 17);
    for metric in [Metric::Analytic, Metric::Numerical] {
        for budget in [coarse, coarse + 1, 40, 100, 333, 1025] {
            let mut calls = 0usize;
            let s = adaptive_samples(1025, dx, step, budget, metric, |i| {
                calls += 1;
                (r.shading(xs[i]), r.grad_analytic(xs[i]))
            })
            .unwrap();
            assert_eq!(s.len(), budget, "{metric:?} budget {budget}");
            assert_eq!(calls, budget, "{metric:?}: one evaluation per sample");
            assert!(s.windows(2).all(|w| w[0].index < w[1].index));
            assert!((0..1025)
                .step_by(step)
                .all(|i| s.iter().any(|p| p.index == i)));
            assert_eq!(s.last().map(|p| p.index), Some(1024));
        }
        // Over budget (more than one sample per pixel) or under the coarse start.
        assert!(adaptive_samples(1025, dx, step, 1026, metric, |_| (0.0, 0.0)).is_err());
        assert!(adaptive_samples(1025, dx, step, coarse - 1, metric, |_| (0.0, 0.0)).is_err());
    }
    for n in [2, 17, 100, 1025] {
        let mut calls = 0usize;
        let s = uniform_samples(1025, n, |_| {
            calls += 1;
            (0.0, 0.0)
        })
        .unwrap();
        assert_eq!((s.len(), calls), (n, n));
    }
}

#[test]
fn analytic_adaptive_sampling_beats_numerical_at_every_budget() {
    let r = BumpyReceiver::paper_fig17();
    let rows = budget_table(&r, FIG_PIXELS, FIG_COARSE_STEP, &FIG_BUDGETS).unwrap();
    println!("RMS error of the reconstructed image ({FIG_PIXELS} pixels, coarse start every {FIG_COARSE_STEP} px)");
    println!("samples  uniform    numerical  analytic   analytic+Hermite");
    for row in &rows {
        println!(
            "{:7}  {:.3e}  {:.3e}  {:.3e}  {:.3e}   (analytic/numerical {:.2})",
            row.samples,
            row.uniform_linear,
            row.numerical_linear,
            row.analytic_linear,
            row.analytic_hermite,
            row.analytic_linear / row.numerical_linear
        );
    }
    for row in &rows {
        assert!(
            row.analytic_linear < row.numerical_linear,
            "{} samples: analytic {} vs numerical {}",
            row.samples,
            row.analytic_linear,
            row.numerical_linear
        );
        // Gradients also improve the reconstruction from the same samples.
        assert!(row.analytic_hermite < row.analytic_linear, "{row:?}");
    }
    // Once the budget resolves the high-frequency end the gap is large: numerical
    // sampling keeps its aliased coarse estimate there.
    let last = rows.last().unwrap();
    assert!(
        last.analytic_linear < 0.5 * last.numerical_linear,
        "{last:?}"
    );
}

/// Fig. 16's point in isolation: constant-frequency bumps sampled once per period at
/// the same phase. Neighbouring samples are equal, so the numerical difference is 0
/// while the analytic gradient is at its largest; numerical adaptive sampling sees
/// a flat image and refines nothing useful, the analytic one refines every period.
#[test]
fn aliasing_hides_bumps_from_numerical_but_not_analytic_gradients() {
    let f = 8.0;
    let r = BumpyReceiver::new(LIGHT, 0.8, f, f, (0.0, 1.0)).unwrap();
    let period = 1.0 / f;
    // The phase of steepest shading within one period.
    let x_star = (0..2000)
        .map(|i| i as f64 * period / 2000.0)
        .max_by(|a, b| {
            r.grad_analytic(*a)
                .abs()
                .total_cmp(&r.grad_analytic(*b).abs())
        })
        .unwrap();
    let g_star = r.grad_analytic(x_star).abs();
    let mut worst_diff = 0.0f64;
    for j in 0..7 {
        let (a, b) = (x_star + j as f64 * period, x_star + (j + 1) as f64 * period);
        let quotient = (r.shading(b) - r.shading(a)) / period;
        worst_diff = worst_diff.max(quotient.abs());
        assert!((r.grad_analytic(b).abs() - g_star).abs() < 1e-9 * g_star);
    }
    println!(
        "coarse samples one period apart at x* = {x_star:.5}: max |dB|/dx {worst_diff:.2e}, analytic |B_x| {g_star:.3}"
    );
    assert!(g_star > 5.0, "{g_star}");
    assert!(worst_diff < 1e-9 * g_star, "{worst_diff}");

    // Adaptive sampling of 7 periods starting at x*, coarse step = one period.
    let per = 128usize;
    let pixels = 7 * per + 1;
    let dx = period / per as f64;
    let xs: Vec<f64> = (0..pixels).map(|i| x_star + i as f64 * dx).collect();
    let exact: Vec<f64> = xs.iter().map(|&x| r.shading(x)).collect();
    let eval = |i: usize| (r.shading(xs[i]), r.grad_analytic(xs[i]));
    let budget = 7 * 8 + 1;
    let err = |m: Metric| {
        let s: Vec<PixelSample> = adaptive_samples(pixels, dx, per, budget, m, eval).unwrap();
        let rec = reconstruct(&xs, &s, Reconstruction::Linear).unwrap();
        // Samples per period: how evenly each method spread the budget.
        let counts: Vec<usize> = (0..7)
            .map(|p| s.iter().filter(|q| q.index / per == p).count())
            .collect();
        (rms_error(&rec, &exact), counts)
    };
    let (ea, ca) = err(Metric::Analytic);
    let (en, cn) = err(Metric::Numerical);
    println!("{budget} samples: analytic RMS {ea:.3e} {ca:?}, numerical RMS {en:.3e} {cn:?}");
    assert!(ea < 0.5 * en, "analytic {ea} vs numerical {en}");
    // The analytic metric spreads the samples evenly over the identical periods.
    assert!(ca.iter().all(|&c| c == ca[0]), "{ca:?}");
}

/// The analytic metric's own blind spot (the paper's "usually accurate"): samples
/// one period apart at a crest of the bumps, where the normal is vertical and the
/// symmetric lighting makes `∂B/∂ν = 0`, see a zero gradient *and* zero differences.
#[test]
fn analytic_metric_is_blind_where_samples_sit_at_gradient_zeros() {
    let f = 8.0;
    let r = BumpyReceiver::new(LIGHT, 0.8, f, f, (0.0, 1.0)).unwrap();
    let period = 1.0 / f;
    let crest = 0.25 * period;
    assert!(r.normal_angle(crest).abs() < 1e-12);
    let steepest = (0..2000)
        .map(|i| r.grad_analytic(i as f64 * period / 2000.0).abs())
        .fold(0.0, f64::max);
    for j in 0..7 {
        let (a, b) = (crest + j as f64 * period, crest + (j + 1) as f64 * period);
        assert!(r.grad_analytic(a).abs() < 1e-9 * steepest);
        assert!((r.shading(b) - r.shading(a)).abs() / period < 1e-9 * steepest);
    }
    // Half-way (the trough) is a zero of B_x too, so one split does not reveal it.
    assert!(r.grad_analytic(crest + 0.5 * period).abs() < 1e-9 * steepest);
}

#[test]
fn figure_writer_produces_finite_csv_and_svg() {
    let dir = std::env::temp_dir().join(format!("gradtrace-fsample-{}", std::process::id()));
    let summary = write_sampling_figures(&dir).unwrap();
    assert_eq!(summary.files.len(), 5);
    assert_eq!(summary.rows.len(), FIG_BUDGETS.len());
    let csv = |name: &str| -> Vec<Vec<f64>> {
        let text = std::fs::read_to_string(dir.join(name)).unwrap();
        text.lines()
            .skip(1)
            .map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()).collect())
            .collect()
    };
    let fig16 = csv("fig16_signal_samples.csv");
    assert_eq!(fig16.len(), FIG_PIXELS);
    assert!(fig16.iter().flatten().all(|v| v.is_finite()));
    assert!(fig16.iter().all(|r| r.len() == 9));
    let count = |c: usize| fig16.iter().map(|r| r[c]).sum::<f64>() as usize;
    assert_eq!((count(7), count(8)), (FIG16_BUDGET, FIG16_BUDGET));
    let fig17 = csv("fig17_error_vs_samples.csv");
    assert_eq!(fig17.len(), FIG_BUDGETS.len());
    assert!(fig17.iter().flatten().all(|v| v.is_finite() && *v > 0.0));
    for name in ["fig16_signal_samples.svg", "fig17_error_vs_samples.svg"] {
        let svg = std::fs::read_to_string(dir.join(name)).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("<polyline"));
        let lower = svg.to_lowercase();
        assert!(!lower.contains("nan") && !lower.contains("inf"), "{name}");
    }
    println!(
        "{}",
        std::fs::read_to_string(dir.join("sampling_summary.txt")).unwrap()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    assert!(BumpyReceiver::new(LIGHT, 0.8, 0.0, 4.0, (0.0, 1.0)).is_err());
    assert!(BumpyReceiver::new(LIGHT, f64::NAN, 2.0, 4.0, (0.0, 1.0)).is_err());
    assert!(BumpyReceiver::new(LIGHT, 0.8, 2.0, 4.0, (1.0, 1.0)).is_err());
    let dark = Lighting {
        sigma: 0.0,
        ..LIGHT
    };
    assert!(BumpyReceiver::new(dark, 0.8, 2.0, 4.0, (0.0, 1.0)).is_err());
    let r = BumpyReceiver::paper_fig17();
    assert!(r.grad_numerical(0.5, 0.0).is_err());
    assert!(r.pixel_positions(1).is_err());
    assert!(adaptive_samples(1, 1.0, 1, 1, Metric::Analytic, |_| (0.0, 0.0)).is_err());
    assert!(adaptive_samples(10, 1.0, 0, 5, Metric::Analytic, |_| (0.0, 0.0)).is_err());
    assert!(adaptive_samples(10, f64::NAN, 2, 6, Metric::Analytic, |_| (0.0, 0.0)).is_err());
    // Non-finite evaluations do not break the refinement or the budget.
    let s = adaptive_samples(100, 0.01, 10, 40, Metric::Analytic, |i| {
        if i % 3 == 0 {
            (f64::NAN, f64::INFINITY)
        } else {
            (1.0, i as f64)
        }
    })
    .unwrap();
    assert_eq!(s.len(), 40);
    let xs = [0.0, 1.0, 2.0];
    let p = |index| PixelSample {
        index,
        value: 0.0,
        gradient: 0.0,
    };
    assert!(reconstruct(&xs, &[p(2), p(0)], Reconstruction::Linear).is_err());
    assert!(reconstruct(&xs, &[p(0), p(3)], Reconstruction::Linear).is_err());
    assert!(reconstruct(&xs, &[], Reconstruction::Linear).is_err());
    assert!(uniform_samples(10, 11, |_| (0.0, 0.0)).is_err());
}
