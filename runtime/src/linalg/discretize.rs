//! Discretisation of continuous-time models.
//!
//! - Zero-order hold: with `u` constant over each sample, `x[k+1] = A_d x[k] + B_d u[k]` with
//!   `[A_d B_d; 0 I] = exp([A B; 0 0] Δt)`; `C` and `D` are unchanged (as `scipy.signal.cont2discrete(...,
//!   method='zoh')` and MATLAB `c2d`).
//! - Van Loan (1978): for `ẋ = A x + G w` with white noise of intensity `Q_c`, the discrete process noise
//!   `Q_d = ∫₀^Δt e^{Aτ} G Q_c Gᵀ e^{Aᵀτ} dτ` follows from `exp([−A, G Q_c Gᵀ; 0, Aᵀ] Δt) = [·, M₁₂; 0, M₂₂]` as
//!   `A_d = M₂₂ᵀ`, `Q_d = A_d M₁₂` (symmetrised).

use nalgebra::DMatrix;

use super::check::{self, MatrixError};
use super::expm::{ExpmError, expm};
use crate::statespace::{StateSpace, StateSpaceError};

/// Why a model could not be discretised.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DiscretizeError {
    #[error(transparent)]
    Input(#[from] MatrixError),
    #[error("the model is already discrete (sample time {dt:?})")]
    AlreadyDiscrete { dt: f64 },
    #[error(transparent)]
    Expm(#[from] ExpmError),
    #[error(transparent)]
    StateSpace(#[from] StateSpaceError),
    /// The matrix whose exponential is taken has entries beyond f64 although the data are finite: the sample
    /// time is too long for the model's rates.
    #[error(
        "{what} overflows f64 (sample time {dt:?}): the sample time is too long for the model's rates; shorten it or rescale the model"
    )]
    Overflow { what: &'static str, dt: f64 },
}

/// Refuses a product with `dt` that left f64, naming it, before the exponential blames a matrix the caller
/// never passed.
fn finite_product(what: &'static str, m: &DMatrix<f64>, dt: f64) -> Result<(), DiscretizeError> {
    if m.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(DiscretizeError::Overflow { what, dt })
    }
}

/// The zero-order-hold equivalent of a continuous-time model with sample time `dt`.
pub fn c2d_zoh(sys: &StateSpace, dt: f64) -> Result<StateSpace, DiscretizeError> {
    if let Some(dt) = sys.dt() {
        return Err(DiscretizeError::AlreadyDiscrete { dt });
    }
    check::positive_scalar("sample time", dt)?;
    let n = check::square("A", sys.a())?;
    let m = sys.b().ncols();
    check::shape("B", sys.b(), n, m)?;
    let (ad, bd) = zoh_blocks(sys.a(), sys.b(), dt)?;
    Ok(StateSpace::new_discrete(
        ad,
        bd,
        sys.c().clone(),
        sys.d().clone(),
        dt,
    )?)
}

/// `(A_d, B_d)` of `ẋ = A x + B u` with `u` held over `dt`: the blocks of `exp([A B; 0 0]·dt)`. The caller has
/// checked that `A` and `B` are finite and of matching rows; a product with `dt` that leaves f64 is an
/// [`DiscretizeError::Overflow`].
pub fn zoh_blocks(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    dt: f64,
) -> Result<(DMatrix<f64>, DMatrix<f64>), DiscretizeError> {
    let (n, m) = (a.nrows(), b.ncols());
    let mut big = DMatrix::<f64>::zeros(n + m, n + m);
    big.view_mut((0, 0), (n, n)).copy_from(&(a * dt));
    big.view_mut((0, n), (n, m)).copy_from(&(b * dt));
    finite_product("[A B]·dt", &big, dt)?;
    let e = expm(&big)?;
    Ok((
        e.view((0, 0), (n, n)).clone_owned(),
        e.view((0, n), (n, m)).clone_owned(),
    ))
}

/// `(A_d, Q_d)` for `ẋ = A x + w`, `E[w(t) w(s)ᵀ] = (G Q_c Gᵀ) δ(t − s)`, sampled every `dt` (Van Loan).
/// `g_qc_gt` is the symmetric positive semidefinite `G Q_c Gᵀ`.
pub fn van_loan(
    a: &DMatrix<f64>,
    g_qc_gt: &DMatrix<f64>,
    dt: f64,
) -> Result<(DMatrix<f64>, DMatrix<f64>), DiscretizeError> {
    let n = check::square("A", a)?;
    check::shape("G Qc Gᵀ", g_qc_gt, n, n)?;
    check::positive_semidefinite("G Qc Gᵀ", g_qc_gt)?;
    check::positive_scalar("sample time", dt)?;
    let mut big = DMatrix::<f64>::zeros(2 * n, 2 * n);
    big.view_mut((0, 0), (n, n)).copy_from(&(-a * dt));
    big.view_mut((0, n), (n, n)).copy_from(&(g_qc_gt * dt));
    big.view_mut((n, n), (n, n))
        .copy_from(&(a.transpose() * dt));
    finite_product("[−A, G Qc Gᵀ; 0, Aᵀ]·dt", &big, dt)?;
    let e = expm(&big)?;
    let ad = e.view((n, n), (n, n)).transpose();
    let qd = &ad * e.view((0, n), (n, n));
    let qd = (&qd + qd.transpose()) * 0.5;
    Ok((ad, qd))
}
