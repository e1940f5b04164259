//! The gait supervisor on scripted insole-force sequences.

use bgc_runtime::control::{
    ControlError, FootEvent, GaitState, GaitSupervisor, GaitThresholds, GrfSample, GrfSensor, Leg,
    LegMode, Transition, classify, ground_reaction_index,
};

// Typical insole readings (N): heel-strike loads the heel, heel-off the ball, heel-flat both.
const STRIKE: GrfSample = GrfSample {
    heel: 400.0,
    ball: 20.0,
}; // P = 380/420 = 0.905
const FLAT: GrfSample = GrfSample {
    heel: 300.0,
    ball: 280.0,
}; // P = 20/580 = 0.034
const OFF: GrfSample = GrfSample {
    heel: 10.0,
    ball: 500.0,
}; // P = −490/510 = −0.961
const AIR: GrfSample = GrfSample {
    heel: 2.0,
    ball: 1.0,
}; // 3 N < 20 N: unloaded
const MID: GrfSample = GrfSample {
    heel: 300.0,
    ball: 100.0,
}; // P = 0.5: between bands

#[test]
fn index_of_equation_30() {
    let th = GaitThresholds::default();
    let p = |g| ground_reaction_index(Leg::Right, g, &th).unwrap();
    assert!(
        (p(GrfSample {
            heel: 30.0,
            ball: 10.0
        })
        .unwrap()
            - 0.5)
            .abs()
            < 1e-15
    );
    assert_eq!(
        p(GrfSample {
            heel: 0.0,
            ball: 50.0
        }),
        Some(-1.0)
    );
    assert_eq!(
        p(GrfSample {
            heel: 50.0,
            ball: 0.0
        }),
        Some(1.0)
    );
    assert_eq!(p(AIR), None);
    // A small negative reading is offset and counts as zero.
    assert_eq!(
        p(GrfSample {
            heel: -5.0,
            ball: 100.0
        }),
        Some(-1.0)
    );
    let fault = ground_reaction_index(
        Leg::Left,
        GrfSample {
            heel: 10.0,
            ball: f64::NAN,
        },
        &th,
    );
    let f = fault.unwrap_err();
    assert_eq!((f.leg, f.sensor), (Leg::Left, GrfSensor::Ball));
    assert!(f.value.is_nan());
    assert_eq!(classify(p(STRIKE), &th), FootEvent::HeelStrike);
    assert_eq!(classify(p(FLAT), &th), FootEvent::HeelFlat);
    assert_eq!(classify(p(OFF), &th), FootEvent::HeelOff);
    assert_eq!(classify(p(MID), &th), FootEvent::NoEvent);
    assert_eq!(classify(p(AIR), &th), FootEvent::Unloaded);
}

/// Feeds `n` identical samples and returns the transitions that fired.
fn feed(s: &mut GaitSupervisor, right: GrfSample, left: GrfSample, n: usize) -> Vec<Transition> {
    (0..n)
        .filter_map(|_| s.update(right, left).transition)
        .collect()
}

#[test]
fn one_full_gait_cycle_visits_s1_to_s4_in_order() {
    let mut s = GaitSupervisor::new(GaitThresholds::default()).unwrap();
    assert_eq!(s.state(), GaitState::RightPreswing);
    // Standing flat: nothing happens.
    assert!(feed(&mut s, FLAT, FLAT, 10).is_empty());
    // p1: right heel-off with left flat → S2 after 3 samples.
    assert_eq!(feed(&mut s, OFF, FLAT, 2), vec![]);
    assert_eq!(feed(&mut s, OFF, FLAT, 1), vec![Transition::P1]);
    assert_eq!(s.state(), GaitState::RightSwing);
    assert_eq!(s.state().mode(Leg::Right), LegMode::Swing);
    // Right foot in the air: no event.
    assert!(feed(&mut s, AIR, FLAT, 20).is_empty());
    // p2: right heel-strike, left flat → S3.
    assert_eq!(feed(&mut s, STRIKE, FLAT, 5), vec![Transition::P2]);
    assert_eq!(s.state(), GaitState::LeftPreswing);
    assert_eq!(s.state().label(), "S3");
    assert_eq!(s.state().mode(Leg::Left), LegMode::Swing);
    assert_eq!(s.state().mode(Leg::Right), LegMode::Stance);
    // p3 → S4, swing in the air, p4 → back to S1.
    assert_eq!(feed(&mut s, FLAT, OFF, 3), vec![Transition::P3]);
    assert_eq!(s.state(), GaitState::LeftSwing);
    assert!(feed(&mut s, FLAT, AIR, 20).is_empty());
    assert_eq!(feed(&mut s, FLAT, STRIKE, 3), vec![Transition::P4]);
    assert_eq!(s.state(), GaitState::RightPreswing);
}

