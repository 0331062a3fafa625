//! The friction monitor's rig: an operated crane (random transport moves), a plant that
//! differs from the twin's identified model and develops a fault, encoders with the rig's
//! quantum and count noise, the twin's loop and its monitor, which writes its frames
//! ([`super::monitor::frame`]). The same code runs on the host (the scenarios of
//! `twin/tests/monitor_scenarios.rs` and the table of `twin/examples/monitor_table.rs`) and
//! under QEMU (the firmware's `MBEGIN`..`MEND` section, compared with the host by
//! `host-tests/tests/qemu_cross.rs`).
//!
//! The plant is this project's own model with perturbed parameters: the rig shows that the
//! monitor runs and finds these faults, not that it generalises to other plants.

use super::control::{Controller, Io, IoError, LoopConfig, Move, Trajectory};
use super::digest::Fnv;
use super::monitor::alarm::Alarm;
use super::monitor::frame::{write_alarm, write_maps};
use super::monitor::{Monitor, Settings};
use super::observer::Observer;
use super::plant::SimPlant;
use super::prng::Prng;
use core::fmt::{self, Write};
use crane_model::{Axis, Bump, Direction, Extensions, Params, Real, State, Stiction};

/// What goes wrong on the rig, from the run's onset on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fault {
    /// Nothing.
    Clean,
    /// Dry friction of X and Y times `factor` (a dry rail).
    DryFriction {
        /// Factor on every dry-friction coefficient.
        factor: f64,
    },
    /// A rough spot on X: a friction bump.
    Bump {
        /// Centre [m].
        center: f64,
        /// Half-width of its support [m].
        width: f64,
        /// Peak [N].
        amplitude: f64,
    },
    /// Breakaway over sliding friction on X and Y becomes `ratio` (Stribeck velocity 0.01 m/s).
    Stiction {
        /// Breakaway over sliding friction.
        ratio: f64,
    },
    /// Dry friction of X and Y grows by `per_hour` (a fraction) per hour (temperature).
    SlowDrift {
        /// Growth per hour (0.05 is 5 %).
        per_hour: f64,
    },
    /// The payload becomes `mass` [kg] (a different load: not friction, a model mismatch).
    Payload {
        /// Payload mass [kg].
        mass: f64,
    },
}

/// One run of the rig.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Run {
    /// The fault.
    pub fault: Fault,
    /// When it appears [s].
    pub onset: f64,
    /// Length of the run [s].
    pub duration: f64,
    /// Seed of the operator's moves, the plant's identification error and the encoder noise.
    pub seed: u32,
    /// A reset of the controller (a watchdog) at this time [s]: the monitor is built anew.
    pub reset_at: Option<f64>,
    /// Plant steps per control period (2 on the host; 1 under QEMU, where the f64 plant is
    /// the slowest part).
    pub substeps: u32,
    /// Map frames every this many periods (0: only at the end).
    pub maps_every: u64,
    /// Report every period ([`Event::Period`]): the recorded run.
    pub record: bool,
}

/// What the rig reports besides the frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// An alarm at time `t` [s].
    Alarm(f64, Alarm),
    /// The true X position crossed the bump's centre at time `t` [s] (a pass).
    Pass(f64),
    /// One period: time `t` [s], the voltages applied during it `u` [V], and the positions the
    /// encoders read at its end `y` [m, m, m, rad, rad] (quantised, without the count noise):
    /// a recorded run of the rig, as a crane data set would hold it.
    Period {
        /// Time at the period's start [s].
        t: f64,
        /// Voltages applied during the period [V].
        u: [f64; 3],
        /// Encoder positions at its end [m, m, m, rad, rad].
        y: [f64; 5],
    },
    /// The monitor's update of a period starts (a cost measurement brackets it).
    MonitorStart,
    /// The monitor's update of a period ended.
    MonitorEnd,
}

/// The plant the twin was identified on: nominal parameters off by a few percent (seeded),
/// a 0.5 kg payload instead of 0.457 kg.
fn plant_params(rng: &mut Prng) -> Params {
    let mut p = Params {
        payload_mass: 0.5,
        ..Params::default()
    };
    let mut off = |scale: f64| 1.0 + scale * rng.uniform();
    let (fx, fy) = (off(0.05), off(0.05));
    p.x.dry_pos = p.x.dry_pos.map(|c| fx * c);
    p.x.dry_neg = p.x.dry_neg.map(|c| fx * c);
    p.y.dry_pos = p.y.dry_pos.map(|c| fy * c);
    p.y.dry_neg = p.y.dry_neg.map(|c| fy * c);
    let (vx, vy) = (off(0.02), off(0.02));
    p.x.viscous_pos *= vx;
    p.x.viscous_neg *= vx;
    p.y.viscous_pos *= vy;
    p.y.viscous_neg *= vy;
    p
}

fn scale_dry(p: &Params, factor: f64) -> Params {
    let mut q = *p;
    for ax in [&mut q.x, &mut q.y] {
        ax.dry_pos = ax.dry_pos.map(|c| factor * c);
        ax.dry_neg = ax.dry_neg.map(|c| factor * c);
    }
    q
}

