//! `bgc fit --plot OUT.svg`: the measured samples and the fitted outputs, one panel per measured output.

use bgc_runtime::fit::{FitReport, Record};
use plotters::prelude::*;
use std::path::Path;

const WIDTH: u32 = 900;
const PANEL_HEIGHT: u32 = 300;

/// Writes the SVG, whole or not at all.
pub fn write(
    path: &Path,
    record: &Record,
    report: &FitReport,
    names: &[String],
) -> Result<(), Box<dyn std::error::Error>> {
    let panels = names.len().max(1) as u32;
    let mut svg = String::new();
    draw(&mut svg, panels, record, report, names)?;
    bgc::files::write_whole(path, svg.as_bytes())?;
    Ok(())
}

/// Draws the panels into `svg`.
fn draw(
    svg: &mut String,
    panels: u32,
    record: &Record,
    report: &FitReport,
    names: &[String],
) -> Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::with_string(svg, (WIDTH, PANEL_HEIGHT * panels)).into_drawing_area();
    root.fill(&WHITE)?;
    let areas = root.split_evenly((names.len().max(1), 1));
    let t0 = record.times.first().copied().unwrap_or(0.0);
    let t1 = record.times.last().copied().unwrap_or(1.0);
    for (c, (area, name)) in areas.iter().zip(names).enumerate() {
        let measured: Vec<(f64, f64)> = record
            .times
            .iter()
            .zip(&record.measured)
            .filter(|(_, m)| !m[c].is_nan())
            .map(|(&t, m)| (t, m[c]))
            .collect();
        let fitted: Vec<(f64, f64)> = record
            .times
            .iter()
            .copied()
            .zip(report.fitted[c].iter().copied())
            .collect();
        let (lo, hi) = measured
            .iter()
            .chain(&fitted)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &(_, y)| {
                (a.min(y), b.max(y))
            });
        let pad = ((hi - lo) * 0.05).max(1e-12);
        let mut chart = ChartBuilder::on(area)
            .caption(name, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(70)
            .build_cartesian_2d(t0..t1, (lo - pad)..(hi + pad))?;
        chart.configure_mesh().x_desc("t [s]").draw()?;
        chart
            .draw_series(
                measured
                    .iter()
                    .map(|&p| Circle::new(p, 2, BLUE.mix(0.5).filled())),
            )?
            .label("measured")
            .legend(|(x, y)| Circle::new((x + 10, y), 3, BLUE.filled()));
        chart
            .draw_series(LineSeries::new(fitted, RED.stroke_width(2)))?
            .label("fitted")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
    }
    root.present()?;
    Ok(())
}
