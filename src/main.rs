//! `gradtrace` command line: a thin layer over the library pipeline
//! (`scene::load` → `accel::Accel::build` → `render::render` → `output`).
//!
//! Everything that can fail reports ONE line `error: <message>` on stderr and exits
//! with status 1; a failed run leaves every previous output untouched (both files
//! are encoded to temporary files first and renamed into place only when both
//! encodes succeeded).

use anyhow::{bail, Context};
use clap::{Args, Parser, Subcommand, ValueEnum};
use gradtrace::accel::Accel;
use gradtrace::brdf::Material;
use gradtrace::math::Vec3;
use gradtrace::output;
use gradtrace::render::{self, RenderOptions, RenderOutput};
use gradtrace::scene::{self, Environment, Integrator, Scene};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

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
    /// Comma-separated strategies [default: all: uniform, gradient, durand,
    /// variance, gradient+vis, second-order].
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    strategies: Vec<String>,
    /// Comma-separated budgets in samples per pixel [default: 0.05,0.1,0.17,0.25,0.5].
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    budgets: Vec<f32>,
    /// Samples per evaluated point (adaptive samples and full-render pixels)
    /// [default: the scene's `[render] spp`].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    spp: Option<u32>,
    /// Samples per pixel of the reference (cached in the output folder) [default: 8 × spp].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    reference_spp: Option<u32>,
    /// Image width in pixels [default: the scene's].
    #[arg(long, value_name = "W", requires = "height", value_parser = clap::value_parser!(u32).range(1..))]
    width: Option<u32>,
    /// Image height in pixels [default: the scene's].
    #[arg(long, value_name = "H", requires = "width", value_parser = clap::value_parser!(u32).range(1..))]
    height: Option<u32>,
    /// Shadow rays per line for the samples' visibility gradients; 0 samples the
    /// lights by points and drops the visibility term [default: 4].
    #[arg(long, value_name = "N")]
    vis_samples: Option<u32>,
    /// How many of each adaptive sample's camera samples carry the analytic
    /// gradient; the rest only refine its radiance [default: min(spp, 16)].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    gradient_spp: Option<u32>,
    /// Random seed of every run; the reference uses its own stream derived from it
    /// [default: the scene's `[render] seed`].
    #[arg(long, value_name = "S")]
    seed: Option<u32>,
    /// Output folder [default: out/<scene-stem>].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// No progress output and no summary table.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args, Debug)]
struct RenderArgs {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Samples per pixel [default: the scene's `[render] spp`].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    spp: Option<u32>,
    /// Longest path in segments from the camera; 1 = only directly visible
    /// emitters [default: the scene's `[render] max_depth`].
    #[arg(long, value_name = "N")]
    max_depth: Option<u32>,
    /// Image width in pixels; needs --height [default: the camera's resolution].
    #[arg(long, value_name = "W", requires = "height",
          value_parser = clap::value_parser!(u32).range(1..))]
    width: Option<u32>,
    /// Image height in pixels; needs --width [default: the camera's resolution].
    #[arg(long, value_name = "H", requires = "width",
          value_parser = clap::value_parser!(u32).range(1..))]
    height: Option<u32>,
    /// Random seed; the same seed gives the same image [default: the scene's
    /// `[render] seed`].
    #[arg(long, value_name = "S")]
    seed: Option<u32>,
    /// Worker threads; never changes the image [default: all cores].
    #[arg(long, value_name = "T", value_parser = clap::value_parser!(u32).range(1..))]
    threads: Option<u32>,
    /// Output EXR path; the PNG is written next to it with the same stem
    /// [default: out/<scene-stem>.exr].
    #[arg(long, value_name = "PATH")]
    out: Option<PathBuf>,
    /// Estimator: `path` (full path tracing) or `direct` (direct lighting only)
    /// [default: the scene's `[render] integrator`].
    #[arg(long, value_enum, value_name = "KIND")]
    integrator: Option<IntegratorArg>,
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
    /// Adaptive sampling: place samples with this strategy (uniform, gradient,
    /// durand, variance, gradient+vis, second-order) and reconstruct every pixel
    /// from them; each sample is a --spp estimate with analytic gradients.
    #[arg(long, value_name = "NAME")]
    strategy: Option<String>,
    /// With --strategy: samples per pixel, e.g. 0.17 evaluates 17% as many points
    /// as there are pixels [default: 0.17].
    #[arg(long, value_name = "F", requires = "strategy")]
    budget: Option<f32>,
    /// With --strategy: `linear` (barycentric) or `gradient` (Sibson C1 with the
    /// analytic gradients) reconstruction [default: gradient].
    #[arg(long, value_name = "KIND", requires = "strategy")]
    interpolation: Option<String>,
    /// No progress bar and no summary line.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Args, Debug)]
