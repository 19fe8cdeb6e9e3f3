//! `gradtrace` command line: clap types and one dispatch into `pipeline`.
//!
//! Everything that can fail reports ONE line `error: <message>` on stderr and exits
//! with status 1; a failed run leaves every previous output untouched.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand};
use gradtrace::adaptive::{Settings, Strategy};
use gradtrace::error::{error_line, one_line};
use gradtrace::pipeline::{self, compare::CompareOptions, progress::ProgressMode};
use gradtrace::reconstruct::Interpolation;
use gradtrace::render::RenderOptions;
use gradtrace::scene::Integrator;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(
    name = "gradtrace",
    version,
    about = "CPU path tracer: renders a TOML scene file to a multi-layer EXR and a PNG"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene to an EXR (beauty + AOV layers) and a tone-mapped PNG.
    Render(RenderArgs),
    /// Print what a scene holds (geometry, materials, lights, camera, settings) and
    /// the BVH build time.
    Info(InfoArgs),
    /// Render a cached high-quality reference, every adaptive-sampling strategy at
    /// several budgets and equal-time baselines, and write `out/<scene>/report.html`
    /// (self-contained), `report.json` and `report.md`.
    Compare(CompareArgs),
}

#[derive(Args, Debug)]
struct CompareArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Comma-separated strategies [default: all].
    #[arg(long, value_parser = strategy(), value_name = "LIST", value_delimiter = ',')]
    strategies: Vec<Strategy>,
    /// Comma-separated budgets in samples per pixel [default: 0.05,0.1,0.17,0.25,0.5].
    #[arg(
        long,
        value_name = "LIST",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    budgets: Vec<f32>,
    /// Samples per pixel of the reference (cached in the output folder) [default: 8 × spp].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    reference_spp: Option<u32>,
    /// Shadow rays per line for the samples' visibility gradients; 0 samples the
    /// lights by points and drops the visibility term [default: 4].
    #[arg(long, value_name = "N")]
    vis_samples: Option<u32>,
    /// How many of each adaptive sample's camera samples carry the analytic
    /// gradient; the rest only refine its radiance [default: min(spp, 16)].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    gradient_spp: Option<u32>,
    /// Output folder [default: out/<scene-stem>].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    #[command(flatten)]
    common: CommonArgs,
}

#[derive(Args, Debug)]
struct RenderArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Longest path in segments from the camera; 1 = only directly visible
    /// emitters [default: the scene's `[render] max_depth`].
    #[arg(long, value_name = "N")]
    max_depth: Option<u32>,
    /// Output EXR path; the PNG is written next to it with the same stem
    /// [default: out/<scene-stem>.exr].
    #[arg(long, value_name = "PATH")]
    out: Option<PathBuf>,
    /// Estimator: `path` (full path tracing) or `direct` (direct lighting only)
    /// [default: the scene's `[render] integrator`].
    #[arg(long, value_parser = integrator(), value_name = "KIND")]
    integrator: Option<Integrator>,
    /// Skip the AOV layers (normal, depth, albedo, object id, variance): the EXR
    /// then holds only R, G, B.
    #[arg(long)]
    no_aovs: bool,
    /// Also compute the analytic image gradients (direct illumination, and the
    /// curvature/bump and camera terms of indirect light) and write them as `grad.*` layers (∂I/∂u, ∂I/∂v and the per-term magnitudes).
    #[arg(long)]
    gradients: bool,
    /// With --gradients: shadow rays per azimuth line for the first hit's direct
    /// light; the same rays give the radiance and the visibility (soft-shadow)
    /// gradient [default: 32; 4 with --strategy]. 0: point light sampling and no
    /// visibility term.
    #[arg(long, value_name = "N")]
    vis_samples: Option<u32>,
    /// With --gradients: bisection steps refining each visibility jump (extra
    /// shadow rays per jump) [default: 0].
    #[arg(long, value_name = "N")]
    vis_refine: Option<u32>,
    /// With --gradients: treat a near light as distant (no SV term) where
    /// 2|n_x|·d exceeds F, the far-light criterion of the first-order paper, Sec. 5.2.
    #[arg(long, value_name = "F")]
    far_light: Option<f32>,
    /// With --strategy: how many of each sample's --spp camera samples carry the
    /// analytic gradient; the rest only refine its radiance [default: min(spp, 16)].
    #[arg(long, value_name = "N", requires = "strategy", value_parser = clap::value_parser!(u32).range(1..))]
    gradient_spp: Option<u32>,
    /// Adaptive sampling: place samples with this strategy and reconstruct every
    /// pixel from them; each sample is a --spp estimate with analytic gradients.
    #[arg(long, value_parser = strategy(), value_name = "NAME")]
    strategy: Option<Strategy>,
    /// With --strategy: samples per pixel, e.g. 0.17 evaluates 17% as many points
    /// as there are pixels [default: 0.17].
    #[arg(
        long,
        value_name = "F",
        requires = "strategy",
        allow_negative_numbers = true
    )]
    budget: Option<f32>,
    /// With --strategy: how every pixel is rebuilt from the samples [default: gradient].
    #[arg(long, value_parser = interpolation(), value_name = "KIND", requires = "strategy")]
    interpolation: Option<Interpolation>,
    #[command(flatten)]
    common: CommonArgs,
}

