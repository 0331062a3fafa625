//! The fixed cross-check scenarios: initial state, parameters and a deterministic input
//! program each, run on the model and reduced to a text digest (the exact bits of the state
//! every few steps and an FNV-1a hash over every step's bits). The firmware prints the digest
//! under QEMU; the host test regenerates it and compares the text.

use super::digest::{write_state, Fnv};
use super::prng::Prng;
use core::f64::consts::{FRAC_PI_2, PI};
use core::fmt::Write;
use crane_model::{Config, Crane, Mode, Params, Real, State, StepError};

/// Which input program a scenario runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Input {
    /// Sinusoids around the breakaway thresholds of X and Y with held noise: stick-slip.
    StickSlip,
    /// 12 V square waves on X and Y: end-stop hits, reversals at full speed.
    EndStops,
    /// Random held rope voltages: hoisting, lowering, sticking, the rope's lower limit.
    Rope,
    /// Random levels held for random times on all axes.
    Random,
    /// Slow triangles across the breakaway thresholds (light payload).
    Breakaway,
}

/// One cross-check scenario.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scenario {
    /// Name printed in the digest.
    pub name: &'static str,
    /// Step [s].
    pub h: f64,
    /// Number of steps.
    pub steps: u32,
    /// A state line is printed every `every` steps (and after the last).
    pub every: u32,
    /// Initial positions.
    pub q0: [f64; 5],
    /// Initial velocities.
    pub qd0: [f64; 5],
    /// Payload mass [kg] (the other parameters are the defaults).
    pub payload: f64,
    /// PRNG seed.
    pub seed: u32,
    /// Input program.
    pub input: Input,
}

impl Scenario {
    /// The model of this scenario: default parameters with its payload, its step, its
    /// initial state.
    pub fn crane<R: Real>(&self) -> Result<Crane<R>, crane_model::Error> {
        let params = Params {
            payload_mass: self.payload,
            ..Params::default()
        };
        let config = Config {
            h: self.h,
            ..Config::default()
        };
        Crane::<R>::new(
            &params,
            config,
            State {
                q: self.q0,
                qd: self.qd0,
            },
        )
    }
}

/// The scenarios, in the order the firmware prints them.
pub const SCENARIOS: [Scenario; 5] = [
    Scenario {
        name: "stick_slip",
        h: 1e-3,
        steps: 4000,
        every: 250,
        q0: [0.25, 0.30, 0.35, FRAC_PI_2, 0.0],
        qd0: [0.0; 5],
        payload: 0.457,
        seed: 1,
        input: Input::StickSlip,
    },
    Scenario {
        name: "end_stops",
        h: 2e-3,
        steps: 3000,
        every: 200,
        q0: [0.30, 0.30, 0.40, FRAC_PI_2, 0.0],
        qd0: [0.0; 5],
        payload: 0.457,
        seed: 2,
        input: Input::EndStops,
    },
    Scenario {
        name: "rope",
        h: 1e-3,
        steps: 4000,
        every: 250,
        q0: [0.20, 0.30, 0.14, FRAC_PI_2 + 0.05, 0.02],
        qd0: [0.0, 0.0, 0.0, 0.1, 0.0],
        payload: 0.457,
        seed: 7,
        input: Input::Rope,
    },
    Scenario {
        name: "random",
        h: 2e-3,
        steps: 5000,
        every: 250,
        q0: [0.25, 0.31, 0.30, FRAC_PI_2 - 0.1, 0.05],
        qd0: [0.01, -0.02, 0.0, 0.0, 0.1],
        payload: 0.457,
        seed: 12345,
        input: Input::Random,
    },
    Scenario {
        name: "breakaway",
        h: 1e-3,
        steps: 6000,
        every: 500,
        q0: [0.10, 0.50, 0.40, FRAC_PI_2, 0.0],
        qd0: [0.0; 5],
        payload: 0.064,
        seed: 3,
        input: Input::Breakaway,
    },
];

/// `sin` through libm (never std's, which differs between platforms).
fn sin(x: f64) -> f64 {
    <f64 as Real>::sin(x)
}

fn sgn(x: f64) -> f64 {
    if x < 0.0 {
        -1.0
    } else {
        1.0
    }
}

/// Triangle wave in `[-1, 1]` with period `p` steps, from step `k` (exact: integers and
/// divisions by a power-free integer, correctly rounded on every platform).
fn triangle(k: u32, p: u32) -> f64 {
    let f = f64::from(k % p) / f64::from(p);
    let v = 4.0 * f;
    if f < 0.25 {
        v
    } else if f < 0.75 {
        2.0 - v
    } else {
        v - 4.0
    }
}

/// State of an input program between steps (held levels).
#[derive(Clone, Copy, Debug)]
pub struct InputGen {
    rng: Prng,
    held: [f64; 3],
    left: u32,
}

impl InputGen {
    /// Starts the program of `sc`.
    pub fn new(sc: &Scenario) -> Self {
        InputGen {
            rng: Prng::new(sc.seed),
            held: [0.0; 3],
            left: 0,
        }
    }

