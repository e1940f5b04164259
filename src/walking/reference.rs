//! The reference `q_d, q̇_d, q̈_d` of Eq. (29) at the control rate, from the dual UKF's estimates at the
//! filter rate.
//!
//! **Prediction at the control rate.** After each filter step the filter's model (Eq. 8 with the current
//! mass estimate) is run forward from the posterior `x̂` one control period at a time, with the same joint
//! torque readings the filter receives, as they arrive: the prediction `x_p(t)` and its acceleration
//! `q̈_p = M⁻¹(u − C q̇ − G − τ_f)` are the filter's time update evaluated between its steps. (Extrapolating
//! `x̂` with a constant acceleration over the 10 ms instead leaves a velocity error of `jerk · τ²/2`, up to
//! 3 °/s at the knee, whose mean the reference then integrates.)
//!
//! **Reference filter.** At every filter step the prediction restarts from the new posterior: it jumps by
//! the filter's correction `K (y − ŷ)`, about half of the 0.9° sensor noise every 10 ms with the paper's
//! `P_v` and `P_n`. A computed-torque controller that followed such a step would need `M(q) · 6 Δq / T²`,
//! hundreds of N m. The reference therefore follows the prediction through a critically damped
//! second-order filter with the prediction's acceleration fed forward,
//!
//! ```text
//! q̈_d = q̈_p + 2 ω_r (q̇_p − q̇_d) + ω_r² (q_p − q_d),
//! ```
//!
//! integrated exactly over each control period with `q̈_d` held (as the zero-order hold holds the
//! controller's torque), so `q_d`, `q̇_d` are continuous and `q̈_d` is their derivative. The prediction's own
//! motion passes without lag (the feedforward), the corrections are spread over about `1/ω_r`.

use super::config::WalkingError;
use super::plant::{LegModel, split};
use bgc_runtime::control::JointReference;
use nalgebra::{Vector3, Vector6};

/// The filter's model run forward at the control rate from its last posterior.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControlRatePredictor {
    /// The filter's model (its current mass estimate).
    pub model: LegModel,
    /// The predicted state `[q, q̇]` at the current control sample (rad, rad/s).
    pub state: Vector6<f64>,
}

impl ControlRatePredictor {
    /// Restarts the prediction from a posterior `x̂` with the filter's current model.
    pub fn restart(&mut self, model: LegModel, posterior: Vector6<f64>) {
        self.model = model;
        self.state = posterior;
    }

    /// The prediction at this sample under the torque reading `u`, then one step of `period` seconds
    /// ahead with `u` held (classical Runge–Kutta, as in the filter's time update). `None`, with the
    /// prediction left where it was, when the model gives no finite acceleration or step.
    pub fn advance(&mut self, u: &Vector3<f64>, period: f64) -> Option<JointReference<3>> {
        let (q, qd) = split(&self.state);
        let (_, qdd) = split(&self.model.derivative(&self.state, u));
        let next = self.model.rk4_step(&self.state, u, period);
        if qdd.iter().chain(next.iter()).any(|v| !v.is_finite()) {
            return None;
        }
        self.state = next;
        Some(JointReference { q, qd, qdd })
    }
}

/// The second-order reference filter of the module docs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceFilter {
    bandwidth: f64,
    period: f64,
    /// `(q_d, q̇_d)` at the next control sample; `None` until the first sample.
    state: Option<(Vector3<f64>, Vector3<f64>)>,
}

impl ReferenceFilter {
    /// A filter of bandwidth `ω_r` (rad/s) stepped every `period` seconds; `ω_r T` must stay below 0.5 so
    /// that the discrete filter keeps the continuous one's damping.
    pub fn new(bandwidth: f64, period: f64) -> Result<Self, WalkingError> {
        if !(period.is_finite() && period > 0.0) {
            return Err(WalkingError::Setting {
                name: "control_period",
                value: period,
                reason: "the control period must be finite and positive",
            });
        }
        if !(bandwidth.is_finite() && bandwidth > 0.0 && bandwidth * period < 0.5) {
            return Err(WalkingError::Setting {
                name: "reference_bandwidth",
                value: bandwidth,
                reason: "the reference filter needs a positive bandwidth well below the control rate",
            });
        }
        Ok(ReferenceFilter {
            bandwidth,
            period,
            state: None,
        })
    }

