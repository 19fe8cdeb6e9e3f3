//! Data and plots of the paper's Fig. 9 (scene, shading, gradients) and Fig. 10
//! (gradient vs. linear interpolation from uniform samples), plus a convergence table
//! of the semianalytic gradient against the number of angular samples.
//!
//! Plots are hand-written SVG polylines: a few hundred lines of markup are simpler
//! than pulling in `plotters`, and there is no font dependency (text elements are
//! left to the viewer's default font).

use super::{rms_relative, Locate, Scene};
use crate::{Error, Result};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// Receiver points per figure (spacing 0.01 over the range [-3, 3]).
const GRID: usize = 601;
/// Angular samples of the semianalytic and sampled curves in Fig. 9c (the paper uses 256 or 512).
const FIG_SAMPLES: usize = 256;
/// Angular sample counts of the convergence table.
const SAMPLE_COUNTS: [usize; 8] = [16, 32, 64, 128, 256, 512, 1024, 2048];
/// Spacing of the uniform coarse samples of Fig. 10.
const COARSE_SPACING: f64 = 0.5;
/// Step of the central differences of the exact shading.
const FD_STEP_EXACT: f64 = 1e-4;

/// One row of the angular convergence table: normalised RMS error (see
/// [`rms_relative`]) of each semianalytic variant and of the sampled shading,
/// against the analytic gradient / exact shading on the figure grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AngularRow {
    pub samples: usize,
    pub sample: f64,
    pub midpoint: f64,
    pub bisection: f64,
    pub bisection_gaps: f64,
    pub shading: f64,
}

/// What [`write_figures`] wrote and the figures it measured on the way.
#[derive(Clone, Debug, PartialEq)]
pub struct FigureSummary {
    pub files: Vec<PathBuf>,
    pub angular: Vec<AngularRow>,
    /// Normalised RMS error of central differences of the exact shading (h = 1e-4).
    pub fd_exact_rms: f64,
    /// The same over the grid points with no kink of `B` within `h` (the two grid
    /// points exactly at the box edges, where `B` is not differentiable, left out).
    pub fd_exact_rms_smooth: f64,
    /// Normalised RMS error of central differences of the 256-sample shading (h = grid spacing).
    pub fd_sampled_rms: f64,
    /// Fig. 10: normalised RMS error of linear interpolation from the coarse samples.
    pub interp_linear_rms: f64,
    /// Fig. 10: same with cubic Hermite interpolation using the analytic gradients.
    pub interp_gradient_rms: f64,
}

/// Writes the flatland figures into `out_dir` (created if missing): `fig9a_scene.svg`,
/// `fig9_shading_gradient.{csv,svg}`, `fig10_interpolation.{csv,svg}`,
/// `fig10_coarse_samples.csv`,
/// `angular_samples.{csv,svg}` and `summary.txt`. Each file is written to a
/// temporary name and renamed, so a failed run leaves earlier outputs intact.
pub fn write_figures(out_dir: &Path) -> Result<FigureSummary> {
    std::fs::create_dir_all(out_dir).map_err(|e| Error::Output {
        path: out_dir.to_path_buf(),
        message: e.to_string(),
    })?;
    let scene = Scene::paper_fig9();
    let (x0, x1) = Scene::FIG_RANGE;
    let dx = (x1 - x0) / (GRID - 1) as f64;
    let xs: Vec<f64> = (0..GRID).map(|i| x0 + i as f64 * dx).collect();
    let mut files = Vec::new();

    // Fig. 9a: the scene.
    files.push(write(out_dir, "fig9a_scene.svg", &scene_svg(&scene))?);
    let fig9 = Fig9::compute(&scene, &xs, dx)?;
    files.extend(fig9.write(out_dir)?);
    let (interp_linear_rms, interp_gradient_rms) = write_fig10(out_dir, &scene, &fig9, &mut files)?;
    let angular = write_angular(out_dir, &scene, &fig9, &mut files)?;
    let summary = FigureSummary {
        files: Vec::new(),
        angular,
        fd_exact_rms: rms_relative(&fig9.g_fd, &fig9.g_ana),
        fd_exact_rms_smooth: fd_exact_rms_smooth(&scene, &fig9),
        fd_sampled_rms: rms_relative(&fig9.g_fd_sampled, &fig9.g_ana),
        interp_linear_rms,
        interp_gradient_rms,
    };
    files.push(write(out_dir, "summary.txt", &summary_text(&summary, dx))?);
    Ok(FigureSummary { files, ..summary })
}