struct InfoArgs {
    /// Scene file (TOML).
    scene: PathBuf,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum IntegratorArg {
    /// Unidirectional path tracing with next-event estimation and MIS.
    Path,
    /// Direct lighting only.
    Direct,
}

impl From<IntegratorArg> for Integrator {
    fn from(a: IntegratorArg) -> Self {
        match a {
            IntegratorArg::Path => Integrator::Path,
            IntegratorArg::Direct => Integrator::Direct,
        }
    }
}

/// Set by the first panic so that a panic in several worker threads prints one line.
static PANICKED: AtomicBool = AtomicBool::new(false);

fn main() -> ExitCode {
    // A bug must still end as one `error:` line and status 1, not a backtrace.
    std::panic::set_hook(Box::new(|info| {
        if !PANICKED.swap(true, Ordering::SeqCst) {
            let msg = info
                .payload()
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| info.payload().downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "panic".into());
            let at = info
                .location()
                .map(|l| format!(" at {}:{}", l.file(), l.line()))
                .unwrap_or_default();
            eprintln!("error: internal error: {}{at}", one_line(&msg));
        }
    }));

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
                    // tips); keep the problem, on one line.
                    let text = e.render().to_string();
                    let problem = text.split("\n\n").next().unwrap_or("invalid arguments");
                    let problem = one_line(problem);
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
            eprintln!("error: {}", error_line(&e));
            ExitCode::FAILURE
        }
        // The hook already printed the line.
        Err(_) => ExitCode::FAILURE,
    }
}

/// The error and its causes as one line. Library errors already quote their
/// source in their own message, so a cause whose text is already there is skipped.
fn error_line(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = one_line(&cause.to_string());
        if !line.contains(&text) {
            if !line.is_empty() {
                line.push_str(": ");
            }
            line.push_str(&text);
        }
    }
    line
}

/// Collapses a possibly multi-line message (e.g. a TOML parser's snippet) into
/// one line, so that `error:` output stays one line per failure.
fn one_line(msg: &str) -> String {
    msg.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Render(args) => render_cmd(args),
        Command::Info(args) => info_cmd(args),
        Command::Compare(args) => compare_cmd(args),
    }
}

/// The EXR and PNG paths of a run: `--out` names the EXR, the PNG shares its stem.
fn output_paths(out: Option<&Path>, scene_stem: &str) -> anyhow::Result<(PathBuf, PathBuf)> {
    let exr = match out {
        Some(p) => p.to_path_buf(),
        None => Path::new("out").join(format!("{scene_stem}.exr")),
    };
    if exr.file_name().is_none() {
        bail!("--out {}: does not name a file", exr.display());
    }
    let png = exr.with_extension("png");
    if png == exr {
        bail!(
            "--out {}: names the PNG; give the EXR path (e.g. {})",
            exr.display(),
            exr.with_extension("exr").display()
        );
    }
    for p in [&exr, &png] {
        if p.is_dir() {
            bail!("{}: cannot write output: is a directory", p.display());
        }
    }
    Ok((exr, png))
}

