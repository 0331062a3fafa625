//! The STM32F405 board firmware (`board-stm32`, default build) under QEMU `netduinoplus2`
//! against the host, and its safety paths.
//!
//! The firmware runs the `F32x` twin's closed loop on the simulated rig, each period released
//! by the TIM5 update interrupt, and prints over USART2 (QEMU's second serial port, here the
//! test's stdout) the same `LBEGIN`/`L`/`LEND`/`LSTAT` lines as `run_demo` on the host. QEMU
//! runs with `-icount shift=0,sleep=off` (1 ns per instruction, idle time skipped): the run is
//! deterministic and its virtual 2 ms periods are exact, so the tick and overrun counts are
//! too. Each run ends through a fault path, selected by the semihosting argument:
//! a forced panic (default), a HardFault (`hardfault`) or the e-stop input (`estop`); the
//! firmware reads TIM3's compare registers back (QEMU models TIM2-5; the board's TIM1 is
//! written the same way) and prints them. Further runs drive every safety input, stall the
//! loop (overrun, watchdog feeds) and overflow the stack (flip-link's layout).
//!
//! Run by `scripts/test.sh` after `cargo rustc -p board-stm32 --bin board-stm32 --target
//! thumbv7em-none-eabihf --release -- -C linker=flip-link` ([`BUILD`]); `BOARD_ELF` overrides
//! the ELF's path.

// crane-twin's `defmt` feature (derives only) does not exist in this crate.
#![allow(unexpected_cfgs)]

#[allow(dead_code, clippy::all)]
#[path = "../../twin/src/logic/mod.rs"]
mod logic;

use crane_model::Params;
use host_tests::qemu::{self, QemuRun};
use logic::control::LoopConfig;
use logic::fastmath::F32x;
use logic::monitor::{Monitor, Settings};
use logic::monitor_rig::run_check;
use logic::plant::{demo_plant, run_demo_monitored};
use std::path::PathBuf;
use std::process::{Command, ExitStatus};
use std::time::Duration;

/// Stack budget of the QEMU build's run [bytes]: 24 KiB, half again the high-water mark
/// measured when it was set (15,452 bytes), and at most a fifth of the stack reserved in the
/// 128 KiB of RAM (131,040 bytes: everything but the 32 bytes of statics).
const STACK_BUDGET: usize = 24 * 1024;

/// How to build the ELF these tests run (flip-link as the linker).
const BUILD: &str = "cargo rustc -p board-stm32 --bin board-stm32 --target thumbv7em-none-eabihf \
     --release -- -C linker=flip-link";

fn workspace_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("host-tests sits in the workspace")
        .to_path_buf()
}

fn board_elf() -> PathBuf {
    let elf = std::env::var_os("BOARD_ELF")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            let target = std::env::var_os("CARGO_TARGET_DIR")
                .map(|d| workspace_root().join(d))
                .unwrap_or_else(|| workspace_root().join("target"));
            target.join("thumbv7em-none-eabihf/release/board-stm32")
        });
    assert!(
        elf.is_file(),
        "board ELF not found at {}: build it first with `{BUILD}` \
         (the default features: the QEMU build; `cargo install flip-link` if missing; or \
         point BOARD_ELF at it)",
        elf.display()
    );
    elf
}

/// Runs the board ELF under QEMU netduinoplus2 with semihosting argument `arg`; returns the
/// exit status and USART2's output.
fn run_board(arg: &str) -> (ExitStatus, String) {
    let elf = board_elf();
    let deadline = Duration::from_secs(240);
    let mut qemu = Command::new("qemu-system-arm");
    qemu.args([
        "-machine",
        "netduinoplus2",
        "-display",
        "none",
        "-monitor",
        "none",
        "-serial",
        "null",
        "-serial",
        "stdio",
        "-icount",
        "shift=0,sleep=off",
        "-semihosting-config",
    ])
    .arg(format!("enable=on,target=native,arg=board-stm32,arg={arg}"))
    .arg("-kernel")
    .arg(&elf);
    let QemuRun {
        status,
        stdout: bytes,
        stderr: err,
    } = qemu::run(qemu, deadline);
    let text = String::from_utf8_lossy(&bytes).replace('\r', "");
    assert!(
        !text.is_empty(),
        "no USART output (exit {status})\n--- stderr ---\n{err}"
    );
    (status, text)
}

