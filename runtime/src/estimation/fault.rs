//! Errors, step outcomes and the fault handling shared by every filter.
//!
//! The contract of every filter step:
//!
//! - a measurement with a NaN or infinite entry is **rejected** ([`UpdateOutcome::Rejected`] with
//!   [`RejectReason::NonFiniteMeasurement`]); the state and covariance keep their predicted values;
//! - when a NIS gate is configured ([`FaultPolicy::nis_gate`]), a measurement whose normalised innovation
//!   squared `NIS = eᵀ S⁻¹ e` exceeds the gate is rejected as an outlier ([`RejectReason::Outlier`]). Under the
//!   filter's own model the NIS is chi-square distributed with `NY` degrees of freedom, so the gate is a
//!   chi-square quantile, e.g. `scipy.stats.chi2.ppf(0.999, NY)` (13.82 for two measurements);
//! - a covariance that loses positive definiteness through rounding is **repaired**: symmetrised, and its
//!   eigenvalues raised to [`FaultPolicy::eigen_floor`]; the repair is reported ([`CovarianceRepair`]). A
//!   covariance with non-finite entries cannot be repaired and is an error;
//! - an innovation covariance that is not positive definite (singular `S`) is an error
//!   ([`EstimationError::SingularInnovation`]), as is a model function returning a non-finite value.
//!   A step that returns an error leaves the filter exactly as it was before the step.
//!
//! Nothing here panics.

use super::dense::{
    all_finite, cholesky_lower_into, cholesky_psd_into, positive_definite_in,
    symmetric_eigen_in_place, symmetrise, with_square_scratch,
};
use crate::model::ParamError;
use nalgebra::{SMatrix, SVector};

/// Why a filter could not be built or could not take a step.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EstimationError {
    /// A constructor argument or setting is out of its domain.
    #[error("{name} = {value:?} is invalid: {reason}")]
    InvalidSetting {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// A matrix given to a constructor has a non-finite entry.
    #[error("matrix {name} has a non-finite entry at ({row}, {col})")]
    NonFiniteMatrix {
        name: &'static str,
        row: usize,
        col: usize,
    },
    /// A covariance given to a constructor (or reached by the filter) is not symmetric positive (semi-)definite.
    #[error("{name} is not a symmetric positive {kind} matrix")]
    NotPositiveDefinite {
        name: &'static str,
        kind: &'static str,
    },
    /// A known input (u) has a non-finite entry; the step was not taken.
    #[error("input u has a non-finite entry at index {index}")]
    NonFiniteInput { index: usize },
    /// A user-supplied model function returned a non-finite value.
    #[error("{function} returned a non-finite value at sigma point {sigma_point}")]
    NonFiniteModelOutput {
        function: &'static str,
        sigma_point: usize,
    },
    /// The innovation covariance `S` is not positive definite, so the gain `P_xy S⁻¹` does not exist.
    #[error("innovation covariance of the {filter} is singular or not positive definite")]
    SingularInnovation { filter: &'static str },
    /// A quantity computed from finite data left the range of `f64` (an input, measurement or state too large
    /// for the arithmetic of the step); the step was not taken.
    #[error(
        "{quantity} of the {filter} overflows f64: an input, measurement or state is too large for the step"
    )]
    Overflow {
        filter: &'static str,
        quantity: &'static str,
    },
    /// The sigma-point weights sum to one from terms far larger than one, so their cancellation amplifies
    /// rounding; here it would leave a covariance entry with fewer than four significant digits.
    #[error(
        "{quantity} of the {filter}, entry {index}: estimated relative rounding error {relative_error:.1e} exceeds \
         1e-4 (four significant digits), because the sigma-point mean weights (sum of magnitudes {amplification:.1e}) cancel; \
         increase alpha or kappa"
    )]
    PrecisionLoss {
        filter: &'static str,
        quantity: &'static str,
        index: usize,
        relative_error: f64,
        amplification: f64,
    },
    /// The covariance has non-finite entries and cannot be repaired.
    #[error("covariance of the {filter} has non-finite entries")]
    NonFiniteCovariance { filter: &'static str },
    /// The steady-state Riccati iteration did not converge.
    #[error(
        "Riccati iteration did not converge in {iterations} iterations (last relative change {change:e})"
    )]
    NotConverged { iterations: usize, change: f64 },
    /// A mode of `A` on or outside the unit circle is not seen by any measurement (`(A, C)` is not detectable),
    /// so the error covariance of that mode grows without bound and no steady-state gain exists.
    #[error(
        "the mode of A at {re} + {im}i is not asymptotically stable and no measurement sees it: (A, C) is not \
         detectable"
    )]
    NotDetectable { re: f64, im: f64 },
    /// A dynamically sized matrix does not have the filter's fixed size.
    #[error("matrix {name} is {rows}x{cols}, expected {expected_rows}x{expected_cols}")]
    Shape {
        name: &'static str,
        rows: usize,
        cols: usize,
        expected_rows: usize,
        expected_cols: usize,
    },
    /// A model given to a discrete filter is continuous-time.
    #[error("the model is continuous-time; a discrete filter needs a sampled model")]
    NotDiscrete,
    /// A matrix that must be invertible is numerically singular.
    #[error("matrix {name} is singular")]
    SingularMatrix { name: &'static str },
    /// A value given to a statistic is NaN or infinite.
    #[error("{what} has a non-finite entry")]
    NonFiniteValue { what: &'static str },
    /// No sensor of a fusion gave a finite value.
    #[error("none of the {sensors} sensors gave a finite value")]
    NoFiniteMeasurement { sensors: usize },
    /// A model refused a parameter value proposed by the parameter filter.
    #[error("the model refused a parameter value: {0}")]
    ParamRefused(#[from] ParamError),
}

/// Why a measurement was not used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RejectReason {
    /// Entry `index` of the measurement is NaN or infinite.
    NonFiniteMeasurement { index: usize },
    /// The normalised innovation squared exceeded the gate.
    Outlier { nis: f64, gate: f64 },
}

/// A covariance repair: the matrix was symmetrised and its eigenvalues raised to `floor`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CovarianceRepair {
    /// The smallest eigenvalue before the repair.
    pub min_eigenvalue: f64,
    /// The floor the eigenvalues were raised to.
    pub floor: f64,
}

