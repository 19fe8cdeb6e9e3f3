//! The command line's types: one clap struct per subcommand, the parsers of the
//! library's closed sets and numbers, and the conversions into pipeline jobs.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand};
use gradtrace::adaptive::{Settings, Strategy};
use gradtrace::output::report::EqualCost;
use gradtrace::pipeline::compare::{self, CompareOptions};
use gradtrace::pipeline::diff::{DiffMetric, DiffOptions};
use gradtrace::pipeline::preview::glossy::GlossyOptions;
use gradtrace::pipeline::preview::shadow_field::ShadowFieldOptions;
use gradtrace::pipeline::{self, progress::ProgressMode};
use gradtrace::reconstruct::Interpolation;
use gradtrace::render::noise_adaptive::NoiseAdaptive;
use gradtrace::render::{Crop, Passes, RenderOptions};
use gradtrace::scene::Integrator;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

#[derive(Parser, Debug)]
#[command(
    name = "gradtrace",
    version = pipeline::VERSION,
    about = "CPU path tracer: renders a TOML scene file to a multi-layer EXR and a PNG"
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand, Debug)]
pub(crate) enum Command {
    /// Render a scene to an EXR (beauty + AOV layers) and a tone-mapped PNG.
    Render(RenderArgs),
    /// Print what a scene holds (geometry, materials, lights, camera, settings) and
    /// the BVH build time.
    Info(InfoArgs),
    /// Render a content-keyed cached reference, every adaptive-sampling strategy at
    /// several budgets (over --seeds repetitions) and the baselines a user would
    /// pick instead at equal time, and write `<out>/report.html` (with its
    /// `report-assets/<id>/`), `report.json` and `report.md`.
    Compare(CompareArgs),
    /// Compare two EXRs' beauty (R, G, B): RMSE, relMSE, FLIP and an error-map
    /// PNG; exit status 1 when --threshold is exceeded.
    Diff(DiffArgs),
    /// Fast approximate previews, always scored against the path tracer:
    /// `shadow-field` (soft shadows from SH shadow fields, rigid and deforming
    /// occluders) or `glossy` (precomputed glossy transfer with vMF lobes).
    #[command(subcommand)]
    Preview(PreviewCommand),
    /// Merge the parts of a split render (tiles from --tile/--crop, sample ranges
    /// from --spp-range) into the whole image: tiles are checked to cover it
    /// exactly once, sample ranges combined weighted by their sample counts.
    Merge(MergeArgs),
}

