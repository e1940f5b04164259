//! The generated `∂f/∂x` of a model whose mass matrix depends on a state through nested sums: a chain of
//! modulated transformers, whose `∂M/∂θ` is a Horner chain over the powers of the modulus. As a tree it grows
//! with the square of the chain (363,772 nodes at 200 links) while it is stored in a size linear in it; it is
//! written over the same named shared subexpressions as the entries of `∂F/∂x`. With the modulus `1 + a cos θ`,
//! `∂M/∂a` is such a chain too, and `jac_p_into` writes it over shared names of its own. A cart-pole I-field behind
//! a nonlinear algebraic loop checks the loop's correction and the mass solve together.

use crate::codegen_support::rustc::build_and_run;
use crate::codegen_support::{generate_text, scratch};
use crate::equations_support::families::mtf_chain;
use crate::loops_globalised::LIBM_STD;
use bgc::codegen::rust::Options;

/// A program that evaluates the module `name` at `f_j = 0.7`, `θ = 0.4`, `τ = 1.3` with the default parameters
/// and runs `body`, which prints an entry of a Jacobian and its worst relative difference from central
/// differences (`h = 1e-6`) of the generated rates, which solve M at each point.
fn program(name: &str, body: &str) -> String {
    format!(
        r#"
#[allow(dead_code, unused_imports, clippy::all)]
mod model {{
    include!("{name}.module");
}}

fn main() {{
    let p = model::Params::default();
    let mut x = model::State::zeros();
    x[0] = 0.7;
    x[1] = 0.4;
    let mut u = model::Inputs::zeros();
    u[0] = 1.3;
    let h = 1e-6;
    let mut worst = 0.0f64;
{body}
}}
"#
    )
}

/// `jac_x_into` at `x, u` into `jac`, and `worst` updated with its worst relative difference from central
/// differences of `rhs`.
const CENTRAL_DIFFERENCES: &str = r#"
    let mut jac = model::JacX::zeros();
    model::jac_x_into(&p, 0.0, &x, &u, &mut jac);
    for c in 0..model::N_STATES {
        let (mut up, mut down) = (x, x);
        up[c] += h;
        down[c] -= h;
        let (fu, fd) = (model::rhs(&p, 0.0, &up, &u), model::rhs(&p, 0.0, &down, &u));
        for r in 0..model::N_STATES {
            let want = (fu[r] - fd[r]) / (2.0 * h);
            worst = worst.max((jac[(r, c)] - want).abs() / (1.0 + want.abs()));
        }
    }
"#;

/// [`CENTRAL_DIFFERENCES`] at the program's point, then `∂f_0/∂x_1` and the worst difference printed.
fn state_columns() -> String {
    format!("{CENTRAL_DIFFERENCES}    println!(\"{{:e}} {{:e}}\", jac[(0, 1)], worst);\n")
}

const PARAMETER_A: &str = r#"
    let mut jac = model::JacP::zeros();
    model::jac_p_into(&p, 0.0, &x, &u, &mut jac);
    let a = model::PARAM_NAMES.iter().position(|n| *n == "a").unwrap();
    let (up, down) = (model::Params { a: p.a + h, ..p }, model::Params { a: p.a - h, ..p });
    let (fu, fd) = (model::rhs(&up, 0.0, &x, &u), model::rhs(&down, 0.0, &x, &u));
    for r in 0..model::N_STATES {
        let want = (fu[r] - fd[r]) / (2.0 * h);
        worst = worst.max((jac[(r, a)] - want).abs() / (1.0 + want.abs()));
    }
    println!("{:e} {:e}", jac[(0, a)], worst);
"#;

/// Generates `text` as the module `name`, checks that the correction `label` is written over names starting with
/// `prefix` and that the module is under `bytes`, then builds and runs [`program`] with `body`: the entry it prints
/// is not small and the Jacobian equals central differences to 1e-6.
fn check(name: &str, text: &str, (label, prefix, bytes): (&str, &str, usize), body: &str) {
    let code = generate_text(&format!("{name}.bg"), text, Options { runtime: false });
    let correction = code.split(label).nth(1).unwrap_or_default();
    let head = correction.lines().next().unwrap_or_default();
    assert!(head.contains(prefix) && !head.contains("cos("), "{head}");
    assert!(code.len() < bytes, "{} bytes", code.len());
    let (entry, worst) = run(name, &code, body);
    assert!(entry.abs() > 1e-3, "{entry:e}");
    assert!(worst < 1e-6, "{worst:e}");
}

