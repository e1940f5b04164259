//! The UKF with non-additive noise (paper 000, Eqs. 7, 10, 11; Wan and van der Merwe 2000, Algorithm 3.1).
//!
//! Model: `x[k+1] = f(x[k], u[k], v[k])`, `y[k] = h(x[k], u[k], n[k])`, `v ~ N(0, Q)` (`NV` entries),
//! `n ~ N(0, R)` (`NN` entries). The state is augmented to `xᵃ = [x; v; n]` of size `NA = NX + NV + NN` with
//! covariance `blkdiag(P, Q, R)`, and one set of `NS = 2 NA + 1` sigma points carries state and noise:
//!
//! - predict: draw `χᵃ` from `([x̂; 0; 0], blkdiag(P, Q, R))`; `χ*ᵢ = f(χˣᵢ, u, χᵛᵢ)`; `x̂⁻ = mean(χ*)`,
//!   `P⁻ = Σ W⁽ᶜ⁾ (χ*ᵢ − x̂⁻)(χ*ᵢ − x̂⁻)ᵀ` (no `+ Q`: the noise went through `f`);
//! - update: `Yᵢ = h(χ*ᵢ, u, χⁿᵢ)` with the points of the same draw, `S = Σ W⁽ᶜ⁾ (Yᵢ − ŷ)(Yᵢ − ŷ)ᵀ` (no `+ R`),
//!   `P_xy`, `K`, `x̂`, `P` as in the additive filter.
//!
//! When `update` is called without a `predict` since the last update, the points are drawn afresh from
//! `(x̂, P)` and the noise covariances.
//!
//! `NA` and `NS` are const parameters because stable Rust cannot compute them; wrong values are compile
//! errors.

use super::fault::{
    CovarianceRepair, EstimationError, UpdateOutcome, check_estimate, check_positive_definite,
};
use super::sigma::SigmaPoints;
use super::unscented::{
    FilterSettings, check_input, evaluate_points, rejected_measurement, settings_methods,
};
use nalgebra::{SMatrix, SVector};

const FILTER: &str = "augmented UKF";

/// A UKF with non-additive process noise (`NV` entries) and measurement noise (`NN` entries).
#[derive(Clone, Debug)]
pub struct AugmentedUkf<
    const NX: usize,
    const NU: usize,
    const NY: usize,
    const NV: usize,
    const NN: usize,
    const NA: usize,
    const NS: usize,
> {
    settings: FilterSettings<NA, NX, NY, NS>,
    x: SVector<f64, NX>,
    p: SMatrix<f64, NX, NX>,
    q: SMatrix<f64, NV, NV>,
    r: SMatrix<f64, NN, NN>,
    /// Propagated state parts of the last predict's points.
    propagated: SMatrix<f64, NX, NS>,
    /// Measurement-noise parts of the last predict's points.
    meas_noise: SMatrix<f64, NN, NS>,
    fresh: bool,
    innovation: SVector<f64, NY>,
    innovation_cov: SMatrix<f64, NY, NY>,
}

impl<
    const NX: usize,
    const NU: usize,
    const NY: usize,
    const NV: usize,
    const NN: usize,
    const NA: usize,
    const NS: usize,
