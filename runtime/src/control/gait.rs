//! The 4-state gait-phase supervisor of Sado et al. (2018): ground-reaction index `P` (Eq. 30), foot events,
//! and the hybrid automaton of Table 2 driven by the event pairs of Table 3.
//!
//! # Ground-reaction index (Eq. 30)
//!
//! `P = (α₁ F₁ + α₂ F₂) / (F₁ + F₂)` with `F₁` the heel and `F₂` the ball-of-foot insole force, `α₁ = 1`,
//! `α₂ = −1`, so `P ∈ [−1, 1]`: `P ≈ 1` heel-strike, `P ≈ 0` heel-flat, `P ≈ −1` heel-off. The paper gives
//! only "≈"; the bands used here are thresholds of [`GaitThresholds`] (defaults: heel-strike `P ≥ 0.7`,
//! heel-flat `|P| ≤ 0.2`, heel-off `P ≤ −0.7`, anything between is no event). A foot carrying less than
//! `min_load` in total is unloaded (in the air): Eq. (30) is 0/0 there, so no `P` and no event.
//!
//! # Automaton (Table 2, Table 3, Fig. 6)
//!
//! | state | right leg | mode | left leg | mode |
//! |---|---|---|---|---|
//! | S1 | pre-swing | swing | stance | stance |
//! | S2 | swing | swing | stance | stance |
//! | S3 | stance | stance | pre-swing | swing |
//! | S4 | stance | stance | swing | swing |
//!
//! Table 3 lists five event pairs `p0 … p4` (right, left): `p0` default (initial position), `p1` (heel-off,
//! heel-flat), `p2` (heel-strike, heel-flat), `p3` (heel-flat, heel-off), `p4` (heel-flat, heel-strike). The
//! figure with the arrows is not in the text, so the arrows are read from the prose: heel-off "detects the
//! pilot intention to initiate swing", heel-strike gives "the beginning of stance", and the heel-flat of one
//! leg "allows the alternate leg to move from pre-swing to swing, and/or from swing to heel-strike". That
//! gives the cycle
//!
//! ```text
//!   p0 → S1 ─p1→ S2 ─p2→ S3 ─p3→ S4 ─p4→ S1
//! ```
//!
//! (right heel-off ends the right pre-swing, right heel-strike ends the right swing and hands pre-swing to
//! the left leg, and symmetrically), with a gait cycle from one heel-off to the next, as the paper states.
//! Each event pair is only acted on in the state it leaves; other pairs are ignored.
//!
//! # Debounce and faults (choices not in the paper)
//!
//! The paper has no hysteresis or debounce. Here a transition fires only after its event pair has been seen
//! on `debounce_samples` consecutive updates (default 3; 1 gives the paper's bare logic), and the dead bands
//! between the event bands act as hysteresis. A non-finite force, or one more negative than `−min_load`
//! (small negative readings are sensor offset and count as zero), is a sensor fault: the state is held, the
//! debounce count is cleared and the fault is reported in the step result; nothing panics.

use super::error::ControlError;

/// A leg.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Leg {
    Right,
    Left,
}

/// The trajectory mode a state enables for a leg (Table 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LegMode {
    Swing,
    Stance,
}

/// The states of Table 2.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GaitState {
    /// S1: right leg pre-swing, left leg stance.
    RightPreswing,
    /// S2: right leg swing, left leg stance.
    RightSwing,
    /// S3: right leg stance, left leg pre-swing.
    LeftPreswing,
    /// S4: right leg stance, left leg swing.
    LeftSwing,
}

impl GaitState {
    /// The paper's label, "S1" … "S4".
    pub fn label(self) -> &'static str {
        match self {
            GaitState::RightPreswing => "S1",
            GaitState::RightSwing => "S2",
            GaitState::LeftPreswing => "S3",
            GaitState::LeftSwing => "S4",
        }
    }

    /// The mode of a leg in this state (Table 2).
    pub fn mode(self, leg: Leg) -> LegMode {
        let right_swings = matches!(self, GaitState::RightPreswing | GaitState::RightSwing);
        match (leg, right_swings) {
            (Leg::Right, true) | (Leg::Left, false) => LegMode::Swing,
            _ => LegMode::Stance,
        }
    }

    /// The event pair that leaves this state, and the state it leads to.
    fn exit(self) -> (Transition, GaitState) {
        match self {
            GaitState::RightPreswing => (Transition::P1, GaitState::RightSwing),
            GaitState::RightSwing => (Transition::P2, GaitState::LeftPreswing),
            GaitState::LeftPreswing => (Transition::P3, GaitState::LeftSwing),
            GaitState::LeftSwing => (Transition::P4, GaitState::RightPreswing),
        }
    }
}

