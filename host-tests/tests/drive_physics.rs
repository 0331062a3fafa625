//! Physics of the single-axis drive (`crane_model::Drive`): energy, exact sticking, the
//! stick-slip staircase, end stops, input path, parameter and input validation, Stribeck
//! weakening, load-dependent and localised friction.

use crane_model::{
    Drive, DriveParams, DriveStepError, LocalFriction, Mode, Motion, PositionForce, Problem,
    MAX_DRIVE_DELAY_STEPS,
};

const H: f64 = 1e-3;

fn spring(stiffness: f64, center: f64) -> PositionForce {
    PositionForce::Spring { stiffness, center }
}

/// Mechanical energy `I v^2 / 2 + V(x) - F x` with the applied force `F` constant.
fn energy(p: &DriveParams, d: &Drive, f: f64) -> f64 {
    let (x, v) = (d.x(), d.v());
    let pot = match p.position_force {
        PositionForce::None => 0.0,
        PositionForce::Spring { stiffness, center } => 0.5 * stiffness * (x - center).powi(2),
        PositionForce::Pendulum { stiffness, center } => stiffness * (1.0 - (x - center).cos()),
    };
    0.5 * p.inertia * v * v + pot - f * x
}

/// Largest relative energy drift over 20 s of a frictionless oscillation (10 and 20 turning
/// points pass through `Stopped`, each located inside its step).
fn max_drift(p: &DriveParams, x0: f64, u: f64) -> (f64, usize) {
    let mut d: Drive = Drive::new(p, H, x0).expect("valid");
    let f = p.gain * u + p.offset;
    d.step(u).expect("step");
    let e0 = energy(p, &d, f);
    let scale = e0.abs().max(1e-12);
    let (mut worst, mut stops) = (0.0f64, 0usize);
    for _ in 0..20_000 {
        let r = d.step(u).expect("step");
        stops += usize::from(r.events);
        worst = worst.max((energy(p, &d, f) - e0).abs() / scale);
    }
    (worst, stops)
}

#[test]
fn frictionless_spring_and_pendulum_conserve_energy() {
    // omega = 10 rad/s, h = 1 ms: RK4's energy error is ~(omega h)^5 per step; the located
    // reversals lose at most I a^2 (h / 2^30)^2 / 2 each.
    let p = DriveParams {
        inertia: 2.0,
        position_force: spring(200.0, 0.05),
        offset: 3.0,
        ..DriveParams::default()
    };
    let (drift, stops) = max_drift(&p, 0.25, 0.0);
    eprintln!("spring: {stops} located reversals, max relative energy drift {drift:e}");
    assert!(stops >= 60, "reversals located: {stops}");
    assert!(drift < 1e-9, "spring: relative energy drift {drift:e}");

    let p = DriveParams {
        motion: Motion::Rotary,
        inertia: 0.5,
        gain: 2.0,
        position_force: PositionForce::Pendulum {
            stiffness: 40.0,
            center: -0.2,
        },
        ..DriveParams::default()
    };
    let (drift, stops) = max_drift(&p, 1.3, 1.5);
    eprintln!("pendulum: {stops} located reversals, max relative energy drift {drift:e}");
    assert!(stops >= 30, "reversals located: {stops}");
    assert!(drift < 1e-9, "pendulum: relative energy drift {drift:e}");
}

#[test]
fn with_friction_energy_never_rises() {
    let mut checked = 0;
    for (i, (visc, kin, stiction, stops)) in [
        (0.0, 0.5, 0.0, false),
        (0.8, 0.0, 0.0, false),
        (0.3, 0.4, 0.5, false),
        (0.0, 0.2, 1.0, true),
        (2.0, 1.0, 0.2, true),
    ]
    .into_iter()
    .enumerate()
    {
        let p = DriveParams {
            inertia: 0.3 + 0.2 * i as f64,
            viscous_pos: visc,
            viscous_neg: visc * 1.5,
            kinetic_pos: kin,
            kinetic_neg: kin * 0.7,
            breakaway_pos: kin * (1.0 + stiction),
            breakaway_neg: kin * 0.7 * (1.0 + stiction),
            offset: 0.4,
            position_force: if i % 2 == 0 {
                spring(150.0, 0.0)
            } else {
                PositionForce::Pendulum {
                    stiffness: 30.0,
                    center: 0.1,
                }
            },
            min: if stops { -0.12 } else { f64::NEG_INFINITY },
            max: if stops { 0.1 } else { f64::INFINITY },
            ..DriveParams::default()
        };
        let mut d: Drive = Drive::new(&p, H, 0.09).expect("valid");
        d.set_state(0.09, -3.0).expect("state");
        let f = p.offset;
        let mut e = energy(&p, &d, f);
        let e0 = e.abs();
        for n in 0..10_000 {
            d.step(0.0).expect("step");
            let e2 = energy(&p, &d, f);
            assert!(
                e2 <= e + 1e-12 * e0,
                "case {i}, step {n}: energy rose from {e} to {e2}"
            );
            e = e2;
            checked += 1;
        }
        if kin > 0.0 {
            assert_eq!(
                d.mode(),
                Mode::Stopped,
                "case {i} comes to rest (dry friction)"
            );
        }
    }
    assert_eq!(checked, 50_000);
}

#[test]
fn a_stopped_axis_stays_bit_exactly_put_below_breakaway() {
    let p = DriveParams {
        kinetic_pos: 1.0,
        kinetic_neg: 1.5,
        breakaway_pos: 2.0,
        breakaway_neg: 3.0,
        position_force: spring(50.0, 0.0),
        offset: 0.25,
        gain: 0.5,
        ..DriveParams::default()
    };
    // Holding force F - k x = 0.5 u + 0.25 - 50 * 0.01 = 0.5 u - 0.25 must stay in (-3, 2).
    let x0 = 0.01;
    let mut d: Drive = Drive::new(&p, H, x0).expect("valid");
    let mut rng = crane_ident::rng::Rng::new(12345);
    for n in 0..20_000 {
        let u = rng.range(-5.5, 4.5); // hold in [-3.0, 2.0)
        let u = if n % 1000 == 0 { 4.4999 } else { u }; // near the positive edge
        d.step(u).expect("step");
        assert_eq!(
            d.x().to_bits(),
            x0.to_bits(),
            "step {n}: moved to {}",
            d.x()
        );
        assert_eq!(d.v().to_bits(), 0.0f64.to_bits());
        assert_eq!(d.mode(), Mode::Stopped);
        let o = d.output();
        assert_eq!(o.acceleration, 0.0);
        assert_eq!(
            o.friction,
            o.applied - o.position_force,
            "static friction holds"
        );
    }
    // Just above breakaway it goes.
    d.step(4.5 + 1e-9).expect("step");
    assert_eq!(d.mode(), Mode::Positive);
    assert!(d.x() > x0);
}

