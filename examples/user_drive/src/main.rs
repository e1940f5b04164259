//! A position drive designed and run in closed loop from its own `.bg` model, step by step as in
//! `docs/runtime.md`: the generated state space, an LQR with integral action on the load angle, the
//! zero-order-hold model and a steady-state Kalman filter on the sampled measurements, and a sampled-data
//! simulation of the loop on the plant's exact zero-order-hold step (the drive is linear, so the runtime's ODE
//! solver is not needed: the crate uses `bgc-runtime` without its `ode` feature). Prints the design and the run
//! as `name: value` lines.

/// The code generated from `drive.bg` by `build.rs`.
mod drive {
    include!(concat!(env!("OUT_DIR"), "/drive.rs"));
}

use bgc_runtime::design::{IntegralAction, dlqe, lqi};
use bgc_runtime::estimation::{EstimationError, KalmanFilter, LinearDiscreteModel};
use bgc_runtime::linalg::c2d_zoh;
use bgc_runtime::linearize::jacobians_at;
use bgc_runtime::matrix::{self, dynamic};
use bgc_runtime::sim::{
    LinearPlant, SampledController, SampledLoopConfig, simulate_sampled_linear_loop,
};
use bgc_runtime::nalgebra::{self, DMatrix, SMatrix, SVector};

/// States `p_inductance, p_rotor, q_shaft_spring, p_load, theta_L`; input `V`; outputs `angle, current`.
const NX: usize = drive::N_STATES;
const NU: usize = drive::N_INPUTS;
const NY: usize = drive::N_OUTPUTS;

/// The sample time of the controller (s).
const SAMPLE_TIME: f64 = 1e-3;
/// The load angle the drive moves to (rad).
const REFERENCE: f64 = 1.0;
/// The length of the run (s).
const DURATION: f64 = 1.5;
/// Standard deviations of the sensors: the load-angle encoder (rad) and the current sensor (A).
const ANGLE_NOISE: f64 = 1e-4;
const CURRENT_NOISE: f64 = 1e-2;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let params = drive::Params::default();
    let model = drive::Model::new(params)?;

    // 1. The linear model: `state_space` in all five states (the energy states and `theta_L`, which the
    //    `angle` output reads). The linearisation at rest from the symbolic Jacobians is the same model.
    let fixed = drive::state_space(&params);
    let (a, b, c, d) = fixed;
    let at_rest = jacobians_at(&model, 0.0, &SVector::zeros(), &SVector::zeros())?;
    let difference = (a - at_rest.0).abs().max() + (b - at_rest.1).abs().max();
    println!("states: {}", drive::STATE_NAMES.join(" "));
    println!("A: {}", row_major(&dynamic(&a)));
    println!("B: {}", row_major(&dynamic(&b)));
    println!("state_space minus linearisation: {difference:e}");

    // 2. LQR with integral action on the load angle: augmented state [x; z], z = ∫(r − angle) dt.
    let c_angle = dynamic(&c.fixed_rows::<1>(0).into_owned());
    let weights = [0.0, 0.0, 0.0, 0.0, 1e3, 1e5];
    let q = DMatrix::from_diagonal(&nalgebra::DVector::from_row_slice(&weights));
    let r = DMatrix::from_element(1, 1, 1.0);
    let design = lqi(
        &dynamic(&a),
        &dynamic(&b),
        &c_angle,
        &q,
        &r,
        IntegralAction::Single,
    )?;
    let kx: SMatrix<f64, NU, NX> = matrix::fixed("K_x", &design.kx)?;
    let kz: SMatrix<f64, NU, 1> = matrix::fixed("K_z", &design.kz1)?;
    println!("K: {}", row_major(&design.k));
    let slowest = design
        .closed_loop_eigenvalues
        .iter()
        .map(|l| l.re)
        .fold(f64::NEG_INFINITY, f64::max);
    println!("slowest closed-loop pole (real part): {slowest}");

    // 3. The sampled plant (zero-order hold, as the loop holds the input) and its steady-state Kalman filter.
    let plant = c2d_zoh(&matrix::state_space(&fixed)?, SAMPLE_TIME)?;
    let plant = LinearDiscreteModel::<NX, NU, NY>::from_state_space(&plant)?;
    // Process noise per sample: an unknown armature voltage error (0.1 V) and load torque (0.05 N m) held over
    // the sample, in the momenta they change.
    let mut qd = SMatrix::<f64, NX, NX>::zeros();
    qd[(0, 0)] = (0.1 * SAMPLE_TIME).powi(2);
    qd[(3, 3)] = (0.05 * SAMPLE_TIME).powi(2);
    qd[(4, 4)] = 1e-14;
    let rd = SMatrix::<f64, NY, NY>::from_diagonal(&SVector::from([
        ANGLE_NOISE.powi(2),
        CURRENT_NOISE.powi(2),
    ]));
    let gains = dlqe(
        &dynamic(&plant.a),
        &DMatrix::identity(NX, NX),
        &dynamic(&plant.c),
        &dynamic(&qd),
        &dynamic(&rd),
    )?;
    let filter_gain: SMatrix<f64, NX, NY> = matrix::fixed("M", &gains.filter_gain)?;
    let p0: SMatrix<f64, NX, NX> = matrix::fixed("P", &gains.p)?;
    println!("M: {}", row_major(&gains.filter_gain));
    let filter = KalmanFilter::with_fixed_gain(plant, qd, rd, filter_gain, SVector::zeros(), p0)?;

    // 4. The sampled-data loop on the linear plant (its exact zero-order-hold step), with noisy measurements.
    let drive_plant = LinearPlant::new(a, b, c, d);
    let mut controller = PositionController {
        filter,
        kx,
        kz,
        integral: 0.0,
        held_input: SVector::zeros(),
        estimates: Vec::new(),
        fault: None,
    };
    let samples = (DURATION / SAMPLE_TIME).round() as usize;
    let mut config = SampledLoopConfig::<NX, NU, NY>::new(SAMPLE_TIME, samples, SVector::zeros());
    config.measurement_noise_std = SVector::from([ANGLE_NOISE, CURRENT_NOISE]);
    config.seed = 15;
    let run = simulate_sampled_linear_loop(&drive_plant, &mut controller, &config)?;
    if let Some(fault) = controller.fault {
        return Err(fault.into());
    }

    let angle = |x: &SVector<f64, NX>| x[4];
    let last = run.states.last().ok_or("the run recorded no state")?;
    let peak = run
        .states
        .iter()
        .map(angle)
        .fold(f64::NEG_INFINITY, f64::max);
    let peak_voltage = run.inputs.iter().map(|u| u[0].abs()).fold(0.0, f64::max);
    let estimate_error = controller
        .estimates
        .iter()
        .zip(&run.states)
        .skip(samples / 2)
        .map(|(e, x)| (angle(e) - angle(x)).abs())
        .fold(0.0, f64::max);
    let settle = run
        .times
        .iter()
        .zip(&run.states)
        .rev()
        .find(|(_, x)| (angle(x) - REFERENCE).abs() > 0.02 * REFERENCE)
        .map_or(0.0, |(t, _)| *t);
    println!("final angle: {}", angle(last));
    println!("final current: {}", last[0] / params.L_a);
    println!("peak angle: {peak}");
    println!("peak voltage: {peak_voltage}");
    println!("2% settling time: {settle}");
    println!("largest angle estimate error (second half): {estimate_error:e}");
    Ok(())
}

