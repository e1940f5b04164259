//! The steps the unscented filters ([`super::ukf`], [`super::ukf_augmented`], [`super::srukf`],
//! [`super::dual_ukf`]) share, generic over the sizes of state, measurement and point set.
//!
//! - input checks: a non-finite input `u` is an error, a non-finite measurement `y` is a rejected update;
//! - [`evaluate_points_into`] (and [`evaluate_points`]): a model function at every sigma point, with the first non-finite output reported as
//!   [`EstimationError::NonFiniteModelOutput`];
//! - [`predicted_moments_into`]: `x̂⁻ = mean(χ*)`, `P⁻ = Σ W⁽ᶜ⁾ (χ*ᵢ − x̂⁻)(χ*ᵢ − x̂⁻)ᵀ (+ Q)`, repaired;
//! - [`innovation_moments`]: `ŷ = mean(Y)`, `S = Σ W⁽ᶜ⁾ (Yᵢ − ŷ)(Yᵢ − ŷ)ᵀ (+ R)`,
//!   `P_xy = Σ W⁽ᶜ⁾ (χᵢ − x̂)(Yᵢ − ŷ)ᵀ`;
//! - [`kalman_correct_in`] (and [`kalman_correct`], with its work matrices on the stack, for the dual UKF's
//!   small parameter filter): NIS and gate, `K = P_xy S⁻¹`, `x̂ += K e`, `P −= K S Kᵀ`, repaired;
//! - [`FilterSettings`]: what the filters are configured with (sigma points, mean and residual functions, fault
//!   policy), with the predict moments and the whole correction of a covariance-form filter as methods, and
//!   [`settings_methods`], the public methods that replace those settings.
//!
//! None of them allocates or panics, and each leaves the caller's estimate alone unless the whole step
//! succeeded. The `_into`/`_in` forms write their `N × NS` and `N × N` results into matrices the caller holds
//! (the filters' work spaces on the heap), so that a step of a large filter has none on the stack; the forms
//! that return matrices by value serve the square-root UKF and the dual UKF's parameter filter.

use super::dense::{cholesky_above_floor, cholesky_solve, first_non_finite, symmetrise};
use super::fault::{
    CovarianceRepair, EstimationError, FaultPolicy, RejectReason, UpdateOutcome,
    repair_covariance_in,
};
use super::sigma::{
    MeanFn, ResidualFn, SigmaPoints, cross_covariance, first_bad_column, rounding_floor, subtract,
    unscented_transform, unscented_transform_into, weighted_mean,
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
    eval: impl FnMut(usize) -> SVector<f64, N>,
) -> Result<SMatrix<f64, N, NS>, EstimationError> {
    let mut out = SMatrix::<f64, N, NS>::zeros();
    evaluate_points_into(function, eval, &mut out)?;
    Ok(out)
}

