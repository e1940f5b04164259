//! `modelDescription.xml` of the back-support plant against the model file and a hand derivation of its
//! structure: units with their SI exponents, parameters with default and description, derivatives naming their
//! states, and the dependencies of `ModelStructure`.
//!
//! The dependencies, by hand (states in the order p_rotor, q_gear_spring, p_sensor_in, q_sensor_spring,
//! p_sensor_out, q_coupling_spring, then the four angles; value references, and FMI 2.0 indices, 21..=30; inputs
//! tau_m 16, omega_h 17): the motor shaft (rotor and gearbox input as one inertia) obeys
//! `(J_m + J_g) ω̇_m = τ_m − b_f ω_m − (b_g ω_m / r_g + k_g q_g + d_g (ω_m / r_g − ω_sint)) / r_g`, so `der(p_rotor)`
//! depends on tau_m, p_rotor, q_gear_spring and p_sensor_in (16 21 22 23); the coupling torque
//! `tau_h = k_eh q_c + d_eh (ω_sext − ω_h)` on omega_h, p_sensor_out and q_coupling_spring (17 25 26), whatever
//! the values of the parameters (d_eh is 0 by default, and still a dependency).

use crate::equations_support::families;
use bgc::build::FsLoader;
use bgc::fmu::{Version, package_sources};
use bgc::span::SourceMap;

fn description(version: Version) -> String {
    let path = crate::fmu_support::workspace().join("models/back_support.bg");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut sources = SourceMap::new();
    let root = sources.add("models/back_support.bg", text);
    let compiled = bgc::codegen::compile(&mut sources, root, &mut FsLoader::default())
        .unwrap_or_else(|d| panic!("{d:?}"));
    package_sources(&compiled, None, version, "models/back_support.bg")
        .unwrap_or_else(|e| panic!("{e}"))
        .description
}

#[test]
fn units_carry_their_si_exponents() {
    let d = description(Version::Fmi2);
    assert!(
        d.contains("<Unit name=\"N m\">\n      <BaseUnit m=\"2\" kg=\"1\" s=\"-2\"/>"),
        "{d}"
    );
    assert!(
        d.contains("<Unit name=\"kg m^2\">\n      <BaseUnit m=\"2\" kg=\"1\"/>"),
        "{d}"
    );
    assert!(
        d.contains("<Unit name=\"rad/s\">\n      <BaseUnit s=\"-1\"/>"),
        "{d}"
    );
}

#[test]
fn parameters_have_their_defaults_and_descriptions() {
    let d = description(Version::Fmi2);
    assert!(d.contains(
        "<ScalarVariable name=\"J_m\" valueReference=\"1\" causality=\"parameter\" variability=\"fixed\" \
         description=\"inertia of the brushless DC motor (I1)\">\n      <Real unit=\"kg m^2\" start=\"0.000306\"/>"
    ), "{d}");
    // A dimensionless parameter (`[1]`) has no unit.
    assert!(d.contains("<Real start=\"160.0\"/>"), "{d}");
    // der(p_rotor) names p_rotor, variable 21 (after 15 parameters, 2 inputs and 3 outputs; the time, value
    // reference 0, is implicit in FMI 2.0).
    assert!(d.contains("name=\"p_rotor\" valueReference=\"21\""), "{d}");
    assert!(
        d.contains("name=\"der(p_rotor)\" valueReference=\"31\""),
        "{d}"
    );
    assert!(d.contains("<Real derivative=\"21\"/>"), "{d}");
    assert!(!d.contains("name=\"time\""), "{d}");
}

#[test]
fn model_structure_lists_the_hand_derived_dependencies() {
    let d = description(Version::Fmi2);
    assert!(
        d.contains("<Unknown index=\"31\" dependencies=\"16 21 22 23\"/>"),
        "{d}"
    );
    assert!(
        d.contains("<Unknown index=\"20\" dependencies=\"17 25 26\"/>"),
        "{d}"
    );
    // FMI 3.0 names value references: the same numbers, and declares the time.
    let d3 = description(Version::Fmi3);
    assert!(
        d3.contains(
            "<ContinuousStateDerivative valueReference=\"31\" dependencies=\"16 21 22 23\"/>"
        ),
        "{d3}"
    );
    assert!(
        d3.contains("<Output valueReference=\"20\" dependencies=\"17 25 26\"/>"),
        "{d3}"
    );
    assert!(d3.contains("instantiationToken=\"{"), "{d3}");
    assert!(
        d3.contains("<Float64 name=\"time\" valueReference=\"0\" causality=\"independent\""),
        "{d3}"
    );
}

/// One mass on a junction with `n - 1` compliances: `n` states.
fn star(n: usize) -> String {
    let mut s = String::from(
        "model star {\n    domain translational;\n    input u [N];\n    Se src = u;\n    1 j;\n    I m = 1;\n    bond src -> j -> m;\n",
    );
    for k in 1..n {
        s += &format!("    C c{k} = 1;\n    bond j -> c{k};\n");
    }
    s + "}\n"
}

fn package(text: String) -> Result<bgc::fmu::Sources, String> {
    let mut sources = SourceMap::new();
    let root = sources.add("star.bg", text);
    let compiled = bgc::codegen::compile(&mut sources, root, &mut FsLoader::default())
        .unwrap_or_else(|d| panic!("{d:?}"));
    package_sources(&compiled, None, Version::Fmi2, "star.bg")
}

/// The FMU's solver keeps the dense state Jacobian and its LU decomposition on the heap: a model of 4,096 states
/// is packaged (256 MiB of them), one of 4,097 refused with the reason and what to use instead. Models of more
/// than 181 states were refused while the Jacobian was on the importer's stack.
#[test]
fn a_model_of_more_than_4096_states_is_refused_with_its_reason() {
    let sources = package(star(4096)).unwrap_or_else(|e| panic!("{e}"));
    assert!(sources.description.contains("<ModelVariables>"));
    let Err(err) = package(star(4097)) else {
        panic!("a model of 4,097 states was packaged")
    };
    assert!(err.contains("model `star` has 4097 states"), "{err}");
    assert!(err.contains("(256 MiB)"), "{err}");
    assert!(err.contains("at most 4096 states"), "{err}");
    assert!(err.contains("bgc simulate"), "{err}");
}

/// The generated Jacobians of a model with algebraic loops keep each block's `∂r/∂x` and `∂f/∂z` on the stack, its
/// tears by the states that its residuals read or whose rates read its tears: one block of 31 tears (the 30 diode
/// currents and the shared resistor's, their sum) by 1,050 states (260,400 bytes) is packaged, 31 by 1,080
/// (267,840 bytes, over 256 KiB) refused, and 30 separate loops of one tear each by 37 states (296 bytes each) are
/// packaged.
#[test]
fn loops_whose_jacobian_matrices_exceed_256_kib_are_refused() {
    package(families::loops_sharing_a_resistor(30, 35)).unwrap_or_else(|e| panic!("{e}"));
    package(families::loops_in_series(30, 37)).unwrap_or_else(|e| panic!("{e}"));
    let Err(err) = package(families::loops_sharing_a_resistor(30, 36)) else {
        panic!("31 tears by 1,080 states were packaged")
    };
    assert!(err.contains("model `hub` has 1080 states"), "{err}");
    assert!(
        err.contains("the algebraic loops' tear variables by states, inputs or outputs (261 KiB)"),
        "{err}"
    );
    assert!(err.contains("more than the 256 KiB"), "{err}");
}
