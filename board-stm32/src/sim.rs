//! The QEMU `netduinoplus2` run: the control loop on the simulated rig (the model with
//! perturbed parameters, as in `crane_twin::logic::plant`), released by the TIM5 interrupt,
//! its PWM duties mirrored into TIM3's compare registers, its transcript over USART2. The
//! host regenerates the transcript and compares it bit for bit
//! (`host-tests/tests/stm32_board.rs`).
//!
//! QEMU has no GPIO model: the safety port's word (`GPIOB_IDR` on the board) is synthesised
//! here and goes through the board's code path ([`guard`], the pin decoding, the supervisor,
//! [`regs::force_safe`]); so does the watchdog feed (counted here: QEMU ignores the IWDG).
//!
//! The semihosting command line (`-semihosting-config arg=...`) picks the run:
//! - default: the demonstration loop, then a forced panic (PWM non-zero before it);
//! - `estop`: the e-stop input goes active at period [`ESTOP_AT`]; the loop runs on in the
//!   safe state to the end;
//! - `inputs`: each of the eight safety inputs in turn (arm, drive, input active, one tick);
//! - `stall`: the loop stalls for [`Supervisor::MAX_MISSED`] periods (tolerated), then for
//!   one more (overrun: safe state, the watchdog no longer fed);
//! - `wdreset`: the start after a watchdog reset (QEMU's RCC reads 0: `RCC_CSR.IWDGRSTF` is
//!   added to the word read): the supervisor refuses to arm, the loop runs to the end with
//!   the outputs off and the watchdog fed, and re-arming is refused;
//! - `hardfault`: a few periods, then an undefined instruction (HardFault);
//! - `irq`: a few periods, then an interrupt without a handler (USART3) is enabled and
//!   pended (the default handler);
//! - `overflow`: a few periods, then a runaway recursion (stack overflow: with flip-link a
//!   HardFault at the start of RAM, the statics untouched).

use crate::{tick_counts, wait_tick, Log};
use board_stm32::guard;
use board_stm32::regs::{self, PwmTimer};
use board_stm32::safety_pins::{
    inputs_from_idr, ALL_SAFETY_PINS, DRIVER_FAULT_PIN, ESTOP_PIN, LIMIT_PINS,
};
use board_stm32::stack;
use board_stm32::watchdog::{ResetCause, RCC_CSR_IWDGRSTF};
use core::cell::RefCell;
use core::fmt::Write;
use cortex_m_semihosting::debug;
use crane_model::Params;
use crane_model::State as CraneState;
use crane_twin::logic::control::{Io, IoError, LoopConfig};
use crane_twin::logic::fastmath::F32x;
use crane_twin::logic::io::pwm_command;
use crane_twin::logic::monitor::{Monitor, Settings};
use crane_twin::logic::monitor_rig::run_check;
use crane_twin::logic::plant::{demo_plant, run_demo_monitored, SimPlant};
use crane_twin::logic::safety::{Cause, State, Supervisor};
use crane_twin::preload::ZeroNowChannel;
use embedded_hal::pwm::SetDutyCycle;
use stm32f4xx_hal::rcc::Rcc;

/// Period at which the `estop` run activates the e-stop input.
pub const ESTOP_AT: u64 = 1000;

/// How the run ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Panic,
    EStop,
    Inputs,
    Stall,
    WatchdogReset,
    HardFault,
    UnexpectedIrq,
    Overflow,
}

/// Reads the semihosting command line (QEMU `-semihosting-config arg=...`).
fn mode() -> Mode {
    let mut buf = [0u8; 256];
    // SAFETY: SYS_GET_CMDLINE writes at most `len` bytes into `buf` (NUL-terminated).
    let r = unsafe { cortex_m_semihosting::syscall!(GET_CMDLINE, buf.as_mut_ptr(), buf.len()) };
    if r != 0 {
        return Mode::Panic;
    }
    let end = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
    let line = buf.get(..end).unwrap_or(&[]);
    let has = |w: &[u8]| line.windows(w.len()).any(|x| x == w);
    if has(b"hardfault") {
        Mode::HardFault
    } else if has(b"overflow") {
        Mode::Overflow
    } else if has(b"irq") {
        Mode::UnexpectedIrq
    } else if has(b"estop") {
        Mode::EStop
    } else if has(b"inputs") {
        Mode::Inputs
    } else if has(b"stall") {
        Mode::Stall
    } else if has(b"wdreset") {
        Mode::WatchdogReset
    } else {
        Mode::Panic
    }
}