#[derive(Args, Debug)]
pub(crate) struct MergeArgs {
    /// The parts (EXR files written by `gradtrace render`).
    #[arg(required = true, value_name = "PARTS")]
    pub(crate) parts: Vec<PathBuf>,
    /// The merged EXR; the PNG is written next to it with the same stem.
    #[arg(long, value_name = "FULL.exr")]
    pub(crate) out: PathBuf,
    /// No summary line.
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

impl Command {
    /// The file a run is about and what it is doing with it, for the one line
    /// a failed allocation prints (`memory::doing`).
    pub(crate) fn doing(&self) -> (&std::path::Path, &'static str) {
        match self {
            Command::Render(a) => (&a.scene, "rendering"),
            Command::Info(a) => (&a.scene, "reading the scene"),
            Command::Diff(a) => (&a.image, "comparing the images"),
            Command::Preview(PreviewCommand::ShadowField(a) | PreviewCommand::Glossy(a)) => {
                (&a.scene, "making the preview")
            }
            Command::Merge(a) => (&a.out, "merging the parts"),
            Command::Compare(a) => (&a.scene, "comparing the renderers"),
        }
    }
}

impl MergeArgs {
    pub(crate) fn job(&self) -> pipeline::merge::MergeJob {
        pipeline::merge::MergeJob {
            parts: self.parts.clone(),
            out: self.out.clone(),
            command: pipeline::command_line(),
        }
    }
}

/// Upper bounds of the counts a user gives, each refused with one line before
/// any work (issue 54: `--frames 4294967295` wrote files until it was killed).
/// Frames of an animation: two files each, 20,000 files at most (the bound of
/// the scene's `[animation] frames` too).
const MAX_FRAMES: i64 = gradtrace::scene::animation::MAX_FRAMES as i64;
/// Views on the glossy preview's orbit: one every 0.1°.
const MAX_ORBIT: i64 = 3_600;
/// Seeds of `compare`: its 95 % intervals stop narrowing usefully long before.
const MAX_SEEDS: i64 = 1_000;
/// Shadow rays per visibility line: 1024 strata along θ are finer than 0.1° of
/// a hemisphere; each costs about 3.5 rays with the ring.
const MAX_VIS_SAMPLES: i64 = 1_024;
/// Bisection steps per visibility jump: an f32 angle has 24 bits, so a 25th
/// step cannot move the jump.
const MAX_VIS_REFINE: i64 = 24;

#[derive(Subcommand, Debug)]
pub(crate) enum PreviewCommand {
    /// Precompute (cached) a shadow field per object and light, shade every pixel,
    /// and write DIR/<scene>.exr (R,G,B, reference.R/G/B, error.Y), a PNG and
    /// DIR/preview.json.
    ShadowField(PreviewArgs),
    /// Precompute (cached) the environment-light transfer as vMF lobes, refined
    /// in angle and space, render the view (and --orbit views), and write
    /// DIR/<scene>.exr, PNGs, DIR/preview.json and a statistics page.
    Glossy(PreviewArgs),
}

#[derive(Args, Debug)]
pub(crate) struct PreviewArgs {
    /// Scene file (TOML).
    pub(crate) scene: PathBuf,
    /// Output folder [default: out/preview-<method>/<scene-stem>].
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    /// shadow-field: render N frames of the scene's [animation] (0: the block's
    /// count; at most 10000, two files each).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=MAX_FRAMES))]
    pub(crate) frames: Option<u32>,
    /// glossy: also render N views on an orbit around the scene (at most 3600,
    /// a view every 0.1°).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=MAX_ORBIT))]
    pub(crate) orbit: Option<u32>,
    /// glossy: split every triangle 1-to-4 N times (4^N times the faces) and make
    /// no adaptive spatial splits (the uniform mesh the adaptive one is compared
    /// against at equal error; angular refinement still runs).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u8).range(0..=6))]
    pub(crate) uniform: Option<u8>,
    /// glossy: vertices the tessellation and adaptive refinement may add to the
    /// scene's own, however dense its meshes [default: 16000].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) max_vertices: Option<u32>,
    /// Samples per pixel the path-traced reference starts at [default: 256]; raised
    /// until its noise is at most half the preview's RMSE (the bias resolved).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) reference_spp: Option<u32>,
    /// The most spp the reference is raised to [default: 4096]; beyond it the bias
    /// and speed-ups are reported unresolved (null, with the reason).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) reference_spp_max: Option<u32>,
    /// Frames the precompute is amortised over in `speedup_with_precompute` [default: 100].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) amortise_frames: Option<u32>,
    /// No progress output and no summary.
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

impl PreviewArgs {
    /// The options that belong to the other preview, refused rather than
    /// silently ignored (issue 54): `--frames` is shadow-field's, `--orbit`,
    /// `--uniform` and `--max-vertices` are glossy's.
    pub(crate) fn only_for(&self, glossy: bool) -> anyhow::Result<()> {
        let given = [
            ("--frames", self.frames.is_some(), false),
            ("--orbit", self.orbit.is_some(), true),
            ("--uniform", self.uniform.is_some(), true),
            ("--max-vertices", self.max_vertices.is_some(), true),
        ];
        if let Some((flag, _, of_glossy)) = given.iter().find(|(_, set, g)| *set && *g != glossy) {
            let owner = if *of_glossy { "glossy" } else { "shadow-field" };
            anyhow::bail!("{flag} is an option of `preview {owner}` only");
        }
        Ok(())
    }

