//! The unscented Kalman filter with additive noise (paper 000, Eqs. 6–22; Wan and van der Merwe 2000).
//!
//! Model: `x[k+1] = f(x[k], u[k]) + v[k]`, `y[k] = h(x[k], u[k]) + n[k]`, `v ~ N(0, Q)`, `n ~ N(0, R)`.
//!
//! Predict (Eqs. 13, 14, 17, 18): sigma points `χ` of `(x̂, P)`, propagated `χ*ᵢ = f(χᵢ, u)`,
//! `x̂⁻ = mean(χ*)`, `P⁻ = Σ W⁽ᶜ⁾ (χ*ᵢ − x̂⁻)(χ*ᵢ − x̂⁻)ᵀ + Q`.
//!
//! Update (Eqs. 16, 19, 21, 22, 12, 9): sigma points are **redrawn** from `(x̂⁻, P⁻)` so that they carry the
//! process noise `Q`; `Yᵢ = h(χᵢ, u)`, `ŷ = mean(Y)`, `S = Σ W⁽ᶜ⁾ (Yᵢ − ŷ)(Yᵢ − ŷ)ᵀ + R`,
//! `P_xy = Σ W⁽ᶜ⁾ (χᵢ − x̂⁻)(Yᵢ − ŷ)ᵀ`, `K = P_xy S⁻¹`, `x̂ = x̂⁻ + K (y − ŷ)`, `P = P⁻ − K S Kᵀ`.
//!
//! **Paper inconsistency.** Eq. 15 of paper 000 augments the propagated points with `±γ√P_v`, which gives
//! `4L + 1` points, while Eqs. 19, 21 and 22 sum over `2L + 1`; Eq. 18 adds `P_v` to a sum over the
//! un-augmented `χ*`. We follow the consistent reading that Wan and van der Merwe give as the alternative to
//! augmentation and that filterpy implements: redraw `2L + 1` points from `(x̂⁻, P⁻)` before the update.
//! Eqs. 7, 10 and 11 also write the measurement noise as non-additive; that form is
//! [`super::ukf_augmented::AugmentedUkf`].
//!
//! Residuals and means go through user functions ([`UnscentedKalmanFilter::with_state_functions`],
//! [`UnscentedKalmanFilter::with_measurement_functions`]) so that angle states and measurements can be wrapped;
//! the update adds `K e` to the state, so a wrapping state mean function should also wrap its output.
//!
//! Every step works on copies and commits at the end: a step that returns an error leaves the filter
//! unchanged. Steps do not allocate.

use super::dense::symmetrise;
use super::fault::{
    CovarianceRepair, EstimationError, FaultPolicy, UpdateOutcome, check_additive_noise,
    check_estimate,
};
use super::sigma::{MeanFn, ResidualFn, SigmaPoints};
use super::unscented::{
    SpaceFns, check_input, evaluate_points, innovation_moments, kalman_correct, model_measurement,
    model_process, predicted_moments, rejected_measurement,
};
use crate::model::DiscreteModel;
use nalgebra::{SMatrix, SVector};

const FILTER: &str = "UKF";

/// An additive-noise UKF with `NX` states, `NU` inputs, `NY` measurements and `NS = 2 NX + 1` sigma points.
#[derive(Clone, Debug)]
pub struct UnscentedKalmanFilter<const NX: usize, const NU: usize, const NY: usize, const NS: usize>
{
    points: SigmaPoints<NX, NS>,
    x: SVector<f64, NX>,
    p: SMatrix<f64, NX, NX>,
    q: SMatrix<f64, NX, NX>,
    r: SMatrix<f64, NY, NY>,
    x_fns: SpaceFns<NX, NS>,
    y_fns: SpaceFns<NY, NS>,
    policy: FaultPolicy,
    innovation: SVector<f64, NY>,
    innovation_cov: SMatrix<f64, NY, NY>,
    gain: SMatrix<f64, NX, NY>,
}

