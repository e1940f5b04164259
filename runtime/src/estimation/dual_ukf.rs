//! The dual UKF: a state UKF and a parameter UKF run side by side (paper 000, Eqs. 6–27; Wan and van der
//! Merwe 2000, Sec. 4).
//!
//! The parameters `w` follow the random walk of Eq. 23, `w[k+1] = w[k] + r[k]`, with the process-noise
//! covariance of Eq. 27, `P_r = (λ_RLS⁻¹ − 1) P_w`. The parameter time update is therefore
//! `P_w⁻ = P_w + P_r = P_w / λ_RLS`: recursive least squares with exponential forgetting, weighting past data by
//! `λ_RLS^age`. (Eq. 27 calls `P_r` the "innovation covariance"; it is the covariance of the parameter process
//! noise `r` of Eq. 23, which is how it is used here.)
//!
//! One step at time `k` with input `u` and measurement `y`, from the posteriors `(x̂, P)` and `(ŵ, P_w)`:
//!
//! 1. parameter time update: `ŵ⁻ = ŵ`, `P_w⁻ = P_w / λ_RLS`;
//! 2. state time update with the model at `ŵ⁻`: `x⁻ = UT[f(·, u, ŵ⁻)]`;
//! 3. state measurement update with `h(·, u, ŵ⁻)`, giving the innovation covariance `S`;
//! 4. parameter measurement update: sigma points `Wᵢ` of `(ŵ⁻, P_w⁻)`; each predicts the measurement by
//!    running the model from the previous state estimate, `dᵢ = h(f(x̂, u, Wᵢ), u, Wᵢ)` (Eq. 24 with
//!    `Y(x, w) = h(f(x, u, w), u, w)`); then `S_d = Σ W⁽ᶜ⁾ (dᵢ − d̂)(dᵢ − d̂)ᵀ + P_e`, `K_w = P_wd S_d⁻¹`,
//!    `ŵ = ŵ⁻ + K_w (y − d̂)`.
//!
//! The paper leaves the covariance `P_e` of the observation error `e` of Eqs. 24 and 26 open. By default we
//! take `P_e = S` ([`ParameterObservationNoise::StateInnovation`]): the parameter observation starts from an
//! uncertain state estimate, and that uncertainty (`C P⁻ Cᵀ` in the linear case) belongs to `e` as much as the
//! sensor noise `R` does. With `P_e = R` alone ([`ParameterObservationNoise::MeasurementNoise`]) the parameter
//! filter reads state-estimation errors as parameter errors, which makes it fragile when the state is poorly
//! known.
//!
//! The parameters must act on the one-step prediction of `y`. With position measurements of an explicit-Euler
//! second-order model they do not (the position after one step does not depend on the force law), and no
//! dual filter of this form can learn them; a semi-implicit discretisation, a velocity or force measurement,
//! or the paper's torque observation (Eq. 25) makes them observable.
//!
//! # Separate observations
//!
//! In the paper the two filters observe different things: the state filter the position sensors (Eq. 7),
//! the parameter filter a torque output `d = Y(x, w) + e` (Eqs. 24–25). [`DualUkf::step_separate`] takes
//! that form: the state filter updates with `y` through `h(x, u, w)` as above, and the parameter filter
//! with its own observation `d` ([`ParameterObservation`], with the covariance `P_e` of `e`) through
//! `Y(x̂, u, w)` evaluated at the state filter's new estimate `x̂`:
//!
//! 4'. sigma points `Wᵢ` of `(ŵ⁻, P_w⁻)`, `dᵢ = Y(x̂, u, Wᵢ)`, `S_d = Σ W⁽ᶜ⁾ (dᵢ − d̂)(dᵢ − d̂)ᵀ + P_e`,
//!    `K_w = P_wd S_d⁻¹`, `ŵ = ŵ⁻ + K_w (d − d̂)`.
//!
//! This is the same recursion as running a second UKF on `w` with identity dynamics, process noise
//! `(λ⁻¹ − 1) P_w` and measurement function `Y(x̂, u, ·)` after the state UKF's update (the unit tests check
//! that equivalence). Without an observation `d` the parameters are held (no forgetting without data).
//!
//! In [`DualUkf::step`] both filters see the same measurement `y`; a model whose parameter observation is
//! a separate quantity, such as the paper's torque, can also include it in `y` and `h` there, at the price
//! of one innovation covariance for both.
//!
//! A non-finite measurement is rejected by both filters; the state is then the prediction and the parameters
//! are left as they were (no forgetting without data). Each filter gates its own NIS. A step that returns an
//! error changes nothing, also on a [`Parametric`] model (whose parameters are set to `ŵ` only when the step
//! succeeds).

