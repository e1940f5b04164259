//! The plots of the study: analogs of the paper's Figs. 10–11 (model check), 15 (disturbance path) and
//! 16–20 (lifting scenario).

use std::path::Path;

use bgc_runtime::analysis::siso_response;
use bgc_workspace::back_support::Study;

use crate::plots::{self, BLUE_, GREEN_, GREY, ORANGE, Panel, RED_, Series};

fn difference(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x - y).collect()
}

fn column(rows: &[[f64; 3]], i: usize) -> Vec<f64> {
    rows.iter().map(|r| r[i]).collect()
}

fn line<'a>(
    label: &'a str,
    x: &'a [f64],
    y: &'a [f64],
    color: plotters::style::RGBColor,
) -> Series<'a> {
    Series {
        label,
        x,
        y,
        color,
        dashed: false,
    }
}

fn dashed<'a>(
    label: &'a str,
    x: &'a [f64],
    y: &'a [f64],
    color: plotters::style::RGBColor,
) -> Series<'a> {
    Series {
        label,
        x,
        y,
        color,
        dashed: true,
    }
}

fn panel<'a>(title: &'a str, y_label: &'a str, series: Vec<Series<'a>>) -> Panel<'a> {
    Panel {
        title,
        x_label: "time (s)",
        y_label,
        series,
        log_x: false,
    }
}

/// Writes the SVG plots; returns how many.
pub fn plots(s: &Study, dir: &Path) -> Result<usize, Box<dyn std::error::Error>> {
    let mc = &s.model_check;
    let t = &mc.times;
    let mut count = 0;
    for (index, file, title, unit, quantity) in [
        (
            1,
            "fig10_sensor_torque.svg",
            "Fig. 10 analog: torque on the torque sensor",
            "torque (N m)",
            "sensor torque",
        ),
        (
            0,
            "fig11_motor_velocity.svg",
            "Fig. 11 analog: motor velocity",
            "velocity (rad/s)",
            "motor velocity",
        ),
    ] {
        let bond_graph = column(&mc.bond_graph, index);
        let eq1 = column(&mc.block_diagram, index);
        let printed = column(&mc.block_diagram_as_printed, index);
        let diff = difference(&bond_graph, &eq1);
        let diff_label = format!("bond graph − Eq. 1 ({quantity})");
        let diff_unit = unit.replace('(', "difference (");
        plots::draw(
            &dir.join(file),
            &[
                panel(
                    title,
                    unit,
                    vec![
                        line(
                            "bond graph, generated from back_support.bg",
                            t,
                            &bond_graph,
                            BLUE_,
                        ),
                        dashed("block diagram, Eq. 1 with b_g/r_g²", t, &eq1, ORANGE),
                        line("Eq. 1 with b_g/r_g as printed", t, &printed, GREY),
                    ],
                ),
                panel(
                    "difference at solver tolerance",
                    &diff_unit,
                    vec![line(&diff_label, t, &diff, RED_)],
                ),
            ],
        )?;
        count += 1;
    }
    let r = &s.scenario;
    let t = &r.times;
    let tau_err = difference(&r.human_torque, &r.human_torque_estimate);
    let vel_err = difference(&r.motor_velocity_measured, &r.motor_velocity_estimate);
    let limit_hi = vec![0.56; t.len()];
    let limit_lo = vec![-0.56; t.len()];
    let figures: Vec<(&str, Panel<'_>)> = vec![
        (
            "fig16_human_torque.svg",
            panel(
                "Fig. 16 analog: torque on the human body, actual and estimated",
                "torque (N m)",
                vec![
                    line("actual y_b", t, &r.human_torque, BLUE_),
                    dashed("estimated ŷ_b", t, &r.human_torque_estimate, ORANGE),
                    line("reference τ_ref", t, &r.reference, GREY),
                ],
            ),
        ),
        (
            "fig17_human_torque_error.svg",
            panel(
                "Fig. 17 analog: estimation error of the torque on the body",
                "y_b − ŷ_b (N m)",
                vec![line("y_b − ŷ_b", t, &tau_err, RED_)],
            ),
        ),
        (
            "fig18_motor_velocity.svg",
            panel(
                "Fig. 18 analog: motor velocity, measured and estimated",
                "velocity (rad/s)",
                vec![
                    line("measured", t, &r.motor_velocity_measured, BLUE_),
                    dashed("estimated", t, &r.motor_velocity_estimate, ORANGE),
                ],
            ),
        ),
        (
            "fig19_motor_velocity_error.svg",
            panel(
                "Fig. 19 analog: motor velocity, measured − estimated",
                "error (rad/s)",
                vec![line("measured − estimated", t, &vel_err, RED_)],
            ),
        ),
        (
            "fig20_motor_torque.svg",
            panel(
                "Fig. 20 analog: motor torque",
                "torque (N m)",
                vec![
                    line("τ_m", t, &r.motor_torque, BLUE_),
                    dashed("±0.56 N m limit", t, &limit_hi, GREY),
                    dashed("", t, &limit_lo, GREY),
                ],
            ),
        ),
    ];
    for (file, p) in figures {
        plots::draw(&dir.join(file), &[p])?;
        count += 1;
    }
    // Fig. 15 analog: |T(jω)| from the trunk velocity to the estimated torque, with and without control.
    let rb = &s.robustness;
    let hz: Vec<f64> = (0..=600)
        .map(|i| 10f64.powf(-2.0 + 5.0 * i as f64 / 600.0))
        .collect();
    let mag = |sys: &bgc_runtime::statespace::StateSpace| -> Result<Vec<f64>, Box<dyn std::error::Error>> {
        hz.iter()
            .map(|f| Ok(20.0 * siso_response(sys, 2.0 * std::f64::consts::PI * f)?.norm().log10()))
            .collect()
    };
    let closed = mag(&rb.disturbance_path)?;
    let open = mag(&rb.open_loop_disturbance_path)?;
    plots::draw(
        &dir.join("fig15_disturbance_bode.svg"),
        &[Panel {
            title: "Fig. 15 analog: trunk velocity → estimated torque on the body",
            x_label: "frequency (Hz)",
            y_label: "gain (dB re 1 N m s/rad)",
            series: vec![
                line("closed loop (LQR + observer)", &hz, &closed, BLUE_),
                dashed("no control (τ_m = 0)", &hz, &open, GREEN_),
            ],
            log_x: true,
        }],
    )?;
    count += 1;
    nyquist(s, dir)?;
    count += 1;
    Ok(count)
}