fn render_cmd(args: RenderArgs) -> anyhow::Result<()> {
    // Settle the output paths before spending time on loading and rendering. The
    // stem is the scene file's, as `Scene::name` gives it.
    let stem = args
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let (exr_path, png_path) = output_paths(args.out.as_deref(), &stem)?;
    let scene = scene::load(&args.scene)?;

    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let opts = RenderOptions {
        spp: args.spp,
        max_depth: args.max_depth,
        seed: args.seed,
        integrator: args.integrator.map(Into::into),
        resolution: args.width.zip(args.height),
        aovs: !args.no_aovs,
        gradients: args.gradients,
        vis_samples: args.vis_samples,
        vis_refine: args.vis_refine,
        far_light: args.far_light,
        gradient_spp: args.gradient_spp,
    };

    if let Some(name) = &args.strategy {
        return adaptive_cmd(&args, name, &scene, &accel, &opts, &exr_path, &png_path);
    }

    let bar = progress_bar(args.quiet);
    // Tiles finish out of order on worker threads; show the furthest count seen.
    let done_max = AtomicUsize::new(0);
    let progress = |done: usize, total: usize| {
        let done = done_max.fetch_max(done, Ordering::Relaxed).max(done);
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    };
    let result = match args.threads {
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t as usize)
            .build()
            .context("cannot start the worker threads")?
            .install(|| render::render(&scene, &accel, &opts, &progress)),
        None => render::render(&scene, &accel, &opts, &progress),
    };
    bar.finish_and_clear();
    let out = result?;

    write_outputs(
        &output::image_from_render(&out),
        &out.beauty,
        (out.width, out.height),
        &exr_path,
        &png_path,
    )?;

    if !args.quiet {
        println!(
            "{}x{}, {} spp, {:.3} s, {}, wrote {} and {}",
            out.width,
            out.height,
            out.spp,
            out.stats.wall_time.as_secs_f64(),
            rays_per_second(&out),
            exr_path.display(),
            png_path.display()
        );
    }
    Ok(())
}

/// `render --strategy`: quadtree sampling with the renderer as estimator, then
/// reconstruction; the EXR holds R,G,B, `samples.density` and `samples.Y`.
fn adaptive_cmd(
    args: &RenderArgs,
    name: &str,
    scene: &gradtrace::scene::Scene,
    accel: &Accel,
    opts: &RenderOptions,
    exr_path: &Path,
    png_path: &Path,
) -> anyhow::Result<()> {
    use gradtrace::adaptive::{Settings, Strategy};
    use gradtrace::reconstruct::Interpolation;
    let strategy = Strategy::from_name(name)?;
    let interpolation =
        Interpolation::from_name(args.interpolation.as_deref().unwrap_or("gradient"))?;
    let settings = Settings::new(strategy, args.budget.unwrap_or(0.17));
    let bar = progress_bar(args.quiet);
    let progress = |done: usize, total: usize| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    };
    let run = || {
        render::adaptive::render_adaptive(scene, accel, opts, &settings, interpolation, &progress)
    };
    let result = match args.threads {
        Some(t) => rayon::ThreadPoolBuilder::new()
            .num_threads(t as usize)
            .build()
            .context("cannot start the worker threads")?
            .install(run),
        None => run(),
    };
    bar.finish_and_clear();
    let out = result?;
    let rec = &out.reconstruction;
    let mut image = rec.to_output_image();
    // Marks the pixels that hold at least one sample (Fig. 14/15's dots).
    image.channels.push(output::Channel {
        name: "samples.Y".into(),
        data: rec
            .density
            .iter()
            .map(|&d| if d > 0.0 { 1.0 } else { 0.0 })
            .collect(),
    });
    write_outputs(
        &image,
        &rec.image,
        (rec.width, rec.height),
        exr_path,
        png_path,
    )?;
    if !args.quiet {
        let st = &out.stats;
        println!(
            "{}x{}, {} at budget {}: {} samples, {:.3} s (quadtree {:.3} s, reconstruction {:.3} s), wrote {} and {}",
            rec.width,
            rec.height,
            strategy.name(),
            settings.budget,
            out.samples.samples.len(),
            st.wall_s,
            st.quadtree_s,
            st.reconstruct_s,
            exr_path.display(),
            png_path.display()
        );
    }
    Ok(())
}

