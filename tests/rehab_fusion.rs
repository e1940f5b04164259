//! The measurement-system example's shared logic (`bgc_workspace::rehab`): the `.bg` models against their
//! hand-derived reference, the sensor synthesis against hand kinematics, the weights of Eq. 27 against a hand
//! computation on the rig's measured variances, the fusion against each single source on several seeds, and the
//! faults (lost frames, a NaN sample).

use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;
use bgc_runtime::model::ContinuousModel;
use bgc_runtime::noise::Rng;
use bgc_workspace::rehab::RehabError;
use bgc_workspace::rehab::experiment::{DEG2_PER_RAD2, Setup, run_leg, run_rig};
use bgc_workspace::rehab::generated::{pendulum_rig_model, rehab_leg_model};
use bgc_workspace::rehab::pipeline::{estimate_sources, fuse};
use bgc_workspace::rehab::plant::{pendulum_rig, rehab_leg};
use bgc_workspace::rehab::sensors::{CameraSpec, GRAVITY, ImuSpec, capture_frames, sample_imu};
use bgc_workspace::rehab::truth::{LegGeometry, RigGeometry, leg_truth, rig_truth};
use nalgebra::SVector;

const DEG: f64 = std::f64::consts::PI / 180.0;

/// Lowers a model file and returns its single model; it must have no diagnostic at all.
fn lower_clean(name: &str, text: &str) -> bgc::ir::Model {
    let mut sources = SourceMap::new();
    let root = sources.add(name, text);
    let (mut models, diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    assert!(
        diags.is_empty(),
        "{}",
        bgc::diagnostic::render::to_text(&sources, &diags, false)
    );
    assert_eq!(models.len(), 1);
    let m = models.remove(0);
    assert_eq!(bgc::lower::validate(&m), Ok(()));
    m
}

fn param(m: &bgc::ir::Model, name: &str) -> f64 {
    let i = m.param_by_name(name);
    assert!(i.is_some(), "no parameter {name}");
    i.and_then(|i| m.params.get(i))
        .map_or(f64::NAN, |p| p.default)
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1.0)
}

#[test]
fn pendulum_rig_bg_lowers_and_matches_the_reference_parameters() {
    let m = lower_clean("pendulum_rig.bg", include_str!("../models/pendulum_rig.bg"));
    let p = pendulum_rig().params;
    // 30 deg is converted to radians; the rest are SI as written.
    for (name, value) in [
        ("A_ref", p.a_ref),
        ("T_ref", p.t_ref),
        ("k_s", p.k_s),
        ("d_s", p.d_s),
        ("J_p", p.j_p),
        ("b_p", p.b_p),
        ("m_p", p.m_p),
        ("l_p", p.l_p),
        ("g", p.g),
    ] {
        assert!(close(param(&m, name), value, 1e-12), "{name}");
    }
    assert!(close(p.a_ref, 30.0 * DEG, 1e-15));
    assert_eq!(m.vars.len(), 2);
    assert_eq!(m.outputs.len(), 3);
}

#[test]
fn rehab_leg_bg_lowers_and_matches_the_reference_curves() {
    let m = lower_clean("rehab_leg.bg", include_str!("../models/rehab_leg.bg"));
    let p = rehab_leg().params;
    assert!(close(param(&m, "T_gait"), p.hip.period, 1e-12));
    assert!(close(param(&m, "T_gait"), p.knee.period, 1e-12));
    assert!(close(param(&m, "J_t"), p.j_t, 1e-12));
    assert!(close(param(&m, "J_c"), p.j_c, 1e-12));
    assert!(close(param(&m, "h0"), p.hip.c0, 1e-12));
    assert!(close(param(&m, "k0"), p.knee.c0, 1e-12));
    for i in 0..4 {
        let n = i + 1;
        assert!(close(param(&m, &format!("ha{n}")), p.hip.a[i], 1e-12));
        assert!(close(param(&m, &format!("hb{n}")), p.hip.b[i], 1e-12));
        assert!(close(param(&m, &format!("ka{n}")), p.knee.a[i], 1e-12));
        assert!(close(param(&m, &format!("kb{n}")), p.knee.b[i], 1e-12));
    }
    assert_eq!(m.outputs.len(), 5);
}

