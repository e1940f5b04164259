//! The state equations bgc derives from models/walking_leg.bg (an I-field with M(q): the mass-matrix form) against
//! the independent Euler–Lagrange derivation of the same chain in `bgc_workspace::walking::dynamics`:
//! `M(q) q̈ + C(q, q̇) q̇ + G(q) = τ − τ_f(q, q̇) − Jᵀ F`, at random states, velocities, torques and link masses.

use bgc::causality::analyse;
use bgc::equations::{Equations, StateSelection, derive, linearise};
use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;
use bgc_runtime::noise::Rng;
use bgc_workspace::walking::anthropometry::{LegFriction, LegSegments};
use bgc_workspace::walking::dynamics::LegDynamics;
use nalgebra::{Vector2, Vector3};

fn equations() -> Equations {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/models/walking_leg.bg");
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut sources = SourceMap::new();
    let root = sources.add("walking_leg.bg", text);
    let (models, diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert!(diags.is_empty(), "{diags:?}");
    let model = models.first().unwrap_or_else(|| panic!("no model"));
    let (causality, _) = analyse(model);
    let (eqs, diags) = derive(model, &causality);
    assert!(diags.is_empty(), "{diags:?}");
    eqs
}

fn index(names: &[String], name: &str) -> usize {
    names
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no `{name}` in {names:?}"))
}

/// Parameter values with the given ones set by name, derived parameters following them.
fn params(eqs: &Equations, given: &[(&str, f64)]) -> Vec<f64> {
    let names: Vec<String> = eqs.params.iter().map(|p| p.0.clone()).collect();
    let mut values = vec![None; names.len()];
    for (n, v) in given {
        values[index(&names, n)] = Some(*v);
    }
    eqs.param_values(&values)
}

fn frictionless() -> Vec<(&'static str, f64)> {
    [
        "b0_knee", "b2_knee", "k_knee", "ts0_knee", "b0_hip", "b2_hip", "k_hip", "ts0_hip",
    ]
    .iter()
    .map(|n| (*n, 0.0))
    .collect()
}

fn assert_close(got: f64, want: f64, scale: f64, what: &str) {
    let err = (got - want).abs() / scale.max(1e-300);
    assert!(
        err < 1e-10,
        "{what}: bgc {got}, Euler–Lagrange {want} (relative {err:e})"
    );
}

#[test]
fn states_are_the_joint_angles_and_rates_in_mass_matrix_form() {
    let eqs = equations();
    let names: Vec<String> = eqs.states.iter().map(|s| s.name.clone()).collect();
    assert_eq!(
        names,
        [
            "q_leg_1", "q_leg_2", "q_leg_3", "f_leg_1", "f_leg_2", "f_leg_3"
        ]
    );
    assert_eq!(eqs.mass.len(), 1);
    assert_eq!(eqs.mass[0].states, vec![3, 4, 5]);
    assert_eq!(eqs.energy_states, 6);
}

#[test]
fn accelerations_match_the_euler_lagrange_derivation() {
    let eqs = equations();
    let inputs = &eqs.inputs;
    let mut rng = Rng::new(7);
    for case in 0..200 {
        // Masses up to 30 % off the table's, so that the derived parameters (inertias, moments) must follow.
        let base = LegSegments::paper_subject();
        let m = base
            .masses()
            .map(|m| m * (1.0 + 0.3 * (rng.uniform() - 0.5)));
        let stance = if case % 2 == 0 { 0.0 } else { 1.0 };
        let mut given = frictionless();
        given.extend([
            ("m_F", m[0]),
            ("m_S", m[1]),
            ("m_T", m[2]),
            ("stance", stance),
        ]);
        let with_friction = case % 3 == 0;
        if with_friction {
            given.clear();
            given.extend([
                ("m_F", m[0]),
                ("m_S", m[1]),
                ("m_T", m[2]),
                ("stance", stance),
            ]);
        }
        let p = params(&eqs, &given);
        let dynamics = LegDynamics::new(base.with_masses(m));
        let q = Vector3::from_fn(|_, _| 1.5 * rng.normal());
        let qd = Vector3::from_fn(|_, _| 4.0 * rng.normal());
        let force = Vector2::new(50.0 * rng.normal(), 600.0 + 100.0 * rng.normal());
        let mut u = vec![0.0; inputs.len()];
        let mut tau = Vector3::zeros();
        for (name, joint) in [
            ("tau_h1", 0),
            ("tau_h2", 1),
            ("tau_h3", 2),
            ("tau_a2", 1),
            ("tau_a3", 2),
        ] {
            let v = 20.0 * rng.normal();
            u[index(inputs, name)] = v;
            tau[joint] += v;
        }
        u[index(inputs, "F_x")] = force[0];
        u[index(inputs, "F_y")] = force[1];
        let x: Vec<f64> = q.iter().chain(qd.iter()).copied().collect();
        let rates = eqs
            .rates_at(&p, &x, &u, 0.0)
            .unwrap_or_else(|e| panic!("case {case}: {e}"));

        let mut rhs = tau;
        if with_friction {
            let f = LegFriction::table8_right().torque(&[q[0], q[1], q[2]], &[qd[0], qd[1], qd[2]]);
            rhs -= Vector3::from(f);
        }
        if stance == 1.0 {
            rhs -= dynamics.ankle_jacobian(&q).transpose() * force;
        }
        let qdd = dynamics
            .acceleration(&q, &qd, &rhs)
            .unwrap_or_else(|| panic!("case {case}: singular M"));
        let scale = qdd.amax();
        for j in 0..3 {
            assert_close(rates[j], qd[j], qd.amax(), &format!("case {case}: q̇{j}"));
            assert_close(
                rates[3 + j],
                qdd[j],
                scale,
                &format!("case {case} (stance {stance}, friction {with_friction}): q̈{j}"),
            );
        }
    }
}

#[test]
fn stored_energy_is_the_kinetic_energy_of_the_chain() {
    let eqs = equations();
    let term = eqs
        .energy
        .iter()
        .find(|t| t.element == "leg")
        .and_then(|t| t.value.clone())
        .unwrap_or_else(|| panic!("no stored energy of the I-field"));
    let p = params(&eqs, &[]);
    let d = LegDynamics::new(LegSegments::paper_subject());
    let mut rng = Rng::new(3);
    for _ in 0..50 {
        let q = Vector3::from_fn(|_, _| 1.5 * rng.normal());
        let qd = Vector3::from_fn(|_, _| 4.0 * rng.normal());
        let x: Vec<f64> = q.iter().chain(qd.iter()).copied().collect();
        let v = bgc::equations::symbols::eval(&term, &|s| match s {
            bgc::equations::symbols::Sym::Param(i) => p.get(i).copied(),
            bgc::equations::symbols::Sym::State(i) => x.get(i).copied(),
            _ => None,
        })
        .unwrap_or_else(|e| panic!("{e:?}"));
        let want = d.kinetic_energy(&q, &qd);
        assert_close(v, want, want, "kinetic energy");
    }
}

#[test]
fn linearisation_matches_finite_differences_of_the_rates() {
    let eqs = equations();
    let p = params(&eqs, &[("stance", 1.0)]);
    let x0 = [0.1, 0.4, -0.2, 0.5, -1.0, 2.0];
    let mut u0 = vec![0.0; eqs.inputs.len()];
    u0[index(&eqs.inputs, "F_y")] = 500.0;
    u0[index(&eqs.inputs, "tau_a3")] = 10.0;
    let ss = linearise(&eqs, StateSelection::Energy, &p, &x0, &u0, 0.0)
        .unwrap_or_else(|e| panic!("{e}"));
    let rates = |x: &[f64], u: &[f64]| {
        eqs.rates_at(&p, x, u, 0.0)
            .unwrap_or_else(|e| panic!("{e}"))
    };
    // Central differences of the rates in the direction of state k or input c.
    let central = |state: Option<usize>, input: Option<usize>, h: f64| {
        let shifted = |sign: f64| {
            let (mut x, mut u) = (x0.to_vec(), u0.clone());
            if let Some(v) = state.and_then(|k| x.get_mut(k)) {
                *v += sign * h;
            }
            if let Some(v) = input.and_then(|c| u.get_mut(c)) {
                *v += sign * h;
            }
            rates(&x, &u)
        };
        let (fp, fm) = (shifted(1.0), shifted(-1.0));
        fp.iter()
            .zip(&fm)
            .map(|(a, b)| (a - b) / (2.0 * h))
            .collect::<Vec<f64>>()
    };
    let columns = (0..6)
        .map(|k| {
            (
                format!("A[.][{k}]"),
                central(Some(k), None, 1e-6),
                ss.a.iter().map(|r| r[k]).collect::<Vec<_>>(),
                1e-5,
            )
        })
        .chain((0..eqs.inputs.len()).map(|c| {
            (
                format!("B[.][{c}]"),
                central(None, Some(c), 1e-3),
                ss.b.iter().map(|r| r[c]).collect(),
                1e-6,
            )
        }));
    for (what, fd, got, tol) in columns {
        for (r, (fd, got)) in fd.iter().zip(&got).enumerate() {
            assert!(
                (got - fd).abs() < tol * (1.0 + fd.abs()),
                "{what} row {r} = {got}, central difference {fd}"
            );
        }
    }
}

/// The Rust code generated from models/walking_leg.bg (crate `bgc_models`, mass matrix solved by Cholesky) against
/// the Euler–Lagrange derivation, with the link masses changed through `Params` (the inertias follow them).
#[test]
fn generated_model_matches_the_euler_lagrange_derivation() {
    use bgc_models::walking_leg as m;
    let mut rng = Rng::new(19);
    for case in 0..100 {
        let base = LegSegments::paper_subject();
        let masses = base.masses().map(|v| v * (0.8 + 0.4 * rng.uniform()));
        let p = m::Params {
            m_F: masses[0],
            m_S: masses[1],
            m_T: masses[2],
            stance: 1.0,
            ..m::Params::default()
        };
        p.validate().unwrap_or_else(|e| panic!("{e}"));
        let q = Vector3::from_fn(|_, _| 1.5 * rng.normal());
        let qd = Vector3::from_fn(|_, _| 4.0 * rng.normal());
        let force = Vector2::new(50.0 * rng.normal(), 600.0 + 100.0 * rng.normal());
        let tau = Vector3::new(0.0, 20.0 * rng.normal(), 20.0 * rng.normal());
        let x = m::State::from_iterator(q.iter().chain(qd.iter()).copied());
        // Inputs in INPUT_NAMES order: tau_a2, tau_a3, tau_h1, tau_h2, tau_h3, F_x, F_y.
        let u = m::Inputs::from_column_slice(&[tau[1], tau[2], 0.0, 0.0, 0.0, force[0], force[1]]);
        assert_eq!(
            m::INPUT_NAMES,
            [
                "tau_a2", "tau_a3", "tau_h1", "tau_h2", "tau_h3", "F_x", "F_y"
            ]
        );
        let dx = m::rhs(&p, 0.0, &x, &u);
        let dynamics = LegDynamics::new(base.with_masses(masses));
        let friction =
            LegFriction::table8_right().torque(&[q[0], q[1], q[2]], &[qd[0], qd[1], qd[2]]);
        let rhs = tau - Vector3::from(friction) - dynamics.ankle_jacobian(&q).transpose() * force;
        let qdd = dynamics
            .acceleration(&q, &qd, &rhs)
            .unwrap_or_else(|| panic!("case {case}: singular M"));
        for j in 0..3 {
            assert_close(dx[3 + j], qdd[j], qdd.amax(), &format!("case {case}: q̈{j}"));
        }
    }
}

/// The worn leg of the walking study (simulated on the generated model) against the hand-derived model with the
/// same torques, torso load and ground reaction, along the synthetic wearer's gait.
#[test]
fn walking_plant_on_the_generated_model_matches_the_hand_model() {
    use bgc_runtime::model::ContinuousModel;
    use bgc_workspace::walking::plant::{LegModel, WalkingPlant, join};
    use bgc_workspace::walking::wearer::{Wearer, WearerConfig};
    let plant = WalkingPlant {
        leg: LegModel::new(LegSegments::paper_subject(), LegFriction::table8_right()),
        wearer: Wearer::new(&WearerConfig::default()),
    };
    let mut rng = Rng::new(23);
    for k in 0..200 {
        let t = 0.01 * k as f64;
        let w = plant.wearer.intended(t);
        let x = join(&w.q, &w.qd) + nalgebra::Vector6::from_fn(|_, _| 0.05 * rng.normal());
        let u = Vector3::new(0.0, 30.0 * rng.normal(), 60.0 * rng.normal());
        let mut dx = nalgebra::Vector6::zeros();
        plant.rhs(t, &x, &u, &mut dx);
        let (q, _) = bgc_workspace::walking::plant::split(&x);
        let torque =
            WalkingPlant::actuator(&u) + plant.human_torque(t, &x) + plant.ground_torque(t, &q);
        let want = plant.leg_at(t).derivative(&x, &torque);
        for i in 0..6 {
            assert_close(dx[i], want[i], want.amax(), &format!("t = {t}: rate {i}"));
        }
    }
}
