//! The summary table, the JSON figures and the plots of the study.

use std::path::Path;

use serde_json::{Value, json};

use bgc_runtime::analysis::{StabilityMargins, siso_response};
use bgc_workspace::back_support::Study;
use bgc_workspace::back_support::lqr::{
    LqrDesign, PAPER_DOUBLE_INTEGRAL_GAIN, PAPER_SINGLE_INTEGRAL_GAIN, PAPER_STATE_GAIN,
};
use bgc_workspace::back_support::observer::{NOISE_BOUNDS, normalised_direction};

use crate::plots::{self, BLUE_, GREEN_, GREY, ORANGE, Panel, RED_, Series};

fn db(gain: Option<f64>) -> Option<f64> {
    gain.filter(|g| g.is_finite() && *g > 0.0)
        .map(|g| 20.0 * g.log10())
}

fn four(v: Option<f64>) -> String {
    v.map_or("n/a".to_string(), |g| format!("{g:.4}"))
}

fn gains(k: &[f64]) -> String {
    let v: Vec<String> = k
        .iter()
        .map(|g| {
            if g.abs() >= 0.01 {
                format!("{g:.4}")
            } else {
                format!("{g:.2e}")
            }
        })
        .collect();
    format!("[{}]", v.join(" "))
}

fn row(what: &str, ours: String, paper: &str) {
    println!("  {what:<44} {ours:<34} {paper}");
}

fn opt(v: Option<f64>, unit: &str) -> String {
    v.map_or("none".to_string(), |x| format!("{x:.2} {unit}"))
}

fn margins_rows(m: &StabilityMargins, paper: bool) {
    let p = |s: &'static str| if paper { s } else { "" };
    row(
        "gain margin (increase)",
        opt(db(m.gain_increase_margin), "dB"),
        p("8.46 dB"),
    );
    row(
        "gain-reduction margin",
        opt(db(m.gain_reduction_margin), "dB"),
        "",
    );
    row(
        "phase margin",
        format!(
            "{:.1}° at {:.1} rad/s",
            m.phase_margin,
            m.gain_crossover.unwrap_or(f64::NAN)
        ),
        p("59°"),
    );
    row(
        "delay margin",
        format!("{:.5} s", m.delay_margin),
        p("0.007 s"),
    );
    row("smallest |1 + L|", format!("{:.3}", m.stability_margin), "");
}

