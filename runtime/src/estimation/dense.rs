//! Small dense linear algebra on fixed-size matrices, written so that it never allocates and never panics.
//!
//! nalgebra's decompositions need typenum bounds for generic const sizes (`SymmetricEigen` needs
//! `Const<N>: DimSub<U1>`), so the few factorisations the filters need live here:
//!
//! - [`cholesky_lower`]: `P = L Lᵀ` with `L` lower triangular and a positive diagonal, or `None` when `P` is not
//!   numerically positive definite;
//! - [`cholesky_psd_into`]: the same for a positive *semi*-definite matrix (zero pivots allowed), used for noise
//!   covariances that may be singular (a noise-free channel);
//! - [`solve_lower`]/[`solve_upper_transposed`]: triangular solves with a lower factor;
//! - [`positive_definite_in`]: the definiteness test of a covariance by an `LDLᵀ` sweep;
//! - [`symmetric_eigen_in_place`]: cyclic Jacobi eigen-decomposition of a symmetric matrix (used to repair
//!   covariances);
//! - [`givens_absorb`]/[`hyperbolic_downdate`]: rank-one update and downdate of a Cholesky factor, the
//!   building blocks of the square-root UKF's "QR" step.
//!
//! Loop indices are bounded by the const sizes, so indexing cannot go out of range.
//!
//! An `N × N` matrix takes `8 N²` bytes wherever it is declared (more than a spawned thread's 2 MiB stack at 512
//! states), so the factorisations a large filter needs write into matrices the caller holds
//! ([`cholesky_lower_into`], [`cholesky_psd_into`], [`positive_definite_in`], [`symmetric_eigen_in_place`]);
//! the functions that return a matrix are those applied to the small matrices of a step (innovation
//! covariances, the dual UKF's parameter covariance). [`with_square_scratch`] lends an `N × N` work matrix: on
//! the stack when it is small, on the heap otherwise.

use nalgebra::{SMatrix, SVector};

/// The largest work matrix (in bytes) that [`with_square_scratch`] puts on the stack: 64 KiB, `N ≤ 90`.
const STACK_SCRATCH_BYTES: usize = 64 << 10;

/// Calls `f` with an `N × N` matrix of zeros to work in: on the stack up to 64 KiB (no allocation), on the heap
/// above (allocated zeroed, never built on the stack).
pub fn with_square_scratch<const N: usize, T>(f: impl FnOnce(&mut SMatrix<f64, N, N>) -> T) -> T {
    if N * N * size_of::<f64>() <= STACK_SCRATCH_BYTES {
        on_stack(f)
    } else {
        f(&mut bytemuck::zeroed_box())
    }
}

/// The stack branch of [`with_square_scratch`], in a frame of its own: a large `N` would otherwise reserve the
/// matrix in the caller's frame even though this branch never runs for it.
#[inline(never)]
fn on_stack<const N: usize, T>(f: impl FnOnce(&mut SMatrix<f64, N, N>) -> T) -> T {
    let mut scratch = SMatrix::<f64, N, N>::zeros();
    f(&mut scratch)
}

/// Symmetrises `m` in place: `m ← (m + mᵀ)/2`.
pub fn symmetrise<const N: usize>(m: &mut SMatrix<f64, N, N>) {
    for i in 0..N {
        for j in (i + 1)..N {
            let v = 0.5 * (m[(i, j)] + m[(j, i)]);
            m[(i, j)] = v;
            m[(j, i)] = v;
        }
    }
}

/// True when every entry is finite: `v · 0` is `±0` for a finite `v` and NaN for an infinite or NaN one, and a NaN
/// survives any sum, so the sum of those products is zero exactly when all entries are finite. The products are
/// summed row by row across the columns (whole columns at a time, in vector registers) and the row sums added
/// at the end: no branch per entry, as a search that stops at the first non-finite entry would compile to.
#[inline(always)]
pub fn all_finite<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> bool {
    let mut row_sums = [0.0_f64; R];
    for column in &m.data.0 {
        for (sum, v) in row_sums.iter_mut().zip(column) {
            *sum += v * 0.0;
        }
    }
    row_sums.iter().sum::<f64>() == 0.0
}

/// Index of the first non-finite entry of a vector.
#[inline(always)]
pub fn first_non_finite<const N: usize>(v: &SVector<f64, N>) -> Option<usize> {
    if all_finite(v) {
        return None;
    }
    v.as_slice().iter().position(|x| !x.is_finite())
}

