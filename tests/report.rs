//! Comparison report: metric known answers (RMSE, relMSE and its trimmed form,
//! FLIP, the 95 % interval), the colour map, and `write_report`'s files (HTML with
//! a headline and linked assets, `report.json` in its documented schema, two
//! Markdown tables per budget, sample maps, error bars, equal-time marks, per-budget
//! error scales) and its all-or-nothing behaviour.

use gradtrace::math::{Vec2, Vec3};
use gradtrace::output::colormap::viridis;
use gradtrace::output::metrics::{
    flip, flip_exposure, relmse, relmse_trimmed, rmse, tone_map_srgb8, RELMSE_EPS, TRIM_FRACTION,
};
use gradtrace::output::report::{
    compute_rows, markdown_table, mean_ci95, write_report, EqualCost, ReferenceInfo, ReportInput,
    ReportRow, Run, RunKind, ASSET_DIR,
};
use std::path::{Path, PathBuf};

mod common;
use common::Rng;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gradtrace-report-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// A textured test image in [0.05, 0.95]: sines of two frequencies plus a hard edge,
/// so that both FLIP's colour and feature pipelines see structure.
fn texture(w: usize, h: usize) -> Vec<Vec3> {
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            let a = 0.5 + 0.3 * (0.4 * x).sin() * (0.3 * y).cos();
            let edge = if x > w as f32 * 0.6 { 0.15 } else { 0.0 };
            Vec3::new(a, (a * 0.8 + edge).min(0.95), (1.0 - a).max(0.05))
        })
        .collect()
}

/// Deterministic zero-mean noise in [-amp, amp] (the shared test generator).
fn add_noise(img: &[Vec3], amp: f32, seed: u64) -> Vec<Vec3> {
    let mut rng = Rng::new(seed);
    let mut next = || rng.next_f32() * 2.0 - 1.0;
    img.iter()
        .map(|p| *p + Vec3::new(next(), next(), next()) * amp)
        .collect()
}

fn box_blur(img: &[Vec3], w: usize, h: usize, r: i64) -> Vec<Vec3> {
    let mut out = vec![Vec3::ZERO; w * h];
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let mut sum = Vec3::ZERO;
            let mut n = 0.0;
            for dy in -r..=r {
                for dx in -r..=r {
                    let (xx, yy) = (
                        (x + dx).clamp(0, w as i64 - 1),
                        (y + dy).clamp(0, h as i64 - 1),
                    );
                    sum += img[(yy * w as i64 + xx) as usize];
                    n += 1.0;
                }
            }
            out[(y * w as i64 + x) as usize] = sum / n;
        }
    }
    out
}

#[test]
fn identical_images_have_zero_error() {
    let (w, h) = (40, 30);
    let r = texture(w, h);
    assert_eq!(rmse(&r, &r).unwrap(), 0.0);
    assert_eq!(relmse(&r, &r).unwrap(), 0.0);
    assert_eq!(flip(&r, &r, w, h).unwrap(), 0.0);
}

#[test]
fn constant_offset_gives_exact_rmse() {
    let r = texture(16, 16);
    for c in [0.01_f32, 0.125, 2.0] {
        let x: Vec<Vec3> = r.iter().map(|p| *p + Vec3::splat(c)).collect();
        let e = rmse(&x, &r).unwrap();
        println!("offset {c}: RMSE {e}");
        assert!((e - c).abs() <= 1e-5 * c.max(1.0), "offset {c}: RMSE {e}");
    }
    // Offset on one channel only: RMSE = c / sqrt(3) (the mean runs over channels).
    let x: Vec<Vec3> = r.iter().map(|p| *p + Vec3::new(0.3, 0.0, 0.0)).collect();
    assert!((rmse(&x, &r).unwrap() - 0.3 / 3f32.sqrt()).abs() < 1e-6);
}

#[test]
fn relmse_follows_its_formula() {
    let r = vec![Vec3::new(1.0, 0.0, 0.5), Vec3::new(2.0, 0.25, 0.0)];
    let x = vec![Vec3::new(1.5, 0.1, 0.5), Vec3::new(1.0, 0.25, 0.3)];
    let eps = f64::from(RELMSE_EPS);
    assert_eq!(RELMSE_EPS, 1e-2);
    let terms = [
        0.25 / (1.0 + eps),
        0.01 / (0.0 + eps),
        0.0,
        1.0 / (4.0 + eps),
        0.0,
        0.09 / (0.0 + eps),
    ];
    let expected = terms.iter().sum::<f64>() / 6.0;
    let got = f64::from(relmse(&x, &r).unwrap());
    println!("relMSE {got} expected {expected}");
    assert!(
        (got - expected).abs() < 1e-6 * expected,
        "{got} vs {expected}"
    );
    // Relative: scaling image and reference together leaves it (nearly) unchanged
    // where r² ≫ ε.
    let big = |v: &[Vec3]| {
        v.iter()
            .map(|p| *p * 100.0 + Vec3::splat(50.0))
            .collect::<Vec<_>>()
    };
    let a = relmse(&big(&x), &big(&r)).unwrap();
    let x2: Vec<Vec3> = big(&x).iter().map(|p| *p * 2.0).collect();
    let r2: Vec<Vec3> = big(&r).iter().map(|p| *p * 2.0).collect();
    let b = relmse(&x2, &r2).unwrap();
    assert!((a - b).abs() < 1e-4 * a, "{a} vs {b}");
}