impl<const NX: usize, const NU: usize, const NY: usize, const NS: usize>
    UnscentedKalmanFilter<NX, NU, NY, NS>
{
    /// A UKF with sigma points `points`, process noise `q` (positive semi-definite), measurement noise `r`
    /// (positive semi-definite; a singular innovation covariance is reported by `update`) and initial
    /// estimate `(x0, p0)` (`p0` positive definite).
    pub fn new(
        points: SigmaPoints<NX, NS>,
        q: SMatrix<f64, NX, NX>,
        r: SMatrix<f64, NY, NY>,
        x0: SVector<f64, NX>,
        p0: SMatrix<f64, NX, NX>,
    ) -> Result<Self, EstimationError> {
        check_additive_noise(&q, &r)?;
        check_estimate(("x0", "P0"), &x0, &p0)?;
        Ok(UnscentedKalmanFilter {
            points,
            x: x0,
            p: p0,
            q,
            r,
            x_fns: SpaceFns::default(),
            y_fns: SpaceFns::default(),
            policy: FaultPolicy::default(),
            innovation: SVector::zeros(),
            innovation_cov: r,
            gain: SMatrix::zeros(),
        })
    }

    /// Replaces the state mean and residual functions (for angle states).
    pub fn with_state_functions(mut self, mean: MeanFn<NX, NS>, residual: ResidualFn<NX>) -> Self {
        self.x_fns = SpaceFns { mean, residual };
        self
    }

    /// Replaces the measurement mean and residual functions (for angle measurements).
    pub fn with_measurement_functions(
        mut self,
        mean: MeanFn<NY, NS>,
        residual: ResidualFn<NY>,
    ) -> Self {
        self.y_fns = SpaceFns { mean, residual };
        self
    }

    /// Replaces the fault policy (NIS gate, eigenvalue floor).
    pub fn set_fault_policy(&mut self, policy: FaultPolicy) -> Result<(), EstimationError> {
        policy.validate()?;
        self.policy = policy;
        Ok(())
    }

    /// Replaces the noise covariances.
    pub fn set_noise(
        &mut self,
        q: SMatrix<f64, NX, NX>,
        r: SMatrix<f64, NY, NY>,
    ) -> Result<(), EstimationError> {
        check_additive_noise(&q, &r)?;
        self.q = q;
        self.r = r;
        Ok(())
    }

    /// Re-initialises the estimate.
    pub fn set_state(
        &mut self,
        x: SVector<f64, NX>,
        p: SMatrix<f64, NX, NX>,
    ) -> Result<(), EstimationError> {
        check_estimate(("x", "P"), &x, &p)?;
        self.x = x;
        self.p = p;
        Ok(())
    }

    /// The time update through the process function `f(x, u)`.
    pub fn predict<F>(
        &mut self,
        u: &SVector<f64, NU>,
        mut f: F,
    ) -> Result<Option<CovarianceRepair>, EstimationError>
    where
        F: FnMut(&SVector<f64, NX>, &SVector<f64, NU>) -> SVector<f64, NX>,
    {
        check_input(u)?;
        let chi = self.points.generate(&self.x, &self.p)?;
        let prop = evaluate_points("process function", |i| f(&chi.column(i).into_owned(), u))?;
        let (x, p, repair) = predicted_moments(
            &prop,
            &self.points,
            &self.x_fns,
            Some(&self.q),
            &self.policy,
            FILTER,
        )?;
        self.x = x;
        self.p = p;
        Ok(repair)
    }

    /// The measurement update with measurement `y` and the measurement function `h(x, u)`.
    pub fn update<H>(
        &mut self,
        y: &SVector<f64, NY>,
        u: &SVector<f64, NU>,
        mut h: H,
    ) -> Result<UpdateOutcome, EstimationError>
    where
        H: FnMut(&SVector<f64, NX>, &SVector<f64, NU>) -> SVector<f64, NY>,
    {
        if let Some(rejected) = rejected_measurement(y) {
            return Ok(rejected);
        }
        check_input(u)?;
        let chi = self.points.generate(&self.x, &self.p)?;
        let ys = evaluate_points("measurement function", |i| {
            h(&chi.column(i).into_owned(), u)
        })?;
        let (y_hat, mut s, pxy) = innovation_moments(
            &chi,
            &self.x,
            self.x_fns.residual,
            &ys,
            &self.y_fns,
            Some(&self.r),
            &self.points,
        );
        symmetrise(&mut s);
        let e = (self.y_fns.residual)(y, &y_hat);
        let outcome = kalman_correct(&mut self.x, &mut self.p, &e, &s, &pxy, &self.policy, FILTER)?;
        self.innovation = e;
        self.innovation_cov = s;
        if let Some(k) = outcome.1 {
            self.gain = k;
        }
        Ok(outcome.0)
    }

    /// [`Self::predict`] with a [`DiscreteModel`]'s `step` as the process function.
    pub fn predict_model<M: DiscreteModel<NX, NU, NY>>(
        &mut self,
        model: &M,
        u: &SVector<f64, NU>,
    ) -> Result<Option<CovarianceRepair>, EstimationError> {
        self.predict(u, model_process(model))
    }

    /// [`Self::update`] with a [`DiscreteModel`]'s `outputs` as the measurement function.
    pub fn update_model<M: DiscreteModel<NX, NU, NY>>(
        &mut self,
        model: &M,
        y: &SVector<f64, NY>,
        u: &SVector<f64, NU>,
    ) -> Result<UpdateOutcome, EstimationError> {
        self.update(y, u, model_measurement(model))
    }

    /// The state estimate.
    pub fn state(&self) -> &SVector<f64, NX> {
        &self.x
    }

    /// The error covariance of the estimate.
    pub fn covariance(&self) -> &SMatrix<f64, NX, NX> {
        &self.p
    }

    /// The innovation `y − ŷ` of the last finite measurement.
    pub fn innovation(&self) -> &SVector<f64, NY> {
        &self.innovation
    }

    /// The innovation covariance `S` of the last finite measurement.
    pub fn innovation_covariance(&self) -> &SMatrix<f64, NY, NY> {
        &self.innovation_cov
    }

    /// The gain of the last accepted update.
    pub fn gain(&self) -> &SMatrix<f64, NX, NY> {
        &self.gain
    }

    /// The measurement noise covariance.
    pub fn measurement_noise(&self) -> &SMatrix<f64, NY, NY> {
        &self.r
    }

    /// The fault policy in use.
    pub fn fault_policy(&self) -> &FaultPolicy {
        &self.policy
    }

    /// The measurement residual function.
    pub(crate) fn measurement_residual(&self) -> ResidualFn<NY> {
        self.y_fns.residual
    }

    /// The sigma-point weights in use.
    pub fn sigma_points(&self) -> &SigmaPoints<NX, NS> {
        &self.points
    }
}
