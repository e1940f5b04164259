//! The nonlinear algebraic loops of a model in generated code.
//!
//! The equations keep such a loop implicit ([`crate::equations::TearBlock`]): its tear variables `z` solve
//! `0 = r(z, x, u, p, t)`, block after block, and the rates, outputs and energy terms hold `z`. The generated
//! module gets:
//! - `N_TEARS`, `TEAR_NAMES` and `Tears` (an `SVector<f64, N_TEARS>`), the error type `LoopError`;
//! - `solve_loops(p, t, x, u) -> Result<Tears, LoopError>`: each block in turn by damped Newton's method on
//!   fixed-size values ([`NEWTON_FN`]), from `z = 0` (`solve_loops_from(p, t, x, u, guess)` starts from the
//!   caller's guess, the last solution of a time-stepping caller, and retries from zero when that fails), with the analytic `∂r/∂z` (symbolic derivatives of the
//!   residuals). It mirrors [`crate::equations::newton`]: the step solves `∂r/∂z Δ = −r`, the damping halves `λ`
//!   until the Armijo test on `Σ (r_i/w_i)²` or the natural monotonicity test (`bgc_contracts`) passes, and the block has converged when `|r_i| ≤ 10⁻¹² s_i` for every
//!   residual, `s_i` being the sum of the magnitudes of its terms ([`crate::equations::residual_scale`]), and the
//!   Newton step from the iterate is within `10⁻¹⁰` of each tear or no longer contracts, after at least one step;
//!   at most 100 iterations. A block of one tear whose Newton iteration fails is solved in a
//!   bracket of a sign change searched outward from the start, as [`crate::equations::newton::bracketed`] does; a
//!   block of several by Powell's dogleg method ([`super::loops_dogleg`]), as the compiler's own evaluation does;
//! - every function that needs the tears (`rhs_into`, `outputs_into`, the Jacobians, the energy functions) starts
//!   with `let z = loop_values(p, t, x, u);`, which is `solve_loops` with all NaN when it fails: the values are then
//!   NaN, never silently wrong. Callers that need to know why call `solve_loops`.
//!
//! The Jacobians follow from the implicit function theorem: with `r(z(x, u), x, u) = 0`,
//! `dz/dx = −(∂r/∂z)⁻¹ ∂r/∂x` and `dz/du = −(∂r/∂z)⁻¹ ∂r/∂u`, so `∂f/∂x` gets `∂f/∂z dz/dx` added (the same for
//! `u` and for the outputs). `∂r/∂z` of all blocks together is block-triangular, so `dz` is formed block by block
//! (`dz_k = −(∂r_k/∂z_k)⁻¹ (∂r_k/∂v + Σ_c ∂r_k/∂z_c dz_c)`, each by `bgc_solve`) with matrices of one block's tears
//! only ([`block_supports`]).

use super::adapter::to_symbolic;
use super::rust::{Draft, MAX_CONSTANT_JACOBIAN_BYTES, TearValues, Writer};
use crate::equations::{Equations, ParamChain, residual_scale};
use crate::symbolic::{Expr, Symbol};
use std::collections::BTreeSet;
use std::fmt::Write;

/// The most tear variables of one block that generated code takes: its `∂r/∂z` is a square matrix on the stack,
/// held to the bound of a dense `JacX` ([`MAX_CONSTANT_JACOBIAN_BYTES`], 181 tears).
const MAX_TEARS: usize = (MAX_CONSTANT_JACOBIAN_BYTES / 8).isqrt();

/// One block of the loops for the generator.
#[derive(Clone, Debug)]
pub(crate) struct LoopBlockPlan {
    /// The index of its first tear in `Tears`.
    pub first: usize,
    pub residuals: Vec<Expr>,
    pub scales: Vec<Expr>,
    /// `∂r_i/∂z_j` over this block's tears.
    pub jacobian: Vec<Vec<Expr>>,
}

/// The loops of a model for the generator.
#[derive(Clone, Debug)]
pub(crate) struct LoopPlan {
    pub tears: Vec<Symbol>,
    pub blocks: Vec<LoopBlockPlan>,
    /// `∂r/∂z`, `∂r/∂x`, `∂r/∂u` of all residuals (in block order) with respect to all tears, states, inputs.
    pub drdz: Vec<Vec<Expr>>,
    pub drdx: Vec<Vec<Expr>>,
    pub drdu: Vec<Vec<Expr>>,
    /// `∂r/∂p` with respect to the free parameters, total through the derived ones.
    pub drdp: Vec<Vec<Expr>>,
    /// `∂f/∂z` and `∂h/∂z`.
    pub dfdz: Vec<Vec<Expr>>,
    pub dhdz: Vec<Vec<Expr>>,
}

