//! (wall time, error) points per strategy → a log-log SVG plot, drawn with plotters.
//!
//! plotters is built without its font stack (`default-features = false`): its
//! naive text layout is only used to place labels, and the SVG backend writes text
//! as `<text>` elements that the browser renders with its own fonts, so no font
//! file is needed at build or run time.

use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters_backend::{BackendCoord, DrawingErrorKind};

/// One line of a plot: a strategy's points `(x, y, point label)`, and for each
/// point its interval `(y_lo, y_hi)`, drawn as an error bar.
#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64, String)>,
    /// One per point (missing ones count as `None`). `None`: the point has no
    /// interval (one seed); it is drawn hollow and the plot's note says why, so
    /// that a missing bar never reads as a tiny one.
    pub bars: Vec<Option<(f64, f64)>>,
}

/// A vertical error bar in pixel coordinates, drawn as SVG `<line>`s (the plot's
/// only ones, so a reader or a test can find every bar): a cap at an end inside
/// the plot, an arrowhead at an end the plot cuts off.
struct Bar {
    /// (x, y) of the upper and the lower end, in chart coordinates.
    ends: [(f64, f64); 2],
    /// Whether the upper / lower end was cut at the plot's edge.
    cut: [bool; 2],
    style: ShapeStyle,
}

impl<'a> PointCollection<'a, (f64, f64)> for &'a Bar {
    type Point = &'a (f64, f64);
    type IntoIter = &'a [(f64, f64); 2];
    fn point_iter(self) -> Self::IntoIter {
        &self.ends
    }
}

impl<DB: DrawingBackend> Drawable<DB> for Bar {
    fn draw<I: Iterator<Item = BackendCoord>>(
        &self,
        pos: I,
        backend: &mut DB,
        _: (u32, u32),
    ) -> Result<(), DrawingErrorKind<DB::ErrorType>> {
        let p: Vec<BackendCoord> = pos.take(2).collect();
        let [top, bottom] = [p[0], p[1]];
        backend.draw_line(top, bottom, &self.style)?;
        // Upper end: the arrow points up (y grows downwards), lower end down.
        for (end, cut, dir) in [(top, self.cut[0], -1), (bottom, self.cut[1], 1)] {
            let (x, y) = end;
            if cut {
                backend.draw_line((x - 4, y - 5 * dir), end, &self.style)?;
                backend.draw_line((x + 4, y - 5 * dir), end, &self.style)?;
            } else {
                backend.draw_line((x - 4, y), (x + 4, y), &self.style)?;
            }
        }
        Ok(())
    }
}

/// Distinguishable line colours (Tableau 10), picked in series order.
const PALETTE: [RGBColor; 10] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0xd6, 0x27, 0x28),
    RGBColor(0x94, 0x67, 0xbd),
    RGBColor(0x8c, 0x56, 0x4b),
    RGBColor(0xe3, 0x77, 0xc2),
    RGBColor(0x7f, 0x7f, 0x7f),
    RGBColor(0xbc, 0xbd, 0x22),
    RGBColor(0x17, 0xbe, 0xcf),
];

