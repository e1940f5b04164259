//! Lyapunov equations by the Bartels–Stewart method.
//!
//! - continuous: `A X + X Aᵀ + Q = 0`, unique when `λᵢ(A) + λⱼ(A) ≠ 0` for all pairs;
//! - discrete: `A X Aᵀ − X + Q = 0`, unique when `λᵢ(A) λⱼ(A) ≠ 1` for all pairs.
//!
//! `A = U T Uᵀ` (one real Schur decomposition) turns either equation into one for `Y = Uᵀ X U` with the
//! quasi-triangular `T`: `T Y + Y Tᵀ = −UᵀQU` resp. `T Y Tᵀ − Y = −UᵀQU`. Reversing the order of the columns of
//! `Y` makes the second factor `P Tᵀ P` upper quasi-triangular too, and the block substitution of
//! [`super::sylvester`](fn@super::sylvester) solves the result in `O(n³)` flops and `O(n²)` memory; the Schur decomposition
//! dominates the cost. Every solution is checked by its relative residual.

use nalgebra::DMatrix;

use super::balance::{frobenius, unit_scale};
use super::check::{self, MatrixError};
use super::schur::{SchurError, real_schur};
use super::sylvester::{Kind, check_unique, reversed, reversed_columns, solve_quasi_triangular};

/// Why a Lyapunov, Sylvester or Stein equation was not solved.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LyapunovError {
    #[error(transparent)]
    Input(#[from] MatrixError),
    #[error(transparent)]
    Schur(#[from] SchurError),
    #[error(
        "the equation has no unique solution: eigenvalues {first:.4e} and {second:.4e} violate the uniqueness condition ({kind})"
    )]
    NoUniqueSolution {
        first: nalgebra::Complex<f64>,
        second: nalgebra::Complex<f64>,
        kind: &'static str,
    },
    #[error("relative residual {residual:e} of the solution exceeds {tolerance:e}")]
    Inaccurate { residual: f64, tolerance: f64 },
    #[error("the solution has entries beyond the range of f64 (about 1.8e308)")]
    Overflow,
}

/// Relative residual above which a solution is refused.
pub(crate) const RESIDUAL_TOLERANCE: f64 = 1e-8;

/// Solves `A X + X Aᵀ + Q = 0` for symmetric `Q`; the solution is symmetric.
pub fn lyap(a: &DMatrix<f64>, q: &DMatrix<f64>) -> Result<DMatrix<f64>, LyapunovError> {
    validate(a, q)?;
    let (q, size) = unit_size(q);
    // A change of the unit of time (a power of two, exact) divides A and Q alike and keeps X: A of unit size, so
    // that the uniqueness test and the residual do not overflow for rates of 1e160 (which were refused as
    // λᵢ + λⱼ = 0).
    let unit = unit_scale(a.amax());
    let (a, q) = (&(a / unit), &(q / unit));
    let scale = frobenius(a).max(f64::MIN_POSITIVE);
    let x = solve_symmetric(a, q, Kind::Continuous, scale, "λᵢ + λⱼ = 0").map_err(|e| match e {
        // The eigenvalues of the caller's A.
        LyapunovError::NoUniqueSolution {
            first,
            second,
            kind,
        } => LyapunovError::NoUniqueSolution {
            first: first * unit,
            second: second * unit,
            kind,
        },
        e => e,
    })?;
    let residual = frobenius(&(a * &x + &x * a.transpose() + q))
        / (2.0 * frobenius(a) * frobenius(&x) + frobenius(q)).max(f64::MIN_POSITIVE);
    accept(x, residual).and_then(|x| scaled_back(x, size))
}

/// Solves `A X Aᵀ − X + Q = 0` for symmetric `Q`; the solution is symmetric.
pub fn dlyap(a: &DMatrix<f64>, q: &DMatrix<f64>) -> Result<DMatrix<f64>, LyapunovError> {
    validate(a, q)?;
    let (q, size) = unit_size(q);
    let q = &q;
    let x = solve_symmetric(a, q, Kind::Discrete, 1.0, "λᵢ λⱼ = 1")?;
    let axa = a * &x * a.transpose();
    let residual = frobenius(&(&axa - &x + q))
        / (frobenius(&axa) + frobenius(&x) + frobenius(q)).max(f64::MIN_POSITIVE);
    accept(x, residual).and_then(|x| scaled_back(x, size))
}

/// `Q` divided by a power of two (exact) that brings its largest entry near 1, and that power: `X` is linear in
/// `Q`, so the equation is solved for `Q / s` and `X` scaled back by `s`, away from overflow (a `Q` of 1e160 has
/// squares beyond `f64`) and underflow.
fn unit_size(q: &DMatrix<f64>) -> (DMatrix<f64>, f64) {
    let s = unit_scale(q.amax());
    (q / s, s)
}

/// `x · size`, refused when that is not finite (a solution beyond `f64`).
fn scaled_back(x: DMatrix<f64>, size: f64) -> Result<DMatrix<f64>, LyapunovError> {
    let x = x * size;
    if x.iter().all(|v| v.is_finite()) {
        Ok(x)
    } else {
        Err(LyapunovError::Overflow)
    }
}

/// `X` of `A X + X Aᵀ + Q = 0` or `A X Aᵀ − X + Q = 0` through one Schur decomposition of `A` (see the module
/// docs), symmetrised.
fn solve_symmetric(
    a: &DMatrix<f64>,
    q: &DMatrix<f64>,
    kind: Kind,
    scale: f64,
    condition: &'static str,
) -> Result<DMatrix<f64>, LyapunovError> {
    let (u, t) = real_schur(a)?;
    let s = reversed(&t.transpose());
    check_unique(&t, &s, kind, scale, condition)?;
    let f = -(u.transpose() * q * &u);
    let w = solve_quasi_triangular(&t, &s, &reversed_columns(&f), kind)?;
    let y = reversed_columns(&w);
    Ok(symmetrize(&(&u * y * u.transpose())))
}

fn validate(a: &DMatrix<f64>, q: &DMatrix<f64>) -> Result<usize, LyapunovError> {
    let n = check::square("A", a)?;
    check::shape("Q", q, n, n)?;
    check::symmetric("Q", q)?;
    Ok(n)
}

/// `x` when it is finite and its relative residual is at most [`RESIDUAL_TOLERANCE`].
pub(crate) fn accept(x: DMatrix<f64>, residual: f64) -> Result<DMatrix<f64>, LyapunovError> {
    if residual.is_finite() && residual <= RESIDUAL_TOLERANCE && x.iter().all(|v| v.is_finite()) {
        Ok(x)
    } else {
        Err(LyapunovError::Inaccurate {
            residual,
            tolerance: RESIDUAL_TOLERANCE,
        })
    }
}

pub(crate) fn symmetrize(x: &DMatrix<f64>) -> DMatrix<f64> {
    (x + x.transpose()) * 0.5
}
