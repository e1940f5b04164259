//! Nonlinear laws, Jacobians and linearisation, energy balance, declared coordinates and their errors, JSON —
//! on models written in the language.

use crate::equations_support;

use bgc::causality::analyse;
use bgc::diagnostic::Diagnostic;
use bgc::equations::symbols::{self as sym, Sym};
use bgc::equations::{
    CoordsError, EnergyKind, Equations, LinearError, StateSelection, declared_state_space, derive,
    jacobians, linear_state_space, linearise, numeric_state_space, to_json,
};
use bgc::ir::Model;
use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;
use equations_support::{Rng, assert_close};

fn model(text: &str) -> Model {
    let mut sources = SourceMap::new();
    let root = sources.add("test.bg", text);
    let (mut models, diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    assert_eq!(models.len(), 1);
    models.remove(0)
}

fn equations(text: &str) -> (Equations, Vec<Diagnostic>, Model) {
    let m = model(text);
    let (causality, _) = analyse(&m);
    let (eqs, diags) = derive(&m, &causality);
    (eqs, diags, m)
}

const HARDENING: &str = r#"
model hardening {
    domain translational;
    param m = 2 [kg];
    param k = 800 [N/m];
    param k3 = 5e4 [N/m^3];
    param d = 4 [N s/m];
    input F [N];
    Se push = F;
    I  mass = m;
    C  spring { e = k*q + k3*q^3; }
    R  damper = d;
    1  v;
    bond push -> v -> mass, spring, damper;
    output x [m] = q(spring);
    coords [q(spring), f(mass)];
}
"#;

#[test]
fn hardening_spring_jacobians_and_linearisation() {
    let (eqs, diags, _) = equations(HARDENING);
    assert!(diags.is_empty(), "{diags:?}");
    // Not linear: the error names the entry and the state.
    match linear_state_space(&eqs, StateSelection::Energy) {
        Err(LinearError::NotLinear { symbol, .. }) => assert_eq!(symbol, "q_spring"),
        other => panic!("{other:?}"),
    }
    // ∂ṗ/∂q = -(k + 3 k3 q²): symbolic, then at an operating point.
    let j = jacobians(&eqs, StateSelection::Energy).expect("jacobians");
    let q_index = eqs
        .states
        .iter()
        .position(|s| s.name == "q_spring")
        .expect("q state");
    let p_index = 1 - q_index;
    let entry = &j.dfdx[p_index][q_index];
    let at = |q: f64| {
        move |s: Sym| match s {
            Sym::Param(0) => Some(2.0),
            Sym::Param(1) => Some(800.0),
            Sym::Param(2) => Some(5e4),
            Sym::State(i) if i == q_index => Some(q),
            _ => None,
        }
    };
    assert_eq!(sym::eval(entry, &at(0.1)), Ok(-(800.0 + 3.0 * 5e4 * 0.01)));
    // The same rate named for code generation evaluates to the same number.
    for (i, f) in eqs.f.iter().enumerate() {
        let f = f.as_ref().expect("rate");
        let shared = bgc::codegen::to_symbolic(&eqs, f).expect("convertible");
        let env = |s: &bgc::symbolic::Symbol| match s.name() {
            "m" => Some(2.0),
            "k" => Some(800.0),
            "k3" => Some(5e4),
            "d" => Some(4.0),
            "F" => Some(1.5),
            "q_spring" => Some(0.1),
            "p_mass" => Some(0.4),
            _ => None,
        };
        let ours =
            sym::eval(f, &|s| env(&bgc::symbolic::Symbol::param(eqs.sym_name(s)))).expect("eval");
        let theirs = shared.eval(env).expect("eval");
        assert!(
            (ours - theirs).abs() <= 1e-12 * ours.abs().max(1.0),
            "rate {i}: {ours} vs {theirs}"
        );
    }
    let mut x0 = vec![0.0; 2];
    x0[q_index] = 0.1;
    x0[p_index] = 0.4;
    let lin = linearise(
        &eqs,
        StateSelection::Energy,
        &eqs.default_params(),
        &x0,
        &[3.0],
        0.0,
    )
    .expect("linearise");
    assert!((lin.a[p_index][q_index] + 800.0 + 1500.0).abs() < 1e-9);
    assert!((lin.a[p_index][p_index] + 4.0 / 2.0).abs() < 1e-12);
    assert!((lin.a[q_index][p_index] - 0.5).abs() < 1e-12);
    // Stored energy of the law, integrated symbolically: k q²/2 + k3 q⁴/4.
    let stored = eqs
        .energy
        .iter()
        .find(|t| t.element == "spring")
        .and_then(|t| t.value.clone())
        .expect("energy");
    let v = sym::eval(&stored, &at(0.1)).unwrap_or(f64::NAN);
    assert!(
        (v - (800.0 * 0.01 / 2.0 + 5e4 * 1e-4 / 4.0)).abs() < 1e-12,
        "{v}"
    );
}

#[test]
fn energy_balance_holds_on_every_trajectory() {
    // dE/dt = Σ ∂E/∂x f(x, u) must equal supplied minus dissipated power, at any state and input: checked at random
    // points for a damped oscillator and for the gear train with two inertias in derivative causality.
    let gear_train = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/corpus/gear_train.bg"
    ))
    .expect("corpus file");
    for text in [HARDENING, gear_train.as_str()] {
        let (eqs, diags, _) = equations(text);
        assert!(diags.is_empty(), "{diags:?}");
        let n = eqs.energy_states;
        let mut rng = Rng(33);
        for _ in 0..5 {
            let x: Vec<f64> = (0..n).map(|_| rng.next() - 0.5).collect();
            let u: Vec<f64> = (0..eqs.inputs.len()).map(|_| rng.next() - 0.5).collect();
            let params = eqs.default_params();
            let value = |s: Sym| match s {
                Sym::Param(i) => params.get(i).copied(),
                Sym::State(i) => x.get(i).copied(),
                Sym::Input(i) => u.get(i).copied(),
                _ => None,
            };
            let mut de_dt = 0.0;
            let (mut supplied, mut dissipated) = (0.0, 0.0);
            for t in &eqs.energy {
                let e = t
                    .value
                    .as_ref()
                    .unwrap_or_else(|| panic!("{} has no energy expression", t.element));
                match t.kind {
                    EnergyKind::Stored => {
                        for i in 0..n {
                            let d = sym::diff(e, Sym::State(i)).expect("differentiable");
                            let f = eqs.f[i].as_ref().expect("rate");
                            de_dt += sym::eval(&d, &value).expect("eval")
                                * sym::eval(f, &value).expect("eval");
                        }
                    }
                    EnergyKind::Supplied => supplied += sym::eval(e, &value).expect("eval"),
                    EnergyKind::Dissipated => dissipated += sym::eval(e, &value).expect("eval"),
                }
            }
            let scale = supplied.abs().max(dissipated.abs()).max(de_dt.abs());
            assert!(
                (de_dt - (supplied - dissipated)).abs() <= 1e-9 * scale,
                "{}: {de_dt} vs {supplied} - {dissipated}",
                eqs.model
            );
        }
    }
}