use super::dense::symmetrise;
use super::fault::{
    CovarianceRepair, EstimationError, FaultPolicy, UpdateOutcome, check_estimate,
    check_positive_semidefinite, repair_covariance,
};
use super::sigma::{MeanFn, SigmaPoints, subtract, weighted_mean};
use super::ukf::UnscentedKalmanFilter;
use super::unscented::{
    Innovation, SpaceFns, check_input, evaluate_points, innovation_moments, kalman_correct,
    rejected_measurement,
};
use crate::model::{DiscreteModel, ParamError, Parametric};
use nalgebra::{SMatrix, SVector};

const FILTER: &str = "dual UKF parameter filter";

/// What a failed evaluation in the parameter filter of [`DualUkf::step`] names.
const MODEL_AT_POINT: &str = "model at a parameter sigma point";

/// The model a dual UKF runs: `x[k+1] = f(x, u, w)` and `y = h(x, u, w)`.
pub trait DualModel<const NX: usize, const NU: usize, const NY: usize, const NP: usize> {
    /// `f(x, u, w)`.
    fn propagate(
        &mut self,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        w: &SVector<f64, NP>,
    ) -> SVector<f64, NX>;
    /// `h(x, u, w)`.
    fn observe(
        &mut self,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        w: &SVector<f64, NP>,
    ) -> SVector<f64, NY>;
    /// Called with the new parameter estimate before a successful step is committed; an error aborts the step.
    fn commit(&mut self, _w: &SVector<f64, NP>) -> Result<(), EstimationError> {
        Ok(())
    }
    /// An error the model met while evaluating (e.g. a refused parameter), reported in place of the
    /// non-finite output it caused.
    fn take_error(&mut self) -> Option<EstimationError> {
        None
    }
}

/// A [`DualModel`] from two closures `f(x, u, w)` and `h(x, u, w)`.
pub struct DualFns<F, H> {
    pub f: F,
    pub h: H,
}

impl<const NX: usize, const NU: usize, const NY: usize, const NP: usize, F, H>
    DualModel<NX, NU, NY, NP> for DualFns<F, H>
where
    F: FnMut(&SVector<f64, NX>, &SVector<f64, NU>, &SVector<f64, NP>) -> SVector<f64, NX>,
    H: FnMut(&SVector<f64, NX>, &SVector<f64, NU>, &SVector<f64, NP>) -> SVector<f64, NY>,
{
    fn propagate(
        &mut self,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        w: &SVector<f64, NP>,
    ) -> SVector<f64, NX> {
        (self.f)(x, u, w)
    }

    fn observe(
        &mut self,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        w: &SVector<f64, NP>,
    ) -> SVector<f64, NY> {
        (self.h)(x, u, w)
    }
}

/// A [`DualModel`] over a [`DiscreteModel`] + [`Parametric`] model whose parameters `indices[j]` are
/// estimated as `w[j]`. A refused parameter value makes the step fail with
/// [`EstimationError::ParamRefused`].
pub struct ParametricDualModel<'a, M, const NP: usize> {
    model: &'a mut M,
    indices: [usize; NP],
    refused: Option<ParamError>,
}

