//! `gradtrace diff A.exr B.exr`: zero for identical files, the closed-form RMSE
//! and relMSE of a known perturbation with the threshold deciding the exit
//! status, and one clear error (naming the file) that writes nothing for bad
//! input.

mod common;
use common::{run_in, temp_dir};
use gradtrace::output::metrics::RELMSE_EPS;
use gradtrace::output::{write_exr, OutputImage};
use gradtrace::pipeline::diff::{self, DiffMetric, DiffOptions};
use std::path::Path;
use std::process::Output;

const W: usize = 20;
const H: usize = 15;

fn stderr_lines(out: &Output) -> Vec<String> {
    String::from_utf8_lossy(&out.stderr)
        .lines()
        .map(str::to_owned)
        .collect()
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A smooth pattern in [0.05, 1.05] per channel, with a second layer so that the
/// beauty has to be picked out of several channels.
fn pattern(w: usize, h: usize) -> Vec<[f32; 3]> {
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
            [0.05 + x, 0.05 + y, 0.05 + 0.5 * (x + y)]
        })
        .collect()
}

fn write_rgb(path: &Path, w: usize, h: usize, rgb: &[[f32; 3]]) {
    let mut img = OutputImage::new(w, h);
    for (k, name) in ["R", "G", "B"].iter().enumerate() {
        img.push_scalar(name, rgb.iter().map(|p| p[k]).collect());
    }
    img.push_scalar("depth.Z", vec![1.0; w * h]);
    write_exr(path, &img).unwrap();
}

fn options(metric: DiffMetric, threshold: Option<f32>) -> DiffOptions {
    DiffOptions {
        metric,
        threshold,
        error_map: None,
    }
}

