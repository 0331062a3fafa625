//! The pure parts of the STM32 board firmware (`board-stm32`, built only for the target),
//! included here verbatim with `#[path]`: the safety pins' decoding, the independent
//! watchdog's configuration over the LSI range and the reset-cause latch, the timers a
//! debugger halt freezes, and the board's log queue. QEMU does not model the GPIO, the IWDG
//! or DBGMCU; these are the values the firmware writes and the decisions it takes
//! (`host-tests/tests/stm32_board.rs` runs the rest under QEMU).

// `regs.rs` has the board/QEMU variants behind the crate's `board` feature (absent here:
// the QEMU variants), and register accessors this test never calls.
#![allow(unexpected_cfgs, dead_code)]

#[path = "../../board-stm32/src/debug_freeze.rs"]
mod debug_freeze;
#[path = "../../board-stm32/src/regs.rs"]
mod regs;
#[path = "../../board-stm32/src/safety_pins.rs"]
mod safety_pins;
#[path = "../../board-stm32/src/txqueue.rs"]
mod txqueue;
#[path = "../../board-stm32/src/watchdog.rs"]
mod watchdog;

use crane_twin::logic::safety::{Cause, Inputs, State, Supervisor, SAFE_OUTPUTS};
use safety_pins::{inputs_from_idr, ALL_SAFETY_PINS, DRIVER_FAULT_PIN, ESTOP_PIN, LIMIT_PINS};
use watchdog::{IwdgConfig, ResetCause, IWDG, LSI_HZ_MAX, LSI_HZ_MIN, LSI_HZ_TYP};

// ---- safety pins ---------------------------------------------------------------------------

#[test]
fn each_safety_pin_decodes_to_its_own_input_and_nothing_else() {
    assert_eq!(inputs_from_idr(0), Inputs::default());
    assert_eq!(inputs_from_idr(0).active(), None);
    let mut pins = vec![ESTOP_PIN, DRIVER_FAULT_PIN];
    pins.extend(LIMIT_PINS.iter().flatten());
    // eight distinct port-B pins
    let mut sorted = pins.clone();
    sorted.sort_unstable();
    sorted.dedup();
    assert_eq!(sorted.len(), 8);
    assert!(pins.iter().all(|&p| p < 16));
    assert_eq!(ALL_SAFETY_PINS.count_ones(), 8);
    let e = inputs_from_idr(1 << ESTOP_PIN);
    assert_eq!(
        e,
        Inputs {
            estop: true,
            ..Inputs::default()
        }
    );
    let f = inputs_from_idr(1 << DRIVER_FAULT_PIN);
    assert_eq!(f.active(), Some(Cause::DriverFault));
    assert!(!f.estop);
    for (axis, ends) in LIMIT_PINS.iter().enumerate() {
        for (end, &pin) in ends.iter().enumerate() {
            let i = inputs_from_idr(1 << pin);
            let mut want = Inputs::default();
            want.limits[axis][end] = true;
            assert_eq!(i, want, "PB{pin}");
            assert_eq!(
                i.active(),
                Some(Cause::Limit {
                    axis: axis as u8,
                    positive: end == 1
                })
            );
        }
    }
}

#[test]
fn other_port_b_pins_are_ignored_and_a_cut_cable_reads_as_the_e_stop() {
    // every other pin high (e.g. the encoder PB3, PB6, PB7): nothing active
    assert_eq!(inputs_from_idr(!ALL_SAFETY_PINS).active(), None);
    // every contact open at once: all active, the e-stop named first
    let all = inputs_from_idr(u32::MAX);
    assert!(all.estop && all.driver_fault);
    assert!(all.limits.iter().flatten().all(|&l| l));
    assert_eq!(all.active(), Some(Cause::EStop));
}

// ---- independent watchdog ----------------------------------------------------------------

/// The longest time between two feeds of a healthy loop [us]: it feeds right after taking a
/// tick, and a tick taken late by `MAX_MISSED` periods is still healthy; plus 0.5 ms for the
/// interrupt latency and the period work's variation (the `F32x` period is < 0.6 ms).
fn longest_healthy_feed_gap_us() -> u32 {
    (Supervisor::MAX_MISSED as u32 + 1) * regs::PERIOD_US + 500
}

