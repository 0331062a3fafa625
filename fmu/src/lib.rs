//! # crane-fmu
//!
//! The crane model (`crane_model::Crane`, hybrid exact-sticking friction, fixed step) as an
//! FMI 2.0 co-simulation FMU, for Simulink, OpenModelica, Dymola, FMPy and every FMI tool.
//!
//! - [`variables`]: the FMU's variables (inputs `u_x, u_y, u_l` [V]; positions, velocities,
//!   modes, friction forces, rope tension, payload position; every model parameter), the one
//!   table both the binary and `modelDescription.xml` are made from.
//! - [`instance`]: the co-simulation state machine around the model, safe Rust.
//! - [`description`]: `modelDescription.xml`, `documentation/index.html`, the GUID.
//! - [`snapshot`]: the FMU state (`fmi2GetFMUstate`) as plain data and its serialized form.
//! - [`ffi`]: the `fmi2*` C entry points; the only unsafe code of the workspace outside the
//!   firmware's HAL, each block with a `// SAFETY:` comment, every body behind
//!   `catch_unwind`.
//! - `src/bin/pack.rs`: `crane-fmu-pack`, which zips `crane.fmu` (`scripts/build-fmu.sh`).

#![deny(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]
#![deny(clippy::undocumented_unsafe_blocks)]
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
#![cfg_attr(test, allow(clippy::unwrap_used))]

pub mod description;
pub mod ffi;
pub mod instance;
pub mod snapshot;
pub mod status;
pub mod variables;