/// Exits QEMU through semihosting (0 success, else failure).
pub fn exit(code: i32) -> ! {
    debug::exit(if code == 0 {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::nop();
    }
}

/// The simulated rig behind the board's timers.
struct SimIo<'a> {
    plant: SimPlant,
    pwm: [ZeroNowChannel<'a, PwmTimer>; 3],
    sup: Supervisor,
    period: u64,
    estop_at: Option<u64>,
    /// Safety port levels set by the run (on top of the e-stop schedule).
    port: u32,
    missed_max: u64,
    /// Watchdog feeds so far.
    feeds: u64,
}

impl SimIo<'_> {
    /// The safety port's word as the board would read it from `GPIOB_IDR` (bit n = PBn high).
    fn idr(&self) -> u32 {
        let estop = self.estop_at.is_some_and(|k| self.period >= k);
        self.port | (u32::from(estop) << ESTOP_PIN)
    }
}

impl Io for SimIo<'_> {
    fn read(&mut self) -> [Result<i32, IoError>; 5] {
        self.plant.read()
    }

    fn write(&mut self, u: [f64; 3]) -> Result<[f64; 3], IoError> {
        // (the supervisor may also have tripped in `wait`: force the safe state whenever
        // it is safe, not only on the transition)
        let idr = self.idr();
        let state = guard::check(&mut self.sup, idr, 0);
        let out = self.sup.outputs(u);
        let applied = self.plant.write(out.volts)?;
        if state == State::Run {
            for (ch, v) in self.pwm.iter_mut().zip(out.volts) {
                ch.set_duty_cycle(pwm_command(v).duty)
                    .map_err(|_| IoError::Driver(0))?;
            }
        }
        Ok(applied)
    }

    fn wait(&mut self) {
        self.plant.advance();
        let missed = wait_tick();
        self.missed_max = self.missed_max.max(missed);
        self.period += 1;
        let idr = self.idr();
        let (_, fed) = guard::at_tick(&mut self.sup, idr, missed);
        self.feeds += u64::from(fed);
    }

    fn truth(&self) -> Option<CraneState<f64>> {
        Some(self.plant.state())
    }
}