/// Fig. 9b/9c: shading and gradients across the receiver, on the figure grid.
struct Fig9 {
    xs: Vec<f64>,
    b_exact: Vec<f64>,
    b_sampled: Vec<f64>,
    g_ana: Vec<f64>,
    g_sample: Vec<f64>,
    g_mid: Vec<f64>,
    g_bis: Vec<f64>,
    g_gaps: Vec<f64>,
    g_theta: Vec<f64>,
    g_fd: Vec<f64>,
    g_fd_sampled: Vec<f64>,
}

impl Fig9 {
    fn compute(scene: &Scene, xs: &[f64], dx: f64) -> Result<Self> {
        let g_semi = |loc| map(xs, |x| scene.grad_semianalytic(x, FIG_SAMPLES, loc));
        Ok(Self {
            xs: xs.to_vec(),
            b_exact: xs.iter().map(|&x| scene.shading(x)).collect(),
            b_sampled: map(xs, |x| scene.shading_sampled(x, FIG_SAMPLES))?,
            g_ana: xs.iter().map(|&x| scene.grad_analytic(x)).collect(),
            g_sample: g_semi(Locate::Sample)?,
            g_mid: g_semi(Locate::Midpoint)?,
            g_bis: g_semi(Locate::Bisection)?,
            g_gaps: g_semi(Locate::BisectionGaps)?,
            g_theta: xs.iter().map(|&x| scene.grad_angular_analytic(x)).collect(),
            g_fd: map(xs, |x| scene.grad_numerical(x, FD_STEP_EXACT))?,
            g_fd_sampled: map(xs, |x| scene.grad_numerical_sampled(x, dx, FIG_SAMPLES))?,
        })
    }

    /// `v` against the grid's abscissae.
    fn pts(&self, v: &[f64]) -> Vec<(f64, f64)> {
        self.xs.iter().copied().zip(v.iter().copied()).collect()
    }

    /// `fig9_shading_gradient.{csv,svg}`.
    fn write(&self, out_dir: &Path) -> Result<Vec<PathBuf>> {
        let mut csv = String::from(
            "x,shading_exact,shading_sampled_256,grad_analytic,grad_semianalytic_256_sample,\
             grad_semianalytic_256_midpoint,grad_semianalytic_256_bisection,\
             grad_semianalytic_256_bisection_gaps,grad_fd_exact,grad_fd_sampled_256,\
             grad_theta_analytic\n",
        );
        for i in 0..self.xs.len() {
            let row = [
                self.xs[i],
                self.b_exact[i],
                self.b_sampled[i],
                self.g_ana[i],
                self.g_sample[i],
                self.g_mid[i],
                self.g_bis[i],
                self.g_gaps[i],
                self.g_fd[i],
                self.g_fd_sampled[i],
                self.g_theta[i],
            ];
            push_row(&mut csv, &row);
        }
        let csv_path = write(out_dir, "fig9_shading_gradient.csv", &csv)?;
        let svg = Svg::new(900.0, 720.0)
            .panel(
                Panel::new(0.0, "Fig. 9b: shading B(x) on the receiver", "x", "B")
                    .series("exact", "#000000", self.pts(&self.b_exact))
                    .series("256 angular samples", "#d62728", self.pts(&self.b_sampled)),
            )
            .panel(
                Panel::new(1.0, "Fig. 9c: gradient dB/dx", "x", "dB/dx")
                    .series(
                        "central differences of 256-sample B",
                        "#bbbbbb",
                        self.pts(&self.g_fd_sampled),
                    )
                    .series("analytic (Eq. 37)", "#000000", self.pts(&self.g_ana))
                    .series(
                        "semianalytic 256, sample position (paper)",
                        "#ff7f0e",
                        self.pts(&self.g_sample),
                    )
                    .series(
                        "semianalytic 256, bisection + gaps",
                        "#1f77b4",
                        self.pts(&self.g_gaps),
                    ),
            )
            .finish();
        Ok(vec![
            csv_path,
            write(out_dir, "fig9_shading_gradient.svg", &svg)?,
        ])
    }
}

