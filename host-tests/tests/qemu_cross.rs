//! The firmware under QEMU against the host model, bit for bit.
//!
//! The scenarios, the observer loop and the digest format live in `twin/src/logic` (plain
//! `core` + `crane_model`), included here verbatim with `#[path]`, so the firmware and this test
//! run the same source. The firmware (built for `thumbv7em-none-eabihf`, run on QEMU's
//! Cortex-M4F `mps2-an386`) prints the digests through semihosting; this test regenerates them
//! on the host and compares the text: the exact bits of all ten state components and the modes
//! every few steps, and an FNV-1a hash over every step's bits, for f64, f32 and `F32x` (f32
//! with FPU-only sine/cosine), for the closed loop (twin state and command bits every
//! period), and the friction monitor's frames on its rig (alarms and maps, `MBEGIN`..`MEND`).
//!
//! Run by `scripts/test.sh` after `cargo build -p firmware --target thumbv7em-none-eabihf
//! --release`; `FIRMWARE_ELF` overrides the ELF's path.

// crane-twin's `defmt` feature (derives only) does not exist in this crate.
#![allow(unexpected_cfgs)]

#[allow(dead_code, clippy::all)]
#[path = "../../twin/src/logic/mod.rs"]
mod logic;

use host_tests::qemu::{self, QemuRun};
use logic::control::{LoopConfig, F64_SEGMENT_BUDGET};
use logic::fastmath::F32x;
use logic::monitor_rig::run_check;
use logic::plant::{demo_plant, run_demo, run_demo_with};
use logic::scenarios::{run, SCENARIOS};
use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;

/// What the firmware prints that the host must reproduce, in the firmware's order.
fn host_digest() -> String {
    let mut out = String::new();
    for sc in SCENARIOS.iter() {
        run::<f64, _>(sc, "f64", &mut out).expect("format");
        run::<f32, _>(sc, "f32", &mut out).expect("format");
        run::<F32x, _>(sc, "f32x", &mut out).expect("format");
    }
    let mut plant = demo_plant().expect("demo plant");
    // The firmware's f64 twin runs with its real-time segment budget.
    let f64_loop = LoopConfig {
        segment_budget: F64_SEGMENT_BUDGET,
        ..LoopConfig::default()
    };
    run_demo_with::<f64, _, _>(&mut plant, &f64_loop, "f64", &mut out).expect("format");
    let mut plant = demo_plant().expect("demo plant");
    run_demo::<f32, _, _>(&mut plant, "f32", &mut out).expect("format");
    let mut plant = demo_plant().expect("demo plant");
    run_demo::<F32x, _, _>(&mut plant, "f32x", &mut out).expect("format");
    // The friction monitor's frames on its rig.
    run_check::<f64, _, _>("f64", &mut out, |_| {}).expect("format");
    run_check::<F32x, _, _>("f32x", &mut out, |_| {}).expect("format");
    out
}

/// The digest lines of a firmware transcript (its other lines are costs and stack figures).
fn digest_lines(text: &str) -> Vec<&str> {
    const KEEP: [&str; 13] = [
        "BEGIN ", "S ", "END ", "ERROR ", "LBEGIN ", "L ", "LEND ", "LSTAT ", "MBEGIN ", "MALARM ",
        "MSUM ", "MMAP ", "MEND ",
    ];
    text.lines()
        .filter(|l| KEEP.iter().any(|k| l.starts_with(k)))
        .collect()
}

fn workspace_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("host-tests sits in the workspace")
        .to_path_buf()
}

/// Runs the firmware under QEMU with a deadline; returns its stdout.
fn run_qemu(elf: &std::path::Path, deadline: Duration) -> String {
    let mut qemu = Command::new("qemu-system-arm");
    qemu.args([
        "-cpu",
        "cortex-m4",
        "-machine",
        "mps2-an386",
        "-nographic",
        "-semihosting-config",
        "enable=on,target=native",
        "-kernel",
    ])
    .arg(elf);
    let QemuRun {
        status,
        stdout,
        stderr: err,
    } = qemu::run(qemu, deadline);
    let text = String::from_utf8(stdout).expect("utf-8 stdout");
    assert!(
        status.success(),
        "firmware exited with {status} under QEMU\n--- stderr ---\n{err}\n--- last stdout lines ---\n{}",
        text.lines().rev().take(10).collect::<Vec<_>>().join("\n")
    );
    text
}

