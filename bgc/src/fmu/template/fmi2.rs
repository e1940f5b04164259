//! The FMI 2.0 C interface (Model Exchange and Co-Simulation in one binary), declared after the standard's
//! `fmi2Functions.h`. Every function checks its pointers, catches panics (none may unwind into the importer),
//! checks the phase of the standard's state machine and reports errors through the importer's logger.

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
pub(crate) type Boolean = c_int;
pub(crate) const FALSE: Boolean = 0;

pub(crate) type Logger =
    unsafe extern "C" fn(*mut c_void, *const c_char, Status, *const c_char, *const c_char, ...);

#[repr(C)]
pub struct CallbackFunctions {
    logger: Option<Logger>,
    allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    step_finished: Option<unsafe extern "C" fn(*mut c_void, Status)>,
    component_environment: *mut c_void,
}

pub(crate) struct Component {
    pub(crate) inst: Instance,
    logger: Option<Logger>,
    env: *mut c_void,
    name: CString,
}

impl Component {
    fn log(&self, status: Status, category: &str, message: &str) {
        if status < WARNING && !self.inst.logging {
            return;
        }
        let (Some(logger), Ok(category), Ok(message)) = (
            self.logger,
            CString::new(category),
            CString::new(message.replace('\0', " ").replace('%', "%%")),
        ) else {
            return;
        };
        // SAFETY: the importer's logger, with C strings that live for the call.
        unsafe {
            logger(
                self.env,
                self.name.as_ptr(),
                status,
                category.as_ptr(),
                c"%s".as_ptr(),
                message.as_ptr(),
            )
        };
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
    // SAFETY: a non-null component is one fmi2Instantiate returned and fmi2FreeInstance has not freed.
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

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// # Safety
/// The arguments of `fmi2Instantiate` in the standard.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: *const c_char,
    fmu_type: c_int,
    guid: *const c_char,
    _resource_location: *const c_char,
    functions: *const CallbackFunctions,
    _visible: Boolean,
    logging_on: Boolean,
) -> *mut c_void {
    let made = catch_unwind(|| {
        if instance_name.is_null() || functions.is_null() || guid.is_null() {
            return None;
        }
        // SAFETY: non-null C strings and callback table from the importer.
        let (name, guid, functions) = unsafe {
            (
                CStr::from_ptr(instance_name),
                CStr::from_ptr(guid),
                &*functions,
            )
        };
        let kind = match fmu_type {
            0 => Kind::ModelExchange,
            1 => Kind::CoSimulation,
            _ => return None,
        };
        let mut comp = Component {
            inst: Instance::new(name.to_string_lossy().into_owned(), kind),
            logger: functions.logger,
            env: functions.component_environment,
            name: name.to_owned(),
        };
        comp.inst.logging = logging_on != FALSE;
        if guid.to_bytes() != crate::GUID.as_bytes() {
            comp.log(
                ERROR,
                "logStatusError",
                &format!(
                    "fmi2Instantiate: the GUID {} is not this FMU's ({})",
                    guid.to_string_lossy(),
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
/// `c` is null or an instance of `fmi2Instantiate` not freed yet.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeInstance(c: *mut c_void) {
    if !c.is_null() {
        // SAFETY: the box fmi2Instantiate made; freed once by the standard's contract.
        let _ = catch_unwind(|| drop(unsafe { Box::from_raw(c as *mut Component) }));
    }
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: *mut c_void,
    logging_on: Boolean,
    _n: usize,
    _categories: *const *const c_char,
) -> Status {
    guarded(c, "fmi2SetDebugLogging", |comp| {
        comp.inst.logging = logging_on != FALSE;
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: *mut c_void,
    tolerance_defined: Boolean,
    tolerance: f64,
    start_time: f64,
    _stop_time_defined: Boolean,
    _stop_time: f64,
) -> Status {
    guarded(c, "fmi2SetupExperiment", |comp| {
        let tol = (tolerance_defined != FALSE).then_some(tolerance);
        comp.inst.setup(tol, start_time)
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: *mut c_void) -> Status {
    guarded(c, "fmi2EnterInitializationMode", |comp| {
        comp.inst
            .expect("fmi2EnterInitializationMode", &[Phase::Instantiated])?;
        comp.inst.phase = Phase::Initialization;
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: *mut c_void) -> Status {
    guarded(c, "fmi2ExitInitializationMode", |comp| {
        comp.inst
            .expect("fmi2ExitInitializationMode", &[Phase::Initialization])?;
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
pub unsafe extern "C" fn fmi2Terminate(c: *mut c_void) -> Status {
    guarded(c, "fmi2Terminate", |comp| {
        comp.inst.expect(
            "fmi2Terminate",
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
pub unsafe extern "C" fn fmi2Reset(c: *mut c_void) -> Status {
    guarded(c, "fmi2Reset", |comp| {
        comp.inst.reset();
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: *mut c_void,
    vr: *const u32,
    n: usize,
    value: *mut f64,
) -> Status {
    guarded(c, "fmi2GetReal", |comp| {
        comp.inst.expect("fmi2GetReal", RUNNING)?;
        let vrs = slice(vr, n, "vr")?;
        comp.inst.get_real(vrs, slice_mut(value, n, "value")?)
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: *mut c_void,
    vr: *const u32,
    n: usize,
    value: *const f64,
) -> Status {
    guarded(c, "fmi2SetReal", |comp| {
        comp.inst.expect("fmi2SetReal", RUNNING)?;
        comp.inst
            .set_real(slice(vr, n, "vr")?, slice(value, n, "value")?)
    })
}

/// The model has only real variables: any other reference is unknown.
fn no_variables(vr: *const u32, n: usize, kind: &str) -> Outcome<()> {
    match slice(vr, n, "vr")?.first() {
        None => Ok(()),
        Some(v) => Err(format!("no {kind} variable has the value reference {v}")),
    }
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetInteger(
    c: *mut c_void,
    vr: *const u32,
    n: usize,
    _v: *mut c_int,
) -> Status {
    guarded(c, "fmi2GetInteger", |_| no_variables(vr, n, "Integer"))
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: *mut c_void,
    vr: *const u32,
    n: usize,
    _v: *const c_int,
) -> Status {
    guarded(c, "fmi2SetInteger", |_| no_variables(vr, n, "Integer"))
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: *mut c_void,
    vr: *const u32,
    n: usize,
    _v: *mut Boolean,
) -> Status {
    guarded(c, "fmi2GetBoolean", |_| no_variables(vr, n, "Boolean"))
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: *mut c_void,
    vr: *const u32,
    n: usize,
    _v: *const Boolean,
) -> Status {
    guarded(c, "fmi2SetBoolean", |_| no_variables(vr, n, "Boolean"))
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetString(
    c: *mut c_void,
    vr: *const u32,
    n: usize,
    _v: *mut *const c_char,
) -> Status {
    guarded(c, "fmi2GetString", |_| no_variables(vr, n, "String"))
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetString(
    c: *mut c_void,
    vr: *const u32,
    n: usize,
    _v: *const *const c_char,
) -> Status {
    guarded(c, "fmi2SetString", |_| no_variables(vr, n, "String"))
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(c: *mut c_void, state: *mut *mut c_void) -> Status {
    guarded(c, "fmi2GetFMUstate", |comp| {
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
pub unsafe extern "C" fn fmi2SetFMUstate(c: *mut c_void, state: *mut c_void) -> Status {
    guarded(c, "fmi2SetFMUstate", |comp| {
        if state.is_null() {
            return Err("the FMU state is null".into());
        }
        // SAFETY: a snapshot of fmi2GetFMUstate, not freed yet.
        comp.inst.restore(unsafe { &*(state as *const Snapshot) });
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: *mut c_void, state: *mut *mut c_void) -> Status {
    guarded(c, "fmi2FreeFMUstate", |_| {
        if state.is_null() {
            return Ok(());
        }
        // SAFETY: the snapshot box of fmi2GetFMUstate; the importer's pointer is cleared after.
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
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: *mut c_void,
    _s: *mut c_void,
    _size: *mut usize,
) -> Status {
    guarded(c, "fmi2SerializedFMUstateSize", |_| {
        Err("this FMU does not serialize its state".into())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: *mut c_void,
    _s: *mut c_void,
    _b: *mut u8,
    _n: usize,
) -> Status {
    guarded(c, "fmi2SerializeFMUstate", |_| {
        Err("this FMU does not serialize its state".into())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: *mut c_void,
    _b: *const u8,
    _n: usize,
    _s: *mut *mut c_void,
) -> Status {
    guarded(c, "fmi2DeSerializeFMUstate", |_| {
        Err("this FMU does not serialize its state".into())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: *mut c_void,
    unknown: *const u32,
    n_unknown: usize,
    known: *const u32,
    n_known: usize,
    dv_known: *const f64,
    dv_unknown: *mut f64,
) -> Status {
    guarded(c, "fmi2GetDirectionalDerivative", |comp| {
        comp.inst.expect("fmi2GetDirectionalDerivative", RUNNING)?;
        comp.inst.directional_derivative(
            slice(unknown, n_unknown, "vUnknown_ref")?,
            slice(known, n_known, "vKnown_ref")?,
            slice(dv_known, n_known, "dvKnown")?,
            slice_mut(dv_unknown, n_unknown, "dvUnknown")?,
        )
    })
}