/// Fig. 10: interpolation from uniform coarse samples (`fig10_interpolation.{csv,svg}`,
/// `fig10_coarse_samples.csv`); returns the RMS errors of linear and gradient
/// interpolation.
fn write_fig10(
    out_dir: &Path,
    scene: &Scene,
    fig9: &Fig9,
    files: &mut Vec<PathBuf>,
) -> Result<(f64, f64)> {
    let (x0, x1) = Scene::FIG_RANGE;
    let (xs, b_exact) = (&fig9.xs, &fig9.b_exact);
    let coarse_n = ((x1 - x0) / COARSE_SPACING).round() as usize + 1;
    let cx: Vec<f64> = (0..coarse_n)
        .map(|i| x0 + i as f64 * COARSE_SPACING)
        .collect();
    let cb: Vec<f64> = cx.iter().map(|&x| scene.shading(x)).collect();
    let cg: Vec<f64> = cx.iter().map(|&x| scene.grad_analytic(x)).collect();
    let lin: Vec<f64> = xs
        .iter()
        .map(|&x| interp(&cx, &cb, &cg, x, false))
        .collect();
    let her: Vec<f64> = xs.iter().map(|&x| interp(&cx, &cb, &cg, x, true)).collect();
    let linear_rms = rms_relative(&lin, b_exact);
    let gradient_rms = rms_relative(&her, b_exact);
    let mut csv = String::from("x,shading_exact,linear_interpolation,gradient_interpolation\n");
    for i in 0..xs.len() {
        push_row(&mut csv, &[xs[i], b_exact[i], lin[i], her[i]]);
    }
    files.push(write(out_dir, "fig10_interpolation.csv", &csv)?);
    let mut csv = String::from("x,shading_exact,grad_analytic\n");
    for i in 0..coarse_n {
        push_row(&mut csv, &[cx[i], cb[i], cg[i]]);
    }
    files.push(write(out_dir, "fig10_coarse_samples.csv", &csv)?);
    let err = |v: &[f64]| {
        xs.iter()
            .zip(v.iter().zip(b_exact))
            .map(|(&x, (a, b))| (x, a - b))
            .collect::<Vec<_>>()
    };
    let svg = Svg::new(900.0, 720.0)
        .panel(
            Panel::new(
                0.0,
                &format!("Fig. 10: interpolation from samples every {COARSE_SPACING}"),
                "x",
                "B",
            )
            .series("exact", "#000000", fig9.pts(b_exact))
            .series("linear", "#d62728", fig9.pts(&lin))
            .series("gradient (cubic Hermite)", "#1f77b4", fig9.pts(&her))
            .markers(cx.iter().copied().zip(cb.iter().copied()).collect()),
        )
        .panel(
            Panel::new(1.0, "interpolation error", "x", "error")
                .series(
                    &format!("linear, RMS rel {linear_rms:.2e}"),
                    "#d62728",
                    err(&lin),
                )
                .series(
                    &format!("gradient, RMS rel {gradient_rms:.2e}"),
                    "#1f77b4",
                    err(&her),
                ),
        )
        .finish();
    files.push(write(out_dir, "fig10_interpolation.svg", &svg)?);
    Ok((linear_rms, gradient_rms))
}

