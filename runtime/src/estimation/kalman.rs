//! The discrete-time linear Kalman filter on fixed sizes.
//!
//! Model: `x[k+1] = A x[k] + B u[k] + w[k]`, `y[k] = C x[k] + D u[k] + v[k]`, `w ~ N(0, Q)`, `v ~ N(0, R)`.
//!
//! Time update (predict): `x⁻ = A x + B u`, `P⁻ = A P Aᵀ + Q`.
//! Measurement update with the innovation `e = y − C x⁻ − D u`, `S = C P⁻ Cᵀ + R`:
//! `x = x⁻ + K e` and the Joseph form `P = (I − K C) P⁻ (I − K C)ᵀ + K R Kᵀ`, the correct covariance for *any* gain
//! `K`, not only the optimal one. It is evaluated from `C P⁻` (computed for `S` anyway) as `P⁻ − K C P⁻ − W Kᵀ`,
//! `W = P⁻ Cᵀ − K S` (the same matrix for any `K`), the upper triangle mirrored, so it is exactly symmetric:
//! about `2 n² m` flops instead of the `4 n³` of the products as written. `A P Aᵀ` likewise computes one triangle.
//!
//! # Cost
//!
//! With `n` states and `m` measurements a step (predict and update) takes about `(11/3) n³ + 6 n² m` flops
//! (a multiply-add counted as two) and lower-order terms: `2 n³` for `A P`, `n³` for one triangle of `(A P) Aᵀ`,
//! `2 n² m` for `C P⁻`, `2 n² m` for the diagonal of `|C| |P⁻| |C|ᵀ` (the singularity floor of `S`), `2 n² m` for
//! the Joseph form, and a positive-definiteness check of `P` after the update (an `LDLᵀ` sweep, `n³/3`); after the
//! prediction the check runs only when `Q` is not definite enough to guarantee the result (see `DefinitePrediction` in the source).
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
//! the covariance is symmetrised after every step and repaired if it loses definiteness.

use super::dense::{
    all_finite, cholesky_above_floor, cholesky_lower, cholesky_solve, first_non_finite,
    symmetric_eigen, symmetrise,
};
use super::fault::{
    CovarianceRepair, EstimationError, FaultPolicy, UpdateOutcome, check_additive_noise,
    check_estimate, check_finite, check_positive_definite, check_positive_semidefinite,
    repair_covariance,
};
use crate::statespace::StateSpace;
use nalgebra::{DMatrix, SMatrix, SVector};

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

    /// Checks that every matrix is finite.
    pub fn validate(&self) -> Result<(), EstimationError> {
        check_finite("A", &self.a)?;
        check_finite("B", &self.b)?;
        check_finite("C", &self.c)?;
        check_finite("D", &self.d)
    }
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
#[derive(Clone, Debug)]
pub struct KalmanFilter<const NX: usize, const NU: usize, const NY: usize> {
    model: LinearDiscreteModel<NX, NU, NY>,
    q: SMatrix<f64, NX, NX>,
    r: SMatrix<f64, NY, NY>,
    x: SVector<f64, NX>,
    p: SMatrix<f64, NX, NX>,
    gain_mode: GainMode<NX, NY>,
    gain: SMatrix<f64, NX, NY>,
    innovation: SVector<f64, NY>,
    innovation_cov: SMatrix<f64, NY, NY>,
    policy: FaultPolicy,
    definite_prediction: DefinitePrediction,
}