/// The plant's parameters and extensions at time `t` [s].
fn faulted(base: &Params, run: &Run, t: f64) -> (Params, Extensions) {
    let mut ext = Extensions::default();
    if t < run.onset {
        return (*base, ext);
    }
    match run.fault {
        Fault::Clean => (*base, ext),
        Fault::DryFriction { factor } => (scale_dry(base, factor), ext),
        Fault::Payload { mass } => (
            Params {
                payload_mass: mass,
                ..*base
            },
            ext,
        ),
        Fault::SlowDrift { per_hour } => (
            scale_dry(base, 1.0 + per_hour * (t - run.onset) / 3600.0),
            ext,
        ),
        Fault::Bump {
            center,
            width,
            amplitude,
        } => {
            let _ = ext.bumps.push(Bump {
                axis: Axis::X,
                center,
                width,
                amplitude,
                direction: Direction::Both,
            });
            (*base, ext)
        }
        Fault::Stiction { ratio } => {
            let s = Some(Stiction {
                ratio,
                velocity: 0.01,
            });
            ext.stiction = [s, s, None];
            (*base, ext)
        }
    }
}

/// Encoders with count noise: each channel reads one count off with probability 1/8.
struct Noisy {
    plant: SimPlant,
    rng: Prng,
}

impl Io for Noisy {
    fn read(&mut self) -> [Result<i32, IoError>; 5] {
        let mut c = self.plant.read();
        for ci in c.iter_mut() {
            let r = self.rng.next_u32();
            if let Ok(v) = ci {
                match r % 16 {
                    0 => *v += 1,
                    1 => *v -= 1,
                    _ => {}
                }
            }
        }
        c
    }
    fn write(&mut self, u: [f64; 3]) -> Result<[f64; 3], IoError> {
        self.plant.write(u)
    }
    fn wait(&mut self) {
        self.plant.wait();
    }
    fn truth(&self) -> Option<State<f64>> {
        self.plant.truth()
    }
}

fn abs(x: f64) -> f64 {
    if x < 0.0 {
        -x
    } else {
        x
    }
}

/// An operator: transport moves to random places, peak speed 0.25 m/s, dwells of 0.3-2 s;
/// the rope length changes in one move of five.
struct Operator {
    rng: Prng,
    from: [f64; 3],
    current: Move,
}

