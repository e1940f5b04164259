//! SVG analogs of the paper's Figs. 11–14, 16 and 17, the joint torques, and the supervisor's view of the
//! gait with the ground reaction of the stance leg.

use bgc_workspace::walking::plant::MOTOR_PEAK_TORQUE;
use bgc_workspace::walking::scenario::{ControlSample, FilterSample, WalkingConfig, WalkingRun};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::error::Error;
use std::path::Path;

#[path = "../common/legend.rs"]
mod legend;

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
type PlotResult<T> = Result<T, Box<dyn Error>>;

const TRUE: RGBColor = RGBColor(0, 0, 0);
const ESTIMATE: RGBColor = RGBColor(31, 119, 180);
const MEASURED: RGBColor = RGBColor(170, 170, 170);
const REFERENCE: RGBColor = RGBColor(214, 39, 40);
const BOUND: RGBColor = RGBColor(255, 127, 14);
const INTENT: RGBColor = RGBColor(44, 160, 44);

const MARGIN: u32 = 8;
const NOTE_HEIGHT: u32 = 26;
const X_LABEL_AREA: u32 = 38;
const Y_LABEL_AREA: u32 = 62;

/// Knee and hip indices in the state order (ankle, knee, hip).
const JOINTS: [(usize, &str); 2] = [(2, "hip"), (1, "knee")];

struct Line {
    name: String,
    color: RGBColor,
    width: u32,
    points: Vec<(f64, f64)>,
}

/// A white SVG canvas of `size` pixels at `path`, split into `grid` (rows, columns) panels above a strip
/// with `note` (the scenario the figure shows).
fn canvas<'a>(
    path: &'a Path,
    size: (u32, u32),
    grid: (usize, usize),
    note: &str,
) -> PlotResult<(Area<'a>, Vec<Area<'a>>)> {
    let root = SVGBackend::new(path, (size.0, size.1 + NOTE_HEIGHT)).into_drawing_area();
    root.fill(&WHITE)?;
    let (charts, strip) = root.split_vertically(size.1);
    strip.draw(&Text::new(
        note.to_string(),
        (12, 4),
        ("sans-serif", 14).into_font().color(&BLACK),
    ))?;
    let areas = charts.split_evenly(grid);
    Ok((root, areas))
}

/// What every figure shows, for its note.
fn scenario_note(cfg: &WalkingConfig) -> String {
    let (t0, t1) = window(cfg);
    format!(
        "Walking: {:.0} s simulated, control at {:.0} Hz, dual UKF at {:.0} Hz, masses start {:.0} % heavy, \
         seed {}; time series show {t0:.0}–{t1:.0} s (masses: the whole run).",
        cfg.duration,
        1.0 / cfg.control_period,
        1.0 / (cfg.control_period * cfg.filter_decimation as f64),
        100.0 * cfg.mass_error,
        cfg.seed
    )
}

fn line(name: &str, color: RGBColor, width: u32, points: Vec<(f64, f64)>) -> Line {
    Line {
        name: name.to_string(),
        color,
        width,
        points,
    }
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    if lo > hi {
        return (-1.0, 1.0);
    }
    let pad = if hi > lo { 0.06 * (hi - lo) } else { 1.0 };
    (lo - pad, hi + pad)
}