#[test]
fn pendulum_agrees_with_lagrange() {
    // m l² θ̈ = -m g l sin θ - b θ̇. The bob's inertias are rigidly coupled to the pivot through `l cos θ` and
    // `l sin θ`, so the state is the pivot's angular velocity (mass-matrix form), not a bob momentum that would
    // give θ̇ = p_x/(m l cos θ), singular with the rod horizontal.
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/corpus/pendulum.bg"
    ))
    .expect("file");
    let (eqs, diags, _) = equations(&text);
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    let names: Vec<&str> = eqs.states.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["f_pivot", "theta"]);
    let (m, l, g, b) = (1.0, 0.5, 9.81, 0.01);
    let mut rng = Rng(3);
    let p = eqs.default_params();
    let mut points: Vec<(f64, f64)> = (0..5)
        .map(|_| (rng.next() - 0.5, (rng.next() - 0.5) * 2.0))
        .collect();
    points.push((0.7, std::f64::consts::FRAC_PI_2));
    for (w, th) in points {
        let rates = eqs.rates_at(&p, &[w, th], &[], 0.0).expect("rates");
        let lagrange = (-m * g * l * th.sin() - b * w) / (m * l * l);
        assert!((rates[1] - w).abs() < 1e-15);
        assert!(
            (rates[0] - lagrange).abs() < 1e-9 * lagrange.abs().max(1.0),
            "{} vs {lagrange}",
            rates[0]
        );
    }
}