#[test]
fn the_watchdog_is_about_10_ms_and_never_bites_a_healthy_loop_over_the_lsi_range() {
    // (PR <= 6 and RLR <= 0xFFF hold by construction: `for_timeout_us`, the next test)
    let nominal = IWDG.timeout_us(LSI_HZ_TYP);
    assert!((9_800..=10_200).contains(&nominal), "{nominal} us nominal");
    let gap = longest_healthy_feed_gap_us();
    let mut lsi = LSI_HZ_MIN;
    while lsi <= LSI_HZ_MAX {
        let t = IWDG.timeout_us(lsi);
        // fast LSI: the shortest timeout still outlasts the longest healthy gap
        assert!(
            t > gap,
            "LSI {lsi} Hz: timeout {t} us <= healthy gap {gap} us"
        );
        // slow LSI: a hung loop is reset within 20 ms (10 periods)
        assert!(t <= 20_000, "LSI {lsi} Hz: timeout {t} us");
        lsi += 250;
    }
    assert_eq!(IWDG.timeout_us(LSI_HZ_MAX), 6_808);
    assert_eq!(IWDG.timeout_us(LSI_HZ_MIN), 18_823);
}

#[test]
fn the_finest_prescaler_is_chosen_and_impossible_timeouts_are_refused() {
    // 10 ms: /4 reaches it with 80 counts of 125 us (the HAL would take /64: 5 counts of 2 ms)
    assert_eq!(IWDG, IwdgConfig { pr: 0, rlr: 79 });
    // 1 s needs /8 (4000 counts of 250 us)
    let c = IwdgConfig::for_timeout_us(1_000_000).expect("1 s");
    assert_eq!(c.pr, 1);
    assert_eq!(c.timeout_us(LSI_HZ_TYP), 1_000_000);
    // the longest: /256 x 4096 at 32 kHz = 32.768 s
    assert!(IwdgConfig::for_timeout_us(32_768_000).is_some());
    assert_eq!(IwdgConfig::for_timeout_us(40_000_000), None);
    assert_eq!(IwdgConfig::for_timeout_us(0), None);
}

/// `RCC_CSR`'s reset flags across resets (RM0090 7.3.21): a reset sets its own flag; the
/// flags are cleared by `RMVF` or by a power-on reset only.
struct CsrModel(u32);

const PORRSTF: u32 = 1 << 27;
const PINRSTF: u32 = 1 << 26;

impl CsrModel {
    fn power_on() -> Self {
        CsrModel(PORRSTF | PINRSTF | (1 << 25))
    }
    fn watchdog_reset(&mut self) {
        // the internal reset also pulls NRST: PINRSTF too
        self.0 |= watchdog::RCC_CSR_IWDGRSTF | PINRSTF;
    }
    fn pin_reset(&mut self) {
        self.0 |= PINRSTF;
    }
    /// What the firmware does at start: decode, clear if allowed, arm.
    fn boot(&mut self, inputs: &Inputs) -> (Supervisor, Result<(), Cause>) {
        let cause = ResetCause::from_rcc_csr(self.0);
        if cause.clear_flags {
            self.0 = 0;
        }
        let mut sup = Supervisor::new();
        let armed = cause.arm(&mut sup, inputs);
        (sup, armed)
    }
}

