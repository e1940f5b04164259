//! SVG plots of the runs, the analogs of the paper's Figs. 10–12, with plotters.

use bgc_workspace::rehab::experiment::SegmentRun;
use plotters::prelude::*;
use std::path::Path;

const DEG: f64 = 180.0 / std::f64::consts::PI;

/// One curve: legend, colour, dashed, points (time [s], angle [deg]).
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
    // Room above the data for the legend.
    let span = (hi - lo).max(1e-3);
    (lo - 0.08 * span, hi + 0.55 * span)
}

/// Draws panels stacked in a `rows x cols` grid into an SVG file; all panels share the time window and the y label.
pub fn draw(
    path: &Path,
    panels: &[(String, Vec<Curve>)],
    grid: (usize, usize),
    window: (f64, f64),
    y_label: &str,
) -> Result<(), String> {
    draw_panels(path, panels, grid, window, y_label)
        .map_err(|e| format!("cannot draw {}: {e}", path.display()))
}

fn draw_panels(
    path: &Path,
    panels: &[(String, Vec<Curve>)],
    grid: (usize, usize),
    window: (f64, f64),
    y_label: &str,
) -> Result<(), Box<dyn std::error::Error>> {
    let (rows, cols) = grid;
    let width = if cols == 1 { 900 } else { 640 * cols as u32 };
    let size = (width, 330 * rows as u32);
    let root = SVGBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE)?;
    let areas = root.split_evenly((rows, cols));
    let (y0, y1) = y_range(panels);
    for (area, (title, curves)) in areas.iter().zip(panels) {
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(38)
            .y_label_area_size(55)
            .build_cartesian_2d(window.0..window.1, y0..y1)?;
        chart
            .configure_mesh()
            .x_desc("time [s]")
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
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 13))
            .draw()?;
    }
    root.present()?;
    Ok(())
}