/// The curves reproduce the normative points they were fitted to within the fit's residuals (0.8 deg hip,
/// 1.5 deg knee): at heel strike hip 30 deg and knee 5 deg, hip extension -9 deg at 55 %, knee peak 61 deg at 75 %.
#[test]
fn gait_curves_pass_through_the_normative_points() {
    let p = rehab_leg().params;
    let at = |c: &bgc_workspace::rehab::plant::GaitCurve, pct: f64| {
        c.value(pct / 100.0 * c.period) / DEG
    };
    assert!((at(&p.hip, 0.0) - 30.0).abs() < 0.8);
    assert!((at(&p.hip, 55.0) + 9.0).abs() < 0.8);
    assert!((at(&p.knee, 0.0) - 5.0).abs() < 1.5);
    assert!((at(&p.knee, 75.0) - 61.0).abs() < 1.5);
    // The rate is the derivative of the value (central difference, h = 1e-5 s).
    for t in [0.1, 0.9, 1.7, 2.6] {
        let fd = (p.knee.value(t + 1e-5) - p.knee.value(t - 1e-5)) / 2e-5;
        assert!((p.knee.rate(t) - fd).abs() < 1e-6, "t = {t}");
    }
}

/// The leg simulated through the solver gives back the curves (the integrated flows plus the values at t = 0), and
/// the calf's inclination is thigh minus knee flexion (Eq. 1 with the paper's signs).
#[test]
fn simulated_leg_follows_the_standard_curves() {
    let leg = rehab_leg();
    let truth = leg_truth(&rehab_leg_model(), LegGeometry::default(), 4.0, 1e-3);
    assert!(truth.is_ok());
    let Ok(truth) = truth else { return };
    for t in [0.5, 1.25, 2.0, 3.7] {
        let thigh = truth.state(0, t).map_or(f64::NAN, |s| s.angle);
        let calf = truth.state(1, t).map_or(f64::NAN, |s| s.angle);
        let (h, k) = (leg.params.hip.value(t), leg.params.knee.value(t));
        assert!((thigh - h).abs() < 1e-6, "thigh at {t}");
        assert!((calf - (h - k)).abs() < 1e-6, "calf at {t}");
    }
    let mut y = SVector::<f64, 5>::zeros();
    leg.outputs(0.0, &SVector::zeros(), &SVector::zeros(), &mut y);
    assert!((y[4] - (leg.params.hip.rate(0.0) - leg.params.knee.rate(0.0))).abs() < 1e-15);
}

/// A stiff coupling makes the pendulum follow the stepper; the twist carries the torque that moves the pendulum,
/// so quasi-statically `k_s q_c ≈ J θ̈ + b θ̇ + m g l sin θ` along the reference (the drive damping's share is
/// second order). Checked at the reference's peak (θ̈ = -A ω², θ̇ = 0) and zero crossing (θ̈ = 0, θ̇ = A ω).
#[test]
fn rig_twist_carries_the_torque_that_moves_the_pendulum() {
    let mut rig = pendulum_rig();
    rig.params.k_s = 2.5e3;
    rig.params.d_s = 2.0;
    let p = rig.params;
    let w = 2.0 * std::f64::consts::PI / p.t_ref;
    let times = [4.0, 4.5]; // a zero crossing (cos = 1) and a positive peak (sin = 1)
    let opts = bgc_runtime::sim::SolverOptions::default();
    let tr = bgc_runtime::sim::simulate_open_loop(
        &rig,
        0.0,
        &rig.initial_state(),
        |_| SVector::<f64, 0>::zeros(),
        &times,
        &opts,
    );
    assert!(tr.is_ok(), "{tr:?}");
    let Ok(tr) = tr else { return };
    // 0.012 * (-0.5236 * 9.870) + 0.35 * 9.81 * 0.18 * sin(30 deg) = -0.0620 + 0.3090 = 0.2470 N m.
    let expected_peak = -p.j_p * p.a_ref * w * w + p.m_p * p.g * p.l_p * p.a_ref.sin();
    assert!((expected_peak - 0.2470).abs() < 1e-4);
    let expected_zero = p.b_p * p.a_ref * w;
    let q = |i: usize| tr.states.get(i).map_or(f64::NAN, |x| x[0]);
    assert!(
        (p.k_s * q(1) - expected_peak).abs() < 0.02 * expected_peak.abs(),
        "peak: {} vs {expected_peak}",
        p.k_s * q(1)
    );
    assert!(
        (p.k_s * q(0) - expected_zero).abs() < 2e-3,
        "zero crossing: {} vs {expected_zero}",
        p.k_s * q(0)
    );
    let theta = |i: usize| tr.states.get(i).map_or(f64::NAN, |x| x[2]);
    assert!(theta(0).abs() < 0.01 * p.a_ref);
    assert!((theta(1) - p.a_ref).abs() < 0.01 * p.a_ref);
}