#[test]
fn identical_files_give_zero_and_exit_0() {
    let dir = temp_dir("identical");
    let rgb = pattern(W, H);
    write_rgb(&dir.join("a.exr"), W, H, &rgb);
    write_rgb(&dir.join("b.exr"), W, H, &rgb);

    let report = diff::run(
        &dir.join("a.exr"),
        &dir.join("b.exr"),
        &options(DiffMetric::Flip, Some(0.0)),
    )
    .unwrap();
    assert_eq!(
        (
            report.rmse,
            report.relmse,
            report.relmse_trimmed,
            report.flip
        ),
        (0.0, 0.0, 0.0, 0.0)
    );
    assert!(!report.exceeds_threshold());

    let out = run_in(&dir, &["diff", "a.exr", "b.exr", "--threshold", "0"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(out.stderr.is_empty());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("rmse            0.000000e0"), "{stdout}");
    assert!(stdout.contains("is within the threshold 0"), "{stdout}");
    // The default error map sits beside A, all at the bottom of the scale.
    let map = image::open(dir.join("a.diff.png")).unwrap().to_rgb8();
    assert_eq!(map.dimensions(), (W as u32, H as u32));
    let zero = gradtrace::output::colormap::viridis8(0.0);
    assert!(map.pixels().all(|p| p.0 == zero));
}

/// k pixels of G raised by δ over a reference r: RMSE = δ·sqrt(k / 3N) and
/// relMSE = (k / 3N) · Σ δ² / (r² + ε) over those pixels, exactly.
#[test]
fn known_perturbation_gives_the_closed_form_and_exit_1_above_the_threshold() {
    let dir = temp_dir("perturbed");
    let reference = pattern(W, H);
    let mut image = reference.clone();
    let (delta, changed) = (0.25_f32, [3usize, 40, 41, 177, 299]);
    for &i in &changed {
        image[i][1] += delta;
    }
    write_rgb(&dir.join("img.exr"), W, H, &image);
    write_rgb(&dir.join("ref.exr"), W, H, &reference);

    let n3 = (3 * W * H) as f64;
    let d = f64::from(delta);
    let want_rmse = d * (changed.len() as f64 / n3).sqrt();
    let want_relmse: f64 = changed
        .iter()
        .map(|&i| {
            // The G value the reference holds, as the EXR stores it (f32).
            let r = f64::from(reference[i][1]);
            let x = f64::from(image[i][1]);
            (x - r) * (x - r) / (r * r + f64::from(RELMSE_EPS))
        })
        .sum::<f64>()
        / n3;
    let report = diff::run(
        &dir.join("img.exr"),
        &dir.join("ref.exr"),
        &options(DiffMetric::Rmse, None),
    )
    .unwrap();
    let close = |got: f32, want: f64| (f64::from(got) - want).abs() <= 1e-5 * want;
    assert!(
        close(report.rmse, want_rmse),
        "{} vs {want_rmse}",
        report.rmse
    );
    assert!(
        close(report.relmse, want_relmse),
        "{} vs {want_relmse}",
        report.relmse
    );
    assert!(report.flip > 0.0);
    // Fewer than 1 % of the pixels differ by one amount: they are at the top of
    // the map's scale, every other pixel at the bottom.
    let map = image::open(dir.join("img.diff.png")).unwrap().to_rgb8();
    let (top, bottom) = (
        gradtrace::output::colormap::viridis8(1.0),
        gradtrace::output::colormap::viridis8(0.0),
    );
    for (i, p) in map.pixels().enumerate() {
        assert_eq!(p.0, if changed.contains(&i) { top } else { bottom }, "{i}");
    }

    let below = format!("{}", want_rmse * 0.99);
    let out = run_in(&dir, &["diff", "img.exr", "ref.exr", "--threshold", &below]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr_lines(&out);
    assert_eq!(err.len(), 1, "{err:?}");
    assert!(err[0].starts_with("error: img.exr differs from ref.exr: rmse"));
    assert!(err[0].contains("above --threshold"), "{err:?}");
    let above = format!("{}", want_rmse * 1.01);
    let out = run_in(&dir, &["diff", "img.exr", "ref.exr", "--threshold", &above]);
    assert_eq!(out.status.code(), Some(0));

    // The threshold applies to the chosen metric: here relMSE < RMSE.
    assert!(want_relmse < 0.99 * want_rmse);
    let args = ["diff", "img.exr", "ref.exr", "--metric", "relmse"];
    let relmse_below = format!("{}", want_relmse * 0.99);
    let out = run_in(&dir, &[&args[..], &["--threshold", &relmse_below]].concat());
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr_lines(&out)[0].contains(": relmse "));
    let out = run_in(&dir, &[&args[..], &["--threshold", &below]].concat());
    assert_eq!(out.status.code(), Some(0), "RMSE's threshold passes relMSE");
}

/// Each bad input: status 1, one `error:` line naming the file and what is
/// wrong, and no error map written.
#[test]
fn bad_inputs_are_one_error_line_and_write_nothing() {
    let dir = temp_dir("bad");
    write_rgb(&dir.join("a.exr"), W, H, &pattern(W, H));
    write_rgb(&dir.join("tall.exr"), H, W, &pattern(H, W));
    let mut depth_only = OutputImage::new(W, H);
    depth_only.push_scalar("depth.Z", vec![1.0; W * H]);
    write_exr(&dir.join("depth.exr"), &depth_only).unwrap();
    std::fs::write(dir.join("text.exr"), "not an EXR").unwrap();
    let before = files_in(&dir);

    let cases: [(&[&str], &[&str]); 5] = [
        (
            &["a.exr", "tall.exr"],
            &["tall.exr", "is 15x20 but a.exr is 20x15"],
        ),
        (
            &["depth.exr", "a.exr"],
            &["depth.exr", "no beauty channels R, G, B", "depth.Z"],
        ),
        (
            &["a.exr", "missing.exr"],
            &["missing.exr", "cannot read file"],
        ),
        (&["text.exr", "a.exr"], &["text.exr", "invalid EXR"]),
        (
            &["a.exr", "a.exr", "--threshold", "-1"],
            &["--threshold", "finite number >= 0"],
        ),
    ];
    for (args, needles) in cases {
        let out = run_in(&dir, &[&["diff"][..], args].concat());
        assert_eq!(out.status.code(), Some(1));
        assert!(out.stdout.is_empty());
        let err = stderr_lines(&out);
        assert_eq!(err.len(), 1, "{err:?}");
        assert!(err[0].starts_with("error: "), "{err:?}");
        for needle in needles {
            assert!(err[0].contains(needle), "{needle:?} in {err:?}");
        }
        assert_eq!(files_in(&dir), before, "nothing written");
    }
}

#[test]
fn error_map_goes_where_asked_and_never_over_an_input() {
    let dir = temp_dir("map");
    write_rgb(&dir.join("a.exr"), W, H, &pattern(W, H));
    let out = run_in(&dir, &["diff", "a.exr", "a.exr", "--error-map", "m.png"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(dir.join("m.png").is_file());
    assert!(!dir.join("a.diff.png").exists());
    let out = run_in(&dir, &["diff", "a.exr", "a.exr", "--error-map", "a.exr"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(stderr_lines(&out)[0].contains("is one of the inputs"));
    assert!(gradtrace::output::read_exr(&dir.join("a.exr")).is_ok());
}
