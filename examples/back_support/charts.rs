//! The plots of the study: analogs of the paper's Figs. 10–11 (model check), 14 (Nyquist), 15 (disturbance
//! path) and 16–20 (lifting scenario), each with a note saying which scenario and design it shows.

use std::path::Path;

use bgc_runtime::analysis::{bode, siso_response};
use bgc_runtime::statespace::StateSpace;
use bgc_workspace::back_support::Study;

use plotters::style::BLACK;

use crate::plots::{self, Arrow, BLUE_, GREEN_, GREY, Marker, ORANGE, Panel, RED_, Series};

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

type PlotResult<T> = Result<T, Box<dyn std::error::Error>>;

const MODEL_CHECK_NOTE: &str = "Model check (Sec. 5.1): open loop, τ_m = 0.1 N m from 0 s, trunk velocity 0.05 rad/s from 0.1 s; BDF solver.";
const LIFTING_NOTE: &str = "Lifting (Sec. 5.2): trunk at 0.1 rad/s from 0 s, τ_ref = 10 N m for 0.1–0.6 s; \
                            sampled LQR of Eq. 15 at 1 kHz, noise of Sec. 4.";

fn time_panel<'a>(title: &'a str, y_label: &'a str, series: Vec<Series<'a>>) -> Panel<'a> {
    Panel::new(title, "time (s)", y_label, series)
}

/// The recovered design's label, e.g. "LTR observer (q = 1e-8)".
fn recovered_label(s: &Study) -> String {
    format!("LTR observer (q = {:.0e})", s.recovery.q)
}

/// Writes the SVG plots; returns how many.
pub fn plots(s: &Study, dir: &Path) -> PlotResult<usize> {
    model_check(s, dir)?;
    lifting(s, dir)?;
    disturbance_bode(s, dir)?;
    nyquist(s, dir)?;
    recovery_sweep(s, dir)?;
    Ok(10)
}

/// Figs. 10–11: the generated model against Eq. 1, and their difference.
fn model_check(s: &Study, dir: &Path) -> PlotResult<()> {
    let mc = &s.model_check;
    let t = &mc.times;
    for (index, file, title, unit, quantity) in [
        (
            1,
            "fig10_sensor_torque.svg",
            "Fig. 10 analog: torque on the torque sensor, model check",
            "torque (N m)",
            "sensor torque",
        ),
        (
            0,
            "fig11_motor_velocity.svg",
            "Fig. 11 analog: motor velocity, model check",
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
                time_panel(
                    title,
                    unit,
                    vec![
                        line("bond graph (back_support.bg)", t, &bond_graph, BLUE_),
                        dashed("Eq. 1 with b_g/r_g²", t, &eq1, ORANGE),
                        line("Eq. 1 with b_g/r_g as printed", t, &printed, GREY),
                    ],
                ),
                time_panel(
                    "bond graph − Eq. 1 (b_g/r_g²): at solver tolerance",
                    &diff_unit,
                    vec![line(&diff_label, t, &diff, RED_)],
                ),
            ],
            &[MODEL_CHECK_NOTE],
        )?;
    }
    Ok(())
}

/// The intervals where `|y| > limit`: `(entry, exit, peak)`, the crossings interpolated between samples.
fn excursions(t: &[f64], y: &[f64], limit: f64) -> Vec<(f64, f64, f64)> {
    let cross = |i: usize, level: f64| {
        let (y0, y1) = (y[i - 1], y[i]);
        t[i - 1] + (level - y0) / (y1 - y0) * (t[i] - t[i - 1])
    };
    let mut out = Vec::new();
    let mut open: Option<(f64, f64)> = None;
    for i in 0..y.len().min(t.len()) {
        let beyond = y[i].abs() > limit;
        let level = limit.copysign(y[i]);
        match (&mut open, beyond) {
            (None, true) => open = Some((if i > 0 { cross(i, level) } else { t[i] }, y[i])),
            (Some((_, peak)), true) if y[i].abs() > peak.abs() => *peak = y[i],
            (Some((start, peak)), false) => {
                out.push((*start, cross(i, limit.copysign(*peak)), *peak));
                open = None;
            }
            _ => {}
        }
    }
    if let Some((start, peak)) = open {
        out.push((start, t.last().copied().unwrap_or(start), peak));
    }
    out
}

