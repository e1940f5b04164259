//! The discrete-time linear Kalman filter on fixed sizes.
//!
//! Model: `x[k+1] = A x[k] + B u[k] + w[k]`, `y[k] = C x[k] + D u[k] + v[k]`, `w ~ N(0, Q)`, `v ~ N(0, R)`.
//!
//! Time update (predict): `x⁻ = A x + B u`, `P⁻ = A P Aᵀ + Q`.
//! Measurement update with the innovation `e = y − C x⁻ − D u`, `S = C P⁻ Cᵀ + R`:
//! `x = x⁻ + K e` and the Joseph form `P = (I − K C) P⁻ (I − K C)ᵀ + K R Kᵀ`, the correct covariance for *any* gain
//! `K`, not only the optimal one. It is evaluated from `P⁻ Cᵀ` (computed for `S` anyway) as
//! `P⁻ − K (P⁻ Cᵀ)ᵀ − W Kᵀ`, `W = P⁻ Cᵀ − K S` (the same matrix for any `K`), without the `n³` products of the
//! form as written. Both covariances are made exactly symmetric by mirroring their upper triangle.
//!
//! # Cost
//!
//! With `n` states, `m` measurements and `p` inputs the arithmetic a step cannot do without (only the upper
//! triangles of the two covariances, no checks) is `3 n³ + 4 n² m + 5 n m² + 3 n² + 7 n m + 2 p (n + m)` flops
//! (a multiply-add counted as two) and terms of lower order. A step executes `2 n³` for `T = P Aᵀ` (whole
//! columns: `A T` needs all of `T`), and for `A T + Q` and the Joseph form `2 n` and `4 m` flops per entry of
//! their upper triangles, computed in blocks of four rows down to the diagonal (the block that holds the
//! diagonal whole; see `products` in the source), about `n³ + 4 n²` and `2 n² m + 8 n m`; then `2 n² m` for
//! `P⁻ Cᵀ`, `2 n m²` each for the gain and `W`, `n m²` for `S`, and `O(n m)` for the innovation, the
//! correction, the singularity floor of `S` and the definiteness certificates. At `n = 7`, `m = 2`, `p = 1`
//! (`runtime/benches/estimation.rs`) that is about 1,850 flops needed and about 2,000 executed (37 of the 49
//! entries of each 7 × 7 product are computed).
//!
//! On an x86-64 processor with AVX2 and FMA the step runs through a copy of its code compiled for them, with
//! fused multiply-adds; elsewhere through the portable code (`kalman/isa.rs`). The two agree to rounding.
//!
//! Every result is checked: the covariance must stay symmetric positive definite, and a test of that
//! (an `LDLᵀ` factorisation, `n³/3` flops, latency-bound by its divisions) runs only when no certificate
//! holds. After the prediction the certificate is `λ_min(Q)`, which bounds `λ_min(A P Aᵀ + Q)`; after the
//! update it is the smallest eigenvalue of the optimal Joseph covariance, `(P⁻⁻¹ + Cᵀ R⁻¹ C)⁻¹`, which bounds
//! that of the Joseph covariance of any gain from below; each must exceed twice a bound on the rounding error
//! of the computed matrix (`kalman/definite.rs` has the derivations). So with `Q` and `R` definite a step
//! factorises nothing larger than `S`; with a singular `Q` or `R` (or a covariance near the rounding floor)
//! the test runs as before, after every step.
//!
//! # Filter gain and predictor gain
//!
//! The gain `K` used here is the **innovation (filter) gain** `K = P⁻ Cᵀ S⁻¹`: it corrects the *current*
//! prediction, `x̂[k|k] = x̂[k|k−1] + K e[k]` (MATLAB's `dlqe` `M`, filterpy's `K`). The **predictor gain**
//! `L = A K` appears when the update and the next prediction are merged into the one-step predictor
//! `x̂[k+1|k] = A x̂[k|k−1] + B u[k] + L (y[k] − C x̂[k|k−1] − D u[k])` (the form of a discrete observer and of
//! a DARE solution `L = A P Cᵀ (C P Cᵀ + R)⁻¹`). [`predictor_gain`] and [`filter_gain_from_predictor`] convert
//! between them; the latter needs `A` invertible.
//!
//! # Steady state
//!
//! [`KalmanFilter::with_fixed_gain`] takes a filter gain from outside (for instance from a DARE solver) and
//! skips the gain computation. The covariance is still propagated with the Joseph form, so that it is the true
//! error covariance of the fixed-gain filter and the NIS gate and health statistics stay meaningful; with the
//! optimal gain it converges to the steady-state covariance. [`steady_state_gain`] computes the optimal
//! steady-state gain by iterating the Riccati recursion to convergence (a fallback when no DARE solver is at
//! hand) and checks the DARE residual of the result.
//!
//! Faults follow [`super::fault`]: non-finite or gated measurements are rejected, a singular `S` is an error,
//! the covariance is kept exactly symmetric and repaired if it loses definiteness.
//!
//! # Large models
//!
//! The filter keeps its `NX × NX` matrices (`A`, `Aᵀ`, `Q`, `P`, the next `P` and a work matrix) on the heap,
//! allocated once by the constructor, and a step declares no `NX × NX` value: a filter of any size runs on any
//! thread (an `NX × NX` matrix exceeds a spawned thread's 2 MiB stack at 512 states), and a step of a small
//! one still allocates nothing. [`KalmanFilter::new`] takes its matrices by value, on the caller's stack;
//! [`KalmanFilter::from_refs`] borrows them, so that a large model's matrices can stay where they are built
//! ([`LinearDiscreteModel::boxed_from_state_space`], [`crate::matrix::boxed_fixed`]). [`steady_state_gain`]
//! works on stack values: for a large model, `crate::design::dlqe` solves the same DARE on `DMatrix`.

