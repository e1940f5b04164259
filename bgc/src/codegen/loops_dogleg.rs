//! Powell's dogleg method in generated code: the fallback of the generated `bgc_newton` for a block of several
//! tears whose damped Newton iteration fails, as [`crate::equations::newton::solve`] falls back on it in the
//! compiler's own evaluation (`bgc simulate`, `bgc statespace --at`).
//!
//! A line search along the Newton direction can creep along a curved valley of `‖r‖²` (a torn loop of cubic
//! resistors makes the residual of degree 9 in the tears); the dogleg step bends from the steepest-descent step
//! towards the Newton step inside a trust radius that follows how well the linear model predicted the last step.
//! The residuals are weighted by their scales at the start, and convergence is the damped method's test on
//! the residual, `|r_i| ≤ LOOP_RTOL · s_i`, and on the Newton step (`bgc_step_ratio`). Fixed-size values
//! only: no allocation, `core`, `nalgebra` and `libm`.

/// Emitted into the module after [`super::loops::NEWTON_FN`]; needs `bgc_solve` ([`super::mass::SOLVE_FN`]).
pub(crate) const DOGLEG_FN: &str = "
/// `a · b` of two vectors of `B` entries.
fn bgc_dot<const B: usize>(a: &SVector<f64, B>, b: &SVector<f64, B>) -> f64 {
    let mut sum = 0.0;
    for i in 0..B {
        sum += a[i] * b[i];
    }
    sum
}

/// Powell's dogleg trust-region method for the block of `B` tears starting at `first`, from the
/// values in `start`: the tears solved, or `None` when it does not converge.
fn bgc_dogleg<const B: usize>(
    start: &Tears,
    first: usize,
    eval: &impl Fn(&Tears) -> LoopEval<B>,
) -> Option<Tears> {
    let mut z = *start;
    let (mut r, mut s, mut jz) = eval(&z);
    let mut w = SVector::<f64, B>::zeros();
    for i in 0..B {
        w[i] = if s[i].is_finite() && s[i] > 0.0 {
            s[i]
        } else {
            1.0
        };
    }
    let merit = |r: &SVector<f64, B>| {
        let mut m = 0.0;
        for i in 0..B {
            m += (r[i] / w[i]) * (r[i] / w[i]);
        }
        m / 2.0
    };
    let mut radius = 0.0;
    for i in 0..B {
        radius += z[first + i] * z[first + i];
    }
    radius = libm::sqrt(radius).max(1.0);
    // The step ratio of the last step if it was a full Newton step from an iterate that passed the
    // residual test, and whether a step was taken.
    let (mut previous, mut moved) = (f64::INFINITY, false);
    for _ in 0..4 * LOOP_MAX_ITERATIONS {
        // The weighted system: the rows of r and its Jacobian divided by w.
        let mut jw = SMatrix::<f64, B, B>::zeros();
        let mut rw = SVector::<f64, B>::zeros();
        let mut converged = moved;
        let mut minus_r = SVector::<f64, B>::zeros();
        for i in 0..B {
            if !r[i].is_finite() || !s[i].is_finite() {
                return None;
            }
            converged &= libm::fabs(r[i]) <= LOOP_RTOL * s[i];
            rw[i] = r[i] / w[i];
            minus_r[i] = -r[i];
            for j in 0..B {
                if !jz[(i, j)].is_finite() {
                    return None;
                }
                jw[(i, j)] = jz[(i, j)] / w[i];
            }
        }
        // Converged after a step: the residual and the Newton step from here within their
        // tolerances, or the step no longer contracting.
        let mut ratio = f64::INFINITY;
        if converged {
            let newton = bgc_solve(jz, minus_r);
            ratio = bgc_step_ratio(&z, first, &newton);
            if ratio <= 1.0 || ratio >= 0.5 * previous {
                return Some(z);
            }
            // The full Newton step, as in the damped method.
            let mut trial = z;
            for i in 0..B {
                trial[first + i] = z[first + i] + newton[i];
            }
            let at = eval(&trial);
            let mut finite = true;
            for i in 0..B {
                finite &= at.0[i].is_finite() && at.1[i].is_finite();
            }
            if finite {
                z = trial;
                (r, s, jz) = at;
                previous = ratio;
                continue;
            }
        }
        let (step, full) = bgc_dogleg_step(&jw, &rw, radius)?;
        let mut predicted = merit(&r);
        let mut trial = z;
        for i in 0..B {
            let mut model = rw[i];
            for j in 0..B {
                model += jw[(i, j)] * step[j];
            }
            predicted -= model * model / 2.0;
            trial[first + i] = z[first + i] + step[i];
        }
        let at = eval(&trial);
        let actual = merit(&r) - merit(&at.0);
        let reduction = if predicted > 0.0 {
            actual / predicted
        } else {
            -1.0
        };
        let length = libm::sqrt(bgc_dot(&step, &step));
        if reduction.is_finite() && reduction > 1e-4 {
            z = trial;
            (r, s, jz) = at;
            previous = if full { ratio } else { f64::INFINITY };
            moved = true;
        }
        if !reduction.is_finite() || reduction < 0.25 {
            radius = length / 4.0;
        } else if reduction > 0.75 && length >= 0.99 * radius {
            radius *= 2.0;
        }
        let mut size = 1.0f64;
        for i in 0..B {
            size = size.max(libm::fabs(z[first + i]));
        }
        if radius <= 1e-15 * size {
            return None;
        }
    }
    None
}

