//! The adaptive integrator of the hybrid model (`crane_model::adaptive`) against the 10 us
//! fixed-step reference, and its physical properties: energy, exact sticking, event times.

use crane_model::adaptive::{energy, Adaptive, EventKind, Tolerances};
use crane_model::{Config, Crane, FrictionLaw, Mode, Params};
use crane_tools::adaptive_run::{hybrid_adaptive, tolerances};
use crane_tools::cases::Case;
use crane_tools::reference;

fn crane(case: &Case, params: &Params) -> Crane {
    Crane::new(
        params,
        Config {
            h: 1e-3,
            law: FrictionLaw::Hybrid,
        },
        case.init,
    )
    .unwrap()
}

/// The time [s] of the rope's first breakaway in `case` under the adaptive integrator with
/// `tol` (None if the run ends without one).
fn first_rope_breakaway(case: &Case, tol: Tolerances) -> Option<f64> {
    let cr = crane(case, &case.params);
    let mut a = Adaptive::new(cr.coeffs(), tol, 0.0, cr.state(), cr.modes()).unwrap();
    let mut u = |t: f64| case.u_at(t);
    while a.time() < case.duration {
        let s = a.step(case.duration, &mut u).unwrap();
        if let Some((EventKind::Breakaway, 2)) = s.event {
            return Some(s.t1);
        }
    }
    None
}

/// Both cases converge to the 10 us fixed-step reference as the tolerance tightens, in far
/// fewer steps than the fixed step needs.
#[test]
fn converges_to_the_fixed_step_reference() {
    for case in Case::all() {
        let refr = reference::reference(&case, 1e-3, 100).unwrap();
        let (loose, st_loose) = hybrid_adaptive(&case, &tolerances(&case, 1e-5)).unwrap();
        let (tight, st_tight) = hybrid_adaptive(&case, &tolerances(&case, 1e-9)).unwrap();
        let (e_loose, e_tight) = (
            reference::rmse(&case, &loose, &refr),
            reference::rmse(&case, &tight, &refr),
        );
        assert!(e_tight < 1e-8, "{}: RMSE {e_tight} at rtol 1e-9", case.name);
        assert!(
            e_tight < e_loose / 100.0,
            "{}: {e_loose} -> {e_tight}",
            case.name
        );
        assert_eq!(loose.states.len(), case.samples() + 1);
        // The 1 ms fixed step takes duration / 1 ms steps; the adaptive one far fewer.
        let fixed_steps = case.samples() as u64;
        assert!(
            st_tight.accepted * 5 < fixed_steps,
            "{}: {} steps",
            case.name,
            st_tight.accepted
        );
        assert!(st_loose.events > 0 && st_loose.accepted < st_tight.accepted);
    }
}

/// Case 1 (dry friction and swing damping): the mechanical energy never rises, beyond the
/// integration error. Without any friction or damping it is conserved to the tolerance.
#[test]
fn energy_never_rises_and_is_conserved_without_friction() {
    let case = Case::one();
    let (tr, _) = hybrid_adaptive(&case, &tolerances(&case, 1e-9)).unwrap();
    let c = *crane(&case, &case.params).coeffs();
    let mut lowest = f64::INFINITY;
    let e0 = energy(&c, &tr.states[0]);
    for s in &tr.states {
        let e = energy(&c, s);
        assert!(e <= lowest + 1e-9, "energy rose: {e} after {lowest}");
        lowest = lowest.min(e);
    }
    assert!(
        lowest < e0 - 0.01,
        "friction must dissipate: {e0} -> {lowest}"
    );

    let mut p = case.params;
    p.y.dry_pos = [0.0; 5];
    p.y.dry_neg = [0.0; 5];
    p.damping_alpha = 0.0;
    p.damping_beta = 0.0;
    let cr = crane(&case, &p);
    let c = *cr.coeffs();
    let tol = Tolerances {
        rtol: 1e-10,
        atol: 1e-12,
        ..Tolerances::default()
    };
    let mut a = Adaptive::new(&c, tol, 0.0, cr.state(), cr.modes()).unwrap();
    let mut u = |_t: f64| [0.0; 3];
    let e0 = energy(&c, &a.state());
    let mut worst: f64 = 0.0;
    while a.time() < 10.0 {
        a.step(10.0, &mut u).unwrap();
        worst = worst.max((energy(&c, &a.state()) - e0).abs());
    }
    assert!(worst < 1e-8 * e0.abs(), "energy drift {worst} of {e0}");
}

