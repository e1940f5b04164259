//! SVG plots of the runs, the analogs of the paper's Figs. 10–12, with plotters.

use bgc_workspace::rehab::experiment::SegmentRun;
use plotters::prelude::*;
use std::path::Path;

#[path = "../common/legend.rs"]
mod legend;

const DEG: f64 = 180.0 / std::f64::consts::PI;

/// One curve: legend, colour, points (time in s, angle in °).
pub struct Curve {
    pub name: String,
    pub color: RGBColor,
    pub points: Vec<(f64, f64)>,
}

const STANDARD: RGBColor = RGBColor(200, 30, 30);
const VISION: RGBColor = RGBColor(30, 140, 30);
const IMU: RGBColor = RGBColor(30, 70, 200);
const FUSION: RGBColor = RGBColor(140, 40, 160);
const ACCEL: RGBColor = RGBColor(150, 150, 150);

fn series(times: &[f64], values: &[f64], window: (f64, f64), scale: f64) -> Vec<(f64, f64)> {
    times
        .iter()
        .zip(values)
        .filter(|(t, _)| **t >= window.0 && **t <= window.1)
        .map(|(&t, &v)| (t, v * scale))
        .collect()
}

/// The curves of a segment run in a time window, in degrees: standard, vision, IMU, fusion.
pub fn angle_curves(run: &SegmentRun, window: (f64, f64)) -> Vec<Curve> {
    let e = &run.estimates;
    vec![
        Curve {
            name: "standard (true angle)".into(),
            color: STANDARD,
            points: series(&e.times, &e.truth, window, DEG),
        },
        Curve {
            name: "vision (first-order hold)".into(),
            color: VISION,
            points: series(&e.times, &e.vision, window, DEG),
        },
        Curve {
            name: "IMU (Kalman filter, Eqs. 5-6)".into(),
            color: IMU,
            points: series(&e.times, &e.imu, window, DEG),
        },
        Curve {
            name: "fusion (Eq. 27 weights)".into(),
            color: FUSION,
            points: series(&e.times, &run.fused, window, DEG),
        },
    ]
}

/// Single-source panels as in Fig. 10: (a) gravity decomposition, (b) IMU filter, (c) vision, (d) fusion, each
/// with the standard curve.
pub fn source_panels(run: &SegmentRun, window: (f64, f64)) -> Vec<(String, Vec<Curve>)> {
    let e = &run.estimates;
    let standard = || Curve {
        name: "standard (true angle)".into(),
        color: STANDARD,
        points: series(&e.times, &e.truth, window, DEG),
    };
    let panel = |title: &str, name: &str, color, values: &[f64]| {
        (
            title.to_string(),
            vec![
                standard(),
                Curve {
                    name: name.into(),
                    color,
                    points: series(&e.times, values, window, DEG),
                },
            ],
        )
    };
    vec![
        panel(
            "(a) gravity decomposition, Eq. 2",
            "accelerometer angle",
            ACCEL,
            &e.accel_angle,
        ),
        panel("(b) IMU Kalman filter, Eqs. 5-6", "IMU", IMU, &e.imu),
        panel("(c) vision", "vision", VISION, &e.vision),
        panel("(d) fusion, Eq. 27", "fusion", FUSION, &run.fused),
    ]
}

/// Error curves (estimate minus standard) in degrees.
pub fn error_curves(run: &SegmentRun, window: (f64, f64)) -> Vec<Curve> {
    let e = &run.estimates;
    let err = |v: &[f64]| -> Vec<f64> { v.iter().zip(&e.truth).map(|(a, b)| a - b).collect() };
    vec![
        Curve {
            name: "vision".into(),
            color: VISION,
            points: series(&e.times, &err(&e.vision), window, DEG),
        },
        Curve {
            name: "IMU".into(),
            color: IMU,
            points: series(&e.times, &err(&e.imu), window, DEG),
        },
        Curve {
            name: "fusion".into(),
            color: FUSION,
            points: series(&e.times, &err(&run.fused), window, DEG),
        },
    ]
}

/// Splits points at non-finite values so that gaps (lost vision) are drawn as gaps.
fn finite_runs(points: &[(f64, f64)]) -> Vec<Vec<(f64, f64)>> {
    let mut runs = vec![Vec::new()];
    for &(t, v) in points {
        if v.is_finite() {
            if let Some(last) = runs.last_mut() {
                last.push((t, v));
            }
        } else if runs.last().is_some_and(|r| !r.is_empty()) {
            runs.push(Vec::new());
        }
    }
    runs.retain(|r| !r.is_empty());
    runs
}

