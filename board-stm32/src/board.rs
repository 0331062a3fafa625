//! The real board: an STM32F405/407 beside three H-bridges (X, Y, rope) and five quadrature
//! encoders. Pin map (a bring-up assumption; change it here):
//!
//! | signal | pin | peripheral |
//! |---|---|---|
//! | PWM X, Y, rope | PA8, PA9, PA10 | TIM1 CH1-CH3 (AF1), 40 kHz, full scale 4200 |
//! | IN1/IN2 X, Y, rope | PC0/PC1, PC2/PC3, PC4/PC5 | push-pull outputs |
//! | driver enable | PC8 | high = enabled |
//! | hoist brake release | PC13 | high = released (spring-applied brake) |
//! | encoder x | PA15, PB3 | TIM2 encoder mode |
//! | encoder y | PA6, PA7 | TIM3 |
//! | encoder L | PB6, PB7 | TIM4 |
//! | encoder alpha | PA0, PA1 | TIM5 |
//! | encoder beta | PC6, PC7 | TIM8 |
//! | e-stop, driver fault | PB0, PB1 | inputs, pull-up; NC contacts to ground: high = active |
//! | limits X-/X+, Y-/Y+, L-/L+ | PB8/PB9, PB10/PB11, PB12/PB13 | same |
//! | log | PA2 | USART2 TX (the Nucleo's ST-LINK virtual COM port) |

use crate::{latched_counts, start_ticks, wait_tick, Log};
use board_stm32::guard;
use board_stm32::regs::{self, PwmTimer};
use board_stm32::safety_pins::inputs_from_idr;
use board_stm32::stack;
use board_stm32::watchdog::ResetCause;
use core::cell::RefCell;
use core::fmt::Write;
use crane_model::Params;
use crane_twin::hal::{DriveSet, HBridge};
use crane_twin::logic::control::{Controller, Io, IoError, LoopConfig, DEMO};
use crane_twin::logic::fastmath::F32x;
use crane_twin::logic::monitor::frame::{write_alarm, write_maps};
use crane_twin::logic::monitor::{Monitor, Settings};
use crane_twin::logic::plant::demo_twin_init;
use crane_twin::logic::safety::{extend_count, Cause, State, Supervisor};
use crane_twin::preload::ZeroNowChannel;
use stm32f4xx_hal::gpio::{gpioa, gpiob, gpioc, AnyPin, Input, Output};
use stm32f4xx_hal::pac;
use stm32f4xx_hal::qei::Qei;
use stm32f4xx_hal::rcc::{Enable, Rcc, Reset};

/// The port A pins the board uses (PA2 went to the USART).
pub struct GpioA {
    pub pa0: gpioa::PA0,
    pub pa1: gpioa::PA1,
    pub pa6: gpioa::PA6,
    pub pa7: gpioa::PA7,
    pub pa8: gpioa::PA8,
    pub pa9: gpioa::PA9,
    pub pa10: gpioa::PA10,
    pub pa15: gpioa::PA15<stm32f4xx_hal::gpio::Alternate<0>>,
}

/// What `main` hands over.
pub struct Parts<'a, W: Write> {
    pub gpioa: GpioA,
    pub gpiob: gpiob::Parts,
    pub gpioc: gpioc::Parts,
    pub tim1: pac::TIM1,
    pub tim2: pac::TIM2,
    pub tim3: pac::TIM3,
    pub tim4: pac::TIM4,
    pub tim5: pac::TIM5,
    pub tim7: pac::TIM7,
    pub tim8: pac::TIM8,
    pub rcc: &'a mut Rcc,
    pub nvic: &'a mut cortex_m::peripheral::NVIC,
    pub reset: ResetCause,
    pub log: &'a mut Log<W>,
}

type Bridge<'a> = HBridge<ZeroNowChannel<'a, PwmTimer>, AnyPin<Output>, AnyPin<Output>>;

/// The board as the loop's I/O.
struct BoardIo<'a> {
    drives: (Bridge<'a>, Bridge<'a>, Bridge<'a>),
    enable: AnyPin<Output>,
    brake: AnyPin<Output>,
    /// The safety inputs (PB0, PB1, PB8-PB13), configured as pull-up inputs and read all at
    /// once through `GPIOB_IDR` ([`regs::safety_port`]).
    _safety_pins: [AnyPin<Input>; 8],
    counts: [i32; 5],
    sup: Supervisor,
}

impl Io for BoardIo<'_> {
    fn read(&mut self) -> [Result<i32, IoError>; 5] {
        let raw = latched_counts();
        for (c, r) in self.counts.iter_mut().zip(raw) {
            *c = extend_count(*c, r);
        }
        self.counts.map(Ok)
    }

    fn write(&mut self, u: [f64; 3]) -> Result<[f64; 3], IoError> {
        // the inputs sampled again right before the outputs (missed periods: see `wait`)
        if let State::Safe(_) = guard::check(&mut self.sup, regs::safety_port(), 0) {
            self.enable.set_low();
            self.brake.set_low();
            return Ok([0.0; 3]);
        }
        let out = self.sup.outputs(u);
        let applied = self.drives.write_all(out.volts);
        if applied.is_err() {
            self.sup.trip(Cause::DriverFault);
            regs::force_safe();
        }
        applied
    }

    fn wait(&mut self) {
        let missed = wait_tick();
        guard::at_tick(&mut self.sup, regs::safety_port(), missed);
    }
}

