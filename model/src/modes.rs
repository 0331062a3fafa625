//! The hybrid automaton's discrete state: one [`Mode`] per drive axis, and the breakaway
//! guards that move a stopped axis into motion.
//!
//! Transitions (paper Fig. "Hybrid model of the 3 axis dynamics", made precise in
//! `docs/MODEL.md`):
//! - `Positive`/`Negative` -> `Stopped` when the velocity reaches 0 (reset `qd := 0`) or the
//!   position reaches the limit it moves towards (reset `q := limit`, `qd := 0`). These are
//!   located inside the step by the integrator.
//! - `Stopped` -> `Positive` when the holding force `F > Cbar+(q)`, -> `Negative` when
//!   `F < -Cbar-(q)`; at a limit only motion away from it is allowed. Evaluated by
//!   [`resolve`] at the start of every step and at once after every event, so a reversal
//!   passes through `Stopped` within the same instant.

use crate::coeffs::{AxisCoeffs, Coeffs};
use crate::dynamics::{at_state, eval_at, Eval, Law, Singular};
use crate::friction::breakaway;
pub use crate::mode::Mode;
use crate::real::Real;
use crate::state::State;

/// Breakaway margin [N] of a stopped axis for a direction: positive when the guard holds.
///
/// `Positive`: `hold - Cbar+(q)`; `Negative`: `-Cbar-(q) - hold`.
pub(crate) fn margin<R: Real>(ax: &AxisCoeffs<R>, q: R, hold: R, dir: Mode) -> R {
    match dir {
        Mode::Negative => -breakaway(ax, Mode::Negative, q) - hold,
        _ => hold - breakaway(ax, Mode::Positive, q),
    }
}

/// The direction a stopped axis would break away in, with its positive margin, if any.
///
/// Motion into a limit the axis sits at is not a candidate. `Positive` wins a tie.
pub(crate) fn candidate<R: Real>(ax: &AxisCoeffs<R>, q: R, hold: R) -> Option<(Mode, R)> {
    candidate_with(ax, q, hold, thresholds(ax, q))
}

/// The breakaway thresholds `(Cbar+(q), Cbar-(q))` of an axis at `q` (stiction included).
fn thresholds<R: Real>(ax: &AxisCoeffs<R>, q: R) -> (R, R) {
    (
        breakaway(ax, Mode::Positive, q),
        breakaway(ax, Mode::Negative, q),
    )
}

/// [`candidate`] with the thresholds `(Cbar+(q), Cbar-(q))` already computed: the same
/// margins, the same bits.
fn candidate_with<R: Real>(
    ax: &AxisCoeffs<R>,
    q: R,
    hold: R,
    (up, down): (R, R),
) -> Option<(Mode, R)> {
    let mut best: Option<(Mode, R)> = None;
    if q < ax.max {
        let m = hold - up;
        if m > R::ZERO {
            best = Some((Mode::Positive, m));
        }
    }
    if q > ax.min {
        let m = -down - hold;
        let better = match best {
            Some((_, b)) => m > b,
            None => m > R::ZERO,
        };
        if better {
            best = Some((Mode::Negative, m));
        }
    }
    best
}

/// Evaluates the breakaway guards of all stopped axes at `y` and releases them, one at a
/// time, largest margin first; returns the dynamics evaluated in the final modes.
///
/// A release is kept only if the released axis then accelerates in its direction (with
/// `qd = 0` that is what makes the new mode consistent); otherwise the axis stays stopped.
/// Work: at most 4 evaluations of the dynamics, all at the same state, so the
/// mode-independent part (trigonometry, mass matrix, Coriolis and gravity terms) and the
/// breakaway thresholds are computed once.
pub(crate) fn resolve<R: Real>(
    c: &Coeffs<R>,
    law: Law<R>,
    y: &State<R>,
    u: &[R; 3],
    modes: &mut [Mode; 3],
) -> Result<Eval<R>, Singular> {
    let pre = at_state(c, y);
    let mut e = eval_at(c, law, &pre, y, modes, u)?;
    let mut th = [(R::ZERO, R::ZERO); 3];
    for i in 0..3 {
        if modes[i] == Mode::Stopped {
            th[i] = thresholds(&c.axes[i], y.q[i]);
        }
    }
    let mut blocked = [false; 3];
    for _ in 0..3 {
        let mut best: Option<(usize, Mode, R)> = None;
        for i in 0..3 {
            if modes[i] != Mode::Stopped || blocked[i] {
                continue;
            }
            if let Some((dir, m)) = candidate_with(&c.axes[i], y.q[i], e.hold[i], th[i]) {
                let better = match best {
                    Some((_, _, b)) => m > b,
                    None => true,
                };
                if better {
                    best = Some((i, dir, m));
                }
            }
        }
        let Some((i, dir, _)) = best else { break };
        modes[i] = dir;
        let e2 = eval_at(c, law, &pre, y, modes, u)?;
        let consistent = match dir {
            Mode::Positive => e2.qdd[i] > R::ZERO,
            Mode::Negative => e2.qdd[i] < R::ZERO,
            Mode::Stopped => false,
        };
        if consistent {
            e = e2;
        } else {
            modes[i] = Mode::Stopped;
            blocked[i] = true;
        }
    }
    Ok(e)
}
