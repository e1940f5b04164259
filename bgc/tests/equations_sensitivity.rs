//! `Equations::param_jacobian_at` (symbolic derivatives, total through derived parameters, with the implicit
//! function theorem for nonlinear loops and mass matrices) against hand derivations of the mass-spring-damper and
//! of the diode loop, and against central differences of `rates_at`/`outputs_at` on the models with derived
//! parameters, an I-field and a nonlinear loop.

use crate::equations_support;

use bgc::causality::analyse;
use bgc::equations::{Equations, Rows, derive};
use bgc::ir::Model;
use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;
use bgc::syntax::ast::ElementKind as K;
use equations_support::*;

/// `Se F -> 1 -> I m, C 1/k, R d`; outputs the spring deflection and the mass velocity; a derived `k2 = 2 k`
/// stiffness would move with `k`, so the spring is `1/k` directly.
fn oscillator() -> Model {
    let mut b = Builder::new("oscillator");
    let m = b.param("m", 2.0);
    let k = b.param("k", 800.0);
    let d = b.param("d", 4.0);
    let force = b.input("F");
    let push = b.node(K::Se, "push", source(force));
    let mass = b.node(K::I, "mass", linear(m));
    let spring = b.node(K::C, "spring", linear(div(c(1.0), k)));
    let damper = b.node(K::R, "damper", linear(d));
    let v = b.junction(K::One, "v");
    b.chain(&[push, v, mass]);
    b.bond(v, spring);
    b.bond(v, damper);
    b.output("x", q(spring));
    b.output("v_mass", f(mass));
    b.finish()
}

