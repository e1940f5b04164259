//! The square-root UKF (van der Merwe and Wan 2001) with additive noise: the same estimator as
//! [`super::ukf::UnscentedKalmanFilter`], but it carries a lower-triangular factor `S` with `S Sᵀ = P` instead
//! of `P`, so the covariance stays symmetric positive semi-definite by construction.
//!
//! Predict: points `x̂, x̂ ± γ Sᵢ`; `χ*ᵢ = f(χᵢ, u)`; `x̂⁻ = mean(χ*)`;
//! `S⁻ = qr([√W₁⁽ᶜ⁾ (χ*₁…₂ₗ − x̂⁻), √Q])` followed by `cholupdate(S⁻, χ*₀ − x̂⁻, W₀⁽ᶜ⁾)` (a downdate when
//! `W₀⁽ᶜ⁾ < 0`). The "qr" is done as a sequence of Givens rotations that absorb each weighted column into the
//! triangular factor started from `√Q` (`dense::givens_absorb`), which is the R factor of the QR
//! decomposition of the stacked matrix without forming it (its width `3L` is not expressible as a const
//! generic).
//!
//! Update: points redrawn from `(x̂⁻, S⁻)` as in the plain UKF; `S_y` from the measurement residuals and `√R`
//! in the same way; `P_xy` as in the UKF; `K = (P_xy / S_yᵀ) / S_y`; `x̂ = x̂⁻ + K e`; and
//! `S = cholupdate(S⁻, K S_y, −1)`, one downdate per column.
//!
//! A downdate that would leave the factor indefinite (rounding, or a huge negative `W₀⁽ᶜ⁾` with a tiny `α`)
//! falls back to forming the covariance, repairing it as in [`super::fault`] and refactoring it; the repair is
//! reported.

use super::dense::{
    cholesky_lower_into, cholesky_psd_into, first_non_finite, givens_absorb, hyperbolic_downdate,
    solve_lower, solve_upper_transposed,
};
use super::fault::{
    CovarianceRepair, EstimationError, UpdateOutcome, check_additive_noise, check_estimate,
    repair_covariance_in,
};
use super::sigma::{ResidualFn, SigmaPoints, cross_covariance, rounding_floor};
use super::unscented::{
    FilterSettings, check_input, check_precision, check_precision_of_diagonal, check_state_mean,
    evaluate_points_into, model_measurement, model_process, rejected_measurement, settings_methods,
};
use crate::matrix::{boxed_copy, zeroed_box};
use crate::model::DiscreteModel;
use nalgebra::{SMatrix, SVector};

const FILTER: &str = "square-root UKF";

/// A square-root UKF with `NX` states, `NU` inputs, `NY` measurements and `NS = 2 NX + 1` sigma points.
///
/// The factors `S` and `√Q` and the work space of a step are kept on the heap, allocated by the constructor,
/// and a step declares no `NX × NX` or `NX × NS` value: a filter of any size runs on any thread.
#[derive(Debug)]
pub struct SquareRootUkf<const NX: usize, const NU: usize, const NY: usize, const NS: usize> {
    settings: FilterSettings<NX, NX, NY, NS>,
    x: SVector<f64, NX>,
    s: Box<SMatrix<f64, NX, NX>>,
    sqrt_q: Box<SMatrix<f64, NX, NX>>,
    sqrt_r: SMatrix<f64, NY, NY>,
    innovation: SVector<f64, NY>,
    sqrt_innovation_cov: SMatrix<f64, NY, NY>,
    work: Box<SquareRootWork<NX, NY, NS>>,
}

/// The matrices a step writes before it commits; their contents between steps mean nothing.
#[derive(Debug)]
struct SquareRootWork<const NX: usize, const NY: usize, const NS: usize> {
    chi: SMatrix<f64, NX, NS>,
    propagated: SMatrix<f64, NX, NS>,
    measured: SMatrix<f64, NY, NS>,
    /// The factor being computed.
    next_s: SMatrix<f64, NX, NX>,
    /// Matrices of the fallbacks: a factor kept before a downdate, a covariance to repair and refactor, and
    /// the repair's work matrix.
    kept: SMatrix<f64, NX, NX>,
    p: SMatrix<f64, NX, NX>,
    repair: SMatrix<f64, NX, NX>,
}

// SAFETY: `SMatrix<f64, _, _>` fields only (arrays of `f64`), for which all-zero bytes are `0.0`.
unsafe impl<const NX: usize, const NY: usize, const NS: usize> bytemuck::Zeroable
    for SquareRootWork<NX, NY, NS>
{
}

