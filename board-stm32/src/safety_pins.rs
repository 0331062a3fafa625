//! The safety inputs on port B: which pin is which input, and their decoding from one read of
//! `GPIOB_IDR` (a consistent snapshot of all eight contacts at the same instant). Pure: the
//! board reads the register, the QEMU build (no GPIO model) synthesises the word, and both
//! decode it here (host-tested in `host-tests/tests/board_pure.rs`).
//!
//! The contacts are normally closed to ground with the pins' pull-ups: a closed (healthy)
//! contact reads low, an open contact or a broken wire reads high = active.

use crane_twin::logic::safety::Inputs;

/// Port B pin of the e-stop input (PB0).
pub const ESTOP_PIN: u32 = 0;
/// Port B pin of the motor driver's fault line (PB1).
pub const DRIVER_FAULT_PIN: u32 = 1;
/// Port B pins of the limit switches `[axis][end]` (axes X, Y, rope; end 0 negative, 1
/// positive): PB8/PB9, PB10/PB11, PB12/PB13.
pub const LIMIT_PINS: [[u32; 2]; 3] = [[8, 9], [10, 11], [12, 13]];

/// Every safety pin as a mask of `GPIOB_IDR`.
pub const ALL_SAFETY_PINS: u32 = (1 << ESTOP_PIN)
    | (1 << DRIVER_FAULT_PIN)
    | (1 << LIMIT_PINS[0][0])
    | (1 << LIMIT_PINS[0][1])
    | (1 << LIMIT_PINS[1][0])
    | (1 << LIMIT_PINS[1][1])
    | (1 << LIMIT_PINS[2][0])
    | (1 << LIMIT_PINS[2][1]);

/// The safety inputs in the port B input data register `idr` (bit n = level of PBn; high =
/// active). Other pins are ignored.
pub fn inputs_from_idr(idr: u32) -> Inputs {
    let high = |pin: u32| idr & (1 << pin) != 0;
    Inputs {
        estop: high(ESTOP_PIN),
        driver_fault: high(DRIVER_FAULT_PIN),
        limits: LIMIT_PINS.map(|ends| ends.map(high)),
    }
}
