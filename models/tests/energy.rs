//! The generated energy functions obey the power balance of a bond graph: the rate of change of the stored energy,
//! `Σ ∂E/∂x_i · ẋ_i` (gradient by central differences of the generated `stored_energy`, rates from the generated
//! `rhs`), equals the power the sources supply minus the power the resistors dissipate.

use crate::support;

use bgc_models::corpus;
use support::Rng;

/// `dE/dt` along the generated rhs, by central differences of `E` in each state.
fn energy_rate<const NX: usize>(
    e: &dyn Fn(&nalgebra::SVector<f64, NX>) -> f64,
    x: &nalgebra::SVector<f64, NX>,
    dx: &nalgebra::SVector<f64, NX>,
) -> (f64, f64) {
    let mut rate = 0.0;
    let mut scale = 0.0;
    for i in 0..NX {
        let h = 1e-4 * x[i].abs().max(1.0);
        let (mut xp, mut xm) = (*x, *x);
        xp[i] += h;
        xm[i] -= h;
        let term = (e(&xp) - e(&xm)) / (2.0 * h) * dx[i];
        rate += term;
        // The term itself, and the rounding of the difference of E (about eps |E| / h): a stiff storage makes E
        // large and the difference in a soft storage's state small.
        scale += term.abs() + 1e6 * f64::EPSILON * e(x).abs() / h * dx[i].abs();
    }
    (rate, scale)
}

macro_rules! power_balance {
    ($($test:ident: $module:path),* $(,)?) => {
        $(
            #[test]
            fn $test() {
                use $module as m;
                let p = m::Params::default();
                let mut rng = Rng::new(7);
                for _ in 0..50 {
                    let x = m::State::from_fn(|_, _| rng.uniform(-1.0, 1.0));
                    let u = m::Inputs::from_fn(|_, _| rng.uniform(-1.0, 1.0));
                    let t = rng.uniform(0.0, 2.0);
                    let dx = m::rhs(&p, t, &x, &u);
                    let (rate, scale) = energy_rate(&|x| m::stored_energy(&p, t, x, &u), &x, &dx);
                    let balance = m::supplied_power(&p, t, &x, &u) - m::dissipated_power(&p, t, &x, &u);
                    assert!(
                        (rate - balance).abs() <= 1e-6 * scale.max(balance.abs()).max(1e-9),
                        "dE/dt = {rate}, supplied - dissipated = {balance}"
                    );
                }
            }
        )*
    };
}

power_balance! {
    dc_motor_load: corpus::dc_motor_load,
    gear_train: corpus::gear_train,
    hydraulic_cylinder: corpus::hydraulic_cylinder,
    msd_chain: corpus::msd_chain,
    oscillator: corpus::oscillator,
    parallel_rlc: corpus::parallel_rlc,
    pendulum: corpus::pendulum,
    quarter_car: corpus::quarter_car,
    resistive_network: corpus::resistive_network,
    series_rlc: corpus::series_rlc,
    two_tank: corpus::two_tank,
    pendulum_rig: bgc_models::pendulum_rig,
    walking_leg: bgc_models::walking_leg,
    ladder_closed: corpus::ladder_closed,
    ladder_loops: corpus::ladder_loops,
}

/// The back-support model supplies power through a flow source whose power needs `d omega_h/dt`, so it has no
/// `supplied_power`; with both inputs zero the sources supply nothing and the stored energy decays at exactly the
/// dissipated power.
#[test]
fn back_support_unforced_energy_decays_by_dissipation() {
    use bgc_models::back_support as m;
    let p = m::Params::default();
    let u = m::Inputs::zeros();
    let mut rng = Rng::new(11);
    for _ in 0..50 {
        let x = m::State::from_fn(|_, _| rng.uniform(-1e-2, 1e-2));
        let dx = m::rhs(&p, 0.0, &x, &u);
        let (rate, scale) = energy_rate(&|x| m::stored_energy(&p, 0.0, x, &u), &x, &dx);
        let dissipated = m::dissipated_power(&p, 0.0, &x, &u);
        assert!(dissipated >= 0.0);
        assert!(
            (rate + dissipated).abs() <= 1e-6 * scale.max(dissipated),
            "dE/dt = {rate}, dissipated = {dissipated}"
        );
    }
}

/// The diode's loop current comes from the generated Newton solve in every energy function: the stored energy still
/// changes at the supplied minus the dissipated power, and the diode never supplies power (`v_d i ≥ 0`). The charge
/// stays within ±1 mC (±1 V on the capacitor), where the loop has a solution.
#[test]
fn diode_rc_power_balance_through_the_loop() {
    use corpus::diode_rc as m;
    let p = m::Params::default();
    let mut rng = Rng::new(13);
    for _ in 0..50 {
        let x = m::State::from_fn(|_, _| rng.uniform(-1e-3, 1e-3));
        let u = m::Inputs::from_fn(|_, _| rng.uniform(-2.0, 2.0));
        let dx = m::rhs(&p, 0.0, &x, &u);
        let (rate, scale) = energy_rate(&|x| m::stored_energy(&p, 0.0, x, &u), &x, &dx);
        let supplied = m::supplied_power(&p, 0.0, &x, &u);
        let dissipated = m::dissipated_power(&p, 0.0, &x, &u);
        let balance = supplied - dissipated;
        assert!(
            (rate - balance).abs() <= 1e-6 * scale.max(balance.abs()).max(1e-9),
            "dE/dt = {rate}, supplied - dissipated = {balance}"
        );
        let y = m::outputs(&p, 0.0, &x, &u);
        let diode_power = y[0] * y[1];
        assert!(diode_power >= 0.0, "diode power {diode_power}");
    }
}
