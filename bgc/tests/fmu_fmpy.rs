//! FMUs of `bgc fmu` (FMI 2.0 and 3.0) in FMPy, a real importer, and FMI 2.0 Co-Simulation also in the Open
//! Simulation Platform's libcosim, a second one: `fmpy validate` accepts the FMU of every model in `models/`, and
//! the simulations of the back-support plant, the walking leg (mass matrix), the diode loop (nonlinear
//! algebraic loop), a voltage divider (no states), a mass on 149 springs (150 states) and a chain of 200 masses
//! (400 states), through Model Exchange (FMPy's CVode) and Co-Simulation (the FMU's own integrator), give the
//! outputs of `bgc simulate` to 1e-6 of each output's range; the directional derivatives equal central
//! differences of the derivatives and outputs, and every dependency they show is listed in `ModelStructure`.
//! FMPy runs on a worker thread of 1 MiB of stack (`fmpy_driver.py`), as importers run FMUs.

use crate::fmu_support::{
    Scenario, bgc_simulate, compare, fmpy_jacobian, fmpy_simulate, fmu, libcosim_simulate,
    validate, workspace,
};

const BACK_SUPPORT: Scenario = Scenario {
    model: "models/back_support.bg",
    t_end: 0.2,
    dt: 1e-3,
    inputs: &[("tau_m", "0.2*step(0.01)"), ("omega_h", "0.5*step(0.02)")],
    rows: &[
        &[0.0, 0.0, 0.0],
        &[0.01, 0.0, 0.0],
        &[0.01, 0.2, 0.0],
        &[0.02, 0.2, 0.0],
        &[0.02, 0.2, 0.5],
        &[0.2, 0.2, 0.5],
    ],
    x0: &[],
    jumps: &[0.01, 0.02],
};

const WALKING_LEG: Scenario = Scenario {
    model: "models/walking_leg.bg",
    t_end: 1.0,
    dt: 1e-2,
    inputs: &[("tau_a3", "2*step(0.1)")],
    rows: &[&[0.0, 0.0], &[0.1, 0.0], &[0.1, 2.0], &[1.0, 2.0]],
    x0: &[("q_leg_1", 0.2)],
    jumps: &[0.1],
};

const DIODE: Scenario = Scenario {
    model: "bgc/tests/corpus/diode_rc.bg",
    t_end: 0.5,
    dt: 5e-3,
    inputs: &[("u", "5-8*step(0.25)")],
    rows: &[&[0.0, 5.0], &[0.25, 5.0], &[0.25, -3.0], &[0.5, -3.0]],
    x0: &[],
    jumps: &[0.25],
};

/// A model without states: Co-Simulation's step took the LU decomposition of the 0×0 Jacobian and panicked in
/// nalgebra (`fmi2DoStep: internal error`); Model Exchange worked.
const NO_STATES: Scenario = Scenario {
    model: "bgc/tests/fmu_support/no_states.bg",
    t_end: 1.0,
    dt: 1e-2,
    inputs: &[("v", "4*step(0.5)")],
    rows: &[&[0.0, 0.0], &[0.5, 0.0], &[0.5, 4.0], &[1.0, 4.0]],
    x0: &[],
    jumps: &[0.5],
};

/// 150 states, above the 127 that nalgebra decomposes at a fixed size: the FMU's library did not compile
/// (`Const<151>: ToTypenum` in its solver's LU); the solver's LU is of dynamic size now.
const WIDE: Scenario = Scenario {
    model: "bgc/tests/fmu_support/wide_star.bg",
    t_end: 0.5,
    dt: 5e-3,
    inputs: &[("u", "step(0.1)")],
    rows: &[&[0.0, 0.0], &[0.1, 0.0], &[0.1, 1.0], &[0.5, 1.0]],
    x0: &[],
    jumps: &[0.1],
};