/// The result of a measurement update that did not fail.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UpdateOutcome {
    /// The measurement was used. `nis` is its normalised innovation squared; `repair` reports a covariance
    /// repair after the update.
    Accepted {
        nis: f64,
        repair: Option<CovarianceRepair>,
    },
    /// The measurement was not used; the state is the predicted one.
    Rejected { reason: RejectReason },
}

impl UpdateOutcome {
    /// True when the measurement was used.
    pub fn is_accepted(&self) -> bool {
        matches!(self, UpdateOutcome::Accepted { .. })
    }
}

/// How a filter treats suspicious data.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaultPolicy {
    /// Reject a measurement whose NIS exceeds this value (`None`: no gate).
    pub nis_gate: Option<f64>,
    /// The smallest eigenvalue a repaired covariance may have.
    pub eigen_floor: f64,
}

impl Default for FaultPolicy {
    fn default() -> Self {
        FaultPolicy {
            nis_gate: None,
            eigen_floor: 1e-12,
        }
    }
}

impl FaultPolicy {
    /// Checks the settings: a gate must be positive, the floor positive and finite.
    pub fn validate(&self) -> Result<(), EstimationError> {
        if let Some(g) = self.nis_gate
            && (g <= 0.0 || g.is_nan())
        {
            return Err(EstimationError::InvalidSetting {
                name: "nis_gate",
                value: g,
                reason: "a NIS gate must be positive",
            });
        }
        if !(self.eigen_floor > 0.0 && self.eigen_floor.is_finite()) {
            return Err(EstimationError::InvalidSetting {
                name: "eigen_floor",
                value: self.eigen_floor,
                reason: "the eigenvalue floor must be positive and finite",
            });
        }
        Ok(())
    }

    /// The outlier verdict for a NIS value, if any.
    pub(crate) fn gate(&self, nis: f64) -> Option<RejectReason> {
        match self.nis_gate {
            Some(gate) if nis > gate || nis.is_nan() => Some(RejectReason::Outlier { nis, gate }),
            _ => None,
        }
    }
}

/// Symmetrises `p` and, when it is not positive definite, raises its eigenvalues to `floor`.
pub(crate) fn repair_covariance<const N: usize>(
    p: &mut SMatrix<f64, N, N>,
    floor: f64,
    filter: &'static str,
) -> Result<Option<CovarianceRepair>, EstimationError> {
    repair_covariance_in(p, floor, filter, &mut SMatrix::zeros())
}

/// [`repair_covariance`] working in `work` (any contents; overwritten): no `N × N` value on the stack, for a
/// filter that keeps its work matrix on the heap.
pub(crate) fn repair_covariance_in<const N: usize>(
    p: &mut SMatrix<f64, N, N>,
    floor: f64,
    filter: &'static str,
    work: &mut SMatrix<f64, N, N>,
) -> Result<Option<CovarianceRepair>, EstimationError> {
    if !all_finite(p) {
        return Err(EstimationError::NonFiniteCovariance { filter });
    }
    symmetrise(p);
    if positive_definite_in(p, &mut work.data.0) {
        return Ok(None);
    }
    // `p` becomes the rotated (nearly diagonal) matrix and `work` the eigenvectors `V`.
    let vals =
        symmetric_eigen_in_place(p, work).ok_or(EstimationError::NonFiniteCovariance { filter })?;
    let min_eigenvalue = vals.iter().copied().fold(f64::INFINITY, f64::min);
    // `P = V diag(max(λ, floor)) Vᵀ`, column `j` as the sum of the columns of `V` weighted by `λₖ V[j, k]`.
    let v = &work.data.0;
    let out = &mut p.data.0;
    for j in 0..N {
        let mut col = [0.0_f64; N];
        for k in 0..N {
            let s = vals[k].max(floor) * v[k][j];
            for (c, vik) in col.iter_mut().zip(&v[k]) {
                *c += vik * s;
            }
        }
        out[j] = col;
    }
    symmetrise(p);
    Ok(Some(CovarianceRepair {
        min_eigenvalue,
        floor,
    }))
}