/// The accelerometer of a still, tilted segment reads gravity only, so Eq. 2 returns the tilt; on a segment
/// turning at a constant rate the unit's x axis also reads the centripetal r ω² and z the tangential term is zero.
#[test]
fn accelerometer_reads_gravity_and_the_motion_at_its_radius() {
    let truth = leg_truth(&rehab_leg_model(), LegGeometry::default(), 3.0, 1e-3);
    assert!(truth.is_ok());
    let Ok(truth) = truth else { return };
    let spec = ImuSpec {
        dt: 0.01,
        accel_noise: 0.0,
        gyro_noise: 0.0,
        gyro_bias: 0.0,
    };
    let samples = sample_imu(&truth, 0, 0.0, &spec, &mut Rng::new(1));
    assert!(samples.is_ok());
    let Ok(samples) = samples else { return };
    // At the hip (radius 0) the thigh unit sees gravity only: Eq. 2 is exact.
    for s in samples.iter().step_by(37) {
        let a = bgc_runtime::estimation::angle::accelerometer_angle(s.acc[0], s.acc[1], s.acc[2]);
        let angle = truth.state(0, s.t).map_or(f64::NAN, |x| x.angle);
        assert!((a - angle).abs() < 1e-12, "t = {}", s.t);
        assert!((s.acc[0].hypot(s.acc[2]) - GRAVITY).abs() < 1e-9);
    }
    // At radius r the specific force along the segment is g cos φ + r ω², across it g sin φ + r φ̈ (hand
    // kinematics of a point on a link about a fixed pivot).
    let r = 0.3;
    let samples = sample_imu(&truth, 0, r, &spec, &mut Rng::new(1));
    let Ok(samples) = samples else { return };
    for s in samples.iter().step_by(41) {
        let x = truth.state(0, s.t);
        let Some(x) = x else { continue };
        let along = GRAVITY * x.angle.cos() + r * x.rate * x.rate;
        let across = GRAVITY * x.angle.sin() + r * x.accel;
        assert!((s.acc[0] - along).abs() < 1e-9 && (s.acc[2] + across).abs() < 1e-9);
    }
}

/// Eq. 27 for two sensors by hand: W_IMU = (1/σ_I²)/(1/σ_I² + 1/σ_V²) = σ_V²/(σ_I² + σ_V²), W_V = 1 − W_IMU,
/// and Eq. 25 at the optimum σ_I² σ_V²/(σ_I² + σ_V²), on the variances this rig measures (seed 1: IMU 17.60 deg²,
/// vision 19.96 deg², as the example prints).
#[test]
fn weights_of_eq_27_match_a_hand_computation_on_the_rig_variances() {
    let rig = run_rig(&pendulum_rig_model(), &Setup::rig(), 1);
    assert!(rig.is_ok(), "{rig:?}");
    let Ok(rig) = rig else { return };
    let [vi, vv] = rig.variances;
    assert!(
        (vi * DEG2_PER_RAD2 - 17.60).abs() < 0.01,
        "{}",
        vi * DEG2_PER_RAD2
    );
    assert!(
        (vv * DEG2_PER_RAD2 - 19.96).abs() < 0.01,
        "{}",
        vv * DEG2_PER_RAD2
    );
    // By hand from the printed variances: 19.96 / (17.60 + 19.96) = 0.5314, and 17.60 * 19.96 / 37.56 = 9.353.
    assert!((rig.weights[0] - 0.5314).abs() < 5e-4, "{:?}", rig.weights);
    assert!((rig.weights[1] - 0.4686).abs() < 5e-4);
    assert!((rig.fused_variance * DEG2_PER_RAD2 - 9.353).abs() < 0.01);
    // And exactly from the unrounded variances.
    assert!((rig.weights[0] - vv / (vi + vv)).abs() < 1e-15);
    assert!((rig.fused_variance - vi * vv / (vi + vv)).abs() < 1e-15);
    // The IMU filter's R is the accelerometer-angle variance measured on the rig (18.64 deg²).
    assert!((rig.accel_variance * DEG2_PER_RAD2 - 18.64).abs() < 0.01);
    assert_eq!(rig.calibration.filter.r, rig.accel_variance);
}

