//! The FMI 3.0 C interface (Model Exchange and Co-Simulation), declared after the standard's `fmi3Functions.h`.
//! As for FMI 2.0: pointers checked, panics caught, the phases of the standard checked, errors logged through the
//! importer's callback. The model has only `Float64` variables, no clocks, no events and no configuration mode.

use crate::ffi::{RUNNING, slice, slice_mut};
use crate::instance::{Instance, Kind, Outcome, Phase, Snapshot};
use core::ffi::{c_char, c_int, c_void};
use std::ffi::{CStr, CString};
use std::panic::{AssertUnwindSafe, catch_unwind};

pub(crate) type Status = c_int;
pub(crate) const OK: Status = 0;
pub(crate) const WARNING: Status = 1;
pub(crate) const ERROR: Status = 3;
pub(crate) const FATAL: Status = 4;

pub(crate) type LogMessage =
    unsafe extern "C" fn(*mut c_void, Status, *const c_char, *const c_char);

pub(crate) struct Component {
    pub(crate) inst: Instance,
    logger: Option<LogMessage>,
    env: *mut c_void,
}

impl Component {
    fn log(&self, status: Status, category: &str, message: &str) {
        if status < WARNING && !self.inst.logging {
            return;
        }
        let (Some(logger), Ok(category), Ok(message)) = (
            self.logger,
            CString::new(category),
            CString::new(message.replace('\0', " ")),
        ) else {
            return;
        };
        // SAFETY: the importer's callback, with C strings that live for the call.
        unsafe { logger(self.env, status, category.as_ptr(), message.as_ptr()) };
    }
}

/// Runs `body` on the instance behind `c`: null checked, panics caught, errors logged.
pub(crate) fn guarded(
    c: *mut c_void,
    call: &str,
    body: impl FnOnce(&mut Component) -> Outcome<()>,
) -> Status {
    if c.is_null() {
        return ERROR;
    }
    // SAFETY: a non-null instance is one fmi3Instantiate… returned and fmi3FreeInstance has not freed.
    let comp = unsafe { &mut *(c as *mut Component) };
    match catch_unwind(AssertUnwindSafe(|| body(&mut *comp))) {
        Ok(Ok(())) => OK,
        Ok(Err(message)) => {
            comp.log(ERROR, "logStatusError", &format!("{call}: {message}"));
            ERROR
        }
        Err(_) => {
            comp.inst.phase = Phase::Error;
            comp.log(
                FATAL,
                "logStatusFatal",
                &format!("{call}: internal error (a panic was caught)"),
            );
            ERROR
        }
    }
}

/// Scalar variables only: as many values as references.
fn same_count(nvr: usize, n_values: usize) -> Outcome<()> {
    if nvr == n_values {
        Ok(())
    } else {
        Err(format!(
            "{nvr} value references but {n_values} values (every variable is a scalar)"
        ))
    }
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

fn instantiate(
    name: *const c_char,
    token: *const c_char,
    kind: Kind,
    logging_on: bool,
    env: *mut c_void,
    logger: Option<LogMessage>,
) -> *mut c_void {
    let made = catch_unwind(|| {
        if name.is_null() || token.is_null() {
            return None;
        }
        // SAFETY: non-null C strings from the importer.
        let (name, token) = unsafe { (CStr::from_ptr(name), CStr::from_ptr(token)) };
        let mut comp = Component {
            inst: Instance::new(name.to_string_lossy().into_owned(), kind),
            logger,
            env,
        };
        comp.inst.logging = logging_on;
        if token.to_bytes() != crate::GUID.as_bytes() {
            comp.log(
                ERROR,
                "logStatusError",
                &format!(
                    "fmi3Instantiate: the instantiation token {} is not this FMU's ({})",
                    token.to_string_lossy(),
                    crate::GUID
                ),
            );
            return None;
        }
        Some(Box::into_raw(Box::new(comp)) as *mut c_void)
    });
    made.ok().flatten().unwrap_or(std::ptr::null_mut())
}

/// # Safety
/// The arguments of `fmi3InstantiateModelExchange` in the standard.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    name: *const c_char,
    token: *const c_char,
    _resources: *const c_char,
    _visible: bool,
    logging_on: bool,
    env: *mut c_void,
    logger: Option<LogMessage>,
) -> *mut c_void {
    instantiate(name, token, Kind::ModelExchange, logging_on, env, logger)
}