/// The loops of `eqs` (`None` without any), for the rates `f` and outputs `h`.
pub(crate) fn plan(
    eqs: &Equations,
    f: &[Expr],
    h: &[Expr],
    (states, inputs): (&[Symbol], &[Symbol]),
    chain: &ParamChain,
) -> Result<Option<LoopPlan>, String> {
    if eqs.tear_blocks.is_empty() {
        return Ok(None);
    }
    // Each block is solved, and corrects the Jacobians, with matrices of its own tears: the largest one bounds them.
    let count = eqs
        .tear_blocks
        .iter()
        .map(|b| b.tears.len())
        .max()
        .unwrap_or(0);
    if count > MAX_TEARS {
        let (kib, bound) = (count * count * 8 / 1024, MAX_CONSTANT_JACOBIAN_BYTES / 1024);
        return Err(format!(
            "one of its algebraic loops has {count} tear variables that must be solved together: the generated \
             Newton iteration and Jacobians keep {count} × {count} matrices ({kib} KiB each) on the stack, more \
             than the {bound} KiB generated code allows (at most {MAX_TEARS} tears a loop); a storage element on \
             the loop (a parasitic compliance or inertia) removes its tear, and `bgc simulate` runs the model as \
             it is"
        ));
    }
    let convert = |e: &Expr| to_symbolic(eqs, e).map_err(|e| e.to_string());
    let mut tears = Vec::new();
    let mut blocks = Vec::new();
    let mut residuals = Vec::new();
    for b in &eqs.tear_blocks {
        let first = tears.len();
        let own: Vec<Symbol> = b
            .names
            .iter()
            .map(|n| Symbol::intermediate(n.as_str()))
            .collect();
        let rs: Vec<Expr> = b.residuals.iter().map(convert).collect::<Result<_, _>>()?;
        let scales: Vec<Expr> = b
            .residuals
            .iter()
            .zip(&b.tears)
            .map(|(r, &z)| convert(&residual_scale(r, z)))
            .collect::<Result<_, _>>()?;
        blocks.push(LoopBlockPlan {
            first,
            jacobian: Expr::jacobian(&rs, &own),
            residuals: rs.clone(),
            scales,
        });
        tears.extend(own);
        residuals.extend(rs);
    }
    Ok(Some(LoopPlan {
        drdz: Expr::jacobian(&residuals, &tears),
        drdx: Expr::jacobian(&residuals, states),
        drdu: Expr::jacobian(&residuals, inputs),
        drdp: chain.jacobian(&residuals),
        dfdz: Expr::jacobian(f, &tears),
        dhdz: Expr::jacobian(h, &tears),
        tears,
        blocks,
    }))
}

/// Damped Newton's method for one block, on fixed-size values (see the module docs). Emitted into the module with
/// [`ITEMS`]; needs `bgc_solve` ([`super::mass::SOLVE_FN`]).
pub(crate) const NEWTON_FN: &str = "
/// The residuals `r`, their scales `s` and `∂r/∂z` of one block of the algebraic loops.
pub type LoopEval<const B: usize> = (SVector<f64, B>, SVector<f64, B>, SMatrix<f64, B, B>);

/// Solves the block of `B` tears starting at `first` in `z`, from the values in `z`: damped
/// Newton's method; where it fails, for a single tear a root in a bracket of a sign change, for
/// several Powell's dogleg method.
fn bgc_newton<const B: usize>(
    z: &mut Tears,
    first: usize,
    block: usize,
    eval: impl Fn(&Tears) -> LoopEval<B>,
) -> Result<(), LoopError> {
    let start = *z;
    let failure = match bgc_damped(z, first, block, &eval) {
        Ok(()) => return Ok(()),
        Err(e) => e,
    };
    let fallback = if B == 1 && start[first].is_finite() {
        bgc_bracketed(&start, first, &eval).map(|root| {
            let mut solved = start;
            solved[first] = root;
            solved
        })
    } else if B > 1 {
        bgc_dogleg(&start, first, &eval)
    } else {
        None
    };
    match fallback {
        Some(solved) => {
            *z = solved;
            Ok(())
        }
        None => Err(failure),
    }
}

/// Copies the finite values of `guess` for the `len` tears from `first` into `z`; true when one of
/// them is nonzero (a start that differs from zero).
fn bgc_start(z: &mut Tears, guess: &Tears, first: usize, len: usize) -> bool {
    let mut warm = false;
    let mut i = first;
    while i < first + len && i < N_TEARS {
        if guess[i].is_finite() {
            z[i] = guess[i];
            warm |= guess[i] != 0.0;
        }
        i += 1;
    }
    warm
}

