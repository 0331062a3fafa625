//! One fixed step of the drive's hybrid automaton.
//!
//! The applied force is held over the step. Inside a mode the motion is integrated by classic
//! RK4. A moving axis whose velocity reaches 0, or whose position reaches the end stop it moves
//! towards, is stopped at the event, located inside the step by bisection (30 iterations) on a
//! cubic Hermite interpolant as in the crane's integrator; the guards are then re-evaluated at
//! once, so a reversal passes through `Stopped` in the same instant. A stopped axis keeps a
//! constant holding force for the rest of the step (its position and the applied force do not
//! change), so it can only break away at the start of a step or right after an event.
//!
//! Bounded work per step: at most [`DRIVE_MAX_SEGMENTS`] segments. Counted in evaluations of
//! the acceleration: the initial resolution (at most 2), per segment but the last one RK4 (3),
//! relocation (3) and a resolution (2), the last segment's RK4 (3): `8 (n - 1) + 5`, 61 for
//! `n = 8`, plus at most `2 * 30` Hermite evaluations per located segment (420). The usual
//! moving step costs 4 evaluations and a resting step at most 1 position-force evaluation (none
//! after the first: [`Drive`](super::Drive) keeps it while the axis rests).
//!
//! The two optional friction effects keep these counts and make an evaluation dearer:
//! Stribeck weakening adds to every moving evaluation one `exp` (libm), a division, two
//! multiplications, a negation, a subtraction and an addition (the usual moving step: 4
//! `exp`); load friction adds once per step, before any evaluation, an absolute value, a
//! multiplication and four additions (the step's dry levels in a copy of the coefficients,
//! `Coeffs::loaded`), nothing per evaluation. With both off no floating-point operation is
//! added (a flag test per evaluation and per step). A resting step decides its breakaway
//! guards before any friction evaluation, so it evaluates no `exp` while it holds.
//! Localised friction adds to every evaluation, and to every resolution of a stopped axis,
//! the bump kernel at its position (a subtraction, a division, two comparisons; inside the
//! support a subtraction, three multiplications and the additions to the levels it uses);
//! a resting axis keeps `b(x)` with its position force. The step is compiled twice
//! (`const BUMP: bool`; [`Drive`](super::Drive) picks one of four compiled steps, load
//! friction and bump on or off, with one test of a byte per step): without a bump it has
//! neither the kernel nor a flag test for it.

use super::force::Coeffs;
use crate::modes::Mode;
use crate::real::Real;

/// Largest number of integration segments (located events + 1) in one drive step.
pub const DRIVE_MAX_SEGMENTS: usize = 8;
/// Bisection iterations when locating a velocity or end-stop event (resolution `h / 2^30`).
const BISECTION_ITERATIONS: usize = 30;

/// What happened during one drive step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DriveReport {
    /// Events located inside the step (velocity reaching 0, end stop reached).
    pub events: u8,
    /// Stops applied at the end of the step without location because the step ran out of
    /// segments ([`DRIVE_MAX_SEGMENTS`]), or because a release decided at the very end of the
    /// step left the axis with zero velocity (released again by the next step). Normally 0.
    pub late_resets: u8,
}

/// Resolves the mode of the axis at `(x, v)` under the applied force `f`; returns the mode
/// and the acceleration in it. A moving axis keeps its mode; a stopped one goes through
/// [`release`] with its holding force `f - position_force(x)` and the localised friction at
/// `x`.
#[inline]
pub(crate) fn resolve<R: Real, const BUMP: bool>(
    c: &Coeffs<R>,
    x: R,
    v: R,
    mode: Mode,
    f: R,
) -> (Mode, R) {
    if mode != Mode::Stopped {
        return (mode, c.accel::<BUMP>(x, v, mode, f));
    }
    release::<R, BUMP>(c, x, v, c.hold(x, f), c.local::<BUMP>(x))
}

