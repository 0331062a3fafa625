//! Physical properties of the model (`crane_model`), checked where cheap against the
//! independent reference as well. Every test here can fail.
#![allow(clippy::needless_range_loop)]

mod common;

use common::{
    compare, energy, frictionless, mass_matrix, model, random_program, ref_mode, Rng, FRAC_PI_2,
};
use crane_model::friction::dry;
use crane_model::{Config, Crane, FrictionLaw, Mode, Params, State, StepError, MIN_HANG};
use host_tests::reference::{RefCrane, RefError, RefEventKind, RefLaw, RefMode, RefParams};

const H: f64 = 1e-3;

fn reference(p: &Params, q: [f64; 5], qd: [f64; 5]) -> RefCrane {
    RefCrane::new(RefParams::from(p), H, RefLaw::Hybrid, q, qd).expect("reference new")
}

/// The reference's own copy of the docs/MODEL.md tables equals the model's `Params::default()`.
#[test]
fn model_defaults_are_the_model_md_tables() {
    assert_eq!(
        RefParams::from(&Params::default()),
        RefParams::model_md_defaults()
    );
}

/// Sets the X and Y velocities so that the X and Y momenta `(M qd)_0`, `(M qd)_1` vanish:
/// without friction and input they are conserved (x, y are cyclic), so the rail and the
/// trolley only oscillate against the swinging payload and never drift into an end stop.
fn zero_drive_momentum(p: &Params, q: &[f64; 5], qd: &mut [f64; 5]) {
    let m = mass_matrix(p, q);
    qd[0] = -(m[0][2] * qd[2] + m[0][3] * qd[3] + m[0][4] * qd[4]) / m[0][0];
    qd[1] = -(m[1][2] * qd[2] + m[1][3] * qd[3]) / m[1][1];
}

/// Runs `steps` zero-input steps and returns the largest |E - E0| / |E0| (model and
/// reference), asserting that no end stop is reached (an end stop is not conservative).
fn max_relative_energy_drift(p: &Params, q: [f64; 5], mut qd: [f64; 5], steps: usize) -> f64 {
    zero_drive_momentum(p, &q, &mut qd);
    let mut m = model(p, H, FrictionLaw::Hybrid, q, qd);
    let mut r = reference(p, q, qd);
    let e0 = energy(p, &m.state());
    let e0_ref = r.energy();
    assert!((e0 - e0_ref).abs() <= 1e-12 * e0.abs(), "{e0} vs {e0_ref}");
    let mut worst = 0.0_f64;
    let mut events = 0usize;
    for k in 0..steps {
        events += m.step([0.0; 3]).expect("model step").events as usize;
        r.step([0.0; 3]).expect("reference step");
        let e = energy(p, &m.state());
        worst = worst.max((e - e0).abs() / e0.abs());
        worst = worst.max((r.energy() - e0).abs() / e0.abs());
        // The scenario must stay away from the end stops (the rope rests on its own).
        for (i, a) in p.axes().into_iter().enumerate() {
            let x = m.state().q[i];
            assert!(
                (x > a.min + 1e-3 && x < a.max - 1e-3) || (i == 2 && x == a.max),
                "step {k}: axis {i} came near an end stop ({x})"
            );
        }
    }
    assert!(events > 0, "the scenario must have velocity events");
    eprintln!("max relative drift {worst:e}, {events} events");
    worst
}

/// Friction, damping and inputs zero: `E = 1/2 qd^T M qd + m_p g z_p` is conserved.
/// 10 s at 1 ms, swinging payload, X and Y moving against it (their velocities cross zero
/// as the payload swings, so velocity events and immediate breakaways happen); the rope rests
/// at its lower end stop `L = max`, where only hoisting is allowed and the weight holds it.
#[test]
fn energy_conserved_without_friction_damping_and_inputs() {
    let p = frictionless(Params::default());
    let q = [0.25, 0.3, 0.57, FRAC_PI_2 + 0.35, 0.25];
    let qd = [0.0, 0.0, 0.0, 0.4, -0.3];
    let drift = max_relative_energy_drift(&p, q, qd, 10_000);
    assert!(drift < 1e-6, "relative energy drift {drift:e}");
}

