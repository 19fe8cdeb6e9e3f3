//! Progress that tells the truth: one bar per phase, named, counted in the
//! phase's own unit (pixels, samples, runs), its ETA from the work done; on a
//! non-terminal (logs, CI) one line every few seconds instead; nothing when quiet.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How often a non-terminal gets a progress line.
const LOG_EVERY: Duration = Duration::from_secs(5);

/// Where progress goes: a terminal bar, log lines on stderr, or nowhere.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProgressMode {
    Bar,
    Log,
    Quiet,
}

impl ProgressMode {
    /// A bar on a terminal, log lines otherwise, nothing when `quiet`.
    pub fn detect(quiet: bool) -> Self {
        if quiet {
            ProgressMode::Quiet
        } else if std::io::stderr().is_terminal() {
            ProgressMode::Bar
        } else {
            ProgressMode::Log
        }
    }
}

/// One phase of a run ("reference", "gradient at 17%", ...), `total` units of
/// `unit` ("pixels", "samples"). Thread-safe: worker threads report with
/// [`Phase::set`] (the furthest count wins) or [`Phase::inc`].
pub struct Phase {
    bar: Option<ProgressBar>,
    name: String,
    unit: &'static str,
    done: AtomicU64,
    total: AtomicU64,
    start: Instant,
    last_log: Mutex<Instant>,
    mode: ProgressMode,
    /// The step now running ([`Phase::step`]), named in the log lines.
    step: Mutex<String>,
}

impl Phase {
    pub fn new(mode: ProgressMode, name: &str, total: u64, unit: &'static str) -> Self {
        let bar = (mode == ProgressMode::Bar).then(|| {
            let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
            // The ETA is indicatif's, from the rate of work done so far.
            let template =
                format!("{{msg}} {{elapsed_precise}} [{{wide_bar}}] {{human_pos}}/{{human_len}} {unit}, ETA {{eta}}");
            if let Ok(style) = ProgressStyle::with_template(&template) {
                bar.set_style(style.progress_chars("=> "));
            }
            bar.set_message(name.to_string());
            bar
        });
        Self {
            bar,
            name: name.into(),
            unit,
            done: AtomicU64::new(0),
            total: AtomicU64::new(total),
            start: Instant::now(),
            last_log: Mutex::new(Instant::now()),
            mode,
            step: Mutex::new(String::new()),
        }
    }

    /// Reports `done` of `total` (monotone: an older, smaller count from another
    /// thread never moves the bar back).
    pub fn set(&self, done: u64, total: u64) {
        self.total.store(total, Ordering::Relaxed);
        let done = self.done.fetch_max(done, Ordering::Relaxed).max(done);
        if let Some(bar) = &self.bar {
            bar.set_length(total);
            bar.set_position(done);
        }
        self.maybe_log(done, total);
    }

    /// Adds `n` units of work done.
    pub fn inc(&self, n: u64) {
        let done = self.done.fetch_add(n, Ordering::Relaxed) + n;
        if let Some(bar) = &self.bar {
            bar.set_position(done);
        }
        self.maybe_log(done, self.total.load(Ordering::Relaxed));
    }

    /// Names the step now running (shown beside the phase's name; on a
    /// non-terminal, logged as a line of its own).
    pub fn message(&self, msg: &str) {
        match self.mode {
            ProgressMode::Bar => {
                if let Some(bar) = &self.bar {
                    bar.set_message(format!("{}: {msg}", self.name));
                }
            }
            ProgressMode::Log => eprintln!("{}: {msg}", self.name),
            ProgressMode::Quiet => {}
        }
    }

    /// Names the step now running without a line of its own: beside the bar's
    /// name, or in the next periodic log line (steps too short to log are many).
    pub fn step(&self, msg: &str) {
        if let Some(bar) = &self.bar {
            bar.set_message(format!("{}: {msg}", self.name));
        }
        if let Ok(mut step) = self.step.lock() {
            msg.clone_into(&mut step);
        }
    }

    fn maybe_log(&self, done: u64, total: u64) {
        if self.mode != ProgressMode::Log {
            return;
        }
        let Ok(mut last) = self.last_log.try_lock() else {
            return;
        };
        if last.elapsed() < LOG_EVERY {
            return;
        }
        *last = Instant::now();
        let secs = self.start.elapsed().as_secs_f64();
        let eta = if done > 0 && total > done {
            format!(", ETA {:.0} s", secs * (total - done) as f64 / done as f64)
        } else {
            String::new()
        };
        let step = match self.step.lock() {
            Ok(s) if !s.is_empty() => format!(" ({s})"),
            _ => String::new(),
        };
        eprintln!(
            "{}{step}: {done}/{total} {} ({:.0}%), {secs:.0} s{eta}",
            self.name,
            self.unit,
            100.0 * done as f64 / total.max(1) as f64
        );
    }

    /// The callback the render and quadtree stages take: (done, total).
    pub fn callback(&self) -> impl Fn(usize, usize) + Sync + '_ {
        move |done, total| self.set(done as u64, total as u64)
    }

    /// The callback of a stage that runs named steps one after another, each
    /// counting (done, total) of its own (the glossy precompute's refinement
    /// steps): one bar over them all, each step's total added as it starts,
    /// its name beside the bar.
    pub fn steps(&self) -> impl Fn(&str, u64, u64) + Sync + '_ {
        // The step running, the work of the steps before it, its total.
        let state = Mutex::new((String::new(), 0u64, 0u64));
        move |step, done, total| {
            let Ok(mut s) = state.lock() else {
                return;
            };
            let (name, base, step_total) = &mut *s;
            if name != step {
                *base += *step_total;
                step.clone_into(name);
                self.step(step);
            }
            *step_total = total;
            self.set(*base + done, *base + total);
        }
    }
}

impl Drop for Phase {
    fn drop(&mut self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}