/// The paper's claim (Eqs. 30, 33, 35): the fusion is better than each single source, on the rig and on both
/// segments of the exoskeleton, whatever the noise realisation. Also the paper's single-source orderings on the
/// exoskeleton: thigh E_vision > E_IMU (Eq. 33), calf E_IMU > E_vision (Eq. 35). (On the rig the two sources are
/// within a few per cent of each other, so their order there depends on the seed.)
#[test]
fn fusion_beats_each_single_source_on_several_seeds() {
    for seed in [1, 7, 42, 1234, 98765] {
        let rig = run_rig(&pendulum_rig_model(), &Setup::rig(), seed);
        assert!(rig.is_ok(), "{rig:?}");
        let Ok(rig) = rig else { return };
        let leg = run_leg(
            &rehab_leg_model(),
            &Setup::leg(),
            &rig.calibration,
            seed + 1,
        );
        assert!(leg.is_ok(), "{leg:?}");
        let Ok([thigh, calf]) = leg else { return };
        for run in [&rig.segment, &thigh, &calf] {
            let f = run.figures;
            assert!(
                f.e_fusion < f.e_imu.min(f.e_vision),
                "seed {seed}, {}: {f:?}",
                run.name
            );
            assert!(run.fused.iter().all(|v| v.is_finite()));
        }
        assert!(thigh.figures.e_vision > thigh.figures.e_imu, "seed {seed}");
        assert!(calf.figures.e_imu > calf.figures.e_vision, "seed {seed}");
    }
}

#[test]
fn same_seed_same_figures_and_another_seed_differs() {
    let a = run_rig(&pendulum_rig_model(), &Setup::rig(), 3).map(|r| r.segment.figures);
    let b = run_rig(&pendulum_rig_model(), &Setup::rig(), 3).map(|r| r.segment.figures);
    let c = run_rig(&pendulum_rig_model(), &Setup::rig(), 4).map(|r| r.segment.figures);
    assert!(a.is_ok());
    assert_eq!(a, b);
    assert_ne!(a, c);
}