/// The QEMU run; returns the exit code (never returns in the panic and HardFault modes).
/// `csr` is `RCC_CSR` as read at start.
pub fn run<W: Write>(_rcc: &mut Rcc, csr: u32, log: &mut Log<W>) -> i32 {
    let mode = mode();
    let _ = writeln!(log, "MODE {mode:?}");
    let timer = RefCell::new(PwmTimer::init());
    let Ok(plant) = demo_plant() else {
        return 2;
    };
    // the board's arming decision, on the reset flags (a watchdog reset synthesised)
    let csr = if mode == Mode::WatchdogReset {
        csr | RCC_CSR_IWDGRSTF
    } else {
        csr
    };
    let mut sup = Supervisor::new();
    let armed = ResetCause::from_rcc_csr(csr).arm(&mut sup, &inputs_from_idr(0));
    let _ = writeln!(log, "ARM {armed:?} csr={csr:08x}");
    if armed.is_err() && mode != Mode::WatchdogReset {
        return 3;
    }
    let Some(mut cp_nvic) = (unsafe { Some(cortex_m::Peripherals::steal().NVIC) }) else {
        return 4;
    };
    crate::start_ticks(&mut cp_nvic);
    let mut io = SimIo {
        plant,
        pwm: [0, 1, 2].map(|ch| ZeroNowChannel::new(&timer, ch)),
        sup,
        period: 0,
        estop_at: (mode == Mode::EStop).then_some(ESTOP_AT),
        port: 0,
        missed_max: 0,
        feeds: 0,
    };
    match mode {
        Mode::Inputs => return every_input(&mut io, log),
        Mode::Stall => return stall(&mut io, log),
        _ => {}
    }
    if matches!(mode, Mode::HardFault | Mode::Overflow | Mode::UnexpectedIrq) {
        for _ in 0..5 {
            let _ = io.write(DRIVE);
            io.wait();
        }
        report_pwm(log, "BEFORE");
        if mode == Mode::Overflow {
            let _ = writeln!(log, "OVERFLOW");
            return recurse(u32::MAX) as i32;
        }
        if mode == Mode::UnexpectedIrq {
            let irq = stm32f4xx_hal::pac::Interrupt::USART3;
            cortex_m::peripheral::NVIC::pend(irq);
            // SAFETY: deliberately enables an interrupt that has no handler: the default
            // handler must leave the PWM at 0 (checked by the host test).
            unsafe { cortex_m::peripheral::NVIC::unmask(irq) };
            return 9;
        }
        // SAFETY: deliberately executes a permanently undefined instruction: the HardFault
        // handler must leave the PWM at 0 (checked by the host test).
        unsafe { core::arch::asm!("udf #0") };
        return 5;
    }
    let cfg = LoopConfig::default();
    // The friction monitor in a static (6.8 KiB off the stack), quick commissioning.
    let Some(monitor) = cortex_m::singleton!(
        : Monitor = Monitor::for_params(&Params::default(), Settings::quick(&cfg))
    ) else {
        return 2;
    };
    let res = run_demo_monitored::<F32x, _, _>(&mut io, &cfg, monitor, "f32x", log);
    let (ticks, overruns) = tick_counts();
    let _ = writeln!(
        log,
        "TICKS periods={} ticks={ticks} overruns={overruns} missed_max={}",
        io.period, io.missed_max
    );
    let _ = writeln!(log, "SUPERVISOR {:?} feeds={}", io.sup.state(), io.feeds);
    report_pwm(log, "BEFORE");
    let layout = stack::Layout::linked();
    // the full scan, and the board's sweep run to its end: the same figure
    let mut sweep = stack::HighWater::new(layout);
    let swept = (0..1_000).map(|_| sweep.step(256)).last().unwrap_or(0);
    let _ = writeln!(
        log,
        "STACK used={} swept={swept} reserved={}",
        stack::high_water(&layout),
        layout.reserved()
    );
    if !matches!(res, Ok(Some(_))) {
        return 6;
    }
    match mode {
        Mode::EStop => {
            if io.sup.state() == State::Safe(Cause::EStop) {
                0
            } else {
                7
            }
        }
        Mode::WatchdogReset => {
            let rearm = io.sup.arm(&inputs_from_idr(0));
            let _ = writeln!(log, "REARM {rearm:?}");
            if io.sup.state() == State::Safe(Cause::WatchdogReset) {
                0
            } else {
                7
            }
        }
        _ => {
            // The friction monitor's rig with its fault (the firmware's `CHECK`): the alarm
            // frames this CPU prints, compared with the host's.
            if !matches!(run_check::<F32x, _, _>("f32x", log, |_| {}), Ok(true)) {
                return 8;
            }
            // The loop leaves a holding duty on the rope; a panic now must zero it.
            let (ccr, _) = regs::pwm_readback();
            let _ = writeln!(log, "FORCED PANIC");
            panic!("forced for the test, ccr={},{},{}", ccr[0], ccr[1], ccr[2]);
        }
    }
}

fn report_pwm<W: Write>(log: &mut Log<W>, tag: &str) {
    let (ccr, ccer) = regs::pwm_readback();
    let _ = writeln!(
        log,
        "{tag} ccr={},{},{} ccer={ccer:x}",
        ccr[0], ccr[1], ccr[2]
    );
}

/// A command with every bridge driven.
const DRIVE: [f64; 3] = [3.0, -2.0, 1.5];