/// Exact sticking: while an axis is `Stopped` its velocity is exactly 0.0 and its position
/// frozen to the bit, in both cases; in case 1 the trolley ends at rest for good.
#[test]
fn sticking_is_exact() {
    for case in Case::all() {
        let (tr, _) = hybrid_adaptive(&case, &tolerances(&case, 1e-7)).unwrap();
        let i = case.observed;
        let mut stuck = 0;
        for w in tr.states.windows(2).zip(tr.modes.windows(2)) {
            let (s, m) = w;
            if m[0][i] == Mode::Stopped && m[1][i] == Mode::Stopped {
                stuck += 1;
                assert_eq!(s[1].qd[i].to_bits(), 0.0f64.to_bits());
                assert_eq!(s[1].q[i].to_bits(), s[0].q[i].to_bits());
            }
        }
        assert!(stuck > 100, "{}: {stuck} stuck samples", case.name);
        // Held axes never move.
        for s in &tr.states {
            for (k, held) in case.held.iter().enumerate() {
                if *held {
                    assert_eq!(s.q[k], case.init.q[k]);
                }
            }
        }
        if case.observed == 1 {
            let last = *tr.modes.last().unwrap();
            assert_eq!(last[1], Mode::Stopped, "case 1 trolley at rest at the end");
        }
    }
}

/// Events located to the tolerance: in case 2 the rope, hanging at rest, breaks away when the
/// net force `A sin(2 pi f t)` reaches `Cbar_l`, at `t* = asin(Cbar_l / A) / (2 pi f)`
/// exactly; the located time is within the event tolerance. Every velocity event ends with
/// the interpolated velocity within `|a| tol` of zero.
#[test]
fn events_are_located_to_tolerance() {
    let case = Case::two();
    let mut tol = tolerances(&case, 1e-8);
    tol.event = 1e-11;
    let cr = crane(&case, &case.params);
    let mut a = Adaptive::new(cr.coeffs(), tol, 0.0, cr.state(), cr.modes()).unwrap();
    let mut u = |t: f64| case.u_at(t);
    let t_star = (case.rope_threshold() / 12.0).asin() / (2.0 * std::f64::consts::PI * 0.5);
    let mut first_breakaway = None;
    let mut velocity_events = 0;
    while a.time() < case.duration {
        let s = a.step(case.duration, &mut u).unwrap();
        match s.event {
            Some((EventKind::Breakaway, 2)) if first_breakaway.is_none() => {
                first_breakaway = Some(s.t1);
            }
            Some((EventKind::Velocity, 2)) => {
                velocity_events += 1;
                let v = a.dense(s.t1).unwrap().qd[2];
                assert!(v.abs() < 30.0 * 1e-11 + 1e-12, "velocity {v} at the event");
                assert_eq!(a.state().qd[2], 0.0);
            }
            _ => {}
        }
    }
    let tb = first_breakaway.expect("the rope breaks away");
    assert!(
        (tb - t_star).abs() <= 2.0 * tol.event + 1e-12,
        "breakaway at {tb}, exact {t_star}"
    );
    assert!(velocity_events >= 4, "{velocity_events} velocity events");
}

/// The breakaway is located on the trajectory at loose tolerances too, where the steps are
/// long and the stage states (where the guard is first seen) are far from it: case 2's first
/// breakaway (the payload hangs at rest, so the margin is the net force alone) within the
/// event tolerance of the exact time at every `rtol` of the sweep's loose end.
#[test]
fn breakaways_are_located_to_tolerance_at_loose_tolerances() {
    let case = Case::two();
    let t_star = (case.rope_threshold() / 12.0).asin() / (2.0 * std::f64::consts::PI * 0.5);
    for rtol in [1e-3, 1e-4, 1e-5, 1e-6] {
        let tol = tolerances(&case, rtol);
        let tb = first_rope_breakaway(&case, tol)
            .unwrap_or_else(|| panic!("no breakaway at rtol {rtol}"));
        assert!(
            (tb - t_star).abs() <= 2.0 * tol.event + 1e-12,
            "rtol {rtol}: breakaway at {tb}, exact {t_star}"
        );
    }
}