/// 400 states, a state Jacobian of 1.25 MiB: the FMU's solver and its directional derivatives held it on the
/// stack, which a 1 MiB worker thread (the driver runs FMPy on one) does not have, and `bgc fmu` refused models of
/// more than 181 states; both keep it on the heap now. The same input and run as `WIDE`.
const LONG_CHAIN: Scenario = Scenario {
    model: "bgc/tests/fmu_support/long_chain.bg",
    ..WIDE
};

/// The required agreement with `bgc simulate`, relative to each output's range.
const AGREEMENT: f64 = 1e-6;

fn agrees(s: &Scenario, version: u8) {
    let path = fmu(s.model, version);
    let reference = bgc_simulate(s);
    let mut runs = vec![
        (
            "FMPy ModelExchange",
            fmpy_simulate(&path, "ModelExchange", s, 1e-11),
        ),
        (
            "FMPy CoSimulation",
            fmpy_simulate(&path, "CoSimulation", s, 1e-10),
        ),
    ];
    if version == 2 {
        // The second importer, with its own experiment settings.
        runs.push(("libcosim CoSimulation", libcosim_simulate(&path, s)));
    }
    for (kind, run) in runs {
        for (name, worst) in compare(&reference, &run, s) {
            eprintln!(
                "{} FMI {version} {kind}: {name} within {worst:.2e} of its range",
                s.model
            );
            assert!(
                worst <= AGREEMENT,
                "{} FMI {version} {kind}: `{name}` differs from bgc simulate by {worst:e} of its range",
                s.model
            );
        }
    }
}

fn jacobian_matches_differences(s: &Scenario, version: u8) {
    let j = fmpy_jacobian(&fmu(s.model, version), s);
    let (dd, fd) = (&j.dd, &j.fd);
    assert!(!dd.is_empty() && dd.len() == fd.len(), "{dd:?} {fd:?}");
    let scale = fd.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for (c, (a, b)) in dd.iter().zip(fd).enumerate() {
        assert_eq!(a.len(), b.len());
        for (r, (x, y)) in a.iter().zip(b).enumerate() {
            assert!(
                (x - y).abs() <= 1e-6 * (y.abs() + 1e-6 * scale),
                "{} column {c} row {r}: directional derivative {x}, central difference {y}",
                s.model
            );
            // Every entry that is not zero is a dependency ModelStructure lists.
            let listed = j
                .deps
                .get(r)
                .is_some_and(|d| d.as_ref().is_none_or(|d| d.contains(&c)));
            assert!(
                y.abs() <= 1e-9 * scale || listed,
                "{} FMI {version}: row {r} depends on column {c} ({y}) but ModelStructure lists {:?}",
                s.model,
                j.deps.get(r)
            );
        }
    }
}

#[test]
fn fmpy_validates_the_fmu_of_every_model() {
    let mut models: Vec<String> = std::fs::read_dir(workspace().join("models"))
        .unwrap_or_else(|e| panic!("models/: {e}"))
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".bg"))
        .collect();
    models.sort();
    assert!(models.len() >= 4, "{models:?}");
    for version in [2, 3] {
        for m in &models {
            validate(&fmu(&format!("models/{m}"), version));
        }
        validate(&fmu(DIODE.model, version));
    }
}

#[test]
fn back_support_fmu_follows_bgc_simulate() {
    agrees(&BACK_SUPPORT, 2);
    agrees(&BACK_SUPPORT, 3);
}

#[test]
fn walking_leg_fmu_follows_bgc_simulate() {
    agrees(&WALKING_LEG, 2);
    agrees(&WALKING_LEG, 3);
}

#[test]
fn diode_loop_fmu_follows_bgc_simulate() {
    agrees(&DIODE, 2);
    agrees(&DIODE, 3);
}

#[test]
fn a_model_of_150_states_follows_bgc_simulate() {
    agrees(&WIDE, 2);
}

#[test]
fn a_model_of_400_states_follows_bgc_simulate_on_a_worker_thread() {
    agrees(&LONG_CHAIN, 2);
    jacobian_matches_differences(&LONG_CHAIN, 2);
}