impl<'a, M: Parametric, const NP: usize> ParametricDualModel<'a, M, NP> {
    /// Wraps `model`; `indices` are the model's parameter indices in the order of `w`.
    pub fn new(model: &'a mut M, indices: [usize; NP]) -> Self {
        ParametricDualModel {
            model,
            indices,
            refused: None,
        }
    }

    /// The model's current values of the estimated parameters (a starting guess for the filter).
    pub fn current(&self) -> Result<SVector<f64, NP>, EstimationError> {
        let mut w = SVector::<f64, NP>::zeros();
        for (j, &index) in self.indices.iter().enumerate() {
            w[j] = self
                .model
                .param(index)
                .ok_or(ParamError::NoSuchParam { index })?;
        }
        Ok(w)
    }

    /// `run(model, out)` with the model's parameters set to `w`; all `NaN` when the model refuses `w` (the
    /// refusal is kept for [`DualModel::take_error`]).
    fn at_parameters<const N: usize>(
        &mut self,
        w: &SVector<f64, NP>,
        run: impl FnOnce(&M, &mut SVector<f64, N>),
    ) -> SVector<f64, N> {
        if !self.set(w) {
            return SVector::repeat(f64::NAN);
        }
        let mut out = SVector::zeros();
        run(self.model, &mut out);
        out
    }

    fn set(&mut self, w: &SVector<f64, NP>) -> bool {
        for (j, &index) in self.indices.iter().enumerate() {
            if let Err(e) = self.model.set_param(index, w[j]) {
                self.refused.get_or_insert(e);
                return false;
            }
        }
        true
    }
}

impl<M, const NX: usize, const NU: usize, const NY: usize, const NP: usize>
    DualModel<NX, NU, NY, NP> for ParametricDualModel<'_, M, NP>
where
    M: DiscreteModel<NX, NU, NY> + Parametric,
{
    fn propagate(
        &mut self,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        w: &SVector<f64, NP>,
    ) -> SVector<f64, NX> {
        self.at_parameters(w, |model, out| model.step(x, u, out))
    }

    fn observe(
        &mut self,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        w: &SVector<f64, NP>,
    ) -> SVector<f64, NY> {
        self.at_parameters(w, |model, out| model.outputs(x, u, out))
    }

    fn commit(&mut self, w: &SVector<f64, NP>) -> Result<(), EstimationError> {
        if self.set(w) {
            Ok(())
        } else {
            Err(self.take_error_inner())
        }
    }

    fn take_error(&mut self) -> Option<EstimationError> {
        self.refused.take().map(EstimationError::ParamRefused)
    }
}

impl<M, const NP: usize> ParametricDualModel<'_, M, NP> {
    fn take_error_inner(&mut self) -> EstimationError {
        match self.refused.take() {
            Some(e) => EstimationError::ParamRefused(e),
            None => EstimationError::InvalidSetting {
                name: "parameter",
                value: f64::NAN,
                reason: "the model refused the parameter estimate",
            },
        }
    }
}

/// What a dual UKF step did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualOutcome {
    /// A repair of the predicted state covariance.
    pub state_prediction_repair: Option<CovarianceRepair>,
    /// The state filter's measurement update.
    pub state: UpdateOutcome,
    /// The parameter filter's measurement update.
    pub parameters: UpdateOutcome,
}

/// The parameter filter's own observation for [`DualUkf::step_separate`]: `d = Y(x, u, w) + e` (Eq. 24)
/// with `e ~ N(0, P_e)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParameterObservation<const ND: usize> {
    /// The observed output `d` (the paper's torque output of Eq. 25).
    pub d: SVector<f64, ND>,
    /// The covariance `P_e` of its error `e` (positive semi-definite; `S_d` must come out definite).
    pub noise: SMatrix<f64, ND, ND>,
}