/// The same with the rope moving too: the payload is lowered by its own weight
/// (frictionless hoist), 1.5 s, until just before the rope would reach its end stop.
#[test]
fn energy_conserved_without_friction_with_moving_rope() {
    let p = frictionless(Params::default());
    let q = [0.25, 0.3, 0.2, FRAC_PI_2 - 0.3, -0.2];
    let qd = [0.0, 0.0, 0.01, -0.5, 0.3];
    let drift = max_relative_energy_drift(&p, q, qd, 1_500);
    assert!(drift < 1e-6, "relative energy drift {drift:e}");
}

/// Largest energy rise between two consecutive steps, relative to |E|, with zero input.
fn max_energy_rise(p: &Params, q: [f64; 5], qd: [f64; 5], steps: usize) -> (f64, usize) {
    let mut m = model(p, H, FrictionLaw::Hybrid, q, qd);
    let mut e = energy(p, &m.state());
    let mut worst = (f64::NEG_INFINITY, 0);
    for k in 0..steps {
        m.step([0.0; 3]).expect("model step");
        let e1 = energy(p, &m.state());
        let rise = (e1 - e) / e.abs().max(1e-3);
        if rise > worst.0 {
            worst = (rise, k + 1);
        }
        e = e1;
    }
    worst
}

/// With friction (defaults) and zero input, E never rises from one step to the next, away
/// from the end stops (40 random swinging starts, drive axes moving or stopped, 5 s each).
///
/// Tolerance 1e-12 |E|: physically E falls by at least the swing damping `D ad^2 h` per step
/// plus the friction work of the moving axes; a stopped axis does no work (qd = 0 exactly).
/// What could add energy numerically is (a) the rounding of E itself, ~1e-16 |E| per term,
/// and (b) the RK4 truncation error, O((w h)^5) relative with w = sqrt(g/L) <= 8.7 rad/s, i.e.
/// below ~5e-11, and RK4 is dissipative on oscillators (|R(iwh)| < 1) to leading order. In
/// these runs E fell by at least 1e-9 |E| at every step, so any rise above 1e-12 |E| would be a
/// real energy source (as the end-stop reset is, see the next test).
#[test]
fn energy_never_rises_with_friction_and_zero_input() {
    let p = Params::default();
    let mut rng = Rng::new(7);
    let mut worst = f64::NEG_INFINITY;
    for case in 0..40 {
        // Mid-range positions (no end stop reached), drive axes moving or stopped, swinging.
        let q = [
            rng.range(0.15, 0.35),
            rng.range(0.2, 0.4),
            rng.range(0.2, 0.5),
            FRAC_PI_2 + rng.range(-0.5, 0.5),
            rng.range(-0.4, 0.4),
        ];
        let mut qd = [
            rng.range(-0.3, 0.3),
            rng.range(-0.3, 0.3),
            rng.range(-0.1, 0.1),
            rng.range(-1.5, 1.5),
            rng.range(-1.5, 1.5),
        ];
        if case % 3 == 0 {
            qd[0] = 0.0;
        }
        if case % 4 == 0 {
            qd[2] = 0.0;
        }
        let (rise, at) = max_energy_rise(&p, q, qd, 5_000);
        worst = worst.max(rise);
        assert!(
            rise <= 1e-12,
            "case {case}: E rose by {rise:e} |E| at step {at} (q {q:?}, qd {qd:?})"
        );
    }
    eprintln!("largest relative rise between steps: {worst:e}");
}

