//! The statistics of a least-squares estimate: standard errors and correlations from the Jacobian at the optimum
//! and the residual variance, and the parameter combinations the data cannot determine.
//!
//! With `m` weighted residuals, `n` fitted quantities and the relative Jacobian `J_k = ∂r/∂θ_k · c_k` (each
//! column scaled by the quantity's size `c_k`, so a column measures the effect of a *relative* change), the
//! residual variance is `s² = ‖r‖²/(m − n)` and the covariance of the relative estimates is `s² (JᵀJ)⁻¹`. From the
//! singular value decomposition `J = U Σ Vᵀ`, the combination `vᵢᵀ ln θ` (the product `Π θ_k^{v_ik}`) has the
//! standard error `s/σᵢ`: a direction whose relative standard error exceeds [`UNDETERMINED`] (or whose singular
//! value is at rounding level) is one the record does not determine.

use nalgebra::DMatrix;

/// The relative standard error above which a combination counts as not determined by the data: it could be
/// twice or half its value and fit the record as well.
pub const UNDETERMINED: f64 = 1.0;

/// A parameter combination the data cannot determine: `Π θ_k^{exponent}` over `(k, exponent)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Direction {
    /// Indices into the fitted quantities with their exponents (the right singular vector, normalised to a
    /// largest entry of 1, entries below 0.05 left out).
    pub combination: Vec<(usize, f64)>,
    /// The standard error of `ln Π θ_k^{exponent}` (infinite when the record does not depend on it at all).
    pub relative_std_error: f64,
}

/// Standard errors and correlations.
#[derive(Clone, Debug, PartialEq)]
pub struct Statistics {
    /// `s²`, the weighted residual sum of squares over the degrees of freedom.
    pub residual_variance: f64,
    pub degrees_of_freedom: usize,
    /// Per fitted quantity, in its own unit (relative standard error times `c_k`).
    pub std_errors: Vec<f64>,
    pub correlation: DMatrix<f64>,
    /// The combinations the data do not determine (empty when all are determined).
    pub undetermined: Vec<Direction>,
}

/// The statistics at an optimum from the residuals' sum of squares, the relative Jacobian and the scales `c_k`
/// (one per column); an error when these do not match or are not finite.
pub fn statistics(ssr: f64, jac_rel: &DMatrix<f64>, scales: &[f64]) -> Result<Statistics, String> {
    let (m, n) = jac_rel.shape();
    if scales.len() != n {
        return Err(format!("{n} Jacobian columns but {} scales", scales.len()));
    }
    let finite = |v: &f64| v.is_finite();
    if !(ssr.is_finite() && jac_rel.iter().all(finite) && scales.iter().all(finite)) {
        return Err("the residuals, the Jacobian or the scales are not finite".into());
    }
    let dof = m.saturating_sub(n);
    let s2 = if dof > 0 { ssr / dof as f64 } else { f64::NAN };
    let s = s2.sqrt();
    if n == 0 || m == 0 {
        return Ok(Statistics {
            residual_variance: s2,
            degrees_of_freedom: dof,
            std_errors: Vec::new(),
            correlation: DMatrix::zeros(n, n),
            undetermined: Vec::new(),
        });
    }
    let svd = crate::linalg::check::svd(jac_rel.clone(), false, true, 10_000)
        .ok_or("the singular value decomposition of the Jacobian did not converge")?;
    let sigma = &svd.singular_values;
    let sigma_max = sigma.max();
    let negligible = sigma_max * (m.max(n) as f64) * f64::EPSILON;
    let mut cov = DMatrix::<f64>::zeros(n, n);
    let mut undetermined = Vec::new();
    let mut unbounded = vec![false; n];
    if let Some(v_t) = &svd.v_t {
        for (i, &sig) in sigma.iter().enumerate() {
            let v = v_t.row(i).transpose();
            let rel = if sig > negligible {
                s / sig
            } else {
                f64::INFINITY
            };
            if rel > UNDETERMINED || !rel.is_finite() {
                undetermined.push(direction(v.as_slice(), rel));
            }
            if sig > negligible {
                cov += &v * v.transpose() * (s2 / (sig * sig));
            } else {
                for (k, x) in v.iter().enumerate() {
                    unbounded[k] |= x.abs() > 1e-8;
                }
            }
        }
    }
    let rel_se: Vec<f64> = (0..n)
        .map(|k| {
            if unbounded[k] {
                f64::INFINITY
            } else {
                cov[(k, k)].abs().sqrt()
            }
        })
        .collect();
    let correlation = DMatrix::from_fn(n, n, |a, b| {
        if a == b {
            1.0
        } else if unbounded[a] || unbounded[b] {
            f64::NAN
        } else {
            cov[(a, b)] / (rel_se[a] * rel_se[b])
        }
    });
    Ok(Statistics {
        residual_variance: s2,
        degrees_of_freedom: dof,
        std_errors: rel_se
            .iter()
            .zip(scales)
            .map(|(r, c)| r * c.abs())
            .collect(),
        correlation,
        undetermined,
    })
}

