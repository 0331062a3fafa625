//! Fixed-step integration of the hybrid automaton.
//!
//! Inputs are held over the step (zero-order hold). Inside a mode the continuous part is
//! integrated by classic RK4. Events of a moving axis (velocity reaching 0, position reaching
//! the limit it moves towards) and breakaway of a stopped axis are detected at the end of the
//! RK4 segment and located inside it: velocity and limit events by bisection (30 iterations)
//! on a cubic Hermite interpolant (error O(h^4), so the event time is not O(h)-late),
//! breakaway by the secant of the holding-force margin. The state is then recomputed at the
//! event by RK4 from the segment start, the reset applied, the guards re-evaluated, and the
//! rest of the step integrated in the new modes.
//!
//! An axis reaching its end stop receives a plastic impact on its own coordinate
//! ([`end_stop_impulse`](crate::dynamics)): the payload keeps its velocity and the kinetic
//! energy can only fall.
//!
//! Bounded work per step: at most `budget` segments ([`MAX_SEGMENTS`] by default; a smaller
//! budget is set with [`Crane::with_segment_budget`](crate::Crane::with_segment_budget)).
//! The last segment locates nothing: what it detects is reset at the step end (late resets).
//! Worst case for budget `n`, counted in evaluations of the dynamics and end-stop solves
//! (each about one evaluation's work): the initial resolution (4), per segment but the last
//! one RK4 (3), relocation (3), at most 3 end-stop solves and a resolution (4), then the last
//! segment's RK4 (3) and the step end (at most 3 + 2 end-stop solves: each drive axis is
//! stopped at most once by the two late sweeps, and two swing stops): `13 (n - 1) + 12`
//! pieces, 103 for the default 8 and 12 for budget 1; the usual step without event costs 4 evaluations whatever the budget.

use crate::dynamics::{end_stop_impulse, eval, Coeffs, Eval, Law, Singular};
use crate::modes::{candidate, margin, resolve, Mode};
use crate::real::Real;
use crate::state::State;

/// Maximum number of integration segments (events + 1) in one step, and the default segment
/// budget ([`Crane::with_segment_budget`](crate::Crane::with_segment_budget) lowers it).
pub const MAX_SEGMENTS: usize = 8;
/// Bisection iterations when locating a velocity or limit event (resolution `h / 2^30`).
pub const BISECTION_ITERATIONS: usize = 30;

/// One classic RK4 step of length `dt` from `y` with first stage `e1 = eval(y)`.
/// Components of stopped axes are copied unchanged. Returns the new state and the last
/// stage's evaluation (an O(h^3) estimate of the dynamics at the end, used for events).
fn rk4<R: Real>(
    c: &Coeffs<R>,
    law: Law<R>,
    y: &State<R>,
    u: &[R; 3],
    modes: &[Mode; 3],
    e1: &Eval<R>,
    dt: R,
) -> Result<(State<R>, Eval<R>), Singular> {
    let held = held_components(law, modes);
    let half = dt * R::HALF;
    let y2 = advance(y, &y.qd, &e1.qdd, half, &held);
    let e2 = eval(c, law, &y2, modes, u)?;
    let y3 = advance(y, &y2.qd, &e2.qdd, half, &held);
    let e3 = eval(c, law, &y3, modes, u)?;
    let y4 = advance(y, &y3.qd, &e3.qdd, dt, &held);
    let e4 = eval(c, law, &y4, modes, u)?;
    let w = dt / R::SIX;
    let mut yn = *y;
    for (j, &hj) in held.iter().enumerate() {
        if hj {
            continue;
        }
        let dq = y.qd[j] + R::TWO * y2.qd[j] + R::TWO * y3.qd[j] + y4.qd[j];
        let dv = e1.qdd[j] + R::TWO * e2.qdd[j] + R::TWO * e3.qdd[j] + e4.qdd[j];
        yn.q[j] = y.q[j] + w * dq;
        yn.qd[j] = y.qd[j] + w * dv;
    }
    Ok((yn, e4))
}

