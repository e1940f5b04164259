//! The symbolic linear solver on 2×2 and 3×3 systems, checked by substituting numbers.

use super::super::{Expr, MAX_SOLVE_SIZE, Symbol, SymbolicError, solve_linear};
use super::{Rng, c, p};
use std::collections::BTreeMap;

fn eval_at(e: &Expr, env: &BTreeMap<Symbol, f64>) -> f64 {
    e.eval_map(env).unwrap_or(f64::NAN)
}

#[test]
fn general_2x2_matches_cramers_rule() {
    let (a, b, cc, d, e, f) = (p("a"), p("b"), p("c"), p("d"), p("e"), p("f"));
    let sol = solve_linear(
        &[vec![a.clone(), b.clone()], vec![cc.clone(), d.clone()]],
        &[e.clone(), f.clone()],
    );
    let sol = sol.map_err(|e| e.to_string());
    let Ok(sol) = sol else {
        panic!("2x2 solve failed: {sol:?}");
    };
    let det = &a * &d - &b * &cc;
    let cramer = [(&e * &d - &b * &f) / &det, (&a * &f - &e * &cc) / &det];
    let mut rng = Rng(5);
    for _ in 0..20 {
        let env: BTreeMap<Symbol, f64> = ["a", "b", "c", "d", "e", "f"]
            .iter()
            .map(|n| (Symbol::param(*n), rng.uniform(-2.0, 2.0)))
            .collect();
        for (x, want) in sol.x.iter().zip(&cramer) {
            let (got, want) = (eval_at(x, &env), eval_at(want, &env));
            assert!(
                (got - want).abs() <= 1e-9 * want.abs().max(1.0),
                "{got} vs {want}"
            );
        }
    }
}

#[test]
fn structurally_zero_pivot_swaps_rows() {
    // [[0, b], [c, d]] x = [5, 6] with b = 2, c = 3, d = 4: numpy.linalg.solve gives [-1.33333333, 2.5].
    let (b, cc, d) = (p("b"), p("c"), p("d"));
    let sol = solve_linear(
        &[vec![c(0.0), b.clone()], vec![cc.clone(), d.clone()]],
        &[c(5.0), c(6.0)],
    );
    let Ok(sol) = sol else {
        panic!("solve failed: {sol:?}");
    };
    assert_eq!(sol.pivots.first(), Some(&cc));
    let env: BTreeMap<Symbol, f64> = [("b", 2.0), ("c", 3.0), ("d", 4.0)]
        .into_iter()
        .map(|(n, v)| (Symbol::param(n), v))
        .collect();
    let got: Vec<f64> = sol.x.iter().map(|x| eval_at(x, &env)).collect();
    assert!(
        (got[0] + 4.0 / 3.0).abs() < 1e-12 && (got[1] - 2.5).abs() < 1e-12,
        "{got:?}"
    );
}

