//! reference + strategy runs → `report.html` (self-contained), `report.json`,
//! `report.md` and the PNG/SVG assets they show, for `gradtrace compare`.
//!
//! Nothing here renders: the caller hands over the reference and every run's image,
//! timings and sample positions. This module measures them (RMSE, relMSE, FLIP on
//! one shared tone mapping, see [`super::metrics`]), draws false-colour error maps,
//! sample-position maps in the style of the paper's Fig. 14/15 and log-log
//! speed-against-error plots, and writes everything atomically: all files are
//! encoded and staged first, and only then renamed into place, so invalid input or
//! a failed encoder leaves the directory untouched.
//!
//! The HTML embeds its images as `data:` URIs and its plots as inline SVG, with no
//! external CSS, scripts or fonts, so it can be mailed or opened offline. The same
//! images are also written as files under `report-assets/` for the Markdown.

use super::atomic::{output_error, stage, Staged};
use super::colormap::{viridis8, viridis_hex};
use super::metrics::{self, luminance, FLIP_PPD, RELMSE_EPS};
use super::plot::{loglog_svg, Series};
use crate::math::{Vec2, Vec3};
use crate::Result;
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};
use serde::Serialize;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

/// Folder (inside the report directory) for the PNG and SVG files.
pub const ASSET_DIR: &str = "report-assets";

/// How a run spent its samples, which decides how it is compared.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RunKind {
    /// Adaptive sampling at `budget` samples per pixel (0.05 = 5 % of the pixels),
    /// compared at equal sample count.
    Adaptive { budget: f32 },
    /// Uniform rendering of every pixel with `spp` samples per pixel, chosen by the
    /// caller to take about the same wall time as an adaptive run: the honest
    /// equal-time baseline.
    EqualTime { spp: u32 },
    /// An interpolation experiment at `budget` samples per pixel (Sec. 8: gradient
    /// vs linear interpolation of soft shadows); shown in its own section.
    Interpolation { budget: f32 },
}

impl RunKind {
    /// Stable machine name, as in `report.json`.
    pub fn name(self) -> &'static str {
        match self {
            RunKind::Adaptive { .. } => "adaptive",
            RunKind::EqualTime { .. } => "equal-time",
            RunKind::Interpolation { .. } => "interpolation",
        }
    }

    fn budget(self) -> Option<f32> {
        match self {
            RunKind::Adaptive { budget } | RunKind::Interpolation { budget } => Some(budget),
            RunKind::EqualTime { .. } => None,
        }
    }

    /// Short text for tables and plot points: "5%" or "4 spp".
    fn short(self) -> String {
        match self {
            RunKind::Adaptive { budget } | RunKind::Interpolation { budget } => percent(budget),
            RunKind::EqualTime { spp } => format!("{spp} spp"),
        }
    }
}

/// One image produced by one strategy at one setting.
#[derive(Clone, Debug)]
pub struct Run {
    /// Strategy name, e.g. "gradient", "uniform". Runs with the same label form
    /// one line in the speed-against-error plots.
    pub label: String,
    pub kind: RunKind,
    /// Number of image samples evaluated (for full renders: pixels × spp).
    pub samples: usize,
    /// Total wall time of the run in seconds, overhead included.
    pub wall_time_s: f64,
    /// The part of `wall_time_s` spent outside the renderer (quadtree and
    /// reconstruction).
    pub overhead_s: f64,
    /// Linear RGB, row-major, top row first, `width × height` pixels.
    pub image: Vec<Vec3>,
    /// Sample positions in continuous pixel coordinates (`[0, W] × [0, H]`, origin
    /// top left, as in `adaptive`); empty for full renders.
    pub sample_positions: Vec<Vec2>,
}

/// Everything the report shows.
#[derive(Clone, Debug)]
pub struct ReportInput {
    pub scene: String,
    pub width: usize,
    pub height: usize,
    /// The high-quality reference, linear RGB.
    pub reference: Vec<Vec3>,
    pub reference_time_s: f64,
    pub reference_spp: u32,
    /// Display exposure in stops, used for every image *and* for FLIP (0 = none).
    pub exposure: f32,
    pub runs: Vec<Run>,
    /// Free text shown at the end (setup, caveats).
    pub notes: Vec<String>,
}