mod definite;
mod isa;
mod products;

use super::dense::{all_finite, cholesky_lower, cholesky_solve, first_non_finite, symmetrise};
use super::fault::{
    CovarianceRepair, EstimationError, FaultPolicy, UpdateOutcome, check_additive_noise,
    check_estimate, check_finite, check_positive_definite, check_positive_semidefinite,
    repair_covariance_in,
};
use crate::linalg::pbh::{Domain, undetectable_mode};
use crate::matrix::{boxed_copy, zeroed_box};
use crate::statespace::StateSpace;
use definite::{DefinitePrediction, DefiniteUpdate, InnovationFloor, UpdateNorms};
#[cfg(target_arch = "x86_64")]
use isa::Fused;
use isa::{Isa, MulAdd, Separate};
use nalgebra::{DMatrix, SMatrix, SVector};
use products::{
    InnovationFactor, congruence_plus, covariance_times_ct, frobenius, innovation_covariance,
    joseph, plus_product,
};

const FILTER: &str = "Kalman filter";

/// A discrete linear model `x[k+1] = A x + B u`, `y = C x + D u` with fixed sizes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearDiscreteModel<const NX: usize, const NU: usize, const NY: usize> {
    pub a: SMatrix<f64, NX, NX>,
    pub b: SMatrix<f64, NX, NU>,
    pub c: SMatrix<f64, NY, NX>,
    pub d: SMatrix<f64, NY, NU>,
}

impl<const NX: usize, const NU: usize, const NY: usize> LinearDiscreteModel<NX, NU, NY> {
    /// The fixed-size model of a discrete-time [`StateSpace`] (sizes and sample time checked).
    pub fn from_state_space(ss: &StateSpace) -> Result<Self, EstimationError> {
        if ss.dt().is_none() {
            return Err(EstimationError::NotDiscrete);
        }
        let m = LinearDiscreteModel {
            a: fixed_from_dynamic("A", ss.a())?,
            b: fixed_from_dynamic("B", ss.b())?,
            c: fixed_from_dynamic("C", ss.c())?,
            d: fixed_from_dynamic("D", ss.d())?,
        };
        m.validate()?;
        Ok(m)
    }

