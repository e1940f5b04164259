//! Damped Newton's method for a small system of nonlinear equations `r(z) = 0` (the nonlinear algebraic loops of
//! [`super::tear`]), with a bracketing fallback for a single equation ([`bracketed`]).
//!
//! Each iteration solves `J(z_k) Δ = −r(z_k)` (Gaussian elimination with partial pivoting) and takes
//! `z_{k+1} = z_k + λ Δ` with the first `λ = 1, 1/2, 1/4, …` that passes the Armijo test
//! `φ(z_k + λΔ) ≤ (1 − 10⁻⁴ λ) φ(z_k)` on `φ(z) = Σ (r_i(z)/w_i)²`, the weights `w_i` being the residual scales at
//! `z_k`, or Deuflhard's natural monotonicity test (`contracts`: the simplified Newton correction at the trial
//! point is at most `1 − λ/4` of the step). The damping keeps a steep law (a diode's exponential) from throwing the
//! iterate where it overflows; the second test, blind to how the rows of `∂r/∂z` are scaled, keeps an
//! ill-conditioned loop from creeping (a loop of a random graph whose Jacobian has determinant 1 against products
//! of 10⁸ ran out of 100 damped steps with the Armijo test alone).
//!
//! Convergence is tested on the residual and on the Newton step. The residual: `|r_i(z)| ≤ rtol · s_i(z)` for
//! every `i`, where `s_i` is the scale of residual `i`, the sum of the magnitudes of its terms
//! ([`super::tear::residual_scale`]); free of units and reachable in floating point (a residual cannot be computed
//! more accurately than `ε · s_i`). A small residual alone does not bound the error of `z` where `∂r/∂z` is
//! ill-conditioned (a loop whose gain is near one along some direction: terms of 10⁹ that cancel to a residual of
//! 10⁻³ can leave the tears 0.1 % from the root), so the Newton step `Δ` from the iterate must be small too:
//! `|Δ_i| ≤ 10⁻¹⁰ |z_i|` (`step_ratio`), or, where rounding keeps it from getting there (a tear at zero, a
//! loop so ill-conditioned that the residuals' rounding moves the tears by more), it must have stopped
//! contracting (`StepTest`). From an iterate that passed the residual test the full Newton step is taken without
//! the line search (the residual no longer measures the distance to the root there). Both tests are checked after
//! at least one Newton step, so a warm start that already passes is polished to the quadratic rate's accuracy,
//! which keeps finite differences of the solution smooth.

// Index loops read like the textbook elimination they implement.
#![allow(clippy::needless_range_loop)]

/// A system `r(z) = 0` of `size()` equations in as many unknowns.
pub trait Problem {
    fn size(&self) -> usize;
    /// Writes `r(z)` and the residual scales `s(z)`.
    fn residual(&mut self, z: &[f64], r: &mut [f64], scale: &mut [f64]);
    /// Writes the Jacobian `∂r/∂z` at `z`, row-major (`jac[i·n + j] = ∂r_i/∂z_j`).
    fn jacobian(&mut self, z: &[f64], jac: &mut [f64]);
}

/// The settings of a solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// The residual tolerance relative to the residual scale.
    pub rtol: f64,
    /// The most Newton iterations.
    pub max_iterations: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            rtol: 1e-12,
            max_iterations: 100,
        }
    }
}

/// Why a solve failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FailureKind {
    /// No damped step decreases the residual: a local minimum of the residual that is not a root (often: the
    /// equations have no solution there).
    NoDescent,
    /// The iterations ran out.
    IterationLimit,
    /// `∂r/∂z` is singular at the iterate.
    Singular,
    /// The residual or the Jacobian is not finite at the iterate.
    NonFinite,
}

impl FailureKind {
    /// A short description for messages.
    pub fn describe(self) -> &'static str {
        match self {
            FailureKind::NoDescent => {
                "no damped step decreases the residual any more (the equations may have no solution here)"
            }
            FailureKind::IterationLimit => "the iteration limit was reached",
            FailureKind::Singular => "the Jacobian of the residuals is singular",
            FailureKind::NonFinite => "the residuals are not finite",
        }
    }
}

/// A failed solve: why, after how many iterations, and the largest residual (absolute value, and which).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Failure {
    pub kind: FailureKind,
    pub iterations: usize,
    /// `|r_index|` at the last iterate (NaN when not finite).
    pub residual: f64,
    pub index: usize,
}

/// The largest `|r_i|` and its index (a non-finite entry counts as the largest).
fn worst(r: &[f64]) -> (f64, usize) {
    let mut best = (0.0, 0);
    for (i, v) in r.iter().enumerate() {
        if !v.is_finite() {
            return (f64::NAN, i);
        }
        if v.abs() > best.0 {
            best = (v.abs(), i);
        }
    }
    best
}

fn merit(r: &[f64], w: &[f64]) -> f64 {
    r.iter().zip(w).map(|(r, w)| (r / w).powi(2)).sum()
}

