//! The FMI 2.0 C entry points (common and co-simulation API, `fmi2Functions.h`).
//!
//! Written by hand rather than with a bindings crate: the maintained Rust FMI crates are
//! `fmi` (an importer: it loads FMUs, it does not export them) and `fmi-export` (FMI 3.0
//! only, driven by a derive macro and `cargo-fmi`); FMI 2.0 export needs only these ~35
//! small functions and five C types, and writing them keeps every unsafe block visible here.
//!
//! Rules every function follows:
//! - its body runs inside [`guard`] (`std::panic::catch_unwind`): a panic becomes
//!   `fmi2Fatal` (the instance is marked failed), it never unwinds into the importer; the
//!   functions that take an instance are written with the one macro `entry!`, which holds
//!   the call of `guard` and its `// SAFETY:` comment (directly, or through `lifecycle!` and
//!   `get_set!`, which each write their functions' `# Safety` contract and the `// SAFETY:`
//!   reasoning of their own unsafe block once);
//! - null pointers are checked before use (`fmi2Error`);
//! - the logic lives in safe Rust ([`Instance`]); this file only converts pointers to slices
//!   and results to statuses, logging every failure through the importer's logger.
//!
//! Memory: the instance is a `Box` from Rust's allocator (the description declares
//! `canNotUseMemoryManagementFunctions="true"`), freed by `fmi2FreeInstance`; so is an FMU
//! state (`fmi2GetFMUstate`, `fmi2DeSerializeFMUstate`), freed by `fmi2FreeFMUstate`.

#![allow(non_snake_case, non_camel_case_types)]

use crate::description::{guid, MODEL_IDENTIFIER};
use crate::instance::Instance;
use crate::snapshot::Snapshot;
use crate::status::{Failure, Phase, Status};
use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// `fmi2Status`.
pub type fmi2Status = c_int;
/// `fmi2OK`.
pub const FMI2_OK: fmi2Status = 0;
/// `fmi2Warning`.
pub const FMI2_WARNING: fmi2Status = 1;
/// `fmi2Discard`.
pub const FMI2_DISCARD: fmi2Status = 2;
/// `fmi2Error`.
pub const FMI2_ERROR: fmi2Status = 3;
/// `fmi2Fatal`.
pub const FMI2_FATAL: fmi2Status = 4;
/// `fmi2CoSimulation` (`fmi2Type`).
pub const FMI2_COSIMULATION: c_int = 1;

/// `fmi2Component`: an opaque pointer to an [`Fmu`].
pub type fmi2Component = *mut c_void;
/// `fmi2ComponentEnvironment`: the importer's pointer, passed back to the logger.
pub type fmi2ComponentEnvironment = *mut c_void;
/// `fmi2FMUstate`: an opaque pointer to a [`Snapshot`] (from `fmi2GetFMUstate` or
/// `fmi2DeSerializeFMUstate`, freed by `fmi2FreeFMUstate`).
pub type fmi2FMUstate = *mut c_void;
/// `fmi2ValueReference`.
pub type fmi2ValueReference = u32;
/// `fmi2Real`.
pub type fmi2Real = f64;
/// `fmi2Integer`.
pub type fmi2Integer = c_int;
/// `fmi2Boolean`.
pub type fmi2Boolean = c_int;
/// `fmi2String`.
pub type fmi2String = *const c_char;
/// `fmi2Byte`.
pub type fmi2Byte = c_char;
/// `fmi2StatusKind`.
pub type fmi2StatusKind = c_int;

/// `fmi2CallbackLogger`: `(env, instanceName, status, category, message, ...)`; `message` is
/// a printf format (this FMU escapes `%` as `%%` and passes no arguments).
pub type fmi2CallbackLogger = unsafe extern "C" fn(
    fmi2ComponentEnvironment,
    fmi2String,
    fmi2Status,
    fmi2String,
    fmi2String,
    ...
);