/// [`evaluate_points`] written into `out`.
pub(crate) fn evaluate_points_into<const N: usize, const NS: usize>(
    function: &'static str,
    mut eval: impl FnMut(usize) -> SVector<f64, N>,
    out: &mut SMatrix<f64, N, NS>,
) -> Result<(), EstimationError> {
    for i in 0..NS {
        out.set_column(i, &eval(i));
    }
    match first_bad_column(out) {
        Some(sigma_point) => Err(EstimationError::NonFiniteModelOutput {
            function,
            sigma_point,
        }),
        None => Ok(()),
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

/// The predicted mean and covariance of the propagated points `prop` (weights of `points`), plus the additive
/// process noise `q` if any; the covariance is repaired under `policy` (the repair is returned) before the mean
/// is checked. The covariance is written into `out.0`, and `out.1` is the repair's work matrix (contents of
/// both overwritten); returns the mean and the repair.
pub(crate) fn predicted_moments_into<const NP: usize, const NX: usize, const NS: usize>(
    prop: &SMatrix<f64, NX, NS>,
    points: &SigmaPoints<NP, NS>,
    fns: &SpaceFns<NX, NS>,
    q: Option<&SMatrix<f64, NX, NX>>,
    policy: &FaultPolicy,
    filter: &'static str,
    (p, work): (&mut SMatrix<f64, NX, NX>, &mut SMatrix<f64, NX, NX>),
) -> Result<(SVector<f64, NX>, Option<CovarianceRepair>), EstimationError> {
    let x = unscented_transform_into(
        prop,
        points.mean_weights(),
        points.covariance_weights(),
        fns.mean,
        fns.residual,
        p,
    );
    if let Some(q) = q {
        *p += q;
    }
    check_state_mean(&x)?;
    let floor = rounding_floor(
        prop,
        &x,
        points.mean_weights(),
        points.covariance_weights(),
        fns.residual,
    );
    check_precision(&floor, p, points, "predicted covariance", filter)?;
    let repair = repair_covariance_in(p, policy.eigen_floor, filter, work)?;
    Ok((x, repair))
}

/// Four significant digits: a covariance entry whose estimated rounding error exceeds this fraction of the
/// entry is refused. The estimate is built from bounds (the dot-product bound `NS ε Σ|W||Y|`, squared where
/// the mean's error enters the covariance), so it lies above the typical error; the walking study's dual UKF
/// with the paper's `α = 1e-3` estimates about 6e-8.
pub(crate) const PRECISION_LIMIT: f64 = 1e-4;

/// `Err(PrecisionLoss)` at the first diagonal entry of `cov` whose rounding estimate `floor` (from
/// [`rounding_floor`]) exceeds [`PRECISION_LIMIT`] of the entry.
pub(crate) fn check_precision<const NP: usize, const N: usize, const NS: usize>(
    floor: &SVector<f64, N>,
    cov: &SMatrix<f64, N, N>,
    points: &SigmaPoints<NP, NS>,
    quantity: &'static str,
    filter: &'static str,
) -> Result<(), EstimationError> {
    check_precision_of_diagonal(floor, &cov.diagonal(), points, quantity, filter)
}

/// [`check_precision`] given the diagonal of the covariance only.
pub(crate) fn check_precision_of_diagonal<const NP: usize, const N: usize, const NS: usize>(
    floor: &SVector<f64, N>,
    diagonal: &SVector<f64, N>,
    points: &SigmaPoints<NP, NS>,
    quantity: &'static str,
    filter: &'static str,
) -> Result<(), EstimationError> {
    for index in 0..N {
        if floor[index] == 0.0 {
            continue;
        }
        let relative_error = floor[index] / diagonal[index].abs();
        if relative_error > PRECISION_LIMIT || relative_error.is_nan() {
            return Err(EstimationError::PrecisionLoss {
                filter,
                quantity,
                index,
                relative_error,
                amplification: points.rounding_amplification(),
            });
        }
    }
    Ok(())
}

/// The moments of the measurement points: `ŷ`, `S`, `P_xy` and the rounding estimate of `diag S`.
pub(crate) type InnovationMoments<const NX: usize, const NY: usize> = (
    SVector<f64, NY>,
    SMatrix<f64, NY, NY>,
    SMatrix<f64, NX, NY>,
    SVector<f64, NY>,
);

/// The predicted measurement `ŷ`, its covariance `S` (plus the additive noise `r` if any; not symmetrised),
/// the cross covariance `P_xy` of the points `chi` (around `x`) and their measurements `ys`, and the rounding
/// estimate of `diag S` ([`rounding_floor`], plus the rounding of adding `r`).
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
) -> InnovationMoments<NX, NY> {
    let wc = points.covariance_weights();
    let (y_hat, mut s) =
        unscented_transform(ys, points.mean_weights(), wc, y_fns.mean, y_fns.residual);
    let mut floor = rounding_floor(ys, &y_hat, points.mean_weights(), wc, y_fns.residual);
    if let Some(r) = r {
        s += r;
        for j in 0..NY {
            floor[j] += f64::EPSILON * (s[(j, j)].abs() + r[(j, j)].abs());
        }
    }
    let pxy = cross_covariance(chi, x, ys, &y_hat, wc, x_residual, y_fns.residual);
    (y_hat, s, pxy, floor)
}

/// The innovation `e` and its covariance `S` with the rounding estimate `floor` of `diag S`, as the
/// correction needs them.
pub(crate) struct Innovation<'a, const M: usize> {
    pub e: &'a SVector<f64, M>,
    pub s: &'a SMatrix<f64, M, M>,
    pub floor: &'a SVector<f64, M>,
}