/// Solves `problem` from the initial guess in `z`, in place. Returns the number of iterations (residual
/// evaluations of the bracketing fallback included).
///
/// Damped Newton first; for a single equation whose Newton iteration fails, a bracket of a sign change is searched
/// outward from the start and the root is found inside it ([`bracketed`]), which converges wherever the residual is
/// continuous and changes sign, however steep it is (a diode's exponential). For several equations whose Newton
/// iteration fails, Powell's dogleg method (`equations/dogleg.rs`) starts again from the same point. On failure `z`
/// holds the last iterate of the damped Newton's method and the error is its failure.
pub fn solve(
    problem: &mut dyn Problem,
    z: &mut [f64],
    settings: Settings,
) -> Result<usize, Failure> {
    let start = z.first().copied();
    let initial = z.to_vec();
    let failure = match damped(problem, z, settings) {
        Ok(k) => return Ok(k),
        Err(f) => f,
    };
    match (problem.size(), start) {
        (1, Some(z0)) if z0.is_finite() => match bracketed(problem, z0, settings) {
            Some((root, evaluations)) => {
                if let Some(z) = z.first_mut() {
                    *z = root;
                }
                Ok(failure.iterations + evaluations)
            }
            None => Err(failure),
        },
        // Several equations: the dogleg method from the same start, which follows a curved valley of the
        // residual where the line search creeps; its failure is reported as the damped method's.
        _ => {
            let mut again = initial.clone();
            match super::dogleg::solve(problem, &mut again, settings) {
                Some(evaluations) => {
                    z[..again.len()].copy_from_slice(&again);
                    Ok(failure.iterations + evaluations)
                }
                None => Err(failure),
            }
        }
    }
}

/// The most residual evaluations of [`bracketed`]: doubling the search interval from `1e-6` reaches `1e300` in
/// about 1,000, and bisecting such a bracket down to adjacent floats takes as many.
const BRACKET_EVALUATIONS: usize = 4000;

/// The relative residual accepted when the bracket has closed to adjacent floats: `√ε`.
const ROUNDING_FLOOR: f64 = 1.490_116_119_384_765_6e-8;

/// The residual and its scale of a one-equation problem at `z`.
fn eval1(problem: &mut dyn Problem, z: f64) -> (f64, f64) {
    let (mut r, mut s) = ([0.0], [0.0]);
    problem.residual(&[z], &mut r, &mut s);
    (r[0], s[0])
}

/// One equation: a root in a bracket of a sign change found outward from `z0`, by Newton steps that stay inside
/// the bracket and halve it at least every other step, else bisection (`rtsafe`). The root and the number of
/// evaluations, or `None` when no sign change is found or the bracket closes on a point whose residual is not
/// below the tolerance (a pole, a jump).
pub fn bracketed(problem: &mut dyn Problem, z0: f64, settings: Settings) -> Option<(f64, usize)> {
    let (r0, s0) = eval1(problem, z0);
    if r0.is_nan() {
        return None;
    }
    // Converged: finite, within the tolerance of the scale (an infinite residual is only a direction), and the
    // Newton step from the point within its tolerance.
    let within = |r: f64, s: f64| r.is_finite() && s.is_finite() && r.abs() <= settings.rtol * s;
    let mut derivative = |x: f64| {
        let mut jac = [f64::NAN];
        problem.jacobian(&[x], &mut jac);
        jac[0]
    };
    let settled = |x: f64, r: f64, s: f64, jac: f64| {
        within(r, s) && (r == 0.0 || step_ratio(&[x], &[r / jac]) <= 1.0)
    };
    if within(r0, s0) && settled(z0, r0, s0, derivative(z0)) {
        return Some((z0, 1));
    }
    let (mut lo, mut hi, mut evaluations) = bracket(problem, (z0, r0, s0))?;
    // `lo` has the negative residual; `x` is the best point so far.
    let (mut x, mut rx, mut sx) = if lo.1.abs() < hi.1.abs() { lo } else { hi };
    let mut step_before = (hi.0 - lo.0).abs();
    let mut step = step_before;
    while evaluations < BRACKET_EVALUATIONS {
        let mut jac = [f64::NAN];
        if rx.is_finite() {
            problem.jacobian(&[x], &mut jac);
        }
        if settled(x, rx, sx, jac[0]) {
            return Some((x, evaluations));
        }
        let newton = x - rx / jac[0];
        let (a, b) = (lo.0.min(hi.0), lo.0.max(hi.0));
        let inside = newton.is_finite() && newton > a && newton < b;
        let fast = (newton - x).abs() <= 0.5 * step_before;
        step_before = step;
        let next = if inside && fast {
            newton
        } else {
            a + (b - a) / 2.0
        };
        step = (next - x).abs();
        if next <= a || next >= b {
            // The bracket is two adjacent floats: the root is known to the last bit. A law steep enough that no
            // float meets the tolerance is accepted when its terms still cancel to half the digits (a pole or
            // a jump, whose residual is as large as its terms, is not).
            let (x, rx, sx) = if lo.1.abs() < hi.1.abs() { lo } else { hi };
            let floor = rx.is_finite() && sx.is_finite() && rx.abs() <= ROUNDING_FLOOR * sx;
            return (within(rx, sx) || floor).then_some((x, evaluations));
        }
        let (r, s) = eval1(problem, next);
        evaluations += 1;
        if r.is_nan() {
            return None;
        }
        if r < 0.0 {
            lo = (next, r, s);
        } else {
            hi = (next, r, s);
        }
        (x, rx, sx) = (next, r, s);
        if r == 0.0 && s.is_finite() {
            return Some((x, evaluations));
        }
    }
    let (x, rx, sx) = if lo.1.abs() < hi.1.abs() { lo } else { hi };
    within(rx, sx).then_some((x, evaluations))
}

