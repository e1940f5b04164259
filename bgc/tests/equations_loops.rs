//! Nonlinear algebraic loops kept implicit: the tear block of corpus/diode_rc.bg, its printed forms, its numeric
//! solution, the linearisation by the implicit function theorem against a hand derivation, the consumer that
//! refuses it (symbolic state spaces) and code generation, which solves it in the generated module.

use bgc::causality::analyse;
use bgc::equations::symbols::{self as sym, Sym};
use bgc::equations::{
    Equations, LinearError, StateSelection, derive, jacobians, linear_state_space,
    linear_through_loops, linearise, numeric_state_space, solve_all, to_json, to_latex, to_text,
};
use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;

const PARAMS: [f64; 4] = [100.0, 1e-6, 0.05, 1e-3];

fn diode_rc() -> Equations {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/corpus/diode_rc.bg");
    derived(path, std::fs::read_to_string(path).expect("corpus file"))
}

/// The equations of the single model of `text`, without errors.
fn derived(name: &str, text: String) -> Equations {
    let mut sources = SourceMap::new();
    let root = sources.add(name, text);
    let (models, diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    let (causality, _) = analyse(&models[0]);
    let (eqs, diags) = derive(&models[0], &causality);
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    eqs
}

/// The diode's loop is solved numerically and is not linear: the state space needs an operating point.
#[test]
fn a_nonlinear_loop_is_not_linear_through_its_loops() {
    assert!(!linear_through_loops(&diode_rc(), StateSelection::Energy));
}

#[test]
fn the_diode_loop_is_one_tear_block_in_the_loop_current() {
    let eqs = diode_rc();
    assert!(eqs.complete());
    assert!(eqs.loops.is_empty(), "not solved exactly");
    assert_eq!(eqs.tear_blocks.len(), 1);
    let block = &eqs.tear_blocks[0];
    assert_eq!(block.names, ["loop_f_diode"]);
    let z = block.tears[0];
    assert_eq!(eqs.sym_name(z), "loop_f_diode");
    // The rate of q is the loop current itself.
    assert_eq!(eqs.f[0].as_ref(), Some(&z.expr()));
    // r(z) = I_s (exp((u - q/C - R_s z)/V_t) - 1) - z, checked at a point against that formula.
    let (q, u, zv) = (3e-4, 1.2, 2e-3);
    let value = |s: Sym| match s {
        Sym::Param(i) => PARAMS.get(i).copied(),
        Sym::State(0) => Some(q),
        Sym::Input(0) => Some(u),
        Sym::Tear(_) => Some(zv),
        _ => None,
    };
    let r = sym::eval(&block.residuals[0], &value).expect("residual evaluates");
    let want = 1e-6 * (((u - q / 1e-3 - 100.0 * zv) / 0.05).exp() - 1.0) - zv;
    assert!((r - want).abs() <= 1e-13 * want.abs(), "{r} vs {want}");
    // The printers show it.
    let text = to_text(&eqs);
    assert!(
        text.contains(
            "algebraic loops, solved numerically (Newton's method):\n  solve for loop_f_diode: 0 = "
        ),
        "{text}"
    );
    assert!(to_latex(&eqs).contains("% algebraic loop, solved numerically for loop_f_diode"));
    let json = to_json(&eqs);
    assert_eq!(json["tear_blocks"][0]["tears"][0], "loop_f_diode");
    assert!(
        json["tear_blocks"][0]["residuals"][0]
            .as_str()
            .is_some_and(|r| r.contains("exp(")),
        "{json}"
    );
}

#[test]
fn the_loop_is_solved_at_a_point_as_brentq_solves_it() {
    // q = 1e-4 C, u = 1 V: u - q/C = 0.9 = R_s i + V_t ln(1 + i/I_s). scipy:
    //   brentq(lambda i: Is*(np.exp((u0 - q0/C - R*i)/Vt) - 1) - i, -Is, 1.0, xtol=1e-300, rtol=1e-15)
    //   = 0.004765333667421019
    let eqs = diode_rc();
    let value = |s: Sym| match s {
        Sym::Param(i) => PARAMS.get(i).copied(),
        Sym::State(0) => Some(1e-4),
        Sym::Input(0) => Some(1.0),
        Sym::Time => Some(0.0),
        _ => None,
    };
    let z = solve_all(&eqs, &value).expect("solves");
    assert_eq!(z.len(), 1);
    // The Newton tolerance (1e-12 of the residual's terms, about 2 i) over |dr/di| = 1 + R_s g' = 10.5 bounds the
    // error by 1e-15.
    assert!((z[0].1 - 0.004765333667421019).abs() < 2e-15, "{z:?}");
    // Reverse bias: the current is -I_s to within exp(-(0.1 + 3)/V_t) ~ 1e-27.
    let reverse = |s: Sym| match s {
        Sym::Input(0) => Some(-3.0),
        other => value(other),
    };
    let z = solve_all(&eqs, &reverse).expect("solves");
    assert!((z[0].1 + 1e-6).abs() < 1e-20, "{z:?}");
}

#[test]
fn linearisation_follows_the_implicit_function_theorem() {
    // With g(v) = I_s (exp(v/V_t) - 1), g' = (i + I_s)/V_t at the solution, differentiating
    // u - q/C = R_s i + v_d and i = g(v_d):
    //   di/dq = -g'/(C (1 + R_s g')) = A,   di/du = g'/(1 + R_s g') = B,
    //   dv_d/dq = -R_s A - 1/C,              dv_d/du = 1 - R_s B.
    // At q = 1e-4, u = 1 with i from brentq (above):
    //   gp = (i0 + Is)/Vt; A = -gp/(C*(1 + R*gp)); B = gp/(1 + R*gp)
    //   = -9.050572881294748, 0.009050572881294747; -R*A - 1/C = -94.94271187052516; 1 - R*B = 0.09494271187052528
    let eqs = diode_rc();
    let ss =
        linearise(&eqs, StateSelection::Energy, &PARAMS, &[1e-4], &[1.0], 0.0).expect("linearises");
    let close = |got: f64, want: f64| (got - want).abs() <= 1e-9 * want.abs();
    assert!(close(ss.a[0][0], -9.050572881294748), "{ss:?}");
    assert!(close(ss.b[0][0], 0.009050572881294747), "{ss:?}");
    assert_eq!(ss.outputs, ["i", "v_d"]);
    assert!(close(ss.c[0][0], -9.050572881294748), "{ss:?}");
    assert!(close(ss.c[1][0], -94.94271187052516), "{ss:?}");
    assert!(close(ss.d[0][0], 0.009050572881294747), "{ss:?}");
    assert!(close(ss.d[1][0], 0.09494271187052528), "{ss:?}");
    // The same by central differences of the loop's solution, as a check of the theorem itself.
    let current = |q: f64, u: f64| {
        let value = |s: Sym| match s {
            Sym::Param(i) => PARAMS.get(i).copied(),
            Sym::State(0) => Some(q),
            Sym::Input(0) => Some(u),
            _ => None,
        };
        solve_all(&eqs, &value).expect("solves")[0].1
    };
    let h = 1e-9;
    let fd_a = (current(1e-4 + h, 1.0) - current(1e-4 - h, 1.0)) / (2.0 * h);
    assert!(
        (fd_a - ss.a[0][0]).abs() < 1e-5 * ss.a[0][0].abs(),
        "{fd_a}"
    );
}

#[test]
fn symbolic_state_spaces_refuse_the_loop() {
    let eqs = diode_rc();
    match linear_state_space(&eqs, StateSelection::Energy) {
        Err(LinearError::NotLinear { entry, symbol, .. }) => {
            assert_eq!(entry, "the rate of `q_cap`");
            assert_eq!(symbol, "loop_f_diode");
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        numeric_state_space(&eqs, StateSelection::Energy, &PARAMS),
        Err(LinearError::NotLinear { .. })
    ));
    let err = jacobians(&eqs, StateSelection::Energy).expect_err("no closed form");
    assert!(matches!(err, LinearError::ImplicitLoop { .. }));
    assert!(err.to_string().contains("`loop_f_diode`"), "{err}");
}

#[test]
fn a_loop_without_a_solution_at_the_operating_point_is_an_error() {
    // A one-way conductance f = k e^2 in series with R_s and C: i = k (u - q/C - R_s i)^2 has no real root when
    // u - q/C < -1/(4 R_s k); with R_s = k = C = 1, q = 0 and u = -10, i^2 + 19 i + 100 = 0.
    let text = include_str!("fixtures/loops/valve_loop.bg");
    let mut sources = SourceMap::new();
    let root = sources.add("valve_loop.bg", text);
    let (models, _) = lower(&mut sources, root, &mut MemoryLoader::new());
    let (causality, _) = analyse(&models[0]);
    let (eqs, diags) = derive(&models[0], &causality);
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    let p = eqs.default_params();
    let err = linearise(&eqs, StateSelection::Energy, &p, &[0.0], &[-10.0], 0.0)
        .expect_err("no solution");
    assert!(
        matches!(&err, LinearError::LoopNotSolved { tears, .. } if tears == "`loop_f_valve`"),
        "{err:?}"
    );
    // The smallest |r| over real i is 100 - 19^2/4 = 9.75, where the damped iteration stops.
    assert!(err.to_string().contains("largest residual 9.75"), "{err}");
    // At u = 0.5 the loop has a solution, i = a + 1/2 - sqrt(a + 1/4) for a = u - q/C = 0.5 (the smaller root).
    let ss = linearise(&eqs, StateSelection::Energy, &p, &[0.0], &[0.5], 0.0).expect("solves");
    // di/dq = -di/da = -(1 - 1/(2 sqrt(a + 1/4))) at a = 0.5.
    let want = -(1.0 - 0.5 / 0.75f64.sqrt());
    assert!(
        (ss.a[0][0] - want).abs() < 1e-12,
        "{} vs {want}",
        ss.a[0][0]
    );
}

#[test]
fn code_generation_solves_the_tear_block_in_the_generated_module() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/corpus/diode_rc.bg");
    let text = std::fs::read_to_string(path).expect("corpus file");
    let mut sources = SourceMap::new();
    let root = sources.add("diode_rc.bg", text);
    let file = match bgc::codegen::compile(&mut sources, root, &mut MemoryLoader::new()) {
        Ok(file) => file,
        Err(diags) => panic!("{diags:?}"),
    };
    let code = bgc::codegen::rust::generate(&file, "diode_rc.bg");
    assert!(!code.contains("compile_error!"), "{code}");
    for item in [
        "pub const N_TEARS: usize = 1;",
        "pub const TEAR_NAMES: [&str; N_TEARS] = [\"loop_f_diode\"];",
        "pub fn solve_loops(p: &Params, t: f64, x: &State, u: &Inputs) -> Result<Tears, LoopError> {",
        "fn bgc_newton<const B: usize>(",
        "    let z = loop_values(p, t, x, u);",
        // The Jacobians go through the loop: dz/dx = −(∂r/∂z)⁻¹ ∂r/∂x.
        "    let dz_0 = bgc_solve(rz_0, rv_0);",
    ] {
        assert!(code.contains(item), "missing `{item}`");
    }
}

