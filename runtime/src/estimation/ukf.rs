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
//!
//! # Large models
//!
//! The filter keeps `P`, `Q` and the work space of a step (the sigma points and their images, the next
//! covariance, a work matrix for the Cholesky factor and the covariance repair) on the heap, allocated once by
//! the constructor, and a step declares no `NX × NX` or `NX × (2 NX + 1)` value: a filter of any size runs on any
//! thread. [`UnscentedKalmanFilter::new`] takes its matrices by value, on the caller's stack;
//! [`UnscentedKalmanFilter::from_refs`] borrows them. `clone_from` copies without allocating.

use super::fault::{
    CovarianceRepair, EstimationError, FaultPolicy, UpdateOutcome, check_additive_noise,
    check_estimate,
};
use super::sigma::{ResidualFn, SigmaPoints};
use super::unscented::{
    FilterSettings, check_input, evaluate_points_into, model_measurement, model_process,
    rejected_measurement, settings_methods,
};
use crate::matrix::boxed_copy;
use crate::model::DiscreteModel;
use nalgebra::{SMatrix, SVector};

const FILTER: &str = "UKF";

/// An additive-noise UKF with `NX` states, `NU` inputs, `NY` measurements and `NS = 2 NX + 1` sigma points.
#[derive(Debug)]
pub struct UnscentedKalmanFilter<const NX: usize, const NU: usize, const NY: usize, const NS: usize>
{
    settings: FilterSettings<NX, NX, NY, NS>,
    x: SVector<f64, NX>,
    p: Box<SMatrix<f64, NX, NX>>,
    q: Box<SMatrix<f64, NX, NX>>,
    r: SMatrix<f64, NY, NY>,
    innovation: SVector<f64, NY>,
    innovation_cov: SMatrix<f64, NY, NY>,
    gain: SMatrix<f64, NX, NY>,
    work: Box<StepWork<NX, NY, NS>>,
}

/// The matrices a step writes before it commits; their contents between steps mean nothing.
#[derive(Debug)]
struct StepWork<const NX: usize, const NY: usize, const NS: usize> {
    /// The sigma points.
    chi: SMatrix<f64, NX, NS>,
    /// Their images under the process function.
    propagated: SMatrix<f64, NX, NS>,
    /// Their images under the measurement function.
    measured: SMatrix<f64, NY, NS>,
    /// The covariance being computed.
    next_p: SMatrix<f64, NX, NX>,
    /// The Cholesky factor of the sigma points, then the covariance repair's work matrix.
    factor: SMatrix<f64, NX, NX>,
}

// SAFETY: `SMatrix<f64, _, _>` fields only (arrays of `f64`), for which all-zero bytes are `0.0`.
unsafe impl<const NX: usize, const NY: usize, const NS: usize> bytemuck::Zeroable
    for StepWork<NX, NY, NS>
{
}

impl<const NX: usize, const NU: usize, const NY: usize, const NS: usize> Clone
    for UnscentedKalmanFilter<NX, NU, NY, NS>
{
    fn clone(&self) -> Self {
        UnscentedKalmanFilter {
            p: boxed_copy(&self.p),
            q: boxed_copy(&self.q),
            work: bytemuck::zeroed_box(),
            ..*self
        }
    }

    fn clone_from(&mut self, source: &Self) {
        self.settings = source.settings;
        self.x = source.x;
        self.p.copy_from(&source.p);
        self.q.copy_from(&source.q);
        self.r = source.r;
        self.innovation = source.innovation;
        self.innovation_cov = source.innovation_cov;
        self.gain = source.gain;
    }
}

