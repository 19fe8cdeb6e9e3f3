//! reference + runs → `report.html`, `report.json`, `report.md` and the image
//! assets they show, for `gradtrace compare`.
//!
//! Nothing here renders: the caller hands over the reference and every run's image,
//! timings and sample positions, each run possibly repeated with several seeds. This
//! module measures them (RMSE, relMSE, relMSE without the 0.01 % worst pixels,
//! FLIP on one shared tone mapping, see [`super::metrics`]), reports each run as the
//! mean over its seeds with a 95 % interval, draws false-colour error maps,
//! sample-position maps in the style of the paper's Fig. 14/15 and log-log
//! speed-against-error plots with error bars, and writes everything atomically: all
//! files are staged first and only then renamed into place, so invalid input or a
//! failed encoder leaves the directory untouched.
//!
//! The report is one output set (`super::atomic::StagedSet`) under one render id:
//! its assets go to a fresh folder `report-assets/<id>/`, then `report.md`,
//! `report.html` and, last, `report.json` (the index: the id and every file) are
//! renamed into place, and only then are the asset folders of other ids removed.
//! A report thus never links another run's assets, two compares into one folder
//! never mix them, and a kill leaves at most one stale folder, swept by the next
//! report. (Swapping a whole staged folder in with `renameat2(RENAME_EXCHANGE)`
//! would be atomic too, but would also swap out the cached reference and kept
//! EXRs that live beside the report, and needs Linux 3.15 and a file system
//! that supports it.)
//!
//! The HTML links its images (JPEG files under `report-assets/<id>/`) and
//! inlines its plots as SVG, with no external CSS, scripts or fonts: the folder can
//! be copied or mailed whole and opened offline.

use super::atomic::{output_error, SetIdHasher, StagedSet};
use super::colormap::{viridis8, viridis_hex};
use super::metrics::{self, luminance, FLIP_PPD, RELMSE_EPS, TRIM_FRACTION};
use super::plot::{loglog_svg, Series};
use crate::math::{Vec2, Vec3};
use crate::Result;
use image::codecs::jpeg::JpegEncoder;
use image::ExtendedColorType;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// Folder (inside the report directory) for the image files.
pub const ASSET_DIR: &str = "report-assets";

/// JPEG quality of the report's images: visually lossless at this size, and a
/// report of a few dozen images stays under 5 MB.
const JPEG_QUALITY: u8 = 90;

/// How a run spent its samples, which decides what it is compared with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RunKind {
    /// Adaptive sampling at `budget` samples per pixel (0.05 = 5 % of the pixels),
    /// `spp` camera samples per evaluated point; strategies compare at equal
    /// sample count. Budgets are f64 as the user wrote them, so that `report.json`
    /// prints 0.17, not a widened f32.
    Adaptive { budget: f64, spp: u32 },
    /// What a user would run instead, every pixel rendered (uniformly, adaptively
    /// per pixel, or denoised), at about the wall time of the `gradient` strategy
    /// at `budget`: the equal-time comparison. `spp`: samples per pixel (mean).
    Baseline { budget: f64, spp: u32 },
    /// Every pixel at `spp`, the same samples per point as the adaptive runs.
    Full { spp: u32 },
    /// An interpolation experiment at `budget` samples per pixel, `spp` per point
    /// (Sec. 8: gradient vs linear interpolation of soft shadows).
    Interpolation { budget: f64, spp: u32 },
    /// An approximate preview (`shadow-field`, `glossy`): its cost is one frame,
    /// its `precompute_s` (as first computed, also when cached) stands apart.
    Preview { precompute_s: f64, cached: bool },
}

/// What an equal-cost run is matched on: the wall time (what a user waits on an
/// idle machine) or the process CPU time, user + system, which other jobs on a
/// shared machine leave nearly untouched (`compare --equal`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EqualCost {
    #[default]
    Wall,
    Cpu,
}

impl EqualCost {
    /// As `report.json` and `--equal` spell it.
    pub fn name(self) -> &'static str {
        match self {
            EqualCost::Wall => "wall",
            EqualCost::Cpu => "cpu",
        }
    }

    /// A run's cost in this measure.
    pub fn of(self, wall_s: f64, cpu_s: f64) -> f64 {
        match self {
            EqualCost::Wall => wall_s,
            EqualCost::Cpu => cpu_s,
        }
    }

    /// "wall time" or "CPU time", for sentences and axis labels.
    pub fn label(self) -> &'static str {
        match self {
            EqualCost::Wall => "wall time",
            EqualCost::Cpu => "CPU time",
        }
    }
}

impl RunKind {
    /// Stable machine name, as in `report.json`.
    pub fn name(self) -> &'static str {
        match self {
            RunKind::Adaptive { .. } => "adaptive",
            RunKind::Baseline { .. } => "baseline",
            RunKind::Full { .. } => "full",
            RunKind::Interpolation { .. } => "interpolation",
            RunKind::Preview { .. } => "preview",
        }
    }

    /// The budget an adaptive or interpolation run spends (`null` for the others).
    fn budget(self) -> Option<f64> {
        match self {
            RunKind::Adaptive { budget, .. } | RunKind::Interpolation { budget, .. } => {
                Some(budget)
            }
            _ => None,
        }
    }

    /// The budget whose time a run is measured against (adaptive and baselines).
    fn group(self) -> Option<f64> {
        match self {
            RunKind::Adaptive { budget, .. } | RunKind::Baseline { budget, .. } => Some(budget),
            _ => None,
        }
    }

    /// Camera samples per evaluated point (adaptive, interpolation) or per pixel;
    /// 0 for a preview, which takes no path-traced samples.
    pub fn spp(self) -> u32 {
        match self {
            RunKind::Adaptive { spp, .. }
            | RunKind::Baseline { spp, .. }
            | RunKind::Full { spp }
            | RunKind::Interpolation { spp, .. } => spp,
            RunKind::Preview { .. } => 0,
        }
    }

    /// A preview's precompute seconds (`null` for the others).
    fn precompute_s(self) -> Option<f64> {
        match self {
            RunKind::Preview { precompute_s, .. } => Some(precompute_s),
            _ => None,
        }
    }

    /// Short text for tables and plot points: "5%" or "4 spp".
    fn short(self) -> String {
        match self {
            RunKind::Adaptive { budget, .. } | RunKind::Interpolation { budget, .. } => {
                percent(budget)
            }
            RunKind::Baseline { spp, .. } | RunKind::Full { spp } => format!("{spp} spp"),
            RunKind::Preview { .. } => PER_FRAME.into(),
        }
    }
}

/// A preview row's setting: its time is one frame's.
const PER_FRAME: &str = "per frame";

/// One image produced by one method at one setting with one seed.
#[derive(Clone, Debug)]
pub struct Run {
    /// Method name, e.g. "gradient", "uniform-all-pixels", "cycles-adaptive". Runs
    /// with the same name and kind are the seeds of one report row, and one line in
    /// the speed-against-error plots.
    pub name: String,
    pub kind: RunKind,
    /// Which repetition (0-based); every repetition has independent random numbers.
    pub seed: u32,
    /// Number of image samples evaluated (for full renders: pixels × spp).
    pub samples: usize,
    /// Total wall time of the run in seconds, overhead included.
    pub wall_time_s: f64,
    /// The process CPU time (user + system, every thread) the run took, over the
    /// same span as `wall_time_s`.
    pub cpu_time_s: f64,
    /// The part of `wall_time_s` spent outside the renderer (quadtree and
    /// reconstruction, or the denoiser).
    pub overhead_s: f64,
    /// For a run meant to take the time of another (the baselines, `gradient+oidn`):
    /// that run's cost at the same seed (in [`ReportInput::equal_cost`]'s measure),
    /// which its own is measured against.
    pub target_s: Option<f64>,
    /// Linear RGB, row-major, top row first, `width × height` pixels.
    pub image: Vec<Vec3>,
    /// Sample positions in continuous pixel coordinates (`[0, W] × [0, H]`, origin
    /// top left, as in `adaptive`); empty for full renders.
    pub sample_positions: Vec<Vec2>,
}

