//! Levenberg–Marquardt minimisation of `½‖r(z)‖²` with simple bounds on `z`.
//!
//! The step solves `(JᵀJ + λ D) δ = −Jᵀr` with `D` the diagonal of `JᵀJ` (Marquardt's scaling, so the method does
//! not depend on the units of `z`), and `λ` follows Nielsen's rule from the ratio of actual to predicted
//! reduction. Bounds are kept by projecting each trial point onto the box; the gradient test ignores components
//! that push against an active bound. A trial point at which the residuals cannot be computed (the simulation
//! fails) counts as a rejected step.
//!
//! **Convergence** is decided as MINPACK and SciPy's `least_squares` do, by three tests, and one more that tells a
//! minimum from a stall:
//! - `gtol` (first-order optimality): the largest cosine between `r` and a free column of `J`,
//!   `max_k |J_kᵀ r| / (‖J_k‖ ‖r‖)` (MINPACK's `gnorm`, independent of the units of `z`), is at most `gtol`;
//! - `ftol`: an accepted step reduced the cost by at most `ftol` times the cost;
//! - `xtol`: the step became smaller than `xtol (‖z‖ + xtol)`;
//! - the `ftol` and `xtol` tests do not stop an iteration whose damping is small (`λ < 1`, the step is
//!   nearly the Gauss–Newton one) while that step is still longer than [`LmOptions::optimality`] standard errors:
//!   a record can be so precise that its standard errors lie below `xtol`;
//! - a step that became negligible, a cost that stopped decreasing, or a damping that grew without bound says
//!   only that the iteration stopped moving: it counts as convergence when the Gauss–Newton step from the final
//!   point is also small *in standard errors*. That measure, [`Minimum::optimality`], is `‖P r‖ / s`, with `P`
//!   the projection onto the range of the free columns of `J` and `s² = ‖r‖² / (m − n)`: the size of the
//!   Gauss–Newton step in the metric of the estimate's covariance `s² (JᵀJ)⁻¹`. Below
//!   [`LmOptions::optimality`] (a tenth of a standard error by default) the remaining distance to the minimum is
//!   statistically nothing. With no more residuals than unknowns there is no standard error to measure by: there
//!   the undamped Gauss–Newton step must be below `√xtol (‖z‖ + √xtol)` instead. Residuals within the problem's
//!   rounding floor ([`Residuals::rounding_floor`]: a record the model reproduces to rounding) are an exact fit,
//!   whose distance is 0: there `‖P r‖` and `s` are both rounding errors, and their ratio is of order one
//!   whatever the iterate. Otherwise the fit **stalled** (e.g. a parameter running off towards infinity, where
//!   the cost keeps falling ever more slowly and the gradient is parallel to the residuals) and is reported as
//!   not converged.

use nalgebra::{DMatrix, DVector};

/// Residuals and their Jacobian at a point.
pub trait Residuals {
    /// `(r(z), ∂r/∂z)`; an error is a point where the model cannot be evaluated.
    fn evaluate(&mut self, z: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>), String>;

    /// The largest change of each coordinate in one step (empty: none). A step that would exceed one is not
    /// tried; the damping grows instead, as a trust region's radius shrinks.
    fn step_limits(&self) -> Vec<f64> {
        Vec::new()
    }

    /// The length of `r` below which the residuals are rounding errors of the values they compare: a fit that
    /// reaches it is exact, and its Gauss–Newton step measures rounding, not a distance to the minimum
    /// (0: the problem does not say).
    fn rounding_floor(&self) -> f64 {
        0.0
    }
}

