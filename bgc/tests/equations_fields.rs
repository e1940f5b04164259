//! Multiport fields: an I-field with a configuration-dependent inertia matrix (mass-matrix form), a C-field and an
//! R-field, against hand-derived equations of motion and the energy balance in simulation; and the errors for
//! what the equations stage does not support.

use bgc::causality::analyse;
use bgc::diagnostic::Diagnostic;
use bgc::equations::symbols::{self as sym, Sym};
use bgc::equations::{EnergyKind, Equations, derive, to_text};
use bgc::lower::{MemoryLoader, lower};
use bgc::simulate::System;
use bgc::simulate::input::Signal;
use bgc::simulate::integrate::{Method, RunOptions, run};
use bgc::span::SourceMap;
use std::path::Path;

fn equations_of_text(name: &str, text: String) -> (Equations, Vec<Diagnostic>) {
    let mut sources = SourceMap::new();
    let root = sources.add(name.to_string(), text);
    let (models, mut diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert_eq!(models.len(), 1, "{name}: {diags:?}");
    let (causality, cdiags) = analyse(&models[0]);
    diags.extend(cdiags);
    let (eqs, ediags) = derive(&models[0], &causality);
    diags.extend(ediags);
    (eqs, diags)
}

fn fixture(name: &str) -> (Equations, Vec<Diagnostic>) {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/fixtures/fields/{name}.bg"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    equations_of_text(&format!("{name}.bg"), text)
}

fn errors(diags: &[Diagnostic]) -> Vec<String> {
    diags
        .iter()
        .filter(|d| d.is_error())
        .map(|d| format!("{}: {}", d.code.0, d.message))
        .collect()
}

fn param(eqs: &Equations, name: &str) -> f64 {
    eqs.params
        .iter()
        .find(|p| p.0 == name)
        .map(|p| p.1)
        .unwrap_or_else(|| panic!("no parameter {name}"))
}

/// A small deterministic generator for test points.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

#[test]
fn double_pendulum_matches_the_textbook_equations() {
    let (eqs, diags) = fixture("double_pendulum");
    assert!(errors(&diags).is_empty(), "{diags:?}");
    insta::assert_snapshot!("field_double_pendulum_text", to_text(&eqs));
    let (m1, m2, l1, l2, g) = (
        param(&eqs, "m1"),
        param(&eqs, "m2"),
        param(&eqs, "l1"),
        param(&eqs, "l2"),
        param(&eqs, "g"),
    );
    let p = eqs.default_params();
    let mut rng = Lcg(11);
    for _ in 0..100 {
        let x: Vec<f64> = (0..4)
            .map(|i| if i < 2 { 3.0 } else { 5.0 } * rng.next())
            .collect();
        let tau = 10.0 * rng.next();
        let dx = eqs
            .rates_at(&p, &x, &[tau], 0.0)
            .unwrap_or_else(|e| panic!("{e}"));
        // (m1+m2) l1 θ1'' + m2 l2 cos Δ θ2'' = τ/l1 − m2 l2 θ2'² sin Δ − (m1+m2) g sin θ1
        // l1 cos Δ θ1'' + l2 θ2'' = l1 θ1'² sin Δ − g sin θ2,   Δ = θ1 − θ2; solved by Cramer's rule.
        let (t1, t2, w1, w2) = (x[0], x[1], x[2], x[3]);
        let d = t1 - t2;
        let (a, b, c, e) = ((m1 + m2) * l1, m2 * l2 * d.cos(), l1 * d.cos(), l2);
        let r1 = tau / l1 - m2 * l2 * w2 * w2 * d.sin() - (m1 + m2) * g * t1.sin();
        let r2 = l1 * w1 * w1 * d.sin() - g * t2.sin();
        let det = a * e - b * c;
        let want = [w1, w2, (r1 * e - b * r2) / det, (a * r2 - c * r1) / det];
        for (k, (got, want)) in dx.iter().zip(want).enumerate() {
            assert!(
                (got - want).abs() <= 1e-12 * (1.0 + want.abs()),
                "rate {k} at {x:?}: bgc {got}, textbook {want}"
            );
        }
    }
}

fn simulate(
    eqs: &Equations,
    params: Vec<f64>,
    inputs: &[&str],
    x0: &[f64],
    t_end: f64,
) -> Vec<Vec<f64>> {
    let signals = inputs
        .iter()
        .map(|s| Signal::parse(s).unwrap_or_else(|e| panic!("{s}: {e}")))
        .collect();
    let (system, warnings) = System::new(eqs, params, signals).unwrap_or_else(|e| panic!("{e}"));
    assert!(warnings.is_empty(), "{warnings:?}");
    let opts = RunOptions {
        t_end,
        dt_out: t_end / 200.0,
        method: Method::Tsit45,
        rtol: 1e-11,
        atol: 1e-13,
        max_steps: 10_000_000,
        max_step: None,
    };
    run(&system, x0, &opts)
        .unwrap_or_else(|e| panic!("{e}"))
        .rows
}

/// The last three columns of a row: stored energy, dissipated and supplied energy.
fn balance(row: &[f64]) -> (f64, f64, f64) {
    let n = row.len();
    (row[n - 3], row[n - 2], row[n - 1])
}

#[test]
fn double_pendulum_keeps_its_energy_balance() {
    let (eqs, _) = fixture("double_pendulum");
    // Without gravity the kinetic energy is conserved; with it, the work of the weights (supplied by the modulated
    // sources) balances it. Ten periods of the slower small-oscillation mode (about 1.9 s each).
    let p = eqs.default_params();
    let mut p0 = p.clone();
    p0[4] = 0.0;
    assert_eq!(eqs.params[4].0, "g");
    for (params, gravity) in [(p0, false), (p, true)] {
        let rows = simulate(&eqs, params, &["0"], &[1.0, -0.5, 2.0, -3.0], 20.0);
        let (e0, _, _) = balance(&rows[0]);
        assert!(e0 > 1.0);
        for row in &rows {
            let (e, dissipated, supplied) = balance(row);
            assert_eq!(dissipated, 0.0);
            if !gravity {
                assert_eq!(supplied, 0.0);
            }
            let drift = (e + dissipated - supplied - e0).abs() / e0;
            assert!(drift < 1e-8, "gravity {gravity}: relative drift {drift}");
        }
    }
}

#[test]
fn c_field_and_r_field_match_hand_derived_equations_and_balance_energy() {
    let (eqs, diags) = fixture("coupled_springs");
    assert!(errors(&diags).is_empty(), "{diags:?}");
    insta::assert_snapshot!("field_coupled_springs_text", to_text(&eqs));
    let names: Vec<&str> = eqs.states.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["p_mass1", "p_mass2", "q_springs_1", "q_springs_2"]);
    let v = |n: &str| param(&eqs, n);
    let (m1, m2, k1, k2, k3) = (v("m1"), v("m2"), v("k1"), v("k2"), v("k3"));
    let (r11, r12, r22) = (v("r11"), v("r12"), v("r22"));
    let p = eqs.default_params();
    let mut rng = Lcg(5);
    for _ in 0..50 {
        let x: Vec<f64> = (0..4).map(|_| rng.next()).collect();
        let force = rng.next();
        let dx = eqs
            .rates_at(&p, &x, &[force], 0.0)
            .unwrap_or_else(|e| panic!("{e}"));
        let (v1, v2, x1, x2) = (x[0] / m1, x[1] / m2, x[2], x[3]);
        let want = [
            force - (k1 + k3) * x1 + k3 * x2 - r11 * v1 - r12 * v2,
            -(k2 + k3) * x2 + k3 * x1 - r12 * v1 - r22 * v2,
            v1,
            v2,
        ];
        for (k, (got, want)) in dx.iter().zip(want).enumerate() {
            assert!(
                (got - want).abs() < 1e-12 * (1.0 + want.abs()),
                "rate {k}: {got} vs {want}"
            );
        }
        // Stored energy of the C-field: ½ qᵀ K q.
        let stored = eqs
            .energy
            .iter()
            .find(|t| t.element == "springs" && t.kind == EnergyKind::Stored)
            .and_then(|t| t.value.clone())
            .unwrap_or_else(|| panic!("no stored energy of the C-field"));
        let e = sym::eval(&stored, &|s| match s {
            Sym::Param(i) => p.get(i).copied(),
            Sym::State(i) => x.get(i).copied(),
            _ => None,
        })
        .unwrap_or_else(|e| panic!("{e:?}"));
        let want = 0.5 * ((k1 + k3) * x1 * x1 - 2.0 * k3 * x1 * x2 + (k2 + k3) * x2 * x2);
        assert!(
            (e - want).abs() < 1e-12 * want.abs().max(1e-12),
            "{e} vs {want}"
        );
    }
    // Driven and damped: stored + dissipated − supplied stays at its start.
    let rows = simulate(&eqs, p, &["5*sin(3*t)"], &[0.2, -0.1, 0.01, 0.02], 10.0);
    let (e0, _, _) = balance(&rows[0]);
    let last = balance(rows.last().unwrap_or_else(|| panic!("no rows")));
    assert!(
        last.1 > 0.01 && last.2.abs() > 0.01,
        "the run did something: {last:?}"
    );
    for row in &rows {
        let (e, d, s) = balance(row);
        assert!(
            (e + d - s - e0).abs() < 1e-8 * (e0 + d.abs() + s.abs()),
            "{e} + {d} - {s} vs {e0}"
        );
    }
}