    /// [`Self::from_state_space`] on the heap, for a model whose matrices do not fit the stack.
    pub fn boxed_from_state_space(ss: &StateSpace) -> Result<Box<Self>, EstimationError> {
        if ss.dt().is_none() {
            return Err(EstimationError::NotDiscrete);
        }
        let mut m: Box<Self> = bytemuck::zeroed_box();
        copy_dynamic("A", ss.a(), &mut m.a)?;
        copy_dynamic("B", ss.b(), &mut m.b)?;
        copy_dynamic("C", ss.c(), &mut m.c)?;
        copy_dynamic("D", ss.d(), &mut m.d)?;
        m.validate()?;
        Ok(m)
    }

    /// Checks that every matrix is finite.
    pub fn validate(&self) -> Result<(), EstimationError> {
        check_finite("A", &self.a)?;
        check_finite("B", &self.b)?;
        check_finite("C", &self.c)?;
        check_finite("D", &self.d)
    }
}

// SAFETY: four `SMatrix<f64, _, _>` (arrays of `f64`), for which all-zero bytes are a valid value (`0.0`).
unsafe impl<const NX: usize, const NU: usize, const NY: usize> bytemuck::Zeroable
    for LinearDiscreteModel<NX, NU, NY>
{
}

/// How the gain is obtained.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GainMode<const NX: usize, const NY: usize> {
    /// `K = P⁻ Cᵀ S⁻¹` at every update.
    TimeVarying,
    /// A fixed innovation (filter) gain, e.g. the steady-state gain.
    Fixed(SMatrix<f64, NX, NY>),
}

/// A discrete Kalman filter with `NX` states, `NU` inputs and `NY` measurements.
///
/// `clone` allocates the filter's matrices anew; `clone_from` copies into those of an existing filter and
/// allocates nothing (for a step that must leave the filter unchanged when it fails).
#[derive(Debug)]
pub struct KalmanFilter<const NX: usize, const NU: usize, const NY: usize> {
    model: Box<LinearDiscreteModel<NX, NU, NY>>,
    q: Box<SMatrix<f64, NX, NX>>,
    r: SMatrix<f64, NY, NY>,
    x: SVector<f64, NX>,
    /// Exactly symmetric: symmetrised when given, and every step computes one triangle and mirrors it.
    p: Box<SMatrix<f64, NX, NX>>,
    /// The covariance a step computes, swapped with `p` when the step succeeds (so that a failed step leaves
    /// `p` as it was).
    next_p: Box<SMatrix<f64, NX, NX>>,
    /// Work space of a step: `P Aᵀ` of the prediction, the factor of the definiteness test, the eigenvectors
    /// of a repair.
    work: Box<SMatrix<f64, NX, NX>>,
    gain_mode: GainMode<NX, NY>,
    gain: SMatrix<f64, NX, NY>,
    innovation: SVector<f64, NY>,
    innovation_cov: SMatrix<f64, NY, NY>,
    policy: FaultPolicy,
    fixed: ModelTerms<NX, NY>,
    /// A lower bound on `λ_min(P)` left by a certified time update; `0` when unknown.
    eigenvalue_floor: f64,
}

/// What a step needs that depends only on the model and the noise covariances, computed once.
#[derive(Debug)]
struct ModelTerms<const NX: usize, const NY: usize> {
    /// `Aᵀ` and `Cᵀ`: the products read their columns (the rows of `A` and `C`) contiguously.
    at: Box<SMatrix<f64, NX, NX>>,
    ct: SMatrix<f64, NX, NY>,
    definite_prediction: DefinitePrediction,
    definite_update: DefiniteUpdate,
    innovation_floor: InnovationFloor<NY>,
    /// The instruction set of the step (`kalman/isa.rs`).
    isa: Isa,
}

impl<const NX: usize, const NY: usize> Clone for ModelTerms<NX, NY> {
    fn clone(&self) -> Self {
        ModelTerms {
            at: boxed_copy(&self.at),
            ..*self
        }
    }

    fn clone_from(&mut self, source: &Self) {
        self.at.copy_from(&source.at);
        self.ct = source.ct;
        self.definite_prediction = source.definite_prediction;
        self.definite_update = source.definite_update;
        self.innovation_floor = source.innovation_floor;
        self.isa = source.isa;
    }
}

