//! Nonlinear algebraic loops with a solution are solved, however steep the law: the diode RC loop of
//! `bgc/tests/corpus/diode_rc.bg` with `u` = 8, 10, 20, 100 V, where damped Newton's method from zero stopped with
//! a residual of 1e37 (and the generated `solve_loops` returned `Err`). The compiler's evaluator (`bgc simulate`,
//! `bgc statespace --at`) and the generated code both fall back to a bracketed root for a one-tear block.
//!
//! Reference: the loop current `i` with the capacitor uncharged solves `i = I_s (exp((u − R_s i)/V_t) − 1)`
//! (`R_s` = 100 Ω, `I_s` = 1e-6 A, `V_t` = 0.05 V). Bisection in Python on `[0, u/100]`, down to adjacent floats:
//!
//! ```text
//! r = lambda i: i - 1e-6*(math.exp((u - 100*i)/0.05) - 1)      # -inf where exp overflows
//! a, b = 0.0, u/100
//! while (m := (a + b)/2) not in (a, b): a, b = (m, b) if r(m) < 0 else (a, m)
//! ```

use crate::cli_support;
use crate::codegen_support;

use cli_support::{bgc, corpus};
use codegen_support::rustc::build_and_run;
use codegen_support::{generate_text, scratch};

pub(crate) const ROOTS: [(f64, f64); 4] = [
    (8.0, 0.074_391_445_163_915_23),
    (10.0, 0.094_273_019_538_969_23),
    (20.0, 0.193_912_416_484_180_8),
    (100.0, 0.993_095_708_335_824_2),
];

/// The `i` column of the first CSV row (t = 0, capacitor uncharged).
fn first_current(csv: &str) -> Option<f64> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next()?.split(',').collect();
    // Header cells carry their unit: `i [A]`.
    let col = header
        .iter()
        .position(|c| c.split(" [").next() == Some("i"))?;
    lines.next()?.split(',').nth(col)?.parse().ok()
}

#[test]
fn bgc_simulate_solves_the_steep_diode_loop() {
    let path = corpus("diode_rc.bg");
    for (u, root) in ROOTS {
        let input = format!("u={u}");
        let (code, out, err) = bgc(&["simulate", &path, "--t-end", "1e-3", "--input", &input]);
        assert_eq!(code, 0, "u = {u}: {err}");
        let i = first_current(&out).unwrap_or(f64::NAN);
        assert!(
            (i - root).abs() <= 1e-9 * root,
            "u = {u}: i = {i}, expected {root}"
        );
    }
}

#[test]
fn bgc_statespace_linearises_at_the_steep_diode_loop() {
    let path = corpus("diode_rc.bg");
    for (u, _) in ROOTS {
        let at = format!("u={u}");
        let (code, out, err) = bgc(&["statespace", &path, "--at", &at]);
        assert_eq!(code, 0, "u = {u}: {err}");
        assert!(out.contains("\"A\""), "{out}");
    }
}

/// `libm` with the real functions (the generated code calls them; `std` computes them here).
pub(crate) const LIBM_STD: &str = r#"
macro_rules! unary {
    ($($name:ident = $f:ident),*) => { $(pub fn $name(x: f64) -> f64 { x.$f() })* };
}
unary!(sin = sin, cos = cos, tan = tan, asin = asin, acos = acos, atan = atan, exp = exp, log = ln,
       log10 = log10, sqrt = sqrt, fabs = abs, tanh = tanh, sinh = sinh, cosh = cosh);
pub fn atan2(y: f64, x: f64) -> f64 { y.atan2(x) }
pub fn pow(x: f64, y: f64) -> f64 { x.powf(y) }
"#;

const MAIN: &str = r#"
#[allow(dead_code, unused_imports, clippy::all)]
mod model {
    include!("diode.module");
}

fn main() {
    let p = model::Params::default();
    let x = model::State::zeros();
    for u in [8.0, 10.0, 20.0, 100.0, f64::NAN] {
        let mut inputs = model::Inputs::zeros();
        inputs[0] = u;
        match model::solve_loops(&p, 0.0, &x, &inputs) {
            Ok(z) => println!("{u} {:e} {:e}", z[0], model::rhs(&p, 0.0, &x, &inputs)[0]),
            Err(e) => println!("{u} error {e}"),
        }
    }
}
"#;

#[test]
fn the_generated_solve_loops_solves_the_steep_diode_loop() {
    let dir = scratch("diode-loops");
    let text = std::fs::read_to_string(corpus("diode_rc.bg")).unwrap_or_else(|e| panic!("{e}"));
    let code = generate_text(
        "diode_rc.bg",
        &text,
        bgc::codegen::rust::Options { runtime: false },
    );
    let printed = build_and_run(&dir, "diode", &code, MAIN, LIBM_STD);
    let _ = std::fs::remove_dir_all(&dir);
    let lines: Vec<&str> = printed.lines().collect();
    assert_eq!(lines.len(), ROOTS.len() + 1, "{printed}");
    // An input of NaN: refused, in words (before: "(NonFinite after 0 iterations, ...)").
    assert_eq!(
        lines[ROOTS.len()],
        "NaN error the algebraic loop for `loop_f_diode` was not solved: a residual or its derivative was not finite \
         after 0 iterations (residual NaN)",
        "{printed}"
    );
    for ((u, root), line) in ROOTS.iter().zip(&lines) {
        let fields: Vec<&str> = line.split(' ').collect();
        let z: f64 = fields
            .get(1)
            .and_then(|f| f.parse().ok())
            .unwrap_or(f64::NAN);
        assert!((z - root).abs() <= 1e-9 * root, "u = {u}: {line}");
        // The capacitor charges with the loop current: dq/dt = i, finite.
        let rate: f64 = fields
            .get(2)
            .and_then(|f| f.parse().ok())
            .unwrap_or(f64::NAN);
        assert!((rate - z).abs() <= 1e-12 * z, "u = {u}: {line}");
    }
}