/// A point with residual and scale.
type Point = (f64, f64, f64);

/// Points of opposite signs of the residual, searched at `z0 ± h` with `h` doubling from `10⁻⁶ max(1, |z0|)`:
/// the one with the negative residual first, the number of evaluations last. Infinite residuals count by their
/// sign (an exponential overflowing on one side still says which side the root is on); NaN ends the search on that
/// side.
fn bracket(problem: &mut dyn Problem, start: Point) -> Option<(Point, Point, usize)> {
    let (z0, r0, _) = start;
    let mut h = 1e-6 * z0.abs().max(1.0);
    // The nearest point on each side known to have the sign of `r0`.
    let mut same = [start, start];
    let mut open = [true, true];
    let mut evaluations = 1;
    while evaluations < BRACKET_EVALUATIONS && open.iter().any(|o| *o) {
        for (side, dir) in [1.0, -1.0].into_iter().enumerate() {
            if !open[side] {
                continue;
            }
            let z = z0 + dir * h;
            if !z.is_finite() {
                open[side] = false;
                continue;
            }
            let (r, s) = eval1(problem, z);
            evaluations += 1;
            if r.is_nan() {
                open[side] = false;
            } else if r == 0.0 || (r < 0.0) != (r0 < 0.0) {
                let near = same[side];
                let far = (z, r, s);
                let (neg, pos) = if r0 < 0.0 { (near, far) } else { (far, near) };
                return Some((neg, pos, evaluations));
            } else {
                same[side] = (z, r, s);
            }
        }
        h *= 2.0;
    }
    None
}

/// Damped Newton's method (the module docs); `z` holds the last iterate.
/// The damped Newton iteration alone, without the fallbacks of [`solve`].
#[cfg(test)]
pub(super) fn damped_for_tests(
    problem: &mut dyn Problem,
    z: &mut [f64],
    settings: Settings,
) -> Result<usize, Failure> {
    damped(problem, z, settings)
}

fn damped(problem: &mut dyn Problem, z: &mut [f64], settings: Settings) -> Result<usize, Failure> {
    let n = problem.size().min(z.len());
    let z = &mut z[..n];
    let (mut r, mut s) = (vec![0.0; n], vec![0.0; n]);
    let (mut r_try, mut s_try) = (vec![0.0; n], vec![0.0; n]);
    let mut jac = vec![0.0; n * n];
    let mut step = vec![0.0; n];
    let mut trial = vec![0.0; n];
    let fail = |kind, iterations, r: &[f64]| {
        let (residual, index) = worst(r);
        Failure {
            kind,
            iterations,
            residual,
            index,
        }
    };
    problem.residual(z, &mut r, &mut s);
    let mut floor = StepTest::default();
    for k in 0..=settings.max_iterations {
        if r.iter().chain(&s).any(|v| !v.is_finite()) {
            return Err(fail(FailureKind::NonFinite, k, &r));
        }
        let converged = within(&r, &s, settings.rtol);
        if k == 0 && r.iter().all(|v| *v == 0.0) {
            return Ok(k);
        }
        if k == settings.max_iterations {
            break;
        }
        problem.jacobian(z, &mut jac);
        step.iter_mut().zip(&r).for_each(|(d, r)| *d = -r);
        let solved = jac.iter().all(|v| v.is_finite()) && lu_solve(&jac, &mut step, n);
        if !solved {
            // A converged iterate where the step cannot be judged (a root where ∂r/∂z is singular) stays.
            if converged && k > 0 {
                return Ok(k);
            }
            let nonfinite = jac.iter().any(|v| !v.is_finite());
            let kind = if nonfinite {
                FailureKind::NonFinite
            } else {
                FailureKind::Singular
            };
            return Err(fail(kind, k, &r));
        }
        let ratio = converged.then(|| step_ratio(z, &step));
        if let Some(ratio) = ratio
            && k > 0
            && floor.accepts(ratio)
        {
            return Ok(k);
        }
        let w: Vec<f64> = s.iter().map(|s| if *s > 0.0 { *s } else { 1.0 }).collect();
        let phi0 = merit(&r, &w);
        let mut lambda = 1.0;
        let mut accepted = false;
        for _ in 0..40 {
            for i in 0..n {
                trial[i] = z[i] + lambda * step[i];
            }
            problem.residual(&trial, &mut r_try, &mut s_try);
            let phi = merit(&r_try, &w);
            // From an iterate that passed the residual test the full step is taken: the residual no longer
            // measures the distance to the root there (it is at its rounding floor, or the loop is
            // ill-conditioned), the Newton step does. The monotonicity test (an elimination) runs only when
            // the others fail.
            let accept = phi.is_finite()
                && (converged
                    || phi <= (1.0 - 1e-4 * lambda) * phi0
                    || contracts(&jac, &r_try, z, &step, lambda));
            if accept {
                accepted = true;
                break;
            }
            lambda /= 2.0;
        }
        if !accepted {
            // No step from a converged iterate leads to finite residuals: it stays as it is.
            if converged {
                return Ok(k);
            }
            return Err(fail(FailureKind::NoDescent, k, &r));
        }
        floor.took(ratio, lambda == 1.0);
        z.copy_from_slice(&trial);
        std::mem::swap(&mut r, &mut r_try);
        std::mem::swap(&mut s, &mut s_try);
    }
    Err(fail(
        FailureKind::IterationLimit,
        settings.max_iterations,
        &r,
    ))
}

