//! What the C interfaces of both versions share: slices and results through the importer's pointers, checked, and
//! the phases most functions are allowed in.

use crate::instance::{Outcome, Phase};
use crate::plant::NX;

/// `n` values at `ptr` (an empty slice for `n == 0`, whatever the pointer), or an error for a null pointer.
pub fn slice<'a, T>(ptr: *const T, n: usize, what: &str) -> Outcome<&'a [T]> {
    if n == 0 {
        Ok(&[])
    } else if ptr.is_null() {
        Err(format!("{what} is a null pointer"))
    } else {
        // SAFETY: the standard makes the importer pass `n` valid values.
        Ok(unsafe { std::slice::from_raw_parts(ptr, n) })
    }
}

/// As [`slice`], for values the FMU writes.
pub fn slice_mut<'a, T>(ptr: *mut T, n: usize, what: &str) -> Outcome<&'a mut [T]> {
    if n == 0 {
        Ok(&mut [])
    } else if ptr.is_null() {
        Err(format!("{what} is a null pointer"))
    } else {
        // SAFETY: as for `slice`, and the importer does not read the values during the call.
        Ok(unsafe { std::slice::from_raw_parts_mut(ptr, n) })
    }
}

/// Writes one result through the importer's pointer.
pub fn write<T>(ptr: *mut T, value: T, what: &str) -> Outcome<()> {
    if ptr.is_null() {
        return Err(format!("{what} is a null pointer"));
    }
    // SAFETY: a non-null pointer the importer gave for this value.
    unsafe { ptr.write(value) };
    Ok(())
}

/// Every phase but the error phase: getting and setting values.
pub const RUNNING: &[Phase] = &[
    Phase::Instantiated,
    Phase::Initialization,
    Phase::Event,
    Phase::ContinuousTime,
    Phase::StepComplete,
    Phase::StepFailed,
    Phase::Terminated,
];

/// Model Exchange between initialisation and termination.
pub const ME_SOLVING: &[Phase] = &[Phase::Event, Phase::ContinuousTime];

/// The phases in which the states and their derivatives may be read: any after `EnterInitializationMode`. Before
/// it the parameters and start values may still change, and the standard's state machine allows no such read.
pub const STATES_READABLE: &[Phase] = &[
    Phase::Initialization,
    Phase::Event,
    Phase::ContinuousTime,
    Phase::StepComplete,
    Phase::StepFailed,
    Phase::Terminated,
    Phase::Error,
];

/// The count of continuous states the importer passes.
pub fn check_count(n: usize) -> Outcome<()> {
    if n == NX {
        Ok(())
    } else {
        Err(format!("the model has {NX} continuous states, not {n}"))
    }
}