/// One line of the summary table (and of `report.json`'s `rows`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReportRow {
    pub label: String,
    /// "adaptive", "equal-time" or "interpolation".
    pub kind: String,
    /// Samples per pixel of an adaptive / interpolation run (0.05 = 5 %).
    pub budget: Option<f32>,
    /// Samples per pixel of an equal-time run.
    pub spp: Option<u32>,
    pub samples: usize,
    pub wall_time_s: f64,
    pub overhead_s: f64,
    pub rmse: f32,
    pub relmse: f32,
    /// Mean LDR-FLIP on the shared tone mapping.
    pub flip: f32,
    /// Reference time / run time; `None` when the run took no measurable time.
    pub speedup_vs_reference: Option<f64>,
}

/// Samples per pixel for a uniform render that takes about `target_time_s`, given
/// that the reference took `reference_time_s` for `reference_spp` (render time is
/// close to linear in spp): `floor(target / reference · spp)`, at least 1. The
/// caller should still report the *measured* time of the baseline.
pub fn equal_time_spp(target_time_s: f64, reference_time_s: f64, reference_spp: u32) -> u32 {
    if !(target_time_s > 0.0 && reference_time_s > 0.0) {
        return 1;
    }
    let spp = (target_time_s / reference_time_s * f64::from(reference_spp)).floor();
    // `as` saturates: a huge ratio gives u32::MAX, NaN cannot occur here.
    (spp as u32).max(1)
}

/// Checks the input and measures every run; nothing is written.
pub fn compute_rows(input: &ReportInput) -> Result<Vec<ReportRow>> {
    validate(input, Path::new("report"))?;
    rows(input, Path::new("report"))
}

/// Writes `report.html`, `report.json`, `report.md` and `report-assets/` into `dir`
/// (created if missing) and returns the table rows. On any error nothing in `dir`
/// is created or replaced.
pub fn write_report(dir: &Path, input: &ReportInput) -> Result<Vec<ReportRow>> {
    let html_path = dir.join("report.html");
    validate(input, &html_path)?;
    let rows = rows(input, &html_path)?;
    let fail = |m: String| output_error(&html_path, m);
    let (w, h) = (input.width, input.height);

    // Every asset as (file name, bytes); PNG bytes are also embedded in the HTML.
    let mut assets: Vec<(String, Vec<u8>)> = Vec::new();
    let reference8 = metrics::tone_map_srgb8(&input.reference, input.exposure)?;
    assets.push((
        "reference.png".into(),
        png_bytes(&reference8, w, h).map_err(fail)?,
    ));

    let ref_lum: Vec<f32> = input.reference.iter().map(|c| luminance(*c)).collect();
    let errors: Vec<Vec<f32>> = input
        .runs
        .iter()
        .map(|r| {
            r.image
                .iter()
                .zip(&ref_lum)
                .map(|(c, l)| (luminance(*c) - l).abs())
                .collect()
        })
        .collect();
    let error_scale = shared_error_scale(&errors);

    let mut cards = Vec::with_capacity(input.runs.len());
    for (i, (run, err)) in input.runs.iter().zip(&errors).enumerate() {
        let stem = format!("run-{i:02}-{}", slug(&run.label));
        let img8 = metrics::tone_map_srgb8(&run.image, input.exposure)?;
        let image = format!("{stem}.png");
        assets.push((image.clone(), png_bytes(&img8, w, h).map_err(fail)?));
        let error = format!("{stem}-error.png");
        assets.push((
            error.clone(),
            png_bytes(&error_map(err, error_scale), w, h).map_err(fail)?,
        ));
        let samples = if run.sample_positions.is_empty() {
            None
        } else {
            let name = format!("{stem}-samples.png");
            let map = sample_map(&reference8, w, h, &run.sample_positions);
            assets.push((name.clone(), png_bytes(&map, w, h).map_err(fail)?));
            Some(name)
        };
        cards.push(Card {
            image,
            error,
            samples,
        });
    }

    let plots = speed_plots(input, &rows).map_err(fail)?;
    for (name, svg) in &plots {
        assets.push((name.clone(), svg.as_bytes().to_vec()));
    }

    let html = html(input, &rows, &cards, &assets, &plots, error_scale);
    let markdown = markdown(input, &rows, &cards, &plots);
    let json = json(input, &rows, error_scale).map_err(fail)?;

    // Stage everything, then commit: a failure before the first rename leaves the
    // old report (if any) intact; the staged temporaries are removed on drop.
    let asset_dir = dir.join(ASSET_DIR);
    std::fs::create_dir_all(&asset_dir)
        .map_err(|e| output_error(&asset_dir, format!("cannot create the directory: {e}")))?;
    let mut staged: Vec<Staged> = Vec::new();
    for (name, bytes) in &assets {
        staged.push(stage_bytes(&asset_dir.join(name), bytes)?);
    }
    staged.push(stage_bytes(&dir.join("report.json"), json.as_bytes())?);
    staged.push(stage_bytes(&dir.join("report.md"), markdown.as_bytes())?);
    // The HTML last, so that a reader who sees the new report sees its assets.
    staged.push(stage_bytes(&html_path, html.as_bytes())?);
    for s in staged {
        s.commit()?;
    }
    Ok(rows)
}

