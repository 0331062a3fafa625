//! The friction monitor on a plant it was not built on (issue 21): `stranger_crane/`, an
//! independent 3-D crane written from the physics spec (`MODEL.md`) by a helper that never read
//! this project's model, twin or monitor. Its own integrator and exact sticking, its own
//! position-dependent friction (a waviness, not the model's polynomials), a 1.5 ms drive lag,
//! PWM steps, ±1-count encoder noise at 1/10, per-seed parameters 3-8 % off nominal. The
//! operator below is this file's own too (moves of one, two or three drives, speeds and
//! dwells unlike the rig's). The twin runs with the nominal parameters, as on a real rig.
//!
//! One seed of each scenario runs in CI; `STRANGER_SEEDS=N` runs seeds `1..=N` and prints the
//! table of `twin/README.md` (`cargo test --release -p crane-twin --test monitor_strangers --
//! --nocapture`); `STRANGER_ONLY=TEXT` runs the scenarios whose name contains TEXT, and
//! `STRANGER_PRINT=1` prints every alarm and the share of periods in which X's map was judged.
//! `STRANGER_INSPECT=S` prints the monitor's internals from the onset for `S` seconds
//! ([`Inspect`]): the coverage and levels at the onset, every move of X and Y (its span, the
//! judged bins it crossed, the level it gave against the level's learned scatter), and at
//! every pass over the bump the bins of X's maps around it against their bands.
#[path = "support/monitor_rig.rs"]
mod rig;
mod stranger_crane;

use crane_model::{Axis, Direction, Mode, Params, State};
use crane_twin::logic::control::{Controller, Io, IoError, LoopConfig, Move, Trajectory};
use crane_twin::logic::monitor::alarm::Alarm;
use crane_twin::logic::monitor::map::BINS;
use crane_twin::logic::monitor::{Monitor, Settings};
use crane_twin::logic::observer::Observer;
use rig::Fault as RigFault;
use stranger_crane::{Config, Fault, StrangerCrane};

/// When a fault appears at the earliest [s] (issue 21's scenarios), and later if the monitor is
/// not ready by then ([`ready_at`]).
const ONSET: f64 = 600.0;

/// The stranger plant behind the twin's driver interface.
struct Board {
    plant: StrangerCrane,
}

impl Io for Board {
    fn read(&mut self) -> [Result<i32, IoError>; 5] {
        self.plant.counts().map(Ok)
    }
    fn write(&mut self, u: [f64; 3]) -> Result<[f64; 3], IoError> {
        // the driver's PWM: 4200 steps over 12 V, saturated (the plant quantises the same way)
        let q = u.map(|v| {
            if v.is_finite() {
                (v.clamp(-12.0, 12.0) * 350.0).round() / 350.0
            } else {
                0.0
            }
        });
        self.plant.apply(q);
        Ok(q)
    }
    fn wait(&mut self) {
        self.plant.step();
    }
}

/// A small xorshift for the operator (its own, not the rig's).
///
/// Kept rather than drawn from the host's generator (`crane_ident::rng`): the operator's moves
/// on every seed are what `twin/README.md`'s stranger table and its per-seed account (ready at
/// 780-892 s and 2,623 s, seed 1's moves after the onset, seed 5's drift levels) describe; a
/// new stream would void that account, not just its counts.
struct Dice(u64);