/// # Safety
/// The arguments of `fmi3InstantiateCoSimulation` in the standard.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    name: *const c_char,
    token: *const c_char,
    _resources: *const c_char,
    _visible: bool,
    logging_on: bool,
    event_mode_used: bool,
    _early_return_allowed: bool,
    _required: *const u32,
    _n_required: usize,
    env: *mut c_void,
    logger: Option<LogMessage>,
    _intermediate_update: *const c_void,
) -> *mut c_void {
    let c = instantiate(name, token, Kind::CoSimulation, logging_on, env, logger);
    if event_mode_used && !c.is_null() {
        // SAFETY: the instance just made.
        let comp = unsafe { &*(c as *const Component) };
        comp.log(
            ERROR,
            "logStatusError",
            "fmi3InstantiateCoSimulation: the FMU has no event mode in Co-Simulation",
        );
        // SAFETY: as above; freed once.
        drop(unsafe { Box::from_raw(c as *mut Component) });
        return std::ptr::null_mut();
    }
    c
}

/// # Safety
/// Never succeeds: the FMU does not support Scheduled Execution.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    _name: *const c_char,
    _token: *const c_char,
    _resources: *const c_char,
    _visible: bool,
    _logging_on: bool,
    _env: *mut c_void,
    _logger: Option<LogMessage>,
    _clock_update: *const c_void,
    _lock: *const c_void,
    _unlock: *const c_void,
) -> *mut c_void {
    std::ptr::null_mut()
}