    /// Voltages for step `k` (0-based) at time `t = k h`.
    pub fn input(&mut self, sc: &Scenario, k: u32) -> [f64; 3] {
        let t = f64::from(k) * sc.h;
        match sc.input {
            Input::StickSlip => {
                if k % 20 == 0 {
                    for v in self.held.iter_mut() {
                        *v = self.rng.uniform();
                    }
                }
                [
                    0.55 * sin(2.0 * PI * 0.7 * t) + 0.15 * self.held[0],
                    0.5 * sin(2.0 * PI * 0.45 * t + 1.0) + 0.15 * self.held[1],
                    -0.5 + 0.8 * sin(2.0 * PI * 0.3 * t) + 0.4 * self.held[2],
                ]
            }
            Input::EndStops => [
                12.0 * sgn(sin(2.0 * PI * t / 4.0 + 0.3)),
                12.0 * sgn(sin(2.0 * PI * t / 4.4)),
                12.0 * sgn(sin(2.0 * PI * t / 5.0)),
            ],
            Input::Rope => {
                if k % 250 == 0 {
                    self.held = [
                        1.5 * self.rng.uniform(),
                        1.5 * self.rng.uniform(),
                        12.0 * self.rng.uniform() - 2.0,
                    ];
                }
                self.held
            }
            Input::Random => {
                if self.left == 0 {
                    self.left = self.rng.range(20, 200);
                    self.held = [
                        6.0 * self.rng.uniform(),
                        6.0 * self.rng.uniform(),
                        8.0 * self.rng.uniform(),
                    ];
                }
                self.left -= 1;
                self.held
            }
            Input::Breakaway => [
                1.0 * triangle(k, 3000),
                0.9 * triangle(k + 750, 2000),
                2.5 * triangle(k + 1500, 3000),
            ],
        }
    }
}

/// What a scenario did, counted per drive axis (X, Y, rope).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// FNV-1a over every step's state bits, modes and result code.
    pub hash: u64,
    /// Events located inside steps, in all.
    pub events: u32,
    /// Late resets, in all.
    pub late: u32,
    /// Rejected steps.
    pub errors: u32,
    /// Stopped -> moving transitions (breakaways).
    pub breakaways: [u32; 3],
    /// Moving -> Stopped transitions.
    pub stops: [u32; 3],
    /// Changes of the direction of motion (through Stopped or within a step).
    pub reversals: [u32; 3],
    /// Steps that end stopped at a limit after moving.
    pub limits: [u32; 3],
}

/// Result code mixed into the hash: events and late resets, or the error.
fn code(r: &Result<crane_model::StepReport, StepError>) -> u8 {
    match r {
        Ok(rep) => (rep.events & 0x0f) | ((rep.late_resets & 0x07) << 4),
        Err(StepError::InputNotFinite { .. }) => 0x80,
        Err(StepError::Singular) => 0x81,
        Err(StepError::NonFinite) => 0x82,
        Err(StepError::OutOfDomain) => 0x83,
        Err(StepError::OutOfLimits { .. }) => 0x84,
    }
}

/// Runs `sc` on `Crane<R>` and writes its digest to `out`, tagged `tag` (e.g. `"f64"`):
/// `BEGIN`, one `S` line every `sc.every` steps, `END` with the hash and the counts.
pub fn run<R: Real, W: Write>(
    sc: &Scenario,
    tag: &str,
    out: &mut W,
) -> Result<Summary, core::fmt::Error> {
    writeln!(
        out,
        "BEGIN {} {} h_us={} steps={}",
        sc.name,
        tag,
        (sc.h * 1e6 + 0.5) as u32,
        sc.steps
    )?;
    let mut crane = match sc.crane::<R>() {
        Ok(c) => c,
        Err(e) => {
            writeln!(out, "ERROR {} {}", sc.name, e)?;
            return Ok(Summary::default());
        }
    };
    let mut sum = Summary::default();
    let mut fnv = Fnv::default();
    let mut gen = InputGen::new(sc);
    let mut modes = crane.modes();
    let mut last_dir = modes;
    write!(out, "S 0")?;
    write_state(out, &crane.state(), &modes)?;
    writeln!(out)?;
    for k in 0..sc.steps {
        let u = gen.input(sc, k).map(R::from_f64);
        let r = crane.step(u);
        match &r {
            Ok(rep) => {
                sum.events += u32::from(rep.events);
                sum.late += u32::from(rep.late_resets);
            }
            Err(_) => sum.errors += 1,
        }
        let s = crane.state();
        let new = crane.modes();
        fnv.step(&s, &new, code(&r));
        let ax = crane.coeffs().axes;
        for i in 0..3 {
            let (a, b) = (modes[i], new[i]);
            if a == Mode::Stopped && b != Mode::Stopped {
                sum.breakaways[i] += 1;
            }
            if a != Mode::Stopped && b == Mode::Stopped {
                sum.stops[i] += 1;
                if s.q[i] == ax[i].min || s.q[i] == ax[i].max {
                    sum.limits[i] += 1;
                }
            }
            if b != Mode::Stopped {
                if last_dir[i] != Mode::Stopped && last_dir[i] != b {
                    sum.reversals[i] += 1;
                }
                last_dir[i] = b;
            }
        }
        modes = new;
        let n = k + 1;
        if n % sc.every == 0 || n == sc.steps {
            write!(out, "S {n}")?;
            write_state(out, &s, &modes)?;
            writeln!(out)?;
        }
    }
    sum.hash = fnv.0;
    writeln!(
        out,
        "END {} {} hash={:016x} events={} late={} errors={} breakaways={:?} stops={:?} reversals={:?} limits={:?}",
        sc.name,
        tag,
        sum.hash,
        sum.events,
        sum.late,
        sum.errors,
        sum.breakaways,
        sum.stops,
        sum.reversals,
        sum.limits
    )?;
    Ok(sum)
}