fn compare_cmd(args: CompareArgs) -> anyhow::Result<()> {
    use gradtrace::adaptive::Strategy;
    use gradtrace::compare::{compare, CompareOptions};
    let stem = args
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let dir = args
        .out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&stem));
    let mut opts = CompareOptions::new(dir.clone());
    if !args.strategies.is_empty() {
        opts.strategies = args
            .strategies
            .iter()
            .map(|s| Strategy::from_name(s.trim()))
            .collect::<Result<_, _>>()?;
    }
    if !args.budgets.is_empty() {
        opts.budgets = args.budgets.clone();
    }
    opts.spp = args.spp;
    opts.reference_spp = args.reference_spp;
    opts.resolution = args.width.zip(args.height);
    if args.vis_samples.is_some() {
        opts.vis_samples = args.vis_samples;
    }
    opts.gradient_spp = args.gradient_spp;
    opts.seed = args.seed;
    let scene = scene::load(&args.scene)?;
    let accel = Accel::build(&scene.meshes, &scene.spheres);
    let bar = progress_bar(args.quiet);
    let steps = 3 + opts.strategies.len() * opts.budgets.len() + 2 + opts.budgets.len();
    bar.set_length(steps as u64);
    let progress = |msg: &str| {
        bar.inc(1);
        bar.set_message(msg.to_string());
    };
    let rows = compare(&scene, &accel, &opts, &progress)?;
    bar.finish_and_clear();
    if !args.quiet {
        println!("{}", gradtrace::output::report::markdown_table(&rows));
        println!("wrote {}", dir.join("report.html").display());
    }
    Ok(())
}

/// The progress bar on stderr, or a hidden one when stderr is not a terminal
/// (logs, pipes, tests) or with --quiet.
fn progress_bar(quiet: bool) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr());
    if let Ok(style) =
        ProgressStyle::with_template("{elapsed_precise} [{wide_bar}] {pos}/{len} tiles, ETA {eta}")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

fn rays_per_second(out: &RenderOutput) -> String {
    let secs = out.stats.wall_time.as_secs_f64();
    if secs > 0.0 {
        format!("{:.2} Mrays/s", out.stats.rays as f64 / secs / 1e6)
    } else {
        "- Mrays/s".into()
    }
}

/// Encodes both files to temporary files, then renames both into place: an
/// encoding failure of either leaves every previous output untouched. Creates the
/// output directory when missing and removes it again if the run then fails.
fn write_outputs(
    image: &output::OutputImage,
    beauty: &[glam::Vec3],
    (width, height): (usize, usize),
    exr: &Path,
    png: &Path,
) -> anyhow::Result<()> {
    let dir = exr.parent().filter(|d| !d.as_os_str().is_empty());
    let created = match dir {
        Some(d) => create_dirs(d)?,
        None => Vec::new(),
    };
    let staged = output::stage_exr(exr, image)
        .and_then(|e| output::stage_png(png, beauty, width, height, 0.0).map(|p| (e, p)));
    let result = staged.and_then(|(e, p)| {
        e.commit()?;
        p.commit()
    });
    if result.is_err() {
        // Innermost first; `remove_dir` only removes empty directories.
        for d in created.iter().rev() {
            let _ = std::fs::remove_dir(d);
        }
    }
    Ok(result?)
}

/// `create_dir_all` that returns the directories it created, outermost first.
fn create_dirs(dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
    let missing: Vec<PathBuf> = dir
        .ancestors()
        .take_while(|a| !a.as_os_str().is_empty() && !a.exists())
        .map(Path::to_path_buf)
        .collect();
    std::fs::create_dir_all(dir)
        .with_context(|| format!("{}: cannot create the output directory", dir.display()))?;
    Ok(missing.into_iter().rev().collect())
}

fn info_cmd(args: InfoArgs) -> anyhow::Result<()> {
    let scene = scene::load(&args.scene)?;
    let t0 = Instant::now();
    // Kept alive until after the timing so that its drop is not measured.
    let _accel = Accel::build(&scene.meshes, &scene.spheres);
    let build = t0.elapsed();
    print!("{}", describe(&scene));
    println!("renderer: {}", render::describe(&scene));
    println!(
        "bvh: built in {:.3} ms ({} primitives)",
        build.as_secs_f64() * 1e3,
        scene
            .meshes
            .iter()
            .map(|m| m.triangles.len())
            .sum::<usize>()
            + scene.spheres.len()
    );
    Ok(())
}

