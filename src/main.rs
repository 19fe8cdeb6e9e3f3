//! `gradtrace` command line: the clap types (`cli.rs`) and one dispatch into
//! `pipeline`.
//!
//! Everything that can fail reports ONE line `error: <message>` on stderr and exits
//! with status 1; a failed run leaves every previous output untouched.

mod cli;

use clap::Parser;
use cli::{preview_dir, Cli, Command, PreviewCommand};
use gradtrace::error::{error_line, one_line};
use gradtrace::pipeline::command_line;
use gradtrace::pipeline::compare;
use gradtrace::pipeline::diff::DiffOptions;
use gradtrace::pipeline::{self, progress::ProgressMode};
use std::process::ExitCode;

/// A failed allocation ends the run with one `error:` line, not an abort.
#[global_allocator]
static ALLOCATOR: gradtrace::memory::OneLineOom = gradtrace::memory::OneLineOom;

/// The x86 features this binary was compiled to assume (`.cargo/config.toml`)
/// that the CPU lacks: run on one, it would die of an illegal instruction.
fn missing_cpu_features() -> Vec<&'static str> {
    #[allow(unused_mut)]
    let mut missing = Vec::new();
    #[cfg(target_arch = "x86_64")]
    {
        macro_rules! need {
            ($($f:tt),*) => {$(
                if cfg!(target_feature = $f) && !std::arch::is_x86_feature_detected!($f) {
                    missing.push($f);
                }
            )*};
        }
        need!("sse3", "ssse3", "sse4.1", "sse4.2", "popcnt", "avx", "avx2", "fma");
        // What a `-C target-cpu=native` build on a recent x86 CPU may assume.
        need!("bmi1", "bmi2", "lzcnt", "f16c", "movbe");
        need!("avx512f", "avx512vl", "avx512bw", "avx512dq", "avx512cd");
    }
    missing
}

fn main() -> ExitCode {
    // A bug must still end as one `error:` line and status 1, not a backtrace.
    gradtrace::error::one_line_panics();
    let missing = missing_cpu_features();
    if !missing.is_empty() {
        eprintln!(
            "error: this gradtrace was built for CPUs with {} and this one lacks them; \
             rebuild with RUSTFLAGS=\"-C target-cpu=native\"",
            missing.join(", ")
        );
        return ExitCode::FAILURE;
    }
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
    // The temporary names of writers killed mid-commit, wherever they wrote.
    gradtrace::output::atomic::sweep_pending();
    match std::panic::catch_unwind(|| run(cli)) {
        Ok(Ok(code)) => code,
        Ok(Err(e)) => {
            eprintln!("error: {}", error_line(e.chain()));
            ExitCode::FAILURE
        }
        // The hook already printed the line.
        Err(_) => ExitCode::FAILURE,
    }
}

/// The exit status of a render that Ctrl-C ended early after writing what it
/// had (the shell's 128 + SIGINT), so that a script can tell it from a render
/// that ran to its end.
const EXIT_INTERRUPTED: u8 = 130;

fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    let _doing = {
        let (path, activity) = match &cli.command {
            Command::Render(a) => (&a.scene, "rendering"),
            Command::Info(a) => (&a.scene, "reading the scene"),
            Command::Diff(a) => (&a.image, "comparing the images"),
            Command::Preview(PreviewCommand::ShadowField(a) | PreviewCommand::Glossy(a)) => {
                (&a.scene, "making the preview")
            }
            Command::Merge(a) => (&a.out, "merging the parts"),
            Command::Compare(a) => (&a.scene, "comparing the renderers"),
        };
        gradtrace::memory::doing(path, activity)
    };
    match cli.command {
        Command::Render(args) => {
            let quiet = args.common.quiet;
            let job = args.into_job();
            let summary = pipeline::render::run(&job)?;
            if !quiet {
                println!("{summary}");
            }
            if job.passes.interrupted() {
                eprintln!(
                    "interrupted: wrote the passes finished before Ctrl-C (exit status {EXIT_INTERRUPTED})"
                );
                return Ok(ExitCode::from(EXIT_INTERRUPTED));
            }
        }
        Command::Info(args) => print!("{}", pipeline::info(&args.scene)?),
        Command::Diff(args) => {
            let opts = DiffOptions {
                metric: args.metric,
                threshold: args.threshold,
                error_map: args.error_map,
            };
            let report = pipeline::diff::run(&args.image, &args.reference, &opts)?;
            println!("{report}");
            if report.exceeds_threshold() {
                anyhow::bail!(
                    "{} differs from {}: {} {:.6e} is above --threshold {}",
                    args.image.display(),
                    args.reference.display(),
                    args.metric.name(),
                    report.value(),
                    opts.threshold.unwrap_or_default()
                );
            }
        }
        Command::Preview(PreviewCommand::ShadowField(a)) => {
            use pipeline::preview::shadow_field::{run, ShadowFieldOptions};
            a.only_for(false)?;
            let mut opts = ShadowFieldOptions::new(&a.scene);
            opts.out_dir = a
                .out
                .unwrap_or_else(|| preview_dir("shadow-field", &a.scene));
            (opts.frames, opts.reference_spp, opts.quiet) = (a.frames, a.reference_spp, a.quiet);
            (opts.reference_spp_max, opts.amortise_frames) =
                (a.reference_spp_max, a.amortise_frames);
            let s = run(&opts)?;
            if !a.quiet {
                println!(
                    "shadow-field: {} entities, precompute {:.2} s{}, shading {:.3} s, RMSE {:.3e} ({:.1}% of the mean), {}; wrote {}",
                    s.entities,
                    s.precompute_s,
                    if s.precompute_cached { " (cached)" } else { "" },
                    s.render_s,
                    s.rmse,
                    100.0 * s.rmse_relative,
                    s.figures.summary(),
                    s.exr.display()
                );
            }
        }
        Command::Preview(PreviewCommand::Glossy(a)) => {
            use pipeline::preview::glossy::{run, GlossyOptions};
            a.only_for(true)?;
            let mut opts = GlossyOptions::new(&a.scene);
            opts.out_dir = a.out.unwrap_or_else(|| preview_dir("glossy", &a.scene));
            (opts.orbit, opts.reference_spp, opts.quiet) = (a.orbit, a.reference_spp, a.quiet);
            (opts.reference_spp_max, opts.amortise_frames) =
                (a.reference_spp_max, a.amortise_frames);
            if let Some(n) = a.uniform {
                (opts.settings.uniform_levels, opts.settings.spatial) = (n, false);
            }
            if let Some(n) = a.max_vertices {
                opts.settings.max_vertices = n as usize;
            }
            let s = run(&opts)?;
            if !a.quiet {
                println!(
                    "glossy: {} → {} vertices, precompute {:.1} s{}, frame {:.1} ms, RMSE {:.3e} ({:.1}% of the mean), {}; wrote {} and {}",
                    s.vertices_initial,
                    s.vertices_final,
                    s.precompute_s,
                    if s.cached { " (cached)" } else { "" },
                    s.render_ms,
                    s.rmse,
                    100.0 * s.rmse / s.reference_mean.max(1e-12),
                    s.figures.summary(),
                    s.exr.display(),
                    s.stats_page.display()
                );
            }
        }
        Command::Merge(args) => {
            let job = pipeline::merge::MergeJob {
                parts: args.parts,
                out: args.out,
                command: command_line(),
            };
            let summary = pipeline::merge::run(&job)?;
            if !args.quiet {
                println!("{summary}");
            }
        }
        Command::Compare(args) => {
            let dir = args
                .out
                .clone()
                .unwrap_or_else(|| compare::default_dir(&args.scene));
            let opts = args.options(dir.clone());
            let mode = ProgressMode::detect(args.common.quiet);
            let rows = pipeline::compare::run(&args.scene, args.common.threads, &opts, mode)?;
            if !args.common.quiet {
                println!("{}", gradtrace::output::report::markdown_table(&rows));
                println!("wrote {}", dir.join("report.html").display());
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}
