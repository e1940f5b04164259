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
    cholesky_lower, cholesky_psd, first_non_finite, givens_absorb, hyperbolic_downdate,
    solve_lower, solve_upper_transposed,
};
use super::fault::{
    CovarianceRepair, EstimationError, UpdateOutcome, check_additive_noise, check_estimate,
    repair_covariance,
};
use super::sigma::{ResidualFn, SigmaPoints, cross_covariance, rounding_floor};
use super::unscented::{
    FilterSettings, check_precision, check_state_mean, model_measurement, model_process,
    rejected_measurement, settings_methods, sigma_images,
};
use crate::model::DiscreteModel;
use nalgebra::{SMatrix, SVector};

const FILTER: &str = "square-root UKF";

/// A square-root UKF with `NX` states, `NU` inputs, `NY` measurements and `NS = 2 NX + 1` sigma points.
#[derive(Clone, Debug)]
pub struct SquareRootUkf<const NX: usize, const NU: usize, const NY: usize, const NS: usize> {
    settings: FilterSettings<NX, NX, NY, NS>,
    x: SVector<f64, NX>,
    s: SMatrix<f64, NX, NX>,
    sqrt_q: SMatrix<f64, NX, NX>,
    sqrt_r: SMatrix<f64, NY, NY>,
    innovation: SVector<f64, NY>,
    sqrt_innovation_cov: SMatrix<f64, NY, NY>,
}

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
        check_additive_noise(&q, &r)?;
        check_estimate(("x0", "P0"), &x0, &p0)?;
        let not_pd = |name| EstimationError::NotPositiveDefinite {
            name,
            kind: "definite",
        };
        Ok(SquareRootUkf {
            settings: FilterSettings::new(points, FILTER),
            x: x0,
            s: cholesky_lower(&p0).ok_or(not_pd("P0"))?,
            sqrt_q: cholesky_psd(&q).ok_or(not_pd("Q"))?,
            sqrt_r: cholesky_psd(&r).ok_or(not_pd("R"))?,
            innovation: SVector::zeros(),
            sqrt_innovation_cov: SMatrix::zeros(),
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
        let draw = || Ok(self.settings.points.generate_from_factor(&self.x, &self.s));
        let (_, prop) = sigma_images("process function", u, draw, f)?;
        let x = (self.settings.x_fns.mean)(&prop, self.settings.points.mean_weights());
        check_state_mean(&x)?;
        let x_residual = self.settings.x_fns.residual;
        let (s, repair) = self.factor_of_spread(&prop, &x, &self.sqrt_q, x_residual)?;
        let points = &self.settings.points;
        let floor = rounding_floor(
            &prop,
            &x,
            points.mean_weights(),
            points.covariance_weights(),
            x_residual,
        );
        let p = s * s.transpose();
        check_precision(&floor, &p, points, "predicted covariance", FILTER)?;
        self.x = x;
        self.s = s;
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
        let draw = || Ok(self.settings.points.generate_from_factor(&self.x, &self.s));
        let (chi, ys) = sigma_images("measurement function", u, draw, h)?;
        let settings = &self.settings;
        let y_hat = (settings.y_fns.mean)(&ys, settings.points.mean_weights());
        let singular = EstimationError::SingularInnovation { filter: FILTER };
        // A factor that needed a repair came from an innovation covariance that was not positive definite.
        let (sy, repair) = self
            .factor_of_spread(&ys, &y_hat, &self.sqrt_r, settings.y_fns.residual)
            .map_err(|_| singular.clone())?;
        if repair.is_some() {
            return Err(singular);
        }
        // A pivot of S_y S_yᵀ at or below the rounding of its diagonal: S is singular to working accuracy.
        let points = &settings.points;
        let mut floor = rounding_floor(
            &ys,
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
            &chi,
            &self.x,
            &ys,
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
        let mut s = self.s;
        let mut ok = true;
        for j in 0..NY {
            let mut col = u_mat.column(j).into_owned();
            if !hyperbolic_downdate(&mut s, &mut col) {
                ok = false;
                break;
            }
        }
        let repair = if ok {
            None
        } else {
            let mut p = self.s * self.s.transpose() - u_mat * u_mat.transpose();
            let (factor, repair) = self.refactor(&mut p)?;
            s = factor;
            repair
        };
        if first_non_finite(&x).is_some() {
            return Err(EstimationError::Overflow {
                filter: FILTER,
                quantity: "corrected state",
            });
        }
        self.x = x;
        self.s = s;
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

    /// The lower factor of `Σ W⁽ᶜ⁾ rᵢ rᵢᵀ + noise noiseᵀ` for residuals `rᵢ = residual(pointsᵢ, mean)`.
    fn factor_of_spread<const M: usize>(
        &self,
        pts: &SMatrix<f64, M, NS>,
        mean: &SVector<f64, M>,
        sqrt_noise: &SMatrix<f64, M, M>,
        residual: ResidualFn<M>,
    ) -> Result<(SMatrix<f64, M, M>, Option<CovarianceRepair>), EstimationError> {
        let wc = self.settings.points.covariance_weights();
        let mut l = *sqrt_noise;
        for i in 1..NS {
            let mut col = residual(&pts.column(i).into_owned(), mean) * wc[i].sqrt();
            givens_absorb(&mut l, &mut col);
        }
        let r0 = residual(&pts.column(0).into_owned(), mean);
        let w0 = wc[0];
        let mut col = r0 * w0.abs().sqrt();
        if w0 >= 0.0 {
            givens_absorb(&mut l, &mut col);
            return Ok((l, None));
        }
        let before = l;
        if hyperbolic_downdate(&mut l, &mut col) {
            return Ok((l, None));
        }
        let mut p = before * before.transpose() + r0 * r0.transpose() * w0;
        self.refactor(&mut p)
    }

    /// Repairs a covariance (reported only if it was not positive definite) and returns its lower factor.
    fn refactor<const M: usize>(
        &self,
        p: &mut SMatrix<f64, M, M>,
    ) -> Result<(SMatrix<f64, M, M>, Option<CovarianceRepair>), EstimationError> {
        let repair = repair_covariance(p, self.settings.policy.eigen_floor, FILTER)?;
        let l = cholesky_lower(p).or_else(|| cholesky_psd(p)).ok_or(
            EstimationError::NotPositiveDefinite {
                name: "square-root UKF covariance",
                kind: "semi-definite",
            },
        )?;
        Ok((l, repair))
    }

    /// The state estimate.
    pub fn state(&self) -> &SVector<f64, NX> {
        &self.x
    }

    /// The lower-triangular factor `S` of the covariance.
    pub fn covariance_factor(&self) -> &SMatrix<f64, NX, NX> {
        &self.s
    }

    /// The covariance `S Sᵀ`.
    pub fn covariance(&self) -> SMatrix<f64, NX, NX> {
        self.s * self.s.transpose()
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
