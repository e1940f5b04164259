//! Sparse Jacobians on the shared engine (`equations::sparse_jacobians`, what `bgc rust` and `bgc statespace` use for
//! large models): outputs defined through earlier outputs stay a small DAG, their derivatives match central
//! differences, and on ordinary models the sparse path agrees with the dense one, errors included.

use bgc::equations::{
    ModelRows, StateSelection, evaluate_at, evaluate_sparse, jacobians, linear_state_space,
    sparse_jacobians, sparse_linear_state_space,
};
use bgc::lower::MemoryLoader;
use bgc::span::SourceMap;
use bgc::symbolic::{Expr, Symbol};

use crate::equations_scaling::equations;
use crate::equations_support::families::{chain_with, output_chain_with};

/// The output chain with `q0 = 2`.
fn output_chain(levels: usize) -> String {
    output_chain_with(levels, 2.0)
}

/// The benchmark chain with masses of 1.5 kg and springs of 3 N/m, driven by a force `u`.
pub fn chain(n: usize) -> String {
    chain_with(n, 1.5, 3.0)
}

/// The outputs of the chain by hand: `y_1 = sin((q/q0)²) + cos(q/q0)`, then `y_i = sin(y²) + cos(y)`.
fn output_values(levels: usize, q: f64, q0: f64) -> Vec<f64> {
    let mut y = vec![(q * q / (q0 * q0)).sin() + (q / q0).cos()];
    while y.len() < levels {
        let p = y[y.len() - 1];
        y.push((p * p).sin() + p.cos());
    }
    y
}

#[test]
fn an_output_chain_of_24_levels_has_small_jacobians_that_match_central_differences() {
    let levels = 24;
    let eqs = equations(&output_chain(levels));
    let rows = ModelRows::new(&eqs);
    let j = sparse_jacobians(&eqs, &rows, StateSelection::All).expect("jacobians");
    let q = eqs
        .states
        .iter()
        .position(|s| s.name == "q_spring")
        .expect("q_spring");
    // Each output reads the spring's displacement only: one entry per row of ∂h/∂x, none in ∂h/∂u.
    assert_eq!(j.dhdx.nnz(), levels);
    assert!(j.dhdx.iter().all(|(_, c, _)| c == q));
    let entries: Vec<Expr> = j.dhdx.iter().map(|(_, _, e)| e.clone()).collect();
    // Stored as a DAG, the 24 derivatives take a few dozen nodes per level; as trees they would double per level.
    let stored = Expr::distinct_nodes(&entries);
    assert!(stored <= 60 * levels, "{stored} nodes");
    assert!(entries.last().is_some_and(|e| e.node_count() > 1 << 20));
    let (q_at, q0) = (0.7, 2.0);
    let value = |e: &Expr, qv: f64| {
        e.eval(|s: &Symbol| match eqs.symbol_name(s).as_str() {
            "q_spring" => Some(qv),
            "q0" => Some(q0),
            "m" | "k" => Some(1.0),
            "p_mass" => Some(0.0),
            _ => None,
        })
        .expect("evaluates")
    };
    let hand = output_values(levels, q_at, q0);
    let step = 1e-6;
    let (up, down) = (
        output_values(levels, q_at + step, q0),
        output_values(levels, q_at - step, q0),
    );
    for (k, e) in entries.iter().enumerate() {
        let h = rows.h[k].as_ref().expect("output derived");
        assert!((value(h, q_at) - hand[k]).abs() < 1e-12, "y{}", k + 1);
        let central = (up[k] - down[k]) / (2.0 * step);
        let exact = value(e, q_at);
        assert!(
            (exact - central).abs() <= 1e-5 * central.abs().max(1.0),
            "∂y{}/∂q: {exact} vs central difference {central}",
            k + 1
        );
    }
}