/// The cart-pole I-field of fixtures/fields/cart_pole_field.bg with a resistive network on the cart that holds a
/// nonlinear algebraic loop: a damper `b` in series with a nonlinear damper `rp1` (`e = b f + b v0 tanh(f/v0)`)
/// that is in parallel with two dampers `b` and `2 b` in series.
fn cart_pole_behind_a_loop() -> Equations {
    derived("cart_pole_loop.bg", cart_pole_behind_a_loop_text())
}

/// The text of [`cart_pole_behind_a_loop`].
pub(crate) fn cart_pole_behind_a_loop_text() -> String {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/fields/cart_pole_field.bg"
    );
    std::fs::read_to_string(path).expect("fixture").replace(
        "    output angle",
        "    param b = 0.5 [N s/m];\n    param v0 = 1 [m/s];\n    \
         1 s1; R rs1 = b; 0 n1; R rp1 { e = b*f + b*v0*tanh(f/v0); }\n    \
         1 s2; R rs2 = b; 0 n2; R rp2 = 2*b;\n    \
         bond cart -> s1; bond s1 -> rs1; bond s1 -> n1; bond n1 -> rp1;\n    \
         bond n1 -> s2; bond s2 -> rs2; bond s2 -> n2; bond n2 -> rp2;\n    output angle",
    )
}

