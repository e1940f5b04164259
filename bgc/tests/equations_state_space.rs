//! The linear state space never drops a term and accepts every linear model:
//! - a source whose value is a signal of time (`Se mains = V0*sin(w*t);`) is refused with an error naming it and
//!   saying how to make it an input (it used to vanish: A and B for the other input alone);
//! - an I-field with a constant inertia matrix (coupled coils) is linear: `M ḟ = F` gives `A = M⁻¹ ∂F/∂x`, checked
//!   against the hand-derived 2×2 inverse.

use bgc::causality::analyse;
use bgc::equations::{
    Equations, LinearError, StateSelection, derive, linear_state_space, numeric_state_space,
};
use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;

fn equations_of(text: &str) -> Equations {
    let mut sources = SourceMap::new();
    let root = sources.add("model.bg", text);
    let (models, mut diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert_eq!(models.len(), 1, "{diags:?}");
    let (causality, cdiags) = analyse(&models[0]);
    diags.extend(cdiags);
    let (eqs, ediags) = derive(&models[0], &causality);
    diags.extend(ediags);
    assert!(!bgc::diagnostic::has_errors(&diags), "{diags:?}");
    eqs
}

#[test]
fn a_signal_of_time_is_refused_by_name() {
    let eqs = equations_of(
        "
model mains {
    domain electrical;
    param V0 = 230 [V];
    param w = 314 [rad/s];
    param L = 0.1 [H];
    param Rl = 5 [Ohm];
    input u [V];
    Se mains = V0*sin(w*t);
    Se drive = u;
    1 loop;
    I coil = L;
    R res = Rl;
    bond mains -> loop -> coil, res;
    bond drive -> loop;
}
",
    );
    assert_eq!(eqs.time_signals, ["mains"]);
    match linear_state_space(&eqs, StateSelection::Energy) {
        Err(e @ LinearError::TimeDependent { .. }) => {
            let msg = e.to_string();
            assert!(msg.contains("`mains`"), "{msg}");
            assert!(msg.contains("input"), "{msg}");
        }
        other => panic!("expected a refusal naming `mains`, got {other:?}"),
    }
    assert!(numeric_state_space(&eqs, StateSelection::Energy, &eqs.default_params()).is_err());
}

#[test]
fn coupled_coils_with_a_constant_matrix_are_linear() {
    let eqs = equations_of(
        "
model coils {
    domain electrical;
    param L1 = 0.2 [H];
    param L2 = 0.3 [H];
    param Lm = 0.1 [H];
    param R1 = 2 [Ohm];
    param R2 = 3 [Ohm];
    input u [V];
    Se drive = u;
    1 l1;
    1 l2;
    IF coupled(2) {
        mass[1, 1] = L1;
        mass[1, 2] = Lm;
        mass[2, 2] = L2;
    }
    R r1 = R1;
    R r2 = R2;
    bond drive -> l1 -> coupled[1];
    bond l1 -> r1;
    bond l2 -> coupled[2];
    bond l2 -> r2;
}
",
    );
    let names: Vec<&str> = eqs.states.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        ["q_coupled_1", "q_coupled_2", "f_coupled_1", "f_coupled_2"]
    );
    let ss = numeric_state_space(&eqs, StateSelection::Energy, &eqs.default_params())
        .unwrap_or_else(|e| panic!("a constant inertia matrix is linear: {e}"));
    // M ḟ = [u − R1 f1, −R2 f2]; M⁻¹ = [[L2, −Lm], [−Lm, L1]] / (L1 L2 − Lm²).
    let (l1, l2, lm, r1, r2) = (0.2, 0.3, 0.1, 2.0, 3.0);
    let det = l1 * l2 - lm * lm;
    let inv = [[l2 / det, -lm / det], [-lm / det, l1 / det]];
    let want_a = [
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
        [0.0, 0.0, -inv[0][0] * r1, -inv[0][1] * r2],
        [0.0, 0.0, -inv[1][0] * r1, -inv[1][1] * r2],
    ];
    let want_b = [0.0, 0.0, inv[0][0], inv[1][0]];
    assert_eq!((ss.a.len(), ss.b.len()), (4, 4));
    for (r, (row, want_row)) in ss.a.iter().zip(&want_a).enumerate() {
        for (c, (got, want)) in row.iter().zip(want_row).enumerate() {
            assert!((got - want).abs() < 1e-12, "A[{r}][{c}] = {got} vs {want}");
        }
    }
    for (r, (row, want)) in ss.b.iter().zip(&want_b).enumerate() {
        assert!(
            (row[0] - want).abs() < 1e-12,
            "B[{r}] = {} vs {want}",
            row[0]
        );
    }
}