impl<const NX: usize, const NU: usize, const NY: usize, const NS: usize>
    UnscentedKalmanFilter<NX, NU, NY, NS>
{
    /// A UKF with sigma points `points`, process noise `q` (positive semi-definite), measurement noise `r`
    /// (positive semi-definite; a singular innovation covariance is reported by `update`) and initial
    /// estimate `(x0, p0)` (`p0` positive definite). The matrices are taken by value, on the caller's stack;
    /// [`Self::from_refs`] borrows them.
    pub fn new(
        points: SigmaPoints<NX, NS>,
        q: SMatrix<f64, NX, NX>,
        r: SMatrix<f64, NY, NY>,
        x0: SVector<f64, NX>,
        p0: SMatrix<f64, NX, NX>,
    ) -> Result<Self, EstimationError> {
        Self::from_refs(points, &q, &r, &x0, &p0)
    }

    /// [`Self::new`] from borrowed matrices, which the filter copies to the heap (for a model whose matrices
    /// do not fit the stack; see the module docs).
    pub fn from_refs(
        points: SigmaPoints<NX, NS>,
        q: &SMatrix<f64, NX, NX>,
        r: &SMatrix<f64, NY, NY>,
        x0: &SVector<f64, NX>,
        p0: &SMatrix<f64, NX, NX>,
    ) -> Result<Self, EstimationError> {
        check_additive_noise(q, r)?;
        check_estimate(("x0", "P0"), x0, p0)?;
        Ok(UnscentedKalmanFilter {
            settings: FilterSettings::new(points, FILTER),
            x: *x0,
            p: boxed_copy(p0),
            q: boxed_copy(q),
            r: *r,
            innovation: SVector::zeros(),
            innovation_cov: *r,
            gain: SMatrix::zeros(),
            work: bytemuck::zeroed_box(),
        })
    }

    settings_methods!();

    /// Replaces the noise covariances.
    pub fn set_noise(
        &mut self,
        q: SMatrix<f64, NX, NX>,
        r: SMatrix<f64, NY, NY>,
    ) -> Result<(), EstimationError> {
        check_additive_noise(&q, &r)?;
        self.q.copy_from(&q);
        self.r = r;
        Ok(())
    }

    /// Re-initialises the estimate.
    pub fn set_state(
        &mut self,
        x: SVector<f64, NX>,
        p: SMatrix<f64, NX, NX>,
    ) -> Result<(), EstimationError> {
        self.set_state_from(&x, &p)
    }

    /// [`Self::set_state`] from borrowed values, copied into the filter (for a `P` held on the heap).
    pub fn set_state_from(
        &mut self,
        x: &SVector<f64, NX>,
        p: &SMatrix<f64, NX, NX>,
    ) -> Result<(), EstimationError> {
        check_estimate(("x", "P"), x, p)?;
        self.x = *x;
        self.p.copy_from(p);
        Ok(())
    }

    /// The time update through the process function `f(x, u)`.
    pub fn predict<F>(
        &mut self,
        u: &SVector<f64, NU>,
        f: F,
    ) -> Result<Option<CovarianceRepair>, EstimationError>
    where
        F: FnMut(&SVector<f64, NX>, &SVector<f64, NU>) -> SVector<f64, NX>,
    {
        let mut f = f;
        check_input(u)?;
        let w = &mut *self.work;
        let points = &self.settings.points;
        points.generate_into(&self.x, &self.p, &mut w.factor, &mut w.chi)?;
        let chi = &w.chi;
        let propagate = |i: usize| f(&chi.column(i).into_owned(), u);
        evaluate_points_into("process function", propagate, &mut w.propagated)?;
        let out = (&mut w.next_p, &mut w.factor);
        let (x, repair) = self
            .settings
            .predicted_into(&w.propagated, Some(&self.q), out)?;
        self.x = x;
        self.p.copy_from(&w.next_p);
        Ok(repair)
    }

    /// The measurement update with measurement `y` and the measurement function `h(x, u)`.
    pub fn update<H>(
        &mut self,
        y: &SVector<f64, NY>,
        u: &SVector<f64, NU>,
        h: H,
    ) -> Result<UpdateOutcome, EstimationError>
    where
        H: FnMut(&SVector<f64, NX>, &SVector<f64, NU>) -> SVector<f64, NY>,
    {
        if let Some(rejected) = rejected_measurement(y) {
            return Ok(rejected);
        }
        let mut h = h;
        check_input(u)?;
        let w = &mut *self.work;
        let points = &self.settings.points;
        points.generate_into(&self.x, &self.p, &mut w.factor, &mut w.chi)?;
        let chi = &w.chi;
        let measure = |i: usize| h(&chi.column(i).into_owned(), u);
        evaluate_points_into("measurement function", measure, &mut w.measured)?;
        let points_and_y = (&w.chi, &w.measured, y);
        let scratch = (&mut w.next_p, &mut w.factor);
        let correction = self.settings.correct_in(
            &mut self.x,
            &mut self.p,
            points_and_y,
            Some(&self.r),
            scratch,
        )?;
        self.innovation = correction.innovation;
        self.innovation_cov = correction.innovation_cov;
        if let Some(k) = correction.gain {
            self.gain = k;
        }
        Ok(correction.outcome)
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
        &self.settings.policy
    }

    /// The measurement residual function.
    pub(crate) fn measurement_residual(&self) -> ResidualFn<NY> {
        self.settings.y_fns.residual
    }

    /// The sigma-point weights in use.
    pub fn sigma_points(&self) -> &SigmaPoints<NX, NS> {
        &self.settings.points
    }
}