#[test]
#[ignore = "needs qemu-system-arm and the release firmware ELF; run by scripts/test.sh"]
fn firmware_under_qemu_matches_host_bit_for_bit() {
    let elf = std::env::var_os("FIRMWARE_ELF")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            // the target dir cargo used: CARGO_TARGET_DIR if set (relative to the workspace)
            let target = std::env::var_os("CARGO_TARGET_DIR")
                .map(|d| workspace_root().join(d))
                .unwrap_or_else(|| workspace_root().join("target"));
            target.join("thumbv7em-none-eabihf/release/firmware")
        });
    assert!(
        elf.is_file(),
        "firmware ELF not found at {}: build it first with \
         `cargo build -p firmware --target thumbv7em-none-eabihf --release` \
         (or point FIRMWARE_ELF at it)",
        elf.display()
    );
    let fw = run_qemu(&elf, Duration::from_secs(300));
    assert!(
        fw.lines().any(|l| l == "DONE ok"),
        "firmware did not report `DONE ok`"
    );
    let host = host_digest();
    let (a, b) = (digest_lines(&fw), digest_lines(&host));
    for (i, (f, h)) in a.iter().zip(b.iter()).enumerate() {
        assert_eq!(
            f, h,
            "line {i} of the digest differs (firmware left, host right); if the sources changed, \
             rebuild the firmware ELF"
        );
    }
    assert_eq!(
        a.len(),
        b.len(),
        "firmware and host digests differ in length"
    );
    let ends = a.iter().filter(|l| l.starts_with("END ")).count();
    assert_eq!(
        ends,
        3 * SCENARIOS.len(),
        "every scenario in f64, f32, f32x"
    );
    assert_eq!(a.iter().filter(|l| l.starts_with("LEND ")).count(), 3);
    // The monitor's sections (f64 and F32x), each with the bump raised where it is.
    assert_eq!(a.iter().filter(|l| l.starts_with("MEND ")).count(), 2);
    let bumps = a
        .iter()
        .filter(|l| l.starts_with("MALARM ") && l.contains("kind=local_friction axis=X"))
        .count();
    assert_eq!(bumps, 2, "the bump, in f64 and in F32x");
    // the painted stack's high-water marks, each section within the budget
    let stack = stack_figures(&fw);
    assert_eq!(stack.len(), 10, "STACK lines: {stack:?}");
    for (section, bytes) in stack {
        assert!(
            bytes <= FIRMWARE_STACK_BUDGET,
            "stack of `{section}`: {bytes} bytes, over the budget {FIRMWARE_STACK_BUDGET}"
        );
    }
}

/// Stack budget of every section of the firmware [bytes]: 32 KiB, half the window the firmware
/// paints (64 KiB: a figure near it would be saturated, not measured) and a quarter of an
/// STM32F405's 128 KiB of RAM. Measured (`scripts/firmware-costs.sh`, firmware/README.md): at
/// most 20,520 (the f64 closed loop with its report).
const FIRMWARE_STACK_BUDGET: usize = 32 * 1024;

/// The `STACK <section> <bytes>` lines of a firmware transcript.
fn stack_figures(text: &str) -> Vec<(&str, usize)> {
    text.lines()
        .filter_map(|l| l.strip_prefix("STACK "))
        .map(|rest| {
            let (section, bytes) = rest
                .split_once(' ')
                .unwrap_or_else(|| panic!("bad STACK line `{rest}`"));
            let bytes = bytes
                .trim()
                .parse()
                .unwrap_or_else(|_| panic!("bad STACK figure in `{rest}`"));
            (section, bytes)
        })
        .collect()
}

#[test]
fn stack_lines_are_read_with_their_section() {
    let t = "FIRMWARE x\nSTACK loop_f64 20520\nL 0 1\nSTACK period_f32x 15868\n";
    assert_eq!(
        stack_figures(t),
        vec![("loop_f64", 20_520), ("period_f32x", 15_868)]
    );
}

/// The scenarios do exercise the automaton: stick-slip, breakaway, reversals, end stops on
/// every drive axis, and no rejected step (host only, fast).
#[test]
fn scenarios_exercise_every_kind_of_mode_switch() {
    let mut sink = String::new();
    let mut total = logic::scenarios::Summary::default();
    for sc in SCENARIOS.iter() {
        assert!(sc.steps >= 2000, "{}: at least 2000 steps", sc.name);
        assert!(sc.h == 1e-3 || sc.h == 2e-3, "{}: h is 1 or 2 ms", sc.name);
        let s = run::<f64, _>(sc, "f64", &mut sink).expect("format");
        assert_eq!(s.errors, 0, "{}: no rejected step", sc.name);
        assert!(s.events > 0, "{}: events located inside steps", sc.name);
        for i in 0..3 {
            total.breakaways[i] += s.breakaways[i];
            total.stops[i] += s.stops[i];
            total.reversals[i] += s.reversals[i];
            total.limits[i] += s.limits[i];
        }
        match sc.name {
            "stick_slip" => {
                assert!(s.breakaways[0] >= 5 && s.breakaways[1] >= 5, "{s:?}");
                assert!(s.stops[0] >= 5 && s.stops[1] >= 5, "{s:?}");
            }
            "end_stops" => assert!(s.limits.iter().all(|&n| n >= 1), "{s:?}"),
            "rope" => assert!(s.limits[2] >= 1 && s.breakaways[2] >= 3, "{s:?}"),
            "breakaway" => assert!(s.breakaways.iter().all(|&n| n >= 3), "{s:?}"),
            "random" => assert!(s.reversals.iter().all(|&n| n >= 10), "{s:?}"),
            other => panic!("unknown scenario {other}"),
        }
    }
    for i in 0..3 {
        assert!(total.breakaways[i] > 0 && total.stops[i] > 0, "{total:?}");
        assert!(total.reversals[i] > 0 && total.limits[i] > 0, "{total:?}");
    }
}

/// The host digest does not depend on anything but the sources (run twice, same text), and
/// the f32 digests differ from the f64 ones (the tags are not decoration).
#[test]
fn host_digest_is_deterministic() {
    let sc = &SCENARIOS[0];
    let (mut a, mut b, mut c) = (String::new(), String::new(), String::new());
    let sa = run::<f64, _>(sc, "f64", &mut a).expect("format");
    let sb = run::<f64, _>(sc, "f64", &mut b).expect("format");
    let sc32 = run::<f32, _>(sc, "f32", &mut c).expect("format");
    assert_eq!(a, b);
    assert_eq!(sa.hash, sb.hash);
    assert_ne!(sa.hash, sc32.hash);
}