    pub(crate) fn shadow_field_options(&self) -> anyhow::Result<ShadowFieldOptions> {
        self.only_for(false)?;
        let mut opts = ShadowFieldOptions::new(&self.scene);
        opts.out_dir = self.out_dir("shadow-field");
        (opts.frames, opts.reference_spp, opts.quiet) =
            (self.frames, self.reference_spp, self.quiet);
        (opts.reference_spp_max, opts.amortise_frames) =
            (self.reference_spp_max, self.amortise_frames);
        Ok(opts)
    }

    pub(crate) fn glossy_options(&self) -> anyhow::Result<GlossyOptions> {
        self.only_for(true)?;
        let mut opts = GlossyOptions::new(&self.scene);
        opts.out_dir = self.out_dir("glossy");
        (opts.orbit, opts.reference_spp, opts.quiet) = (self.orbit, self.reference_spp, self.quiet);
        (opts.reference_spp_max, opts.amortise_frames) =
            (self.reference_spp_max, self.amortise_frames);
        if let Some(n) = self.uniform {
            (opts.settings.uniform_levels, opts.settings.spatial) = (n, false);
        }
        if let Some(n) = self.max_vertices {
            opts.settings.max_vertices = n as usize;
        }
        Ok(opts)
    }

    fn out_dir(&self, method: &str) -> PathBuf {
        self.out
            .clone()
            .unwrap_or_else(|| preview_dir(method, &self.scene))
    }
}

impl DiffArgs {
    pub(crate) fn options(&self) -> DiffOptions {
        DiffOptions {
            metric: self.metric,
            threshold: self.threshold,
            error_map: self.error_map.clone(),
        }
    }
}

#[derive(Args, Debug)]
pub(crate) struct DiffArgs {
    /// The image to judge (EXR).
    pub(crate) image: PathBuf,
    /// The reference (EXR): relMSE divides by its square, FLIP's reference.
    pub(crate) reference: PathBuf,
    /// Metric for --threshold and the error map.
    #[arg(long, value_parser = diff_metric(), value_name = "NAME", default_value = "rmse")]
    pub(crate) metric: DiffMetric,
    /// Exit with status 1 when the --metric is above this.
    #[arg(long, value_name = "X", allow_negative_numbers = true)]
    pub(crate) threshold: Option<f32>,
    /// Error-map PNG (viridis) [default: <IMAGE stem>.diff.png beside IMAGE].
    #[arg(long, value_name = "PATH")]
    pub(crate) error_map: Option<PathBuf>,
}

// Negative numbers reach the value parsers, which name the flag in the error.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub(crate) struct CompareArgs {
    /// Scene file (TOML).
    pub(crate) scene: PathBuf,
    /// Comma-separated strategies [default: all].
    #[arg(long, value_parser = strategy(), value_name = "LIST", value_delimiter = ',')]
    pub(crate) strategies: Vec<Strategy>,
    /// Comma-separated budgets in samples per pixel [default: 0.05,0.1,0.17,0.25,0.5].
    #[arg(
        long,
        value_name = "LIST",
        value_delimiter = ',',
        value_parser = compare_budget
    )]
    pub(crate) budgets: Vec<f64>,
    /// Samples per pixel of the reference (cached in the output folder) [default: 8 × spp].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) reference_spp: Option<u32>,
    /// Shadow rays per line for the samples' visibility gradients; 0 samples the
    /// lights by points and drops the visibility term [default: 4; at most 1024].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=MAX_VIS_SAMPLES))]
    pub(crate) vis_samples: Option<u32>,
    /// How many of each adaptive sample's camera samples carry the analytic
    /// gradient; the rest only refine its radiance [default: min(spp, 16)].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) gradient_spp: Option<u32>,
    /// Repeat every run with this many independent seeds; the report gives means
    /// and 95% intervals (use 4 or more for conclusions; at most 1000).
    #[arg(long, value_name = "K", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=MAX_SEEDS))]
    pub(crate) seeds: u32,
    /// Keep every run's image as an EXR under <out>/runs/.
    #[arg(long)]
    pub(crate) keep_exr: bool,
    /// Show the images of every budget in the report (default: the headline budget's).
    #[arg(long)]
    pub(crate) all_images: bool,
    /// What the baselines are matched on: `wall` (wall-clock time, what a user
    /// waits on an idle machine) or `cpu` (process CPU time, user + system, which
    /// other jobs on a shared machine barely change) [default: wall].
    #[arg(long, value_parser = equal_cost(), value_name = "wall|cpu")]
    pub(crate) equal: Option<EqualCost>,
    /// Leave out the preview rows (shadow-field, glossy), added where the scene suits them.
    #[arg(long)]
    pub(crate) no_previews: bool,
    /// Output folder [default: out/ and the scene's path, e.g. out/validation-cornell].
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) common: CommonArgs,
}