#[test]
fn a_watchdog_reset_keeps_the_board_safe_until_power_cycled() {
    let clear = Inputs::default();
    let mut csr = CsrModel::power_on();
    let (sup, armed) = csr.boot(&clear);
    assert_eq!(armed, Ok(()));
    assert_eq!(sup.state(), State::Run);
    // the loop hangs: the watchdog resets the chip
    csr.watchdog_reset();
    let (mut sup, armed) = csr.boot(&clear);
    assert_eq!(armed, Err(Cause::WatchdogReset));
    assert_eq!(sup.state(), State::Safe(Cause::WatchdogReset));
    assert_eq!(sup.outputs([6.0; 3]), SAFE_OUTPUTS);
    // re-arming in the same run is refused, whatever the inputs
    assert_eq!(sup.arm(&clear), Err(Cause::WatchdogReset));
    assert_eq!(sup.check(&clear, 0), State::Safe(Cause::WatchdogReset));
    // the safe board keeps feeding (alive, outputs driven off: no reset loop)
    assert!(sup.feeds_watchdog());
    // someone presses reset: still a watchdog reset (the flags were kept)
    csr.pin_reset();
    let (_, armed) = csr.boot(&clear);
    assert_eq!(armed, Err(Cause::WatchdogReset));
    // only a power-cycle arms again
    let mut csr = CsrModel::power_on();
    assert_eq!(csr.boot(&clear).1, Ok(()));
    // and a clean boot with an input active stays safe, naming it
    let mut csr = CsrModel::power_on();
    let estop = inputs_from_idr(1 << ESTOP_PIN);
    assert_eq!(csr.boot(&estop).1, Err(Cause::EStop));
}

// ---- debugger halt ---------------------------------------------------------------------------

/// The freeze bit of each timer (RM0090 38.16.4-5): (APB2 register?, bit).
fn freeze_bit(timer: usize) -> (bool, u32) {
    match timer {
        regs::TIM1 => (true, 0),
        regs::TIM8 => (true, 1),
        regs::TIM2 => (false, 0),
        regs::TIM3 => (false, 1),
        regs::TIM4 => (false, 2),
        regs::TIM5 => (false, 3),
        0x4000_1000 => (false, 4), // TIM6
        regs::TIM7 => (false, 5),
        _ => panic!("no freeze bit known for the timer at {timer:#x}"),
    }
}

#[test]
fn a_debugger_halt_freezes_every_timer_in_use_and_the_watchdog() {
    let used = [
        regs::BOARD_PWM_TIM,
        regs::BOARD_PERIOD_TIM,
        regs::QEMU_PWM_TIM,
        regs::QEMU_PERIOD_TIM,
    ]
    .into_iter()
    .chain(regs::ENCODER_TIMS);
    for t in used {
        let (apb2, bit) = freeze_bit(t);
        let mask = if apb2 {
            debug_freeze::APB2_FREEZE
        } else {
            debug_freeze::APB1_FREEZE
        };
        assert_ne!(mask & (1 << bit), 0, "timer at {t:#x} not frozen");
    }
    // DBG_IWDG_STOP: a halted core is not reset under the debugger
    assert_ne!(debug_freeze::APB1_FREEZE & (1 << 12), 0);
    // only defined bits (APB1: TIM2-7, TIM12-14, RTC, WWDG, IWDG, I2C timeouts, CAN;
    // APB2: TIM1, TIM8, TIM9-11)
    let apb1_defined: u32 = 0x1FF | (0b111 << 10) | (0b111 << 21) | (0b11 << 25);
    let apb2_defined: u32 = 0b11 | (0b111 << 16);
    assert_eq!(debug_freeze::APB1_FREEZE & !apb1_defined, 0);
    assert_eq!(debug_freeze::APB2_FREEZE & !apb2_defined, 0);
}

// ---- log queue -------------------------------------------------------------------------------

#[test]
fn the_log_queue_keeps_order_across_the_wrap_and_counts_what_it_drops() {
    let mut q = txqueue::TxQueue::<8>::new();
    assert!(q.is_empty());
    assert_eq!(q.pop(), None);
    assert_eq!(q.push(b"abcde"), 5);
    assert_eq!((q.pop(), q.pop()), (Some(b'a'), Some(b'b')));
    // wraps: 3 left + 5 = 8, full
    assert_eq!(q.push(b"fghij"), 5);
    assert_eq!(q.len(), 8);
    // full: the rest of a line is dropped, not blocked on
    assert_eq!(q.push(b"XYZ"), 0);
    assert_eq!(q.dropped(), 3);
    let mut out = Vec::new();
    while let Some(b) = q.pop() {
        out.push(b);
    }
    assert_eq!(out, b"cdefghij");
    assert!(q.is_empty());
    // a long line into an empty queue: the first N bytes go, the rest counted
    assert_eq!(q.push(b"0123456789"), 8);
    assert_eq!(q.dropped(), 5);
}