/// With friction and zero input, E must not rise when an axis hits its end stop either.
///
/// This was FINDING F1 (CONTRACT_NOTES.md): the first limit reset set only `qd_i := 0` and
/// kept the swing rates, so E rose by 0.0178 J here. The contract's end-stop impulse (a
/// plastic impact on coordinate i only, `M dqd = lambda e_i`) keeps the payload's velocity
/// and loses `qd_i^2 / (2 w_i)`, `w = M^-1 e_i`. Here the rail reaches x = 0 at 8 cm/s while
/// the payload swings in beta at 2.2 rad/s; model and reference agree bit for bit.
#[test]
fn energy_never_rises_at_an_end_stop() {
    let p = Params::default();
    let q = [0.0006, 0.0026, 0.512, 1.4935, -0.3756];
    let qd = [-0.0792, -0.0221, 0.0128, 0.130, 2.175];
    let mut m = model(&p, H, FrictionLaw::Hybrid, q, qd);
    let mut r = reference(&p, q, qd);
    let mut e = energy(&p, &m.state());
    let mut hit = false;
    for k in 0..200 {
        m.step([0.0; 3]).expect("model step");
        r.step([0.0; 3]).expect("reference step");
        if let Some(msg) = compare(k + 1, &m, &r) {
            panic!("{msg}");
        }
        let e1 = energy(&p, &m.state());
        hit |= m.state().q[0] == 0.0;
        assert!(
            e1 - e <= 1e-12 * e.abs(),
            "step {}: E rose by {:e} J (|E| = {:.3} J) at the end stop x = {}",
            k + 1,
            e1 - e,
            e.abs(),
            m.state().q[0]
        );
        e = e1;
    }
    assert!(hit, "the scenario must reach the end stop");
}

/// The same over 60 random starts next to the end stops of X, Y and the rope (drive axes
/// moving into them, payload swinging in both angles), zero input, 1 s each: E never rises
/// by more than 1e-12 |E| from one step to the next, and every run hits at least one end stop
/// (the reference's located limit events; the reference runs alongside, bit for bit).
/// Before the end-stop impulse, rises of up to 0.017 J were seen in such runs.
#[test]
fn energy_never_rises_at_random_end_stops() {
    let p = Params::default();
    let mut rng = Rng::new(31);
    let mut worst = f64::NEG_INFINITY;
    let mut stops = 0usize;
    for case in 0..60 {
        let mut q = [
            0.0,
            0.0,
            0.0,
            FRAC_PI_2 + rng.range(-0.5, 0.5),
            rng.range(-0.5, 0.5),
        ];
        let mut qd = [0.0, 0.0, 0.0, rng.range(-2.0, 2.0), rng.range(-2.5, 2.5)];
        for (i, a) in p.axes().into_iter().enumerate() {
            let (d, v) = (rng.range(0.0, 0.002), rng.range(0.06, 0.2));
            let upper = rng.below(2) == 0;
            q[i] = if upper { a.max - d } else { a.min + d };
            qd[i] = if upper { v } else { -v };
        }
        if case % 3 == 1 {
            qd[2] = 0.0; // the rope holds; only X and Y hit their stops
        }
        let mut m = model(&p, H, FrictionLaw::Hybrid, q, qd);
        let mut r = reference(&p, q, qd);
        let mut e = energy(&p, &m.state());
        let mut hit = 0;
        for k in 0..1000 {
            m.step([0.0; 3]).expect("model step");
            let info = r.step([0.0; 3]).expect("reference step");
            if let Some(msg) = compare(k + 1, &m, &r) {
                panic!("case {case}: {msg}");
            }
            hit += info
                .events
                .iter()
                .filter(|ev| ev.kind == RefEventKind::Limit)
                .count();
            let e1 = energy(&p, &m.state());
            let rise = (e1 - e) / e.abs();
            worst = worst.max(rise);
            assert!(
                rise <= 1e-12,
                "case {case} step {}: E rose by {rise:e} |E| (q {q:?}, qd {qd:?})",
                k + 1
            );
            e = e1;
        }
        assert!(
            hit > 0,
            "case {case}: no end stop reached (q {q:?}, qd {qd:?})"
        );
        stops += hit;
    }
    eprintln!("{stops} end stops; largest relative rise between steps: {worst:e}");
}