impl<const NX: usize, const NY: usize> ModelTerms<NX, NY> {
    fn of<const NU: usize>(
        model: &LinearDiscreteModel<NX, NU, NY>,
        q: &SMatrix<f64, NX, NX>,
        r: &SMatrix<f64, NY, NY>,
    ) -> Self {
        let mut at = zeroed_box::<NX, NX>();
        at.tr_copy_from(&model.a);
        ModelTerms {
            at,
            ct: model.c.transpose(),
            definite_prediction: DefinitePrediction::of(&model.a, q),
            definite_update: DefiniteUpdate::of(&model.c, r),
            innovation_floor: InnovationFloor::of(&model.c),
            isa: Isa::detect(),
        }
    }
}

impl<const NX: usize, const NU: usize, const NY: usize> Clone for KalmanFilter<NX, NU, NY> {
    fn clone(&self) -> Self {
        KalmanFilter {
            model: boxed_model(&self.model),
            q: boxed_copy(&self.q),
            p: boxed_copy(&self.p),
            // Work space: its contents are never read before a step writes them.
            next_p: zeroed_box(),
            work: zeroed_box(),
            fixed: self.fixed.clone(),
            ..*self
        }
    }

    fn clone_from(&mut self, source: &Self) {
        copy_model(&mut self.model, &source.model);
        self.q.copy_from(&source.q);
        self.r = source.r;
        self.x = source.x;
        self.p.copy_from(&source.p);
        self.gain_mode = source.gain_mode;
        self.gain = source.gain;
        self.innovation = source.innovation;
        self.innovation_cov = source.innovation_cov;
        self.policy = source.policy;
        self.fixed.clone_from(&source.fixed);
        self.eigenvalue_floor = source.eigenvalue_floor;
    }
}

/// A copy of `model` on the heap, written there matrix by matrix.
fn boxed_model<const NX: usize, const NU: usize, const NY: usize>(
    model: &LinearDiscreteModel<NX, NU, NY>,
) -> Box<LinearDiscreteModel<NX, NU, NY>> {
    let mut out: Box<LinearDiscreteModel<NX, NU, NY>> = bytemuck::zeroed_box();
    copy_model(&mut out, model);
    out
}

/// Copies the matrices of `source` into `out` (by reference: `*out = *source` may pass through the stack).
fn copy_model<const NX: usize, const NU: usize, const NY: usize>(
    out: &mut LinearDiscreteModel<NX, NU, NY>,
    source: &LinearDiscreteModel<NX, NU, NY>,
) {
    out.a.copy_from(&source.a);
    out.b.copy_from(&source.b);
    out.c.copy_from(&source.c);
    out.d.copy_from(&source.d);
}

impl<const NX: usize, const NU: usize, const NY: usize> KalmanFilter<NX, NU, NY> {
    /// A time-varying filter. `q` and `r` must be symmetric positive semi-definite (a noise-free sensor is
    /// allowed; an innovation covariance that ends up singular is then reported by `update`), `p0` positive
    /// definite (and symmetric to rounding; it is kept symmetrised).
    ///
    /// The matrices are taken by value, on the caller's stack; for a model of several hundred states use
    /// [`Self::from_refs`] (see the module docs).
    pub fn new(
        model: LinearDiscreteModel<NX, NU, NY>,
        q: SMatrix<f64, NX, NX>,
        r: SMatrix<f64, NY, NY>,
        x0: SVector<f64, NX>,
        p0: SMatrix<f64, NX, NX>,
    ) -> Result<Self, EstimationError> {
        Self::from_refs(&model, &q, &r, &x0, &p0)
    }

