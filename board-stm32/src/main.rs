//! The crane twin on an STM32F405/407 at 168 MHz beside the motor drivers (issue 14).
//!
//! - Clock (`rcc` feature, part of `board`): flash 5 wait states with prefetch and the ART
//!   caches set first, then HSE 8 MHz -> PLL -> 168 MHz (APB1 42 MHz, APB2 84 MHz) through
//!   `stm32f4xx-hal`. QEMU `netduinoplus2` has no RCC model (its registers read 0, so the HAL
//!   would wait for `HSERDY` forever): the default (QEMU) build leaves it out and runs on the
//!   reset clock.
//! - A timer interrupt every 2 ms (TIM7 on the board, TIM5 under QEMU) latches the encoder
//!   counters and releases the period; the loop counts overruns ([`TickLatch`], `u64`).
//! - The twin is `F32x` (f32 with FPU-only sine/cosine); f64 stays the offline reference.
//! - Safety: the supervisor (e-stop, limit switches, driver fault, overruns) gates every
//!   command through `board_stm32::guard`; the panic and HardFault handlers call
//!   [`regs::force_safe`] before anything else (the HardFault entry resets the stack pointer
//!   first: a stack overflow with flip-link's layout faults below RAM); the independent
//!   watchdog (10 ms nominal) is fed once per period while the loop keeps its period, and a
//!   watchdog reset keeps the board safe until power-cycled; DBGMCU freezes the timers while
//!   a debugger halts the core.
//! - Log: text lines over USART2 (115200 8N1); with `probe`, also defmt over RTT.
//!
//! The default build is the QEMU one: the plant is the model itself (`SimPlant`), the PWM
//! duties are mirrored into TIM3's compare registers, and the run ends with a forced panic
//! (or, with a semihosting argument, another path: `src/sim.rs`) so the host tests
//! `host-tests/tests/stm32_board.rs` can check the safe state.
#![no_std]
#![no_main]

#[cfg(feature = "board")]
mod board;
#[cfg(not(feature = "board"))]
mod sim;

use board_stm32::regs::{self, PERIOD_US};
use board_stm32::stack;
#[cfg(feature = "board")]
use board_stm32::txqueue::TxQueue;
use board_stm32::watchdog::{self, ResetCause};
use core::cell::RefCell;
use core::fmt::Write;
use core::panic::PanicInfo;
use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::interrupt::Mutex;
use cortex_m_rt::{entry, exception};
use crane_twin::logic::safety::TickLatch;
#[cfg(feature = "probe")]
use defmt_rtt as _;
use stm32f4xx_hal::pac::{self, interrupt};
use stm32f4xx_hal::prelude::*;

/// The period clock shared with the timer interrupt.
static TICKS: Mutex<RefCell<TickLatch>> = Mutex::new(RefCell::new(TickLatch::new()));
/// Encoder counters latched at the last tick (board).
static LATCHED: Mutex<RefCell<[u16; 5]>> = Mutex::new(RefCell::new([0; 5]));

/// Waits (WFI) for the next tick; returns the periods missed since the previous one taken.
pub fn wait_tick() -> u64 {
    loop {
        let t = cortex_m::interrupt::free(|cs| TICKS.borrow(cs).borrow_mut().take());
        if let Some(missed) = t {
            return missed;
        }
        cortex_m::asm::wfi();
    }
}

/// Ticks and overruns so far.
pub fn tick_counts() -> (u64, u64) {
    cortex_m::interrupt::free(|cs| {
        let t = TICKS.borrow(cs).borrow();
        (t.ticks(), t.overruns())
    })
}

/// Encoder counters latched at the last tick.
pub fn latched_counts() -> [u16; 5] {
    cortex_m::interrupt::free(|cs| *LATCHED.borrow(cs).borrow())
}

/// The period interrupt: latch the encoders, count the tick.
fn on_period_interrupt() {
    if regs::ack_period_timer() {
        #[cfg(feature = "board")]
        let counts = regs::encoder_counts();
        cortex_m::interrupt::free(|cs| {
            #[cfg(feature = "board")]
            {
                *LATCHED.borrow(cs).borrow_mut() = counts;
            }
            TICKS.borrow(cs).borrow_mut().on_tick();
        });
    }
}

