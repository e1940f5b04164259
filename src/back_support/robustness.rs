//! Margins of the loop broken at the plant input and the disturbance rejection from the trunk velocity
//! (Sec. 5.2, Figs. 13–15), for the double-integral LQR with the continuous observer of Eq. 9.
//!
//! The controller, from the measurements `y = [y_v; y_t]` to `τ_m` (Fig. 12 with `τ_ref = 0`), has the state
//! `[x̂; z; ∫z]`:
//!
//! `x̂' = (A₁ − B_m K_x − L C) x̂ − B_m K_z z − B_m K_∫z ∫z + L y`, `ż = −C_b x̂`, `(∫z)' = z`,
//! `τ_m = −K_x x̂ − K_z z − K_∫z ∫z`.
//!
//! The loop at the plant input is `L_in = −C(s) P(s)` with `P = (A₁, B_m, [C_v; C_t])`, and its margins follow
//! python-control's `stability_margins` (`bgc_runtime::analysis`). For comparison, the loop of the LQR with
//! the full state measured, `K (sI − A_aug)⁻¹ B_aug`, is reported too.
//!
//! The controller that actually runs (the scenario's) is sampled at `T`: the current-estimate Kalman filter
//! with its innovation gain `M`, the LQR on `x̂[k|k]` and forward-Euler integrators. With the prior estimate
//! `x̂⁻` as its state, `x̂[k|k] = (I − M C) x̂⁻ + M y`, it reads
//!
//! `x̂⁻' = A_d x̂[k|k] + B_d τ_m`, `z' = z − T C_b x̂[k|k]`, `(∫z)' = ∫z + T z`,
//! `τ_m = −K_x x̂[k|k] − K_z z − K_∫z ∫z`,
//!
//! and its loop with the zero-order-hold plant `(A_d, B_d, [C_v; C_t])` is analysed the same way
//! ([`sampled_controller`]); its frequency response includes the sampling and the hold.
//!
//! The disturbance path is the closed loop from the true trunk velocity (entering plant and observer, Eq. 8)
//! to the estimated torque on the body `ŷ_b = C_b x̂ − d_eh θ̇_h`, state `[δ; x̂; z; ∫z]`. With two integrators
//! of the torque error its DC gain is zero: a constant trunk velocity is rejected completely, and "the first
//! frequency at which the gain falls 3 dB below its DC value" does not exist. We report instead the
//! rejection bandwidth of Skogestad & Postlethwaite (Sec. 2.4.5): the lowest frequency at which the ratio of
//! the closed-loop to the open-loop (`τ_m = 0`) response rises through −3 dB, i.e. up to which the control
//! attenuates the trunk's effect on the body torque; and the frequency of the peak of the closed-loop gain
//! (the "most destructive" trunk motion of the paper).

use nalgebra::DMatrix;

use bgc_runtime::analysis::{
    Resolvent, StabilityMargins, dc_gain, logspace, loop_at_plant_input, peak_gain,
    stability_margins,
};
use bgc_runtime::statespace::StateSpace;

use super::BackSupportError;
use super::lqr::LqrDesign;
use super::observer::ObserverDesign;
use super::plant::DesignModel;

/// The frequency-domain figures of the design.
#[derive(Clone, Debug, PartialEq)]
pub struct Robustness {
    /// Margins of the observer-based loop broken at the plant input.
    pub observer_loop: StabilityMargins,
    /// Margins of the sampled loop at the plant input (controller of the scenario, zero-order-hold plant).
    pub sampled_loop: StabilityMargins,
    /// Margins of the full-state LQR loop broken at the plant input.
    pub state_feedback_loop: StabilityMargins,
    /// `|T(0)|` of the disturbance path (N m per rad/s).
    pub disturbance_dc_gain: f64,
    /// Peak of `|T(jω)|` (N m per rad/s) and its frequency (Hz).
    pub disturbance_peak_gain: f64,
    pub disturbance_peak_frequency_hz: f64,
    /// The rejection bandwidth (Hz), if the ratio crosses −3 dB in the scanned range.
    pub rejection_bandwidth_hz: Option<f64>,
    /// The observer-based loop transfer at the plant input (for Nyquist plots).
    pub loop_at_input: StateSpace,
    /// The full-state LQR loop transfer `K (sI − A_aug)⁻¹ B_aug` (for Nyquist plots).
    pub state_feedback_loop_transfer: StateSpace,
    /// The disturbance path as a model (for Bode plots).
    pub disturbance_path: StateSpace,
    /// The uncontrolled disturbance path `(A₁, B_h, C_b, d_b)`.
    pub open_loop_disturbance_path: StateSpace,
}