/// A mass on a spring with its position `x = ∫ f(mass)` declared as a coordinate beside the spring's deflection:
/// `x − q` is constant (both integrate the one flow), but three coordinates for the three states in play are a
/// plain change of variables. Numeric and symbolic paths give the hand-derived `ẋ = v`, `m v̇ = F − d v − k q`,
/// `q̇ = v` (the symbolic one used to eliminate the invariant and refuse the map as not invertible).
#[test]
fn as_many_declared_coordinates_as_states_are_a_change_of_variables_whatever_the_invariants() {
    let eqs = equations_of(
        "model osc { domain translational; param m = 2 [kg]; param k = 8 [N/m]; param d = 1 [N s/m];
         input F [N]; Se push = F; 1 v; I mass = m; C spring = 1 / k; R damper = d;
         var x [m] = int(f(mass)); bond push -> v -> mass, spring, damper;
         coords [x, f(mass), q(spring)]; output pos [m] = x; }",
    );
    let (m, k, d) = (2.0, 8.0, 1.0);
    let a = [[0.0, 1.0, 0.0], [0.0, -d / m, -k / m], [0.0, 1.0, 0.0]];
    let b = [0.0, 1.0 / m, 0.0];
    let p = eqs.default_params();
    let numeric = bgc::equations::declared_state_space(&eqs, &p).expect("numeric");
    let symbolic = bgc::equations::declared_state_space_symbolic(&eqs).expect("symbolic");
    let symbolic = bgc::equations::evaluate_at(&eqs, &symbolic, &p, &[0.0; 3], &[0.0], 0.0)
        .expect("evaluated");
    for ss in [numeric, symbolic] {
        assert_eq!(ss.states, ["x", "f_mass", "q_spring"]);
        for r in 0..3 {
            assert_eq!(ss.a[r], a[r], "A row {r}");
            assert_eq!(ss.b[r], [b[r]], "B row {r}");
        }
        assert_eq!(ss.c, [[1.0, 0.0, 0.0]]);
    }
}

/// A coefficient that varies with time (`MSe src = u*cos(w*t)`: `B = cos(w t)/R`) is not a nonlinearity in the
/// states or inputs: the refusal says the model is time-varying and names the element, where it used to say "not
/// linear" and ask for an operating point as if a state were to blame. A term in `t` that no element's value holds
/// (an output's own) is named once, not "a value that uses `t`, whose value uses `t`".
#[test]
fn a_time_varying_coefficient_and_a_signal_written_into_an_output_are_named_as_such() {
    let eqs = equations_of(
        "model m { domain electrical; param w = 2 [rad/s]; input u [V]; MSe src = u * cos(w * t); 1 j;
         R r = 2; C c = 0.5; bond src -> j -> r, c; }",
    );
    let rows = bgc::equations::ModelRows::new(&eqs);
    for result in [
        linear_state_space(&eqs, StateSelection::Energy).map(|_| ()),
        bgc::equations::sparse_linear_state_space(&eqs, &rows, StateSelection::Energy).map(|_| ()),
    ] {
        match result {
            Err(e @ LinearError::TimeVarying { .. }) => {
                let msg = e.to_string();
                assert!(
                    msg.contains("B[0][0] depends on `t` through `src`"),
                    "{msg}"
                );
            }
            other => panic!("expected a time-varying model, got {other:?}"),
        }
    }
    let eqs = equations_of(
        "model m { domain electrical; param w = 2 [rad/s]; param V0 = 3 [V]; input u [V]; Se src = u; 1 j;
         R r = 2; C c = 0.5; bond src -> j -> r, c; output y [V] = e(c) + V0 * sin(w * t); }",
    );
    match linear_state_space(&eqs, StateSelection::Energy) {
        Err(e @ LinearError::TimeDependent { .. }) => {
            let msg = e.to_string();
            assert!(
                msg.contains("output `y` depends on time through a term written with `t`:"),
                "{msg}"
            );
        }
        other => panic!("expected a refusal of the signal in `y`, got {other:?}"),
    }
}