impl<const NX: usize, const NU: usize, const NY: usize, const NS: usize> Clone
    for SquareRootUkf<NX, NU, NY, NS>
{
    fn clone(&self) -> Self {
        SquareRootUkf {
            s: boxed_copy(&self.s),
            sqrt_q: boxed_copy(&self.sqrt_q),
            work: bytemuck::zeroed_box(),
            ..*self
        }
    }
}

/// The work matrices of [`factor_of_spread`] and [`refactor`]: the factor kept before a downdate, the
/// covariance of a fallback, the repair's work matrix.
type Fallback<'a, const M: usize> = (
    &'a mut SMatrix<f64, M, M>,
    &'a mut SMatrix<f64, M, M>,
    &'a mut SMatrix<f64, M, M>,
);

impl<const NX: usize, const NU: usize, const NY: usize, const NS: usize>
    SquareRootUkf<NX, NU, NY, NS>
{
    /// Built from covariances, which are factored here (`q` may be singular).
    pub fn new(
        points: SigmaPoints<NX, NS>,
        q: SMatrix<f64, NX, NX>,
        r: SMatrix<f64, NY, NY>,
        x0: SVector<f64, NX>,
        p0: SMatrix<f64, NX, NX>,
    ) -> Result<Self, EstimationError> {
        Self::from_refs(points, &q, &r, &x0, &p0)
    }

    /// [`Self::new`] from borrowed matrices (for a model whose matrices do not fit the stack); the factors
    /// are computed on the heap.
    pub fn from_refs(
        points: SigmaPoints<NX, NS>,
        q: &SMatrix<f64, NX, NX>,
        r: &SMatrix<f64, NY, NY>,
        x0: &SVector<f64, NX>,
        p0: &SMatrix<f64, NX, NX>,
    ) -> Result<Self, EstimationError> {
        check_additive_noise(q, r)?;
        check_estimate(("x0", "P0"), x0, p0)?;
        let not_pd = |name| EstimationError::NotPositiveDefinite {
            name,
            kind: "definite",
        };
        let (mut s, mut sqrt_q) = (zeroed_box::<NX, NX>(), zeroed_box::<NX, NX>());
        let mut sqrt_r = SMatrix::<f64, NY, NY>::zeros();
        if !cholesky_lower_into(p0, &mut s) {
            return Err(not_pd("P0"));
        }
        if !cholesky_psd_into(q, &mut sqrt_q) {
            return Err(not_pd("Q"));
        }
        if !cholesky_psd_into(r, &mut sqrt_r) {
            return Err(not_pd("R"));
        }
        Ok(SquareRootUkf {
            settings: FilterSettings::new(points, FILTER),
            x: *x0,
            s,
            sqrt_q,
            sqrt_r,
            innovation: SVector::zeros(),
            sqrt_innovation_cov: SMatrix::zeros(),
            work: bytemuck::zeroed_box(),
        })
    }

    settings_methods!();

    /// The time update through `f(x, u)`.
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
        let settings = &self.settings;
        let w = &mut *self.work;
        settings
            .points
            .generate_from_factor_into(&self.x, &self.s, &mut w.chi);
        let chi = &w.chi;
        let propagate = |i: usize| f(&chi.column(i).into_owned(), u);
        evaluate_points_into("process function", propagate, &mut w.propagated)?;
        let prop = &w.propagated;
        let x = (settings.x_fns.mean)(prop, settings.points.mean_weights());
        check_state_mean(&x)?;
        let x_residual = settings.x_fns.residual;
        let spread = (prop, &x, &*self.sqrt_q, x_residual);
        let fallback = (&mut w.kept, &mut w.p, &mut w.repair);
        let repair = factor_of_spread(settings, spread, &mut w.next_s, fallback)?;
        let points = &settings.points;
        let floor = rounding_floor(
            prop,
            &x,
            points.mean_weights(),
            points.covariance_weights(),
            x_residual,
        );
        let diagonal = outer_diagonal(&w.next_s);
        check_precision_of_diagonal(&floor, &diagonal, points, "predicted covariance", FILTER)?;
        self.x = x;
        self.s.copy_from(&w.next_s);
        Ok(repair)
    }

    /// The measurement update with `y` and `h(x, u)`.
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
        let settings = &self.settings;
        let w = &mut *self.work;
        settings
            .points
            .generate_from_factor_into(&self.x, &self.s, &mut w.chi);
        let chi = &w.chi;
        let measure = |i: usize| h(&chi.column(i).into_owned(), u);
        evaluate_points_into("measurement function", measure, &mut w.measured)?;
        let (chi, ys) = (&w.chi, &w.measured);
        let y_hat = (settings.y_fns.mean)(ys, settings.points.mean_weights());
        let singular = EstimationError::SingularInnovation { filter: FILTER };
        // A factor that needed a repair came from an innovation covariance that was not positive definite.
        let mut sy = SMatrix::<f64, NY, NY>::zeros();
        let small = &mut (SMatrix::zeros(), SMatrix::zeros(), SMatrix::zeros());
        let spread = (ys, &y_hat, &self.sqrt_r, settings.y_fns.residual);
        let fallback = (&mut small.0, &mut small.1, &mut small.2);
        let repair =
            factor_of_spread(settings, spread, &mut sy, fallback).map_err(|_| singular.clone())?;
        if repair.is_some() {
            return Err(singular);
        }
        // A pivot of S_y S_yᵀ at or below the rounding of its diagonal: S is singular to working accuracy.
        let points = &settings.points;
        let mut floor = rounding_floor(
            ys,
            &y_hat,
            points.mean_weights(),
            points.covariance_weights(),
            settings.y_fns.residual,
        );
        let r = self.sqrt_r * self.sqrt_r.transpose();
        for j in 0..NY {
            floor[j] += f64::EPSILON * r[(j, j)];
        }
        let at_floor = |i: usize| {
            let pivot = sy[(i, i)] * sy[(i, i)];
            pivot <= floor[i] || pivot.is_nan() || floor[i].is_nan()
        };
        if (0..NY).any(at_floor) {
            return Err(singular);
        }
        let s_y = sy * sy.transpose();
        check_precision(&floor, &s_y, points, "innovation covariance", FILTER)?;
        let pxy = cross_covariance(
            chi,
            &self.x,
            ys,
            &y_hat,
            settings.points.covariance_weights(),
            settings.x_fns.residual,
            settings.y_fns.residual,
        );
        let e = (settings.y_fns.residual)(y, &y_hat);
        let whitened = solve_lower(&sy, &e).ok_or(singular.clone())?;
        let nis = whitened.norm_squared();
        if !nis.is_finite() {
            return Err(EstimationError::Overflow {
                filter: FILTER,
                quantity: "normalised innovation squared",
            });
        }
        self.innovation = e;
        self.sqrt_innovation_cov = sy;
        if let Some(reason) = settings.policy.gate(nis) {
            return Ok(UpdateOutcome::Rejected { reason });
        }
        // K = P_xy (S_y S_yᵀ)⁻¹  ⇔  Kᵀ = S_y⁻ᵀ S_y⁻¹ P_xyᵀ.
        let k = solve_lower(&sy, &pxy.transpose())
            .and_then(|z| solve_upper_transposed(&sy, &z))
            .ok_or(singular)?
            .transpose();
        let x = self.x + k * e;
        let u_mat = k * sy;
        let s = &mut w.next_s;
        s.copy_from(&self.s);
        let mut ok = true;
        for j in 0..NY {
            let mut col = u_mat.column(j).into_owned();
            if !hyperbolic_downdate(s, &mut col) {
                ok = false;
                break;
            }
        }
        let repair = if ok {
            None
        } else {
            // `S Sᵀ − U Uᵀ`, each product summed as it would be formed.
            let p = &mut w.p;
            outer_product_into(&self.s, p);
            for j in 0..NX {
                for i in 0..NX {
                    let mut uut = 0.0;
                    for a in 0..NY {
                        uut += u_mat[(i, a)] * u_mat[(j, a)];
                    }
                    p[(i, j)] -= uut;
                }
            }
            refactor(settings, p, s, &mut w.repair)?
        };
        if first_non_finite(&x).is_some() {
            return Err(EstimationError::Overflow {
                filter: FILTER,
                quantity: "corrected state",
            });
        }
        self.x = x;
        self.s.copy_from(&w.next_s);
        Ok(UpdateOutcome::Accepted { nis, repair })
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

    /// The lower-triangular factor `S` of the covariance.
    pub fn covariance_factor(&self) -> &SMatrix<f64, NX, NX> {
        &self.s
    }

    /// The covariance `S Sᵀ`, on the heap.
    pub fn covariance(&self) -> Box<SMatrix<f64, NX, NX>> {
        let mut p = zeroed_box::<NX, NX>();
        outer_product_into(&self.s, &mut p);
        p
    }

    /// The innovation of the last finite measurement.
    pub fn innovation(&self) -> &SVector<f64, NY> {
        &self.innovation
    }

    /// The innovation covariance `S_y S_yᵀ` of the last finite measurement.
    pub fn innovation_covariance(&self) -> SMatrix<f64, NY, NY> {
        self.sqrt_innovation_cov * self.sqrt_innovation_cov.transpose()
    }
}