/// Periods between two map summaries of the friction monitor on the log (a minute at 2 ms).
const MAPS_EVERY: u32 = 30_000;

/// Sets up the timers and pins and runs the `F32x` twin along the demonstration trajectory
/// once the supervisor is armed. Never returns while the loop runs.
pub fn run<W: Write>(p: Parts<'_, W>) -> i32 {
    let Parts {
        gpioa,
        gpiob,
        gpioc,
        tim1,
        tim2,
        tim3,
        tim4,
        tim5,
        tim7,
        tim8,
        rcc,
        nvic,
        reset,
        log,
    } = p;
    // Safe levels on the driver lines before anything is enabled.
    let mut enable = gpioc.pc8.into_push_pull_output().erase();
    let mut brake = gpioc.pc13.into_push_pull_output().erase();
    enable.set_low();
    brake.set_low();
    let dir = [
        gpioc.pc0.into_push_pull_output().erase(),
        gpioc.pc1.into_push_pull_output().erase(),
        gpioc.pc2.into_push_pull_output().erase(),
        gpioc.pc3.into_push_pull_output().erase(),
        gpioc.pc4.into_push_pull_output().erase(),
        gpioc.pc5.into_push_pull_output().erase(),
    ];
    // TIM1: clock, pins, then the register set-up shared with the QEMU build.
    pac::TIM1::enable(rcc);
    pac::TIM1::reset(rcc);
    let _pwm_pins = (
        gpioa.pa8.into_alternate::<1>(),
        gpioa.pa9.into_alternate::<1>(),
        gpioa.pa10.into_alternate::<1>(),
    );
    let _ = tim1;
    let timer = RefCell::new(PwmTimer::init());
    // Encoders (the HAL puts the timers in encoder mode, counting both edges of both channels).
    let _qx = Qei::new(
        tim2,
        (
            gpioa.pa15.into_floating_input(),
            gpiob.pb3.into_floating_input(),
        ),
        rcc,
    );
    let _qy = Qei::new(tim3, (gpioa.pa6, gpioa.pa7), rcc);
    let _ql = Qei::new(tim4, (gpiob.pb6, gpiob.pb7), rcc);
    let _qa = Qei::new(tim5, (gpioa.pa0, gpioa.pa1), rcc);
    let _qb = Qei::new(tim8, (gpioc.pc6, gpioc.pc7), rcc);
    pac::TIM7::enable(rcc);
    pac::TIM7::reset(rcc);
    let _ = tim7;

    let [d0, d1, d2, d3, d4, d5] = dir;
    let mut io = BoardIo {
        drives: (
            HBridge::new(ZeroNowChannel::new(&timer, 0), d0, d1),
            HBridge::new(ZeroNowChannel::new(&timer, 1), d2, d3),
            HBridge::new(ZeroNowChannel::new(&timer, 2), d4, d5),
        ),
        enable,
        brake,
        _safety_pins: [
            gpiob.pb0.into_pull_up_input().erase(),
            gpiob.pb1.into_pull_up_input().erase(),
            gpiob.pb8.into_pull_up_input().erase(),
            gpiob.pb9.into_pull_up_input().erase(),
            gpiob.pb10.into_pull_up_input().erase(),
            gpiob.pb11.into_pull_up_input().erase(),
            gpiob.pb12.into_pull_up_input().erase(),
            gpiob.pb13.into_pull_up_input().erase(),
        ],
        counts: [0; 5],
        sup: Supervisor::new(),
    };
    start_ticks(nvic);
    // Arm only after a clean reset and with every input clear; after a watchdog reset stay
    // safe until power-cycled.
    let inputs = inputs_from_idr(regs::safety_port());
    let armed = reset.arm(&mut io.sup, &inputs);
    let _ = writeln!(log, "ARM {armed:?} inputs={inputs:?}");
    if armed.is_ok() {
        io.enable.set_high();
        io.brake.set_high();
    }
    let cfg = LoopConfig::default();
    let Ok(mut ctrl) = Controller::<F32x>::new(&Params::default(), demo_twin_init(), &cfg) else {
        return 2;
    };
    // The friction monitor: alarms as frames on the log, and to the supervisor (which only
    // reports them unless set to derate); the maps once a minute.
    // (in a static: 6.8 KiB off the stack)
    let Some(monitor) = cortex_m::singleton!(
        : Monitor = Monitor::for_params(&Params::default(), Settings::for_loop(&cfg))
    ) else {
        return 2;
    };
    let mut k: u32 = 0;
    // the stack's high-water mark, 256 words (about 11 us) a period
    let mut stack_use = stack::HighWater::new(stack::Layout::linked());
    loop {
        let t = f64::from(k) * cfg.period;
        let p = ctrl.run_period(&mut io, &DEMO.at::<F32x>(t));
        if let Some(a) = monitor.update(ctrl.observer(), p.predicted) {
            io.sup.alarm();
            let _ = write_alarm(log, &a);
        }
        if k % MAPS_EVERY == MAPS_EVERY - 1 {
            let _ = write_maps(log, monitor);
        }
        let stack = stack_use.step(256);
        if k % 500 == 0 {
            let (ticks, overruns) = crate::tick_counts();
            let _ = writeln!(
                log,
                "P {k} state={:?} ticks={ticks} overruns={overruns} stack={stack} log_dropped={}",
                io.sup.state(),
                crate::log_dropped()
            );
        }
        k = k.wrapping_add(1);
        io.wait();
    }
}