/// The Kalman correction shared by the unscented filters: `S` checked (a Cholesky pivot at or below its
/// rounding estimate means `S` is singular; a diagonal known to fewer than four digits is a precision
/// loss), NIS and gate, `K = P_xy S⁻¹`, `x += K e`, `P −= K S Kᵀ`, repair. `x` and `p` change only when the
/// measurement is accepted and no error occurs.
pub(crate) fn kalman_correct<const NP: usize, const N: usize, const M: usize, const NS: usize>(
    x: &mut SVector<f64, N>,
    p: &mut SMatrix<f64, N, N>,
    innovation: Innovation<'_, M>,
    pxy: &SMatrix<f64, N, M>,
    points: &SigmaPoints<NP, NS>,
    policy: &FaultPolicy,
    filter: &'static str,
) -> Result<(UpdateOutcome, Option<SMatrix<f64, N, M>>), EstimationError> {
    let scratch = (&mut SMatrix::zeros(), &mut SMatrix::zeros());
    kalman_correct_in(x, p, innovation, pxy, (points, policy, filter), scratch)
}

/// [`kalman_correct`] computing the new covariance in `scratch.0` (copied into `p` on acceptance) with
/// `scratch.1` as the repair's work matrix (contents of both overwritten).
pub(crate) fn kalman_correct_in<
    const NP: usize,
    const N: usize,
    const M: usize,
    const NS: usize,