/// Lower Cholesky factor of a symmetric positive-definite matrix (only the lower triangle is read), or `None`
/// when a pivot is not positive or not finite.
pub fn cholesky_lower<const N: usize>(p: &SMatrix<f64, N, N>) -> Option<SMatrix<f64, N, N>> {
    let mut l = SMatrix::<f64, N, N>::zeros();
    cholesky_lower_into(p, &mut l).then_some(l)
}

/// [`cholesky_lower`] written into `l` (whose upper triangle must be zero, or is left as it was); `false`, with
/// `l` partly written, when a pivot is not positive or not finite.
pub fn cholesky_lower_into<const N: usize>(
    p: &SMatrix<f64, N, N>,
    l: &mut SMatrix<f64, N, N>,
) -> bool {
    for j in 0..N {
        let mut d = p[(j, j)];
        for k in 0..j {
            d -= l[(j, k)] * l[(j, k)];
        }
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let ljj = d.sqrt();
        l[(j, j)] = ljj;
        for i in (j + 1)..N {
            let mut s = p[(i, j)];
            for k in 0..j {
                s -= l[(i, k)] * l[(j, k)];
            }
            l[(i, j)] = s / ljj;
        }
    }
    true
}

/// [`positive_definite_in`] with a work matrix on the stack.
#[cfg(test)]
pub fn positive_definite<const N: usize>(p: &SMatrix<f64, N, N>) -> bool {
    positive_definite_in(p, &mut [[0.0_f64; N]; N])
}

/// Whether the symmetric `p` (only the lower triangle is read) is numerically positive definite: the test of
/// [`cholesky_lower`] (every pivot positive and finite) by an `LDLᵀ` sweep, which needs one division per column and
/// no square root; the filters check their covariance with it after every step. `ld` is its work matrix (any
/// contents; overwritten), held by the caller so that a large `N` needs no `N × N` value on the stack.
#[inline]
pub fn positive_definite_in<const N: usize>(
    p: &SMatrix<f64, N, N>,
    ld: &mut [[f64; N]; N],
) -> bool {
    // `P = L D Lᵀ` with unit lower `L`, kept by rows as `ld[i][k] = l_ik d_k` so that every sum below is a dot
    // product of two contiguous row prefixes: one multiply-add per term. Only the prefixes before the diagonal
    // are read, and each is written before it is read.
    // `w[k] = l_jk` (`= ld[j][k] / d_k`) for the current column `j`.
    let mut w = [0.0_f64; N];
    let mut inv = [0.0_f64; N];
    for j in 0..N {
        for k in 0..j {
            w[k] = ld[j][k] * inv[k];
        }
        let d = p[(j, j)] - dot(&ld[j][..j], &w[..j]);
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        inv[j] = 1.0 / d;
        for i in (j + 1)..N {
            ld[i][j] = p[(i, j)] - dot(&ld[i][..j], &w[..j]);
        }
    }
    true
}