/// The rates of the cart-pole behind the loop, by hand: the network's force on the cart is `b v + e`, where the
/// effort `e` across the parallel pair solves `e = g(v − e/(3 b))`; then `M(θ) [v̇; ω̇] = [m l ω² sin θ + F − b v − e;
/// −m g l sin θ]` with `M = [[M + m, m l cos θ], [m l cos θ, m l²]]`. States `[x, θ, v, ω]`.
fn cart_pole_rates(x: &[f64; 4], force: f64) -> [f64; 4] {
    let (big_m, m, l, g, b, v0) = (2.0, 0.5, 0.6, 9.81, 0.5, 1.0);
    let [_, theta, v, w] = *x;
    let gain = |f: f64| b * f + b * v0 * (f / v0).tanh();
    // Bisection on e between 0 and the effort with the pair's other branch open (a bracket of the root).
    let residual = |e: f64| gain(v - e / (3.0 * b)) - e;
    let (mut lo, mut hi) = (0.0_f64, gain(v));
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if (residual(mid) > 0.0) == (residual(lo) > 0.0) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let e = 0.5 * (lo + hi);
    let f1 = m * l * w * w * theta.sin() + force - b * v - e;
    let f2 = -m * g * l * theta.sin();
    let (m11, m12, m22) = (big_m + m, m * l * theta.cos(), m * l * l);
    let det = m11 * m22 - m12 * m12;
    [
        v,
        w,
        (m22 * f1 - m12 * f2) / det,
        (m11 * f2 - m12 * f1) / det,
    ]
}