fn equations_of(path: &str) -> Equations {
    let text = std::fs::read_to_string(path).expect("model file");
    let mut sources = SourceMap::new();
    let root = sources.add(path, text);
    let (models, diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    let (causality, _) = analyse(&models[0]);
    let (eqs, diags) = derive(&models[0], &causality);
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    eqs
}

fn equations_of_text(text: &str) -> Equations {
    let mut sources = SourceMap::new();
    let root = sources.add("msd.bg", text.to_string());
    let (models, diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    let (causality, _) = analyse(&models[0]);
    let (eqs, diags) = derive(&models[0], &causality);
    assert!(diags.iter().all(|d| !d.is_error()), "{diags:?}");
    eqs
}

fn index(eqs: &Equations, name: &str) -> usize {
    eqs.params
        .iter()
        .position(|p| p.0 == name)
        .unwrap_or_else(|| panic!("no parameter {name}"))
}

/// `(∂f/∂p, ∂h/∂p)` by central differences of `rates_at` and `outputs_at`, each parameter stepped through
/// `param_values` (so that the derived parameters move with it): Richardson's extrapolation of the quotients at
/// the steps `h = 1e-3 |p|` and `h/2`, `(4 D(h/2) − D(h))/3`, whose error is of order `h⁴` (truncation) and
/// `ε/h` (rounding), both well below the 1e-6 the tests ask for.
fn differences(
    eqs: &Equations,
    given: &[Option<f64>],
    (x, u, t): (&[f64], &[f64], f64),
    free: &[usize],
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let values = eqs.param_values(given);
    let mut fp = vec![vec![0.0; free.len()]; x.len()];
    let mut hp = vec![vec![0.0; free.len()]; eqs.outputs.len()];
    for (c, &k) in free.iter().enumerate() {
        let at = |v: f64| {
            let mut g = given.to_vec();
            g[k] = Some(v);
            let p = eqs.param_values(&g);
            let mut all = eqs.rates_at(&p, x, u, t).expect("rates");
            all.extend(eqs.outputs_at(&p, x, u, t).expect("outputs"));
            all
        };
        let quotient = |h: f64| -> Vec<f64> {
            let (plus, minus) = (at(values[k] + h), at(values[k] - h));
            plus.iter()
                .zip(&minus)
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect()
        };
        let h = 1e-3
            * if values[k] == 0.0 {
                1.0
            } else {
                values[k].abs()
            };
        let (coarse, fine) = (quotient(h), quotient(h / 2.0));
        let d: Vec<f64> = coarse
            .iter()
            .zip(&fine)
            .map(|(a, b)| (4.0 * b - a) / 3.0)
            .collect();
        for (i, row) in fp.iter_mut().chain(hp.iter_mut()).enumerate() {
            row[c] = d[i];
        }
    }
    (fp, hp)
}

/// `got` and `want` agree entry by entry to `rel` of the largest magnitude in the entry's column (a difference
/// quotient's error scales with the column, not with an entry that happens to be near zero).
fn agree(what: &str, got: &[Vec<f64>], want: &[Vec<f64>], rel: f64) {
    assert_eq!(got.len(), want.len(), "{what}: rows");
    let cols = want.first().map_or(0, Vec::len);
    for c in 0..cols {
        let scale = want.iter().map(|r| r[c].abs()).fold(1e-12, f64::max);
        for (r, (g, w)) in got.iter().zip(want).enumerate() {
            assert!(
                (g[c] - w[c]).abs() <= rel * scale,
                "{what}[{r}][{c}]: {} against {} (column scale {scale})",
                g[c],
                w[c]
            );
        }
    }
}

#[test]
fn parameter_jacobian_matches_the_hand_derivation() {
    let model = oscillator();
    let (causality, _) = analyse(&model);
    let (eqs, diags) = derive(&model, &causality);
    assert!(diags.is_empty(), "{diags:?}");
    // States [p, q]: ṗ = F − d p/m − k q, q̇ = p/m; outputs x = q, v = p/m.
    let (p, q, m, k, d) = (0.8, 0.01, 2.0, 800.0, 4.0);
    let given = vec![None; 3];
    let j = eqs
        .param_jacobian_at(&given, &[p, q], &[1.5], 0.0, &[0, 1, 2])
        .unwrap();
    // Symbolic derivatives evaluated: equal to the last bits of the formulas.
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-13 * b.abs().max(1.0);
    // ∂ṗ/∂m = d p/m², ∂ṗ/∂k = −q, ∂ṗ/∂d = −p/m; ∂q̇/∂m = −p/m².
    let fp = [[d * p / (m * m), -q, -p / m], [-p / (m * m), 0.0, 0.0]];
    for (row, want) in j.fp.iter().zip(fp) {
        for (got, want) in row.iter().zip(want) {
            assert!(close(*got, want), "{:?}", j.fp);
        }
    }
    // ∂f/∂x = [[−d/m, −k], [1/m, 0]]; ∂h/∂x = [[0, 1], [1/m, 0]]; ∂h/∂p: only ∂v/∂m = −p/m².
    let fx = [[-d / m, -k], [1.0 / m, 0.0]];
    let hx = [[0.0, 1.0], [1.0 / m, 0.0]];
    let hp = [[0.0, 0.0, 0.0], [-p / (m * m), 0.0, 0.0]];
    for (got, want) in j.fx.iter().zip(fx).chain(j.hx.iter().zip(hx)) {
        assert!(
            got.iter().zip(want).all(|(g, w)| close(*g, w)),
            "{got:?} {want:?}"
        );
    }
    for (got, want) in j.hp.iter().zip(hp) {
        assert!(
            got.iter().zip(want).all(|(g, w)| close(*g, w)),
            "{got:?} {want:?}"
        );
    }
    // Without the outputs: the same rates' Jacobians.
    let rates = eqs
        .rate_param_jacobian_at(&given, &[p, q], &[1.5], 0.0, &[0, 1, 2])
        .unwrap();
    assert_eq!((rates.fx, rates.fp), (j.fx, j.fp));
    assert!(rates.hx.is_empty() && rates.hp.is_empty());
}

const DERIVED_SPRING: &str = "
model msd {
    domain translational;
    param m = 2 [kg];
    param k = 400 [N/m];
    param k_s = 2 * k [N/m];
    param b = 4 [N s/m];
    input F [N];
    Se push = F;
    I mass = m;
    C spring = 1 / k_s;
    R damper = b;
    1 v;
    bond push -> v -> mass, spring, damper;
    output x [m] = q(spring);
    output v_m [m/s] = f(mass);
}
";

#[test]
fn a_derived_parameter_carries_the_derivative_of_its_source() {
    let eqs = equations_of_text(DERIVED_SPRING);
    let (k, k_s) = (index(&eqs, "k"), index(&eqs, "k_s"));
    let p_row = eqs.states.iter().position(|s| s.name == "p_mass").unwrap();
    let (p, q) = (0.3, 0.02);
    let x: Vec<f64> = eqs
        .states
        .iter()
        .map(|s| if s.name == "p_mass" { p } else { q })
        .collect();
    let free = [k, k_s];
    // ṗ = F − k_s q − b p/m with k_s = 2 k: ∂ṗ/∂k = −2 q through k_s, ∂ṗ/∂k_s = −q when k_s is set directly.
    let j = eqs
        .param_jacobian_at(&vec![None; eqs.params.len()], &x, &[0.0], 0.0, &[k])
        .unwrap();
    assert_eq!(j.fp[p_row], [-2.0 * q]);
    let j = eqs
        .param_jacobian_at(&vec![None; eqs.params.len()], &x, &[0.0], 0.0, &free)
        .unwrap();
    // With k_s chosen too, it is set directly and no longer follows k.
    assert_eq!(j.fp[p_row], [0.0, -q]);
    // k_s given a value (held there): k no longer moves the spring.
    let mut given = vec![None; eqs.params.len()];
    given[k_s] = Some(900.0);
    let j = eqs
        .param_jacobian_at(&given, &x, &[0.0], 0.0, &[k])
        .unwrap();
    assert_eq!(j.fp[p_row], [0.0]);
    let (fp, _) = differences(&eqs, &given, (&x, &[0.0], 0.0), &[k]);
    assert_eq!(fp[p_row], [0.0]);
}

#[test]
fn the_diode_loop_is_differentiated_by_the_implicit_function_theorem() {
    let eqs = equations_of(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/corpus/diode_rc.bg"
    ));
    let given = vec![None; eqs.params.len()];
    let (q, u) = (3e-4, 1.2);
    let free: Vec<usize> = (0..eqs.params.len()).collect();
    let j = eqs
        .param_jacobian_at(&given, &[q], &[u], 0.0, &free)
        .unwrap();
    // q̇ = z with r(z) = I_s (exp((u − q/C − R z)/V_t) − 1) − z = 0, so dz/dR = −(∂r/∂R)/(∂r/∂z) with
    // ∂r/∂R = −I_s e z/V_t and ∂r/∂z = −I_s e R/V_t − 1, e = exp((u − q/C − R z)/V_t).
    let p = eqs.param_values(&given);
    let (r, i_s, v_t, c) = (p[0], p[1], p[2], p[3]);
    let z = eqs.rates_at(&p, &[q], &[u], 0.0).unwrap()[0];
    let e = ((u - q / c - r * z) / v_t).exp();
    let dz_dr = -(i_s * e * z / v_t) / (i_s * e * r / v_t + 1.0);
    let got = j.fp[0][index(&eqs, "R_s")];
    assert!(
        (got - dz_dr).abs() <= 1e-9 * dz_dr.abs(),
        "{got} against {dz_dr}"
    );
    let (fp, hp) = differences(&eqs, &given, (&[q], &[u], 0.0), &free);
    agree("∂f/∂p", &j.fp, &fp, 1e-6);
    agree("∂h/∂p", &j.hp, &hp, 1e-6);
}

/// A point of the walking leg: angles within ±1 rad, rates within ±3 rad/s, torques within ±20 N m.
fn walking_point(eqs: &Equations, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = Lcg(seed);
    let x = eqs
        .states
        .iter()
        .map(|s| {
            let r = 2.0 * rng.next() - 1.0;
            if s.name.starts_with("q_") { r } else { 3.0 * r }
        })
        .collect();
    let u = eqs
        .inputs
        .iter()
        .map(|_| 20.0 * (2.0 * rng.next() - 1.0))
        .collect();
    (x, u)
}

struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn the_walking_leg_mass_matrix_rows_agree_with_central_differences() {
    let eqs = equations_of(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/walking_leg.bg"
    ));
    assert!(eqs.has_mass());
    // Masses and the height move the derived inertias, lengths and gravity moments of M(q), G(q); the
    // friction parameters enter the forces only. (Not `eps`: at these speeds `tanh(f/eps)` is nearly saturated,
    // its derivative five orders below the rates, beyond what a difference quotient resolves to 1e-6.)
    let free: Vec<usize> = ["m_T", "m_S", "m_F", "height", "g", "b2_knee", "b0_knee"]
        .iter()
        .map(|n| index(&eqs, n))
        .collect();
    let mut given = vec![None; eqs.params.len()];
    given[index(&eqs, "stance")] = Some(1.0);
    for seed in 1..4 {
        let (x, u) = walking_point(&eqs, seed);
        let j = eqs.param_jacobian_at(&given, &x, &u, 0.0, &free).unwrap();
        let (fp, hp) = differences(&eqs, &given, (&x, &u, 0.0), &free);
        agree("∂f/∂p", &j.fp, &fp, 1e-6);
        agree("∂h/∂p", &j.hp, &hp, 1e-6);
        // ∂f/∂x against the linearisation (its own implicit mass-matrix rule, on the stage's expressions).
        let lin = bgc::equations::linearise(
            &eqs,
            bgc::equations::StateSelection::All,
            &eqs.param_values(&given),
            &x,
            &u,
            0.0,
        )
        .unwrap();
        agree("∂f/∂x", &j.fx, &lin.a, 1e-12);
        agree("∂h/∂x", &j.hx, &lin.c, 1e-12);
    }
}