/// `Σ a_k b_k` over two slices of one length.
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Lower Cholesky factor of `p` whose pivots must each exceed `floor` (the rounding error with which the
/// diagonal of `p` is known), or `None`: a pivot at or below its floor means that `p` is singular to within
/// the accuracy of its entries, even when rounding left it a tiny positive value.
pub fn cholesky_above_floor<const N: usize>(
    p: &SMatrix<f64, N, N>,
    floor: &SVector<f64, N>,
) -> Option<SMatrix<f64, N, N>> {
    let l = cholesky_lower(p)?;
    (0..N)
        .all(|j| l[(j, j)] * l[(j, j)] > floor[j])
        .then_some(l)
}

/// [`cholesky_psd_into`] returning the factor.
#[cfg(test)]
pub fn cholesky_psd<const N: usize>(p: &SMatrix<f64, N, N>) -> Option<SMatrix<f64, N, N>> {
    let mut l = SMatrix::<f64, N, N>::zeros();
    cholesky_psd_into(p, &mut l).then_some(l)
}

/// Lower factor `L` with `L Lᵀ = P` of a symmetric positive *semi*-definite matrix, written into `l`, which
/// must be zero on entry. A pivot below `tol · max(1, max diag)` is treated as zero (its column is left zero);
/// a clearly negative pivot or a non-finite entry gives `false`.
pub fn cholesky_psd_into<const N: usize>(
    p: &SMatrix<f64, N, N>,
    l: &mut SMatrix<f64, N, N>,
) -> bool {
    if !all_finite(p) {
        return false;
    }
    let scale = (0..N).map(|i| p[(i, i)].abs()).fold(1.0_f64, f64::max);
    let tol = 1e-12 * scale;
    for j in 0..N {
        let mut d = p[(j, j)];
        for k in 0..j {
            d -= l[(j, k)] * l[(j, k)];
        }
        if d < -tol {
            return false;
        }
        if d <= tol {
            // A zero pivot: the rest of this column must vanish too for P to be semi-definite.
            for i in (j + 1)..N {
                let mut s = p[(i, j)];
                for k in 0..j {
                    s -= l[(i, k)] * l[(j, k)];
                }
                if s.abs() > tol.sqrt() * scale.sqrt() {
                    return false;
                }
            }
            continue;
        }
        let ljj = d.sqrt();
        l[(j, j)] = ljj;
        for i in (j + 1)..N {
            let mut s = p[(i, j)];
            for k in 0..j {
                s -= l[(i, k)] * l[(j, k)];
            }
            l[(i, j)] = s / ljj;
        }
    }
    true
}

/// Solves `L X = B` for `X` with `L` lower triangular; `None` if a diagonal entry is zero or the result is not
/// finite.
pub fn solve_lower<const N: usize, const C: usize>(
    l: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, C>,
) -> Option<SMatrix<f64, N, C>> {
    let mut x = *b;
    for c in 0..C {
        for i in 0..N {
            let mut s = x[(i, c)];
            for k in 0..i {
                s -= l[(i, k)] * x[(k, c)];
            }
            let d = l[(i, i)];
            if d == 0.0 {
                return None;
            }
            x[(i, c)] = s / d;
        }
    }
    all_finite(&x).then_some(x)
}

/// Solves `Lᵀ X = B` for `X` with `L` lower triangular (so `Lᵀ` is upper triangular).
pub fn solve_upper_transposed<const N: usize, const C: usize>(
    l: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, C>,
) -> Option<SMatrix<f64, N, C>> {
    let mut x = *b;
    for c in 0..C {
        for i in (0..N).rev() {
            let mut s = x[(i, c)];
            for k in (i + 1)..N {
                s -= l[(k, i)] * x[(k, c)];
            }
            let d = l[(i, i)];
            if d == 0.0 {
                return None;
            }
            x[(i, c)] = s / d;
        }
    }
    all_finite(&x).then_some(x)
}

/// Solves `P X = B` given the lower Cholesky factor `L` of `P`.
pub fn cholesky_solve<const N: usize, const C: usize>(
    l: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, C>,
) -> Option<SMatrix<f64, N, C>> {
    solve_lower(l, b).and_then(|z| solve_upper_transposed(l, &z))
}

/// Solves `A X = B` by Gaussian elimination with partial pivoting; `None` when `A` is numerically singular.
/// The elimination works on a copy of `A` in a [`with_square_scratch`] matrix (on the heap for a large `N`).
pub fn solve_general<const N: usize, const C: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, C>,
) -> Option<SMatrix<f64, N, C>> {
    with_square_scratch(|m: &mut SMatrix<f64, N, N>| {
        m.copy_from(a);
        eliminate(m, b)
    })
}

/// [`solve_general`] overwriting `m` (`A`) with its eliminated form.
fn eliminate<const N: usize, const C: usize>(
    m: &mut SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, C>,
) -> Option<SMatrix<f64, N, C>> {
    let mut x = *b;
    let scale = m.amax();
    if !(scale > 0.0 && scale.is_finite()) {
        return None;
    }
    for k in 0..N {
        let mut piv = k;
        for i in (k + 1)..N {
            if m[(i, k)].abs() > m[(piv, k)].abs() {
                piv = i;
            }
        }
        if m[(piv, k)].abs() <= 1e-14 * scale {
            return None;
        }
        m.swap_rows(k, piv);
        x.swap_rows(k, piv);
        for i in (k + 1)..N {
            let f = m[(i, k)] / m[(k, k)];
            for j in k..N {
                m[(i, j)] -= f * m[(k, j)];
            }
            for j in 0..C {
                x[(i, j)] -= f * x[(k, j)];
            }
        }
    }
    for j in 0..C {
        for i in (0..N).rev() {
            let mut s = x[(i, j)];
            for k in (i + 1)..N {
                s -= m[(i, k)] * x[(k, j)];
            }
            x[(i, j)] = s / m[(i, i)];
        }
    }
    all_finite(&x).then_some(x)
}