/// The points, their mean, the factor of the additive noise and the residual function whose spread
/// [`factor_of_spread`] factors.
type Spread<'a, const M: usize, const NS: usize> = (
    &'a SMatrix<f64, M, NS>,
    &'a SVector<f64, M>,
    &'a SMatrix<f64, M, M>,
    ResidualFn<M>,
);

/// Writes into `l` the lower factor of `Σ W⁽ᶜ⁾ rᵢ rᵢᵀ + noise noiseᵀ` for residuals `rᵢ = residual(pointsᵢ,
/// mean)`, with the work matrices of its fallback in `fallback`.
fn factor_of_spread<const NX: usize, const NY: usize, const M: usize, const NS: usize>(
    settings: &FilterSettings<NX, NX, NY, NS>,
    (pts, mean, sqrt_noise, residual): Spread<'_, M, NS>,
    l: &mut SMatrix<f64, M, M>,
    (kept, p, work): Fallback<'_, M>,
) -> Result<Option<CovarianceRepair>, EstimationError> {
    let wc = settings.points.covariance_weights();
    l.copy_from(sqrt_noise);
    for i in 1..NS {
        let mut col = residual(&pts.column(i).into_owned(), mean) * wc[i].sqrt();
        givens_absorb(l, &mut col);
    }
    let r0 = residual(&pts.column(0).into_owned(), mean);
    let w0 = wc[0];
    let mut col = r0 * w0.abs().sqrt();
    if w0 >= 0.0 {
        givens_absorb(l, &mut col);
        return Ok(None);
    }
    kept.copy_from(l);
    if hyperbolic_downdate(l, &mut col) {
        return Ok(None);
    }
    // `K Kᵀ + (r₀ r₀ᵀ) W₀` from the factor kept before the downdate, entry by entry as the products form it.
    outer_product_into(kept, p);
    for j in 0..M {
        for i in 0..M {
            p[(i, j)] += r0[i] * r0[j] * w0;
        }
    }
    refactor(settings, p, l, work)
}