/// Stopped axes whose holding force stays below the dry-friction threshold keep their
/// positions bit for bit: 100 s with a small swing, zero input.
#[test]
fn stopped_axes_below_threshold_hold_bit_for_bit() {
    let p = Params::default();
    let q = [0.2, 0.3, 0.4, FRAC_PI_2 + 0.05, 0.04];
    let qd = [0.0, 0.0, 0.0, 0.1, -0.1];
    let mut m = model(&p, H, FrictionLaw::Hybrid, q, qd);
    let mut r = reference(&p, q, qd);
    for k in 0..100_000 {
        m.step([0.0; 3]).expect("model step");
        if k < 20_000 {
            r.step([0.0; 3]).expect("reference step");
        }
        let s = m.state();
        for i in 0..3 {
            assert_eq!(s.q[i].to_bits(), q[i].to_bits(), "step {}: q[{i}]", k + 1);
            assert_eq!(
                s.qd[i].to_bits(),
                0.0f64.to_bits(),
                "step {}: qd[{i}]",
                k + 1
            );
            if k < 20_000 {
                assert_eq!(
                    r.q()[i].to_bits(),
                    q[i].to_bits(),
                    "reference step {}",
                    k + 1
                );
            }
        }
        assert_eq!(m.modes(), [Mode::Stopped; 3], "step {}", k + 1);
        if k % 1000 == 0 {
            // The premise: every holding force is inside its friction band.
            let f = m.output().expect("output").friction;
            for (i, a) in p.axes().into_iter().enumerate() {
                let up = dry(&a.dry_pos, q[i]);
                let down = dry(&a.dry_neg, q[i]);
                assert!(f[i] < up && f[i] > -down, "axis {i}: hold {} N", f[i]);
            }
        }
    }
    // The swing went on (the test is not trivially static).
    assert!(m.state().qd[3] != 0.0);
}

/// Default payload (0.457 kg, `m_p g = 4.48 N < Cbar_l = 8.583 N`): with `u_l = 0` the hoist
/// is self-locking and L stays bit for bit constant, hanging still and while the trolley is
/// driven (moderate multisine voltages on X and Y make the payload swing).
#[test]
fn default_payload_hangs_with_zero_hoist_voltage() {
    let p = Params::default();
    assert!(p.payload_mass * p.gravity < p.rope.dry_pos[0]);
    let l0 = 0.4;
    // Hanging still: nothing may move at all.
    let q = [0.2, 0.3, l0, FRAC_PI_2, 0.0];
    let mut m = model(&p, H, FrictionLaw::Hybrid, q, [0.0; 5]);
    for k in 0..20_000 {
        m.step([0.0; 3]).expect("step");
        assert_eq!(m.state().q[2].to_bits(), l0.to_bits(), "step {}", k + 1);
        assert_eq!(m.modes()[2], Mode::Stopped);
    }
    // Trolley driven, payload swinging, u_l = 0.
    let mut m = model(&p, H, FrictionLaw::Hybrid, q, [0.0; 5]);
    let mut r = reference(&p, q, [0.0; 5]);
    let mut max_swing = 0.0_f64;
    for k in 0..30_000 {
        let t = k as f64 * H;
        let u = [
            5.0 * (2.0 * std::f64::consts::PI * 0.4 * t).sin(),
            5.0 * (2.0 * std::f64::consts::PI * 0.3 * t + 1.0).sin(),
            0.0,
        ];
        m.step(u).expect("step");
        r.step(u).expect("reference step");
        assert_eq!(m.state().q[2].to_bits(), l0.to_bits(), "step {}", k + 1);
        assert_eq!(r.q()[2].to_bits(), l0.to_bits(), "reference step {}", k + 1);
        assert_eq!(m.state().qd[2].to_bits(), 0.0f64.to_bits());
        max_swing = max_swing.max((m.state().q[3] - FRAC_PI_2).abs());
    }
    assert!(max_swing > 0.05, "the payload must swing ({max_swing})");
}

