//! The model check of Sec. 5.1: the bond-graph model bgc generates from `models/back_support.bg`
//! ([`super::plant::bond_graph_model`]: 10 states, the 6 energy states of Fig. 6 and 4 integrated angles)
//! against the block diagram of Eq. 1 ([`super::block_diagram`]), both from rest, driven by `τ_m = 0.1 N m`
//! from `t = 0` and a trunk velocity of `0.05 rad/s` from `t = 0.1 s`, compared over 1 s in sensor torque and
//! motor velocity.
//!
//! Both models run on the same solver with tight tolerances, in two segments (the trunk velocity steps at
//! 0.1 s, and an implicit method must not step across the jump), so their difference measures the solver
//! error alone when the equations agree. The same run of Eq. 1 with the gearbox friction as printed there
//! (`b_g / r_g`) shows the size of that discrepancy.

use nalgebra::SVector;

use bgc_runtime::model::ContinuousModel;
use bgc_runtime::sim::{Method, SolverOptions, simulate_open_loop};

use super::BackSupportError;
use super::block_diagram::{BlockDiagram, GearFriction};
use super::params::Params;
use super::plant::{bond_graph_model, output};

/// Motor torque of the check (N m).
pub const MOTOR_TORQUE: f64 = 0.1;
/// Trunk velocity of the check (rad/s) and when it starts (s).
pub const TRUNK_VELOCITY: f64 = 0.05;
pub const TRUNK_START: f64 = 0.1;
/// Duration of the check (s) and output interval (s).
pub const DURATION: f64 = 1.0;
pub const OUTPUT_STEP: f64 = 1e-3;

/// Outputs of the three runs and their largest differences.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelCheck {
    pub times: Vec<f64>,
    /// `[θ̇_m, sensor torque, human torque]` of the generated bond-graph model.
    pub bond_graph: Vec<[f64; 3]>,
    /// The same of Eq. 1 with `b_g / r_g²`.
    pub block_diagram: Vec<[f64; 3]>,
    /// The same of Eq. 1 with `b_g / r_g` as printed.
    pub block_diagram_as_printed: Vec<[f64; 3]>,
    /// Largest |difference| bond graph vs Eq. 1 (`b_g / r_g²`): sensor torque (N m), motor velocity (rad/s).
    pub max_torque_difference: f64,
    pub max_velocity_difference: f64,
    /// Largest |difference| bond graph vs Eq. 1 as printed (`b_g / r_g`).
    pub max_torque_difference_as_printed: f64,
    pub max_velocity_difference_as_printed: f64,
    /// The solver settings of the runs.
    pub solver: SolverOptions,
}

/// The inputs `[τ_m, θ̇_h]` of the check at time `t`, on the segment that starts at `segment_start`.
fn input(segment_start: f64) -> impl Fn(f64) -> SVector<f64, 2> {
    let trunk = if segment_start >= TRUNK_START {
        TRUNK_VELOCITY
    } else {
        0.0
    };
    move |_t| SVector::<f64, 2>::new(MOTOR_TORQUE, trunk)
}

/// Runs a model with `N` states over the check in two segments, from rest, and returns its outputs on the
/// output grid.
fn run<const N: usize, M: ContinuousModel<N, 2, 3>>(
    model: &M,
    times: &[f64],
    solver: &SolverOptions,
) -> Result<Vec<[f64; 3]>, BackSupportError> {
    let split = times.partition_point(|&t| t <= TRUNK_START + 1e-12);
    let (first, second) = times.split_at(split);
    let x0 = SVector::<f64, N>::zeros();
    let a = simulate_open_loop(model, 0.0, &x0, input(0.0), first, solver)?;
    let x_switch = match a.states.last() {
        Some(x)
            if first
                .last()
                .is_some_and(|&t| (t - TRUNK_START).abs() < 1e-12) =>
        {
            *x
        }
        _ => {
            return Err(BackSupportError::Setup {
                what: "the model check's output grid must contain the trunk start time",
            });
        }
    };
    let b = simulate_open_loop(
        model,
        TRUNK_START,
        &x_switch,
        input(TRUNK_START),
        second,
        solver,
    )?;
    // The outputs at the switch time are those of the first segment (trunk still at rest).
    Ok(a.outputs
        .iter()
        .chain(b.outputs.iter())
        .map(|y| [y[0], y[1], y[2]])
        .collect())
}

fn max_difference(a: &[[f64; 3]], b: &[[f64; 3]], index: usize) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x[index] - y[index]).abs())
        .fold(0.0, f64::max)
}

/// Runs the model check for the given parameters.
pub fn model_check(p: &Params) -> Result<ModelCheck, BackSupportError> {
    let solver = SolverOptions {
        method: Method::Bdf,
        rtol: 1e-10,
        atol: 1e-12,
        ..SolverOptions::default()
    };
    let steps = (DURATION / OUTPUT_STEP).round() as usize;
    let times: Vec<f64> = (0..=steps).map(|k| k as f64 * OUTPUT_STEP).collect();
    let generated = bond_graph_model(p)?;
    let bond_graph_out = run(&generated, &times, &solver)?;
    let eq1 = BlockDiagram {
        params: *p,
        gear_friction: GearFriction::OutputSide,
    };
    let eq1_out = run(&eq1, &times, &solver)?;
    let eq1_printed = BlockDiagram {
        params: *p,
        gear_friction: GearFriction::AsPrintedInEq1,
    };
    let printed_out = run(&eq1_printed, &times, &solver)?;
    let (t, v) = (output::SENSOR_TORQUE, output::MOTOR_VELOCITY);
    Ok(ModelCheck {
        max_torque_difference: max_difference(&bond_graph_out, &eq1_out, t),
        max_velocity_difference: max_difference(&bond_graph_out, &eq1_out, v),
        max_torque_difference_as_printed: max_difference(&bond_graph_out, &printed_out, t),
        max_velocity_difference_as_printed: max_difference(&bond_graph_out, &printed_out, v),
        times,
        bond_graph: bond_graph_out,
        block_diagram: eq1_out,
        block_diagram_as_printed: printed_out,
        solver,
    })
}
