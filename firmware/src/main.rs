//! The crane twin on a Cortex-M4F, run under QEMU (`mps2-an386`) with the plant simulated by
//! the model itself. It prints, through semihosting:
//! 1. the bit-exact cross-check digests of the scenarios in f64, f32 and [`F32x`] (f32 with
//!    FPU-only sine/cosine) (`BEGIN`/`S`/`END`),
//!    which `host-tests/tests/qemu_cross.rs` regenerates on the host and compares;
//! 2. the closed loop (observer + feedforward + PD) on the simulated board, driven through the
//!    embedded-hal traits, f64, f32 and `F32x` (`LBEGIN`/`L`/`LEND`/`LSTAT`);
//! 3. cost sections (`BENCH label n`): each of the `n` measured intervals is bracketed by
//!    calls to [`bench_start`] and [`bench_stop`], which the instruction-counting QEMU plugin
//!    of `scripts/firmware-costs.sh` watches;
//! 4. the stack high-water marks (`STACK`), from a painted stack;
//! 5. the friction monitor's frames on its rig (`MBEGIN`/`MALARM`/`MSUM`/`MMAP`/`MEND`), also
//!    compared with the host, and its RAM (`RAM monitor`).
//!
//! Exit code 0 when everything ran, 1 if a section failed to start.
#![no_std]
#![no_main]

use core::fmt::Write;
use cortex_m_rt::entry;
use cortex_m_semihosting::debug;
#[cfg(not(feature = "probe"))]
use cortex_m_semihosting::hio;
use crane_model::{dynamics, Config, Crane, Law, Mode, Params, Real, MAX_SEGMENTS};
use crane_twin::board::SimBus;
use crane_twin::logic::control::{Controller, LoopConfig, DEMO, F64_SEGMENT_BUDGET};
use crane_twin::logic::fastmath::F32x;
use crane_twin::logic::monitor::Monitor;
use crane_twin::logic::monitor_rig::{check_periods, run_check, Event};
use crane_twin::logic::plant::{demo_init, demo_plant, demo_twin_init, run_demo_with};
use crane_twin::logic::scenarios::{run, InputGen, Scenario, SCENARIOS};
#[cfg(feature = "probe")]
use defmt_rtt as _;
#[cfg(feature = "probe")]
use panic_probe as _;
#[cfg(not(feature = "probe"))]
use panic_semihosting as _;

/// Start of a measured interval (watched by the instruction-counting plugin).
#[inline(never)]
#[no_mangle]
pub extern "C" fn bench_start() {
    cortex_m::asm::nop();
}

/// End of a measured interval (watched by the instruction-counting plugin). Its body differs
/// from [`bench_start`]'s so the linker cannot fold the two into one address.
#[inline(never)]
#[no_mangle]
pub extern "C" fn bench_stop() {
    cortex_m::asm::nop();
    cortex_m::asm::nop();
}

/// The transcript, one line at a time: semihosting stdout (QEMU, CI), or with the `probe`
/// feature a defmt frame per line over RTT (a real board: semihosting would halt the core
/// without a debugger).
struct Out {
    buf: [u8; 512],
    len: usize,
    #[cfg(not(feature = "probe"))]
    stream: Option<hio::HostStream>,
}

impl Out {
    fn new() -> Self {
        Out {
            buf: [0; 512],
            len: 0,
            #[cfg(not(feature = "probe"))]
            stream: hio::hstdout().ok(),
        }
    }

    #[cfg(not(feature = "probe"))]
    fn flush(&mut self) {
        if let Some(s) = self.stream.as_mut() {
            let _ = s.write_all(&self.buf[..self.len]);
        }
        self.len = 0;
    }

    #[cfg(feature = "probe")]
    fn flush(&mut self) {
        let line = self.buf.get(..self.len).unwrap_or(&[]);
        let line = line.strip_suffix(b"\n").unwrap_or(line);
        defmt::println!("{=[u8]:a}", line);
        self.len = 0;
    }
}

impl Write for Out {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        for &b in s.as_bytes() {
            if self.len == self.buf.len() {
                self.flush();
            }
            self.buf[self.len] = b;
            self.len += 1;
            if b == b'\n' {
                self.flush();
            }
        }
        Ok(())
    }
}

