//! Physical parameters of the back-support exoskeleton (Shojaei Barjuei, Caldwell & Ortiz, Designs 2020, 4,
//! 53, Table 1 and Sec. 4).
//!
//! The paper prints `b_g`, `d_g`, `k_eh`, `J_h`, `b_h` and neglects `b_f`, `d_s`, `d_eh`. The inertias, the
//! gear ratio and the stiffnesses it does not print come from the datasheets of the parts in its Table 3
//! (maxon EC 90 flat, Harmonic Drive SHD-25-160, ME TS110a) and from fitting its printed LQR gains (Eq. 16);
//! with them the single-integral design reproduces Eq. 16 to the printed two decimals (see [`super::lqr`]).

/// The parameters of Eqs. 1 and 3 in SI units (kg m², N m/rad, N m s/rad).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Motor rotor inertia `J_m`.
    pub j_m: f64,
    /// Gearbox input inertia `J_g`.
    pub j_g: f64,
    /// Gear ratio `r_g` (motor turns per output turn).
    pub r_g: f64,
    /// Gearbox stiffness `k_g` (output side).
    pub k_g: f64,
    /// Gearbox damping `d_g` (output side).
    pub d_g: f64,
    /// Gearbox friction `b_g` (output side, to ground).
    pub b_g: f64,
    /// Motor/gearbox friction `b_f` (motor side, to ground).
    pub b_f: f64,
    /// Inertia of the torque sensor's internal ring `J_s_int`.
    pub j_s_int: f64,
    /// Inertia of the torque sensor's external ring `J_s_ext`.
    pub j_s_ext: f64,
    /// Torque sensor stiffness `k_s`.
    pub k_s: f64,
    /// Torque sensor damping `d_s`.
    pub d_s: f64,
    /// Equivalent trunk–exoskeleton stiffness `k_eh`.
    pub k_eh: f64,
    /// Equivalent trunk–exoskeleton damping `d_eh`.
    pub d_eh: f64,
    /// Trunk inertia `J_h` (only in the fourth line of Eq. 1: the trunk velocity is imposed).
    pub j_h: f64,
    /// Hip damping `b_h` (idem).
    pub b_h: f64,
}

impl Params {
    /// The values of the paper and of the seeds' README.
    pub fn paper() -> Self {
        Params {
            j_m: 3.06e-4,
            j_g: 0.40e-4,
            r_g: 160.0,
            k_g: 2.64e4,
            d_g: 6.0,
            b_g: 0.65,
            b_f: 0.0,
            j_s_int: 1e-4,
            j_s_ext: 1.19e-3,
            k_s: 3.38e4,
            d_s: 0.0,
            k_eh: 1125.0,
            d_eh: 0.0,
            j_h: 0.0491,
            b_h: 0.75,
        }
    }

    /// The motor-side inertia `J_m + J_g`.
    pub fn j_motor(&self) -> f64 {
        self.j_m + self.j_g
    }

    /// Checks that inertias, ratio and stiffnesses are positive and damping non-negative, all finite.
    pub fn validate(&self) -> Result<(), super::BackSupportError> {
        let positive = [
            ("J_m + J_g", self.j_motor()),
            ("r_g", self.r_g),
            ("k_g", self.k_g),
            ("J_s_int", self.j_s_int),
            ("J_s_ext", self.j_s_ext),
            ("k_s", self.k_s),
            ("k_eh", self.k_eh),
            ("J_h", self.j_h),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(super::BackSupportError::Parameter {
                    name,
                    value,
                    reason: "must be positive and finite",
                });
            }
        }
        let non_negative = [
            ("d_g", self.d_g),
            ("b_g", self.b_g),
            ("b_f", self.b_f),
            ("d_s", self.d_s),
            ("d_eh", self.d_eh),
            ("b_h", self.b_h),
        ];
        for (name, value) in non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return Err(super::BackSupportError::Parameter {
                    name,
                    value,
                    reason: "must be non-negative and finite",
                });
            }
        }
        Ok(())
    }
}