#[test]
fn a_model_without_states_follows_bgc_simulate() {
    agrees(&NO_STATES, 2);
    agrees(&NO_STATES, 3);
}

#[test]
fn directional_derivatives_equal_central_differences_within_the_listed_dependencies() {
    for version in [2, 3] {
        jacobian_matches_differences(&BACK_SUPPORT, version);
        jacobian_matches_differences(&WALKING_LEG, version);
        jacobian_matches_differences(&DIODE, version);
    }
}

#[test]
fn the_c_interface_refuses_misuse_and_keeps_instances_apart() {
    let v = crate::fmu_support::fmpy_interface(&fmu(BACK_SUPPORT.model, 2), "interface");
    let error = serde_json::json!(3);
    // Another model's GUID and a null name give no instance; the first is logged.
    assert_eq!(v["wrong_guid_is_null"], true, "{v}");
    assert_eq!(v["wrong_guid_logged"], true, "{v}");
    assert_eq!(v["null_name_is_null"], true, "{v}");
    // A null component, a step before initialisation, a null value array, a parameter after initialisation:
    // fmi2Error, and the step's refusal is logged.
    for key in [
        "null_component",
        "step_before_init",
        "null_values",
        "param_after_init",
    ] {
        assert_eq!(v[key], error, "{key}: {v}");
    }
    assert_eq!(v["step_before_init_logged"], true, "{v}");
    // `fmi2GetDerivatives` answered a Co-Simulation instance and a Model Exchange one before initialisation
    // (fmi2OK, with the start values' derivatives); the standard allows neither. From initialisation on it answers.
    assert_eq!(v["derivatives_of_co_simulation"], error, "{v}");
    assert_eq!(v["derivatives_before_init"], error, "{v}");
    assert_eq!(v["derivatives_in_init"], serde_json::json!(0), "{v}");
    // A non-physical parameter is refused in words (before: the error's `Debug` form, `NonPhysical { name: ...`).
    let logged: Vec<String> =
        serde_json::from_value(v["non_physical_logged"].clone()).unwrap_or_default();
    assert!(
        logged.len() == 1
            && logged[0].contains("= -1.0 is not physical: ")
            && !logged[0].contains('{'),
        "{v}"
    );
    // Instance a is driven by a motor torque, b is not: b stays at rest.
    let a: Vec<f64> = serde_json::from_value(v["a"].clone()).unwrap_or_default();
    let b: Vec<f64> = serde_json::from_value(v["b"].clone()).unwrap_or_default();
    assert!(a.len() == 3 && a.iter().all(|x| x.abs() > 1e-3), "{v}");
    assert_eq!(b, vec![0.0; 3], "{v}");
    // Restoring a saved state repeats the steps from it exactly; Reset returns to the start (input 0: rest).
    assert_eq!(v["get_state"], 0);
    assert_eq!(v["set_state"], 0);
    assert_eq!(v["a_on"], v["a_again"], "{v}");
    assert_ne!(v["a_on"], v["a"], "{v}");
    assert_eq!(v["reset"], 0);
    assert_eq!(v["after_reset"], v["b"], "{v}");
}

#[test]
fn the_fmi3_interface_refuses_misuse() {
    let v = crate::fmu_support::fmpy_interface(&fmu(BACK_SUPPORT.model, 3), "interface3");
    // Another model's instantiation token gives no instance, and the importer is told why.
    assert_eq!(v["wrong_token_is_null"], true, "{v}");
    assert_eq!(v["wrong_token_logged"], true, "{v}");
    // A step before initialisation, a parameter after it, as many values as references: fmi3Error.
    let error = serde_json::json!(3);
    for key in ["step_before_init", "param_after_init", "counts_differ"] {
        assert_eq!(v[key], error, "{key}: {v}");
    }
    assert_eq!(v["enter_init"], 0, "{v}");
    assert_eq!(v["exit_init"], 0, "{v}");
    assert_eq!(v["step"], 0, "{v}");
    assert_eq!(v["last_successful_time"], 0.01, "{v}");
}