/// What a [`DualUkf::step_separate`] step did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeparateOutcome<const ND: usize> {
    /// A repair of the predicted state covariance.
    pub state_prediction_repair: Option<CovarianceRepair>,
    /// The state filter's measurement update.
    pub state: UpdateOutcome,
    /// The parameter filter's update; `None` when no parameter observation was given.
    pub parameters: Option<UpdateOutcome>,
    /// The parameter filter's innovation `d − d̂` (zero when it did not update).
    pub parameter_innovation: SVector<f64, ND>,
}

/// A dual UKF over `NX` states and `NP` parameters (`NSX = 2 NX + 1`, `NSP = 2 NP + 1` sigma points).
#[derive(Clone, Debug)]
pub struct DualUkf<
    const NX: usize,
    const NU: usize,
    const NY: usize,
    const NP: usize,
    const NSX: usize,
    const NSP: usize,
> {
    state: UnscentedKalmanFilter<NX, NU, NY, NSX>,
    /// A copy of `state` taken at the start of a step (by `clone_from`, which allocates nothing), restored
    /// when the step fails.
    backup: UnscentedKalmanFilter<NX, NU, NY, NSX>,
    param_points: SigmaPoints<NP, NSP>,
    w: SVector<f64, NP>,
    pw: SMatrix<f64, NP, NP>,
    forgetting: f64,
    param_policy: FaultPolicy,
    param_innovation: SVector<f64, NY>,
    param_measurement_mean: MeanFn<NY, NSP>,
    param_noise: ParameterObservationNoise,
}

/// The covariance `P_e` of the parameter filter's observation error `e` (Eqs. 24, 26).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParameterObservationNoise {
    /// `P_e = S`, the state filter's innovation covariance `Cov(y − ŷ⁻)` at this step: the error of the
    /// parameter observation includes the uncertainty of the state estimate it starts from, not only the
    /// sensor noise. Without it the parameter filter takes state errors for parameter errors and can diverge
    /// when the parameters act weakly on `y`. The default.
    StateInnovation,
    /// `P_e = R`, the sensor noise alone (the textbook dual UKF; only safe when the state is known well).
    MeasurementNoise,
}

impl<
    const NX: usize,
    const NU: usize,
    const NY: usize,
    const NP: usize,
    const NSX: usize,
    const NSP: usize,
