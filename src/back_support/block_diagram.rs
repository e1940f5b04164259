//! The block-diagram model of Eq. 1, coded independently of [`super::plant`] in second-order form: each line of
//! Eq. 1 is a torque balance solved for its acceleration.
//!
//! State `[θ_m, θ_s_int, θ_s_ext, θ_h, θ̇_m, θ̇_s_int, θ̇_s_ext]`, inputs `[τ_m, θ̇_h]` (the trunk velocity is imposed,
//! as in Fig. 4, so the fourth line of Eq. 1 only fixes the torque the trunk exerts and is not integrated),
//! outputs `[θ̇_m, sensor torque, torque on the human body]` as in [`super::plant`].
//!
//! Eq. 1 prints the gearbox friction in the motor line as `(b_g / r_g) θ̇_m`, Eq. 3 as `b_g / r_g²` (in
//! `−(b_f r_g² + b_g + d_g) / ((J_m + J_g) r_g²)`). The bond graph of Fig. 6 puts `R: b_g` on the 1-junction
//! after the transformer, where it sees the output velocity `θ̇_m / r_g` and reflects to the motor as
//! `b_g θ̇_m / r_g²`; [`GearFriction::OutputSide`] (the default of the model check) follows Eq. 3 and the bond
//! graph, [`GearFriction::AsPrintedInEq1`] shows what the printed form would change.

use nalgebra::SVector;

use bgc_runtime::model::ContinuousModel;

use super::params::Params;

/// How the gearbox friction enters the motor line of Eq. 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GearFriction {
    /// `(b_g / r_g²) θ̇_m`: Eq. 3 and the bond graph.
    OutputSide,
    /// `(b_g / r_g) θ̇_m`: Eq. 1 as printed.
    AsPrintedInEq1,
}

/// Eq. 1 in second-order form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockDiagram {
    pub params: Params,
    pub gear_friction: GearFriction,
}

impl ContinuousModel<7, 2, 3> for BlockDiagram {
    fn rhs(&self, _t: f64, x: &SVector<f64, 7>, u: &SVector<f64, 2>, dx: &mut SVector<f64, 7>) {
        let p = &self.params;
        let (th_m, th_si, th_se, th_h) = (x[0], x[1], x[2], x[3]);
        let (w_m, w_si, w_se) = (x[4], x[5], x[6]);
        let (tau_m, w_h) = (u[0], u[1]);
        let gear_friction = match self.gear_friction {
            GearFriction::OutputSide => p.b_g / (p.r_g * p.r_g),
            GearFriction::AsPrintedInEq1 => p.b_g / p.r_g,
        };
        // Torques transmitted by the gearbox, the sensor and the trunk interface (output side).
        let tau_g = p.k_g * (th_m / p.r_g - th_si) + p.d_g * (w_m / p.r_g - w_si);
        let tau_s = p.k_s * (th_si - th_se) + p.d_s * (w_si - w_se);
        let tau_eh = p.k_eh * (th_se - th_h) + p.d_eh * (w_se - w_h);
        // Line 1: τ_m − b_f θ̇_m − (J_m + J_g) θ̈_m − τ_g / r_g − friction θ̇_m = 0.
        let acc_m = (tau_m - p.b_f * w_m - tau_g / p.r_g - gear_friction * w_m) / p.j_motor();
        // Line 2: τ_g − J_s_int θ̈_s_int − τ_s = 0.
        let acc_si = (tau_g - tau_s) / p.j_s_int;
        // Line 3: τ_s − J_s_ext θ̈_s_ext − τ_eh = 0.
        let acc_se = (tau_s - tau_eh) / p.j_s_ext;
        *dx = SVector::<f64, 7>::from_column_slice(&[w_m, w_si, w_se, w_h, acc_m, acc_si, acc_se]);
    }

    fn outputs(&self, _t: f64, x: &SVector<f64, 7>, u: &SVector<f64, 2>, y: &mut SVector<f64, 3>) {
        let p = &self.params;
        let tau_s = p.k_s * (x[1] - x[2]) + p.d_s * (x[5] - x[6]);
        let tau_eh = p.k_eh * (x[2] - x[3]) + p.d_eh * (x[6] - u[1]);
        *y = SVector::<f64, 3>::new(x[4], tau_s, tau_eh);
    }
}