/// Which of the five coordinates are held fixed (stopped drive axes, hybrid law only).
fn held_components<R: Real>(law: Law<R>, modes: &[Mode; 3]) -> [bool; 5] {
    let mut held = [false; 5];
    if law == Law::Hybrid {
        for (h, m) in held.iter_mut().zip(modes) {
            *h = *m == Mode::Stopped;
        }
    }
    held
}

/// RK4 stage state `y + dt * (v, a)`, held components unchanged.
fn advance<R: Real>(y: &State<R>, v: &[R; 5], a: &[R; 5], dt: R, held: &[bool; 5]) -> State<R> {
    let mut s = *y;
    for (j, &hj) in held.iter().enumerate() {
        if !hj {
            s.q[j] = y.q[j] + dt * v[j];
            s.qd[j] = y.qd[j] + dt * a[j];
        }
    }
    s
}

/// Cubic Hermite interpolant on `th` in [0, 1] through `y0`, `y1` with end slopes `m0`, `m1`
/// (slopes already scaled by the interval length).
fn hermite<R: Real>(th: R, y0: R, y1: R, m0: R, m1: R) -> R {
    let t2 = th * th;
    let t3 = t2 * th;
    let h00 = R::TWO * t3 - R::THREE * t2 + R::ONE;
    let h10 = t3 - R::TWO * t2 + th;
    let h01 = -R::TWO * t3 + R::THREE * t2;
    let h11 = t3 - t2;
    h00 * y0 + h10 * m0 + h01 * y1 + h11 * m1
}