/// `fmi2CallbackFunctions` (copied at instantiation; only the logger and the environment
/// are used).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct fmi2CallbackFunctions {
    /// Logger (may be null: then nothing is logged).
    pub logger: Option<fmi2CallbackLogger>,
    /// `allocateMemory` (unused).
    pub allocate_memory: Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>,
    /// `freeMemory` (unused).
    pub free_memory: Option<unsafe extern "C" fn(*mut c_void)>,
    /// `stepFinished` (unused: the FMU never returns `fmi2Pending`).
    pub step_finished: Option<unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2Status)>,
    /// The importer's environment pointer.
    pub component_environment: fmi2ComponentEnvironment,
}

/// What `fmi2Component` points to.
pub struct Fmu {
    instance: Instance,
    name: CString,
    logger: Option<fmi2CallbackLogger>,
    env: fmi2ComponentEnvironment,
    logging_on: bool,
}

impl Fmu {
    /// Sends one message to the importer's logger (errors always, other statuses only with
    /// debug logging on).
    fn log(&self, status: fmi2Status, category: &str, message: &str) {
        if status == FMI2_OK && !self.logging_on {
            return;
        }
        let Some(logger) = self.logger else { return };
        let text = CString::new(message.replace('%', "%%").replace('\0', " ")).unwrap_or_default();
        let category = CString::new(category).unwrap_or_default();
        // SAFETY: the logger is the importer's function of the FMI signature, given at
        // instantiation; all string arguments are valid NUL-terminated strings alive for the
        // call, and the message contains no unescaped `%`, so no variadic argument is read.
        unsafe {
            logger(
                self.env,
                self.name.as_ptr(),
                status,
                category.as_ptr(),
                text.as_ptr(),
            )
        };
    }

    fn report(&self, r: Result<(), Failure>) -> fmi2Status {
        match r {
            Ok(()) => FMI2_OK,
            Err(f) => {
                let status = match f.status {
                    Status::Warning => FMI2_WARNING,
                    Status::Discard => FMI2_DISCARD,
                    Status::Error => FMI2_ERROR,
                    Status::Fatal => FMI2_FATAL,
                };
                self.log(status, "logStatusError", &f.message);
                status
            }
        }
    }
}

/// Runs `body` on the instance behind `c`, catching panics. Null `c` is `fmi2Error`.
///
/// # Safety
/// `c` is null or a pointer returned by [`fmi2Instantiate`] and not yet freed, used by one
/// thread at a time (FMI 2.0 rule).
unsafe fn guard(c: fmi2Component, body: impl FnOnce(&mut Fmu) -> fmi2Status) -> fmi2Status {
    if c.is_null() {
        return FMI2_ERROR;
    }
    // SAFETY: by the contract above `c` came from `Box::into_raw` in `fmi2Instantiate` and
    // is not aliased during the call.
    let fmu = unsafe { &mut *(c as *mut Fmu) };
    match catch_unwind(AssertUnwindSafe(|| body(fmu))) {
        Ok(status) => status,
        Err(_) => {
            // The body panicked: the instance may be half-updated, so it is not used again.
            let _ = catch_unwind(AssertUnwindSafe(|| {
                fmu.instance.poison();
                fmu.log(
                    FMI2_FATAL,
                    "logStatusFatal",
                    "internal panic caught; instance unusable",
                );
            }));
            FMI2_FATAL
        }
    }
}

/// A slice from an FMI array argument; `None` if the pointer is null while `n > 0`.
///
/// # Safety
/// If non-null, `p` points to `n` valid, initialised elements not mutated during the call.
unsafe fn slice<'a, T>(p: *const T, n: usize) -> Option<&'a [T]> {
    if n == 0 {
        return Some(&[]);
    }
    if p.is_null() {
        return None;
    }
    // SAFETY: non-null, and by the contract above valid for `n` reads.
    Some(unsafe { std::slice::from_raw_parts(p, n) })
}

/// A mutable slice from an FMI output array argument; `None` if null while `n > 0`.
///
/// # Safety
/// If non-null, `p` points to `n` writable elements not otherwise accessed during the call.
unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> Option<&'a mut [T]> {
    if n == 0 {
        return Some(&mut []);
    }
    if p.is_null() {
        return None;
    }
    // SAFETY: non-null, and by the contract above valid and exclusive for `n` writes.
    Some(unsafe { std::slice::from_raw_parts_mut(p, n) })
}