/// Slips of a run: (start step, end step, x at start, x at end, input at the end).
fn slips(
    d: &mut Drive,
    u: impl Fn(usize) -> f64,
    steps: usize,
) -> Vec<(usize, usize, f64, f64, f64)> {
    let mut out = Vec::new();
    let mut start: Option<(usize, f64)> = None;
    let mut x_stuck = d.x();
    for n in 0..steps {
        let x_before = d.x();
        d.step(u(n)).expect("step");
        match (d.mode(), start) {
            (Mode::Stopped, Some((s, x0))) => {
                out.push((s, n, x0, d.x(), u(n)));
                start = None;
                x_stuck = d.x();
            }
            (Mode::Stopped, None) => {
                assert_eq!(
                    d.x().to_bits(),
                    x_stuck.to_bits(),
                    "stuck axis moved at step {n}"
                );
            }
            (_, None) => start = Some((n, x_before)),
            _ => {}
        }
    }
    out
}

#[test]
fn stick_slip_staircase_on_a_ramp_against_a_spring() {
    // Joint-like: the torque ramps up slowly against a restoring torque. Breakaway 10, kinetic
    // 6: each slip overshoots the equilibrium and stops with the holding torque near
    // 2 * 6 - 10 = 2 < 10, so it sticks again while the torque keeps rising.
    let (k, bp, kp) = (40.0, 10.0, 6.0);
    let p = DriveParams {
        motion: Motion::Rotary,
        inertia: 0.1,
        viscous_pos: 0.05,
        viscous_neg: 0.05,
        kinetic_pos: kp,
        kinetic_neg: kp,
        breakaway_pos: bp,
        breakaway_neg: bp,
        position_force: spring(k, 0.0),
        ..DriveParams::default()
    };
    let mut d: Drive = Drive::new(&p, H, 0.0).expect("valid");
    let rate = 2.0; // N m/s
    let s = slips(&mut d, |n| rate * n as f64 * H, 60_000);
    assert!(s.len() >= 10, "slips: {}", s.len());
    let jump = 2.0 * (bp - kp) / k; // 0.2 rad without damping or ramp
    for (i, w) in s.windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
        assert!(b.4 > a.4, "the torque keeps rising between slips");
        assert!(
            b.0 > a.1 + 100,
            "slip {i}: sticks a while before the next slip"
        );
    }
    for &(s0, s1, x0, x1, u1) in &s {
        assert!(x1 > x0, "a slip moves forward");
        assert!(
            ((x1 - x0) - jump).abs() < 0.1 * jump,
            "slip from {x0} to {x1}: jump {} vs {jump}",
            x1 - x0
        );
        assert!(
            s1 - s0 < 200,
            "a slip lasts half a period (~50 ms): {} steps",
            s1 - s0
        );
        // Stopped with the holding torque below breakaway (2 * kinetic - breakaway, about).
        let hold = u1 - k * x1;
        assert!(hold < bp && hold > -bp, "holding torque {hold} at the stop");
    }
}

#[test]
fn stick_slip_staircase_of_a_joint_against_gravity() {
    // CICESE-like joint 1: gravity `40.3 sin(x)` N m, static 10.75 / 12.0, kinetic 8 / 9 N m,
    // a torque ramp of 2 N m/s to 30 N m (below the 40.3 N m gravity can hold at most).
    let p = DriveParams {
        motion: Motion::Rotary,
        inertia: 0.12,
        viscous_pos: 0.3,
        viscous_neg: 0.35,
        kinetic_pos: 8.0,
        kinetic_neg: 9.0,
        breakaway_pos: 10.75,
        breakaway_neg: 12.0,
        position_force: PositionForce::Pendulum {
            stiffness: 40.3,
            center: 0.0,
        },
        ..DriveParams::default()
    };
    let mut d: Drive = Drive::new(&p, H, 0.0).expect("valid");
    let s = slips(&mut d, |n| 2.0 * n as f64 * H, 15_000);
    assert!(s.len() >= 4, "slips: {}", s.len());
    let first = s[0];
    // The first slip starts when the torque passes breakaway (x = 0, no gravity yet).
    let u_first = 2.0 * first.0 as f64 * H;
    assert!(
        (u_first - 10.75).abs() < 0.01,
        "first breakaway at {u_first} N m"
    );
    for w in s.windows(2) {
        assert!(w[1].0 > w[0].1 + 100, "sticks between slips");
        assert!(w[1].4 > w[0].4, "the torque keeps rising");
    }
    for &(_, _, x0, x1, u1) in &s {
        assert!(x1 > x0, "each slip moves up");
        let hold = u1 - 40.3 * x1.sin();
        assert!(
            hold < 10.75 && hold > -12.0,
            "stuck with holding torque {hold}"
        );
    }
}

#[test]
fn a_reversal_passes_through_stopped_within_the_step() {
    let p = DriveParams {
        inertia: 1.0,
        position_force: spring(100.0, 0.0),
        ..DriveParams::default()
    };
    let mut d: Drive = Drive::new(&p, H, 0.1).expect("valid");
    d.step(0.0).expect("step");
    assert_eq!(d.mode(), Mode::Negative, "released at once");
    let mut reversals = 0;
    for n in 0..2000 {
        let before = d.mode();
        let r = d.step(0.0).expect("step");
        assert_ne!(
            d.mode(),
            Mode::Stopped,
            "step {n}: a frictionless spring never rests"
        );
        if d.mode() != before {
            assert_eq!(r.events, 1, "step {n}: the reversal is a located stop");
            assert_eq!(r.late_resets, 0);
            reversals += 1;
        }
    }
    // omega = 10 rad/s: a reversal every pi/10 s, 6 in 2 s.
    assert_eq!(reversals, 6);
}

