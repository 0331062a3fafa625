//! The safety step of every period, one code path for the board and the QEMU build (which
//! differ only in where the safety port's word comes from: `GPIOB_IDR` on the board, a
//! synthesised word under QEMU, which has no GPIO model).
//!
//! - [`check`]: the supervisor sees the decoded inputs and the missed periods; whenever it is
//!   safe (every period, not only on the transition) the hardware safe state is forced again.
//! - [`at_tick`]: [`check`] right after the loop took the period's tick, then the watchdog feed,
//!   only while [`Supervisor::feeds_watchdog`] (the loop keeps its period).

use crate::{regs, safety_pins};
use crane_twin::logic::safety::{State, Supervisor};

/// Checks `sup` with the safety port word `idr` and `missed` periods; forces the hardware safe
/// state ([`regs::force_safe`]) whenever the result is safe. Returns the state.
pub fn check(sup: &mut Supervisor, idr: u32, missed: u64) -> State {
    let state = sup.check(&safety_pins::inputs_from_idr(idr), missed);
    if let State::Safe(_) = state {
        regs::force_safe();
    }
    state
}

/// What the loop does once it has taken a tick: [`check`], then feeds the watchdog if the
/// supervisor allows it. Returns the state and whether the watchdog was fed.
pub fn at_tick(sup: &mut Supervisor, idr: u32, missed: u64) -> (State, bool) {
    let state = check(sup, idr, missed);
    let feed = sup.feeds_watchdog();
    if feed {
        regs::watchdog_feed();
    }
    (state, feed)
}
