//! The plant: the linear state space of Eq. 3 in the paper's coordinates, taken from the model the bgc compiler
//! generates from `models/back_support.bg` (the bond graph of Fig. 6), and the 6-state design model.
//!
//! State `x = [θ_m, θ̇_m, θ_s_int, θ̇_s_int, θ_s_ext, θ̇_s_ext, θ_h]` (Eq. 2), inputs `u = [τ_m, θ̇_h]`, outputs
//! `y = [y_v, y_t, y_b]`: the motor velocity `θ̇_m`, the sensor torque `k_s (θ_s_int − θ_s_ext) + d_s (θ̇_s_int −
//! θ̇_s_ext)` (Eq. 5) and the torque on the human body `k_eh (θ_s_ext − θ_h) + d_eh (θ̇_s_ext − θ̇_h)` (Eq. 6).
//!
//! [`plant`] is the single source of the plant model for everything else in [`super`]: it maps [`Params`] onto
//! the generated `bgc_models::back_support::Params` ([`generated_params`]) and reads `A, B, C, D` from the
//! generated `state_space_declared`, whose coordinates (`coords` in the `.bg` file) are the seven above, in
//! that order, with the inputs and outputs in the order above ([`plant`] checks the generated names). In the
//! bond graph `R: b_g` sits after the gearbox transformer, where it sees the output velocity `θ̇_m / r_g`, so it
//! reaches the motor line as `b_g / r_g²`, as in Eq. 3. The integration test holds these matrices against Eq. 3
//! coded by hand; [`super::block_diagram`] (Eq. 1, coded independently) is the check of Sec. 5.1
//! ([`super::model_check`]), which simulates the generated 10-state model itself ([`bond_graph_model`]).
//!
//! # The design model
//!
//! The trunk angle `θ_h` integrates the imposed trunk velocity; a rigid rotation of the whole chain,
//! `x = v θ_h` with `v = [r_g, 0, 1, 0, 1, 0, 1]`, twists no spring and moves no damper, so `A v = 0` and
//! `C_torques v = 0`. In the angles relative to the trunk, `δ = x₁…₆ − v₁…₆ θ_h`,
//!
//! `δ̇ = A₁ δ + B_m τ_m + (B_θ̇h,₁…₆ − v₁…₆) θ̇_h`, `y_v = C_v δ`, `y_t = C_t δ`, `y_b = C_b δ − d_eh θ̇_h`,
//!
//! with `A₁`, `B_m`, `C_b` exactly the paper's (Eqs. 4, 7): at the design point `θ_h = 0` these are the
//! paper's coordinates, and for a moving trunk they are the only reading of the 6-state model in which the
//! state feedback of Eq. 16 stays meaningful (`θ_m` itself ramps at `r_g θ̇_h`). The trunk velocity is then a
//! known input of the observer, as in Eq. 8.

use nalgebra::{DMatrix, SVector};

use bgc_runtime::matrix::dynamic;
use bgc_runtime::sim::LinearPlant;
use bgc_runtime::statespace::StateSpace;

use bgc_models::back_support as generated;

use super::BackSupportError;
use super::params::Params;

/// Number of plant states.
pub const NX: usize = 7;
/// Plant inputs: motor torque and trunk velocity.
pub const NU: usize = 2;
/// Plant outputs: motor velocity, sensor torque, torque on the human body.
pub const NY: usize = 3;

/// Indices into the plant state.
pub mod state {
    pub const THETA_M: usize = 0;
    pub const OMEGA_M: usize = 1;
    pub const THETA_S_INT: usize = 2;
    pub const OMEGA_S_INT: usize = 3;
    pub const THETA_S_EXT: usize = 4;
    pub const OMEGA_S_EXT: usize = 5;
    pub const THETA_H: usize = 6;
}

/// Indices into the plant output.
pub mod output {
    /// Motor velocity `y_v` (rad/s).
    pub const MOTOR_VELOCITY: usize = 0;
    /// Torque sensor `y_t` (N m).
    pub const SENSOR_TORQUE: usize = 1;
    /// Torque on the human body `y_b` (N m).
    pub const HUMAN_TORQUE: usize = 2;
}

/// The linear plant `ẋ = A x + B u`, `y = C x + D u`.
pub type Plant = LinearPlant<NX, NU, NY>;

/// The coordinates, inputs and outputs the generated model must declare, in this order, for its
/// `state_space_declared` to be Eq. 3 in the coordinates of Eq. 2.
pub const GENERATED_COORDS: [&str; NX] = [
    "theta_m",
    "f_rotor",
    "theta_sint",
    "f_sensor_in",
    "theta_sext",
    "f_sensor_out",
    "theta_h",
];
/// The inputs `[τ_m, θ̇_h]` as the generated model names them.
pub const GENERATED_INPUTS: [&str; NU] = ["tau_m", "omega_h"];
/// The outputs `[y_v, y_t, y_b]` as the generated model names them.
pub const GENERATED_OUTPUTS: [&str; NY] = ["omega_m", "tau_s", "tau_h"];

/// The generated model's parameters for the study's (same quantities, same SI units).
pub fn generated_params(p: &Params) -> generated::Params {
    generated::Params {
        J_m: p.j_m,
        J_g: p.j_g,
        b_f: p.b_f,
        r_g: p.r_g,
        b_g: p.b_g,
        k_g: p.k_g,
        d_g: p.d_g,
        J_sint: p.j_s_int,
        k_s: p.k_s,
        d_s: p.d_s,
        J_sext: p.j_s_ext,
        k_eh: p.k_eh,
        d_eh: p.d_eh,
        J_h: p.j_h,
        b_h: p.b_h,
    }
}