impl Dice {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// An operator unlike the rig's: a move drives one, two or all three drives (a third each),
/// at 0.12-0.30 m/s peak, dwells 0.5-4 s, the rope changed in one move of four.
struct Operator {
    dice: Dice,
    from: [f64; 3],
    current: Move,
}

impl Operator {
    fn new(seed: u64) -> Self {
        let start = [0.25, 0.30, 0.35];
        Operator {
            dice: Dice(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1),
            from: start,
            current: Move {
                start: 0.0,
                duration: 1.0,
                to: start,
            },
        }
    }
    fn next(&mut self, t: f64) {
        let d = &mut self.dice;
        let mut to = self.current.to;
        let which = d.unit();
        if which < 1.0 / 3.0 {
            to[0] = d.range(0.03, 0.47);
        } else if which < 2.0 / 3.0 {
            to[0] = d.range(0.03, 0.47);
            to[1] = d.range(0.03, 0.59);
        } else {
            to[1] = d.range(0.03, 0.59);
        }
        if d.unit() < 0.25 {
            to[2] = d.range(0.25, 0.50);
        }
        let speed = d.range(0.12, 0.30);
        let dist = to
            .iter()
            .zip(self.current.to)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let dwell = d.range(0.5, 4.0);
        self.from = self.current.to;
        self.current = Move {
            start: t + dwell,
            duration: (1.875 * dist / speed).max(0.8),
            to,
        };
    }
    fn reference(&mut self, t: f64) -> Trajectory<'_> {
        if t >= self.current.start + self.current.duration {
            self.next(t);
        }
        Trajectory {
            from: self.from,
            moves: core::slice::from_ref(&self.current),
        }
    }
}

/// What a run gave: alarms with their time, and the passes over the bump's centre.
struct Outcome {
    /// When the fault appeared [s].
    onset: f64,
    /// When the monitor was first ready ([`Monitor::ready`]) [s].
    ready: Option<f64>,
    alarms: Vec<(f64, Alarm)>,
    passes: Vec<f64>,
    /// Periods in which the monitor judged X's map, and all periods, before and after the
    /// onset.
    judged: [[u64; 2]; 2],
}

/// Runs the f64 twin and the monitor (default settings) against the stranger plant, the fault
/// from `onset` [s], for `duration` [s] (or until the monitor is ready, with `until_ready`).
fn run(fault: Fault, seed: u64, onset: f64, duration: f64, until_ready: bool) -> Outcome {
    let cfg = LoopConfig::default();
    let mut io = Board {
        plant: StrangerCrane::new(Config {
            seed,
            fault,
            onset,
            period: cfg.period,
        }),
    };
    let q = io.plant.truth();
    let init = State {
        q: [q[0], q[1], q[2], q[3], q[4]],
        qd: [0.0; 5],
    };
    let mut ctrl =
        Controller::<f64>::new(&Params::default(), init, &cfg).expect("nominal parameters");
    let mut monitor = Monitor::new(ctrl.observer(), Settings::for_loop(&cfg));
    let mut op = Operator::new(seed);
    let bump = match fault {
        Fault::Bump { center, .. } => Some(center),
        _ => None,
    };
    let mut out = Outcome {
        onset,
        ready: None,
        alarms: Vec::new(),
        passes: Vec::new(),
        judged: [[0; 2]; 2],
    };
    let mut last_x = q[0];
    let mut inspect = Inspect::from_env(onset, bump);
    for k in 0..(duration / cfg.period) as u64 {
        let t = k as f64 * cfg.period;
        let r = op.reference(t).at::<f64>(t);
        let p = ctrl.run_period(&mut io, &r);
        let before = inspect.as_mut().map(|i| i.before(&monitor));
        if let Some(a) = monitor.update(ctrl.observer(), p.predicted) {
            out.alarms.push((t, a));
        }
        if let (Some(i), Some(b)) = (inspect.as_mut(), before) {
            i.after(t, &monitor, ctrl.observer(), b, io.plant.truth()[0]);
        }
        if out.ready.is_none() && monitor.ready() {
            out.ready = Some(t);
            if until_ready {
                break;
            }
        }
        let after = usize::from(t >= onset);
        out.judged[after][0] += u64::from(monitor.judging(Axis::X));
        out.judged[after][1] += 1;
        if let Some(c) = bump {
            let x = io.plant.truth()[0];
            if (last_x - c) * (x - c) <= 0.0 && last_x != x {
                out.passes.push(t);
            }
            last_x = x;
        }
        io.wait();
    }
    if let Some(i) = inspect {
        i.header(duration, &monitor);
    }
    out
}

