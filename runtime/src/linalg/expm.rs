//! The matrix exponential by Padé approximation with scaling and squaring (Higham 2005, "The scaling and
//! squaring method for the matrix exponential revisited", Algorithm 2.3).
//!
//! For `‖A‖₁ ≤ θₘ` the diagonal Padé approximant `rₘ` of degree `m ∈ {3, 5, 7, 9}` is accurate to unit
//! roundoff in exact arithmetic; otherwise `A` is scaled by `2⁻ˢ` so that `‖2⁻ˢA‖₁ ≤ θ₁₃`, `r₁₃` is evaluated
//! and squared `s` times. Cost: about `6 + s` matrix products and one LU solve, `O(n³)`.
//!
//! Models in physical units are badly scaled (stiffness over inertia of 10⁸ next to unit entries), which makes
//! `‖A‖₁` far larger than the spectral radius, forces many squarings and loses accuracy with each. So `A` is
//! first balanced by an exact power-of-two diagonal similarity, `e^A = D e^{D⁻¹AD} D⁻¹` (see
//! [`super::balance`]), whenever that reduces `‖A‖₁`.

use nalgebra::DMatrix;

use super::balance::balancing_scales;
use super::check::{self, MatrixError};

/// Why the exponential could not be computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ExpmError {
    #[error(transparent)]
    Input(#[from] MatrixError),
    #[error("the Padé denominator is singular (‖A‖₁ = {norm:?})")]
    SingularDenominator { norm: f64 },
    #[error("the exponential overflows (‖A‖₁ = {norm:?})")]
    Overflow { norm: f64 },
}

const THETA: [(usize, f64); 4] = [
    (3, 1.495585217958292e-2),
    (5, 2.53939833006323e-1),
    (7, 9.504178996162932e-1),
    (9, 2.097847961257068e0),
];
const THETA_13: f64 = 5.371920351148152e0;

const B3: [f64; 4] = [120.0, 60.0, 12.0, 1.0];
const B5: [f64; 6] = [30240.0, 15120.0, 3360.0, 420.0, 30.0, 1.0];
const B7: [f64; 8] = [
    17297280.0, 8648640.0, 1995840.0, 277200.0, 25200.0, 1512.0, 56.0, 1.0,
];
const B9: [f64; 10] = [
    17643225600.0,
    8821612800.0,
    2075673600.0,
    302702400.0,
    30270240.0,
    2162160.0,
    110880.0,
    3960.0,
    90.0,
    1.0,
];
const B13: [f64; 14] = [
    64764752532480000.0,
    32382376266240000.0,
    7771770303897600.0,
    1187353796428800.0,
    129060195264000.0,
    10559470521600.0,
    670442572800.0,
    33522128640.0,
    1323241920.0,
    40840800.0,
    960960.0,
    16380.0,
    182.0,
    1.0,
];

/// `e^A` for a square, finite `A`.
pub fn expm(a: &DMatrix<f64>) -> Result<DMatrix<f64>, ExpmError> {
    check::square("A", a)?;
    let d = balancing_scales(a);
    let balanced = DMatrix::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)] * d[j] / d[i]);
    if one_norm(&balanced) < one_norm(a) {
        let e = expm_unbalanced(&balanced)?;
        Ok(DMatrix::from_fn(a.nrows(), a.ncols(), |i, j| {
            e[(i, j)] * d[i] / d[j]
        }))
    } else {
        expm_unbalanced(a)
    }
}

/// Higham's algorithm on a validated square matrix.
fn expm_unbalanced(a: &DMatrix<f64>) -> Result<DMatrix<f64>, ExpmError> {
    let n = a.nrows();
    let norm = one_norm(a);
    let identity = DMatrix::<f64>::identity(n, n);
    // A² of the unscaled A only where a low-degree approximant serves (‖A‖₁ ≤ θ₉): above about 1e154 it
    // overflows, although the exponential of a stable A of that size is finite (near zero).
    let a2 = if norm <= THETA[THETA.len() - 1].1 {
        a * a
    } else {
        DMatrix::zeros(0, 0)
    };
    for &(m, theta) in &THETA {
        if norm <= theta {
            let coeffs: &[f64] = match m {
                3 => &B3,
                5 => &B5,
                7 => &B7,
                _ => &B9,
            };
            // U = A Σ b_{2k+1} A^{2k}, V = Σ b_{2k} A^{2k}
            let mut u_sum = &identity * coeffs[1];
            let mut v_sum = &identity * coeffs[0];
            let mut power = identity.clone();
            for k in 1..=m / 2 {
                power = &power * &a2;
                u_sum += &power * coeffs[2 * k + 1];
                v_sum += &power * coeffs[2 * k];
            }
            let u = a * u_sum;
            return pade_solve(&u, &v_sum, norm);
        }
    }
    // Scaling: ‖A / 2ˢ‖₁ ≤ θ₁₃.
    let s = if norm > THETA_13 {
        (norm / THETA_13).log2().ceil().max(0.0) as i32
    } else {
        0
    };
    // 2⁻ˢ stays a normal number for every finite ‖A‖₁ (s ≤ 1022).
    if s > 1022 {
        return Err(ExpmError::Overflow { norm });
    }
    let scale = 2f64.powi(-s);
    let a1 = a * scale;
    let a2 = &a1 * &a1;
    let a4 = &a2 * &a2;
    let a6 = &a4 * &a2;
    let b = &B13;
    let u_inner = &a6 * (&a6 * b[13] + &a4 * b[11] + &a2 * b[9]);
    let u = &a1 * (u_inner + &a6 * b[7] + &a4 * b[5] + &a2 * b[3] + &identity * b[1]);
    let v = &a6 * (&a6 * b[12] + &a4 * b[10] + &a2 * b[8])
        + &a6 * b[6]
        + &a4 * b[4]
        + &a2 * b[2]
        + &identity * b[0];
    let mut r = pade_solve(&u, &v, norm)?;
    for _ in 0..s {
        r = &r * &r;
    }
    if r.iter().all(|v| v.is_finite()) {
        Ok(r)
    } else {
        Err(ExpmError::Overflow { norm })
    }
}

/// `r = (V − U)⁻¹ (V + U)`.
fn pade_solve(u: &DMatrix<f64>, v: &DMatrix<f64>, norm: f64) -> Result<DMatrix<f64>, ExpmError> {
    let r = (v - u)
        .lu()
        .solve(&(v + u))
        .ok_or(ExpmError::SingularDenominator { norm })?;
    if r.iter().all(|x| x.is_finite()) {
        Ok(r)
    } else {
        Err(ExpmError::Overflow { norm })
    }
}

/// The maximum absolute column sum.
fn one_norm(a: &DMatrix<f64>) -> f64 {
    a.column_iter()
        .map(|c| c.iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}