/// The host's transcript of the `F32x` demonstration loop (what the firmware prints).
fn host_loop() -> String {
    let mut plant = demo_plant().expect("demo plant");
    let mut out = String::new();
    let cfg = LoopConfig::default();
    let mut monitor = Monitor::for_params(&Params::default(), Settings::quick(&cfg));
    run_demo_monitored::<F32x, _, _>(&mut plant, &cfg, &mut monitor, "f32x", &mut out)
        .expect("format");
    run_check::<F32x, _, _>("f32x", &mut out, |_| {}).expect("format");
    out
}

fn loop_lines(text: &str) -> Vec<&str> {
    text.lines()
        .filter(|l| {
            [
                "LBEGIN ", "L ", "LEND ", "LSTAT ", "MBEGIN ", "MALARM ", "MSUM ", "MMAP ", "MEND ",
            ]
            .iter()
            .any(|k| l.starts_with(k))
        })
        .collect()
}

/// The value of `key=` in the first line starting with `prefix`.
fn field<'a>(text: &'a str, prefix: &str, key: &str) -> &'a str {
    let line = text
        .lines()
        .find(|l| l.starts_with(prefix))
        .unwrap_or_else(|| panic!("no `{prefix}` line in:\n{text}"));
    let at = line
        .find(&format!("{key}="))
        .unwrap_or_else(|| panic!("no `{key}=` in `{line}`"));
    line[at + key.len() + 1..]
        .split_whitespace()
        .next()
        .unwrap_or("")
}

fn ccr(text: &str, prefix: &str) -> [u32; 3] {
    triple(text, prefix, "ccr")
}

/// Three comma-separated numbers in `key=` of the first line starting with `prefix`.
fn triple(text: &str, prefix: &str, key: &str) -> [u32; 3] {
    let v: Vec<u32> = field(text, prefix, key)
        .split(',')
        .map(|x| x.parse().expect("ccr value"))
        .collect();
    [v[0], v[1], v[2]]
}

#[test]
#[ignore = "needs qemu-system-arm and the board ELF; run by scripts/test.sh"]
fn stm32_trajectory_matches_host_and_a_forced_panic_zeroes_the_pwm() {
    let (status, fw) = run_board("panic");
    // 1. the twin's trajectory over the UART, bit for bit
    let host = host_loop();
    let (a, b) = (loop_lines(&fw), loop_lines(&host));
    assert_eq!(a.len(), b.len(), "loop transcript lengths differ:\n{fw}");
    for (i, (f, h)) in a.iter().zip(b.iter()).enumerate() {
        assert_eq!(f, h, "line {i} differs (board left, host right)");
    }
    assert_eq!(a.iter().filter(|l| l.starts_with("L ")).count(), 16);
    // the friction monitor ran in the board's period (its 4 map frames match), then its rig
    // with the bump: the same alarm as the host's, at the same period
    assert!(a.iter().filter(|l| l.starts_with("MSUM ")).count() > 4);
    assert_eq!(a.iter().filter(|l| l.starts_with("MEND f32x")).count(), 1);
    assert!(
        a.iter()
            .any(|l| l.starts_with("MALARM ") && l.contains("kind=local_friction axis=X")),
        "{fw}"
    );
    // 2. the timer interrupt drove every period, none overran (deterministic under icount)
    assert_eq!(field(&fw, "TICKS ", "periods"), "4000");
    assert_eq!(field(&fw, "TICKS ", "ticks"), "4000");
    assert_eq!(field(&fw, "TICKS ", "overruns"), "0");
    assert!(fw.contains("SUPERVISOR Run"), "{fw}");
    // the loop fed the watchdog once per period, from the period loop
    assert_eq!(field(&fw, "SUPERVISOR ", "feeds"), "4000");
    // 3. the painted stack's high-water mark over the whole run (4000 periods, the timer
    //    interrupt, the formatting of every line) within its budget
    let used: usize = field(&fw, "STACK ", "used").parse().expect("stack used");
    let reserved: usize = field(&fw, "STACK ", "reserved").parse().expect("reserved");
    assert!(
        used > 1024,
        "the paint was not overwritten at all: {used} bytes"
    );
    // the board's incremental sweep (256 words a period) finds the same mark
    assert_eq!(field(&fw, "STACK ", "swept"), used.to_string());
    assert!(
        used <= STACK_BUDGET,
        "stack high-water mark {used} bytes over the budget {STACK_BUDGET}"
    );
    assert!(
        STACK_BUDGET * 5 <= reserved,
        "budget {STACK_BUDGET} not a fifth of the {reserved} bytes reserved"
    );
    // 4. the forced panic: PWM running before, compare registers and outputs 0 after
    let before = ccr(&fw, "BEFORE ");
    assert!(
        before.iter().any(|&c| c > 0),
        "PWM idle before the panic: {before:?}"
    );
    assert!(fw.contains("PANIC forced for the test"), "{fw}");
    assert_eq!(ccr(&fw, "SAFE "), [0, 0, 0]);
    assert_eq!(field(&fw, "SAFE ", "ccer"), "0");
    assert!(!status.success(), "a panic exits with failure");
}

