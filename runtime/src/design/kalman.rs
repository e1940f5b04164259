//! Steady-state Kalman gains, continuous ([`lqe`]) and discrete ([`dlqe`]), by duality with the LQR (the
//! equations and conventions are in their documentation).

use nalgebra::{Complex, DMatrix};

use crate::linalg::check;
use crate::linalg::{RiccatiError, care, dare};

/// A continuous steady-state Kalman gain.
#[derive(Clone, Debug, PartialEq)]
pub struct Kalman {
    /// `L = P Cᵀ R_n⁻¹`.
    pub l: DMatrix<f64>,
    /// The steady-state error covariance.
    pub p: DMatrix<f64>,
    /// The eigenvalues of `A − L C`.
    pub observer_eigenvalues: Vec<Complex<f64>>,
    pub relative_residual: f64,
}

/// A discrete steady-state Kalman filter.
#[derive(Clone, Debug, PartialEq)]
pub struct DiscreteKalman {
    /// The predictor gain `L = A P Cᵀ (C P Cᵀ + R_n)⁻¹`.
    pub predictor_gain: DMatrix<f64>,
    /// The innovation (measurement-update) gain `M = P Cᵀ (C P Cᵀ + R_n)⁻¹`.
    pub filter_gain: DMatrix<f64>,
    /// The a-priori covariance `P = cov(x[k] − x̂[k|k−1])`.
    pub p: DMatrix<f64>,
    /// The a-posteriori covariance `Z = P − M C P = cov(x[k] − x̂[k|k])`.
    pub z: DMatrix<f64>,
    /// The eigenvalues of `A − L C`.
    pub observer_eigenvalues: Vec<Complex<f64>>,
    pub relative_residual: f64,
}

/// Checks the shapes and forms `G Q_n Gᵀ`.
fn process_noise(
    a: &DMatrix<f64>,
    g: &DMatrix<f64>,
    c: &DMatrix<f64>,
    qn: &DMatrix<f64>,
) -> Result<DMatrix<f64>, RiccatiError> {
    let n = check::square("A", a)?;
    let w = g.ncols();
    check::shape("G", g, n, w)?;
    if !g.is_empty() {
        check::finite("G", g)?;
    }
    check::shape("C", c, c.nrows(), n)?;
    check::shape("Qn", qn, w, w)?;
    check::positive_semidefinite("Qn", qn)?;
    let gqg = g * qn * g.transpose();
    if !gqg.iter().all(|v| v.is_finite()) {
        // Finite G and Qn whose product overflows: not a NaN the caller passed.
        return Err(RiccatiError::OutOfRange {
            what: "G Qn Gᵀ",
            iterations: 0,
        });
    }
    Ok((&gqg + gqg.transpose()) * 0.5)
}

/// Maps an error of the dual (control) problem to the estimation problem.
fn dual_error(e: RiccatiError) -> RiccatiError {
    match e {
        RiccatiError::NotStabilizable {
            eigenvalue,
            direction,
        } => RiccatiError::NotDetectable {
            eigenvalue,
            direction: direction.map(|d| d.map(|z| z.conj())),
        },
        RiccatiError::NotDetectable {
            eigenvalue,
            direction,
        } => RiccatiError::NotStabilizable {
            eigenvalue,
            direction: direction.map(|d| d.map(|z| z.conj())),
        },
        other => other,
    }
}

/// The continuous steady-state Kalman gain, by duality with the LQR.
///
/// Model: `ẋ = A x + B u + G w`, `y = C x + v`, `E[wwᵀ] = Q_n δ`, `E[vvᵀ] = R_n δ`. The error covariance
/// `P` solves the filter Riccati equation `A P + P Aᵀ − P Cᵀ R_n⁻¹ C P + G Q_n Gᵀ = 0` (Eq. 9 of the
/// back-support paper), i.e. the CARE of `(Aᵀ, Cᵀ, G Q_n Gᵀ, R_n)`, and the observer
/// `x̂̇ = A x̂ + B u + L (y − C x̂)` has `L = P Cᵀ R_n⁻¹` (MATLAB/python-control `lqe`).
///
/// By duality an undetectable mode of `(C, A)` is reported as [`RiccatiError::NotDetectable`] (with the right
/// eigenvector `v`, `A v = λ v`, `C v = 0`), and an unstable mode that the process noise does not excite
/// (`(A, G Q_n^{1/2})` not stabilisable) as [`RiccatiError::NotStabilizable`] (with the left eigenvector).
pub fn lqe(
    a: &DMatrix<f64>,
    g: &DMatrix<f64>,
    c: &DMatrix<f64>,
    qn: &DMatrix<f64>,
    rn: &DMatrix<f64>,
) -> Result<Kalman, RiccatiError> {
    let gqg = process_noise(a, g, c, qn)?;
    let dual = care(&a.transpose(), &c.transpose(), &gqg, rn).map_err(dual_error)?;
    Ok(Kalman {
        l: dual.k.transpose(),
        p: dual.x,
        observer_eigenvalues: dual.closed_loop_eigenvalues,
        relative_residual: dual.relative_residual,
    })
}

/// The discrete steady-state Kalman filter, by duality with the discrete LQR.
///
/// Model: `x[k+1] = A x[k] + B u[k] + G w[k]`, `y[k] = C x[k] + v[k]`, `E[w wᵀ] = Q_n`, `E[v vᵀ] = R_n`. `P`
/// (the a-priori covariance of `x[k]` given `y` up to `k − 1`) solves the DARE of `(Aᵀ, Cᵀ, G Q_n Gᵀ, R_n)`. Two
/// gains are returned:
///
/// - the predictor gain `L = A P Cᵀ (C P Cᵀ + R_n)⁻¹` for
///   `x̂[k+1|k] = A x̂[k|k−1] + B u[k] + L (y[k] − C x̂[k|k−1])` (python-control's `dlqe` returns this `L`);
/// - the innovation (filter) gain `M = P Cᵀ (C P Cᵀ + R_n)⁻¹` for the measurement update
///   `x̂[k|k] = x̂[k|k−1] + M (y[k] − C x̂[k|k−1])` (MATLAB's `dlqe` returns this `M`); `L = A M`. This is the
///   gain [`crate::estimation::KalmanFilter::with_fixed_gain`] takes.
///
/// Undetectable and unexcited unstable modes are reported as for [`lqe`].
pub fn dlqe(
    a: &DMatrix<f64>,
    g: &DMatrix<f64>,
    c: &DMatrix<f64>,
    qn: &DMatrix<f64>,
    rn: &DMatrix<f64>,
) -> Result<DiscreteKalman, RiccatiError> {
    let gqg = process_noise(a, g, c, qn)?;
    let dual = dare(&a.transpose(), &c.transpose(), &gqg, rn).map_err(dual_error)?;
    let p = dual.x;
    let pct = &p * c.transpose();
    let s = c * &pct + rn;
    // M = P Cᵀ S⁻¹, computed as (S⁻ᵀ (P Cᵀ)ᵀ)ᵀ with S symmetric.
    let filter_gain = s
        .clone()
        .lu()
        .solve(&pct.transpose())
        .ok_or(RiccatiError::Singular {
            what: "C P Cᵀ + Rn",
        })?
        .transpose();
    let z = &p - &filter_gain * c * &p;
    let z = (&z + z.transpose()) * 0.5;
    Ok(DiscreteKalman {
        predictor_gain: dual.k.transpose(),
        filter_gain,
        p,
        z,
        observer_eigenvalues: dual.closed_loop_eigenvalues,
        relative_residual: dual.relative_residual,
    })
}