    /// [`Self::new`] from borrowed matrices, which the filter copies to the heap: for a model whose matrices
    /// do not fit the stack, built in a `Box` (see the module docs).
    pub fn from_refs(
        model: &LinearDiscreteModel<NX, NU, NY>,
        q: &SMatrix<f64, NX, NX>,
        r: &SMatrix<f64, NY, NY>,
        x0: &SVector<f64, NX>,
        p0: &SMatrix<f64, NX, NX>,
    ) -> Result<Self, EstimationError> {
        model.validate()?;
        check_additive_noise(q, r)?;
        check_estimate(("x0", "P0"), x0, p0)?;
        let mut p = boxed_copy(p0);
        symmetrise(&mut p);
        Ok(KalmanFilter {
            model: boxed_model(model),
            q: boxed_copy(q),
            r: *r,
            x: *x0,
            p,
            next_p: zeroed_box(),
            work: zeroed_box(),
            gain_mode: GainMode::TimeVarying,
            gain: SMatrix::zeros(),
            innovation: SVector::zeros(),
            innovation_cov: *r,
            policy: FaultPolicy::default(),
            fixed: ModelTerms::of(model, q, r),
            eigenvalue_floor: 0.0,
        })
    }

    /// A steady-state filter with the fixed innovation gain `k` (see the module docs for predictor gains).
    pub fn with_fixed_gain(
        model: LinearDiscreteModel<NX, NU, NY>,
        q: SMatrix<f64, NX, NX>,
        r: SMatrix<f64, NY, NY>,
        k: SMatrix<f64, NX, NY>,
        x0: SVector<f64, NX>,
        p0: SMatrix<f64, NX, NX>,
    ) -> Result<Self, EstimationError> {
        let mut f = Self::new(model, q, r, x0, p0)?;
        f.set_fixed_gain(k)?;
        Ok(f)
    }

    /// Makes the filter a steady-state one with the fixed innovation gain `k` from now on (the form of
    /// [`Self::with_fixed_gain`] for a filter built by [`Self::from_refs`]).
    pub fn set_fixed_gain(&mut self, k: SMatrix<f64, NX, NY>) -> Result<(), EstimationError> {
        check_finite("K", &k)?;
        self.gain_mode = GainMode::Fixed(k);
        self.gain = k;
        Ok(())
    }

    /// Replaces the fault policy (NIS gate, eigenvalue floor).
    pub fn set_fault_policy(&mut self, policy: FaultPolicy) -> Result<(), EstimationError> {
        policy.validate()?;
        self.policy = policy;
        Ok(())
    }