/// The monitor's internals printed from the onset for a while (`STRANGER_INSPECT=S` [s]),
/// for the diagnosis of a miss (`twin/README.md`, the independent plant's misses).
struct Inspect {
    onset: f64,
    until: f64,
    bump: Option<f64>,
    started: bool,
    /// Per watched axis: the direction sliding (1 positive, 0 negative) and where the slide
    /// began [m], from the twin's modes.
    slide: [Option<(usize, f64, f64)>; 2],
    last_x: f64,
    /// Passes over the bump so far, and a move of X over it whose local check is printed
    /// once evaluated: (direction, when [s]).
    passes: usize,
    report: Option<(usize, f64)>,
}

/// The levels of the four maps before an update ([`Monitor::level`]).
type Levels = [[(f32, f32); 2]; 2];

fn dir_of(d: usize) -> Direction {
    if d == 1 {
        Direction::Positive
    } else {
        Direction::Negative
    }
}

impl Inspect {
    fn from_env(onset: f64, bump: Option<f64>) -> Option<Self> {
        let s: f64 = std::env::var("STRANGER_INSPECT").ok()?.parse().ok()?;
        Some(Inspect {
            onset,
            until: onset + s,
            bump,
            started: false,
            slide: [None; 2],
            last_x: f64::NAN,
            passes: 0,
            report: None,
        })
    }

    fn before(&self, m: &Monitor) -> Levels {
        let l = |a: Axis, d: usize| m.level(a, dir_of(d)).unwrap_or_default();
        [
            [l(Axis::X, 0), l(Axis::X, 1)],
            [l(Axis::Y, 0), l(Axis::Y, 1)],
        ]
    }

    /// Judged bins of a map between `a` and `b` [m], and the map's judged bins in all.
    fn judged_between(m: &Monitor, axis: Axis, d: usize, a: f64, b: f64) -> (usize, usize) {
        let Some(map) = m.map(axis, dir_of(d)) else {
            return (0, 0);
        };
        let s = m.settings().map;
        let (lo, hi) = (map.bin(a.min(b) as f32), map.bin(a.max(b) as f32));
        let all = (0..BINS).filter(|k| map.view(*k, &s).judged).count();
        ((lo..=hi).filter(|k| map.view(*k, &s).judged).count(), all)
    }

    fn after(&mut self, t: f64, m: &Monitor, obs: &Observer<f64>, before: Levels, x_true: f64) {
        if t < self.onset || t > self.until {
            self.last_x = x_true;
            return;
        }
        if !self.started {
            self.started = true;
            self.header(t, m);
        }
        let q = obs.state().q;
        for (i, axis) in [Axis::X, Axis::Y].into_iter().enumerate() {
            let dir = match obs.modes()[i] {
                Mode::Positive => Some(1usize),
                Mode::Negative => Some(0usize),
                Mode::Stopped => None,
            };
            if let Some((d, from, t0)) = self.slide[i] {
                if dir != Some(d) {
                    let (lv, band) = m.level(axis, dir_of(d)).unwrap_or_default();
                    let gave = lv.to_bits() != before[i][d].0.to_bits();
                    let (crossed, _) = Self::judged_between(m, axis, d, from, q[i]);
                    let sd = band.max(0.0).sqrt();
                    println!(
                        "    t {t:.1} move {axis:?}{} {from:.3}->{:.3} m ({:.1} s): judged bins crossed {crossed}, {} level {lv:+.3} N, sd {sd:.3} N, z {:+.1}",
                        if d == 1 { '+' } else { '-' },
                        q[i],
                        t - t0,
                        if gave { "gave" } else { "no new" },
                        lv / sd.max(1e-9)
                    );
                    self.slide[i] = None;
                    if let Some(c) = self.bump {
                        if i == 0 && (from - c) * (q[i] - c) < 0.0 {
                            self.report = Some((d, t + 0.04));
                        }
                    }
                }
            }
            if self.slide[i].is_none() {
                if let Some(d) = dir {
                    self.slide[i] = Some((d, q[i], t));
                }
            }
        }
        if let Some(c) = self.bump {
            if (self.last_x - c) * (x_true - c) <= 0.0 && self.last_x != x_true {
                self.passes += 1;
                println!("    t {t:.1} pass {} over the bump", self.passes);
            }
            if let Some((d, at)) = self.report {
                if t >= at {
                    self.report = None;
                    self.bins(t, m, c, d);
                }
            }
        }
        self.last_x = x_true;
    }