#[test]
fn i_field_in_derivative_causality_is_refused_with_its_place() {
    let (_, diags) = fixture("field_derivative");
    let d = diags
        .iter()
        .find(|d| d.is_error())
        .unwrap_or_else(|| panic!("no error: {diags:?}"));
    assert_eq!(d.code.0, "BG0605");
    assert!(
        d.message.contains("`body`") && d.message.contains("derivative causality"),
        "{}",
        d.message
    );
    assert!(d.primary_span().is_some(), "no place: {d:?}");
}

#[test]
fn inertia_matrix_that_depends_on_an_input_is_refused() {
    let text = "model m { domain translational; input u [1]; 1 j1; 1 j2; Se s = 1;
        IF body(2) { mass[1,1] = 2 + u; mass[2,2] = 1; }
        bond s -> j1 -> body[1]; bond j2 -> body[2]; }";
    let (_, diags) = equations_of_text("input_mass.bg", text.into());
    let errs = errors(&diags);
    assert!(
        errs.iter()
            .any(|e| e.starts_with("BG0605") && e.contains("own port displacements")),
        "{errs:?}"
    );
}

#[test]
fn non_conservative_c_field_gets_no_energy_and_a_warning() {
    let text =
        "model m { domain translational; param a = 1 [kg]; param k = 10 [N/m]; param c = 3 [N/m];
        param d = 5 [N/m]; 1 j1; 1 j2; I m1 = a; I m2 = a;
        CF spring(2) { e[1] = k*q[1] - c*q[2]; e[2] = k*q[2] - d*q[1]; }
        bond j1 -> m1; bond j2 -> m2; bond j1 -> spring[1]; bond j2 -> spring[2]; }";
    let (eqs, diags) = equations_of_text("asymmetric.bg", text.into());
    assert!(errors(&diags).is_empty(), "{diags:?}");
    assert!(
        diags
            .iter()
            .any(|d| d.code.0 == "BG0607" && d.message.contains("symmetric")),
        "{diags:?}"
    );
    let term = eqs.energy.iter().find(|t| t.element == "spring");
    assert_eq!(term.map(|t| t.value.is_none()), Some(true));
}