>(
    x: &mut SVector<f64, N>,
    p: &mut SMatrix<f64, N, N>,
    innovation: Innovation<'_, M>,
    pxy: &SMatrix<f64, N, M>,
    (points, policy, filter): (&SigmaPoints<NP, NS>, &FaultPolicy, &'static str),
    (new_p, work): (&mut SMatrix<f64, N, N>, &mut SMatrix<f64, N, N>),
) -> Result<(UpdateOutcome, Option<SMatrix<f64, N, M>>), EstimationError> {
    let Innovation { e, s, floor } = innovation;
    let singular = EstimationError::SingularInnovation { filter };
    let ls = cholesky_above_floor(s, floor).ok_or(singular.clone())?;
    check_precision(floor, s, points, "innovation covariance", filter)?;
    let nis = e.dot(&cholesky_solve(&ls, e).ok_or(singular.clone())?);
    if !nis.is_finite() {
        return Err(EstimationError::Overflow {
            filter,
            quantity: "normalised innovation squared",
        });
    }
    if let Some(reason) = policy.gate(nis) {
        return Ok((UpdateOutcome::Rejected { reason }, None));
    }
    // K = P_xy S⁻¹  ⇔  Kᵀ = S⁻¹ P_xyᵀ.
    let k = cholesky_solve(&ls, &pxy.transpose())
        .ok_or(singular)?
        .transpose();
    let new_x = *x + k * e;
    // `P − (K S) Kᵀ`, entry by entry, each sum over the measurements in order (as the product would form it).
    let ks = k * s;
    for j in 0..N {
        for i in 0..N {
            let mut kskt = 0.0;
            for a in 0..M {
                kskt += ks[(i, a)] * k[(j, a)];
            }
            new_p[(i, j)] = p[(i, j)] - kskt;
        }
    }
    if first_non_finite(&new_x).is_some() {
        return Err(EstimationError::Overflow {
            filter,
            quantity: "corrected state",
        });
    }
    let repair = repair_covariance_in(new_p, policy.eigen_floor, filter, work)?;
    *x = new_x;
    p.copy_from(new_p);
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

/// The configuration an unscented filter carries besides its estimate and noise: the sigma points (over `NP`
/// dimensions: the state, or the augmented state), the mean and residual functions of the state (`NX`) and
/// measurement (`NY`) spaces, the fault policy, and the filter's name for its errors.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FilterSettings<const NP: usize, const NX: usize, const NY: usize, const NS: usize>
{
    pub points: SigmaPoints<NP, NS>,
    pub x_fns: SpaceFns<NX, NS>,
    pub y_fns: SpaceFns<NY, NS>,
    pub policy: FaultPolicy,
    pub filter: &'static str,
}

/// What [`FilterSettings::correct`] found: the outcome, the gain when the measurement was accepted, and the
/// innovation `e = y − ŷ` and its covariance `S` (kept by the filters even for a gated measurement).
pub(crate) struct Correction<const NX: usize, const NY: usize> {
    pub outcome: UpdateOutcome,
    pub gain: Option<SMatrix<f64, NX, NY>>,
    pub innovation: SVector<f64, NY>,
    pub innovation_cov: SMatrix<f64, NY, NY>,
}

impl<const NP: usize, const NX: usize, const NY: usize, const NS: usize>
    FilterSettings<NP, NX, NY, NS>
{
    /// The points `points` with plain means and residuals and the default fault policy.
    pub fn new(points: SigmaPoints<NP, NS>, filter: &'static str) -> Self {
        FilterSettings {
            points,
            x_fns: SpaceFns::default(),
            y_fns: SpaceFns::default(),
            policy: FaultPolicy::default(),
            filter,
        }
    }

    /// [`predicted_moments_into`] of the propagated points `prop` with these settings.
    pub fn predicted_into(
        &self,
        prop: &SMatrix<f64, NX, NS>,
        q: Option<&SMatrix<f64, NX, NX>>,
        out: (&mut SMatrix<f64, NX, NX>, &mut SMatrix<f64, NX, NX>),
    ) -> Result<(SVector<f64, NX>, Option<CovarianceRepair>), EstimationError> {
        let (points, fns, policy) = (&self.points, &self.x_fns, &self.policy);
        predicted_moments_into(prop, points, fns, q, policy, self.filter, out)
    }

    /// The measurement correction of a covariance-form filter at the estimate `(x, p)`: [`innovation_moments`]
    /// of the points `chi` and their measurements `ys` (plus `r` if the noise is additive), `S` symmetrised,
    /// `e = residual(y, ŷ)`, then [`kalman_correct_in`] with the new covariance and the repair's work matrix
    /// in `scratch`, which changes `x` and `p` only on acceptance.
    pub fn correct_in(
        &self,
        x: &mut SVector<f64, NX>,
        p: &mut SMatrix<f64, NX, NX>,
        (chi, ys, y): (
            &SMatrix<f64, NX, NS>,
            &SMatrix<f64, NY, NS>,
            &SVector<f64, NY>,
        ),
        r: Option<&SMatrix<f64, NY, NY>>,
        scratch: (&mut SMatrix<f64, NX, NX>, &mut SMatrix<f64, NX, NX>),
    ) -> Result<Correction<NX, NY>, EstimationError> {
        let (y_hat, mut s, pxy, floor) = innovation_moments(
            chi,
            x,
            self.x_fns.residual,
            ys,
            &self.y_fns,
            r,
            &self.points,
        );
        symmetrise(&mut s);
        let e = (self.y_fns.residual)(y, &y_hat);
        let innovation = Innovation {
            e: &e,
            s: &s,
            floor: &floor,
        };
        let settings = (&self.points, &self.policy, self.filter);
        let (outcome, gain) = kalman_correct_in(x, p, innovation, &pxy, settings, scratch)?;
        Ok(Correction {
            outcome,
            gain,
            innovation: e,
            innovation_cov: s,
        })
    }
}

/// The public methods by which every unscented filter replaces its [`FilterSettings`] (the field `settings`):
/// the state and measurement mean and residual functions (for angles: a circular mean and a wrapped residual;
/// the update adds `K e` to the state, so a wrapping state mean function should also wrap its output) and the
/// fault policy. Expanded inside an `impl` block whose const parameters include `NX`, `NY` and `NS`.
macro_rules! settings_methods {
    () => {
        /// Replaces the state mean and residual functions (for angle states).
        pub fn with_state_functions(
            mut self,
            mean: $crate::estimation::sigma::MeanFn<NX, NS>,
            residual: $crate::estimation::sigma::ResidualFn<NX>,
        ) -> Self {
            self.settings.x_fns = $crate::estimation::unscented::SpaceFns { mean, residual };
            self
        }

        /// Replaces the measurement mean and residual functions (for angle measurements).
        pub fn with_measurement_functions(
            mut self,
            mean: $crate::estimation::sigma::MeanFn<NY, NS>,
            residual: $crate::estimation::sigma::ResidualFn<NY>,
        ) -> Self {
            self.settings.y_fns = $crate::estimation::unscented::SpaceFns { mean, residual };
            self
        }

        /// Replaces the fault policy (NIS gate, eigenvalue floor).
        pub fn set_fault_policy(
            &mut self,
            policy: $crate::estimation::fault::FaultPolicy,
        ) -> Result<(), $crate::estimation::fault::EstimationError> {
            policy.validate()?;
            self.settings.policy = policy;
            Ok(())
        }
    };
}
pub(crate) use settings_methods;