> DualUkf<NX, NU, NY, NP, NSX, NSP>
{
    /// A dual UKF from a configured state UKF, parameter sigma points, the initial parameter estimate
    /// `(w0, pw0)` and the forgetting factor `λ_RLS ∈ (0, 1]` (1: no forgetting).
    pub fn new(
        state: UnscentedKalmanFilter<NX, NU, NY, NSX>,
        param_points: SigmaPoints<NP, NSP>,
        w0: SVector<f64, NP>,
        pw0: SMatrix<f64, NP, NP>,
        forgetting: f64,
    ) -> Result<Self, EstimationError> {
        check_estimate(("w0", "Pw0"), &w0, &pw0)?;
        if !(forgetting > 0.0 && forgetting <= 1.0) {
            return Err(EstimationError::InvalidSetting {
                name: "lambda_RLS",
                value: forgetting,
                reason: "the forgetting factor must lie in (0, 1]",
            });
        }
        Ok(DualUkf {
            backup: state.clone(),
            state,
            param_points,
            w: w0,
            pw: pw0,
            forgetting,
            param_policy: FaultPolicy::default(),
            param_innovation: SVector::zeros(),
            param_measurement_mean: weighted_mean::<NY, NSP>,
            param_noise: ParameterObservationNoise::StateInnovation,
        })
    }

    /// Replaces the mean of the measurement predictions of the parameter sigma points (needed with angle
    /// measurements; the residual is the state filter's measurement residual).
    pub fn with_parameter_measurement_mean(mut self, mean: MeanFn<NY, NSP>) -> Self {
        self.param_measurement_mean = mean;
        self
    }

    /// Chooses the observation-error covariance of the parameter filter.
    pub fn with_parameter_observation_noise(mut self, noise: ParameterObservationNoise) -> Self {
        self.param_noise = noise;
        self
    }

    /// Sets the fault policy of the parameter filter (the state filter keeps its own).
    pub fn set_parameter_fault_policy(
        &mut self,
        policy: FaultPolicy,
    ) -> Result<(), EstimationError> {
        policy.validate()?;
        self.param_policy = policy;
        Ok(())
    }

    /// The state filter, e.g. to change its fault policy.
    pub fn state_filter_mut(&mut self) -> &mut UnscentedKalmanFilter<NX, NU, NY, NSX> {
        &mut self.state
    }

    /// One predict–update step of both filters.
    pub fn step<M: DualModel<NX, NU, NY, NP>>(
        &mut self,
        model: &mut M,
        u: &SVector<f64, NU>,
        y: &SVector<f64, NY>,
    ) -> Result<DualOutcome, EstimationError> {
        let result = self.restored_on_error(|filter| filter.step_inner(model, u, y));
        match (result, model.take_error()) {
            (_, Some(e)) => Err(e),
            (r, None) => r,
        }
    }

    /// [`Self::step`] with closures `f(x, u, w)` and `h(x, u, w)`.
    pub fn step_with<F, H>(
        &mut self,
        u: &SVector<f64, NU>,
        y: &SVector<f64, NY>,
        f: F,
        h: H,
    ) -> Result<DualOutcome, EstimationError>
    where
        F: FnMut(&SVector<f64, NX>, &SVector<f64, NU>, &SVector<f64, NP>) -> SVector<f64, NX>,
        H: FnMut(&SVector<f64, NX>, &SVector<f64, NU>, &SVector<f64, NP>) -> SVector<f64, NY>,
    {
        self.step(&mut DualFns { f, h }, u, y)
    }

    fn step_inner<M: DualModel<NX, NU, NY, NP>>(
        &mut self,
        model: &mut M,
        u: &SVector<f64, NU>,
        y: &SVector<f64, NY>,
    ) -> Result<DualOutcome, EstimationError> {
        check_input(u)?;
        let st = &mut self.state;
        let x_prev = *st.state();
        let w_prior = self.w;
        let state_prediction_repair = st.predict(u, |x, u| model.propagate(x, u, &w_prior))?;

        if let Some(rejected) = rejected_measurement(y) {
            model.commit(&self.w)?;
            return Ok(DualOutcome {
                state_prediction_repair,
                state: rejected,
                parameters: rejected,
            });
        }

        // State filter measurement update with the prior parameters (those the prediction used).
        let state = st.update(y, u, |x, u| model.observe(x, u, &w_prior))?;

        // Parameter filter: Eq. 27 time update, then the measurement update through the model.
        let mut w = w_prior;
        let mut pw = self.pw;
        let d_fns = SpaceFns {
            mean: self.param_measurement_mean,
            residual: st.measurement_residual(),
        };
        let observation_noise = match self.param_noise {
            ParameterObservationNoise::MeasurementNoise => *st.measurement_noise(),
            ParameterObservationNoise::StateInnovation => *st.innovation_covariance(),
        };
        let (parameters, e) = self.parameter_update(
            &mut w,
            &mut pw,
            y,
            &d_fns,
            &observation_noise,
            MODEL_AT_POINT,
            |wi| {
                let xi = model.propagate(&x_prev, u, wi);
                model.observe(&xi, u, wi)
            },
        )?;

        model.commit(&w)?;
        self.w = w;
        self.pw = pw;
        self.param_innovation = e;
        Ok(DualOutcome {
            state_prediction_repair,
            state,
            parameters,
        })
    }

    /// One step with separate observations (module docs, "Separate observations"): the state filter
    /// predicts with `f(x, u, w)` and updates with the measurement `y` through `h(x, u, w)`, both at the
    /// prior parameters; then, if `observation` is given, the parameter filter forgets (Eq. 27) and updates
    /// with `d` through `Y(x̂, u, w)` at the state filter's new estimate `x̂`. A non-finite `y` leaves the
    /// state at its prediction; a non-finite `d` is rejected and leaves the parameters as they were (an
    /// observation refused by the parameter filter's NIS gate keeps the forgetting, as in [`Self::step`]).
    /// A step that returns an error changes nothing.
    pub fn step_separate<const ND: usize, F, H, Y>(
        &mut self,
        u: &SVector<f64, NU>,
        y: &SVector<f64, NY>,
        observation: Option<&ParameterObservation<ND>>,
        f: F,
        h: H,
        output: Y,
    ) -> Result<SeparateOutcome<ND>, EstimationError>
    where
        F: FnMut(&SVector<f64, NX>, &SVector<f64, NU>, &SVector<f64, NP>) -> SVector<f64, NX>,
        H: FnMut(&SVector<f64, NX>, &SVector<f64, NU>, &SVector<f64, NP>) -> SVector<f64, NY>,
        Y: FnMut(&SVector<f64, NX>, &SVector<f64, NU>, &SVector<f64, NP>) -> SVector<f64, ND>,
    {
        self.restored_on_error(|filter| filter.step_separate_inner(u, y, observation, f, h, output))
    }

    fn step_separate_inner<const ND: usize, F, H, Y>(
        &mut self,
        u: &SVector<f64, NU>,
        y: &SVector<f64, NY>,
        observation: Option<&ParameterObservation<ND>>,
        mut f: F,
        mut h: H,
        mut output: Y,
    ) -> Result<SeparateOutcome<ND>, EstimationError>
    where
        F: FnMut(&SVector<f64, NX>, &SVector<f64, NU>, &SVector<f64, NP>) -> SVector<f64, NX>,
        H: FnMut(&SVector<f64, NX>, &SVector<f64, NU>, &SVector<f64, NP>) -> SVector<f64, NY>,
        Y: FnMut(&SVector<f64, NX>, &SVector<f64, NU>, &SVector<f64, NP>) -> SVector<f64, ND>,
    {
        check_input(u)?;
        if let Some(obs) = observation {
            check_positive_semidefinite("P_e", &obs.noise)?;
        }
        let w_prior = self.w;
        let st = &mut self.state;
        let state_prediction_repair = st.predict(u, |x, u| f(x, u, &w_prior))?;
        let state = st.update(y, u, |x, u| h(x, u, &w_prior))?;

        let mut w = w_prior;
        let mut pw = self.pw;
        let mut parameter_innovation = SVector::<f64, ND>::zeros();
        let parameters = match observation {
            None => None,
            Some(obs) => match rejected_measurement(&obs.d) {
                Some(rejected) => Some(rejected),
                None => {
                    let x_post = *st.state();
                    let (outcome, e) = self.parameter_update(
                        &mut w,
                        &mut pw,
                        &obs.d,
                        &SpaceFns::default(),
                        &obs.noise,
                        "parameter observation function",
                        |wi| output(&x_post, u, wi),
                    )?;
                    if outcome.is_accepted() {
                        parameter_innovation = e;
                    }
                    Some(outcome)
                }
            },
        };
        self.w = w;
        self.pw = pw;
        Ok(SeparateOutcome {
            state_prediction_repair,
            state,
            parameters,
            parameter_innovation,
        })
    }

    /// Runs `step` on the filter and restores the state filter as it was when `step` fails (the parameters
    /// and the model are committed only at a step's end).
    fn restored_on_error<T>(
        &mut self,
        step: impl FnOnce(&mut Self) -> Result<T, EstimationError>,
    ) -> Result<T, EstimationError> {
        self.backup.clone_from(&self.state);
        let result = step(self);
        if result.is_err() {
            self.state.clone_from(&self.backup);
        }
        result
    }

    /// The parameter filter's step on an observation `d` (`what` names the observation function in errors): forgetting (Eq. 27, `P_w / λ`, repaired), sigma points
    /// of `w`, the observation predicted at each (`observe(w_i)`), and the Kalman correction of `(w, P_w)` with
    /// the observation noise `noise`. Returns the outcome and the innovation `e = d − d̂` (through `fns.residual`).
    #[allow(clippy::too_many_arguments)]
    fn parameter_update<const ND: usize>(
        &self,
        w: &mut SVector<f64, NP>,
        pw: &mut SMatrix<f64, NP, NP>,
        d: &SVector<f64, ND>,
        fns: &SpaceFns<ND, NSP>,
        noise: &SMatrix<f64, ND, ND>,
        what: &'static str,
        mut observe: impl FnMut(&SVector<f64, NP>) -> SVector<f64, ND>,
    ) -> Result<(UpdateOutcome, SVector<f64, ND>), EstimationError> {
        *pw /= self.forgetting;
        repair_covariance(pw, self.param_policy.eigen_floor, FILTER)?;
        let wpts = self.param_points.generate(w, pw)?;
        let ds = evaluate_points(what, |i| observe(&wpts.column(i).into_owned()))?;
        let (d_hat, mut sd, pwd, floor) = innovation_moments(
            &wpts,
            w,
            subtract::<NP>,
            &ds,
            fns,
            Some(noise),
            &self.param_points,
        );
        symmetrise(&mut sd);
        let e = (fns.residual)(d, &d_hat);
        let innovation = Innovation {
            e: &e,
            s: &sd,
            floor: &floor,
        };
        let (outcome, _) = kalman_correct(
            w,
            pw,
            innovation,
            &pwd,
            &self.param_points,
            &self.param_policy,
            FILTER,
        )?;
        Ok((outcome, e))
    }

    /// [`Self::step`] on a [`DiscreteModel`] + [`Parametric`] model, estimating its parameters `indices`
    /// (in the order of `w`). On success the model holds the new parameter estimate.
    pub fn step_parametric<M>(
        &mut self,
        model: &mut M,
        indices: [usize; NP],
        u: &SVector<f64, NU>,
        y: &SVector<f64, NY>,
    ) -> Result<DualOutcome, EstimationError>
    where
        M: DiscreteModel<NX, NU, NY> + Parametric,
    {
        let before = self.w;
        let mut adapter = ParametricDualModel::new(model, indices);
        let result = self.step(&mut adapter, u, y);
        if result.is_err() {
            // Leave the model at the estimate the filter still holds; a refusal here cannot happen because
            // that estimate was accepted before.
            let _ = adapter.set(&before);
        }
        result
    }

    /// The state estimate.
    pub fn state(&self) -> &SVector<f64, NX> {
        self.state.state()
    }

    /// The state error covariance.
    pub fn state_covariance(&self) -> &SMatrix<f64, NX, NX> {
        self.state.covariance()
    }

    /// The parameter estimate.
    pub fn parameters(&self) -> &SVector<f64, NP> {
        &self.w
    }

    /// The parameter error covariance.
    pub fn parameter_covariance(&self) -> &SMatrix<f64, NP, NP> {
        &self.pw
    }

    /// The forgetting factor `λ_RLS`.
    pub fn forgetting_factor(&self) -> f64 {
        self.forgetting
    }

    /// The state filter's innovation of the last finite measurement.
    pub fn innovation(&self) -> &SVector<f64, NY> {
        self.state.innovation()
    }

    /// The state filter's innovation covariance.
    pub fn innovation_covariance(&self) -> &SMatrix<f64, NY, NY> {
        self.state.innovation_covariance()
    }

    /// The parameter filter's innovation of the last accepted step.
    pub fn parameter_innovation(&self) -> &SVector<f64, NY> {
        &self.param_innovation
    }
}

#[cfg(test)]
mod tests;
