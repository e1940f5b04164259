//! Sylvester and Stein equations by the Bartels–Stewart method on real Schur forms.
//!
//! - continuous: `A X + X B + C = 0`, unique when `λᵢ(A) + μⱼ(B) ≠ 0` for all pairs;
//! - discrete (Stein): `A X B − X + C = 0`, unique when `λᵢ(A) μⱼ(B) ≠ 1` for all pairs.
//!
//! `A = U T Uᵀ`, `B = V S Vᵀ` (real Schur forms) turn either equation into one for `Y = Uᵀ X V` with the
//! quasi-triangular `T` and `S`, which `solve_quasi_triangular` solves by substitution over the `1x1` and `2x2`
//! diagonal blocks: the column blocks of `S` forwards, in each the row blocks of `T` backwards, each a linear
//! system of order at most 4. The substitution costs `O(m²n + mn²)` flops and the two Schur decompositions
//! `O(m³ + n³)`, so the whole solve is `O(n³)` (no `n x n` system per column). The Lyapunov equations
//! ([`super::lyapunov`]) are the special case `B = Aᵀ`, which needs one Schur decomposition.

use nalgebra::{DMatrix, DVector};

use super::check;
use super::lyapunov::{LyapunovError, RESIDUAL_TOLERANCE, accept};
use super::schur::{block_eigenvalues, diagonal_blocks, real_schur};

/// Which equation a quasi-triangular solve is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    /// `T Y + Y S = F`.
    Continuous,
    /// `T Y S − Y = F`.
    Discrete,
}

/// Solves `A X + X B + C = 0` (`A` is `m x m`, `B` is `n x n`, `C` and `X` are `m x n`); scipy's
/// `solve_sylvester(A, B, -C)`. Refused: non-finite or mis-shaped inputs, `λᵢ(A) + μⱼ(B) ≈ 0`, or a relative
/// residual above `1e-8`.
pub fn sylvester(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
) -> Result<DMatrix<f64>, LyapunovError> {
    let (u, t, s, v) = validated_schur_pair(a, b, c)?;
    let scale = (a.norm() + b.norm()).max(f64::MIN_POSITIVE);
    check_unique(&t, &s, Kind::Continuous, scale, "λᵢ(A) + μⱼ(B) = 0")?;
    let f = -(u.transpose() * c * &v);
    let y = solve_quasi_triangular(&t, &s, &f, Kind::Continuous)?;
    let x = &u * y * v.transpose();
    let residual = (a * &x + &x * b + c).norm()
        / ((a.norm() + b.norm()) * x.norm() + c.norm()).max(f64::MIN_POSITIVE);
    accept(x, residual)
}

/// Solves the Stein equation `A X B − X + C = 0` (shapes as in [`sylvester`]). Refused: non-finite or
/// mis-shaped inputs, `λᵢ(A) μⱼ(B) ≈ 1`, or a relative residual above `1e-8`.
pub fn stein(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
) -> Result<DMatrix<f64>, LyapunovError> {
    let (u, t, s, v) = validated_schur_pair(a, b, c)?;
    check_unique(&t, &s, Kind::Discrete, 1.0, "λᵢ(A) μⱼ(B) = 1")?;
    let f = -(u.transpose() * c * &v);
    let y = solve_quasi_triangular(&t, &s, &f, Kind::Discrete)?;
    let x = &u * y * v.transpose();
    let axb = a * &x * b;
    let residual =
        (&axb - &x + c).norm() / (axb.norm() + x.norm() + c.norm()).max(f64::MIN_POSITIVE);
    accept(x, residual)
}

type SchurPair = (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, DMatrix<f64>);

/// Checks shapes and finiteness, then `A = U T Uᵀ`, `B = V S Vᵀ` as `(U, T, S, V)`.
fn validated_schur_pair(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    c: &DMatrix<f64>,
) -> Result<SchurPair, LyapunovError> {
    let m = check::square("A", a)?;
    let n = check::square("B", b)?;
    check::shape("C", c, m, n)?;
    let (u, t) = real_schur(a)?;
    let (v, s) = real_schur(b)?;
    Ok((u, t, s, v))
}

/// Refuses `T`, `S` (named by `condition` in the error) with `λᵢ + μⱼ ≈ 0` (continuous, relative to `scale`) or `λᵢ μⱼ ≈ 1` (discrete), which
/// leave the equation without a unique solution.
pub(crate) fn check_unique(
    t: &DMatrix<f64>,
    s: &DMatrix<f64>,
    kind: Kind,
    scale: f64,
    condition: &'static str,
) -> Result<(), LyapunovError> {
    let lt = block_eigenvalues(t)?;
    let ls = block_eigenvalues(s)?;
    for &l in &lt {
        for &mu in &ls {
            let gap = match kind {
                Kind::Continuous => (l + mu).norm(),
                Kind::Discrete => (l * mu - 1.0).norm(),
            };
            if gap <= 1e3 * f64::EPSILON * scale {
                return Err(LyapunovError::NoUniqueSolution {
                    first: l,
                    second: mu,
                    kind: condition,
                });
            }
        }
    }
    Ok(())
}

