//! The FMI 3.0 C interface (Model Exchange and Co-Simulation), declared after the standard's `fmi3Functions.h`.
//! As for FMI 2.0: pointers checked, panics caught, the phases of the standard checked, errors logged through the
//! importer's callback. The model has only `Float64` variables, no clocks, no events and no configuration mode.

use crate::instance::{Instance, Kind, Outcome, Phase, Snapshot};
use crate::plant::NX;
use core::ffi::{c_char, c_int, c_void};
use std::ffi::{CStr, CString};
use std::panic::{AssertUnwindSafe, catch_unwind};

type Status = c_int;
const OK: Status = 0;
const WARNING: Status = 1;
const ERROR: Status = 3;
const FATAL: Status = 4;

type LogMessage = unsafe extern "C" fn(*mut c_void, Status, *const c_char, *const c_char);

struct Component {
    inst: Instance,
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
fn guarded(c: *mut c_void, call: &str, body: impl FnOnce(&mut Component) -> Outcome<()>) -> Status {
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
            comp.log(FATAL, "logStatusFatal", &format!("{call}: internal error (a panic was caught)"));
            ERROR
        }
    }
}

fn slice<'a, T>(ptr: *const T, n: usize, what: &str) -> Outcome<&'a [T]> {
    if n == 0 {
        Ok(&[])
    } else if ptr.is_null() {
        Err(format!("{what} is a null pointer"))
    } else {
        // SAFETY: the standard makes the importer pass `n` valid values.
        Ok(unsafe { std::slice::from_raw_parts(ptr, n) })
    }
}

fn slice_mut<'a, T>(ptr: *mut T, n: usize, what: &str) -> Outcome<&'a mut [T]> {
    if n == 0 {
        Ok(&mut [])
    } else if ptr.is_null() {
        Err(format!("{what} is a null pointer"))
    } else {
        // SAFETY: as for `slice`, and the importer does not read the values during the call.
        Ok(unsafe { std::slice::from_raw_parts_mut(ptr, n) })
    }
}

fn write<T>(ptr: *mut T, value: T, what: &str) -> Outcome<()> {
    if ptr.is_null() {
        return Err(format!("{what} is a null pointer"));
    }
    // SAFETY: a non-null pointer the importer gave for this value.
    unsafe { ptr.write(value) };
    Ok(())
}

/// Scalar variables only: as many values as references.
fn same_count(nvr: usize, n_values: usize) -> Outcome<()> {
    if nvr == n_values {
        Ok(())
    } else {
        Err(format!("{nvr} value references but {n_values} values (every variable is a scalar)"))
    }
}

const RUNNING: &[Phase] = &[
    Phase::Instantiated,
    Phase::Initialization,
    Phase::Event,
    Phase::ContinuousTime,
    Phase::StepComplete,
    Phase::StepFailed,
    Phase::Terminated,
];
const ME_SOLVING: &[Phase] = &[Phase::Event, Phase::ContinuousTime];

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
        comp.log(ERROR, "logStatusError", "fmi3InstantiateCoSimulation: the FMU has no event mode in Co-Simulation");
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
        comp.inst.setup(tolerance_defined.then_some(tolerance), start_time)?;
        comp.inst.phase = Phase::Initialization;
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3ExitInitializationMode(c: *mut c_void) -> Status {
    guarded(c, "fmi3ExitInitializationMode", |comp| {
        comp.inst.expect("fmi3ExitInitializationMode", &[Phase::Initialization])?;
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
        comp.inst.expect("fmi3EnterEventMode", &[Phase::Event, Phase::ContinuousTime, Phase::StepComplete])?;
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
        comp.inst.expect("fmi3EnterStepMode", &[Phase::Event, Phase::StepComplete])?;
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
            &[Phase::Event, Phase::ContinuousTime, Phase::StepComplete, Phase::StepFailed],
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
        comp.inst.get_real(slice(vr, nvr, "valueReferences")?, slice_mut(values, n_values, "values")?)
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
        comp.inst.set_real(slice(vr, nvr, "valueReferences")?, slice(values, n_values, "values")?)
    })
}

/// The getters and setters of the types the model has no variables of: any reference is unknown.
macro_rules! no_variables_of_type {
    ($($get:ident, $set:ident, $t:ty;)*) => {$(
        /// # Safety
        /// As the standard requires.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $get(c: *mut c_void, vr: *const u32, nvr: usize, _v: *mut $t, _n: usize) -> Status {
            guarded(c, stringify!($get), |_| unknown_references(vr, nvr))
        }

        /// # Safety
        /// As the standard requires.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $set(c: *mut c_void, vr: *const u32, nvr: usize, _v: *const $t, _n: usize) -> Status {
            guarded(c, stringify!($set), |_| unknown_references(vr, nvr))
        }
    )*};
}

no_variables_of_type! {
    fmi3GetFloat32, fmi3SetFloat32, f32;
    fmi3GetInt8, fmi3SetInt8, i8;
    fmi3GetUInt8, fmi3SetUInt8, u8;
    fmi3GetInt16, fmi3SetInt16, i16;
    fmi3GetUInt16, fmi3SetUInt16, u16;
    fmi3GetInt32, fmi3SetInt32, i32;
    fmi3GetUInt32, fmi3SetUInt32, u32;
    fmi3GetInt64, fmi3SetInt64, i64;
    fmi3GetUInt64, fmi3SetUInt64, u64;
    fmi3GetBoolean, fmi3SetBoolean, bool;
    fmi3GetString, fmi3SetString, *const c_char;
}