/// One chart with a legend where it covers no curve (`common/legend.rs`).
fn panel(area: &Area, title: &str, x_desc: &str, y_desc: &str, lines: &[Line]) -> PlotResult<()> {
    let (x0, x1) = range(lines.iter().flat_map(|l| l.points.iter().map(|p| p.0)));
    let (y0, y1) = range(lines.iter().flat_map(|l| l.points.iter().map(|p| p.1)));
    let titled = area.titled(title, ("sans-serif", 18))?;
    let (w, h) = titled.dim_in_pixel();
    let plot_px = (
        f64::from(w.saturating_sub(2 * MARGIN + Y_LABEL_AREA).max(1)),
        f64::from(h.saturating_sub(2 * MARGIN + X_LABEL_AREA).max(1)),
    );
    let curves: Vec<Vec<(f64, f64)>> = lines
        .iter()
        .map(|l| {
            l.points
                .iter()
                .filter(|p| p.0.is_finite() && p.1.is_finite())
                .map(|p| {
                    (
                        legend::normalise(p.0, (x0, x1)),
                        legend::normalise(p.1, (y0, y1)),
                    )
                })
                .collect()
        })
        .collect();
    let labels: Vec<&str> = lines
        .iter()
        .map(|l| l.name.as_str())
        .filter(|n| !n.is_empty())
        .collect();
    let placement = legend::place(&curves, plot_px, legend::legend_size(&labels, 13.0));
    let y1 = y0 + (y1 - y0) * placement.headroom;
    let mut chart = ChartBuilder::on(&titled)
        .margin(MARGIN)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 14))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    for l in lines {
        let style = ShapeStyle::from(&l.color).stroke_width(l.width);
        // A non-finite value breaks the line (e.g. P of an unloaded foot); only the first piece is labelled.
        let pieces = l
            .points
            .split(|p| !p.1.is_finite())
            .filter(|piece| !piece.is_empty());
        for (i, piece) in pieces.enumerate() {
            let drawn = chart.draw_series(LineSeries::new(piece.iter().copied(), style))?;
            if i == 0 && !l.name.is_empty() {
                drawn
                    .label(l.name.as_str())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
            }
        }
    }
    chart
        .configure_series_labels()
        .position(placement.position)
        .background_style(WHITE.mix(0.9))
        .border_style(RGBColor(120, 120, 120))
        .label_font(("sans-serif", 13))
        .draw()?;
    Ok(())
}

/// The normalised autocorrelation (biased estimator, as `FilterHealth`) for lags `0..=max_lag`.
fn autocorrelation(x: &[f64], max_lag: usize) -> Vec<(f64, f64)> {
    let n = x.len();
    if n < 2 {
        return Vec::new();
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let d: Vec<f64> = x.iter().map(|v| v - mean).collect();
    let c0: f64 = d.iter().map(|v| v * v).sum();
    if c0 <= 0.0 {
        return Vec::new();
    }
    (0..=max_lag.min(n - 1))
        .map(|l| {
            let c: f64 = (l..n).map(|k| d[k] * d[k - l]).sum();
            (l as f64, c / c0)
        })
        .collect()
}

/// The time window shown in the time-series plots: three seconds late in the run.
fn window(cfg: &WalkingConfig) -> (f64, f64) {
    let end = cfg.duration;
    let start = (end - 3.0).max(cfg.warmup).max(0.0);
    (start, end)
}

fn filter_in(r: &WalkingRun, w: (f64, f64)) -> Vec<&FilterSample> {
    r.filter
        .iter()
        .filter(|s| s.t >= w.0 && s.t <= w.1)
        .collect()
}

fn control_in(r: &WalkingRun, w: (f64, f64)) -> Vec<&ControlSample> {
    r.control
        .iter()
        .filter(|s| s.t >= w.0 && s.t <= w.1)
        .collect()
}

fn series<T>(samples: &[&T], f: impl Fn(&T) -> (f64, f64)) -> Vec<(f64, f64)> {
    samples.iter().map(|s| f(s)).collect()
}

fn fig11(r: &WalkingRun, cfg: &WalkingConfig, path: &Path) -> PlotResult<()> {
    let (root, areas) = canvas(path, (1200, 800), (2, 2), &scenario_note(cfg))?;
    let s = filter_in(r, window(cfg));
    for (col, (j, name)) in JOINTS.iter().enumerate() {
        let j = *j;
        panel(
            &areas[col],
            &format!("Fig. 11 analog: {name} angle, generated vs measured"),
            "time (s)",
            "angle (°)",
            &[
                line(
                    "sensor",
                    MEASURED,
                    1,
                    series(&s, |x| (x.t, x.q_measured[j])),
                ),
                line("true", TRUE, 2, series(&s, |x| (x.t, x.q_true[j]))),
                line(
                    "dual UKF",
                    ESTIMATE,
                    2,
                    series(&s, |x| (x.t, x.q_estimate[j])),
                ),
            ],
        )?;
        panel(
            &areas[2 + col],
            &format!("{name} angular velocity, generated vs true"),
            "time (s)",
            "angular velocity (°/s)",
            &[
                line("true", TRUE, 2, series(&s, |x| (x.t, x.qd_true[j]))),
                line(
                    "dual UKF",
                    ESTIMATE,
                    2,
                    series(&s, |x| (x.t, x.qd_estimate[j])),
                ),
            ],
        )?;
    }
    root.present()?;
    Ok(())
}

fn after_warmup<'a>(r: &'a WalkingRun, cfg: &WalkingConfig) -> Vec<&'a FilterSample> {
    r.filter.iter().filter(|s| s.t >= cfg.warmup).collect()
}

