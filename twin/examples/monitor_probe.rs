//! Diagnosis of one rig run (how the causes in twin/README.md "Where a move begins or ends" and
//! "Commissioning" were found): at every alarm, the state of the alarm's map around its place
//! over the 12 s before it (per bin the sample count, age in moves, current level, reference,
//! change beyond the travel's level, band, recent scatter and z score), the maps' viscous
//! slopes every 50 s, and on request:
//! - `PROBE_PASSES=1`: X's maps around 0.31 m 0.6 s after each pass over it, with the checks;
//! - `PROBE_TRACE=1`: X's local-check state whenever it changes;
//! - `PROBE_SAMPLES=FILE`: every sample-worthy period of X and Y (`t axis dir x v a r
//!   periods_sliding`, the raw residual before the viscous correction);
//! - `PROBE_CHECK=1`: the firmware's `CHECK` run with `Settings::quick` instead
//!   (`PROBE_AMP`, `PROBE_DUR`, `PROBE_WARM`, `PROBE_JUDGED` override it).
//!
//! `cargo run -p crane-twin --release --example monitor_probe -- SCENARIO SEED [DURATION]`
//! with SCENARIO one of clean, dry, bump, stiction, slow, payload (the fault at 600 s).
use crane_model::{Axis, Direction};
use crane_twin::logic::control::LoopConfig;
use crane_twin::logic::monitor::alarm::AlarmKind;
use crane_twin::logic::monitor::map::BINS;
use crane_twin::logic::monitor::{Monitor, Settings};
use crane_twin::logic::monitor_rig::{run_inspect, Event, Fault, Run};
use std::collections::VecDeque;

struct Sink;
impl core::fmt::Write for Sink {
    fn write_str(&mut self, _: &str) -> core::fmt::Result {
        Ok(())
    }
}

fn dump(hist: &VecDeque<(f64, Monitor)>, axis: Axis, dir: Direction, center: usize) {
    let lo = center.saturating_sub(4);
    let hi = (center + 4).min(BINS - 1);
    for (t, m) in hist {
        let Some(map) = m.map(axis, dir) else {
            continue;
        };
        let s = m.settings().map;
        let (level, lband) = m.level(axis, dir).unwrap_or((0.0, 0.0));
        let (mut sum, mut n) = (0.0f32, 0);
        for b in 0..BINS {
            if map.count(b) >= s.judged {
                sum += map.view(b, &s).band;
                n += 1;
            }
        }
        let pooled = sum / n.max(1) as f32;
        println!(
            "t {t:8.1} level {level:+.3} lsd {:.3} pooled_sd {:.3}",
            lband.sqrt(),
            pooled.sqrt()
        );
        for b in lo..=hi {
            let v = map.view(b, &s);
            let band = v.band.max(pooled);
            println!(
                "   bin {b:2} x {:.3} n {:5} age {:3} cur {:+.3} ref {:+.3} dev-lvl {:+.3} band_sd {:.3} scat_sd {:.3} z {:+.2}",
                map.center(b),
                map.count(b),
                v.age,
                map.current(b),
                map.reference(b),
                v.deviation - level,
                v.band.sqrt(),
                map.scatter(b).sqrt(),
                (v.deviation - level) / band.sqrt()
            );
        }
    }
}

/// Per-period samples of X and Y for an offline look: `t i dir x v a r sliding_for`.
struct Acc {
    last_v: [f64; 2],
    since: [u32; 2],
    out: Option<std::io::BufWriter<std::fs::File>>,
}

fn samples(acc: &mut Acc, t: f64, obs: &crane_twin::logic::observer::Observer<f64>) {
    use std::io::Write;
    let st = obs.state();
    let d = obs.disturbance();
    for (i, di) in d.iter().enumerate().take(2) {
        let v = st.qd[i];
        let a = (v - acc.last_v[i]) / 2e-3;
        acc.last_v[i] = v;
        let dir = match obs.modes()[i] {
            crane_model::Mode::Positive => 1,
            crane_model::Mode::Negative => -1,
            crane_model::Mode::Stopped => 0,
        };
        if dir == 0 {
            acc.since[i] = 0;
            continue;
        }
        acc.since[i] += 1;
        if acc.since[i] < 44 || v.abs() < 0.0611 {
            continue;
        }
        let r = -di * f64::from(dir);
        if let Some(o) = acc.out.as_mut() {
            let _ = writeln!(o, "{t} {i} {dir} {} {v} {a} {r} {}", st.q[i], acc.since[i]);
        }
    }
}

thread_local! {
    static TRACE: std::cell::RefCell<String> = const { std::cell::RefCell::new(String::new()) };
}