fn direction(v: &[f64], rel: f64) -> Direction {
    let big = v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    // The sign of a singular vector is arbitrary: make the largest entry positive.
    let sign = v
        .iter()
        .find(|x| x.abs() == big)
        .map_or(1.0, |x| x.signum());
    let mut combination: Vec<(usize, f64)> = v
        .iter()
        .enumerate()
        .map(|(k, x)| (k, sign * x / big))
        .filter(|(_, e)| e.abs() >= 0.05)
        .collect();
    combination.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
    Direction {
        combination,
        relative_std_error: rel,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn straight_line_standard_errors_match_the_textbook_formula() {
        // y = a + b x at x = 0..4 with residuals r: se(b) = s / √Σ(x − x̄)², se(a) = s √(1/n + x̄²/Σ(x − x̄)²).
        let x = [0.0, 1.0, 2.0, 3.0, 4.0];
        let j = DMatrix::from_fn(5, 2, |i, k| if k == 0 { 1.0 } else { x[i] });
        let ssr = 0.3;
        let st = statistics(ssr, &j, &[1.0, 1.0]).unwrap();
        let s = (ssr / 3.0f64).sqrt();
        let sxx: f64 = 10.0;
        assert!((st.std_errors[1] - s / sxx.sqrt()).abs() < 1e-12);
        assert!((st.std_errors[0] - s * (0.2 + 4.0 / sxx).sqrt()).abs() < 1e-12);
        // corr(a, b) = −x̄ / √(x̄² + Sxx/n) = −2/√6.
        assert!((st.correlation[(0, 1)] + 2.0 / 6.0f64.sqrt()).abs() < 1e-12);
        assert!(st.undetermined.is_empty());
    }

    #[test]
    fn a_non_finite_jacobian_or_mismatched_scales_are_errors() {
        // A NaN entry made the singular value decomposition panic; scales shorter than the columns gave a
        // shorter list of standard errors.
        let mut j = DMatrix::from_element(3, 2, 1.0);
        assert!(statistics(1.0, &j, &[1.0]).is_err());
        assert!(statistics(f64::NAN, &j, &[1.0, 1.0]).is_err());
        j[(1, 1)] = f64::NAN;
        assert!(statistics(1.0, &j, &[1.0, 1.0]).is_err());
    }

    #[test]
    fn a_product_that_only_enters_together_is_named() {
        // Two columns equal: only θ₀θ₁ is determined, θ₀/θ₁ is not.
        let j = DMatrix::from_fn(6, 2, |i, _| (i as f64).sin());
        let st = statistics(0.01, &j, &[1.0, 1.0]).unwrap();
        assert_eq!(st.undetermined.len(), 1);
        let c = &st.undetermined[0].combination;
        assert_eq!(c.len(), 2);
        assert!(
            (c[0].1 - 1.0).abs() < 1e-12 && (c[1].1 + 1.0).abs() < 1e-12,
            "{c:?}"
        );
    }
}
