//! LQR with single and double integral action on the torque on the human body (Sec. 5.2, Eqs. 10–17), on the
//! 6-state design model `(A₁, B_m, C_b)` of [`super::plant`].
//!
//! Augmented states `[x; z]` with `ż = τ_ref − y_b` (Eq. 10) and `[x; z; ∫z]` (Eq. 12); control law
//! `u = −K [x; z; ∫z]` (Eqs. 11, 13), so that the integral gains come out negative as in Eq. 17. Weights of
//! Eqs. 14 and 15; the gains are computed by `bgc_runtime::design::lqi`.
//!
//! # The printed weights against the printed gains
//!
//! For an integrator state `z` whose column of the augmented `A` is zero (nothing depends on `z` but the
//! control), the `(z, z)` entry of the Riccati equation `AᵀX + XA − XBR⁻¹BᵀX + Q = 0` reduces to
//! `q_z − (BᵀX)_z² / r = 0`, so `|K_z| = √(q_z / r)`: the weights alone fix it. That holds for the single
//! integrator of Eq. 10 and for the outer integrator `∫z` of Eq. 12 (the inner `z` feeds `∫z`, so its gain is
//! not fixed this way). Hence:
//!
//! - Eq. 15 with Eq. 17: `√(5·10¹⁵ / 10¹²) = 70.71` — consistent;
//! - Eq. 14 with Eq. 17: `√(5·10¹³ / 10¹²) = 7.07`, but Eq. 17 prints `3.16 = √(10¹³ / 10¹²)`. With
//!   `q_z = 10¹³` the design reproduces all of Eq. 16 to its two printed decimals, so Eq. 14's `5·10¹³` is a
//!   misprint for `10¹³` (or the gains were computed with other weights than those printed).
//!
//! If the same misprint affects Eq. 15, its design is [`LqrDesigns::double_reproducing`]; the example runs the
//! scenario with both (with `q_z = 10¹³` the peak motor torque stays inside the paper's ±0.56 N m, with the
//! printed `5·10¹³` it does not).
//!
//! Eq. 13 writes the double-integral law with the single design's `F'_ix`, `F'_iz`; the LQR of Eq. 12 gives
//! its own state and inner-integral gains (reported by [`LqrDesigns::double`]).

use nalgebra::{Complex, DMatrix, DVector};

use bgc_runtime::design::{IntegralAction, lqi};

use super::BackSupportError;
use super::plant::DesignModel;

/// `F'_ix` of Eq. 16.
pub const PAPER_STATE_GAIN: [f64; 6] = [1.00, 0.03, 0.64, 0.0, 0.02, 0.0];
/// `F'_iz` of Eq. 17 (single integral action).
pub const PAPER_SINGLE_INTEGRAL_GAIN: f64 = -3.16;
/// `F_iz` of Eq. 17 (the outer integrator of the double integral action).
pub const PAPER_DOUBLE_INTEGRAL_GAIN: f64 = -70.71;

/// State weights of Eqs. 14 and 15 (the first six entries).
pub const STATE_WEIGHTS: [f64; 6] = [1e5, 1e5, 1e7, 1e7, 1e7, 1e7];
/// The weight of `z` printed in Eqs. 14 and 15.
pub const PRINTED_Z_WEIGHT: f64 = 5e13;
/// The weight of `z` that reproduces Eqs. 16–17 (`F'_iz = −√(10¹³/10¹²)`).
pub const REPRODUCING_Z_WEIGHT: f64 = 1e13;
/// The weight of `∫z` of Eq. 15.
pub const OUTER_Z_WEIGHT: f64 = 5e15;
/// `R'_c = R_c` of Eqs. 14–15.
pub const CONTROL_WEIGHT: f64 = 1e12;

/// One LQR design with integral action.
#[derive(Clone, Debug, PartialEq)]
pub struct LqrDesign {
    /// The diagonal of `Q` (7 or 8 entries).
    pub q: Vec<f64>,
    pub r: f64,
    /// `K` on `[x; z]` or `[x; z; ∫z]`, `u = −K [...]`.
    pub k: Vec<f64>,
    pub closed_loop_eigenvalues: Vec<Complex<f64>>,
    pub relative_residual: f64,
}

impl LqrDesign {
    /// The state part `K_x` (the first six entries; fewer if `k` is shorter).
    pub fn state_gain(&self) -> &[f64] {
        &self.k[..self.k.len().min(6)]
    }

    /// The gain of the outermost integrator (`z` for single, `∫z` for double action).
    pub fn outer_integral_gain(&self) -> Option<f64> {
        self.k.get(6..).and_then(|tail| tail.last().copied())
    }

    /// `√(q_outer / r)`: the magnitude the outer integral gain must have (module docs).
    pub fn outer_gain_from_weights(&self) -> Option<f64> {
        self.q
            .get(6..)
            .and_then(|tail| tail.last())
            .map(|q| (q / self.r).sqrt())
    }
}

/// The designs the example reports.
#[derive(Clone, Debug, PartialEq)]
pub struct LqrDesigns {
    /// Single integral action with the weights printed in Eq. 14.
    pub single: LqrDesign,
    /// Single integral action with `q_z = 10¹³`, which reproduces Eqs. 16–17.
    pub single_reproducing: LqrDesign,
    /// Double integral action with the weights of Eq. 15 (used in the scenario).
    pub double: LqrDesign,
    /// Double integral action with Eq. 15's `q_z` replaced by the `10¹³` that Eqs. 16–17 imply.
    pub double_reproducing: LqrDesign,
}

/// One design: `q` is the diagonal of `Q`, its length selects single (7) or double (8) action.
pub fn design(model: &DesignModel, q: &[f64], r: f64) -> Result<LqrDesign, BackSupportError> {
    let action = match q.len() {
        7 => IntegralAction::Single,
        8 => IntegralAction::Double,
        _ => {
            return Err(BackSupportError::Setup {
                what: "the LQR weight diagonal must have 7 (single) or 8 (double integral) entries",
            });
        }
    };
    let qm = DMatrix::from_diagonal(&DVector::from_column_slice(q));
    let rm = DMatrix::from_element(1, 1, r);
    let sol = lqi(&model.a, &model.b_m, &model.c_b, &qm, &rm, action)?;
    Ok(LqrDesign {
        q: q.to_vec(),
        r,
        k: sol.k.iter().copied().collect(),
        closed_loop_eigenvalues: sol.closed_loop_eigenvalues,
        relative_residual: sol.relative_residual,
    })
}

/// The designs of Eqs. 14–15, and both again with the `q_z = 10¹³` that reproduces Eqs. 16–17.
pub fn designs(model: &DesignModel) -> Result<LqrDesigns, BackSupportError> {
    let weights =
        |tail: &[f64]| -> Vec<f64> { STATE_WEIGHTS.iter().chain(tail).copied().collect() };
    Ok(LqrDesigns {
        single: design(model, &weights(&[PRINTED_Z_WEIGHT]), CONTROL_WEIGHT)?,
        single_reproducing: design(model, &weights(&[REPRODUCING_Z_WEIGHT]), CONTROL_WEIGHT)?,
        double: design(
            model,
            &weights(&[PRINTED_Z_WEIGHT, OUTER_Z_WEIGHT]),
            CONTROL_WEIGHT,
        )?,
        double_reproducing: design(
            model,
            &weights(&[REPRODUCING_Z_WEIGHT, OUTER_Z_WEIGHT]),
            CONTROL_WEIGHT,
        )?,
    })
}