/// Convergence in the number of angular samples (`angular_samples.{csv,svg}`).
fn write_angular(
    out_dir: &Path,
    scene: &Scene,
    fig9: &Fig9,
    files: &mut Vec<PathBuf>,
) -> Result<Vec<AngularRow>> {
    let xs = &fig9.xs;
    let mut angular = Vec::new();
    let mut csv = String::from(
        "samples,rms_sample,rms_midpoint,rms_bisection,rms_bisection_gaps,rms_shading\n",
    );
    for &n in &SAMPLE_COUNTS {
        let e = |loc| -> Result<f64> {
            Ok(rms_relative(
                &map(xs, |x| scene.grad_semianalytic(x, n, loc))?,
                &fig9.g_ana,
            ))
        };
        let row = AngularRow {
            samples: n,
            sample: e(Locate::Sample)?,
            midpoint: e(Locate::Midpoint)?,
            bisection: e(Locate::Bisection)?,
            bisection_gaps: e(Locate::BisectionGaps)?,
            shading: rms_relative(&map(xs, |x| scene.shading_sampled(x, n))?, &fig9.b_exact),
        };
        push_row(
            &mut csv,
            &[
                n as f64,
                row.sample,
                row.midpoint,
                row.bisection,
                row.bisection_gaps,
                row.shading,
            ],
        );
        angular.push(row);
    }
    files.push(write(out_dir, "angular_samples.csv", &csv)?);
    files.push(write(
        out_dir,
        "angular_samples.svg",
        &angular_svg(&angular),
    )?);
    Ok(angular)
}

fn angular_svg(angular: &[AngularRow]) -> String {
    let col = |f: fn(&AngularRow) -> f64| {
        angular
            .iter()
            .map(|r| (r.samples as f64, f(r)))
            .collect::<Vec<_>>()
    };
    Svg::new(900.0, 400.0)
        .panel(
            Panel::new(
                0.0,
                "semianalytic gradient vs angular samples",
                "samples",
                "RMS rel. error",
            )
            .log_x()
            .log_y()
            .series("sample position (paper)", "#d62728", col(|r| r.sample))
            .series("midpoint", "#1f77b4", col(|r| r.midpoint))
            .series("bisection", "#2ca02c", col(|r| r.bisection))
            .series(
                "bisection + object-id gaps",
                "#9467bd",
                col(|r| r.bisection_gaps),
            )
            .series("sampled shading B", "#7f7f7f", col(|r| r.shading)),
        )
        .finish()
}

/// RMS error of the exact shading's central differences over the grid points with
/// no kink of `B` within the step.
fn fd_exact_rms_smooth(scene: &Scene, fig9: &Fig9) -> f64 {
    let smooth: Vec<usize> = (0..fig9.xs.len())
        .filter(|&i| {
            let s = scene.signature(fig9.xs[i]);
            scene.signature(fig9.xs[i] - FD_STEP_EXACT) == s
                && scene.signature(fig9.xs[i] + FD_STEP_EXACT) == s
        })
        .collect();
    let pick = |v: &[f64]| smooth.iter().map(|&i| v[i]).collect::<Vec<_>>();
    rms_relative(&pick(&fig9.g_fd), &pick(&fig9.g_ana))
}

/// `summary.txt`: the convergence table and the measured errors.
fn summary_text(summary: &FigureSummary, dx: f64) -> String {
    let (x0, x1) = Scene::FIG_RANGE;
    let mut text = String::new();
    let _ = writeln!(
        text,
        "flatland (paper Sec. 6.3): normalised RMS errors on {GRID} receiver points in [{x0}, {x1}]"
    );
    let _ = writeln!(
        text,
        "samples  sample_pos  midpoint   bisection  bis+gaps   shading"
    );
    for r in &summary.angular {
        let _ = writeln!(
            text,
            "{:7}  {:.3e}  {:.3e}  {:.3e}  {:.3e}  {:.3e}",
            r.samples, r.sample, r.midpoint, r.bisection, r.bisection_gaps, r.shading
        );
    }
    let _ = writeln!(
        text,
        "central differences: exact B (h=1e-4) {:.3e} ({:.3e} away from kinks), 256-sample B (h={dx}) {:.3e}",
        summary.fd_exact_rms, summary.fd_exact_rms_smooth, summary.fd_sampled_rms
    );
    let _ = writeln!(
        text,
        "Fig. 10 interpolation from spacing {COARSE_SPACING}: linear {:.3e}, gradient {:.3e}",
        summary.interp_linear_rms, summary.interp_gradient_rms
    );
    text
}