#[test]
fn flip_grows_with_blur_and_noise() {
    let (w, h) = (64, 48);
    let r = texture(w, h);
    let blur1 = flip(&box_blur(&r, w, h, 1), &r, w, h).unwrap();
    let blur3 = flip(&box_blur(&r, w, h, 3), &r, w, h).unwrap();
    let noise_small = flip(&add_noise(&r, 0.02, 1), &r, w, h).unwrap();
    let noise_big = flip(&add_noise(&r, 0.15, 1), &r, w, h).unwrap();
    println!("FLIP blur r=1 {blur1:.4}, r=3 {blur3:.4}; noise ±0.02 {noise_small:.4}, ±0.15 {noise_big:.4}");
    assert!(blur1 > 0.0 && blur3 > blur1, "{blur1} {blur3}");
    assert!(
        noise_small > 0.0 && noise_big > noise_small,
        "{noise_small} {noise_big}"
    );
    assert!(noise_big < 1.0 && blur3 < 1.0);
}

#[test]
fn flip_judges_the_displayed_tone_mapping() {
    // Differences above 1.0 are clipped by the display mapping at exposure 0, so FLIP
    // sees nothing there while RMSE does; at exposure -3 they become visible.
    let (w, h) = (32, 32);
    let r: Vec<Vec3> = texture(w, h)
        .iter()
        .map(|p| *p + Vec3::splat(1.5))
        .collect();
    let x: Vec<Vec3> = r.iter().map(|p| *p * 1.5).collect();
    assert!(rmse(&x, &r).unwrap() > 0.5);
    assert_eq!(flip(&x, &r, w, h).unwrap(), 0.0);
    let dimmed = flip_exposure(&x, &r, w, h, -3.0).unwrap();
    println!("FLIP of a 1.5x brighter HDR image at exposure -3: {dimmed:.4}");
    assert!(dimmed > 0.05);
    // And the mapping is the PNG writer's.
    assert_eq!(
        tone_map_srgb8(&[Vec3::new(0.0, 0.5, 1.0)], 0.0).unwrap(),
        vec![0, 188, 255]
    );
}

#[test]
fn metrics_reject_bad_input() {
    let a = vec![Vec3::ONE; 6];
    let b = vec![Vec3::ONE; 5];
    assert!(rmse(&a, &b).is_err());
    assert!(relmse(&a, &b).is_err());
    assert!(flip(&a, &b, 3, 2).is_err());
    assert!(flip(&a, &a, 4, 2).is_err(), "size disagrees with w x h");
    assert!(rmse(&[], &[]).is_err());
    let mut nan = a.clone();
    nan[2].y = f32::NAN;
    assert!(rmse(&nan, &a).is_err());
    assert!(flip(&a, &nan, 3, 2).is_err());
}

#[test]
fn viridis_endpoints_and_monotone_lightness() {
    let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 0.02;
    // matplotlib's viridis table: first, middle and last entries.
    assert!(
        close(viridis(0.0), Vec3::new(0.267, 0.005, 0.329)),
        "{}",
        viridis(0.0)
    );
    assert!(
        close(viridis(0.5), Vec3::new(0.128, 0.567, 0.551)),
        "{}",
        viridis(0.5)
    );
    assert!(
        close(viridis(1.0), Vec3::new(0.993, 0.906, 0.144)),
        "{}",
        viridis(1.0)
    );
    let lum = |c: Vec3| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    for k in 0..50 {
        let (t0, t1) = (k as f32 / 50.0, (k + 1) as f32 / 50.0);
        assert!(
            lum(viridis(t1)) > lum(viridis(t0)),
            "lightness not increasing at {t0}"
        );
    }
    assert_eq!(viridis(f32::NAN), viridis(0.0));
    assert_eq!(viridis(7.0), viridis(1.0));
}

#[test]
fn trimmed_relmse_drops_only_the_worst_pixels() {
    let r = texture(100, 100);
    let mut x = r.clone();
    // One firefly among 10,000 pixels: 0.01 % of them.
    x[4321] = Vec3::splat(500.0);
    let full = relmse(&x, &r).unwrap();
    let trimmed = relmse_trimmed(&x, &r, TRIM_FRACTION).unwrap();
    println!("relMSE with one firefly {full:.3e}, trimmed {trimmed:.3e}");
    assert!(full > 1.0, "the firefly dominates: {full}");
    assert_eq!(trimmed, 0.0, "without it the images are equal");
    // No trimming is plain relMSE; trimming never drops an ordinary pixel.
    assert!((relmse_trimmed(&x, &r, 0.0).unwrap() - full).abs() <= 1e-6 * full);
    let noisy = add_noise(&r, 0.05, 3);
    let (a, b) = (
        relmse(&noisy, &r).unwrap(),
        relmse_trimmed(&noisy, &r, TRIM_FRACTION).unwrap(),
    );
    assert!(b < a && b > 0.99 * a, "{a} vs {b}");
    assert!(relmse_trimmed(&x, &r, 1.0).is_err());
}