#[cfg(feature = "board")]
#[interrupt]
fn TIM7() {
    on_period_interrupt();
}

#[cfg(not(feature = "board"))]
#[interrupt]
fn TIM5() {
    on_period_interrupt();
}

/// The period timer's interrupt line of this build.
#[cfg(feature = "board")]
const PERIOD_IRQ: pac::Interrupt = pac::Interrupt::TIM7;
#[cfg(not(feature = "board"))]
const PERIOD_IRQ: pac::Interrupt = pac::Interrupt::TIM5;

/// The board's log queue, emptied by the USART2 interrupt.
#[cfg(feature = "board")]
static TXQ: Mutex<RefCell<TxQueue<1024>>> = Mutex::new(RefCell::new(TxQueue::new()));

/// Writes into [`TXQ`] and wakes the USART2 interrupt (never blocks; drops what does not fit).
#[cfg(feature = "board")]
pub struct QueuedTx;

#[cfg(feature = "board")]
impl Write for QueuedTx {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        cortex_m::interrupt::free(|cs| {
            if let Ok(mut q) = TXQ.borrow(cs).try_borrow_mut() {
                q.push(s.as_bytes());
                regs::usart_tx_interrupt_enable(true);
            }
        });
        Ok(())
    }
}

/// Log bytes dropped because the queue was full (board).
#[cfg(feature = "board")]
pub fn log_dropped() -> u64 {
    cortex_m::interrupt::free(|cs| TXQ.borrow(cs).borrow().dropped())
}

#[cfg(feature = "board")]
#[interrupt]
fn USART2() {
    cortex_m::interrupt::free(|cs| {
        if let Ok(mut q) = TXQ.borrow(cs).try_borrow_mut() {
            regs::usart_tx_interrupt(|| q.pop());
        }
    });
}

/// Sends what is still queued, blocking (fault handlers, interrupts off).
fn flush_log_queue() {
    #[cfg(feature = "board")]
    cortex_m::interrupt::free(|cs| {
        if let Ok(mut q) = TXQ.borrow(cs).try_borrow_mut() {
            regs::usart_tx_interrupt_enable(false);
            while let Some(b) = q.pop() {
                regs::usart_write_raw(&[b]);
            }
        }
    });
}

/// The log line: USART2 through the HAL; with `probe` each line also as a defmt frame.
pub struct Log<W: Write> {
    uart: W,
    #[cfg(feature = "probe")]
    line: LineBuf,
}

impl<W: Write> Log<W> {
    fn new(uart: W) -> Self {
        Log {
            uart,
            #[cfg(feature = "probe")]
            line: LineBuf::new(),
        }
    }
}

impl<W: Write> Write for Log<W> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        #[cfg(feature = "probe")]
        for part in s.split_inclusive('\n') {
            let _ = self.line.write_str(part);
            if part.ends_with('\n') || self.line.len == self.line.buf.len() {
                defmt::println!("{=[u8]:a}", self.line.as_bytes());
                self.line.len = 0;
            }
        }
        self.uart.write_str(s)
    }
}