/// The observer-based controller of the module docs, from `[y_v; y_t]` to `τ_m`.
pub fn controller(
    model: &DesignModel,
    lqr: &LqrDesign,
    l: &DMatrix<f64>,
) -> Result<StateSpace, BackSupportError> {
    let (kx, kz, kzz) = gains(lqr)?;
    let mut a = DMatrix::zeros(8, 8);
    a.view_mut((0, 0), (6, 6))
        .copy_from(&(&model.a - &model.b_m * &kx - l * &model.c_meas));
    a.view_mut((0, 6), (6, 1)).copy_from(&(&model.b_m * -kz));
    a.view_mut((0, 7), (6, 1)).copy_from(&(&model.b_m * -kzz));
    a.view_mut((6, 0), (1, 6)).copy_from(&(-&model.c_b));
    a[(7, 6)] = 1.0;
    let mut b = DMatrix::zeros(8, 2);
    b.view_mut((0, 0), (6, 2)).copy_from(l);
    let mut c = DMatrix::zeros(1, 8);
    c.view_mut((0, 0), (1, 6)).copy_from(&(-&kx));
    c[(0, 6)] = -kz;
    c[(0, 7)] = -kzz;
    Ok(StateSpace::new(a, b, c, DMatrix::zeros(1, 2))?)
}

fn gains(lqr: &LqrDesign) -> Result<(DMatrix<f64>, f64, f64), BackSupportError> {
    if lqr.k.len() != 8 {
        return Err(BackSupportError::Setup {
            what: "the robustness analysis needs a double-integral design (8 gains)",
        });
    }
    Ok((
        DMatrix::from_row_slice(1, 6, &lqr.k[..6]),
        lqr.k[6],
        lqr.k[7],
    ))
}

/// The sampled controller of the module docs, from `[y_v; y_t]` to `τ_m`, for the zero-order-hold model
/// `(a_d, b_d)` of `(A₁, B_m)` at sample time `dt` and the innovation gain `m`.
pub fn sampled_controller(
    model: &DesignModel,
    lqr: &LqrDesign,
    a_d: &DMatrix<f64>,
    b_d: &DMatrix<f64>,
    m: &DMatrix<f64>,
    dt: f64,
) -> Result<StateSpace, BackSupportError> {
    let (kx, kz, kzz) = gains(lqr)?;
    // x̂[k|k] = E x̂⁻ + M y with E = I − M C.
    let e = DMatrix::<f64>::identity(6, 6) - m * &model.c_meas;
    // τ_m = −K_x E x̂⁻ − K_z z − K_∫z ∫z − K_x M y.
    let mut c = DMatrix::zeros(1, 8);
    c.view_mut((0, 0), (1, 6)).copy_from(&(-(&kx * &e)));
    c[(0, 6)] = -kz;
    c[(0, 7)] = -kzz;
    let d = -(&kx * m);
    // x̂⁻' = A_d (E x̂⁻ + M y) + B_d τ_m = (A_d E + B_d C) [x̂⁻; ·] + B_d (−K_z z − K_∫z ∫z) + (A_d M + B_d D) y.
    let mut a = DMatrix::zeros(8, 8);
    a.view_mut((0, 0), (6, 8)).copy_from(&(b_d * &c));
    let top_left = a.view((0, 0), (6, 6)) + a_d * &e;
    a.view_mut((0, 0), (6, 6)).copy_from(&top_left);
    let mut b = DMatrix::zeros(8, 2);
    b.view_mut((0, 0), (6, 2)).copy_from(&(a_d * m + b_d * &d));
    // z' = z − T C_b (E x̂⁻ + M y), (∫z)' = ∫z + T z.
    a.view_mut((6, 0), (1, 6))
        .copy_from(&(&model.c_b * &e * -dt));
    a[(6, 6)] = 1.0;
    a[(7, 6)] = dt;
    a[(7, 7)] = 1.0;
    b.view_mut((6, 0), (1, 2))
        .copy_from(&(&model.c_b * m * -dt));
    Ok(StateSpace::new_discrete(a, b, c, d, dt)?)
}