/// A fixed-step run with steps longer than the grid, put on the grid: every grid point, the
/// compared velocity equal to the interpolant the error is scored with, positions close to the
/// reference, the samples themselves untouched.
#[test]
fn a_fixed_step_run_on_the_grid_keeps_its_samples_and_the_scored_interpolant() {
    for case in Case::all() {
        let h = 0.025;
        let tr = reference::hybrid(&case, h, false).expect("runs");
        assert_eq!(tr.stride, 25);
        let grid = tr.clone().on_grid(&case);
        assert_eq!(grid.stride, 1);
        assert_eq!(grid.states.len(), tr.grid_len() + 1);
        assert_eq!(grid.modes.len(), grid.states.len());
        for g in 0..=tr.grid_len() {
            let v = tr.velocity_at_grid(&case, g).expect("inside the run");
            let w = grid.states[g].qd[case.observed];
            assert!(
                (v - w).abs() <= 1e-12 * (1.0 + v.abs()),
                "grid {g}: {v} vs {w}"
            );
            if g % tr.stride == 0 {
                assert_eq!(grid.states[g], tr.states[g / tr.stride], "sample {g}");
            }
        }
        // Positions by the Hermite interpolant through positions and velocities: within a
        // millimetre (or milliradian) of the 10 us reference everywhere.
        let refr = reference::reference(&case, 1e-3, 100).expect("reference");
        for (g, s) in grid.states.iter().enumerate() {
            for i in 0..5 {
                let d = (s.q[i] - refr.states[g].q[i]).abs();
                assert!(d < 1e-3, "case {} grid {g} q[{i}]: {d}", case.observed);
            }
        }
    }
}

/// Whether a stopped axis's breakaway guard is crossed at one of `n - 1` points inside the
/// last accepted step `[t0, t1]` (the dense state, the modes of the step, the case's input).
fn hidden_breakaway(case: &Case, a: &Adaptive, t0: f64, t1: f64, n: usize) -> bool {
    use crane_model::dynamics::{eval, Law};
    use crane_model::friction::breakaway;
    let c = *crane(case, &case.params).coeffs();
    let modes = a.step_modes();
    (1..n).any(|j| {
        let t = t0 + (t1 - t0) * j as f64 / n as f64;
        let y = a.dense(t).expect("a step was taken");
        let e = eval(&c, Law::Hybrid, &y, &modes, &case.u_at(t)).expect("evaluates");
        (0..3).any(|i| {
            let (ax, q) = (&c.axes[i], y.q[i]);
            modes[i] == Mode::Stopped
                && ((q < ax.max && e.hold[i] > breakaway(ax, Mode::Positive, q))
                    || (q > ax.min && -e.hold[i] > breakaway(ax, Mode::Negative, q)))
        })
    })
}

/// A stopped axis's guard is seen only at the stages, so a step may not hide a breakaway
/// (the holding force crossing its level and coming back between two stages): checked at 63
/// points inside every accepted step without an event, in both cases over the sweep's
/// tolerances. Without the guard bound case 1 (trolleys stuck under a swinging payload) hid
/// one in 1 / 6 / 1 steps at `rtol` 1e-3 / 1e-4 / 1e-5.
#[test]
fn no_breakaway_hides_inside_a_step() {
    for case in Case::all() {
        for rtol in [1e-3, 1e-4, 1e-5, 1e-7] {
            let cr = crane(&case, &case.params);
            let tol = tolerances(&case, rtol);
            let mut a = Adaptive::new(cr.coeffs(), tol, 0.0, cr.state(), cr.modes()).unwrap();
            let mut u = |t: f64| case.u_at(t);
            let mut hidden = Vec::new();
            while a.time() < case.duration {
                let s = a.step(case.duration, &mut u).unwrap();
                if s.event.is_none() && hidden_breakaway(&case, &a, s.t0, s.t1, 64) {
                    hidden.push(s.t0);
                }
            }
            assert!(
                hidden.is_empty(),
                "{} rtol {rtol}: breakaways hidden in the steps from {hidden:?}",
                case.name
            );
        }
    }
}

/// A brief excursion past the breakaway level is not stepped over: case 2's rope, hanging at
/// rest with every axis stuck (the error estimate is zero, the steps grow fivefold a step),
/// driven by a net force whose peak is only 2 % above the level (past it for 6 % of each
/// period), with no largest step, breaks away at `t* = asin(Cbar_l / A) / (2 pi f)`.
#[test]
fn a_brief_excursion_past_the_breakaway_level_is_found() {
    let mut case = Case::two();
    let amplitude = 1.02 * case.rope_threshold();
    if let crane_tools::cases::Input::RopeSine { amplitude: a, .. } = &mut case.input {
        *a = amplitude;
    }
    let t_star = (case.rope_threshold() / amplitude).asin() / (2.0 * std::f64::consts::PI * 0.5);
    for rtol in [1e-3, 1e-5, 1e-7] {
        let tol = tolerances(&case, rtol);
        assert!(tol.hmax.is_infinite());
        let tb = first_rope_breakaway(&case, tol)
            .unwrap_or_else(|| panic!("rtol {rtol}: the rope never breaks away"));
        assert!(
            (tb - t_star).abs() <= 2.0 * tol.event + 1e-12,
            "rtol {rtol}: breakaway at {tb}, exact {t_star}"
        );
    }
}