/// Deuflhard's natural monotonicity test: the simplified Newton correction at the trial point,
/// `Δ̄ = −J(z)⁻¹ r(z + λΔ)` with the iterate's Jacobian `jac`, is at most `1 − λ/4` of the step `Δ`, in norms
/// scaled by the tears' magnitudes. Unlike the residual's decrease it does not change when the rows of `∂r/∂z` are
/// scaled, so it accepts the steps towards the root of an ill-conditioned loop (a weak direction whose residual
/// the strong ones' curvature hides) where the residual's line search creeps.
fn contracts(jac: &[f64], r_trial: &[f64], z: &[f64], step: &[f64], lambda: f64) -> bool {
    let n = step.len();
    let mut bar: Vec<f64> = r_trial.iter().map(|v| -v).collect();
    if !lu_solve(jac, &mut bar, n) {
        return false;
    }
    let norm = |v: &[f64]| {
        let squares = v.iter().zip(z.iter().zip(step)).map(|(v, (z, d))| {
            let scale = z.abs().max((z + d).abs());
            (v / if scale > 0.0 { scale } else { 1.0 }).powi(2)
        });
        squares.sum::<f64>().sqrt()
    };
    norm(&bar) <= (1.0 - lambda / 4.0) * norm(step)
}

/// The residual test: `|r_i| ≤ rtol · s_i` for every `i`.
pub(super) fn within(r: &[f64], s: &[f64], rtol: f64) -> bool {
    r.iter().zip(s).all(|(r, s)| r.abs() <= rtol * s)
}

/// The Newton step's size in units of its tolerance, `max_i |Δ_i| / (STEP_RTOL · |z_i|)`: an iterate whose step
/// is within it is accurate to about `STEP_RTOL` (Newton's method converges quadratically from there); `∞` for a
/// step that is not finite or that moves a tear at zero. The tolerance has no absolute part: what rounding leaves
/// of a tear at zero, `|(∂r/∂z)⁻¹| ε s`, is known only by how the steps stop contracting ([`StepTest`]).
pub(super) fn step_ratio(z: &[f64], step: &[f64]) -> f64 {
    z.iter().zip(step).fold(0.0, |m: f64, (z, d)| {
        let q = if *d == 0.0 {
            0.0
        } else {
            d.abs() / (STEP_RTOL * z.abs())
        };
        m.max(if q.is_nan() { f64::INFINITY } else { q })
    })
}

/// The Newton step's tolerance relative to the tear ([`step_ratio`]).
const STEP_RTOL: f64 = 1e-10;

/// The step half of the convergence test, at iterates that passed the residual test: the Newton step is within
/// the tolerance (`ratio ≤ 1`), or it is at least half the full step that led to the iterate from one that also
/// passed. Newton's method at least halves its steps near a root at every precision the arithmetic resolves
/// (quadratically where `∂r/∂z` is regular), so a step that does not is rounding noise, `|(∂r/∂z)⁻¹| ε s` in
/// size: the iterate is as accurate as the residuals can be evaluated.
#[derive(Clone, Copy, Debug)]
pub(super) struct StepTest {
    /// The ratio of the last step if it was a full step from an iterate that passed the residual test.
    previous: f64,
}

impl Default for StepTest {
    fn default() -> Self {
        StepTest {
            previous: f64::INFINITY,
        }
    }
}

impl StepTest {
    /// True when an iterate with this step ratio has converged.
    pub(super) fn accepts(&self, ratio: f64) -> bool {
        ratio <= 1.0 || ratio >= 0.5 * self.previous
    }

    /// Records the step taken: its ratio when the iterate passed the residual test, and whether it was full.
    pub(super) fn took(&mut self, ratio: Option<f64>, full: bool) {
        self.previous = match ratio {
            Some(q) if full => q,
            _ => f64::INFINITY,
        };
    }
}

/// Solves `a x = b` in place (`a` row-major `n × n`; `b` becomes `x`). False when a pivot is zero or below `1e-14`
/// times the largest entry of its column before elimination.
pub(super) fn lu_solve(a: &[f64], b: &mut [f64], n: usize) -> bool {
    Lu::factor(a.to_vec(), n).is_some_and(|lu| lu.solve(b))
}

