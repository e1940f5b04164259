//! The observer from the motor velocity and the sensor torque (Sec. 3, Eqs. 4–9) with the noise of Sec. 4.
//!
//! # Noise
//!
//! Sec. 4 bounds the noises: `|w_τm| ≤ 0.1·10⁻³ N m` (motor torque), `|w_θ̇h| ≤ 0.15·10⁻³ rad/s` (trunk
//! velocity), `|v_v| ≤ 0.1·10⁻⁶ rad/s` (encoder velocity), `|v_t| ≤ 35·10⁻³ N m` (torque sensor). We read each
//! bound as three standard deviations of a zero-mean Gaussian (`σ = bound / 3`, so 99.7 % of the samples
//! respect it), sampled and held at the control rate `T = 1 ms` as the simulation does. A uniform reading
//! (`σ = bound/√3`) scales every variance by the same factor 3, which leaves all gains below unchanged.
//!
//! - Discrete filter at `T`: the held input noises enter through the zero-order-hold input matrix, `Q_d =
//!   B_d diag(σ_τ², σ_h²) B_dᵀ` (exact), `R_d = diag(σ_v², σ_t²)`.
//! - Continuous observer (Eq. 9): intensities `Q = diag(σ_τ², σ_h²) T`, `R = diag(σ_v², σ_t²) T` (the
//!   low-frequency spectral density of noise held over `T`).
//!
//! # The paper's 7-state observer is not detectable
//!
//! Eq. 9 is posed on `A'` (7 states, with `θ_h`) and the measurements `y_v`, `y_t`. Neither sees the rigid
//! rotation `v = [r_g, 0, 1, 0, 1, 0, 1]` of the chain with the trunk: `A' v = 0` and `C' v = 0`, an
//! unobservable mode at `λ = 0`, which is not asymptotically stable, so the pair is not detectable and Eq. 9
//! has no stabilising solution (the text's `C' = [C_v; C_b]` with `C_b` completed by Eq. 6 to the torque on
//! the body, `−k_eh` on `θ_h`, is blind to it as well). The runtime's PBH test names the mode and its
//! direction, and `lqe` refuses the design with that mode ([`seven_state_check`]).
//!
//! # The design that works
//!
//! The angles relative to the trunk ([`super::plant::DesignModel`]) remove the rigid rotation: the 6-state
//! model `(A₁, [B_m B_h], [C_v; C_t])` with the trunk velocity as a known input is observable, and the torque
//! on the body `y_b = C_b δ − d_eh θ̇_h` is a function of its state. [`design`] computes the continuous gain of
//! Eq. 9 for it and the discrete steady-state Kalman filter at the control rate.

use nalgebra::{Complex, DMatrix, DVector};

use bgc_runtime::design::{DiscreteKalman, Kalman, dlqe, lqe};
use bgc_runtime::linalg::{Domain, Mode, RiccatiError, c2d_zoh, is_detectable, unobservable_modes};
use bgc_runtime::matrix::dynamic;

use super::BackSupportError;
use super::params::Params;
use super::plant::{DesignModel, Plant};

/// The noise bounds of Sec. 4: motor torque (N m), trunk velocity (rad/s), encoder velocity (rad/s), torque
/// sensor (N m).
pub const NOISE_BOUNDS: [f64; 4] = [0.1e-3, 0.15e-3, 0.1e-6, 35e-3];

/// Standard deviations of the noises (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoiseModel {
    /// Motor torque `σ_τ` (N m).
    pub motor_torque: f64,
    /// Trunk velocity `σ_h` (rad/s).
    pub trunk_velocity: f64,
    /// Encoder velocity `σ_v` (rad/s).
    pub motor_velocity: f64,
    /// Torque sensor `σ_t` (N m).
    pub sensor_torque: f64,
}

impl NoiseModel {
    /// The bounds of Sec. 4 read as 3σ.
    pub fn three_sigma() -> Self {
        let [t, h, v, s] = NOISE_BOUNDS.map(|b| b / 3.0);
        NoiseModel {
            motor_torque: t,
            trunk_velocity: h,
            motor_velocity: v,
            sensor_torque: s,
        }
    }

    fn input_variances(&self) -> DMatrix<f64> {
        DMatrix::from_diagonal(&DVector::from_column_slice(&[
            self.motor_torque.powi(2),
            self.trunk_velocity.powi(2),
        ]))
    }

    fn measurement_variances(&self) -> DMatrix<f64> {
        DMatrix::from_diagonal(&DVector::from_column_slice(&[
            self.motor_velocity.powi(2),
            self.sensor_torque.powi(2),
        ]))
    }
}

