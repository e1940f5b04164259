//! The lifting scenario of Sec. 5.2: the trunk moves at a constant 0.1 rad/s from rest at `t = 0`; the
//! reference torque on the body is 10 N m from 0.1 s for 0.5 s; the double-integral LQR acts on the discrete
//! Kalman filter's estimate in a sampled-data loop at 1 kHz with the noise of [`super::observer`].
//!
//! Each sample `k` (time `t_k`): the filter predicts with the previous input, `x̂⁻ = A_d x̂ + B_d [τ_m; θ̇_h]`
//! (the trunk velocity is a known input, Eq. 8), updates with the noisy `y_v`, `y_t`, and the controller
//! applies `τ_m = −K_x x̂ − K_z z − K_∫z ∫z` (Eq. 13) held over the interval; the integrators advance by forward
//! Euler, `z ← z + T (τ_ref − ŷ_b)`, `∫z ← ∫z + T z`, with the estimated torque `ŷ_b = C_b x̂ − d_eh θ̇_h`
//! (Fig. 12). The plant is [`super::plant`] in absolute angles, advanced exactly over each held interval by
//! `bgc_runtime::sim::simulate_sampled_linear_loop` (the zero-order-hold step; [`PlantIntegration::Ode`]
//! integrates it with an ODE solver instead, as a check), with the input noises as held process disturbances
//! (`w_τm / (J_m + J_g)` on `θ̈_m`, `w_θ̇h` on `θ̇_h`) and the measurement noises on `y_v`, `y_t`.

use nalgebra::{SMatrix, SVector};

use bgc_runtime::estimation::kalman::fixed_from_dynamic;
use bgc_runtime::estimation::{EstimationError, KalmanFilter, LinearDiscreteModel};
use bgc_runtime::sim::{
    SampledController, SampledLoopConfig, SolverOptions, simulate_sampled_linear_loop,
    simulate_sampled_loop,
};

use super::BackSupportError;
use super::lqr::LqrDesign;
use super::observer::{NoiseModel, ObserverDesign};
use super::params::Params;
use super::plant::{DesignModel, NX, Plant, output, state};

/// How the plant is advanced between samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PlantIntegration {
    /// The exact zero-order-hold step of the linear plant (one matrix exponential per run).
    ExactZoh,
    /// An ODE solve per sample interval, with these settings: the same record up to the solver's tolerance.
    Ode(SolverOptions),
}

/// Settings of the scenario.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScenarioConfig {
    /// Length of the run (s).
    pub duration: f64,
    pub sample_time: f64,
    /// Trunk velocity (rad/s), from `t = 0`.
    pub trunk_velocity: f64,
    /// Reference torque on the body (N m), its start and duration (s).
    pub reference: f64,
    pub reference_start: f64,
    pub reference_duration: f64,
    pub noise: NoiseModel,
    pub seed: u64,
    pub integration: PlantIntegration,
}

impl ScenarioConfig {
    /// The scenario of Sec. 5.2 over 1 s.
    pub fn paper() -> Self {
        ScenarioConfig {
            duration: 1.0,
            sample_time: 1e-3,
            trunk_velocity: 0.1,
            reference: 10.0,
            reference_start: 0.1,
            reference_duration: 0.5,
            noise: NoiseModel::three_sigma(),
            seed: 2020,
            integration: PlantIntegration::ExactZoh,
        }
    }

    /// The reference torque at time `t` (a sample at the switching instant already sees the new value).
    pub fn reference_at(&self, t: f64) -> f64 {
        let eps = 1e-9 * self.sample_time;
        let on = t + eps >= self.reference_start
            && t + eps < self.reference_start + self.reference_duration;
        if on { self.reference } else { 0.0 }
    }
}

/// The record of a run, one entry per controller sample `t_k`, `k = 0 … N−1`.
#[derive(Clone, Debug, PartialEq)]
pub struct ScenarioResult {
    pub times: Vec<f64>,
    pub reference: Vec<f64>,
    /// Motor torque applied over `[t_k, t_k + T)` (N m).
    pub motor_torque: Vec<f64>,
    /// Torque on the human body: the plant's and the filter's estimate (N m).
    pub human_torque: Vec<f64>,
    pub human_torque_estimate: Vec<f64>,
    /// Motor velocity: the plant's, the measured and the estimate (rad/s).
    pub motor_velocity: Vec<f64>,
    pub motor_velocity_measured: Vec<f64>,
    pub motor_velocity_estimate: Vec<f64>,
    /// Largest |τ_m| and when (s).
    pub peak_motor_torque: f64,
    pub peak_time: f64,
    /// Mean squared errors of the estimates: human torque (N² m²), motor velocity against the measurement and
    /// against the plant's velocity (rad²/s²).
    pub human_torque_mse: f64,
    pub motor_velocity_mse: f64,
    pub motor_velocity_mse_true: f64,
}