/// A square matrix factored by Gaussian elimination with partial pivoting, `P a = L U`, to solve with many
/// right-hand sides: an algebraic loop that is linear with a Jacobian of parameters only is factored once per
/// simulation, not at every solve.
#[derive(Clone, Debug, PartialEq)]
pub struct Lu {
    /// `U` on and above the diagonal, `L`'s multipliers below it (row-major).
    factors: Vec<f64>,
    /// The row swapped with row `k` at step `k`.
    pivots: Vec<usize>,
    n: usize,
}

impl Lu {
    /// Factors `a` (row-major `n × n`); `None` when a pivot is zero or below `1e-14` times the largest entry of
    /// its column before elimination.
    pub fn factor(mut a: Vec<f64>, n: usize) -> Option<Lu> {
        if a.len() != n * n {
            return None;
        }
        let mut pivots = Vec::with_capacity(n);
        for col in 0..n {
            let column_scale = (0..n).fold(0.0f64, |m, i| m.max(a[i * n + col].abs()));
            let pivot =
                (col..n).max_by(|&i, &j| a[i * n + col].abs().total_cmp(&a[j * n + col].abs()))?;
            let p = a[pivot * n + col];
            if p == 0.0 || p.abs() <= 1e-14 * column_scale {
                return None;
            }
            if pivot != col {
                for j in 0..n {
                    a.swap(pivot * n + j, col * n + j);
                }
            }
            pivots.push(pivot);
            for i in col + 1..n {
                let factor = a[i * n + col] / p;
                a[i * n + col] = factor;
                if factor == 0.0 {
                    continue;
                }
                for j in col + 1..n {
                    a[i * n + j] -= factor * a[col * n + j];
                }
            }
        }
        Some(Lu {
            factors: a,
            pivots,
            n,
        })
    }

    /// Solves `a x = b` in place; false when `b` has another length or `x` is not finite.
    pub fn solve(&self, b: &mut [f64]) -> bool {
        let (a, n) = (&self.factors, self.n);
        if b.len() != n {
            return false;
        }
        // The rows were swapped whole, multipliers included: all the swaps first, then `L`.
        for (col, &pivot) in self.pivots.iter().enumerate() {
            b.swap(pivot, col);
        }
        for col in 0..n {
            for i in col + 1..n {
                let factor = a[i * n + col];
                if factor != 0.0 {
                    b[i] -= factor * b[col];
                }
            }
        }
        for i in (0..n).rev() {
            let mut acc = b[i];
            for j in i + 1..n {
                acc -= a[i * n + j] * b[j];
            }
            b[i] = acc / a[i * n + i];
        }
        b.iter().all(|v| v.is_finite())
    }
}

/// Solves a problem whose residual is affine in `z` with the constant Jacobian factored in `lu`: Newton steps
/// with that factorisation, accepted by the tests of [`solve`] (residuals within the tolerance, then a step within
/// its tolerance or no longer contracting). False when they do not pass within a few steps (rounding that
/// refinement does not remove, or a residual that is not affine after all): the caller then runs [`solve`].
pub fn solve_affine(problem: &mut dyn Problem, lu: &Lu, z: &mut [f64], settings: Settings) -> bool {
    let n = problem.size();
    if z.len() != n || lu.n != n {
        return false;
    }
    let (mut r, mut s, mut step) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut floor = StepTest::default();
    for k in 0..AFFINE_STEPS {
        problem.residual(z, &mut r, &mut s);
        if r.iter().chain(&s).any(|v| !v.is_finite()) {
            return false;
        }
        if k == 0 && r.iter().all(|v| *v == 0.0) {
            return true;
        }
        let converged = within(&r, &s, settings.rtol);
        step.iter_mut().zip(&r).for_each(|(d, r)| *d = -r);
        if !lu.solve(&mut step) {
            return false;
        }
        let ratio = converged.then(|| step_ratio(z, &step));
        if let Some(ratio) = ratio
            && k > 0
            && floor.accepts(ratio)
        {
            return true;
        }
        floor.took(ratio, true);
        z.iter_mut().zip(&step).for_each(|(z, d)| *z += d);
    }
    false
}

/// The most steps [`solve_affine`] takes: one lands on the solution, the next confirms it, and a third or fourth
/// refines what rounding left.
const AFFINE_STEPS: usize = 4;

#[cfg(test)]
mod tests {
    use super::*;

    /// `r(z) = (z0² + z1² − 4, exp(z0) + z1 − 1)` with scales the magnitudes of the terms.
    struct Circle;

    impl Problem for Circle {
        fn size(&self) -> usize {
            2
        }
        fn residual(&mut self, z: &[f64], r: &mut [f64], s: &mut [f64]) {
            r[0] = z[0] * z[0] + z[1] * z[1] - 4.0;
            s[0] = z[0] * z[0] + z[1] * z[1] + 4.0;
            r[1] = z[0].exp() + z[1] - 1.0;
            s[1] = z[0].exp() + z[1].abs() + 1.0;
        }
        fn jacobian(&mut self, z: &[f64], j: &mut [f64]) {
            j.copy_from_slice(&[2.0 * z[0], 2.0 * z[1], z[0].exp(), 1.0]);
        }
    }