/// Figs. 16–20: the lifting scenario with the observer of Eq. 9, and the recovered observer's errors and torque.
fn lifting(s: &Study, dir: &Path) -> PlotResult<()> {
    let r = &s.scenario;
    let rr = &s.recovery.scenario;
    let t = &r.times;
    let tau_err = difference(&r.human_torque, &r.human_torque_estimate);
    let tau_err_ltr = difference(&rr.human_torque, &rr.human_torque_estimate);
    let vel_err = difference(&r.motor_velocity_measured, &r.motor_velocity_estimate);
    let vel_err_ltr = difference(&rr.motor_velocity_measured, &rr.motor_velocity_estimate);
    let ltr = recovered_label(s);
    let limit_hi = vec![0.56; t.len()];
    let limit_lo = vec![-0.56; t.len()];
    let mut fig20 = time_panel(
        "Fig. 20 analog: motor torque against the ±0.56 N m limit",
        "torque (N m)",
        vec![
            line("τ_m, Eq. 9 observer", t, &r.motor_torque, BLUE_),
            dashed(&ltr, &rr.times, &rr.motor_torque, GREEN_),
            dashed("±0.56 N m limit", t, &limit_hi, GREY),
            dashed("", t, &limit_lo, GREY),
        ],
    );
    for (start, end, peak) in excursions(t, &r.motor_torque, 0.56) {
        fig20.markers.push(Marker {
            at: (start, 0.56_f64.copysign(peak)),
            text: format!("beyond ±0.56 N m {start:.3}–{end:.3} s, peak {peak:+.3} N m"),
            color: RED_,
        });
    }
    let figures: Vec<(&str, Panel<'_>)> = vec![
        (
            "fig16_human_torque.svg",
            time_panel(
                "Fig. 16 analog: torque on the human body, actual and estimated",
                "torque (N m)",
                vec![
                    line("actual y_b", t, &r.human_torque, BLUE_),
                    dashed(
                        "estimated ŷ_b (Eq. 9 observer)",
                        t,
                        &r.human_torque_estimate,
                        ORANGE,
                    ),
                    line("reference τ_ref", t, &r.reference, GREY),
                ],
            ),
        ),
        (
            "fig17_human_torque_error.svg",
            time_panel(
                "Fig. 17 analog: estimation error of the torque on the body",
                "y_b − ŷ_b (N m)",
                vec![
                    line("Eq. 9 observer", t, &tau_err, RED_),
                    line(&ltr, &rr.times, &tau_err_ltr, BLUE_),
                ],
            ),
        ),
        (
            "fig18_motor_velocity.svg",
            time_panel(
                "Fig. 18 analog: motor velocity, measured and estimated",
                "velocity (rad/s)",
                vec![
                    line("measured", t, &r.motor_velocity_measured, BLUE_),
                    dashed(
                        "estimated (Eq. 9 observer)",
                        t,
                        &r.motor_velocity_estimate,
                        ORANGE,
                    ),
                ],
            ),
        ),
        (
            "fig19_motor_velocity_error.svg",
            time_panel(
                "Fig. 19 analog: motor velocity, measured − estimated",
                "error (rad/s)",
                vec![
                    line("Eq. 9 observer", t, &vel_err, RED_),
                    line(&ltr, &rr.times, &vel_err_ltr, BLUE_),
                ],
            ),
        ),
        ("fig20_motor_torque.svg", fig20),
    ];
    for (file, p) in figures {
        plots::draw(&dir.join(file), &[p], &[LIFTING_NOTE])?;
    }
    Ok(())
}

/// Fig. 15: gain and phase from the trunk velocity to the estimated torque on the body.
fn disturbance_bode(s: &Study, dir: &Path) -> PlotResult<()> {
    let rb = &s.robustness;
    let hz: Vec<f64> = (0..=600)
        .map(|i| 10f64.powf(-2.0 + 5.0 * i as f64 / 600.0))
        .collect();
    let w: Vec<f64> = hz.iter().map(|f| 2.0 * std::f64::consts::PI * f).collect();
    let closed = bode(&rb.disturbance_path, 0, 0, &w)?;
    let open = bode(&rb.open_loop_disturbance_path, 0, 0, &w)?;
    let mut gain = Panel::new(
        "Fig. 15 analog: trunk velocity → estimated torque on the body, gain",
        "frequency (Hz)",
        "gain (dB re 1 N m s/rad)",
        vec![
            line(
                "closed loop (LQR + Eq. 9 observer)",
                &hz,
                &closed.magnitude_db,
                BLUE_,
            ),
            dashed("no control (τ_m = 0)", &hz, &open.magnitude_db, GREEN_),
        ],
    );
    gain.log_x = true;
    let mut phase = Panel::new(
        "phase",
        "frequency (Hz)",
        "phase (°)",
        vec![
            line(
                "closed loop (LQR + Eq. 9 observer)",
                &hz,
                &closed.phase_deg,
                BLUE_,
            ),
            dashed("no control (τ_m = 0)", &hz, &open.phase_deg, GREEN_),
        ],
    );
    phase.log_x = true;
    plots::draw(
        &dir.join("fig15_disturbance_bode.svg"),
        &[gain, phase],
        &[
            "Closed loop of Sec. 5.2 (double-integral LQR of Eq. 15, continuous observer of Eq. 9), τ_ref = 0; \
           phase unwrapped.",
        ],
    )
}