/// Drive positions never leave their limits, and an axis is Stopped exactly when its
/// velocity is 0.0, at every step: random saturating inputs (|u| up to 20 V), long runs that
/// hit every end stop. The reference is checked alongside on the first run.
#[test]
fn limits_hold_and_stopped_iff_zero_velocity() {
    let mut hits = [[false; 2]; 3];
    for run in 0..6u64 {
        let p = Params {
            payload_mass: [0.457, 0.2, 0.6, 0.064, 0.3, 0.5][run as usize],
            ..Params::default()
        };
        let mut rng = Rng::new(100 + run);
        let progs = [
            random_program(&mut rng, 20.0),
            random_program(&mut rng, 20.0),
            random_program(&mut rng, 20.0),
        ];
        let q = [0.25, 0.3, 0.35, FRAC_PI_2, 0.0];
        let mut m = model(&p, H, FrictionLaw::Hybrid, q, [0.0; 5]);
        let mut r = (run == 0).then(|| reference(&p, q, [0.0; 5]));
        for k in 0..40_000 {
            let u = [progs[0].at(k, H), progs[1].at(k, H), progs[2].at(k, H)];
            m.step(u)
                .unwrap_or_else(|e| panic!("run {run} step {}: {e}", k + 1));
            check_invariants(&p, &m.state(), &m.modes().map(ref_mode), run, k + 1);
            if let Some(r) = r.as_mut() {
                r.step(u).expect("reference step");
                check_invariants(&p, &r.state_as_model(), &r.modes(), run, k + 1);
            }
            for (i, a) in p.axes().into_iter().enumerate() {
                hits[i][0] |= m.state().q[i] == a.min;
                hits[i][1] |= m.state().q[i] == a.max;
            }
        }
    }
    assert_eq!(hits, [[true; 2]; 3], "every end stop must be reached");
}

fn check_invariants(p: &Params, s: &State<f64>, modes: &[RefMode; 3], run: u64, step: usize) {
    assert!(
        s.q.iter().chain(s.qd.iter()).all(|v| v.is_finite()),
        "run {run} step {step}: {s:?}"
    );
    let hang = libm::sin(s.q[3]) * libm::cos(s.q[4]);
    assert!(
        hang >= MIN_HANG,
        "run {run} step {step}: sin(alpha) cos(beta) = {hang} below MIN_HANG"
    );
    for (i, a) in p.axes().into_iter().enumerate() {
        assert!(
            s.q[i] >= a.min && s.q[i] <= a.max,
            "run {run} step {step}: q[{i}] = {} outside [{}, {}]",
            s.q[i],
            a.min,
            a.max
        );
        assert_eq!(
            modes[i] == RefMode::Stopped,
            s.qd[i] == 0.0,
            "run {run} step {step}: axis {i} mode {:?} with velocity {:e}",
            modes[i],
            s.qd[i]
        );
        match modes[i] {
            RefMode::Positive => assert!(s.qd[i] > 0.0),
            RefMode::Negative => assert!(s.qd[i] < 0.0),
            RefMode::Stopped => {}
        }
    }
}

trait AsModelState {
    fn state_as_model(&self) -> State<f64>;
}

impl AsModelState for RefCrane {
    fn state_as_model(&self) -> State<f64> {
        State {
            q: self.q(),
            qd: self.qd(),
        }
    }
}

/// What the 10^6-step run saw.
#[derive(Debug, Default)]
struct MillionRun {
    /// Rejected steps by error: Singular, NonFinite, OutOfDomain.
    rejected: [usize; 3],
    /// First rejected step (1-based) and its error.
    first: Option<(usize, StepError)>,
    /// Longest run of consecutive rejected steps.
    longest_run: usize,
    /// Rejected steps at the end of the run, in a row.
    final_run: usize,
    /// Accepted steps after the first rejected one.
    accepted_after_first: usize,
    /// Smallest `sin(alpha) cos(beta)` of an accepted state.
    min_hang: f64,
}

