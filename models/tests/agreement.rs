//! Every generated model (the exoskeleton models and the compiler's corpus) against the compiler's own evaluation
//! of its equations, finite differences and, where the model is linear, the compiler's numeric state space.

use crate::support;

use bgc_models::corpus;
use support::{check_agreement, check_agreement_in, check_state_space};

macro_rules! agreement {
    ($($test:ident: $module:path => $file:expr),* $(,)?) => {
        $(
            #[test]
            fn $test() {
                use $module as m;
                check_agreement::<m::Model, { m::N_STATES }, { m::N_INPUTS }, { m::N_OUTPUTS }>(
                    $file,
                    m::Model::default(),
                );
            }
        )*
    };
}

agreement! {
    back_support: bgc_models::back_support => "models/back_support.bg",
    pendulum_rig: bgc_models::pendulum_rig => "models/pendulum_rig.bg",
    rehab_leg: bgc_models::rehab_leg => "models/rehab_leg.bg",
    walking_leg: bgc_models::walking_leg => "models/walking_leg.bg",
    dc_motor_load: corpus::dc_motor_load => "bgc/tests/corpus/dc_motor_load.bg",
    gear_train: corpus::gear_train => "bgc/tests/corpus/gear_train.bg",
    hydraulic_cylinder: corpus::hydraulic_cylinder => "bgc/tests/corpus/hydraulic_cylinder.bg",
    msd_chain: corpus::msd_chain => "bgc/tests/corpus/msd_chain.bg",
    oscillator: corpus::oscillator => "bgc/tests/corpus/oscillator.bg",
    parallel_rlc: corpus::parallel_rlc => "bgc/tests/corpus/parallel_rlc.bg",
    pendulum: corpus::pendulum => "bgc/tests/corpus/pendulum.bg",
    quarter_car: corpus::quarter_car => "bgc/tests/corpus/quarter_car.bg",
    resistive_network: corpus::resistive_network => "bgc/tests/corpus/resistive_network.bg",
    series_rlc: corpus::series_rlc => "bgc/tests/corpus/series_rlc.bg",
    two_tank: corpus::two_tank => "bgc/tests/corpus/two_tank.bg",
    ladder_closed: corpus::ladder_closed => "models/tests/models/ladder_closed.bg",
    ladder_loops: corpus::ladder_loops => "models/tests/models/ladder_loops.bg",
}

/// The diode's nonlinear loop, solved by the generated Newton iteration. The charge is drawn from ±1 mC so that the
/// capacitor voltage `q/C` stays within a few volts (at ±1 C it would be ±1000 V, where `exp(v/V_t)` overflows and
/// neither side has a solution).
#[test]
fn diode_rc() {
    use corpus::diode_rc as m;
    check_agreement_in::<m::Model, { m::N_STATES }, { m::N_INPUTS }, { m::N_OUTPUTS }>(
        "bgc/tests/corpus/diode_rc.bg",
        m::Model::default(),
        1e-3,
    );
}

/// Loops solved block after block, a block reading an earlier one's tear: the generated Jacobians' correction through
/// the loops, block by block, against finite differences of the generated rates and outputs. Charges within ±1 mC, as
/// for `diode_rc`.
#[test]
fn chained_loops() {
    use corpus::chained_loops as m;
    check_agreement_in::<m::Model, { m::N_STATES }, { m::N_INPUTS }, { m::N_OUTPUTS }>(
        "models/tests/models/chained_loops.bg",
        m::Model::default(),
        1e-3,
    );
}

macro_rules! state_space {
    ($($test:ident: $module:path => $file:expr),* $(,)?) => {
        $(
            #[test]
            fn $test() {
                use $module as m;
                let p = m::Params::default();
                let values: Vec<f64> = (0..m::N_PARAMS).map(|i| p.get(i).unwrap_or(f64::NAN)).collect();
                check_state_space($file, &values, &m::state_space(&p), false);
            }
        )*
    };
}

state_space! {
    back_support_state_space: bgc_models::back_support => "models/back_support.bg",
    dc_motor_load_state_space: corpus::dc_motor_load => "bgc/tests/corpus/dc_motor_load.bg",
    gear_train_state_space: corpus::gear_train => "bgc/tests/corpus/gear_train.bg",
    hydraulic_cylinder_state_space: corpus::hydraulic_cylinder => "bgc/tests/corpus/hydraulic_cylinder.bg",
    msd_chain_state_space: corpus::msd_chain => "bgc/tests/corpus/msd_chain.bg",
    oscillator_state_space: corpus::oscillator => "bgc/tests/corpus/oscillator.bg",
    parallel_rlc_state_space: corpus::parallel_rlc => "bgc/tests/corpus/parallel_rlc.bg",
    quarter_car_state_space: corpus::quarter_car => "bgc/tests/corpus/quarter_car.bg",
    resistive_network_state_space: corpus::resistive_network => "bgc/tests/corpus/resistive_network.bg",
    series_rlc_state_space: corpus::series_rlc => "bgc/tests/corpus/series_rlc.bg",
    two_tank_state_space: corpus::two_tank => "bgc/tests/corpus/two_tank.bg",
    ladder_closed_state_space: corpus::ladder_closed => "models/tests/models/ladder_closed.bg",
}