/// Checks that a matrix has finite entries.
pub(crate) fn check_finite<const R: usize, const C: usize>(
    name: &'static str,
    m: &SMatrix<f64, R, C>,
) -> Result<(), EstimationError> {
    for j in 0..C {
        for i in 0..R {
            if !m[(i, j)].is_finite() {
                return Err(EstimationError::NonFiniteMatrix {
                    name,
                    row: i,
                    col: j,
                });
            }
        }
    }
    Ok(())
}

/// Checks that a covariance is finite, symmetric (to rounding) and positive definite.
pub(crate) fn check_positive_definite<const N: usize>(
    name: &'static str,
    m: &SMatrix<f64, N, N>,
) -> Result<(), EstimationError> {
    check_finite(name, m)?;
    let not_pd = EstimationError::NotPositiveDefinite {
        name,
        kind: "definite",
    };
    // The factor is written into a work matrix: on the heap for a large `N` (see `dense`).
    if !is_symmetric(m) || !with_square_scratch(|l| cholesky_lower_into(m, l)) {
        return Err(not_pd);
    }
    Ok(())
}

/// Checks that a covariance is finite, symmetric and positive semi-definite (a zero noise channel is allowed).
pub(crate) fn check_positive_semidefinite<const N: usize>(
    name: &'static str,
    m: &SMatrix<f64, N, N>,
) -> Result<(), EstimationError> {
    check_finite(name, m)?;
    if !is_symmetric(m) || !with_square_scratch(|l| cholesky_psd_into(m, l)) {
        return Err(EstimationError::NotPositiveDefinite {
            name,
            kind: "semi-definite",
        });
    }
    Ok(())
}

/// Checks the noise covariances `Q` and `R` (positive semi-definite) of an additive-noise filter.
pub(crate) fn check_additive_noise<const NX: usize, const NY: usize>(
    q: &SMatrix<f64, NX, NX>,
    r: &SMatrix<f64, NY, NY>,
) -> Result<(), EstimationError> {
    check_positive_semidefinite("Q", q)?;
    check_positive_semidefinite("R", r)
}

/// Checks an estimate `(x, P)`: `x` finite, `P` positive definite; `names` are those of `x` and `P` in errors.
pub(crate) fn check_estimate<const NX: usize>(
    names: (&'static str, &'static str),
    x: &SVector<f64, NX>,
    p: &SMatrix<f64, NX, NX>,
) -> Result<(), EstimationError> {
    check_finite(names.0, x)?;
    check_positive_definite(names.1, p)
}

fn is_symmetric<const N: usize>(m: &SMatrix<f64, N, N>) -> bool {
    let scale = m.amax().max(f64::MIN_POSITIVE);
    (0..N).all(|i| (0..i).all(|j| (m[(i, j)] - m[(j, i)]).abs() <= 1e-10 * scale))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix2;

    #[test]
    fn indefinite_covariance_is_floored_and_reported() {
        // Eigenvalues of [[1, 2], [2, 1]] are 3 and -1; the repair keeps the eigenvectors and floors -1.
        let mut p = Matrix2::new(1.0, 2.0, 2.0, 1.0);
        let r = repair_covariance(&mut p, 1e-6, "test").unwrap().unwrap();
        assert!((r.min_eigenvalue + 1.0).abs() < 1e-12);
        // V diag(3, 1e-6) Vᵀ with V = [1 1; 1 -1]/√2.
        let expected = Matrix2::new(1.5 + 0.5e-6, 1.5 - 0.5e-6, 1.5 - 0.5e-6, 1.5 + 0.5e-6);
        assert!((p - expected).norm() < 1e-12, "{p}");
    }

    #[test]
    fn healthy_covariance_is_only_symmetrised_and_nan_is_an_error() {
        let mut p = Matrix2::new(2.0, 0.1, 0.1 + 1e-15, 1.0);
        assert_eq!(repair_covariance(&mut p, 1e-9, "test"), Ok(None));
        assert_eq!(p[(0, 1)], p[(1, 0)]);
        let mut q = Matrix2::new(f64::NAN, 0.0, 0.0, 1.0);
        assert!(matches!(
            repair_covariance(&mut q, 1e-9, "test"),
            Err(EstimationError::NonFiniteCovariance { .. })
        ));
    }

    #[test]
    fn gate_rejects_above_threshold_only() {
        let policy = FaultPolicy {
            nis_gate: Some(5.0),
            ..FaultPolicy::default()
        };
        assert_eq!(policy.gate(4.9), None);
        assert!(matches!(
            policy.gate(5.1),
            Some(RejectReason::Outlier { .. })
        ));
        assert!(
            FaultPolicy {
                nis_gate: Some(-1.0),
                ..FaultPolicy::default()
            }
            .validate()
            .is_err()
        );
    }
}
