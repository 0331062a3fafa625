//! Physical effects beyond the paper's model, switched off by default.
//!
//! These are the model extensions that the discrepancy workbench fits when measured data shows
//! the baseline is wrong: localised friction bumps, Stribeck stiction, a constant bias force,
//! an input dead band and an input delay. All are fixed-capacity and allocation-free, so the
//! firmware can run the extended model. A disabled effect adds no floating-point operation,
//! so the baseline's bits are unchanged.

use crate::params::{check, Error, Problem};
use crate::real::Real;

/// Maximum number of localised friction bumps over all axes.
pub const MAX_BUMPS: usize = 4;
/// Capacity of the input delay line, in steps (delays up to `MAX_DELAY_STEPS - 1` steps).
pub const MAX_DELAY_STEPS: usize = 64;

/// A drive axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Axis {
    /// Rail, along X.
    X,
    /// Trolley, along Y.
    Y,
    /// Rope length.
    Rope,
}

impl Axis {
    /// Index in the model's drive-axis arrays (X 0, Y 1, rope 2).
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Rope => 2,
        }
    }
}

/// Which motion direction an effect applies to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Direction {
    /// Positive velocity only.
    Positive,
    /// Negative velocity only.
    Negative,
    /// Both directions.
    Both,
}

/// A localised bump (or dip, with negative amplitude) of dry friction over a stretch of an
/// axis: `amplitude * (1 - s^2)^2` for `|s| < 1`, `s = (q - center) / width`, added to the
/// dry-friction magnitude before its clamp at zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bump {
    /// Axis it lies on.
    pub axis: Axis,
    /// Centre [m].
    pub center: f64,
    /// Half-width of its support [m] (> 0); the full width at half height is about `1.1 width`.
    pub width: f64,
    /// Peak change of the dry-friction magnitude [N] (negative for a dip).
    pub amplitude: f64,
    /// Directions of motion it affects.
    pub direction: Direction,
}

/// Stribeck stiction: breakaway force `ratio * Cbar(q)`, and sliding friction
/// `Cbar(q) (1 + (ratio - 1) exp(-(v / velocity)^2))` falling to `Cbar(q)` as speed grows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stiction {
    /// Breakaway over sliding friction (>= 1; 1 is no stiction).
    pub ratio: f64,
    /// Stribeck velocity scale [m/s] (> 0).
    pub velocity: f64,
}

/// All extensions; `Extensions::default()` is the paper's model.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Extensions {
    /// Localised friction bumps (at most [`MAX_BUMPS`]).
    pub bumps: heapless::Vec<Bump, MAX_BUMPS>,
    /// Stiction per drive axis (X, Y, rope).
    pub stiction: [Option<Stiction>; 3],
    /// Constant bias force per drive axis [N], along the axis.
    pub force_offset: [f64; 3],
    /// Input dead band per drive axis [V] (>= 0): `|u| <= d` gives 0, else `u - sign(u) d`.
    pub deadzone: [f64; 3],
    /// Input delay per drive axis [s] (>= 0), rounded to whole steps of the simulator.
    pub delay: [f64; 3],
}

const BUMP_FIELDS: [[&str; 3]; MAX_BUMPS] = [
    ["bumps[0].center", "bumps[0].width", "bumps[0].amplitude"],
    ["bumps[1].center", "bumps[1].width", "bumps[1].amplitude"],
    ["bumps[2].center", "bumps[2].width", "bumps[2].amplitude"],
    ["bumps[3].center", "bumps[3].width", "bumps[3].amplitude"],
];
const STICTION_FIELDS: [[&str; 2]; 3] = [
    ["stiction[0].ratio", "stiction[0].velocity"],
    ["stiction[1].ratio", "stiction[1].velocity"],
    ["stiction[2].ratio", "stiction[2].velocity"],
];
const OFFSET_FIELDS: [&str; 3] = ["force_offset[0]", "force_offset[1]", "force_offset[2]"];
const DEADZONE_FIELDS: [&str; 3] = ["deadzone[0]", "deadzone[1]", "deadzone[2]"];
const DELAY_FIELDS: [&str; 3] = ["delay[0]", "delay[1]", "delay[2]"];

impl Extensions {
    /// Checks every field and converts the delays to whole steps of `h` [s].
    pub fn validate(&self, h: f64) -> Result<[usize; 3], Error> {
        for (b, names) in self.bumps.iter().zip(BUMP_FIELDS.iter()) {
            let [c, w, a] = *names;
            check(c, b.center, Problem::NotFinite)?;
            check(w, b.width, Problem::NotPositive)?;
            check(a, b.amplitude, Problem::NotFinite)?;
        }
        for (s, names) in self.stiction.iter().zip(STICTION_FIELDS.iter()) {
            if let Some(s) = s {
                let [r, v] = *names;
                check(r, s.ratio, Problem::NotFinite)?;
                if s.ratio < 1.0 {
                    return Err(Error {
                        field: r,
                        problem: Problem::BelowOne,
                        value: s.ratio,
                    });
                }
                check(v, s.velocity, Problem::NotPositive)?;
            }
        }
        for (v, name) in self.force_offset.iter().zip(OFFSET_FIELDS) {
            check(name, *v, Problem::NotFinite)?;
        }
        for (v, name) in self.deadzone.iter().zip(DEADZONE_FIELDS) {
            check(name, *v, Problem::Negative)?;
        }
        let mut steps = [0usize; 3];
        for ((v, name), n) in self.delay.iter().zip(DELAY_FIELDS).zip(steps.iter_mut()) {
            check(name, *v, Problem::Negative)?;
            let k = libm::round(*v / h);
            if k > (MAX_DELAY_STEPS - 1) as f64 {
                return Err(Error {
                    field: name,
                    problem: Problem::TooLarge,
                    value: *v,
                });
            }
            *n = k as usize;
        }
        Ok(steps)
    }
}

/// Input dead band [V]: `|u| <= d` gives 0, else `u - sign(u) d` (the amplifier's dead zone).
#[inline]
pub fn deadband<R: Real>(u: R, d: R) -> R {
    if u > d {
        u - d
    } else if u < -d {
        u + d
    } else {
        R::ZERO
    }
}

/// A delay line of input vectors with fixed capacity, oldest overwritten.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DelayLine<R: Copy> {
    buf: [[R; 3]; MAX_DELAY_STEPS],
    head: usize,
}

impl<R: Copy> DelayLine<R> {
    /// A line filled with `zero` (inputs before the start are taken as zero).
    pub(crate) fn new(zero: R) -> Self {
        DelayLine {
            buf: [[zero; 3]; MAX_DELAY_STEPS],
            head: 0,
        }
    }

    /// Pushes `u`, then returns per axis the input pushed `steps[i]` pushes ago (0: `u`).
    pub(crate) fn push(&mut self, u: [R; 3], steps: &[usize; 3]) -> [R; 3] {
        self.head = (self.head + 1) % MAX_DELAY_STEPS;
        if let Some(slot) = self.buf.get_mut(self.head) {
            *slot = u;
        }
        let mut out = u;
        for (i, (o, &k)) in out.iter_mut().zip(steps).enumerate() {
            let idx = (self.head + MAX_DELAY_STEPS - k % MAX_DELAY_STEPS) % MAX_DELAY_STEPS;
            if let Some(v) = self.buf.get(idx).and_then(|row| row.get(i)) {
                *o = *v;
            }
        }
        out
    }
}