/// models/walking_leg.bg without friction, stiffness or actuation: over 5 s of large swinging (several periods of
/// the leg as a pendulum), the kinetic energy plus the work done against gravity (the modulated gravity sources'
/// supplied energy, counted negative when they take energy) stays at its start; without gravity the kinetic
/// energy alone is conserved.
#[test]
fn walking_leg_conserves_energy_when_frictionless_and_unactuated() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/walking_leg.bg");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (eqs, diags) = equations_of_text("walking_leg.bg", text);
    assert!(errors(&diags).is_empty(), "{diags:?}");
    let names: Vec<&str> = eqs.params.iter().map(|p| p.0.as_str()).collect();
    let zero = [
        "b0_knee", "b2_knee", "k_knee", "ts0_knee", "b0_hip", "b2_hip", "k_hip", "ts0_hip",
    ];
    for gravity in [true, false] {
        let given: Vec<Option<f64>> = names
            .iter()
            .map(|n| (zero.contains(n) || (!gravity && *n == "g")).then_some(0.0))
            .collect();
        let p = eqs.param_values(&given);
        let inputs = vec!["0"; eqs.inputs.len()];
        let rows = simulate(&eqs, p, &inputs, &[0.2, 0.5, 0.6, 1.0, -2.0, 2.0], 5.0);
        let (e0, _, _) = balance(&rows[0]);
        let mut moved = 0.0f64;
        for row in &rows {
            let (e, d, s) = balance(row);
            assert_eq!(d, 0.0);
            moved = moved.max(s.abs());
            let drift = (e + d - s - e0).abs() / e0;
            assert!(
                drift < 1e-8,
                "gravity {gravity}: relative drift {drift} at {row:?}"
            );
        }
        // With gravity the weights exchange energy with the chain; without, they do nothing.
        assert_eq!(moved > 0.1 * e0, gravity, "exchanged {moved} of {e0}");
    }
}