fn fig12(r: &WalkingRun, cfg: &WalkingConfig, path: &Path) -> PlotResult<()> {
    let (root, areas) = canvas(path, (1200, 800), (2, 2), &scenario_note(cfg))?;
    let s = filter_in(r, window(cfg));
    let all = after_warmup(r, cfg);
    for (col, (j, name)) in JOINTS.iter().enumerate() {
        let j = *j;
        panel(
            &areas[col],
            &format!("Fig. 12 analog: {name} innovation (residual)"),
            "time (s)",
            "residual y − ŷ⁻ (°)",
            &[line(
                "residual",
                ESTIMATE,
                1,
                series(&s, |x| (x.t, x.residual[j])),
            )],
        )?;
        let res: Vec<f64> = all.iter().map(|x| x.residual[j]).collect();
        panel(
            &areas[2 + col],
            &format!("{name} residual autocorrelation (after warm-up)"),
            "lag (filter steps of 10 ms)",
            "normalised autocorrelation",
            &[line("ρ(lag)", ESTIMATE, 2, autocorrelation(&res, 50))],
        )?;
    }
    root.present()?;
    Ok(())
}

fn fig13(r: &WalkingRun, cfg: &WalkingConfig, path: &Path) -> PlotResult<()> {
    let (root, areas) = canvas(path, (1200, 800), (2, 2), &scenario_note(cfg))?;
    let s = filter_in(r, window(cfg));
    for (col, (j, name)) in JOINTS.iter().enumerate() {
        let j = *j;
        panel(
            &areas[col],
            &format!("Fig. 13 analog: {name} angle error and 1σ bound"),
            "time (s)",
            "angle error x − x̂ (°)",
            &[
                line(
                    "error",
                    ESTIMATE,
                    1,
                    series(&s, |x| (x.t, x.q_true[j] - x.q_estimate[j])),
                ),
                line("+1σ", BOUND, 2, series(&s, |x| (x.t, x.q_sigma[j]))),
                line("−1σ", BOUND, 2, series(&s, |x| (x.t, -x.q_sigma[j]))),
            ],
        )?;
        panel(
            &areas[2 + col],
            &format!("{name} velocity error and 1σ bound"),
            "time (s)",
            "velocity error (°/s)",
            &[
                line(
                    "error",
                    ESTIMATE,
                    1,
                    series(&s, |x| (x.t, x.qd_true[j] - x.qd_estimate[j])),
                ),
                line("+1σ", BOUND, 2, series(&s, |x| (x.t, x.qd_sigma[j]))),
                line("−1σ", BOUND, 2, series(&s, |x| (x.t, -x.qd_sigma[j]))),
            ],
        )?;
    }
    root.present()?;
    Ok(())
}