/// The closed loop from the trunk velocity to the estimated torque on the body (module docs).
pub fn disturbance_path(
    model: &DesignModel,
    lqr: &LqrDesign,
    l: &DMatrix<f64>,
) -> Result<StateSpace, BackSupportError> {
    let (kx, kz, kzz) = gains(lqr)?;
    let n = 14;
    let mut a = DMatrix::zeros(n, n);
    let bm = &model.b_m;
    // Plant δ' = A₁ δ + B_m τ_m + B_h θ̇_h with τ_m = −K_x x̂ − K_z z − K_∫z ∫z.
    a.view_mut((0, 0), (6, 6)).copy_from(&model.a);
    a.view_mut((0, 6), (6, 6)).copy_from(&(-(bm * &kx)));
    a.view_mut((0, 12), (6, 1)).copy_from(&(bm * -kz));
    a.view_mut((0, 13), (6, 1)).copy_from(&(bm * -kzz));
    // Observer x̂' = A₁ x̂ + B_m τ_m + B_h θ̇_h + L C (δ − x̂).
    a.view_mut((6, 0), (6, 6)).copy_from(&(l * &model.c_meas));
    a.view_mut((6, 6), (6, 6))
        .copy_from(&(&model.a - bm * &kx - l * &model.c_meas));
    a.view_mut((6, 12), (6, 1)).copy_from(&(bm * -kz));
    a.view_mut((6, 13), (6, 1)).copy_from(&(bm * -kzz));
    // z' = −ŷ_b = −C_b x̂ − d_b θ̇_h (τ_ref = 0), (∫z)' = z.
    a.view_mut((12, 6), (1, 6)).copy_from(&(-&model.c_b));
    a[(13, 12)] = 1.0;
    let mut b = DMatrix::zeros(n, 1);
    b.view_mut((0, 0), (6, 1)).copy_from(&model.b_h);
    b.view_mut((6, 0), (6, 1)).copy_from(&model.b_h);
    b[(12, 0)] = -model.d_b;
    let mut c = DMatrix::zeros(1, n);
    c.view_mut((0, 6), (1, 6)).copy_from(&model.c_b);
    let d = DMatrix::from_element(1, 1, model.d_b);
    Ok(StateSpace::new(a, b, c, d)?)
}

/// Frequencies (Hz) scanned for the rejection bandwidth, and points.
const SCAN_LOW_HZ: f64 = 1e-3;
const SCAN_HIGH_HZ: f64 = 1e4;
const SCAN_POINTS: usize = 2001;