    #[test]
    fn finds_the_intersection_of_a_circle_and_an_exponential() {
        // The root near (1, -1.7): scipy.optimize.fsolve(lambda z: [z[0]**2 + z[1]**2 - 4,
        // np.exp(z[0]) + z[1] - 1], [1, -1.7], xtol=1e-14) = [1.00416874, -1.72963729].
        let mut z = [1.0, -1.7];
        let k = solve(&mut Circle, &mut z, Settings::default());
        assert!(k.is_ok(), "{k:?}");
        assert!((z[0] - 1.004_168_74).abs() < 1e-8, "{z:?}");
        assert!((z[1] + 1.729_637_29).abs() < 1e-8, "{z:?}");
        let (mut r, mut s) = ([0.0; 2], [0.0; 2]);
        Circle.residual(&z, &mut r, &mut s);
        assert!(r[0].abs() < 1e-12 * s[0] && r[1].abs() < 1e-12 * s[1]);
    }

    /// `r(z) = z² + 1`: no real root.
    struct NoRoot;

    impl Problem for NoRoot {
        fn size(&self) -> usize {
            1
        }
        fn residual(&mut self, z: &[f64], r: &mut [f64], s: &mut [f64]) {
            r[0] = z[0] * z[0] + 1.0;
            s[0] = z[0] * z[0] + 1.0;
        }
        fn jacobian(&mut self, z: &[f64], j: &mut [f64]) {
            j[0] = 2.0 * z[0];
        }
    }

    #[test]
    fn an_equation_without_a_root_fails_with_its_residual() {
        let mut z = [0.5];
        let err = solve(&mut NoRoot, &mut z, Settings::default());
        match err {
            Err(f) => {
                assert!(matches!(
                    f.kind,
                    FailureKind::NoDescent | FailureKind::Singular
                ));
                // z² + 1 ≥ 1 everywhere.
                assert!(f.residual >= 1.0, "{f:?}");
                assert_eq!(f.index, 0);
            }
            Ok(k) => panic!("converged in {k} iterations to {z:?}"),
        }
        // From z = 0 the Jacobian is singular at once.
        let mut z = [0.0];
        assert_eq!(
            solve(&mut NoRoot, &mut z, Settings::default()).map_err(|f| f.kind),
            Err(FailureKind::Singular)
        );
    }

    /// `r(i) = i − I_s (exp((u − R i)/V_t) − 1)`: the diode loop of `bgc/tests/corpus/diode_rc.bg` with the
    /// capacitor uncharged, scales the magnitudes of the terms.
    struct Diode {
        u: f64,
    }

    impl Problem for Diode {
        fn size(&self) -> usize {
            1
        }
        fn residual(&mut self, z: &[f64], r: &mut [f64], s: &mut [f64]) {
            let e = (self.u - 100.0 * z[0]) / 0.05;
            r[0] = z[0] - 1e-6 * (e.exp() - 1.0);
            s[0] = z[0].abs() + 1e-6 * (e.exp() + 1.0);
        }
        fn jacobian(&mut self, z: &[f64], j: &mut [f64]) {
            j[0] = 1.0 + 1e-6 * ((self.u - 100.0 * z[0]) / 0.05).exp() * 100.0 / 0.05;
        }
    }

    #[test]
    fn a_steep_scalar_loop_is_solved_by_bracketing_where_damped_newton_stops() {
        // Roots by bisection in Python down to adjacent floats on [0, u/100], where r goes from < 0 to > 0:
        //   r = lambda i: i - 1e-6*(math.exp((u - 100*i)/0.05) - 1)   (-inf where exp overflows)
        //   a, b = 0.0, u/100; repeat: m = (a+b)/2; a, b = (m, b) if r(m) < 0 else (a, m)
        // u = 10: 0.09427301953896923; u = 100: 0.9930957083358242.
        for (u, root) in [
            (10.0, 0.094_273_019_538_969_23),
            (100.0, 0.993_095_708_335_824_2),
        ] {
            let mut z = [0.0];
            assert!(damped(&mut Diode { u }, &mut z, Settings::default()).is_err());
            let mut z = [0.0];
            let k = solve(&mut Diode { u }, &mut z, Settings::default());
            assert!(k.is_ok(), "u = {u}: {k:?}");
            assert!((z[0] - root).abs() < 1e-10, "u = {u}: {z:?}");
        }
        for u in [8.0, 20.0, 1e3] {
            let mut z = [0.0];
            assert!(
                solve(&mut Diode { u }, &mut z, Settings::default()).is_ok(),
                "u = {u}"
            );
            let (mut r, mut s) = ([0.0], [0.0]);
            Diode { u }.residual(&z, &mut r, &mut s);
            assert!(r[0].abs() <= 1e-12 * s[0], "u = {u}: {r:?} {s:?}");
        }
    }

