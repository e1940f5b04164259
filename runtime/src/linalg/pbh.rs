//! Controllability and observability: Popov–Belevitch–Hautus tests and the Kalman rank tests.
//!
//! A mode `λ` of `A` is uncontrollable when `rank [A − λI, B] < n`; then a left eigenvector `w` with
//! `wᴴ A = λ wᴴ` and `wᴴ B = 0` exists and is the *direction* of the mode (the combination of states that no input
//! can move). Dually `λ` is unobservable when `rank [A − λI; C] < n`, with a right eigenvector `v`, `A v = λ v`,
//! `C v = 0` (the state direction invisible in the outputs).
//!
//! Rank is decided from the smallest singular value of the PBH matrix relative to its norm, after balancing `A`
//! (see [`super::balance`]) and scaling `B` (resp. `C`) to the norm of `A`, both of which preserve the rank and
//! make the decision independent of the units of the states and inputs. A mode is reported when
//! `σ_min / ‖[A − λI, B]‖ < PBH_TOLERANCE`. Near a defective eigenvalue the computed `λ` may be perturbed by
//! about `√ε`, so the tolerance is generous; the Riccati solvers additionally check their results.

use nalgebra::{Complex, DMatrix, DVector};

use super::balance::{balanced_norm, balancing_scales, frobenius, unit_scale};
use super::check::{self, MatrixError};
use super::schur::{SchurError, eigenvalues};

/// Relative smallest singular value below which a PBH matrix is treated as rank deficient.
pub const PBH_TOLERANCE: f64 = 1e-8;

/// Whether stability means `Re λ < 0` or `|λ| < 1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Domain {
    Continuous,
    Discrete,
}

impl Domain {
    /// Whether `λ` is asymptotically stable in this domain with a margin, so that modes on the stability
    /// boundary (computed with rounding error) count as unstable: `Re λ < −1e-12 · scale` in continuous time,
    /// where `scale` is the norm of the balanced matrix the eigenvalue came from (eigenvalue errors are
    /// proportional to it, and a margin in absolute units would depend on the unit of time: a model in
    /// 10⁻²⁰ of its rates' units was called unstable), and `|λ| < 1 − 1e-12 · max(1, scale)` in discrete time
    /// (pass `scale = 1`).
    pub fn is_stable(self, lambda: Complex<f64>, scale: f64) -> bool {
        match self {
            Domain::Continuous => lambda.re < -1e-12 * scale,
            Domain::Discrete => lambda.norm() < 1.0 - 1e-12 * scale.max(1.0),
        }
    }
}

/// An uncontrollable or unobservable mode.
#[derive(Clone, Debug, PartialEq)]
pub struct Mode {
    pub eigenvalue: Complex<f64>,
    /// Unit-norm state direction: the left eigenvector `w` (`wᴴB = 0`) for an uncontrollable mode, the right
    /// eigenvector `v` (`Cv = 0`) for an unobservable one.
    pub direction: DVector<Complex<f64>>,
    /// `σ_min / ‖PBH matrix‖` after balancing: 0 for an exactly uncontrollable (unobservable) mode.
    pub margin: f64,
}

