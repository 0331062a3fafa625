//! Register-level parts of the STM32F405/407 board firmware shared by the binary
//! (`src/main.rs`) and the on-target tests (`tests/on_target.rs`, `defmt-test`, run with a
//! probe: `cargo test -p board-stm32 --target thumbv7em-none-eabihf --features board,probe
//! --test on_target` with the probe-rs runner).
#![no_std]

pub mod debug_freeze;
pub mod guard;
#[cfg_attr(not(feature = "board"), allow(dead_code))]
pub mod regs;
pub mod safety_pins;
pub mod stack;
pub mod txqueue;
pub mod watchdog;