/// The window of the Nyquist plot: Re from, Re to, Im from, Im to.
const NYQUIST_WINDOW: (f64, f64, f64, f64) = (-3.4, 2.0, -2.0, 2.0);

/// Pieces of the Nyquist curve of `sys` inside [`NYQUIST_WINDOW`], by increasing ω (a piece ends where the
/// curve leaves the window, so that no line jumps across it).
fn nyquist_pieces(sys: &StateSpace) -> PlotResult<Vec<(Vec<f64>, Vec<f64>)>> {
    let (x0, x1, y0, y1) = NYQUIST_WINDOW;
    let mut runs: Vec<(Vec<f64>, Vec<f64>)> = vec![(Vec::new(), Vec::new())];
    let points = 4000;
    for i in 0..=points {
        let w = 10f64.powf(-1.0 + 6.0 * i as f64 / points as f64);
        let l = siso_response(sys, w)?;
        match runs.last_mut() {
            Some(run) if (x0..=x1).contains(&l.re) && (y0..=y1).contains(&l.im) => {
                run.0.push(l.re);
                run.1.push(l.im);
            }
            Some(run) if !run.0.is_empty() => runs.push((Vec::new(), Vec::new())),
            _ => {}
        }
    }
    runs.retain(|r| r.0.len() > 1);
    Ok(runs)
}

/// Arrowheads at a third and two thirds of each piece's length, pointing towards increasing ω.
fn direction_arrows(
    pieces: &[(Vec<f64>, Vec<f64>)],
    color: plotters::style::RGBColor,
) -> Vec<Arrow> {
    let mut arrows = Vec::new();
    for (re, im) in pieces {
        let seg: Vec<f64> = re
            .windows(2)
            .zip(im.windows(2))
            .map(|(x, y)| (x[1] - x[0]).hypot(y[1] - y[0]))
            .collect();
        let total: f64 = seg.iter().sum();
        if total < 0.3 {
            continue;
        }
        for fraction in [1.0 / 3.0, 2.0 / 3.0] {
            let mut run = 0.0;
            if let Some(i) = seg.iter().position(|d| {
                run += d;
                run >= fraction * total
            }) {
                arrows.push(Arrow {
                    from: (re[i], im[i]),
                    to: (re[i + 1], im[i + 1]),
                    color,
                });
            }
        }
    }
    arrows
}

/// Fig. 14: the Nyquist curves at the plant input near −1: the observer of Eq. 9, the recovered observer and
/// the LQR alone, with the unit circle.
fn nyquist(s: &Study, dir: &Path) -> PlotResult<()> {
    let eq9 = nyquist_pieces(&s.robustness.loop_at_input)?;
    let ltr = nyquist_pieces(&s.recovery.robustness.loop_at_input)?;
    let lqr = nyquist_pieces(&s.robustness.state_feedback_loop_transfer)?;
    let circle = 360;
    let angle = |k: usize| 2.0 * std::f64::consts::PI * k as f64 / circle as f64;
    let cx: Vec<f64> = (0..=circle).map(|k| angle(k).cos()).collect();
    let cy: Vec<f64> = (0..=circle).map(|k| angle(k).sin()).collect();
    let ltr_label = recovered_label(s);
    let mut series: Vec<Series<'_>> = Vec::new();
    for (pieces, label, color, is_dashed) in [
        (&eq9, "LQR + Eq. 9 observer", RED_, false),
        (&ltr, ltr_label.as_str(), BLUE_, false),
        (&lqr, "LQR alone (state measured)", GREEN_, true),
    ] {
        for (i, (re, im)) in pieces.iter().enumerate() {
            let label = if i == 0 { label } else { "" };
            series.push(if is_dashed {
                dashed(label, re, im, color)
            } else {
                line(label, re, im, color)
            });
        }
    }
    series.push(dashed("unit circle", &cx, &cy, GREY));
    let mut panel = Panel::new(
        "Fig. 14 analog: Nyquist curves at the plant input near −1 (ω > 0)",
        "Re L(jω)",
        "Im L(jω)",
        series,
    );
    panel.equal_aspect = true;
    panel.height = 640;
    panel.markers.push(Marker {
        at: (-1.0, 0.0),
        text: "−1".to_string(),
        color: BLACK,
    });
    panel.arrows = [
        direction_arrows(&eq9, RED_),
        direction_arrows(&ltr, BLUE_),
        direction_arrows(&lqr, GREEN_),
    ]
    .into_iter()
    .flatten()
    .collect();
    plots::draw(
        &dir.join("fig14_nyquist.svg"),
        &[panel],
        &[
            "Zoom on −3.4 ≤ Re L ≤ 2, |Im L| ≤ 2 around −1: the double integrator sends L(jω) to infinity as ω → 0",
            "(in from the lower left); resonances take the curves out of the window and back. Arrows: increasing ω.",
            "Loop broken at the motor torque input (Fig. 12), double-integral LQR of Eq. 15, continuous observers.",
        ],
    )
}