/// File names of one run's images inside [`ASSET_DIR`].
struct Card {
    image: String,
    error: String,
    samples: Option<String>,
}

fn validate(input: &ReportInput, path: &Path) -> Result<()> {
    let err = |m: String| Err(output_error(path, m));
    let (w, h) = (input.width, input.height);
    let n = match w.checked_mul(h) {
        Some(n) if n > 0 && u32::try_from(w).is_ok() && u32::try_from(h).is_ok() => n,
        _ => return err(format!("invalid resolution {w}x{h}")),
    };
    if input.reference.len() != n {
        return err(format!(
            "the reference has {} pixels, expected {w}x{h} = {n}",
            input.reference.len()
        ));
    }
    if !input.exposure.is_finite() {
        return err(format!("exposure must be finite, got {}", input.exposure));
    }
    if !(input.reference_time_s.is_finite() && input.reference_time_s >= 0.0) {
        return err(format!("invalid reference time {}", input.reference_time_s));
    }
    if let Some(i) = input.reference.iter().position(|p| !p.is_finite()) {
        return err(format!(
            "non-finite reference pixel at ({}, {})",
            i % w,
            i / w
        ));
    }
    for run in &input.runs {
        let what = format!("run {:?} ({})", run.label, run.kind.short());
        if run.image.len() != n {
            return err(format!(
                "{what} has {} pixels, expected {w}x{h} = {n}",
                run.image.len()
            ));
        }
        if let Some(i) = run.image.iter().position(|p| !p.is_finite()) {
            return err(format!(
                "{what}: non-finite pixel at ({}, {})",
                i % w,
                i / w
            ));
        }
        for t in [run.wall_time_s, run.overhead_s] {
            if !(t.is_finite() && t >= 0.0) {
                return err(format!("{what}: invalid time {t}"));
            }
        }
        if let Some(b) = run.kind.budget() {
            if !(b > 0.0 && b <= 16.0) {
                return err(format!(
                    "{what}: budget must lie in (0, 16] samples per pixel, got {b}"
                ));
            }
        }
        let inside = |p: &Vec2| {
            p.is_finite() && p.x >= 0.0 && p.y >= 0.0 && p.x <= w as f32 && p.y <= h as f32
        };
        if let Some(p) = run.sample_positions.iter().find(|p| !inside(p)) {
            return err(format!(
                "{what}: sample position {p} lies outside [0, {w}] x [0, {h}]"
            ));
        }
    }
    Ok(())
}

