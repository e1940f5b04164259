//! A block of algebraic loops whose `∂r/∂z` is ill-conditioned is solved to its root in generated code, not only to
//! its residual tolerance: the generated damped Newton's method and its dogleg fallback test the Newton step from
//! the iterate as `crate::equations::newton` does (its unit test `an_ill_conditioned_loop_is_solved_...` holds the
//! same problem).
//!
//! The block: two tears `z`, `w = z0 + z1`, `d = z0 − z1`, `r0 = M d + β w² + μ w + w³ − c0`,
//! `r1 = M d + β w² − μ w − w³ − c1` with `M = 10⁶` and `c = 3·10⁶ ± (μ w + w³)`. Its terms are of 10⁶ and cancel
//! to leave `w`, along which `∂r/∂w` is 0.03 to 27: residuals within `10⁻¹² s` (3·10⁻⁶) can sit 10⁻⁴ from the root
//! along `w`. The root of the data as stored: `μ w + w³ = (c0 − c1)/2`, a cubic with one real root (Newton's method
//! on it below), and `2 M d = c0 + c1 − 2 β w²`. Before the step test the generated solver returned
//! `z0 = 1.5500216` for the root `1.5499999999` (β = 0, w = 0.1). With `β` = 10⁶ or 10⁷ the valley bends, and
//! the damped method with the Armijo test alone ran out of iterations (as did the dogleg fallback); the natural
//! monotonicity test follows it.

use crate::codegen_support::rustc::build_and_run;
use crate::codegen_support::{generate_text, scratch};
use crate::loops_globalised::{LIBM_STD, two_diode_loops};

const M: f64 = 1e6;

/// The data `c` for the weak coordinate `w`, and the block's root.
fn valley(w: f64, beta: f64, mu: f64) -> ([f64; 2], [f64; 2]) {
    let k = mu * w + w.powi(3);
    let c = [3e6 + k, 3e6 - k];
    let half = (c[0] - c[1]) / 2.0;
    let mut w = half.cbrt();
    for _ in 0..50 {
        w -= (mu * w + w.powi(3) - half) / (mu + 3.0 * w * w);
    }
    let d = (c[0] + c[1] - 2.0 * beta * w * w) / (2.0 * M);
    (c, [(w + d) / 2.0, (w - d) / 2.0])
}

const MAIN: &str = r#"
#[allow(dead_code, unused_imports, clippy::all)]
mod model {
    include!("two.module");

    pub fn valley(z: &Tears, c: [f64; 2], beta: f64, mu: f64) -> LoopEval<2> {
        let m = 1e6;
        let (w, d) = (z[0] + z[1], z[0] - z[1]);
        let weak = mu * w + w * w * w;
        let strong = m * d + beta * w * w;
        let terms = (m * d).abs() + (beta * w * w).abs() + (mu * w).abs() + (w * w * w).abs();
        let (dw, bw) = (mu + 3.0 * w * w, 2.0 * beta * w);
        let (mut r, mut s, mut j) = (SVector::<f64, 2>::zeros(), SVector::<f64, 2>::zeros(), SMatrix::<f64, 2, 2>::zeros());
        r[0] = strong + weak - c[0];
        r[1] = strong - weak - c[1];
        s[0] = terms + c[0].abs();
        s[1] = terms + c[1].abs();
        j[(0, 0)] = m + bw + dw;
        j[(0, 1)] = -m + bw + dw;
        j[(1, 0)] = m + bw - dw;
        j[(1, 1)] = -m + bw - dw;
        (r, s, j)
    }

    pub fn run(c: [f64; 2], beta: f64, mu: f64, start: [f64; 2]) {
        let mut z = Tears::zeros();
        z[0] = start[0];
        z[1] = start[1];
        let eval = |z: &Tears| valley(z, c, beta, mu);
        match bgc_newton(&mut z, 0, 0, eval) {
            Ok(()) => print!("{:e} {:e}", z[0], z[1]),
            Err(e) => print!("error {e}"),
        }
        // The dogleg method on its own, on the straight valley (on the bent one it fails as the
        // compiler's does, and the damped method needs no fallback).
        if beta != 0.0 {
            println!();
            return;
        }
        z[0] = start[0];
        z[1] = start[1];
        match bgc_dogleg(&z, 0, &eval) {
            Some(z) => println!(" {:e} {:e}", z[0], z[1]),
            None => println!(" dogleg failed"),
        }
    }
}

fn main() {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<f64>().unwrap_or(f64::NAN));
    let mut next = || args.next().unwrap_or(f64::NAN);
    loop {
        let (c0, c1, beta, mu, s0, s1) = (next(), next(), next(), next(), next(), next());
        if c0.is_nan() {
            break;
        }
        model::run([c0, c1], beta, mu, [s0, s1]);
    }
}
"#;

#[test]
fn the_generated_solver_reaches_the_root_of_an_ill_conditioned_block() {
    let dir = scratch("ill-conditioned-loops");
    let code = generate_text(
        "two.bg",
        &two_diode_loops(),
        bgc::codegen::rust::Options { runtime: false },
    );
    assert!(code.contains("pub const N_TEARS: usize = 2;"), "{code}");
    let mut cases = Vec::new();
    for w in [0.1, 0.3, 1.0] {
        let (c, root) = valley(w, 0.0, 1e-3);
        for start in [[0.0, 0.0], [1.0, -1.0], [2.0 * root[0], root[1]]] {
            cases.push(Case {
                c,
                beta: 0.0,
                mu: 1e-3,
                start,
                root,
            });
        }
    }
    for (beta, mu, start) in [
        (1e6, 1e-3, [1.0, -1.0]),
        (1e7, 1e-2, [0.0, 0.0]),
        (1e7, 1e-2, [1.0, -1.0]),
    ] {
        let (c, root) = valley(3.0, beta, mu);
        cases.push(Case {
            c,
            beta,
            mu,
            start,
            root,
        });
    }
    let main = MAIN.replace(
        "let mut args = std::env::args().skip(1)",
        &format!("let mut args = {:?}.into_iter()", args(&cases)),
    );
    let printed = build_and_run(&dir, "two", &code, &main, LIBM_STD);
    let _ = std::fs::remove_dir_all(&dir);
    let lines: Vec<&str> = printed.lines().collect();
    assert_eq!(lines.len(), cases.len(), "{printed}");
    for (case, line) in cases.iter().zip(lines) {
        let z: Vec<f64> = line.split(' ').filter_map(|v| v.parse().ok()).collect();
        let expected = if case.beta == 0.0 { 4 } else { 2 };
        assert_eq!(z.len(), expected, "{case:?}: {line}");
        for (z, root) in z.iter().zip(case.root.iter().cycle()) {
            assert!(
                (z - root).abs() <= 1e-8 * root.abs(),
                "{case:?}: {z} against {root} ({line})"
            );
        }
    }
}

/// One block's data, its start and its root.
#[derive(Debug)]
struct Case {
    c: [f64; 2],
    beta: f64,
    mu: f64,
    start: [f64; 2],
    root: [f64; 2],
}

/// The cases as the program's list of numbers: `c0 c1 β μ start0 start1` each, in full precision.
fn args(cases: &[Case]) -> Vec<String> {
    cases
        .iter()
        .flat_map(|k| [k.c[0], k.c[1], k.beta, k.mu, k.start[0], k.start[1]])
        .map(|v| format!("{v:e}"))
        .collect()
}