/// The stack window painted to measure the high-water mark.
const PAINT_BYTES: usize = 64 * 1024;
const PAINT: u32 = 0xDEAD_BEEF;

/// Paints `PAINT_BYTES` of stack below the current frame (leaving 256 bytes of margin).
fn paint_stack() -> (usize, usize) {
    let sp = cortex_m::register::msp::read() as usize;
    let top = (sp - 256) & !3;
    let bottom = top - PAINT_BYTES;
    let mut p = bottom;
    while p < top {
        // SAFETY: [bottom, top) lies below the live stack frames (256 bytes under the current
        // stack pointer) inside the 4 MiB RAM of the board, above .bss (checked in main).
        unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
    (bottom, sp)
}

/// Bytes of stack used below `sp0` since [`paint_stack`] (the lowest overwritten word).
fn stack_used(window: (usize, usize)) -> usize {
    let (bottom, sp0) = window;
    let mut p = bottom;
    // SAFETY: the same window that paint_stack wrote.
    while p < sp0 && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    sp0 - p
}

/// Loop settings of the f64 twin: the library defaults with the real-time segment budget.
fn f64_loop() -> LoopConfig {
    LoopConfig {
        segment_budget: F64_SEGMENT_BUDGET,
        ..LoopConfig::default()
    }
}

/// Closed loop on the simulated board (embedded-hal path): 4000 periods of 2 ms. Never
/// inlined, so its frame (the board, plant and controller) is below the painted window.
#[inline(never)]
fn closed_loop<R: Real>(tag: &str, cfg: &LoopConfig, out: &mut Out) -> bool {
    let Ok(plant) = demo_plant() else {
        return false;
    };
    let bus = SimBus::new(plant);
    let mut io = bus.io();
    match run_demo_with::<R, _, _>(&mut io, cfg, tag, out) {
        Ok(Some(_summary)) => {
            // The loop's records as structured defmt values (`crane-twin/defmt`).
            #[cfg(feature = "probe")]
            defmt::println!("loop {=str}: counters {}", tag, _summary.counters);
            true
        }
        _ => false,
    }
}

/// Cost of `Crane::<R>::step` with segment budget `budget` over a scenario, one interval per
/// step.
fn bench_model<R: Real>(tag: &str, sc: &Scenario, budget: usize, out: &mut Out) -> bool {
    let Ok(mut crane) = sc.crane::<R>().and_then(|c| c.with_segment_budget(budget)) else {
        return false;
    };
    let _ = writeln!(out, "BENCH model_step_{tag}_{} {}", sc.name, sc.steps);
    let mut gen = InputGen::new(sc);
    for k in 0..sc.steps {
        let u = gen.input(sc, k).map(R::from_f64);
        bench_start();
        let r = crane.step(u);
        bench_stop();
        core::hint::black_box(r.ok());
    }
    true
}

/// Cost of setting the twin to a corrected state (`Crane::set_state`, what the observer does
/// every period), and, for comparison, of rebuilding it (`Crane::new`, what it did before).
fn bench_set_state<R: Real>(tag: &str, n: u32, out: &mut Out) -> bool {
    let params = Params::default();
    let config = Config {
        h: 2e-3,
        ..Config::default()
    };
    let Ok(mut twin) = Crane::<R>::new(&params, config, demo_init()) else {
        return false;
    };
    let mut ok = true;
    let _ = writeln!(out, "BENCH twin_set_state_{tag} {n}");
    for k in 0..n {
        let mut s = demo_init();
        s.qd[0] = f64::from(k) * 1e-3;
        bench_start();
        let r = twin.set_state(core::hint::black_box(s));
        bench_stop();
        ok &= r.is_ok();
    }
    let _ = writeln!(out, "BENCH twin_rebuild_{tag} {n}");
    for k in 0..n {
        let mut s = demo_init();
        s.qd[0] = f64::from(k) * 1e-3;
        bench_start();
        let c = Crane::<R>::new(&params, config, core::hint::black_box(s));
        bench_stop();
        ok &= c.is_ok();
    }
    ok
}

/// Cost of one evaluation of the dynamics (`dynamics::eval`: mass matrix, forces, 5x5 solve),
/// the unit of the model's work bound (at most 108 per step, NUMERICS.md).
fn bench_eval<R: Real>(tag: &str, n: u32, out: &mut Out) -> bool {
    let Ok(crane) = Crane::<R>::new(&Params::default(), Config::default(), demo_init()) else {
        return false;
    };
    let c = crane.coeffs();
    let modes = [Mode::Positive, Mode::Negative, Mode::Positive];
    let _ = writeln!(out, "BENCH eval_{tag} {n}");
    let mut ok = true;
    for k in 0..n {
        let mut s = crane.state();
        s.q[3] = R::from_f64(1.5 + f64::from(k) * 1e-3);
        s.qd[0] = R::from_f64(0.1);
        s.qd[1] = R::from_f64(-0.1);
        s.qd[2] = R::from_f64(0.05);
        let u = [R::from_f64(3.0); 3];
        bench_start();
        let e = dynamics::eval(c, Law::Hybrid, &s, &modes, &u);
        bench_stop();
        ok &= core::hint::black_box(e).is_ok();
    }
    ok
}

/// Cost of one full control period (reference, encoders, observer with its model step,
/// feedforward, PD, PWM write), on the simulated board; the plant's own step is outside.
/// Never inlined (its frame counts in the stack figure).
#[inline(never)]
fn bench_period<R: Real>(tag: &str, cfg: &LoopConfig, periods: u32, out: &mut Out) -> bool {
    let cfg = *cfg;
    let Ok(plant) = demo_plant() else {
        return false;
    };
    let bus = SimBus::new(plant);
    let mut io = bus.io();
    let Ok(mut ctrl) = Controller::<R>::new(&Params::default(), demo_twin_init(), &cfg) else {
        return false;
    };
    let _ = writeln!(out, "BENCH period_{tag} {periods}");
    for k in 0..periods {
        let t = f64::from(k) * cfg.period;
        bench_start();
        let r = DEMO.at::<R>(t);
        let p = ctrl.run_period(&mut io, &r);
        bench_stop();
        core::hint::black_box(p.command);
        crane_twin::logic::control::Io::wait(&mut io);
    }
    true
}

/// The board's encoder path around an `Io`: the counts are latched when the period starts
/// (in `wait`, as the STM32 board's timer interrupt latches its counters at the tick) and
/// `read` returns the latch. Same counts, same bits; the simulated encoders' arithmetic (a
/// register read on hardware) then falls outside the measured period.
struct Latched<I: crane_twin::logic::control::Io> {
    inner: I,
    counts: [Result<i32, crane_twin::logic::control::IoError>; 5],
}

impl<I: crane_twin::logic::control::Io> crane_twin::logic::control::Io for Latched<I> {
    fn read(&mut self) -> [Result<i32, crane_twin::logic::control::IoError>; 5] {
        self.counts
    }
    fn write(&mut self, u: [f64; 3]) -> Result<[f64; 3], crane_twin::logic::control::IoError> {
        self.inner.write(u)
    }
    fn wait(&mut self) {
        self.inner.wait();
        self.counts = self.inner.read();
    }
}

/// [`bench_period`] with the encoders latched at the tick ([`Latched`]), as on the STM32
/// board: what a board's period costs.
#[inline(never)]
fn bench_period_latched<R: Real>(tag: &str, cfg: &LoopConfig, periods: u32, out: &mut Out) -> bool {
    let cfg = *cfg;
    let Ok(plant) = demo_plant() else {
        return false;
    };
    let bus = SimBus::new(plant);
    let mut inner = bus.io();
    let counts = crane_twin::logic::control::Io::read(&mut inner);
    let mut io = Latched { inner, counts };
    let Ok(mut ctrl) = Controller::<R>::new(&Params::default(), demo_twin_init(), &cfg) else {
        return false;
    };
    let _ = writeln!(out, "BENCH period_{tag}_latched {periods}");
    for k in 0..periods {
        let t = f64::from(k) * cfg.period;
        bench_start();
        let r = DEMO.at::<R>(t);
        let p = ctrl.run_period(&mut io, &r);
        bench_stop();
        core::hint::black_box(p.command);
        crane_twin::logic::control::Io::wait(&mut io);
    }
    true
}

/// The monitor's rig (`MBEGIN`..`MEND`, compared with the host), each monitor update
/// bracketed by the bench markers (`BENCH monitor_<tag> n`).
fn monitor_check<R: Real>(tag: &str, out: &mut Out) -> bool {
    let _ = writeln!(out, "BENCH monitor_{tag} {}", check_periods());
    let mut frames = Out::new();
    matches!(
        run_check::<R, _, _>(tag, &mut frames, |e| match e {
            Event::MonitorStart => bench_start(),
            Event::MonitorEnd => bench_stop(),
            Event::Alarm(..) | Event::Pass(_) | Event::Period { .. } => {}
        }),
        Ok(true)
    )
}

#[entry]
fn main() -> ! {
    let mut out = Out::new();
    let mut ok = true;
    let _ = writeln!(out, "FIRMWARE crane-twin {}", env!("CARGO_PKG_VERSION"));

    let w = paint_stack();
    for sc in SCENARIOS.iter() {
        ok &= run::<f64, _>(sc, "f64", &mut out).is_ok();
        ok &= run::<f32, _>(sc, "f32", &mut out).is_ok();
        ok &= run::<F32x, _>(sc, "f32x", &mut out).is_ok();
    }
    let _ = writeln!(out, "STACK scenarios {}", stack_used(w));

    let w = paint_stack();
    let default = LoopConfig::default();
    ok &= closed_loop::<f64>("f64", &f64_loop(), &mut out);
    let _ = writeln!(out, "STACK loop_f64 {}", stack_used(w));
    let w = paint_stack();
    ok &= closed_loop::<f32>("f32", &default, &mut out);
    let _ = writeln!(out, "STACK loop_f32 {}", stack_used(w));
    let w = paint_stack();
    ok &= closed_loop::<F32x>("f32x", &default, &mut out);
    let _ = writeln!(out, "STACK loop_f32x {}", stack_used(w));

    // The friction monitor on its rig: frames compared with the host's, and the cost of
    // each monitor update (between the bench markers).
    let _ = writeln!(out, "RAM monitor {}", Monitor::RAM_BYTES);
    let w = paint_stack();
    ok &= monitor_check::<f64>("f64", &mut out);
    let _ = writeln!(out, "STACK monitor_f64 {}", stack_used(w));
    let w = paint_stack();
    ok &= monitor_check::<F32x>("f32x", &mut out);
    let _ = writeln!(out, "STACK monitor_f32x {}", stack_used(w));

    let w = paint_stack();
    ok &= bench_period::<f64>("f64", &f64_loop(), 4000, &mut out);
    let _ = writeln!(out, "STACK period_f64 {}", stack_used(w));
    let w = paint_stack();
    ok &= bench_period::<f64>("f64_budget8", &default, 4000, &mut out);
    let _ = writeln!(out, "STACK period_f64_budget8 {}", stack_used(w));
    let w = paint_stack();
    ok &= bench_period::<f32>("f32", &default, 4000, &mut out);
    let _ = writeln!(out, "STACK period_f32 {}", stack_used(w));
    let w = paint_stack();
    ok &= bench_period::<F32x>("f32x", &default, 4000, &mut out);
    let _ = writeln!(out, "STACK period_f32x {}", stack_used(w));
    ok &= bench_period_latched::<F32x>("f32x", &default, 4000, &mut out);
    ok &= bench_period_latched::<f64>("f64", &f64_loop(), 4000, &mut out);
    for sc in [&SCENARIOS[1], &SCENARIOS[3]] {
        ok &= bench_model::<f64>("f64", sc, MAX_SEGMENTS, &mut out);
        ok &= bench_model::<f64>("f64_budget1", sc, 1, &mut out);
        ok &= bench_model::<f32>("f32", sc, MAX_SEGMENTS, &mut out);
        ok &= bench_model::<F32x>("f32x", sc, MAX_SEGMENTS, &mut out);
    }
    ok &= bench_eval::<f64>("f64", 100, &mut out);
    ok &= bench_eval::<f32>("f32", 100, &mut out);
    ok &= bench_eval::<F32x>("f32x", 100, &mut out);
    ok &= bench_set_state::<f64>("f64", 100, &mut out);
    ok &= bench_set_state::<f32>("f32", 100, &mut out);
    ok &= bench_set_state::<F32x>("f32x", 100, &mut out);

    let _ = writeln!(out, "DONE {}", if ok { "ok" } else { "FAILED" });
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}