/// Prints the summary table.
pub fn print_table(s: &Study) {
    let mc = &s.model_check;
    println!("Back-support exoskeleton (Shojaei Barjuei et al., Designs 2020, 4, 53)");
    println!("  {:<44} {:<34} paper", "", "bgc");
    println!("1. Model check, Eq. 3 vs Eq. 1 (τ_m = 0.1 N m, θ̇_h = 0.05 rad/s after 0.1 s, 1 s)");
    row(
        "max |Δ sensor torque|, Eq. 1 with b_g/r_g²",
        format!("{:.2e} N m", mc.max_torque_difference),
        "0.09 N m (20-sim vs MATLAB)",
    );
    row(
        "max |Δ motor velocity|, Eq. 1 with b_g/r_g²",
        format!("{:.2e} rad/s", mc.max_velocity_difference),
        "0.07 rad/s",
    );
    row(
        "max |Δ sensor torque|, Eq. 1 with b_g/r_g",
        format!("{:.2} N m", mc.max_torque_difference_as_printed),
        "(Eq. 1 as printed)",
    );
    row(
        "max |Δ motor velocity|, Eq. 1 with b_g/r_g",
        format!("{:.2} rad/s", mc.max_velocity_difference_as_printed),
        "",
    );
    row(
        "solver (BDF) rtol / atol",
        format!("{:e} / {:e}", mc.solver.rtol, mc.solver.atol),
        "",
    );
    println!("2. LQR on (A₁, B_m, C_b), u = −K [x; z; ∫z], ż = τ_ref − y_b");
    let l = &s.lqr;
    row(
        "single, Eq. 14 (q_z = 5e13): K_x",
        gains(l.single.state_gain()),
        "F'_ix = [1.00 0.03 0.64 0 0.02 0]",
    );
    row(
        "single, Eq. 14: K_z",
        four(l.single.outer_integral_gain()),
        &format!("F'_iz = {PAPER_SINGLE_INTEGRAL_GAIN}"),
    );
    row(
        "single, q_z = 1e13: K_x",
        gains(l.single_reproducing.state_gain()),
        "Eq. 16 reproduced",
    );
    row(
        "single, q_z = 1e13: K_z",
        four(l.single_reproducing.outer_integral_gain()),
        "−3.16 reproduced",
    );
    row(
        "double, Eq. 15: K_x",
        gains(l.double.state_gain()),
        "(Eq. 13 reuses F'_ix)",
    );
    row(
        "double, Eq. 15: K_z, K_∫z",
        format!("{:.4}, {:.4}", l.double.k[6], l.double.k[7]),
        &format!("F_iz = {PAPER_DOUBLE_INTEGRAL_GAIN}"),
    );
    row(
        "double, q_z = 1e13: K_x",
        gains(l.double_reproducing.state_gain()),
        "",
    );
    row(
        "double, q_z = 1e13: K_z, K_∫z",
        gains(l.double_reproducing.k.get(6..).unwrap_or(&[])),
        "",
    );
    row(
        "√(q_z/r): single Eq. 14, Eq. 15 outer",
        format!(
            "{}, {}",
            four(l.single.outer_gain_from_weights()),
            four(l.double.outer_gain_from_weights())
        ),
        "3.16, 70.71 printed",
    );
    println!("3. Observer from y_v, y_t (noise bounds {NOISE_BOUNDS:?} read as 3σ)");
    for c in &s.seven_state {
        let mode = c.unobservable.first().map_or("none".to_string(), |m| {
            let d: Vec<String> = normalised_direction(m)
                .iter()
                .map(|z| format!("{:.5}", z.re))
                .collect();
            format!("λ = {:.1e}, v = [{}]", m.eigenvalue.re, d.join(" "))
        });
        row(
            &format!("7-state (A', {}) detectable", c.name),
            format!("{}", c.detectable),
            "paper: observable",
        );
        row("  unobservable mode (PBH)", mode, "");
        row(
            "  lqe (Eq. 9)",
            c.lqe.as_ref().map_or_else(
                |_| "refused: not detectable".to_string(),
                |_| "solved".to_string(),
            ),
            "",
        );
    }
    let o = &s.observer;
    row(
        "6-state relative model observable",
        format!("{}", o.observable),
        "",
    );
    let slowest = o
        .continuous
        .observer_eigenvalues
        .iter()
        .map(|e| e.re)
        .fold(f64::NEG_INFINITY, f64::max);
    let fastest = o
        .continuous
        .observer_eigenvalues
        .iter()
        .map(|e| e.re)
        .fold(f64::INFINITY, f64::min);
    row(
        "continuous observer poles, Re range",
        format!("{fastest:.3e} … {slowest:.3e} 1/s"),
        "",
    );
    let rho = o
        .discrete
        .observer_eigenvalues
        .iter()
        .map(|e| e.norm())
        .fold(0.0, f64::max);
    row(
        "discrete KF at 1 kHz, spectral radius",
        format!("{rho:.5}"),
        "",
    );
    let r = &s.scenario;
    println!("4. Lifting scenario (θ̇_h = 0.1 rad/s, τ_ref = 10 N m for 0.1–0.6 s, 1 kHz, noise)");
    row(
        "peak |τ_m|",
        format!("{:.3} N m at {:.3} s", r.peak_motor_torque, r.peak_time),
        "within ±0.56 N m",
    );
    let q = &s.scenario_reproducing;
    row(
        "  same with q_z = 1e13 in Eq. 15",
        format!("{:.3} N m at {:.3} s", q.peak_motor_torque, q.peak_time),
        "",
    );
    row(
        "MSE of estimated human torque",
        format!("{:.3e} N² m²", r.human_torque_mse),
        "≈ 1e-4",
    );
    row(
        "  predicted by the filter (C_b Z C_bᵀ)",
        format!("{:.3e} N² m²", s.observer.predicted_human_torque_variance),
        "",
    );
    row(
        "MSE of motor velocity (est. vs measured)",
        format!("{:.3e} rad²/s²", r.motor_velocity_mse),
        "≈ 3e-6",
    );
    row(
        "MSE of motor velocity (est. vs true)",
        format!("{:.3e} rad²/s²", r.motor_velocity_mse_true),
        "",
    );
    row(
        "  predicted by the filter (Z₂₂)",
        format!(
            "{:.3e} rad²/s²",
            s.observer.predicted_motor_velocity_variance
        ),
        "",
    );
    let rb = &s.robustness;
    println!(
        "5. Loop broken at the plant input, double-integral LQR + continuous observer (Eq. 9)"
    );
    margins_rows(&rb.observer_loop, true);
    println!("   sampled loop at 1 kHz: the scenario's Kalman filter + LQR, zero-order-hold plant");
    margins_rows(&rb.sampled_loop, false);
    println!("   same loop with the full state measured (LQR alone)");
    margins_rows(&rb.state_feedback_loop, false);
    println!("   trunk velocity → estimated human torque (closed loop)");
    row(
        "DC gain",
        format!("{:.1e} N m s/rad", rb.disturbance_dc_gain),
        "",
    );
    row(
        "peak gain",
        format!(
            "{:.1} N m s/rad at {:.2} Hz",
            rb.disturbance_peak_gain, rb.disturbance_peak_frequency_hz
        ),
        "worst 4–6.2 Hz",
    );
    row(
        "rejection bandwidth (|T_cl/T_ol| = −3 dB)",
        opt(rb.rejection_bandwidth_hz, "Hz"),
        "52 Hz (−3 dB of DC)",
    );
}