#[test]
fn the_back_support_agrees_with_central_differences() {
    let eqs = equations_of(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/back_support.bg"
    ));
    let given = vec![None; eqs.params.len()];
    let free: Vec<usize> = (0..eqs.params.len())
        .filter(|&k| eqs.derived[k].is_none())
        .collect();
    let x: Vec<f64> = (0..eqs.states.len())
        .map(|i| 0.1 * (i as f64 + 1.0) * if i % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    let u: Vec<f64> = (0..eqs.inputs.len()).map(|i| 2.0 - i as f64).collect();
    let j = eqs.param_jacobian_at(&given, &x, &u, 0.3, &free).unwrap();
    let (fp, hp) = differences(&eqs, &given, (&x, &u, 0.3), &free);
    agree("∂f/∂p", &j.fp, &fp, 1e-6);
    agree("∂h/∂p", &j.hp, &hp, 1e-6);
}

#[test]
fn a_parameter_index_out_of_range_is_an_error() {
    let model = oscillator();
    let (causality, _) = analyse(&model);
    let (eqs, _) = derive(&model, &causality);
    assert!(
        eqs.param_jacobian_at(&[None; 3], &[0.0, 0.0], &[0.0], 0.0, &[7])
            .is_err()
    );
    // A point of the wrong size is an error too, not a panic.
    assert!(
        eqs.param_jacobian_at(&[None; 3], &[0.0], &[0.0], 0.0, &[0])
            .is_err()
    );
}