fn y_range(panels: &[(String, Vec<Curve>)]) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (_, curves) in panels {
        for c in curves {
            for &(_, v) in &c.points {
                if v.is_finite() {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return (-1.0, 1.0);
    }
    let span = (hi - lo).max(1e-3);
    (lo - 0.06 * span, hi + 0.06 * span)
}

const MARGIN: u32 = 10;
const X_LABEL_AREA: u32 = 38;
const Y_LABEL_AREA: u32 = 55;
const NOTE_HEIGHT: u32 = 26;
const LEGEND_FONT: f64 = 13.0;

/// Draws panels stacked in a `rows x cols` grid into an SVG file, with `note` (the scenario) under them; all
/// panels share the time window, the y range and the y label.
pub fn draw(
    path: &Path,
    panels: &[(String, Vec<Curve>)],
    grid: (usize, usize),
    window: (f64, f64),
    y_label: &str,
    note: &str,
) -> Result<(), String> {
    draw_panels(path, panels, grid, window, y_label, note)
        .map_err(|e| format!("cannot draw {}: {e}", path.display()))
}

/// The legend placement of one panel's curves in the shared ranges.
fn placement(
    curves: &[Curve],
    window: (f64, f64),
    y: (f64, f64),
    plot_px: (f64, f64),
) -> legend::Placement {
    let norm: Vec<Vec<(f64, f64)>> = curves
        .iter()
        .map(|c| {
            c.points
                .iter()
                .filter(|p| p.1.is_finite())
                .map(|p| (legend::normalise(p.0, window), legend::normalise(p.1, y)))
                .collect()
        })
        .collect();
    let labels: Vec<&str> = curves.iter().map(|c| c.name.as_str()).collect();
    legend::place(&norm, plot_px, legend::legend_size(&labels, LEGEND_FONT))
}

fn draw_panels(
    path: &Path,
    panels: &[(String, Vec<Curve>)],
    grid: (usize, usize),
    window: (f64, f64),
    y_label: &str,
    note: &str,
) -> Result<(), Box<dyn std::error::Error>> {
    let (rows, cols) = grid;
    let width = if cols == 1 { 900 } else { 640 * cols as u32 };
    let charts_height = 330 * rows as u32;
    let root = SVGBackend::new(path, (width, charts_height + NOTE_HEIGHT)).into_drawing_area();
    root.fill(&WHITE)?;
    let (charts, strip) = root.split_vertically(charts_height);
    strip.draw(&Text::new(
        note.to_string(),
        (12, 4),
        ("sans-serif", 14).into_font().color(&BLACK),
    ))?;
    let areas = charts.split_evenly((rows, cols));
    let titled: Vec<_> = areas
        .iter()
        .zip(panels)
        .map(|(area, (title, _))| area.titled(title, ("sans-serif", 18)))
        .collect::<Result<_, _>>()?;
    let (y0, y1) = y_range(panels);
    // One y range for all panels: the largest headroom any panel's legend needs.
    let placements: Vec<legend::Placement> = titled
        .iter()
        .zip(panels)
        .map(|(area, (_, curves))| {
            let (w, h) = area.dim_in_pixel();
            let plot_px = (
                f64::from(w.saturating_sub(2 * MARGIN + Y_LABEL_AREA).max(1)),
                f64::from(h.saturating_sub(2 * MARGIN + X_LABEL_AREA).max(1)),
            );
            placement(curves, window, (y0, y1), plot_px)
        })
        .collect();
    let headroom = placements.iter().map(|p| p.headroom).fold(1.0, f64::max);
    let y1 = y0 + (y1 - y0) * headroom;
    for ((area, (_, curves)), place) in titled.iter().zip(panels).zip(&placements) {
        let mut chart = ChartBuilder::on(area)
            .margin(MARGIN)
            .x_label_area_size(X_LABEL_AREA)
            .y_label_area_size(Y_LABEL_AREA)
            .build_cartesian_2d(window.0..window.1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc(y_label)
            .label_style(("sans-serif", 13))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()?;
        for c in curves {
            let style = ShapeStyle::from(&c.color).stroke_width(2);
            let mut first = true;
            for run in finite_runs(&c.points) {
                let drawn = chart.draw_series(LineSeries::new(run, style))?;
                if first {
                    let color = c.color;
                    drawn.label(c.name.clone()).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(3))
                    });
                    first = false;
                }
            }
        }
        // With a free corner the legend sits there; otherwise above the data in the headroom.
        let position = if place.headroom > 1.0 {
            SeriesLabelPosition::UpperRight
        } else {
            place.position.clone()
        };
        chart
            .configure_series_labels()
            .position(position)
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .label_font(("sans-serif", LEGEND_FONT as u32))
            .draw()?;
    }
    root.present()?;
    Ok(())
}