/// Draws a log-log plot (both axes logarithmic) of every series as a polyline
/// through its points sorted by x, each point marked and labelled.
///
/// Points with a non-positive or non-finite coordinate cannot be shown on a log
/// axis and are left out (a perfect RMSE of 0 has no place on the plot); when no
/// point remains the plot says so instead of failing. Every other point gets its
/// error bar: an end beyond a decade past the points (a lower end ≤ 0 above all,
/// which a log axis cannot show) is cut at the plot's edge and drawn as an arrow,
/// and a note under the plot explains arrows and hollow (one-seed) points.
/// Returns the SVG document.
pub fn loglog_svg(
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
) -> Result<String, String> {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    let series: Vec<Series> = series
        .iter()
        .map(|s| {
            let bar = |i: usize| s.bars.get(i).copied().flatten();
            let mut kept: Vec<_> = s
                .points
                .iter()
                .enumerate()
                .filter(|(_, p)| ok(p.0) && ok(p.1))
                .map(|(i, p)| (p.clone(), bar(i).filter(|b| b.0.is_finite() && ok(b.1))))
                .collect();
            kept.sort_by(|a, b| a.0 .0.total_cmp(&b.0 .0));
            Series {
                name: s.name.clone(),
                points: kept.iter().map(|k| k.0.clone()).collect(),
                bars: kept.iter().map(|k| k.1).collect(),
            }
        })
        .filter(|s| !s.points.is_empty())
        .collect();
    let all = || series.iter().flat_map(|s| s.points.iter());
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 460)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        if series.is_empty() {
            root.draw(&Text::new(
                format!("{title}: no positive data to plot"),
                (20, 30),
                ("sans-serif", 16).into_font(),
            ))
            .map_err(|e| e.to_string())?;
            root.present().map_err(|e| e.to_string())?;
        } else {
            // plotters' own log axis labels only powers of ten, which leaves a plot
            // spanning less than a decade without any number; so the chart is linear
            // in log10 space and the 1-2-5 ticks are drawn here.
            let (x0, x1) = padded_log_range(all().map(|p| p.0));
            // Bar ends stretch the axis by at most a decade past the points; beyond
            // that (or at a lower end ≤ 0) a bar is cut and drawn as an arrow.
            let lowest = all().map(|p| p.1).fold(f64::INFINITY, f64::min);
            let highest = all().map(|p| p.1).fold(0.0, f64::max);
            let shown = |v: f64| ok(v) && v >= lowest / 10.0 && v <= highest * 10.0;
            let bar_ends = series
                .iter()
                .flat_map(|s| s.bars.iter().flatten().flat_map(|b| [b.0, b.1]))
                .filter(|&v| shown(v));
            let (y0, y1) = padded_log_range(all().map(|p| p.1).chain(bar_ends));
            let mut chart = ChartBuilder::on(&root)
                .caption(title, ("sans-serif", 20))
                .margin(12)
                .margin_bottom(30)
                .x_label_area_size(40)
                .y_label_area_size(70)
                .build_cartesian_2d(x0.log10()..x1.log10(), y0.log10()..y1.log10())
                .map_err(|e| e.to_string())?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_labels(0)
                .y_labels(0)
                .x_desc(x_desc)
                .y_desc(y_desc)
                .draw()
                .map_err(|e| e.to_string())?;
            draw_ticks(&root, &mut chart, (x0, x1), (y0, y1))?;
            let (mut cut_any, mut hollow_any) = (false, false);
            for (i, s) in series.iter().enumerate() {
                let color = PALETTE[i % PALETTE.len()];
                let xy: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .map(|p| (p.0.log10(), p.1.log10()))
                    .collect();
                chart
                    .draw_series(LineSeries::new(xy.clone(), color.stroke_width(2)))
                    .map_err(|e| e.to_string())?
                    .label(s.name.clone())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                    });
                let bars = s.points.iter().zip(&s.bars).filter_map(|(p, b)| {
                    let (lo, hi) = (*b)?;
                    let (top, bottom) = (hi.min(y1), if lo > y0 { lo } else { y0 });
                    cut_any |= hi > y1 || lo <= y0;
                    Some(Bar {
                        ends: [(p.0.log10(), top.log10()), (p.0.log10(), bottom.log10())],
                        cut: [hi > y1, lo <= y0],
                        style: color.stroke_width(1),
                    })
                });
                chart.draw_series(bars).map_err(|e| e.to_string())?;
                hollow_any |= s.bars.iter().any(Option::is_none);
                chart
                    .draw_series(s.points.iter().zip(&s.bars).map(|(p, b)| {
                        let style = if b.is_some() {
                            color.filled()
                        } else {
                            WHITE.filled()
                        };
                        EmptyElement::at((p.0.log10(), p.1.log10()))
                            + Circle::new((0, 0), 4, style)
                            + Circle::new((0, 0), 4, color.stroke_width(1))
                            + Text::new(p.2.clone(), (6, -14), ("sans-serif", 13).into_font())
                    }))
                    .map_err(|e| e.to_string())?;
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(|e| e.to_string())?;
            let mut note = String::from("Bars: 95% interval over the seeds.");
            if cut_any {
                note += " Arrow: the interval goes on past the plot's edge.";
            }
            if hollow_any {
                note += " Hollow point: one seed, no interval.";
            }
            let (_, height) = root.dim_in_pixel();
            root.draw(&Text::new(
                note,
                (12, height as i32 - 20),
                ("sans-serif", 13).into_font(),
            ))
            .map_err(|e| e.to_string())?;
            root.present().map_err(|e| e.to_string())?;
        }
    }
    Ok(svg)
}