#[entry]
fn main() -> ! {
    // Outputs are off at reset (timers disabled, GPIO inputs): nothing to undo first.
    // The free stack painted for its high-water mark (interrupts are still off).
    let layout = stack::Layout::linked();
    stack::paint(&layout);
    // (an opaque store: the compiler cannot fold the static into flash)
    CANARY.store(core::hint::black_box(CANARY_VALUE), Ordering::Relaxed);
    let (Some(dp), Some(mut cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
        fault_stop(b"PANIC peripherals taken twice\r\n");
    };
    // Reset cause (RCC_CSR): after a watchdog reset the supervisor is not armed again, and the
    // flags stay set so that only a power-cycle clears them.
    let csr = regs::rcc_csr();
    let reset = ResetCause::from_rcc_csr(csr);
    if reset.clear_flags {
        regs::clear_reset_flags();
    }
    #[cfg(feature = "rcc")]
    let mut rcc = {
        // Flash latency and the ART accelerator first, before the clock goes up.
        dp.FLASH.acr().modify(|_, w| unsafe {
            w.latency().bits(5);
            w.prften().set_bit();
            w.icen().set_bit();
            w.dcen().set_bit()
        });
        dp.RCC.freeze(
            stm32f4xx_hal::rcc::Config::hse(8.MHz())
                .sysclk(168.MHz())
                .hclk(168.MHz())
                .pclk1(42.MHz())
                .pclk2(84.MHz()),
        )
    };
    #[cfg(not(feature = "rcc"))]
    let mut rcc = dp.RCC.constrain();

    regs::freeze_timers_in_debug();
    let gpioa = dp.GPIOA.split(&mut rcc);
    let Ok(tx) = dp.USART2.tx(gpioa.pa2, 115_200.bps(), &mut rcc) else {
        fault_stop(b"PANIC usart\r\n");
    };
    // The board queues its log and sends it from the USART interrupt (a line never blocks
    // the period); the QEMU build writes through (its USART has no baud-rate delay, and the
    // transcript must be complete).
    #[cfg(feature = "board")]
    let mut log = {
        let _configured: stm32f4xx_hal::serial::Tx<pac::USART2, u8> = tx;
        // SAFETY: the handler only touches the log queue (under a lock) and USART2.
        unsafe {
            cp.NVIC.set_priority(pac::Interrupt::USART2, 0x80);
            cortex_m::peripheral::NVIC::unmask(pac::Interrupt::USART2);
        }
        Log::new(QueuedTx)
    };
    #[cfg(not(feature = "board"))]
    let mut log = Log::new(tx);
    let _ = writeln!(
        log,
        "\r\nBOARD crane-twin {} sysclk={} Hz",
        env!("CARGO_PKG_VERSION"),
        rcc.clocks.sysclk().raw()
    );
    let _ = writeln!(log, "RESET csr={csr:08x} watchdog={}", reset.watchdog);
    let _ = writeln!(
        log,
        "LAYOUT stack={:08x}..{:08x} statics={:08x}..{:08x} reserved={} below_statics={}",
        layout.stack_limit,
        layout.stack_top,
        layout.data_start,
        layout.bss_end,
        layout.reserved(),
        layout.stack_below_statics()
    );

    // The independent watchdog: fed by the period loop only (`guard::at_tick`).
    let _ = dp.IWDG;
    regs::watchdog_start(watchdog::IWDG);
    let _ = writeln!(
        log,
        "IWDG pr={} rlr={} timeout={} us (LSI {}-{} kHz: {}-{} us)",
        watchdog::IWDG.pr,
        watchdog::IWDG.rlr,
        watchdog::IWDG.timeout_us(watchdog::LSI_HZ_TYP),
        watchdog::LSI_HZ_MIN / 1000,
        watchdog::LSI_HZ_MAX / 1000,
        watchdog::IWDG.timeout_us(watchdog::LSI_HZ_MAX),
        watchdog::IWDG.timeout_us(watchdog::LSI_HZ_MIN),
    );

    #[cfg(feature = "board")]
    let code = board::run(board::Parts {
        gpioa: board::GpioA {
            pa0: gpioa.pa0,
            pa1: gpioa.pa1,
            pa6: gpioa.pa6,
            pa7: gpioa.pa7,
            pa8: gpioa.pa8,
            pa9: gpioa.pa9,
            pa10: gpioa.pa10,
            pa15: gpioa.pa15,
        },
        gpiob: dp.GPIOB.split(&mut rcc),
        gpioc: dp.GPIOC.split(&mut rcc),
        tim1: dp.TIM1,
        tim2: dp.TIM2,
        tim3: dp.TIM3,
        tim4: dp.TIM4,
        tim5: dp.TIM5,
        tim7: dp.TIM7,
        tim8: dp.TIM8,
        rcc: &mut rcc,
        nvic: &mut cp.NVIC,
        reset,
        log: &mut log,
    });
    #[cfg(not(feature = "board"))]
    let code = {
        let _ = &mut cp;
        sim::run(&mut rcc, csr, &mut log)
    };
    let _ = writeln!(log, "DONE {code}");
    #[cfg(not(feature = "board"))]
    sim::exit(code);
    #[allow(unreachable_code)]
    loop {
        // The board never leaves `board::run`; keep the watchdog fed only while the loop runs.
        cortex_m::asm::wfi();
    }
}

/// Starts the 2 ms period interrupt.
pub fn start_ticks(nvic: &mut cortex_m::peripheral::NVIC) {
    regs::start_period_timer(PERIOD_US);
    // SAFETY: the handler only touches the tick latch and the period timer, both ready.
    unsafe {
        nvic.set_priority(PERIOD_IRQ, 0x40);
        cortex_m::peripheral::NVIC::unmask(PERIOD_IRQ);
    }
}

/// Safe state, a message on the raw USART, then stop (QEMU: exit with failure; board: wait
/// for the watchdog, whose reset keeps the supervisor safe).
fn fault_stop(msg: &[u8]) -> ! {
    regs::force_safe();
    regs::usart_write_raw(msg);
    report_safe_state();
    #[cfg(not(feature = "board"))]
    sim::exit(1);
    #[allow(unreachable_code)]
    loop {
        cortex_m::asm::nop();
    }
}

/// Writes the PWM registers as read back after the safe state.
fn report_safe_state() {
    let (ccr, ccer) = regs::pwm_readback();
    let mut line = LineBuf::new();
    let _ = writeln!(
        line,
        "SAFE ccr={},{},{} ccer={:x}\r",
        ccr[0], ccr[1], ccr[2], ccer
    );
    regs::usart_write_raw(line.as_bytes());
}

/// A fixed buffer for a line formatted in a fault handler.
struct LineBuf {
    buf: [u8; 96],
    len: usize,
}

impl LineBuf {
    fn new() -> Self {
        LineBuf {
            buf: [0; 96],
            len: 0,
        }
    }
    fn as_bytes(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }
}

impl Write for LineBuf {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        for &b in s.as_bytes() {
            if let Some(slot) = self.buf.get_mut(self.len) {
                *slot = b;
                self.len += 1;
            }
        }
        Ok(())
    }
}