/// A 1 s camera outage, scattered lost frames, a NaN gyro sample, a NaN accelerometer sample, and a NaN gyro
/// sample inside the outage: nothing panics, nothing in the fused output is NaN, and the fused estimate is the
/// remaining source wherever one source is missing.
#[test]
fn lost_frames_and_nan_samples_fall_back_to_the_remaining_source() {
    let rig = run_rig(&pendulum_rig_model(), &Setup::rig(), 1);
    let Ok(rig) = rig else { panic!("{rig:?}") };
    let setup = Setup::leg();
    let truth = leg_truth(&rehab_leg_model(), LegGeometry::default(), 8.0, 1e-3);
    let Ok(truth) = truth else {
        panic!("{truth:?}")
    };
    let camera = CameraSpec {
        lost_probability: 0.3,
        ..setup.camera
    };
    let frames = capture_frames(&truth, 1, &camera, &mut Rng::new(5)).map(|c| c.frames);
    let samples = sample_imu(&truth, 1, 0.12, &setup.imu, &mut Rng::new(6));
    let (Ok(mut frames), Ok(mut samples)) = (frames, samples) else {
        panic!("sensor synthesis failed")
    };
    frames.retain(|f| !(3.0..4.0).contains(&f.arrival));
    let nan_gyro = 100;
    let nan_accel = 150;
    let nan_in_outage = samples
        .iter()
        .position(|s| s.t > 3.6)
        .unwrap_or(samples.len());
    for (k, s) in samples.iter_mut().enumerate() {
        if k == nan_gyro || k == nan_in_outage {
            s.gyro = f64::NAN;
        }
        if k == nan_accel {
            s.acc[2] = f64::NAN;
        }
    }
    let est = estimate_sources(
        &truth,
        1,
        &samples,
        &frames,
        setup.imu.dt,
        &rig.calibration.filter,
        setup.max_vision_age,
    );
    let Ok(est) = est else { panic!("{est:?}") };
    let fused = fuse(&est, &rig.calibration.fusion, None);
    let Ok(fused) = fused else {
        panic!("{fused:?}")
    };
    assert_eq!(fused.len(), samples.len());
    assert!(fused.iter().all(|v| v.is_finite()));
    assert!(est.imu.iter().all(|v| v.is_finite()));
    // The NaN gyro sample is no IMU reading: the fusion is the vision there.
    assert!(!est.imu_valid[nan_gyro] && est.vision[nan_gyro].is_finite());
    assert!((fused[nan_gyro] - est.vision[nan_gyro]).abs() < 1e-12);
    // So is the NaN accelerometer sample.
    assert!(!est.imu_valid[nan_accel]);
    assert!((fused[nan_accel] - est.vision[nan_accel]).abs() < 1e-12);
    // Inside the outage (after the hold's limit) vision is absent and the fusion is the IMU.
    let outage: Vec<usize> = (0..est.times.len())
        .filter(|&k| est.times[k] > 3.0 + setup.max_vision_age + 0.05 && est.times[k] < 4.0)
        .collect();
    assert!(outage.len() > 40);
    for &k in &outage {
        assert!(est.vision[k].is_nan(), "t = {}", est.times[k]);
        if k != nan_in_outage {
            assert!((fused[k] - est.imu[k]).abs() < 1e-12);
        }
    }
    // With neither source, the fused value is the IMU filter's prediction, finite and close to the truth.
    assert!(!est.imu_valid[nan_in_outage]);
    let k = nan_in_outage;
    assert!((fused[k] - est.truth[k]).abs() < 15.0 * DEG);
    // The IMU filter keeps tracking through the NaN samples (held gyro rate): no jump.
    for k in [nan_gyro, nan_accel, nan_in_outage] {
        assert!((est.imu[k + 1] - est.imu[k]).abs() < 3.0 * DEG);
    }
    // The Eqs. 19-21 stage survives the same faults.
    let smoothed = fuse(&est, &rig.calibration.fusion, Some(1e-4));
    assert!(smoothed.is_ok_and(|v| v.iter().all(|x| x.is_finite())));
}

#[test]
fn bad_settings_are_refused_with_their_name() {
    let truth = rig_truth(&pendulum_rig_model(), RigGeometry::default(), 1.0, 1e-3);
    let Ok(truth) = truth else {
        panic!("{truth:?}")
    };
    let camera = CameraSpec {
        lost_probability: 1.0,
        ..Setup::rig().camera
    };
    assert!(matches!(
        capture_frames(&truth, 0, &camera, &mut Rng::new(1)),
        Err(RehabError::BadSetting {
            name: "camera.lost_probability",
            ..
        })
    ));
    let imu = ImuSpec {
        dt: -0.01,
        ..Setup::rig().imu
    };
    assert!(matches!(
        sample_imu(&truth, 0, 0.2, &imu, &mut Rng::new(1)),
        Err(RehabError::BadSetting { name: "imu.dt", .. })
    ));
    assert!(matches!(
        sample_imu(&truth, 3, 0.2, &Setup::rig().imu, &mut Rng::new(1)),
        Err(RehabError::BadSetting {
            name: "segment",
            ..
        })
    ));
    assert!(matches!(
        rig_truth(
            &pendulum_rig_model(),
            RigGeometry::default(),
            f64::NAN,
            1e-3
        ),
        Err(RehabError::BadSetting { name: "t_end", .. })
    ));
}

/// Noise-free markers at the knee and the ankle give back the calf's angle (the knee itself moving with the thigh),
/// and each frame arrives `latency` after its capture.
#[test]
fn noise_free_markers_give_the_segment_angle() {
    let truth = leg_truth(&rehab_leg_model(), LegGeometry::default(), 3.0, 1e-3);
    let Ok(truth) = truth else {
        panic!("{truth:?}")
    };
    let camera = CameraSpec {
        frame_rate: 25.0,
        latency: 0.05,
        pixel_noise: 0.0,
        scale: 600.0,
        lost_probability: 0.0,
    };
    let capture = capture_frames(&truth, 1, &camera, &mut Rng::new(9));
    let Ok(capture) = capture else {
        panic!("{capture:?}")
    };
    assert_eq!(capture.frames.len(), capture.captured);
    assert!(capture.captured >= 74 && capture.captured <= 75);
    for f in &capture.frames {
        let angle = truth
            .state(1, f.arrival - camera.latency)
            .map_or(f64::NAN, |s| s.angle);
        assert!((f.angle - angle).abs() < 1e-9, "t = {}", f.arrival);
    }
}