/// The residual, its scale and its derivative of a one-tear block with the tear at `v`.
fn bgc_at<const B: usize>(
    start: &Tears,
    first: usize,
    eval: &impl Fn(&Tears) -> LoopEval<B>,
    v: f64,
) -> (f64, f64, f64) {
    let mut trial = *start;
    trial[first] = v;
    let (r, s, jz) = eval(&trial);
    if B == 0 {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    (r[0], s[0], jz[(0, 0)])
}

/// One tear: a bracket of a sign change searched at `z0 ± h`, `h` doubling from
/// `1e-6 max(1, |z0|)`, then Newton steps kept inside the bracket that halve it at least every
/// other step, else bisection.
fn bgc_bracketed<const B: usize>(
    start: &Tears,
    first: usize,
    eval: &impl Fn(&Tears) -> LoopEval<B>,
) -> Option<f64> {
    let z0 = start[first];
    let (r0, s0, j0) = bgc_at(start, first, eval, z0);
    if r0.is_nan() {
        return None;
    }
    // Converged: finite and within the tolerance (an infinite residual only gives a direction), and
    // the Newton step from the point within its tolerance.
    let within = |r: f64, s: f64| r.is_finite() && s.is_finite() && libm::fabs(r) <= LOOP_RTOL * s;
    let settled = |x: f64, r: f64, s: f64, j: f64| {
        let step = r / j;
        within(r, s) && (r == 0.0 || libm::fabs(step) <= LOOP_STEP_RTOL * libm::fabs(x))
    };
    if settled(z0, r0, s0, j0) {
        return Some(z0);
    }
    let mut evaluations = 1;
    let mut h = 1e-6;
    if libm::fabs(z0) > 1.0 {
        h *= libm::fabs(z0);
    }
    let mut same = [(z0, r0, s0, j0), (z0, r0, s0, j0)];
    let mut open = [true, true];
    let mut found = None;
    while found.is_none() && evaluations < LOOP_BRACKET_EVALUATIONS && (open[0] || open[1]) {
        for side in 0..2 {
            if !open[side] || found.is_some() {
                continue;
            }
            let dir = if side == 0 { 1.0 } else { -1.0 };
            let v = z0 + dir * h;
            if !v.is_finite() {
                open[side] = false;
                continue;
            }
            let (r, s, j) = bgc_at(start, first, eval, v);
            evaluations += 1;
            if r.is_nan() {
                open[side] = false;
            } else if r == 0.0 || (r < 0.0) != (r0 < 0.0) {
                let near = same[side];
                let far = (v, r, s, j);
                found = Some(if r0 < 0.0 { (near, far) } else { (far, near) });
            } else {
                same[side] = (v, r, s, j);
            }
        }
        h *= 2.0;
    }
    let (mut lo, mut hi) = found?;
    let mut x = if libm::fabs(lo.1) < libm::fabs(hi.1) {
        lo
    } else {
        hi
    };
    let mut step_before = libm::fabs(hi.0 - lo.0);
    let mut step = step_before;
    while evaluations < LOOP_BRACKET_EVALUATIONS {
        if settled(x.0, x.1, x.2, x.3) {
            return Some(x.0);
        }
        let newton = if x.1.is_finite() {
            x.0 - x.1 / x.3
        } else {
            f64::NAN
        };
        let (a, b) = if lo.0 < hi.0 {
            (lo.0, hi.0)
        } else {
            (hi.0, lo.0)
        };
        let inside = newton.is_finite() && newton > a && newton < b;
        let fast = libm::fabs(newton - x.0) <= 0.5 * step_before;
        step_before = step;
        let next = if inside && fast {
            newton
        } else {
            a + (b - a) / 2.0
        };
        step = libm::fabs(next - x.0);
        if next <= a || next >= b {
            // Adjacent floats: accepted when the terms still cancel to half the digits.
            let best = if libm::fabs(lo.1) < libm::fabs(hi.1) {
                lo
            } else {
                hi
            };
            let floor = best.1.is_finite()
                && best.2.is_finite()
                && libm::fabs(best.1) <= 1.4901161193847656e-8 * best.2;
            return if within(best.1, best.2) || floor {
                Some(best.0)
            } else {
                None
            };
        }
        let (r, s, j) = bgc_at(start, first, eval, next);
        evaluations += 1;
        if r.is_nan() {
            return None;
        }
        if r < 0.0 {
            lo = (next, r, s, j);
        } else {
            hi = (next, r, s, j);
        }
        x = (next, r, s, j);
        if r == 0.0 && s.is_finite() {
            return Some(x.0);
        }
    }
    let best = if libm::fabs(lo.1) < libm::fabs(hi.1) {
        lo
    } else {
        hi
    };
    if within(best.1, best.2) {
        Some(best.0)
    } else {
        None
    }
}

/// The Newton step's size in units of its tolerance, `LOOP_STEP_RTOL |z_i|` (infinite when it is
/// not finite or moves a tear at zero).
fn bgc_step_ratio<const B: usize>(z: &Tears, first: usize, step: &SVector<f64, B>) -> f64 {
    let mut ratio = 0.0f64;
    for i in 0..B {
        if step[i] != 0.0 {
            let q = libm::fabs(step[i]) / (LOOP_STEP_RTOL * libm::fabs(z[first + i]));
            ratio = if q.is_nan() {
                f64::INFINITY
            } else {
                ratio.max(q)
            };
        }
    }
    ratio
}

/// Deuflhard's natural monotonicity test: the simplified Newton correction at the trial point
/// (with the iterate's Jacobian `jz`) is at most `1 - lambda/4` of the step, in norms scaled by
/// the tears' magnitudes. It does not change when the rows of the Jacobian are scaled, so it
/// accepts the steps of an ill-conditioned block that the residual's decrease rejects.
fn bgc_contracts<const B: usize>(
    jz: &SMatrix<f64, B, B>,
    r_trial: &SVector<f64, B>,
    z: &Tears,
    first: usize,
    step: &SVector<f64, B>,
    lambda: f64,
) -> bool {
    let mut minus_r = SVector::<f64, B>::zeros();
    for i in 0..B {
        minus_r[i] = -r_trial[i];
    }
    let correction = bgc_solve(*jz, minus_r);
    let (mut correction_norm, mut step_norm) = (0.0, 0.0);
    for i in 0..B {
        let mut scale = libm::fabs(z[first + i]).max(libm::fabs(z[first + i] + step[i]));
        if scale == 0.0 {
            scale = 1.0;
        }
        correction_norm += (correction[i] / scale) * (correction[i] / scale);
        step_norm += (step[i] / scale) * (step[i] / scale);
    }
    libm::sqrt(correction_norm) <= (1.0 - lambda / 4.0) * libm::sqrt(step_norm)
}

/// Damped Newton's method for the block, from the values in `z`.
fn bgc_damped<const B: usize>(
    z: &mut Tears,
    first: usize,
    block: usize,
    eval: &impl Fn(&Tears) -> LoopEval<B>,
) -> Result<(), LoopError> {
    let (mut r, mut s, mut jz) = eval(z);
    let fail = |kind: LoopFailure, iterations: usize, r: &SVector<f64, B>| {
        let mut worst = 0;
        for i in 0..B {
            if !r[i].is_finite() || libm::fabs(r[i]) > libm::fabs(r[worst]) {
                worst = i;
                if !r[i].is_finite() {
                    break;
                }
            }
        }
        LoopError {
            block,
            tear: first + worst,
            kind,
            iterations,
            residual: if B == 0 { 0.0 } else { libm::fabs(r[worst]) },
        }
    };
    // The step ratio of the last step if it was a full step from an iterate that passed the
    // residual test.
    let mut previous = f64::INFINITY;
    for k in 0..=LOOP_MAX_ITERATIONS {
        let mut finite = true;
        let mut converged = true;
        let mut all_zero = true;
        for i in 0..B {
            finite &= r[i].is_finite() && s[i].is_finite();
            converged &= libm::fabs(r[i]) <= LOOP_RTOL * s[i];
            all_zero &= r[i] == 0.0;
        }
        if !finite {
            return Err(fail(LoopFailure::NonFinite, k, &r));
        }
        if k == 0 && all_zero {
            return Ok(());
        }
        if k == LOOP_MAX_ITERATIONS {
            break;
        }
        let mut minus_r = SMatrix::<f64, B, 1>::zeros();
        let mut jacobian_finite = true;
        for i in 0..B {
            for j in 0..B {
                jacobian_finite &= jz[(i, j)].is_finite();
            }
            minus_r[i] = -r[i];
        }
        let step = bgc_solve(jz, minus_r);
        let mut solved = jacobian_finite;
        for i in 0..B {
            solved &= step[i].is_finite();
        }
        if !solved {
            // A converged iterate where the step cannot be judged (a singular root) stays.
            if converged && k > 0 {
                return Ok(());
            }
            let kind = if jacobian_finite {
                LoopFailure::Singular
            } else {
                LoopFailure::NonFinite
            };
            return Err(fail(kind, k, &r));
        }
        // Converged: the residual and the Newton step within their tolerances, or the step no
        // longer contracting (the rounding floor).
        let ratio = if converged {
            bgc_step_ratio(z, first, &step)
        } else {
            f64::INFINITY
        };
        if converged && k > 0 && (ratio <= 1.0 || ratio >= 0.5 * previous) {
            return Ok(());
        }
        let mut weights = SVector::<f64, B>::zeros();
        let mut merit = 0.0;
        for i in 0..B {
            weights[i] = if s[i] > 0.0 { s[i] } else { 1.0 };
            merit += (r[i] / weights[i]) * (r[i] / weights[i]);
        }
        let mut lambda = 1.0;
        let mut accepted = None;
        let mut trial = *z;
        for _ in 0..40 {
            for i in 0..B {
                trial[first + i] = z[first + i] + lambda * step[i];
            }
            let at = eval(&trial);
            let mut merit_trial = 0.0;
            for i in 0..B {
                merit_trial += (at.0[i] / weights[i]) * (at.0[i] / weights[i]);
            }
            // From a converged iterate the full step: the residual no longer measures the
            // distance to the root there, the Newton step does. The monotonicity test (an
            // elimination) runs only when the others fail.
            let accept = merit_trial.is_finite()
                && (converged
                    || merit_trial <= (1.0 - 1e-4 * lambda) * merit
                    || bgc_contracts(&jz, &at.0, z, first, &step, lambda));
            if accept {
                accepted = Some(at);
                break;
            }
            lambda /= 2.0;
        }
        match accepted {
            Some(at) => {
                previous = if converged && lambda == 1.0 {
                    ratio
                } else {
                    f64::INFINITY
                };
                *z = trial;
                (r, s, jz) = at;
            }
            // No step from a converged iterate has finite residuals: it stays.
            None if converged => return Ok(()),
            None => return Err(fail(LoopFailure::NoDescent, k, &r)),
        }
    }
    Err(fail(LoopFailure::IterationLimit, LOOP_MAX_ITERATIONS, &r))
}
";

/// The error types and constants of the loops (after `N_TEARS` and `Tears`).
const ITEMS: &str = "
/// The residual tolerance of the loops, relative to the magnitudes of each residual's terms.
pub const LOOP_RTOL: f64 = 1e-12;
/// The Newton step's tolerance at an iterate whose residuals are within `LOOP_RTOL`, relative to
/// its tear; a step that no longer contracts (the rounding floor) is accepted too.
pub const LOOP_STEP_RTOL: f64 = 1e-10;

/// The most Newton iterations per block of the loops.
pub const LOOP_MAX_ITERATIONS: usize = 100;
/// The most residual evaluations of the bracketing fallback for a one-tear block.
pub const LOOP_BRACKET_EVALUATIONS: usize = 4000;

/// Why Newton's method stopped without solving a block of the algebraic loops.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoopFailure {
    /// No damped step decreases the residual (the equations may have no solution here).
    NoDescent,
    /// `LOOP_MAX_ITERATIONS` iterations did not converge.
    IterationLimit,
    /// `∂r/∂z` is singular at the iterate.
    Singular,
    /// The residuals or their derivatives are not finite at the iterate.
    NonFinite,
}

