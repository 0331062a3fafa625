//! The friction monitor's scenarios on the host: an operated crane (random transport moves),
//! a plant that differs from the twin's identified model and develops a fault, encoders with
//! the rig's quantum and count noise, the twin's loop and its monitor. Shared by
//! `tests/monitor_scenarios.rs` (a few seeds in CI) and `examples/monitor_table.rs` (the
//! README's table: 20 clean hours, 10 seeds per fault).
#![allow(dead_code)]

use crane_model::{Axis, Bump, Direction, Extensions, Params, State, Stiction};
use crane_twin::logic::control::{Controller, Io, IoError, LoopConfig, Move, Trajectory};
use crane_twin::logic::monitor::alarm::{Alarm, AlarmKind};
use crane_twin::logic::monitor::{Monitor, Settings};
use crane_twin::logic::plant::SimPlant;
use crane_twin::logic::prng::Prng;

/// What goes wrong on the rig, from `onset` [s] on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fault {
    /// Nothing.
    Clean,
    /// Dry friction of X and Y times `factor` (a dry rail).
    DryFriction { factor: f64 },
    /// A rough spot on X: a friction bump of `amplitude` [N], support half-width `width` [m].
    Bump {
        center: f64,
        width: f64,
        amplitude: f64,
    },
    /// Breakaway over sliding friction on X and Y becomes `ratio`.
    Stiction { ratio: f64 },
    /// Dry friction of X and Y grows by `per_hour` (fraction) per hour (temperature).
    SlowDrift { per_hour: f64 },
}

/// One run.
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
}

/// What the monitor said.
#[derive(Clone, Debug, Default)]
pub struct Outcome {
    /// Alarms with their time [s].
    pub alarms: Vec<(f64, Alarm)>,
    /// Times [s] at which the true X position crossed the bump centre (a pass).
    pub passes: Vec<f64>,
    /// Seconds simulated.
    pub seconds: f64,
    /// The monitor at the end.
    pub monitor: Option<Monitor>,
}

/// The plant the twin was identified on: nominal parameters off by a few percent (seeded), a
/// 0.5 kg payload instead of 0.457 kg.
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

/// The fault's plant at time `t` [s] (`None` before the onset or when nothing changes).
fn faulted(base: &Params, run: &Run, t: f64) -> (Params, Extensions) {
    let mut ext = Extensions::default();
    if t < run.onset {
        return (*base, ext);
    }
    match run.fault {
        Fault::Clean => (*base, ext),
        Fault::DryFriction { factor } => (scale_dry(base, factor), ext),
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
        let d = (0..3)
            .map(|i| (to[i] - self.current.to[i]).abs())
            .fold(0.0, f64::max);
        let duration = (1.875 * d / 0.25).max(0.8);
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

/// Runs one scenario: the twin's loop on the faulted plant, its monitor watching.
pub fn run(run: &Run) -> Outcome {
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
    let Ok(plant) = SimPlant::new(&base, init, cfg.period, 2) else {
        return Outcome::default();
    };
    let mut io = Noisy {
        plant,
        rng: Prng::new(rng.next_u32()),
    };
    let Ok(mut ctrl) = Controller::<f64>::new(&Params::default(), init, &cfg) else {
        return Outcome::default();
    };
    let mut monitor = Monitor::new(ctrl.observer(), Settings::for_loop(&cfg));
    let mut op = Operator {
        rng: Prng::new(rng.next_u32()),
        from: START,
        current: Move {
            start: 0.0,
            duration: 1.0,
            to: START,
        },
    };
    let mut out = Outcome::default();
    let periods = (run.duration / cfg.period) as u64;
    let retune_every = (10.0 / cfg.period) as u64;
    let onset = (run.onset / cfg.period) as u64;
    let bump = match run.fault {
        Fault::Bump { center, .. } => Some(center),
        _ => None,
    };
    let mut last_x = START[0];
    for k in 0..periods {
        let t = k as f64 * cfg.period;
        let changes = k == onset
            || (matches!(run.fault, Fault::SlowDrift { .. }) && k > onset && k % retune_every == 0);
        if changes {
            let (p, ext) = faulted(&base, run, t);
            let _ = io.plant.retune(&p, &ext);
        }
        let r = op.reference(t).at::<f64>(t);
        let p = ctrl.run_period(&mut io, &r);
        if run.reset_at.is_some_and(|r| (r / cfg.period) as u64 == k) {
            monitor = Monitor::new(ctrl.observer(), Settings::for_loop(&cfg));
        }
        if let Some(a) = monitor.update(ctrl.observer(), p.predicted) {
            out.alarms.push((t, a));
        }
        if let (Some(c), Some(s)) = (bump, io.truth()) {
            let x = s.q[0];
            if (last_x - c) * (x - c) <= 0.0 && last_x != x {
                out.passes.push(t);
            }
            last_x = x;
        }
        io.wait();
    }
    out.seconds = run.duration;
    out.monitor = Some(monitor);
    out
}

/// Whether an alarm is what the fault should raise, where it should.
pub fn expected(fault: &Fault, a: &Alarm) -> bool {
    match (fault, a.kind) {
        (Fault::DryFriction { .. }, AlarmKind::FrictionDrift { change }) => {
            a.axis != Axis::Rope && change > 0.0
        }
        (
            Fault::Bump { center, .. },
            AlarmKind::LocalFriction {
                position, change, ..
            },
        ) => a.axis == Axis::X && (f64::from(position) - center).abs() <= 0.02 && change > 0.0,
        (Fault::Stiction { .. }, AlarmKind::StictionRise { .. }) => a.axis != Axis::Rope,
        _ => false,
    }
}