fn fig14(r: &WalkingRun, cfg: &WalkingConfig, path: &Path) -> PlotResult<()> {
    let (root, areas) = canvas(path, (1200, 800), (2, 2), &scenario_note(cfg))?;
    let all = after_warmup(r, cfg);
    for (col, (j, name)) in JOINTS.iter().enumerate() {
        let j = *j;
        let pos: Vec<f64> = all.iter().map(|x| x.q_true[j] - x.q_estimate[j]).collect();
        let vel: Vec<f64> = all
            .iter()
            .map(|x| x.qd_true[j] - x.qd_estimate[j])
            .collect();
        panel(
            &areas[col],
            &format!("Fig. 14 analog: {name} angle error autocorrelation"),
            "lag (filter steps of 10 ms)",
            "normalised autocorrelation",
            &[line("ρ(lag)", ESTIMATE, 2, autocorrelation(&pos, 50))],
        )?;
        panel(
            &areas[2 + col],
            &format!("{name} velocity error autocorrelation"),
            "lag (filter steps of 10 ms)",
            "normalised autocorrelation",
            &[line("ρ(lag)", ESTIMATE, 2, autocorrelation(&vel, 50))],
        )?;
    }
    root.present()?;
    Ok(())
}

fn fig16(r: &WalkingRun, cfg: &WalkingConfig, path: &Path) -> PlotResult<()> {
    let (root, areas) = canvas(path, (1200, 800), (2, 2), &scenario_note(cfg))?;
    let s = control_in(r, window(cfg));
    for (col, (j, name)) in JOINTS.iter().enumerate() {
        let j = *j;
        panel(
            &areas[col],
            &format!("Fig. 16 analog: {name} angle, reference vs exoskeleton"),
            "time (s)",
            "angle (°)",
            &[
                line(
                    "wearer (intended)",
                    INTENT,
                    2,
                    series(&s, |x| (x.t, x.q_intended[j])),
                ),
                line(
                    "reference (dual UKF)",
                    REFERENCE,
                    2,
                    series(&s, |x| (x.t, x.q_reference[j])),
                ),
                line("exoskeleton", TRUE, 1, series(&s, |x| (x.t, x.q[j]))),
            ],
        )?;
        panel(
            &areas[2 + col],
            &format!("{name} angular velocity, reference vs exoskeleton"),
            "time (s)",
            "angular velocity (°/s)",
            &[
                line(
                    "reference (dual UKF)",
                    REFERENCE,
                    2,
                    series(&s, |x| (x.t, x.qd_reference[j])),
                ),
                line("exoskeleton", TRUE, 1, series(&s, |x| (x.t, x.qd[j]))),
            ],
        )?;
    }
    root.present()?;
    Ok(())
}

fn fig17(r: &WalkingRun, cfg: &WalkingConfig, path: &Path) -> PlotResult<()> {
    let (root, areas) = canvas(path, (1200, 900), (3, 1), &scenario_note(cfg))?;
    let s: Vec<&FilterSample> = r.filter.iter().collect();
    let names = ["m1 (foot)", "m2 (shank)", "m3 (thigh, + torso in stance)"];
    for (i, name) in names.iter().enumerate() {
        panel(
            &areas[i],
            &format!("Fig. 17 analog: estimated {name}"),
            "time (s)",
            "mass (kg)",
            &[
                line("true", TRUE, 2, series(&s, |x| (x.t, x.masses_true[i]))),
                line("dual UKF", ESTIMATE, 2, series(&s, |x| (x.t, x.masses[i]))),
                line(
                    "±1σ",
                    BOUND,
                    1,
                    series(&s, |x| (x.t, x.masses[i] + x.mass_sigma[i])),
                ),
                line(
                    "",
                    BOUND,
                    1,
                    series(&s, |x| (x.t, x.masses[i] - x.mass_sigma[i])),
                ),
            ],
        )?;
    }
    root.present()?;
    Ok(())
}

fn state_number(label: &str) -> f64 {
    match label {
        "S1" => 1.0,
        "S2" => 2.0,
        "S3" => 3.0,
        "S4" => 4.0,
        _ => 0.0,
    }
}