    /// `r(z) = 1` below `z = 2` and `−1` from there on: a sign change at a jump, which is no root.
    struct Jump;

    impl Problem for Jump {
        fn size(&self) -> usize {
            1
        }
        fn residual(&mut self, z: &[f64], r: &mut [f64], s: &mut [f64]) {
            r[0] = if z[0] < 2.0 { 1.0 } else { -1.0 };
            s[0] = 1.0;
        }
        fn jacobian(&mut self, _z: &[f64], j: &mut [f64]) {
            j[0] = 0.0;
        }
    }

    #[test]
    fn a_sign_change_without_a_root_is_not_taken_for_one() {
        let mut z = [0.0];
        let err = solve(&mut Jump, &mut z, Settings::default());
        assert!(
            matches!(
                err,
                Err(Failure {
                    kind: FailureKind::Singular,
                    ..
                })
            ),
            "{err:?} {z:?}"
        );
    }

    #[test]
    fn solves_small_linear_systems() {
        // [[0, 2], [3, 1]] x = [4, 5]: x = (1, 2), with a pivot swap.
        let a = [0.0, 2.0, 3.0, 1.0];
        let mut b = [4.0, 5.0];
        assert!(lu_solve(&a, &mut b, 2));
        assert!((b[0] - 1.0).abs() < 1e-15 && (b[1] - 2.0).abs() < 1e-15);
        let singular = [1.0, 2.0, 2.0, 4.0];
        assert!(!lu_solve(&singular, &mut [1.0, 1.0], 2));
    }