/// 10^6 steps (1000 s) of random saturating inputs (|u| up to 20 V, a new random program of
/// holds, ramps, multisines and square waves every 20 s) on the default crane. After every
/// step, accepted or rejected: the state is finite, every drive position is within its
/// limits, an axis is Stopped exactly when its velocity is 0, and the state is in the swing
/// domain `sin(alpha) cos(beta) >= MIN_HANG`; a rejected step leaves state, modes and time
/// unchanged.
fn million_random_steps() -> MillionRun {
    let p = Params::default();
    let mut rng = Rng::new(2024);
    let q = [0.25, 0.3, 0.35, FRAC_PI_2, 0.0];
    let mut m = model(&p, H, FrictionLaw::Hybrid, q, [0.0; 5]);
    let mut run = MillionRun {
        min_hang: f64::INFINITY,
        ..MillionRun::default()
    };
    let mut k = 0usize;
    while k < 1_000_000 {
        let progs = [
            random_program(&mut rng, 20.0),
            random_program(&mut rng, 20.0),
            random_program(&mut rng, 20.0),
        ];
        for j in 0..20_000 {
            let u = [progs[0].at(j, H), progs[1].at(j, H), progs[2].at(j, H)];
            let (before, modes, t) = (m.state(), m.modes(), m.time());
            k += 1;
            match m.step(u) {
                Ok(_) => {
                    let s = m.state();
                    run.min_hang = run.min_hang.min(libm::sin(s.q[3]) * libm::cos(s.q[4]));
                    if run.first.is_some() {
                        run.accepted_after_first += 1;
                    }
                    run.final_run = 0;
                }
                Err(e) => {
                    assert_eq!(
                        m.state(),
                        before,
                        "step {k}: rejected step changed the state"
                    );
                    assert_eq!(m.modes(), modes, "step {k}");
                    assert_eq!(m.time().to_bits(), t.to_bits(), "step {k}");
                    match e {
                        StepError::Singular => run.rejected[0] += 1,
                        StepError::NonFinite => run.rejected[1] += 1,
                        // outside the swing domain or the limits
                        StepError::OutOfDomain | StepError::OutOfLimits { .. } => {
                            run.rejected[2] += 1
                        }
                        StepError::InputNotFinite { .. } => panic!("step {k}: {e}"),
                    }
                    run.first.get_or_insert((k, e));
                    run.final_run += 1;
                    run.longest_run = run.longest_run.max(run.final_run);
                }
            }
            check_invariants(&p, &m.state(), &m.modes().map(ref_mode), 0, k);
        }
    }
    run
}

/// 10^6 steps of random saturating inputs never give a non-finite state (nor one outside the
/// limits or the swing domain): see `million_random_steps`.
///
/// Before the swing stops (CONTRACT_NOTES.md F3) the saturating inputs pumped the payload out
/// of the domain at step 167,472 and every later step was rejected; with the stops no step is
/// rejected and the smallest `sin(alpha) cos(beta)` is the stops' corner, cos(1.4)^2.
#[test]
fn a_million_random_saturating_steps_never_give_a_non_finite_state() {
    let run = million_random_steps();
    let total: usize = run.rejected.iter().sum();
    eprintln!(
        "10^6 random saturating steps: {total} rejected (Singular {}, NonFinite {}, \
         OutOfDomain {}); first {:?}; longest run of rejections {}; {} accepted after the \
         first rejection; {} rejected in a row at the end; smallest accepted hang {}",
        run.rejected[0],
        run.rejected[1],
        run.rejected[2],
        run.first,
        run.longest_run,
        run.accepted_after_first,
        run.final_run,
        run.min_hang
    );
    assert!(run.min_hang >= MIN_HANG);
    // With the swing stops the twin stays in its domain and usable: no step is rejected.
    assert_eq!(total, 0, "{run:?}");
}