/// [`symmetric_eigen_in_place`] on a copy of `m`, returning the eigenvalues and the eigenvectors.
#[cfg(test)]
pub fn symmetric_eigen<const N: usize>(
    m: &SMatrix<f64, N, N>,
) -> Option<(SVector<f64, N>, SMatrix<f64, N, N>)> {
    let mut a = *m;
    let mut v = SMatrix::<f64, N, N>::zeros();
    let values = symmetric_eigen_in_place(&mut a, &mut v)?;
    Some((values, v))
}

/// Eigen-decomposition `M = V diag(λ) Vᵀ` of a symmetric matrix by the cyclic Jacobi method, in matrices the
/// caller holds: `a` (`M`, symmetrised first) is rotated towards its diagonal of eigenvalues and `v` (any
/// contents) receives the eigenvectors (columns). Returns the eigenvalues, or `None` if an entry is not finite
/// or the sweeps do not converge.
pub fn symmetric_eigen_in_place<const N: usize>(
    a: &mut SMatrix<f64, N, N>,
    v: &mut SMatrix<f64, N, N>,
) -> Option<SVector<f64, N>> {
    if !all_finite(a) {
        return None;
    }
    symmetrise(a);
    v.fill_with_identity();
    let norm = a.norm();
    if norm == 0.0 {
        return Some(SVector::zeros());
    }
    for _sweep in 0..100 {
        let mut off = 0.0;
        for i in 0..N {
            for j in (i + 1)..N {
                off += a[(i, j)] * a[(i, j)];
            }
        }
        if off.sqrt() <= 1e-15 * norm {
            return Some(SVector::from_fn(|i, _| a[(i, i)]));
        }
        for p in 0..N {
            for q in (p + 1)..N {
                let apq = a[(p, q)];
                if apq == 0.0 {
                    continue;
                }
                // Rotation that zeroes a[p][q] (Golub and Van Loan, Algorithm 8.5.2).
                let tau = (a[(q, q)] - a[(p, p)]) / (2.0 * apq);
                let t = tau.signum() / (tau.abs() + (1.0 + tau * tau).sqrt());
                let t = if tau == 0.0 { 1.0 } else { t };
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = t * c;
                for k in 0..N {
                    let akp = a[(k, p)];
                    let akq = a[(k, q)];
                    a[(k, p)] = c * akp - s * akq;
                    a[(k, q)] = s * akp + c * akq;
                }
                for k in 0..N {
                    let apk = a[(p, k)];
                    let aqk = a[(q, k)];
                    a[(p, k)] = c * apk - s * aqk;
                    a[(q, k)] = s * apk + c * aqk;
                }
                for k in 0..N {
                    let vkp = v[(k, p)];
                    let vkq = v[(k, q)];
                    v[(k, p)] = c * vkp - s * vkq;
                    v[(k, q)] = s * vkp + c * vkq;
                }
            }
        }
    }
    None
}

/// Replaces the lower factor `L` by `L'` with `L' L'ᵀ = L Lᵀ + v vᵀ`, using Givens rotations (a QR step on
/// `[L v]ᵀ`); `v` is overwritten. Works when `L` has zero diagonal entries.
pub fn givens_absorb<const N: usize>(l: &mut SMatrix<f64, N, N>, v: &mut SVector<f64, N>) {
    for k in 0..N {
        let lkk = l[(k, k)];
        let vk = v[k];
        let r = lkk.hypot(vk);
        if r == 0.0 {
            continue;
        }
        let c = lkk / r;
        let s = vk / r;
        l[(k, k)] = r;
        v[k] = 0.0;
        for i in (k + 1)..N {
            let lik = l[(i, k)];
            let vi = v[i];
            l[(i, k)] = c * lik + s * vi;
            v[i] = -s * lik + c * vi;
        }
    }
}