fn rows(input: &ReportInput, path: &Path) -> Result<Vec<ReportRow>> {
    let (w, h) = (input.width, input.height);
    let wrap = |e: crate::Error| output_error(path, e.to_string());
    input
        .runs
        .iter()
        .map(|run| {
            Ok(ReportRow {
                label: run.label.clone(),
                kind: run.kind.name().into(),
                budget: run.kind.budget(),
                spp: match run.kind {
                    RunKind::EqualTime { spp } => Some(spp),
                    _ => None,
                },
                samples: run.samples,
                wall_time_s: run.wall_time_s,
                overhead_s: run.overhead_s,
                rmse: metrics::rmse(&run.image, &input.reference).map_err(wrap)?,
                relmse: metrics::relmse(&run.image, &input.reference).map_err(wrap)?,
                flip: metrics::flip_exposure(&run.image, &input.reference, w, h, input.exposure)
                    .map_err(wrap)?,
                speedup_vs_reference: (run.wall_time_s > 0.0)
                    .then(|| input.reference_time_s / run.wall_time_s),
            })
        })
        .collect()
}

/// The luminance error that maps to the top of the colour scale, shared by all
/// runs so that their maps compare: the largest per-run 99th percentile (a
/// maximum would let a few firefly pixels make every map black).
fn shared_error_scale(errors: &[Vec<f32>]) -> f32 {
    let p99 = |e: &Vec<f32>| {
        let mut v = e.clone();
        let k = ((v.len() as f64 * 0.99) as usize).min(v.len() - 1);
        *v.select_nth_unstable_by(k, f32::total_cmp).1
    };
    let s = errors
        .iter()
        .filter(|e| !e.is_empty())
        .map(p99)
        .fold(0.0_f32, f32::max);
    if s > 0.0 && s.is_finite() {
        s
    } else {
        1.0
    }
}

/// |Δ luminance| / scale through viridis, as 8-bit RGB.
fn error_map(err: &[f32], scale: f32) -> Vec<u8> {
    err.iter().flat_map(|e| viridis8(e / scale)).collect()
}

/// Sample dots over the reference dimmed to 35 % (Fig. 14/15 style): each sample
/// colours the pixel it falls in.
fn sample_map(reference8: &[u8], w: usize, h: usize, positions: &[Vec2]) -> Vec<u8> {
    let mut out: Vec<u8> = reference8
        .iter()
        .map(|&c| (f32::from(c) * 0.35).round() as u8)
        .collect();
    for p in positions {
        // Positions on the right/bottom border belong to the last pixel.
        let i = (p.x as usize).min(w - 1);
        let j = (p.y as usize).min(h - 1);
        out[3 * (j * w + i)..3 * (j * w + i) + 3].copy_from_slice(&[255, 96, 32]);
    }
    out
}

fn png_bytes(rgb8: &[u8], w: usize, h: usize) -> std::result::Result<Vec<u8>, String> {
    let mut out = Vec::new();
    PngEncoder::new(&mut out)
        .write_image(rgb8, w as u32, h as u32, ExtendedColorType::Rgb8)
        .map_err(|e| format!("PNG encoder: {e}"))?;
    Ok(out)
}

fn stage_bytes(path: &Path, bytes: &[u8]) -> Result<Staged> {
    stage(path, |out| out.write_all(bytes).map_err(|e| e.to_string()))
}

/// Wall time against RMSE and against FLIP, one line per label (plot file name, SVG).
fn speed_plots(
    input: &ReportInput,
    rows: &[ReportRow],
) -> std::result::Result<Vec<(String, String)>, String> {
    let mut labels: Vec<&str> = Vec::new();
    for r in &input.runs {
        if !labels.contains(&r.label.as_str()) {
            labels.push(&r.label);
        }
    }
    let series = |metric: fn(&ReportRow) -> f64| -> Vec<Series> {
        labels
            .iter()
            .map(|l| Series {
                name: (*l).to_string(),
                points: input
                    .runs
                    .iter()
                    .zip(rows)
                    .filter(|(run, _)| run.label == *l)
                    .map(|(run, row)| (row.wall_time_s, metric(row), run.kind.short()))
                    .collect(),
            })
            .collect()
    };
    let title = |m: &str| format!("{}: wall time vs {m}", input.scene);
    Ok(vec![
        (
            "speed_rmse.svg".into(),
            loglog_svg(
                &title("RMSE"),
                "wall time (s)",
                "RMSE",
                &series(|r| f64::from(r.rmse)),
            )?,
        ),
        (
            "speed_flip.svg".into(),
            loglog_svg(
                &title("FLIP"),
                "wall time (s)",
                "mean FLIP",
                &series(|r| f64::from(r.flip)),
            )?,
        ),
    ])
}