/// The dogleg step within `radius` for the model `r + J p`, and whether it is the full Newton step;
/// `None` when the gradient is zero and no Newton step exists.
fn bgc_dogleg_step<const B: usize>(
    j: &SMatrix<f64, B, B>,
    r: &SVector<f64, B>,
    radius: f64,
) -> Option<(SVector<f64, B>, bool)> {
    let mut minus_r = SVector::<f64, B>::zeros();
    for i in 0..B {
        minus_r[i] = -r[i];
    }
    let newton = bgc_solve(*j, minus_r);
    let mut has_newton = true;
    for i in 0..B {
        has_newton &= newton[i].is_finite();
    }
    if has_newton && libm::sqrt(bgc_dot(&newton, &newton)) <= radius {
        return Some((newton, true));
    }
    // The gradient g = Jᵀ r of the model's merit at p = 0, and J g.
    let mut g = SVector::<f64, B>::zeros();
    let mut jg = SVector::<f64, B>::zeros();
    for c in 0..B {
        for i in 0..B {
            g[c] += j[(i, c)] * r[i];
        }
    }
    for i in 0..B {
        for c in 0..B {
            jg[i] += j[(i, c)] * g[c];
        }
    }
    let (gg, jgjg) = (bgc_dot(&g, &g), bgc_dot(&jg, &jg));
    if gg == 0.0 || jgjg == 0.0 {
        return None;
    }
    // The minimiser of the model along -g (the Cauchy point), or the boundary along -g.
    let mut cauchy = SVector::<f64, B>::zeros();
    for i in 0..B {
        cauchy[i] = -g[i] * gg / jgjg;
    }
    let cc = bgc_dot(&cauchy, &cauchy);
    if !has_newton || libm::sqrt(cc) >= radius {
        let scale = radius / libm::sqrt(gg);
        for i in 0..B {
            cauchy[i] = -g[i] * scale;
        }
        return Some((cauchy, false));
    }
    // From the Cauchy point towards the Newton point, to the boundary: |c + tau (N - c)| = radius.
    let mut d = SVector::<f64, B>::zeros();
    for i in 0..B {
        d[i] = newton[i] - cauchy[i];
    }
    let (dd, cd) = (bgc_dot(&d, &d), bgc_dot(&cauchy, &d));
    let tau = (-cd + libm::sqrt((cd * cd + dd * (radius * radius - cc)).max(0.0))) / dd;
    for i in 0..B {
        cauchy[i] += tau * d[i];
    }
    Some((cauchy, false))
}
";
