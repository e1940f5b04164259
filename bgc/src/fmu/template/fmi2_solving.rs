//! The Model Exchange and Co-Simulation functions of the FMI 2.0 interface (the common ones are in
//! `fmi2.rs`), with the same checks.

use crate::ffi::{ME_SOLVING, STATES_READABLE, check_count, slice, slice_mut, write};
use crate::fmi2::*;
use crate::instance::{Kind, Outcome, Phase};
use core::ffi::{c_char, c_int, c_void};

#[repr(C)]
pub struct EventInfo {
    new_discrete_states_needed: Boolean,
    terminate_simulation: Boolean,
    nominals_of_continuous_states_changed: Boolean,
    values_of_continuous_states_changed: Boolean,
    next_event_time_defined: Boolean,
    next_event_time: f64,
}

fn expect_kind(comp: &Component, call: &str, kind: Kind) -> Outcome<()> {
    if comp.inst.kind == kind {
        Ok(())
    } else {
        Err(format!(
            "{call} is not a function of {:?} (this instance is {:?})",
            kind, comp.inst.kind
        ))
    }
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterEventMode(c: *mut c_void) -> Status {
    guarded(c, "fmi2EnterEventMode", |comp| {
        expect_kind(comp, "fmi2EnterEventMode", Kind::ModelExchange)?;
        comp.inst.expect("fmi2EnterEventMode", ME_SOLVING)?;
        comp.inst.phase = Phase::Event;
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2NewDiscreteStates(c: *mut c_void, info: *mut EventInfo) -> Status {
    guarded(c, "fmi2NewDiscreteStates", |comp| {
        expect_kind(comp, "fmi2NewDiscreteStates", Kind::ModelExchange)?;
        comp.inst.expect("fmi2NewDiscreteStates", &[Phase::Event])?;
        // No discrete states and no events: the iteration ends at once.
        let none = EventInfo {
            new_discrete_states_needed: FALSE,
            terminate_simulation: FALSE,
            nominals_of_continuous_states_changed: FALSE,
            values_of_continuous_states_changed: FALSE,
            next_event_time_defined: FALSE,
            next_event_time: 0.0,
        };
        write(info, none, "fmi2EventInfo")
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: *mut c_void) -> Status {
    guarded(c, "fmi2EnterContinuousTimeMode", |comp| {
        expect_kind(comp, "fmi2EnterContinuousTimeMode", Kind::ModelExchange)?;
        comp.inst
            .expect("fmi2EnterContinuousTimeMode", &[Phase::Event])?;
        comp.inst.phase = Phase::ContinuousTime;
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
    c: *mut c_void,
    _no_set_prior: Boolean,
    enter_event_mode: *mut Boolean,
    terminate: *mut Boolean,
) -> Status {
    guarded(c, "fmi2CompletedIntegratorStep", |comp| {
        expect_kind(comp, "fmi2CompletedIntegratorStep", Kind::ModelExchange)?;
        comp.inst
            .expect("fmi2CompletedIntegratorStep", &[Phase::ContinuousTime])?;
        write(enter_event_mode, FALSE, "enterEventMode")?;
        write(terminate, FALSE, "terminateSimulation")
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetTime(c: *mut c_void, time: f64) -> Status {
    guarded(c, "fmi2SetTime", |comp| {
        expect_kind(comp, "fmi2SetTime", Kind::ModelExchange)?;
        comp.inst.expect("fmi2SetTime", ME_SOLVING)?;
        comp.inst.set_time(time)
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetContinuousStates(
    c: *mut c_void,
    x: *const f64,
    n: usize,
) -> Status {
    guarded(c, "fmi2SetContinuousStates", |comp| {
        expect_kind(comp, "fmi2SetContinuousStates", Kind::ModelExchange)?;
        comp.inst.expect("fmi2SetContinuousStates", ME_SOLVING)?;
        check_count(n)?;
        comp.inst.set_states(slice(x, n, "x")?)
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetContinuousStates(c: *mut c_void, x: *mut f64, n: usize) -> Status {
    guarded(c, "fmi2GetContinuousStates", |comp| {
        comp.inst.expect("fmi2GetContinuousStates", STATES_READABLE)?;
        check_count(n)?;
        slice_mut(x, n, "x")?.copy_from_slice(comp.inst.states());
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDerivatives(c: *mut c_void, dx: *mut f64, n: usize) -> Status {
    guarded(c, "fmi2GetDerivatives", |comp| {
        expect_kind(comp, "fmi2GetDerivatives", Kind::ModelExchange)?;
        comp.inst.expect("fmi2GetDerivatives", STATES_READABLE)?;
        check_count(n)?;
        let out = slice_mut(dx, n, "derivatives")?;
        out.copy_from_slice(&comp.inst.derivatives()?);
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetEventIndicators(c: *mut c_void, _z: *mut f64, n: usize) -> Status {
    guarded(c, "fmi2GetEventIndicators", |_| {
        if n == 0 {
            Ok(())
        } else {
            Err(format!("the model has no event indicators, not {n}"))
        }
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
    c: *mut c_void,
    x: *mut f64,
    n: usize,
) -> Status {
    guarded(c, "fmi2GetNominalsOfContinuousStates", |_| {
        check_count(n)?;
        slice_mut(x, n, "x_nominal")?.fill(1.0);
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: *mut c_void,
    _vr: *const u32,
    n: usize,
    _order: *const c_int,
    _value: *const f64,
) -> Status {
    guarded(c, "fmi2SetRealInputDerivatives", |_| {
        if n == 0 {
            Ok(())
        } else {
            Err("this FMU does not interpolate inputs (canInterpolateInputs is false)".into())
        }
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: *mut c_void,
    _vr: *const u32,
    n: usize,
    _order: *const c_int,
    _value: *mut f64,
) -> Status {
    guarded(c, "fmi2GetRealOutputDerivatives", |_| {
        if n == 0 {
            Ok(())
        } else {
            Err("this FMU does not give output derivatives (maxOutputDerivativeOrder is 0)".into())
        }
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DoStep(
    c: *mut c_void,
    t: f64,
    h: f64,
    _no_set_prior: Boolean,
) -> Status {
    guarded(c, "fmi2DoStep", |comp| {
        expect_kind(comp, "fmi2DoStep", Kind::CoSimulation)?;
        comp.inst.expect("fmi2DoStep", &[Phase::StepComplete])?;
        comp.inst.do_step(t, h)
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CancelStep(c: *mut c_void) -> Status {
    guarded(c, "fmi2CancelStep", |_| {
        Err("fmi2DoStep is never pending: nothing to cancel".into())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStatus(
    c: *mut c_void,
    _kind: c_int,
    _value: *mut Status,
) -> Status {
    guarded(c, "fmi2GetStatus", |_| {
        Err("fmi2DoStep is never pending: no status to ask for".into())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(c: *mut c_void, kind: c_int, value: *mut f64) -> Status {
    guarded(c, "fmi2GetRealStatus", |comp| {
        // fmi2LastSuccessfulTime
        if kind == 2 {
            write(value, comp.inst.time(), "value")
        } else {
            Err(format!("no real status of kind {kind}"))
        }
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: *mut c_void,
    kind: c_int,
    _value: *mut c_int,
) -> Status {
    guarded(c, "fmi2GetIntegerStatus", |_| {
        Err(format!("no integer status of kind {kind}"))
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: *mut c_void,
    kind: c_int,
    value: *mut Boolean,
) -> Status {
    guarded(c, "fmi2GetBooleanStatus", |_| {
        // fmi2Terminated: the FMU never asks to stop.
        if kind == 3 {
            write(value, FALSE, "value")
        } else {
            Err(format!("no boolean status of kind {kind}"))
        }
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: *mut c_void,
    kind: c_int,
    _value: *mut *const c_char,
) -> Status {
    guarded(c, "fmi2GetStringStatus", |_| {
        Err(format!("no string status of kind {kind}"))
    })
}