/// The controller run at every sample: Kalman measurement update, control law, integrator, time update.
struct PositionController {
    filter: KalmanFilter<NX, NU, NY>,
    kx: SMatrix<f64, NU, NX>,
    kz: SMatrix<f64, NU, 1>,
    /// `z = ∫ (r − angle) dt`, by forward Euler at the sample time.
    integral: f64,
    /// The input held since the last sample (the one the measurement was taken under).
    held_input: SVector<f64, NU>,
    /// `x̂[k|k]` of every sample.
    estimates: Vec<SVector<f64, NX>>,
    /// The first estimation error; the loop then holds zero volts.
    fault: Option<EstimationError>,
}

impl PositionController {
    fn step(&mut self, y: &SVector<f64, NY>) -> Result<SVector<f64, NU>, EstimationError> {
        // Measurement update: y[k] was measured while the previous input was held.
        self.filter.update(y, &self.held_input)?;
        let x = *self.filter.state();
        self.estimates.push(x);
        // The LQI law u = −K_x x̂ − K_z z on the current estimate and integrator.
        let u = -(self.kx * x) - self.kz * SVector::<f64, 1>::new(self.integral);
        // The integrator, for the next sample.
        self.integral += SAMPLE_TIME * (REFERENCE - y[0]);
        // Time update with the input the plant now receives until the next sample.
        self.filter.predict(&u)?;
        self.held_input = u;
        Ok(u)
    }
}

impl SampledController<NY, NU> for PositionController {
    fn update(&mut self, _k: usize, _t: f64, y: &SVector<f64, NY>) -> SVector<f64, NU> {
        match self.step(y) {
            Ok(u) => u,
            Err(e) => {
                self.fault.get_or_insert(e);
                SVector::zeros()
            }
        }
    }
}

/// The entries of `m`, row after row, separated by spaces.
fn row_major(m: &DMatrix<f64>) -> String {
    let mut out = Vec::with_capacity(m.len());
    for i in 0..m.nrows() {
        for j in 0..m.ncols() {
            out.push(format!("{:e}", m[(i, j)]));
        }
    }
    out.join(" ")
}