#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub(crate) struct RenderArgs {
    /// Scene file (TOML).
    pub(crate) scene: PathBuf,
    /// Longest path in segments from the camera; 1 = only directly visible
    /// emitters [default: the scene's `[render] max_depth`].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) max_depth: Option<u32>,
    /// Output EXR path; the PNG is written next to it with the same stem
    /// [default: out/<scene-stem>.exr].
    #[arg(long, value_name = "PATH")]
    pub(crate) out: Option<PathBuf>,
    /// Estimator: `path` (full path tracing) or `direct` (direct lighting only)
    /// [default: the scene's `[render] integrator`].
    #[arg(long, value_parser = integrator(), value_name = "KIND")]
    pub(crate) integrator: Option<Integrator>,
    /// Skip the AOV layers (normal, depth, albedo, object id, variance): the EXR
    /// then holds only R, G, B.
    #[arg(long)]
    pub(crate) no_aovs: bool,
    /// Shade every path one hit at a time, never eight hits in SIMD lanes (the
    /// lanes take Lambertian meshes lit by area lights): the same image, slower;
    /// for comparing the two.
    #[arg(long)]
    pub(crate) no_lanes: bool,
    /// Also compute the analytic image gradients (direct illumination, and the
    /// curvature/bump and camera terms of indirect light) and write them as `grad.*` layers (∂I/∂u, ∂I/∂v and the per-term magnitudes).
    #[arg(long)]
    pub(crate) gradients: bool,
    /// Denoise the beauty with Intel Open Image Denoise, guided by the albedo and
    /// normal AOVs: R,G,B (and the PNG) hold it, `noisy.R/G/B` the render. Needs a
    /// build with `--features oidn` (README.md, "Optional: denoiser").
    #[arg(long, conflicts_with = "strategy")]
    pub(crate) denoise: bool,
    /// Gradient-domain reconstruction: render with --gradients and solve a
    /// screened Poisson problem (L1 by IRLS, or L2) for the direct light from the
    /// analytic gradients: R,G,B (and the PNG) hold it, `noisy.R/G/B` the render.
    #[arg(long, value_parser = reconstruct_norm(), value_name = "KIND", conflicts_with_all = ["strategy", "denoise"])]
    pub(crate) reconstruct: Option<gradtrace::reconstruct::poisson::Norm>,
    /// With --reconstruct: a quarter of --spp in every pixel, then the rest (the
    /// same total) where one sample's noise, the analytic gradient and the contrast
    /// the gradient leaves unexplained are largest (at most 16 × --spp a pixel);
    /// writes `samples.spp`.
    #[arg(long, requires = "reconstruct")]
    pub(crate) dense_adaptive: bool,
    /// With --gradients: shadow rays per azimuth line for the first hit's
    /// visibility (soft-shadow) gradient; the radiance is the plain render's, bit for
    /// bit [default: 4; at most 1024]. 0: no visibility term.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=MAX_VIS_SAMPLES))]
    pub(crate) vis_samples: Option<u32>,
    /// With --gradients: bisection steps refining each visibility jump (extra
    /// shadow rays per jump) [default: 0; at most 24].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=MAX_VIS_REFINE))]
    pub(crate) vis_refine: Option<u32>,
    /// With --gradients: the probability of marching a sample's ring (~70 % of its
    /// visibility rays) where two probe rays and the radiance's shadow ray agree
    /// (fully lit or fully blocked as far as they see); the crossings' weights
    /// account for it, so the gradient stays unbiased. 1 marches every ring
    /// [default: 0.25].
    #[arg(long, value_name = "Q", value_parser = vis_gate)]
    pub(crate) vis_gate: Option<f32>,
    /// With --gradients: treat a near light as distant (no SV term) where
    /// 2|n_x|·d exceeds F, the far-light criterion of the first-order paper, Sec. 5.2.
    #[arg(long, value_name = "F", value_parser = positive)]
    pub(crate) far_light: Option<f32>,
    /// With --strategy: how many of each sample's --spp camera samples carry the
    /// analytic gradient; the rest only refine its radiance [default: min(spp, 16)].
    #[arg(long, value_name = "N", requires = "strategy", value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) gradient_spp: Option<u32>,
    /// Adaptive sampling: place samples with this strategy and reconstruct every
    /// pixel from them; each sample is a --spp estimate with analytic gradients.
    #[arg(long, value_parser = strategy(), value_name = "NAME")]
    pub(crate) strategy: Option<Strategy>,
    /// With --strategy: samples per pixel, e.g. 0.17 evaluates 17% as many points
    /// as there are pixels [default: 0.17].
    #[arg(
        long,
        value_name = "F",
        requires = "strategy",
        value_parser = budget
    )]
    pub(crate) budget: Option<f32>,
    /// With --strategy: how every pixel is rebuilt from the samples [default: gradient].
    #[arg(long, value_parser = interpolation(), value_name = "KIND", requires = "strategy")]
    pub(crate) interpolation: Option<Interpolation>,
    #[command(flatten)]
    pub(crate) split: SplitArgs,
    #[command(flatten)]
    pub(crate) common: CommonArgs,
}