#[test]
fn back_support_declared_state_space() {
    use bgc_models::back_support as m;
    let p = m::Params::default();
    let values: Vec<f64> = (0..m::N_PARAMS)
        .map(|i| p.get(i).unwrap_or(f64::NAN))
        .collect();
    assert_eq!(
        m::COORD_NAMES,
        [
            "theta_m",
            "f_rotor",
            "theta_sint",
            "f_sensor_in",
            "theta_sext",
            "f_sensor_out",
            "theta_h"
        ]
    );
    check_state_space(
        "models/back_support.bg",
        &values,
        &m::state_space_declared(&p),
        true,
    );
}

/// Hand-derived entries of the paper's Eq. (3) (declared coordinates `θ_m, ω_m, θ_sint, ω_sint, ...`):
/// `θ̇_m = ω_m`; the merged motor and gearbox-input inertia `J_m + J_g` is accelerated by the motor torque, so
/// `B[1][0] = 1/(J_m + J_g)`; the sensor's internal ring feels the gearbox spring through the gear ratio:
/// `A[3][0] = k_g/(r_g J_sint)`, and its own angle with `-(k_g + k_s)/J_sint`.
#[test]
fn back_support_declared_entries_by_hand() {
    use bgc_models::back_support as m;
    let p = m::Params::default();
    let (a, b, _, _) = m::state_space_declared(&p);
    let rel = |got: f64, want: f64| (got - want).abs() <= 1e-12 * want.abs();
    assert_eq!(a[(0, 1)], 1.0);
    assert!(rel(b[(1, 0)], 1.0 / (p.J_m + p.J_g)), "{}", b[(1, 0)]);
    assert!(rel(a[(3, 0)], p.k_g / (p.r_g * p.J_sint)), "{}", a[(3, 0)]);
    assert!(rel(a[(3, 2)], -(p.k_g + p.k_s) / p.J_sint), "{}", a[(3, 2)]);
}

use crate::eq3;

/// The generated `state_space_declared` is the hand-written Eq. (3) (see `support/eq3.rs`), entry for entry.
#[test]
fn back_support_declared_is_the_papers_eq3() {
    use bgc_models::back_support as m;
    let p = m::Params::default();
    let hand = eq3::Eq3::new(&eq3::Eq3Params::of(&p));
    let (a, b, _, _) = m::state_space_declared(&p);
    for r in 0..7 {
        for c in 0..7 {
            let (g, w) = (a[(r, c)], hand.a[(r, c)]);
            assert!(
                (g - w).abs() <= 1e-12 * w.abs().max(1.0),
                "A[{r}][{c}]: generated {g}, by hand {w}"
            );
        }
        for c in 0..2 {
            let (g, w) = (b[(r, c)], hand.b[(r, c)]);
            assert!(
                (g - w).abs() <= 1e-12 * w.abs().max(1.0),
                "B[{r}][{c}]: generated {g}, by hand {w}"
            );
        }
    }
}

/// The generated rhs (energy states and angles) moves the declared coordinates as the hand-written Eq. (3) does, on
/// states where each spring's deflection matches the angles (the invariant the angles and deflections share).
#[test]
fn back_support_rhs_follows_eq3() {
    use bgc_models::back_support as m;
    let p = m::Params::default();
    let hand = eq3::Eq3::new(&eq3::Eq3Params::of(&p));
    let mut rng = support::Rng::new(3);
    for _ in 0..100 {
        let z = nalgebra::SVector::<f64, 7>::from_fn(|_, _| rng.uniform(-1.0, 1.0));
        let u = m::Inputs::new(rng.uniform(-5.0, 5.0), rng.uniform(-1.0, 1.0));
        let (th_m, w_m, th_si, w_si, th_se, w_se, th_h) =
            (z[0], z[1], z[2], z[3], z[4], z[5], z[6]);
        // States: p_rotor, q_gear_spring, p_sensor_in, q_sensor_spring, p_sensor_out, q_coupling_spring, angles.
        let x = m::State::from_column_slice(&[
            p.J_m * w_m,
            th_m / p.r_g - th_si,
            p.J_sint * w_si,
            th_si - th_se,
            p.J_sext * w_se,
            th_se - th_h,
            th_m,
            th_si,
            th_se,
            th_h,
        ]);
        let dx = m::rhs(&p, 0.0, &x, &u);
        let generated = [
            dx[6],
            dx[0] / p.J_m,
            dx[7],
            dx[2] / p.J_sint,
            dx[8],
            dx[4] / p.J_sext,
            dx[9],
        ];
        let mut want = nalgebra::SVector::<f64, 7>::zeros();
        hand.rhs(&z, &u, &mut want);
        for i in 0..7 {
            let scale = (hand.a.abs() * z.abs() + hand.b.abs() * u.abs())[i];
            assert!(
                (generated[i] - want[i]).abs() <= 1e-12 * scale.max(1.0),
                "ż[{i}]: generated {}, Eq. (3) {}",
                generated[i],
                want[i]
            );
        }
    }
}