// The generated models against the hand-derived reference.

/// Both generated models keep the layout the study reads: energy states first (the rig's coupling twist and
/// pendulum momentum; the leg has none, both inertias being in derivative causality), then the integrated flows.
#[test]
fn generated_models_have_the_layout_the_study_reads() {
    use bgc_models::{pendulum_rig, rehab_leg};
    use bgc_workspace::rehab::generated::{LegLayout, RigLayout};
    assert_eq!(
        pendulum_rig::STATE_NAMES,
        ["q_coupling", "p_pendulum", "theta", "theta_m"]
    );
    assert_eq!(pendulum_rig::N_ENERGY_STATES, 2);
    assert_eq!(
        pendulum_rig::OUTPUT_NAMES,
        ["theta_pend", "omega_pend", "theta_motor"]
    );
    assert_eq!(rehab_leg::STATE_NAMES, ["phi_hip", "phi_knee"]);
    assert_eq!(rehab_leg::N_ENERGY_STATES, 0);
    let rig = RigLayout::of_generated();
    assert_eq!(
        rig,
        Ok(RigLayout {
            twist: 0,
            momentum: 1,
            rotor: 3,
            angle: 0,
            rate: 1,
        })
    );
    let leg = LegLayout::of_generated();
    assert_eq!(
        leg,
        Ok(LegLayout {
            thigh_angle: 0,
            calf_angle: 2,
            thigh_rate: 3,
            calf_rate: 4,
        })
    );
}

/// The generated `Params::default()` are the hand-derived reference's values (the `.bg` defaults in SI units).
#[test]
fn generated_defaults_are_the_reference_parameters() {
    let g = *pendulum_rig_model().params();
    let h = pendulum_rig().params;
    for (name, a, b) in [
        ("A_ref", g.A_ref, h.a_ref),
        ("T_ref", g.T_ref, h.t_ref),
        ("k_s", g.k_s, h.k_s),
        ("d_s", g.d_s, h.d_s),
        ("J_p", g.J_p, h.j_p),
        ("b_p", g.b_p, h.b_p),
        ("m_p", g.m_p, h.m_p),
        ("l_p", g.l_p, h.l_p),
        ("g", g.g, h.g),
    ] {
        assert!(close(a, b, 1e-15), "{name}: {a} vs {b}");
    }
    let g = *rehab_leg_model().params();
    let h = rehab_leg().params;
    assert!(close(g.T_gait, h.hip.period, 1e-15));
    assert!(close(g.J_t, h.j_t, 1e-15) && close(g.J_c, h.j_c, 1e-15));
    assert!(close(g.h0, h.hip.c0, 1e-15) && close(g.k0, h.knee.c0, 1e-15));
    let hip = [
        (g.ha1, g.hb1),
        (g.ha2, g.hb2),
        (g.ha3, g.hb3),
        (g.ha4, g.hb4),
    ];
    let knee = [
        (g.ka1, g.kb1),
        (g.ka2, g.kb2),
        (g.ka3, g.kb3),
        (g.ka4, g.kb4),
    ];
    for i in 0..4 {
        assert!(close(hip[i].0, h.hip.a[i], 1e-15) && close(hip[i].1, h.hip.b[i], 1e-15));
        assert!(close(knee[i].0, h.knee.a[i], 1e-15) && close(knee[i].1, h.knee.b[i], 1e-15));
    }
}

/// The rig with a stiff coupling and heavier damping in both forms (the parameters are set on each side by name).
fn stiff_rigs() -> (
    bgc_workspace::rehab::generated::PendulumRigModel,
    bgc_workspace::rehab::plant::PendulumRig,
) {
    let mut hand = pendulum_rig();
    hand.params.k_s = 2.5e3;
    hand.params.d_s = 2.0;
    hand.params.m_p = 0.5;
    let generated =
        bgc_workspace::rehab::generated::PendulumRigModel::new(bgc_models::pendulum_rig::Params {
            k_s: 2.5e3,
            d_s: 2.0,
            m_p: 0.5,
            ..bgc_models::pendulum_rig::Params::default()
        });
    assert!(generated.is_ok(), "{generated:?}");
    (generated.unwrap_or_default(), hand)
}