fn null_argument(fmu: &Fmu, what: &str) -> fmi2Status {
    fmu.report(Err(Failure {
        status: Status::Error,
        message: format!("{what}: null pointer argument"),
    }))
}

/// A get or set of a variable type this FMU has none of (`kind`: "Boolean", "String"):
/// `fmi2OK` for no value reference, else an error naming the first one.
fn no_variable_of(fmu: &Fmu, kind: &str, vr: &[fmi2ValueReference]) -> fmi2Status {
    match vr.first() {
        None => FMI2_OK,
        Some(r) => fmu.report(Err(Failure {
            status: Status::Error,
            message: format!("no {kind} variable with value reference {r}"),
        })),
    }
}

fn unsupported(fmu: &Fmu, what: &str) -> fmi2Status {
    fmu.report(Err(Failure {
        status: Status::Error,
        message: format!(
            "{what} is not supported by this FMU (see modelDescription.xml capability flags)"
        ),
    }))
}

/// `fmi2GetTypesPlatform`: `"default"`.
#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

/// `fmi2GetVersion`: `"2.0"`.
#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// Reads a C string argument; `None` for null or non-UTF-8.
///
/// # Safety
/// `p` is null or a valid NUL-terminated string.
unsafe fn text(p: fmi2String) -> Option<String> {
    if p.is_null() {
        return None;
    }
    // SAFETY: non-null and NUL-terminated by the contract above.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .ok()
        .map(str::to_owned)
}

/// `fmi2Instantiate`: checks the type (co-simulation), the GUID and the instance name;
/// returns null on any error (logged when a logger was given).
///
/// # Safety
/// String arguments are null or NUL-terminated; `functions` is null or points to a valid
/// `fmi2CallbackFunctions`.
#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: fmi2String,
    fmu_type: c_int,
    fmu_guid: fmi2String,
    _fmu_resource_location: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    logging_on: fmi2Boolean,
) -> fmi2Component {
    let made = catch_unwind(AssertUnwindSafe(|| {
        let callbacks = if functions.is_null() {
            None
        } else {
            // SAFETY: non-null and, by the contract, a valid struct; it is copied.
            Some(unsafe { *functions })
        };
        // SAFETY: null or NUL-terminated by the contract.
        let name = unsafe { text(instance_name) };
        // SAFETY: as above.
        let given_guid = unsafe { text(fmu_guid) };
        let fmu = Fmu {
            instance: Instance::new(),
            name: CString::new(name.clone().unwrap_or_else(|| MODEL_IDENTIFIER.into()))
                .unwrap_or_default(),
            logger: callbacks.and_then(|c| c.logger),
            env: callbacks.map_or(std::ptr::null_mut(), |c| c.component_environment),
            logging_on: logging_on != 0,
        };
        let problem = if callbacks.is_none() {
            Some("fmi2Instantiate: functions is null".to_string())
        } else if matches!(name.as_deref(), None | Some("")) {
            Some("fmi2Instantiate: instanceName is null or empty".to_string())
        } else if fmu_type != FMI2_COSIMULATION {
            Some(format!(
                "fmi2Instantiate: this FMU supports co-simulation only (fmuType {fmu_type})"
            ))
        } else if given_guid.as_deref() != Some(guid()) {
            Some(format!(
                "fmi2Instantiate: GUID {:?} does not match this binary's {}",
                given_guid.unwrap_or_default(),
                guid()
            ))
        } else {
            None
        };
        match problem {
            Some(p) => {
                fmu.log(FMI2_ERROR, "logStatusError", &p);
                std::ptr::null_mut()
            }
            None => Box::into_raw(Box::new(fmu)) as fmi2Component,
        }
    }));
    made.unwrap_or(std::ptr::null_mut())
}

/// `fmi2FreeInstance` (null is ignored).
///
/// # Safety
/// `c` is null or from [`fmi2Instantiate`], not used afterwards.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    if c.is_null() {
        return;
    }
    let _ = catch_unwind(|| {
        // SAFETY: `c` came from `Box::into_raw` in `fmi2Instantiate` and is freed once.
        drop(unsafe { Box::from_raw(c as *mut Fmu) });
    });
}