impl<const NX: usize, const NU: usize, const NY: usize> KalmanFilter<NX, NU, NY> {
    /// A time-varying filter. `q` and `r` must be symmetric positive semi-definite (a noise-free sensor is
    /// allowed; an innovation covariance that ends up singular is then reported by `update`), `p0` positive
    /// definite.
    pub fn new(
        model: LinearDiscreteModel<NX, NU, NY>,
        q: SMatrix<f64, NX, NX>,
        r: SMatrix<f64, NY, NY>,
        x0: SVector<f64, NX>,
        p0: SMatrix<f64, NX, NX>,
    ) -> Result<Self, EstimationError> {
        model.validate()?;
        check_additive_noise(&q, &r)?;
        check_estimate(("x0", "P0"), &x0, &p0)?;
        Ok(KalmanFilter {
            model,
            q,
            r,
            x: x0,
            p: p0,
            gain_mode: GainMode::TimeVarying,
            gain: SMatrix::zeros(),
            innovation: SVector::zeros(),
            innovation_cov: r,
            policy: FaultPolicy::default(),
            definite_prediction: DefinitePrediction::of(&model.a, &q),
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
        check_finite("K", &k)?;
        let mut f = Self::new(model, q, r, x0, p0)?;
        f.gain_mode = GainMode::Fixed(k);
        f.gain = k;
        Ok(f)
    }

    /// Replaces the fault policy (NIS gate, eigenvalue floor).
    pub fn set_fault_policy(&mut self, policy: FaultPolicy) -> Result<(), EstimationError> {
        policy.validate()?;
        self.policy = policy;
        Ok(())
    }

    /// Re-initialises the estimate.
    pub fn set_state(
        &mut self,
        x: SVector<f64, NX>,
        p: SMatrix<f64, NX, NX>,
    ) -> Result<(), EstimationError> {
        check_estimate(("x", "P"), &x, &p)?;
        self.x = x;
        self.p = p;
        Ok(())
    }

    /// The time update `x⁻ = A x + B u`, `P⁻ = A P Aᵀ + Q`. A non-finite `u` is an error and changes nothing.
    pub fn predict(
        &mut self,
        u: &SVector<f64, NU>,
    ) -> Result<Option<CovarianceRepair>, EstimationError> {
        if let Some(index) = first_non_finite(u) {
            return Err(EstimationError::NonFiniteInput { index });
        }
        let m = &self.model;
        let x = m.a * self.x + m.b * u;
        if first_non_finite(&x).is_some() {
            return Err(EstimationError::Overflow {
                filter: FILTER,
                quantity: "predicted state",
            });
        }
        let mut p = congruence_plus(&m.a, &self.p, &self.q);
        let repair = if self.definite_prediction.holds(self.p.trace()) && all_finite(&p) {
            None
        } else {
            repair_covariance(&mut p, self.policy.eigen_floor, FILTER)?
        };
        self.x = x;
        self.p = p;
        Ok(repair)
    }

    /// The measurement update with measurement `y` taken while input `u` was applied (for the `D u` term).
    pub fn update(
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
        let m = &self.model;
        let e = y - m.c * self.x - m.d * u;
        // M = C P⁻ serves the innovation covariance, the gain and the Joseph form.
        let cp = m.c * self.p;
        let mut s = cp * m.c.transpose() + self.r;
        symmetrise(&mut s);
        let singular = EstimationError::SingularInnovation { filter: FILTER };
        let ls = cholesky_above_floor(&s, &self.innovation_floor()).ok_or(singular.clone())?;
        let overflow = |quantity| EstimationError::Overflow {
            filter: FILTER,
            quantity,
        };
        if first_non_finite(&e).is_some() {
            return Err(overflow("innovation"));
        }
        let nis = e.dot(&cholesky_solve(&ls, &e).ok_or(singular.clone())?);
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
            // K = P Cᵀ S⁻¹, i.e. Kᵀ = S⁻¹ C P (P and S symmetric).
            GainMode::TimeVarying => cholesky_solve(&ls, &cp).ok_or(singular)?.transpose(),
        };
        let x = self.x + k * e;
        if first_non_finite(&x).is_some() {
            return Err(overflow("corrected state"));
        }
        let mut p = joseph(&self.p, &k, &cp, &s);
        let repair = repair_covariance(&mut p, self.policy.eigen_floor, FILTER)?;
        self.x = x;
        self.p = p;
        self.gain = k;
        Ok(UpdateOutcome::Accepted { nis, repair })
    }

    /// The rounding error with which `diag(C P Cᵀ + R)` is known, `NX ε (|C| |P| |C|ᵀ)ⱼⱼ + ε Rⱼⱼ`: a Cholesky
    /// pivot of `S` at or below it means `S` is singular to working accuracy.
    fn innovation_floor(&self) -> SVector<f64, NY> {
        let c = &self.model.c;
        SVector::from_fn(|j, _| {
            // Only the diagonal of |C| |P| |C|ᵀ: Σₐ |cⱼₐ| Σ_b |pₐ_b| |cⱼ_b|.
            let mut spread = 0.0;
            for a in 0..NX {
                let mut row = 0.0;
                for b in 0..NX {
                    row += self.p[(a, b)].abs() * c[(j, b)].abs();
                }
                spread += c[(j, a)].abs() * row;
            }
            f64::EPSILON * (NX.max(1) as f64 * spread + self.r[(j, j)].abs())
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

/// A test that makes the factorisation of `P⁻ = A P Aᵀ + Q` after a time update unnecessary when `Q` is
/// positive definite enough: `A P Aᵀ ⪰ 0`, so `λ_min(A P Aᵀ + Q) ≥ λ_min(Q)`, and the rounding error `E` of the
/// computed `P⁻` is bounded entrywise by `γ (|A| |P| |A|ᵀ + |Q|)`, `γ = (2n + 2) ε` (two products of length `n`
/// and a sum), so `‖E‖₂ ≤ γ (‖A‖_F² tr P + ‖Q‖_F)` for positive-definite `P` (`‖P‖_F ≤ tr P`). When `λ_min(Q)`
/// exceeds twice that bound, the computed `P⁻` is positive definite by Weyl's inequality with the same margin
/// the factorisation test asks for, and the `O(n³)` test is skipped; otherwise it runs as after every update.
#[derive(Clone, Copy, Debug)]
struct DefinitePrediction {
    /// `λ_min(Q)` less its own rounding error (`n ε ‖Q‖_F`); not positive for a singular `Q`.
    q_min: f64,
    a_frobenius_sq: f64,
    q_frobenius: f64,
    gamma: f64,
}

impl DefinitePrediction {
    fn of<const NX: usize>(a: &SMatrix<f64, NX, NX>, q: &SMatrix<f64, NX, NX>) -> Self {
        let n = NX as f64;
        let q_frobenius = q.norm();
        let q_min = symmetric_eigen(q).map_or(f64::NEG_INFINITY, |(values, _)| values.min())
            - n * f64::EPSILON * q_frobenius;
        DefinitePrediction {
            q_min,
            a_frobenius_sq: a.norm_squared(),
            q_frobenius,
            gamma: (2.0 * n + 2.0) * f64::EPSILON,
        }
    }

    /// Whether `fl(A P Aᵀ + Q)` is positive definite for every positive-definite `P` with trace `trace_p`.
    fn holds(&self, trace_p: f64) -> bool {
        let bound = self.gamma * (self.a_frobenius_sq * trace_p + self.q_frobenius);
        self.q_min > 2.0 * bound
    }
}

/// `A P Aᵀ + Q` for symmetric `P` and `Q`: `A P` in full, then the upper triangle of `(A P) Aᵀ`, mirrored (the
/// product is symmetric, so half of its `2 NX³` flops are not needed).
fn congruence_plus<const NX: usize>(
    a: &SMatrix<f64, NX, NX>,
    p: &SMatrix<f64, NX, NX>,
    q: &SMatrix<f64, NX, NX>,
) -> SMatrix<f64, NX, NX> {
    // (A P)ᵀ = P Aᵀ, so row i of A P is column i of P Aᵀ: each entry is a dot product of two columns.
    let at = a.transpose();
    let pat = p * at;
    let mut out = *q;
    for j in 0..NX {
        for i in 0..=j {
            let sum = q[(i, j)] + pat.column(i).dot(&at.column(j));
            out[(i, j)] = sum;
            out[(j, i)] = sum;
        }
    }
    out
}

/// The Joseph form `(I − K C) P (I − K C)ᵀ + K R Kᵀ` for any gain `K`, from `M = C P` and `S = C P Cᵀ + R`
/// (already computed for the innovation), without forming `I − K C`: with `G = I − K C`, `G P = P − K M` and
/// `G P Cᵀ = Mᵀ − K (S − R)` (`P` is symmetric), so `G P Gᵀ + K R Kᵀ = P − K M − W Kᵀ` with `W = Mᵀ − K S`. The
/// upper triangle is computed and mirrored: `2 NX (NX + 1) NY` flops for the result instead of about `4 NX³`.
fn joseph<const NX: usize, const NY: usize>(
    p: &SMatrix<f64, NX, NX>,
    k: &SMatrix<f64, NX, NY>,
    m: &SMatrix<f64, NY, NX>,
    s: &SMatrix<f64, NY, NY>,
) -> SMatrix<f64, NX, NX> {
    let w = m.transpose() - k * s;
    let mut out = *p;
    for j in 0..NX {
        for i in 0..=j {
            let mut sum = p[(i, j)];
            for a in 0..NY {
                sum -= k[(i, a)] * m[(a, j)] + w[(i, a)] * k[(j, a)];
            }
            out[(i, j)] = sum;
            out[(j, i)] = sum;
        }
    }
    out
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
/// is below `tol`, then checks the DARE residual. Converges when `(A, C)` is detectable and `(A, Q^½)`
/// stabilisable; otherwise [`EstimationError::NotConverged`].
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
        change = (next - p).norm() / next.norm().max(f64::MIN_POSITIVE);
        p = next;
        if change < tol {
            let (k, pf) = filtered(&p)?;
            let residual = (a * pf * a.transpose() + q - p).norm() / p.norm().max(1.0);
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
mod tests {
    use super::*;
    use nalgebra::dmatrix;

    #[test]
    fn model_from_state_space_checks_shape_and_sampling() {
        let ss = StateSpace::new_discrete(
            dmatrix![1.0, 0.1; 0.0, 1.0],
            dmatrix![0.0; 0.1],
            dmatrix![1.0, 0.0],
            dmatrix![0.0],
            0.1,
        )
        .unwrap();
        let m = LinearDiscreteModel::<2, 1, 1>::from_state_space(&ss).unwrap();
        assert_eq!(m.a[(0, 1)], 0.1);
        assert_eq!(m.b[(1, 0)], 0.1);
        assert!(matches!(
            LinearDiscreteModel::<3, 1, 1>::from_state_space(&ss),
            Err(EstimationError::Shape {
                name: "A",
                rows: 2,
                expected_rows: 3,
                ..
            })
        ));
        let (a, b, c, d, _) = ss.into_parts();
        let cont = StateSpace::new(a, b, c, d).unwrap();
        assert_eq!(
            LinearDiscreteModel::<2, 1, 1>::from_state_space(&cont),
            Err(EstimationError::NotDiscrete)
        );
    }

    /// `A` singular: a predictor gain cannot be turned back into a filter gain.
    #[test]
    fn filter_gain_from_predictor_needs_invertible_a() {
        let a = SMatrix::<f64, 2, 2>::new(1.0, 2.0, 2.0, 4.0);
        let l = SMatrix::<f64, 2, 1>::new(0.1, 0.2);
        assert_eq!(
            filter_gain_from_predictor(&a, &l),
            Err(EstimationError::SingularMatrix { name: "A" })
        );
    }
}
