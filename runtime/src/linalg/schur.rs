//! Real Schur decomposition and eigenvalues without panics.
//!
//! nalgebra's `Schur::try_new` returns `None` when the QR iteration does not converge; these wrappers turn that
//! into an error value and split the quasi-triangular factor into its 1x1 and 2x2 diagonal blocks.

use super::balance::unit_scale;
use nalgebra::{Complex, DMatrix, Schur};

/// Why a Schur decomposition, or the reading of a quasi-triangular factor, failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SchurError {
    #[error("a Schur decomposition needs a square matrix, got {rows}x{cols}")]
    NotSquare { rows: usize, cols: usize },
    #[error("entry ({row}, {col}) of the matrix is not a finite number")]
    NonFinite { row: usize, col: usize },
    #[error("the matrix is not upper quasi-triangular: 2x2 blocks overlap at row {row}")]
    NotQuasiTriangular { row: usize },
    #[error("the real Schur decomposition of a {n}x{n} matrix did not converge")]
    NoConvergence { n: usize },
    /// Finite entries whose eigenvalues (at most `n` times the largest entry) exceed f64.
    #[error("the eigenvalues of the {n}x{n} matrix leave the range of f64; rescale it")]
    OutOfRange { n: usize },
}

/// `a`'s size when it is square with finite entries: the QR iteration would otherwise return NaN factors as if
/// they were a decomposition.
fn checked(a: &DMatrix<f64>) -> Result<usize, SchurError> {
    let (rows, cols) = a.shape();
    if rows != cols {
        return Err(SchurError::NotSquare { rows, cols });
    }
    if let Some(k) = a.iter().position(|v| !v.is_finite()) {
        return Err(SchurError::NonFinite {
            row: k % rows,
            col: k / rows,
        });
    }
    Ok(rows)
}

/// The scale of [`unit_scale`] for `a`. The QR iteration runs on `a / s` and its results are scaled back by `s`:
/// on a matrix of entries near 1e-200 the iteration's products would underflow (eigenvalues of 0, on the
/// stability boundary).
fn matrix_scale(a: &DMatrix<f64>) -> f64 {
    unit_scale(a.amax())
}

/// `a = u t uᵀ` with `u` orthogonal and `t` upper quasi-triangular.
pub fn real_schur(a: &DMatrix<f64>) -> Result<(DMatrix<f64>, DMatrix<f64>), SchurError> {
    let n = checked(a)?;
    let scale = matrix_scale(a);
    let (u, t) = Schur::try_new(a / scale, f64::EPSILON, 1000 * n.max(10))
        .ok_or(SchurError::NoConvergence { n })?
        .unpack();
    let t = t * scale;
    if t.iter().chain(u.iter()).all(|v| v.is_finite()) {
        Ok((u, t))
    } else {
        Err(SchurError::OutOfRange { n })
    }
}

/// The eigenvalues of a square matrix, in the order of the diagonal of its real Schur form.
pub fn eigenvalues(a: &DMatrix<f64>) -> Result<Vec<Complex<f64>>, SchurError> {
    let n = checked(a)?;
    if n == 0 {
        // A model without states (a static gain) has none; nalgebra's eigenvalues of a 0×0 matrix index out of it.
        return Ok(Vec::new());
    }
    let scale = matrix_scale(a);
    let values: Vec<Complex<f64>> = Schur::try_new(a / scale, f64::EPSILON, 1000 * n.max(10))
        .ok_or(SchurError::NoConvergence { n })?
        .complex_eigenvalues()
        .iter()
        .map(|l| l * scale)
        .collect();
    // A result is never NaN or infinite without an error.
    if values.iter().all(|l| l.re.is_finite() && l.im.is_finite()) {
        Ok(values)
    } else {
        Err(SchurError::OutOfRange { n })
    }
}

/// The diagonal blocks of an upper quasi-triangular matrix as `(start, size)` with size 1 or 2.
///
/// nalgebra sets deflated subdiagonal entries to exactly zero, so any non-zero subdiagonal entry starts a 2x2
/// block; two consecutive non-zero subdiagonal entries mean `t` is not quasi-triangular.
pub fn diagonal_blocks(t: &DMatrix<f64>) -> Result<Vec<(usize, usize)>, SchurError> {
    let (n, cols) = t.shape();
    if n != cols {
        return Err(SchurError::NotSquare { rows: n, cols });
    }
    let mut blocks = Vec::new();
    let mut j = 0;
    while j < n {
        if j + 1 < n && t[(j + 1, j)] != 0.0 {
            if j + 2 < n && t[(j + 2, j + 1)] != 0.0 {
                return Err(SchurError::NotQuasiTriangular { row: j + 1 });
            }
            blocks.push((j, 2));
            j += 2;
        } else {
            blocks.push((j, 1));
            j += 1;
        }
    }
    Ok(blocks)
}

/// The eigenvalues of an upper quasi-triangular matrix (a real Schur factor), read from its diagonal blocks.
pub fn block_eigenvalues(t: &DMatrix<f64>) -> Result<Vec<Complex<f64>>, SchurError> {
    let mut out = Vec::with_capacity(t.nrows());
    for (s, size) in diagonal_blocks(t)? {
        if size == 1 {
            out.push(Complex::new(t[(s, s)], 0.0));
            continue;
        }
        let (a, b, c, d) = (t[(s, s)], t[(s, s + 1)], t[(s + 1, s)], t[(s + 1, s + 1)]);
        let mean = 0.5 * (a + d);
        let disc = (0.5 * (a - d)).powi(2) + b * c;
        if disc >= 0.0 {
            let r = disc.sqrt();
            out.push(Complex::new(mean + r, 0.0));
            out.push(Complex::new(mean - r, 0.0));
        } else {
            let r = (-disc).sqrt();
            out.push(Complex::new(mean, r));
            out.push(Complex::new(mean, -r));
        }
    }
    Ok(out)
}