    /// The reference for this control sample given the prediction `target` at this instant; advances the
    /// filter to the next sample. The first call starts the filter on the target.
    pub fn next(&mut self, target: &JointReference<3>) -> JointReference<3> {
        let (q, qd) = self.state.unwrap_or((target.q, target.qd));
        let w = self.bandwidth;
        let qdd = target.qdd + (target.qd - qd) * (2.0 * w) + (target.q - q) * (w * w);
        let h = self.period;
        self.state = Some((q + qd * h + qdd * (0.5 * h * h), qd + qdd * h));
        JointReference { q, qd, qdd }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PERIOD: f64 = 1e-3;

    /// A prediction that moves with constant acceleration passes through the filter exactly: the feedback
    /// terms stay zero and the held-acceleration integration is exact for it.
    #[test]
    fn a_prediction_with_its_own_acceleration_passes_without_lag() {
        let mut filter = ReferenceFilter::new(2.0 * std::f64::consts::PI * 2.0, PERIOD)
            .unwrap_or_else(|e| panic!("{e}"));
        let (a, b, c) = (
            Vector3::new(0.1, 0.3, -0.2),
            Vector3::new(1.0, -2.0, 0.5),
            Vector3::new(-3.0, 8.0, 1.5),
        );
        for k in 0..500 {
            let t = k as f64 * PERIOD;
            let target = JointReference {
                q: a + b * t + c * (0.5 * t * t),
                qd: b + c * t,
                qdd: c,
            };
            let r = filter.next(&target);
            assert!((r.q - target.q).amax() < 1e-12, "q at {t}");
            assert!((r.qd - target.qd).amax() < 1e-12, "q̇ at {t}");
            assert!((r.qdd - c).amax() < 1e-9, "q̈ at {t}");
        }
    }

    /// A unit step of the prediction is followed as the continuous critically damped response
    /// `1 − (1 + ω t) e^{−ω t}` within 0.003 (the held-acceleration recursion at `ω T = 0.0126` departs from
    /// it by 0.0024 at most, computed with numpy:
    /// `q, qd = q + qd*h + qdd*h*h/2, qd + qdd*h` with `qdd = 2*w*(0 - qd) + w*w*(1 - q)` over 2 s), without
    /// overshoot, and settled to 0.1 % after 0.75 s (`ω t = 9.4`).
    #[test]
    fn a_step_is_followed_critically_damped() {
        let w = 2.0 * std::f64::consts::PI * 2.0;
        let mut filter = ReferenceFilter::new(w, PERIOD).unwrap_or_else(|e| panic!("{e}"));
        let zero = JointReference {
            q: Vector3::zeros(),
            qd: Vector3::zeros(),
            qdd: Vector3::zeros(),
        };
        filter.next(&zero);
        let step = JointReference {
            q: Vector3::repeat(1.0),
            ..zero
        };
        for k in 1..=1000 {
            let t = (k - 1) as f64 * PERIOD;
            let r = filter.next(&step);
            let exact = 1.0 - (1.0 + w * t) * (-w * t).exp();
            assert!(
                (r.q[0] - exact).abs() < 3e-3,
                "t = {t}: {} vs {exact}",
                r.q[0]
            );
            assert!(r.q[1] <= 1.0, "overshoot at {t}");
            if t >= 0.75 {
                assert!((r.q[2] - 1.0).abs() < 1e-3, "t = {t}: {}", r.q[2]);
            }
        }
    }

    /// Bandwidths that are not positive or too close to the control rate, and bad periods, are refused.
    #[test]
    fn bad_settings_are_refused() {
        for (bandwidth, period) in [
            (0.0, PERIOD),
            (500.0, PERIOD),
            (f64::NAN, PERIOD),
            (10.0, 0.0),
        ] {
            assert!(
                ReferenceFilter::new(bandwidth, period).is_err(),
                "{bandwidth}, {period}"
            );
        }
    }
}
