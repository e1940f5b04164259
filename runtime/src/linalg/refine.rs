//! Newton refinement of a Riccati solution, shared by the continuous (Kleinman, [`super::care`]) and discrete
//! (Hewer, [`super::dare`]) solvers.
//!
//! From an iterate `X` with residual `Res(X)`, the Newton step solves the Lyapunov equation of the closed loop
//! for a correction `Δ` and proposes `X + Δ` (symmetrised). A proposal is accepted only while the relative
//! residual decreases, so the result is never worse than the base solver's: rounding stalls the iteration
//! instead of undoing the solution. The iteration stops at `max_steps` accepted steps, once the relative
//! residual is at rounding level (`1e-15`), after a step that did not halve it (Newton's steps do until rounding
//! holds them), or when a correction or an evaluation fails.

use nalgebra::DMatrix;

use super::balance::frobenius;
use super::lyapunov::symmetrize;

/// Relative residual below which a Riccati iterate is not refined further (rounding level).
const ROUNDING_LEVEL: f64 = 1e-15;

/// What the refinement needs to know of an iterate's evaluation.
pub(crate) trait Evaluated {
    /// `‖Res(X)‖_F` divided by the sum of the Frobenius norms of the equation's terms.
    fn relative(&self) -> f64;
}

/// The best iterate reached from `x` (evaluated as `eval`) and the number of accepted Newton steps.
/// `correction(x, eval)` is the Newton correction `Δ` at `x`, `evaluate(x)` evaluates a proposal; either
/// returning `None` ends the refinement at the current iterate.
pub(crate) fn refine<E: Evaluated>(
    mut x: DMatrix<f64>,
    mut eval: E,
    max_steps: usize,
    mut correction: impl FnMut(&DMatrix<f64>, &E) -> Option<DMatrix<f64>>,
    mut evaluate: impl FnMut(&DMatrix<f64>) -> Option<E>,
) -> (DMatrix<f64>, usize) {
    let mut steps = 0;
    while steps < max_steps && eval.relative() > ROUNDING_LEVEL {
        let Some(delta) = correction(&x, &eval) else {
            break;
        };
        let candidate = symmetrize(&(&x + delta));
        let Some(next) = evaluate(&candidate) else {
            break;
        };
        if next.relative().is_nan() || next.relative() >= eval.relative() {
            break;
        }
        // Newton at least halves the residual until rounding holds it; a smaller gain means rounding does, and
        // further steps (each an O(n³) Lyapunov solve) would only trade its last digits.
        let at_rounding = next.relative() > 0.5 * eval.relative();
        steps += 1;
        x = candidate;
        eval = next;
        if at_rounding {
            break;
        }
    }
    (x, steps)
}

/// `‖residual‖_F / terms`, where `terms` is the sum of the norms of the equation's terms; the absolute norm
/// when every term is zero, so that a nonzero residual is not hidden by a division by zero.
pub(crate) fn relative_residual(residual: &DMatrix<f64>, terms: f64) -> f64 {
    let norm = frobenius(residual);
    if terms > 0.0 { norm / terms } else { norm }
}