#[test]
fn mean_ci95_matches_student_t() {
    let (m, ci) = mean_ci95(&[1.0, 2.0, 3.0, 4.0]);
    // s = sqrt(5/3), t(3 dof) = 3.182: 3.182 · s / 2.
    assert_eq!(m, 2.5);
    let expected = 3.182 * (5.0f64 / 3.0).sqrt() / 2.0;
    assert!((ci.unwrap() - expected).abs() < 1e-9);
    assert_eq!(mean_ci95(&[7.0]), (7.0, None));
}

const W: usize = 32;
const H: usize = 24;

/// A reference and runs: two adaptive strategies at two budgets, each with two
/// seeds (the second slower by 30 %, so that a mean is not the first seed's
/// time), a full render, the uniform baselines at each budget's time (at 5 %,
/// seed 1 takes 4 % longer: within the tolerance), a one-seed cycles-adaptive
/// baseline at 25 % that took 20 % longer than its target, and the Sec. 8
/// interpolation pair. `uniform` at 5 % has one seed twice as noisy as the
/// other: its interval reaches below 0.
fn sample_input() -> ReportInput {
    let reference = texture(W, H);
    let positions = |n: usize| -> Vec<Vec2> {
        (0..n)
            .map(|k| Vec2::new((k * 7 % W) as f32 + 0.5, (k * 5 % H) as f32 + 0.5))
            .collect()
    };
    let run = |name: &str, kind: RunKind, seed: u32, noise: f32, time: f64, samples: usize| Run {
        name: name.into(),
        kind,
        seed,
        samples,
        wall_time_s: time,
        cpu_time_s: time * 1.5,
        overhead_s: time * 0.1,
        target_s: None,
        image: add_noise(&reference, noise, samples as u64 + 97 * seed as u64),
        sample_positions: if matches!(kind, RunKind::Baseline { .. } | RunKind::Full { .. }) {
            vec![]
        } else {
            positions(samples)
        },
    };
    let mut runs = Vec::new();
    for seed in 0..2 {
        let slow = 1.0 + 0.3 * f64::from(seed);
        runs.push(run(
            "full",
            RunKind::Full { spp: 4 },
            seed,
            0.04,
            2.0 * slow,
            W * H * 4,
        ));
        for (budget, noise, time, n) in [(0.05, 0.08, 0.5, 38), (0.25, 0.03, 1.5, 192)] {
            let time = time * slow;
            let b = RunKind::Adaptive { budget, spp: 4 };
            runs.push(run("gradient", b, seed, noise, time, n));
            let wide = if budget == 0.05 {
                1.0 + seed as f32
            } else {
                1.0
            };
            runs.push(run("uniform", b, seed, noise * 1.5 * wide, time * 0.8, n));
            let spp = (4.0 * time / 2.0).round().max(1.0) as u32;
            let kind = RunKind::Baseline { budget, spp };
            let late = if budget == 0.05 && seed == 1 {
                1.04
            } else {
                1.0
            };
            let mut baseline = run(
                "uniform-all-pixels",
                kind,
                seed,
                noise * 1.2,
                time * late,
                W * H * spp as usize,
            );
            baseline.target_s = Some(time);
            runs.push(baseline);
            if budget == 0.25 && seed == 0 {
                let kind = RunKind::Baseline { budget, spp: 2 };
                let mut cycles = run("cycles-adaptive", kind, 0, 0.04, time * 1.2, W * H * 2);
                cycles.target_s = Some(time);
                runs.push(cycles);
            }
        }
    }
    let interp = RunKind::Interpolation {
        budget: 0.01,
        spp: 64,
    };
    runs.push(run(
        "1% grid, gradient interpolation",
        interp,
        0,
        0.05,
        0.2,
        8,
    ));
    runs.push(run(
        "1% grid, linear interpolation",
        interp,
        0,
        0.09,
        0.2,
        8,
    ));
    ReportInput {
        scene: "test <scene>".into(),
        scene_hash: "ab".repeat(32),
        command: "gradtrace compare test.toml".into(),
        version: "0.1.0 (test)".into(),
        threads: 2,
        equal_cost: EqualCost::Wall,
        width: W,
        height: H,
        reference: reference.clone(),
        reference_info: ReferenceInfo {
            spp: 1024,
            time_s: 10.0,
            cache_key: "cd".repeat(32),
            reused: false,
        },
        exposure: 0.0,
        runs,
        all_images: false,
        notes: vec!["a note with <markup> & symbols".into()],
    }
}

