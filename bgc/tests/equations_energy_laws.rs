//! Stored energy of storages whose law is written in the other form (`C { q = e/k; }`, `I { p = m*f; }`), in
//! integral and in derivative causality, and of a nonlinear inertia drawn the unusual way: every law the engine can
//! integrate has its energy, so that stored + dissipated − supplied stays constant.
//!
//! Hand derivation: `I { p = m f }` stores `p²/(2m)`; `C { q = e/k }` (so `e = k q`) stores `k q²/2`; an inertia
//! `I { p = m2 f }` in derivative causality, whose flow is the junction's common flow `f`, stores
//! `∫ f dp = m2 f²/2`.

use bgc::causality::analyse;
use bgc::diagnostic::Diagnostic;
use bgc::equations::symbols::{self as sym, Sym};
use bgc::equations::{EnergyKind, Equations, derive};
use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;

fn equations_of(text: &str) -> (Equations, Vec<Diagnostic>) {
    let mut sources = SourceMap::new();
    let root = sources.add("laws.bg", text);
    let (models, mut diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert_eq!(models.len(), 1, "{diags:?}");
    let (causality, cdiags) = analyse(&models[0]);
    diags.extend(cdiags);
    let (eqs, ediags) = derive(&models[0], &causality);
    diags.extend(ediags);
    assert!(!bgc::diagnostic::has_errors(&diags), "{diags:?}");
    (eqs, diags)
}

fn term(eqs: &Equations, element: &str, kind: EnergyKind, x: &[f64], u: &[f64]) -> f64 {
    let p = eqs.default_params();
    let value = eqs
        .energy
        .iter()
        .find(|t| t.element == element && t.kind == kind)
        .and_then(|t| t.value.as_ref())
        .unwrap_or_else(|| panic!("no {kind:?} energy for `{element}`: {:?}", eqs.energy));
    sym::eval(value, &|s| match s {
        Sym::Param(i) => p.get(i).copied(),
        Sym::State(i) => x.get(i).copied(),
        Sym::Input(i) => u.get(i).copied(),
        Sym::Time => Some(0.0),
        _ => None,
    })
    .expect("energy term evaluates")
}

const OTHER_FORM: &str = "
model other_form {
    domain translational;
    param m = 2 [kg];
    param m2 = 3 [kg];
    param k = 50 [N/m];
    param b = 0.5 [N s/m];
    input F [N];
    Se push = F;
    1 v;
    I mass { p = m*f; }
    I rider { p = m2*f; }
    C spring { q = e/k; }
    R damper = b;
    bond push -> v -> mass, rider, spring, damper;
}
";

#[test]
fn laws_in_the_other_form_store_their_energy() {
    let (eqs, diags) = equations_of(OTHER_FORM);
    let energy_warnings: Vec<&Diagnostic> = diags.iter().filter(|d| d.code.0 == "BG0607").collect();
    assert!(energy_warnings.is_empty(), "{energy_warnings:?}");
    let (m, m2, k, b) = (2.0, 3.0, 50.0, 0.5);
    // One inertia has the state, the other is in derivative causality.
    let ip = eqs
        .states
        .iter()
        .position(|s| s.name.starts_with("p_"))
        .expect("a momentum");
    let iq = eqs
        .states
        .iter()
        .position(|s| s.name == "q_spring")
        .expect("q_spring");
    let integral_mass = if eqs.states[ip].name == "p_mass" {
        m
    } else {
        m2
    };
    let derivative_mass = m + m2 - integral_mass;
    let derivative = if integral_mass == m { "rider" } else { "mass" };
    let integral = if integral_mass == m { "mass" } else { "rider" };
    let params = eqs.default_params();
    for (pv, qv, fv) in [(1.3, -0.2, 4.0), (-0.7, 0.05, -1.0), (2.5, 0.4, 0.0)] {
        let mut x = vec![0.0; eqs.states.len()];
        x[ip] = pv;
        x[iq] = qv;
        let u = [fv];
        let flow = pv / integral_mass;
        let stored = |e: &str| term(&eqs, e, EnergyKind::Stored, &x, &u);
        let close = |what: &str, got: f64, want: f64| {
            assert!(
                (got - want).abs() <= 1e-12 * (1.0 + want.abs()),
                "{what}: {got} vs {want}"
            );
        };
        close(
            "integral inertia",
            stored(integral),
            pv * pv / (2.0 * integral_mass),
        );
        close(
            "derivative inertia",
            stored(derivative),
            derivative_mass * flow * flow / 2.0,
        );
        close("spring", stored("spring"), k * qv * qv / 2.0);
        // Energy balance: d/dt of the total stored energy equals supplied − dissipated.
        let dx = eqs.rates_at(&params, &x, &u, 0.0).expect("rates");
        let total_rate = (1.0 + derivative_mass / integral_mass) * flow * dx[ip] + k * qv * dx[iq];
        let supplied = term(&eqs, "push", EnergyKind::Supplied, &x, &u);
        let dissipated = term(&eqs, "damper", EnergyKind::Dissipated, &x, &u);
        close("dissipated", dissipated, b * flow * flow);
        close("balance", total_rate, supplied - dissipated);
    }
}

#[test]
fn a_nonlinear_law_on_a_reversed_bond_stores_positive_energy() {
    let (eqs, _) = equations_of(
        "
model reversed {
    domain electrical;
    param L = 0.4 [H];
    param C0 = 0.1 [F];
    param k3 = 1 [V/C^3];
    param Rr = 2 [Ohm];
    input u [V];
    Se drive = u;
    1 loop;
    I coil { f = p/L; }
    C cap { e = q/C0 + k3*q^3; }
    R res = Rr;
    bond drive -> loop -> res;
    bond coil -> loop;
    bond cap -> loop;
}
",
    );
    let ip = eqs
        .states
        .iter()
        .position(|s| s.name == "p_coil")
        .expect("p_coil");
    let iq = eqs
        .states
        .iter()
        .position(|s| s.name == "q_cap")
        .expect("q_cap");
    let mut x = vec![0.0; eqs.states.len()];
    x[ip] = -0.8;
    x[iq] = 0.3;
    let coil = term(&eqs, "coil", EnergyKind::Stored, &x, &[0.0]);
    let cap = term(&eqs, "cap", EnergyKind::Stored, &x, &[0.0]);
    assert!((coil - 0.64 / 0.8).abs() < 1e-12, "{coil}");
    let want = 0.09 / 0.2 + 0.3f64.powi(4) / 4.0;
    assert!((cap - want).abs() < 1e-12, "{cap} vs {want}");
}