    /// The coverage and levels of the four maps at `t` [s] (the onset, and the run's end).
    fn header(&self, t: f64, m: &Monitor) {
        println!("    inspect at {t:.1} s: ready {}", m.ready());
        for axis in [Axis::X, Axis::Y] {
            for d in 0..2 {
                let c = m.coverage(axis, dir_of(d)).unwrap_or_default();
                let (lv, band) = m.level(axis, dir_of(d)).unwrap_or_default();
                let (_, all) = Self::judged_between(m, axis, d, 0.0, 0.0);
                println!(
                    "    {axis:?}{}: restarts {} moves {} judged bins {all}; level {lv:+.3} N sd {:.3} N",
                    if d == 1 { '+' } else { '-' },
                    c.restarts,
                    c.moves,
                    band.max(0.0).sqrt()
                );
            }
        }
    }

    /// After a move of X in direction `d` over the bump centre `c` [m]: that map's bins around
    /// it (change against the travel's level and band sd [N], `*` not judged, age in moves)
    /// and both maps' local checks.
    fn bins(&self, t: f64, m: &Monitor, c: f64, d: usize) {
        let Some(map) = m.map(Axis::X, dir_of(d)) else {
            return;
        };
        let s = m.settings().map;
        let (lv, _) = m.level(Axis::X, dir_of(d)).unwrap_or_default();
        let b0 = map.bin(c as f32);
        let mut row = String::new();
        for b in b0.saturating_sub(5)..(b0 + 6).min(BINS) {
            let v = map.view(b, &s);
            row.push_str(&format!(
                " [{:.3}{} {:+.2}/{:.2} a{}]",
                map.center(b),
                if v.judged { "" } else { "*" },
                v.deviation - lv,
                v.band.max(0.0).sqrt(),
                v.age
            ));
        }
        let sign = |d: usize| if d == 1 { '+' } else { '-' };
        println!(
            "    t {t:.1} after move X{} (passes {}):{row}",
            sign(d),
            self.passes
        );
        for e in 0..2 {
            if let Some(l) = m.local_state(Axis::X, dir_of(e)) {
                let out: Vec<String> = (0..BINS)
                    .filter(|b| l.out_of_band >> b & 1 == 1)
                    .map(|b| format!("{:.3}", map.center(b)))
                    .collect();
                println!(
                    "      X{} local: candidate {:?} passes {} local (pending, standing) {:?} drift {:?} pattern {:?} pooled sd {:.3} N; out of band at {}",
                    sign(e),
                    l.candidate,
                    l.passes,
                    l.local,
                    l.drift,
                    l.pattern,
                    l.pooled.max(0.0).sqrt(),
                    out.join(" ")
                );
            }
        }
    }
}

/// The rig's judgement of an alarm, for the stranger's fault.
fn expected(fault: Fault, a: &Alarm) -> bool {
    let f = match fault {
        Fault::Clean => RigFault::Clean,
        Fault::DryFriction { factor } => RigFault::DryFriction { factor },
        Fault::Bump {
            center,
            width,
            amplitude,
        } => RigFault::Bump {
            center,
            width,
            amplitude,
        },
        Fault::Stiction { ratio } => RigFault::Stiction { ratio },
        Fault::SlowDrift { per_hour } => RigFault::SlowDrift { per_hour },
        Fault::Payload { mass } => RigFault::Payload { mass },
    };
    rig::expected(&f, a)
}

/// One scenario: its fault, the run's length [s] and the detection bound after the onset [s]
/// (`None`: no alarm is expected).
struct Scenario {
    name: &'static str,
    fault: Fault,
    duration: f64,
    bound: Option<f64>,
}

