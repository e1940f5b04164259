//! SVG line charts (plotters) of the study: stacked panels per file, axes with units in parentheses, legends
//! where they cover no curve ([`legend`]), optional equal aspect, markers, arrows and notes under the panels.

use std::path::Path;

use plotters::coord::Shift;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::prelude::*;

#[path = "../common/legend.rs"]
mod legend;

/// One curve of a panel.
pub struct Series<'a> {
    pub label: &'a str,
    pub x: &'a [f64],
    pub y: &'a [f64],
    pub color: RGBColor,
    pub dashed: bool,
}

/// A marked point with a text beside it.
pub struct Marker {
    pub at: (f64, f64),
    pub text: String,
    pub color: RGBColor,
}

/// An arrowhead on a curve, pointing from `from` to `to` (data coordinates).
pub struct Arrow {
    pub from: (f64, f64),
    pub to: (f64, f64),
    pub color: RGBColor,
}

/// One panel: a title, axis labels (with units) and its curves.
pub struct Panel<'a> {
    pub title: &'a str,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub series: Vec<Series<'a>>,
    /// Logarithmic x axis (for Bode plots).
    pub log_x: bool,
    /// One data unit is as long on both axes (a circle stays a circle).
    pub equal_aspect: bool,
    pub markers: Vec<Marker>,
    pub arrows: Vec<Arrow>,
    /// Height of the panel in pixels.
    pub height: u32,
}

impl<'a> Panel<'a> {
    /// A linear panel with curves only.
    pub fn new(
        title: &'a str,
        x_label: &'a str,
        y_label: &'a str,
        series: Vec<Series<'a>>,
    ) -> Self {
        Panel {
            title,
            x_label,
            y_label,
            series,
            log_x: false,
            equal_aspect: false,
            markers: Vec::new(),
            arrows: Vec::new(),
            height: PANEL_HEIGHT,
        }
    }
}

pub const BLUE_: RGBColor = RGBColor(31, 119, 180);
pub const ORANGE: RGBColor = RGBColor(255, 127, 14);
pub const GREEN_: RGBColor = RGBColor(44, 160, 44);
pub const RED_: RGBColor = RGBColor(214, 39, 40);
pub const GREY: RGBColor = RGBColor(110, 110, 110);

type DrawResult = Result<(), Box<dyn std::error::Error>>;
type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

const WIDTH: u32 = 900;
const PANEL_HEIGHT: u32 = 380;
const NOTE_LINE: u32 = 20;
const MARGIN: u32 = 12;
const MARGIN_RIGHT: u32 = 30;
const X_LABEL_AREA: u32 = 45;
const Y_LABEL_AREA: u32 = 90;
const LEGEND_FONT: f64 = 14.0;