/// The observer-based double-integral controller as a sampled controller of the plant.
struct Controller<'a> {
    filter: KalmanFilter<6, 2, 2>,
    k_x: SMatrix<f64, 1, 6>,
    k_z: f64,
    k_zz: f64,
    c_b: SMatrix<f64, 1, 6>,
    d_b: f64,
    cfg: &'a ScenarioConfig,
    z: f64,
    zz: f64,
    previous: Option<SVector<f64, 2>>,
    estimates: Vec<SVector<f64, 6>>,
    failure: Option<EstimationError>,
}

impl Controller<'_> {
    fn step(&mut self, t: f64, y: &SVector<f64, 3>) -> Result<SVector<f64, 2>, EstimationError> {
        if let Some(u_prev) = self.previous {
            self.filter.predict(&u_prev)?;
        }
        let trunk = self.cfg.trunk_velocity;
        let measured = SVector::<f64, 2>::new(y[output::MOTOR_VELOCITY], y[output::SENSOR_TORQUE]);
        let u_now = SVector::<f64, 2>::new(0.0, trunk);
        self.filter.update(&measured, &u_now)?;
        let x_hat = *self.filter.state();
        let human_torque = (self.c_b * x_hat)[0] + self.d_b * trunk;
        let tau_m = -(self.k_x * x_hat)[0] - self.k_z * self.z - self.k_zz * self.zz;
        let dt = self.cfg.sample_time;
        self.zz += dt * self.z;
        self.z += dt * (self.cfg.reference_at(t) - human_torque);
        let u = SVector::<f64, 2>::new(tau_m, trunk);
        self.previous = Some(u);
        self.estimates.push(x_hat);
        Ok(u)
    }
}

impl SampledController<3, 2> for Controller<'_> {
    fn update(&mut self, _k: usize, t: f64, y: &SVector<f64, 3>) -> SVector<f64, 2> {
        if self.failure.is_some() {
            return SVector::repeat(f64::NAN);
        }
        match self.step(t, y) {
            Ok(u) => u,
            Err(e) => {
                // A NaN input stops the simulation; the error is reported after it.
                self.failure = Some(e);
                SVector::repeat(f64::NAN)
            }
        }
    }
}

/// The filter's initial covariance: the steady-state a-priori covariance, made strictly positive definite by
/// adding 10⁻⁹ of its diagonal (it is singular to rounding: two noise inputs drive six states). With a fixed gain
/// the covariance only feeds the filter's bookkeeping (Joseph propagation, innovation statistics), not the
/// estimate.
fn initial_covariance(p: &nalgebra::DMatrix<f64>) -> Result<SMatrix<f64, 6, 6>, BackSupportError> {
    let p: SMatrix<f64, 6, 6> = fixed_from_dynamic("P", p)?;
    Ok(p + SMatrix::<f64, 6, 6>::from_diagonal(&(p.diagonal() * 1e-9)))
}

fn mean_squared(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len()).max(1) as f64;
    a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / n
}

