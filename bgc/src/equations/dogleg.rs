//! Powell's dogleg trust-region method for `r(z) = 0`: the fallback of [`super::newton::solve`] for a system of
//! several equations whose damped Newton iteration fails.
//!
//! A line search along the Newton direction can creep along a curved valley of `‖r‖²` for hundreds of steps (a
//! cubic law inside another, as a torn loop of cubic resistors gives, makes the residual of degree 9 in the tears).
//! The dogleg step bends from the steepest-descent (Cauchy) step towards the Newton step inside a radius that
//! follows how well the linear model predicted the last step, so it turns with the valley. Each residual is divided
//! by its scale at the start (the same weights throughout, so `‖r/w‖²` is one merit function), and convergence is
//! the damped method's test on the residual and the Newton step ([`super::newton::StepTest`]).

use super::newton::{Problem, Settings, StepTest, lu_solve, step_ratio, within};

/// Steps tried before giving up: the trust region also needs steps to grow and shrink.
const STEP_FACTOR: usize = 4;

/// Solves from the start in `z`, in place; the number of residual evaluations, or `None` when it does not
/// converge (then `z` is left as it was given).
pub(super) fn solve(problem: &mut dyn Problem, z: &mut [f64], settings: Settings) -> Option<usize> {
    let n = problem.size().min(z.len());
    let mut x = z[..n].to_vec();
    let (mut r, mut s) = (vec![0.0; n], vec![0.0; n]);
    let (mut r_try, mut s_try) = (vec![0.0; n], vec![0.0; n]);
    let mut jac = vec![0.0; n * n];
    problem.residual(&x, &mut r, &mut s);
    let w: Vec<f64> = s
        .iter()
        .map(|s| if s.is_finite() && *s > 0.0 { *s } else { 1.0 })
        .collect();
    let merit =
        |r: &[f64]| -> f64 { r.iter().zip(&w).map(|(r, w)| (r / w).powi(2)).sum::<f64>() / 2.0 };
    let mut radius = x.iter().map(|v| v * v).sum::<f64>().sqrt().max(1.0);
    let (mut floor, mut moved) = (StepTest::default(), false);
    for k in 1..=settings.max_iterations * STEP_FACTOR {
        if r.iter().chain(&s).any(|v| !v.is_finite()) {
            return None;
        }
        problem.jacobian(&x, &mut jac);
        if jac.iter().any(|v| !v.is_finite()) {
            return None;
        }
        // Converged after a step: the residual and the Newton step from here within their tolerances.
        let mut ratio = None;
        if moved && within(&r, &s, settings.rtol) {
            let mut newton: Vec<f64> = r.iter().map(|v| -v).collect();
            if !lu_solve(&jac, &mut newton, n) {
                // A root where ∂r/∂z is singular: the step cannot be judged.
                z[..n].copy_from_slice(&x);
                return Some(k);
            }
            let q = step_ratio(&x, &newton);
            if floor.accepts(q) {
                z[..n].copy_from_slice(&x);
                return Some(k);
            }
            // The full Newton step, as in the damped method: the residual no longer measures the distance to
            // the root here.
            let trial: Vec<f64> = x.iter().zip(&newton).map(|(x, p)| x + p).collect();
            problem.residual(&trial, &mut r_try, &mut s_try);
            if r_try.iter().chain(&s_try).all(|v| v.is_finite()) {
                x = trial;
                std::mem::swap(&mut r, &mut r_try);
                std::mem::swap(&mut s, &mut s_try);
                floor.took(Some(q), true);
                continue;
            }
            ratio = Some(q);
        }
        // The weighted system: rows of r and J divided by w.
        let rw: Vec<f64> = r.iter().zip(&w).map(|(r, w)| r / w).collect();
        let jw: Vec<f64> = (0..n * n).map(|k| jac[k] / w[k / n]).collect();
        let (step, full) = dogleg_step(&jw, &rw, n, radius)?;
        let predicted = merit(&r) - linear_merit(&jw, &rw, &step, n);
        let trial: Vec<f64> = x.iter().zip(&step).map(|(x, p)| x + p).collect();
        problem.residual(&trial, &mut r_try, &mut s_try);
        let actual = merit(&r) - merit(&r_try);
        let ratio_of_reduction = if predicted > 0.0 {
            actual / predicted
        } else {
            -1.0
        };
        let length = step.iter().map(|v| v * v).sum::<f64>().sqrt();
        if ratio_of_reduction.is_finite() && ratio_of_reduction > 1e-4 {
            x = trial;
            std::mem::swap(&mut r, &mut r_try);
            std::mem::swap(&mut s, &mut s_try);
            floor.took(ratio, full);
            moved = true;
        }
        radius = match ratio_of_reduction {
            q if !q.is_finite() || q < 0.25 => length / 4.0,
            q if q > 0.75 && length >= 0.99 * radius => 2.0 * radius,
            _ => radius,
        };
        let size = x.iter().map(|v| v.abs()).fold(1.0f64, f64::max);
        if radius <= 1e-15 * size {
            return None;
        }
    }
    None
}