fn json(
    input: &ReportInput,
    rows: &[ReportRow],
    error_scale: f32,
) -> std::result::Result<String, String> {
    let value = serde_json::json!({
        "scene": input.scene,
        "width": input.width,
        "height": input.height,
        "reference_spp": input.reference_spp,
        "reference_time_s": input.reference_time_s,
        "exposure": input.exposure,
        "relmse_eps": RELMSE_EPS,
        "flip": { "variant": "LDR-FLIP (flip-rs, FLIP v1.7)", "pixels_per_degree": FLIP_PPD,
                  "input": "8-bit sRGB of linear x 2^exposure, as the PNGs" },
        "error_map_scale": error_scale,
        "rows": rows,
        "notes": input.notes,
    });
    serde_json::to_string_pretty(&value).map_err(|e| e.to_string())
}

/// The summary table as Markdown (also what goes into closing notes; the CLI can
/// print it).
pub fn markdown_table(rows: &[ReportRow]) -> String {
    let mut s = String::from(
        "| strategy | kind | budget | samples | wall time (s) | overhead (s) | RMSE | relMSE | FLIP | speed-up vs full |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.3} | {:.3} | {:.4e} | {:.4e} | {:.4} | {} |",
            r.label.replace('|', "\\|"),
            r.kind,
            budget_text(r),
            r.samples,
            r.wall_time_s,
            r.overhead_s,
            r.rmse,
            r.relmse,
            r.flip,
            r.speedup_vs_reference
                .map_or("–".into(), |v| format!("{v:.1}×")),
        );
    }
    s
}

fn budget_text(r: &ReportRow) -> String {
    match (r.budget, r.spp) {
        (Some(b), _) => percent(b),
        (None, Some(spp)) => format!("{spp} spp"),
        _ => "–".into(),
    }
}

fn markdown(
    input: &ReportInput,
    rows: &[ReportRow],
    cards: &[Card],
    plots: &[(String, String)],
) -> String {
    let mut s = format!("# Strategy comparison: {}\n\n", input.scene);
    let _ = writeln!(s, "{}\n", meta_line(input));
    s += &markdown_table(rows);
    s += "\n";
    for (name, _) in plots {
        let _ = writeln!(s, "![{name}]({ASSET_DIR}/{name})");
    }
    let _ = writeln!(s, "\n![reference]({ASSET_DIR}/reference.png)\n");
    for (run, card) in input.runs.iter().zip(cards) {
        let _ = write!(
            s,
            "- {} ({}): [image]({ASSET_DIR}/{}) · [error]({ASSET_DIR}/{})",
            run.label,
            run.kind.short(),
            card.image,
            card.error
        );
        if let Some(m) = &card.samples {
            let _ = write!(s, " · [samples]({ASSET_DIR}/{m})");
        }
        s += "\n";
    }
    if !input.notes.is_empty() {
        s += "\n## Notes\n\n";
        for n in &input.notes {
            let _ = writeln!(s, "- {n}");
        }
    }
    s
}

fn meta_line(input: &ReportInput) -> String {
    format!(
        "{}×{} pixels; reference {} spp in {:.1} s; exposure {:+} stops; relMSE ε = {}; \
         FLIP: LDR-FLIP at {:.1} pixels/degree on the displayed 8-bit sRGB.",
        input.width,
        input.height,
        input.reference_spp,
        input.reference_time_s,
        input.exposure,
        RELMSE_EPS,
        FLIP_PPD
    )
}

