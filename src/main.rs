//! `gradtrace` command line: the clap types (`cli.rs`) and one dispatch into
//! `pipeline`.
//!
//! Everything that can fail reports ONE line `error: <message>` on stderr and exits
//! with status 1; a failed run leaves every previous output untouched.

mod cli;

use clap::Parser;
use cli::{Cli, Command, PreviewCommand};
use gradtrace::error::{error_line, one_line};
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

/// One dispatch: each command runs in `pipeline`, which formats its own summary.
fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    let (path, activity) = cli.command.doing();
    let _doing = gradtrace::memory::doing(path, activity);
    match cli.command {
        Command::Render(args) => {
            let quiet = args.common.quiet;
            let job = args.into_job();
            show(quiet, pipeline::render::run(&job)?);
            if job.passes.interrupted() {
                eprintln!("{}", pipeline::render::interrupted_note());
                return Ok(ExitCode::from(pipeline::render::EXIT_INTERRUPTED));
            }
        }
        Command::Info(args) => print!("{}", pipeline::info(&args.scene)?),
        Command::Diff(args) => {
            let report = pipeline::diff::run(&args.image, &args.reference, &args.options())?;
            show(false, &report);
            if let Some(message) = report.threshold_error() {
                anyhow::bail!(message);
            }
        }
        Command::Preview(PreviewCommand::ShadowField(a)) => {
            let opts = a.shadow_field_options()?;
            show(a.quiet, pipeline::preview::shadow_field::run(&opts)?);
        }
        Command::Preview(PreviewCommand::Glossy(a)) => {
            let opts = a.glossy_options()?;
            show(a.quiet, pipeline::preview::glossy::run(&opts)?);
        }
        Command::Merge(args) => show(args.quiet, pipeline::merge::run(&args.job())?),
        Command::Compare(args) => {
            let mode = ProgressMode::detect(args.common.quiet);
            let opts = args.options();
            let summary = pipeline::compare::run(&args.scene, args.common.threads, &opts, mode)?;
            show(args.common.quiet, summary);
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// A command's summary on stdout, unless `--quiet`.
fn show(quiet: bool, summary: impl std::fmt::Display) {
    if !quiet {
        println!("{summary}");
    }
}
