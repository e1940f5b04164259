//! The walking exoskeleton (Sado et al. 2018): the hand-derived leg dynamics against physics and against the
//! `.bg` model, the stance leg's ground reaction and the plant's consistency with the wearer's gait, the
//! passive ankle in the computed torque, the motors' limits, the gait supervisor on the synthetic wearer's
//! insoles, the dual UKF's mass estimates and the closed loop's figures (shorter runs than the example's 20 s, stated per test, to keep debug builds fast).

use bgc::ir::{Expr, Relation};
use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;
use bgc::syntax::ast::BinOp;
use bgc_runtime::control::{GaitState, GaitSupervisor, GaitThresholds, Leg, LegMode};
use bgc_runtime::noise::Rng;
use bgc_runtime::sim::{Method, SolverOptions, simulate_open_loop};
use bgc_workspace::walking::anthropometry::{LegFriction, LegSegments};
use bgc_workspace::walking::dynamics::LegDynamics;
use bgc_workspace::walking::plant::{
    LegModel, MOTOR_PEAK_TORQUE, WalkingPlant, join, passive_ankle_torque,
};
use bgc_workspace::walking::scenario::{SensorNoise, WalkingConfig, run};
use bgc_workspace::walking::wearer::{STANCE_FRACTION, Wearer, WearerConfig};
use nalgebra::{Matrix3, Vector2, Vector3};
use std::f64::consts::FRAC_PI_2;

fn leg() -> LegDynamics {
    LegDynamics::new(LegSegments::paper_subject())
}

fn random_state(rng: &mut Rng) -> (Vector3<f64>, Vector3<f64>) {
    let q = Vector3::from_fn(|_, _| 2.0 * rng.normal());
    let qd = Vector3::from_fn(|_, _| 5.0 * rng.normal());
    (q, qd)
}

/// Centres of mass (thigh, shank, foot) and absolute link angles, written out from the geometry, independently
/// of the `D(φ)` formulas of the derivation.
fn centres(d: &LegDynamics, q: &Vector3<f64>) -> ([Vector2<f64>; 3], [f64; 3]) {
    let s = &d.segments;
    let (pt, ps) = (q[2], q[2] - q[1]);
    let pf = ps + q[0] + FRAC_PI_2;
    let r = |phi: f64| Vector2::new(phi.sin(), -phi.cos());
    let knee = r(pt) * s.thigh.length;
    let ankle = knee + r(ps) * s.shank.length;
    (
        [
            r(pt) * s.thigh.com,
            knee + r(ps) * s.shank.com,
            ankle + r(pf) * s.foot.com,
        ],
        [pt, ps, pf],
    )
}

/// Kinetic energy from the velocities of the centres of mass (central differences along q̇) and the link
/// rotation rates: `Σ ½ m v² + ½ I ω²`.
fn kinetic_energy_from_points(d: &LegDynamics, q: &Vector3<f64>, qd: &Vector3<f64>) -> f64 {
    let h = 1e-6;
    let (cp, ap) = centres(d, &(q + qd * h));
    let (cm, am) = centres(d, &(q - qd * h));
    let s = &d.segments;
    let segs = [s.thigh, s.shank, s.foot];
    (0..3)
        .map(|i| {
            let v = (cp[i] - cm[i]) / (2.0 * h);
            let w = (ap[i] - am[i]) / (2.0 * h);
            0.5 * segs[i].mass * v.norm_squared() + 0.5 * segs[i].inertia() * w * w
        })
        .sum()
}

#[test]
fn mass_matrix_is_symmetric_positive_definite_and_gives_the_kinetic_energy_of_the_points() {
    let d = leg();
    let mut rng = Rng::new(11);
    for _ in 0..200 {
        let (q, qd) = random_state(&mut rng);
        let m = d.mass_matrix(&q);
        assert!(
            (m - m.transpose()).abs().max() < 1e-14,
            "M not symmetric at {q:?}"
        );
        let eig = m.symmetric_eigenvalues();
        assert!(
            eig.min() > 1e-4,
            "M not positive definite at {q:?}: {eig:?}"
        );
        let t_points = kinetic_energy_from_points(&d, &q, &qd);
        let t_matrix = d.kinetic_energy(&q, &qd);
        assert!(
            (t_points - t_matrix).abs() < 1e-6 * t_matrix.max(1.0),
            "kinetic energy {t_matrix} vs {t_points} from the points"
        );
    }
}