const CSS: &str = "body{font-family:sans-serif;margin:1.5em;color:#222;max-width:110em}\
table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:.25em .6em;text-align:right}\
td:first-child,th:first-child,td:nth-child(2){text-align:left}th{background:#eee}\
.grid{display:flex;flex-wrap:wrap;gap:1.2em}.card{flex:1 1 40em;border:1px solid #ccc;padding:.6em;border-radius:4px}\
.imgs{display:flex;gap:.4em;flex-wrap:wrap}figure{margin:0;flex:1 1 0;min-width:10em}figcaption{font-size:.8em;color:#555}\
img{image-rendering:pixelated;max-width:100%;height:auto}.plots{display:flex;flex-wrap:wrap;gap:1em}";

fn html(
    input: &ReportInput,
    rows: &[ReportRow],
    cards: &[Card],
    assets: &[(String, Vec<u8>)],
    plots: &[(String, String)],
    error_scale: f32,
) -> String {
    let data = |name: &str| {
        let bytes = assets
            .iter()
            .find(|(n, _)| n == name)
            .map_or(&[][..], |(_, b)| b);
        format!("data:image/png;base64,{}", base64(bytes))
    };
    let (w, h) = (input.width, input.height);
    let img = |name: &str, alt: &str| {
        format!(
            "<figure style=\"max-width:{w}px\"><img width=\"{w}\" height=\"{h}\" alt=\"{a}\" src=\"{}\"><figcaption>{a}</figcaption></figure>",
            data(name),
            a = esc(alt)
        )
    };
    let mut s = String::new();
    let _ = write!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>gradtrace compare: {0}</title>\
         <style>{CSS}</style></head><body>\n<h1>Strategy comparison: {0}</h1>\n<p>{1}</p>\n",
        esc(&input.scene),
        esc(&meta_line(input))
    );

    s += "<h2>Summary</h2>\n<table><tr><th>strategy</th><th>kind</th><th>budget</th><th>samples</th>\
          <th>wall time (s)</th><th>overhead (s)</th><th>RMSE</th><th>relMSE</th><th>FLIP</th><th>speed-up vs full</th></tr>\n";
    for r in rows {
        let _ = writeln!(
            s,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.3}</td><td>{:.3}</td><td>{:.4e}</td>\
             <td>{:.4e}</td><td>{:.4}</td><td>{}</td></tr>",
            esc(&r.label),
            r.kind,
            budget_text(r),
            r.samples,
            r.wall_time_s,
            r.overhead_s,
            r.rmse,
            r.relmse,
            r.flip,
            r.speedup_vs_reference.map_or("–".into(), |v| format!("{v:.1}×"))
        );
    }
    s += "</table>\n<p>Adaptive rows compare strategies at equal sample count; equal-time rows render every \
          pixel uniformly with fewer samples per pixel in about the same wall time, the honest baseline for \
          any claimed speed-up.</p>\n";

    s += "<h2>Speed against error</h2>\n<p>Log-log; one line per strategy, points labelled by budget.</p>\n<div class=\"plots\">\n";
    for (_, svg) in plots {
        s += &inline_svg(svg);
        s += "\n";
    }
    s += "</div>\n";

    s += "<h2>Reference</h2>\n";
    s += &img(
        "reference.png",
        &format!("reference, {} spp", input.reference_spp),
    );
    let _ = write!(
        s,
        "\n<h3>Error-map scale</h3>\n<p>|luminance(run) − luminance(reference)|, linear units, shared by all maps.</p>\n{}\n",
        legend_svg(error_scale)
    );

    // (kind name, heading, explanation)
    let sections = [
        ("adaptive", "Adaptive sampling (equal sample count)", ""),
        (
            "equal-time",
            "Equal-time baselines",
            "Uniform rendering of every pixel with fewer samples per pixel, at about the wall time of an adaptive run.",
        ),
        (
            "interpolation",
            "Gradient vs linear interpolation (Sec. 8)",
            "The same sparse samples reconstructed with and without the analytic gradients.",
        ),
    ];
    for (kind, title, blurb) in sections {
        let members: Vec<usize> = (0..input.runs.len())
            .filter(|&i| input.runs[i].kind.name() == kind)
            .collect();
        if members.is_empty() {
            continue;
        }
        let _ = writeln!(s, "<h2>{title}</h2>");
        if !blurb.is_empty() {
            let _ = writeln!(s, "<p>{blurb}</p>");
        }
        s += "<div class=\"grid\">\n";
        for i in members {
            let (run, row, card) = (&input.runs[i], &rows[i], &cards[i]);
            let name = format!("{} ({})", run.label, run.kind.short());
            let _ = write!(
                s,
                "<div class=\"card\"><h3>{}</h3><p>{} samples, {:.3} s; RMSE {:.4e}, relMSE {:.4e}, FLIP {:.4}</p><div class=\"imgs\">",
                esc(&name),
                row.samples,
                row.wall_time_s,
                row.rmse,
                row.relmse,
                row.flip
            );
            s += &img(&card.image, &name);
            s += &img(&card.error, "error map");
            if let Some(m) = &card.samples {
                s += &img(
                    m,
                    &format!("{} sample positions", run.sample_positions.len()),
                );
            }
            s += "</div></div>\n";
        }
        s += "</div>\n";
    }

    if !input.notes.is_empty() {
        s += "<h2>Notes</h2>\n<ul>\n";
        for n in &input.notes {
            let _ = writeln!(s, "<li>{}</li>", esc(n));
        }
        s += "</ul>\n";
    }
    s += "</body></html>\n";
    s
}