fn scenarios() -> Vec<Scenario> {
    vec![
        Scenario {
            name: "clean",
            fault: Fault::Clean,
            duration: 3600.0,
            bound: None,
        },
        Scenario {
            name: "dry friction +30 % once ready",
            fault: Fault::DryFriction { factor: 1.3 },
            duration: 700.0,
            bound: Some(30.0),
        },
        Scenario {
            name: "1 N bump at x = 0.31 m once ready",
            fault: Fault::Bump {
                center: 0.31,
                width: 0.015,
                amplitude: 1.0,
            },
            duration: 900.0,
            bound: Some(300.0),
        },
        Scenario {
            name: "stiction ratio 1.0 -> 1.8 once ready",
            fault: Fault::Stiction { ratio: 1.8 },
            duration: 900.0,
            bound: Some(300.0),
        },
        Scenario {
            name: "dry friction +5 %/h from 600 s",
            fault: Fault::SlowDrift { per_hour: 0.05 },
            duration: 3600.0,
            bound: None,
        },
    ]
}

/// One scenario judged: the first expected alarm's delay after the onset [s] (if any), the
/// passes over the bump before it, and the alarms not expected.
struct Judged {
    delay: Option<f64>,
    passes: usize,
    other: Vec<(f64, Alarm)>,
}

fn judge(s: &Scenario, o: &Outcome) -> Judged {
    let first = o
        .alarms
        .iter()
        .find(|(t, a)| *t >= o.onset && expected(s.fault, a))
        .map(|(t, _)| *t);
    Judged {
        delay: first.map(|t| t - o.onset),
        passes: first.map_or(0, |t| {
            o.passes
                .iter()
                .filter(|p| **p >= o.onset && **p <= t)
                .count()
        }),
        other: o
            .alarms
            .iter()
            .filter(|(_, a)| !expected(s.fault, a))
            .copied()
            .collect(),
    }
}

