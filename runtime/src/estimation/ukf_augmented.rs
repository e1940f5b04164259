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
    FilterSettings, check_input, evaluate_points_into, rejected_measurement, settings_methods,
};
use crate::matrix::boxed_copy;
use nalgebra::{SMatrix, SVector};

const FILTER: &str = "augmented UKF";

/// A UKF with non-additive process noise (`NV` entries) and measurement noise (`NN` entries).
///
/// `P`, the propagated points and the work space of a step are kept on the heap, allocated by the constructor,
/// and a step declares no matrix of `NX²`, `NA²` or `NA NS` entries: a filter of any size runs on any thread.
#[derive(Debug)]
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
    p: Box<SMatrix<f64, NX, NX>>,
    q: SMatrix<f64, NV, NV>,
    r: SMatrix<f64, NN, NN>,
    /// Propagated state parts of the last predict's points.
    propagated: Box<SMatrix<f64, NX, NS>>,
    /// Measurement-noise parts of the last predict's points.
    meas_noise: SMatrix<f64, NN, NS>,
    fresh: bool,
    innovation: SVector<f64, NY>,
    innovation_cov: SMatrix<f64, NY, NY>,
    work: Box<AugmentedWork<NX, NY, NA, NS>>,
}

/// The matrices a step writes before it commits; their contents between steps mean nothing.
#[derive(Debug)]
struct AugmentedWork<const NX: usize, const NY: usize, const NA: usize, const NS: usize> {
    /// The augmented covariance `diag(P, Q, R)`.
    pa: SMatrix<f64, NA, NA>,
    /// Its Cholesky factor.
    factor: SMatrix<f64, NA, NA>,
    /// The augmented sigma points.
    chi: SMatrix<f64, NA, NS>,
    /// The state parts of the points a step propagates or measures.
    states: SMatrix<f64, NX, NS>,
    /// The points' measurements.
    measured: SMatrix<f64, NY, NS>,
    /// The covariance being computed, and the covariance repair's work matrix.
    next_p: SMatrix<f64, NX, NX>,
    repair: SMatrix<f64, NX, NX>,
}

// SAFETY: `SMatrix<f64, _, _>` fields only (arrays of `f64`), for which all-zero bytes are `0.0`.
unsafe impl<const NX: usize, const NY: usize, const NA: usize, const NS: usize> bytemuck::Zeroable
    for AugmentedWork<NX, NY, NA, NS>
{
}

impl<
    const NX: usize,
    const NU: usize,
    const NY: usize,
    const NV: usize,
    const NN: usize,
    const NA: usize,
    const NS: usize,
> Clone for AugmentedUkf<NX, NU, NY, NV, NN, NA, NS>
{
    fn clone(&self) -> Self {
        AugmentedUkf {
            p: boxed_copy(&self.p),
            propagated: boxed_copy(&self.propagated),
            work: bytemuck::zeroed_box(),
            ..*self
        }
    }
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
    /// model instead), `p0` positive definite. The matrices are taken by value, on the caller's stack;
    /// [`Self::from_refs`] borrows them.
    pub fn new(
        points: SigmaPoints<NA, NS>,
        q: SMatrix<f64, NV, NV>,
        r: SMatrix<f64, NN, NN>,
        x0: SVector<f64, NX>,
        p0: SMatrix<f64, NX, NX>,
    ) -> Result<Self, EstimationError> {
        Self::from_refs(points, &q, &r, &x0, &p0)
    }

    /// [`Self::new`] from borrowed matrices, copied into the filter (`P₀` of a large model held on the heap).
    pub fn from_refs(
        points: SigmaPoints<NA, NS>,
        q: &SMatrix<f64, NV, NV>,
        r: &SMatrix<f64, NN, NN>,
        x0: &SVector<f64, NX>,
        p0: &SMatrix<f64, NX, NX>,
    ) -> Result<Self, EstimationError> {
        #[allow(clippy::let_unit_value)]
        let () = Self::SIZE_CHECK;
        check_positive_definite("Q", q)?;
        check_positive_definite("R", r)?;
        check_estimate(("x0", "P0"), x0, p0)?;
        Ok(AugmentedUkf {
            settings: FilterSettings::new(points, FILTER),
            x: *x0,
            p: boxed_copy(p0),
            q: *q,
            r: *r,
            propagated: bytemuck::zeroed_box(),
            meas_noise: SMatrix::zeros(),
            fresh: false,
            innovation: SVector::zeros(),
            innovation_cov: SMatrix::zeros(),
            work: bytemuck::zeroed_box(),
        })
    }

    settings_methods!();

    /// The sigma points of `(x, P)` augmented with the noise, written into `work.chi`.
    fn augmented_points(&mut self) -> Result<(), EstimationError> {
        let mut xa = SVector::<f64, NA>::zeros();
        xa.fixed_rows_mut::<NX>(0).copy_from(&self.x);
        let w = &mut *self.work;
        w.pa.fill(0.0);
        w.pa.fixed_view_mut::<NX, NX>(0, 0).copy_from(&*self.p);
        w.pa.fixed_view_mut::<NV, NV>(NX, NX).copy_from(&self.q);
        w.pa.fixed_view_mut::<NN, NN>(NX + NV, NX + NV)
            .copy_from(&self.r);
        self.settings
            .points
            .generate_into(&xa, &w.pa, &mut w.factor, &mut w.chi)
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
        self.augmented_points()?;
        let w = &mut *self.work;
        let chi = &w.chi;
        let propagate = |i: usize| {
            let c = chi.column(i);
            let xs: SVector<f64, NX> = c.fixed_rows::<NX>(0).into_owned();
            let vs: SVector<f64, NV> = c.fixed_rows::<NV>(NX).into_owned();
            f(&xs, u, &vs)
        };
        evaluate_points_into("process function", propagate, &mut w.states)?;
        let out = (&mut w.next_p, &mut w.repair);
        let (x, repair) = self.settings.predicted_into(&w.states, None, out)?;
        self.x = x;
        self.p.copy_from(&w.next_p);
        self.propagated.copy_from(&w.states);
        self.meas_noise = w.chi.fixed_rows::<NN>(NX + NV).into_owned();
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
        // The points' state and noise parts: those of the last prediction, or drawn anew into the work space.
        let ns = if self.fresh {
            self.work.states.copy_from(&*self.propagated);
            self.meas_noise
        } else {
            self.augmented_points()?;
            let w = &mut *self.work;
            w.states.copy_from(&w.chi.fixed_rows::<NX>(0));
            w.chi.fixed_rows::<NN>(NX + NV).into_owned()
        };
        let w = &mut *self.work;
        let xs = &w.states;
        let measure = |i: usize| {
            let xi: SVector<f64, NX> = xs.column(i).into_owned();
            let ni: SVector<f64, NN> = ns.column(i).into_owned();
            h(&xi, u, &ni)
        };
        evaluate_points_into("measurement function", measure, &mut w.measured)?;
        let scratch = (&mut w.next_p, &mut w.repair);
        let correction = self.settings.correct_in(
            &mut self.x,
            &mut self.p,
            (&w.states, &w.measured, y),
            None,
            scratch,
        )?;
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