/// Stopping tolerances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LmOptions {
    pub max_iterations: usize,
    /// Stop when the largest cosine between the residuals and a free column of the Jacobian is below this.
    pub gtol: f64,
    /// Stop when the step is below `xtol (‖z‖ + xtol)`.
    pub xtol: f64,
    /// Stop when an accepted step reduces the cost by less than `ftol` times the cost.
    pub ftol: f64,
    /// The largest change of a logarithmic coordinate in one step (1: a factor of e), for problems that say which
    /// coordinates are logarithmic ([`Residuals::step_limits`]): a first Gauss–Newton step along a direction the
    /// data barely determine can otherwise throw a parameter many decades away, onto a plateau it never leaves.
    pub max_log_step: f64,
    /// A stop by `xtol`, `ftol` or unbounded damping counts as convergence only when the Gauss–Newton step from
    /// the final point is below this many standard errors ([`Minimum::optimality`]) (or, with no more residuals
    /// than unknowns, below `√xtol (‖z‖ + √xtol)` in length).
    pub optimality: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            max_iterations: 200,
            gtol: 1e-10,
            xtol: 1e-8,
            ftol: 1e-10,
            optimality: 0.1,
            max_log_step: 1.0,
        }
    }
}

impl LmOptions {
    /// Refuses tolerances that would silently disable a test (a NaN compares false with everything) or make
    /// every point pass it.
    pub fn check(&self) -> Result<(), String> {
        let settings = [
            ("gtol", self.gtol),
            ("xtol", self.xtol),
            ("ftol", self.ftol),
            ("optimality", self.optimality),
        ];
        if let Some((name, v)) = settings.iter().find(|(_, v)| !(v.is_finite() && *v >= 0.0)) {
            return Err(format!(
                "LmOptions::{name} = {v:?}: it must be finite and not negative"
            ));
        }
        if self.max_log_step.is_nan() || self.max_log_step <= 0.0 {
            return Err(format!(
                "LmOptions::max_log_step = {:?}: it must be positive (infinite for no limit)",
                self.max_log_step
            ));
        }
        Ok(())
    }
}

/// Why the minimisation stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The gradient vanished (to `gtol`).
    Gradient,
    /// The step became negligible (to `xtol`).
    Step,
    /// The cost stopped decreasing (to `ftol`).
    Cost,
    /// No step could reduce the cost (`λ` grew without bound).
    NoProgress,
    /// The iteration limit was reached before any test passed.
    MaxIterations,
}

impl StopReason {
    /// A sentence for reports.
    pub fn describe(self) -> &'static str {
        match self {
            StopReason::Gradient => "the gradient vanished (a minimum)",
            StopReason::Step => "the step became negligible",
            StopReason::Cost => "the cost stopped decreasing",
            StopReason::NoProgress => "no step reduced the cost further",
            StopReason::MaxIterations => "the iteration limit was reached",
        }
    }
}

/// Whether the minimisation found a minimum.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Convergence {
    /// A minimum: the gradient test passed, or the iteration stopped moving within
    /// [`LmOptions::optimality`] standard errors of the minimum (or a negligible Gauss–Newton step from it).
    Converged,
    /// The iteration stopped moving (negligible step, cost or no progress) while the Gauss–Newton step was
    /// still larger than [`LmOptions::optimality`] standard errors: not a minimum.
    Stalled,
    /// The iteration limit was reached.
    IterationLimit,
}

impl Convergence {
    pub fn converged(self) -> bool {
        self == Convergence::Converged
    }

    /// A word for reports.
    pub fn describe(self) -> &'static str {
        match self {
            Convergence::Converged => "converged",
            Convergence::Stalled => "stalled (not a minimum)",
            Convergence::IterationLimit => "not converged (iteration limit)",
        }
    }
}

/// The result of a minimisation.
#[derive(Clone, Debug)]
pub struct Minimum {
    pub z: Vec<f64>,
    pub residuals: DVector<f64>,
    pub jacobian: DMatrix<f64>,
    pub iterations: usize,
    pub stop: StopReason,
    pub convergence: Convergence,
    /// The Gauss–Newton step from `z` in standard errors, `‖P r‖ / s` (see the module docs); 0 at an exact
    /// minimum, and at an exact fit (residuals within [`Residuals::rounding_floor`]), where the ratio of two
    /// rounding errors would measure nothing.
    pub optimality: f64,
}

/// The damping beyond which no step is worth trying.
const LAMBDA_MAX: f64 = 1e16;

