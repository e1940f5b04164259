//! LQR with integral action on chosen outputs: [`lqi`] (the design, its source and its sign conventions are in
//! its documentation).

use nalgebra::{Complex, DMatrix};

use super::DesignError;
use crate::linalg::care;
use crate::linalg::check;

/// The number of integrators per integrated output.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegralAction {
    /// `ż₁ = r − C_I x` (Eq. 10).
    Single,
    /// `ż₁ = r − C_I x`, `ż₂ = z₁` (Eq. 12).
    Double,
}

impl IntegralAction {
    fn count(self) -> usize {
        match self {
            IntegralAction::Single => 1,
            IntegralAction::Double => 2,
        }
    }
}

/// An LQR design with integral action; `u = −K_x x − K_z₁ z₁ − K_z₂ z₂`.
#[derive(Clone, Debug, PartialEq)]
pub struct Lqi {
    /// The full gain `[K_x, K_z₁, (K_z₂)]` on the augmented state.
    pub k: DMatrix<f64>,
    /// The state gain `K_x` (`m x n`).
    pub kx: DMatrix<f64>,
    /// The gain `K_z₁` on the error integrals `z₁ = ∫(r − C_I x)` (`m x p`).
    pub kz1: DMatrix<f64>,
    /// The gain `K_z₂` on `z₂ = ∫z₁` (`m x p`), for double action.
    pub kz2: Option<DMatrix<f64>>,
    /// The augmented `A_aug`, `B_aug` the gain was designed for.
    pub a_aug: DMatrix<f64>,
    pub b_aug: DMatrix<f64>,
    /// The stabilising Riccati solution of the augmented problem.
    pub x: DMatrix<f64>,
    /// The eigenvalues of `A_aug − B_aug K`.
    pub closed_loop_eigenvalues: Vec<Complex<f64>>,
    pub relative_residual: f64,
}

/// LQR with integral action on chosen outputs (Shojaei Barjuei, Caldwell & Ortiz, Designs 2020, 4, 53,
/// Sec. 5.2, Eqs. 10–13).
///
/// The plant `ẋ = A x + B u` is augmented with integrators of the tracking error of the outputs
/// `y_I = C_I x` (`p` rows):
///
/// - single action (Eq. 10): `ż₁ = r − C_I x`; augmented state `[x; z₁]`,
///   `A_aug = [A 0; −C_I 0]`, `B_aug = [B; 0]`;
/// - double action (Eq. 12): additionally `ż₂ = z₁`, i.e. the second integrator integrates the first
///   integrator's state (the time integral of the error integral); augmented state `[x; z₁; z₂]`,
///   `A_aug = [A 0 0; −C_I 0 0; 0 I 0]`, `B_aug = [B; 0; 0]`.
///
/// Eq. 12 of the paper prints the last row of `A_i` with seven entries, "0 0 0 0 0 1 0", for an 8-column
/// matrix, so the position of the 1 is ambiguous. We read it as the 1 in the column of `z₁` (row
/// `[0₁ₓ₆, 1, 0]`), because the control law of Eq. 13, `u = −F'ᵢₓx − F'ᵢ_z z − F_iz ∫₀ᵗ z dτ`, feeds back the
/// integral of `z`, and because the stated purpose (rejecting ramps of the trunk angle) needs two integrators
/// of the torque error; a 1 in the column of `θ̇_s_ext` would integrate a velocity, not the error.
///
/// The gain is the LQR gain of the augmented system, `u = −K [x; z₁; z₂] = −K_x x − K_z₁ z₁ − K_z₂ z₂`, for the
/// weights `Q` (size `n + p` or `n + 2p`) and `R`; the reference `r` enters only the integrators and is zero in
/// the design. In closed loop `ẋ_aug = (A_aug − B_aug K) x_aug + E r` with `E = [0; I; 0]` (the `τ_ref` column
/// of Eq. 10). Single action removes the steady-state error of `y_I` for constant references and
/// disturbances; double action also for ramps (the paper's motivation: the trunk angle ramps while the trunk
/// moves at constant velocity). Sign conventions:
///
/// - This is MATLAB's `lqi` convention (`ż = r − y`, `u = −K[x; z]`): with it the integral gains of a plant
///   whose output rises with `u` come out negative, as the paper's `F'ᵢ_z = −3.16`, `F_iz = −70.71` (Eq. 17).
/// - python-control's `lqr(A, B, Q, R, integral_action=C)` augments with `ż = C x` (no minus sign, no
///   reference): its state gains equal `K_x` and its integral gains are `−K_z₁`. It has no double action.
///
/// `q` weights the augmented state `[x; z₁]` or `[x; z₁; z₂]`, `r` the inputs.
pub fn lqi(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    c_int: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    action: IntegralAction,
) -> Result<Lqi, DesignError> {
    let n = check::square("A", a)?;
    let m = b.ncols();
    check::shape("B", b, n, m)?;
    let p = c_int.nrows();
    check::shape("C_I", c_int, p, n)?;
    let levels = action.count();
    let na = n + levels * p;
    check::shape("Q", q, na, na)?;

    let mut a_aug = DMatrix::<f64>::zeros(na, na);
    a_aug.view_mut((0, 0), (n, n)).copy_from(a);
    a_aug.view_mut((n, 0), (p, n)).copy_from(&(-c_int));
    if action == IntegralAction::Double {
        a_aug
            .view_mut((n + p, n), (p, p))
            .copy_from(&DMatrix::<f64>::identity(p, p));
    }
    let mut b_aug = DMatrix::<f64>::zeros(na, m);
    b_aug.view_mut((0, 0), (n, m)).copy_from(b);

    let sol = care(&a_aug, &b_aug, q, r)?;
    let kx = sol.k.view((0, 0), (m, n)).clone_owned();
    let kz1 = sol.k.view((0, n), (m, p)).clone_owned();
    let kz2 =
        (action == IntegralAction::Double).then(|| sol.k.view((0, n + p), (m, p)).clone_owned());
    Ok(Lqi {
        k: sol.k,
        kx,
        kz1,
        kz2,
        a_aug,
        b_aug,
        x: sol.x,
        closed_loop_eigenvalues: sol.closed_loop_eigenvalues,
        relative_residual: sol.relative_residual,
    })
}