/// What the runtime says about one measurement matrix of the 7-state observer of Eq. 9.
#[derive(Clone, Debug, PartialEq)]
pub struct SevenStateCase {
    pub name: &'static str,
    /// The measurement matrix (rows over the 7 plant states).
    pub c: DMatrix<f64>,
    pub detectable: bool,
    /// The unobservable modes by the PBH test.
    pub unobservable: Vec<Mode>,
    /// The outcome of the continuous Kalman design (`lqe`) on `(A', C')`.
    pub lqe: Result<Kalman, RiccatiError>,
}

/// The 7-state observer of Eq. 9 with the measured outputs `[C_v; C_t]` and with the text's `[C_v; C_b]`
/// (completed by Eq. 6).
pub fn seven_state_check(
    plant: &Plant,
    noise: &NoiseModel,
    sample_time: f64,
) -> Result<Vec<SevenStateCase>, BackSupportError> {
    let a = dynamic(&plant.a);
    let g = dynamic(&plant.b);
    let qn = noise.input_variances() * sample_time;
    let rn = noise.measurement_variances() * sample_time;
    let rows = |r0: usize, r1: usize| -> DMatrix<f64> {
        DMatrix::from_fn(2, 7, |i, j| plant.c[(if i == 0 { r0 } else { r1 }, j)])
    };
    let cases = [
        ("[C_v; C_t] (measured)", rows(0, 1)),
        ("[C_v; C_b] (text, Eq. 6)", rows(0, 2)),
    ];
    cases
        .into_iter()
        .map(|(name, c)| {
            Ok(SevenStateCase {
                name,
                detectable: is_detectable(&a, &c, Domain::Continuous)?,
                unobservable: unobservable_modes(&a, &c)?,
                lqe: lqe(&a, &g, &c, &qn, &rn),
                c,
            })
        })
        .collect()
}

/// The observers of the working design.
#[derive(Clone, Debug, PartialEq)]
pub struct ObserverDesign {
    pub noise: NoiseModel,
    pub sample_time: f64,
    /// Whether `(A₁, [C_v; C_t])` is observable (no unobservable mode by the PBH test).
    pub observable: bool,
    /// The continuous observer of Eq. 9 on the 6-state model.
    pub continuous: Kalman,
    /// The zero-order-hold model at the sample time (inputs `[τ_m, θ̇_h]`).
    pub a_d: DMatrix<f64>,
    pub b_d: DMatrix<f64>,
    /// `Q_d`, `R_d` of the discrete filter.
    pub q_d: DMatrix<f64>,
    pub r_d: DMatrix<f64>,
    /// The discrete steady-state Kalman filter.
    pub discrete: DiscreteKalman,
    /// The steady-state variances of the filtered estimates' errors the filter predicts (`Z` of
    /// [`DiscreteKalman`]): human torque `C_b Z C_bᵀ` (N² m²) and motor velocity `Z₂₂` (rad²/s²).
    pub predicted_human_torque_variance: f64,
    pub predicted_motor_velocity_variance: f64,
}

/// Continuous and discrete observers on the 6-state design model (module docs).
pub fn design(
    model: &DesignModel,
    noise: &NoiseModel,
    sample_time: f64,
) -> Result<ObserverDesign, BackSupportError> {
    let ss = model.measurement_model()?;
    let observable = unobservable_modes(ss.a(), ss.c())?.is_empty();
    let continuous = lqe(
        ss.a(),
        ss.b(),
        ss.c(),
        &(noise.input_variances() * sample_time),
        &(noise.measurement_variances() * sample_time),
    )?;
    let d = c2d_zoh(&ss, sample_time)?;
    let q_in = noise.input_variances();
    let q_d = d.b() * &q_in * d.b().transpose();
    let r_d = noise.measurement_variances();
    let discrete = dlqe(d.a(), d.b(), ss.c(), &q_in, &r_d)?;
    let predicted_human_torque_variance =
        (&model.c_b * &discrete.z * model.c_b.transpose())[(0, 0)];
    let predicted_motor_velocity_variance = discrete.z[(1, 1)];
    Ok(ObserverDesign {
        noise: *noise,
        sample_time,
        observable,
        continuous,
        a_d: d.a().clone(),
        b_d: d.b().clone(),
        q_d: (&q_d + q_d.transpose()) * 0.5,
        r_d,
        discrete,
        predicted_human_torque_variance,
        predicted_motor_velocity_variance,
    })
}

/// A mode direction normalised to `θ_m = 1` (unchanged if its `θ_m` entry is zero), for printing.
pub fn normalised_direction(mode: &Mode) -> Vec<Complex<f64>> {
    match mode.direction.iter().next() {
        Some(&pivot) if pivot.norm() > 0.0 => mode.direction.iter().map(|z| z / pivot).collect(),
        _ => mode.direction.iter().copied().collect(),
    }
}

/// The direction expected for the unobservable rigid rotation, normalised to `θ_m = 1`.
pub fn expected_rigid_direction(p: &Params) -> Vec<f64> {
    super::plant::rigid_rotation(p)
        .iter()
        .map(|v| v / p.r_g)
        .collect()
}