/// The run and the monitor's settings from the command line (`FAULT SEED DURATION`) and, with
/// `PROBE_CHECK`, the firmware's check run with `PROBE_AMP`, `PROBE_DUR`, `PROBE_JUDGED` and
/// `PROBE_WARM` overrides.
fn run_and_settings() -> (Run, Settings) {
    let args: Vec<String> = std::env::args().collect();
    let fault = match args.get(1).map(String::as_str).unwrap_or("clean") {
        "dry" => Fault::DryFriction { factor: 1.3 },
        "bump" => Fault::Bump {
            center: 0.31,
            width: 0.015,
            amplitude: 1.0,
        },
        "stiction" => Fault::Stiction { ratio: 1.8 },
        "slow" => Fault::SlowDrift { per_hour: 0.05 },
        "payload" => Fault::Payload { mass: 2.0 },
        _ => Fault::Clean,
    };
    let seed: u32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let duration: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(3600.0);
    let run = Run {
        fault,
        onset: 600.0,
        duration,
        seed,
        reset_at: None,
        substeps: 2,
        maps_every: 0,
        record: false,
    };
    let mut settings = Settings::for_loop(&LoopConfig::default());
    let mut run = run;
    if std::env::var_os("PROBE_CHECK").is_some() {
        run = crane_twin::logic::monitor_rig::CHECK;
        settings = Settings::quick(&LoopConfig::default());
        let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
        if let Some(a) = env("PROBE_AMP") {
            run.fault = Fault::Bump {
                center: 0.31,
                width: 0.015,
                amplitude: a,
            };
        }
        if let Some(d) = env("PROBE_DUR") {
            run.duration = d;
        }
        if let Some(j) = env("PROBE_JUDGED") {
            settings.map.judged = j as u16;
        }
        if let Some(j) = env("PROBE_WARM") {
            settings.map.warm = j as u16;
        }
    }
    (run, settings)
}

fn main() {
    let (run, settings) = run_and_settings();
    let every: u64 = 250;
    let keep = 24;
    let mut hist: VecDeque<(f64, Monitor)> = VecDeque::new();
    let mut k = 0u64;
    let mut acc = Acc {
        last_v: [0.0; 2],
        since: [0; 2],
        out: std::env::var("PROBE_SAMPLES")
            .ok()
            .and_then(|p| std::fs::File::create(p).ok())
            .map(std::io::BufWriter::new),
    };
    let alarms = std::cell::RefCell::new(Vec::new());
    let passes = std::cell::RefCell::new(Vec::new());
    let _ = run_inspect::<f64, _, _, _>(
        &run,
        &settings,
        "probe",
        &mut Sink,
        |e| match e {
            Event::Alarm(t, a) => alarms.borrow_mut().push((t, a)),
            Event::Pass(t) => passes.borrow_mut().push(t),
            _ => {}
        },
        |t, m, obs| {
            k += 1;
            samples(&mut acc, t, obs);
            if let Some((ta, a)) = alarms.borrow().last() {
                if *ta == t {
                    println!("ALARM t {t:.1} {a:?}");
                    let map = m.map(a.axis, a.direction).unwrap_or_else(|| {
                        m.map(a.axis, Direction::Positive).expect("watched axis")
                    });
                    let center = match a.kind {
                        AlarmKind::LocalFriction { position, .. } => map.bin(position),
                        _ => 32,
                    };
                    let dirs = match a.direction {
                        Direction::Both => vec![Direction::Negative, Direction::Positive],
                        d => vec![d],
                    };
                    let mut h = hist.clone();
                    h.push_back((t, m.clone()));
                    for d in dirs {
                        println!("-- map {:?} {:?}", a.axis, d);
                        dump(&h, a.axis, d, center);
                    }
                    let ps: Vec<_> = passes
                        .borrow()
                        .iter()
                        .copied()
                        .filter(|p| *p >= 25.0)
                        .collect();
                    println!("passes since onset {}: {ps:.1?}", ps.len());
                }
            }
            let after_pass = passes.borrow().last().is_some_and(|p| {
                t - p >= 0.6
                    && t - p < 0.6 + 1.5e-3
                    && (*p >= 599.0 || std::env::var_os("PROBE_CHECK").is_some())
            });
            if after_pass && std::env::var_os("PROBE_PASSES").is_some() {
                println!("PASS+0.6 s at t {t:.1}");
                let dbg = format!("{m:?}");
                if let (Some(a), Some(b)) = (dbg.find("checks: "), dbg.find("breakaway: ")) {
                    println!("{}", &dbg[a..b]);
                }
                let h: VecDeque<_> = [(t, m.clone())].into_iter().collect();
                for d in [Direction::Negative, Direction::Positive] {
                    println!("-- map X {d:?}");
                    let c = m.map(Axis::X, d).map_or(31, |mp| mp.bin(0.31));
                    dump(&h, Axis::X, d, c);
                }
            }
            if std::env::var_os("PROBE_TRACE").is_some() && t >= 600.0 {
                let dbg = format!("{m:?}");
                if let Some(a) = dbg.find("checks: ") {
                    let c = &dbg[a..];
                    let mut cur = String::new();
                    for part in c.split("Checks {").skip(1).take(2) {
                        let l = part.find("local:").unwrap_or(0);
                        let e = part.find(", entered").unwrap_or(part.len());
                        cur.push_str(
                            &part[l..e]
                                .replace("span: ", "")
                                .replace("candidate: ", "cand "),
                        );
                        cur.push_str(" | ");
                    }
                    TRACE.with(|tr| {
                        let mut tr = tr.borrow_mut();
                        if *tr != cur {
                            println!("TRACE t {t:.3} {cur}");
                            *tr = cur;
                        }
                    });
                }
            }
            if k % 25_000 == 0 {
                for ax in [Axis::X, Axis::Y] {
                    for d in [Direction::Negative, Direction::Positive] {
                        if let Some(mp) = m.map(ax, d) {
                            println!("SLOPE t {t:.0} {ax:?} {d:?} {:?}", mp.viscous_slope());
                        }
                    }
                }
            }
            if k % every == 0 {
                hist.push_back((t, m.clone()));
                if hist.len() > keep {
                    hist.pop_front();
                }
            }
        },
    );
    println!("alarms: {}", alarms.borrow().len());
}