/// The breakaway guards of a stopped axis at `x` with holding force `hold`
/// (`f - position_force(x)`) and localised friction `b` at `x` (`Coeffs::bump_at(x)`): it
/// breaks away positive if `hold > Bp` (and `x < max`), negative if `hold < -Bn` (and
/// `x > min`), with the breakaway levels `(Bp, Bn)` of `c` at `x` (the step's, load share
/// included, plus `b`), the larger positive margin winning (positive on a tie); the release
/// stands only if the acceleration `(hold - friction) / inertia` then has the direction's
/// sign. Returns the mode and the acceleration (0 when it stays stopped). Out of line: it
/// runs only when a guard opens, and inlined it made the usual steps dearer.
#[inline(never)]
pub(crate) fn release<R: Real, const BUMP: bool>(
    c: &Coeffs<R>,
    x: R,
    v: R,
    hold: R,
    b: Option<R>,
) -> (Mode, R) {
    // `None` without a bump, known to the compiler (no test in the bump-free step).
    let b = if BUMP { b } else { None };
    let Some(dir) = breakaway::<R, BUMP>(c, x, hold, b) else {
        return (Mode::Stopped, R::ZERO);
    };
    // The same bits as `c.accel(x, v, dir, f)`: `hold` is `c.hold(x, f)`, `b` is
    // `c.bump_at(x)`.
    let a = (hold - c.friction_with(dir, b, v)) / c.inertia;
    let consistent = match dir {
        Mode::Positive => a > R::ZERO,
        _ => a < R::ZERO,
    };
    if consistent {
        (dir, a)
    } else {
        (Mode::Stopped, R::ZERO)
    }
}

/// The guards of [`release`] alone: the direction a stopped axis at `x` with holding force
/// `hold` and localised friction `b` would break away in, before the acceleration check;
/// `None`: it holds (and [`release`] returns `Stopped`), decided without evaluating the
/// friction.
#[inline]
pub(crate) fn breakaway<R: Real, const BUMP: bool>(
    c: &Coeffs<R>,
    x: R,
    hold: R,
    b: Option<R>,
) -> Option<Mode> {
    let (bp, bn) = c.breakaway_at(if BUMP { b } else { None });
    let mut best: Option<(Mode, R)> = None;
    if x < c.max {
        let m = hold - bp;
        if m > R::ZERO {
            best = Some((Mode::Positive, m));
        }
    }
    if x > c.min {
        let m = -bn - hold;
        let better = match best {
            Some((_, b)) => m > b,
            None => m > R::ZERO,
        };
        if better {
            best = Some((Mode::Negative, m));
        }
    }
    best.map(|(dir, _)| dir)
}

/// One RK4 step of length `dt` in a moving `mode` from `(x, v)` with first stage `a1`.
/// Returns the new position and velocity and the last stage's acceleration.
#[inline]
fn rk4<R: Real, const BUMP: bool>(
    c: &Coeffs<R>,
    x: R,
    v: R,
    mode: Mode,
    f: R,
    a1: R,
    dt: R,
) -> (R, R, R) {
    let half = dt * R::HALF;
    let x2 = x + half * v;
    let v2 = v + half * a1;
    let a2 = c.accel::<BUMP>(x2, v2, mode, f);
    let x3 = x + half * v2;
    let v3 = v + half * a2;
    let a3 = c.accel::<BUMP>(x3, v3, mode, f);
    let x4 = x + dt * v3;
    let v4 = v + dt * a3;
    let a4 = c.accel::<BUMP>(x4, v4, mode, f);
    let w = dt / R::SIX;
    let xn = x + w * (v + R::TWO * v2 + R::TWO * v3 + v4);
    let vn = v + w * (a1 + R::TWO * a2 + R::TWO * a3 + a4);
    (xn, vn, a4)
}

/// Cubic Hermite interpolant on `th` in [0, 1] through `y0`, `y1` with end slopes `m0`, `m1`
/// (already scaled by the interval length).
#[inline]
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

/// The velocity is zero or points against the moving mode.
#[inline]
fn velocity_violated<R: Real>(mode: Mode, v: R) -> bool {
    match mode {
        Mode::Positive => v <= R::ZERO,
        Mode::Negative => v >= R::ZERO,
        Mode::Stopped => false,
    }
}