fn map(xs: &[f64], f: impl Fn(f64) -> Result<f64>) -> Result<Vec<f64>> {
    xs.iter().map(|&x| f(x)).collect()
}

/// Appends one CSV row, every value in `{:.10e}`.
pub(super) fn push_row(csv: &mut String, row: &[f64]) {
    for (i, v) in row.iter().enumerate() {
        if i > 0 {
            csv.push(',');
        }
        let _ = write!(csv, "{v:.10e}");
    }
    csv.push('\n');
}

/// Writes `contents` to `dir/name` with the renderer's atomic writer (temporary
/// file, fsync, rename), so a reader never sees a half-written figure.
pub(super) fn write(dir: &Path, name: &str, contents: &str) -> Result<PathBuf> {
    let path = dir.join(name);
    crate::output::write_atomic(&path, |w| {
        w.write_all(contents.as_bytes()).map_err(|e| e.to_string())
    })?;
    Ok(path)
}

/// Interpolates the coarse samples at `x`: linear, or cubic Hermite using the
/// gradients (the 1D form of gradient interpolation, Sec. 8.1 / Fig. 10). The paper
/// builds a quadratic Bézier per span from the two tangents; in 1D the cubic Hermite
/// uses the same data (two values, two slopes) without the tangent-intersection
/// control point, which is undefined when the two slopes are equal.
fn interp(cx: &[f64], cb: &[f64], cg: &[f64], x: f64, hermite: bool) -> f64 {
    let n = cx.len();
    if n < 2 {
        return cb.first().copied().unwrap_or(0.0);
    }
    let i = cx.partition_point(|&c| c <= x).clamp(1, n - 1) - 1;
    let h = cx[i + 1] - cx[i];
    let t = (x - cx[i]) / h;
    if !hermite {
        return cb[i] + t * (cb[i + 1] - cb[i]);
    }
    let (t2, t3) = (t * t, t * t * t);
    (2.0 * t3 - 3.0 * t2 + 1.0) * cb[i]
        + (t3 - 2.0 * t2 + t) * h * cg[i]
        + (-2.0 * t3 + 3.0 * t2) * cb[i + 1]
        + (t3 - t2) * h * cg[i + 1]
}