/// Two diode loops side by side: a module with two tears, so that the generated solvers of blocks of two are
/// emitted and can be driven directly.
pub(crate) fn two_diode_loops() -> String {
    let text = std::fs::read_to_string(corpus("diode_rc.bg")).unwrap_or_else(|e| panic!("{e}"));
    let start = text.find("    Se source").unwrap_or_default();
    let end = text.find("    output i").unwrap_or_default();
    let second = text[start..end]
        .replace("source", "source2")
        .replace("loop_current", "loop_current2")
        .replace("series", "series2")
        .replace("diode", "diode2")
        .replace("cap ", "cap2 ")
        .replace("cap;", "cap2;");
    text.replacen("    output i", &format!("{second}    output i"), 1)
}

/// The block of two tears on which damped Newton's method creeps (the loop of cubic resistors through modulated
/// transformers of bgc's property test, seed 8169226994125556156; the same system as `CubicLoop` in
/// `equations::dogleg`), driven through the generated `bgc_damped` and `bgc_newton`.
const CUBIC_MAIN: &str = r#"
#[allow(dead_code, unused_imports, clippy::all)]
mod model {
    include!("two.module");

    pub fn cubic(z: &Tears) -> LoopEval<2> {
        let (n1, n2, n3, v0, k0, v1, k1) = (1.395, 1.2925, 0.7, 1.725, 0.2295, 2.02, 0.254);
        let (v2, v3, v4, l0) = (1.23, 1.6825, 2.24, 2.2975);
        let (q, w, u0, u1): (f64, f64, f64, f64) =
            (0.21291896135803667, -0.528186186553325, 0.13311726524149825, 0.9393400554106819);
        let (e, f) = (z[0], z[1]);
        let l = l0 * (0.3 * w.cos() + 1.0);
        let m = 1.0 + 0.3 * q.cos();
        let s = n2 * f - l * (n1 * f * m + e / v1 + k1 * e.powi(3) - u1) + u0;
        let a = (v3 + v4) * s / (n3 * n3);
        let x = n1 * e * m - n2 * a - q / v2;
        let (mut r, mut scale, mut j) = (SVector::zeros(), SVector::zeros(), SMatrix::zeros());
        r[0] = l * a - e;
        r[1] = x / v0 + k0 * x.powi(3) - f;
        scale[0] = (l * a).abs() + e.abs();
        scale[1] = (x / v0).abs() + (k0 * x.powi(3)).abs() + f.abs();
        let (ds_de, ds_df) = (-l * (1.0 / v1 + 3.0 * k1 * e * e), n2 - l * n1 * m);
        let c = (v3 + v4) / (n3 * n3);
        let (dx_de, dx_df) = (n1 * m - n2 * c * ds_de, -n2 * c * ds_df);
        let g = 1.0 / v0 + 3.0 * k0 * x * x;
        j[(0, 0)] = l * c * ds_de - 1.0;
        j[(0, 1)] = l * c * ds_df;
        j[(1, 0)] = g * dx_de;
        j[(1, 1)] = g * dx_df - 1.0;
        (r, scale, j)
    }

    pub fn run() {
        let mut z = Tears::zeros();
        match bgc_damped(&mut z, 0, 0, &cubic) {
            Ok(()) => println!("damped solved"),
            Err(e) => println!("damped {:?}", e.kind),
        }
        let mut z = Tears::zeros();
        match bgc_newton(&mut z, 0, 0, cubic) {
            Ok(()) => {
                let (r, s, _) = cubic(&z);
                let within = r[0].abs() <= LOOP_RTOL * s[0] && r[1].abs() <= LOOP_RTOL * s[1];
                println!("{} {} {within}", z[0], z[1]);
            }
            Err(e) => println!("error {e}"),
        }
    }
}

fn main() {
    model::run();
}
"#;

/// The generated `bgc_newton` falls back on Powell's dogleg method for a block of several tears, as the
/// compiler's evaluation does: on a block where damped Newton's method fails it finds the root that
/// `scipy.optimize.root(r, [0, 0], method="hybr")` finds, [0.61577178, 0.45092652].
#[test]
fn the_generated_solver_solves_a_block_where_damped_newton_creeps() {
    let dir = scratch("dogleg-loops");
    let code = generate_text(
        "two.bg",
        &two_diode_loops(),
        bgc::codegen::rust::Options { runtime: false },
    );
    assert!(code.contains("pub const N_TEARS: usize = 2;"), "{code}");
    let printed = build_and_run(&dir, "two", &code, CUBIC_MAIN, LIBM_STD);
    let _ = std::fs::remove_dir_all(&dir);
    let lines: Vec<&str> = printed.lines().collect();
    // The damped method alone fails here (it ends where no damped step decreases the residual or contracts the
    // Newton step; the compiler's, whose elimination refuses smaller pivots, at a Jacobian it takes for singular).
    assert!(
        lines
            .first()
            .is_some_and(|l| l.starts_with("damped ") && *l != "damped solved"),
        "{printed}"
    );
    let fields: Vec<&str> = lines.get(1).map_or(vec![], |l| l.split(' ').collect());
    let value = |k: usize| fields.get(k).and_then(|f| f.parse::<f64>().ok());
    assert!(
        value(0).is_some_and(|e| (e - 0.615_771_78).abs() < 1e-8)
            && value(1).is_some_and(|f| (f - 0.450_926_52).abs() < 1e-8)
            && fields.get(2) == Some(&"true"),
        "{printed}"
    );
}