fn v3(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

fn material_kind(m: &Material) -> String {
    match m {
        Material::Lambert { albedo } => format!("lambert albedo={}", v3(*albedo)),
        Material::BlinnPhong { kd, ks, exponent } => {
            format!(
                "blinn_phong kd={} ks={} exponent={exponent}",
                v3(*kd),
                v3(*ks)
            )
        }
        Material::CookTorrance { kd, ks, exponent } => {
            format!(
                "cook_torrance kd={} ks={} exponent={exponent}",
                v3(*kd),
                v3(*ks)
            )
        }
        Material::Mirror { reflectance } => format!("mirror reflectance={}", v3(*reflectance)),
    }
}

fn environment_kind(e: Option<&Environment>) -> String {
    match e {
        None => "none (black)".into(),
        Some(Environment::Constant { radiance }) => format!("constant radiance={}", v3(*radiance)),
        Some(Environment::Image {
            width,
            height,
            scale,
            ..
        }) => format!("image {width}x{height} scale={scale}"),
        Some(Environment::GaussianSky {
            direction,
            sharpness,
            peak,
            ambient,
        }) => format!(
            "gaussian_sky direction={} sharpness={sharpness} peak={} ambient={}",
            v3(*direction),
            v3(*peak),
            v3(*ambient)
        ),
    }
}

/// The `info` report (everything but the BVH line), one fact per line.
fn describe(s: &Scene) -> String {
    use std::fmt::Write;
    let mut o = String::new();
    let tris: usize = s.meshes.iter().map(|m| m.triangles.len()).sum();
    let with_normals = s.meshes.iter().filter(|m| !m.normals.is_empty()).count();
    let _ = writeln!(o, "scene: {}", s.path.display());
    let _ = writeln!(
        o,
        "triangles: {tris} ({} degenerate skipped)",
        s.stats.degenerate_triangles
    );
    let _ = writeln!(o, "spheres: {}", s.spheres.len());
    let _ = writeln!(
        o,
        "meshes: {} ({with_normals} with normals, {} without)",
        s.meshes.len(),
        s.meshes.len() - with_normals
    );
    let _ = writeln!(o, "materials: {}", s.materials.len());
    for (i, m) in s.materials.iter().enumerate() {
        let name = s.material_names.get(i).map(String::as_str).unwrap_or("?");
        let _ = writeln!(o, "  {name}: {}", material_kind(m));
    }
    let _ = writeln!(o, "emitters: {}", s.emitter_count());
    for m in s.meshes.iter().filter(|m| m.emission != Vec3::ZERO) {
        let shape = if m.rect.is_some() { "rect" } else { "mesh" };
        let _ = writeln!(
            o,
            "  {} ({shape}, {} triangles): radiance={}",
            m.name,
            m.triangles.len(),
            v3(m.emission)
        );
    }
    for sp in s.spheres.iter().filter(|sp| sp.emission != Vec3::ZERO) {
        let _ = writeln!(
            o,
            "  {} (sphere r={}): radiance={}",
            sp.name,
            sp.radius,
            v3(sp.emission)
        );
    }
    let _ = writeln!(
        o,
        "environment: {}",
        environment_kind(s.environment.as_ref())
    );
    let _ = writeln!(o, "bump maps: {}", s.bumps.len());
    for (i, b) in s.bumps.iter().enumerate() {
        let users: Vec<&str> = s
            .meshes
            .iter()
            .filter(|m| m.bump == Some(i as u32))
            .map(|m| m.name.as_str())
            .chain(
                s.spheres
                    .iter()
                    .filter(|sp| sp.bump == Some(i as u32))
                    .map(|sp| sp.name.as_str()),
            )
            .collect();
        let _ = writeln!(
            o,
            "  {}: {} sinusoids, used by [{}]",
            b.name,
            b.terms.len(),
            users.join(", ")
        );
    }
    let c = &s.camera;
    let _ = writeln!(
        o,
        "camera: from={} to={} up={} fov_y={} deg, {}x{}",
        v3(c.from),
        v3(c.to),
        v3(c.up),
        c.fov_y,
        c.width,
        c.height
    );
    let r = &s.settings;
    let integrator = match r.integrator {
        Integrator::Path => "path",
        Integrator::Direct => "direct",
    };
    let _ = writeln!(
        o,
        "render: spp={} max_depth={} seed={} integrator={integrator} rr_depth={}",
        r.spp, r.max_depth, r.seed, r.rr_depth
    );
    o
}