#[test]
fn mass_matrix_rate_minus_twice_coriolis_is_skew_symmetric() {
    let d = leg();
    let mut rng = Rng::new(12);
    for _ in 0..200 {
        let (q, qd) = random_state(&mut rng);
        let n = d.mass_matrix_rate(&q, &qd) - 2.0 * d.coriolis_matrix(&q, &qd);
        assert!(
            (n + n.transpose()).abs().max() < 1e-10,
            "Ṁ − 2C not skew at {q:?}, {qd:?}"
        );
        // The analytic Ṁ agrees with a central difference of M along q̇.
        let h = 1e-6;
        let fd = (d.mass_matrix(&(q + qd * h)) - d.mass_matrix(&(q - qd * h))) / (2.0 * h);
        let scale = d.mass_matrix_rate(&q, &qd).abs().max().max(1.0);
        assert!((fd - d.mass_matrix_rate(&q, &qd)).abs().max() < 1e-7 * scale);
        // C q̇ from the matrix equals the vector form.
        let cq = d.coriolis_matrix(&q, &qd) * qd;
        assert!((cq - d.coriolis_torque(&q, &qd)).abs().max() < 1e-12 * cq.abs().max().max(1.0));
    }
}

/// `C(q, q̇) q̇` from Christoffel symbols of finite-difference derivatives of `M`, and `G = ∂V/∂q` from finite
/// differences of the potential energy.
#[test]
fn coriolis_and_gravity_follow_from_the_lagrangian() {
    let d = leg();
    let mut rng = Rng::new(13);
    let h = 1e-6;
    for _ in 0..100 {
        let (q, qd) = random_state(&mut rng);
        let dm: Vec<Matrix3<f64>> = (0..3)
            .map(|k| {
                let e = Vector3::ith(k, h);
                (d.mass_matrix(&(q + e)) - d.mass_matrix(&(q - e))) / (2.0 * h)
            })
            .collect();
        let c = Vector3::from_fn(|i, _| {
            let mut s = 0.0;
            for j in 0..3 {
                for k in 0..3 {
                    s += 0.5 * (dm[k][(i, j)] + dm[j][(i, k)] - dm[i][(j, k)]) * qd[j] * qd[k];
                }
            }
            s
        });
        let cq = d.coriolis_torque(&q, &qd);
        assert!(
            (c - cq).abs().max() < 1e-6 * cq.abs().max().max(1.0),
            "{c:?} vs {cq:?}"
        );
        let g = Vector3::from_fn(|k, _| {
            let e = Vector3::ith(k, h);
            (d.potential_energy(&(q + e)) - d.potential_energy(&(q - e))) / (2.0 * h)
        });
        assert!((g - d.gravity_torque(&q)).abs().max() < 1e-6);
    }
}

/// The frictionless, unactuated leg released from rest at hip 40°, knee 60°, ankle −10° conserves energy.
/// 3 s, Tsit5 at rtol = atol = 1e-12. Drift is relative to the energy of the swing above the hanging rest.
#[test]
fn frictionless_leg_conserves_energy() {
    let model = LegModel::new(LegSegments::paper_subject(), LegFriction::none());
    let d = model.dynamics;
    let deg = std::f64::consts::PI / 180.0;
    let q0 = Vector3::new(-10.0 * deg, 60.0 * deg, 40.0 * deg);
    let x0 = join(&q0, &Vector3::zeros());
    let times: Vec<f64> = (0..=300).map(|i| i as f64 * 0.01).collect();
    let opts = SolverOptions {
        method: Method::Tsit45,
        rtol: 1e-12,
        atol: 1e-12,
        max_steps: 1_000_000,
    };
    let traj = simulate_open_loop(&model, 0.0, &x0, |_| Vector3::zeros(), &times, &opts)
        .unwrap_or_else(|e| panic!("simulation failed: {e}"));
    let energy = |x: &nalgebra::Vector6<f64>| {
        d.energy(
            &x.fixed_rows::<3>(0).into_owned(),
            &x.fixed_rows::<3>(3).into_owned(),
        )
    };
    let e0 = energy(&x0);
    // At rest hanging straight down: hip 0, knee 0, ankle 0 (foot horizontal).
    let scale = e0 - d.potential_energy(&Vector3::zeros());
    assert!(scale > 5.0, "swing energy {scale} J");
    let drift = traj
        .states
        .iter()
        .map(|x| ((energy(x) - e0) / scale).abs())
        .fold(0.0, f64::max);
    assert!(drift < 1e-8, "relative energy drift {drift:e}");
    // The leg really moved: the knee swung through more than 30°.
    let knee_range = traj.states.iter().map(|x| x[1]).fold(f64::MIN, f64::max)
        - traj.states.iter().map(|x| x[1]).fold(f64::MAX, f64::min);
    assert!(knee_range > 30.0 * deg);
}