/// At random states and times the generated right-hand sides and outputs equal the hand-derived ones (same state
/// order, see the layout test), and so does the pendulum's angular acceleration `ṗ / J_p` the truth reads off.
#[test]
fn generated_and_hand_derived_right_hand_sides_agree_at_random_states() {
    use bgc_workspace::rehab::generated::{RigLayout, rig_angular_acceleration};
    let layout = RigLayout::of_generated();
    assert!(layout.is_ok());
    let Ok(layout) = layout else { return };
    let u = SVector::<f64, 0>::zeros();
    let mut rng = Rng::new(7);
    let (stiff_gen, stiff_hand) = stiff_rigs();
    let rigs = [
        (pendulum_rig_model(), pendulum_rig()),
        (stiff_gen, stiff_hand),
    ];
    for (generated, hand) in &rigs {
        for _ in 0..200 {
            let t = 10.0 * rng.uniform();
            let x = SVector::<f64, 4>::from_fn(|i, _| {
                // Twist within ±0.1 rad, momentum within ±0.05 N m s, angles within ±π.
                let scale = [0.1, 0.05, std::f64::consts::PI, std::f64::consts::PI];
                scale.get(i).copied().unwrap_or(0.0) * (2.0 * rng.uniform() - 1.0)
            });
            let (mut dg, mut dh) = (SVector::<f64, 4>::zeros(), SVector::<f64, 4>::zeros());
            generated.rhs(t, &x, &u, &mut dg);
            hand.rhs(t, &x, &u, &mut dh);
            let (mut yg, mut yh) = (SVector::<f64, 3>::zeros(), SVector::<f64, 3>::zeros());
            generated.outputs(t, &x, &u, &mut yg);
            hand.outputs(t, &x, &u, &mut yh);
            for i in 0..4 {
                assert!(
                    close(dg[i], dh[i], 1e-12),
                    "rig dx[{i}] at t = {t}: {dg} vs {dh}"
                );
            }
            for i in 0..3 {
                assert!(close(yg[i], yh[i], 1e-12), "rig y[{i}] at t = {t}");
            }
            let acc = rig_angular_acceleration(generated, &layout, t, &x);
            assert!(close(acc, dh[1] / hand.params.j_p, 1e-12), "t = {t}");
        }
    }
    let (generated, hand) = (rehab_leg_model(), rehab_leg());
    for _ in 0..200 {
        let t = 10.0 * rng.uniform();
        let x = SVector::<f64, 2>::new(2.0 * rng.uniform() - 1.0, 2.0 * rng.uniform() - 1.0);
        let (mut dg, mut dh) = (SVector::<f64, 2>::zeros(), SVector::<f64, 2>::zeros());
        generated.rhs(t, &x, &u, &mut dg);
        hand.rhs(t, &x, &u, &mut dh);
        let (mut yg, mut yh) = (SVector::<f64, 5>::zeros(), SVector::<f64, 5>::zeros());
        generated.outputs(t, &x, &u, &mut yg);
        hand.outputs(t, &x, &u, &mut yh);
        for i in 0..2 {
            assert!(close(dg[i], dh[i], 1e-12), "leg dx[{i}] at t = {t}");
        }
        for i in 0..5 {
            assert!(
                close(yg[i], yh[i], 1e-12),
                "leg y[{i}] at t = {t}: {yg} vs {yh}"
            );
        }
    }
}