/// The position reached the end stop the moving mode heads for.
#[inline]
fn limit_violated<R: Real>(mode: Mode, x: R, min: R, max: R) -> bool {
    match mode {
        Mode::Positive => x >= max,
        Mode::Negative => x <= min,
        Mode::Stopped => false,
    }
}

fn clamp<R: Real>(x: R, min: R, max: R) -> R {
    if x > max {
        max
    } else if x < min {
        min
    } else {
        x
    }
}

/// Resets a moving axis that violates its mode at `(x, v)`: the end stop first (`x := stop`),
/// else the velocity (`x` clamped into the stops); `v := 0`, `Stopped`. Returns whether it
/// reset.
fn sweep<R: Real>(c: &Coeffs<R>, x: &mut R, v: &mut R, mode: &mut Mode) -> bool {
    if limit_violated(*mode, *x, c.min, c.max) {
        *x = if *mode == Mode::Positive {
            c.max
        } else {
            c.min
        };
    } else if velocity_violated(*mode, *v) {
        *x = clamp(*x, c.min, c.max);
    } else {
        return false;
    }
    *v = R::ZERO;
    *mode = Mode::Stopped;
    true
}

/// Advances `(x, v, mode)` by `h` under the applied force `f` (held). `hold0` is the holding
/// force `f - position_force(x0)` of a stopped axis when the caller knows it (the same bits
/// as computing it here; `None` computes it). `BUMP` must be `c.bump_on`: the step without
/// localised friction is compiled without it. Returns the new state, mode and what happened.
/// Pure: the caller commits.
pub(crate) fn step<R: Real, const BUMP: bool>(
    c: &Coeffs<R>,
    h: R,
    (x0, v0, mode0): (R, R, Mode),
    f: R,
    hold0: Option<R>,
) -> (R, R, Mode, DriveReport) {
    let (mut x, mut v) = (x0, v0);
    let mut report = DriveReport::default();
    let mut done = R::ZERO;
    let (mut mode, mut a1) = match (mode0, hold0) {
        (Mode::Stopped, Some(hold)) => release::<R, BUMP>(c, x, v, hold, c.local::<BUMP>(x)),
        _ => resolve::<R, BUMP>(c, x, v, mode0, f),
    };
    for seg in 0..DRIVE_MAX_SEGMENTS {
        if mode == Mode::Stopped {
            // The holding force is constant for the rest of the step: it stays stopped.
            break;
        }
        let tau = h - done;
        let (xn, vn, a4) = rk4::<R, BUMP>(c, x, v, mode, f, a1, tau);
        if seg + 1 == DRIVE_MAX_SEGMENTS {
            // The last segment locates nothing: the late sweep below resets what it crossed.
            x = xn;
            v = vn;
            break;
        }
        let mut first: Option<R> = None;
        let mut limit_first = false;
        if velocity_violated(mode, vn) {
            let (s0, s1) = (tau * a1, tau * a4);
            let th = bisect(|t| !velocity_violated(mode, hermite(t, v, vn, s0, s1)));
            first = Some(th);
        }
        if limit_violated(mode, xn, c.min, c.max) {
            let (s0, s1) = (tau * v, tau * vn);
            let th = bisect(|t| !limit_violated(mode, hermite(t, x, xn, s0, s1), c.min, c.max));
            let earlier = match first {
                Some(b) => th < b,
                None => true,
            };
            if earlier {
                first = Some(th);
                limit_first = true;
            }
        }
        let Some(th) = first else {
            x = xn;
            v = vn;
            break;
        };
        let s = th * tau;
        let (xe, _, _) = rk4::<R, BUMP>(c, x, v, mode, f, a1, s);
        x = if limit_first {
            if mode == Mode::Positive {
                c.max
            } else {
                c.min
            }
        } else {
            clamp(xe, c.min, c.max)
        };
        v = R::ZERO;
        report.events = report.events.saturating_add(1);
        done = done + s;
        (mode, a1) = resolve::<R, BUMP>(c, x, v, Mode::Stopped, f);
        if done >= h {
            break;
        }
    }
    if sweep(c, &mut x, &mut v, &mut mode) {
        report.late_resets = report.late_resets.saturating_add(1);
    }
    (x, v, mode, report)
}