/// # Safety
/// `c` is null or an instance not freed yet.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3FreeInstance(c: *mut c_void) {
    if !c.is_null() {
        // SAFETY: the box of fmi3Instantiate…; freed once by the standard's contract.
        let _ = catch_unwind(|| drop(unsafe { Box::from_raw(c as *mut Component) }));
    }
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    c: *mut c_void,
    logging_on: bool,
    _n: usize,
    _categories: *const *const c_char,
) -> Status {
    guarded(c, "fmi3SetDebugLogging", |comp| {
        comp.inst.logging = logging_on;
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterInitializationMode(
    c: *mut c_void,
    tolerance_defined: bool,
    tolerance: f64,
    start_time: f64,
    _stop_time_defined: bool,
    _stop_time: f64,
) -> Status {
    guarded(c, "fmi3EnterInitializationMode", |comp| {
        comp.inst
            .setup(tolerance_defined.then_some(tolerance), start_time)?;
        comp.inst.phase = Phase::Initialization;
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3ExitInitializationMode(c: *mut c_void) -> Status {
    guarded(c, "fmi3ExitInitializationMode", |comp| {
        comp.inst
            .expect("fmi3ExitInitializationMode", &[Phase::Initialization])?;
        comp.inst.phase = match comp.inst.kind {
            Kind::ModelExchange => Phase::Event,
            Kind::CoSimulation => Phase::StepComplete,
        };
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterEventMode(c: *mut c_void) -> Status {
    guarded(c, "fmi3EnterEventMode", |comp| {
        comp.inst.expect(
            "fmi3EnterEventMode",
            &[Phase::Event, Phase::ContinuousTime, Phase::StepComplete],
        )?;
        comp.inst.phase = Phase::Event;
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3EnterStepMode(c: *mut c_void) -> Status {
    guarded(c, "fmi3EnterStepMode", |comp| {
        if comp.inst.kind != Kind::CoSimulation {
            return Err("fmi3EnterStepMode is a function of Co-Simulation".into());
        }
        comp.inst
            .expect("fmi3EnterStepMode", &[Phase::Event, Phase::StepComplete])?;
        comp.inst.phase = Phase::StepComplete;
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3Terminate(c: *mut c_void) -> Status {
    guarded(c, "fmi3Terminate", |comp| {
        comp.inst.expect(
            "fmi3Terminate",
            &[
                Phase::Event,
                Phase::ContinuousTime,
                Phase::StepComplete,
                Phase::StepFailed,
            ],
        )?;
        comp.inst.phase = Phase::Terminated;
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3Reset(c: *mut c_void) -> Status {
    guarded(c, "fmi3Reset", |comp| {
        comp.inst.reset();
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFloat64(
    c: *mut c_void,
    vr: *const u32,
    nvr: usize,
    values: *mut f64,
    n_values: usize,
) -> Status {
    guarded(c, "fmi3GetFloat64", |comp| {
        comp.inst.expect("fmi3GetFloat64", RUNNING)?;
        same_count(nvr, n_values)?;
        comp.inst.get_real(
            slice(vr, nvr, "valueReferences")?,
            slice_mut(values, n_values, "values")?,
        )
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetFloat64(
    c: *mut c_void,
    vr: *const u32,
    nvr: usize,
    values: *const f64,
    n_values: usize,
) -> Status {
    guarded(c, "fmi3SetFloat64", |comp| {
        comp.inst.expect("fmi3SetFloat64", RUNNING)?;
        same_count(nvr, n_values)?;
        comp.inst.set_real(
            slice(vr, nvr, "valueReferences")?,
            slice(values, n_values, "values")?,
        )
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFMUState(c: *mut c_void, state: *mut *mut c_void) -> Status {
    guarded(c, "fmi3GetFMUState", |comp| {
        if state.is_null() {
            return Err("the FMU state pointer is null".into());
        }
        let snapshot = comp.inst.snapshot();
        // SAFETY: checked non-null; a non-null `*state` is a snapshot of an earlier call, overwritten in place.
        unsafe {
            if (*state).is_null() {
                *state = Box::into_raw(Box::new(snapshot)) as *mut c_void;
            } else {
                *(*state as *mut Snapshot) = snapshot;
            }
        }
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetFMUState(c: *mut c_void, state: *mut c_void) -> Status {
    guarded(c, "fmi3SetFMUState", |comp| {
        if state.is_null() {
            return Err("the FMU state is null".into());
        }
        // SAFETY: a snapshot of fmi3GetFMUState, not freed yet.
        comp.inst.restore(unsafe { &*(state as *const Snapshot) });
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3FreeFMUState(c: *mut c_void, state: *mut *mut c_void) -> Status {
    guarded(c, "fmi3FreeFMUState", |_| {
        if state.is_null() {
            return Ok(());
        }
        // SAFETY: the snapshot box of fmi3GetFMUState; the importer's pointer is cleared after.
        unsafe {
            if !(*state).is_null() {
                drop(Box::from_raw(*state as *mut Snapshot));
                *state = std::ptr::null_mut();
            }
        }
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn fmi3GetDirectionalDerivative(
    c: *mut c_void,
    unknowns: *const u32,
    n_unknowns: usize,
    knowns: *const u32,
    n_knowns: usize,
    seed: *const f64,
    n_seed: usize,
    sensitivity: *mut f64,
    n_sensitivity: usize,
) -> Status {
    guarded(c, "fmi3GetDirectionalDerivative", |comp| {
        comp.inst.expect("fmi3GetDirectionalDerivative", RUNNING)?;
        same_count(n_knowns, n_seed)?;
        same_count(n_unknowns, n_sensitivity)?;
        comp.inst.directional_derivative(
            slice(unknowns, n_unknowns, "unknowns")?,
            slice(knowns, n_knowns, "knowns")?,
            slice(seed, n_seed, "seed")?,
            slice_mut(sensitivity, n_sensitivity, "sensitivity")?,
        )
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn fmi3GetAdjointDerivative(
    c: *mut c_void,
    unknowns: *const u32,
    n_unknowns: usize,
    knowns: *const u32,
    n_knowns: usize,
    seed: *const f64,
    n_seed: usize,
    sensitivity: *mut f64,
    n_sensitivity: usize,
) -> Status {
    guarded(c, "fmi3GetAdjointDerivative", |comp| {
        comp.inst.expect("fmi3GetAdjointDerivative", RUNNING)?;
        same_count(n_unknowns, n_seed)?;
        same_count(n_knowns, n_sensitivity)?;
        comp.inst.adjoint_derivative(
            slice(unknowns, n_unknowns, "unknowns")?,
            slice(knowns, n_knowns, "knowns")?,
            slice(seed, n_seed, "seed")?,
            slice_mut(sensitivity, n_sensitivity, "sensitivity")?,
        )
    })
}