/// Builds and runs [`program`] with `body` on the module `code` (named `name`): the two numbers it prints.
fn run(name: &str, code: &str, body: &str) -> (f64, f64) {
    let dir = scratch(&format!("{name}-jacobian"));
    let printed = build_and_run(&dir, name, code, &program(name, body), LIBM_STD);
    let _ = std::fs::remove_dir_all(&dir);
    let fields: Vec<f64> = printed
        .split_whitespace()
        .map(|v| v.parse().unwrap_or(f64::NAN))
        .collect();
    assert_eq!(fields.len(), 2, "{printed}");
    (fields[0], fields[1])
}

/// 40 links: `jac_x` equals central differences of `rhs` to 1e-6, its `θ` column (which holds the `∂M/∂θ`
/// correction) is not small, and the module is 151 kB (266 kB with `∂M/∂θ` printed as a tree).
#[test]
fn the_jacobian_of_a_chain_of_modulated_transformers_is_written_over_shared_names() {
    let correction = ("∂M[1, 1]/∂theta = ", "*dfdx_", 200_000);
    check("mtf", &mtf_chain(40), correction, &state_columns());
}

/// The chain of 40 links with the modulus `1 + a cos θ`: the column of `a` in `jac_p` equals central differences
/// of `rhs` in `a` to 1e-6 and is not small, `∂M/∂a` is written over `dmdp_` names, and the module is 192 kB
/// (294 kB with `∂M/∂a` printed as a tree).
#[test]
fn the_parameter_jacobian_of_a_chain_of_modulated_transformers_is_written_over_shared_names() {
    let text = mtf_chain(40)
        .replace("1 + 0.1*cos(theta)", "1 + a*cos(theta)")
        .replace("    input tau", "    param a = 0.1 [1];\n    input tau");
    check(
        "mtfa",
        &text,
        ("∂M[1, 1]/∂a = ", "dmdp_", 240_000),
        PARAMETER_A,
    );
}

/// The cart-pole I-field of fixtures/fields/cart_pole_field.bg behind the resistive network of a nonlinear loop (as
/// in `equations_loops.rs`): `jac_x_into` first adds the loop's correction `∂F/∂z dz/dx` to the rows of `∂F`,
/// then solves the mass block's rows with `M(θ)`. At 20 points it equals central differences of the generated
/// rates, which solve the loop and `M` at each point, to 1e-6 (1.2e-9 when this was written).
#[test]
fn a_mass_matrix_behind_a_loop_has_the_jacobian_of_its_rates() {
    let text = crate::equations_loops::cart_pole_behind_a_loop_text();
    let code = generate_text("cart_loop.bg", &text, Options { runtime: false });
    for item in ["pub const N_TEARS: usize = 1;", "    bgc_solve_rows(jac, ["] {
        assert!(code.contains(item), "no `{}`", item.trim());
    }
    let point = r#"
        for i in 0..model::N_STATES {
            x[i] = 0.3 * (((i + k) % 5) as f64 - 2.0) + 0.01 * k as f64;
        }
        u[0] = 0.4 - 0.05 * k as f64;
"#;
    let largest = r#"
        for r in 0..model::N_STATES {
            for c in 0..model::N_STATES {
                largest = largest.max(jac[(r, c)].abs());
            }
        }
"#;
    let body = format!(
        "    let mut largest = 0.0f64;\n    for k in 0..20 {{{point}{CENTRAL_DIFFERENCES}{largest}    }}\n    \
         println!(\"{{:e}} {{:e}}\", largest, worst);\n"
    );
    let (largest, worst) = run("cart_loop", &code, &body);
    assert!(largest > 1.0, "{largest:e}");
    assert!(worst < 1e-6, "{worst:e}");
}
