//! Linear-quadratic regulators.
//!
//! Continuous: minimise `∫ xᵀQx + 2xᵀNu + uᵀRu dt` subject to `ẋ = Ax + Bu`; the optimum is `u = −Kx` with
//! `K = R⁻¹(BᵀX + Nᵀ)` and `X` the stabilising solution of the CARE (as MATLAB's `lqr` and python-control's
//! `lqr`, which return the same `K`, `X` and closed-loop eigenvalues).
//!
//! Discrete: minimise `Σ xₖᵀQxₖ + uₖᵀRuₖ` subject to `xₖ₊₁ = Axₖ + Buₖ`; `K = (R + BᵀXB)⁻¹BᵀXA` with `X` the
//! stabilising solution of the DARE (MATLAB `dlqr`, python-control `dlqr`).

use nalgebra::DMatrix;

use crate::linalg::{Riccati, RiccatiError, care_with_cross, dare_with_cross};

/// Continuous LQR: `K` (with `u = −Kx`), `X` and the eigenvalues of `A − BK` in a [`Riccati`].
pub fn lqr(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
) -> Result<Riccati, RiccatiError> {
    care_with_cross(a, b, q, r, None)
}

/// Continuous LQR with the cross weight `N` (cost term `2xᵀNu`).
pub fn lqr_with_cross(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    n: &DMatrix<f64>,
) -> Result<Riccati, RiccatiError> {
    care_with_cross(a, b, q, r, Some(n))
}

/// Discrete LQR: `K = (R + BᵀXB)⁻¹BᵀXA` (with `u[k] = −K x[k]`), `X` and the eigenvalues of `A − BK`.
pub fn dlqr(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
) -> Result<Riccati, RiccatiError> {
    dare_with_cross(a, b, q, r, None)
}

/// Discrete LQR with the cross weight `N` (cost term `2xᵀNu`).
pub fn dlqr_with_cross(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    n: &DMatrix<f64>,
) -> Result<Riccati, RiccatiError> {
    dare_with_cross(a, b, q, r, Some(n))
}
