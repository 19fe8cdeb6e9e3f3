//! Comparison report: metric known answers (RMSE, relMSE, FLIP), the colour map,
//! base64, and `write_report`'s files (self-contained HTML, parseable JSON with the
//! right rows, Markdown table, sample maps) and its all-or-nothing behaviour.

use gradtrace::math::{Vec2, Vec3};
use gradtrace::output::colormap::viridis;
use gradtrace::output::metrics::{flip, flip_exposure, relmse, rmse, tone_map_srgb8, RELMSE_EPS};
use gradtrace::output::report::{
    base64, compute_rows, equal_time_spp, markdown_table, write_report, ReportInput, Run, RunKind,
    ASSET_DIR,
};
use std::path::PathBuf;

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
fn base64_matches_rfc4648_vectors() {
    for (input, out) in [
        ("", ""),
        ("f", "Zg=="),
        ("fo", "Zm8="),
        ("foo", "Zm9v"),
        ("foob", "Zm9vYg=="),
        ("fooba", "Zm9vYmE="),
        ("foobar", "Zm9vYmFy"),
    ] {
        assert_eq!(base64(input.as_bytes()), out);
    }
    assert_eq!(base64(&[0xfb, 0xff, 0xbf]), "+/+/");
}

const W: usize = 32;
const H: usize = 24;

/// A reference and six runs: two adaptive strategies at two budgets, one
/// equal-time baseline and the Sec. 8 interpolation pair.
fn sample_input() -> ReportInput {
    let reference = texture(W, H);
    let positions = |n: usize| -> Vec<Vec2> {
        (0..n)
            .map(|k| Vec2::new((k * 7 % W) as f32 + 0.5, (k * 5 % H) as f32 + 0.5))
            .collect()
    };
    let run = |label: &str, kind: RunKind, noise: f32, time: f64, samples: usize| Run {
        label: label.into(),
        kind,
        samples,
        wall_time_s: time,
        overhead_s: time * 0.1,
        image: add_noise(&reference, noise, samples as u64),
        sample_positions: if matches!(kind, RunKind::EqualTime { .. }) {
            vec![]
        } else {
            positions(samples)
        },
    };
    ReportInput {
        scene: "test <scene>".into(),
        width: W,
        height: H,
        reference: reference.clone(),
        reference_time_s: 10.0,
        reference_spp: 1024,
        exposure: 0.0,
        runs: vec![
            run(
                "gradient",
                RunKind::Adaptive { budget: 0.05 },
                0.08,
                0.5,
                38,
            ),
            run(
                "gradient",
                RunKind::Adaptive { budget: 0.25 },
                0.03,
                1.5,
                192,
            ),
            run("uniform", RunKind::Adaptive { budget: 0.05 }, 0.12, 0.4, 38),
            run(
                "uniform",
                RunKind::Adaptive { budget: 0.25 },
                0.06,
                1.2,
                192,
            ),
            run(
                "uniform-full",
                RunKind::EqualTime { spp: 2 },
                0.1,
                0.6,
                W * H * 2,
            ),
            run(
                "gradient-interp",
                RunKind::Interpolation { budget: 0.01 },
                0.05,
                0.2,
                8,
            ),
            run(
                "linear-interp",
                RunKind::Interpolation { budget: 0.01 },
                0.09,
                0.2,
                8,
            ),
        ],
        notes: vec!["a note with <markup> & symbols".into()],
    }
}

