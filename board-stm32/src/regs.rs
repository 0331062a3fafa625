//! Register-level pieces that must work without the HAL's objects: the fault handlers' safe
//! state (they cannot own the HAL's PWM or pins), the PWM compare writes with their update
//! event, the 2 ms period timer and the encoder counters read in its interrupt. Addresses and
//! offsets from RM0090 (STM32F405/407 reference manual), the same on every STM32F4 timer.
//!
//! Which timer does what:
//!
//! | role | board (`--features board`) | QEMU `netduinoplus2` (default build) |
//! |---|---|---|
//! | H-bridge PWM, 3 channels, 40 kHz | TIM1 (advanced: `BDTR.MOE`) | TIM3 (QEMU models TIM2-5 only) |
//! | 2 ms control period interrupt | TIM7 (basic timer, 84 MHz) | TIM5 (QEMU's timers count at 1 GHz) |
//! | encoders x, y, L, alpha, beta | TIM2, TIM3, TIM4, TIM5, TIM8 (encoder mode) | simulated plant |

use crate::debug_freeze;
use crate::watchdog::IwdgConfig;
use core::ptr::{read_volatile, write_volatile};
use crane_twin::logic::io::PWM_MAX;
use crane_twin::preload::PreloadedTimer;

/// TIM1 (APB2).
pub const TIM1: usize = 0x4001_0000;
/// TIM2 (APB1).
pub const TIM2: usize = 0x4000_0000;
/// TIM3 (APB1).
pub const TIM3: usize = 0x4000_0400;
/// TIM4 (APB1).
pub const TIM4: usize = 0x4000_0800;
/// TIM5 (APB1).
pub const TIM5: usize = 0x4000_0C00;
/// TIM7 (APB1).
pub const TIM7: usize = 0x4000_1400;
/// TIM8 (APB2).
pub const TIM8: usize = 0x4001_0400;
/// USART2 (the log line; QEMU's second serial port).
pub const USART2: usize = 0x4000_4400;
/// DBGMCU APB1 freeze register.
pub const DBGMCU_APB1_FZ: usize = 0xE004_2008;
/// DBGMCU APB2 freeze register.
pub const DBGMCU_APB2_FZ: usize = 0xE004_200C;
/// GPIOB (the safety inputs, [`crate::safety_pins`]).
pub const GPIOB: usize = 0x4002_0400;
/// GPIOC (driver enable PC8, brake release PC13, direction pins PC0-PC5).
pub const GPIOC: usize = 0x4002_0800;
/// Independent watchdog.
pub const IWDG: usize = 0x4000_3000;
/// RCC reset and clock control (`RCC_CSR` at +0x74).
pub const RCC: usize = 0x4002_3800;

// Timer register offsets.
const CR1: usize = 0x00;
const DIER: usize = 0x0C;
const SR: usize = 0x10;
const EGR: usize = 0x14;
const CCMR1: usize = 0x18;
const CCMR2: usize = 0x1C;
const CCER: usize = 0x20;
const CNT: usize = 0x24;
const PSC: usize = 0x28;
const ARR: usize = 0x2C;
const CCR1: usize = 0x34;
const BDTR: usize = 0x44;

/// The board's PWM timer.
pub const BOARD_PWM_TIM: usize = TIM1;
/// The board's period timer.
pub const BOARD_PERIOD_TIM: usize = TIM7;
/// The QEMU build's PWM timer (QEMU models TIM2-5 only).
pub const QEMU_PWM_TIM: usize = TIM3;
/// The QEMU build's period timer.
pub const QEMU_PERIOD_TIM: usize = TIM5;
/// The PWM timer of this build.
#[cfg(feature = "board")]
pub const PWM_TIM: usize = BOARD_PWM_TIM;
/// The PWM timer of this build.
#[cfg(not(feature = "board"))]
pub const PWM_TIM: usize = QEMU_PWM_TIM;
/// The period timer of this build.
#[cfg(feature = "board")]
pub const PERIOD_TIM: usize = BOARD_PERIOD_TIM;
/// The period timer of this build.
#[cfg(not(feature = "board"))]
pub const PERIOD_TIM: usize = QEMU_PERIOD_TIM;
/// Control period [us].
pub const PERIOD_US: u32 = 2_000;
/// Clock of the period timer [Hz]: APB1 timers at 2 x 42 MHz on the board; QEMU's STM32F2xx
/// timer model counts at a fixed 1 GHz (`clock-frequency` of its SoC), whatever RCC says.
#[cfg(feature = "board")]
pub const PERIOD_TIM_HZ: u32 = 84_000_000;
/// Clock of the period timer [Hz] (see the board variant).
#[cfg(not(feature = "board"))]
pub const PERIOD_TIM_HZ: u32 = 1_000_000_000;
/// Encoder counters x, y, L, alpha, beta (board only).
pub const ENCODER_TIMS: [usize; 5] = [TIM2, TIM3, TIM4, TIM5, TIM8];