/// How a render is split across machines and time.
#[derive(Args, Debug)]
pub(crate) struct SplitArgs {
    /// Render only tile K of N (0-based; N bands of rows); the EXR's data window
    /// is the tile inside the full image, for `gradtrace merge`.
    #[arg(long, value_name = "K/N", value_parser = parse_tile, allow_hyphen_values = true, conflicts_with_all = ["crop", "strategy"])]
    pub(crate) tile: Option<(u32, u32)>,
    /// Render only the pixels x0 ≤ x < x1, y0 ≤ y < y1 (like pbrt-v4's --pixelbounds).
    #[arg(long, value_name = "x0,y0,x1,y1", value_parser = parse_crop, allow_hyphen_values = true, conflicts_with = "strategy")]
    pub(crate) crop: Option<Crop>,
    /// Render only sample indices A..B−1 of every pixel (of --spp); disjoint
    /// ranges are pieces of one render, combined by `gradtrace merge`.
    #[arg(long, value_name = "A:B", value_parser = parse_spp_range, allow_hyphen_values = true, conflicts_with = "strategy")]
    pub(crate) spp_range: Option<(u32, u32)>,
    /// Render in passes of doubling sample count until SECONDS have passed (at most
    /// --spp, default 2^20), then write the samples reached; Ctrl-C writes the
    /// passes finished so far.
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds, conflicts_with_all = ["strategy", "spp_range"])]
    pub(crate) time_limit: Option<f64>,
    /// Continue the render in FILE.exr (written with --time-limit or --spp-range)
    /// up to --spp or --time-limit; writes FILE.exr unless --out says otherwise.
    #[arg(long, value_name = "FILE.exr", conflicts_with_all = ["strategy", "spp_range", "tile", "crop", "noise_threshold"])]
    pub(crate) resume: Option<PathBuf>,
    /// Cycles-style per-pixel adaptive sampling: a pixel stops when its noise
    /// estimate falls below this (Blender's "Noise Threshold", e.g. 0.01); --spp
    /// is the most samples a pixel gets [default: 1024]. Writes `samples.spp`.
    #[arg(long, value_name = "F", conflicts_with_all = ["strategy", "spp_range", "tile", "crop"])]
    pub(crate) noise_threshold: Option<f32>,
    /// With --noise-threshold: samples every pixel takes before its first check
    /// [default: Cycles' max(4, 16 / threshold^0.3), at most max(4, --spp / 4)].
    #[arg(long, value_name = "N", requires = "noise_threshold", value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) min_spp: Option<u32>,
}