/// The margins of the observer-based loop against the recovery weight, with the requirements and the LQR's own.
fn recovery_sweep(s: &Study, dir: &Path) -> PlotResult<()> {
    let points: Vec<_> = s.recovery.sweep.iter().filter(|p| p.q > 0.0).collect();
    let q: Vec<f64> = points.iter().map(|p| p.q).collect();
    let gm: Vec<f64> = points
        .iter()
        .map(|p| crate::figures::db(p.margins.gain_increase_margin).unwrap_or(f64::NAN))
        .collect();
    let reduction: Vec<f64> = points
        .iter()
        .map(|p| crate::figures::db(p.margins.gain_reduction_margin).unwrap_or(f64::NAN))
        .collect();
    let pm: Vec<f64> = points.iter().map(|p| p.margins.phase_margin).collect();
    let ends = [
        q.first().copied().unwrap_or(1e-12),
        q.last().copied().unwrap_or(1.0),
    ];
    let lqr = &s.robustness.state_feedback_loop;
    let (gm_req, gm_req_low, pm_req) = ([6.0, 6.0], [-6.0, -6.0], [45.0, 45.0]);
    let pm_lqr = [lqr.phase_margin, lqr.phase_margin];
    let chosen = s.recovery.q;
    let rec = &s.recovery.robustness.observer_loop;
    let mut gain = Panel::new(
        "Loop transfer recovery: gain margin at the plant input against q",
        "fictitious motor-torque noise intensity q (N² m² s)",
        "gain margin (dB)",
        vec![
            line("gain increase margin", &q, &gm, BLUE_),
            line("gain reduction margin", &q, &reduction, ORANGE),
            dashed("required ±6 dB", &ends, &gm_req, GREY),
            dashed("", &ends, &gm_req_low, GREY),
        ],
    );
    gain.log_x = true;
    gain.markers.push(Marker {
        at: (chosen, 6.0),
        text: match crate::figures::db(rec.gain_increase_margin) {
            Some(g) => format!("chosen q = {chosen:.0e}: {g:.1} dB"),
            None => format!("chosen q = {chosen:.0e}: no phase crossover, gain unbounded"),
        },
        color: RED_,
    });
    let mut phase = Panel::new(
        "phase margin against q",
        "fictitious motor-torque noise intensity q (N² m² s)",
        "phase margin (°)",
        vec![
            line("LQR + observer with q B_m B_mᵀ", &q, &pm, BLUE_),
            dashed("required 45°", &ends, &pm_req, GREY),
            dashed("LQR alone (state measured)", &ends, &pm_lqr, GREEN_),
        ],
    );
    phase.log_x = true;
    phase.markers.push(Marker {
        at: (chosen, rec.phase_margin),
        text: format!("chosen: {:.1}°", rec.phase_margin),
        color: RED_,
    });
    plots::draw(
        &dir.join("ltr_margins.svg"),
        &[gain, phase],
        &[
            "Continuous observer of Eq. 9 with fictitious noise q at the motor torque (real intensity 1.1e-12), \
             double-integral LQR of Eq. 15.",
            "A missing point: no such crossing (the gain may change without limit that way).",
            "The chosen q is the smallest whose continuous and 1 kHz loops meet 6 dB / 45° with the estimation \
             errors within the paper's.",
        ],
    )
}