/// The options every rendering command takes.
#[derive(Args, Debug)]
struct CommonArgs {
    /// Samples per pixel (per evaluated point for adaptive samples)
    /// [default: the scene's `[render] spp`].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    spp: Option<u32>,
    /// Image width in pixels; needs --height [default: the camera's resolution].
    #[arg(long, value_name = "W", requires = "height", value_parser = clap::value_parser!(u32).range(1..))]
    width: Option<u32>,
    /// Image height in pixels; needs --width [default: the camera's resolution].
    #[arg(long, value_name = "H", requires = "width", value_parser = clap::value_parser!(u32).range(1..))]
    height: Option<u32>,
    /// Random seed; the same seed gives the same image (compare's reference uses
    /// its own stream derived from it) [default: the scene's `[render] seed`].
    #[arg(long, value_name = "S")]
    seed: Option<u32>,
    /// Worker threads; never changes an image [default: all cores].
    #[arg(long, value_name = "T", value_parser = clap::value_parser!(u32).range(1..))]
    threads: Option<u32>,
    /// No progress output and no summary.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args, Debug)]
struct InfoArgs {
    /// Scene file (TOML).
    scene: PathBuf,
}

/// A closed set of the library's (`Strategy`, `Interpolation`, `Integrator`) as a
/// clap parser: the choices are the library's names (listed in `--help` and in
/// the error), `aliases` the spellings of earlier versions.
fn choices<T: Copy + Send + Sync + 'static>(
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

fn strategy() -> impl TypedValueParser<Value = Strategy> {
    choices(&Strategy::ALL, Strategy::name, Strategy::aliases)
}

fn interpolation() -> impl TypedValueParser<Value = Interpolation> {
    choices(&Interpolation::ALL, Interpolation::name, |_| &[])
}

fn integrator() -> impl TypedValueParser<Value = Integrator> {
    choices(&Integrator::ALL, Integrator::name, |_| &[])
}

fn main() -> ExitCode {
    // A bug must still end as one `error:` line and status 1, not a backtrace.
    gradtrace::error::one_line_panics();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            match e.kind() {
                // --help, --version and a bare `gradtrace` are not failures of a run.
                ErrorKind::DisplayHelp
                | ErrorKind::DisplayVersion
                | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => e.exit(),
                _ => {
                    // clap's message is several lines (the problem, then usage and
                    // tips); keep the problem.
                    let text = e.render().to_string();
                    let problem =
                        one_line(text.split("\n\n").next().unwrap_or("invalid arguments"));
                    let problem = problem.strip_prefix("error: ").unwrap_or(&problem);
                    eprintln!("error: {problem} (see --help)");
                    return ExitCode::FAILURE;
                }
            }
        }
    };
    match std::panic::catch_unwind(|| run(cli)) {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) => {
            eprintln!("error: {}", error_line(e.chain()));
            ExitCode::FAILURE
        }
        // The hook already printed the line.
        Err(_) => ExitCode::FAILURE,
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Render(args) => {
            let quiet = args.common.quiet;
            let summary = pipeline::render::run(&args.into_job())?;
            if !quiet {
                println!("{summary}");
            }
        }
        Command::Info(args) => print!("{}", pipeline::info(&args.scene)?),
        Command::Compare(args) => {
            let dir = args.out.clone().unwrap_or_else(|| default_dir(&args.scene));
            let opts = args.options(dir.clone());
            let mode = ProgressMode::detect(args.common.quiet);
            let rows = pipeline::compare::run(&args.scene, args.common.threads, &opts, mode)?;
            if !args.common.quiet {
                println!("{}", gradtrace::output::report::markdown_table(&rows));
                println!("wrote {}", dir.join("report.html").display());
            }
        }
    }
    Ok(())
}

/// `out/<scene-stem>`: where a command writes when not told.
fn default_dir(scene: &Path) -> PathBuf {
    let stem = scene
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy());
    Path::new("out").join(stem.as_ref())
}

impl RenderArgs {
    fn into_job(self) -> pipeline::render::RenderJob {
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
                far_light: self.far_light,
                gradient_spp: self.gradient_spp,
                ..Default::default()
            },
            adaptive,
            threads: c.threads,
            progress: ProgressMode::detect(c.quiet),
            out: self.out,
            scene: self.scene,
        }
    }
}

impl CompareArgs {
    fn options(&self, dir: PathBuf) -> CompareOptions {
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
        opts
    }
}