/// Repairs the covariance `p` (reported only if it was not positive definite) and writes its lower factor
/// into `l`; `work` is the repair's work matrix.
fn refactor<const NX: usize, const NY: usize, const M: usize, const NS: usize>(
    settings: &FilterSettings<NX, NX, NY, NS>,
    p: &mut SMatrix<f64, M, M>,
    l: &mut SMatrix<f64, M, M>,
    work: &mut SMatrix<f64, M, M>,
) -> Result<Option<CovarianceRepair>, EstimationError> {
    let repair = repair_covariance_in(p, settings.policy.eigen_floor, FILTER, work)?;
    l.fill(0.0);
    if cholesky_lower_into(p, l) {
        return Ok(repair);
    }
    l.fill(0.0);
    if cholesky_psd_into(p, l) {
        return Ok(repair);
    }
    Err(EstimationError::NotPositiveDefinite {
        name: "square-root UKF covariance",
        kind: "semi-definite",
    })
}

/// `S Sᵀ` written into `out`, each entry summed over the columns of `S` in order (as the product forms it).
fn outer_product_into<const N: usize>(s: &SMatrix<f64, N, N>, out: &mut SMatrix<f64, N, N>) {
    for j in 0..N {
        for i in 0..N {
            let mut sum = 0.0;
            for k in 0..N {
                sum += s[(i, k)] * s[(j, k)];
            }
            out[(i, j)] = sum;
        }
    }
}

/// The diagonal of `S Sᵀ`, summed as [`outer_product_into`] sums it.
fn outer_diagonal<const N: usize>(s: &SMatrix<f64, N, N>) -> SVector<f64, N> {
    SVector::from_fn(|i, _| {
        let mut sum = 0.0;
        for k in 0..N {
            sum += s[(i, k)] * s[(i, k)];
        }
        sum
    })
}