#[test]
#[ignore = "needs qemu-system-arm and the board ELF; run by scripts/test.sh"]
fn stm32_hardfault_zeroes_the_pwm() {
    let (status, fw) = run_board("hardfault");
    assert!(fw.contains("MODE HardFault"), "{fw}");
    let before = ccr(&fw, "BEFORE ");
    assert!(
        before.iter().all(|&c| c > 0),
        "PWM not driven before: {before:?}"
    );
    assert!(fw.contains("HARDFAULT"), "{fw}");
    assert_eq!(ccr(&fw, "SAFE "), [0, 0, 0]);
    assert_eq!(field(&fw, "SAFE ", "ccer"), "0");
    assert!(!status.success());
}

#[test]
#[ignore = "needs qemu-system-arm and the board ELF; run by scripts/test.sh"]
fn stm32_estop_forces_the_safe_state() {
    let (status, fw) = run_board("estop");
    assert!(fw.contains("MODE EStop"), "{fw}");
    // the loop ran normally up to the e-stop (period 1000): its lines equal the host's
    let host = host_loop();
    let (a, b) = (loop_lines(&fw), loop_lines(&host));
    for k in [0, 250, 500, 750, 1000] {
        let tag = format!("L {k} ");
        let f = a.iter().find(|l| l.starts_with(&tag)).expect("board line");
        let h = b.iter().find(|l| l.starts_with(&tag)).expect("host line");
        assert_eq!(f, h, "period {k}");
    }
    // after it the twin sees no drive (0 V applied): the trajectories part
    let f = a
        .iter()
        .find(|l| l.starts_with("L 1250 "))
        .expect("board line");
    let h = b
        .iter()
        .find(|l| l.starts_with("L 1250 "))
        .expect("host line");
    assert_ne!(f, h, "the e-stop changed nothing");
    assert!(fw.contains("SUPERVISOR Safe(EStop)"), "{fw}");
    assert_eq!(ccr(&fw, "BEFORE "), [0, 0, 0]);
    assert_eq!(field(&fw, "BEFORE ", "ccer"), "0");
    assert!(status.success(), "the e-stop run ends normally:\n{fw}");
}

/// The `INPUT` line of pin `pin` (e.g. `PB8`).
fn input_line<'a>(fw: &'a str, pin: &str) -> &'a str {
    let tag = format!("INPUT {pin} ");
    fw.lines()
        .find(|l| l.starts_with(&tag))
        .unwrap_or_else(|| panic!("no `{tag}` line in:\n{fw}"))
}

