//! Levenberg–Marquardt minimisation of `½‖r(z)‖²` with simple bounds on `z`.
//!
//! The step solves `(JᵀJ + λ D) δ = −Jᵀr` with `D` the diagonal of `JᵀJ` (Marquardt's scaling, so the method does
//! not depend on the units of `z`), and `λ` follows Nielsen's rule from the ratio of actual to predicted
//! reduction. Bounds are kept by projecting each trial point onto the box; the gradient test ignores components
//! that push against an active bound. A trial point at which the residuals cannot be computed (the simulation
//! fails) counts as a rejected step.

use nalgebra::{DMatrix, DVector};

/// Residuals and their Jacobian at a point.
pub trait Residuals {
    /// `(r(z), ∂r/∂z)`; an error is a point where the model cannot be evaluated.
    fn evaluate(&mut self, z: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>), String>;
}

/// Stopping tolerances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LmOptions {
    pub max_iterations: usize,
    /// Stop when the largest (projected) gradient component of the scaled problem is below this.
    pub gtol: f64,
    /// Stop when the step is below `xtol (‖z‖ + xtol)`.
    pub xtol: f64,
    /// Stop when an accepted step reduces the cost by less than `ftol` times the cost.
    pub ftol: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            max_iterations: 200,
            gtol: 1e-10,
            xtol: 1e-8,
            ftol: 1e-10,
        }
    }
}

/// Why the minimisation stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The gradient vanished (to `gtol`): a minimum.
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

    /// True for the reasons that mean convergence.
    pub fn converged(self) -> bool {
        !matches!(self, StopReason::MaxIterations)
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
    let project = |z: &mut [f64]| {
        for ((v, lo), hi) in z.iter_mut().zip(lower).zip(upper) {
            *v = v.clamp(*lo, *hi);
        }
    };
    let mut z = z0.to_vec();
    project(&mut z);
    let (mut r, mut j) = problem.evaluate(&z)?;
    let mut cost = 0.5 * r.norm_squared();
    // λ multiplies the diagonal D of JᵀJ (Marquardt's scaling): it is dimensionless.
    let mut lambda = 1e-3;
    let mut nu = 2.0;
    let mut stop = StopReason::MaxIterations;
    let mut iterations = 0;
    while iterations < opts.max_iterations {
        let jtj = j.transpose() * &j;
        let g = j.transpose() * &r;
        let diag = jtj.diagonal().map(|d| d.max(1e-30));
        if projected_gradient(&z, &g, &diag, lower, upper) <= opts.gtol * (1.0 + cost.sqrt()) {
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
        let mut trial: Vec<f64> = z.iter().zip(delta.iter()).map(|(a, d)| a + d).collect();
        project(&mut trial);
        let step = DVector::from_iterator(z.len(), trial.iter().zip(&z).map(|(a, b)| a - b));
        let z_norm = DVector::from_column_slice(&z).norm();
        if step.norm() <= opts.xtol * (z_norm + opts.xtol) {
            stop = StopReason::Step;
            break;
        }
        let predicted = -(step.dot(&g)) - 0.5 * step.dot(&(&jtj * &step));
        let accepted = match problem.evaluate(&trial) {
            Ok((r_new, j_new)) if r_new.iter().all(|v| v.is_finite()) => {
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
                if reduction <= opts.ftol * cost {
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
    Ok(Minimum {
        z,
        residuals: r,
        jacobian: j,
        iterations,
        stop,
    })
}

/// The largest gradient component in Marquardt's scaling (`g_k / √D_k`), leaving out components that point out
/// of the box at an active bound.
fn projected_gradient(
    z: &[f64],
    g: &DVector<f64>,
    diag: &DVector<f64>,
    lower: &[f64],
    upper: &[f64],
) -> f64 {
    let mut worst: f64 = 0.0;
    for k in 0..z.len() {
        if !blocked(z[k], g[k], lower[k], upper[k]) {
            worst = worst.max(g[k].abs() / diag[k].sqrt());
        }
    }
    worst
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
    let svd = nalgebra::SVD::try_new(scaled, true, true, f64::EPSILON, 1000)?;
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
        assert!(m.stop.converged());
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
}
