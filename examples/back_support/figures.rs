//! The figures of the study as JSON.

use serde_json::{Value, json};

use bgc_runtime::analysis::StabilityMargins;
use bgc_workspace::back_support::Study;
use bgc_workspace::back_support::lqr::{
    LqrDesign, PAPER_DOUBLE_INTEGRAL_GAIN, PAPER_SINGLE_INTEGRAL_GAIN, PAPER_STATE_GAIN,
};
use bgc_workspace::back_support::observer::normalised_direction;

/// A gain factor in dB (`None` for a missing, infinite or non-positive one).
pub fn db(gain: Option<f64>) -> Option<f64> {
    gain.filter(|g| g.is_finite() && *g > 0.0)
        .map(|g| 20.0 * g.log10())
}

fn lqr_json(d: &LqrDesign) -> Value {
    let r = d.r;
    json!({ "Q": d.q, "R": r, "K": d.k })
}

fn margins_json(m: &StabilityMargins) -> Value {
    json!({
        "gain_margin_db": db(m.gain_increase_margin),
        "gain_reduction_margin_db": db(m.gain_reduction_margin),
        "gain_increase_unbounded": m.gain_increase_margin.is_none(),
        "phase_margin_deg": m.phase_margin,
        "phase_crossover_rad_s": m.phase_crossover,
        "gain_crossover_rad_s": m.gain_crossover,
        "delay_margin_s": m.delay_margin,
        "stability_margin": m.stability_margin,
    })
}

/// The design tuned by loop transfer recovery: the chosen weight, its margins, scenario and the sweep.
fn recovery_json(s: &Study) -> Value {
    let r = &s.recovery;
    let sweep: Vec<Value> = r
        .sweep
        .iter()
        .map(|p| {
            json!({
                "q": p.q,
                "gain_margin_db": db(p.margins.gain_increase_margin),
                "phase_margin_deg": p.margins.phase_margin,
                "delay_margin_s": p.margins.delay_margin,
            })
        })
        .collect();
    json!({
        "q": r.q,
        "observer_noise_std": [r.observer.noise.motor_torque, r.observer.noise.trunk_velocity,
                               r.observer.noise.motor_velocity, r.observer.noise.sensor_torque],
        "continuous_gain": r.observer.continuous.l.iter().collect::<Vec<_>>(),
        "discrete_filter_gain": r.observer.discrete.filter_gain.iter().collect::<Vec<_>>(),
        "margins": margins_json(&r.robustness.observer_loop),
        "sampled_margins": margins_json(&r.robustness.sampled_loop),
        "peak_tau_m": r.scenario.peak_motor_torque,
        "tau_h_estimation_mse": r.scenario.human_torque_mse,
        "omega_m_estimation_mse": r.scenario.motor_velocity_mse,
        "omega_m_estimation_mse_true": r.scenario.motor_velocity_mse_true,
        "sweep": sweep,
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
        "recovery": recovery_json(s),
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