#[test]
#[ignore = "needs qemu-system-arm and the board ELF; run by scripts/test.sh"]
fn stm32_every_safety_input_forces_the_safe_state() {
    // e-stop PB0, driver fault PB1, limits X-/X+ PB8/PB9, Y-/Y+ PB10/PB11, L-/L+ PB12/PB13:
    // each alone, through the board's pin decoding, supervisor and `force_safe`
    let (status, fw) = run_board("inputs");
    assert!(fw.contains("MODE Inputs"), "{fw}");
    let expect = [
        ("PB0", "Safe(EStop)".to_string()),
        ("PB1", "Safe(DriverFault)".to_string()),
    ]
    .into_iter()
    .chain((0..6).map(|k| {
        (
            ["PB8", "PB9", "PB10", "PB11", "PB12", "PB13"][k],
            format!(
                "Safe(Limit {{ axis: {}, positive: {} }})",
                k / 2,
                k % 2 == 1
            ),
        )
    }));
    for (pin, state) in expect {
        let line = input_line(&fw, pin);
        let before = triple(line, "INPUT ", "before");
        assert!(
            before.iter().all(|&c| c > 0),
            "{pin}: PWM not driven before: {line}"
        );
        assert!(line.contains(&format!("state={state} ")), "{pin}: {line}");
        // the loop kept commanding for three periods: nothing reached the PWM
        assert_eq!(ccr(line, "INPUT "), [0, 0, 0], "{pin}: {line}");
        assert_eq!(field(line, "INPUT ", "ccer"), "0", "{pin}: {line}");
        // a safe state with the loop alive keeps the watchdog fed (no reset loop)
        assert_eq!(field(line, "INPUT ", "fed"), "3", "{pin}: {line}");
    }
    // every contact open at once (a cut cable): the e-stop is named
    let all = input_line(&fw, "all");
    assert!(all.contains("state=Safe(EStop) "), "{all}");
    assert_eq!(ccr(all, "INPUT "), [0, 0, 0]);
    assert!(status.success(), "{fw}");
}

#[test]
#[ignore = "needs qemu-system-arm and the board ELF; run by scripts/test.sh"]
fn stm32_a_stalled_loop_trips_overrun_and_stops_feeding_the_watchdog() {
    let (status, fw) = run_board("stall");
    assert!(fw.contains("MODE Stall"), "{fw}");
    let line = |missed: &str| {
        fw.lines()
            .find(|l| l.starts_with(&format!("STALL missed={missed} ")))
            .unwrap_or_else(|| panic!("no STALL missed={missed} line in:\n{fw}"))
    };
    // two periods late: tolerated; the timer interrupt counted both overruns
    let ok = line("2");
    assert!(ok.contains("state=Run "), "{ok}");
    assert_eq!(field(ok, "STALL ", "feeds"), "11", "{ok}");
    assert_eq!(field(ok, "STALL ", "overruns"), "2", "{ok}");
    assert!(ccr(ok, "STALL ").iter().all(|&c| c > 0), "{ok}");
    // three: overrun, safe state, and the watchdog is never fed again (on the board it
    // resets the chip 6.8-18.8 ms later and the reset latches `WatchdogReset`)
    let bad = line("3");
    assert!(bad.contains("state=Safe(Overrun) "), "{bad}");
    assert_eq!(field(bad, "STALL ", "feeds"), "0", "{bad}");
    assert_eq!(field(bad, "STALL ", "overruns"), "5", "{bad}");
    assert_eq!(ccr(bad, "STALL "), [0, 0, 0]);
    assert_eq!(field(bad, "STALL ", "ccer"), "0");
    assert!(status.success(), "{fw}");
}

/// A hexadecimal field of the `LAYOUT` line: `key=lo..hi`.
fn range(fw: &str, key: &str) -> (u32, u32) {
    let v = field(fw, "LAYOUT ", key);
    let (lo, hi) = v.split_once("..").expect("lo..hi");
    (
        u32::from_str_radix(lo, 16).expect("hex"),
        u32::from_str_radix(hi, 16).expect("hex"),
    )
}