#[test]
fn glitches_shorter_than_the_debounce_and_out_of_order_events_are_ignored() {
    let mut s = GaitSupervisor::new(GaitThresholds::default()).unwrap();
    // Two heel-off samples, one flat, two heel-off: never three in a row.
    for r in [OFF, OFF, FLAT, OFF, OFF, MID] {
        assert_eq!(s.update(r, FLAT).transition, None);
    }
    assert_eq!(s.state(), GaitState::RightPreswing);
    // p2 and p3 patterns do not leave S1.
    assert!(feed(&mut s, STRIKE, FLAT, 10).is_empty());
    assert!(feed(&mut s, FLAT, OFF, 10).is_empty());
    assert_eq!(s.state(), GaitState::RightPreswing);
    // Without debounce the paper's bare logic fires on the first sample.
    let mut bare = GaitSupervisor::new(GaitThresholds {
        debounce_samples: 1,
        ..GaitThresholds::default()
    })
    .unwrap();
    assert_eq!(feed(&mut bare, OFF, FLAT, 1), vec![Transition::P1]);
}

#[test]
fn nan_force_holds_the_state_reports_and_restarts_the_debounce() {
    let mut s = GaitSupervisor::new(GaitThresholds::default()).unwrap();
    assert!(feed(&mut s, OFF, FLAT, 2).is_empty());
    let step = s.update(
        GrfSample {
            heel: f64::NAN,
            ball: 400.0,
        },
        FLAT,
    );
    assert_eq!(step.state, GaitState::RightPreswing);
    assert_eq!(step.transition, None);
    assert_eq!(step.right_event, FootEvent::Fault);
    let fault = step.fault.unwrap();
    assert_eq!((fault.leg, fault.sensor), (Leg::Right, GrfSensor::Heel));
    assert_eq!(s.fault_count(), 1);
    // The two heel-off samples before the fault no longer count: three more are needed.
    assert!(feed(&mut s, OFF, FLAT, 2).is_empty());
    assert_eq!(feed(&mut s, OFF, FLAT, 1), vec![Transition::P1]);
    // An infinite or strongly negative left reading is also a fault.
    let step = s.update(
        AIR,
        GrfSample {
            heel: f64::INFINITY,
            ball: 0.0,
        },
    );
    assert_eq!(step.fault.map(|f| f.leg), Some(Leg::Left));
    let step = s.update(
        AIR,
        GrfSample {
            heel: -100.0,
            ball: 0.0,
        },
    );
    assert_eq!(step.fault.map(|f| f.value), Some(-100.0));
    assert_eq!(s.fault_count(), 3);
    assert_eq!(s.state(), GaitState::RightSwing);
    assert_eq!(s.reset(), Transition::P0);
    assert_eq!(s.state(), GaitState::RightPreswing);
}

#[test]
fn inconsistent_thresholds_are_refused() {
    let bad = |th| {
        matches!(
            GaitSupervisor::new(th),
            Err(ControlError::BadThreshold { .. })
        )
    };
    let d = GaitThresholds::default();
    assert!(bad(GaitThresholds { flat: 0.8, ..d }));
    assert!(bad(GaitThresholds { heel_off: 0.0, ..d }));
    assert!(bad(GaitThresholds { min_load: 0.0, ..d }));
    assert!(bad(GaitThresholds {
        debounce_samples: 0,
        ..d
    }));
    assert!(bad(GaitThresholds {
        alpha_heel: -1.0,
        alpha_ball: 1.0,
        ..d
    }));
    assert!(bad(GaitThresholds {
        heel_strike: f64::NAN,
        ..d
    }));
}