/// `½‖r + J p‖²`: the merit the linear model predicts after the step `p`.
fn linear_merit(j: &[f64], r: &[f64], p: &[f64], n: usize) -> f64 {
    (0..n)
        .map(|i| {
            let v = r[i] + (0..n).map(|c| j[i * n + c] * p[c]).sum::<f64>();
            v * v
        })
        .sum::<f64>()
        / 2.0
}

/// The dogleg step within `radius` for the model `r + J p` (J row-major `n × n`), and whether it is the full Newton
/// step; `None` when the gradient is zero and no Newton step exists.
fn dogleg_step(j: &[f64], r: &[f64], n: usize, radius: f64) -> Option<(Vec<f64>, bool)> {
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut newton: Vec<f64> = r.iter().map(|v| -v).collect();
    let has_newton = lu_solve(j, &mut newton, n);
    if has_newton && norm(&newton) <= radius {
        return Some((newton, true));
    }
    // The gradient of ½‖r + J p‖² at p = 0, and the minimiser of the model along it.
    let g: Vec<f64> = (0..n)
        .map(|c| (0..n).map(|i| j[i * n + c] * r[i]).sum())
        .collect();
    let jg: Vec<f64> = (0..n)
        .map(|i| (0..n).map(|c| j[i * n + c] * g[c]).sum())
        .collect();
    let (gg, jgjg) = (
        g.iter().map(|v| v * v).sum::<f64>(),
        jg.iter().map(|v| v * v).sum::<f64>(),
    );
    if gg == 0.0 || jgjg == 0.0 {
        return None;
    }
    let cauchy: Vec<f64> = g.iter().map(|v| -v * gg / jgjg).collect();
    let cauchy_length = norm(&cauchy);
    if !has_newton || cauchy_length >= radius {
        let scale = radius / gg.sqrt();
        return Some((g.iter().map(|v| -v * scale).collect(), false));
    }
    // From the Cauchy point towards the Newton point, to the boundary: ‖c + τ (N − c)‖ = radius.
    let d: Vec<f64> = newton.iter().zip(&cauchy).map(|(a, b)| a - b).collect();
    let (dd, cd) = (
        d.iter().map(|v| v * v).sum::<f64>(),
        cauchy.iter().zip(&d).map(|(a, b)| a * b).sum::<f64>(),
    );
    let cc = cauchy_length * cauchy_length;
    let tau = (-cd + (cd * cd + dd * (radius * radius - cc)).max(0.0).sqrt()) / dd;
    Some((
        cauchy.iter().zip(&d).map(|(c, d)| c + tau * d).collect(),
        false,
    ))
}

#[cfg(test)]
mod tests {
    use super::super::newton::{self, Problem, Settings};

    /// Two tears of a loop of cubic resistors through modulated transformers, as bgc tears it (the property test's
    /// graph of seed 8169226994125556156 at one of its points): `z = (e, f)`,
    /// `r_0 = L A − e`, `r_1 = x/v0 + k0 x³ − f` with `A = (v3 + v4) s / n3²`,
    /// `s = n2 f − L (n1 f (1 + 0.3 cos q) + e/v1 + k1 e³ − u1) + u0` and `x = n1 e (1 + 0.3 cos q) − n2 A − q/v2`.
    struct CubicLoop;