/// A model with a mass matrix and a nonlinear loop is linearised in its rates, not its generalised forces: `A` and
/// `B` equal central differences of the hand-derived rates, and the sparse linearisation gives the same numbers.
#[test]
fn a_mass_matrix_behind_a_loop_is_linearised_in_the_rates() {
    use bgc::equations::{ModelRows, SparseNumericStateSpace, linearise_sparse, state_selection};
    let eqs = cart_pole_behind_a_loop();
    assert!(!eqs.mass.is_empty() && !eqs.tear_blocks.is_empty());
    let names: Vec<&str> = eqs.states.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["q_body_1", "q_body_2", "f_body_1", "f_body_2"]);
    let params = eqs.default_params();
    let rows = ModelRows::new(&eqs);
    let selection = state_selection(&eqs, &rows);
    for (x0, u0) in [([0.1, 0.3, 0.7, -0.4], 0.5), ([0.0, -1.2, -0.2, 0.9], -1.0)] {
        let ss = linearise(&eqs, selection, &params, &x0, &[u0], 0.0).expect("linearises");
        let h = 1e-6;
        for k in 0..5 {
            let (mut up, mut down) = ((x0, u0), (x0, u0));
            if k < 4 {
                up.0[k] += h;
                down.0[k] -= h;
            } else {
                up.1 += h;
                down.1 -= h;
            }
            let (fu, fd) = (
                cart_pole_rates(&up.0, up.1),
                cart_pole_rates(&down.0, down.1),
            );
            for i in 0..4 {
                let want = (fu[i] - fd[i]) / (2.0 * h);
                let got = if k < 4 { ss.a[i][k] } else { ss.b[i][0] };
                assert!(
                    (got - want).abs() < 1e-6 * (1.0 + want.abs()),
                    "d rate {i} / d column {k} at {x0:?}: {got} vs {want}"
                );
            }
        }
        let sparse = linearise_sparse(&eqs, &rows, selection, (&params, &x0, &[u0], 0.0))
            .expect("linearises");
        assert_eq!(sparse, SparseNumericStateSpace::from_dense(&ss));
    }
}

/// The diagnostics of deriving the single model of `text`, each as its code and the source text its primary label
/// marks.
fn derive_findings(text: &str) -> Vec<(String, String)> {
    let mut sources = SourceMap::new();
    let root = sources.add("m.bg", text);
    let (models, diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    let (causality, _) = analyse(&models[0]);
    let (_, diags) = derive(&models[0], &causality);
    diags
        .iter()
        .filter(|d| d.is_error())
        .map(|d| {
            let marked = d.primary_span().map_or("", |s| sources.snippet(s));
            (d.code.0.to_string(), marked.to_string())
        })
        .collect()
}

/// A singular loop (loop gain one: `u = R1 i − R1 i`) leaves the current undetermined, and a stroke that puts both
/// storages of an LC circuit in derivative causality leaves no state to find it from. Neither model has an output
/// or a rate that reads the undetermined variables, only the energy terms do: the model is still refused, with one
/// error at the loop or the storage, as it is when an output reads them (and then only once).
#[test]
fn a_variable_only_the_energy_terms_read_is_refused_when_it_is_undetermined() {
    let singular = "model m { domain electrical; param R1 = 1 [Ohm]; input u [V]; Se a = u; 1 j; R r1 = R1; \
                    R r2 { e = -R1 * f; } bond a -> j -> r1, r2; OUTPUT }";
    let chain = "model m { domain electrical; input u [V]; Se a = u; 1 j; I i = 2; C c = 0.25; \
                 bond a -> j -> i; bond j -> c stroke c; OUTPUT }";
    for (text, output, code, at) in [
        (singular, "output i [A] = f(r1);", "BG0603", "R r1 = R1;"),
        (chain, "output vc [V] = e(c);", "BG0604", "I i = 2;"),
    ] {
        let without = derive_findings(&text.replace("OUTPUT", ""));
        assert_eq!(without, [(code.to_string(), at.to_string())], "{text}");
        let with = derive_findings(&text.replace("OUTPUT", output));
        assert_eq!(with.len(), 1, "{with:?}");
        assert_eq!(with[0].0, code, "{with:?}");
    }
}