#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    // Outputs off and driver disabled before anything else (formatting could fault).
    regs::force_safe();
    cortex_m::interrupt::disable();
    flush_log_queue();
    let mut line = LineBuf::new();
    let _ = writeln!(line, "PANIC {}\r", info.message());
    regs::usart_write_raw(line.as_bytes());
    #[cfg(feature = "probe")]
    defmt::error!("panic: safe state");
    fault_stop(b"")
}

/// A static in RAM, set at start, whose value the HardFault handler reports: a stack overflow
/// that ran into the statics would have overwritten it (with flip-link it faults first).
pub static CANARY: AtomicU32 = AtomicU32::new(0);
/// The canary's value.
pub const CANARY_VALUE: u32 = 0x5AFE_C0DE;

// The HardFault entry, in assembly, instead of cortex-m-rt's trampoline: before any Rust code
// (which pushes registers) the stack pointer goes back to the top of the stack. After a stack
// overflow (with flip-link: below the start of RAM) the exception is entered with the stack
// pointer below RAM, and the handler's first push would fault again inside HardFault: a
// lockup, with the PWM still running until the watchdog bites. The exception frame is given up
// (this handler never returns).
core::arch::global_asm!(
    ".section .HardFault.user, \"ax\"",
    ".global HardFault",
    ".type HardFault,%function",
    ".thumb_func",
    "HardFault:",
    "ldr r0, ={top}",
    "bic r0, r0, #7",
    "msr msp, r0",
    "b {handler}",
    ".ltorg",
    ".size HardFault, . - HardFault",
    top = sym _stack_start,
    handler = sym hard_fault,
);

extern "C" {
    static _stack_start: u32;
}

/// Any exception or interrupt without a handler of its own (an interrupt enabled by mistake,
/// an NMI): safe state first, like a HardFault (cortex-m-rt's default would spin with the PWM
/// running until the watchdog bites).
#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    regs::force_safe();
    cortex_m::interrupt::disable();
    flush_log_queue();
    let mut line = LineBuf::new();
    let _ = writeln!(line, "UNEXPECTED irq {irqn}\r");
    regs::usart_write_raw(line.as_bytes());
    fault_stop(b"")
}

/// The HardFault handler proper, on a fresh stack: safe state first.
extern "C" fn hard_fault() -> ! {
    regs::force_safe();
    flush_log_queue();
    regs::usart_write_raw(b"HARDFAULT\r\n");
    let mut line = LineBuf::new();
    let _ = writeln!(line, "CANARY {:08x}\r", CANARY.load(Ordering::Relaxed));
    regs::usart_write_raw(line.as_bytes());
    fault_stop(b"")
}