/// Why a PBH or rank test could not be carried out.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PbhError {
    #[error(transparent)]
    Input(#[from] MatrixError),
    #[error(transparent)]
    Schur(#[from] SchurError),
    #[error("the singular value decomposition of a {rows}x{cols} matrix did not converge")]
    Svd { rows: usize, cols: usize },
}

/// Every mode of `A` (one of each complex-conjugate pair) with its PBH controllability margin, sorted by
/// increasing margin. [`uncontrollable_modes`] keeps those below [`PBH_TOLERANCE`].
pub fn controllability_margins(a: &DMatrix<f64>, b: &DMatrix<f64>) -> Result<Vec<Mode>, PbhError> {
    controllability_margins_where(a, b, |_| true)
}

/// The modes of `A` whose eigenvalue satisfies `keep`, with their PBH controllability margins, sorted by
/// increasing margin: one SVD per kept mode, none for the others.
fn controllability_margins_where(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    keep: impl Fn(Complex<f64>) -> bool,
) -> Result<Vec<Mode>, PbhError> {
    let n = check::square("A", a)?;
    check::shape("B", b, n, b.ncols())?;
    // The dual system (Aᵀ, Bᵀ): an uncontrollable left eigenvector of A is an unobservable right one of Aᵀ.
    let mut modes = observability_margins_where(&a.transpose(), &b.transpose(), keep)?;
    for m in &mut modes {
        // wᴴ A = λ wᴴ  ⇔  Aᵀ w̄ = λ w̄: the right vector of the dual is the conjugate of w.
        m.direction = m.direction.map(|z| z.conj());
    }
    Ok(modes)
}

/// Every mode of `A` (one of each complex-conjugate pair) with its PBH observability margin, sorted by
/// increasing margin. [`unobservable_modes`] keeps those below [`PBH_TOLERANCE`].
pub fn observability_margins(a: &DMatrix<f64>, c: &DMatrix<f64>) -> Result<Vec<Mode>, PbhError> {
    observability_margins_where(a, c, |_| true)
}

/// The modes of `A` whose eigenvalue satisfies `keep`, with their PBH observability margins, sorted by
/// increasing margin: one SVD per kept mode, none for the others.
fn observability_margins_where(
    a: &DMatrix<f64>,
    c: &DMatrix<f64>,
    keep: impl Fn(Complex<f64>) -> bool,
) -> Result<Vec<Mode>, PbhError> {
    let n = check::square("A", a)?;
    check::shape("C", c, c.nrows(), n)?;
    let d = balancing_scales(a);
    let mut ab = a.clone();
    // C at unit magnitude before the balancing multiplies its columns (1e300 times a scale of 2¹⁰⁰ overflowed).
    let mut cb = c / unit_scale(c.amax());
    for j in 0..n {
        for i in 0..n {
            ab[(i, j)] *= d[j] / d[i];
        }
        for i in 0..cb.nrows() {
            cb[(i, j)] *= d[j];
        }
    }
    // A and C by powers of two (exact) to unit magnitude: the norms, their ratio and the PBH matrices neither
    // overflow nor underflow whatever the units (a subnormal C made the ratio infinite), and the eigenvalues are
    // scaled back when reported.
    let a_scale = unit_scale(ab.amax());
    ab /= a_scale;
    cb /= unit_scale(cb.amax());
    let a_norm = frobenius(&ab);
    let c_norm = frobenius(&cb);
    if c_norm > 0.0 && a_norm > 0.0 {
        cb *= a_norm / c_norm;
    }
    let p = cb.nrows();
    let mut modes = Vec::new();
    for lambda in eigenvalues(&ab)? {
        if lambda.im < 0.0 || !keep(lambda * a_scale) {
            continue;
        }
        let mut m = DMatrix::<Complex<f64>>::zeros(n + p, n);
        for j in 0..n {
            for i in 0..n {
                m[(i, j)] = Complex::new(ab[(i, j)], 0.0);
            }
            m[(j, j)] -= lambda;
            for i in 0..p {
                m[(n + i, j)] = Complex::new(cb[(i, j)], 0.0);
            }
        }
        let scale = frobenius(&m).max(f64::MIN_POSITIVE);
        let (rows, cols) = m.shape();
        let svd = check::svd(m, false, true, 10_000).ok_or(PbhError::Svd { rows, cols })?;
        let sigma_min = svd.singular_values[n - 1];
        let v_t = svd.v_t.ok_or(PbhError::Svd { rows, cols })?;
        // The right singular vector for σ_min, mapped back through the balancing: v = D v_b.
        let mut direction =
            DVector::<Complex<f64>>::from_fn(n, |i, _| v_t[(n - 1, i)].conj() * d[i]);
        let norm = direction.norm();
        if norm > 0.0 {
            direction /= Complex::new(norm, 0.0);
        }
        modes.push(Mode {
            eigenvalue: lambda * a_scale,
            direction,
            margin: sigma_min / scale,
        });
    }
    modes.sort_by(|x, y| x.margin.total_cmp(&y.margin));
    Ok(modes)
}

/// The uncontrollable modes of `(A, B)` by the PBH test (one of each conjugate pair).
pub fn uncontrollable_modes(a: &DMatrix<f64>, b: &DMatrix<f64>) -> Result<Vec<Mode>, PbhError> {
    let mut modes = controllability_margins(a, b)?;
    modes.retain(|m| m.margin < PBH_TOLERANCE);
    Ok(modes)
}

/// The unobservable modes of `(A, C)` by the PBH test (one of each conjugate pair).
pub fn unobservable_modes(a: &DMatrix<f64>, c: &DMatrix<f64>) -> Result<Vec<Mode>, PbhError> {
    let mut modes = observability_margins(a, c)?;
    modes.retain(|m| m.margin < PBH_TOLERANCE);
    Ok(modes)
}

/// The least controllable of the uncontrollable modes of `(A, B)` that are not asymptotically stable, if any.
/// Only the modes that are not stable are tested (stable modes need no input), so a stable system costs one
/// eigenvalue decomposition and no SVD.
pub fn unstabilizable_mode(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    domain: Domain,
) -> Result<Option<Mode>, PbhError> {
    let scale = stability_scale(a, domain);
    let modes = controllability_margins_where(a, b, |l| !domain.is_stable(l, scale))?;
    Ok(modes.into_iter().find(|m| m.margin < PBH_TOLERANCE))
}

/// The least observable of the unobservable modes of `(A, C)` that are not asymptotically stable, if any;
/// only the modes that are not stable are tested.
pub fn undetectable_mode(
    a: &DMatrix<f64>,
    c: &DMatrix<f64>,
    domain: Domain,
) -> Result<Option<Mode>, PbhError> {
    let scale = stability_scale(a, domain);
    let modes = observability_margins_where(a, c, |l| !domain.is_stable(l, scale))?;
    Ok(modes.into_iter().find(|m| m.margin < PBH_TOLERANCE))
}

/// Whether every mode of `A` that is not asymptotically stable is controllable from `B`.
pub fn is_stabilizable(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    domain: Domain,
) -> Result<bool, PbhError> {
    Ok(unstabilizable_mode(a, b, domain)?.is_none())
}

/// Whether every mode of `A` that is not asymptotically stable is observable from `C`.
pub fn is_detectable(a: &DMatrix<f64>, c: &DMatrix<f64>, domain: Domain) -> Result<bool, PbhError> {
    Ok(undetectable_mode(a, c, domain)?.is_none())
}

/// The controllability matrix `[B, AB, …, Aⁿ⁻¹B]`.
pub fn controllability_matrix(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
) -> Result<DMatrix<f64>, PbhError> {
    let n = check::square("A", a)?;
    check::shape("B", b, n, b.ncols())?;
    let m = b.ncols();
    let mut out = DMatrix::<f64>::zeros(n, n * m);
    let mut block = b.clone();
    for k in 0..n {
        out.view_mut((0, k * m), (n, m)).copy_from(&block);
        block = a * block;
    }
    Ok(out)
}

/// The observability matrix `[C; CA; …; CAⁿ⁻¹]`.
pub fn observability_matrix(a: &DMatrix<f64>, c: &DMatrix<f64>) -> Result<DMatrix<f64>, PbhError> {
    let n = check::square("A", a)?;
    check::shape("C", c, c.nrows(), n)?;
    Ok(controllability_matrix(&a.transpose(), &c.transpose())?.transpose())
}

/// The numerical rank of `m`: singular values above `rel_tol · σ_max` (use about `1e-10` for well-scaled
/// models; the Kalman matrices of stiff models are badly scaled, for which the PBH tests are more reliable).
pub fn numerical_rank(m: &DMatrix<f64>, rel_tol: f64) -> Result<usize, PbhError> {
    check::finite("M", m)?;
    // A NaN tolerance compared false with every singular value and gave rank 0.
    check::positive_scalar("relative rank tolerance", rel_tol)?;
    let (rows, cols) = m.shape();
    let svd = check::svd(m.clone(), false, false, 10_000).ok_or(PbhError::Svd { rows, cols })?;
    let s_max = svd.singular_values.max();
    Ok(svd
        .singular_values
        .iter()
        .filter(|&&s| s > rel_tol * s_max)
        .count())
}

/// The rank of the controllability matrix of `(A, B)` (`n` when controllable).
pub fn controllability_rank(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    rel_tol: f64,
) -> Result<usize, PbhError> {
    numerical_rank(&controllability_matrix(a, b)?, rel_tol)
}

/// The rank of the observability matrix of `(A, C)` (`n` when observable).
pub fn observability_rank(
    a: &DMatrix<f64>,
    c: &DMatrix<f64>,
    rel_tol: f64,
) -> Result<usize, PbhError> {
    numerical_rank(&observability_matrix(a, c)?, rel_tol)
}

/// The `scale` argument of [`Domain::is_stable`] for eigenvalues of `a`: NaN when `a` has a non-finite entry (the
/// solvers refuse such a matrix before they ask).
pub fn stability_scale(a: &DMatrix<f64>, domain: Domain) -> f64 {
    match domain {
        Domain::Continuous => balanced_norm(a),
        Domain::Discrete => 1.0,
    }
}