fn unknown_references(vr: *const u32, nvr: usize) -> Outcome<()> {
    match slice(vr, nvr, "valueReferences")?.first() {
        None => Ok(()),
        Some(v) => Err(format!("no variable of this type has the value reference {v}")),
    }
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetBinary(
    c: *mut c_void,
    vr: *const u32,
    nvr: usize,
    _sizes: *mut usize,
    _v: *mut *const u8,
    _n: usize,
) -> Status {
    guarded(c, "fmi3GetBinary", |_| unknown_references(vr, nvr))
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetBinary(
    c: *mut c_void,
    vr: *const u32,
    nvr: usize,
    _sizes: *const usize,
    _v: *const *const u8,
    _n: usize,
) -> Status {
    guarded(c, "fmi3SetBinary", |_| unknown_references(vr, nvr))
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetClock(c: *mut c_void, vr: *const u32, nvr: usize, _v: *mut bool) -> Status {
    guarded(c, "fmi3GetClock", |_| unknown_references(vr, nvr))
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetClock(c: *mut c_void, vr: *const u32, nvr: usize, _v: *const bool) -> Status {
    guarded(c, "fmi3SetClock", |_| unknown_references(vr, nvr))
}

/// The functions of clocks, configuration mode and model partitions: the model has none of them.
macro_rules! unsupported {
    ($($name:ident($($arg:ident: $t:ty),*);)*) => {$(
        /// # Safety
        /// As the standard requires; always refused.
        #[unsafe(no_mangle)]
        pub unsafe extern "C" fn $name(c: *mut c_void, $($arg: $t),*) -> Status {
            $(let _ = $arg;)*
            guarded(c, stringify!($name), |_| Err("the model has no clocks, structural parameters or partitions".into()))
        }
    )*};
}

unsupported! {
    fmi3GetIntervalDecimal(vr: *const u32, n: usize, intervals: *mut f64, qualifiers: *mut c_int);
    fmi3GetIntervalFraction(vr: *const u32, n: usize, counters: *mut u64, resolutions: *mut u64, qualifiers: *mut c_int);
    fmi3GetShiftDecimal(vr: *const u32, n: usize, shifts: *mut f64);
    fmi3GetShiftFraction(vr: *const u32, n: usize, counters: *mut u64, resolutions: *mut u64);
    fmi3SetIntervalDecimal(vr: *const u32, n: usize, intervals: *const f64);
    fmi3SetIntervalFraction(vr: *const u32, n: usize, counters: *const u64, resolutions: *const u64);
    fmi3SetShiftDecimal(vr: *const u32, n: usize, shifts: *const f64);
    fmi3SetShiftFraction(vr: *const u32, n: usize, counters: *const u64, resolutions: *const u64);
    fmi3EnterConfigurationMode();
    fmi3ExitConfigurationMode();
    fmi3ActivateModelPartition(clock: u32, time: f64);
    fmi3GetNumberOfVariableDependencies(vr: u32, n: *mut usize);
    fmi3GetVariableDependencies(dependent: u32, element_dependent: *mut usize, independents: *mut u32, element_independents: *mut usize, kinds: *mut c_int, n: usize);
    fmi3SerializedFMUStateSize(state: *mut c_void, size: *mut usize);
    fmi3SerializeFMUState(state: *mut c_void, bytes: *mut u8, size: usize);
    fmi3DeserializeFMUState(bytes: *const u8, size: usize, state: *mut *mut c_void);
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
        comp.inst.expect("fmi3UpdateDiscreteStates", &[Phase::Event])?;
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
        comp.inst.expect("fmi3EnterContinuousTimeMode", &[Phase::Event])?;
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
        comp.inst.expect("fmi3CompletedIntegratorStep", &[Phase::ContinuousTime])?;
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

fn check_count(n: usize) -> Outcome<()> {
    if n == NX {
        Ok(())
    } else {
        Err(format!("the model has {NX} continuous states, not {n}"))
    }
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetContinuousStates(c: *mut c_void, x: *const f64, n: usize) -> Status {
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
pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(c: *mut c_void, dx: *mut f64, n: usize) -> Status {
    guarded(c, "fmi3GetContinuousStateDerivatives", |comp| {
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
        if n == 0 { Ok(()) } else { Err(format!("the model has no event indicators, not {n}")) }
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetContinuousStates(c: *mut c_void, x: *mut f64, n: usize) -> Status {
    guarded(c, "fmi3GetContinuousStates", |comp| {
        check_count(n)?;
        slice_mut(x, n, "continuousStates")?.copy_from_slice(comp.inst.states());
        Ok(())
    })
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(c: *mut c_void, x: *mut f64, n: usize) -> Status {
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
    guarded(c, "fmi3GetNumberOfEventIndicators", |_| write(n, 0, "nEventIndicators"))
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(c: *mut c_void, n: *mut usize) -> Status {
    guarded(c, "fmi3GetNumberOfContinuousStates", |_| write(n, NX, "nContinuousStates"))
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
        if nvr == 0 { Ok(()) } else { Err("this FMU does not give output derivatives".into()) }
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