fn lqr_json(d: &LqrDesign) -> Value {
    let r = d.r;
    json!({ "Q": d.q, "R": r, "K": d.k })
}

fn margins_json(m: &StabilityMargins) -> Value {
    json!({
        "gain_margin_db": db(m.gain_increase_margin),
        "gain_reduction_margin_db": db(m.gain_reduction_margin),
        "phase_margin_deg": m.phase_margin,
        "phase_crossover_rad_s": m.phase_crossover,
        "gain_crossover_rad_s": m.gain_crossover,
        "delay_margin_s": m.delay_margin,
        "stability_margin": m.stability_margin,
    })
}

/// The figures as JSON.
pub fn json(s: &Study) -> Value {
    let mc = &s.model_check;
    let r = &s.scenario;
    let rb = &s.robustness;
    let seven: Vec<Value> = s
        .seven_state
        .iter()
        .map(|c| {
            json!({
                "measurements": c.name,
                "detectable": c.detectable,
                "unobservable_modes": c.unobservable.iter().map(|m| json!({
                    "eigenvalue": [m.eigenvalue.re, m.eigenvalue.im],
                    "direction_theta_m_1": normalised_direction(m).iter().map(|z| z.re).collect::<Vec<_>>(),
                })).collect::<Vec<_>>(),
                "lqe_error": c.lqe.as_ref().err().map(|e| e.to_string()),
            })
        })
        .collect();
    json!({
        "model_check": {
            "max_sensor_torque_difference": mc.max_torque_difference,
            "max_motor_velocity_difference": mc.max_velocity_difference,
            "max_sensor_torque_difference_bg_over_rg": mc.max_torque_difference_as_printed,
            "max_motor_velocity_difference_bg_over_rg": mc.max_velocity_difference_as_printed,
        },
        "lqr_single": lqr_json(&s.lqr.single),
        "lqr_single_reproducing_eq16": lqr_json(&s.lqr.single_reproducing),
        "lqr_double": lqr_json(&s.lqr.double),
        "lqr_double_qz_1e13": lqr_json(&s.lqr.double_reproducing),
        "paper_gains": {
            "F_ix": PAPER_STATE_GAIN,
            "F_iz_single": PAPER_SINGLE_INTEGRAL_GAIN,
            "F_iz_double": PAPER_DOUBLE_INTEGRAL_GAIN,
        },
        "observer": {
            "seven_state": seven,
            "six_state_observable": s.observer.observable,
            "continuous_gain": s.observer.continuous.l.iter().collect::<Vec<_>>(),
            "discrete_filter_gain": s.observer.discrete.filter_gain.iter().collect::<Vec<_>>(),
            "noise_std": [s.observer.noise.motor_torque, s.observer.noise.trunk_velocity,
                          s.observer.noise.motor_velocity, s.observer.noise.sensor_torque],
        },
        "margins": margins_json(&rb.observer_loop),
        "sampled_margins": margins_json(&rb.sampled_loop),
        "state_feedback_margins": margins_json(&rb.state_feedback_loop),
        "disturbance": {
            "dc_gain": rb.disturbance_dc_gain,
            "peak_gain": rb.disturbance_peak_gain,
            "peak_frequency_hz": rb.disturbance_peak_frequency_hz,
            "rejection_bandwidth_hz": rb.rejection_bandwidth_hz,
        },
        "peak_tau_m": r.peak_motor_torque,
        "peak_tau_m_time_s": r.peak_time,
        "peak_tau_m_qz_1e13": s.scenario_reproducing.peak_motor_torque,
        "tau_h_estimation_mse": r.human_torque_mse,
        "omega_m_estimation_mse": r.motor_velocity_mse,
        "omega_m_estimation_mse_true": r.motor_velocity_mse_true,
    })
}

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
        let plant = column(&mc.plant, index);
        let eq1 = column(&mc.block_diagram, index);
        let printed = column(&mc.block_diagram_as_printed, index);
        let diff = difference(&plant, &eq1);
        let diff_label = format!("Eq. 3 − Eq. 1 ({quantity})");
        let diff_unit = unit.replace('(', "difference (");
        plots::draw(
            &dir.join(file),
            &[
                panel(
                    title,
                    unit,
                    vec![
                        line("plant, Eq. 3 (bond graph)", t, &plant, BLUE_),
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
    Ok(count)
}