/// The lowest frequency (Hz) at which `|num(jω)| / |den(jω)|` rises through `level_db`, by a logarithmic scan
/// and bisection.
fn ratio_crossing(
    num: &StateSpace,
    den: &StateSpace,
    level_db: f64,
) -> Result<Option<f64>, BackSupportError> {
    let (num, den) = (Resolvent::new(num), Resolvent::new(den));
    let f = |hz: f64| -> Result<f64, BackSupportError> {
        let w = 2.0 * std::f64::consts::PI * hz;
        let ratio = num.siso(w)?.norm() / den.siso(w)?.norm();
        Ok(20.0 * ratio.log10() - level_db)
    };
    let grid = logspace(SCAN_LOW_HZ, SCAN_HIGH_HZ, SCAN_POINTS)?;
    let mut prev: Option<(f64, f64)> = None;
    for &hz in &grid {
        let v = f(hz)?;
        if let Some((h0, v0)) = prev
            && v0 < 0.0
            && v >= 0.0
        {
            let (mut lo, mut hi) = (h0, hz);
            for _ in 0..100 {
                let mid = (lo * hi).sqrt();
                if f(mid)? < 0.0 { lo = mid } else { hi = mid }
            }
            return Ok(Some((lo * hi).sqrt()));
        }
        prev = Some((hz, v));
    }
    Ok(None)
}

/// Margins and disturbance rejection of the double-integral design with the continuous observer gain `l`, and
/// the margins of the sampled loop of `observer`'s discrete filter.
pub fn analyse(
    model: &DesignModel,
    lqr: &LqrDesign,
    l: &DMatrix<f64>,
    observer: &ObserverDesign,
) -> Result<Robustness, BackSupportError> {
    let plant = StateSpace::new(
        model.a.clone(),
        model.b_m.clone(),
        model.c_meas.clone(),
        DMatrix::zeros(2, 1),
    )?;
    let ctl = controller(model, lqr, l)?;
    let loop_at_input = loop_at_plant_input(&plant, &ctl)?;
    let observer_loop = stability_margins(&loop_at_input)?;
    let dt = observer.sample_time;
    let b_d = observer.b_d.columns(0, 1).clone_owned();
    let plant_d = StateSpace::new_discrete(
        observer.a_d.clone(),
        b_d.clone(),
        model.c_meas.clone(),
        DMatrix::zeros(2, 1),
        dt,
    )?;
    let ctl_d = sampled_controller(
        model,
        lqr,
        &observer.a_d,
        &b_d,
        &observer.discrete.filter_gain,
        dt,
    )?;
    let sampled_loop = stability_margins(&loop_at_plant_input(&plant_d, &ctl_d)?)?;
    let (kx, kz, kzz) = gains(lqr)?;
    let mut a_aug = DMatrix::zeros(8, 8);
    a_aug.view_mut((0, 0), (6, 6)).copy_from(&model.a);
    a_aug.view_mut((6, 0), (1, 6)).copy_from(&(-&model.c_b));
    a_aug[(7, 6)] = 1.0;
    let mut b_aug = DMatrix::zeros(8, 1);
    b_aug.view_mut((0, 0), (6, 1)).copy_from(&model.b_m);
    let mut k = DMatrix::zeros(1, 8);
    k.view_mut((0, 0), (1, 6)).copy_from(&kx);
    k[(0, 6)] = kz;
    k[(0, 7)] = kzz;
    let state_feedback_loop_transfer = StateSpace::new(a_aug, b_aug, k, DMatrix::zeros(1, 1))?;
    let state_feedback_loop = stability_margins(&state_feedback_loop_transfer)?;
    let path = disturbance_path(model, lqr, l)?;
    let open = StateSpace::new(
        model.a.clone(),
        model.b_h.clone(),
        model.c_b.clone(),
        DMatrix::from_element(1, 1, model.d_b),
    )?;
    let (peak, peak_w) = peak_gain(&path)?;
    Ok(Robustness {
        observer_loop,
        sampled_loop,
        state_feedback_loop,
        disturbance_dc_gain: dc_gain(&path)?[(0, 0)].abs(),
        disturbance_peak_gain: peak,
        disturbance_peak_frequency_hz: peak_w / (2.0 * std::f64::consts::PI),
        rejection_bandwidth_hz: ratio_crossing(&path, &open, -3.0)?,
        loop_at_input,
        state_feedback_loop_transfer,
        disturbance_path: path,
        open_loop_disturbance_path: open,
    })
}