/// The model generated from `models/back_support.bg` (10 states: 6 energy states, then the angles
/// `θ_m, θ_s_int, θ_s_ext, θ_h`), with the given parameters.
pub fn bond_graph_model(p: &Params) -> Result<generated::Model, BackSupportError> {
    p.validate()?;
    check_generated_names()?;
    Ok(generated::Model::new(generated_params(p))?)
}

/// Refuses a generated model whose coordinates, inputs or outputs are not those of Eq. 2 in the study's order.
fn check_generated_names() -> Result<(), BackSupportError> {
    if generated::COORD_NAMES != GENERATED_COORDS {
        return Err(BackSupportError::Setup {
            what: "the generated back_support model's coordinates are not those of Eq. 2 in order",
        });
    }
    if generated::INPUT_NAMES != GENERATED_INPUTS || generated::OUTPUT_NAMES != GENERATED_OUTPUTS {
        return Err(BackSupportError::Setup {
            what: "the generated back_support model's inputs or outputs are not [τ_m, θ̇_h] and [y_v, y_t, y_b]",
        });
    }
    Ok(())
}

/// The plant of Eq. 3 for the given parameters: the generated model's state space in the declared coordinates
/// (see the module docs).
pub fn plant(p: &Params) -> Result<Plant, BackSupportError> {
    let model = bond_graph_model(p)?;
    let (a, b, c, d) = generated::state_space_declared(model.params());
    Ok(Plant::new(a, b, c, d))
}

/// The 6-state design model in angles relative to the trunk (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct DesignModel {
    /// `A₁` (6 x 6).
    pub a: DMatrix<f64>,
    /// `B_m` (6 x 1).
    pub b_m: DMatrix<f64>,
    /// The trunk-velocity input `B_θ̇h,₁…₆ − v₁…₆` (6 x 1).
    pub b_h: DMatrix<f64>,
    /// The measurements `[C_v; C_t]` (2 x 6).
    pub c_meas: DMatrix<f64>,
    /// `C_b` (1 x 6): the torque on the human body is `C_b δ + d_b θ̇_h`.
    pub c_b: DMatrix<f64>,
    /// The feedthrough `d_b = −d_eh` of the trunk velocity to the human torque.
    pub d_b: f64,
}

/// Relative size of `‖A v‖`, `‖C v‖` below which the rigid rotation `v` counts as force-free.
const RIGID_ROTATION_TOLERANCE: f64 = 1e-12;

/// The rigid rotation `v = [r_g, 0, 1, 0, 1, 0, 1]` of the whole chain with the trunk.
pub fn rigid_rotation(p: &Params) -> SVector<f64, NX> {
    SVector::<f64, NX>::from_column_slice(&[p.r_g, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0])
}

/// The design model of `plant` (see the module docs); refuses a plant for which the rigid rotation is not
/// force-free (then the relative coordinates do not decouple the trunk angle).
pub fn design_model(plant: &Plant, p: &Params) -> Result<DesignModel, BackSupportError> {
    let v = rigid_rotation(p);
    let scale = plant.a.abs().max() * v.abs().max();
    let av = (*plant.a * v).abs().max();
    let cv = (*plant.c * v).abs().max() / plant.c.abs().max().max(f64::MIN_POSITIVE);
    if av > RIGID_ROTATION_TOLERANCE * scale || cv > RIGID_ROTATION_TOLERANCE * v.abs().max() {
        return Err(BackSupportError::NotRigidInvariant {
            residual: (av / scale).max(cv),
        });
    }
    let a = dynamic(&plant.a).view((0, 0), (6, 6)).clone_owned();
    let b_m = DMatrix::from_fn(6, 1, |i, _| plant.b[(i, 0)]);
    let b_h = DMatrix::from_fn(6, 1, |i, _| plant.b[(i, 1)] - v[i]);
    let c_meas = DMatrix::from_fn(2, 6, |i, j| plant.c[(i, j)]);
    let c_b = DMatrix::from_fn(1, 6, |_, j| plant.c[(output::HUMAN_TORQUE, j)]);
    Ok(DesignModel {
        a,
        b_m,
        b_h,
        c_meas,
        c_b,
        d_b: plant.d[(output::HUMAN_TORQUE, 1)],
    })
}

impl DesignModel {
    /// The relative state `δ` of a plant state `x`.
    pub fn relative_state(x: &SVector<f64, NX>, p: &Params) -> SVector<f64, 6> {
        let v = rigid_rotation(p);
        SVector::<f64, 6>::from_fn(|i, _| x[i] - v[i] * x[state::THETA_H])
    }

    /// `ẋ = A₁ x + [B_m B_h] [τ_m; θ̇_h]`, `y = [C_v; C_t] x` as a [`StateSpace`] with both inputs.
    pub fn measurement_model(&self) -> Result<StateSpace, BackSupportError> {
        let mut b = DMatrix::zeros(6, 2);
        b.set_column(0, &self.b_m.column(0));
        b.set_column(1, &self.b_h.column(0));
        Ok(StateSpace::new(
            self.a.clone(),
            b,
            self.c_meas.clone(),
            DMatrix::zeros(2, 2),
        )?)
    }
}