/// A block of the algebraic loops that was not solved.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoopError {
    /// The block (in solving order).
    pub block: usize,
    /// The tear (index into `TEAR_NAMES`) with the largest residual.
    pub tear: usize,
    pub kind: LoopFailure,
    pub iterations: usize,
    /// `|r|` of that tear at the last iterate (NaN when not finite).
    pub residual: f64,
}

impl core::fmt::Display for LoopError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let tear = TEAR_NAMES.get(self.tear).copied().unwrap_or(\"?\");
        let why = match self.kind {
            LoopFailure::NoDescent => \"no damped Newton step decreased the residual\",
            LoopFailure::IterationLimit => \"Newton's method did not converge\",
            LoopFailure::Singular => \"the loop's Jacobian was singular\",
            LoopFailure::NonFinite => \"a residual or its derivative was not finite\",
        };
        write!(
            f,
            \"the algebraic loop for `{tear}` was not solved: {why} after {} iterations \\
             (residual {:e})\",
            self.iterations, self.residual
        )
    }
}
";

impl Writer<'_> {
    /// The items of the loops: sizes, error types, one residual function per block, `solve_loops`, `loop_values`.
    pub(super) fn loop_fns(&mut self) {
        let Some(lp) = self.plan.loops.clone() else {
            return;
        };
        let names: Vec<String> = lp.tears.iter().map(|s| s.name().to_string()).collect();
        self.out.push('\n');
        self.doc(
            0,
            "The number of tear variables of the nonlinear algebraic loops.",
        );
        let _ = writeln!(self.out, "pub const N_TEARS: usize = {};", names.len());
        self.name_array("TEAR_NAMES", "N_TEARS", "tear variables", &names);
        self.out.push('\n');
        self.doc(0, "The values of the tear variables.");
        self.out
            .push_str("pub type Tears = SVector<f64, N_TEARS>;\n");
        self.out.push_str(ITEMS);
        for (k, b) in lp.blocks.iter().enumerate() {
            let n = b.residuals.len();
            let mut all: Vec<&Expr> = b.residuals.iter().chain(&b.scales).collect();
            all.extend(b.jacobian.iter().flatten().filter(|e| !e.is_zero()));
            let mut d = self.draft_through_loops(&all, false, TearValues::Given);
            d.lines
                .push(format!("    let mut r = SVector::<f64, {n}>::zeros();"));
            d.lines
                .push(format!("    let mut s = SVector::<f64, {n}>::zeros();"));
            let mutable = if b.jacobian.iter().flatten().any(|e| !e.is_zero()) {
                "mut "
            } else {
                ""
            };
            d.lines.push(format!(
                "    let {mutable}jz = SMatrix::<f64, {n}, {n}>::zeros();"
            ));
            for (i, r) in b.residuals.iter().enumerate() {
                let tear = names.get(b.first + i).cloned().unwrap_or_default();
                self.statement(
                    &mut d,
                    &format!("r[{tear}] = "),
                    r,
                    &format!("r[{i}] = "),
                    ";",
                );
                let scale = b
                    .scales
                    .get(i)
                    .cloned()
                    .unwrap_or_else(|| Expr::constant(1.0));
                self.statement(
                    &mut d,
                    &format!("s[{tear}] = "),
                    &scale,
                    &format!("s[{i}] = "),
                    ";",
                );
            }
            for (i, row) in b.jacobian.iter().enumerate() {
                for (j, e) in row.iter().enumerate() {
                    if e.is_zero() {
                        continue;
                    }
                    let label = format!(
                        "∂r[{}]/∂{} = ",
                        names.get(b.first + i).cloned().unwrap_or_default(),
                        names.get(b.first + j).cloned().unwrap_or_default()
                    );
                    self.statement(&mut d, &label, e, &format!("jz[({i}, {j})] = "), ";");
                }
            }
            d.lines.push("    (r, s, jz)".into());
            let uses = d.uses;
            let block_names = names
                .get(b.first..b.first + n)
                .unwrap_or_default()
                .join("`, `");
            self.emit_function(
                &format!(
                    "Block {k} of the algebraic loops (`{block_names}`): the residuals `0 = r(z, x, u, p, t)`, their scales and `∂r/∂z`, at the tears `z`."
                ),
                &format!("bgc_loop_block_{k}"),
                vec![
                    ("p", "&Params", uses.p),
                    ("t", "f64", uses.t),
                    ("x", "&State", uses.x),
                    ("u", "&Inputs", uses.u),
                    ("z", "&Tears", true),
                ],
                &format!(" -> LoopEval<{n}>"),
                d,
            );
        }
        // Each block from the caller's guess (a non-finite guess counts as zero); when that fails and the guess
        // was not zero, once more from zero, as the compiler's evaluator does.
        let mut body = String::from("    let mut z = Tears::zeros();\n");
        for (k, b) in lp.blocks.iter().enumerate() {
            let n = b.residuals.len();
            let _ = write!(
                body,
                "    let block = |at: &Tears| bgc_loop_block_{k}(p, t, x, u, at);
    let warm = bgc_start(&mut z, guess, {first}, {n});
    if let Err(e) = bgc_newton(&mut z, {first}, {k}, block) {{
        if !warm {{
            return Err(e);
        }}
        bgc_start(&mut z, &Tears::zeros(), {first}, {n});
        bgc_newton(&mut z, {first}, {k}, block)?;
    }}
",
                first = b.first,
            );
        }
        body.push_str("    Ok(z)\n");
        self.out.push('\n');
        self.doc(
            0,
            "Solves the nonlinear algebraic loops at `(t, x, u)`: each block in turn by damped Newton's method from zero, to `|r| ≤ LOOP_RTOL` times the magnitudes of each residual's terms. The error names the block that was not solved. A caller that steps through time starts from the last solution with `solve_loops_from`.",
        );
        self.out.push_str(
            "pub fn solve_loops(p: &Params, t: f64, x: &State, u: &Inputs) -> Result<Tears, LoopError> {
    solve_loops_from(p, t, x, u, &Tears::zeros())
}
",
        );
        self.out.push('\n');
        self.doc(
            0,
            "Solves the nonlinear algebraic loops as `solve_loops` does, with Newton's method starting from `guess` (typically the solution at the previous time step, which is close and keeps the solution on its branch when the loop has several); a block that fails from a nonzero guess is solved once more from zero. A non-finite guess counts as zero. The model functions (`rhs`, `outputs`, ...) start from zero, so that they are pure functions of their arguments.",
        );
        self.out.push_str(
            "pub fn solve_loops_from(
    p: &Params,
    t: f64,
    x: &State,
    u: &Inputs,
    guess: &Tears,
) -> Result<Tears, LoopError> {
",
        );
        self.out.push_str(&body);
        self.out.push_str("}\n");
        self.out.push_str(
            "
/// The tears for the model functions: `solve_loops`, or all NaN when it fails (so that what
/// depends on them is NaN, never silently wrong).
fn loop_values(p: &Params, t: f64, x: &State, u: &Inputs) -> Tears {
    match solve_loops(p, t, x, u) {
        Ok(z) => z,
        Err(_) => {
            let mut z = Tears::zeros();
            z.fill(f64::NAN);
            z
        }
    }
}
",
        );
    }

    /// Binds the tears of `used` in `d`: from `tears`, `let loop_v = z[i];` each, after
    /// `let z = loop_values(p, t, x, u);` when the body solves the loops. The names bound, none when `used` holds
    /// no tear.
    pub(super) fn bind_tears(
        &self,
        d: &mut Draft,
        used: &BTreeSet<Symbol>,
        tears: TearValues,
    ) -> Vec<String> {
        let Some(lp) = &self.plan.loops else {
            return Vec::new();
        };
        if tears == TearValues::None || !lp.tears.iter().any(|s| used.contains(s)) {
            return Vec::new();
        }
        if tears == TearValues::Solved {
            d.lines.push("    let z = loop_values(p, t, x, u);".into());
            d.uses.p = true;
            d.uses.t = true;
            d.uses.x = true;
            d.uses.u = true;
        }
        let mut bound = Vec::new();
        for (i, s) in lp.tears.iter().enumerate() {
            if used.contains(s) {
                let name = self.name(s);
                d.lines.push(format!("    let {name} = z[{i}];"));
                d.push_local(name.clone());
                bound.push(name);
            }
        }
        bound
    }

    /// The expressions the loop correction of a Jacobian needs ([`Self::loop_correction`]): the cells it writes,
    /// listed by the same walk.
    pub(super) fn loop_correction_exprs(&self, g_z: &[Vec<Expr>], r_v: &[Vec<Expr>]) -> Vec<Expr> {
        let mut listed = Vec::new();
        self.correction_into(&mut Sink::Listed(&mut listed), g_z, r_v);
        listed
    }

    /// The lines that add `∂g/∂z dz/dv` to `jac`, `dz/dv = −(∂r/∂z)⁻¹ ∂r/∂v`, block by block
    /// ([`block_supports`]): block `k` solves `∂r_k/∂z_k dz_k = −(∂r_k/∂v + Σ_c ∂r_k/∂z_c dz_c)` over the earlier
    /// blocks `c` it reads, at the columns it reaches only, and adds `∂g/∂z_k dz_k` at the rows that read its tears.
    /// The matrices on the stack are a block's tears by those rows and columns, so independent loops keep small
    /// ones however many there are, and the products cost their counts, not `rows × cols × N_TEARS`.
    pub(super) fn loop_correction(&self, d: &mut Draft, g_z: &[Vec<Expr>], r_v: &[Vec<Expr>]) {
        self.correction_into(&mut Sink::Body(d), g_z, r_v);
    }

    /// The loop correction of `g` by `v` into `sink`: nothing when no row of `∂g/∂z` reads a tear or no residual
    /// reads `v`.
    fn correction_into(&self, sink: &mut Sink<'_>, g_z: &[Vec<Expr>], r_v: &[Vec<Expr>]) {
        let Some(lp) = &self.plan.loops else {
            return;
        };
        let (supports, formed) = formed_blocks(lp, g_z, r_v);
        let reads_tears = supports.iter().any(|s| !s.rows.is_empty());
        let reads_v = supports.iter().any(|s| !s.cols.is_empty());
        if !(reads_tears && reads_v) {
            return;
        }
        if let Sink::Body(d) = sink {
            d.lines.extend(self.comment_lines(
                "Through the algebraic loops (implicit function theorem), block by block: dz_k = −(∂r_k/∂z_k)⁻¹ \
                 (∂r_k/∂v + Σ ∂r_k/∂z_c dz_c), jac += (∂/∂z_k) dz_k, only at the rows that read a tear of the block \
                 (`LOOP_ROWS_k`) and the columns that its residuals reach (`LOOP_COLS_k`).",
            ));
        }
        for (k, b) in lp.blocks.iter().enumerate() {
            if formed[k] {
                self.block_correction(sink, lp, (k, b), (&supports, &formed), (g_z, r_v));
            }
        }
    }

    /// Block `k`'s part of [`Self::loop_correction`].
    fn block_correction(
        &self,
        sink: &mut Sink<'_>,
        lp: &LoopPlan,
        (k, b): (usize, &LoopBlockPlan),
        (supports, formed): (&[BlockSupport], &[bool]),
        (g_z, r_v): (&[Vec<Expr>], &[Vec<Expr>]),
    ) {
        let support = &supports[k];
        let (n, first) = (b.residuals.len(), b.first);
        let (n_rows, n_cols) = (support.rows.len(), support.cols.len());
        let index_list = |name: String, list: &[usize]| {
            let items: Vec<String> = list.iter().map(usize::to_string).collect();
            let head = format!("    const {name}: [usize; {}] = ", items.len());
            crate::codegen::format::array(&head, &items, ";", 4, self.width)
        };
        sink.line(|| index_list(format!("LOOP_COLS_{k}"), &support.cols));
        sink.line(|| format!("    let mut rz_{k} = SMatrix::<f64, {n}, {n}>::zeros();"));
        sink.line(|| format!("    let mut rv_{k} = SMatrix::<f64, {n}, {n_cols}>::zeros();"));
        for i in 0..n {
            for j in 0..n {
                self.cell(
                    sink,
                    &format!("rz_{k}"),
                    (i, j),
                    &lp.drdz[first + i][first + j],
                    false,
                );
            }
            for (j, &col) in support.cols.iter().enumerate() {
                self.cell(sink, &format!("rv_{k}"), (i, j), &r_v[first + i][col], true);
            }
        }
        for (c, earlier) in lp.blocks.iter().enumerate().take(k) {
            if !formed[c] || !reads_block(lp, k, c) {
                continue;
            }
            let width = earlier.residuals.len();
            let to = format!("rc_{k}_{c}");
            sink.line(|| format!("    let mut {to} = SMatrix::<f64, {n}, {width}>::zeros();"));
            for i in 0..n {
                for m in 0..width {
                    let e = &lp.drdz[first + i][earlier.first + m];
                    self.cell(sink, &to, (i, m), e, false);
                }
            }
            // Where each of block c's columns is among block k's (a superset, by construction).
            let at: Vec<usize> = supports[c]
                .cols
                .iter()
                .filter_map(|col| support.cols.iter().position(|x| x == col))
                .collect();
            sink.line(|| index_list(format!("LOOP_AT_{k}_{c}"), &at));
            sink.line(|| {
                format!(
                    "    for (j, &to) in LOOP_AT_{k}_{c}.iter().enumerate() {{\n        for i in 0..{n} {{\n            \
                     for m in 0..{width} {{\n                rv_{k}[(i, to)] -= {to}[(i, m)] * dz_{c}[(m, j)];\n            \
                     }}\n        }}\n    }}"
                )
            });
        }
        sink.line(|| format!("    let dz_{k} = bgc_solve(rz_{k}, rv_{k});"));
        if n_rows == 0 {
            return;
        }
        sink.line(|| index_list(format!("LOOP_ROWS_{k}"), &support.rows));
        sink.line(|| format!("    let mut gz_{k} = SMatrix::<f64, {n_rows}, {n}>::zeros();"));
        for (i, &row) in support.rows.iter().enumerate() {
            for m in 0..n {
                self.cell(
                    sink,
                    &format!("gz_{k}"),
                    (i, m),
                    &g_z[row][first + m],
                    false,
                );
            }
        }
        sink.line(|| {
            format!(
                "    for (i, &row) in LOOP_ROWS_{k}.iter().enumerate() {{\n        for (j, &col) in \
                 LOOP_COLS_{k}.iter().enumerate() {{\n            for m in 0..{n} {{\n                \
                 jac[(row, col)] += gz_{k}[(i, m)] * dz_{k}[(m, j)];\n            }}\n        }}\n    }}"
            )
        });
    }

    /// `var[(i, j)] = e;` (`-e` with `negate`) under its equation, unless `e` is zero; listed, `e` itself.
    fn cell(&self, sink: &mut Sink<'_>, var: &str, (i, j): (usize, usize), e: &Expr, negate: bool) {
        if e.is_zero() {
            return;
        }
        match sink {
            Sink::Listed(listed) => listed.push(e.clone()),
            Sink::Body(d) => {
                let value = if negate { -e } else { e.clone() };
                self.statement(
                    d,
                    &format!("{var}[{i}, {j}] = "),
                    &value,
                    &format!("{var}[({i}, {j})] = "),
                    ";",
                );
            }
        }
    }
}