/// Fig. 9a: the receiver, the blockers, and the lighting profile drawn above.
fn scene_svg(scene: &Scene) -> String {
    let (w, h) = (900.0, 450.0);
    let (x0, x1) = Scene::FIG_RANGE;
    let scale = (w - 80.0) / (x1 - x0);
    let px = |x: f64| 40.0 + (x - x0) * scale;
    let py = |y: f64| h - 40.0 - y * scale;
    let mut s = svg_open(w, h);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="24" font-size="16">Fig. 9a: flatland scene (receiver y = 0, blockers, Gaussian lighting lobe)</text>"#,
        40.0
    );
    let _ = writeln!(
        s,
        r#"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="black" stroke-width="3"/>"#,
        px(x0),
        py(0.0),
        px(x1),
        py(0.0)
    );
    for b in scene.blockers() {
        match b {
            super::Blocker::Rect(r) => {
                let _ = writeln!(
                    s,
                    r##"<rect x="{:.2}" y="{:.2}" width="{:.2}" height="{:.2}" fill="#888888" stroke="black"/>"##,
                    px(r.min[0]),
                    py(r.max[1]),
                    (r.max[0] - r.min[0]) * scale,
                    (r.max[1] - r.min[1]) * scale
                );
            }
            super::Blocker::Circle(c) => {
                let _ = writeln!(
                    s,
                    r##"<circle cx="{:.2}" cy="{:.2}" r="{:.2}" fill="#888888" stroke="black"/>"##,
                    px(c.center[0]),
                    py(c.center[1]),
                    c.radius * scale
                );
            }
        }
    }
    // The lighting T(θ) as a polar curve around the receiver centre.
    let l = scene.lighting();
    let peak = l.transport(0.0).max(1e-12);
    let pts: Vec<(f64, f64)> = (0..=180)
        .map(|i| {
            let th = -std::f64::consts::FRAC_PI_2 + i as f64 * std::f64::consts::PI / 180.0;
            let r = 2.4 + 0.6 * l.transport(th) / peak;
            (px(r * th.sin()), py(r * th.cos()))
        })
        .collect();
    polyline(&mut s, &pts, "#ff7f0e");
    s.push_str("</svg>\n");
    s
}

fn svg_open(w: f64, h: f64) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"sans-serif\">\n<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n"
    )
}

fn polyline(s: &mut String, pts: &[(f64, f64)], color: &str) {
    s.push_str("<polyline fill=\"none\" stroke-width=\"1.5\" stroke=\"");
    s.push_str(color);
    s.push_str("\" points=\"");
    for (x, y) in pts {
        let _ = write!(s, "{x:.2},{y:.2} ");
    }
    s.push_str("\"/>\n");
}

/// A stack of plot panels, each one row of the document. Shared with
/// `sampling.rs` (Figs. 16-17) so the flatland figures have one SVG writer.
pub(super) struct Svg {
    w: f64,
    h: f64,
    panels: Vec<Panel>,
}

/// One labelled polyline of a panel.
struct Series {
    label: String,
    color: String,
    points: Vec<(f64, f64)>,
}

/// One plot panel: labelled polylines, optional circled markers and rows of
/// sample-position ticks (the first tick row along the top edge, later ones along
/// the bottom edge).
pub(super) struct Panel {
    row: f64,
    title: String,
    xlabel: String,
    ylabel: String,
    log_x: bool,
    log_y: bool,
    series: Vec<Series>,
    markers: Vec<(f64, f64)>,
    ticks: Vec<(String, Vec<f64>)>,
}

impl Panel {
    pub(super) fn new(row: f64, title: &str, xlabel: &str, ylabel: &str) -> Self {
        Self {
            row,
            title: title.into(),
            xlabel: xlabel.into(),
            ylabel: ylabel.into(),
            log_x: false,
            log_y: false,
            series: Vec::new(),
            markers: Vec::new(),
            ticks: Vec::new(),
        }
    }
    /// Log scale on both axes.
    pub(super) fn log(self) -> Self {
        self.log_x().log_y()
    }
    fn log_x(mut self) -> Self {
        self.log_x = true;
        self
    }
    fn log_y(mut self) -> Self {
        self.log_y = true;
        self
    }
    pub(super) fn series(mut self, label: &str, color: &str, pts: Vec<(f64, f64)>) -> Self {
        self.series.push(Series {
            label: label.into(),
            color: color.into(),
            points: pts,
        });
        self
    }
    fn markers(mut self, pts: Vec<(f64, f64)>) -> Self {
        self.markers = pts;
        self
    }
    /// Adds one row of sample-position ticks at the abscissae `xs`; they do not
    /// widen the axis range.
    pub(super) fn ticks(mut self, color: &str, xs: Vec<f64>) -> Self {
        self.ticks.push((color.into(), xs));
        self
    }
}

impl Svg {
    pub(super) fn new(w: f64, h: f64) -> Self {
        Self {
            w,
            h,
            panels: Vec::new(),
        }
    }
    pub(super) fn panel(mut self, p: Panel) -> Self {
        self.panels.push(p);
        self
    }