    const N1: f64 = 1.395;
    const N2: f64 = 1.2925;
    const N3: f64 = 0.7;
    const V0: f64 = 1.725;
    const K0: f64 = 0.2295;
    const V1: f64 = 2.02;
    const K1: f64 = 0.254;
    const V2: f64 = 1.23;
    const V3: f64 = 1.6825;
    const V4: f64 = 2.24;
    const L0: f64 = 2.2975;
    const Q: f64 = 0.212_918_961_358_036_67;
    const W: f64 = -0.528_186_186_553_325;
    const U0: f64 = 0.133_117_265_241_498_25;
    const U1: f64 = 0.939_340_055_410_681_9;

    impl CubicLoop {
        /// The residuals, their scales (the magnitudes of the outer terms) and the Jacobian.
        fn at(z: &[f64]) -> ([f64; 2], [f64; 2], [f64; 4]) {
            let (e, f) = (z[0], z[1]);
            let l = L0 * (0.3 * W.cos() + 1.0);
            let m = 1.0 + 0.3 * Q.cos();
            let s = N2 * f - l * (N1 * f * m + e / V1 + K1 * e.powi(3) - U1) + U0;
            let a = (V3 + V4) * s / (N3 * N3);
            let x = N1 * e * m - N2 * a - Q / V2;
            let r = [l * a - e, x / V0 + K0 * x.powi(3) - f];
            let scale = [
                (l * a).abs() + e.abs(),
                (x / V0).abs() + (K0 * x.powi(3)).abs() + f.abs(),
            ];
            let (ds_de, ds_df) = (-l * (1.0 / V1 + 3.0 * K1 * e * e), N2 - l * N1 * m);
            let c = (V3 + V4) / (N3 * N3);
            let (dx_de, dx_df) = (N1 * m - N2 * c * ds_de, -N2 * c * ds_df);
            let g = 1.0 / V0 + 3.0 * K0 * x * x;
            (
                r,
                scale,
                [
                    l * c * ds_de - 1.0,
                    l * c * ds_df,
                    g * dx_de,
                    g * dx_df - 1.0,
                ],
            )
        }
    }

    impl Problem for CubicLoop {
        fn size(&self) -> usize {
            2
        }
        fn residual(&mut self, z: &[f64], r: &mut [f64], s: &mut [f64]) {
            let (rr, ss, _) = CubicLoop::at(z);
            r.copy_from_slice(&rr);
            s.copy_from_slice(&ss);
        }
        fn jacobian(&mut self, z: &[f64], j: &mut [f64]) {
            j.copy_from_slice(&CubicLoop::at(z).2);
        }
    }

    #[test]
    fn a_loop_where_the_line_search_creeps_is_solved_by_the_dogleg_from_the_same_start() {
        // The root: scipy.optimize.root(r, [0, 0], method="hybr") = [0.61577178, 0.45092652] (53 evaluations);
        // the damped Newton method alone still has |r| ≈ 6,000 after its 100 iterations.
        let settings = Settings::default();
        let mut z = [0.0, 0.0];
        assert!(super::solve(&mut CubicLoop, &mut z.clone(), settings).is_some());
        let solved = newton::solve(&mut CubicLoop, &mut z, settings);
        assert!(solved.is_ok(), "{solved:?}");
        assert!(
            (z[0] - 0.615_771_78).abs() < 1e-8 && (z[1] - 0.450_926_52).abs() < 1e-8,
            "{z:?}"
        );
        let (r, s, _) = CubicLoop::at(&z);
        assert!(
            r[0].abs() <= 1e-12 * s[0] && r[1].abs() <= 1e-12 * s[1],
            "{r:?}"
        );
    }

    #[test]
    fn without_the_dogleg_the_same_loop_is_not_solved() {
        // The reason for the fallback: the damped iteration alone fails here, as the generated one does
        // (`bgc/tests/loops_globalised.rs`).
        let mut z = [0.0, 0.0];
        let (mut r, mut s) = ([0.0; 2], [0.0; 2]);
        let damped = newton::damped_for_tests(&mut CubicLoop, &mut z, Settings::default());
        assert!(damped.is_err(), "{damped:?}");
        CubicLoop.residual(&z, &mut r, &mut s);
        assert!(r[1].abs() > 1.0, "{z:?} {r:?}");
    }
}