pub(crate) fn parse_tile(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("{s:?}: expected K/N with 0 ≤ K < N, e.g. 3/8");
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let (k, n): (u32, u32) = (k.parse().map_err(|_| bad())?, n.parse().map_err(|_| bad())?);
    (k < n).then_some((k, n)).ok_or_else(bad)
}

pub(crate) fn parse_crop(s: &str) -> Result<Crop, String> {
    let bad = || format!("{s:?}: expected x0,y0,x1,y1 in pixels with x0 < x1, y0 < y1");
    let v: Vec<u32> = s
        .split(',')
        .map(|t| t.trim().parse().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    let [x0, y0, x1, y1] = v[..] else {
        return Err(bad());
    };
    (x0 < x1 && y0 < y1)
        .then_some(Crop { x0, y0, x1, y1 })
        .ok_or_else(bad)
}

pub(crate) fn parse_spp_range(s: &str) -> Result<(u32, u32), String> {
    gradtrace::pipeline::merge::parse_range(s)
        .ok_or_else(|| format!("{s:?}: expected A:B with A < B, e.g. 0:256"))
}

pub(crate) fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(t) if t.is_finite() && t > 0.0 && t < 1e9 => Ok(t),
        _ => Err(format!(
            "{s:?}: expected a number of seconds in (0, 1e9) (1e9 s is 31 years)"
        )),
    }
}

/// The options every rendering command takes.
#[derive(Args, Debug)]
pub(crate) struct CommonArgs {
    /// Samples per pixel (per evaluated point for adaptive samples)
    /// [default: the scene's `[render] spp`].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) spp: Option<u32>,
    /// Image width in pixels; needs --height [default: the camera's resolution].
    #[arg(long, value_name = "W", requires = "height", value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) width: Option<u32>,
    /// Image height in pixels; needs --width [default: the camera's resolution].
    #[arg(long, value_name = "H", requires = "width", value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) height: Option<u32>,
    /// Random seed; the same seed gives the same image (compare's reference uses
    /// its own stream derived from it) [default: the scene's `[render] seed`].
    #[arg(long, value_name = "S")]
    pub(crate) seed: Option<u32>,
    /// Worker threads; never changes an image [default: all cores].
    #[arg(long, value_name = "T", value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) threads: Option<u32>,
    /// Refuse a run estimated to need more memory than this many GiB
    /// [default: 90% of the memory available].
    #[arg(long, value_name = "GIB", value_parser = gibibytes)]
    pub(crate) max_memory: Option<f32>,
    /// No progress output and no summary.
    #[arg(long, short)]
    pub(crate) quiet: bool,
}

#[derive(Args, Debug)]
pub(crate) struct InfoArgs {
    /// Scene file (TOML).
    pub(crate) scene: PathBuf,
}

/// A finite number > 0 (NaN, infinities and negatives are refused by name).
pub(crate) fn positive(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("expected a finite number > 0, got {s:?}")),
    }
}

