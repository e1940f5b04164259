//! The summary table of the study on stdout, beside the paper's figures.

use bgc_runtime::analysis::StabilityMargins;
use bgc_workspace::back_support::Study;
use bgc_workspace::back_support::lqr::{PAPER_DOUBLE_INTEGRAL_GAIN, PAPER_SINGLE_INTEGRAL_GAIN};
use bgc_workspace::back_support::observer::{NOISE_BOUNDS, normalised_direction};

use crate::figures::db;

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
    println!("  {what:<52} {ours:<34} {paper}");
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
    println!("  {:<52} {:<34} paper", "", "bgc");
    println!(
        "1. Model check, generated bond-graph model (back_support.bg) vs Eq. 1 (τ_m = 0.1 N m, θ̇_h = 0.05 rad/s \
         after 0.1 s, 1 s)"
    );
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
        four(l.double_reproducing.k.get(6).copied())
            + ", "
            + &four(l.double_reproducing.k.get(7).copied()),
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
            format!(
                "λ = {:.2}{:+.2}i, v = [{}]",
                m.eigenvalue.re,
                m.eigenvalue.im,
                d.join(" ")
            )
        });
        row(
            &format!("7-state, C' = {}: detectable", c.name),
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