fn seeds() -> u64 {
    std::env::var("STRANGER_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1)
}

/// Scenarios whose bound the monitor misses on this plant on some of the README's 5 seeds
/// (measured: `twin/README.md`): printed, not asserted. With `STRANGER_SEEDS` of 5 or more
/// the test fails when one of them is met on every seed (then it belongs out of this list),
/// so the list cannot go stale; every other scenario is asserted on every seed run.
const KNOWN_MISSES: &[&str] = &[
    "dry friction +30 % once ready",
    "1 N bump at x = 0.31 m once ready",
];

/// How one scenario went over the seeds.
#[derive(Default)]
struct Tally {
    hit: usize,
    delays: Vec<f64>,
    passes: Vec<usize>,
    other: usize,
    failures: Vec<String>,
    /// The onset of each seed's fault [s].
    onsets: Vec<f64>,
    /// Hours simulated over the seeds.
    hours: f64,
}

/// When the monitor is first ready on seed `seed`'s plant and operator [s] (the run up to the
/// onset is the clean run), if within an hour.
fn ready_at(seed: u64) -> Option<f64> {
    run(Fault::Clean, seed, f64::INFINITY, 3600.0, true).ready
}

/// The onset of a fault on seed `seed`: [`ONSET`], or the next whole second after the monitor
/// is ready if that is later (a fault that begins before the monitor is ready is learned as
/// the reference, by design: [`Monitor::ready`]).
fn onset_for(seed: u64) -> f64 {
    ready_at(seed).map_or(ONSET, |r| ONSET.max(r.floor() + 1.0))
}

fn tally(s: &Scenario, n: u64, print: bool) -> Tally {
    let mut t = Tally::default();
    // `STRANGER_SEED_LIST=a,b,...`: only those of the seeds (for a diagnosis)
    let list: Option<Vec<u64>> = std::env::var("STRANGER_SEED_LIST")
        .ok()
        .map(|l| l.split(',').filter_map(|x| x.trim().parse().ok()).collect());
    for seed in 1..=n {
        if list.as_ref().is_some_and(|l| !l.contains(&seed)) {
            continue;
        }
        let onset = if s.bound.is_some() {
            onset_for(seed)
        } else {
            ONSET
        };
        let o = run(s.fault, seed, onset, s.duration - ONSET + onset, false);
        t.onsets.push(onset);
        t.hours += (s.duration - ONSET + onset) / 3600.0;
        if print {
            println!(
                "  {} seed {seed}: onset {onset:.0} s, monitor ready at {:?} s",
                s.name, o.ready
            );
            let share = |k: usize| 100.0 * o.judged[k][0] as f64 / o.judged[k][1].max(1) as f64;
            println!(
                "  {} seed {seed}: X judged {:.1} % of the periods before the onset, {:.1} % after",
                s.name,
                share(0),
                share(1)
            );
            for (at, a) in &o.alarms {
                println!("  {} seed {seed} t {at:.1} {a:?}", s.name);
            }
        }
        let j = judge(s, &o);
        t.other += j.other.len();
        if !j.other.is_empty() {
            t.failures.push(format!(
                "{} seed {seed}: alarms not expected {:?}",
                s.name, j.other
            ));
        }
        let Some(bound) = s.bound else { continue };
        let bump = matches!(s.fault, Fault::Bump { .. });
        match j.delay {
            Some(d) if d <= bound && (!bump || j.passes <= 3) => {
                t.hit += 1;
                t.delays.push(d);
                t.passes.push(j.passes);
            }
            _ => t.failures.push(format!(
                "{} seed {seed}: not detected within {bound} s (delay {:?}, {} passes): {:?}",
                s.name, j.delay, j.passes, o.alarms
            )),
        }
    }
    t.delays.sort_by(f64::total_cmp);
    t.passes.sort_unstable();
    t
}

/// The README's table row of a scenario.
fn row(s: &Scenario, n: u64, t: &Tally) -> String {
    let hours = t.hours;
    let at = |v: &[f64], k: usize| v.get(k).map_or("-".into(), |x| format!("{x:.1} s"));
    let mut onsets = t.onsets.clone();
    onsets.sort_by(f64::total_cmp);
    format!(
        "| {} | {n} | {hours:.1} | {} / {} | {} | {} / {} | {} | {} ({:.2} per hour) |",
        s.name,
        at(&onsets, onsets.len() / 2),
        at(&onsets, onsets.len().wrapping_sub(1)),
        s.bound.map_or("no alarm expected".into(), |b| format!(
            "{} / {n} (<= {b} s)",
            t.hit
        )),
        at(&t.delays, t.delays.len() / 2),
        at(&t.delays, t.delays.len().wrapping_sub(1)),
        t.passes
            .get(t.passes.len() / 2)
            .zip(t.passes.last())
            .map_or("-".into(), |(m, x)| format!("{m} / {x}")),
        t.other,
        t.other as f64 / hours
    )
}

#[test]
fn the_monitor_on_an_independent_plant() {
    let n = seeds();
    let only = std::env::var("STRANGER_ONLY").ok();
    let print = std::env::var_os("STRANGER_PRINT").is_some();
    println!("| scenario | seeds | hours | onset median / max | detected (within bound) | delay median / max | passes median / max | other alarms |");
    println!("|---|---|---|---|---|---|---|---|");
    let mut failures = Vec::new();
    for s in scenarios() {
        if only.as_ref().is_some_and(|o| !s.name.contains(o.as_str())) {
            continue;
        }
        let t = tally(&s, n, print);
        println!("{}", row(&s, n, &t));
        if KNOWN_MISSES.contains(&s.name) {
            for f in &t.failures {
                println!("  known miss: {f}");
            }
            if t.failures.is_empty() && n >= 5 {
                failures.push(format!(
                    "{}: a known miss is now met on all {n} seeds: take it out of KNOWN_MISSES and update twin/README.md",
                    s.name
                ));
            }
        } else {
            failures.extend(t.failures);
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