/// A memory limit in GiB: at least 1 MiB, which no run fits in anyway; below
/// it a message would have to speak of "0 MiB allowed".
pub(crate) fn gibibytes(s: &str) -> Result<f32, String> {
    match positive(s) {
        Ok(v) if v >= 1.0 / 1024.0 => Ok(v),
        _ => Err(format!(
            "expected a number of GiB ≥ 0.0009765625 (1 MiB), got {s:?}"
        )),
    }
}

/// A budget: samples per pixel in (0, 16], e.g. 0.17 for 17% of the pixels.
pub(crate) fn budget(s: &str) -> Result<f32, String> {
    match positive(s) {
        Ok(v) if v <= 16.0 => Ok(v),
        _ => Err(format!(
            "expected samples per pixel in (0, 16], e.g. 0.17, got {s:?}"
        )),
    }
}

/// A budget of `compare`: as [`budget`], but kept as the f64 of what was written,
/// which `report.json` prints back unchanged (0.17, not 0.17000000178813934).
pub(crate) fn compare_budget(s: &str) -> Result<f64, String> {
    budget(s)?;
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && v <= 16.0 => Ok(v),
        _ => Err(format!(
            "expected samples per pixel in (0, 16], e.g. 0.17, got {s:?}"
        )),
    }
}

/// `--vis-gate`: a probability in (0, 1] (0 would never march a line, a bias).
pub(crate) fn vis_gate(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v > 0.0 && v <= 1.0 => Ok(v),
        _ => Err(format!(
            "expected a probability in (0, 1], e.g. 0.125, got {s:?}"
        )),
    }
}

/// A closed set of the library's (`Strategy`, `Interpolation`, `Integrator`) as a
/// clap parser: the choices are the library's names (listed in `--help` and in
/// the error), `aliases` the spellings of earlier versions.
pub(crate) fn choices<T: Copy + Send + Sync + 'static>(
    all: &'static [T],
    name: fn(T) -> &'static str,
    aliases: fn(T) -> &'static [&'static str],
) -> impl TypedValueParser<Value = T> {
    let values = all
        .iter()
        .map(|&v| PossibleValue::new(name(v)).aliases(aliases(v).iter().copied()));
    PossibleValuesParser::new(values).map(move |typed| {
        let canonical = all
            .iter()
            .find(|&&v| name(v) == typed || aliases(v).contains(&typed.as_str()));
        // The parser only lets listed spellings through.
        *canonical.unwrap_or(&all[0])
    })
}

pub(crate) fn strategy() -> impl TypedValueParser<Value = Strategy> {
    choices(&Strategy::ALL, Strategy::name, Strategy::aliases)
}

pub(crate) fn interpolation() -> impl TypedValueParser<Value = Interpolation> {
    choices(&Interpolation::ALL, Interpolation::name, |_| &[])
}

pub(crate) fn integrator() -> impl TypedValueParser<Value = Integrator> {
    choices(&Integrator::ALL, Integrator::name, |_| &[])
}

pub(crate) fn equal_cost() -> impl TypedValueParser<Value = EqualCost> {
    choices(&[EqualCost::Wall, EqualCost::Cpu], EqualCost::name, |_| &[])
}

pub(crate) fn reconstruct_norm(
) -> impl TypedValueParser<Value = gradtrace::reconstruct::poisson::Norm> {
    use gradtrace::reconstruct::poisson::Norm;
    choices(&Norm::ALL, Norm::name, |_| &[])
}

pub(crate) fn diff_metric() -> impl TypedValueParser<Value = DiffMetric> {
    choices(&DiffMetric::ALL, DiffMetric::name, |_| &[])
}

/// `out/preview-<method>/<scene path>`: the folder a preview writes when not told.
pub(crate) fn preview_dir(method: &str, scene: &std::path::Path) -> PathBuf {
    let name = compare::default_dir(scene);
    let name = name.file_name().map_or("scene".into(), |n| n.to_owned());
    PathBuf::from("out")
        .join(format!("preview-{method}"))
        .join(name)
}