/// Draws the panels stacked vertically into an SVG file, with `notes` as lines of text under them (what the
/// figure shows: scenario, window, conventions).
pub fn draw(path: &Path, panels: &[Panel<'_>], notes: &[&str]) -> DrawResult {
    let notes_height = if notes.is_empty() {
        0
    } else {
        NOTE_LINE * notes.len() as u32 + 10
    };
    let charts_height: u32 = panels.iter().map(|p| p.height).sum();
    let root = SVGBackend::new(path, (WIDTH, charts_height + notes_height)).into_drawing_area();
    root.fill(&WHITE)?;
    let (charts, text) = root.split_vertically(charts_height);
    let breaks: Vec<i32> = panels
        .iter()
        .scan(0i32, |top, p| {
            *top += i32::try_from(p.height).unwrap_or(i32::MAX);
            Some(*top)
        })
        .take(panels.len().saturating_sub(1))
        .collect();
    let areas = charts.split_by_breakpoints(Vec::<i32>::new(), breaks);
    for (area, panel) in areas.iter().zip(panels) {
        draw_panel(area, panel)?;
    }
    for (i, note) in notes.iter().enumerate() {
        text.draw(&Text::new(
            note.to_string(),
            (MARGIN as i32 + 8, (NOTE_LINE as usize * i) as i32 + 4),
            ("sans-serif", 15).into_font().color(&BLACK),
        ))?;
    }
    root.present()?;
    Ok(())
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    let pad = if span > 0.0 {
        0.06 * span
    } else {
        lo.abs().max(1e-12) * 0.1
    };
    (lo - pad, hi + pad)
}

/// Grows the shorter range about its centre so that one unit takes as many pixels on both axes.
fn equalise(x: (f64, f64), y: (f64, f64), px: (f64, f64)) -> ((f64, f64), (f64, f64)) {
    let (sx, sy) = ((x.1 - x.0) / px.0, (y.1 - y.0) / px.1);
    let s = sx.max(sy);
    let grow = |r: (f64, f64), n: f64| {
        let (c, half) = ((r.0 + r.1) / 2.0, s * n / 2.0);
        (c - half, c + half)
    };
    (grow(x, px.0), grow(y, px.1))
}

fn draw_panel(area: &Area<'_>, panel: &Panel<'_>) -> DrawResult {
    let titled = area.titled(panel.title, ("sans-serif", 20))?;
    let (w, h) = titled.dim_in_pixel();
    let plot_px = (
        f64::from(
            w.saturating_sub(MARGIN + MARGIN_RIGHT + Y_LABEL_AREA)
                .max(1),
        ),
        f64::from(h.saturating_sub(2 * MARGIN + X_LABEL_AREA).max(1)),
    );
    let xs = || panel.series.iter().flat_map(|s| s.x.iter().copied());
    let (mut x, mut y) = (
        range(xs()),
        range(panel.series.iter().flat_map(|s| s.y.iter().copied())),
    );
    if panel.log_x {
        let lo = xs().filter(|v| *v > 0.0).fold(f64::INFINITY, f64::min);
        let hi = xs().filter(|v| v.is_finite()).fold(0.0, f64::max);
        x = (lo, hi);
    }
    if panel.equal_aspect {
        (x, y) = equalise(x, y, plot_px);
    }
    let placement = legend_placement(panel, x, y, plot_px);
    y.1 = y.0 + (y.1 - y.0) * placement.headroom;
    let mut builder = ChartBuilder::on(&titled);
    builder
        .margin(MARGIN)
        .margin_right(MARGIN_RIGHT)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA);
    if panel.log_x {
        let mut chart = builder.build_cartesian_2d((x.0..x.1).log_scale(), y.0..y.1)?;
        configure(&mut chart, panel)?;
        plot_series(&mut chart, panel, placement.position)?;
    } else {
        let mut chart = builder.build_cartesian_2d(x.0..x.1, y.0..y.1)?;
        configure(&mut chart, panel)?;
        plot_series(&mut chart, panel, placement.position)?;
    }
    Ok(())
}

/// The legend's corner for the panel's curves, markers included (normalised to the plotting area).
fn legend_placement(
    panel: &Panel<'_>,
    x: (f64, f64),
    y: (f64, f64),
    plot_px: (f64, f64),
) -> legend::Placement {
    let nx = |v: f64| {
        if panel.log_x {
            legend::normalise(v.max(f64::MIN_POSITIVE).log10(), (x.0.log10(), x.1.log10()))
        } else {
            legend::normalise(v, x)
        }
    };
    let mut curves: Vec<Vec<(f64, f64)>> = panel
        .series
        .iter()
        .map(|s| {
            s.x.iter()
                .zip(s.y)
                .filter(|(a, b)| a.is_finite() && b.is_finite())
                .map(|(a, b)| (nx(*a), legend::normalise(*b, y)))
                .collect()
        })
        .collect();
    // A marker's text runs to its right: keep that strip free as well.
    for m in &panel.markers {
        let (px, py) = (nx(m.at.0), legend::normalise(m.at.1, y));
        let text_w = (m.text.chars().count() as f64 * 8.0 + 12.0) / plot_px.0;
        curves.push(vec![(px, py), (px + text_w, py + 18.0 / plot_px.1)]);
    }
    let labels: Vec<&str> = panel
        .series
        .iter()
        .map(|s| s.label)
        .filter(|l| !l.is_empty())
        .collect();
    legend::place(&curves, plot_px, legend::legend_size(&labels, LEGEND_FONT))
}