fn wr(addr: usize, v: u32) {
    // SAFETY: callers pass a peripheral register address of this chip (constants above plus
    // RM0090 offsets); a 32-bit volatile store has no other effect on memory.
    unsafe { write_volatile(addr as *mut u32, v) }
}

fn rd(addr: usize) -> u32 {
    // SAFETY: as in `wr`, a volatile load of a peripheral register.
    unsafe { read_volatile(addr as *const u32) }
}

/// The safe state, first thing of the panic and HardFault handlers and of a supervisor trip:
/// main output off (TIM1 `BDTR.MOE`), compare registers 0 made effective by an update event,
/// channel outputs disabled, driver enable low, hoist brake applied. Uses no HAL object, no
/// stack beyond its frame, no lock; idempotent.
pub fn force_safe() {
    #[cfg(feature = "board")]
    wr(PWM_TIM + BDTR, 0);
    for ch in 0..3 {
        wr(PWM_TIM + CCR1 + 4 * ch, 0);
    }
    wr(PWM_TIM + EGR, 1);
    wr(PWM_TIM + CCER, 0);
    // BSRR upper half resets: PC8 (driver enable), PC13 (brake release), PC0-PC5 (IN1/IN2).
    #[cfg(feature = "board")]
    wr(GPIOC + 0x18, ((1 << 8) | (1 << 13) | 0x3F) << 16);
}

/// The PWM compare registers CCR1-CCR3 and CCER as read back (for the QEMU checks).
pub fn pwm_readback() -> ([u32; 3], u32) {
    (
        [
            rd(PWM_TIM + CCR1),
            rd(PWM_TIM + CCR1 + 4),
            rd(PWM_TIM + CCR1 + 8),
        ],
        rd(PWM_TIM + CCER),
    )
}

/// The three-channel PWM timer: PWM mode 1, preloaded compares and auto-reload, full scale
/// [`PWM_MAX`] ticks (40 kHz at 168 MHz, no prescaler). On the board the HAL has enabled its
/// clock and routed the pins first.
#[derive(Debug)]
pub struct PwmTimer(());

impl PwmTimer {
    /// Configures and starts the PWM timer with every compare at 0.
    pub fn init() -> Self {
        let oc_pwm1_preload = (0b110 << 4) | (1 << 3);
        wr(PWM_TIM + CR1, 0);
        wr(PWM_TIM + PSC, 0);
        wr(PWM_TIM + ARR, u32::from(PWM_MAX) - 1);
        wr(PWM_TIM + CCMR1, oc_pwm1_preload | (oc_pwm1_preload << 8));
        wr(PWM_TIM + CCMR2, oc_pwm1_preload);
        for ch in 0..3 {
            wr(PWM_TIM + CCR1 + 4 * ch, 0);
        }
        wr(PWM_TIM + EGR, 1);
        wr(PWM_TIM + CCER, 1 | (1 << 4) | (1 << 8));
        #[cfg(feature = "board")]
        wr(PWM_TIM + BDTR, 1 << 15);
        // ARPE | CEN
        wr(PWM_TIM + CR1, (1 << 7) | 1);
        PwmTimer(())
    }
}

impl PreloadedTimer for PwmTimer {
    fn max_compare(&self) -> u16 {
        PWM_MAX
    }
    fn set_compare(&mut self, ch: usize, value: u16) {
        if ch < 3 {
            wr(PWM_TIM + CCR1 + 4 * ch, u32::from(value));
        }
    }
    fn force_update(&mut self) {
        wr(PWM_TIM + EGR, 1);
    }
}

/// Starts the period timer: an update interrupt every `period_us` microseconds.
pub fn start_period_timer(period_us: u32) {
    wr(PERIOD_TIM + CR1, 0);
    wr(PERIOD_TIM + PSC, PERIOD_TIM_HZ / 1_000_000 - 1);
    wr(PERIOD_TIM + ARR, period_us - 1);
    wr(PERIOD_TIM + EGR, 1);
    wr(PERIOD_TIM + SR, 0);
    wr(PERIOD_TIM + DIER, 1);
    wr(PERIOD_TIM + CR1, 1);
}

