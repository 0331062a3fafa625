//! Messy single-axis logs that `tests/strangers.rs` and the real-data transforms do not
//! cover: a very long log at 10 kHz, one very short held-out run beside long ones, runs that
//! never move mixed with runs that do, runs at different sample rates in one data set, a
//! vertical axis logged one direction per run, a coarse encoder whose step is comparable to a
//! slip, and an input recorded past the amplifier's limit.
//!
//! Each data set is synthesised with the project's hybrid drive model
//! (`crane_ident::simulate::simulate_drive`), written to a temporary directory as CSV +
//! `dataset.toml` exactly as a user would, and diagnosed end to end with
//! [`crane_diagnose::diagnose`]. Each test asserts what must hold whatever the rule that
//! produces it: a report or a clear error, physical parameters, no cause named that the truth
//! does not hold, and a bounded run time.
//!
//! `cargo test -p crane-diagnose --test messy_logs -- --nocapture` prints one line per case.

// `!(x <= limit)` on purpose: a NaN must fail the check, not pass it
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crane_diagnose::{diagnose, Cause, DiagnoseError, DiagnoseOptions, Report, Verdict};
use crane_ident::rng::Rng;
use crane_ident::simulate::simulate_drive;
use crane_model::drive::{DriveParams, Motion};
use std::fmt::Write as _;
use std::path::PathBuf;

mod support;
use support::pulses;

/// One run as written: sample period [s], recorded input, recorded position, kind.
struct Log {
    dt: f64,
    u: Vec<f64>,
    x: Vec<f64>,
    kind: &'static str,
}

/// A linear carriage: inertia [kg], dry level [N] (breakaway = kinetic unless `brk`), viscous
/// [N s/m].
fn carriage(inertia: f64, kin: f64, brk: f64, visc: f64) -> DriveParams {
    DriveParams {
        motion: Motion::Linear,
        inertia,
        kinetic_pos: kin,
        kinetic_neg: kin,
        breakaway_pos: brk,
        breakaway_neg: brk,
        viscous_pos: visc,
        viscous_neg: visc,
        ..DriveParams::default()
    }
}

/// The truth simulated on `u` from `x0` at rest, measured with an encoder of step `q` (0:
/// exact) and Gaussian noise `noise` [m].
fn record(
    truth: &DriveParams,
    dt: f64,
    u: &[f64],
    x0: f64,
    q: f64,
    noise: f64,
    rng: &mut Rng,
) -> Vec<f64> {
    let x = simulate_drive(truth, x0, 0.0, dt, u).expect("truth simulates");
    x.iter()
        .map(|&x| {
            let y = x + noise * rng.normal();
            if q > 0.0 {
                (y / q).round() * q
            } else {
                y
            }
        })
        .collect()
}

/// The log most tests use: four trapezoidal pulses of 8-20 N, 0.4 s long with 0.3 s rests,
/// alternating, the truth recorded with an encoder count `q` and no noise.
fn pulse_log(rng: &mut Rng, truth: &DriveParams, dt: f64, q: f64) -> Log {
    let u = pulses(rng, dt, 4, 8.0, 20.0, 0.4, 0.3, 0.0, false);
    let x = record(truth, dt, &u, 0.0, q, 0.0, rng);
    Log {
        dt,
        u,
        x,
        kind: "other",
    }
}

/// A fresh directory per call: tests run in parallel, and two of them may diagnose the same
/// rig under the same name (one removing the directory while the other reads it).
fn tmp(name: &str) -> PathBuf {
    static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("messy_{k}_{name}"))
}