fn configure<'a, X>(
    chart: &mut ChartContext<
        'a,
        SVGBackend<'a>,
        Cartesian2d<X, plotters::coord::types::RangedCoordf64>,
    >,
    panel: &Panel<'_>,
) -> DrawResult
where
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let y_range = chart.y_range();
    let span = y_range.end - y_range.start;
    let x_range = chart.x_range();
    let x_span = x_range.end - x_range.start;
    chart
        .configure_mesh()
        .x_desc(panel.x_label)
        .y_desc(panel.y_label)
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .light_line_style(RGBColor(235, 235, 235))
        .y_label_formatter(&|v| format_tick(*v, span))
        .x_label_formatter(&|v| {
            if panel.log_x {
                format!("{v:.0e}")
            } else {
                format_tick(*v, x_span)
            }
        })
        .draw()?;
    Ok(())
}

fn plot_series<'a, X>(
    chart: &mut ChartContext<
        'a,
        SVGBackend<'a>,
        Cartesian2d<X, plotters::coord::types::RangedCoordf64>,
    >,
    panel: &Panel<'_>,
    legend_position: SeriesLabelPosition,
) -> DrawResult
where
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    for s in &panel.series {
        let style = s.color.stroke_width(2);
        let points: Vec<(f64, f64)> =
            s.x.iter()
                .zip(s.y)
                .filter(|(x, y)| x.is_finite() && y.is_finite())
                .map(|(x, y)| (*x, *y))
                .collect();
        let color = s.color;
        let drawn = if s.dashed {
            chart.draw_series(DashedLineSeries::new(points, 8, 5, style))?
        } else {
            chart.draw_series(LineSeries::new(points, style))?
        };
        // A curve with an empty label (e.g. the second of a pair of limit lines) gets no legend entry.
        if !s.label.is_empty() {
            drawn.label(s.label).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        }
    }
    for m in &panel.markers {
        let color = m.color;
        chart.draw_series(std::iter::once(
            EmptyElement::at(m.at)
                + Circle::new((0, 0), 6, color.stroke_width(2))
                + Cross::new((0, 0), 4, color.stroke_width(2))
                + Text::new(
                    m.text.clone(),
                    (10, -18),
                    ("sans-serif", 14).into_font().color(&color),
                ),
        ))?;
    }
    for a in &panel.arrows {
        let (from, to) = (chart.backend_coord(&a.from), chart.backend_coord(&a.to));
        let head = arrowhead(from, to);
        let color = a.color;
        // Drawn in pixels so that every head has the same size whatever the axes' scales.
        let base = chart.plotting_area().get_base_pixel();
        let shifted: Vec<(i32, i32)> = head.iter().map(|p| (p.0 - base.0, p.1 - base.1)).collect();
        chart
            .plotting_area()
            .strip_coord_spec()
            .draw(&Polygon::new(shifted, color.filled()))?;
    }
    chart
        .configure_series_labels()
        .position(legend_position)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .label_font(("sans-serif", LEGEND_FONT as u32))
        .draw()?;
    Ok(())
}

/// A filled triangle of 14 px pointing along `from → to`, tip at `to`.
fn arrowhead(from: (i32, i32), to: (i32, i32)) -> Vec<(i32, i32)> {
    let (dx, dy) = (f64::from(to.0 - from.0), f64::from(to.1 - from.1));
    let len = dx.hypot(dy).max(1e-9);
    let (ux, uy) = (dx / len, dy / len);
    let (length, half_width) = (14.0, 6.0);
    let tip = (f64::from(to.0), f64::from(to.1));
    let back = (tip.0 - length * ux, tip.1 - length * uy);
    let left = (back.0 - half_width * uy, back.1 + half_width * ux);
    let right = (back.0 + half_width * uy, back.1 - half_width * ux);
    [tip, left, right]
        .iter()
        .map(|p| (p.0.round() as i32, p.1.round() as i32))
        .collect()
}

/// Ticks in plain notation where readable, scientific otherwise; a tick that is zero up to rounding relative
/// to the axis span prints as 0.
fn format_tick(v: f64, span: f64) -> String {
    let a = v.abs();
    if a <= 1e-9 * span.abs() {
        "0".to_string()
    } else if (1e-2..1e4).contains(&a) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.1e}")
    }
}
