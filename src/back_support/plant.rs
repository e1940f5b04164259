//! The plant: the linear state space of Eq. 3 in the paper's coordinates, and the 6-state design model.
//!
//! State `x = [θ_m, θ̇_m, θ_s_int, θ̇_s_int, θ_s_ext, θ̇_s_ext, θ_h]` (Eq. 2), inputs `u = [τ_m, θ̇_h]`, outputs
//! `y = [y_v, y_t, y_b]`: the motor velocity `θ̇_m`, the sensor torque `k_s (θ_s_int − θ_s_ext) + d_s (θ̇_s_int −
//! θ̇_s_ext)` (Eq. 5) and the torque on the human body `k_eh (θ_s_ext − θ_h) + d_eh (θ̇_s_ext − θ̇_h)` (Eq. 6).
//!
//! [`plant`] is the single source of the plant model for everything else in [`super`]. It is coded here by hand
//! from Eq. 3, with the gearbox friction entering the motor equation as `b_g / r_g²` (the bond graph of Fig. 6
//! puts `b_g` on the gearbox output, which reflects to the motor through the transformer squared). The model
//! the bgc compiler generates from `models/back_support.bg` (the bond graph of Fig. 6, with the same state
//! coordinates, inputs and outputs in the same order) replaces this hand-coded matrix in [`plant`] once the
//! compiler pipeline produces it; [`super::block_diagram`] (Eq. 1, coded independently) stays as the check.
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

use nalgebra::{DMatrix, SMatrix, SVector};

use bgc_runtime::model::ContinuousModel;
use bgc_runtime::statespace::StateSpace;

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
#[derive(Clone, Debug, PartialEq)]
pub struct Plant {
    pub a: SMatrix<f64, NX, NX>,
    pub b: SMatrix<f64, NX, NU>,
    pub c: SMatrix<f64, NY, NX>,
    pub d: SMatrix<f64, NY, NU>,
}

/// The plant of Eq. 3 for the given parameters (see the module docs).
pub fn plant(p: &Params) -> Result<Plant, BackSupportError> {
    p.validate()?;
    let j = p.j_motor();
    let rg = p.r_g;
    let (jsi, jse) = (p.j_s_int, p.j_s_ext);
    #[rustfmt::skip]
    let a = SMatrix::<f64, NX, NX>::from_row_slice(&[
        0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        -p.k_g / (j * rg * rg), -(p.b_f * rg * rg + p.b_g + p.d_g) / (j * rg * rg),
            p.k_g / (j * rg), p.d_g / (j * rg), 0.0, 0.0, 0.0,
        0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0,
        p.k_g / (jsi * rg), p.d_g / (jsi * rg), -(p.k_g + p.k_s) / jsi, -(p.d_g + p.d_s) / jsi,
            p.k_s / jsi, p.d_s / jsi, 0.0,
        0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0,
        0.0, 0.0, p.k_s / jse, p.d_s / jse, -(p.k_eh + p.k_s) / jse, -(p.d_eh + p.d_s) / jse,
            p.k_eh / jse,
        0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    ]);
    #[rustfmt::skip]
    let b = SMatrix::<f64, NX, NU>::from_row_slice(&[
        0.0, 0.0,
        1.0 / j, 0.0,
        0.0, 0.0,
        0.0, 0.0,
        0.0, 0.0,
        0.0, p.d_eh / jse,
        0.0, 1.0,
    ]);
    #[rustfmt::skip]
    let c = SMatrix::<f64, NY, NX>::from_row_slice(&[
        0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        0.0, 0.0, p.k_s, p.d_s, -p.k_s, -p.d_s, 0.0,
        0.0, 0.0, 0.0, 0.0, p.k_eh, p.d_eh, -p.k_eh,
    ]);
    #[rustfmt::skip]
    let d = SMatrix::<f64, NY, NU>::from_row_slice(&[
        0.0, 0.0,
        0.0, 0.0,
        0.0, -p.d_eh,
    ]);
    Ok(Plant { a, b, c, d })
}

impl Plant {
    /// The plant as a continuous-time [`StateSpace`].
    pub fn state_space(&self) -> Result<StateSpace, BackSupportError> {
        Ok(StateSpace::new(
            dynamic(&self.a),
            dynamic(&self.b),
            dynamic(&self.c),
            dynamic(&self.d),
        )?)
    }
}

impl ContinuousModel<NX, NU, NY> for Plant {
    fn rhs(&self, _t: f64, x: &SVector<f64, NX>, u: &SVector<f64, NU>, dx: &mut SVector<f64, NX>) {
        *dx = self.a * x + self.b * u;
    }

    fn outputs(
        &self,
        _t: f64,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        y: &mut SVector<f64, NY>,
    ) {
        *y = self.c * x + self.d * u;
    }

    fn jac_x(
        &self,
        _t: f64,
        _x: &SVector<f64, NX>,
        _u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NX, NX>,
    ) {
        *jac = self.a;
    }

    fn jac_u(
        &self,
        _t: f64,
        _x: &SVector<f64, NX>,
        _u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NX, NU>,
    ) {
        *jac = self.b;
    }

    fn output_jac_x(
        &self,
        _t: f64,
        _x: &SVector<f64, NX>,
        _u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NY, NX>,
    ) {
        *jac = self.c;
    }

    fn output_jac_u(
        &self,
        _t: f64,
        _x: &SVector<f64, NX>,
        _u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NY, NU>,
    ) {
        *jac = self.d;
    }
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
    let av = (plant.a * v).abs().max();
    let cv = (plant.c * v).abs().max() / plant.c.abs().max().max(f64::MIN_POSITIVE);
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

/// A fixed-size matrix as a dynamic one.
pub fn dynamic<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> DMatrix<f64> {
    DMatrix::from_fn(R, C, |i, j| m[(i, j)])
}
