//! Dependent storage behind a modulus that varies with the state: a cart-pole written with modulated
//! transformers and the same system as an I-field give the same rates at every angle (including those where the
//! plain sequential causality would divide by a vanishing `l sin θ` or `l cos θ`), both equal the hand-derived
//! equations of motion, simulate from θ = 0, and linearise at θ = 0 to the hand-derived state space.
//!
//! Hand derivation (θ from the downward vertical, bob at `(x + l sin θ, −l cos θ)`):
//! `T = ½ M v² + ½ m ((v + l cos θ ω)² + (l sin θ ω)²)`, `V = −m g l cos θ`, so
//! ```text
//! (M + m) v̇ + m l cos θ ω̇ = F + m l sin θ ω²
//! m l cos θ v̇ + m l² ω̇    = −m g l sin θ
//! ```

use bgc::causality::analyse;
use bgc::diagnostic::Diagnostic;
use bgc::equations::{Equations, StateSelection, derive, linearise};
use bgc::lower::{MemoryLoader, lower};
use bgc::simulate::System;
use bgc::simulate::input::Signal;
use bgc::simulate::integrate::{Method, RunOptions, run};
use bgc::span::SourceMap;
use std::path::Path;

pub(crate) fn fixture(name: &str) -> Equations {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/fixtures/{name}.bg"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    from_text(name, text)
}