    pub(super) fn finish(self) -> String {
        let mut s = svg_open(self.w, self.h);
        let rows = self.panels.len().max(1) as f64;
        let ph = self.h / rows;
        for p in &self.panels {
            draw_panel(
                &mut s,
                p,
                70.0,
                p.row * ph + 30.0,
                self.w - 100.0,
                ph - 75.0,
            );
        }
        s.push_str("</svg>\n");
        s
    }
}

/// Where a panel sits on the page and the (transformed) data range it shows.
struct Frame<'p> {
    p: &'p Panel,
    left: f64,
    top: f64,
    w: f64,
    h: f64,
    xmin: f64,
    xmax: f64,
    ymin: f64,
    ymax: f64,
}

impl<'p> Frame<'p> {
    /// The range of every drawable point of `p` (ticks do not widen it), the y range
    /// padded by 5%.
    fn new(p: &'p Panel, left: f64, top: f64, w: f64, h: f64) -> Self {
        let mut f = Self {
            p,
            left,
            top,
            w,
            h,
            xmin: f64::MAX,
            xmax: f64::MIN,
            ymin: f64::MAX,
            ymax: f64::MIN,
        };
        let all = p
            .series
            .iter()
            .flat_map(|sr| sr.points.iter())
            .chain(p.markers.iter())
            .filter(|q| f.ok(q));
        let (mut xmin, mut xmax, mut ymin, mut ymax) = (f.xmin, f.xmax, f.ymin, f.ymax);
        for &(x, y) in all {
            xmin = xmin.min(f.tx(x));
            xmax = xmax.max(f.tx(x));
            ymin = ymin.min(f.ty(y));
            ymax = ymax.max(f.ty(y));
        }
        if xmin > xmax {
            (xmin, xmax, ymin, ymax) = (0.0, 1.0, 0.0, 1.0);
        }
        if xmax - xmin < 1e-300 {
            xmax = xmin + 1.0;
        }
        if ymax - ymin < 1e-300 {
            ymax = ymin + 1.0;
        }
        let pad = 0.05 * (ymax - ymin);
        (f.xmin, f.xmax, f.ymin, f.ymax) = (xmin, xmax, ymin - pad, ymax + pad);
        f
    }
    fn tx(&self, v: f64) -> f64 {
        if self.p.log_x {
            v.log10()
        } else {
            v
        }
    }
    fn ty(&self, v: f64) -> f64 {
        if self.p.log_y {
            v.log10()
        } else {
            v
        }
    }
    /// Drawable: finite, and positive on a log axis.
    fn ok(&self, (x, y): &(f64, f64)) -> bool {
        x.is_finite() && y.is_finite() && (!self.p.log_x || *x > 0.0) && (!self.p.log_y || *y > 0.0)
    }
    fn sx(&self, x: f64) -> f64 {
        self.left + (self.tx(x) - self.xmin) / (self.xmax - self.xmin) * self.w
    }
    fn sy(&self, y: f64) -> f64 {
        self.top + self.h - (self.ty(y) - self.ymin) / (self.ymax - self.ymin) * self.h
    }
}

/// Draws one panel with frame, 5 ticks per axis, the series and a legend. Non-finite
/// values (and non-positive ones on log axes) are skipped, never written.
fn draw_panel(s: &mut String, p: &Panel, left: f64, top: f64, w: f64, h: f64) {
    let f = Frame::new(p, left, top, w, h);
    draw_axes(s, &f);
    draw_series(s, &f);
    draw_marks(s, &f);
}