/// Acknowledges the period timer's update interrupt; `true` if it was pending.
pub fn ack_period_timer() -> bool {
    let pending = rd(PERIOD_TIM + SR) & 1 != 0;
    wr(PERIOD_TIM + SR, 0);
    pending
}

/// The five encoder counters' low 16 bits (board; extended to `i32` by the loop).
pub fn encoder_counts() -> [u16; 5] {
    ENCODER_TIMS.map(|t| rd(t + CNT) as u16)
}

/// Freezes every timer and the watchdog while a debugger halts the core (DBGMCU): the PWM
/// timer TIM1 then also disables its outputs (RM0090 32.16: as after a break event), the
/// period timer stops ticking and the watchdog does not reset a halted core.
pub fn freeze_timers_in_debug() {
    wr(
        DBGMCU_APB1_FZ,
        rd(DBGMCU_APB1_FZ) | debug_freeze::APB1_FREEZE,
    );
    wr(
        DBGMCU_APB2_FZ,
        rd(DBGMCU_APB2_FZ) | debug_freeze::APB2_FREEZE,
    );
}

/// The safety inputs' port: `GPIOB_IDR` (board; decoded by
/// [`crate::safety_pins::inputs_from_idr`]).
pub fn safety_port() -> u32 {
    rd(GPIOB + 0x10)
}

/// `RCC_CSR` (the reset flags).
pub fn rcc_csr() -> u32 {
    rd(RCC + 0x74)
}

/// Clears the reset flags (`RCC_CSR.RMVF`).
pub fn clear_reset_flags() {
    wr(RCC + 0x74, rd(RCC + 0x74) | (1 << 24));
}

// IWDG registers and keys (RM0090 21.4).
const IWDG_KR: usize = IWDG;
const IWDG_PR: usize = IWDG + 0x04;
const IWDG_RLR: usize = IWDG + 0x08;
const IWDG_SR: usize = IWDG + 0x0C;

/// Starts the independent watchdog with `cfg` (it cannot be stopped again): start key (which
/// also starts the LSI), unlock, prescaler and reload, wait (bounded) until both are taken over
/// in the LSI domain, reload.
pub fn watchdog_start(cfg: IwdgConfig) {
    wr(IWDG_KR, 0xCCCC);
    wr(IWDG_KR, 0x5555);
    wr(IWDG_PR, u32::from(cfg.pr));
    wr(IWDG_RLR, u32::from(cfg.rlr));
    // PVU | RVU clear: a few LSI periods (<= 0.4 ms); bounded in case the LSI never starts
    // (the counter then never runs either, and the board has no watchdog: logged by `main`).
    let mut n = 0u32;
    while rd(IWDG_SR) & 0b11 != 0 && n < 1_000_000 {
        n += 1;
    }
    watchdog_feed();
}

/// Reloads the independent watchdog's counter.
pub fn watchdog_feed() {
    wr(IWDG_KR, 0xAAAA);
}

/// Sends the next byte on the log USART from its interrupt: `next` is asked for a byte only
/// when the transmit register is empty; with none left the interrupt is switched off.
pub fn usart_tx_interrupt(next: impl FnOnce() -> Option<u8>) {
    if rd(USART2) & (1 << 7) == 0 {
        return;
    }
    match next() {
        Some(b) => wr(USART2 + 4, u32::from(b)),
        None => usart_tx_interrupt_enable(false),
    }
}

/// Switches the log USART's transmit-empty interrupt (`CR1.TXEIE`) on or off.
pub fn usart_tx_interrupt_enable(on: bool) {
    let cr1 = rd(USART2 + 0x0C) & !(1 << 7);
    wr(USART2 + 0x0C, cr1 | (u32::from(on) << 7));
}

/// Blocking write of bytes to the log USART from a fault handler (no HAL object). Bounded:
/// gives up on a byte after 100,000 polls of `TXE`.
pub fn usart_write_raw(bytes: &[u8]) {
    for &b in bytes {
        let mut n = 0u32;
        while rd(USART2) & (1 << 7) == 0 && n < 100_000 {
            n += 1;
        }
        wr(USART2 + 4, u32::from(b));
    }
}