/// An SVG document made fit for inline HTML: the XML declaration and the
/// namespace attribute are dropped (HTML parsers put `<svg>` in the SVG namespace
/// themselves), which also keeps the report free of any `http` reference.
fn inline_svg(svg: &str) -> String {
    let body = match svg.find("<svg") {
        Some(i) => &svg[i..],
        None => svg,
    };
    body.replace(" xmlns=\"http://www.w3.org/2000/svg\"", "")
}

/// Horizontal viridis bar from 0 to `scale` with five ticks.
fn legend_svg(scale: f32) -> String {
    let mut s = String::from(
        "<svg width=\"420\" height=\"48\" viewBox=\"0 0 420 48\"><defs><linearGradient id=\"viridis\">",
    );
    for k in 0..=16 {
        let t = k as f32 / 16.0;
        let _ = write!(
            s,
            "<stop offset=\"{t}\" stop-color=\"{}\"/>",
            viridis_hex(t)
        );
    }
    s += "</linearGradient></defs><rect x=\"10\" y=\"4\" width=\"400\" height=\"18\" fill=\"url(#viridis)\" stroke=\"#444\"/>";
    for k in 0..=4 {
        let x = 10.0 + 100.0 * k as f32;
        let v = scale * k as f32 / 4.0;
        let anchor = match k {
            0 => "start",
            4 => "end",
            _ => "middle",
        };
        let _ = write!(
            s,
            "<line x1=\"{x}\" y1=\"22\" x2=\"{x}\" y2=\"27\" stroke=\"#444\"/>\
             <text x=\"{x}\" y=\"40\" font-size=\"12\" text-anchor=\"{anchor}\" font-family=\"sans-serif\">{}{v:.3e}</text>",
            if k == 4 { "≥ " } else { "" }
        );
    }
    s += "</svg>";
    s
}

/// Budget in samples per pixel as a percentage of the pixels: 0.05 → "5%".
fn percent(budget: f32) -> String {
    let p = f64::from(budget) * 100.0;
    let s = format!("{p:.2}");
    format!("{}%", s.trim_end_matches('0').trim_end_matches('.'))
}

/// File-name-safe form of a label.
fn slug(label: &str) -> String {
    let s: String = label
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .take(40)
        .collect();
    if s.is_empty() {
        "run".into()
    } else {
        s
    }
}

/// Minimal HTML escaping for text and attribute values.
fn esc(text: &str) -> String {
    let mut s = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => s += "&amp;",
            '<' => s += "&lt;",
            '>' => s += "&gt;",
            '"' => s += "&quot;",
            '\'' => s += "&#39;",
            c => s.push(c),
        }
    }
    s
}

/// Standard base64 (RFC 4648, with padding) for the `data:` URIs.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}