/// The event pairs of Table 3.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transition {
    /// Default (initial position): enter S1.
    P0,
    /// Right heel-off, left heel-flat.
    P1,
    /// Right heel-strike, left heel-flat.
    P2,
    /// Right heel-flat, left heel-off.
    P3,
    /// Right heel-flat, left heel-strike.
    P4,
}

impl Transition {
    /// The (right, left) events of this pair; `None` for `P0`.
    pub fn events(self) -> Option<(FootEvent, FootEvent)> {
        use FootEvent::*;
        match self {
            Transition::P0 => None,
            Transition::P1 => Some((HeelOff, HeelFlat)),
            Transition::P2 => Some((HeelStrike, HeelFlat)),
            Transition::P3 => Some((HeelFlat, HeelOff)),
            Transition::P4 => Some((HeelFlat, HeelStrike)),
        }
    }
}

/// A foot event read from `P`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FootEvent {
    /// `P ≈ 1`.
    HeelStrike,
    /// `P ≈ 0`.
    HeelFlat,
    /// `P ≈ −1`.
    HeelOff,
    /// Less than `min_load` on the foot: no `P`.
    Unloaded,
    /// `P` in a dead band between two events.
    NoEvent,
    /// A force reading was faulty (see [`GrfFault`]).
    Fault,
}

/// The two insole forces of one foot (N).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GrfSample {
    /// `F₁`, the heel (rear) sensor.
    pub heel: f64,
    /// `F₂`, the ball-of-foot (front) sensor.
    pub ball: f64,
}

/// Which insole sensor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GrfSensor {
    Heel,
    Ball,
}

/// A faulty force reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GrfFault {
    pub leg: Leg,
    pub sensor: GrfSensor,
    pub value: f64,
}

/// Coefficients, event bands and debounce of the supervisor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaitThresholds {
    /// `α₁`, the heel weight of Eq. (30) (paper: 1).
    pub alpha_heel: f64,
    /// `α₂`, the ball weight of Eq. (30) (paper: −1).
    pub alpha_ball: f64,
    /// `P` at or above which the foot is in heel-strike.
    pub heel_strike: f64,
    /// `P` at or below which the foot is in heel-off.
    pub heel_off: f64,
    /// Half-width of the heel-flat band `|P| ≤ flat`.
    pub flat: f64,
    /// Total force (N) below which the foot is unloaded.
    pub min_load: f64,
    /// Consecutive updates an event pair must persist before its transition fires (≥ 1).
    pub debounce_samples: u32,
}

impl Default for GaitThresholds {
    fn default() -> Self {
        GaitThresholds {
            alpha_heel: 1.0,
            alpha_ball: -1.0,
            heel_strike: 0.7,
            heel_off: -0.7,
            flat: 0.2,
            min_load: 20.0,
            debounce_samples: 3,
        }
    }
}

impl GaitThresholds {
    fn check(&self) -> Result<(), ControlError> {
        let bad = |name, value, reason| {
            Err(ControlError::BadThreshold {
                name,
                value,
                reason,
            })
        };
        for (name, v) in [
            ("alpha_heel", self.alpha_heel),
            ("alpha_ball", self.alpha_ball),
            ("heel_strike", self.heel_strike),
            ("heel_off", self.heel_off),
            ("flat", self.flat),
            ("min_load", self.min_load),
        ] {
            if !v.is_finite() {
                return bad(name, v, "thresholds must be finite");
            }
        }
        if self.alpha_heel <= self.alpha_ball {
            return bad(
                "alpha_heel",
                self.alpha_heel,
                "α₁ must exceed α₂ so that heel load raises P",
            );
        }
        if self.flat < 0.0 {
            return bad(
                "flat",
                self.flat,
                "the heel-flat half-width must be non-negative",
            );
        }
        if self.heel_strike <= self.flat {
            return bad(
                "heel_strike",
                self.heel_strike,
                "the heel-strike band must lie above the heel-flat band",
            );
        }
        if self.heel_off >= -self.flat {
            return bad(
                "heel_off",
                self.heel_off,
                "the heel-off band must lie below the heel-flat band",
            );
        }
        if self.min_load <= 0.0 {
            return bad(
                "min_load",
                self.min_load,
                "the contact load must be positive",
            );
        }
        if self.debounce_samples == 0 {
            return bad("debounce_samples", 0.0, "at least one sample is needed");
        }
        Ok(())
    }
}

