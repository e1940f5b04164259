//! The steps the unscented filters ([`super::ukf`], [`super::ukf_augmented`], [`super::srukf`],
//! [`super::dual_ukf`]) share, generic over the sizes of state, measurement and point set.
//!
//! - input checks: a non-finite input `u` is an error, a non-finite measurement `y` is a rejected update;
//! - [`evaluate_points`]: a model function at every sigma point, with the first non-finite output reported as
//!   [`EstimationError::NonFiniteModelOutput`];
//! - [`predicted_moments`]: `x̂⁻ = mean(χ*)`, `P⁻ = Σ W⁽ᶜ⁾ (χ*ᵢ − x̂⁻)(χ*ᵢ − x̂⁻)ᵀ (+ Q)`, repaired;
//! - [`innovation_moments`]: `ŷ = mean(Y)`, `S = Σ W⁽ᶜ⁾ (Yᵢ − ŷ)(Yᵢ − ŷ)ᵀ (+ R)`,
//!   `P_xy = Σ W⁽ᶜ⁾ (χᵢ − x̂)(Yᵢ − ŷ)ᵀ`;
//! - [`kalman_correct`]: NIS and gate, `K = P_xy S⁻¹`, `x̂ += K e`, `P −= K S Kᵀ`, repaired.
//!
//! None of them allocates or panics; each returns its results by value so that the caller commits only when
//! the whole step succeeded.

use super::dense::{cholesky_lower, cholesky_solve, first_non_finite};
use super::fault::{
    CovarianceRepair, EstimationError, FaultPolicy, RejectReason, UpdateOutcome, repair_covariance,
};
use super::sigma::{
    MeanFn, ResidualFn, SigmaPoints, cross_covariance, first_bad_column, subtract,
    unscented_transform, weighted_mean,
};
use crate::model::DiscreteModel;
use nalgebra::{SMatrix, SVector};

/// The mean and residual functions of one space (state or measurement) of `N` entries over `NS` points.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SpaceFns<const N: usize, const NS: usize> {
    pub mean: MeanFn<N, NS>,
    pub residual: ResidualFn<N>,
}

impl<const N: usize, const NS: usize> Default for SpaceFns<N, NS> {
    /// The plain weighted mean and difference (no wrapped entries).
    fn default() -> Self {
        SpaceFns {
            mean: weighted_mean::<N, NS>,
            residual: subtract::<N>,
        }
    }
}

/// `Err(NonFiniteInput)` at the first non-finite entry of the input `u`.
pub(crate) fn check_input<const NU: usize>(u: &SVector<f64, NU>) -> Result<(), EstimationError> {
    match first_non_finite(u) {
        Some(index) => Err(EstimationError::NonFiniteInput { index }),
        None => Ok(()),
    }
}

/// The rejected outcome of a measurement `y` with a non-finite entry, `None` when `y` is finite.
pub(crate) fn rejected_measurement<const NY: usize>(y: &SVector<f64, NY>) -> Option<UpdateOutcome> {
    first_non_finite(y).map(|index| UpdateOutcome::Rejected {
        reason: RejectReason::NonFiniteMeasurement { index },
    })
}

/// The columns `eval(0) … eval(NS − 1)`; a non-finite column is an error naming `function` and the point.
pub(crate) fn evaluate_points<const N: usize, const NS: usize>(
    function: &'static str,
    mut eval: impl FnMut(usize) -> SVector<f64, N>,
) -> Result<SMatrix<f64, N, NS>, EstimationError> {
    let mut out = SMatrix::<f64, N, NS>::zeros();
    for i in 0..NS {
        out.set_column(i, &eval(i));
    }
    match first_bad_column(&out) {
        Some(sigma_point) => Err(EstimationError::NonFiniteModelOutput {
            function,
            sigma_point,
        }),
        None => Ok(out),
    }
}

/// `Err` when the state mean function gave a non-finite mean.
pub(crate) fn check_state_mean<const N: usize>(x: &SVector<f64, N>) -> Result<(), EstimationError> {
    match first_non_finite(x) {
        Some(_) => Err(EstimationError::NonFiniteModelOutput {
            function: "state mean function",
            sigma_point: 0,
        }),
        None => Ok(()),
    }
}

/// A predicted mean, its covariance and the repair the covariance needed.
pub(crate) type Prediction<const NX: usize> = (
    SVector<f64, NX>,
    SMatrix<f64, NX, NX>,
    Option<CovarianceRepair>,
);

/// The predicted mean and covariance of the propagated points `prop` (weights of `points`), plus the additive
/// process noise `q` if any; the covariance is repaired under `policy` (the repair is returned) before the mean
/// is checked.
pub(crate) fn predicted_moments<const NP: usize, const NX: usize, const NS: usize>(
    prop: &SMatrix<f64, NX, NS>,
    points: &SigmaPoints<NP, NS>,
    fns: &SpaceFns<NX, NS>,
    q: Option<&SMatrix<f64, NX, NX>>,
    policy: &FaultPolicy,
    filter: &'static str,
) -> Result<Prediction<NX>, EstimationError> {
    let (x, mut p) = unscented_transform(
        prop,
        points.mean_weights(),
        points.covariance_weights(),
        fns.mean,
        fns.residual,
    );
    if let Some(q) = q {
        p += q;
    }
    let repair = repair_covariance(&mut p, policy.eigen_floor, filter)?;
    check_state_mean(&x)?;
    Ok((x, p, repair))
}

/// The predicted measurement `ŷ`, its covariance `S` (plus the additive noise `r` if any; not symmetrised)
/// and the cross covariance `P_xy` of the points `chi` (around `x`) and their measurements `ys`.
pub(crate) fn innovation_moments<
    const NP: usize,
    const NX: usize,
    const NY: usize,
    const NS: usize,
>(
    chi: &SMatrix<f64, NX, NS>,
    x: &SVector<f64, NX>,
    x_residual: ResidualFn<NX>,
    ys: &SMatrix<f64, NY, NS>,
    y_fns: &SpaceFns<NY, NS>,
    r: Option<&SMatrix<f64, NY, NY>>,
    points: &SigmaPoints<NP, NS>,
) -> (SVector<f64, NY>, SMatrix<f64, NY, NY>, SMatrix<f64, NX, NY>) {
    let wc = points.covariance_weights();
    let (y_hat, mut s) =
        unscented_transform(ys, points.mean_weights(), wc, y_fns.mean, y_fns.residual);
    if let Some(r) = r {
        s += r;
    }
    let pxy = cross_covariance(chi, x, ys, &y_hat, wc, x_residual, y_fns.residual);
    (y_hat, s, pxy)
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

/// A [`DiscreteModel`]'s `step` as a process function `f(x, u)`.
pub(crate) fn model_process<const NX: usize, const NU: usize, const NY: usize>(
    model: &impl DiscreteModel<NX, NU, NY>,
) -> impl FnMut(&SVector<f64, NX>, &SVector<f64, NU>) -> SVector<f64, NX> + '_ {
    move |x, u| {
        let mut next = SVector::zeros();
        model.step(x, u, &mut next);
        next
    }
}

/// A [`DiscreteModel`]'s `outputs` as a measurement function `h(x, u)`.
pub(crate) fn model_measurement<const NX: usize, const NU: usize, const NY: usize>(
    model: &impl DiscreteModel<NX, NU, NY>,
) -> impl FnMut(&SVector<f64, NX>, &SVector<f64, NU>) -> SVector<f64, NY> + '_ {
    move |x, u| {
        let mut out = SVector::zeros();
        model.outputs(x, u, &mut out);
        out
    }
}
