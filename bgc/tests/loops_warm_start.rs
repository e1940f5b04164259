//! Warm starts of the nonlinear algebraic loops: the generated `solve_loops_from` starts Newton's method from the
//! caller's guess (the last solution of a time-stepping caller) and falls back to zero when that start fails;
//! `bgc simulate` starts each solve from the previous one. The diode RC loop of `bgc/tests/corpus/diode_rc.bg`
//! (references in `loops_globalised`) is followed through u = 8, 10, 20, 100 V, each solve from the last, and from
//! starts that are useless (NaN, far off), and the residual is checked against the diode law.

use crate::cli_support::{Csv, corpus, simulate};
use crate::codegen_support::rustc::build_and_run;
use crate::codegen_support::{generate_text, scratch};
use crate::loops_globalised::{LIBM_STD, ROOTS};

/// `R_s`, `I_s`, `V_t`, `C_v` of the corpus model (its defaults).
const R_S: f64 = 100.0;
const I_S: f64 = 1e-6;
const V_T: f64 = 0.05;
const C_V: f64 = 1e-3;

/// The loop's residual at current `i` with the source at `u` and the capacitor at `v_c`, relative to the larger of
/// its two terms: `i − I_s (exp((u − R_s i − v_c)/V_t) − 1)`.
fn relative_residual(i: f64, u: f64, v_c: f64) -> f64 {
    let diode = I_S * (((u - R_S * i - v_c) / V_T).exp() - 1.0);
    (i - diode).abs() / i.abs().max(diode.abs())
}

const MAIN: &str = r#"
#[allow(dead_code, unused_imports, clippy::all)]
mod model {
    include!("diode.module");
}

fn main() {
    let p = model::Params::default();
    let x = model::State::zeros();
    let mut last = model::Tears::zeros();
    // Continuation: each solve from the previous solution.
    for u in [8.0, 10.0, 20.0, 100.0] {
        let mut inputs = model::Inputs::zeros();
        inputs[0] = u;
        match model::solve_loops_from(&p, 0.0, &x, &inputs, &last) {
            Ok(z) => {
                println!("warm {u} {:e}", z[0]);
                last = z;
            }
            Err(e) => println!("warm {u} error {e}"),
        }
    }
    // Useless starts: not finite, or far beyond the solution.
    for (name, guess) in [("nan", f64::NAN), ("inf", f64::INFINITY), ("far", 1e6), ("negative", -1e3)] {
        let mut start = model::Tears::zeros();
        start[0] = guess;
        let mut inputs = model::Inputs::zeros();
        inputs[0] = 10.0;
        match model::solve_loops_from(&p, 0.0, &x, &inputs, &start) {
            Ok(z) => println!("{name} 10 {:e}", z[0]),
            Err(e) => println!("{name} 10 error {e}"),
        }
    }
}
"#;

#[test]
fn the_generated_solve_loops_from_follows_the_diode_loop_from_the_last_solution() {
    let dir = scratch("diode-warm");
    let text = std::fs::read_to_string(corpus("diode_rc.bg")).unwrap_or_else(|e| panic!("{e}"));
    let code = generate_text(
        "diode_rc.bg",
        &text,
        bgc::codegen::rust::Options { runtime: false },
    );
    let printed = build_and_run(&dir, "diode", &code, MAIN, LIBM_STD);
    let _ = std::fs::remove_dir_all(&dir);
    let solved: Vec<(String, f64, f64)> = printed
        .lines()
        .map(|line| {
            let f: Vec<&str> = line.split(' ').collect();
            let num = |k: usize| f.get(k).and_then(|v| v.parse().ok()).unwrap_or(f64::NAN);
            (
                f.first().copied().unwrap_or_default().to_string(),
                num(1),
                num(2),
            )
        })
        .collect();
    assert_eq!(solved.len(), 8, "{printed}");
    let root_at = |u: f64| ROOTS.iter().find(|r| r.0 == u).map_or(f64::NAN, |r| r.1);
    for (how, u, z) in &solved {
        assert!(
            relative_residual(*z, *u, 0.0) <= 1e-9,
            "{how} u = {u}: z = {z}, residual {:e}\n{printed}",
            relative_residual(*z, *u, 0.0)
        );
        let root = root_at(*u);
        assert!(
            (z - root).abs() <= 1e-9 * root,
            "{how} u = {u}: {z} vs {root}"
        );
    }
}

/// `bgc simulate` with the source ramping from 8 V to 100 V while the capacitor charges: at every row the loop
/// current and the diode voltage satisfy the diode law and Kirchhoff's voltage law with the capacitor's charge.
#[test]
fn bgc_simulate_follows_the_diode_loop_through_a_ramp() {
    let path = corpus("diode_rc.bg");
    let csv: Csv = simulate(&[
        &path,
        "--t-end",
        "1e-3",
        "--dt-out",
        "1e-5",
        "--input",
        "u=8+92000*t",
    ]);
    let (t, q, i, v_d) = (csv.col("t"), csv.col("q_cap"), csv.col("i"), csv.col("v_d"));
    assert_eq!(t.len(), 101);
    for k in 0..t.len() {
        let u = 8.0 + 92_000.0 * t[k];
        let v_c = q[k] / C_V;
        assert!(
            relative_residual(i[k], u, v_c) <= 1e-9,
            "t = {}: i = {}, residual {:e}",
            t[k],
            i[k],
            relative_residual(i[k], u, v_c)
        );
        // The diode's voltage is what the source leaves after the resistor and the capacitor.
        assert!(
            (v_d[k] - (u - R_S * i[k] - v_c)).abs() <= 1e-9 * u,
            "t = {}: v_d = {}",
            t[k],
            v_d[k]
        );
    }
    // The loop current grows with the source (checked against the bracketed references at the two ends).
    assert!((i[0] - ROOTS[0].1).abs() <= 1e-9 * ROOTS[0].1, "{}", i[0]);
}

/// Across a breakpoint (a fresh solver starts there) the loop is solved from the solution before it: the source
/// jumps from 8 V to 100 V at t = 0.5 ms, and every row, on both sides, satisfies the diode law.
#[test]
fn bgc_simulate_solves_the_diode_loop_across_a_jump_of_the_source() {
    let path = corpus("diode_rc.bg");
    let csv: Csv = simulate(&[
        &path,
        "--t-end",
        "1e-3",
        "--dt-out",
        "1e-4",
        "--input",
        "u=8+92*step(0.5e-3)",
    ]);
    let (t, q, i) = (csv.col("t"), csv.col("q_cap"), csv.col("i"));
    assert_eq!(t.len(), 11);
    for k in 0..t.len() {
        let u = if t[k] < 0.5e-3 { 8.0 } else { 100.0 };
        let r = relative_residual(i[k], u, q[k] / C_V);
        assert!(r <= 1e-9, "t = {}: i = {}, residual {r:e}", t[k], i[k]);
    }
    assert!(i[10] > 0.9 && i[4] < 0.08, "{i:?}");
}