#[test]
fn spring_chain_3x3() {
    // Three springs in a chain, forces F1 on node 1 and F2 on node 3:
    //   import numpy as np
    //   A = np.array([[1+2, -2, 0], [-2, 2+3, -3], [0, -3, 3.]]); b = np.array([1, 0, 2.])
    //   np.linalg.solve(A, b)  # array([3., 4., 4.66666667])
    let (k1, k2, k3, f1, f2) = (p("k1"), p("k2"), p("k3"), p("F1"), p("F2"));
    let a = vec![
        vec![&k1 + &k2, -&k2, c(0.0)],
        vec![-&k2, &k2 + &k3, -&k3],
        vec![c(0.0), -&k3, k3.clone()],
    ];
    let rhs = vec![f1.clone(), c(0.0), f2.clone()];
    let sol = solve_linear(&a, &rhs);
    let Ok(sol) = sol else {
        panic!("3x3 solve failed: {sol:?}");
    };
    let env: BTreeMap<Symbol, f64> = [
        ("k1", 1.0),
        ("k2", 2.0),
        ("k3", 3.0),
        ("F1", 1.0),
        ("F2", 2.0),
    ]
    .into_iter()
    .map(|(n, v)| (Symbol::param(n), v))
    .collect();
    let got: Vec<f64> = sol.x.iter().map(|x| eval_at(x, &env)).collect();
    for (g, w) in got.iter().zip([3.0, 4.0, 14.0 / 3.0]) {
        assert!((g - w).abs() < 1e-12, "{got:?}");
    }
    // And the residual A x - b vanishes at random parameter values.
    let mut rng = Rng(9);
    for _ in 0..20 {
        let env: BTreeMap<Symbol, f64> = ["k1", "k2", "k3", "F1", "F2"]
            .iter()
            .map(|n| (Symbol::param(*n), rng.uniform(0.5, 3.0)))
            .collect();
        let x: Vec<f64> = sol.x.iter().map(|x| eval_at(x, &env)).collect();
        for (row, b) in a.iter().zip(&rhs) {
            let lhs: f64 = row
                .iter()
                .zip(&x)
                .map(|(aij, xj)| eval_at(aij, &env) * xj)
                .sum();
            let b = eval_at(b, &env);
            assert!(
                (lhs - b).abs() < 1e-9 * b.abs().max(1.0),
                "residual {}",
                lhs - b
            );
        }
    }
}

#[test]
fn singular_and_oversized_systems_are_refused() {
    let k = p("k");
    // Second column structurally zero once the first is eliminated: [[k, k], [2k, 2k]].
    let singular = solve_linear(
        &[vec![k.clone(), k.clone()], vec![2.0 * &k, 2.0 * &k]],
        &[c(1.0), c(2.0)],
    );
    assert_eq!(singular, Err(SymbolicError::Singular { column: 1 }));
    let n = MAX_SOLVE_SIZE + 1;
    let big = solve_linear(&vec![vec![c(1.0); n]; n], &vec![c(0.0); n]);
    assert_eq!(
        big,
        Err(SymbolicError::SystemTooLarge {
            n,
            max: MAX_SOLVE_SIZE
        })
    );
    let ragged = solve_linear(&[vec![c(1.0)], vec![c(1.0), c(2.0)]], &[c(0.0), c(0.0)]);
    assert_eq!(
        ragged,
        Err(SymbolicError::ShapeMismatch {
            row: 0,
            found: 1,
            expected: 2
        })
    );
}

#[test]
fn general_4x4_leaves_no_residual() {
    // The largest accepted system, fully symbolic: check A x = b at random values of its 20 symbols.
    let a: Vec<Vec<Expr>> = (0..4)
        .map(|i| (0..4).map(|j| p(&format!("a{i}{j}"))).collect())
        .collect();
    let b: Vec<Expr> = (0..4).map(|i| p(&format!("b{i}"))).collect();
    let sol = solve_linear(&a, &b);
    let Ok(sol) = sol else {
        panic!("4x4 solve failed: {sol:?}");
    };
    let mut rng = Rng(17);
    for _ in 0..20 {
        let mut env: BTreeMap<Symbol, f64> = BTreeMap::new();
        for i in 0..4 {
            for j in 0..4 {
                // Diagonally dominant, so the system is well conditioned.
                let v = rng.uniform(-1.0, 1.0) + if i == j { 5.0 } else { 0.0 };
                env.insert(Symbol::param(format!("a{i}{j}")), v);
            }
            env.insert(Symbol::param(format!("b{i}")), rng.uniform(-1.0, 1.0));
        }
        let x: Vec<f64> = sol.x.iter().map(|x| eval_at(x, &env)).collect();
        for (row, rhs) in a.iter().zip(&b) {
            let lhs: f64 = row
                .iter()
                .zip(&x)
                .map(|(aij, xj)| eval_at(aij, &env) * xj)
                .sum();
            let rhs = eval_at(rhs, &env);
            assert!((lhs - rhs).abs() < 1e-12, "residual {}", lhs - rhs);
        }
    }
}
