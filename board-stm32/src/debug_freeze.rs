//! What a debugger halt freezes (`DBGMCU_APB1_FZ`, `DBGMCU_APB2_FZ`, RM0090 38.16.4-5): every
//! timer the firmware uses (PWM, period, encoders) and the independent watchdog. A frozen TIM1
//! also disables its outputs (RM0090 "Debug mode": as after a break, with `MOE` cleared), so a
//! halted core does not leave the bridges driven. Pure values (host-tested in
//! `host-tests/tests/board_pure.rs`); [`crate::regs::freeze_timers_in_debug`] writes them.

/// `DBGMCU_APB1_FZ` bits: `DBG_TIM2_STOP`..`DBG_TIM7_STOP` (bits 0-5) and `DBG_IWDG_STOP`
/// (bit 12).
pub const APB1_FREEZE: u32 = 0b11_1111 | (1 << 12);
/// `DBGMCU_APB2_FZ` bits: `DBG_TIM1_STOP` (bit 0), `DBG_TIM8_STOP` (bit 1).
pub const APB2_FREEZE: u32 = 0b11;
