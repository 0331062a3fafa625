//! # crane-twin
//!
//! The crane's digital twin for a Cortex-M4F next to the motor drivers, `no_std`, no heap:
//! - [`logic`]: the numeric core, plain `core` + `crane_model` (shared verbatim with the host
//!   cross-check): the observer ([`logic::observer`]), friction-aware feedforward
//!   ([`logic::feedforward`]), the control period ([`logic::control`]), the simulated plant
//!   ([`logic::plant`]) and the bit-exact cross-check scenarios ([`logic::scenarios`]);
//! - [`hal`]: the hardware boundary on embedded-hal 1.0 (`SetDutyCycle` + two `OutputPin`s
//!   per H-bridge, an [`hal::Encoder`] trait of our own, a period ticker);
//! - [`preload`]: PWM channels whose zero duty takes effect at once on a timer with preloaded
//!   compare registers (a direction change happens with the bridge really off);
//! - [`board`]: the QEMU "board": the embedded-hal pins and encoders are backed by the model.

#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

pub mod board;
pub mod hal;
pub mod logic;
pub mod preload;