/// Minimises `½‖r(z)‖²` from `z0` within `lower ≤ z ≤ upper`.
pub fn minimise(
    problem: &mut dyn Residuals,
    z0: &[f64],
    lower: &[f64],
    upper: &[f64],
    opts: &LmOptions,
) -> Result<Minimum, String> {
    opts.check()?;
    if lower.len() != z0.len() || upper.len() != z0.len() {
        return Err(format!(
            "{} coordinates with {} lower and {} upper bounds",
            z0.len(),
            lower.len(),
            upper.len()
        ));
    }
    // `clamp` below needs ordered, non-NaN bounds; a NaN start would be clamped to NaN and never move.
    for (k, ((&z, &lo), &hi)) in z0.iter().zip(lower).zip(upper).enumerate() {
        if lo.is_nan() || hi.is_nan() || lo > hi || !z.is_finite() {
            return Err(format!(
                "coordinate {k}: start {z:?} with bounds [{lo:?}, {hi:?}]"
            ));
        }
    }
    let project = |z: &mut [f64]| {
        for ((v, lo), hi) in z.iter_mut().zip(lower).zip(upper) {
            *v = v.clamp(*lo, *hi);
        }
    };
    let mut z = z0.to_vec();
    project(&mut z);
    let (mut r, mut j) = problem.evaluate(&z)?;
    let mut cost = 0.5 * r.norm_squared();
    check_start(&r, &j, cost)?;
    // λ multiplies the diagonal D of JᵀJ (Marquardt's scaling): it is dimensionless.
    let mut lambda = 1e-3;
    let mut nu = 2.0;
    let mut stop = StopReason::MaxIterations;
    let mut iterations = 0;
    let limits = problem.step_limits();
    while iterations < opts.max_iterations {
        let jtj = j.transpose() * &j;
        let g = j.transpose() * &r;
        check_products(&jtj, &g, iterations)?;
        let diag = jtj.diagonal().map(|d| d.max(1e-30));
        if largest_cosine(&z, &j, &r, &g, lower, upper) <= opts.gtol {
            stop = StopReason::Gradient;
            break;
        }
        iterations += 1;
        // Coordinates held at a bound by the gradient take no part in the step; the others move freely.
        let mut j_free = j.clone();
        for k in 0..z.len() {
            if blocked(z[k], g[k], lower[k], upper[k]) {
                j_free.column_mut(k).fill(0.0);
            }
        }
        let Some(delta) = solve_damped(&j_free, &r, &diag, lambda) else {
            lambda *= nu;
            nu *= 2.0;
            continue;
        };
        if delta.iter().zip(&limits).any(|(d, limit)| d.abs() > *limit) {
            lambda *= nu;
            nu *= 2.0;
            continue;
        }
        let mut trial: Vec<f64> = z.iter().zip(delta.iter()).map(|(a, d)| a + d).collect();
        project(&mut trial);
        let step = DVector::from_iterator(z.len(), trial.iter().zip(&z).map(|(a, b)| a - b));
        let z_norm = DVector::from_column_slice(&z).norm();
        // A small step with little damping is the Gauss–Newton step itself: when the statistics say it is still
        // worth taking (a record so precise that its standard errors are below xtol), it is taken.
        if step.norm() <= opts.xtol * (z_norm + opts.xtol)
            && (lambda >= 1.0 || gauss_newton_distance(&z, &j, &r, lower, upper) <= opts.optimality)
        {
            stop = StopReason::Step;
            break;
        }
        let predicted = -(step.dot(&g)) - 0.5 * step.dot(&(&jtj * &step));
        let accepted = match problem.evaluate(&trial) {
            Ok((r_new, j_new)) if r_new.iter().chain(j_new.iter()).all(|v| v.is_finite()) => {
                let new_cost = 0.5 * r_new.norm_squared();
                let rho = (cost - new_cost) / predicted.max(f64::MIN_POSITIVE);
                (new_cost < cost && rho > 0.0).then_some((r_new, j_new, new_cost, rho))
            }
            _ => None,
        };
        match accepted {
            Some((r_new, j_new, new_cost, rho)) => {
                let reduction = cost - new_cost;
                z = trial;
                r = r_new;
                j = j_new;
                cost = new_cost;
                lambda *= (1.0 / 3.0f64).max(1.0 - (2.0 * rho - 1.0).powi(3));
                nu = 2.0;
                if reduction <= opts.ftol * cost
                    && (lambda >= 1.0
                        || gauss_newton_distance(&z, &j, &r, lower, upper) <= opts.optimality)
                {
                    stop = StopReason::Cost;
                    break;
                }
            }
            None => {
                lambda *= nu;
                nu *= 2.0;
                if lambda > LAMBDA_MAX {
                    stop = StopReason::NoProgress;
                    break;
                }
            }
        }
    }
    // The final point's products too: the iteration may have ended right after the evaluation that reached it.
    check_products(&(j.transpose() * &j), &(j.transpose() * &r), iterations)?;
    // Residuals at the rounding level of the values they compare (a record the model reproduces exactly) have
    // a standard error of the same order, so the Gauss–Newton step in standard errors is noise of order one.
    let exact = r.norm() <= problem.rounding_floor();
    let optimality = match exact {
        true => 0.0,
        false => gauss_newton_distance(&z, &j, &r, lower, upper),
    };
    // Without degrees of freedom there is no standard error to measure by: the step's length decides.
    let near = opts.xtol.sqrt();
    let gn_negligible = j.nrows() <= j.ncols()
        && gauss_newton_step(&z, &j, &r, lower, upper)
            .is_some_and(|step| step <= near * (DVector::from_column_slice(&z).norm() + near));
    let convergence = match stop {
        StopReason::Gradient => Convergence::Converged,
        StopReason::MaxIterations => Convergence::IterationLimit,
        _ if optimality <= opts.optimality || gn_negligible => Convergence::Converged,
        _ => Convergence::Stalled,
    };
    Ok(Minimum {
        z,
        residuals: r,
        jacobian: j,
        iterations,
        stop,
        convergence,
        optimality,
    })
}