#[test]
fn report_writes_three_files_and_assets() {
    let dir = temp_dir("full");
    let input = sample_input();
    let rows = write_report(&dir, &input).unwrap();
    println!("{}", markdown_table(&rows));
    // One row per (method, setting): 1 full + 2 budgets × 3 + cycles-adaptive + 2
    // interpolation.
    assert_eq!(rows.len(), 1 + 6 + 1 + 2);
    // Rows carry the mean over the seeds of each run's figures, and its interval.
    for row in &rows {
        let members: Vec<&Run> = input
            .runs
            .iter()
            .filter(|r| {
                r.name == row.name && r.kind.name() == row.kind && {
                    let b = match r.kind {
                        RunKind::Adaptive { budget, .. } | RunKind::Baseline { budget, .. } => {
                            Some(budget)
                        }
                        _ => None,
                    };
                    b == row.equal_time_budget
                }
            })
            .collect();
        assert_eq!(members.len() as u32, row.seeds, "{}", row.name);
        let rmses: Vec<f64> = members
            .iter()
            .map(|r| f64::from(rmse(&r.image, &input.reference).unwrap()))
            .collect();
        let (m, ci) = mean_ci95(&rmses);
        assert!((f64::from(row.rmse) - m).abs() < 1e-7, "{}", row.name);
        assert_eq!(row.rmse_ci95.is_some(), members.len() > 1);
        if let Some(c) = ci {
            assert!((f64::from(row.rmse_ci95.unwrap()) - c).abs() < 1e-7);
        }
        let flips: Vec<f64> = members
            .iter()
            .map(|r| f64::from(flip(&r.image, &input.reference, W, H).unwrap()))
            .collect();
        assert!((f64::from(row.flip) - mean_ci95(&flips).0).abs() < 1e-6);
    }
    assert_eq!(compute_rows(&input).unwrap(), rows);

    // report.json: the documented schema.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    for key in [
        "scene",
        "scene_hash",
        "command",
        "version",
        "threads",
        "reference",
        "runs",
    ] {
        assert!(!json[key].is_null(), "report.json lacks {key}");
    }
    assert_eq!(json["scene"], "test <scene>");
    assert_eq!(json["reference"]["spp"], 1024);
    assert_eq!(json["reference"]["reused"], false);
    assert_eq!(json["reference"]["cache_key"], "cd".repeat(32));
    let jruns = json["runs"].as_array().unwrap();
    assert_eq!(jruns.len(), rows.len());
    for (j, r) in jruns.iter().zip(&rows) {
        for key in [
            "name",
            "kind",
            "budget",
            "seeds",
            "spp",
            "wall_s",
            "rmse",
            "rmse_ci95",
            "relmse",
            "relmse_trimmed",
            "flip",
        ] {
            assert!(j.get(key).is_some(), "run lacks {key}");
        }
        assert_eq!(j["name"], r.name.as_str());
        assert!((j["rmse"].as_f64().unwrap() - f64::from(r.rmse)).abs() < 1e-7);
    }
    let baseline = jruns.iter().find(|j| j["kind"] == "baseline").unwrap();
    assert!(baseline["budget"].is_null());
    assert!(baseline["spp"].as_u64().unwrap() >= 1);
    // Adaptive runs carry their samples per point, and what that spends per pixel.
    let adaptive = jruns.iter().find(|j| j["kind"] == "adaptive").unwrap();
    assert_eq!(adaptive["spp"], 4);
    let per_pixel = adaptive["samples"].as_f64().unwrap() * 4.0 / (W * H) as f64;
    assert!((adaptive["spp_per_pixel"].as_f64().unwrap() - per_pixel).abs() < 1e-12);
    assert_eq!(adaptive["seeds"], 2);

    // The headline names the lowest equal-time RMSE at the budget nearest 17%.
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let head = json["headline"].as_str().unwrap();
    println!("{head}");
    let contenders: Vec<&ReportRow> = rows
        .iter()
        .filter(|r| r.equal_time_budget == Some(0.25) && r.name != "uniform")
        .collect();
    let best = contenders
        .iter()
        .min_by(|a, b| a.rmse.total_cmp(&b.rmse))
        .unwrap();
    assert!(
        head.contains("budget 25%") && head.contains(&format!("{} has the lowest RMSE", best.name)),
        "{head}"
    );
    // Where FLIP crowns another method, the headline says so; where not, it is silent.
    let flip_best = contenders
        .iter()
        .min_by(|a, b| a.flip.total_cmp(&b.flip))
        .unwrap();
    assert_eq!(
        head.contains(&format!("By FLIP, {} is lowest", flip_best.name)),
        flip_best.name != best.name,
        "{head}"
    );
    assert_eq!(
        head.contains("By FLIP"),
        flip_best.name != best.name,
        "{head}"
    );
    assert!(html.contains("class=\"headline\""));

    // Markdown: two tables (time and RMSE; the other metrics) per budget, and for
    // the full and interpolation runs.
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert_eq!(md.matches("| method |").count(), 2 * 4, "{md}");

    // HTML: nothing external; images are the asset files, each written once.
    for bad in [
        "http:",
        "https:",
        "src=\"/",
        "<link",
        "<script",
        "@import",
        "url(http",
        "data:image",
    ] {
        assert!(!html.contains(bad), "HTML contains {bad:?}");
    }
    let srcs: Vec<&str> = html
        .split("src=\"")
        .skip(1)
        .map(|s| &s[..s.find('"').unwrap()])
        .collect();
    assert!(srcs.iter().all(|s| s.starts_with(ASSET_DIR)));
    for src in &srcs {
        assert!(dir.join(src).exists(), "{src}");
    }
    // Images of the first seed at the headline budget (25%, the nearest to 17%),
    // of the full render and of the interpolation runs: 4 + 1 + 2 cards.
    let cards = 4 + 1 + 2;
    let with_samples = 2 + 2;
    assert_eq!(srcs.len(), 1 + 2 * cards + with_samples);
    assert_eq!(
        html.matches("<svg").count(),
        2 + cards,
        "plots and a legend per map"
    );
    assert!(html.contains("a note with &lt;markup&gt; &amp; symbols"));
    assert!(!html.contains("<scene>"), "scene name must be escaped");
    for label in ["gradient", "uniform", "uniform-all-pixels"] {
        assert!(html.contains(&format!(">{label}<")), "{label}");
    }
    // The linked images and the two plots (which the HTML inlines).
    let assets = std::fs::read_dir(assets_of(&dir)).unwrap().count();
    assert_eq!(assets, srcs.len() + 2);
    // One folder, the report's own.
    assert_eq!(std::fs::read_dir(dir.join(ASSET_DIR)).unwrap().count(), 1);
    let id = assets_of(&dir)
        .file_name()
        .unwrap()
        .to_string_lossy()
        .into_owned();
    assert!(md.contains(&format!("({ASSET_DIR}/{id}/speed_rmse.svg)")));
    assert!(assets_of(&dir).join("speed_rmse.svg").exists());
    // No temporary files left behind.
    for d in [dir.clone(), dir.join(ASSET_DIR), assets_of(&dir)] {
        for e in std::fs::read_dir(d).unwrap() {
            let name = e.unwrap().file_name().to_string_lossy().to_string();
            assert!(!name.starts_with('.'), "leftover {name}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn sample_map_marks_sample_pixels_over_dimmed_reference() {
    let dir = temp_dir("samples");
    let mut input = sample_input();
    input.runs.retain(|r| r.name == "gradient" && r.seed == 0);
    input.runs.truncate(1);
    input.runs[0].sample_positions = vec![Vec2::new(3.5, 2.5), Vec2::new(W as f32, H as f32)];
    write_report(&dir, &input).unwrap();
    let path = assets_of(&dir).join("run-000-gradient-samples.png");
    let img = image::open(&path).unwrap().to_rgb8();
    assert_eq!((img.width() as usize, img.height() as usize), (W, H));
    let marker = [255, 96, 32];
    assert_eq!(img.get_pixel(3, 2).0, marker);
    assert_eq!(
        img.get_pixel(W as u32 - 1, H as u32 - 1).0,
        marker,
        "border sample → last pixel"
    );
    let reference8 = tone_map_srgb8(&input.reference, 0.0).unwrap();
    let marked = img.pixels().filter(|p| p.0 == marker).count();
    assert_eq!(marked, 2);
    // Elsewhere: the reference at 35 %.
    let i = 5 * W + 10;
    let dim = |c: u8| (f32::from(c) * 0.35).round() as u8;
    assert_eq!(
        img.get_pixel(10, 5).0,
        [
            dim(reference8[3 * i]),
            dim(reference8[3 * i + 1]),
            dim(reference8[3 * i + 2])
        ]
    );
    // Error map: a run equal to the reference maps to viridis(0) everywhere (up
    // to JPEG's rounding of a flat colour).
    input.runs[0].image = input.reference.clone();
    write_report(&dir, &input).unwrap();
    let err = image::open(assets_of(&dir).join("run-000-gradient-error.jpg"))
        .unwrap()
        .to_rgb8();
    let v0 = viridis(0.0).to_array().map(|v| (v * 255.0).round() as i32);
    assert!(err
        .pixels()
        .all(|p| (0..3).all(|k| (p.0[k] as i32 - v0[k]).abs() <= 3)));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A way to make a valid input invalid.
type Spoil = Box<dyn Fn(&mut ReportInput)>;

#[test]
fn bad_input_writes_nothing() {
    let cases: Vec<(&str, Spoil)> = vec![
        (
            "run size",
            Box::new(|i| i.runs[2].image.pop().map(|_| ()).unwrap()),
        ),
        ("reference size", Box::new(|i| i.reference.push(Vec3::ZERO))),
        ("resolution", Box::new(|i| i.width = 0)),
        ("nan pixel", Box::new(|i| i.runs[1].image[7].x = f32::NAN)),
        (
            "sample outside",
            Box::new(|i| i.runs[1].sample_positions.push(Vec2::new(-1.0, 3.0))),
        ),
        ("negative time", Box::new(|i| i.runs[3].wall_time_s = -1.0)),
        (
            "zero budget",
            Box::new(|i| {
                i.runs[1].kind = RunKind::Adaptive {
                    budget: 0.0,
                    spp: 4,
                }
            }),
        ),
        ("exposure", Box::new(|i| i.exposure = f32::INFINITY)),
    ];
    for (name, spoil) in cases {
        let dir = temp_dir(&format!("bad-{}", name.replace(' ', "-")));
        let mut input = sample_input();
        spoil(&mut input);
        let e = write_report(&dir, &input).expect_err(name);
        println!("{name}: {e}");
        assert!(!dir.exists(), "{name}: the directory was created");
        assert!(compute_rows(&input).is_err(), "{name}");
    }
    // An existing report is left untouched by a failed rewrite.
    let dir = temp_dir("keep");
    write_report(&dir, &sample_input()).unwrap();
    let before = std::fs::read(dir.join("report.html")).unwrap();
    let mut bad = sample_input();
    bad.runs[0].image.truncate(3);
    assert!(write_report(&dir, &bad).is_err());
    assert_eq!(std::fs::read(dir.join("report.html")).unwrap(), before);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn report_with_no_runs_or_zero_error_still_writes() {
    // A run identical to the reference has RMSE 0, which a log axis cannot show;
    // the plot leaves it out instead of failing.
    let dir = temp_dir("degenerate");
    let mut input = sample_input();
    input.runs.truncate(1);
    input.runs[0].image = input.reference.clone();
    input.runs[0].wall_time_s = 0.0;
    let rows = write_report(&dir, &input).unwrap();
    assert_eq!(rows[0].rmse, 0.0);
    input.runs.clear();
    assert!(write_report(&dir, &input).unwrap().is_empty());
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert!(html.contains("no positive data to plot"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The value of attribute `name` in one SVG tag.
fn attr(tag: &str, name: &str) -> f64 {
    let key = format!(" {name}=\"");
    let at = tag.find(&key).unwrap_or_else(|| panic!("{name} in {tag}")) + key.len();
    tag[at..at + tag[at..].find('"').unwrap()].parse().unwrap()
}

/// Every `<NAME …>` tag of `svg`.
fn tags<'a>(svg: &'a str, name: &str) -> Vec<&'a str> {
    let open = format!("<{name} ");
    svg.match_indices(&open)
        .map(|(i, _)| &svg[i..i + svg[i..].find('>').unwrap()])
        .collect()
}

/// Every point of both speed plots has its error bar — the widest too, whose
/// lower end (≤ 0) a log axis cannot show — except a one-seed point, which is
/// hollow and explained under the plot.
#[test]
fn every_plotted_point_has_an_error_bar() {
    let dir = temp_dir("bars");
    let input = sample_input();
    let rows = write_report(&dir, &input).unwrap();
    let plotted: Vec<&ReportRow> = rows.iter().filter(|r| r.kind != "interpolation").collect();
    // The input has an interval reaching below zero, and a one-seed row.
    assert!(plotted
        .iter()
        .any(|r| r.rmse_ci95.is_some_and(|c| c >= r.rmse)));
    let one_seed = plotted.iter().filter(|r| r.seeds == 1).count();
    assert_eq!(one_seed, 1);
    for plot in ["speed_rmse.svg", "speed_flip.svg"] {
        let svg = std::fs::read_to_string(assets_of(&dir).join(plot)).unwrap();
        // A point: its outline circle; a hollow one is filled white.
        let circles = tags(&svg, "circle");
        let points: Vec<&&str> = circles
            .iter()
            .filter(|c| c.contains("fill=\"none\""))
            .collect();
        assert_eq!(points.len(), plotted.len(), "{plot}");
        let lines = tags(&svg, "line");
        let mut hollow = 0;
        let mut cut = 0;
        for p in points {
            let (x, y) = (attr(p, "cx"), attr(p, "cy"));
            let white = circles.iter().any(|c| {
                c.contains("fill=\"#FFFFFF\"") && attr(c, "cx") == x && attr(c, "cy") == y
            });
            if white {
                hollow += 1;
                continue;
            }
            let bar = lines.iter().find(|l| {
                attr(l, "x1") == x
                    && attr(l, "x2") == x
                    && attr(l, "y1").min(attr(l, "y2")) <= y
                    && attr(l, "y1").max(attr(l, "y2")) >= y
            });
            let bar = bar.unwrap_or_else(|| panic!("{plot}: no error bar at ({x}, {y})"));
            // An arrowhead: two slanted lines meeting at one end of the bar.
            let ends = [
                (attr(bar, "x1"), attr(bar, "y1")),
                (attr(bar, "x2"), attr(bar, "y2")),
            ];
            cut += ends
                .iter()
                .filter(|(ex, ey)| {
                    lines
                        .iter()
                        .filter(|l| {
                            attr(l, "x2") == *ex && attr(l, "y2") == *ey && attr(l, "x1") != *ex
                        })
                        .count()
                        == 2
                })
                .count();
        }
        assert_eq!(hollow, one_seed, "{plot}");
        assert!(
            svg.contains("Hollow point: one seed, no interval."),
            "{plot}"
        );
        if plot == "speed_rmse.svg" {
            assert!(cut >= 1, "the interval below zero is drawn as an arrow");
            assert!(svg.contains("Arrow: the interval goes on past"));
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The `<td>` texts of every row of every HTML table, per table.
fn html_tables(html: &str) -> Vec<Vec<Vec<String>>> {
    html.split("<table>")
        .skip(1)
        .map(|t| {
            t[..t.find("</table>").unwrap()]
                .split("<tr")
                .skip(1)
                .map(|row| {
                    row.split("<td>")
                        .skip(1)
                        .map(|c| c[..c.find("</td>").unwrap()].to_string())
                        .collect::<Vec<_>>()
                })
                .filter(|cells: &Vec<String>| !cells.is_empty())
                .collect()
        })
        .collect()
}

/// A run's setting as the report prints it: "25%" or "3 spp".
fn setting_of(kind: RunKind) -> String {
    match kind {
        RunKind::Adaptive { budget, .. } | RunKind::Interpolation { budget, .. } => {
            let p = format!("{:.2}", budget * 100.0);
            format!("{}%", p.trim_end_matches('0').trim_end_matches('.'))
        }
        RunKind::Baseline { spp, .. } | RunKind::Full { spp } => format!("{spp} spp"),
        RunKind::Preview { .. } => "per frame".into(),
    }
}

/// An image card gives its row's mean wall time, as the table prints it, not the
/// time of the seed whose image it shows.
#[test]
fn image_cards_show_the_tables_mean_time() {
    let dir = temp_dir("cards");
    let mut input = sample_input();
    input.all_images = true;
    write_report(&dir, &input).unwrap();
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let tables = html_tables(&html);
    let mut checked = 0;
    let mut differs_from_seed0 = 0;
    for card in html.split("<div class=\"card\">").skip(1) {
        let title = &card[4..card.find("</h4>").unwrap()];
        let (name, setting) = title.rsplit_once(" (").unwrap();
        let setting = setting.trim_end_matches(')');
        let p = &card[card.find("<p>").unwrap() + 3..];
        let time = &p[..p.find(" s;").unwrap()];
        // The time table's rows of this method and setting (10 cells; name, kind,
        // setting, …, wall time in the sixth).
        let cells: Vec<&String> = tables
            .iter()
            .flatten()
            .filter(|r| r.len() == 10 && r[0] == name && r[2] == setting)
            .map(|r| &r[5])
            .collect();
        assert!(!cells.is_empty(), "no table row for {title}");
        assert!(
            cells.iter().all(|c| *c == time),
            "{title}: card {time}, table {cells:?}"
        );
        checked += 1;
        let seed0 = input
            .runs
            .iter()
            .find(|r| r.name == name && r.seed == 0 && setting_of(r.kind) == setting);
        // (A baseline whose seeds differ in spp has none: the card gives the mean.)
        if let Some(seed0) = seed0 {
            differs_from_seed0 += usize::from(format!("{:.3}", seed0.wall_time_s) != time);
        }
    }
    assert_eq!(checked, 1 + 2 * 3 + 1 + 2);
    assert!(
        differs_from_seed0 >= 6,
        "the test input must tell a mean from seed 0"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Rows whose time is off their target by more than 5 % are marked in the HTML
/// and Markdown tables, in `report.json` and in the headline; a row 4 % off is not.
#[test]
fn rows_off_equal_time_are_marked() {
    let dir = temp_dir("equal-time");
    let rows = write_report(&dir, &sample_input()).unwrap();
    let find = |name: &str, budget: f64| {
        rows.iter()
            .find(|r| r.name == name && r.equal_time_budget == Some(budget))
            .unwrap()
    };
    let cycles = find("cycles-adaptive", 0.25);
    assert!((cycles.time_vs_target.unwrap() - 0.2).abs() < 1e-9);
    assert_eq!(cycles.equal_time, Some(false));
    let uniform = find("uniform-all-pixels", 0.05);
    assert!((uniform.time_vs_target.unwrap() - 0.04).abs() < 1e-9);
    assert_eq!(uniform.equal_time, Some(true));
    assert_eq!(find("uniform-all-pixels", 0.25).equal_time, Some(true));
    assert_eq!(find("gradient", 0.25).time_vs_target, None);

    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let off_rows: Vec<&str> = html
        .split("<tr class=\"off\">")
        .skip(1)
        .map(|r| &r[..r.find("</tr>").unwrap()])
        .collect();
    // Both tables of the section mark the row.
    assert_eq!(off_rows.len(), 2, "{off_rows:?}");
    assert!(off_rows.iter().all(|r| r.contains(">cycles-adaptive<")));
    assert!(off_rows[0].contains("+20.0% †"));
    assert!(html.contains("† beyond ±5%: not an equal-time result"));
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    let md_row = |name: &str, setting: &str| -> String {
        md.lines()
            .find(|l| l.starts_with(&format!("| {name} | baseline | {setting} |")))
            .unwrap()
            .to_string()
    };
    assert!(md_row("cycles-adaptive", "2 spp").contains("| +20.0% † |"));
    let u = md_row("uniform-all-pixels", "1 spp");
    assert!(u.contains("| +4.0% |") && !u.contains('†'), "{u}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    let j = json["runs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["name"] == "cycles-adaptive")
        .unwrap();
    assert_eq!(j["equal_time"], false);
    assert!(json["headline"]
        .as_str()
        .unwrap()
        .contains("Not at equal time (beyond ±5%): cycles-adaptive +20.0% †"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `report.json` documents each of its top-level keys in `fields` and each key of
/// a run in `run_fields`, one line each: a key added without its line fails.
#[test]
fn report_json_documents_every_field() {
    let dir = temp_dir("fields");
    write_report(&dir, &sample_input()).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    let keys = |v: &serde_json::Value| -> Vec<String> {
        let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
        k.sort();
        k
    };
    assert_eq!(keys(&json), keys(&json["fields"]));
    for run in json["runs"].as_array().unwrap() {
        assert_eq!(keys(run), keys(&json["run_fields"]));
    }
    for doc in [&json["fields"], &json["run_fields"]] {
        for (k, line) in doc.as_object().unwrap() {
            let line = line.as_str().unwrap();
            assert!(line.len() > 10 && !line.contains('\n'), "{k}: {line:?}");
        }
    }
    for k in ["width", "height", "exposure", "error_map_scale"] {
        assert!(json["fields"][k].is_string(), "{k}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The 99th percentile of |Δ luminance| of one run, as the report's scale takes it.
fn p99_error(run: &Run, reference: &[Vec3]) -> f32 {
    let lum = |c: Vec3| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    let mut e: Vec<f32> = run
        .image
        .iter()
        .zip(reference)
        .map(|(a, b)| (lum(*a) - lum(*b)).abs())
        .collect();
    e.sort_by(f32::total_cmp);
    e[((e.len() as f64 * 0.99) as usize).min(e.len() - 1)]
}

/// Each budget's error maps (and the full render's, and the interpolation runs')
/// have their own colour scale, the largest 99th percentile among their maps, and
/// its maximum is printed under each of them.
#[test]
fn error_maps_have_one_scale_per_budget() {
    let dir = temp_dir("scales");
    let mut input = sample_input();
    input.all_images = true;
    write_report(&dir, &input).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    let scales = json["error_map_scale"].as_array().unwrap();
    let labels: Vec<&str> = scales.iter().map(|s| s["maps"].as_str().unwrap()).collect();
    assert_eq!(
        labels,
        [
            "full render",
            "budget 5%",
            "budget 25%",
            "interpolation, 1%"
        ]
    );
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    let mut maxima = Vec::new();
    for s in scales {
        let group = |r: &&Run| {
            r.seed == 0
                && match (s["budget"].as_f64(), r.kind) {
                    (None, RunKind::Full { .. }) => true,
                    (
                        Some(b),
                        RunKind::Adaptive { budget, .. } | RunKind::Baseline { budget, .. },
                    ) => budget == b && s["maps"] != "interpolation, 1%",
                    (Some(b), RunKind::Interpolation { budget, .. }) => {
                        budget == b && s["maps"] == "interpolation, 1%"
                    }
                    _ => false,
                }
        };
        let expected = input
            .runs
            .iter()
            .filter(group)
            .map(|r| p99_error(r, &input.reference))
            .fold(0.0f32, f32::max);
        let max = s["max"].as_f64().unwrap() as f32;
        assert!(
            (max - expected).abs() <= 1e-6 * expected,
            "{}: {max} vs {expected}",
            s["maps"]
        );
        // Printed on the legend under each of its maps.
        assert!(html.contains(&format!("≥ {max:.2e}<")), "{max:.2e}");
        maxima.push(max);
    }
    assert!(
        maxima[1] > 1.5 * maxima[2],
        "the two budgets' errors differ, so must their scales: {maxima:?}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// End to end through the command line: budgets reach `report.json` as written
/// (0.17, not the f32's 0.17000000178813934), adaptive runs carry their spp.
#[test]
fn compare_writes_budgets_as_given() {
    let dir = temp_dir("cli-budgets");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_gradtrace"))
        .args([
            "compare",
            "scenes/cornell.toml",
            "--width",
            "24",
            "--height",
            "16",
        ])
        .args([
            "--spp",
            "2",
            "--reference-spp",
            "4",
            "--strategies",
            "gradient",
        ])
        .args(["--budgets", "0.17,0.3", "--quiet", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(dir.join("report.json")).unwrap();
    assert!(text.contains("\"budget\": 0.17,"), "{text}");
    assert!(text.contains("\"equal_time_budget\": 0.3,"), "{text}");
    assert!(!text.contains("0.1700000") && !text.contains("0.3000000"));
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    for run in json["runs"].as_array().unwrap() {
        if run["kind"] == "adaptive" {
            assert_eq!(run["spp"], 2, "{run}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The report's asset folder, `report-assets/<render_id of report.json>`.
fn assets_of(dir: &Path) -> PathBuf {
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    dir.join(ASSET_DIR)
        .join(json["render_id"].as_str().unwrap())
}

/// `equal_cost` decides what `time_vs_target` measures: the sample runs' CPU time
/// is 1.5 × their wall time, so cycles-adaptive at 25 %, 20 % over its target in
/// wall seconds, is 1.5 × 1.2 − 1 = 80 % over it in CPU seconds; the mode is in
/// `report.json`, every row carries both costs, the headline names the measure.
#[test]
fn equal_cost_decides_what_time_vs_target_measures() {
    let mut input = sample_input();
    let target = |rows: &[ReportRow]| {
        rows.iter()
            .find(|r| r.name == "cycles-adaptive" && r.equal_time_budget == Some(0.25))
            .unwrap()
            .time_vs_target
            .unwrap()
    };
    assert!((target(&compute_rows(&input).unwrap()) - 0.2).abs() < 1e-9);
    input.equal_cost = EqualCost::Cpu;
    let rows = compute_rows(&input).unwrap();
    assert!((target(&rows) - 0.8).abs() < 1e-9, "{}", target(&rows));
    for r in &rows {
        assert!((r.cpu_s - 1.5 * r.wall_s).abs() < 1e-9, "{r:?}");
    }
    let dir = temp_dir("equal-cpu");
    write_report(&dir, &input).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(json["equal_cost"], "cpu");
    assert!(json["runs"][0]["cpu_s"].as_f64().unwrap() > 0.0);
    assert!(json["headline"]
        .as_str()
        .unwrap()
        .starts_with("At equal CPU time on"));
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    assert!(md.contains("| wall time (s) | CPU time (s) |"), "{md}");
    std::fs::remove_dir_all(&dir).unwrap();
}
