//! The QEMU `netduinoplus2` run: the control loop on the simulated rig (the model with
//! perturbed parameters, as in `crane_twin::logic::plant`), released by the TIM5 interrupt,
//! its PWM duties mirrored into TIM3's compare registers, its transcript over USART2. The
//! host regenerates the transcript and compares it bit for bit
//! (`host-tests/tests/stm32_board.rs`).
//!
//! The semihosting command line (`-semihosting-config arg=...`) picks how the run ends:
//! - default: the demonstration loop, then a forced panic (PWM non-zero before it);
//! - `estop`: the e-stop input goes active at period [`ESTOP_AT`]; the run continues 50
//!   periods in the safe state;
//! - `hardfault`: a few periods, then an undefined instruction (HardFault).

use crate::{tick_counts, wait_tick, Log};
use board_stm32::regs::{self, PwmTimer};
use core::cell::RefCell;
use core::fmt::Write;
use cortex_m_semihosting::debug;
use crane_model::State as CraneState;
use crane_twin::logic::control::{Io, IoError, LoopConfig};
use crane_twin::logic::fastmath::F32x;
use crane_twin::logic::io::pwm_command;
use crane_twin::logic::plant::{demo_plant, run_demo_with, SimPlant};
use crane_twin::logic::safety::{Cause, Inputs, State, Supervisor};
use crane_twin::preload::ZeroNowChannel;
use embedded_hal::pwm::SetDutyCycle;
use stm32f4xx_hal::rcc::Rcc;
use stm32f4xx_hal::watchdog::IndependentWatchdog;

/// Period at which the `estop` run activates the e-stop input.
pub const ESTOP_AT: u64 = 1000;

/// How the run ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Panic,
    EStop,
    HardFault,
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
    } else if has(b"estop") {
        Mode::EStop
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
    wdg: &'a mut IndependentWatchdog,
    period: u64,
    estop_at: Option<u64>,
    missed_max: u64,
}

impl SimIo<'_> {
    fn inputs(&self) -> Inputs {
        Inputs {
            estop: self.estop_at.is_some_and(|k| self.period >= k),
            ..Inputs::default()
        }
    }
}

impl Io for SimIo<'_> {
    fn read(&mut self) -> [Result<i32, IoError>; 5] {
        self.plant.read()
    }

    fn write(&mut self, u: [f64; 3]) -> Result<[f64; 3], IoError> {
        // (the supervisor may also have tripped in `wait`: force the safe state whenever
        // it is safe, not only on the transition)
        let state = self.sup.check(&self.inputs(), 0);
        if let State::Safe(_) = state {
            regs::force_safe();
        }
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
        self.wdg.feed();
        let missed = wait_tick();
        self.missed_max = self.missed_max.max(missed);
        self.period += 1;
        self.sup.check(&self.inputs(), missed);
    }

    fn truth(&self) -> Option<CraneState<f64>> {
        Some(self.plant.state())
    }
}

/// The QEMU run; returns the exit code (never returns in the panic and HardFault modes).
pub fn run<W: Write>(_rcc: &mut Rcc, wdg: &mut IndependentWatchdog, log: &mut Log<W>) -> i32 {
    let mode = mode();
    let _ = writeln!(log, "MODE {mode:?}");
    let timer = RefCell::new(PwmTimer::init());
    let Ok(plant) = demo_plant() else {
        return 2;
    };
    let mut sup = Supervisor::new();
    if sup.arm(&Inputs::default()).is_err() {
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
        wdg,
        period: 0,
        estop_at: (mode == Mode::EStop).then_some(ESTOP_AT),
        missed_max: 0,
    };
    if mode == Mode::HardFault {
        for _ in 0..5 {
            let _ = io.write([3.0, -2.0, 1.5]);
            io.wait();
        }
        report_pwm(log, "BEFORE");
        // SAFETY: deliberately executes a permanently undefined instruction: the HardFault
        // handler must leave the PWM at 0 (checked by the host test).
        unsafe { core::arch::asm!("udf #0") };
        return 5;
    }
    let cfg = LoopConfig::default();
    let res = run_demo_with::<F32x, _, _>(&mut io, &cfg, "f32x", log);
    let (ticks, overruns) = tick_counts();
    let _ = writeln!(
        log,
        "TICKS periods={} ticks={ticks} overruns={overruns} missed_max={}",
        io.period, io.missed_max
    );
    let _ = writeln!(log, "SUPERVISOR {:?}", io.sup.state());
    report_pwm(log, "BEFORE");
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
        _ => {
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
