//! Lagrange's equations for an inertia matrix given as a function of the configuration, the independent
//! reference of the differential tests for multiport inertias and for mechanisms of modulated transformers.

use super::{Cx, central_difference, richardson, solve};

/// `M ḟ = e - c(q, f)` solved for `ḟ`: `mass(q)` evaluates the inertia matrix (row-major) at displacements `q`,
/// `e` are the port efforts and `v` the port flows.
pub fn accelerations(
    mass: &dyn Fn(&[f64]) -> Option<Vec<f64>>,
    q: &[f64],
    v: &[f64],
    e: &[f64],
) -> Option<Vec<f64>> {
    let n = q.len();
    let at = |l: usize, h: f64| {
        let mut shifted = q.to_vec();
        shifted[l] += h;
        mass(&shifted)
    };
    let central = |l: usize, h: f64| Some(central_difference(&at(l, h)?, &at(l, -h)?, h));
    // `dm[l][i * n + j]` = ∂M_ij/∂q_l, Richardson-extrapolated (error of order h⁴).
    let dm: Vec<Vec<f64>> = (0..n)
        .map(|l| Some(richardson(&central(l, 1e-3)?, &central(l, 5e-4)?)))
        .collect::<Option<_>>()?;
    let rhs: Vec<f64> = (0..n)
        .map(|k| {
            let changing: f64 = (0..n)
                .flat_map(|l| (0..n).map(move |j| (l, j)))
                .map(|(l, j)| dm[l][k * n + j] * v[l] * v[j])
                .sum();
            e[k] - changing + 0.5 * quadratic_form(&dm[k], v)
        })
        .collect();
    solve_dense(&mass(q)?, rhs)
}

/// `v' M v` for the `n × n` matrix `m` (row-major), `n` the length of `v`.
pub fn quadratic_form(m: &[f64], v: &[f64]) -> f64 {
    let n = v.len();
    let pairs = (0..n).flat_map(|i| (0..n).map(move |j| (i, j)));
    pairs.map(|(i, j)| m[i * n + j] * v[i] * v[j]).sum()
}

/// `M x = b` for the `n × n` matrix `m` (row-major), `n` the length of `b`; `None` when `M` is singular.
pub fn solve_dense(m: &[f64], b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    let rows = (0..n)
        .map(|i| (0..n).map(|j| Cx::re(m[i * n + j])).collect())
        .collect();
    let x = solve(rows, b.into_iter().map(Cx::re).collect())?;
    Some(x.iter().map(|a| a.0).collect())
}