/// Simulated over 5 s through the same solver, the generated and hand-derived rigs (defaults and the stiff
/// variant) and legs give the same angles and rates; `rig_initial_state` is the reference's transient-free start.
#[test]
fn generated_and_hand_derived_models_give_the_same_trajectories() {
    use bgc_runtime::sim::{SolverOptions, simulate_open_loop};
    use bgc_workspace::rehab::generated::{RigLayout, rig_initial_state};
    let opts = SolverOptions {
        rtol: 1e-10,
        atol: 1e-12,
        ..SolverOptions::default()
    };
    let times: Vec<f64> = (0..=500).map(|k| k as f64 * 0.01).collect();
    let zero_u = |_: f64| SVector::<f64, 0>::zeros();
    let layout = RigLayout::of_generated();
    assert!(layout.is_ok());
    let Ok(layout) = layout else { return };
    let (stiff_gen, stiff_hand) = stiff_rigs();
    let mut worst: f64 = 0.0;
    for (generated, hand) in [
        (pendulum_rig_model(), pendulum_rig()),
        (stiff_gen, stiff_hand),
    ] {
        let x0 = rig_initial_state(&generated, &layout);
        assert_eq!(x0, Ok(hand.initial_state()));
        let x0 = x0.unwrap_or_else(|_| SVector::zeros());
        let tg = simulate_open_loop(&generated, 0.0, &x0, zero_u, &times, &opts);
        let th = simulate_open_loop(&hand, 0.0, &hand.initial_state(), zero_u, &times, &opts);
        assert!(tg.is_ok() && th.is_ok());
        let (Ok(tg), Ok(th)) = (tg, th) else { return };
        assert_eq!(tg.outputs.len(), times.len());
        assert_eq!(th.outputs.len(), times.len());
        // The pendulum swings (the comparison is not of two resting states).
        let swing = tg.outputs.iter().map(|y| y[0].abs()).fold(0.0, f64::max);
        assert!(swing > 0.4, "{swing}");
        for (yg, yh) in tg.outputs.iter().zip(&th.outputs) {
            worst = worst.max((yg[0] - yh[0]).abs()).max((yg[2] - yh[2]).abs());
            assert!((yg[1] - yh[1]).abs() < 1e-6, "rate {} vs {}", yg[1], yh[1]);
        }
    }
    assert!(worst < 1e-8, "rig angles differ by {worst} rad");

    let (generated, hand) = (rehab_leg_model(), rehab_leg());
    let x0 = SVector::<f64, 2>::zeros();
    let tg = simulate_open_loop(&generated, 0.0, &x0, zero_u, &times, &opts);
    let th = simulate_open_loop(&hand, 0.0, &x0, zero_u, &times, &opts);
    assert!(tg.is_ok() && th.is_ok());
    let (Ok(tg), Ok(th)) = (tg, th) else { return };
    let mut worst: f64 = 0.0;
    for (yg, yh) in tg.outputs.iter().zip(&th.outputs) {
        for i in 0..3 {
            worst = worst.max((yg[i] - yh[i]).abs());
        }
        assert!((yg[3] - yh[3]).abs() < 1e-12 && (yg[4] - yh[4]).abs() < 1e-12);
    }
    assert!(worst < 1e-8, "leg angles differ by {worst} rad");
}

/// The truth the study simulates from the generated rig equals the hand-derived rig's trajectory, and its angular
/// acceleration is the reference's `ṗ / J_p` at the reference's states.
#[test]
fn rig_truth_from_the_generated_model_follows_the_reference() {
    use bgc_runtime::sim::{SolverOptions, simulate_open_loop};
    let truth = rig_truth(&pendulum_rig_model(), RigGeometry::default(), 3.0, 1e-3);
    assert!(truth.is_ok(), "{truth:?}");
    let Ok(truth) = truth else { return };
    let hand = pendulum_rig();
    let times = [0.0, 0.37, 1.0, 1.9, 2.5, 3.0];
    let opts = SolverOptions {
        rtol: 1e-10,
        atol: 1e-12,
        ..SolverOptions::default()
    };
    let zero_u = |_: f64| SVector::<f64, 0>::zeros();
    let th = simulate_open_loop(&hand, 0.0, &hand.initial_state(), zero_u, &times, &opts);
    assert!(th.is_ok());
    let Ok(th) = th else { return };
    for ((&t, x), y) in times.iter().zip(&th.states).zip(&th.outputs) {
        let s = truth.state(0, t);
        assert!(s.is_some());
        let Some(s) = s else { return };
        let mut dx = SVector::<f64, 4>::zeros();
        hand.rhs(t, x, &SVector::zeros(), &mut dx);
        assert!((s.angle - y[0]).abs() < 1e-7, "angle at {t}");
        assert!((s.rate - y[1]).abs() < 1e-6, "rate at {t}");
        assert!(
            (s.accel - dx[1] / hand.params.j_p).abs() < 1e-4,
            "accel at {t}: {} vs {}",
            s.accel,
            dx[1] / hand.params.j_p
        );
    }
}