/// Replaces `L` by `L'` with `L' L'ᵀ = L Lᵀ − v vᵀ` (hyperbolic rotations). Returns `false`, leaving `L`
/// partly modified, when the result would not be positive definite; callers keep a copy to fall back on.
pub fn hyperbolic_downdate<const N: usize>(
    l: &mut SMatrix<f64, N, N>,
    v: &mut SVector<f64, N>,
) -> bool {
    for k in 0..N {
        let lkk = l[(k, k)];
        let vk = v[k];
        let r2 = lkk * lkk - vk * vk;
        if !(r2 > 0.0 && r2.is_finite()) || lkk == 0.0 {
            return false;
        }
        let r = r2.sqrt();
        let c = r / lkk;
        let s = vk / lkk;
        l[(k, k)] = r;
        for i in (k + 1)..N {
            let lik = (l[(i, k)] - s * v[i]) / c;
            l[(i, k)] = lik;
            v[i] = c * v[i] - s * lik;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Vector3};

    fn spd() -> Matrix3<f64> {
        Matrix3::new(4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0)
    }

    /// Every position and every kind of non-finite value is found, and the largest finite values are not
    /// mistaken for one (`f64::MAX · 0 = 0`).
    #[test]
    fn finiteness_is_decided_at_every_entry() {
        let m = nalgebra::Matrix3x2::new(f64::MAX, -f64::MAX, 1e-300, -0.0, 5e-324, 1.0);
        assert!(all_finite(&m));
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for k in 0..6 {
                let mut b = m;
                b[k] = bad;
                assert!(!all_finite(&b), "{bad} at {k}");
                let v = Vector3::new(1.0, 2.0, 3.0);
                let mut w = v;
                w[k % 3] = bad;
                assert_eq!(first_non_finite(&w), Some(k % 3));
                assert_eq!(first_non_finite(&v), None);
            }
        }
    }

    #[test]
    fn cholesky_reproduces_matrix_and_rejects_indefinite() {
        let p = spd();
        let l = cholesky_lower(&p).unwrap();
        assert!((l * l.transpose() - p).norm() < 1e-14);
        assert!(l[(0, 1)] == 0.0 && l[(0, 2)] == 0.0 && l[(1, 2)] == 0.0);
        let bad = Matrix3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0); // eigenvalues 3, -1, 1
        assert!(cholesky_lower(&bad).is_none());
        assert!(cholesky_psd(&bad).is_none());
    }

    #[test]
    fn psd_cholesky_accepts_singular() {
        let p = Matrix3::from_diagonal(&Vector3::new(2.0, 0.0, 1.0));
        let l = cholesky_psd(&p).unwrap();
        assert!((l * l.transpose() - p).norm() < 1e-15);
    }

    #[test]
    fn eigen_matches_characteristic_polynomial() {
        // [[2,1],[1,2]] has eigenvalues 1 and 3.
        let m = nalgebra::Matrix2::new(2.0, 1.0, 1.0, 2.0);
        let (vals, vecs) = symmetric_eigen(&m).unwrap();
        let mut v = [vals[0], vals[1]];
        v.sort_by(f64::total_cmp);
        assert!((v[0] - 1.0).abs() < 1e-14 && (v[1] - 3.0).abs() < 1e-14);
        let back = vecs * nalgebra::Matrix2::from_diagonal(&vals) * vecs.transpose();
        assert!((back - m).norm() < 1e-14);
    }

    #[test]
    fn rank_one_update_and_downdate_match_direct_products() {
        let p = spd();
        let l0 = cholesky_lower(&p).unwrap();
        let v = Vector3::new(0.3, -0.7, 1.1);
        let mut l = l0;
        let mut w = v;
        givens_absorb(&mut l, &mut w);
        assert!((l * l.transpose() - (p + v * v.transpose())).norm() < 1e-13);
        let mut w = v;
        assert!(hyperbolic_downdate(&mut l, &mut w));
        assert!((l * l.transpose() - p).norm() < 1e-13);
        // Removing more than is there fails.
        let mut big = Vector3::new(10.0, 0.0, 0.0);
        let mut l2 = l0;
        assert!(!hyperbolic_downdate(&mut l2, &mut big));
    }

    #[test]
    fn triangular_solves_invert_factor() {
        let p = spd();
        let l = cholesky_lower(&p).unwrap();
        let b = Vector3::new(1.0, 2.0, 3.0);
        let x = cholesky_solve(&l, &b).unwrap();
        assert!((p * x - b).norm() < 1e-14);
    }
}
