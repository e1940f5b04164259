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

use super::dense::{cholesky_lower, cholesky_solve, first_non_finite, symmetrise};
use super::fault::{
    CovarianceRepair, EstimationError, FaultPolicy, RejectReason, UpdateOutcome, check_finite,
    check_positive_definite, check_positive_semidefinite, repair_covariance,
};
use super::sigma::{
    MeanFn, ResidualFn, SigmaPoints, cross_covariance, first_bad_column, subtract,
    unscented_transform, weighted_mean,
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
    x_mean: MeanFn<NX, NS>,
    x_residual: ResidualFn<NX>,
    y_mean: MeanFn<NY, NS>,
    y_residual: ResidualFn<NY>,
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
        check_positive_semidefinite("Q", &q)?;
        check_positive_semidefinite("R", &r)?;
        check_finite("x0", &x0)?;
        check_positive_definite("P0", &p0)?;
        Ok(UnscentedKalmanFilter {
            points,
            x: x0,
            p: p0,
            q,
            r,
            x_mean: weighted_mean::<NX, NS>,
            x_residual: subtract::<NX>,
            y_mean: weighted_mean::<NY, NS>,
            y_residual: subtract::<NY>,
            policy: FaultPolicy::default(),
            innovation: SVector::zeros(),
            innovation_cov: r,
            gain: SMatrix::zeros(),
        })
    }

    /// Replaces the state mean and residual functions (for angle states).
    pub fn with_state_functions(mut self, mean: MeanFn<NX, NS>, residual: ResidualFn<NX>) -> Self {
        self.x_mean = mean;
        self.x_residual = residual;
        self
    }

    /// Replaces the measurement mean and residual functions (for angle measurements).
    pub fn with_measurement_functions(
        mut self,
        mean: MeanFn<NY, NS>,
        residual: ResidualFn<NY>,
    ) -> Self {
        self.y_mean = mean;
        self.y_residual = residual;
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
        check_positive_semidefinite("Q", &q)?;
        check_positive_semidefinite("R", &r)?;
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
        check_finite("x", &x)?;
        check_positive_definite("P", &p)?;
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
        if let Some(index) = first_non_finite(u) {
            return Err(EstimationError::NonFiniteInput { index });
        }
        let chi = self.points.generate(&self.x, &self.p)?;
        let mut prop = SMatrix::<f64, NX, NS>::zeros();
        for i in 0..NS {
            prop.set_column(i, &f(&chi.column(i).into_owned(), u));
        }
        if let Some(sigma_point) = first_bad_column(&prop) {
            return Err(EstimationError::NonFiniteModelOutput {
                function: "process function",
                sigma_point,
            });
        }
        let (x, mut p) = unscented_transform(
            &prop,
            self.points.mean_weights(),
            self.points.covariance_weights(),
            self.x_mean,
            self.x_residual,
        );
        p += self.q;
        let repair = repair_covariance(&mut p, self.policy.eigen_floor, FILTER)?;
        if first_non_finite(&x).is_some() {
            return Err(EstimationError::NonFiniteModelOutput {
                function: "state mean function",
                sigma_point: 0,
            });
        }
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
        if let Some(index) = first_non_finite(y) {
            return Ok(UpdateOutcome::Rejected {
                reason: RejectReason::NonFiniteMeasurement { index },
            });
        }
        if let Some(index) = first_non_finite(u) {
            return Err(EstimationError::NonFiniteInput { index });
        }
        let chi = self.points.generate(&self.x, &self.p)?;
        let mut ys = SMatrix::<f64, NY, NS>::zeros();
        for i in 0..NS {
            ys.set_column(i, &h(&chi.column(i).into_owned(), u));
        }
        if let Some(sigma_point) = first_bad_column(&ys) {
            return Err(EstimationError::NonFiniteModelOutput {
                function: "measurement function",
                sigma_point,
            });
        }
        let wc = self.points.covariance_weights();
        let (y_hat, mut s) = unscented_transform(
            &ys,
            self.points.mean_weights(),
            wc,
            self.y_mean,
            self.y_residual,
        );
        s += self.r;
        symmetrise(&mut s);
        let pxy = cross_covariance(
            &chi,
            &self.x,
            &ys,
            &y_hat,
            wc,
            self.x_residual,
            self.y_residual,
        );
        let e = (self.y_residual)(y, &y_hat);
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
        self.predict(u, |x, u| {
            let mut next = SVector::zeros();
            model.step(x, u, &mut next);
            next
        })
    }

    /// [`Self::update`] with a [`DiscreteModel`]'s `outputs` as the measurement function.
    pub fn update_model<M: DiscreteModel<NX, NU, NY>>(
        &mut self,
        model: &M,
        y: &SVector<f64, NY>,
        u: &SVector<f64, NU>,
    ) -> Result<UpdateOutcome, EstimationError> {
        self.update(y, u, |x, u| {
            let mut out = SVector::zeros();
            model.outputs(x, u, &mut out);
            out
        })
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
        self.y_residual
    }

    /// The sigma-point weights in use.
    pub fn sigma_points(&self) -> &SigmaPoints<NX, NS> {
        &self.points
    }
}

/// The Kalman correction shared by the unscented filters: NIS and gate, `K = P_xy S⁻¹`, `x += K e`,
/// `P −= K S Kᵀ`, repair. `x` and `p` change only when the measurement is accepted and no error occurs.
pub(crate) fn kalman_correct<const N: usize, const M: usize>(
    x: &mut SVector<f64, N>,
    p: &mut SMatrix<f64, N, N>,
    e: &SVector<f64, M>,
    s: &SMatrix<f64, M, M>,
    pxy: &SMatrix<f64, N, M>,
    policy: &FaultPolicy,
    filter: &'static str,
) -> Result<(UpdateOutcome, Option<SMatrix<f64, N, M>>), EstimationError> {
    let singular = EstimationError::SingularInnovation { filter };
    let ls = cholesky_lower(s).ok_or(singular.clone())?;
    let nis = e.dot(&cholesky_solve(&ls, e).ok_or(singular.clone())?);
    if let Some(reason) = policy.gate(nis) {
        return Ok((UpdateOutcome::Rejected { reason }, None));
    }
    // K = P_xy S⁻¹  ⇔  Kᵀ = S⁻¹ P_xyᵀ.
    let k = cholesky_solve(&ls, &pxy.transpose())
        .ok_or(singular)?
        .transpose();
    let new_x = *x + k * e;
    let mut new_p = *p - k * s * k.transpose();
    let repair = repair_covariance(&mut new_p, policy.eigen_floor, filter)?;
    if first_non_finite(&new_x).is_some() {
        return Err(EstimationError::NonFiniteCovariance { filter });
    }
    *x = new_x;
    *p = new_p;
    Ok((UpdateOutcome::Accepted { nis, repair }, Some(k)))
}