/// Solves `T Y + Y S = F` (continuous) or `T Y S − Y = F` (discrete) for upper quasi-triangular `T` (`m x m`)
/// and `S` (`n x n`) by block substitution; see the module docs.
pub(crate) fn solve_quasi_triangular(
    t: &DMatrix<f64>,
    s: &DMatrix<f64>,
    f: &DMatrix<f64>,
    kind: Kind,
) -> Result<DMatrix<f64>, LyapunovError> {
    let (m, n) = f.shape();
    let row_blocks = diagonal_blocks(t)?;
    let col_blocks = diagonal_blocks(s)?;
    let mut y = DMatrix::<f64>::zeros(m, n);
    for &(j0, q) in &col_blocks {
        // G_J = F_J − Y_{<J} S_{<J,J} (continuous) or F_J − T (Y_{<J} S_{<J,J}) (discrete): the solved columns.
        let mut g = f.columns(j0, q).clone_owned();
        if j0 > 0 {
            let known = y.columns(0, j0) * s.view((0, j0), (j0, q));
            match kind {
                Kind::Continuous => g -= known,
                Kind::Discrete => g -= t * known,
            }
        }
        let s_jj = s.view((j0, j0), (q, q)).clone_owned();
        for &(i0, p) in row_blocks.iter().rev() {
            let t_ii = t.view((i0, i0), (p, p)).clone_owned();
            let rhs = g.view((i0, 0), (p, q)).clone_owned();
            let y_ij = solve_small(&t_ii, &s_jj, &rhs, kind)?;
            y.view_mut((i0, j0), (p, q)).copy_from(&y_ij);
            if i0 > 0 {
                // The rows above see T_{<I,I} Y_IJ (times S_JJ in the discrete case).
                let coupled = match kind {
                    Kind::Continuous => y_ij,
                    Kind::Discrete => &y_ij * &s_jj,
                };
                let update = t.view((0, i0), (i0, p)) * coupled;
                let mut above = g.rows_mut(0, i0);
                above -= update;
            }
        }
    }
    Ok(y)
}

/// Solves the `p x q` block equation `T Y + Y S = G` or `T Y S − Y = G` (`p, q ≤ 2`) through its Kronecker form
/// (column-major `vec`): `(I ⊗ T + Sᵀ ⊗ I) vec Y` resp. `(Sᵀ ⊗ T − I) vec Y`, by Gaussian elimination with
/// complete pivoting.
fn solve_small(
    t: &DMatrix<f64>,
    s: &DMatrix<f64>,
    g: &DMatrix<f64>,
    kind: Kind,
) -> Result<DMatrix<f64>, LyapunovError> {
    let (p, q) = g.shape();
    let size = p * q;
    let mut k = DMatrix::<f64>::zeros(size, size);
    for b in 0..q {
        for a in 0..q {
            for i in 0..p {
                for j in 0..p {
                    // Row (b, i) of vec Y's equation, column (a, j): Y[j, a] enters through T[i, j] S[a, b].
                    let value = match kind {
                        Kind::Continuous => {
                            let from_t = if a == b { t[(i, j)] } else { 0.0 };
                            let from_s = if i == j { s[(a, b)] } else { 0.0 };
                            from_t + from_s
                        }
                        Kind::Discrete => {
                            let identity = if a == b && i == j { 1.0 } else { 0.0 };
                            t[(i, j)] * s[(a, b)] - identity
                        }
                    };
                    k[(b * p + i, a * p + j)] = value;
                }
            }
        }
    }
    let rhs = DVector::from_column_slice(g.as_slice());
    let sol = k
        .full_piv_lu()
        .solve(&rhs)
        .ok_or(LyapunovError::Inaccurate {
            residual: f64::INFINITY,
            tolerance: RESIDUAL_TOLERANCE,
        })?;
    Ok(DMatrix::from_column_slice(p, q, sol.as_slice()))
}

/// `P M P` for the reversal permutation `P`: maps a lower quasi-triangular matrix to an upper one with the same
/// blocks (so `Tᵀ` becomes a valid second factor of [`solve_quasi_triangular`]).
pub(crate) fn reversed(mat: &DMatrix<f64>) -> DMatrix<f64> {
    let (r, c) = mat.shape();
    DMatrix::from_fn(r, c, |i, j| mat[(r - 1 - i, c - 1 - j)])
}

/// `M P`: the columns of `M` in reverse order.
pub(crate) fn reversed_columns(mat: &DMatrix<f64>) -> DMatrix<f64> {
    let (r, c) = mat.shape();
    DMatrix::from_fn(r, c, |i, j| mat[(i, c - 1 - j)])
}