/// `P` of Eq. (30) for one foot: `Ok(None)` when unloaded, `Err` with the faulty sensor on a bad reading.
pub fn ground_reaction_index(
    leg: Leg,
    grf: GrfSample,
    th: &GaitThresholds,
) -> Result<Option<f64>, GrfFault> {
    let read = |sensor, value: f64| {
        if !value.is_finite() || value < -th.min_load {
            Err(GrfFault { leg, sensor, value })
        } else {
            Ok(value.max(0.0))
        }
    };
    let f1 = read(GrfSensor::Heel, grf.heel)?;
    let f2 = read(GrfSensor::Ball, grf.ball)?;
    let total = f1 + f2;
    if total < th.min_load {
        return Ok(None);
    }
    Ok(Some((th.alpha_heel * f1 + th.alpha_ball * f2) / total))
}

/// The foot event for an index `P` (`None`: unloaded).
pub fn classify(p: Option<f64>, th: &GaitThresholds) -> FootEvent {
    match p {
        None => FootEvent::Unloaded,
        Some(p) if p >= th.heel_strike => FootEvent::HeelStrike,
        Some(p) if p <= th.heel_off => FootEvent::HeelOff,
        Some(p) if p.abs() <= th.flat => FootEvent::HeelFlat,
        Some(_) => FootEvent::NoEvent,
    }
}

/// The result of one supervisor update.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SupervisorStep {
    /// The state after the update.
    pub state: GaitState,
    /// The transition that fired on this update, if any.
    pub transition: Option<Transition>,
    pub right_event: FootEvent,
    pub left_event: FootEvent,
    pub right_index: Option<f64>,
    pub left_index: Option<f64>,
    /// The first faulty reading of this update (right foot first); the state was held.
    pub fault: Option<GrfFault>,
}

/// The gait-phase automaton.
#[derive(Clone, Debug, PartialEq)]
pub struct GaitSupervisor {
    thresholds: GaitThresholds,
    state: GaitState,
    /// Consecutive updates on which the current state's exit pair has been seen.
    pending: u32,
    faults: u64,
}

impl GaitSupervisor {
    /// A supervisor in its default state (transition `p0`: S1, standing with the right leg to go first).
    pub fn new(thresholds: GaitThresholds) -> Result<Self, ControlError> {
        thresholds.check()?;
        Ok(GaitSupervisor {
            thresholds,
            state: GaitState::RightPreswing,
            pending: 0,
            faults: 0,
        })
    }

    /// Returns to the default state (`p0`).
    pub fn reset(&mut self) -> Transition {
        self.state = GaitState::RightPreswing;
        self.pending = 0;
        Transition::P0
    }

    pub fn state(&self) -> GaitState {
        self.state
    }

    pub fn thresholds(&self) -> &GaitThresholds {
        &self.thresholds
    }

    /// The number of updates so far that carried a faulty reading.
    pub fn fault_count(&self) -> u64 {
        self.faults
    }

    /// Processes one pair of insole readings.
    pub fn update(&mut self, right: GrfSample, left: GrfSample) -> SupervisorStep {
        let th = self.thresholds;
        let r = ground_reaction_index(Leg::Right, right, &th);
        let l = ground_reaction_index(Leg::Left, left, &th);
        let fault = r.err().or(l.err());
        let event = |res: &Result<Option<f64>, GrfFault>| match res {
            Ok(p) => classify(*p, &th),
            Err(_) => FootEvent::Fault,
        };
        let (right_event, left_event) = (event(&r), event(&l));
        let mut step = SupervisorStep {
            state: self.state,
            transition: None,
            right_event,
            left_event,
            right_index: r.ok().flatten(),
            left_index: l.ok().flatten(),
            fault,
        };
        if fault.is_some() {
            self.faults += 1;
            self.pending = 0;
            return step;
        }
        let (transition, next) = self.state.exit();
        if transition.events() == Some((right_event, left_event)) {
            self.pending += 1;
            if self.pending >= th.debounce_samples {
                self.state = next;
                self.pending = 0;
                step.state = next;
                step.transition = Some(transition);
            }
        } else {
            self.pending = 0;
        }
        step
    }
}