/// A NaN or infinite input is rejected with an error naming the input; nothing changes.
#[test]
fn non_finite_input_is_rejected_and_changes_nothing() {
    let p = Params::default();
    let q = [0.2, 0.3, 0.4, FRAC_PI_2 + 0.2, 0.1];
    let qd = [0.1, -0.1, 0.0, 0.3, 0.2];
    let mut m = model(&p, H, FrictionLaw::Hybrid, q, qd);
    let mut r = reference(&p, q, qd);
    for _ in 0..50 {
        m.step([3.0, -2.0, 0.5]).expect("step");
        r.step([3.0, -2.0, 0.5]).expect("step");
    }
    let bad = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];
    for axis in 0..3 {
        for b in bad {
            let mut u = [1.0, 1.0, 1.0];
            u[axis] = b;
            let (s, modes, t, out) = (m.state(), m.modes(), m.time(), m.output());
            let err = m.step(u).expect_err("non-finite input must be rejected");
            assert_eq!(err, StepError::InputNotFinite { axis });
            let name = ["u_x", "u_y", "u_l"][axis];
            assert!(err.to_string().contains(name), "{err}");
            assert_eq!(m.state(), s);
            assert_eq!(m.modes(), modes);
            assert_eq!(m.time().to_bits(), t.to_bits());
            assert_eq!(m.output(), out, "output() must use the last accepted input");
            let rs = r.state();
            assert!(r.step(u).is_err());
            assert_eq!(r.state(), rs);
        }
    }
    // And the crane goes on as if nothing happened, still bit-exact with the reference.
    m.step([1.0, 1.0, 1.0]).expect("step");
    r.step([1.0, 1.0, 1.0]).expect("step");
    assert_eq!(m.state().q.map(f64::to_bits), r.q().map(f64::to_bits));
    assert_eq!(m.state().qd.map(f64::to_bits), r.qd().map(f64::to_bits));
}

/// Invalid parameters, configurations and initial states are rejected by `Crane::new` with an
/// error whose message names the field.
#[test]
fn invalid_parameters_are_rejected_naming_the_field() {
    type Edit = fn(&mut Params, &mut Config, &mut State<f64>);
    let cases: Vec<(&str, Edit)> = vec![
        ("payload_mass", |p, _, _| p.payload_mass = 0.0),
        ("payload_mass", |p, _, _| p.payload_mass = f64::NAN),
        ("trolley_mass", |p, _, _| p.trolley_mass = -1.0),
        ("rail_mass", |p, _, _| p.rail_mass = -0.1),
        ("gravity", |p, _, _| p.gravity = f64::INFINITY),
        ("damping_alpha", |p, _, _| p.damping_alpha = -1e-3),
        ("damping_beta", |p, _, _| p.damping_beta = f64::NAN),
        ("x.inertia", |p, _, _| p.x.inertia = -2.0),
        ("x.gain", |p, _, _| p.x.gain = 0.0),
        ("y.viscous_pos", |p, _, _| p.y.viscous_pos = -1.0),
        ("y.viscous_neg", |p, _, _| p.y.viscous_neg = f64::NAN),
        ("rope.gain", |p, _, _| p.rope.gain = -8.53),
        ("x.dry_pos[2]", |p, _, _| p.x.dry_pos[2] = f64::INFINITY),
        ("rope.dry_neg[0]", |p, _, _| p.rope.dry_neg[0] = f64::NAN),
        ("y.min", |p, _, _| p.y.min = 0.7),
        ("rope.min", |p, _, _| p.rope.min = 0.0),
        ("x.max", |p, _, _| p.x.max = f64::NAN),
        ("config.h", |_, c, _| c.h = 0.0),
        ("config.h", |_, c, _| c.h = f64::NAN),
        ("gamma", |_, c, _| c.law = FrictionLaw::Tanh { gamma: 0.0 }),
        ("state.q[0]", |_, _, s| s.q[0] = 0.6),
        ("state.q[2]", |_, _, s| s.q[2] = 0.1),
        ("state.q[3]", |_, _, s| s.q[3] = 0.0),
        ("state.q[3]", |_, _, s| s.q[3] = 4.0),
        ("state.qd[4]", |_, _, s| s.qd[4] = f64::NAN),
    ];
    for (field, edit) in cases {
        let mut p = Params::default();
        let mut c = Config {
            h: H,
            law: FrictionLaw::Hybrid,
        };
        let mut s = State {
            q: [0.2, 0.3, 0.4, FRAC_PI_2, 0.0],
            qd: [0.0; 5],
        };
        edit(&mut p, &mut c, &mut s);
        match Crane::<f64>::new(&p, c, s) {
            Ok(_) => panic!("`{field}` edit was accepted"),
            Err(e) => {
                let msg = e.to_string();
                assert!(msg.contains(field), "error for `{field}`: {msg}");
            }
        }
        // The reference refuses the same inputs.
        let law = match c.law {
            FrictionLaw::Hybrid => RefLaw::Hybrid,
            FrictionLaw::Tanh { gamma } => RefLaw::Tanh { gamma },
        };
        assert!(RefCrane::new(RefParams::from(&p), c.h, law, s.q, s.qd).is_err());
    }
}