/// How the reference was obtained.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReferenceInfo {
    pub spp: u32,
    /// Its render time when it was rendered (also when reused from the cache).
    pub time_s: f64,
    /// The content key of the cached file: scene, assets, settings, renderer version.
    pub cache_key: String,
    /// Whether this run reused the cached file.
    pub reused: bool,
}

/// Everything the report shows.
#[derive(Clone, Debug)]
pub struct ReportInput {
    pub scene: String,
    /// `Scene::content_hash`: the scene file and every file it references.
    pub scene_hash: String,
    /// The command line that produced the report.
    pub command: String,
    /// Crate version and git commit.
    pub version: String,
    pub threads: usize,
    /// What the baselines' time was matched on (and `target_s` is measured in).
    pub equal_cost: EqualCost,
    pub width: usize,
    pub height: usize,
    /// The high-quality reference, linear RGB.
    pub reference: Vec<Vec3>,
    pub reference_info: ReferenceInfo,
    /// Display exposure in stops, used for every image *and* for FLIP (0 = none).
    pub exposure: f32,
    pub runs: Vec<Run>,
    /// Images for every budget (default: the headline budget's, the full render's
    /// and the interpolation runs', first seed only, so the report stays small).
    pub all_images: bool,
    /// Free text shown at the end (setup, caveats).
    pub notes: Vec<String>,
}

/// One row of the tables and of `report.json`'s `runs`: a method at one setting,
/// its figures the mean over its seeds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReportRow {
    /// Method name (strategy or baseline).
    pub name: String,
    /// "adaptive", "baseline", "full" or "interpolation".
    pub kind: String,
    /// Samples per pixel of an adaptive / interpolation run (0.05 = 5 %); null for
    /// baselines and full renders.
    pub budget: Option<f64>,
    /// For adaptive runs and baselines: the budget of the `gradient` run whose
    /// wall time the baselines match.
    pub equal_time_budget: Option<f64>,
    pub seeds: u32,
    /// Camera samples per evaluated point (adaptive, interpolation) or per pixel
    /// (baselines — the mean for per-pixel adaptive ones — and full renders).
    pub spp: u32,
    /// Camera samples per image pixel, what the run spent: samples × spp / pixels
    /// for adaptive and interpolation runs, samples / pixels for the others.
    pub spp_per_pixel: f64,
    pub samples: usize,
    /// Wall seconds (a preview: one frame), mean over the seeds.
    pub wall_s: f64,
    /// Process CPU seconds over the same span, mean over the seeds.
    pub cpu_s: f64,
    /// A preview's precompute (as first computed, also when cached); null otherwise.
    pub precompute_s: Option<f64>,
    /// Whether that precompute came from the cache; null for the others.
    pub precompute_cached: Option<bool>,
    pub overhead_s: f64,
    /// For runs meant to take another's time (baselines, `gradient+oidn`): the
    /// seeds' largest relative deviation from that cost (wall or CPU, as the report's
    /// `equal_cost`), signed (0.12 = 12 % longer).
    pub time_vs_target: Option<f64>,
    /// Whether `time_vs_target` lies within ±[`EQUAL_TIME_TOLERANCE`]; rows where it
    /// does not are marked in the tables. Null where there is no target.
    pub equal_time: Option<bool>,
    pub rmse: f32,
    /// Half-width of the 95 % interval of the mean RMSE over the seeds (Student t);
    /// null with one seed.
    pub rmse_ci95: Option<f32>,
    pub relmse: f32,
    /// relMSE without the [`TRIM_FRACTION`] pixels of highest error.
    pub relmse_trimmed: f32,
    /// Mean LDR-FLIP on the shared tone mapping.
    pub flip: f32,
    /// As `rmse_ci95`, for FLIP.
    pub flip_ci95: Option<f32>,
}

/// How far an equal-time run's wall time may stray from its target before its
/// row is marked: beyond it, "equal time" would be a claim the timings do not back.
pub const EQUAL_TIME_TOLERANCE: f64 = 0.05;

/// The mark of such a row, explained under each table.
const OFF_TIME_MARK: &str = "†";

/// The figures of one run (one seed).
#[derive(Clone, Copy, Debug)]
struct Measured {
    rmse: f32,
    relmse: f32,
    relmse_trimmed: f32,
    flip: f32,
}

/// Two-sided 95 % Student-t quantiles for 1..=30 degrees of freedom (then 1.96).
const T95: [f64; 30] = [
    12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
    2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
    2.052, 2.048, 2.045, 2.042,
];

/// Mean and the half-width of its 95 % interval (None for fewer than 2 values).
pub fn mean_ci95(values: &[f64]) -> (f64, Option<f64>) {
    let n = values.len();
    let mean = values.iter().sum::<f64>() / n.max(1) as f64;
    if n < 2 {
        return (mean, None);
    }
    let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1) as f64;
    let t = T95.get(n - 2).copied().unwrap_or(1.96);
    (mean, Some(t * (var / n as f64).sqrt()))
}

/// Checks the input and measures every run; nothing is written.
pub fn compute_rows(input: &ReportInput) -> Result<Vec<ReportRow>> {
    validate(input, Path::new("report"))?;
    let measured = measure(input, Path::new("report"))?;
    Ok(summarise(input, &measured))
}

/// Writes `report.html`, `report.json`, `report.md` and `report-assets/<id>/` into `dir`
/// (created if missing) and returns the rows. On any error nothing in `dir` is
/// created or replaced.
pub fn write_report(dir: &Path, input: &ReportInput) -> Result<Vec<ReportRow>> {
    write_report_with(dir, input, |_| Ok(()))
}