/// Evaluates an expression of the lowered `.bg` model at joint angles `q` (for the field's `q[i]` and the
/// `var`s `th1..th3`), with parameters at their defaults and inputs at zero except those in `overrides`.
fn eval(model: &bgc::ir::Model, e: &Expr, q: &Vector3<f64>, overrides: &[(&str, f64)]) -> f64 {
    let go = |e: &Expr| eval(model, e, q, overrides);
    match e {
        Expr::Const(c) => *c,
        Expr::Param(id) => {
            let p = &model.params[*id];
            overrides
                .iter()
                .find(|(n, _)| *n == p.name)
                .map_or(p.default, |(_, v)| *v)
        }
        Expr::Input(id) => overrides
            .iter()
            .find(|(n, _)| *n == model.inputs[*id].name)
            .map_or(0.0, |(_, v)| *v),
        Expr::Var(id) => match model.vars[*id].name.as_str() {
            "th1" => q[0],
            "th2" => q[1],
            "th3" => q[2],
            other => panic!("unexpected var {other}"),
        },
        Expr::FieldPort { port, .. } => q[*port as usize],
        Expr::Neg(a) => -go(a),
        Expr::Binary(op, a, b) => {
            let (a, b) = (go(a), go(b));
            match op {
                BinOp::Add => a + b,
                BinOp::Sub => a - b,
                BinOp::Mul => a * b,
                BinOp::Div => a / b,
                BinOp::Pow => a.powf(b),
            }
        }
        Expr::Call(f, args) => {
            let a = go(&args[0]);
            match f.name() {
                "sin" => a.sin(),
                "cos" => a.cos(),
                "tanh" => a.tanh(),
                other => panic!("unexpected function {other}"),
            }
        }
        other => panic!("unexpected expression {other:?}"),
    }
}