/// First `th` in (0, 1] where `still(th)` turns false, by bisection (`still(1)` is false).
fn bisect<R: Real>(still: impl Fn(R) -> bool) -> R {
    let mut lo = R::ZERO;
    let mut hi = R::ONE;
    for _ in 0..BISECTION_ITERATIONS {
        let mid = R::HALF * (lo + hi);
        if still(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// Kind of event found in a segment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Velocity,
    Limit,
    Breakaway,
}

/// Velocity violation of a moving axis: its velocity is zero or points against its mode.
pub(crate) fn velocity_violated<R: Real>(mode: Mode, qd: R) -> bool {
    match mode {
        Mode::Positive => qd <= R::ZERO,
        Mode::Negative => qd >= R::ZERO,
        Mode::Stopped => false,
    }
}

/// Limit violation of a moving axis: it reached the limit it moves towards.
pub(crate) fn limit_violated<R: Real>(mode: Mode, q: R, min: R, max: R) -> bool {
    match mode {
        Mode::Positive => q >= max,
        Mode::Negative => q <= min,
        Mode::Stopped => false,
    }
}

fn clamp<R: Real>(q: R, min: R, max: R) -> R {
    if q > max {
        max
    } else if q < min {
        min
    } else {
        q
    }
}

/// Applies the reset of an axis that stops by a velocity event (`qd := 0`, `q` clamped).
pub(crate) fn stop_velocity<R: Real>(
    c: &Coeffs<R>,
    y: &mut State<R>,
    modes: &mut [Mode; 3],
    i: usize,
) {
    let ax = &c.axes[i];
    y.qd[i] = R::ZERO;
    y.q[i] = clamp(y.q[i], ax.min, ax.max);
    modes[i] = Mode::Stopped;
}

/// Applies the reset of an axis that reached a limit: a plastic impact on its end stop
/// ([`end_stop_impulse`]), then `q := limit`, `qd := 0`.
pub(crate) fn stop_limit<R: Real>(
    c: &Coeffs<R>,
    y: &mut State<R>,
    modes: &mut [Mode; 3],
    i: usize,
) -> Result<(), Singular> {
    end_stop_impulse(c, y, modes, i)?;
    let ax = &c.axes[i];
    y.q[i] = if modes[i] == Mode::Positive {
        ax.max
    } else {
        ax.min
    };
    y.qd[i] = R::ZERO;
    modes[i] = Mode::Stopped;
    Ok(())
}

/// Resets every moving axis whose velocity or position violates its mode; returns how many.
pub(crate) fn sweep<R: Real>(
    c: &Coeffs<R>,
    y: &mut State<R>,
    modes: &mut [Mode; 3],
) -> Result<u8, Singular> {
    let mut n = 0;
    for i in 0..3 {
        let (min, max) = (c.axes[i].min, c.axes[i].max);
        if limit_violated(modes[i], y.q[i], min, max) {
            stop_limit(c, y, modes, i)?;
            n += 1;
        } else if velocity_violated(modes[i], y.qd[i]) {
            stop_velocity(c, y, modes, i);
            n += 1;
        }
    }
    Ok(n)
}

/// What happened during one step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepReport {
    /// Events located inside the step (velocity zero, limit, breakaway).
    pub events: u8,
    /// Resets applied at the end of the step without location, because the step ran out of
    /// segments (its segment budget, [`MAX_SEGMENTS`] by default). Normally 0 with the
    /// default budget.
    pub late_resets: u8,
    /// Swing angles stopped at [`SWING_STOP`] at the end of the step. Normally 0.
    pub swing_stops: u8,
}

/// Swing stops [rad]: each swing angle is kept within this angle of the vertical
/// (`alpha in [pi/2 - SWING_STOP, pi/2 + SWING_STOP]`, `beta in [-SWING_STOP, SWING_STOP]`),
/// about 80 degrees. Beyond them the swing coordinates approach their singularity
/// (`M44 = m_p L^2 sin^2 alpha`) and a taut-rope pendulum is no longer a model of the rig; a
/// (virtual) stop there is a plastic impact on that angle, so the twin stays in its domain
/// and usable whatever the inputs.
pub const SWING_STOP: f64 = 1.4;

/// Applies the swing stops at the end of a step: an angle beyond its stop is clamped to it
/// and, if still moving outwards, receives the end-stop impulse and `qd := 0`.
fn swing_stops<R: Real>(
    c: &Coeffs<R>,
    y: &mut State<R>,
    modes: &[Mode; 3],
) -> Result<u8, Singular> {
    let half_pi = core::f64::consts::FRAC_PI_2;
    let bounds = [
        (3, half_pi - SWING_STOP, half_pi + SWING_STOP),
        (4, -SWING_STOP, SWING_STOP),
    ];
    let mut n = 0;
    for (j, lo, hi) in bounds {
        let (lo, hi) = (R::from_f64(lo), R::from_f64(hi));
        let q = y.q[j];
        if q > hi || q < lo {
            let outward = if q > hi {
                y.qd[j] > R::ZERO
            } else {
                y.qd[j] < R::ZERO
            };
            if outward {
                end_stop_impulse(c, y, modes, j)?;
                y.qd[j] = R::ZERO;
            }
            y.q[j] = clamp(q, lo, hi);
            n += 1;
        }
    }
    Ok(n)
}

/// Advances the hybrid automaton by `h` with held input `u` (already saturated), in at most
/// `budget` segments (`1..=MAX_SEGMENTS`; values outside are clamped into that range).
/// On error nothing is written back: the caller keeps the old state.
pub(crate) fn step_hybrid<R: Real>(
    c: &Coeffs<R>,
    h: R,
    y0: &State<R>,
    modes0: &[Mode; 3],
    u: &[R; 3],
    budget: usize,
) -> Result<(State<R>, [Mode; 3], StepReport), Singular> {
    let budget = budget.clamp(1, MAX_SEGMENTS);
    let law = Law::Hybrid;
    let mut y = *y0;
    let mut modes = *modes0;
    let mut report = StepReport::default();
    let mut done = R::ZERO;
    let mut e1 = resolve(c, law, &y, u, &mut modes)?;
    for seg in 0..budget {
        let tau = h - done;
        let (yn, e4) = rk4(c, law, &y, u, &modes, &e1, tau)?;
        if seg + 1 == budget {
            // The last segment locates nothing (so it does not search either): whatever it
            // crossed is reset at the step end by the late sweep.
            y = yn;
            break;
        }
        // Earliest event in this segment, as a fraction of tau.
        let mut first: Option<(R, usize, Kind)> = None;
        let mut consider = |th: R, i: usize, k: Kind| {
            let earlier = match first {
                Some((b, _, _)) => th < b,
                None => true,
            };
            if earlier {
                first = Some((th, i, k));
            }
        };
        for (i, ax) in c.axes.iter().enumerate() {
            let mode = modes[i];
            if mode == Mode::Stopped {
                if let Some((dir, m1)) = candidate(ax, y.q[i], e4.hold[i]) {
                    let m0 = margin(ax, y.q[i], e1.hold[i], dir);
                    if m0 < R::ZERO {
                        let th = m0 / (m0 - m1);
                        let th = if th > R::ONE { R::ONE } else { th };
                        consider(th, i, Kind::Breakaway);
                    }
                }
                continue;
            }
            if velocity_violated(mode, yn.qd[i]) {
                let (v0, v1) = (y.qd[i], yn.qd[i]);
                let (s0, s1) = (tau * e1.qdd[i], tau * e4.qdd[i]);
                let th = bisect(|t| {
                    let v = hermite(t, v0, v1, s0, s1);
                    !velocity_violated(mode, v)
                });
                consider(th, i, Kind::Velocity);
            }
            if limit_violated(mode, yn.q[i], ax.min, ax.max) {
                let (p0, p1) = (y.q[i], yn.q[i]);
                let (s0, s1) = (tau * y.qd[i], tau * yn.qd[i]);
                let th = bisect(|t| {
                    let p = hermite(t, p0, p1, s0, s1);
                    !limit_violated(mode, p, ax.min, ax.max)
                });
                consider(th, i, Kind::Limit);
            }
        }
        let Some((th, i, kind)) = first else {
            y = yn;
            break;
        };
        let s = th * tau;
        let (ye, _) = rk4(c, law, &y, u, &modes, &e1, s)?;
        y = ye;
        match kind {
            Kind::Velocity => stop_velocity(c, &mut y, &mut modes, i),
            Kind::Limit => stop_limit(c, &mut y, &mut modes, i)?,
            Kind::Breakaway => {}
        }
        sweep(c, &mut y, &mut modes)?;
        report.events = report.events.saturating_add(1);
        done = done + s;
        e1 = resolve(c, law, &y, u, &mut modes)?;
        if done >= h {
            break;
        }
    }
    report.late_resets = sweep(c, &mut y, &mut modes)?;
    report.swing_stops = swing_stops(c, &mut y, &modes)?;
    if report.swing_stops > 0 {
        // The swing-stop impulse changes the drive velocities too: stop any it reversed.
        report.late_resets += sweep(c, &mut y, &mut modes)?;
    }
    Ok((y, modes, report))
}

/// Advances the smooth `tanh` comparison model by one plain RK4 step of length `h`;
/// limits by projection (position clamped, velocity into the limit zeroed).
pub(crate) fn step_smooth<R: Real>(
    c: &Coeffs<R>,
    gamma: R,
    h: R,
    y0: &State<R>,
    u: &[R; 3],
) -> Result<State<R>, Singular> {
    let law = Law::Tanh(gamma);
    let modes = [Mode::Positive; 3];
    let e1 = eval(c, law, y0, &modes, u)?;
    let (mut y, _) = rk4(c, law, y0, u, &modes, &e1, h)?;
    for (i, ax) in c.axes.iter().enumerate() {
        if y.q[i] > ax.max {
            y.q[i] = ax.max;
            if y.qd[i] > R::ZERO {
                y.qd[i] = R::ZERO;
            }
        } else if y.q[i] < ax.min {
            y.q[i] = ax.min;
            if y.qd[i] < R::ZERO {
                y.qd[i] = R::ZERO;
            }
        }
    }
    Ok(y)
}