/// [`write_report`] with more members of the set (`compare --keep-exr`'s EXRs),
/// which `extra` stages under the report's id; they are renamed before the pages.
pub fn write_report_with(
    dir: &Path,
    input: &ReportInput,
    extra: impl FnOnce(&mut StagedSet) -> Result<()>,
) -> Result<Vec<ReportRow>> {
    let html_path = dir.join("report.html");
    validate(input, &html_path)?;
    let measured = measure(input, &html_path)?;
    let rows = summarise(input, &measured);
    let fail = |m: String| output_error(&html_path, m);
    let (w, h) = (input.width, input.height);

    let mut assets: Vec<(String, Vec<u8>)> = Vec::new();
    let reference8 = metrics::tone_map_srgb8(&input.reference, input.exposure)?;
    assets.push((
        "reference.jpg".into(),
        jpeg_bytes(&reference8, w, h).map_err(fail)?,
    ));
    let ref_lum: Vec<f32> = input.reference.iter().map(|c| luminance(*c)).collect();
    let error_of = |run: &Run| -> Vec<f32> {
        run.image
            .iter()
            .zip(&ref_lum)
            .map(|(c, l)| (luminance(*c) - l).abs())
            .collect()
    };
    let shown = shown_runs(input);
    let errors: Vec<Vec<f32>> = shown.iter().map(|&i| error_of(&input.runs[i])).collect();
    // One colour scale per budget (and one for the full render, one for the
    // interpolation runs): a scale shared with a coarser budget would leave a fine
    // budget's maps uniformly dark.
    let mut scales: Vec<ErrorScale> = Vec::new();
    let card_scale: Vec<usize> = shown
        .iter()
        .map(|&i| {
            let (label, budget) = scale_group(input.runs[i].kind);
            match scales.iter().position(|g| g.label == label) {
                Some(k) => k,
                None => {
                    scales.push(ErrorScale {
                        label,
                        budget,
                        max: 0.0,
                    });
                    scales.len() - 1
                }
            }
        })
        .collect();
    for (k, scale) in scales.iter_mut().enumerate() {
        let members: Vec<&Vec<f32>> = errors
            .iter()
            .zip(&card_scale)
            .filter(|(_, &g)| g == k)
            .map(|(e, _)| e)
            .collect();
        scale.max = error_scale(&members);
    }
    let mut cards = Vec::with_capacity(shown.len());
    for ((&i, err), &scale) in shown.iter().zip(&errors).zip(&card_scale) {
        let run = &input.runs[i];
        let stem = format!("run-{i:03}-{}", slug(&run.name));
        let img8 = metrics::tone_map_srgb8(&run.image, input.exposure)?;
        let image = format!("{stem}.jpg");
        assets.push((image.clone(), jpeg_bytes(&img8, w, h).map_err(fail)?));
        let error = format!("{stem}-error.jpg");
        let map = error_map(err, scales[scale].max);
        assets.push((error.clone(), jpeg_bytes(&map, w, h).map_err(fail)?));
        let samples = (!run.sample_positions.is_empty()).then(|| format!("{stem}-samples.png"));
        if let Some(name) = &samples {
            let map = sample_map(&reference8, w, h, &run.sample_positions);
            assets.push((name.clone(), png_bytes(&map, w, h).map_err(fail)?));
        }
        cards.push(Card {
            run: i,
            image,
            error,
            samples,
            scale,
        });
    }

    let plots = speed_plots(input, &rows).map_err(fail)?;
    for (name, svg) in &plots {
        assets.push((name.clone(), svg.clone().into_bytes()));
    }
    let json = json(input, &rows, &scales);
    // The id: every asset's bytes and the figures (which cover the pages).
    let mut hasher = SetIdHasher::new();
    for (name, bytes) in &assets {
        hasher.bytes(name.as_bytes()).bytes(bytes);
    }
    hasher.bytes(json.to_string().as_bytes());
    let id = hasher.finish();
    let prefix = format!("{ASSET_DIR}/{id}");
    let html = html(input, &rows, &cards, &plots, &scales, &prefix);
    let html = html.replacen("<html", &format!("<!-- render_id: {id} -->\n<html"), 1);
    let markdown = markdown(input, &rows, &cards, &scales, &prefix);
    let markdown = format!("{markdown}\n<!-- render_id: {id} -->\n");

    // Stage everything, then commit: a failure before the first rename leaves the
    // old report (if any) intact; the staged temporaries are removed on drop
    // (and the fresh asset folder with them, if this run made it).
    let asset_root = dir.join(ASSET_DIR);
    let asset_dir = asset_root.join(&id);
    let made_folder = !asset_dir.exists();
    std::fs::create_dir_all(&asset_dir)
        .map_err(|e| output_error(&asset_dir, format!("cannot create the directory: {e}")))?;
    let staged = (|| {
        let mut set = StagedSet::new(id.clone());
        for (name, bytes) in &assets {
            set.stage_bytes(&asset_dir.join(name), bytes)?;
        }
        extra(&mut set)?;
        set.stage_bytes(&dir.join("report.md"), markdown.as_bytes())?;
        set.stage_bytes(&html_path, html.as_bytes())?;
        // The index last: a reader who trusts it finds every file it lists.
        set.stage_index(&dir.join("report.json"), json)?;
        Ok::<_, crate::Error>(set)
    })();
    let set = match staged {
        Ok(set) => set,
        Err(e) => {
            if made_folder {
                let _ = std::fs::remove_dir(&asset_dir);
                let _ = std::fs::remove_dir(&asset_root);
            }
            return Err(e);
        }
    };
    set.commit()?;
    remove_other_assets(&asset_root, &id);
    Ok(rows)
}

