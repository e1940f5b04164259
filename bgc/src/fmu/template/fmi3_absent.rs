//! The FMI 3.0 functions of what the model does not have (variables of types other than `Float64`, clocks,
//! configuration mode, model partitions, variable dependencies at run time, serialised states): each refuses with
//! an error through the importer's logger, or accepts an empty request.

use crate::ffi::slice;
use crate::fmi3::*;
use crate::instance::Outcome;
use core::ffi::{c_char, c_int, c_void};

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
        Some(v) => Err(format!(
            "no variable of this type has the value reference {v}"
        )),
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
pub unsafe extern "C" fn fmi3GetClock(
    c: *mut c_void,
    vr: *const u32,
    nvr: usize,
    _v: *mut bool,
) -> Status {
    guarded(c, "fmi3GetClock", |_| unknown_references(vr, nvr))
}

/// # Safety
/// As the standard requires.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetClock(
    c: *mut c_void,
    vr: *const u32,
    nvr: usize,
    _v: *const bool,
) -> Status {
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