> AugmentedUkf<NX, NU, NY, NV, NN, NA, NS>
{
    const SIZE_CHECK: () = assert!(NA == NX + NV + NN, "NA must equal NX + NV + NN");

    /// `q` and `r` must be positive definite (a noise entry with zero variance should be left out of the
    /// model instead), `p0` positive definite.
    pub fn new(
        points: SigmaPoints<NA, NS>,
        q: SMatrix<f64, NV, NV>,
        r: SMatrix<f64, NN, NN>,
        x0: SVector<f64, NX>,
        p0: SMatrix<f64, NX, NX>,
    ) -> Result<Self, EstimationError> {
        #[allow(clippy::let_unit_value)]
        let () = Self::SIZE_CHECK;
        check_positive_definite("Q", &q)?;
        check_positive_definite("R", &r)?;
        check_estimate(("x0", "P0"), &x0, &p0)?;
        Ok(AugmentedUkf {
            settings: FilterSettings::new(points, FILTER),
            x: x0,
            p: p0,
            q,
            r,
            propagated: SMatrix::zeros(),
            meas_noise: SMatrix::zeros(),
            fresh: false,
            innovation: SVector::zeros(),
            innovation_cov: SMatrix::zeros(),
        })
    }

    settings_methods!();

    fn augmented_points(&self) -> Result<SMatrix<f64, NA, NS>, EstimationError> {
        let mut xa = SVector::<f64, NA>::zeros();
        xa.fixed_rows_mut::<NX>(0).copy_from(&self.x);
        let mut pa = SMatrix::<f64, NA, NA>::zeros();
        pa.fixed_view_mut::<NX, NX>(0, 0).copy_from(&self.p);
        pa.fixed_view_mut::<NV, NV>(NX, NX).copy_from(&self.q);
        pa.fixed_view_mut::<NN, NN>(NX + NV, NX + NV)
            .copy_from(&self.r);
        self.settings.points.generate(&xa, &pa)
    }

    /// The time update through `f(x, u, v)`.
    pub fn predict<F>(
        &mut self,
        u: &SVector<f64, NU>,
        mut f: F,
    ) -> Result<Option<CovarianceRepair>, EstimationError>
    where
        F: FnMut(&SVector<f64, NX>, &SVector<f64, NU>, &SVector<f64, NV>) -> SVector<f64, NX>,
    {
        check_input(u)?;
        let chi = self.augmented_points()?;
        let prop = evaluate_points("process function", |i| {
            let c = chi.column(i);
            let xs: SVector<f64, NX> = c.fixed_rows::<NX>(0).into_owned();
            let vs: SVector<f64, NV> = c.fixed_rows::<NV>(NX).into_owned();
            f(&xs, u, &vs)
        })?;
        let noise: SMatrix<f64, NN, NS> = chi.fixed_rows::<NN>(NX + NV).into_owned();
        let (x, p, repair) = self.settings.predicted(&prop, None)?;
        self.x = x;
        self.p = p;
        self.propagated = prop;
        self.meas_noise = noise;
        self.fresh = true;
        Ok(repair)
    }

    /// The measurement update with `y` and `h(x, u, n)`.
    pub fn update<H>(
        &mut self,
        y: &SVector<f64, NY>,
        u: &SVector<f64, NU>,
        mut h: H,
    ) -> Result<UpdateOutcome, EstimationError>
    where
        H: FnMut(&SVector<f64, NX>, &SVector<f64, NU>, &SVector<f64, NN>) -> SVector<f64, NY>,
    {
        if let Some(rejected) = rejected_measurement(y) {
            self.fresh = false;
            return Ok(rejected);
        }
        check_input(u)?;
        let (xs, ns) = if self.fresh {
            (self.propagated, self.meas_noise)
        } else {
            let chi = self.augmented_points()?;
            (
                chi.fixed_rows::<NX>(0).into_owned(),
                chi.fixed_rows::<NN>(NX + NV).into_owned(),
            )
        };
        let ys = evaluate_points("measurement function", |i| {
            let xi: SVector<f64, NX> = xs.column(i).into_owned();
            let ni: SVector<f64, NN> = ns.column(i).into_owned();
            h(&xi, u, &ni)
        })?;
        let correction = self
            .settings
            .correct(&mut self.x, &mut self.p, &xs, &ys, y, None)?;
        self.innovation = correction.innovation;
        self.innovation_cov = correction.innovation_cov;
        self.fresh = false;
        Ok(correction.outcome)
    }

    /// The state estimate.
    pub fn state(&self) -> &SVector<f64, NX> {
        &self.x
    }

    /// The error covariance.
    pub fn covariance(&self) -> &SMatrix<f64, NX, NX> {
        &self.p
    }

    /// The innovation of the last finite measurement.
    pub fn innovation(&self) -> &SVector<f64, NY> {
        &self.innovation
    }

    /// The innovation covariance of the last finite measurement.
    pub fn innovation_covariance(&self) -> &SMatrix<f64, NY, NY> {
        &self.innovation_cov
    }
}
