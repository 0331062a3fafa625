//! The hybrid model of a case under the adaptive integrator (`crane_model::adaptive`),
//! sampled on the case's output grid by its dense output.

use crate::cases::Case;
use crate::error::{Error, Result};
use crate::reference::Trajectory;
use crane_model::adaptive::{Adaptive, AdaptiveStats, Tolerances};
use crane_model::{Config, Crane, FrictionLaw};

/// Tolerances for a case at relative tolerance `rtol` (`atol = rtol / 100`, events to
/// `1e-3 rtol` seconds but at least 1e-12 s, no largest step: the error control follows the
/// smooth input and the guard bound of the integrator keeps the stuck axes' breakaways from
/// hiding between the stages, see `Adaptive`'s module documentation).
pub fn tolerances(_case: &Case, rtol: f64) -> Tolerances {
    Tolerances {
        rtol,
        atol: rtol * 1e-2,
        hmax: f64::INFINITY,
        event: (rtol * 1e-3).max(1e-12),
    }
}

/// The hybrid model of `case` by the adaptive integrator with `tol`; continuous-time input.
pub fn hybrid_adaptive(case: &Case, tol: &Tolerances) -> Result<(Trajectory, AdaptiveStats)> {
    let crane: Crane = Crane::new(
        &case.params,
        Config {
            h: 1e-3,
            law: FrictionLaw::Hybrid,
        },
        case.init,
    )
    .map_err(|error| Error::Setup {
        what: "hybrid model of the case",
        error,
    })?;
    let mut a = Adaptive::new(crane.coeffs(), *tol, 0.0, crane.state(), crane.modes()).map_err(
        |error| Error::Adaptive {
            what: "adaptive hybrid",
            t: 0.0,
            error,
        },
    )?;
    let n = case.samples();
    let mut tr = Trajectory {
        h: 0.0,
        stride: 1,
        states: Vec::with_capacity(n + 1),
        modes: Vec::with_capacity(n + 1),
        ..Trajectory::default()
    };
    tr.states.push(crane.state());
    tr.modes.push(crane.modes());
    let t_end = case.duration;
    let mut next = 1usize;
    let mut u = |t: f64| case.u_at(t);
    while a.time() < t_end {
        let t = a.time();
        let s = a.step(t_end, &mut u).map_err(|error| Error::Adaptive {
            what: "adaptive hybrid",
            t,
            error,
        })?;
        let poly = a.dense_poly().ok_or(Error::NoDenseOutput { t: a.time() })?;
        // The grid points this step covers: `next ..= end`, every `k` with `k dt <= t1`
        // (all the rest once the run has ended).
        let tk = |k: usize| k as f64 * case.sample;
        let mut end = if s.t1 >= t_end {
            n
        } else {
            ((s.t1 / case.sample) as usize).min(n)
        };
        while end < n && tk(end + 1) <= s.t1 {
            end += 1;
        }
        while end >= next && tk(end) > s.t1 && s.t1 < t_end {
            end -= 1;
        }
        if end < next {
            continue;
        }
        // Inside the step: the dense output in the step's modes; at an event's end: the state
        // after the reset, in the new modes.
        let after_reset = s.event.is_some() && tk(end) >= s.t1;
        let dense_end = if after_reset { end - 1 } else { end };
        if dense_end + 1 > next {
            tr.states
                .extend((next..dense_end + 1).map(|k| poly.at(tk(k))));
            tr.modes
                .extend(core::iter::repeat_n(a.step_modes(), dense_end + 1 - next));
        }
        if after_reset {
            tr.states.push(a.state());
            tr.modes.push(a.modes());
        }
        next = end + 1;
    }
    let st = a.stats();
    tr.steps = st.accepted;
    tr.events = st.events;
    Ok((tr, st))
}