/// Defines one `fmi2*` entry point that takes the instance `c` first: the arguments after
/// `c`, and a body that runs with the instance (`|fmu| ...`, `fmu: &mut Fmu`) inside
/// [`guard`]. The body is a closure outside the unsafe block, so any unsafe operation in it
/// needs its own `unsafe` block and `// SAFETY:` comment. The caller's doc comment must
/// state the function's `# Safety` contract, which includes [`guard`]'s for `c`.
macro_rules! entry {
    (
        $(#[$attr:meta])*
        fn $name:ident($($arg:tt: $ty:ty),* $(,)?) |$fmu:pat_param| $body:expr
    ) => {
        $(#[$attr])*
        #[no_mangle]
        pub unsafe extern "C" fn $name(c: fmi2Component, $($arg: $ty),*) -> fmi2Status {
            let body = |$fmu: &mut Fmu| -> fmi2Status { $body };
            // SAFETY: `c` is null or a live instance used by one thread at a time, per this
            // function's contract (which includes `guard`'s).
            unsafe { guard(c, body) }
        }
    };
}

entry! {
    /// `fmi2SetDebugLogging`: switches non-error messages on or off (categories are ignored).
    ///
    /// # Safety
    /// See [`guard`].
    fn fmi2SetDebugLogging(
        logging_on: fmi2Boolean,
        _n_categories: usize,
        _categories: *const fmi2String,
    ) |fmu| {
        fmu.logging_on = logging_on != 0;
        FMI2_OK
    }
}

/// Defines `fmi2*` entry points that pass their arguments to one [`Instance`] method
/// returning `Result<(), Failure>` and report its result (`fmi2OK`, or the failure's status
/// with its message logged), through `entry!`. Each item is a doc comment and
/// `fn NAME(ARG: TYPE, ...) => METHOD(ARG, ...);`. Every function defined here gets the
/// `# Safety` section written below ([`guard`]'s contract); its only unsafe block is the one
/// in `entry!`, whose `// SAFETY:` comment rests on that contract.
macro_rules! lifecycle {
    ($(
        $(#[$attr:meta])*
        fn $name:ident($($arg:ident: $ty:ty),* $(,)?) => $method:ident($($pass:ident),*);
    )*) => {$(
        entry! {
            $(#[$attr])*
            ///
            /// # Safety
            /// `c` is null or from [`fmi2Instantiate`] and not yet freed, used by one thread at
            /// a time (`guard`'s contract).
            fn $name($($arg: $ty),*) |fmu| {
                let r = fmu.instance.$method($($pass),*);
                fmu.report(r)
            }
        }
    )*};
}

// Safety: the `# Safety` section and the `// SAFETY:` reasoning of these functions are
// written once, at `lifecycle!` and `entry!`.
lifecycle! {
    /// `fmi2SetupExperiment`: the start time; tolerance and stop time are not used.
    fn fmi2SetupExperiment(
        _tolerance_defined: fmi2Boolean,
        _tolerance: fmi2Real,
        start_time: fmi2Real,
        _stop_time_defined: fmi2Boolean,
        _stop_time: fmi2Real,
    ) => setup_experiment(start_time);

    /// `fmi2EnterInitializationMode`.
    fn fmi2EnterInitializationMode() => enter_initialization();

    /// `fmi2ExitInitializationMode`: validates parameters and initial state (the model's error
    /// text goes to the logger).
    fn fmi2ExitInitializationMode() => exit_initialization();

    /// `fmi2Terminate`.
    fn fmi2Terminate() => terminate();

    /// `fmi2DoStep`: `communicationStepSize` must be a whole multiple of `config.h`.
    fn fmi2DoStep(
        current_communication_point: fmi2Real,
        communication_step_size: fmi2Real,
        _no_set_fmu_state_prior: fmi2Boolean,
    ) => do_step(current_communication_point, communication_step_size);
}

entry! {
    /// `fmi2Reset`: back to the state after instantiation, start values restored.
    ///
    /// # Safety
    /// See [`guard`].
    fn fmi2Reset() |fmu| {
        fmu.instance.reset();
        FMI2_OK
    }
}

/// Defines the `fmi2Get*` and `fmi2Set*` entry points, `(c, vr, nvr, value)` with `vr:
/// *const fmi2ValueReference`, `nvr: usize` and `value: *mut T` (get) or `*const T` (set),
/// through `entry!`. Each item is a doc comment and `fn NAME(get T) => ACTION;` or
/// `fn NAME(set T) => ACTION;`, where `ACTION` is an [`Instance`] method `(vr, values)` whose
/// result is reported, or a string `"Kind"`: a type this FMU has no variables of
/// ([`no_variable_of`]). A null `vr` or `value` while `nvr > 0` is `fmi2Error`, logged as
/// "NAME: null pointer argument"; `nvr == 0` reads and writes nothing.
///
/// Every function defined here gets the `# Safety` section written below; the one unsafe
/// block written here (the two slices) rests on it, and the call of [`guard`] on `entry!`'s.
macro_rules! get_set {
    ($($(#[$attr:meta])* fn $name:ident($dir:ident $ty:ty) => $action:tt;)*) => {
        $(get_set!(@$dir $(#[$attr])* $name $ty, $action);)*
    };
    (@get $(#[$attr:meta])* $name:ident $ty:ty, $action:tt) => {
        get_set!(@entry $(#[$attr])* $name *mut $ty, slice_mut, $action);
    };
    (@set $(#[$attr:meta])* $name:ident $ty:ty, $action:tt) => {
        get_set!(@entry $(#[$attr])* $name *const $ty, slice, $action);
    };
    (@entry $(#[$attr:meta])* $name:ident $ptr:ty, $slice:ident, $action:tt) => {
        entry! {
            $(#[$attr])*
            ///
            /// # Safety
            /// `c` is null or from [`fmi2Instantiate`] and not yet freed, used by one thread at
            /// a time (`guard`'s contract); `vr` and `value` are null or valid for `nvr` elements.
            fn $name(vr: *const fmi2ValueReference, nvr: usize, value: $ptr) |fmu| {
                // SAFETY: null or valid for `nvr` elements per this function's contract
                // (above); `slice` and `slice_mut` check for null before use.
                let (Some(vr), Some(value)) = (unsafe { (slice(vr, nvr), $slice(value, nvr)) })
                else {
                    return null_argument(fmu, stringify!($name));
                };
                get_set!(@do fmu, vr, value, $action)
            }
        }
    };
    (@do $fmu:ident, $vr:ident, $value:ident, $method:ident) => {{
        let r = $fmu.instance.$method($vr, $value);
        $fmu.report(r)
    }};
    (@do $fmu:ident, $vr:ident, $value:ident, $kind:literal) => {{
        let _ = $value;
        no_variable_of($fmu, $kind, $vr)
    }};
}

// Safety: the `# Safety` section and the `// SAFETY:` reasoning of these functions are
// written once, at `get_set!` and `entry!`.
get_set! {
    /// `fmi2GetReal`.
    fn fmi2GetReal(get fmi2Real) => get_real;
    /// `fmi2GetInteger`.
    fn fmi2GetInteger(get fmi2Integer) => get_integer;
    /// `fmi2GetBoolean`: the FMU has no Boolean variables, so any value reference is an error.
    fn fmi2GetBoolean(get fmi2Boolean) => "Boolean";
    /// `fmi2GetString`: no String variables (any value reference is an error).
    fn fmi2GetString(get fmi2String) => "String";
    /// `fmi2SetReal`: inputs and parameters (see `Instance::set_real`).
    fn fmi2SetReal(set fmi2Real) => set_real;
    /// `fmi2SetInteger`: the segment budget and the friction law.
    fn fmi2SetInteger(set fmi2Integer) => set_integer;
    /// `fmi2SetBoolean`: no Boolean variables (any value reference is an error).
    fn fmi2SetBoolean(set fmi2Boolean) => "Boolean";
    /// `fmi2SetString`: no String variables (any value reference is an error).
    fn fmi2SetString(set fmi2String) => "String";
}

entry! {
    /// `fmi2CancelStep`: steps are synchronous, there is nothing to cancel.
    ///
    /// # Safety
    /// See [`guard`].
    fn fmi2CancelStep() |fmu| unsupported(fmu, "fmi2CancelStep (steps are synchronous)")
}

entry! {
    /// `fmi2GetStatus` and friends: only meaningful after `fmi2Pending`, which this FMU never
    /// returns; `fmi2Terminated` is answered (true after a failed step).
    ///
    /// # Safety
    /// See [`guard`]; `value` null or writable.
    fn fmi2GetStatus(_kind: fmi2StatusKind, _value: *mut fmi2Status) |_| FMI2_DISCARD
}

entry! {
    /// `fmi2GetRealStatus`: `fmi2LastSuccessfulTime` (2) gives the FMU's time.
    ///
    /// # Safety
    /// See [`guard`]; `value` null or writable.
    fn fmi2GetRealStatus(kind: fmi2StatusKind, value: *mut fmi2Real) |fmu| {
        // SAFETY: null or writable for one element per this function's contract.
        let Some(out) = (unsafe { slice_mut(value, 1) }) else {
            return null_argument(fmu, "fmi2GetRealStatus");
        };
        if kind == 2 {
            out[0] = fmu.instance.time();
            FMI2_OK
        } else {
            FMI2_DISCARD
        }
    }
}

entry! {
    /// `fmi2GetIntegerStatus`: nothing to report.
    ///
    /// # Safety
    /// See [`guard`].
    fn fmi2GetIntegerStatus(_kind: fmi2StatusKind, _value: *mut fmi2Integer) |_| FMI2_DISCARD
}

entry! {
    /// `fmi2GetBooleanStatus`: `fmi2Terminated` (3) is true after a failed step.
    ///
    /// # Safety
    /// See [`guard`]; `value` null or writable.
    fn fmi2GetBooleanStatus(kind: fmi2StatusKind, value: *mut fmi2Boolean) |fmu| {
        // SAFETY: null or writable for one element per this function's contract.
        let Some(out) = (unsafe { slice_mut(value, 1) }) else {
            return null_argument(fmu, "fmi2GetBooleanStatus");
        };
        if kind == 3 {
            out[0] = c_int::from(fmu.instance.phase() == Phase::Failed);
            FMI2_OK
        } else {
            FMI2_DISCARD
        }
    }
}

entry! {
    /// `fmi2GetStringStatus`: nothing to report.
    ///
    /// # Safety
    /// See [`guard`].
    fn fmi2GetStringStatus(_kind: fmi2StatusKind, _value: *mut fmi2String) |_| FMI2_DISCARD
}

// ---- FMU state -------------------------------------------------------------------------
// An `fmi2FMUstate` is a `Box<Snapshot>` from Rust's allocator (`Box::into_raw`), owned by
// the importer until `fmi2FreeFMUstate`. A snapshot holds no pointer to its instance, so it
// may be set into any instance of this FMU.

/// Stores `snap` in `*slot`: in the state already there (FMI: "`*FMUstate` is overwritten"),
/// else in a new one.
///
/// # Safety
/// `slot` is non-null and valid for reads and writes of one `fmi2FMUstate`, which is null or
/// a state of this FMU not yet freed and not used elsewhere during the call.
unsafe fn store(slot: *mut fmi2FMUstate, snap: Snapshot) {
    // SAFETY: `slot` is valid for reads by the contract above.
    let old = unsafe { *slot };
    if old.is_null() {
        // SAFETY: `slot` is valid for writes by the contract above.
        unsafe { *slot = Box::into_raw(Box::new(snap)) as fmi2FMUstate };
    } else {
        // SAFETY: a non-null `*slot` came from `Box::into_raw` of a `Snapshot` here and is
        // live and unaliased, by the contract above.
        unsafe { *(old as *mut Snapshot) = snap };
    }
}

/// The snapshot behind an `fmi2FMUstate`, `None` if null.
///
/// # Safety
/// `state` is null or a state of this FMU not yet freed, not written during the call.
unsafe fn snapshot_at<'a>(state: fmi2FMUstate) -> Option<&'a Snapshot> {
    // SAFETY: null or from `Box::into_raw` of a live `Snapshot`, by the contract above.
    unsafe { (state as *const Snapshot).as_ref() }
}

entry! {
    /// `fmi2GetFMUstate`: a copy of everything that determines the instance's future
    /// ([`Snapshot`]) in `*state` (a new state if `*state` is null, else the state there is
    /// overwritten). Allowed in every phase.
    ///
    /// # Safety
    /// See [`guard`]; `state` is null or points to a readable and writable `fmi2FMUstate`
    /// that is null or a state of this FMU not yet freed.
    fn fmi2GetFMUstate(state: *mut fmi2FMUstate) |fmu| {
        if state.is_null() {
            return null_argument(fmu, "fmi2GetFMUstate");
        }
        // SAFETY: non-null, and per this function's contract valid and holding null or a
        // live state of this FMU.
        unsafe { store(state, fmu.instance.snapshot()) };
        FMI2_OK
    }
}

entry! {
    /// `fmi2SetFMUstate`: back to `state` (parameters, inputs, time, simulator). The values
    /// are checked as at initialisation; on error the instance is unchanged.
    ///
    /// # Safety
    /// See [`guard`]; `state` is null or a state of this FMU not yet freed.
    fn fmi2SetFMUstate(state: fmi2FMUstate) |fmu| {
        // SAFETY: null or a live state of this FMU, per this function's contract.
        let Some(snap) = (unsafe { snapshot_at(state) }) else {
            return null_argument(fmu, "fmi2SetFMUstate");
        };
        let r = fmu.instance.restore(snap);
        fmu.report(r)
    }
}

entry! {
    /// `fmi2FreeFMUstate`: frees `*state` and sets it to null (a null `*state` is ignored).
    ///
    /// # Safety
    /// See [`guard`]; `state` is null or points to a readable and writable `fmi2FMUstate`
    /// that is null or a state of this FMU not yet freed, not used afterwards.
    fn fmi2FreeFMUstate(state: *mut fmi2FMUstate) |fmu| {
        if state.is_null() {
            return null_argument(fmu, "fmi2FreeFMUstate");
        }
        // SAFETY: non-null and valid for reads and writes per this function's contract.
        let old = unsafe { std::mem::replace(&mut *state, std::ptr::null_mut()) };
        if !old.is_null() {
            // SAFETY: from `Box::into_raw` of a `Snapshot` in `store`, freed once here (the
            // importer's pointer is now null).
            drop(unsafe { Box::from_raw(old as *mut Snapshot) });
        }
        FMI2_OK
    }
}

entry! {
    /// `fmi2SerializedFMUstateSize`: the byte count of `state` serialized (the same for every
    /// state of this FMU).
    ///
    /// # Safety
    /// See [`guard`]; `state` is null or a state of this FMU not yet freed; `size` is null or
    /// writable.
    fn fmi2SerializedFMUstateSize(state: fmi2FMUstate, size: *mut usize) |fmu| {
        // SAFETY: per this function's contract: `state` null or live, `size` null or writable.
        let (Some(snap), Some(out)) = (unsafe { (snapshot_at(state), slice_mut(size, 1)) })
        else {
            return null_argument(fmu, "fmi2SerializedFMUstateSize");
        };
        out[0] = snap.to_bytes().len();
        FMI2_OK
    }
}

entry! {
    /// `fmi2SerializeFMUstate`: writes `state` to `bytes`, whose `size` must be
    /// [`fmi2SerializedFMUstateSize`]'s.
    ///
    /// # Safety
    /// See [`guard`]; `state` is null or a state of this FMU not yet freed; `bytes` is null or
    /// writable for `size` bytes.
    fn fmi2SerializeFMUstate(state: fmi2FMUstate, bytes: *mut fmi2Byte, size: usize) |fmu| {
        // SAFETY: per this function's contract: `state` null or live, `bytes` null or
        // writable for `size` bytes (`c_char` and `u8` have the same layout).
        let (Some(snap), Some(out)) =
            (unsafe { (snapshot_at(state), slice_mut(bytes as *mut u8, size)) })
        else {
            return null_argument(fmu, "fmi2SerializeFMUstate");
        };
        let data = snap.to_bytes();
        if data.len() != size {
            return fmu.report(Err(Failure {
                status: Status::Error,
                message: format!(
                    "fmi2SerializeFMUstate: size {size} given, the state needs {} bytes \
                     (fmi2SerializedFMUstateSize)",
                    data.len()
                ),
            }));
        }
        out.copy_from_slice(&data);
        FMI2_OK
    }
}

entry! {
    /// `fmi2DeSerializeFMUstate`: reads a state written by [`fmi2SerializeFMUstate`] (of an
    /// FMU with the same GUID) into `*state` (a new state if `*state` is null, else the state
    /// there is overwritten). A wrong size, header or checksum is `fmi2Error` with a logged
    /// message, `*state` unchanged.
    ///
    /// # Safety
    /// See [`guard`]; `bytes` is null or readable for `size` bytes; `state` is null or points
    /// to a readable and writable `fmi2FMUstate` that is null or a state of this FMU not yet
    /// freed.
    fn fmi2DeSerializeFMUstate(
        bytes: *const fmi2Byte,
        size: usize,
        state: *mut fmi2FMUstate,
    ) |fmu| {
        // SAFETY: null or readable for `size` bytes per this function's contract (`c_char`
        // and `u8` have the same layout).
        let Some(data) = (unsafe { slice(bytes as *const u8, size) }) else {
            return null_argument(fmu, "fmi2DeSerializeFMUstate");
        };
        if state.is_null() {
            return null_argument(fmu, "fmi2DeSerializeFMUstate");
        }
        match Snapshot::from_bytes(data) {
            Ok(snap) => {
                // SAFETY: non-null, and per this function's contract valid and holding null
                // or a live state of this FMU.
                unsafe { store(state, snap) };
                FMI2_OK
            }
            Err(f) => fmu.report(Err(f)),
        }
    }
}

macro_rules! not_supported {
    ($name:ident ( $($arg:ident : $ty:ty),* )) => {
        entry! {
            #[doc = concat!("`", stringify!($name), "`: not supported (capability flag false); `fmi2Error`.")]
            ///
            /// # Safety
            /// See [`guard`].
            fn $name($(_: $ty),*) |fmu| unsupported(fmu, stringify!($name))
        }
    };
}

not_supported!(fmi2GetDirectionalDerivative(
    unknown: *const fmi2ValueReference,
    n_unknown: usize,
    known: *const fmi2ValueReference,
    n_known: usize,
    dv_known: *const fmi2Real,
    dv_unknown: *mut fmi2Real
));
not_supported!(fmi2SetRealInputDerivatives(
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *const fmi2Real
));
not_supported!(fmi2GetRealOutputDerivatives(
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *mut fmi2Real
));

#[cfg(test)]
mod tests {
    #![allow(clippy::panic, clippy::undocumented_unsafe_blocks)]
    use super::*;

    #[test]
    fn a_panic_in_an_entry_point_becomes_fatal_and_the_instance_is_unusable() {
        let cb = fmi2CallbackFunctions {
            logger: None,
            allocate_memory: None,
            free_memory: None,
            step_finished: None,
            component_environment: std::ptr::null_mut(),
        };
        let g = CString::new(guid()).unwrap_or_default();
        // Pointers below are valid for each call; `c` is freed once at the end.
        let c =
            unsafe { fmi2Instantiate(c"t".as_ptr(), 1, g.as_ptr(), std::ptr::null(), &cb, 0, 0) };
        assert!(!c.is_null());
        unsafe {
            assert_eq!(fmi2EnterInitializationMode(c), FMI2_OK);
            assert_eq!(fmi2ExitInitializationMode(c), FMI2_OK);
            assert_eq!(guard(c, |_| panic!("injected")), FMI2_FATAL);
            assert_eq!(fmi2DoStep(c, 0.0, 1e-3, 0), FMI2_ERROR);
            assert_eq!(fmi2Reset(c), FMI2_OK);
            fmi2FreeInstance(c);
        }
    }
}