    /// Re-initialises the estimate (`p` is kept symmetrised).
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
        symmetrise(&mut self.p);
        self.eigenvalue_floor = 0.0;
        Ok(())
    }

    /// The time update `x⁻ = A x + B u`, `P⁻ = A P Aᵀ + Q`. A non-finite `u` is an error and changes nothing.
    pub fn predict(
        &mut self,
        u: &SVector<f64, NU>,
    ) -> Result<Option<CovarianceRepair>, EstimationError> {
        match self.fixed.isa {
            Isa::Portable => self.predict_with::<Separate>(u),
            // SAFETY: `Isa::Avx2Fma` is made only by `Isa::detect`, after this processor reported AVX2 and FMA.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2Fma => unsafe { self.predict_avx2_fma(u) },
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn predict_avx2_fma(
        &mut self,
        u: &SVector<f64, NU>,
    ) -> Result<Option<CovarianceRepair>, EstimationError> {
        self.predict_with::<Fused>(u)
    }

    #[inline(always)]
    fn predict_with<M: MulAdd>(
        &mut self,
        u: &SVector<f64, NU>,
    ) -> Result<Option<CovarianceRepair>, EstimationError> {
        if let Some(index) = first_non_finite(u) {
            return Err(EstimationError::NonFiniteInput { index });
        }
        let m = &*self.model;
        let x = plus_product::<M, NX, NU>(
            &plus_product::<M, NX, NX>(&SVector::zeros(), &m.a, &self.x),
            &m.b,
            u,
        );
        if first_non_finite(&x).is_some() {
            return Err(EstimationError::Overflow {
                filter: FILTER,
                quantity: "predicted state",
            });
        }
        let p = &mut *self.next_p;
        congruence_plus::<M, NX>(&m.a, &self.fixed.at, &self.p, &self.q, p, &mut self.work);
        // A certificate also bounds every entry of `p` far below overflow; without one, `repair_covariance`
        // checks that they are finite.
        let certified = self
            .fixed
            .definite_prediction
            .eigenvalue_floor(self.p.trace());
        let repair = match certified {
            Some(_) => None,
            None => repair_covariance_in(p, self.policy.eigen_floor, FILTER, &mut self.work)?,
        };
        self.x = x;
        std::mem::swap(&mut self.p, &mut self.next_p);
        self.eigenvalue_floor = certified.unwrap_or(0.0);
        Ok(repair)
    }

    /// The measurement update with measurement `y` taken while input `u` was applied (for the `D u` term).
    pub fn update(
        &mut self,
        y: &SVector<f64, NY>,
        u: &SVector<f64, NU>,
    ) -> Result<UpdateOutcome, EstimationError> {
        match self.fixed.isa {
            Isa::Portable => self.update_with::<Separate>(y, u),
            // SAFETY: as in `predict`.
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2Fma => unsafe { self.update_avx2_fma(y, u) },
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn update_avx2_fma(
        &mut self,
        y: &SVector<f64, NY>,
        u: &SVector<f64, NU>,
    ) -> Result<UpdateOutcome, EstimationError> {
        self.update_with::<Fused>(y, u)
    }

    #[inline(always)]
    fn update_with<M: MulAdd>(
        &mut self,
        y: &SVector<f64, NY>,
        u: &SVector<f64, NU>,
    ) -> Result<UpdateOutcome, EstimationError> {
        if let Some(index) = first_non_finite(y) {
            return Ok(UpdateOutcome::Rejected {
                reason: super::fault::RejectReason::NonFiniteMeasurement { index },
            });
        }
        if let Some(index) = first_non_finite(u) {
            return Err(EstimationError::NonFiniteInput { index });
        }
        let m = &*self.model;
        let e = y - plus_product::<M, NY, NU>(
            &plus_product::<M, NY, NX>(&SVector::zeros(), &m.c, &self.x),
            &m.d,
            u,
        );
        // P Cᵀ = (C P)ᵀ serves the innovation covariance, the gain and the Joseph form.
        let pct = covariance_times_ct::<M, NX, NY>(&self.p, &self.fixed.ct);
        let s = innovation_covariance::<M, NX, NY>(&pct, &self.fixed.ct, &self.r);
        let singular = EstimationError::SingularInnovation { filter: FILTER };
        let ls = cholesky_lower(&s).ok_or(singular.clone())?;
        let pivots = SVector::<f64, NY>::from_fn(|j, _| ls[(j, j)] * ls[(j, j)]);
        let floor = &self.fixed.innovation_floor;
        let trace_p = self.p.trace();
        if !floor.pivots_clear(&pivots, &self.fixed.ct, &self.p, trace_p, &self.r) {
            return Err(singular);
        }
        let overflow = |quantity| EstimationError::Overflow {
            filter: FILTER,
            quantity,
        };
        if first_non_finite(&e).is_some() {
            return Err(overflow("innovation"));
        }
        let factor = InnovationFactor::new(ls);
        let nis = factor.whiten(&e).norm_squared();
        if !nis.is_finite() {
            return Err(overflow("normalised innovation squared"));
        }
        self.innovation = e;
        self.innovation_cov = s;
        if let Some(reason) = self.policy.gate(nis) {
            return Ok(UpdateOutcome::Rejected { reason });
        }
        let k = match self.gain_mode {
            GainMode::Fixed(k) => k,
            GainMode::TimeVarying => {
                let k = factor.gain::<M, NX>(&pct);
                if !all_finite(&k) {
                    return Err(singular);
                }
                k
            }
        };
        let x = plus_product::<M, NX, NY>(&self.x, &k, &e);
        if first_non_finite(&x).is_some() {
            return Err(overflow("corrected state"));
        }
        let p = &mut *self.next_p;
        let w = joseph::<M, NX, NY>(&self.p, &k, &pct, &s, p);
        let certified = self.eigenvalue_floor > 0.0
            && self.fixed.definite_update.holds(
                self.eigenvalue_floor,
                &UpdateNorms {
                    trace_p,
                    pct: frobenius::<M, NX, NY>(&pct),
                    s: frobenius::<M, NY, NY>(&s),
                    k: frobenius::<M, NX, NY>(&k),
                    w: frobenius::<M, NX, NY>(&w),
                },
            );
        let repair = if certified {
            None
        } else {
            repair_covariance_in(p, self.policy.eigen_floor, FILTER, &mut self.work)?
        };
        self.x = x;
        std::mem::swap(&mut self.p, &mut self.next_p);
        self.gain = k;
        self.eigenvalue_floor = 0.0;
        Ok(UpdateOutcome::Accepted { nis, repair })
    }

    /// The state estimate.
    pub fn state(&self) -> &SVector<f64, NX> {
        &self.x
    }

    /// The error covariance of the estimate.
    pub fn covariance(&self) -> &SMatrix<f64, NX, NX> {
        &self.p
    }

    /// The innovation gain used by the last accepted update (the fixed gain in steady-state mode).
    pub fn gain(&self) -> &SMatrix<f64, NX, NY> {
        &self.gain
    }

    /// The innovation `e = y − C x⁻ − D u` of the last finite measurement (also when it was gated out).
    pub fn innovation(&self) -> &SVector<f64, NY> {
        &self.innovation
    }

    /// The innovation covariance `S` of the last finite measurement.
    pub fn innovation_covariance(&self) -> &SMatrix<f64, NY, NY> {
        &self.innovation_cov
    }

    /// The model the filter runs.
    pub fn model(&self) -> &LinearDiscreteModel<NX, NU, NY> {
        &self.model
    }
}

/// Copies `m` into `out`, checking its shape (an error naming `name` otherwise).
fn copy_dynamic<const R: usize, const C: usize>(
    name: &'static str,
    m: &DMatrix<f64>,
    out: &mut SMatrix<f64, R, C>,
) -> Result<(), EstimationError> {
    if m.nrows() != R || m.ncols() != C {
        return Err(EstimationError::Shape {
            name,
            rows: m.nrows(),
            cols: m.ncols(),
            expected_rows: R,
            expected_cols: C,
        });
    }
    out.copy_from(m);
    Ok(())
}

/// Copies a dynamically sized matrix (e.g. a gain from [`crate::design`]) into a fixed-size one, checking
/// its shape.
pub fn fixed_from_dynamic<const R: usize, const C: usize>(
    name: &'static str,
    m: &DMatrix<f64>,
) -> Result<SMatrix<f64, R, C>, EstimationError> {
    crate::matrix::fixed(name, m).map_err(|_| EstimationError::Shape {
        name,
        rows: m.nrows(),
        cols: m.ncols(),
        expected_rows: R,
        expected_cols: C,
    })
}

/// The predictor gain `L = A K` from the innovation gain `K`.
pub fn predictor_gain<const NX: usize, const NY: usize>(
    a: &SMatrix<f64, NX, NX>,
    k: &SMatrix<f64, NX, NY>,
) -> SMatrix<f64, NX, NY> {
    a * k
}

/// The innovation gain `K = A⁻¹ L` from a predictor gain `L`; an error when `A` is singular.
pub fn filter_gain_from_predictor<const NX: usize, const NY: usize>(
    a: &SMatrix<f64, NX, NX>,
    l: &SMatrix<f64, NX, NY>,
) -> Result<SMatrix<f64, NX, NY>, EstimationError> {
    check_finite("A", a)?;
    check_finite("L", l)?;
    super::dense::solve_general(a, l).ok_or(EstimationError::SingularMatrix { name: "A" })
}

/// The optimal steady-state gains and covariances of a linear filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SteadyStateGain<const NX: usize, const NY: usize> {
    /// Innovation (filter) gain `K = P Cᵀ (C P Cᵀ + R)⁻¹`.
    pub filter_gain: SMatrix<f64, NX, NY>,
    /// Predictor gain `L = A K`.
    pub predictor_gain: SMatrix<f64, NX, NY>,
    /// The a-priori covariance `P`, the stabilising solution of the DARE
    /// `P = A P Aᵀ − A P Cᵀ (C P Cᵀ + R)⁻¹ C P Aᵀ + Q`.
    pub predicted_covariance: SMatrix<f64, NX, NX>,
    /// The a-posteriori covariance `(I − K C) P`.
    pub filtered_covariance: SMatrix<f64, NX, NX>,
    /// Iterations used.
    pub iterations: usize,
}

/// Iterates the Riccati recursion `P ← A (P − P Cᵀ S⁻¹ C P) Aᵀ + Q` from `P = Q + I` until the relative change
/// is below `tol`, then checks the DARE residual. An undetectable `(A, C)` is refused first
/// ([`EstimationError::NotDetectable`], by the PBH test of [`crate::linalg::pbh`]); the recursion converges
/// when moreover `(A, Q^½)` is stabilisable, otherwise [`EstimationError::NotConverged`].
pub fn steady_state_gain<const NX: usize, const NY: usize>(
    a: &SMatrix<f64, NX, NX>,
    c: &SMatrix<f64, NY, NX>,
    q: &SMatrix<f64, NX, NX>,
    r: &SMatrix<f64, NY, NY>,
    tol: f64,
    max_iterations: usize,
) -> Result<SteadyStateGain<NX, NY>, EstimationError> {
    check_finite("A", a)?;
    check_finite("C", c)?;
    check_positive_semidefinite("Q", q)?;
    check_positive_definite("R", r)?;
    if !(tol > 0.0 && tol.is_finite()) {
        return Err(EstimationError::InvalidSetting {
            name: "tol",
            value: tol,
            reason: "the tolerance must be positive and finite",
        });
    }
    // Without this the recursion diverges until P overflows and reports only that it did not converge.
    let (a_dyn, c_dyn) = (crate::matrix::dynamic(a), crate::matrix::dynamic(c));
    if let Ok(Some(mode)) = undetectable_mode(&a_dyn, &c_dyn, Domain::Discrete) {
        return Err(EstimationError::NotDetectable {
            re: mode.eigenvalue.re,
            im: mode.eigenvalue.im,
        });
    }
    let singular = EstimationError::SingularInnovation {
        filter: "Riccati iteration",
    };
    let filtered = |p: &SMatrix<f64, NX, NX>| -> Result<_, EstimationError> {
        let mut s = c * p * c.transpose() + r;
        symmetrise(&mut s);
        let ls = cholesky_lower(&s).ok_or(singular.clone())?;
        let k = cholesky_solve(&ls, &(c * p))
            .ok_or(singular.clone())?
            .transpose();
        let mut pf = p - k * c * p;
        symmetrise(&mut pf);
        Ok((k, pf))
    };
    let mut p = q + SMatrix::<f64, NX, NX>::identity();
    let mut change = f64::INFINITY;
    for it in 1..=max_iterations {
        let (_, pf) = filtered(&p)?;
        let mut next = a * pf * a.transpose() + q;
        symmetrise(&mut next);
        if !super::dense::all_finite(&next) {
            break;
        }
        // Largest entries, not Frobenius norms: the norm of a diverging P (an undetectable mode) overflows
        // to infinity long before its entries do, and a change divided by it would read as convergence.
        change = (next - p).amax() / next.amax().max(f64::MIN_POSITIVE);
        p = next;
        if change < tol {
            let (k, pf) = filtered(&p)?;
            let residual = (a * pf * a.transpose() + q - p).amax() / p.amax().max(1.0);
            if residual > 1e3 * tol.max(f64::EPSILON) {
                return Err(EstimationError::NotConverged {
                    iterations: it,
                    change: residual,
                });
            }
            return Ok(SteadyStateGain {
                filter_gain: k,
                predictor_gain: a * k,
                predicted_covariance: p,
                filtered_covariance: pf,
                iterations: it,
            });
        }
    }
    Err(EstimationError::NotConverged {
        iterations: max_iterations,
        change,
    })
}

#[cfg(test)]
mod tests;
