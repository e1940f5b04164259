//! Parameter terms: the generated `rhs`, `outputs` and Jacobians read their parameter-only subexpressions
//! (`1/m`, `d/m`, `J_m/(J_m + J_g)`) from `ParamTerms`, computed once per parameter set by `Model` and at each call
//! by the free functions, so that no division by parameters is left in a linear model's rhs.

use crate::codegen_support::rustc::build_and_run;
use crate::codegen_support::{generate_text, scratch, workspace};
use crate::loops_globalised::LIBM_STD;
use bgc::codegen::rust::Options;

/// The body of the function whose signature starts with `head`, up to its closing brace.
fn body_of<'a>(code: &'a str, head: &str) -> &'a str {
    let start = code
        .find(head)
        .unwrap_or_else(|| panic!("no `{head}` in\n{code}"));
    let rest = &code[start..];
    let end = rest.find("\n}\n").unwrap_or(rest.len());
    &rest[..end]
}

/// The lines of `body` that are code, not comments.
fn code_lines(body: &str) -> Vec<&str> {
    body.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect()
}

#[test]
fn the_back_support_rhs_divides_by_no_parameter() {
    let text = std::fs::read_to_string(workspace().join("models/back_support.bg"))
        .unwrap_or_else(|e| panic!("{e}"));
    let code = generate_text("back_support.bg", &text, Options::default());
    let rhs = body_of(&code, "pub fn rhs_with(");
    // Before: `... * p.J_m / (p.J_m + p.J_g)`, `p_rotor / p.J_m`, ...: five divisions by parameters per call.
    for line in code_lines(rhs).into_iter().skip(1) {
        assert!(!line.contains('/'), "a division in the rhs: {line}\n{rhs}");
    }
    assert!(rhs.contains("c."), "{rhs}");
    // The reciprocals live in `ParamTerms`, computed in `ParamTerms::at`.
    let at = body_of(&code, "    pub fn at(p: &Params) -> ParamTerms {");
    assert!(at.contains("let inv_J_m = 1.0 / p.J_m;"), "{at}");
    // `rhs_into` keeps its signature and computes the terms; `Model` holds them and recomputes them with its
    // parameters.
    assert!(
        code.contains(
            "pub fn rhs_into(p: &Params, t: f64, x: &State, u: &Inputs, dx: &mut State) {\n    \
             rhs_with(p, &ParamTerms::at(p), t, x, u, dx);\n}"
        ),
        "{code}"
    );
    assert!(code.contains("    terms: ParamTerms,\n"), "{code}");
    assert!(
        code.contains("        rhs_with(&self.params, &self.terms, t, x, u, dx);\n"),
        "{code}"
    );
    assert!(
        code.contains("        *self = Model::at(self.params);\n"),
        "{code}"
    );
}

const MAIN: &str = r#"
#[allow(dead_code, unused_imports, clippy::all)]
mod model {
    include!("oscillator.module");
}

fn main() {
    let p = model::Params { m: 4.0, k: 500.0, d: 3.0 };
    let mut x = model::State::zeros();
    x[0] = 2.0;
    x[1] = 0.01;
    let mut u = model::Inputs::zeros();
    u[0] = 1.5;
    let free = model::rhs(&p, 0.0, &x, &u);
    let mut with = model::State::zeros();
    model::rhs_with(&p, &model::ParamTerms::at(&p), 0.0, &x, &u, &mut with);
    let mut jac = model::JacX::zeros();
    model::jac_x_into(&p, 0.0, &x, &u, &mut jac);
    println!("{:e} {:e} {:e} {:e}", free[0], free[1], with[0], with[1]);
    println!("{:e} {:e} {:e} {:e}", jac[(0, 0)], jac[(0, 1)], jac[(1, 0)], jac[(1, 1)]);
}
"#;

#[test]
fn the_oscillator_with_parameter_terms_gives_the_hand_derived_rates() {
    let text = std::fs::read_to_string(workspace().join("bgc/tests/corpus/oscillator.bg"))
        .unwrap_or_else(|e| panic!("{e}"));
    let code = generate_text("oscillator.bg", &text, Options { runtime: false });
    let rhs = body_of(&code, "pub fn rhs_with(");
    assert!(
        code_lines(rhs).iter().skip(1).all(|l| !l.contains('/')),
        "{rhs}"
    );
    let dir = scratch("param-terms");
    let printed = build_and_run(&dir, "oscillator", &code, MAIN, LIBM_STD);
    let _ = std::fs::remove_dir_all(&dir);
    let values: Vec<f64> = printed
        .split_whitespace()
        .map(|v| v.parse().unwrap_or(f64::NAN))
        .collect();
    // By hand, states (p_mass, q_spring), m = 4, k = 500, d = 3, F = 1.5, p = 2, q = 0.01:
    // ṗ = F − k q − d p/m = 1.5 − 5 − 1.5 = −5, q̇ = p/m = 0.5; ∂f/∂x = [[−d/m, −k], [1/m, 0]].
    let expected = [-5.0, 0.5, -5.0, 0.5, -0.75, -500.0, 0.25, 0.0];
    assert_eq!(values.len(), expected.len(), "{printed}");
    for (v, e) in values.iter().zip(expected) {
        assert!(
            (v - e).abs() <= 1e-15 * e.abs().max(1.0),
            "{v} vs {e}\n{printed}"
        );
    }
}