#[test]
fn without_stiction_and_spring_the_axis_never_sticks_above_kinetic() {
    let kp = 2.0;
    let p = DriveParams {
        inertia: 1.5,
        viscous_pos: 0.5,
        kinetic_pos: kp,
        kinetic_neg: kp,
        breakaway_pos: kp,
        breakaway_neg: kp,
        ..DriveParams::default()
    };
    let mut d: Drive = Drive::new(&p, H, 0.0).expect("valid");
    let mut moved = 0;
    for n in 0..10_000 {
        let u = 3.0 * kp * n as f64 / 10_000.0;
        d.step(u).expect("step");
        if u > kp {
            assert_eq!(d.mode(), Mode::Positive, "stuck at step {n} with F = {u}");
            moved += 1;
        } else {
            assert_eq!(
                d.mode(),
                Mode::Stopped,
                "moved at step {n} with F = {u} <= kinetic"
            );
        }
    }
    assert!(moved > 6000);
    // With a breakaway above kinetic, the same ramp waits for the breakaway level.
    let p2 = DriveParams {
        breakaway_pos: 1.5 * kp,
        ..p
    };
    let mut d: Drive = Drive::new(&p2, H, 0.0).expect("valid");
    for n in 0..10_000 {
        let u = 3.0 * kp * n as f64 / 10_000.0;
        d.step(u).expect("step");
        if u <= 1.5 * kp {
            assert_eq!(
                d.mode(),
                Mode::Stopped,
                "broke away below breakaway at F = {u}"
            );
        }
    }
    assert_eq!(d.mode(), Mode::Positive);
}

#[test]
fn end_stops_are_respected_and_absorb_the_impact() {
    let p = DriveParams {
        inertia: 0.2,
        kinetic_pos: 0.3,
        kinetic_neg: 0.3,
        breakaway_pos: 0.5,
        breakaway_neg: 0.5,
        min: -0.05,
        max: 0.1,
        ..DriveParams::default()
    };
    let mut d: Drive = Drive::new(&p, H, 0.0).expect("valid");
    let mut hits = 0;
    for n in 0..4000 {
        let u = if (n / 1000) % 2 == 0 { 5.0 } else { -5.0 };
        let r = d.step(u).expect("step");
        assert!(
            d.x() >= p.min && d.x() <= p.max,
            "x = {} at step {n}",
            d.x()
        );
        if d.x() == p.max || d.x() == p.min {
            assert_eq!(d.v(), 0.0, "at the stop the axis rests");
            assert_eq!(d.mode(), Mode::Stopped);
            hits += usize::from(r.events);
        }
    }
    assert!(hits >= 4, "end-stop events: {hits}");
    // Pushed into the stop it stays there; pulled away it leaves.
    d.set_state(p.max, 0.0).expect("state");
    for _ in 0..100 {
        d.step(50.0).expect("step");
        assert_eq!(d.x(), p.max);
    }
    d.step(-50.0).expect("step");
    assert_eq!(d.mode(), Mode::Negative);
    assert!(d.x() < p.max);
    // A velocity into a stop is dropped by set_state.
    d.set_state(p.min, -1.0).expect("state");
    assert_eq!((d.v(), d.mode()), (0.0, Mode::Stopped));
}

#[test]
fn dead_band_and_delay_shape_the_input() {
    let base = DriveParams {
        gain: 2.0,
        deadband: 0.5,
        delay_steps: 7,
        ..DriveParams::default()
    };
    // Inside the dead band: no force.
    let mut d: Drive = Drive::new(&base, H, 0.0).expect("valid");
    for _ in 0..100 {
        d.step(0.5).expect("step");
    }
    assert_eq!((d.x(), d.mode()), (0.0, Mode::Stopped));
    // A step of 1.5 gives 2 * (1.5 - 0.5) = 2 N exactly 7 steps later.
    let mut d: Drive = Drive::new(&base, H, 0.0).expect("valid");
    for n in 0..20 {
        d.step(1.5).expect("step");
        let f = d.output().applied;
        if n < 7 {
            assert_eq!((f, d.x()), (0.0, 0.0), "step {n}");
        } else {
            assert_eq!(f, 2.0, "step {n}");
            assert!(d.x() > 0.0);
        }
    }
    // The full capacity is usable.
    let p = DriveParams {
        delay_steps: MAX_DRIVE_DELAY_STEPS,
        deadband: 0.0,
        ..base
    };
    let mut d: Drive = Drive::new(&p, H, 0.0).expect("valid");
    for n in 0..=MAX_DRIVE_DELAY_STEPS {
        d.step(n as f64 + 1.0).expect("step");
    }
    assert_eq!(d.output().applied, 2.0, "the first input, 64 steps later");
}

#[test]
fn non_finite_input_is_rejected_with_state_and_delay_line_unchanged() {
    let p = DriveParams {
        kinetic_pos: 0.2,
        kinetic_neg: 0.2,
        breakaway_pos: 0.3,
        breakaway_neg: 0.3,
        position_force: spring(10.0, 0.0),
        delay_steps: 3,
        ..DriveParams::default()
    };
    let mut a: Drive = Drive::new(&p, H, 0.0).expect("valid");
    for n in 0..500 {
        a.step((n as f64 * 0.01).sin() * 3.0).expect("step");
    }
    let mut b = a.clone();
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let (x, v, m, t) = (b.x(), b.v(), b.mode(), b.time());
        assert_eq!(b.step(bad), Err(DriveStepError::InputNotFinite));
        assert_eq!(
            (b.x().to_bits(), b.v().to_bits(), b.mode()),
            (x.to_bits(), v.to_bits(), m)
        );
        assert_eq!(b.time(), t);
    }
    // An overflowing force is rejected too.
    let big = DriveParams {
        gain: 1e10,
        delay_steps: 0,
        ..p
    };
    let mut c: Drive = Drive::new(&big, H, 0.0).expect("valid");
    assert_eq!(c.step(1e300), Err(DriveStepError::ForceNotFinite));
    assert_eq!((c.x(), c.steps()), (0.0, 0));
    // The rejected steps did not shift the delay line: both continue bit for bit.
    for n in 0..500 {
        let u = (n as f64 * 0.02).cos() * 2.0;
        a.step(u).expect("step");
        b.step(u).expect("step");
        assert_eq!(a.x().to_bits(), b.x().to_bits());
        assert_eq!(a.v().to_bits(), b.v().to_bits());
    }
}