#[test]
fn report_writes_three_files_and_assets() {
    let dir = temp_dir("full");
    let input = sample_input();
    let rows = write_report(&dir, &input).unwrap();
    assert_eq!(rows.len(), input.runs.len());
    for r in &rows {
        println!(
            "{:16} {:13} {:>6} RMSE {:.4} relMSE {:.4} FLIP {:.4} speed-up {:?}",
            r.label,
            r.kind,
            r.budget.map_or(String::new(), |b| b.to_string()),
            r.rmse,
            r.relmse,
            r.flip,
            r.speedup_vs_reference
        );
    }
    // Rows carry the metrics of the images.
    for (row, run) in rows.iter().zip(&input.runs) {
        assert_eq!(row.rmse, rmse(&run.image, &input.reference).unwrap());
        assert_eq!(row.flip, flip(&run.image, &input.reference, W, H).unwrap());
        assert_eq!(row.speedup_vs_reference, Some(10.0 / run.wall_time_s));
    }
    assert_eq!(compute_rows(&input).unwrap(), rows);

    // JSON parses and holds the same rows.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).unwrap()).unwrap();
    assert_eq!(json["scene"], "test <scene>");
    assert_eq!(json["width"], W);
    assert_eq!(json["reference_spp"], 1024);
    let jrows = json["rows"].as_array().unwrap();
    assert_eq!(jrows.len(), rows.len());
    for (j, r) in jrows.iter().zip(&rows) {
        assert_eq!(j["label"], r.label.as_str());
        assert_eq!(j["kind"], r.kind.as_str());
        assert_eq!(j["samples"], r.samples);
        assert!((j["rmse"].as_f64().unwrap() - f64::from(r.rmse)).abs() < 1e-7);
        assert!((j["flip"].as_f64().unwrap() - f64::from(r.flip)).abs() < 1e-7);
    }
    assert_eq!(jrows[4]["spp"], 2);
    assert!(jrows[4]["budget"].is_null());
    assert_eq!(jrows[0]["budget"].as_f64().unwrap() as f32, 0.05);

    // Markdown: a header, a separator and one line per run.
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    let table: Vec<&str> = md.lines().filter(|l| l.starts_with('|')).collect();
    assert_eq!(table.len(), 2 + rows.len(), "{md}");
    assert!(
        table[2].starts_with("| gradient | adaptive | 5% | 38 |"),
        "{}",
        table[2]
    );
    assert!(table[6].contains("| 2 spp |"), "{}", table[6]);

    // HTML: self-contained, every image a data URI.
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    for bad in [
        "http:", "https:", "src=\"/", "<link", "<script", "@import", "url(http",
    ] {
        assert!(!html.contains(bad), "HTML contains {bad:?}");
    }
    let srcs: Vec<&str> = html.split("src=\"").skip(1).collect();
    assert!(srcs.iter().all(|s| s.starts_with("data:image/png;base64,")));
    let with_samples = input
        .runs
        .iter()
        .filter(|r| !r.sample_positions.is_empty())
        .count();
    let expected_images = 1 + 2 * input.runs.len() + with_samples;
    println!("HTML {} bytes, {} embedded images", html.len(), srcs.len());
    assert_eq!(srcs.len(), expected_images);
    assert_eq!(html.matches("<svg").count(), 3, "two plots and the legend");
    assert!(html.contains("Equal-time baselines"));
    assert!(html.contains("Gradient vs linear interpolation (Sec. 8)"));
    assert!(html.contains("a note with &lt;markup&gt; &amp; symbols"));
    assert!(!html.contains("<scene>"), "scene name must be escaped");
    // Plots: one line per strategy, legend names present.
    for label in ["gradient", "uniform", "uniform-full", "linear-interp"] {
        assert!(
            html.contains(&format!(">{label}<")) || html.contains(&format!(">{label} <")),
            "{label}"
        );
    }

    // Assets on disk: reference, image + error per run, samples where given, 2 plots.
    let assets = std::fs::read_dir(dir.join(ASSET_DIR)).unwrap().count();
    assert_eq!(assets, expected_images + 2);
    // No temporary files left behind.
    for d in [dir.clone(), dir.join(ASSET_DIR)] {
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
    input.runs.truncate(1);
    input.runs[0].sample_positions = vec![Vec2::new(3.5, 2.5), Vec2::new(W as f32, H as f32)];
    write_report(&dir, &input).unwrap();
    let path = dir.join(ASSET_DIR).join("run-00-gradient-samples.png");
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
    // Error map: a run equal to the reference maps to viridis(0) everywhere.
    input.runs[0].image = input.reference.clone();
    write_report(&dir, &input).unwrap();
    let err = image::open(dir.join(ASSET_DIR).join("run-00-gradient-error.png"))
        .unwrap()
        .to_rgb8();
    let v0 = viridis(0.0).to_array().map(|v| (v * 255.0).round() as u8);
    assert!(err.pixels().all(|p| p.0 == v0));
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
            Box::new(|i| i.runs[0].sample_positions.push(Vec2::new(-1.0, 3.0))),
        ),
        ("negative time", Box::new(|i| i.runs[3].wall_time_s = -1.0)),
        (
            "zero budget",
            Box::new(|i| i.runs[0].kind = RunKind::Adaptive { budget: 0.0 }),
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
    assert_eq!(rows[0].speedup_vs_reference, None);
    input.runs.clear();
    assert!(write_report(&dir, &input).unwrap().is_empty());
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert!(html.contains("no positive data to plot"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn equal_time_spp_scales_with_time() {
    assert_eq!(equal_time_spp(1.0, 10.0, 1024), 102);
    assert_eq!(
        equal_time_spp(0.001, 10.0, 1024),
        1,
        "never below one sample"
    );
    assert_eq!(equal_time_spp(0.0, 10.0, 1024), 1);
    assert_eq!(
        equal_time_spp(5.0, 0.0, 1024),
        1,
        "no reference time: no basis"
    );
    assert_eq!(equal_time_spp(20.0, 10.0, 64), 128);
    let rows = compute_rows(&sample_input()).unwrap();
    let table = markdown_table(&rows);
    assert_eq!(table.lines().count(), rows.len() + 2);
    assert!(
        table.contains("| linear-interp | interpolation | 1% | 8 |"),
        "{table}"
    );
}