fn lowered_walking_leg() -> bgc::ir::Model {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/models/walking_leg.bg");
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut sources = SourceMap::new();
    let root = sources.add("walking_leg.bg", text);
    let (mut models, diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert!(
        diags.is_empty(),
        "{}",
        bgc::diagnostic::render::to_text(&sources, &diags, false)
    );
    assert_eq!(models.len(), 1);
    models.remove(0)
}

fn source_effort(model: &bgc::ir::Model, name: &str) -> Expr {
    let node = model
        .node_by_name(name)
        .unwrap_or_else(|| panic!("no element {name}"));
    match &model.graph[node].relation {
        Relation::Source(e) => e.clone(),
        other => panic!("{name} is not a source: {other:?}"),
    }
}

/// `models/walking_leg.bg` lowers without diagnostics, and its I-field `M(q)`, gravity sources and ground
/// reaction sources evaluate to the hand derivation's `M(q)`, `−G(q)` and `−Jᵀ F` at random angles.
#[test]
fn bg_model_matches_the_derivation() {
    let model = lowered_walking_leg();
    let leg_node = model
        .node_by_name("leg")
        .unwrap_or_else(|| panic!("no I-field"));
    let entries = match &model.graph[leg_node].relation {
        Relation::MassMatrix { n: 3, entries } => entries.clone(),
        other => panic!("leg is not a 3-port I-field: {other:?}"),
    };
    let d = leg();
    let mut rng = Rng::new(14);
    for _ in 0..50 {
        let (q, _) = random_state(&mut rng);
        let m = d.mass_matrix(&q);
        for i in 0..3 {
            for j in 0..3 {
                let v = eval(&model, &entries[3 * i + j], &q, &[]);
                assert!(
                    (v - m[(i, j)]).abs() < 1e-12,
                    "M[{i},{j}] = {v}, derived {}",
                    m[(i, j)]
                );
            }
        }
        let g = d.gravity_torque(&q);
        for (i, name) in ["gravity_ankle", "gravity_knee", "gravity_hip"]
            .iter()
            .enumerate()
        {
            let v = eval(&model, &source_effort(&model, name), &q, &[]);
            assert!(
                (v + g[i]).abs() < 1e-12,
                "{name} = {v}, derived −G = {}",
                -g[i]
            );
        }
        let f = Vector2::new(40.0 * rng.normal(), 700.0 + 50.0 * rng.normal());
        let jtf = d.ankle_jacobian(&q).transpose() * f;
        let over = [("stance", 1.0), ("F_x", f[0]), ("F_y", f[1])];
        for (i, name) in ["ground_knee", "ground_hip"].iter().enumerate() {
            let e = source_effort(&model, name);
            let v = eval(&model, &e, &q, &over);
            assert!(
                (v + jtf[i + 1]).abs() < 1e-9,
                "{name} = {v}, derived −JᵀF = {}",
                -jtf[i + 1]
            );
            assert_eq!(
                eval(&model, &e, &q, &[("F_x", f[0]), ("F_y", f[1])]),
                0.0,
                "{name} in swing"
            );
        }
        assert!(
            jtf[0].abs() < 1e-12,
            "a force at the ankle moves the ankle joint"
        );
    }
}

/// The supervisor on the synthetic wearer's insole forces (noise-free, then with 5 N noise), sampled at
/// 1 kHz for 5.3 gait cycles: the automaton cycles S1 → S2 → S3 → S4 → S1 with each event pair at its place in the
/// right leg's cycle (p1 right heel-off late in stance, p2 right heel-strike, p3 left heel-off just after,
/// p4 left heel-strike at mid-cycle), and the right leg is in the stance mode only while its foot is down.
#[test]
fn supervisor_follows_the_gait_of_the_synthetic_wearer() {
    let wearer = Wearer::new(&WearerConfig {
        duration: 6.0,
        ..WearerConfig::default()
    });
    for insole_noise in [0.0, 5.0] {
        let mut rng = Rng::new(21);
        let mut sup = GaitSupervisor::new(GaitThresholds::default())
            .unwrap_or_else(|e| panic!("thresholds refused: {e}"));
        let mut events = Vec::new();
        for k in 0.. {
            let t = k as f64 * 1e-3;
            if wearer.phase(t).0 >= 5.3 {
                break;
            }
            let (r, l) = wearer.insoles(t);
            let mut noisy = |g: bgc_runtime::control::GrfSample| bgc_runtime::control::GrfSample {
                heel: g.heel + insole_noise * rng.normal(),
                ball: g.ball + insole_noise * rng.normal(),
            };
            let step = sup.update(noisy(r), noisy(l));
            let p = wearer.cycle_fraction(t, false);
            if step.state.mode(Leg::Right) == LegMode::Stance {
                assert!(
                    p < STANCE_FRACTION,
                    "right leg in stance mode with the foot up, t = {t}"
                );
            }
            if p >= STANCE_FRACTION {
                assert_eq!(step.state.mode(Leg::Right), LegMode::Swing, "t = {t}");
            }
            if let Some(tr) = step.transition {
                events.push((tr, step.state, p));
            }
        }
        use bgc_runtime::control::Transition::*;
        let expected = [
            (P1, GaitState::RightSwing, 0.54, 0.62),
            (P2, GaitState::LeftPreswing, 0.0, 0.05),
            (P3, GaitState::LeftSwing, 0.04, 0.12),
            (P4, GaitState::RightPreswing, 0.50, 0.55),
        ];
        // The run starts at the right heel strike in S1, so the first event is p1 at 0.56 cycles; by 5.3 cycles
        // p1 has fired five times (0.56 … 4.56), p2 and p3 five times (1.0 … 5.06), p4 four times (1.5 … 4.5).
        assert_eq!(events.len(), 19, "noise {insole_noise}: {events:?}");
        for (i, (tr, state, p)) in events.iter().enumerate() {
            let (want, want_state, lo, hi) = expected[i % 4];
            assert_eq!((*tr, *state), (want, want_state), "transition {i}");
            assert!((lo..hi).contains(p), "{want:?} at cycle fraction {p}");
        }
    }
}

/// Noise-free, no torso load, 4 s: the masses, started 20 % too heavy, converge to the leg's (mean over the
/// last second within 0.5 %; the run gives 0.1 % or better: the one-period averages of the torque
/// observation leave a little modelling error).
#[test]
fn dual_ukf_masses_converge_on_a_noise_free_run() {
    let mut cfg = WalkingConfig::paper(4.0);
    cfg.noise = SensorNoise::none();
    cfg.wearer.torso_mass = 0.0;
    let out = run(&cfg).unwrap_or_else(|e| panic!("{e}"));
    let truth = LegSegments::paper_subject().masses();
    for (i, &m) in truth.iter().enumerate() {
        assert!(
            (cfg.estimator.initial_masses[i] / m - 1.2).abs() < 1e-12,
            "initial mass {i} not 20 % off"
        );
        let estimate = out.masses.final_mean[i];
        assert!(
            (estimate - m).abs() < 0.005 * m,
            "m{} = {estimate} kg, true {m} kg",
            i + 1
        );
    }
    // Without the torso the thigh is the same in stance and swing, and so is its estimate.
    let m = &out.masses;
    assert!(
        (m.m3_stance_mean - truth[2]).abs() < 0.01 * truth[2],
        "{m:?}"
    );
    assert!(
        (m.m3_swing_mean - truth[2]).abs() < 0.01 * truth[2],
        "{m:?}"
    );
}

/// Noise-free with the 8 kg torso load, 4 s: m₃ follows the load on and off the thigh (Fig. 17). The
/// forgetting factor's memory (about 50 ms) makes the estimate lag the load, which comes on and goes off
/// within 120 ms: in single support it sits about 0.9 kg below the loaded thigh, in swing 0.7 kg above the
/// bare one (bounds: 1.2 kg).
#[test]
fn dual_ukf_thigh_mass_follows_the_torso_load() {
    let mut cfg = WalkingConfig::paper(4.0);
    cfg.noise = SensorNoise::none();
    let out = run(&cfg).unwrap_or_else(|e| panic!("{e}"));
    let m = &out.masses;
    assert_eq!(m.m3_true_stance - m.m3_true_swing, 8.0);
    assert!(
        (m.m3_stance_mean - m.m3_true_stance).abs() < 1.2,
        "m3 in single support {} (true {})",
        m.m3_stance_mean,
        m.m3_true_stance
    );
    assert!(
        (m.m3_swing_mean - m.m3_true_swing).abs() < 1.2,
        "m3 in swing {} (true {})",
        m.m3_swing_mean,
        m.m3_true_swing
    );
    assert!((m.final_mean[0] - m.true_swing[0]).abs() < 0.02 * m.true_swing[0]);
    assert!((m.final_mean[1] - m.true_swing[1]).abs() < 0.02 * m.true_swing[1]);
}

/// The example's closed loop with the paper's sensor noise, 6 s (the example runs 20 s): the Table 7 and
/// Table 9 figures, the motors and the masses stay within bounds about twice the figures the run gives
/// (Table 9: knee 0.026° and 0.91 °/s, hip 0.011° and 0.36 °/s; the paper's 0.242° and 0.318 °/s, 0.020° and
/// 0.085 °/s).
#[test]
fn closed_loop_figures_within_bounds() {
    let cfg = WalkingConfig::paper(6.0);
    let out = run(&cfg).unwrap_or_else(|e| panic!("{e}"));
    for row in &out.table7 {
        // Innovations: small (σ of the sensors is 0.89°), zero-mean and white.
        assert!(row.mean_residual_deg.abs() < 0.2, "{row:?}");
        assert!(row.mean_residual_autocorrelation.abs() < 0.1, "{row:?}");
        assert!(row.mean_position_error_deg.abs() < 0.2, "{row:?}");
        assert!(row.position_outside_one_sigma_percent < 45.0, "{row:?}");
    }
    for row in out.table7.iter().filter(|r| r.joint != "ankle") {
        assert!(row.position_outside_one_sigma_percent > 15.0, "{row:?}");
        // Knee and hip speeds reach 330 and 180 °/s; the mean velocity error is a fraction of a °/s.
        assert!(row.mean_velocity_error_deg_s.abs() < 1.0, "{row:?}");
    }
    // The foot is light (0.012 kg m² about the ankle): the torque sensors' noise moves its speed by about
    // 1.5 °/s per filter period, more than the paper's P_v allows for, and the ankle's velocity error wanders
    // (mean 5 °/s over this run; the joint reaches 240 °/s).
    let ankle = &out.table7[0];
    assert!(ankle.mean_velocity_error_deg_s.abs() < 10.0, "{ankle:?}");
    let nis = out.mean_nis.unwrap_or(f64::NAN);
    assert!(
        (1.0..3.0).contains(&nis),
        "mean NIS {nis} for 3 measurements"
    );
    let [ankle, knee, hip] = [&out.table9[0], &out.table9[1], &out.table9[2]];
    assert!(knee.position_rmse_deg < 0.06, "{knee:?}");
    assert!(knee.velocity_rmse_deg_s < 2.0, "{knee:?}");
    assert!(hip.position_rmse_deg < 0.025, "{hip:?}");
    assert!(hip.velocity_rmse_deg_s < 0.8, "{hip:?}");
    // The exoskeleton moves with the wearer: within 0.3° at the knee and hip (0.14° and 0.16° in this run,
    // the filter's position estimate being 0.6° off); the passive ankle is carried by the wearer.
    for row in [knee, hip] {
        assert!(row.wearer_position_rmse_deg < 0.3, "{row:?}");
    }
    assert!(ankle.wearer_position_rmse_deg < 0.05, "{ankle:?}");
    // The motors stay within their ratings in more than 99 % of the periods and deliver their share.
    let a = &out.actuators;
    assert_eq!(a.peak_torque[0], 0.0);
    assert!(
        a.peak_torque[1] <= 17.0 && a.peak_torque[2] <= 38.0,
        "{a:?}"
    );
    assert!(
        a.saturated_percent[1] < 1.0 && a.saturated_percent[2] < 1.0,
        "{a:?}"
    );
    assert!(a.rms_torque[1] > 3.0 && a.rms_torque[2] > 6.0, "{a:?}");
    assert_eq!(out.transitions.len(), 21);
    let m = &out.masses;
    assert!(m.m3_stance_mean - m.m3_swing_mean > 5.0, "{m:?}");
    for i in 0..2 {
        assert!(
            (m.final_mean[i] - m.true_swing[i]).abs() < 0.05 * m.true_swing[i],
            "{m:?}"
        );
    }
}

/// The synthetic wearer's analytic velocities and accelerations are the derivatives of its angles (central
/// differences, across the once-a-second blends of rate and excursion too), the ranges are those of normal
/// gait (hip about ±20°, knee 0–60°, ankle within ±15°, with the 4 % excursion variation on top), and the
/// right foot is down 62 % of each cycle.
#[test]
fn synthetic_wearer_kinematics_are_consistent_and_realistic() {
    let wearer = Wearer::new(&WearerConfig {
        duration: 10.0,
        ..WearerConfig::default()
    });
    let deg = 180.0 / std::f64::consts::PI;
    let h = 1e-5;
    let (mut lo, mut hi) = (Vector3::repeat(f64::MAX), Vector3::repeat(f64::MIN));
    let mut stance = 0usize;
    let n = 9000;
    for k in 0..n {
        let t = 0.5 + k as f64 * 1e-3;
        let w = wearer.intended(t);
        let (p, m) = (wearer.intended(t + h), wearer.intended(t - h));
        let qd = (p.q - m.q) / (2.0 * h);
        let qdd = (p.qd - m.qd) / (2.0 * h);
        assert!(
            (qd - w.qd).abs().max() < 1e-6 * w.qd.abs().max().max(1.0),
            "q̇ at t = {t}"
        );
        assert!(
            (qdd - w.qdd).abs().max() < 1e-5 * w.qdd.abs().max().max(1.0),
            "q̈ at t = {t}"
        );
        lo = lo.inf(&(w.q * deg));
        hi = hi.sup(&(w.q * deg));
        stance += usize::from(wearer.right_in_stance(t));
    }
    assert!(
        lo[0] > -17.0 && hi[0] < 12.0,
        "ankle {:.1}..{:.1}°",
        lo[0],
        hi[0]
    );
    assert!(
        lo[1] > 0.0 && hi[1] < 65.0 && hi[1] > 55.0,
        "knee {:.1}..{:.1}°",
        lo[1],
        hi[1]
    );
    assert!(
        lo[2] > -16.0 && lo[2] < -10.0 && hi[2] > 20.0 && hi[2] < 25.0,
        "hip {:.1}..{:.1}°",
        lo[2],
        hi[2]
    );
    let fraction = stance as f64 / n as f64;
    assert!(
        (fraction - STANCE_FRACTION).abs() < 0.02,
        "stance fraction {fraction}"
    );
    // The cycle varies: the phase after 9 s is not exactly 9 cycles, but close.
    let (phi, _, _) = wearer.phase(9.5);
    assert!(
        (phi - 9.5).abs() > 1e-3 && (phi - 9.5).abs() < 0.3,
        "phase {phi}"
    );
}

fn worn_leg(assistance: [f64; 3]) -> WalkingPlant {
    WalkingPlant {
        leg: LegModel::new(LegSegments::paper_subject(), LegFriction::table8_right()),
        wearer: Wearer::new(&WearerConfig {
            duration: 6.0,
            assistance,
            ..WearerConfig::default()
        }),
    }
}

/// The ground reaction of the stance leg (Eq. 2): both insoles together carry the body weight at every
/// instant; the right foot's reaction has the vertical component `W · share`, points from the ankle
/// through the hip, so it exerts no torque about the hip, and loads the knee with `λ l_T l_S sin θ₂`
/// (`λ = R_y / (−p_y)`, derived by hand in `plant.rs`'s docs); `Jᵀ R` is the virtual work of `R` on the
/// ankle point (central differences of the ankle position).
#[test]
fn ground_reaction_carries_the_body_weight_through_the_hip() {
    let plant = worn_leg([0.0; 3]);
    let w = &plant.wearer;
    let d = plant.leg.dynamics;
    let s = d.segments;
    let mut loaded = 0;
    for k in 0..5000 {
        let t = k as f64 * 1e-3;
        let (r, l) = w.insoles(t);
        let total = r.heel + r.ball + l.heel + l.ball;
        assert!(
            (total - w.body_weight).abs() < 1e-9 * w.body_weight,
            "t = {t}: {total}"
        );
        let share = w.support_share(t);
        assert!((0.0..=1.0).contains(&share));
        assert!(((r.heel + r.ball) - share * w.body_weight).abs() < 1e-9 * w.body_weight);
        assert_eq!(share, w.torso_load(t));
        let q = w.intended(t).q;
        let reaction = plant.ground_reaction(t, &q);
        assert!((reaction[1] - share * w.body_weight).abs() < 1e-9 * w.body_weight);
        let torque = plant.ground_torque(t, &q);
        let ankle = d.ankle_position(&q);
        let lambda = reaction[1] / -ankle[1];
        let knee = lambda * s.thigh.length * s.shank.length * q[1].sin();
        assert!(torque[0].abs() < 1e-9, "ankle {torque:?}");
        assert!(torque[2].abs() < 1e-9 * w.body_weight, "hip {torque:?}");
        assert!(
            (torque[1] - knee).abs() < 1e-9 * w.body_weight,
            "knee {torque:?} vs {knee}"
        );
        let h = 1e-6;
        for j in 0..3 {
            let e = Vector3::ith(j, h);
            let dp = (d.ankle_position(&(q + e)) - d.ankle_position(&(q - e))) / (2.0 * h);
            assert!((reaction.dot(&dp) - torque[j]).abs() < 1e-5 * w.body_weight);
        }
        if !w.right_in_stance(t) {
            assert_eq!(reaction, Vector2::zeros(), "t = {t}");
        } else if share == 1.0 {
            loaded += 1;
        }
    }
    // Single support: 12 % to 50 % of each of the five cycles.
    assert!(
        (1800..2000).contains(&loaded),
        "{loaded} ms in single support"
    );
}

/// The wearer alone walks the leg: with no motor torque and the wearer supplying the whole joint torque
/// the gait needs (Eqs. 2–3 inverse dynamics less the ground's `Jᵀ R`), the simulated leg (torso on the
/// thigh, ground reaction, friction) stays on the wearer's trajectory for 3 s, swing and stance.
#[test]
fn wearer_alone_walks_the_leg_along_the_gait() {
    let plant = worn_leg([0.0; 3]);
    let start = plant.wearer.intended(0.0);
    let x0 = join(&start.q, &start.qd);
    let times: Vec<f64> = (0..=300).map(|i| i as f64 * 0.01).collect();
    let opts = SolverOptions {
        method: Method::Tsit45,
        rtol: 1e-10,
        atol: 1e-12,
        max_steps: 1_000_000,
    };
    let traj = simulate_open_loop(&plant, 0.0, &x0, |_| Vector3::zeros(), &times, &opts)
        .unwrap_or_else(|e| panic!("simulation failed: {e}"));
    let worst = times
        .iter()
        .zip(&traj.states)
        .map(|(&t, x)| (x.fixed_rows::<3>(0) - plant.wearer.intended(t).q).amax())
        .fold(0.0, f64::max);
    assert!(worst < 1e-6, "largest deviation {worst:e} rad");
    // With the whole demand left to the motors, the wearer's torque is only the braces' correction.
    let assisted = worn_leg([0.0, 1.0, 1.0]);
    let t = 3.2;
    let w = assisted.wearer.intended(t);
    let human = assisted.human_torque(t, &join(&w.q, &w.qd));
    assert!(
        human[1].abs() < 1e-12 && human[2].abs() < 1e-12,
        "{human:?}"
    );
    assert!((human[0] - assisted.joint_torque_demand(t)[0]).abs() < 1e-12);
}

/// Eq. (28) made deliverable with the passive ankle: the ankle entry is zero and, under the model, the knee
/// and hip get exactly the commanded accelerations while the ankle moves as its own torque makes it.
#[test]
fn passive_ankle_torque_keeps_the_commanded_knee_and_hip_accelerations() {
    let d = leg();
    let mut rng = Rng::new(15);
    for _ in 0..100 {
        let (q, qd) = random_state(&mut rng);
        let u = Vector3::from_fn(|_, _| 20.0 * rng.normal());
        let m = d.mass_matrix(&q);
        let bias = d.coriolis_torque(&q, &qd) + d.gravity_torque(&q);
        let tau = m * u + bias;
        let delivered =
            passive_ankle_torque(&m, &tau).unwrap_or_else(|| panic!("M00 = {}", m[(0, 0)]));
        assert_eq!(delivered[0], 0.0);
        let qdd = d
            .acceleration(&q, &qd, &delivered)
            .unwrap_or_else(|| panic!("M(q) singular at {q:?}"));
        let scale = u.amax().max(1.0);
        assert!((qdd[1] - u[1]).abs() < 1e-9 * scale, "{qdd:?} vs {u:?}");
        assert!((qdd[2] - u[2]).abs() < 1e-9 * scale, "{qdd:?} vs {u:?}");
        assert!((qdd[0] - (u[0] - tau[0] / m[(0, 0)])).abs() < 1e-9 * scale);
    }
    assert_eq!(
        passive_ankle_torque(&Matrix3::zeros(), &Vector3::zeros()),
        None
    );
}

/// The motors deliver at most their ratings (17 N m knee, 38 N m hip, none at the passive ankle), and a
/// non-finite command delivers nothing.
#[test]
fn motors_deliver_at_most_their_ratings() {
    assert_eq!(MOTOR_PEAK_TORQUE, [0.0, 17.0, 38.0]);
    let u = Vector3::new(5.0, -30.0, 20.0);
    assert_eq!(WalkingPlant::actuator(&u), Vector3::new(0.0, -17.0, 20.0));
    assert!(WalkingPlant::saturates(&u));
    assert!(!WalkingPlant::saturates(&Vector3::new(100.0, 17.0, -38.0)));
    assert_eq!(
        WalkingPlant::actuator(&Vector3::new(1.0, f64::NAN, f64::INFINITY)),
        Vector3::zeros()
    );
}

/// Settings out of their domain are refused with the setting's name, not a panic.
#[test]
fn bad_settings_are_refused() {
    use bgc_workspace::walking::scenario::WalkingError;
    let refused = |cfg: WalkingConfig| match run(&cfg) {
        Err(WalkingError::Setting { name, .. }) => name.to_string(),
        Err(WalkingError::Estimation { source, .. }) => format!("{source}"),
        other => panic!("accepted: {:?}", other.map(|r| r.table9)),
    };
    let base = WalkingConfig::paper(3.0);
    assert_eq!(
        refused(WalkingConfig {
            control_period: 0.0,
            ..base
        }),
        "control_period"
    );
    assert_eq!(
        refused(WalkingConfig {
            filter_decimation: 0,
            ..base
        }),
        "filter_decimation"
    );
    assert_eq!(
        refused(WalkingConfig {
            duration: f64::NAN,
            ..base
        }),
        "duration"
    );
    assert_eq!(
        refused(WalkingConfig {
            impedance_frequency: -1.0,
            ..base
        }),
        "impedance_frequency"
    );
    let mut cfg = base;
    cfg.estimator.forgetting = 1.5;
    assert!(refused(cfg).contains("lambda_RLS"));
    let mut cfg = base;
    cfg.estimator.initial_masses[2] = 0.0;
    assert!(refused(cfg).contains("initial_masses"));
    let mut cfg = base;
    cfg.estimator.torque_error_std[0] = f64::INFINITY;
    assert!(refused(cfg).contains("torque_error_std"));
    for bandwidth in [0.0, 500.0, f64::NAN] {
        assert_eq!(
            refused(WalkingConfig {
                reference_bandwidth: bandwidth,
                ..base
            }),
            "reference_bandwidth"
        );
    }
}

/// The leg's masses as runtime parameters: read, set (the inertia follows the mass) and refused when
/// non-physical.
#[test]
fn leg_masses_are_runtime_parameters() {
    use bgc_runtime::model::{ParamError, Parametric};
    let mut model = LegModel::new(LegSegments::paper_subject(), LegFriction::none());
    assert_eq!(model.param(2), Some(0.1057 * 77.0));
    let inertia = model.dynamics.segments.thigh.inertia();
    assert_eq!(model.set_param(2, 2.0 * 0.1057 * 77.0), Ok(()));
    assert!((model.dynamics.segments.thigh.inertia() - 2.0 * inertia).abs() < 1e-12);
    assert_eq!(
        model.set_param(3, 1.0),
        Err(ParamError::NoSuchParam { index: 3 })
    );
    assert!(matches!(
        model.set_param(0, -1.0),
        Err(ParamError::NonPhysical {
            name: "m1_foot",
            ..
        })
    ));
    assert_eq!(model.param(5), None);
}