fn from_text(name: &str, text: String) -> Equations {
    let mut sources = SourceMap::new();
    let root = sources.add(format!("{name}.bg"), text);
    let (models, mut diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert_eq!(models.len(), 1, "{name}: {diags:?}");
    let (causality, cdiags) = analyse(&models[0]);
    diags.extend(cdiags);
    let (eqs, ediags) = derive(&models[0], &causality);
    diags.extend(ediags);
    let errors: Vec<&Diagnostic> = diags.iter().filter(|d| d.is_error()).collect();
    assert!(errors.is_empty(), "{name}: {errors:?}");
    eqs
}

fn state(eqs: &Equations, name: &str) -> usize {
    eqs.states
        .iter()
        .position(|s| s.name == name)
        .unwrap_or_else(|| panic!("no state {name} in {:?}", eqs.states))
}

const M: f64 = 2.0;
const MB: f64 = 0.5;
const L: f64 = 0.6;
const G: f64 = 9.81;

/// `(v̇, ω̇)` of the hand-derived equations of motion.
fn hand_rates(theta: f64, w: f64, force: f64) -> (f64, f64) {
    let (a, b, d) = (M + MB, MB * L * theta.cos(), MB * L * L);
    let r1 = force + MB * L * theta.sin() * w * w;
    let r2 = -MB * G * L * theta.sin();
    let det = a * d - b * b;
    ((d * r1 - b * r2) / det, (a * r2 - b * r1) / det)
}

/// The MTF model's state vector for `(x, θ, v, ω)`.
fn mtf_point(eqs: &Equations, x: f64, theta: f64, v: f64, w: f64) -> Vec<f64> {
    let mut s = vec![0.0; eqs.states.len()];
    s[state(eqs, "x")] = x;
    s[state(eqs, "theta")] = theta;
    s[state(eqs, "f_cart")] = v;
    s[state(eqs, "f_pivot")] = w;
    s
}

fn field_point(eqs: &Equations, x: f64, theta: f64, v: f64, w: f64) -> Vec<f64> {
    let mut s = vec![0.0; eqs.states.len()];
    s[state(eqs, "q_body_1")] = x;
    s[state(eqs, "q_body_2")] = theta;
    s[state(eqs, "f_body_1")] = v;
    s[state(eqs, "f_body_2")] = w;
    s
}

#[test]
fn cart_pole_as_mtfs_equals_the_i_field_and_the_hand_derivation_at_every_angle() {
    let mtf = fixture("fields/cart_pole_mtf");
    let field = fixture("fields/cart_pole_field");
    let (pm, pf) = (mtf.default_params(), field.default_params());
    let angles = [
        0.0,
        std::f64::consts::FRAC_PI_2,
        std::f64::consts::PI,
        -std::f64::consts::FRAC_PI_2,
        1.1,
        -2.3,
    ];
    for &theta in &angles {
        for &(v, w, force) in &[(0.0, 0.0, 0.0), (0.4, -1.3, 2.0), (-1.1, 0.7, -0.5)] {
            let a = mtf
                .rates_at(&pm, &mtf_point(&mtf, 0.2, theta, v, w), &[force], 0.0)
                .unwrap_or_else(|e| panic!("MTF model at θ = {theta}: {e}"));
            let b = field
                .rates_at(&pf, &field_point(&field, 0.2, theta, v, w), &[force], 0.0)
                .unwrap_or_else(|e| panic!("I-field model at θ = {theta}: {e}"));
            let (dv, dw) = hand_rates(theta, w, force);
            let pairs = [
                (a[state(&mtf, "f_cart")], b[state(&field, "f_body_1")], dv),
                (a[state(&mtf, "f_pivot")], b[state(&field, "f_body_2")], dw),
                (a[state(&mtf, "theta")], b[state(&field, "q_body_2")], w),
                (a[state(&mtf, "x")], b[state(&field, "q_body_1")], v),
            ];
            for (k, (got_mtf, got_field, want)) in pairs.into_iter().enumerate() {
                let tol = 1e-12 * (1.0 + want.abs());
                assert!(
                    (got_mtf - want).abs() < tol && (got_field - want).abs() < tol,
                    "θ = {theta}, v = {v}, ω = {w}, F = {force}, rate {k}: MTF {got_mtf}, field {got_field}, hand {want}"
                );
            }
        }
    }
}

#[test]
fn cart_pole_as_mtfs_has_the_mass_matrix_form_not_a_quotient() {
    let eqs = fixture("fields/cart_pole_mtf");
    assert_eq!(eqs.mass.len(), 1, "{:?}", eqs.mass);
    let block = &eqs.mass[0];
    let mut rows: Vec<&str> = block
        .states
        .iter()
        .map(|&i| eqs.states[i].name.as_str())
        .collect();
    rows.sort_unstable();
    assert_eq!(rows, ["f_cart", "f_pivot"]);
    // No rate divides by anything but parameters: the configuration enters M, which is solved numerically.
    let text = bgc::equations::to_text(&eqs);
    for line in text.lines().filter(|l| l.contains("d/dt")) {
        assert!(
            !line.contains("/(l*sin")
                && !line.contains("/(l*cos")
                && !line.contains("/sin")
                && !line.contains("/cos"),
            "{line}"
        );
    }
}

#[test]
fn cart_pole_as_mtfs_simulates_from_the_bottom() {
    let eqs = fixture("fields/cart_pole_mtf");
    let signals = vec![Signal::parse("1").unwrap_or_else(|e| panic!("{e}"))];
    let (system, _) =
        System::new(&eqs, eqs.default_params(), signals).unwrap_or_else(|e| panic!("{e}"));
    let opts = RunOptions {
        t_end: 0.5,
        dt_out: 0.05,
        method: Method::Tsit45,
        rtol: 1e-10,
        atol: 1e-12,
        max_steps: 1_000_000,
        max_step: None,
    };
    let traj = run(&system, &mtf_point(&eqs, 0.0, 0.0, 0.0, 0.0), &opts)
        .unwrap_or_else(|e| panic!("simulate from θ = 0: {e}"));
    let col = |name: &str| {
        traj.columns
            .iter()
            .position(|c| c == name || c.starts_with(&format!("{name} ")))
            .unwrap_or_else(|| panic!("no column {name} in {:?}", traj.columns))
    };
    let (v, w) = (col("f_cart"), col("f_pivot"));
    let offset = traj.columns.len() - traj.rows[1].len();
    // At t = 0 the hand-derived accelerations under F = 1 N; the first sample follows them to first order.
    let (dv, dw) = hand_rates(0.0, 0.0, 1.0);
    let t1 = traj.times[1];
    let row = &traj.rows[1];
    assert!(
        (row[v - offset] / t1 - dv).abs() < 0.05 * dv.abs()
            && (row[w - offset] / t1 - dw).abs() < 0.05 * dw.abs(),
        "{:?} at t = {t1}: want v̇ {dv}, ω̇ {dw}",
        row
    );
    assert!(traj.rows.iter().flatten().all(|v| v.is_finite()));
}

#[test]
fn cart_pole_as_mtfs_linearises_at_the_bottom_to_the_hand_derived_state_space() {
    let eqs = fixture("fields/cart_pole_mtf");
    let p = eqs.default_params();
    let x0 = mtf_point(&eqs, 0.0, 0.0, 0.0, 0.0);
    let ss = linearise(&eqs, StateSelection::All, &p, &x0, &[0.0], 0.0)
        .unwrap_or_else(|e| panic!("{e}"));
    // At θ = 0: det = M m l²; v̇ = (m g / M) θ + F / M, ω̇ = −(M + m) g θ / (M l) − F / (M l).
    let (iv, iw, it, ix) = (
        state(&eqs, "f_cart"),
        state(&eqs, "f_pivot"),
        state(&eqs, "theta"),
        state(&eqs, "x"),
    );
    let want = [
        (iv, it, MB * G / M),
        (iw, it, -(M + MB) * G / (M * L)),
        (it, iw, 1.0),
        (ix, iv, 1.0),
    ];
    for (r, row) in ss.a.iter().enumerate() {
        for (c, &got) in row.iter().enumerate() {
            let w = want
                .iter()
                .find(|&&(wr, wc, _)| wr == r && wc == c)
                .map_or(0.0, |t| t.2);
            assert!((got - w).abs() < 1e-12, "A[{r}][{c}] = {got}, want {w}");
        }
    }
    let b_want = |r: usize| match r {
        _ if r == iv => 1.0 / M,
        _ if r == iw => -1.0 / (M * L),
        _ => 0.0,
    };
    for (r, row) in ss.b.iter().enumerate() {
        assert!((row[0] - b_want(r)).abs() < 1e-12, "B[{r}] = {}", row[0]);
    }
}

#[test]
fn pendulum_of_mtfs_is_regular_when_horizontal() {
    // bgc/tests/corpus/pendulum.bg: x = l sin θ, y = −l cos θ, pivot friction b. m l² ω̇ = −m g l sin θ − b ω.
    let eqs = fixture("../corpus/pendulum");
    let p = eqs.default_params();
    let (m, l, g, b) = (1.0, 0.5, 9.81, 0.01);
    for &theta in &[
        std::f64::consts::FRAC_PI_2,
        -std::f64::consts::FRAC_PI_2,
        0.0,
        2.0,
    ] {
        let w = 0.8;
        let mut x = vec![0.0; eqs.states.len()];
        x[state(&eqs, "theta")] = theta;
        x[state(&eqs, "f_pivot")] = w;
        let r = eqs
            .rates_at(&p, &x, &[], 0.0)
            .unwrap_or_else(|e| panic!("θ = {theta}: {e}"));
        let want = (-m * g * l * theta.sin() - b * w) / (m * l * l);
        let got = r[state(&eqs, "f_pivot")];
        assert!((got - want).abs() < 1e-12, "θ = {theta}: {got} vs {want}");
    }
}

#[test]
fn capacitor_behind_a_modulated_gyrator_is_regular_where_the_modulus_vanishes() {
    // L = ½ (J + c m²) ω² with m = k cos θ: (J + c m²) ω̇ + c m m' ω² = −b ω.
    let eqs = fixture("fields/gyrator_mgy");
    let p = eqs.default_params();
    let (c, j, k, b) = (0.5, 2.0, 1.5, 0.1);
    for &theta in &[std::f64::consts::FRAC_PI_2, 0.0, 1.2, -2.5] {
        let w = -0.9;
        let mut x = vec![0.0; eqs.states.len()];
        x[state(&eqs, "theta")] = theta;
        x[state(&eqs, "f_a")] = w;
        let r = eqs
            .rates_at(&p, &x, &[], 0.0)
            .unwrap_or_else(|e| panic!("θ = {theta}: {e}"));
        let (m, dm) = (k * theta.cos(), -k * theta.sin());
        let want = (-c * m * dm * w * w - b * w) / (j + c * m * m);
        let got = r[state(&eqs, "f_a")];
        assert!((got - want).abs() < 1e-12, "θ = {theta}: {got} vs {want}");
    }
}

/// `n` levers side by side, lever `k`: `Se tau -> 1 a_k {I J, R b} -> MTF m_k -> 1 o_k {I J}` with the modulus
/// `n_k = 1 + 0.5 cos θ_k`, `θ_k = ∫ f(a_k)`.
pub(crate) fn levers(n: usize) -> String {
    let mut s = String::from(
        "model levers {\n    domain rotational;\n    param J = 1 [kg m^2];\n    param b = 0.1 [N m s/rad];\n    input tau [N m];\n",
    );
    for k in 0..n {
        s += &format!(
            "    var th{k} [rad] = int(f(a{k}));\n    Se d{k} = tau;\n    1 a{k};\n    I ia{k} = J;\n    R ra{k} = b;\n    1 o{k};\n    I io{k} = J;\n    MTF m{k} = 1 + 0.5*cos(th{k});\n    bond d{k} -> a{k};\n    bond a{k} -> ia{k};\n    bond a{k} -> ra{k};\n    bond a{k} -> m{k} -> o{k};\n    bond o{k} -> io{k};\n"
        );
    }
    s + "}\n"
}

/// Levers that share nothing have mass matrices that share nothing: one 1×1 block each, named after its junction,
/// not one square with a row per lever. By hand, with `w = f(o)`, `f(a) = n w` and the power balance
/// `d/dt(½ J (n w)² + ½ J w²) = (τ − b n w) n w`: `J (n² + 1) ẇ = n (τ − b n w) + ½ J n² w² sin θ`.
#[test]
fn separate_levers_have_separate_mass_blocks_and_the_hand_derived_rates() {
    let count = 40;
    let eqs = from_text("levers", levers(count));
    assert_eq!(eqs.mass.len(), count, "{:?}", eqs.mass);
    for (k, block) in eqs.mass.iter().enumerate() {
        let lever = count - 1 - k;
        assert_eq!(block.element, format!("o{lever}"));
        assert_eq!(block.states, [state(&eqs, &format!("f_o{lever}"))]);
        assert_eq!(block.matrix.len(), 1);
    }
    let (j, b, tau) = (1.0, 0.1, 0.8);
    let mut x = vec![0.0; eqs.states.len()];
    let point = |k: usize| (0.37 * k as f64 - 2.0, 0.6 - 0.05 * k as f64);
    for k in 0..count {
        let (theta, w) = point(k);
        x[state(&eqs, &format!("th{k}"))] = theta;
        x[state(&eqs, &format!("f_o{k}"))] = w;
    }
    let rates = eqs
        .rates_at(&eqs.default_params(), &x, &[tau], 0.0)
        .unwrap_or_else(|e| panic!("{e}"));
    for k in 0..count {
        let (theta, w) = point(k);
        let n = 1.0 + 0.5 * theta.cos();
        let dw =
            (n * (tau - b * n * w) + 0.5 * j * n * n * w * w * theta.sin()) / (j * (n * n + 1.0));
        let pairs = [
            (rates[state(&eqs, &format!("f_o{k}"))], dw),
            (rates[state(&eqs, &format!("th{k}"))], n * w),
        ];
        for (got, want) in pairs {
            assert!(
                (got - want).abs() < 1e-12 * (1.0 + want.abs()),
                "lever {k}: {got} vs {want}"
            );
        }
    }
}

/// The sparse linearisation of models with mass-matrix rows gives the dense one's numbers: the cart-pole of MTFs
/// (one block coupling two velocities), the same as an I-field, and separate levers (one block each).
#[test]
fn the_sparse_linearisation_of_mass_matrix_rows_is_the_dense_one() {
    use bgc::equations::{ModelRows, SparseNumericStateSpace, linearise_sparse, state_selection};
    let models = [
        fixture("fields/cart_pole_mtf"),
        fixture("fields/cart_pole_field"),
        from_text("levers", levers(5)),
    ];
    for eqs in &models {
        assert!(!eqs.mass.is_empty());
        let rows = ModelRows::new(eqs);
        let selection = state_selection(eqs, &rows);
        let n = eqs.state_count(selection);
        let params = eqs.default_params();
        for seed in 0..4 {
            let x0: Vec<f64> = (0..n)
                .map(|i| 0.3 * ((i + seed) % 5) as f64 - 0.55)
                .collect();
            let u0: Vec<f64> = (0..eqs.inputs.len())
                .map(|k| 0.8 - 0.4 * (k + seed) as f64)
                .collect();
            let dense = linearise(eqs, selection, &params, &x0, &u0, 0.0)
                .unwrap_or_else(|e| panic!("{}: {e}", eqs.model));
            let sparse = linearise_sparse(eqs, &rows, selection, (&params, &x0, &u0, 0.0))
                .unwrap_or_else(|e| panic!("{}: {e}", eqs.model));
            assert_eq!(
                sparse,
                SparseNumericStateSpace::from_dense(&dense),
                "{} at {x0:?}",
                eqs.model
            );
        }
    }
}

/// The simulation's Jacobian of mass-matrix rows is that of the rates, not of the generalised forces: every entry
/// equals central differences of the simulated rhs (which solves `M ẋ_B = F`), for the cart-pole of MTFs, the
/// cart-pole as an I-field and forty levers, at three points each. The levers' Jacobian stays sparse: each
/// lever's rows read its own two states only.
#[test]
fn the_simulations_jacobian_of_mass_matrix_rows_equals_differences_of_the_rates() {
    let models = [
        fixture("fields/cart_pole_mtf"),
        fixture("fields/cart_pole_field"),
        from_text("levers", levers(40)),
    ];
    for eqs in &models {
        let signal = Signal::parse("0.7*sin(3*t)").unwrap_or_else(|e| panic!("{e}"));
        let (system, _) =
            System::new(eqs, eqs.default_params(), vec![signal]).unwrap_or_else(|e| panic!("{e}"));
        let pattern = system.jacobian_pattern().expect("a symbolic Jacobian");
        let n = eqs.states.len();
        if eqs.model == "levers" {
            // Per lever: the angle's rate (the modulus times the velocity) and the velocity's rate each read the
            // lever's angle and velocity, and nothing of the other levers.
            assert_eq!(pattern.iter().filter(|(r, _)| *r < n).count(), 4 * 40);
        }
        let mut stack = Vec::new();
        for seed in 0..3 {
            let t = 0.2 + 0.3 * seed as f64;
            let mut u = Vec::new();
            system.inputs_at(t, &mut u);
            let mut y: Vec<f64> = (0..n)
                .map(|i| 0.4 * ((3 * i + seed) % 7) as f64 - 1.1)
                .collect();
            y.extend([0.0, 0.0]);
            let mut values = vec![0.0; pattern.len()];
            system
                .jacobian_values(&y, &u, t, &mut values, &mut stack)
                .expect("a symbolic Jacobian");
            let mut jac = vec![vec![0.0; n]; n];
            for (&(r, c), v) in pattern.iter().zip(&values) {
                if r < n {
                    jac[r][c] = *v;
                }
            }
            let h = 1e-6;
            for c in 0..n {
                let (mut up, mut down) = (y.clone(), y.clone());
                up[c] += h;
                down[c] -= h;
                let (mut fu, mut fd) = (vec![0.0; n + 2], vec![0.0; n + 2]);
                system
                    .rhs(&up, &mut u, t, &mut fu, &mut stack)
                    .expect("rhs");
                system
                    .rhs(&down, &mut u, t, &mut fd, &mut stack)
                    .expect("rhs");
                for r in 0..n {
                    let want = (fu[r] - fd[r]) / (2.0 * h);
                    assert!(
                        (jac[r][c] - want).abs() < 1e-6 * (1.0 + want.abs()),
                        "{}: d rate {r} / d state {c} at {y:?}: {} vs {want}",
                        eqs.model,
                        jac[r][c]
                    );
                }
            }
        }
    }
}