    /// A 3 × 3 system whose elimination swaps rows after the first column's multipliers are stored, solved for two
    /// right-hand sides with one factorisation: `x = (1, 1, 1)` and `x = (1, −2, 1)` (by hand: `A x = b`).
    #[test]
    fn a_factorisation_solves_several_right_hand_sides() {
        let a = vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 10.0];
        let lu = Lu::factor(a, 3).expect("regular");
        for (mut b, x) in [
            ([6.0, 15.0, 25.0], [1.0, 1.0, 1.0]),
            ([0.0, 0.0, 1.0], [1.0, -2.0, 1.0]),
        ] {
            assert!(lu.solve(&mut b));
            for (got, want) in b.iter().zip(x) {
                assert!((got - want).abs() < 1e-13, "{b:?} vs {x:?}");
            }
        }
        assert!(
            Lu::factor(vec![1.0, 2.0, 2.0, 4.0], 2).is_none(),
            "singular"
        );
    }

    /// `r(z) = A z − b` with the scales the magnitudes of its terms.
    struct Affine {
        a: [[f64; 2]; 2],
        b: [f64; 2],
    }

    impl Problem for Affine {
        fn size(&self) -> usize {
            2
        }
        fn residual(&mut self, z: &[f64], r: &mut [f64], s: &mut [f64]) {
            for i in 0..2 {
                r[i] = self.a[i][0] * z[0] + self.a[i][1] * z[1] - self.b[i];
                s[i] = (self.a[i][0] * z[0]).abs() + (self.a[i][1] * z[1]).abs() + self.b[i].abs();
            }
        }
        fn jacobian(&mut self, _: &[f64], jac: &mut [f64]) {
            jac.copy_from_slice(&[self.a[0][0], self.a[0][1], self.a[1][0], self.a[1][1]]);
        }
    }

    #[test]
    fn an_affine_problem_is_solved_with_its_factorisation_and_a_wrong_one_is_refused() {
        let mut p = Affine {
            a: [[2.0, 1.0], [1.0, 3.0]],
            b: [3.0, 5.0],
        };
        let lu = Lu::factor(vec![2.0, 1.0, 1.0, 3.0], 2).expect("regular");
        let mut z = [10.0, -7.0];
        assert!(solve_affine(&mut p, &lu, &mut z, Settings::default()));
        // x = (4/5, 7/5).
        assert!(
            (z[0] - 0.8).abs() < 1e-14 && (z[1] - 1.4).abs() < 1e-14,
            "{z:?}"
        );
        // A factorisation of another matrix does not converge in its few steps: the caller runs Newton's method.
        let wrong = Lu::factor(vec![1.0, 0.0, 0.0, 1.0], 2).expect("regular");
        let mut z = [10.0, -7.0];
        assert!(!solve_affine(&mut p, &wrong, &mut z, Settings::default()));
    }

    /// Two tears along a valley: with `w = z0 + z1` and `d = z0 − z1`, `r0 = M d + β w² + μ w + w³ − c0` and
    /// `r1 = M d + β w² − μ w − w³ − c1` (`M` = 10⁶). The terms are of 10⁶ and cancel to leave the weak direction
    /// `w` (`∂(r0 − r1)/∂w` = 0.03 to 27 at the roots below): a residual within `10⁻¹² s` is no closer than 10⁻⁵ to
    /// the root along it. With `β ≠ 0` the valley bends: a step along `w` raises both residuals by `β w²`.
    struct Valley {
        c: [f64; 2],
        beta: f64,
        mu: f64,
    }

    const VALLEY_M: f64 = 1e6;

    impl Valley {
        /// The data for the root at `w` (`d` about 3).
        fn new(w: f64, beta: f64, mu: f64) -> Self {
            let k = mu * w + w.powi(3);
            Valley {
                c: [3e6 + k, 3e6 - k],
                beta,
                mu,
            }
        }

        /// The root of the data as stored: `μ w + w³ = (c0 − c1)/2` (a cubic with one real root, by Newton's
        /// method on it, well-conditioned: `3w² + μ` ≥ 0.03 near it) and `2 M d = c0 + c1 − 2 β w²`.
        fn root(&self) -> [f64; 2] {
            let k = (self.c[0] - self.c[1]) / 2.0;
            let mut w = k.cbrt();
            for _ in 0..50 {
                w -= (self.mu * w + w.powi(3) - k) / (self.mu + 3.0 * w * w);
            }
            let d = (self.c[0] + self.c[1] - 2.0 * self.beta * w * w) / (2.0 * VALLEY_M);
            [(w + d) / 2.0, (w - d) / 2.0]
        }

        fn at(&self, z: &[f64]) -> ([f64; 2], [f64; 2], [f64; 4]) {
            let (w, d) = (z[0] + z[1], z[0] - z[1]);
            let weak = self.mu * w + w.powi(3);
            let strong = VALLEY_M * d + self.beta * w * w;
            let terms = (VALLEY_M * d).abs()
                + (self.beta * w * w).abs()
                + (self.mu * w).abs()
                + w.powi(3).abs();
            let (dw, bw) = (self.mu + 3.0 * w * w, 2.0 * self.beta * w);
            (
                [strong + weak - self.c[0], strong - weak - self.c[1]],
                [terms + self.c[0].abs(), terms + self.c[1].abs()],
                [
                    VALLEY_M + bw + dw,
                    -VALLEY_M + bw + dw,
                    VALLEY_M + bw - dw,
                    -VALLEY_M + bw - dw,
                ],
            )
        }

        /// `z` within `1e-8` of the root, tear by tear.
        fn at_root(&self, z: &[f64]) -> bool {
            z.iter()
                .zip(self.root())
                .all(|(z, root)| (z - root).abs() <= 1e-8 * root.abs())
        }
    }

    impl Problem for Valley {
        fn size(&self) -> usize {
            2
        }
        fn residual(&mut self, z: &[f64], r: &mut [f64], s: &mut [f64]) {
            let (rr, ss, _) = self.at(z);
            r.copy_from_slice(&rr);
            s.copy_from_slice(&ss);
        }
        fn jacobian(&mut self, z: &[f64], j: &mut [f64]) {
            j.copy_from_slice(&self.at(z).2);
        }
    }

    #[test]
    fn an_ill_conditioned_loop_is_solved_to_its_root_not_to_its_residual_tolerance() {
        // Before the step test, damped Newton's method from zero stopped at z0 = 1.5500216 for the root
        // 1.5499999999 (w = 0.1; residuals within 10⁻¹² s); now the tears are as accurate as rounding allows:
        // ε s / (∂r/∂w) ≈ 2e-16 · 3·10⁶ / 0.03 ≈ 2e-8 in w, 1e-8 relative to the tears.
        for w in [0.1, 0.3, 1.0] {
            let valley = Valley::new(w, 0.0, 1e-3);
            let root = valley.root();
            for start in [[0.0, 0.0], [1.0, -1.0], [2.0 * root[0], root[1]]] {
                let mut problem = Valley::new(w, 0.0, 1e-3);
                let mut z = start;
                let k = solve(&mut problem, &mut z, Settings::default());
                assert!(
                    k.is_ok() && valley.at_root(&z),
                    "w = {w} from {start:?}: {k:?} {z:?}"
                );
                // The dogleg method on its own, as the fallback of a failed damped iteration.
                let mut by_dogleg = start;
                let k =
                    super::super::dogleg::solve(&mut problem, &mut by_dogleg, Settings::default());
                assert!(
                    k.is_some() && valley.at_root(&by_dogleg),
                    "w = {w} from {start:?}: {by_dogleg:?}"
                );
            }
        }
    }

    #[test]
    fn a_bent_ill_conditioned_valley_is_followed_by_the_natural_monotonicity_test() {
        // With the Armijo test alone the damped method ran out of its 100 iterations at w = 1.78, 2.42 and 0.34
        // (residuals 93, 1.2e6, 8.9e4), and the dogleg fallback failed too; with the natural monotonicity test
        // the damped method reaches each root in 5 iterations.
        for (beta, mu, start) in [
            (1e6, 1e-3, [1.0, -1.0]),
            (1e7, 1e-2, [0.0, 0.0]),
            (1e7, 1e-2, [1.0, -1.0]),
        ] {
            let mut valley = Valley::new(3.0, beta, mu);
            let mut z = start;
            let k = damped(&mut valley, &mut z, Settings::default());
            assert!(
                k.is_ok_and(|k| k <= 10) && valley.at_root(&z),
                "β = {beta}, μ = {mu} from {start:?}: {k:?} {z:?} against {:?}",
                valley.root()
            );
        }
    }
}