/// The start must be a point the optimality tests can read: residuals, Jacobian and cost finite, and a cost that
/// is zero only when the residuals are. Otherwise the gradient test sees `|Jᵀr| / (‖J‖ ‖r‖) = 0` (an infinite or
/// underflowed norm) and reports a minimum at the start.
fn check_start(r: &DVector<f64>, j: &DMatrix<f64>, cost: f64) -> Result<(), String> {
    if let Some(k) = r.iter().position(|v| !v.is_finite()) {
        return Err(format!(
            "the weighted residual {k} is {:?} at the start",
            r[k]
        ));
    }
    if j.iter().any(|v| !v.is_finite()) {
        return Err("the Jacobian of the residuals is not finite at the start".into());
    }
    if !cost.is_finite() || (cost == 0.0 && r.iter().any(|v| *v != 0.0)) {
        return Err(format!(
            "the weighted squared error at the start is {cost:e}, out of the range of f64: scale the record, the \
             weights or the starting values"
        ));
    }
    Ok(())
}

/// Refuses products of the Jacobian that overflow (`JᵀJ`, `Jᵀr`): a residual of 1e151 and a Jacobian of 1e153 each
/// fit in f64, their squares summed over the samples do not, and an infinite `JᵀJ` scales every step to zero and
/// every cosine of the gradient test to zero: the start came back as a converged minimum with standard errors of
/// 0. Checked at each iteration and at the final point, since `J` changes as the parameters move.
fn check_products(jtj: &DMatrix<f64>, g: &DVector<f64>, iteration: usize) -> Result<(), String> {
    let finite = jtj.iter().all(|v| v.is_finite()) && g.iter().all(|v| v.is_finite());
    match finite {
        true => Ok(()),
        false => Err(format!(
            "the products of the Jacobian of the weighted residuals (JᵀJ, Jᵀr) are out of the range of f64 at \
             iteration {iteration}: scale the record, the weights or the parameters"
        )),
    }
}