#[test]
fn a_law_that_must_be_inverted_and_is_not_affine_is_an_error() {
    // The resistor hangs on the 0-junction of an effort source, so it receives the effort and must give its flow:
    // e = b0 sign(f) + b2 f cannot be solved for f.
    let text = r#"
model coulomb {
    domain translational;
    param b0 = 0.2 [N];
    param b2 = 0.1 [N s/m];
    param m = 3 [kg];
    input u [N];
    Se drive = u;
    0  node;
    R  friction { e = b0*sign(f) + b2*f; }
    1  v;
    I  mass = m;
    bond drive -> node -> friction;
    bond node -> v -> mass;
    output slip [m/s] = f(friction);
}
"#;
    let (_, diags, m) = equations(text);
    let err = diags
        .iter()
        .find(|d| d.code.0 == "BG0601")
        .unwrap_or_else(|| panic!("{diags:?}"));
    let friction = m.node_by_name("friction").expect("node");
    assert_eq!(
        err.primary_span(),
        m.spans.nodes.get(friction.index()).copied()
    );
    // The same resistor with an affine law is inverted: f = (e - b0)/b2.
    let affine = text.replace("b0*sign(f) + b2*f", "b0 + b2*f");
    let (eqs, diags, _) = equations(&affine);
    assert!(diags.is_empty(), "{diags:?}");
    let value = |s: Sym| match s {
        Sym::Param(i) => [0.2, 0.1, 3.0].get(i).copied(),
        Sym::State(0) => Some(0.7),
        Sym::Input(0) => Some(1.5),
        _ => None,
    };
    let slip = sym::eval(eqs.outputs[0].explicit.as_ref().expect("output"), &value).expect("eval");
    assert!((slip - (1.5 - 0.2) / 0.1).abs() < 1e-12, "{slip}");
    assert_eq!(eqs.f[0], Some(Sym::Input(0).expr()));
}

#[test]
fn square_declared_coordinates_are_a_similarity() {
    // z = [q, p/m]: ż = [[0, 1], [-k/m, -d/m]] z + [0, 1/m] F (with the linear spring).
    let text = HARDENING
        .replace("C  spring { e = k*q + k3*q^3; }", "C  spring = 1/k;")
        .replace("param k3 = 5e4 [N/m^3];", "");
    let (eqs, diags, _) = equations(&text);
    assert!(diags.is_empty(), "{diags:?}");
    let (m, k, d) = (2.0, 800.0, 4.0);
    let ss = declared_state_space(&eqs, &eqs.default_params()).expect("coords");
    assert_eq!(ss.states, ["q_spring", "f_mass"]);
    assert_close("A", &ss.a, &[vec![0.0, 1.0], vec![-k / m, -d / m]], 1e-12);
    assert_close("B", &ss.b, &[vec![0.0], vec![1.0 / m]], 1e-12);
    assert_close("C", &ss.c, &[vec![1.0, 0.0]], 1e-12);
    // The energy-coordinate model is the same system.
    let energy =
        numeric_state_space(&eqs, StateSelection::Energy, &eqs.default_params()).expect("linear");
    assert_eq!(energy.a.len(), 2);
    let json = to_json(&eqs);
    assert_eq!(json["states"][0]["name"], "p_mass");
    assert_eq!(json["coords"][1]["value"], "p_mass/m");
}

#[test]
fn declared_coordinates_that_do_not_determine_the_state_are_refused() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/back_support.bg"
    ))
    .expect("file");
    // Six of the seven coordinates: the trunk angle is missing.
    let short = text.replace(", theta_h];", "];");
    let (eqs, diags, _) = equations(&short);
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    match declared_state_space(&eqs, &eqs.default_params()) {
        // 6 energy states and 3 angles, tied by the 2 invariants of the gear and sensor springs: 7 dimensions.
        Err(CoordsError::NotInvertible {
            coords: 6,
            subspace: 7,
            invariants: 2,
        }) => {}
        other => panic!("{other:?}"),
    }
    // A coordinate that is not linear in the states.
    let squared = text.replace("f(rotor), theta_sint", "f(rotor)^2, theta_sint");
    let (eqs, diags, m) = equations(&squared);
    let err = diags
        .iter()
        .find(|d| d.code.0 == "BG0606")
        .unwrap_or_else(|| panic!("{diags:?}"));
    assert_eq!(err.primary_span(), m.spans.coords.get(1).copied());
    assert!(eqs.coords.is_none());
}