/// Outputs defined through earlier outputs (`y_i = sin(y_{i-1}²) + cos(y_{i-1})`, 24 levels): each output reads the
/// previous one three times, so written out as a tree `y_24` has about 3²⁴ nodes. The sensitivity keeps each
/// earlier output as one shared node; its `∂y/∂p` agree with differences of the outputs.
#[test]
fn outputs_through_earlier_outputs_are_differentiated_as_shared_nodes() {
    let eqs = equations_of_text(&crate::equations_support::families::output_chain(24));
    let given = vec![None; eqs.params.len()];
    let free = [index(&eqs, "q0"), index(&eqs, "k")];
    let point: (&[f64], &[f64], f64) = (&[0.3, 0.7], &[], 0.0);
    let jac = eqs
        .sensitivity(&given, &free)
        .expect("sensitivity")
        .at(&eqs.param_values(&given), point, Rows::Outputs)
        .expect("at the point");
    let (_, hp) = differences(&eqs, &given, point, &free);
    assert_eq!(jac.hp.len(), 24);
    agree("∂h/∂p", &jac.hp, &hp, 1e-6);
    // Not a vacuous agreement: q0 scales the first output's arguments, and it reaches the last one.
    assert!(hp[23][0].abs() > 1e-6, "∂y_24/∂q0 = {}", hp[23][0]);
}