/// Where the loop correction goes: written into a function body, or its cells' expressions only listed (for the
/// body's bindings, before it is written).
enum Sink<'s> {
    Body(&'s mut Draft),
    Listed(&'s mut Vec<Expr>),
}

impl Sink<'_> {
    /// Appends the line `make` builds to a body.
    fn line(&mut self, make: impl FnOnce() -> String) {
        if let Sink::Body(d) = self {
            d.lines.push(make());
        }
    }
}

/// Where block `k`'s part of a Jacobian's loop correction is: the rows of `∂g/∂z` that read its tears, and the
/// columns of `v` its residuals read directly or through the earlier blocks' tears they read (ascending).
#[derive(Clone, Debug, Default)]
pub(crate) struct BlockSupport {
    pub rows: Vec<usize>,
    pub cols: Vec<usize>,
}

/// The [`BlockSupport`] of each block, and whether its `dz` is formed: where it reaches a column and is used, by
/// rows that read its tears or by a later block, formed, that reads them.
fn formed_blocks(
    lp: &LoopPlan,
    g_z: &[Vec<Expr>],
    r_v: &[Vec<Expr>],
) -> (Vec<BlockSupport>, Vec<bool>) {
    let supports = block_supports(lp, g_z, r_v);
    let mut formed = vec![false; lp.blocks.len()];
    for k in (0..lp.blocks.len()).rev() {
        let used = !supports[k].rows.is_empty()
            || (k + 1..lp.blocks.len()).any(|j| formed[j] && reads_block(lp, j, k));
        formed[k] = used && !supports[k].cols.is_empty();
    }
    (supports, formed)
}