/// MINPACK's first-order optimality: the largest `|J_kᵀ r| / (‖J_k‖ ‖r‖)` over the columns free to move
/// (0 when the residuals vanish; a column the residuals do not depend on counts as 0).
fn largest_cosine(
    z: &[f64],
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    g: &DVector<f64>,
    lower: &[f64],
    upper: &[f64],
) -> f64 {
    let r_norm = r.norm();
    if r_norm == 0.0 {
        return 0.0;
    }
    let mut worst: f64 = 0.0;
    for k in 0..z.len() {
        let col = j.column(k).norm();
        if col > 0.0 && !blocked(z[k], g[k], lower[k], upper[k]) {
            worst = worst.max(g[k].abs() / (col * r_norm));
        }
    }
    worst
}

/// `‖P r‖ / s`: the Gauss–Newton step from `z` in standard errors, with `P` the projection onto the range of
/// the free columns of `J` (directions below [`TRUNCATION`] left out, as in the step) and `s² = ‖r‖²/(m − n)`.
/// Infinite when the decomposition fails.
fn gauss_newton_distance(
    z: &[f64],
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    lower: &[f64],
    upper: &[f64],
) -> f64 {
    let (m, n) = j.shape();
    let r_norm = r.norm();
    if r_norm == 0.0 || n == 0 {
        return 0.0;
    }
    let g = j.transpose() * r;
    // Columns scaled to unit norm: the projection does not change, the truncation becomes unit-free.
    let mut free = j.clone();
    for k in 0..n {
        let norm = free.column(k).norm();
        if blocked(z[k], g[k], lower[k], upper[k]) || norm == 0.0 {
            free.column_mut(k).fill(0.0);
        } else {
            free.column_mut(k).scale_mut(1.0 / norm);
        }
    }
    let Some(svd) = crate::linalg::check::svd(free, true, false, 1000) else {
        return f64::INFINITY;
    };
    let Some(u) = svd.u.as_ref() else {
        return f64::INFINITY;
    };
    let sigma_max = svd.singular_values.max();
    let projected: f64 = svd
        .singular_values
        .iter()
        .enumerate()
        .filter(|&(_, &sigma)| sigma > TRUNCATION * sigma_max && sigma > 0.0)
        .map(|(i, _)| u.column(i).dot(r).powi(2))
        .sum();
    let s = r_norm / (m.saturating_sub(n).max(1) as f64).sqrt();
    projected.sqrt() / s
}

/// The length of the undamped (truncated) Gauss–Newton step from `z` over the free coordinates.
fn gauss_newton_step(
    z: &[f64],
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    lower: &[f64],
    upper: &[f64],
) -> Option<f64> {
    let g = j.transpose() * r;
    let mut free = j.clone();
    for k in 0..z.len() {
        if blocked(z[k], g[k], lower[k], upper[k]) {
            free.column_mut(k).fill(0.0);
        }
    }
    let diag = free.column_iter().map(|c| c.norm_squared().max(1e-30));
    let diag = DVector::from_iterator(z.len(), diag);
    solve_damped(&free, r, &diag, 0.0).map(|d| d.norm())
}

/// The singular values of the scaled Jacobian below this fraction of the largest are dropped from the step:
/// directions the residuals do not feel (to the precision of the Jacobian) are left where they are instead of
/// wandering off; the statistics then report them ([`super::stats`]).
const TRUNCATION: f64 = 1e-9;

/// True when the coordinate sits on a bound and descent (`−g`) points out of the box.
fn blocked(z: f64, g: f64, lower: f64, upper: f64) -> bool {
    (z <= lower && g > 0.0) || (z >= upper && g < 0.0)
}

