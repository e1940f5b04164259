//! A symbolic linear solver for the small systems of algebraic loops and derivative-causality elimination.
//!
//! [`solve_linear`] solves `A x = b` by Gaussian elimination with row exchanges. In each column it takes, among the
//! remaining rows, an entry that is not structurally zero (not 0 after simplification and expansion): a non-zero
//! constant if there is one, else the smallest entry by [`Expr::node_count`], the upper row on ties. Then it
//! eliminates below the pivot and substitutes back.
//!
//! Limits:
//! - `n ≤` [`MAX_SOLVE_SIZE`]: expressions grow quickly with `n` and nothing here cancels common factors of
//!   rational expressions, so the results are correct but not minimal;
//! - "structurally non-zero" is not "non-zero": a pivot such as `k1 - k2` vanishes for some parameter values. The
//!   pivots are returned so the caller can check them (e.g. at the default parameters) and report a singular loop;
//! - a column with no structurally non-zero candidate makes the system [`SymbolicError::Singular`].

use super::SymbolicError;
use super::expr::Expr;

/// The largest system [`solve_linear`] accepts.
pub const MAX_SOLVE_SIZE: usize = 4;

/// The solution of `A x = b` and the pivots it divided by (in elimination order). The solution is valid where every
/// pivot is non-zero.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearSolution {
    pub x: Vec<Expr>,
    pub pivots: Vec<Expr>,
}

/// Solves `a x = b` for a square `a` given row by row, `n = b.len() ≤ MAX_SOLVE_SIZE`.
pub fn solve_linear(a: &[Vec<Expr>], b: &[Expr]) -> Result<LinearSolution, SymbolicError> {
    let n = b.len();
    if n > MAX_SOLVE_SIZE {
        return Err(SymbolicError::SystemTooLarge {
            n,
            max: MAX_SOLVE_SIZE,
        });
    }
    if let Some((row, r)) = a.iter().enumerate().find(|(_, r)| r.len() != n) {
        return Err(SymbolicError::ShapeMismatch {
            row,
            found: r.len(),
            expected: n,
        });
    }
    if a.len() != n {
        return Err(SymbolicError::ShapeMismatch {
            row: a.len(),
            found: a.len(),
            expected: n,
        });
    }
    // The augmented matrix [a | b].
    let mut m: Vec<Vec<Expr>> = a
        .iter()
        .zip(b)
        .map(|(row, rhs)| row.iter().cloned().chain([rhs.clone()]).collect())
        .collect();
    let mut pivots = Vec::with_capacity(n);
    for k in 0..n {
        let p = choose_pivot(&m, k).ok_or(SymbolicError::Singular { column: k })?;
        m.swap(k, p);
        let pivot_row = m.get(k).cloned().unwrap_or_default();
        let pivot = pivot_row.get(k).cloned().unwrap_or_else(Expr::zero);
        for row in m.iter_mut().skip(k + 1) {
            let factor = entry(row, k) / &pivot;
            if factor.is_zero() {
                continue;
            }
            for (j, slot) in row.iter_mut().enumerate().skip(k) {
                *slot = if j == k {
                    Expr::zero()
                } else {
                    &*slot - &factor * entry(&pivot_row, j)
                };
            }
        }
        pivots.push(pivot);
    }
    let mut x = vec![Expr::zero(); n];
    for k in (0..n).rev() {
        let row = m.get(k).map(Vec::as_slice).unwrap_or_default();
        let known = Expr::sum((k + 1..n).map(|j| entry(row, j) * entry(&x, j)));
        let value = (entry(row, n) - known) / entry(&pivots, k);
        if let Some(slot) = x.get_mut(k) {
            *slot = value;
        }
    }
    Ok(LinearSolution { x, pivots })
}

fn entry(v: &[Expr], i: usize) -> Expr {
    v.get(i).cloned().unwrap_or_else(Expr::zero)
}

fn is_structurally_zero(e: &Expr) -> bool {
    e.is_zero() || e.expand().is_zero()
}

/// The row (≥ k) of the pivot for column k, if any entry there is structurally non-zero.
fn choose_pivot(m: &[Vec<Expr>], k: usize) -> Option<usize> {
    let candidates: Vec<(usize, Expr)> = m
        .iter()
        .enumerate()
        .skip(k)
        .map(|(i, row)| (i, entry(row, k)))
        .filter(|(_, e)| !is_structurally_zero(e))
        .collect();
    candidates
        .iter()
        .find(|(_, e)| e.as_const().is_some_and(f64::is_finite))
        .or_else(|| candidates.iter().min_by_key(|(i, e)| (e.node_count(), *i)))
        .map(|(i, _)| *i)
}