impl Operator {
    fn next(&mut self, start: f64) {
        let r = &mut self.rng;
        let mut u = |lo: f64, hi: f64| lo + (hi - lo) * 0.5 * (r.uniform() + 1.0);
        let to = [
            u(0.03, 0.47),
            u(0.03, 0.59),
            if u(0.0, 1.0) < 0.2 {
                u(0.25, 0.50)
            } else {
                self.current.to[2]
            },
        ];
        let dwell = u(0.3, 2.0);
        let mut d = 0.0;
        for (a, b) in to.iter().zip(self.current.to) {
            let e = abs(a - b);
            if e > d {
                d = e;
            }
        }
        let duration = 1.875 * d / 0.25;
        let duration = if duration > 0.8 { duration } else { 0.8 };
        self.from = self.current.to;
        self.current = Move {
            start: start + dwell,
            duration,
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

const START: [f64; 3] = [0.25, 0.30, 0.35];

/// Runs one rig run with a twin in scalar type `R`, the monitor with `settings`; writes its
/// frames to `out` (`MBEGIN tag`, alarms as they come, the maps every `run.maps_every`
/// periods and at the end, `MEND tag hash=<FNV-1a of every alarm's bits>`) and reports
/// alarms and passes to `event`. `Ok(false)` if the rig could not be built.
pub fn run<R: Real, W: Write, E: FnMut(Event)>(
    run: &Run,
    settings: &Settings,
    tag: &str,
    out: &mut W,
    event: E,
) -> Result<bool, fmt::Error> {
    run_inspect::<R, W, E, _>(run, settings, tag, out, event, |_, _, _| {})
}

/// [`run`], and `inspect` sees the monitor and the observer after every period's update (at
/// time `t` [s]): for
/// a diagnosis of its state on the host.
pub fn run_inspect<R: Real, W: Write, E: FnMut(Event), I: FnMut(f64, &Monitor, &Observer<R>)>(
    run: &Run,
    settings: &Settings,
    tag: &str,
    out: &mut W,
    mut event: E,
    mut inspect: I,
) -> Result<bool, fmt::Error> {
    let cfg = LoopConfig::default();
    let mut rng = Prng::new(run.seed.wrapping_mul(2_654_435_761).wrapping_add(1));
    let base = plant_params(&mut rng);
    let init = State {
        q: [
            START[0],
            START[1],
            START[2],
            core::f64::consts::FRAC_PI_2,
            0.0,
        ],
        qd: [0.0; 5],
    };
    writeln!(
        out,
        "MBEGIN {tag} seed={} duration={}",
        run.seed, run.duration
    )?;
    let Ok(plant) = SimPlant::new(&base, init, cfg.period, run.substeps) else {
        writeln!(out, "ERROR {tag} plant")?;
        return Ok(false);
    };
    let mut io = Noisy {
        plant,
        rng: Prng::new(rng.next_u32()),
    };
    let Ok(mut ctrl) = Controller::<R>::new(&Params::default(), init, &cfg) else {
        writeln!(out, "ERROR {tag} controller")?;
        return Ok(false);
    };
    let mut monitor = Monitor::new(ctrl.observer(), *settings);
    let mut op = Operator {
        rng: Prng::new(rng.next_u32()),
        from: START,
        current: Move {
            start: 0.0,
            duration: 1.0,
            to: START,
        },
    };
    let periods = (run.duration / cfg.period) as u64;
    let retune_every = (10.0 / cfg.period) as u64;
    let onset = (run.onset / cfg.period) as u64;
    let reset = run.reset_at.map(|r| (r / cfg.period) as u64);
    let bump = match run.fault {
        Fault::Bump { center, .. } => Some(center),
        _ => None,
    };
    let slow = matches!(run.fault, Fault::SlowDrift { .. });
    let record = run.record;
    let mut fnv = Fnv::default();
    let mut last_x = START[0];
    for k in 0..periods {
        let t = k as f64 * cfg.period;
        if k == onset || (slow && k > onset && k % retune_every == 0) {
            let (p, ext) = faulted(&base, run, t);
            let _ = io.plant.retune(&p, &ext);
        }
        let r = op.reference(t).at::<R>(t);
        let p = ctrl.run_period(&mut io, &r);
        if reset == Some(k) {
            monitor = Monitor::new(ctrl.observer(), *settings);
        }
        event(Event::MonitorStart);
        let alarm = monitor.update(ctrl.observer(), p.predicted);
        event(Event::MonitorEnd);
        if let Some(a) = alarm {
            write_alarm(out, &a)?;
            alarm_bits(&mut fnv, &a);
            event(Event::Alarm(t, a));
        }
        inspect(t, &monitor, ctrl.observer());
        if run.maps_every > 0 && k > 0 && k % run.maps_every == 0 {
            write_maps(out, &monitor)?;
        }
        if let (Some(c), Some(s)) = (bump, io.truth()) {
            let x = s.q[0];
            if (last_x - c) * (x - c) <= 0.0 && last_x != x {
                event(Event::Pass(t));
            }
            last_x = x;
        }
        io.wait();
        if record {
            let counts = io.plant.counts();
            let scale = super::io::EncoderScale::RIG;
            let y = super::io::Channel::ALL.map(|ch| scale.position(ch, counts[ch.index()]));
            event(Event::Period {
                t,
                u: io.plant.volts(),
                y,
            });
        }
    }
    write_maps(out, &monitor)?;
    writeln!(out, "MEND {tag} hash={:016x}", fnv.0)?;
    Ok(true)
}

fn alarm_bits(fnv: &mut Fnv, a: &Alarm) {
    use super::monitor::alarm::AlarmKind;
    fnv.u64(a.period);
    fnv.u64(a.axis.index() as u64);
    let (x, y, z) = match a.kind {
        AlarmKind::FrictionDrift { change } => (change, 0.0, 0.0),
        AlarmKind::LocalFriction {
            position,
            width,
            change,
        } => (position, width, change),
        AlarmKind::StictionRise { ratio, learned } => (ratio, learned, 0.0),
        AlarmKind::ModelMismatch {
            mean_square,
            learned,
        } => (mean_square, learned, 0.0),
    };
    for v in [x, y, z] {
        fnv.u64(u64::from(v.to_bits()));
    }
}

/// The firmware's monitor section (`MBEGIN`..`MEND`): a 2 N bump on X at 0.31 m from 25 s,
/// 45 s in all, the plant stepped once per period, maps every 15 s, with
/// [`Settings::quick`] (seed 1: the bump is raised at 42.9 s; with the quick statistics other
/// seeds raise it later, or raise a false local change elsewhere). Host and QEMU print the same frames (f64 bit for bit; f32 and `F32x`
/// too, since both sides use IEEE single without fused operations).
pub const CHECK: Run = Run {
    fault: Fault::Bump {
        center: 0.31,
        width: 0.015,
        amplitude: 2.0,
    },
    onset: 25.0,
    duration: 45.0,
    seed: 1,
    reset_at: None,
    substeps: 1,
    maps_every: 7500,
    record: false,
};

/// Runs [`CHECK`] with a twin in scalar type `R`, writing its frames under `tag`; `event`
/// sees every event (the firmware brackets the monitor's updates to count their cost).
pub fn run_check<R: Real, W: Write, E: FnMut(Event)>(
    tag: &str,
    out: &mut W,
    event: E,
) -> Result<bool, fmt::Error> {
    let settings = Settings::quick(&LoopConfig::default());
    run::<R, W, E>(&CHECK, &settings, tag, out, event)
}

/// Periods of [`CHECK`] (monitor updates a cost measurement of it brackets).
pub fn check_periods() -> u64 {
    (CHECK.duration / LoopConfig::default().period) as u64
}