/// Writes the runs (time stamps from 0 at each run's own rate) with this `dataset.toml`
/// head and diagnoses the directory; the directory is removed afterwards.
fn diagnose_logs(name: &str, head: &str, logs: &[Log]) -> (Result<Report, DiagnoseError>, f64) {
    let dir = tmp(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut toml = format!("description = \"messy log {name}\"\n{head}\n");
    for (k, l) in logs.iter().enumerate() {
        let file = format!("run{k}.csv");
        writeln!(toml, "\n[[runs]]\nfile = \"{file}\"\nkind = \"{}\"", l.kind).unwrap();
        let mut csv = String::with_capacity(40 * l.x.len());
        csv.push_str("t,x,u\n");
        for i in 0..l.x.len() {
            writeln!(csv, "{:.7},{},{}", i as f64 * l.dt, l.x[i], l.u[i]).unwrap();
        }
        std::fs::write(dir.join(file), csv).unwrap();
    }
    std::fs::write(dir.join("dataset.toml"), toml).unwrap();
    let started = std::time::Instant::now();
    let out = diagnose(&dir, &DiagnoseOptions::default());
    let secs = started.elapsed().as_secs_f64();
    let _ = std::fs::remove_dir_all(&dir);
    (out, secs)
}

fn line(name: &str, secs: f64, out: &Result<Report, DiagnoseError>) -> String {
    match out {
        Err(e) => format!("{name:<36} {secs:7.2} s  error: {e}"),
        Ok(r) => {
            let mut s = format!(
                "{name:<36} {secs:7.2} s  verdict {} ({:?})",
                r.verdict,
                r.findings.iter().map(|f| f.cause).collect::<Vec<_>>()
            );
            s.push_str(&support::model_line(r));
            for f in &r.findings {
                write!(s, "\n      finding {}: {}", f.cause, f.evidence.note).unwrap();
            }
            if let Some(m) = &r.final_model {
                for f in &m.flags {
                    write!(s, "\n      flag: {f}").unwrap();
                }
            }
            for c in &r.candidates {
                write!(
                    s,
                    "\n      candidate {} score {:.3} supported {} {:?}",
                    c.cause, c.score, c.supported, c.parameters
                )
                .unwrap();
            }
            write!(s, "\n      reason: {}", r.verdict_reason).unwrap();
            s
        }
    }
}

/// Problems of a report's final model against a truth without hidden effects (gain 1): the
/// inertia within `tol` of the truth, dry and viscous levels non-negative and within 2x, no
/// cause named.
fn judge_plain(truth: &DriveParams, r: &Report, tol: f64) -> Vec<String> {
    let mut bad = Vec::new();
    for f in &r.findings {
        bad.push(format!("invented cause {}", f.cause));
    }
    let Some(m) = &r.final_model else {
        bad.push("no final model".into());
        return bad;
    };
    let j = truth.inertia;
    if !(m.inertia > j / tol && m.inertia < j * tol) {
        bad.push(format!(
            "inertia {:.4e} not within x{tol} of {j}",
            m.inertia
        ));
    }
    let fk = truth.breakaway_pos.max(truth.breakaway_neg);
    for (n, v) in [
        ("kinetic_pos", m.kinetic_pos),
        ("kinetic_neg", m.kinetic_neg),
        ("breakaway_pos", m.breakaway_pos),
        ("breakaway_neg", m.breakaway_neg),
    ] {
        if !(v >= 0.0 && v <= 2.0 * fk) {
            bad.push(format!("{n} {v:.4e} outside [0, {:.4e}]", 2.0 * fk));
        }
    }
    let d = truth.viscous_pos.max(truth.viscous_neg);
    for (n, v) in [
        ("viscous_pos", m.viscous_pos),
        ("viscous_neg", m.viscous_neg),
    ] {
        if !(v >= 0.0 && v <= 3.0 * d) {
            bad.push(format!("{n} {v:.4e} outside [0, {:.4e}]", 3.0 * d));
        }
    }
    bad
}

// ---- the cases ---------------------------------------------------------------------------------

/// Two 60 s runs of pulses at 10 kHz (1.2 M rows) recorded from `truth` with a 1 um encoder.
fn long_logs(truth: &DriveParams, rng: &mut Rng) -> Vec<Log> {
    let dt = 1e-4;
    (0..2)
        .map(|_| {
            let mut u = Vec::new();
            while (u.len() as f64) * dt < 60.0 {
                u.extend(pulses(rng, dt, 4, 8.0, 20.0, 0.4, 0.3, 0.0, false));
            }
            u.truncate((60.0 / dt) as usize);
            let x = record(truth, dt, &u, 0.0, 1e-6, 0.0, rng);
            Log {
                dt,
                u,
                x,
                kind: "other",
            }
        })
        .collect()
}

/// A 10 kHz log of 120 s (2 runs of 60 s, 1.2 M rows): a report with nothing invented, in
/// bounded time.
#[test]
fn a_long_10khz_log() {
    let mut rng = Rng::new(11);
    let truth = carriage(2.0, 4.0, 4.0, 8.0);
    let logs = long_logs(&truth, &mut rng);
    let (out, secs) = diagnose_logs(
        "long_10khz",
        "position_unit = \"m\"\ninput_unit = \"N\"",
        &logs,
    );
    println!("{}", line("long_10khz_120s", secs, &out));
    let r = out.expect("a report");
    let bad = judge_plain(&truth, &r, 1.5);
    assert!(bad.is_empty(), "{bad:?}");
    assert_eq!(r.verdict, Verdict::None, "{}", r.verdict_reason);
    // run time is printed (--nocapture), not asserted: a wall-clock bound in a unit test
    // flakes under load; the figures are in the crate docs' "Messy logs" table
}

/// The same 10 kHz x 120 s log with a spring (100 N/m): the baseline is wrong, so every
/// candidate is fitted and simulated on 1.2 M samples.
#[test]
fn a_long_10khz_log_with_a_spring() {
    let mut rng = Rng::new(21);
    let mut truth = carriage(2.0, 4.0, 4.0, 8.0);
    truth.position_force = crane_model::drive::PositionForce::Spring {
        stiffness: 100.0,
        center: 0.0,
    };
    let logs = long_logs(&truth, &mut rng);
    let (out, secs) = diagnose_logs(
        "long_10khz_spring",
        "position_unit = \"m\"\ninput_unit = \"N\"",
        &logs,
    );
    println!("{}", line("long_10khz_120s_spring", secs, &out));
    let r = out.expect("a report");
    assert_eq!(
        r.verdict,
        Verdict::Found(Cause::RestoringForce),
        "{}",
        r.verdict_reason
    );
    for f in &r.findings {
        assert_eq!(f.cause, Cause::RestoringForce, "invented {}", f.cause);
    }
    // run time printed, not asserted (see `a_long_10khz_log`)
}

/// One very short held-out run (10 ms) beside long ones at 2 kHz with a 10 um encoder: the
/// derivative window must not be limited by that run, and the diagnosis must match the one
/// without it. Before: the snippet capped every run's window at 7 samples (17 without it),
/// the inertia came out 1.35 (truth 2) and an `input_delay` of 8 samples (grid edge) was
/// named.
#[test]
fn a_very_short_held_out_run() {
    let mut rng = Rng::new(12);
    let truth = carriage(2.0, 4.0, 4.0, 8.0);
    let dt = 5e-4;
    let q = 1e-5;
    let mut logs: Vec<Log> = (0..4).map(|_| pulse_log(&mut rng, &truth, dt, q)).collect();
    let head = "position_unit = \"m\"\ninput_unit = \"N\"";
    let (ref_out, secs) = diagnose_logs("short_held_ref", head, &logs);
    println!("{}", line("four_long_runs_2kHz", secs, &ref_out));
    // a 10 ms snippet, written as a fifth run and held out by the default split (index 5 would
    // be fitting): put it at index 3 and the fourth long run at index 4
    let u: Vec<f64> = (0..20).map(|i| if i < 5 { 0.0 } else { 15.0 }).collect();
    let x = record(&truth, dt, &u, 0.0, q, 0.0, &mut rng);
    let fourth = logs.pop().unwrap();
    logs.push(Log {
        dt,
        u,
        x,
        kind: "other",
    });
    logs.push(fourth);
    let (out, secs) = diagnose_logs("short_held", head, &logs);
    println!("{}", line("plus_a_10ms_held_out_run", secs, &out));
    let r = out.expect("a report");
    let bad = judge_plain(&truth, &r, 1.3);
    assert!(bad.is_empty(), "{bad:?}");
    let (a, b) = (
        r.final_model.as_ref().unwrap().inertia,
        ref_out.unwrap().final_model.unwrap().inertia,
    );
    assert!(
        (a / b - 1.0).abs() < 0.1,
        "inertia {a} with the short run, {b} without"
    );
}

/// Runs that never leave rest (the input below breakaway) mixed with runs that move, in
/// either order: the default split (every second run held out) puts every resting run on one
/// side. Resting runs fitted: an error that names the moving held-out runs and the fix
/// (before: "the fitting runs never move", although half the data set moves). Resting runs
/// held out: a report that says its held-out score tests no motion.
#[test]
fn resting_runs_mixed_with_moving_runs() {
    let truth = carriage(2.0, 4.0, 5.0, 8.0);
    let dt = 1e-3;
    let head = "position_unit = \"m\"\ninput_unit = \"N\"";
    for rest_first in [false, true] {
        let mut rng = Rng::new(13);
        let logs: Vec<Log> = (0..4)
            .map(|k| {
                let rests = (k % 2 == 0) == rest_first;
                let (lo, hi) = if rests { (1.0, 3.0) } else { (8.0, 20.0) };
                let u = pulses(&mut rng, dt, 4, lo, hi, 0.4, 0.3, 0.0, false);
                let x = record(&truth, dt, &u, 0.0, 1e-6, 0.0, &mut rng);
                Log {
                    dt,
                    u,
                    x,
                    kind: "other",
                }
            })
            .collect();
        let name = if rest_first {
            "resting_runs_fitted"
        } else {
            "resting_runs_held_out"
        };
        let (out, secs) = diagnose_logs(name, head, &logs);
        println!("{}", line(name, secs, &out));
        match out {
            Ok(r) => {
                let bad = judge_plain(&truth, &r, 1.5);
                assert!(bad.is_empty(), "{name}: {bad:?}");
                // every held-out run rests: the report must say its score tests no motion
                // (before: `none`, "held-out NMAE 0.00 %", nothing more)
                let moves = r
                    .heldout_simulation
                    .as_ref()
                    .is_some_and(|h| h.runs.iter().any(|r| r.moves));
                assert!(
                    moves || r.verdict_reason.contains("no held-out run moves"),
                    "{name}: {}",
                    r.verdict_reason
                );
                // and its verdict is no `none`: nothing was tested (issue 22), and the text
                // prints no figure for a resting run
                if !moves {
                    assert_eq!(r.verdict, Verdict::Untested, "{name}");
                    let text = r.summary();
                    assert!(text.contains("moves in none of them"), "{text}");
                    assert!(!text.contains("0.00 %"), "{text}");
                }
            }
            Err(e) => {
                let m = e.to_string();
                assert!(
                    m.contains("validation") && m.contains("run"),
                    "{name}: the error must say which runs to hold out: {m}"
                );
            }
        }
    }
}

/// Runs at two sample rates in one data set (1 kHz and 200 Hz, alternating), nothing hidden.
#[test]
fn runs_at_different_sample_rates() {
    let mut rng = Rng::new(14);
    let truth = carriage(2.0, 4.0, 4.0, 8.0);
    let logs: Vec<Log> = (0..4)
        .map(|k| {
            let dt = if k < 2 { 1e-3 } else { 5e-3 };
            pulse_log(&mut rng, &truth, dt, 1e-6)
        })
        .collect();
    let (out, secs) = diagnose_logs(
        "two_rates",
        "position_unit = \"m\"\ninput_unit = \"N\"",
        &logs,
    );
    println!("{}", line("two_rates_1kHz_200Hz", secs, &out));
    let r = out.expect("a report");
    let bad = judge_plain(&truth, &r, 1.5);
    assert!(bad.is_empty(), "{bad:?}");
}

/// A vertical linear axis (gravity a constant load of -m g, held by a constant input) logged
/// one direction per run, up, down, up, down. The default split (every second run held out)
/// fits the up runs and holds out the down runs: nothing can be said about the down direction
/// and the report must say so (before: `unexplained`, "no candidate cuts it", 54.8 %, no
/// word on why). Declared with the last two runs held out (`kind = "validation"`), the
/// fitting runs move both ways and the load is found.
#[test]
fn a_vertical_axis_one_direction_per_run() {
    let mut rng = Rng::new(15);
    let mut truth = carriage(3.0, 5.0, 5.0, 20.0);
    truth.offset = -3.0 * 9.81;
    let dt = 1e-3;
    let mut logs: Vec<Log> = (0..4)
        .map(|k| {
            // the hold input 29.43 N; up: + 8..20 N, down: - 8..20 N
            let s = if k % 2 == 0 { 1.0 } else { -1.0 };
            let u: Vec<f64> = pulses(&mut rng, dt, 4, 8.0, 20.0, 0.4, 0.3, 0.0, true)
                .into_iter()
                .map(|v| 29.43 + s * v)
                .collect();
            let x = record(&truth, dt, &u, 0.0, 1e-6, 0.0, &mut rng);
            Log {
                dt,
                u,
                x,
                kind: "other",
            }
        })
        .collect();
    let head = "position_unit = \"m\"\ninput_unit = \"N\"";
    let (out, secs) = diagnose_logs("vertical_one_way", head, &logs);
    println!("{}", line("vertical_up_down_default_split", secs, &out));
    let r = out.expect("a report");
    assert!(
        r.findings.is_empty(),
        "named {:?}",
        r.findings.iter().map(|f| f.cause).collect::<Vec<_>>()
    );
    assert_eq!(r.verdict, Verdict::Unexplained);
    assert!(
        r.verdict_reason.contains("move negative") && r.verdict_reason.contains("validation"),
        "the reason must name the unseen direction and the fix: {}",
        r.verdict_reason
    );
    for l in &mut logs[2..] {
        l.kind = "validation";
    }
    let (out, secs) = diagnose_logs("vertical_declared", head, &logs);
    println!("{}", line("vertical_up_down_declared_split", secs, &out));
    let r = out.expect("a report");
    for f in &r.findings {
        assert!(
            matches!(f.cause, Cause::ForceOffset | Cause::DirectionAsymmetry),
            "invented {}",
            f.cause
        );
    }
    let m = r.final_model.as_ref().unwrap();
    assert!(m.inertia > 1.5 && m.inertia < 6.0, "J {}", m.inertia);
    // what sliding data fix (a load and dry levels split only where the load alone moves the
    // axis): the net constant force moving up, `offset - Fk+` (truth -29.43 - 5), and moving
    // down, `offset + Fk-` (truth -29.43 + 5)
    let (up, down) = (m.offset - m.kinetic_pos, m.offset + m.kinetic_neg);
    assert!(
        (up + 34.43).abs() < 1.0 && (down + 24.43).abs() < 1.0,
        "net constant force up {up}, down {down} (truth -34.43, -24.43)"
    );
}

/// A coarse encoder on a slow axis logged fast: slides of 0.5-1 m/s at 1 kHz, so one count
/// (0.5-2 mm) is 0.5 to 4 samples' travel, 25-100 counts a slide. Before: with a count of 1 or
/// 2 mm no sample was "moving" (the motion threshold was floored at one count per sample) and
/// the diagnosis refused the data ("0 sliding samples"). Now a report with physical
/// parameters, the inertia within 1.5x (0.52, 0.54, 0.58 against 0.5).
///
/// Nothing is hidden, and nothing is named. With the 1 mm count the least-squares baseline
/// simulates the held-out runs at 7.32 % (parameters from derivatives over 55 samples of a
/// quantised position, J 0.535, D 1.9-3.3 against 0.5, 2.0), above the `none` level, and a
/// stand-in used to be named: `input_saturation` at 7.5 N, later a 1-sample `input_delay`.
/// A delay is now refined with the inertia and friction by output error before it is named
/// (`drive/select.rs`, `pick`): it settles at 0.5 samples, within the log's timing, and the
/// refined baseline is the final model (3.60 %, `none`).
#[test]
fn a_coarse_encoder() {
    let truth = carriage(0.5, 3.0, 3.0, 2.0);
    let dt = 1e-3;
    let mut failures = Vec::new();
    for q in [5e-4, 1e-3, 2e-3] {
        let mut rng = Rng::new(16);
        let logs: Vec<Log> = (0..4)
            .map(|_| {
                let u = pulses(&mut rng, dt, 8, 5.0, 8.0, 0.1, 0.2, 0.0, false);
                let x = record(&truth, dt, &u, 0.0, q, 0.0, &mut rng);
                Log {
                    dt,
                    u,
                    x,
                    kind: "other",
                }
            })
            .collect();
        let name = format!("coarse_encoder_{}mm", q * 1e3);
        let (out, secs) = diagnose_logs(&name, "position_unit = \"m\"\ninput_unit = \"N\"", &logs);
        println!("{}", line(&name, secs, &out));
        match out {
            Ok(r) => {
                let mut bad = judge_plain(&truth, &r, 1.5);
                // nothing is saturated: that stand-in is refused by the output-error check
                if r.findings.iter().any(|f| f.cause == Cause::InputSaturation) {
                    bad.push("input_saturation named".into());
                }
                if !bad.is_empty() {
                    failures.push(format!("{name}: {bad:?}"));
                }
            }
            Err(e) => failures.push(format!("{name}: {e}")),
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The logger records the command, the amplifier limits the force to 12 N: the recorded input
/// (8-20 N pulses) runs past the limit. Whatever is named, the parameters stay physical; a
/// cause other than `input_saturation` is a stand-in: the report must say the rest is
/// unexplained and flag a grid-searched value at its grid edge.
#[test]
fn an_input_past_the_amplifier_limit() {
    let r = saturated();
    let m = r.final_model.as_ref().unwrap();
    assert!(m.inertia > 0.0 && m.kinetic_pos >= 0.0 && m.kinetic_neg >= 0.0);
    assert!(m.viscous_pos >= 0.0 && m.viscous_neg >= 0.0);
    if r.findings.iter().any(|f| f.cause != Cause::InputSaturation) {
        assert!(
            r.verdict_reason.contains("not explained"),
            "{}",
            r.verdict_reason
        );
    }
    for f in &r.findings {
        if f.cause == Cause::InputDelay && f.parameters["delay_samples"] >= 8.0 {
            assert!(f.evidence.note.contains("grid edge"), "{}", f.evidence.note);
        }
    }
}

/// The same rig: the saturation is named, alone, at its level within 10 % (12 N), in the
/// finding and the final model, with its unit. Before the `input_saturation` candidate:
/// `input_delay` (8 samples, grid edge) and `input_deadzone` stood in (held-out NMAE 42.3 ->
/// 27.8 %, "the rest is not explained").
#[test]
fn an_input_past_the_amplifier_limit_names_the_saturation() {
    let r = saturated();
    assert_eq!(
        r.findings.iter().map(|f| f.cause).collect::<Vec<_>>(),
        vec![Cause::InputSaturation],
        "{}",
        r.verdict_reason
    );
    assert_eq!(r.verdict, Verdict::Found(Cause::InputSaturation));
    let f = &r.findings[0];
    let s = f.parameters["saturation"];
    assert!((s / 12.0 - 1.0).abs() < 0.1, "saturation {s} N, truth 12 N");
    assert!(
        f.evidence.note.contains(&format!("{s:.4} N")),
        "{}",
        f.evidence.note
    );
    let m = r.final_model.as_ref().unwrap();
    assert_eq!(m.saturation, Some(s));
    assert_eq!(m.force_unit, "N");
    assert!((m.inertia / 2.0 - 1.0).abs() < 0.1, "J {} of 2", m.inertia);
    let h = r.heldout_simulation.as_ref().unwrap();
    assert!(
        h.nmae_after < 0.25 * h.nmae_before,
        "held-out NMAE {} -> {}",
        h.nmae_before,
        h.nmae_after
    );
}

/// Rigs with nothing saturated (the same pulses and carriage, the input applied as recorded)
/// whose baseline is wrong for another reason, so every candidate is tried: a saturation is
/// never named (and the first cause named is the truth's).
#[test]
fn nothing_saturated_names_no_saturation() {
    let head = "position_unit = \"m\"\ninput_unit = \"N\"";
    let dt = 1e-3;
    // (a 6-sample delay or a breakaway of 7 N against 4 sliding leaves this baseline within the
    // `none` level on these long pulses: no candidate is tried there)
    let cases: [(&str, Cause); 2] = [
        ("unsaturated_spring", Cause::RestoringForce),
        ("unsaturated_deadband", Cause::InputDeadzone),
    ];
    let mut failures = Vec::new();
    for (name, cause) in cases {
        let mut rng = Rng::new(18);
        let mut truth = carriage(2.0, 4.0, 4.0, 8.0);
        match cause {
            Cause::RestoringForce => {
                truth.position_force = crane_model::drive::PositionForce::Spring {
                    stiffness: 100.0,
                    center: 0.0,
                }
            }
            _ => truth.deadband = 3.0,
        }
        let logs: Vec<Log> = (0..4)
            .map(|_| pulse_log(&mut rng, &truth, dt, 1e-6))
            .collect();
        let (out, secs) = diagnose_logs(name, head, &logs);
        println!("{}", line(name, secs, &out));
        let r = out.expect("a report");
        let named: Vec<Cause> = r.findings.iter().map(|f| f.cause).collect();
        if named.contains(&Cause::InputSaturation) || named.first() != Some(&cause) {
            failures.push(format!("{name}: named {named:?}, truth {cause}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

fn saturated() -> Report {
    let mut rng = Rng::new(17);
    let truth = carriage(2.0, 4.0, 4.0, 8.0);
    let dt = 1e-3;
    let logs: Vec<Log> = (0..4)
        .map(|_| {
            let u = pulses(&mut rng, dt, 4, 8.0, 20.0, 0.4, 0.3, 0.0, false);
            let applied: Vec<f64> = u.iter().map(|v| v.clamp(-12.0, 12.0)).collect();
            let x = record(&truth, dt, &applied, 0.0, 1e-6, 0.0, &mut rng);
            Log {
                dt,
                u,
                x,
                kind: "other",
            }
        })
        .collect();
    let (out, secs) = diagnose_logs(
        "saturated",
        "position_unit = \"m\"\ninput_unit = \"N\"",
        &logs,
    );
    println!("{}", line("input_past_limit", secs, &out));
    out.expect("a report")
}

/// Fitting runs whose only motion is one encoder count: the data's limit, said as an input
/// error naming the sliding samples (it was reported as a model failure, `model: only 0
/// sliding samples ...`).
#[test]
fn a_single_count_of_motion_is_the_datas_limit_not_the_models() {
    let dt = 0.01;
    let one_count = |kind| Log {
        dt,
        u: (0..400).map(|i| if i < 200 { 1.0 } else { 0.0 }).collect(),
        x: (0..400).map(|i| if i < 200 { 0.0 } else { 1e-3 }).collect(),
        kind,
    };
    let (out, secs) = diagnose_logs(
        "one_count",
        "position_unit = \"m\"\ninput_unit = \"N\"",
        &[one_count("other"), one_count("validation")],
    );
    println!("{}", line("one_count_of_motion", secs, &out));
    match out {
        Err(DiagnoseError::Input(m)) => {
            assert!(
                m.contains("sliding samples") && m.contains("not identifiable"),
                "{m}"
            )
        }
        other => panic!("expected an input error, got {other:?}"),
    }
}

/// The own-log floor (`drive/floor.rs`) is measured on each log: with nothing hidden the
/// baseline leaves about what it leaves on its own replayed log (so `none`), and a coarser
/// encoder on the same motion raises the floor.
#[test]
fn the_own_log_floor_is_measured_on_each_log() {
    let truth = carriage(2.0, 4.0, 4.0, 8.0);
    let dt = 1e-3;
    let head = "position_unit = \"m\"\ninput_unit = \"N\"";
    let mut floors = Vec::new();
    for q in [1e-6, 2e-3] {
        let mut rng = Rng::new(29);
        let logs: Vec<Log> = (0..4).map(|_| pulse_log(&mut rng, &truth, dt, q)).collect();
        let name = format!("own_log_floor_q{q}");
        let (out, secs) = diagnose_logs(&name, head, &logs);
        println!("{}", line(&name, secs, &out));
        let r = out.expect("a clean log diagnoses");
        let e = &r.baseline_errors[0];
        let f = e
            .nmae_own_log
            .expect("the floor is computed on single-axis data");
        let held = r.heldout_simulation.as_ref().unwrap().moving_nmae_before;
        assert!(f > 0.0 && f.is_finite(), "{name}: floor {f}");
        assert!(
            held <= 8.0 * f.max(e.nmae_noise),
            "{name}: {held} vs floor {f}"
        );
        assert_eq!(r.verdict, Verdict::None, "{name}: {}", r.verdict_reason);
        floors.push(f);
    }
    assert!(
        floors[1] > floors[0],
        "a coarser encoder must raise the floor: {floors:?}"
    );
}