/// Removes what other reports left under `report-assets/`: the folders of other
/// ids (a report whose index is replaced, or a killed run's) and the flat files
/// of the layout before ids. Best effort: a leftover is only disk space, never
/// linked by the report in place.
fn remove_other_assets(root: &Path, id: &str) {
    let Ok(entries) = std::fs::read_dir(root) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Ok(kind) = e.file_type() else {
            continue;
        };
        let ours = name.len() == 32 && name.bytes().all(|b| b.is_ascii_hexdigit());
        if kind.is_dir() && ours && name != id {
            let _ = std::fs::remove_dir_all(e.path());
        } else if kind.is_file()
            && [".jpg", ".png", ".svg"].iter().any(|x| name.ends_with(x))
            && !name.starts_with('.')
        {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// File names of one shown run's images inside [`ASSET_DIR`].
struct Card {
    run: usize,
    image: String,
    error: String,
    samples: Option<String>,
    /// Index of its error map's scale.
    scale: usize,
}

/// The colour scale of one group of error maps.
#[derive(Serialize)]
struct ErrorScale {
    /// "budget 17%", "full render" or "interpolation, 1%".
    #[serde(rename = "maps")]
    label: String,
    budget: Option<f64>,
    /// |Δ luminance| at the top of the scale.
    max: f32,
}

/// The error-scale group of a run and its budget.
fn scale_group(kind: RunKind) -> (String, Option<f64>) {
    match kind {
        RunKind::Adaptive { budget, .. } | RunKind::Baseline { budget, .. } => {
            (format!("budget {}", percent(budget)), Some(budget))
        }
        RunKind::Full { .. } => ("full render".into(), None),
        RunKind::Interpolation { budget, .. } => {
            (format!("interpolation, {}", percent(budget)), Some(budget))
        }
        RunKind::Preview { .. } => ("previews".into(), None),
    }
}

/// The budget the headline and the default images are about: the one closest to
/// 17 % (the paper's Fig. 14/15), among those with a `gradient` run.
fn headline_budget(input: &ReportInput) -> Option<f64> {
    input
        .runs
        .iter()
        .filter(|r| r.name == "gradient")
        .filter_map(|r| r.kind.group())
        .min_by(|a, b| (a - 0.17).abs().total_cmp(&(b - 0.17).abs()))
}

/// Indices of the runs whose images the report shows: the first seed of the
/// headline budget's runs (of every budget with `all_images`), of the full render
/// and of the interpolation runs.
fn shown_runs(input: &ReportInput) -> Vec<usize> {
    let head = headline_budget(input);
    (0..input.runs.len())
        .filter(|&i| {
            let r = &input.runs[i];
            r.seed == 0
                && match r.kind.group() {
                    Some(b) => input.all_images || Some(b) == head,
                    None => true,
                }
        })
        .collect()
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
    let t = input.reference_info.time_s;
    if !(t.is_finite() && t >= 0.0) {
        return err(format!("invalid reference time {t}"));
    }
    if let Some(i) = input.reference.iter().position(|p| !p.is_finite()) {
        return err(format!(
            "non-finite reference pixel at ({}, {})",
            i % w,
            i / w
        ));
    }
    for run in &input.runs {
        let what = format!("run {:?} ({})", run.name, run.kind.short());
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
        let precompute = run.kind.precompute_s().unwrap_or(0.0);
        for t in [run.wall_time_s, run.cpu_time_s, run.overhead_s, precompute] {
            if !(t.is_finite() && t >= 0.0) {
                return err(format!("{what}: invalid time {t}"));
            }
        }
        if let Some(b) = run.kind.budget().or(run.kind.group()) {
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

/// Every run's figures against the reference (in parallel: FLIP dominates).
fn measure(input: &ReportInput, path: &Path) -> Result<Vec<Measured>> {
    use rayon::prelude::*;
    let (w, h) = (input.width, input.height);
    let wrap = |e: crate::Error| output_error(path, e.to_string());
    let r = &input.reference;
    input
        .runs
        .par_iter()
        .map(|run| {
            Ok(Measured {
                rmse: metrics::rmse(&run.image, r).map_err(wrap)?,
                relmse: metrics::relmse(&run.image, r).map_err(wrap)?,
                relmse_trimmed: metrics::relmse_trimmed(&run.image, r, TRIM_FRACTION)
                    .map_err(wrap)?,
                flip: metrics::flip_exposure(&run.image, r, w, h, input.exposure).map_err(wrap)?,
            })
        })
        .collect()
}

/// One row per (name, kind): means over the seeds, in the order rows first appear.
fn summarise(input: &ReportInput, measured: &[Measured]) -> Vec<ReportRow> {
    let mut groups: Vec<(usize, Vec<usize>)> = Vec::new();
    for (i, run) in input.runs.iter().enumerate() {
        let same = |g: &(usize, Vec<usize>)| {
            let first = &input.runs[g.0];
            first.name == run.name
                && first.kind.name() == run.kind.name()
                && first.kind.budget() == run.kind.budget()
                && first.kind.group() == run.kind.group()
        };
        match groups.iter_mut().find(|g| same(g)) {
            Some(g) => g.1.push(i),
            None => groups.push((i, vec![i])),
        }
    }
    groups
        .iter()
        .map(|(first, members)| {
            let run = &input.runs[*first];
            let stat = |f: &dyn Fn(usize) -> f64| {
                mean_ci95(&members.iter().map(|&i| f(i)).collect::<Vec<_>>())
            };
            let (rmse, rmse_ci) = stat(&|i| f64::from(measured[i].rmse));
            let (flip, flip_ci) = stat(&|i| f64::from(measured[i].flip));
            let mean = |f: &dyn Fn(usize) -> f64| stat(f).0;
            let samples = mean(&|i| input.runs[i].samples as f64);
            let spp_mean = mean(&|i| f64::from(input.runs[i].kind.spp()));
            let pixels = (input.width * input.height) as f64;
            let spp_per_pixel = match run.kind {
                RunKind::Adaptive { .. } | RunKind::Interpolation { .. } => {
                    samples * spp_mean / pixels
                }
                _ => samples / pixels,
            };
            // The seed furthest from its target decides: a mean could hide a seed
            // at half the time behind one at one and a half.
            let time_vs_target = members
                .iter()
                .filter_map(|&i| {
                    let r = &input.runs[i];
                    r.target_s
                        .filter(|t| *t > 0.0)
                        .map(|t| input.equal_cost.of(r.wall_time_s, r.cpu_time_s) / t - 1.0)
                })
                .max_by(|a, b| a.abs().total_cmp(&b.abs()));
            ReportRow {
                name: run.name.clone(),
                kind: run.kind.name().into(),
                budget: run.kind.budget(),
                equal_time_budget: run.kind.group(),
                seeds: members.len() as u32,
                spp: spp_mean.round() as u32,
                spp_per_pixel,
                samples: samples.round() as usize,
                wall_s: mean(&|i| input.runs[i].wall_time_s),
                cpu_s: mean(&|i| input.runs[i].cpu_time_s),
                precompute_s: run.kind.precompute_s(),
                precompute_cached: match run.kind {
                    RunKind::Preview { cached, .. } => Some(cached),
                    _ => None,
                },
                overhead_s: mean(&|i| input.runs[i].overhead_s),
                time_vs_target,
                equal_time: time_vs_target.map(|d| d.abs() <= EQUAL_TIME_TOLERANCE),
                rmse: rmse as f32,
                rmse_ci95: rmse_ci.map(|c| c as f32),
                relmse: mean(&|i| f64::from(measured[i].relmse)) as f32,
                relmse_trimmed: mean(&|i| f64::from(measured[i].relmse_trimmed)) as f32,
                flip: flip as f32,
                flip_ci95: flip_ci.map(|c| c as f32),
            }
        })
        .collect()
}

/// For each budget: the equal-time contenders (the `gradient` run, `gradient+oidn`
/// and every baseline matched to it) and the one with the lowest mean RMSE.
fn equal_time_groups(rows: &[ReportRow]) -> Vec<(f64, Vec<&ReportRow>)> {
    let mut budgets: Vec<f64> = rows.iter().filter_map(|r| r.equal_time_budget).collect();
    budgets.sort_by(f64::total_cmp);
    budgets.dedup();
    budgets
        .into_iter()
        .map(|b| {
            let mut members: Vec<&ReportRow> = rows
                .iter()
                .filter(|r| r.equal_time_budget == Some(b))
                .filter(|r| {
                    r.kind == "baseline" || r.name.starts_with("gradient+") || r.name == "gradient"
                })
                .collect();
            members.sort_by(|a, b| a.rmse.total_cmp(&b.rmse));
            (b, members)
        })
        .filter(|(_, m)| m.len() > 1)
        .collect()
}

/// "At equal time on X (budget 17 %, about 3.0 s), Y has the lowest RMSE: …".
fn headline(input: &ReportInput, rows: &[ReportRow]) -> Option<String> {
    let head = headline_budget(input)?;
    let (b, members) = equal_time_groups(rows)
        .into_iter()
        .find(|(b, _)| *b == head)?;
    let best = members[0];
    let cost = |r: &ReportRow| input.equal_cost.of(r.wall_s, r.cpu_s);
    let unit = match input.equal_cost {
        EqualCost::Wall => "s",
        EqualCost::Cpu => "CPU s",
    };
    let time = members
        .iter()
        .find(|r| r.name == "gradient")
        .map_or(cost(best), |r| cost(r));
    let others = members[1..]
        .iter()
        .map(|r| {
            format!(
                "{} {} ({:.2} {unit})",
                r.name,
                value_ci(r.rmse, r.rmse_ci95),
                cost(r)
            )
        })
        .collect::<Vec<_>>()
        .join(", ");
    let seeds = best.seeds;
    // RMSE decides the sentence; where the other metrics crown another method the
    // sentence says so, since a denoiser or a smooth reconstruction can win one
    // metric and lose another.
    let lowest = |metric: fn(&ReportRow) -> f32| {
        members
            .iter()
            .min_by(|a, b| metric(a).total_cmp(&metric(b)))
            .copied()
    };
    let mut dissent = String::new();
    for (label, metric) in [
        (
            "trimmed relMSE",
            (|r: &ReportRow| r.relmse_trimmed) as fn(&ReportRow) -> f32,
        ),
        ("FLIP", |r: &ReportRow| r.flip),
    ] {
        if let Some(r) = lowest(metric).filter(|r| r.name != best.name) {
            dissent.push_str(&format!(
                " By {label}, {} is lowest ({:.3e}; {} {:.3e}).",
                r.name,
                metric(r),
                best.name,
                metric(best)
            ));
        }
    }
    // A contender that missed the time is named, so the sentence claims no more
    // than the timings hold.
    let off: Vec<String> = members
        .iter()
        .filter(|r| r.equal_time == Some(false))
        .map(|r| format!("{} {}", r.name, time_vs_target_cell(r)))
        .collect();
    if !off.is_empty() {
        dissent.push_str(&format!(
            " Not at equal time (beyond ±{}%): {}.",
            100.0 * EQUAL_TIME_TOLERANCE,
            off.join(", ")
        ));
    }
    Some(format!(
        "At equal {} on {} (budget {}, about {time:.2} {unit} per image, {seeds} seed{}), {} has the lowest RMSE: {} ({:.2} {unit}); then {others}.{dissent}",
        match input.equal_cost {
            EqualCost::Wall => "time",
            EqualCost::Cpu => "CPU time",
        },
        input.scene,
        percent(b),
        if seeds == 1 { "" } else { "s" },
        best.name,
        value_ci(best.rmse, best.rmse_ci95),
        cost(best),
    ))
}

/// `2.64e-3 ± 5.1e-5` (or the value alone with one seed).
fn value_ci(v: f32, ci: Option<f32>) -> String {
    match ci {
        Some(c) => format!("{v:.3e} ± {c:.1e}"),
        None => format!("{v:.3e}"),
    }
}

fn jpeg_bytes(rgb8: &[u8], w: usize, h: usize) -> std::result::Result<Vec<u8>, String> {
    let mut out = Vec::new();
    JpegEncoder::new_with_quality(&mut out, JPEG_QUALITY)
        .encode(rgb8, w as u32, h as u32, ExtendedColorType::Rgb8)
        .map_err(|e| format!("JPEG encoder: {e}"))?;
    Ok(out)
}

/// Sample maps stay PNG: a JPEG would smear the one-pixel dots.
fn png_bytes(rgb8: &[u8], w: usize, h: usize) -> std::result::Result<Vec<u8>, String> {
    use image::codecs::png::PngEncoder;
    use image::ImageEncoder;
    let mut out = Vec::new();
    PngEncoder::new(&mut out)
        .write_image(rgb8, w as u32, h as u32, ExtendedColorType::Rgb8)
        .map_err(|e| format!("PNG encoder: {e}"))?;
    Ok(out)
}

/// Cost (wall or CPU time, as the report's `equal_cost`; a preview's per frame)
/// against RMSE (with the seeds' 95 % intervals) and against FLIP, one line per
/// method (plot file name, SVG).
fn speed_plots(
    input: &ReportInput,
    rows: &[ReportRow],
) -> std::result::Result<Vec<(String, String)>, String> {
    let mut names: Vec<&str> = Vec::new();
    for r in rows.iter().filter(|r| r.kind != "interpolation") {
        if !names.contains(&r.name.as_str()) {
            names.push(&r.name);
        }
    }
    let cost = |r: &ReportRow| input.equal_cost.of(r.wall_s, r.cpu_s);
    let series = |metric: fn(&ReportRow) -> (f64, Option<f64>)| -> Vec<Series> {
        names
            .iter()
            .map(|n| {
                let members: Vec<&ReportRow> = rows
                    .iter()
                    .filter(|r| r.name == *n && r.kind != "interpolation")
                    .collect();
                Series {
                    name: (*n).to_string(),
                    points: members
                        .iter()
                        .map(|r| (cost(r), metric(r).0, setting(r)))
                        .collect(),
                    bars: members
                        .iter()
                        .map(|r| {
                            let (v, ci) = metric(r);
                            ci.map(|c| (v - c, v + c))
                        })
                        .collect(),
                }
            })
            .collect()
    };
    let label = input.equal_cost.label();
    let title = |m: &str| format!("{}: {label} vs {m}", input.scene);
    let axis = format!("{label} (s)");
    Ok(vec![
        (
            "speed_rmse.svg".into(),
            loglog_svg(
                &title("RMSE"),
                &axis,
                "RMSE (95% interval over seeds)",
                &series(|r| (f64::from(r.rmse), r.rmse_ci95.map(f64::from))),
            )?,
        ),
        (
            "speed_flip.svg".into(),
            loglog_svg(
                &title("FLIP"),
                &axis,
                "mean FLIP (95% interval over seeds)",
                &series(|r| (f64::from(r.flip), r.flip_ci95.map(f64::from))),
            )?,
        ),
    ])
}

fn json(input: &ReportInput, rows: &[ReportRow], scales: &[ErrorScale]) -> serde_json::Value {
    serde_json::json!({
        "scene": input.scene,
        "scene_hash": input.scene_hash,
        "command": input.command,
        "version": input.version,
        "threads": input.threads,
        "equal_cost": input.equal_cost.name(),
        "width": input.width,
        "height": input.height,
        "reference": input.reference_info,
        "runs": rows,
        "headline": headline(input, rows),
        "metrics": {
            "rmse": "sqrt of the mean squared error over pixels and RGB channels",
            "relmse_eps": RELMSE_EPS,
            "relmse_trimmed_fraction": TRIM_FRACTION,
            "ci95": "half-width of the 95% Student-t interval of the mean over the seeds",
            "flip": { "variant": "LDR-FLIP (flip-rs, FLIP v1.7)", "pixels_per_degree": FLIP_PPD,
                      "input": "8-bit sRGB of linear x 2^exposure, as the images" },
            "equal_time_tolerance": EQUAL_TIME_TOLERANCE,
        },
        "exposure": input.exposure,
        "error_map_scale": scales,
        "notes": input.notes,
        "fields": documentation(&JSON_FIELDS),
        "run_fields": documentation(&RUN_FIELDS),
    })
}

/// A JSON object of (key, one line) pairs.
fn documentation(fields: &[(&str, &str)]) -> serde_json::Value {
    fields
        .iter()
        .map(|(k, v)| ((*k).to_string(), serde_json::Value::from(*v)))
        .collect::<serde_json::Map<_, _>>()
        .into()
}

/// `report.json`'s own documentation of its top-level keys (its `fields`), so that
/// a reader of the file alone knows what each number means.
const JSON_FIELDS: [(&str, &str); 19] = [
    ("scene", "name of the compared scene"),
    ("render_id", "the id every file of this report carries (its assets: their folder report-assets/<id>/); written last, so a file without it belongs to another run"),
    ("files", "every file of this report, relative to its folder (assets, --keep-exr EXRs, report.md, report.html)"),
    ("scene_hash", "SHA-256 of the scene file and every file it references"),
    ("command", "the command line that wrote this report"),
    ("version", "gradtrace's version and git commit"),
    ("threads", "worker threads every run used"),
    ("equal_cost", "what the baselines' cost was matched on (compare --equal): wall (wall-clock seconds) or cpu (process CPU seconds, user + system); time_vs_target is in this measure"),
    ("width", "image width in pixels, of the reference and of every run"),
    ("height", "image height in pixels, of the reference and of every run"),
    ("reference", "{spp, time_s (its render time, also when reused), cache_key, reused (from the cache)}"),
    ("runs", "one row per method and setting, its figures the mean over its seeds; keys in run_fields"),
    ("headline", "the sentence naming the lowest RMSE at equal time at the budget nearest 17% (null without one)"),
    ("metrics", "how the errors are defined: relMSE's epsilon, the trimmed fraction, FLIP's variant, the equal-time tolerance"),
    ("exposure", "display exposure in stops applied to every image and to FLIP's input (0 = none)"),
    ("error_map_scale", "per group of error maps ({maps, budget, max}): the |luminance(run) - luminance(reference)| at the top of its colour scale, the largest 99th percentile of its maps"),
    ("notes", "setup and caveats, as the report's Notes"),
    ("fields", "this object: one line per top-level key"),
    ("run_fields", "one line per key of an entry of runs"),
];

/// `report.json`'s documentation of a row's keys (its `run_fields`).
const RUN_FIELDS: [(&str, &str); 21] = [
    ("name", "method: a strategy, a baseline, full, or a Sec. 8 interpolation run"),
    ("kind", "adaptive, baseline, full, interpolation or preview (shadow-field, glossy: an approximate method, scored against the same reference)"),
    ("budget", "samples per pixel of an adaptive or interpolation run as given (0.17 = 17% of the pixels); null otherwise"),
    ("equal_time_budget", "for adaptive runs and baselines: the budget whose gradient run's time the baselines match"),
    ("seeds", "repetitions with independent random numbers; the figures are their mean"),
    ("spp", "camera samples per evaluated point (adaptive, interpolation) or per pixel (baselines: the mean; full)"),
    ("spp_per_pixel", "camera samples per image pixel the run spent (adaptive: samples x spp / pixels)"),
    ("samples", "points evaluated (adaptive, interpolation) or camera samples (full renders, baselines), mean over the seeds"),
    ("wall_s", "wall time in seconds, overhead included, mean over the seeds; a preview: one frame, its precompute apart"),
    ("cpu_s", "process CPU seconds (user + system, every thread) over the same span as wall_s, mean over the seeds"),
    ("precompute_s", "a preview's precompute in wall seconds (as first computed, also when read from the cache); null for the others"),
    ("precompute_cached", "whether a preview's precompute was read from the cache (<out>/cache/); null for the others"),
    ("overhead_s", "the part of wall_s outside the renderer: quadtree and reconstruction, or the denoiser"),
    ("time_vs_target", "runs meant to take the gradient run's time: the seeds' largest relative deviation from it (in the equal_cost measure), signed; null otherwise"),
    ("equal_time", "whether |time_vs_target| <= metrics.equal_time_tolerance (false rows are marked in the report); null without a target"),
    ("rmse", "root mean squared error against the reference, mean over the seeds"),
    ("rmse_ci95", "half-width of its 95% Student-t interval over the seeds; null with one seed"),
    ("relmse", "mean relative squared error, (x - ref)^2 / (ref^2 + relmse_eps)"),
    ("relmse_trimmed", "relmse without the relmse_trimmed_fraction pixels of highest error"),
    ("flip", "mean LDR-FLIP on the displayed images"),
    ("flip_ci95", "half-width of FLIP's 95% interval over the seeds; null with one seed"),
];

/// The first table of a section: what each run cost, and its RMSE.
const TIME_COLUMNS: [&str; 10] = [
    "method",
    "kind",
    "budget / spp",
    "seeds",
    "samples",
    "wall time (s)",
    "CPU time (s)",
    "overhead (s)",
    "time vs target",
    "RMSE (± 95%)",
];

/// The second table of a section: the other metrics of the same rows (one table
/// of fourteen columns did not fit an 800-pixel window).
const METRIC_COLUMNS: [&str; 5] = [
    "method",
    "budget / spp",
    "relMSE",
    "relMSE, 0.01% trimmed",
    "FLIP (± 95%)",
];

/// The previews' table: a frame's cost, the precompute apart, and the RMSE
/// against the same reference as every other row.
const PREVIEW_COLUMNS: [&str; 7] = [
    "method",
    "kind",
    "precompute (s)",
    "frame wall time (s)",
    "frame CPU time (s)",
    "RMSE",
    "FLIP",
];

/// A row's setting: "17%", "16 spp" or "per frame".
fn setting(r: &ReportRow) -> String {
    match r.budget {
        Some(b) => percent(b),
        None if r.kind == "preview" => PER_FRAME.into(),
        None => format!("{} spp", r.spp),
    }
}

/// A wall time as the tables and the image cards print it (one format, so that
/// both show the same number).
fn seconds(s: f64) -> String {
    format!("{s:.3}")
}

/// A mean with its interval, or with "(1 seed)" where there is none.
fn cell_ci(v: f32, ci: Option<f32>, digits: usize) -> String {
    match ci {
        Some(c) => format!("{v:.digits$e} ± {c:.1e}"),
        None => format!("{v:.digits$e} (1 seed)"),
    }
}

/// "+12.3% †" (beyond the tolerance), "−1.0%", or "–" without a target.
fn time_vs_target_cell(r: &ReportRow) -> String {
    match r.time_vs_target {
        Some(d) => {
            let mark = if r.equal_time == Some(false) {
                format!(" {OFF_TIME_MARK}")
            } else {
                String::new()
            };
            format!("{:+.1}%{mark}", 100.0 * d)
        }
        None => "–".into(),
    }
}

/// A row's cells, in [`TIME_COLUMNS`] order.
fn time_cells(r: &ReportRow) -> Vec<String> {
    vec![
        r.name.clone(),
        r.kind.clone(),
        setting(r),
        r.seeds.to_string(),
        r.samples.to_string(),
        seconds(r.wall_s),
        seconds(r.cpu_s),
        seconds(r.overhead_s),
        time_vs_target_cell(r),
        cell_ci(r.rmse, r.rmse_ci95, 3),
    ]
}

/// A preview row's cells, in [`PREVIEW_COLUMNS`] order.
fn preview_cells(r: &ReportRow) -> Vec<String> {
    let precompute = r.precompute_s.map_or("–".into(), |p| {
        let cached = if r.precompute_cached == Some(true) {
            " (cached)"
        } else {
            ""
        };
        format!("{}{cached}", seconds(p))
    });
    vec![
        r.name.clone(),
        r.kind.clone(),
        precompute,
        seconds(r.wall_s),
        seconds(r.cpu_s),
        format!("{:.3e}", r.rmse),
        format!("{:.3e}", r.flip),
    ]
}

/// A section's tables: (columns, cells) for each.
type Columns = (&'static [&'static str], fn(&ReportRow) -> Vec<String>);

/// The previews get one table of their own columns; every other section the
/// time table and the metric table.
fn section_columns(members: &[&ReportRow]) -> Vec<Columns> {
    if !members.is_empty() && members.iter().all(|r| r.kind == "preview") {
        vec![(&PREVIEW_COLUMNS, preview_cells)]
    } else {
        vec![(&TIME_COLUMNS, time_cells), (&METRIC_COLUMNS, metric_cells)]
    }
}

/// A row's cells, in [`METRIC_COLUMNS`] order.
fn metric_cells(r: &ReportRow) -> Vec<String> {
    vec![
        r.name.clone(),
        setting(r),
        format!("{:.3e}", r.relmse),
        format!("{:.3e}", r.relmse_trimmed),
        cell_ci(r.flip, r.flip_ci95, 3),
    ]
}

/// The lines under a section's tables that explain what its cells may show.
fn table_notes(members: &[&ReportRow]) -> Vec<String> {
    let mut notes = Vec::new();
    if members.iter().any(|r| r.time_vs_target.is_some()) {
        notes.push(format!(
            "time vs target: the cost (wall or CPU time, the report's equal cost) against the gradient run's at the same seed, the seed furthest off; \
             {OFF_TIME_MARK} beyond ±{}%: not an equal-time result.",
            100.0 * EQUAL_TIME_TOLERANCE
        ));
    }
    if members.iter().any(|r| r.kind == "preview") {
        notes.push(
            "Previews: approximations (shadow-field: direct light on diffuse surfaces; glossy: \
             environment light with one bounce), scored against the same reference as every row; \
             their cost is one frame, the precompute apart (cached under <out>/cache/)."
                .into(),
        );
    }
    if members.iter().any(|r| r.seeds == 1 && r.kind != "preview") {
        notes.push("(1 seed): a single run, so no interval (a hollow point in the plots).".into());
    }
    notes
}

/// Rows as tables: the full render, one table per budget (its strategies at equal
/// samples, then the baselines at the `gradient` run's time), the interpolation runs.
fn tables(rows: &[ReportRow]) -> Vec<(String, Vec<&ReportRow>)> {
    let mut out = Vec::new();
    let full: Vec<&ReportRow> = rows.iter().filter(|r| r.kind == "full").collect();
    if !full.is_empty() {
        out.push((
            "Full render (every pixel, the adaptive runs' samples per point)".into(),
            full,
        ));
    }
    let mut budgets: Vec<f64> = rows.iter().filter_map(|r| r.equal_time_budget).collect();
    budgets.sort_by(f64::total_cmp);
    budgets.dedup();
    for b in budgets {
        let mut members: Vec<&ReportRow> = rows
            .iter()
            .filter(|r| r.equal_time_budget == Some(b))
            .collect();
        // Adaptive first, each part by RMSE.
        members.sort_by(|x, y| {
            (x.kind != "adaptive")
                .cmp(&(y.kind != "adaptive"))
                .then(x.rmse.total_cmp(&y.rmse))
        });
        out.push((
            format!(
                "Budget {}: strategies at equal samples; baselines at the gradient run's time (the equal cost: wall or CPU)",
                percent(b)
            ),
            members,
        ));
    }
    let interp: Vec<&ReportRow> = rows.iter().filter(|r| r.kind == "interpolation").collect();
    if !interp.is_empty() {
        out.push((
            "Gradient vs linear interpolation (Sec. 8, 1% of the pixels)".into(),
            interp,
        ));
    }
    let previews: Vec<&ReportRow> = rows.iter().filter(|r| r.kind == "preview").collect();
    if !previews.is_empty() {
        out.push((
            "Previews (one frame; the precompute apart)".into(),
            previews,
        ));
    }
    out
}

/// The tables as Markdown (the CLI prints them; closing notes quote them): per
/// section, time and RMSE first, then the other metrics.
pub fn markdown_table(rows: &[ReportRow]) -> String {
    let mut s = String::new();
    let table = |s: &mut String,
                 columns: &[&str],
                 cells: &dyn Fn(&ReportRow) -> Vec<String>,
                 members: &[&ReportRow],
                 text_columns: usize| {
        let _ = writeln!(s, "| {} |", columns.join(" | "));
        let _ = writeln!(
            s,
            "|{}{}",
            "---|".repeat(text_columns),
            "---:|".repeat(columns.len() - text_columns)
        );
        for r in members {
            let c: Vec<String> = cells(r).iter().map(|c| c.replace('|', "\\|")).collect();
            let _ = writeln!(s, "| {} |", c.join(" | "));
        }
        *s += "\n";
    };
    for (title, members) in tables(rows) {
        let _ = writeln!(s, "**{title}**\n");
        for (columns, cells) in section_columns(&members) {
            let text = if columns[1] == "kind" { 2 } else { 1 };
            table(&mut s, columns, &cells, &members, text);
        }
        for n in table_notes(&members) {
            let _ = writeln!(s, "{n}\n");
        }
    }
    s
}

/// `assets`: the folder the links point into (`report-assets/<id>`).
fn markdown(
    input: &ReportInput,
    rows: &[ReportRow],
    cards: &[Card],
    scales: &[ErrorScale],
    assets: &str,
) -> String {
    let mut s = format!("# Comparison: {}\n\n", input.scene);
    if let Some(line) = headline(input, rows) {
        let _ = writeln!(s, "**{line}**\n");
    }
    let _ = writeln!(s, "{}\n", meta_line(input));
    s += &markdown_table(rows);
    let _ = writeln!(
        s,
        "![RMSE against time]({assets}/speed_rmse.svg)\n![FLIP against time]({assets}/speed_flip.svg)"
    );
    let _ = writeln!(s, "\n![reference]({assets}/reference.jpg)");
    for (k, scale) in scales.iter().enumerate() {
        let _ = writeln!(s, "\n{}\n", scale_caption(scale));
        for card in cards.iter().filter(|c| c.scale == k) {
            let run = &input.runs[card.run];
            let _ = write!(
                s,
                "- {} ({}): [image]({assets}/{}) · [error]({assets}/{})",
                run.name,
                run.kind.short(),
                card.image,
                card.error
            );
            if let Some(m) = &card.samples {
                let _ = write!(s, " · [samples]({assets}/{m})");
            }
            s += "\n";
        }
    }
    if !input.notes.is_empty() {
        s += "\n## Notes\n\n";
        for n in &input.notes {
            let _ = writeln!(s, "- {n}");
        }
    }
    s
}

/// "Error maps, budget 17%: |Δ luminance| from 0 to 1.48e-1 …".
fn scale_caption(scale: &ErrorScale) -> String {
    format!(
        "Error maps, {}: |luminance(run) − luminance(reference)|, linear, from 0 to {:.2e} (this group's scale: the largest 99th percentile of its maps).",
        scale.label, scale.max
    )
}

fn meta_line(input: &ReportInput) -> String {
    let r = &input.reference_info;
    format!(
        "{}×{} pixels; reference {} spp, rendered in {:.1} s ({}; key {}); {} threads; equal cost: {}; exposure {:+} stops; \
         relMSE ε = {}; trimmed relMSE leaves out the {}% of pixels with the highest error; \
         FLIP: LDR-FLIP at {:.1} pixels/degree on the displayed 8-bit sRGB; {}.",
        input.width,
        input.height,
        r.spp,
        r.time_s,
        if r.reused { "reused from the cache" } else { "rendered for this report" },
        &r.cache_key[..r.cache_key.len().min(16)],
        input.threads,
        input.equal_cost.label(),
        input.exposure,
        RELMSE_EPS,
        TRIM_FRACTION * 100.0,
        FLIP_PPD,
        input.version
    )
}

const CSS: &str = "body{font-family:sans-serif;margin:1em auto;color:#222;max-width:78em;padding:0 1em}\
.table{overflow-x:auto}table{border-collapse:collapse;margin:.6em 0;font-size:.9em}\
td,th{border:1px solid #bbb;padding:.2em .4em;text-align:right;white-space:nowrap}\
th{white-space:normal;vertical-align:bottom}td:first-child{white-space:normal;min-width:7em}\
td:first-child,th:first-child,td:nth-child(2){text-align:left}th{background:#eee}\
tr.off td{background:#fdecea}.tnote{font-size:.85em;color:#444;margin:.2em 0 .8em}\
.headline{font-size:1.15em;background:#f4f7ee;border-left:4px solid #6a3;padding:.5em .8em}\
.grid{display:flex;flex-wrap:wrap;gap:1em}.card{flex:1 1 24em;border:1px solid #ccc;padding:.5em;border-radius:4px}\
.imgs{display:flex;gap:.4em;flex-wrap:wrap}figure{margin:0;flex:1 1 0;min-width:9em}figcaption{font-size:.8em;color:#555}\
img{max-width:100%;height:auto;image-rendering:auto}svg{max-width:100%;height:auto}.plots{display:flex;flex-wrap:wrap;gap:1em}";

/// One HTML table of `members`; rows off the equal time are marked by class too.
fn html_table(
    s: &mut String,
    columns: &[&str],
    cells: &dyn Fn(&ReportRow) -> Vec<String>,
    members: &[&ReportRow],
) {
    *s += "<div class=\"table\"><table><tr>";
    for c in columns {
        let _ = write!(s, "<th>{}</th>", esc(c));
    }
    *s += "</tr>\n";
    for r in members {
        *s += if r.equal_time == Some(false) {
            "<tr class=\"off\">"
        } else {
            "<tr>"
        };
        for c in cells(r) {
            let _ = write!(s, "<td>{}</td>", esc(&c));
        }
        *s += "</tr>\n";
    }
    *s += "</table></div>\n";
}

fn html(
    input: &ReportInput,
    rows: &[ReportRow],
    cards: &[Card],
    plots: &[(String, String)],
    scales: &[ErrorScale],
    assets: &str,
) -> String {
    let (w, h) = (input.width, input.height);
    // Thumbnails scale smoothly; a click opens the full-size file.
    // `extra` follows the caption inside the figure (an error map's colour bar).
    let figure = |name: &str, alt: &str, extra: &str| {
        format!(
            "<figure><a href=\"{assets}/{name}\"><img width=\"{w}\" height=\"{h}\" alt=\"{a}\" src=\"{assets}/{name}\"></a><figcaption>{a}</figcaption>{extra}</figure>",
            a = esc(alt)
        )
    };
    let img = |name: &str, alt: &str| figure(name, alt, "");
    let mut s = String::new();
    let _ = write!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><meta name=\"viewport\" content=\"width=device-width\">\
         <title>gradtrace compare: {0}</title><style>{CSS}</style></head><body>\n<h1>Comparison: {0}</h1>\n",
        esc(&input.scene)
    );
    if let Some(line) = headline(input, rows) {
        let _ = writeln!(s, "<p class=\"headline\">{}</p>", esc(&line));
    }
    let _ = writeln!(s, "<p>{}</p>", esc(&meta_line(input)));
    for (title, members) in tables(rows) {
        let _ = writeln!(s, "<h2>{}</h2>", esc(&title));
        for (columns, cells) in section_columns(&members) {
            html_table(&mut s, columns, &cells, &members);
        }
        for n in table_notes(&members) {
            let _ = writeln!(s, "<p class=\"tnote\">{}</p>", esc(&n));
        }
    }
    s += "<p>Strategies compare at equal sample count. Baselines are what a user would run instead — every pixel \
          uniformly, a per-pixel adaptive sampler, a denoised render — at about the wall time of the gradient \
          strategy at the same budget: the comparison any speed-up claim must win.</p>\n";
    s += "<h2>Speed against error</h2>\n<p>Log-log; one line per method, points labelled by budget or samples per \
          pixel; bars: 95% interval over the seeds (an arrow where it goes on past the plot's edge; a hollow \
          point: one seed, no interval).</p>\n<div class=\"plots\">\n";
    for (_, svg) in plots {
        s += &inline_svg(svg);
        s += "\n";
    }
    s += "</div>\n<h2>Images</h2>\n";
    s += &img(
        "reference.jpg",
        &format!("reference, {} spp", input.reference_info.spp),
    );
    for (k, scale) in scales.iter().enumerate() {
        let _ = writeln!(
            s,
            "<h3>Error maps, {}</h3>\n<p>{}</p>\n<div class=\"grid\">",
            esc(&scale.label),
            esc(&scale_caption(scale))
        );
        for (n, card) in cards.iter().enumerate().filter(|(_, c)| c.scale == k) {
            let run = &input.runs[card.run];
            // The run's own row: same method, kind and setting (a name alone would
            // find the method at another budget).
            let row = rows.iter().find(|r| {
                r.name == run.name
                    && r.kind == run.kind.name()
                    && r.budget == run.kind.budget()
                    && r.equal_time_budget == run.kind.group()
            });
            // The row's setting too: a baseline's spp is the seeds' mean there.
            let name = format!(
                "{} ({})",
                run.name,
                row.map_or_else(|| run.kind.short(), setting)
            );
            let _ = write!(s, "<div class=\"card\"><h4>{}</h4>", esc(&name));
            if let Some(row) = row {
                // The row's mean, as the table prints it; the images are one seed's.
                let _ = write!(
                    s,
                    "<p>{} s; RMSE {} ({}; images: seed {})</p>",
                    seconds(row.wall_s),
                    value_ci(row.rmse, row.rmse_ci95),
                    if row.seeds == 1 {
                        "1 seed".to_string()
                    } else {
                        format!("mean of {} seeds", row.seeds)
                    },
                    run.seed
                );
            }
            s += "<div class=\"imgs\">";
            s += &img(&card.image, &name);
            s += &figure(&card.error, "error map", &legend_svg(scale.max, n));
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

/// Horizontal viridis bar from 0 to `scale` with three ticks (one under each map);
/// `n` keeps its gradient's id unique in the page.
fn legend_svg(scale: f32, n: usize) -> String {
    let mut s = format!(
        "<svg width=\"240\" height=\"34\" viewBox=\"0 0 240 34\"><defs><linearGradient id=\"viridis{n}\">"
    );
    for k in 0..=16 {
        let t = k as f32 / 16.0;
        let _ = write!(
            s,
            "<stop offset=\"{t}\" stop-color=\"{}\"/>",
            viridis_hex(t)
        );
    }
    let _ = write!(
        s,
        "</linearGradient></defs><rect x=\"6\" y=\"2\" width=\"228\" height=\"12\" fill=\"url(#viridis{n})\" stroke=\"#444\"/>"
    );
    for k in 0..=2 {
        let x = 6.0 + 114.0 * k as f32;
        let v = scale * k as f32 / 2.0;
        let anchor = ["start", "middle", "end"][k];
        let _ = write!(
            s,
            "<text x=\"{x}\" y=\"28\" font-size=\"11\" text-anchor=\"{anchor}\" font-family=\"sans-serif\">{}{v:.2e}</text>",
            if k == 2 { "≥ " } else { "" }
        );
    }
    s += "</svg>";
    s
}

/// The luminance error that maps to the top of one group's colour scale, shared
/// by its maps so that they compare: the largest per-map 99th percentile (a
/// maximum would let a few firefly pixels make every map black).
fn error_scale(errors: &[&Vec<f32>]) -> f32 {
    let p99 = |e: &Vec<f32>| {
        let mut v = e.clone();
        let k = ((v.len() as f64 * 0.99) as usize).min(v.len() - 1);
        *v.select_nth_unstable_by(k, f32::total_cmp).1
    };
    let s = errors
        .iter()
        .filter(|e| !e.is_empty())
        .map(|e| p99(e))
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

/// Budget in samples per pixel as a percentage of the pixels: 0.05 → "5%".
fn percent(budget: f64) -> String {
    let p = budget * 100.0;
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