#[test]
fn the_sparse_state_space_of_a_chain_is_the_dense_one() {
    let eqs = equations(&chain(12));
    let rows = ModelRows::new(&eqs);
    let sparse = sparse_linear_state_space(&eqs, &rows, StateSelection::Energy).expect("linear");
    let dense = linear_state_space(&eqs, StateSelection::Energy).expect("linear");
    let params = eqs.default_params();
    let n = dense.states.len();
    let (x0, u0) = (vec![0.0; n], vec![0.0; eqs.inputs.len()]);
    let expected = evaluate_at(&eqs, &dense, &params, &x0, &u0, 0.0).expect("dense values");
    let got = evaluate_sparse(&eqs, &sparse, &params, &x0, &u0, 0.0)
        .expect("sparse values")
        .to_dense();
    for (m, e) in [
        (&got.a, &expected.a),
        (&got.b, &expected.b),
        (&got.c, &expected.c),
        (&got.d, &expected.d),
    ] {
        assert_eq!(m.len(), e.len());
        for (rg, re) in m.iter().zip(e) {
            for (g, x) in rg.iter().zip(re) {
                assert!((g - x).abs() <= 1e-12 * x.abs().max(1.0), "{g} vs {x}");
            }
        }
    }
    // Each mass row reads its own momentum, the springs on either side, and the force on the first: a band.
    assert!(sparse.dfdx.nnz() <= 3 * n);
    // The wall spring's rate is the first mass's velocity: 1/m.
    let wall = sparse.dfdx.get(0, 1).expect("∂q_wall/∂p_mass1");
    assert!(
        (wall
            .eval(|s: &Symbol| (eqs.symbol_name(s) == "m").then_some(1.5))
            .expect("value")
            - 1.0 / 1.5)
            .abs()
            < 1e-15
    );
}

#[test]
fn sparse_and_dense_paths_refuse_a_nonlinear_model_alike() {
    let eqs = equations(&output_chain(3));
    let rows = ModelRows::new(&eqs);
    let sparse = sparse_linear_state_space(&eqs, &rows, StateSelection::Energy);
    let dense = linear_state_space(&eqs, StateSelection::Energy);
    assert!(sparse.is_err());
    assert_eq!(
        sparse.err().map(|e| e.to_string()),
        dense.err().map(|e| e.to_string())
    );
    // Its Jacobians exist on both paths and agree at a point.
    let dense = jacobians(&eqs, StateSelection::Energy).expect("dense jacobians");
    let sparse = sparse_jacobians(&eqs, &rows, StateSelection::Energy).expect("sparse jacobians");
    let params = eqs.default_params();
    let x0 = vec![0.3, 0.9];
    let expected = evaluate_at(&eqs, &dense, &params, &x0, &[], 0.0).expect("dense values");
    let got = evaluate_sparse(&eqs, &sparse, &params, &x0, &[], 0.0)
        .expect("sparse values")
        .to_dense();
    for (rg, re) in got.c.iter().zip(&expected.c) {
        for (g, x) in rg.iter().zip(re) {
            assert!((g - x).abs() <= 1e-12 * x.abs().max(1.0), "{g} vs {x}");
        }
    }
}

#[test]
fn generated_code_of_a_24_level_output_chain_grows_with_its_dag() {
    let mut sources = SourceMap::new();
    let root = sources.add("outchain.bg".to_string(), output_chain(24));
    let compiled = bgc::codegen::compile(&mut sources, root, &mut MemoryLoader::new())
        .unwrap_or_else(|d| panic!("{d:?}"));
    let code = bgc::codegen::rust::generate_with(
        &compiled,
        "outchain.bg",
        bgc::codegen::rust::Options { runtime: false },
    );
    // Every output reads the one before it from `y`, which it was written to; no name is missing.
    assert!(code.contains("y[23] = libm::sin(bgc_powi(y[22], 2)) + libm::cos(y[22]);"));
    assert!(!code.contains("compile_error!"));
    // The derivatives are written over `let`s of their shared subexpressions: the module stays small (written out
    // as trees, ∂y24/∂q alone would take millions of nodes).
    assert!(code.contains("let dhdx_1 = "));
    assert!(code.len() < 200_000, "{} bytes", code.len());
}
