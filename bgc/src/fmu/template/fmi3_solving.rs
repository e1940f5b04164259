//! The Model Exchange and Co-Simulation functions of the FMI 3.0 interface (the common ones are in
//! `fmi3.rs`), with the same checks.

use crate::ffi::{ME_SOLVING, STATES_READABLE, check_count, slice, slice_mut, write};
use crate::fmi3::*;
use crate::instance::{Kind, Outcome, Phase};
use crate::plant::NX;
use core::ffi::c_void;

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EvaluateDiscreteStates(c: *mut c_void) -> Status {
    guarded(c, "fmi3EvaluateDiscreteStates", |_| Ok(()))
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3UpdateDiscreteStates(
    c: *mut c_void,
    update_needed: *mut bool,
    terminate: *mut bool,
    nominals_changed: *mut bool,
    values_changed: *mut bool,
    next_event_time_defined: *mut bool,
    next_event_time: *mut f64,
) -> Status {
    guarded(c, "fmi3UpdateDiscreteStates", |comp| {
        comp.inst
            .expect("fmi3UpdateDiscreteStates", &[Phase::Event])?;
        // No discrete states and no events: the iteration ends at once.
        write(update_needed, false, "discreteStatesNeedUpdate")?;
        write(terminate, false, "terminateSimulation")?;
        write(nominals_changed, false, "nominalsOfContinuousStatesChanged")?;
        write(values_changed, false, "valuesOfContinuousStatesChanged")?;
        write(next_event_time_defined, false, "nextEventTimeDefined")?;
        write(next_event_time, 0.0, "nextEventTime")
    })
}

fn model_exchange(comp: &Component, call: &str) -> Outcome<()> {
    if comp.inst.kind == Kind::ModelExchange {
        Ok(())
    } else {
        Err(format!("{call} is a function of Model Exchange"))
    }
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterContinuousTimeMode(c: *mut c_void) -> Status {
    guarded(c, "fmi3EnterContinuousTimeMode", |comp| {
        model_exchange(comp, "fmi3EnterContinuousTimeMode")?;
        comp.inst
            .expect("fmi3EnterContinuousTimeMode", &[Phase::Event])?;
        comp.inst.phase = Phase::ContinuousTime;
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
    c: *mut c_void,
    _no_set_prior: bool,
    enter_event_mode: *mut bool,
    terminate: *mut bool,
) -> Status {
    guarded(c, "fmi3CompletedIntegratorStep", |comp| {
        model_exchange(comp, "fmi3CompletedIntegratorStep")?;
        comp.inst
            .expect("fmi3CompletedIntegratorStep", &[Phase::ContinuousTime])?;
        write(enter_event_mode, false, "enterEventMode")?;
        write(terminate, false, "terminateSimulation")
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetTime(c: *mut c_void, time: f64) -> Status {
    guarded(c, "fmi3SetTime", |comp| {
        model_exchange(comp, "fmi3SetTime")?;
        comp.inst.expect("fmi3SetTime", ME_SOLVING)?;
        comp.inst.set_time(time)
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetContinuousStates(
    c: *mut c_void,
    x: *const f64,
    n: usize,
) -> Status {
    guarded(c, "fmi3SetContinuousStates", |comp| {
        model_exchange(comp, "fmi3SetContinuousStates")?;
        comp.inst.expect("fmi3SetContinuousStates", ME_SOLVING)?;
        check_count(n)?;
        comp.inst.set_states(slice(x, n, "continuousStates")?)
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(
    c: *mut c_void,
    dx: *mut f64,
    n: usize,
) -> Status {
    guarded(c, "fmi3GetContinuousStateDerivatives", |comp| {
        comp.inst
            .expect("fmi3GetContinuousStateDerivatives", STATES_READABLE)?;
        check_count(n)?;
        let out = slice_mut(dx, n, "derivatives")?;
        out.copy_from_slice(&comp.inst.derivatives()?);
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetEventIndicators(c: *mut c_void, _z: *mut f64, n: usize) -> Status {
    guarded(c, "fmi3GetEventIndicators", |_| {
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
pub unsafe extern "C" fn fmi3GetContinuousStates(c: *mut c_void, x: *mut f64, n: usize) -> Status {
    guarded(c, "fmi3GetContinuousStates", |comp| {
        comp.inst.expect("fmi3GetContinuousStates", STATES_READABLE)?;
        check_count(n)?;
        slice_mut(x, n, "continuousStates")?.copy_from_slice(comp.inst.states());
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(
    c: *mut c_void,
    x: *mut f64,
    n: usize,
) -> Status {
    guarded(c, "fmi3GetNominalsOfContinuousStates", |_| {
        check_count(n)?;
        slice_mut(x, n, "nominals")?.fill(1.0);
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfEventIndicators(c: *mut c_void, n: *mut usize) -> Status {
    guarded(c, "fmi3GetNumberOfEventIndicators", |_| {
        write(n, 0, "nEventIndicators")
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(c: *mut c_void, n: *mut usize) -> Status {
    guarded(c, "fmi3GetNumberOfContinuousStates", |_| {
        write(n, NX, "nContinuousStates")
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetOutputDerivatives(
    c: *mut c_void,
    _vr: *const u32,
    nvr: usize,
    _orders: *const i32,
    _values: *mut f64,
    _n: usize,
) -> Status {
    guarded(c, "fmi3GetOutputDerivatives", |_| {
        if nvr == 0 {
            Ok(())
        } else {
            Err("this FMU does not give output derivatives".into())
        }
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn fmi3DoStep(
    c: *mut c_void,
    t: f64,
    h: f64,
    _no_set_prior: bool,
    event_handling_needed: *mut bool,
    terminate: *mut bool,
    early_return: *mut bool,
    last_successful_time: *mut f64,
) -> Status {
    guarded(c, "fmi3DoStep", |comp| {
        if comp.inst.kind != Kind::CoSimulation {
            return Err("fmi3DoStep is a function of Co-Simulation".into());
        }
        comp.inst.expect("fmi3DoStep", &[Phase::StepComplete])?;
        let result = comp.inst.do_step(t, h);
        write(event_handling_needed, false, "eventHandlingNeeded")?;
        write(terminate, false, "terminateSimulation")?;
        write(early_return, false, "earlyReturn")?;
        write(last_successful_time, comp.inst.time(), "lastSuccessfulTime")?;
        result
    })
}