fn supervisor(r: &WalkingRun, cfg: &WalkingConfig, path: &Path) -> PlotResult<()> {
    let (root, areas) = canvas(path, (1200, 1000), (3, 1), &scenario_note(cfg))?;
    let s = control_in(r, window(cfg));
    let index = |f: fn(&ControlSample) -> Option<f64>| -> Vec<(f64, f64)> {
        // An unloaded foot has no P: the line breaks there.
        s.iter().map(|x| (x.t, f(x).unwrap_or(f64::NAN))).collect()
    };
    panel(
        &areas[0],
        "Ground-reaction index P (Eq. 30): 1 heel strike, 0 heel flat, −1 heel off; none in the air",
        "time (s)",
        "P",
        &[
            line("right", ESTIMATE, 2, index(|x| x.right_index)),
            line("left", REFERENCE, 2, index(|x| x.left_index)),
        ],
    )?;
    panel(
        &areas[1],
        "Supervisor state (Table 2): S1 R pre-swing, S2 R swing, S3 L pre-swing, S4 L swing",
        "time (s)",
        "state",
        &[line(
            "state",
            TRUE,
            2,
            series(&s, |x| (x.t, state_number(x.state))),
        )],
    )?;
    panel(
        &areas[2],
        "Ground reaction on the right foot (Eq. 2), from the insoles, along the leg's axis",
        "time (s)",
        "force (N)",
        &[
            line(
                "R_y (up)",
                ESTIMATE,
                2,
                series(&s, |x| (x.t, x.ground_reaction[1])),
            ),
            line(
                "R_x (forward)",
                REFERENCE,
                2,
                series(&s, |x| (x.t, x.ground_reaction[0])),
            ),
        ],
    )?;
    root.present()?;
    Ok(())
}

fn torques(r: &WalkingRun, cfg: &WalkingConfig, path: &Path) -> PlotResult<()> {
    let (root, areas) = canvas(path, (1200, 800), (2, 1), &scenario_note(cfg))?;
    let s = control_in(r, window(cfg));
    for (row, (j, name)) in JOINTS.iter().enumerate() {
        let j = *j;
        let rating = MOTOR_PEAK_TORQUE[j];
        panel(
            &areas[row],
            &format!("{name} torques: motor (rated ±{rating} N m) and wearer"),
            "time (s)",
            "torque (N m)",
            &[
                line(
                    "wearer (brace sensors)",
                    INTENT,
                    2,
                    series(&s, |x| (x.t, x.human_torque[j])),
                ),
                line(
                    "motor command",
                    BOUND,
                    1,
                    series(&s, |x| (x.t, x.commanded_torque[j])),
                ),
                line(
                    "motor delivered",
                    ESTIMATE,
                    2,
                    series(&s, |x| (x.t, x.actuator_torque[j])),
                ),
            ],
        )?;
    }
    root.present()?;
    Ok(())
}

/// Writes every plot into `dir` (created if missing); returns the file names.
pub fn write_all(r: &WalkingRun, cfg: &WalkingConfig, dir: &Path) -> PlotResult<Vec<String>> {
    std::fs::create_dir_all(dir)?;
    let files = [
        "fig11_states.svg",
        "fig12_residuals.svg",
        "fig13_state_errors.svg",
        "fig14_error_autocorrelation.svg",
        "fig16_tracking.svg",
        "fig17_masses.svg",
        "supervisor.svg",
        "torques.svg",
    ];
    fig11(r, cfg, &dir.join(files[0]))?;
    fig12(r, cfg, &dir.join(files[1]))?;
    fig13(r, cfg, &dir.join(files[2]))?;
    fig14(r, cfg, &dir.join(files[3]))?;
    fig16(r, cfg, &dir.join(files[4]))?;
    fig17(r, cfg, &dir.join(files[5]))?;
    supervisor(r, cfg, &dir.join(files[6]))?;
    torques(r, cfg, &dir.join(files[7]))?;
    Ok(files.iter().map(|f| f.to_string()).collect())
}