/// `Crane::new` rejects an initial state outside the swing domain
/// `sin(alpha) cos(beta) >= MIN_HANG` with an error naming `state.q[4]`, like the reference
/// (`InvalidState("q[4]")`); states just inside are accepted by both.
#[test]
fn new_rejects_initial_states_outside_the_swing_domain() {
    // The swing stops (1.4 rad per angle) bound the initial state too; the field is named.
    let p = Params::default();
    let c = Config {
        h: H,
        law: FrictionLaw::Hybrid,
    };
    let stop = crane_model::SWING_STOP;
    let cases: [(f64, f64, Option<&str>); 8] = [
        (FRAC_PI_2, 0.0, None),
        (FRAC_PI_2, stop, None),
        (FRAC_PI_2, -stop, None),
        (FRAC_PI_2 + stop, stop, None), // the corner: hang = cos(1.4)^2 = 0.029 >= MIN_HANG
        (FRAC_PI_2, 1.41, Some("q[4]")),
        (FRAC_PI_2, 3.0, Some("q[4]")), // payload above the trolley
        (FRAC_PI_2 - 1.41, 0.0, Some("q[3]")),
        (std::f64::consts::PI - 0.0999, 0.0, Some("q[3]")),
    ];
    for (alpha, beta, bad) in cases {
        let s = State {
            q: [0.2, 0.3, 0.4, alpha, beta],
            qd: [0.0; 5],
        };
        let m = Crane::<f64>::new(&p, c, s);
        let r = RefCrane::new(RefParams::from(&p), H, RefLaw::Hybrid, s.q, s.qd);
        match bad {
            None => {
                assert!(m.is_ok(), "alpha {alpha}, beta {beta}: model {:?}", m.err());
                assert!(
                    r.is_ok(),
                    "alpha {alpha}, beta {beta}: reference {:?}",
                    r.err()
                );
                let hang = libm::sin(alpha) * libm::cos(beta);
                assert!(hang >= MIN_HANG, "alpha {alpha}, beta {beta}: hang {hang}");
            }
            Some(field) => {
                assert_eq!(
                    r.err(),
                    Some(RefError::InvalidState(field)),
                    "alpha {alpha}"
                );
                match m {
                    Ok(_) => panic!("alpha {alpha}, beta {beta}: model accepted it"),
                    Err(e) => assert!(e.to_string().contains(&format!("state.{field}")), "{e}"),
                }
            }
        }
    }
}

/// Sanity of the sign conventions against docs/MODEL.md: a positive voltage accelerates each axis
/// in its positive direction, the rope tension of a payload hanging still is `m_p g`, and the
/// payload hangs at `z_p = -L`.
#[test]
fn sign_conventions() {
    let p = Params::default();
    let q = [0.2, 0.3, 0.4, FRAC_PI_2, 0.0];
    let mut m = model(&p, H, FrictionLaw::Hybrid, q, [0.0; 5]);
    m.step([0.0; 3]).expect("step");
    let o = m.output().expect("output");
    assert!(
        (o.tension - p.payload_mass * p.gravity).abs() < 1e-9,
        "{}",
        o.tension
    );
    assert!((o.payload[2] + 0.4).abs() < 1e-12);
    for _ in 0..200 {
        m.step([6.0, 6.0, 6.0]).expect("step");
    }
    let s = m.state();
    assert!(s.q[0] > q[0] && s.q[1] > q[1] && s.q[2] > q[2], "{s:?}");
    assert_eq!(m.modes(), [Mode::Positive; 3]);
}