/// A flag that Ctrl-C sets (a second Ctrl-C exits at once), for renders in passes.
pub(crate) fn cancel_on_ctrl_c() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let set = flag.clone();
    let installed = ctrlc::set_handler(move || {
        if set.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!("interrupted: writing the passes finished so far (Ctrl-C again to abort)");
    });
    if installed.is_err() {
        eprintln!("warning: cannot catch Ctrl-C; an interrupt will write nothing");
    }
    flag
}

impl RenderArgs {
    pub(crate) fn into_job(self) -> pipeline::render::RenderJob {
        let sp = self.split;
        let time_limit = sp.time_limit.map(Duration::from_secs_f64);
        let passes = Passes {
            time_limit: time_limit.filter(|_| sp.noise_threshold.is_none()),
            cancel: (sp.time_limit.is_some() || sp.resume.is_some()).then(cancel_on_ctrl_c),
        };
        let noise_adaptive = sp.noise_threshold.map(|t| {
            let max_spp = self.common.spp.unwrap_or(1024);
            let mut s = NoiseAdaptive::new(t, max_spp);
            if let Some(m) = sp.min_spp {
                s.min_spp = m;
            }
            s.time_limit = time_limit;
            s
        });
        let adaptive = self.strategy.map(|s| {
            let settings = Settings::new(s, self.budget.unwrap_or(0.17));
            let interpolation = self.interpolation.unwrap_or(Interpolation::Gradient);
            (settings, interpolation)
        });
        let c = self.common;
        pipeline::render::RenderJob {
            options: RenderOptions {
                spp: c.spp,
                max_depth: self.max_depth,
                seed: c.seed,
                integrator: self.integrator,
                resolution: c.width.zip(c.height),
                aovs: !self.no_aovs,
                gradients: self.gradients,
                vis_samples: self.vis_samples,
                vis_refine: self.vis_refine,
                vis_gate: self.vis_gate,
                far_light: self.far_light,
                gradient_spp: self.gradient_spp,
                crop: sp.crop,
                sample_range: sp.spp_range,
                merge_planes: false,
                no_lanes: self.no_lanes,
            },
            tile: sp.tile,
            passes,
            resume: sp.resume,
            noise_adaptive,
            command: gradtrace::pipeline::command_line(),
            adaptive,
            denoise: self.denoise,
            reconstruct: self.reconstruct,
            dense_adaptive: self.dense_adaptive,
            threads: c.threads,
            max_memory: c
                .max_memory
                .map(|g| (f64::from(g) * (1u64 << 30) as f64) as u64),
            progress: ProgressMode::detect(c.quiet),
            out: self.out,
            scene: self.scene,
        }
    }
}

impl CompareArgs {
    /// The options, writing to `--out` or the scene's default folder.
    pub(crate) fn options(&self) -> CompareOptions {
        let dir = self
            .out
            .clone()
            .unwrap_or_else(|| compare::default_dir(&self.scene));
        let mut opts = CompareOptions::new(dir);
        if !self.strategies.is_empty() {
            opts.strategies = self.strategies.clone();
        }
        if !self.budgets.is_empty() {
            opts.budgets = self.budgets.clone();
        }
        let c = &self.common;
        opts.spp = c.spp;
        opts.reference_spp = self.reference_spp;
        opts.resolution = c.width.zip(c.height);
        if self.vis_samples.is_some() {
            opts.vis_samples = self.vis_samples;
        }
        opts.gradient_spp = self.gradient_spp;
        opts.seed = c.seed;
        opts.seeds = self.seeds;
        opts.keep_exr = self.keep_exr;
        opts.all_images = self.all_images;
        opts.equal = self.equal.unwrap_or_default();
        opts.previews = !self.no_previews;
        opts.command = std::env::args().collect::<Vec<_>>().join(" ");
        opts
    }
}