/// Whether the residuals of block `k` read a tear of block `c`.
fn reads_block(lp: &LoopPlan, k: usize, c: usize) -> bool {
    let (Some(b), Some(earlier)) = (lp.blocks.get(k), lp.blocks.get(c)) else {
        return false;
    };
    let theirs = earlier.first..earlier.first + earlier.residuals.len();
    (b.first..b.first + b.residuals.len()).any(|i| {
        theirs.clone().any(|m| {
            lp.drdz
                .get(i)
                .and_then(|row| row.get(m))
                .is_some_and(|e| !e.is_zero())
        })
    })
}

/// The [`BlockSupport`] of each block of `lp` for the correction of `g` by `v` (`∂g/∂z`, `∂r/∂v`).
pub(crate) fn block_supports(
    lp: &LoopPlan,
    g_z: &[Vec<Expr>],
    r_v: &[Vec<Expr>],
) -> Vec<BlockSupport> {
    let mut supports: Vec<BlockSupport> = Vec::with_capacity(lp.blocks.len());
    for b in &lp.blocks {
        let own = b.first..b.first + b.residuals.len();
        let mut cols = std::collections::BTreeSet::new();
        for i in own.clone() {
            let row = r_v.get(i).map_or(&[][..], Vec::as_slice);
            cols.extend((0..row.len()).filter(|&j| !row[j].is_zero()));
        }
        for (c, earlier) in supports.iter().enumerate() {
            if reads_block(lp, supports.len(), c) {
                cols.extend(earlier.cols.iter().copied());
            }
        }
        let rows = (0..g_z.len())
            .filter(|&r| {
                own.clone()
                    .any(|m| g_z[r].get(m).is_some_and(|e| !e.is_zero()))
            })
            .collect();
        supports.push(BlockSupport {
            rows,
            cols: cols.into_iter().collect(),
        });
    }
    supports
}