/// Arms `io` afresh with the outputs re-enabled and every input clear, then drives [`DRIVE`]
/// for `periods` periods.
fn arm_and_drive(io: &mut SimIo<'_>, periods: u32) -> bool {
    io.port = 0;
    io.sup = Supervisor::new();
    let _ = PwmTimer::init();
    if io.sup.arm(&inputs_from_idr(io.idr())).is_err() {
        return false;
    }
    for _ in 0..periods {
        if io.write(DRIVE).is_err() {
            return false;
        }
        io.wait();
    }
    true
}

/// Each safety input alone, through the board's decoding and [`guard`]: armed and driving,
/// the input's pin goes high, one tick; the loop goes on commanding [`DRIVE`]. One `INPUT`
/// line per input: the PWM before, the supervisor state, the PWM read back after.
fn every_input<W: Write>(io: &mut SimIo<'_>, log: &mut Log<W>) -> i32 {
    let mut pins = [ESTOP_PIN, DRIVER_FAULT_PIN, 0, 0, 0, 0, 0, 0];
    for (k, p) in LIMIT_PINS.iter().flatten().enumerate() {
        pins[2 + k] = *p;
    }
    for pin in pins {
        if !arm_and_drive(io, 5) {
            return 8;
        }
        let (before, _) = regs::pwm_readback();
        io.port = 1 << pin;
        io.wait();
        let feeds = io.feeds;
        for _ in 0..3 {
            let _ = io.write(DRIVE);
            io.wait();
        }
        let (ccr, ccer) = regs::pwm_readback();
        let _ = writeln!(
            log,
            "INPUT PB{pin} before={},{},{} state={:?} ccr={},{},{} ccer={ccer:x} fed={}",
            before[0],
            before[1],
            before[2],
            io.sup.state(),
            ccr[0],
            ccr[1],
            ccr[2],
            io.feeds - feeds,
        );
    }
    // every contact open at once (a cut cable): e-stop first
    if !arm_and_drive(io, 5) {
        return 8;
    }
    io.port = ALL_SAFETY_PINS;
    io.wait();
    let (ccr, ccer) = regs::pwm_readback();
    let _ = writeln!(
        log,
        "INPUT all state={:?} ccr={},{},{} ccer={ccer:x}",
        io.sup.state(),
        ccr[0],
        ccr[1],
        ccr[2]
    );
    0
}

/// Busy for `periods` whole periods without taking a tick (a loop that overran).
fn busy_periods(periods: u64) {
    let (t0, _) = tick_counts();
    while tick_counts().0 < t0 + periods {
        cortex_m::asm::nop();
    }
}

/// The loop stalls: first [`Supervisor::MAX_MISSED`] periods (tolerated: still `Run`, still
/// feeding), then one more (`Overrun`: safe state, no feed from then on). `STALL` lines with
/// the state, the missed periods, the feeds in the 10 periods after it and the PWM.
fn stall<W: Write>(io: &mut SimIo<'_>, log: &mut Log<W>) -> i32 {
    if !arm_and_drive(io, 10) {
        return 8;
    }
    for missed in [Supervisor::MAX_MISSED, Supervisor::MAX_MISSED + 1] {
        let _ = io.write(DRIVE);
        // this period's tick has been taken: `missed` more go by before the next is taken
        busy_periods(missed + 1);
        let feeds = io.feeds;
        io.wait();
        let state = io.sup.state();
        for _ in 0..10 {
            let _ = io.write(DRIVE);
            io.wait();
        }
        let (ccr, ccer) = regs::pwm_readback();
        let (_, overruns) = tick_counts();
        let _ = writeln!(
            log,
            "STALL missed={missed} state={state:?} feeds={} overruns={overruns} ccr={},{},{} ccer={ccer:x}",
            io.feeds - feeds,
            ccr[0],
            ccr[1],
            ccr[2],
        );
    }
    0
}

/// A runaway recursion with small frames (about 32 bytes a level: without flip-link it would
/// write over every static on its way down before faulting below RAM).
#[inline(never)]
fn recurse(depth: u32) -> u32 {
    let mut buf = [depth; 4];
    core::hint::black_box(&mut buf);
    if depth == 0 {
        return buf[0];
    }
    recurse(depth - 1).wrapping_add(core::hint::black_box(buf[1]))
}