/// Frame, title, axis labels and 5 ticks with grid lines per axis.
fn draw_axes(s: &mut String, f: &Frame) {
    let (p, left, top, w, h) = (f.p, f.left, f.top, f.w, f.h);
    let _ = writeln!(
        s,
        r#"<rect x="{left}" y="{top}" width="{w}" height="{h}" fill="none" stroke="black"/>"#
    );
    let _ = writeln!(
        s,
        r#"<text x="{left}" y="{}" font-size="14">{}</text>"#,
        top - 8.0,
        p.title
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" font-size="12" text-anchor="middle">{}</text>"#,
        left + 0.5 * w,
        top + h + 34.0,
        p.xlabel
    );
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" font-size="12" text-anchor="middle" transform="rotate(-90 {} {})">{}</text>"#,
        left - 52.0,
        top + 0.5 * h,
        left - 52.0,
        top + 0.5 * h,
        p.ylabel
    );
    for i in 0..=4 {
        let t = i as f64 / 4.0;
        let (vx, vy) = (
            f.xmin + t * (f.xmax - f.xmin),
            f.ymin + t * (f.ymax - f.ymin),
        );
        let lx = if p.log_x { 10f64.powf(vx) } else { vx };
        let ly = if p.log_y { 10f64.powf(vy) } else { vy };
        let (gx, gy) = (left + t * w, top + h - t * h);
        let _ = writeln!(
            s,
            r##"<line x1="{gx:.2}" y1="{top}" x2="{gx:.2}" y2="{}" stroke="#eeeeee"/><text x="{gx:.2}" y="{}" font-size="11" text-anchor="middle">{}</text>"##,
            top + h,
            top + h + 16.0,
            tick(lx)
        );
        let _ = writeln!(
            s,
            r##"<line x1="{left}" y1="{gy:.2}" x2="{}" y2="{gy:.2}" stroke="#eeeeee"/><text x="{}" y="{:.2}" font-size="11" text-anchor="end">{}</text>"##,
            left + w,
            left - 4.0,
            gy + 4.0,
            tick(ly)
        );
    }
}

/// The polylines and their legend entries.
fn draw_series(s: &mut String, f: &Frame) {
    let (left, top, w) = (f.left, f.top, f.w);
    for (k, sr) in f.p.series.iter().enumerate() {
        let (label, color, pts) = (&sr.label, &sr.color, &sr.points);
        let q: Vec<(f64, f64)> = pts
            .iter()
            .filter(|q| f.ok(q))
            .map(|&(x, y)| (f.sx(x), f.sy(y)))
            .collect();
        polyline(s, &q, color);
        let ly = top + 16.0 + 16.0 * k as f64;
        let _ = writeln!(
            s,
            r#"<line x1="{}" y1="{ly}" x2="{}" y2="{ly}" stroke="{color}" stroke-width="2"/><text x="{}" y="{}" font-size="12">{label}</text>"#,
            left + w - 250.0,
            left + w - 225.0,
            left + w - 220.0,
            ly + 4.0
        );
    }
}

/// Circled markers, then the rows of sample-position ticks (first row at the top).
fn draw_marks(s: &mut String, f: &Frame) {
    let (p, top, h) = (f.p, f.top, f.h);
    for q in p.markers.iter().filter(|q| f.ok(q)) {
        let _ = writeln!(
            s,
            r#"<circle cx="{:.2}" cy="{:.2}" r="3.5" fill="none" stroke="black"/>"#,
            f.sx(q.0),
            f.sy(q.1)
        );
    }
    for (k, (color, xs)) in p.ticks.iter().enumerate() {
        let (ya, yb) = if k == 0 {
            (top, top + 8.0)
        } else {
            (top + h - 8.0, top + h)
        };
        for &x in xs
            .iter()
            .filter(|x| x.is_finite() && (!p.log_x || **x > 0.0))
        {
            let _ = writeln!(
                s,
                r#"<line x1="{0:.2}" y1="{ya}" x2="{0:.2}" y2="{yb}" stroke="{color}"/>"#,
                f.sx(x)
            );
        }
    }
}

fn tick(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e4 || v.abs() < 1e-2) {
        format!("{v:.1e}")
    } else {
        format!("{v:.3}")
    }
}