/// `δ` from `(JᵀJ + λ D) δ = −Jᵀr`, through the SVD of the scaled Jacobian `Ĵ = J D^{−½} = U Σ Vᵀ`:
/// `δ = −D^{−½} Σᵢ σᵢ/(σᵢ² + λ) (uᵢᵀ r) vᵢ` over the singular values above [`TRUNCATION`]; `None` when the
/// decomposition fails.
fn solve_damped(
    j: &DMatrix<f64>,
    r: &DVector<f64>,
    diag: &DVector<f64>,
    lambda: f64,
) -> Option<DVector<f64>> {
    let scale = diag.map(|d| 1.0 / d.sqrt());
    let mut scaled = j.clone();
    for (k, s) in scale.iter().enumerate() {
        scaled.column_mut(k).scale_mut(*s);
    }
    let svd = crate::linalg::check::svd(scaled, true, true, 1000)?;
    let (u, v_t) = (svd.u.as_ref()?, svd.v_t.as_ref()?);
    let sigma_max = svd.singular_values.max();
    let mut delta = DVector::zeros(j.ncols());
    for (i, &sigma) in svd.singular_values.iter().enumerate() {
        if sigma <= TRUNCATION * sigma_max || sigma == 0.0 {
            continue;
        }
        let coefficient = -sigma / (sigma * sigma + lambda) * u.column(i).dot(r);
        delta += v_t.row(i).transpose() * coefficient;
    }
    let delta = delta.component_mul(&scale);
    delta.iter().all(|v| v.is_finite()).then_some(delta)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock's function as residuals `(10 (z₁ − z₀²), 1 − z₀)`: the minimum is at (1, 1).
    struct Rosenbrock;

    impl Residuals for Rosenbrock {
        fn evaluate(&mut self, z: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>), String> {
            let r = DVector::from_vec(vec![10.0 * (z[1] - z[0] * z[0]), 1.0 - z[0]]);
            let j = DMatrix::from_row_slice(2, 2, &[-20.0 * z[0], 10.0, -1.0, 0.0]);
            Ok((r, j))
        }
    }

    #[test]
    fn finds_the_rosenbrock_minimum() {
        let inf = f64::INFINITY;
        let m = minimise(
            &mut Rosenbrock,
            &[-1.2, 1.0],
            &[-inf; 2],
            &[inf; 2],
            &LmOptions::default(),
        )
        .unwrap();
        assert!(
            (m.z[0] - 1.0).abs() < 1e-8 && (m.z[1] - 1.0).abs() < 1e-8,
            "{:?}",
            m.z
        );
        assert_eq!(m.convergence, Convergence::Converged);
    }

    #[test]
    fn bad_bounds_starts_and_options_are_errors() {
        // Inverted or NaN bounds made `clamp` panic, bounds shorter than the start panicked on an index, and a NaN
        // tolerance silently switched its test off.
        let inf = f64::INFINITY;
        let opts = LmOptions::default();
        let z0 = [-1.2, 1.0];
        for (lower, upper) in [([1.0, -inf], [0.0, inf]), ([f64::NAN, -inf], [inf, inf])] {
            assert!(minimise(&mut Rosenbrock, &z0, &lower, &upper, &opts).is_err());
        }
        assert!(minimise(&mut Rosenbrock, &z0, &[-inf], &[inf], &opts).is_err());
        assert!(
            minimise(
                &mut Rosenbrock,
                &[f64::NAN, 1.0],
                &[-inf; 2],
                &[inf; 2],
                &opts
            )
            .is_err()
        );
        for bad in [
            LmOptions {
                gtol: f64::NAN,
                ..opts
            },
            LmOptions {
                optimality: -1.0,
                ..opts
            },
            LmOptions {
                max_log_step: f64::NAN,
                ..opts
            },
            LmOptions {
                max_log_step: 0.0,
                ..opts
            },
        ] {
            let got = minimise(&mut Rosenbrock, &z0, &[-inf; 2], &[inf; 2], &bad);
            assert!(got.is_err(), "{bad:?}");
        }
    }

    #[test]
    fn a_bound_holds_the_minimum_on_it() {
        // With z₀ ≤ 0.5 the constrained minimum of Rosenbrock lies on the bound at z₀ = 0.5, z₁ = 0.25.
        let inf = f64::INFINITY;
        let m = minimise(
            &mut Rosenbrock,
            &[-1.2, 1.0],
            &[-inf; 2],
            &[0.5, inf],
            &LmOptions::default(),
        )
        .unwrap();
        assert!(
            (m.z[0] - 0.5).abs() < 1e-12 && (m.z[1] - 0.25).abs() < 1e-7,
            "{:?}",
            m.z
        );
    }

    /// `r = (z − 1, z − 2)` with the Jacobian given with the wrong sign: every step goes uphill, the damping grows
    /// without bound, and the gradient is far from zero.
    struct WrongJacobian;

    impl Residuals for WrongJacobian {
        fn evaluate(&mut self, z: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>), String> {
            let r = DVector::from_vec(vec![z[0] - 1.0, z[0] - 2.0]);
            Ok((r, DMatrix::from_element(2, 1, -1.0)))
        }
    }

    #[test]
    fn a_fit_that_stops_moving_away_from_a_minimum_is_a_stall() {
        let m = minimise(
            &mut WrongJacobian,
            &[0.0],
            &[f64::NEG_INFINITY],
            &[f64::INFINITY],
            &LmOptions::default(),
        )
        .unwrap();
        assert_eq!(m.stop, StopReason::NoProgress);
        assert_eq!(m.convergence, Convergence::Stalled);
        // At z = 0: r = (−1, −2), P r = −1.5 (1, 1), s = ‖r‖/√(2 − 1) = √5: ‖P r‖/s = 1.5 √2/√5.
        let want = 1.5 * 2.0f64.sqrt() / 5.0f64.sqrt();
        assert!((m.optimality - want).abs() < 1e-12, "{}", m.optimality);
    }

    #[test]
    fn the_optimality_of_a_noisy_minimum_is_nil_and_of_a_start_is_its_distance_in_standard_errors()
    {
        // A straight line through (0, 0), (1, 1), (2, 3): the Gauss–Newton step from the least-squares slope is
        // zero; from a slope one standard error off it is one standard error long.
        struct Line;
        impl Residuals for Line {
            fn evaluate(&mut self, z: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>), String> {
                let r = DVector::from_vec(vec![0.0, z[0] - 1.0, 2.0 * z[0] - 3.0]);
                Ok((r, DMatrix::from_column_slice(3, 1, &[0.0, 1.0, 2.0])))
            }
        }
        let inf = f64::INFINITY;
        let m = minimise(&mut Line, &[0.0], &[-inf], &[inf], &LmOptions::default()).unwrap();
        // Slope 7/5, residuals (0, 0.4, −0.2): s² = 0.2/2, se = s/√5.
        assert!((m.z[0] - 1.4).abs() < 1e-9 && m.optimality < 1e-6, "{m:?}");
        assert_eq!(m.convergence, Convergence::Converged);
        let se = (0.1f64 / 5.0).sqrt();
        let (r, j) = Line.evaluate(&[1.4 + se]).unwrap();
        let d = gauss_newton_distance(&[1.4 + se], &j, &r, &[-inf], &[inf]);
        // There s² is that of the displaced residuals: ‖r‖² = 0.2 + 5 se² = 0.3, s = √(0.3/2).
        let want = (5.0f64).sqrt() * se / (0.3f64 / 2.0).sqrt();
        assert!((d - want).abs() < 1e-12, "{d} vs {want}");
    }

    /// A current `v/R` through a resistor measured exactly (`v/10`, each value rounded once): near `R = 10` the
    /// residuals are rounding errors, and the Gauss–Newton step measured in their standard error was 6.7, a stall
    /// ("the fit stalled (not a minimum)" for a record the model reproduces exactly). With the rounding floor
    /// of the measured values the fit is exact and converged.
    struct Divider {
        floor: bool,
    }

    impl Residuals for Divider {
        fn evaluate(&mut self, z: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>), String> {
            let v = |k: usize| 1.0 + k as f64 * 0.1;
            // The model multiplies by the conductance, the record divides: they differ in the last place.
            let r = DVector::from_fn(50, |k, _| v(k) * z[0].recip() - v(k) / 10.0);
            let j = DMatrix::from_fn(50, 1, |k, _| -v(k) / (z[0] * z[0]));
            Ok((r, j))
        }

        fn rounding_floor(&self) -> f64 {
            let measured = (0..50).map(|k| (1.0 + k as f64 * 0.1) / 10.0);
            match self.floor {
                true => 1e3 * f64::EPSILON * measured.map(|y| y * y).sum::<f64>().sqrt(),
                false => 0.0,
            }
        }
    }

    #[test]
    fn a_record_reproduced_to_rounding_is_an_exact_fit_not_a_stall() {
        let inf = f64::INFINITY;
        let run = |floor| {
            minimise(
                &mut Divider { floor },
                &[3.0],
                &[0.0],
                &[inf],
                &LmOptions::default(),
            )
            .unwrap()
        };
        let exact = run(true);
        assert!((exact.z[0] - 10.0).abs() <= 1e-13, "{exact:?}");
        assert_eq!(exact.convergence, Convergence::Converged);
        assert_eq!(exact.optimality, 0.0);
        // Without the floor, the same iterate reads as a stall: the ratio of two rounding errors.
        let blind = run(false);
        assert!((blind.z[0] - 10.0).abs() <= 1e-13, "{blind:?}");
        assert_eq!(blind.convergence, Convergence::Stalled, "{blind:?}");
        assert!(blind.optimality > 0.1, "{blind:?}");
    }

    /// `r = 1e154 (z − 1)` three times from `z = 1.001`: each residual (1e151) and its cost fit in f64, but `JᵀJ`
    /// (3e308) does not. The infinite products made every step and every gradient cosine zero, and the start came
    /// back as a converged minimum; it is now an error.
    struct Steep;

    impl Residuals for Steep {
        fn evaluate(&mut self, z: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>), String> {
            Ok((
                DVector::from_element(3, 1e154 * (z[0] - 1.0)),
                DMatrix::from_element(3, 1, 1e154),
            ))
        }
    }

    #[test]
    fn a_jacobian_whose_products_overflow_is_an_error_not_a_minimum() {
        let inf = f64::INFINITY;
        let m = minimise(&mut Steep, &[1.001], &[-inf], &[inf], &LmOptions::default());
        let err = m.expect_err("out of range");
        assert!(
            err.contains("(JᵀJ, Jᵀr) are out of the range of f64 at iteration 0"),
            "{err}"
        );
    }

    /// `r = scale (z − 1, z − 2)`: with `scale` 1e200 the squared norm overflows, with 1e-170 it underflows to 0.
    /// Either way the gradient test read `|Jᵀr| / (‖J‖ ‖r‖)` as 0 and returned the start as a converged minimum.
    struct Scaled(f64);

    impl Residuals for Scaled {
        fn evaluate(&mut self, z: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>), String> {
            let r = DVector::from_vec(vec![self.0 * (z[0] - 1.0), self.0 * (z[0] - 2.0)]);
            Ok((r, DMatrix::from_element(2, 1, self.0)))
        }
    }

    #[test]
    fn a_start_whose_squared_error_is_out_of_range_is_an_error_not_a_minimum() {
        let inf = f64::INFINITY;
        for scale in [1e200, 1e-170] {
            let got = minimise(
                &mut Scaled(scale),
                &[0.0],
                &[-inf],
                &[inf],
                &LmOptions::default(),
            );
            let err = got.expect_err("refused");
            assert!(err.contains("out of the range of f64"), "{scale}: {err}");
        }
        let m = minimise(
            &mut Scaled(1.0),
            &[0.0],
            &[-inf],
            &[inf],
            &LmOptions::default(),
        )
        .unwrap();
        assert!((m.z[0] - 1.5).abs() < 1e-9, "{m:?}");
    }

    #[test]
    fn settings_and_starts_are_named_with_their_exact_value() {
        // Display would write 1e300 as 301 digits and drop the sign of -0.0; Debug writes `1e300` and `-0.0`.
        let opts = LmOptions {
            gtol: -1e300,
            ..LmOptions::default()
        };
        assert_eq!(
            opts.check().expect_err("negative"),
            "LmOptions::gtol = -1e300: it must be finite and not negative"
        );
        let opts = LmOptions {
            max_log_step: -0.0,
            ..LmOptions::default()
        };
        assert!(
            opts.check()
                .expect_err("not positive")
                .starts_with("LmOptions::max_log_step = -0.0:")
        );
        let err = minimise(
            &mut Scaled(1.0),
            &[f64::INFINITY],
            &[-1e300],
            &[1e300],
            &LmOptions::default(),
        )
        .expect_err("an infinite start");
        assert!(
            err.contains("start inf with bounds [-1e300, 1e300]"),
            "{err}"
        );
    }
}