#[test]
fn bad_parameters_name_their_field() {
    let ok = DriveParams {
        kinetic_pos: 1.0,
        kinetic_neg: 1.0,
        breakaway_pos: 1.0,
        breakaway_neg: 1.0,
        ..DriveParams::default()
    };
    assert!(Drive::<f64>::new(&ok, H, 0.0).is_ok());
    type Case = (fn(&mut DriveParams), &'static str, Problem);
    fn bump(center: f64, half_width: f64, amplitude: f64) -> LocalFriction {
        LocalFriction::Bump {
            center,
            half_width,
            amplitude,
        }
    }
    let cases: [Case; 29] = [
        (|p| p.inertia = 0.0, "inertia", Problem::NotPositive),
        (|p| p.inertia = f64::INFINITY, "inertia", Problem::NotFinite),
        (|p| p.gain = -1.0, "gain", Problem::NotPositive),
        (|p| p.viscous_pos = -0.1, "viscous_pos", Problem::Negative),
        (
            |p| p.viscous_neg = f64::NAN,
            "viscous_neg",
            Problem::NotFinite,
        ),
        (|p| p.kinetic_pos = -1.0, "kinetic_pos", Problem::Negative),
        (|p| p.kinetic_neg = -1.0, "kinetic_neg", Problem::Negative),
        (
            |p| p.breakaway_pos = 0.9,
            "breakaway_pos",
            Problem::BelowKinetic,
        ),
        (
            |p| p.breakaway_neg = 0.5,
            "breakaway_neg",
            Problem::BelowKinetic,
        ),
        (|p| p.offset = f64::NAN, "offset", Problem::NotFinite),
        (
            |p| p.position_force = spring(-3.0, 0.0),
            "position_force.stiffness",
            Problem::Negative,
        ),
        (
            |p| {
                p.position_force = PositionForce::Pendulum {
                    stiffness: 1.0,
                    center: f64::INFINITY,
                }
            },
            "position_force.center",
            Problem::NotFinite,
        ),
        (|p| p.deadband = -0.1, "deadband", Problem::Negative),
        (|p| p.delay_steps = 65, "delay_steps", Problem::TooLarge),
        (|p| p.min = f64::NAN, "min", Problem::NotANumber),
        (|p| p.max = f64::NAN, "max", Problem::NotANumber),
        (|p| (p.min, p.max) = (1.0, 1.0), "min", Problem::EmptyRange),
        (
            |p| p.stribeck_velocity = -0.01,
            "stribeck_velocity",
            Problem::Negative,
        ),
        (
            |p| p.stribeck_velocity = f64::INFINITY,
            "stribeck_velocity",
            Problem::NotFinite,
        ),
        (
            |p| p.load_friction = -0.1,
            "load_friction",
            Problem::Negative,
        ),
        (
            |p| p.load_friction = 1.0,
            "load_friction",
            Problem::NotBelowOne,
        ),
        (
            |p| p.load_friction = f64::NAN,
            "load_friction",
            Problem::NotFinite,
        ),
        (
            |p| p.local_friction = bump(f64::NAN, 0.1, 1.0),
            "local_friction.center",
            Problem::NotFinite,
        ),
        (
            |p| p.local_friction = bump(0.0, 0.0, 1.0),
            "local_friction.half_width",
            Problem::NotPositive,
        ),
        (
            |p| p.local_friction = bump(0.0, f64::INFINITY, 1.0),
            "local_friction.half_width",
            Problem::NotFinite,
        ),
        (
            |p| p.local_friction = bump(0.0, 0.1, f64::INFINITY),
            "local_friction.amplitude",
            Problem::NotFinite,
        ),
        // A dip deeper than the kinetic level (1 N) of either direction.
        (
            |p| p.local_friction = bump(0.0, 0.1, -1.01),
            "local_friction.amplitude",
            Problem::LevelBelowZero,
        ),
        (
            |p| {
                p.kinetic_neg = 0.5;
                p.local_friction = bump(0.0, 0.1, -0.75);
            },
            "local_friction.amplitude",
            Problem::LevelBelowZero,
        ),
        (
            |p| {
                (p.kinetic_pos, p.breakaway_pos) = (0.0, 0.0);
                p.local_friction = bump(0.0, 0.1, -1e-300);
            },
            "local_friction.amplitude",
            Problem::LevelBelowZero,
        ),
    ];
    for (mutate, field, problem) in cases {
        let mut p = ok;
        mutate(&mut p);
        let e = Drive::<f64>::new(&p, H, 0.0).expect_err(field);
        assert_eq!((e.field, e.problem), (field, problem), "{e}");
        assert!(e.to_string().contains(field));
    }
    // A dip down to exactly 0 is valid, and so is any bump.
    for amplitude in [-1.0, 0.0, 1e9] {
        let p = DriveParams {
            local_friction: bump(0.3, 0.1, amplitude),
            ..ok
        };
        assert!(Drive::<f64>::new(&p, H, 0.0).is_ok(), "{amplitude}");
    }
    for (h, problem) in [(0.0, Problem::NotPositive), (f64::NAN, Problem::NotFinite)] {
        let e = Drive::<f64>::new(&ok, h, 0.0).expect_err("h");
        assert_eq!((e.field, e.problem), ("h", problem));
    }
    let bounded = DriveParams {
        min: -1.0,
        max: 1.0,
        ..ok
    };
    let e = Drive::<f64>::new(&bounded, H, 1.5).expect_err("x0");
    assert_eq!((e.field, e.problem), ("state.x", Problem::OutOfLimits));
    let mut d = Drive::<f64>::new(&bounded, H, 0.5).expect("valid");
    let e = d.set_state(0.0, f64::NAN).expect_err("v");
    assert_eq!((e.field, e.problem), ("state.v", Problem::NotFinite));
    assert_eq!(d.x(), 0.5, "a rejected set_state changes nothing");
}

#[test]
fn f32_drive_follows_f64_on_stick_slip() {
    let p = DriveParams {
        motion: Motion::Rotary,
        inertia: 0.1,
        viscous_pos: 0.05,
        viscous_neg: 0.05,
        kinetic_pos: 6.0,
        kinetic_neg: 6.0,
        breakaway_pos: 10.0,
        breakaway_neg: 10.0,
        position_force: PositionForce::Pendulum {
            stiffness: 40.0,
            center: 0.0,
        },
        ..DriveParams::default()
    };
    let mut a: Drive<f64> = Drive::new(&p, H, 0.0).expect("valid");
    let mut b: Drive<f32> = Drive::new(&p, H, 0.0).expect("valid");
    let mut worst = 0.0f64;
    for n in 0..20_000 {
        let u = 30.0 * (n as f64 * H * 0.5).sin();
        a.step(u).expect("f64 step");
        b.step(u as f32).expect("f32 step");
        worst = worst.max((a.x() - f64::from(b.x())).abs());
    }
    let range = 2.0; // rad, about
    assert!(worst < 1e-3 * range, "f32 vs f64 position: {worst}");
}

/// A slider with stiction (kinetic 1, breakaway 2 N) and Stribeck weakening at `vs` [m/s].
fn stribeck_slider(vs: f64) -> DriveParams {
    DriveParams {
        inertia: 1.0,
        viscous_pos: 0.5,
        viscous_neg: 0.7,
        kinetic_pos: 1.0,
        kinetic_neg: 1.2,
        breakaway_pos: 2.0,
        breakaway_neg: 2.5,
        stribeck_velocity: vs,
        ..DriveParams::default()
    }
}

#[test]
fn stribeck_breakaway_is_continuous_and_the_friction_then_weakens_to_kinetic() {
    let vs = 0.01;
    let p = stribeck_slider(vs);
    let rate = 1.0; // N/s
    let mut d: Drive = Drive::new(&p, H, 0.0).expect("valid");
    let mut n = 0usize;
    // The ramp breaks it away at the breakaway level, not at the kinetic one.
    loop {
        let u = rate * n as f64 * H;
        d.step(u).expect("step");
        n += 1;
        if d.mode() != Mode::Stopped {
            assert!(
                u > p.breakaway_pos && u <= p.breakaway_pos + rate * H,
                "broke away at F = {u}"
            );
            break;
        }
        assert_eq!(d.x(), 0.0, "moved below breakaway at F = {u}");
        assert!(n < 3000, "never broke away");
    }
    // Just after breakaway the sliding friction is at the breakaway level (continuous with
    // the static friction that held it; a plain kinetic law would drop to 1 N at once)...
    let o = d.output();
    assert!(
        (o.friction - p.breakaway_pos).abs() < 1e-3,
        "friction right after breakaway: {}",
        o.friction
    );
    // ... then falls with speed while the force has hardly changed, so the axis accelerates
    // away (velocity weakening): at v = vs the excess over kinetic is down to exp(-1).
    let (mut friction_prev, mut seen_vs) = (o.friction, false);
    while d.v() < 20.0 * vs {
        let u = rate * n as f64 * H;
        d.step(u).expect("step");
        n += 1;
        assert_eq!(d.mode(), Mode::Positive, "re-stuck at F = {u}");
        let o = d.output();
        let v = d.v();
        let expected = 1.0 + (2.0 - 1.0) * (-(v / vs) * (v / vs)).exp() + 0.5 * v;
        assert!(
            (o.friction - expected).abs() < 1e-12,
            "friction {} vs {expected} at v = {v}",
            o.friction
        );
        if v > 1e-3 && v < 2.0 * vs {
            // (below 2.6 vs the weakening outweighs the viscous rise)
            assert!(o.friction < friction_prev, "the friction falls with speed");
        }
        if v >= vs && !seen_vs {
            seen_vs = true;
            assert!(u < p.breakaway_pos + 0.2, "F = {u} at v = vs");
            assert!(
                o.friction < 1.0 + 0.4 + 0.5 * v,
                "friction {} at v = vs",
                o.friction
            );
            assert!(o.acceleration > 0.5, "accelerates away: {}", o.acceleration);
        }
        friction_prev = o.friction;
        assert!(n < 3000, "never reached 20 vs");
    }
    // Far above vs it is the kinetic + viscous law.
    for _ in 0..500 {
        d.step(3.0).expect("step");
        let v = d.v();
        assert!(v > 20.0 * vs);
        let f = d.output().friction;
        assert!(
            (f - (1.0 + 0.5 * v)).abs() < 1e-9,
            "friction {f} at v = {v}"
        );
    }
    // Likewise moving negative, with the negative levels.
    d.set_state(d.x(), -0.5).expect("state");
    for _ in 0..200 {
        d.step(-3.0).expect("step");
        let v = d.v();
        assert!(v < -20.0 * vs);
        let f = d.output().friction;
        assert!(
            (f - (-1.2 + 0.7 * v)).abs() < 1e-9,
            "friction {f} at v = {v}"
        );
    }
}

#[test]
fn stribeck_a_force_between_kinetic_and_breakaway_keeps_a_fast_axis_moving_and_stops_a_slow_one() {
    // F = 1.5 N: above kinetic (1), below breakaway (2). The friction `1 + exp(-(v/vs)^2) +
    // 0.5 v` equals F at v ~ 0.83 vs (unstable) and at v = 1 m/s (stable).
    let vs = 0.01;
    let p = stribeck_slider(vs);
    let f = 1.5;
    let mut fast: Drive = Drive::new(&p, H, 0.0).expect("valid");
    fast.set_state(0.0, 5.0 * vs).expect("state");
    let mut slow = fast.clone();
    slow.set_state(0.0, 0.5 * vs).expect("state");
    for _ in 0..30_000 {
        fast.step(f).expect("step");
        slow.step(f).expect("step");
    }
    assert_eq!(fast.mode(), Mode::Positive);
    assert!((fast.v() - 1.0).abs() < 1e-5, "steady speed {}", fast.v());
    assert_eq!(slow.mode(), Mode::Stopped, "the slow one stops and sticks");
    assert!(slow.x() > 0.0 && slow.x() < vs);
    // Without weakening both reach the steady speed.
    let plain = DriveParams {
        stribeck_velocity: 0.0,
        ..p
    };
    let mut d: Drive = Drive::new(&plain, H, 0.0).expect("valid");
    d.set_state(0.0, 0.5 * vs).expect("state");
    for _ in 0..30_000 {
        d.step(f).expect("step");
    }
    assert!((d.v() - 1.0).abs() < 1e-5, "no weakening: speed {}", d.v());
}

/// A geared axis: kinetic 1, breakaway 1.5 N, load friction `mu` of the drive effort.
fn geared(mu: f64) -> DriveParams {
    DriveParams {
        inertia: 2.0,
        gain: 2.0,
        kinetic_pos: 1.0,
        kinetic_neg: 1.0,
        breakaway_pos: 1.5,
        breakaway_neg: 1.5,
        load_friction: mu,
        ..DriveParams::default()
    }
}

#[test]
fn load_friction_holds_up_to_breakaway_over_one_minus_mu_and_brakes_harder() {
    let mu = 0.25;
    let p = geared(mu);
    let limit = p.breakaway_pos / (1.0 - mu); // 2 N
    for (force, holds) in [
        (1.9, true),
        (limit - 1e-9, true),
        (limit, true),
        (limit + 1e-9, false),
        (2.5, false),
    ] {
        for sign in [1.0, -1.0] {
            let mut d: Drive = Drive::new(&p, H, 0.0).expect("valid");
            let u = sign * force / p.gain;
            for _ in 0..1000 {
                d.step(u).expect("step");
            }
            let f = sign * force;
            if holds {
                assert_eq!(d.mode(), Mode::Stopped, "moved under F = {f}");
                assert_eq!(d.x().to_bits(), 0.0f64.to_bits());
                assert_eq!(d.output().friction, f, "static friction holds");
            } else {
                let m = if sign > 0.0 {
                    Mode::Positive
                } else {
                    Mode::Negative
                };
                assert_eq!(d.mode(), m, "stuck under F = {f}");
            }
        }
    }
    // Without load friction 1.9 N breaks it away.
    let mut d: Drive = Drive::new(&geared(0.0), H, 0.0).expect("valid");
    d.step(1.9 / 2.0).expect("step");
    assert_eq!(d.mode(), Mode::Positive);

    // Sliding: a = (F - kinetic - mu |F|) / J, pushing along or braking against the motion.
    for force in [3.0, -3.0] {
        let mut d: Drive = Drive::new(&p, H, 0.0).expect("valid");
        let v0 = 5.0;
        d.set_state(0.0, v0).expect("state");
        let a = (force - 1.0 - mu * f64::abs(force)) / p.inertia; // 0.625, -2.375
        for n in 1..=1000 {
            d.step(force / p.gain).expect("step");
            let t = n as f64 * H;
            assert!(
                (d.v() - (v0 + a * t)).abs() < 1e-9,
                "F = {force}, t = {t}: v = {} vs {}",
                d.v(),
                v0 + a * t
            );
            let o = d.output();
            assert!(
                (o.acceleration - a).abs() < 1e-12,
                "acceleration {}",
                o.acceleration
            );
            assert!((o.friction - (1.0 + mu * f64::abs(force))).abs() < 1e-12);
        }
    }
    // The offset carries no load: moving under the offset alone, the friction is kinetic.
    let biased = DriveParams { offset: 4.0, ..p };
    let mut d: Drive = Drive::new(&biased, H, 0.0).expect("valid");
    d.set_state(0.0, 1.0).expect("state");
    d.step(0.0).expect("step");
    assert_eq!(d.output().friction, 1.0);
    let a = (4.0 - 1.0) / p.inertia;
    assert!((d.v() - (1.0 + a * H)).abs() < 1e-12, "v = {}", d.v());
    let v1 = d.v();
    d.step(1.0).expect("step");
    assert_eq!(d.output().friction, 1.0 + mu * 2.0);
    let a = (2.0 + 4.0 - 1.0 - mu * 2.0) / p.inertia;
    assert!((d.v() - (v1 + a * H)).abs() < 1e-12, "v = {}", d.v());
}

/// FNV-1a over the bits of `x`, `v`, the mode and `output()` after every step of a ramp with
/// a sine; also the located events and the stuck steps.
fn trajectory_hash(p: &DriveParams) -> (u64, u32, usize) {
    let mut d: Drive = Drive::new(p, H, 0.0).expect("valid");
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    let (mut events, mut stuck) = (0u32, 0usize);
    let mut eat = |w: u64| {
        for b in w.to_le_bytes() {
            hash ^= u64::from(b);
            hash = hash.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for n in 0..20_000 {
        let t = n as f64 * H;
        let u = 0.8 * t + 16.0 * (2.0 * std::f64::consts::PI * 1.3 * t).sin();
        let r = d.step(u).expect("step");
        let o = d.output();
        events += u32::from(r.events);
        stuck += usize::from(d.mode() == Mode::Stopped);
        for w in [
            d.x().to_bits(),
            d.v().to_bits(),
            d.mode() as u64,
            u64::from(r.events),
            o.acceleration.to_bits(),
            o.friction.to_bits(),
        ] {
            eat(w);
        }
    }
    (hash, events, stuck)
}

#[test]
fn with_both_effects_off_the_trajectory_bits_are_those_of_the_model_without_them() {
    // A stick-slip joint with gravity, a dead band and a delay; both new fields at 0.
    let p = DriveParams {
        motion: Motion::Rotary,
        inertia: 0.12,
        viscous_pos: 0.3,
        viscous_neg: 0.35,
        kinetic_pos: 8.0,
        kinetic_neg: 9.0,
        breakaway_pos: 10.75,
        breakaway_neg: 12.0,
        offset: 0.5,
        position_force: PositionForce::Pendulum {
            stiffness: 40.3,
            center: 0.0,
        },
        deadband: 0.05,
        delay_steps: 3,
        ..DriveParams::default()
    };
    let explicit = DriveParams {
        stribeck_velocity: 0.0,
        load_friction: 0.0,
        ..p
    };
    assert_eq!(p.stribeck_velocity, 0.0);
    assert_eq!(p.load_friction, 0.0);
    let (h, events, stuck) = trajectory_hash(&p);
    assert!(
        events > 5 && stuck > 1000,
        "{events} events, {stuck} stuck steps"
    );
    assert_eq!(h, trajectory_hash(&explicit).0);
    // Recorded with the model before `stribeck_velocity` and `load_friction` existed
    // (commit 21144e4): the same operations, the same bits.
    assert_eq!(h, GOLDEN_BEFORE_FRICTION_EFFECTS, "got {h:#018x}");
    // And either effect changes them.
    for q in [
        DriveParams {
            stribeck_velocity: 0.05,
            ..p
        },
        DriveParams {
            load_friction: 0.1,
            ..p
        },
    ] {
        assert_ne!(trajectory_hash(&q).0, h);
    }
}

/// [`trajectory_hash`] of the joint of the test above, from the model at commit 21144e4
/// (before the two friction effects), computed there with the same function.
const GOLDEN_BEFORE_FRICTION_EFFECTS: u64 = 0x2bab_7c9b_bc0c_1ecb;

#[test]
fn f32_drive_follows_f64_with_stribeck_and_load_friction() {
    let p = DriveParams {
        motion: Motion::Rotary,
        inertia: 0.1,
        viscous_pos: 0.05,
        viscous_neg: 0.05,
        kinetic_pos: 6.0,
        kinetic_neg: 6.0,
        breakaway_pos: 10.0,
        breakaway_neg: 10.0,
        position_force: PositionForce::Pendulum {
            stiffness: 40.0,
            center: 0.0,
        },
        stribeck_velocity: 0.05,
        load_friction: 0.1,
        ..DriveParams::default()
    };
    let mut a: Drive<f64> = Drive::new(&p, H, 0.0).expect("valid");
    let mut b: Drive<f32> = Drive::new(&p, H, 0.0).expect("valid");
    let (mut worst, mut slips) = (0.0f64, 0usize);
    for n in 0..20_000 {
        let u = 30.0 * (n as f64 * H * 0.5).sin();
        let before = a.mode();
        a.step(u).expect("f64 step");
        b.step(u as f32).expect("f32 step");
        slips += usize::from(before == Mode::Stopped && a.mode() != Mode::Stopped);
        worst = worst.max((a.x() - f64::from(b.x())).abs());
    }
    assert!(slips >= 2, "slips: {slips}");
    let range = 2.0; // rad, about
    assert!(worst < 1e-3 * range, "f32 vs f64 position: {worst}");
}

/// A 2 kg slider with kinetic 1 N, breakaway 1.5 N both ways and a bump of `amplitude` [N],
/// half-width 0.05 m, at 0.2 m.
fn bumpy(amplitude: f64) -> DriveParams {
    DriveParams {
        inertia: 2.0,
        kinetic_pos: 1.0,
        kinetic_neg: 1.0,
        breakaway_pos: 1.5,
        breakaway_neg: 1.5,
        local_friction: LocalFriction::Bump {
            center: 0.2,
            half_width: 0.05,
            amplitude,
        },
        ..DriveParams::default()
    }
}

/// The force [N] at which an axis resting at `x0` breaks away under a ramp `sign * n * 1e-6`
/// (after 100 steps held at 0, so that it breaks away from the kept resting state), and the
/// position it then moves from.
fn breakaway_force(p: &DriveParams, x0: f64, sign: f64) -> (f64, f64) {
    let mut d: Drive = Drive::new(p, H, x0).expect("valid");
    for _ in 0..100 {
        d.step(0.0).expect("step");
    }
    for n in 1..10_000_000u32 {
        let f = sign * f64::from(n) * 1e-6;
        d.step(f).expect("step");
        if d.mode() != Mode::Stopped {
            return (f, x0);
        }
        assert_eq!(d.x().to_bits(), x0.to_bits(), "a held axis stays put");
    }
    panic!("never broke away from {x0}");
}

#[test]
fn a_bump_raises_the_breakaway_level_where_the_axis_rests() {
    for amplitude in [0.8, -0.6] {
        let p = bumpy(amplitude);
        for sign in [1.0, -1.0] {
            // At the centre `breakaway + amplitude`; outside (and on the edge of the support,
            // where `b = 0`) only `breakaway`; half-way out `breakaway + amplitude * 9 / 16`.
            for (x0, level) in [
                (0.2, 1.5 + amplitude),
                (0.0, 1.5),
                (0.25, 1.5),
                (0.5, 1.5),
                (0.225, 1.5 + amplitude * 0.5625),
            ] {
                let (f, _) = breakaway_force(&p, x0, sign);
                assert!(
                    f.abs() > level - 1e-9 && f.abs() <= level + 1.01e-6,
                    "A = {amplitude}, x0 = {x0}: broke away at {f}, level {level}"
                );
            }
        }
    }
    // Exactly at the level it holds, one ulp above it slips (the guard is strict).
    let p = bumpy(0.8);
    let level: f64 = 1.5 + 0.8; // `breakaway + b(center)`, `b(center) = 0.8 * 1 * 1`
    for (f, holds) in [(level, true), (f64::from_bits(level.to_bits() + 1), false)] {
        let mut d: Drive = Drive::new(&p, H, 0.2).expect("valid");
        for _ in 0..10 {
            d.step(f).expect("step");
        }
        assert_eq!(d.mode() == Mode::Stopped, holds, "F = {f}");
    }
    // Without the bump the same axis needs 1.5 N at the centre.
    let flat = DriveParams {
        local_friction: LocalFriction::None,
        ..p
    };
    let (f, _) = breakaway_force(&flat, 0.2, 1.0);
    assert!(f > 1.5 - 1e-9 && f <= 1.5 + 1.01e-6, "{f}");
}

#[test]
fn a_slide_across_a_bump_loses_its_integral_and_decelerates_inside() {
    // Kinetic 0.5 N, no viscous, pushed by nothing: outside the bump the energy
    // `m v^2 / 2 + C x` is constant; across it falls by `A w 16 / 15`.
    let (amplitude, half_width) = (3.0, 0.1);
    let p = DriveParams {
        inertia: 2.0,
        kinetic_pos: 0.5,
        kinetic_neg: 0.5,
        breakaway_pos: 0.5,
        breakaway_neg: 0.5,
        local_friction: LocalFriction::Bump {
            center: 0.6,
            half_width,
            amplitude,
        },
        ..DriveParams::default()
    };
    let e = |d: &Drive| 0.5 * p.inertia * d.v() * d.v() + 0.5 * d.x();
    let mut d: Drive = Drive::new(&p, H, 0.0).expect("valid");
    d.set_state(0.0, 2.0).expect("state");
    let e0 = e(&d);
    let mut worst_outside = 0.0f64;
    let mut inside_steps = 0;
    while d.x() < 1.0 {
        let (x0, v0) = (d.x(), d.v());
        d.step(0.0).expect("step");
        assert_eq!(d.mode(), Mode::Positive, "stopped at {}", d.x());
        let a = (d.v() - v0) / H;
        let s = (0.5 * (x0 + d.x()) - 0.6) / half_width;
        if s.abs() < 0.9 {
            // Inside: decelerates by (C + b(x)) / m, more than the C / m outside.
            let b = amplitude * (1.0 - s * s).powi(2);
            assert!(
                (a + (0.5 + b) / p.inertia).abs() < 1e-2 * (0.5 + b),
                "x = {}: a = {a}, expected {}",
                d.x(),
                -(0.5 + b) / p.inertia
            );
            assert!(a < -0.25 - 1e-3);
            let o = d.output();
            let bx = {
                let s = (d.x() - 0.6) / half_width;
                amplitude * (1.0 - s * s) * (1.0 - s * s)
            };
            assert!((o.friction - (0.5 + bx)).abs() < 1e-12, "{}", o.friction);
            inside_steps += 1;
        } else if d.x() < 0.5 && x0 > 0.0 {
            worst_outside = worst_outside.max((e(&d) - e0).abs());
            assert!((a + 0.25).abs() < 1e-9, "outside: a = {a}");
        }
    }
    assert!(inside_steps > 50, "{inside_steps}");
    assert!(
        worst_outside < 1e-12,
        "energy drift before the bump: {worst_outside}"
    );
    let lost = e0 - e(&d);
    let integral = amplitude * half_width * 16.0 / 15.0; // 0.32 J
                                                         // RK4 meets the jumps of `b''` at the edges of the support (`b` is C1 only): its error
                                                         // there is O(h^3) per edge, 4e-8 J at h = 1 ms, 64 times less at h / 4.
    let err = (lost - integral).abs();
    assert!(
        err < 1e-6 * integral,
        "lost {lost} J, integral of b {integral} J"
    );
    let mut fine: Drive = Drive::new(&p, H / 4.0, 0.0).expect("valid");
    fine.set_state(0.0, 2.0).expect("state");
    while fine.x() < 1.0 {
        fine.step(0.0).expect("step");
    }
    let err_fine = ((e0 - e(&fine)) - integral).abs();
    assert!(err_fine < err / 20.0, "h: {err} J, h / 4: {err_fine} J");
    // The same slide without the bump loses nothing but C x.
    let flat = DriveParams {
        local_friction: LocalFriction::None,
        ..p
    };
    let mut d: Drive = Drive::new(&flat, H, 0.0).expect("valid");
    d.set_state(0.0, 2.0).expect("state");
    while d.x() < 1.0 {
        d.step(0.0).expect("step");
    }
    assert!((e(&d) - e0).abs() < 1e-12);
    // A negative slide across it (Negative mode) loses the same.
    let mut d: Drive = Drive::new(&p, H, 1.2).expect("valid");
    d.set_state(1.2, -2.0).expect("state");
    let en = |d: &Drive| 0.5 * p.inertia * d.v() * d.v() - 0.5 * d.x();
    let e0 = en(&d);
    while d.x() > 0.2 {
        d.step(0.0).expect("step");
    }
    assert!(((e0 - en(&d)) - integral).abs() < 1e-6 * integral);
}

#[test]
fn without_local_friction_the_trajectory_bits_are_those_of_the_model_without_it() {
    // The joint of `with_both_effects_off_...`: stick-slip with gravity, dead band, delay.
    let p = DriveParams {
        motion: Motion::Rotary,
        inertia: 0.12,
        viscous_pos: 0.3,
        viscous_neg: 0.35,
        kinetic_pos: 8.0,
        kinetic_neg: 9.0,
        breakaway_pos: 10.75,
        breakaway_neg: 12.0,
        offset: 0.5,
        position_force: PositionForce::Pendulum {
            stiffness: 40.3,
            center: 0.0,
        },
        deadband: 0.05,
        delay_steps: 3,
        ..DriveParams::default()
    };
    assert_eq!(p.local_friction, LocalFriction::None, "the default");
    let (h, events, stuck) = trajectory_hash(&p);
    assert!(events > 5 && stuck > 1000);
    // The bits of the model before the friction effects (commit 21144e4) and before the bump.
    assert_eq!(h, GOLDEN_BEFORE_FRICTION_EFFECTS, "got {h:#018x}");
    // A bump of amplitude 0 is off: the same bits.
    let zero = DriveParams {
        local_friction: LocalFriction::Bump {
            center: 0.1,
            half_width: 0.5,
            amplitude: 0.0,
        },
        ..p
    };
    assert_eq!(trajectory_hash(&zero).0, h);
    // A bump (or dip) on the travelled range changes them; one far away does not.
    for (center, amplitude, changes) in [(0.1, 1.0, true), (0.1, -2.0, true), (50.0, 1.0, false)] {
        let q = DriveParams {
            local_friction: LocalFriction::Bump {
                center,
                half_width: 0.5,
                amplitude,
            },
            ..p
        };
        assert_eq!(trajectory_hash(&q).0 != h, changes, "{center}, {amplitude}");
    }
}

#[test]
fn f32_drive_follows_f64_with_a_bump() {
    let p = DriveParams {
        motion: Motion::Rotary,
        inertia: 0.1,
        viscous_pos: 0.05,
        viscous_neg: 0.05,
        kinetic_pos: 6.0,
        kinetic_neg: 6.0,
        breakaway_pos: 10.0,
        breakaway_neg: 10.0,
        position_force: PositionForce::Pendulum {
            stiffness: 40.0,
            center: 0.0,
        },
        stribeck_velocity: 0.05,
        load_friction: 0.1,
        local_friction: LocalFriction::Bump {
            center: 0.3,
            half_width: 0.2,
            amplitude: 4.0,
        },
        ..DriveParams::default()
    };
    let mut a: Drive<f64> = Drive::new(&p, H, 0.0).expect("valid");
    let mut b: Drive<f32> = Drive::new(&p, H, 0.0).expect("valid");
    let (mut worst, mut inside) = (0.0f64, 0usize);
    for n in 0..20_000 {
        let u = 30.0 * (n as f64 * H * 0.5).sin();
        a.step(u).expect("f64 step");
        b.step(u as f32).expect("f32 step");
        inside += usize::from((a.x() - 0.3).abs() < 0.2);
        worst = worst.max((a.x() - f64::from(b.x())).abs());
    }
    assert!(inside > 1000, "steps on the bump: {inside}");
    assert!(worst < 1e-3 * 2.0, "f32 vs f64 position: {worst}");
}
