//! The generated `∂f/∂x` of a model whose mass matrix depends on a state through nested sums: a chain of
//! modulated transformers, whose `∂M/∂θ` is a Horner chain over the powers of the modulus. As a tree it grows
//! with the square of the chain (363,772 nodes at 200 links) while it is stored in a size linear in it; it is
//! written over the same named shared subexpressions as the entries of `∂F/∂x`. With the modulus `1 + a cos θ`,
//! `∂M/∂a` is such a chain too, and `jac_p_into` writes it over shared names of its own.

use crate::codegen_support::rustc::build_and_run;
use crate::codegen_support::{generate_text, scratch};
use crate::equations_support::families::mtf_chain;
use crate::loops_globalised::LIBM_STD;
use bgc::codegen::rust::Options;

const MAIN: &str = r#"
#[allow(dead_code, unused_imports, clippy::all)]
mod model {
    include!("mtf.module");
}

fn main() {
    let p = model::Params::default();
    let mut x = model::State::zeros();
    x[0] = 0.7;
    x[1] = 0.4;
    let mut u = model::Inputs::zeros();
    u[0] = 1.3;
    let mut jac = model::JacX::zeros();
    model::jac_x_into(&p, 0.0, &x, &u, &mut jac);
    // Central differences of the generated rates, which solve M at each point.
    let h = 1e-6;
    let mut worst = 0.0f64;
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
    println!("{:e} {:e}", jac[(0, 1)], worst);
}
"#;

/// 40 links: `jac_x` equals central differences of `rhs` to 1e-6, its `θ` column (which holds the `∂M/∂θ`
/// correction) is not small, and the module is 151 kB (266 kB with `∂M/∂θ` printed as a tree).
#[test]
fn the_jacobian_of_a_chain_of_modulated_transformers_is_written_over_shared_names() {
    let code = generate_text("mtf.bg", &mtf_chain(40), Options { runtime: false });
    let correction = code.split("∂M[1, 1]/∂theta = ").nth(1).unwrap_or_default();
    let head = correction.lines().next().unwrap_or_default();
    assert!(head.contains("*dfdx_") && !head.contains("cos("), "{head}");
    assert!(code.len() < 200_000, "{} bytes", code.len());
    let dir = scratch("mtf-jacobian");
    let printed = build_and_run(&dir, "mtf", &code, MAIN, LIBM_STD);
    let _ = std::fs::remove_dir_all(&dir);
    let fields: Vec<f64> = printed
        .split_whitespace()
        .map(|v| v.parse().unwrap_or(f64::NAN))
        .collect();
    assert_eq!(fields.len(), 2, "{printed}");
    assert!(fields[0].abs() > 1e-3, "{printed}");
    assert!(fields[1] < 1e-6, "{printed}");
}

const PARAM_MAIN: &str = r#"
#[allow(dead_code, unused_imports, clippy::all)]
mod model {
    include!("mtfa.module");
}

fn main() {
    let p = model::Params::default();
    let mut x = model::State::zeros();
    x[0] = 0.7;
    x[1] = 0.4;
    let mut u = model::Inputs::zeros();
    u[0] = 1.3;
    let mut jac = model::JacP::zeros();
    model::jac_p_into(&p, 0.0, &x, &u, &mut jac);
    let a = model::PARAM_NAMES.iter().position(|n| *n == "a").unwrap();
    // Central differences of the generated rates in `a`, which solve M at each value.
    let h = 1e-6;
    let (up, down) = (model::Params { a: p.a + h, ..p }, model::Params { a: p.a - h, ..p });
    let (fu, fd) = (model::rhs(&up, 0.0, &x, &u), model::rhs(&down, 0.0, &x, &u));
    let mut worst = 0.0f64;
    for r in 0..model::N_STATES {
        let want = (fu[r] - fd[r]) / (2.0 * h);
        worst = worst.max((jac[(r, a)] - want).abs() / (1.0 + want.abs()));
    }
    println!("{:e} {:e}", jac[(0, a)], worst);
}
"#;

/// The chain of 40 links with the modulus `1 + a cos θ`: the column of `a` in `jac_p` equals central differences
/// of `rhs` in `a` to 1e-6 and is not small, `∂M/∂a` is written over `dmdp_` names, and the module is 192 kB
/// (294 kB with `∂M/∂a` printed as a tree).
#[test]
fn the_parameter_jacobian_of_a_chain_of_modulated_transformers_is_written_over_shared_names() {
    let text = mtf_chain(40)
        .replace("1 + 0.1*cos(theta)", "1 + a*cos(theta)")
        .replace("    input tau", "    param a = 0.1 [1];\n    input tau");
    let code = generate_text("mtfa.bg", &text, Options { runtime: false });
    let correction = code.split("∂M[1, 1]/∂a = ").nth(1).unwrap_or_default();
    let head = correction.lines().next().unwrap_or_default();
    assert!(head.contains("dmdp_") && !head.contains("cos("), "{head}");
    assert!(code.len() < 240_000, "{} bytes", code.len());
    let dir = scratch("mtfa-jacobian");
    let printed = build_and_run(&dir, "mtfa", &code, PARAM_MAIN, LIBM_STD);
    let _ = std::fs::remove_dir_all(&dir);
    let fields: Vec<f64> = printed
        .split_whitespace()
        .map(|v| v.parse().unwrap_or(f64::NAN))
        .collect();
    assert_eq!(fields.len(), 2, "{printed}");
    assert!(fields[0].abs() > 1e-3, "{printed}");
    assert!(fields[1] < 1e-6, "{printed}");
}