#[test]
#[ignore = "needs qemu-system-arm and the board ELF; run by scripts/test.sh"]
fn stm32_a_stack_overflow_faults_into_the_safe_state_leaving_the_statics_intact() {
    let (status, fw) = run_board("overflow");
    assert!(fw.contains("MODE Overflow"), "{fw}");
    // flip-link's layout: the stack at the bottom of RAM (0x2000_0000), the statics above it
    let (stack_lo, stack_hi) = range(&fw, "stack");
    let (data_lo, data_hi) = range(&fw, "statics");
    assert!(
        field(&fw, "LAYOUT ", "below_statics") == "true" && stack_hi <= data_lo,
        "the stack is not below .data/.bss: the ELF was not linked with flip-link; \
         build it with `{BUILD}`\n{fw}"
    );
    assert_eq!(
        stack_lo, 0x2000_0000,
        "the stack must end at the start of RAM"
    );
    assert_eq!(
        data_hi, 0x2002_0000,
        "the statics end at the end of the 128 KiB RAM"
    );
    // the runaway recursion: a HardFault (not a lockup, not silent corruption), the safe
    // state, and the canary static intact (a plain link overwrites it on the way down)
    assert!(
        ccr(&fw, "BEFORE ").iter().all(|&c| c > 0),
        "PWM not driven before"
    );
    assert!(fw.contains("OVERFLOW\nHARDFAULT\n"), "{fw}");
    let canary = fw
        .lines()
        .find_map(|l| l.strip_prefix("CANARY "))
        .expect("CANARY line");
    assert_eq!(canary, "5afec0de", "a static was overwritten by the stack");
    assert_eq!(ccr(&fw, "SAFE "), [0, 0, 0]);
    assert_eq!(field(&fw, "SAFE ", "ccer"), "0");
    assert!(!status.success());
}

#[test]
#[ignore = "needs qemu-system-arm and the board ELF; run by scripts/test.sh"]
fn stm32_after_a_watchdog_reset_the_board_stays_safe() {
    // QEMU's RCC reads 0: the firmware adds IWDGRSTF to the reset flags it read
    let (status, fw) = run_board("wdreset");
    assert!(fw.contains("MODE WatchdogReset"), "{fw}");
    let arm = fw
        .lines()
        .find(|l| l.starts_with("ARM "))
        .expect("ARM line");
    assert!(arm.starts_with("ARM Err(WatchdogReset) "), "{arm}");
    // the loop ran its 4000 periods (alive, the watchdog fed every period) with nothing
    // reaching the drives: the trajectory is not the host's driven one
    assert_eq!(field(&fw, "TICKS ", "periods"), "4000");
    assert_eq!(field(&fw, "SUPERVISOR ", "feeds"), "4000");
    assert!(fw.contains("SUPERVISOR Safe(WatchdogReset) "), "{fw}");
    let host = host_loop();
    let (a, b) = (loop_lines(&fw), loop_lines(&host));
    let tag = "L 1000 ";
    let f = a.iter().find(|l| l.starts_with(tag)).expect("board line");
    let h = b.iter().find(|l| l.starts_with(tag)).expect("host line");
    assert_ne!(f, h, "the drives were commanded after a watchdog reset");
    assert_eq!(ccr(&fw, "BEFORE "), [0, 0, 0]);
    assert_eq!(field(&fw, "BEFORE ", "ccer"), "0");
    // and it cannot be re-armed: only a power-cycle clears the latch
    assert!(fw.contains("REARM Err(WatchdogReset)"), "{fw}");
    assert!(status.success(), "{fw}");
}

#[test]
#[ignore = "needs qemu-system-arm and the board ELF; run by scripts/test.sh"]
fn stm32_an_unexpected_interrupt_forces_the_safe_state() {
    let (status, fw) = run_board("irq");
    assert!(fw.contains("MODE UnexpectedIrq"), "{fw}");
    assert!(
        ccr(&fw, "BEFORE ").iter().all(|&c| c > 0),
        "PWM not driven before"
    );
    // USART3 is interrupt 39 (cortex-m-rt's number: negative for core exceptions)
    assert!(fw.contains("UNEXPECTED irq 39\n"), "{fw}");
    assert_eq!(ccr(&fw, "SAFE "), [0, 0, 0]);
    assert_eq!(field(&fw, "SAFE ", "ccer"), "0");
    assert!(!status.success(), "{fw}");
}