/// The 1-2-5 grid lines and tick labels of a log-log chart spanning
/// `x0..x1` × `y0..y1` (data units; the chart itself is in log10 units).
fn draw_ticks(
    root: &DrawingArea<SVGBackend, plotters::coord::Shift>,
    chart: &mut ChartContext<
        SVGBackend,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Result<(), String> {
    let grid = BLACK.mix(0.12);
    let label_font = ("sans-serif", 14).into_font();
    for t in nice_ticks(x0, x1) {
        let lx = t.log10();
        let (ly0, ly1) = (y0.log10(), y1.log10());
        chart
            .draw_series(LineSeries::new([(lx, ly0), (lx, ly1)], grid))
            .map_err(|e| e.to_string())?;
        let (px, py) = chart.backend_coord(&(lx, ly0));
        let style = TextStyle::from(label_font.clone()).pos(Pos::new(HPos::Center, VPos::Top));
        root.draw(&Text::new(format_tick(t), (px, py + 6), style))
            .map_err(|e| e.to_string())?;
    }
    for t in nice_ticks(y0, y1) {
        let ly = t.log10();
        let (lx0, lx1) = (x0.log10(), x1.log10());
        chart
            .draw_series(LineSeries::new([(lx0, ly), (lx1, ly)], grid))
            .map_err(|e| e.to_string())?;
        let (px, py) = chart.backend_coord(&(lx0, ly));
        let style = TextStyle::from(label_font.clone()).pos(Pos::new(HPos::Right, VPos::Center));
        root.draw(&Text::new(format_tick(t), (px - 6, py), style))
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// [min, max] of positive values widened by 25 % on each side in log space (and to
/// a factor of 2 at least), so points do not sit on the frame.
fn padded_log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = values.fold((f64::INFINITY, 0.0_f64), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if hi / lo < 2.0 {
        let mid = (lo * hi).sqrt();
        lo = mid / 2.0_f64.sqrt();
        hi = mid * 2.0_f64.sqrt();
    }
    let pad = (hi / lo).powf(0.08);
    (lo / pad, hi * pad)
}

/// Tick values in [lo, hi] on a 1-2-5 sequence per decade; every integer mantissa
/// when that gives fewer than three, powers of ten only when it gives more than ten.
fn nice_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let ticks = |mantissas: &[f64]| -> Vec<f64> {
        let (d0, d1) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        (d0..=d1)
            .flat_map(|d| mantissas.iter().map(move |m| m * 10f64.powi(d)))
            .filter(|v| *v >= lo && *v <= hi)
            .collect()
    };
    let t = ticks(&[1.0, 2.0, 5.0]);
    if t.len() < 3 {
        ticks(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
    } else if t.len() > 10 {
        ticks(&[1.0])
    } else {
        t
    }
}

/// Short tick text: 3 significant digits, scientific outside [1e-3, 1e4).
fn format_tick(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    if v.abs() < 1e-3 || v.abs() >= 1e4 {
        return format!("{v:.1e}");
    }
    let decimals = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}