/// Runs the scenario with the double-integral design `lqr` and the discrete filter of `observer`.
pub fn run(
    params: &Params,
    plant: &Plant,
    model: &DesignModel,
    lqr: &LqrDesign,
    observer: &ObserverDesign,
    cfg: &ScenarioConfig,
) -> Result<ScenarioResult, BackSupportError> {
    if lqr.k.len() != 8 {
        return Err(BackSupportError::Setup {
            what: "the scenario needs a double-integral design (8 gains)",
        });
    }
    if (observer.sample_time - cfg.sample_time).abs() > 1e-12 * cfg.sample_time {
        return Err(BackSupportError::Setup {
            what: "the observer was designed for another sample time than the scenario's",
        });
    }
    let samples = (cfg.duration / cfg.sample_time).round();
    if !(1.0..1e7).contains(&samples) {
        return Err(BackSupportError::Setup {
            what: "the scenario needs between 1 and 10⁷ samples",
        });
    }
    let samples = samples as usize;
    let linear = LinearDiscreteModel::<6, 2, 2> {
        a: fixed_from_dynamic("A_d", &observer.a_d)?,
        b: fixed_from_dynamic("B_d", &observer.b_d)?,
        c: fixed_from_dynamic("C", &model.c_meas)?,
        d: SMatrix::zeros(),
    };
    let filter = KalmanFilter::with_fixed_gain(
        linear,
        fixed_from_dynamic("Q_d", &observer.q_d)?,
        fixed_from_dynamic("R_d", &observer.r_d)?,
        fixed_from_dynamic("M", &observer.discrete.filter_gain)?,
        SVector::zeros(),
        initial_covariance(&observer.discrete.p)?,
    )?;
    let mut controller = Controller {
        filter,
        k_x: SMatrix::<f64, 1, 6>::from_row_slice(lqr.state_gain()),
        k_z: lqr.k[6],
        k_zz: lqr.k[7],
        c_b: fixed_from_dynamic("C_b", &model.c_b)?,
        d_b: model.d_b,
        cfg,
        z: 0.0,
        zz: 0.0,
        previous: None,
        estimates: Vec::with_capacity(samples),
        failure: None,
    };
    let mut process = SVector::<f64, NX>::zeros();
    process[state::OMEGA_M] = cfg.noise.motor_torque / params.j_motor();
    process[state::THETA_H] = cfg.noise.trunk_velocity;
    let loop_cfg = SampledLoopConfig::<NX, 2, 3> {
        t0: 0.0,
        sample_time: cfg.sample_time,
        samples,
        x0: SVector::zeros(),
        initial_input: SVector::<f64, 2>::new(0.0, cfg.trunk_velocity),
        measurement_delay: 0,
        measurement_noise_std: SVector::<f64, 3>::new(
            cfg.noise.motor_velocity,
            cfg.noise.sensor_torque,
            0.0,
        ),
        process_noise_std: process,
        seed: cfg.seed,
        solver: match cfg.integration {
            PlantIntegration::Ode(solver) => solver,
            PlantIntegration::ExactZoh => SolverOptions::default(),
        },
    };
    let simulated = match cfg.integration {
        PlantIntegration::ExactZoh => {
            simulate_sampled_linear_loop(plant, &mut controller, &loop_cfg)
        }
        PlantIntegration::Ode(_) => simulate_sampled_loop(plant, &mut controller, &loop_cfg),
    };
    if let Some(e) = controller.failure {
        return Err(e.into());
    }
    let traj = simulated?;
    let n = traj.inputs.len();
    let times = traj.times[..n].to_vec();
    let motor_torque: Vec<f64> = traj.inputs.iter().map(|u| u[0]).collect();
    let human_torque: Vec<f64> = traj.states[..n]
        .iter()
        .zip(&traj.inputs)
        .map(|(x, u)| (*plant.c * x + *plant.d * u)[output::HUMAN_TORQUE])
        .collect();
    let human_torque_estimate: Vec<f64> = controller
        .estimates
        .iter()
        .map(|x| (controller.c_b * x)[0] + model.d_b * cfg.trunk_velocity)
        .collect();
    let motor_velocity: Vec<f64> = traj.states[..n].iter().map(|x| x[state::OMEGA_M]).collect();
    let motor_velocity_measured: Vec<f64> = traj.measurements[..n]
        .iter()
        .map(|y| y[output::MOTOR_VELOCITY])
        .collect();
    let motor_velocity_estimate: Vec<f64> = controller.estimates.iter().map(|x| x[1]).collect();
    let (peak_index, peak) =
        motor_torque
            .iter()
            .enumerate()
            .fold((0, 0.0_f64), |(bi, bv), (i, v)| {
                if v.abs() > bv { (i, v.abs()) } else { (bi, bv) }
            });
    Ok(ScenarioResult {
        peak_motor_torque: peak,
        peak_time: times.get(peak_index).copied().unwrap_or(0.0),
        human_torque_mse: mean_squared(&human_torque, &human_torque_estimate),
        motor_velocity_mse: mean_squared(&motor_velocity_measured, &motor_velocity_estimate),
        motor_velocity_mse_true: mean_squared(&motor_velocity, &motor_velocity_estimate),
        reference: times.iter().map(|&t| cfg.reference_at(t)).collect(),
        times,
        motor_torque,
        human_torque,
        human_torque_estimate,
        motor_velocity,
        motor_velocity_measured,
        motor_velocity_estimate,
    })
}
