//! The simulation's Jacobian through nonlinear algebraic loops (implicit function theorem), against central finite
//! differences of the rates with the loops solved at each point, and its sparsity for separate loops.

use bgc::equations::Equations;
use bgc::simulate::System;
use bgc::simulate::input::Signal;
use bgc::simulate::integrate::{Method, RunOptions, run};

use crate::equations_scaling::equations;
use crate::equations_support::families::loops_in_series;

/// `pairs` pairs of diode loops, the second of each driven by the first's diode current (`MSe s2 = r_m f(d1)`): the
/// second loop's residual reads the first loop's tear, so `∂z₂/∂q_c1` comes only through `∂z₁/∂q_c1`. A hundred
/// pairs (200 states) take the sparse path, where the Jacobian goes through the loops.
fn chained(pairs: usize) -> String {
    let mut s = String::from(
        "model chained {\n    domain electrical;\n    input u [V];\n    param I_s = 1e-6 [A];\n    \
         param V_t = 0.05 [V];\n    param r_m = 50 [Ohm];\n",
    );
    for k in 1..=pairs {
        s += &format!(
            "    Se s1_{k} = u;\n    1 l1_{k};\n    R r1_{k} = 100;\n    R d1_{k} {{ f = I_s * (exp(e / V_t) - 1); }}\n    \
             C c1_{k} = 1e-3;\n    bond s1_{k} -> l1_{k} -> r1_{k}, d1_{k}, c1_{k};\n    \
             MSe s2_{k} = r_m * f(d1_{k});\n    1 l2_{k};\n    R r2_{k} = 200;\n    \
             R d2_{k} {{ f = I_s * (exp(e / V_t) - 1); }}\n    C c2_{k} = 2e-3;\n    \
             bond s2_{k} -> l2_{k} -> r2_{k}, d2_{k}, c2_{k};\n"
        );
    }
    s + "}\n"
}