/// Fig. 14 analog: the Nyquist curve of the observer-based loop at the plant input near −1, with the unit
/// circle; points farther than 3 from the origin are left out (the double integrator sends the curve to
/// infinity at low frequency).
fn nyquist(s: &Study, dir: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let rb = &s.robustness;
    // Contiguous runs of points inside the window, drawn as separate curves so that no line jumps across.
    let mut runs: Vec<(Vec<f64>, Vec<f64>)> = vec![(Vec::new(), Vec::new())];
    let points = 4000;
    for i in 0..=points {
        let w = 10f64.powf(-1.0 + 6.0 * i as f64 / points as f64);
        let l = siso_response(&rb.loop_at_input, w)?;
        match runs.last_mut() {
            Some(run) if l.norm() <= 3.0 => {
                run.0.push(l.re);
                run.1.push(l.im);
            }
            Some(run) if !run.0.is_empty() => runs.push((Vec::new(), Vec::new())),
            _ => {}
        }
    }
    let circle = 360;
    let cx: Vec<f64> = (0..=circle)
        .map(|k| (2.0 * std::f64::consts::PI * k as f64 / circle as f64).cos())
        .collect();
    let cy: Vec<f64> = (0..=circle)
        .map(|k| (2.0 * std::f64::consts::PI * k as f64 / circle as f64).sin())
        .collect();
    let (mx, my) = (vec![-1.0, -1.0], vec![-0.05, 0.05]);
    plots::draw(
        &dir.join("fig14_nyquist.svg"),
        &[Panel {
            title: "Fig. 14 analog: Nyquist curve at the plant input near −1 (ω > 0)",
            x_label: "Re L(jω)",
            y_label: "Im L(jω)",
            series: runs
                .iter()
                .enumerate()
                .map(|(i, (re, im))| {
                    let label = if i == 0 { "L(jω), LQR + observer" } else { "" };
                    line(label, re, im, BLUE_)
                })
                .chain([
                    dashed("unit circle", &cx, &cy, GREY),
                    line("critical point −1", &mx, &my, RED_),
                ])
                .collect(),
            log_x: false,
        }],
    )?;
    Ok(())
}
