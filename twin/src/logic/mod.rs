//! The numeric logic of the twin, shared verbatim by the firmware, this crate's tests and the
//! host cross-check (`host-tests/tests/qemu_cross.rs` includes this directory with `#[path]`).
//!
//! Everything here uses only `core` and `crane_model` (no embedded-hal, no `crate::` paths
//! outside `logic`), so the same source compiles for the Cortex-M4F and for the host and gives
//! the same bits on both. Elementary functions go through [`crane_model::Real`] (libm), never
//! through std's inherent `f64` methods.

// `k % n == 0` reads as the period it is (and `is_multiple_of` is newer than the MSRV).
#![allow(clippy::manual_is_multiple_of)]

pub mod control;
pub mod digest;
pub mod fastmath;
pub mod feedforward;
pub mod io;
pub mod monitor;
pub mod monitor_rig;
pub mod observer;
pub mod plant;
pub mod prng;
pub mod safety;
pub mod scenarios;