fn compiled(eqs: &Equations, u: &str) -> System {
    let signal = Signal::parse(u).unwrap_or_else(|e| panic!("{e}"));
    System::new(eqs, eqs.default_params(), vec![signal])
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

/// The rates' Jacobian at `y` by central differences, loops solved at every shifted point.
fn finite_differences(system: &System, y: &[f64], t: f64) -> Vec<Vec<f64>> {
    let dim = y.len();
    let mut u = Vec::new();
    let mut stack = Vec::new();
    let mut at = |y: &[f64]| {
        system.inputs_at(t, &mut u);
        let mut dy = vec![0.0; dim];
        system
            .rhs(y, &mut u, t, &mut dy, &mut stack)
            .unwrap_or_else(|e| panic!("{e}"));
        dy
    };
    let mut columns = Vec::with_capacity(dim);
    for c in 0..dim {
        let h = 1e-8 * (1.0 + y[c].abs());
        let (mut up, mut down) = (y.to_vec(), y.to_vec());
        up[c] += h;
        down[c] -= h;
        let (fu, fd) = (at(&up), at(&down));
        columns.push(
            fu.iter()
                .zip(&fd)
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect::<Vec<_>>(),
        );
    }
    (0..dim)
        .map(|r| columns.iter().map(|col| col[r]).collect())
        .collect()
}

/// The symbolic Jacobian at `y` as `(row, column, value)`.
fn symbolic(system: &System, y: &[f64], t: f64) -> Vec<(usize, usize, f64)> {
    let pattern = system.jacobian_pattern().expect("a symbolic Jacobian");
    let mut u = Vec::new();
    system.inputs_at(t, &mut u);
    let mut values = vec![0.0; pattern.len()];
    system
        .jacobian_values(y, &u, t, &mut values, &mut Vec::new())
        .expect("a symbolic Jacobian");
    pattern
        .into_iter()
        .zip(values)
        .map(|((r, c), v)| (r, c, v))
        .collect()
}

fn index(eqs: &Equations, name: &str) -> usize {
    eqs.states
        .iter()
        .position(|s| s.name == name)
        .unwrap_or_else(|| panic!("no state {name}"))
}

#[test]
fn the_jacobian_through_chained_loops_is_that_of_finite_differences() {
    let pairs = 100;
    let eqs = equations(&chained(pairs));
    assert_eq!(
        eqs.tear_blocks.len(),
        2 * pairs,
        "two loops a pair, solved one after the other"
    );
    let system = compiled(&eqs, "0.9");
    // Both diodes of each pair conduct: a few tenths of a volt across each.
    let mut y = vec![0.0; eqs.states.len() + 2];
    for k in 1..=pairs {
        y[index(&eqs, &format!("q_c1_{k}"))] = 2e-4;
        y[index(&eqs, &format!("q_c2_{k}"))] = -1e-4;
    }
    let (q1, q2) = (index(&eqs, "q_c1_7"), index(&eqs, "q_c2_7"));
    let want = finite_differences(&system, &y, 0.0);
    let got = symbolic(&system, &y, 0.0);
    // The second loop's rate reads the first loop's state only through the first loop's tear.
    let chained = got
        .iter()
        .find(|(r, c, _)| *r == q2 && *c == q1)
        .expect("an entry ∂(d/dt q_c2)/∂q_c1");
    assert!(
        chained.2.abs() > 1e-3,
        "the chained entry {} is as if the first loop did not move",
        chained.2
    );
    for (r, c, v) in &got {
        let w = want[*r][*c];
        assert!(
            (v - w).abs() <= 1e-6 * (1.0 + w.abs()),
            "entry ({r}, {c}): {v} against finite differences {w}"
        );
    }
    // Every entry that finite differences see above their noise (the loops are solved to 1e-12 of their terms) is
    // in the pattern.
    let scale = want.iter().flatten().fold(0.0f64, |m, w| m.max(w.abs()));
    let listed: std::collections::HashSet<(usize, usize)> =
        got.iter().map(|e| (e.0, e.1)).collect();
    for (r, row) in want.iter().enumerate() {
        for (c, w) in row.iter().enumerate() {
            assert!(
                listed.contains(&(r, c)) || w.abs() < 1e-6 * scale,
                "entry ({r}, {c}) = {w} missing"
            );
        }
    }
}

#[test]
fn separate_loops_keep_a_sparse_jacobian_and_one_wide_loop_takes_finite_differences() {
    let (loops, caps) = (30, 10);
    let eqs = equations(&loops_in_series(loops, caps));
    let system = compiled(&eqs, "0.9");
    let n = eqs.states.len();
    assert_eq!(n, loops * caps);
    let y: Vec<f64> = (0..n + 2).map(|k| 1e-5 * (k % 7) as f64).collect();
    let got = symbolic(&system, &y, 0.0);
    // Each capacitor's rate is its loop's current, which reads the loop's capacitors and no other.
    for r in 0..n {
        let loop_of = |s: usize| eqs.states[s].name.split('_').next().map(str::to_string);
        let columns: Vec<usize> = got.iter().filter(|e| e.0 == r).map(|e| e.1).collect();
        assert_eq!(columns.len(), caps, "row {r}");
        assert!(
            columns.iter().all(|&c| loop_of(c) == loop_of(r)),
            "row {r}: {columns:?}"
        );
    }
    let want = finite_differences(&system, &y, 0.0);
    for (r, c, v) in got.iter().filter(|e| e.0 < 2 * caps) {
        let w = want[*r][*c];
        assert!(
            (v - w).abs() <= 1e-6 * (1.0 + w.abs()),
            "({r}, {c}): {v} vs {w}"
        );
    }
    // One loop over 300 capacitors couples them all: a dense Jacobian, left to finite differences.
    let wide = equations(&loops_in_series(1, 300));
    assert!(compiled(&wide, "0.9").jacobian_pattern().is_none());
}

/// 25 identical diode loops (250 states, the sparse path with the loops' implicit derivatives) against one loop
/// alone (10 states, the dense path with finite differences): every loop follows the lone loop's trajectory.
#[test]
fn separate_loops_on_the_sparse_path_follow_one_loop_on_the_dense_path() {
    let opts = RunOptions {
        t_end: 0.2,
        dt_out: 0.01,
        method: Method::Bdf,
        rtol: 1e-8,
        atol: 1e-12,
        max_steps: 100_000,
        max_step: None,
    };
    let drive = "0.9*sin(30*t)";
    let one = equations(&loops_in_series(1, 10));
    let lone = run(&compiled(&one, drive), &[0.0; 10], &opts).unwrap_or_else(|e| panic!("{e}"));
    let many = equations(&loops_in_series(25, 10));
    let all = run(&compiled(&many, drive), &[0.0; 250], &opts).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(lone.times, all.times);
    let peak = lone
        .rows
        .iter()
        .flat_map(|r| &r[..10])
        .fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(peak > 1e-5, "the capacitors charge: {peak}");
    for (a, b) in lone.rows.iter().zip(&all.rows) {
        for (k, s) in many.states.iter().enumerate() {
            let c: usize = s
                .name
                .rsplit('_')
                .next()
                .and_then(|c| c.parse().ok())
                .unwrap_or(0);
            let want = a[index(&one, &format!("q_c1_{c}"))];
            assert!(
                (b[k] - want).abs() <= 1e-6 * peak,
                "{}: {} vs {want}",
                s.name,
                b[k]
            );
        }
    }
}
