//! The drive model (`crane_model::Drive<f64>`) must reproduce the independent reference
//! (`host_tests::drive_reference`) bit for bit: position, velocity, mode, time, the step
//! report and `output()` after every step (accepted or rejected with the same error), for
//! random valid parameters (with and without stiction, Stribeck weakening, load friction and
//! a localised friction bump or dip, spring and pendulum, dead band, delay, end stops) and random inputs (holds, ramps, steps,
//! sines, noise, bad values).

use crane_ident::rng::Rng;
use crane_model::{
    Drive, DriveParams, DriveStepError, LocalFriction, Mode, Motion, PositionForce,
    MAX_DRIVE_DELAY_STEPS,
};
use host_tests::drive_reference::{
    DriveMode, RefBump, RefDrive, RefDriveError, RefDriveParams, RefPositionForce,
};
use proptest::prelude::*;

/// Steps per random case.
const STEPS: usize = 5000;
/// Random cases.
const CASES: u32 = 1024;

fn to_ref(p: &DriveParams) -> RefDriveParams {
    RefDriveParams {
        i: p.inertia,
        k: p.gain,
        dp: p.viscous_pos,
        dn: p.viscous_neg,
        cp: p.kinetic_pos,
        cn: p.kinetic_neg,
        bp: p.breakaway_pos,
        bn: p.breakaway_neg,
        b: p.offset,
        p: match p.position_force {
            PositionForce::None => RefPositionForce::None,
            PositionForce::Spring { stiffness, center } => RefPositionForce::Spring {
                k: stiffness,
                x0: center,
            },
            PositionForce::Pendulum { stiffness, center } => RefPositionForce::Pendulum {
                k: stiffness,
                x0: center,
            },
        },
        d: p.deadband,
        n: p.delay_steps,
        min: p.min,
        max: p.max,
        vs: p.stribeck_velocity,
        mu: p.load_friction,
        bump: match p.local_friction {
            LocalFriction::None => None,
            LocalFriction::Bump {
                center,
                half_width,
                amplitude,
            } => Some(RefBump {
                xc: center,
                w: half_width,
                a: amplitude,
            }),
        },
    }
}

fn ref_mode(m: Mode) -> DriveMode {
    match m {
        Mode::Negative => DriveMode::Negative,
        Mode::Stopped => DriveMode::Stopped,
        Mode::Positive => DriveMode::Positive,
    }
}

fn ref_error(e: DriveStepError) -> RefDriveError {
    match e {
        DriveStepError::InputNotFinite => RefDriveError::InputNotFinite,
        DriveStepError::ForceNotFinite => RefDriveError::ForceNotFinite,
        DriveStepError::NonFinite => RefDriveError::NonFinite,
    }
}

/// One random coefficient that is zero in about a quarter of the cases.
fn maybe_zero(hi: f64) -> impl Strategy<Value = f64> {
    prop_oneof![1 => Just(0.0), 3 => 0.0..hi]
}

fn params_strategy() -> impl Strategy<Value = DriveParams> {
    let friction = (
        maybe_zero(5.0),
        maybe_zero(5.0),
        maybe_zero(8.0),
        maybe_zero(8.0),
        // stiction excess over kinetic: none (equal) or up to +100 %
        prop_oneof![1 => Just((0.0, 0.0)), 2 => (0.0f64..1.0, 0.0f64..1.0)],
    );
    let position = prop_oneof![
        Just(PositionForce::None),
        (0.0f64..300.0, -0.3f64..0.3)
            .prop_map(|(stiffness, center)| PositionForce::Spring { stiffness, center }),
        (0.0f64..60.0, -1.0f64..1.0)
            .prop_map(|(stiffness, center)| PositionForce::Pendulum { stiffness, center }),
    ];
    // Stribeck velocity and load friction: each non-zero in half of the cases.
    let extra = (
        prop_oneof![1 => Just(0.0), 1 => 0.002f64..0.5],
        prop_oneof![1 => Just(0.0), 1 => 0.0f64..0.9],
    );
    // Localised friction in half of the cases: the centre as a fraction of the range the
    // axis starts in (so that it is crossed), the half-width, and the amplitude as a fraction
    // of the deepest dip allowed (down to `-min(kinetic)`, exactly that in some cases: a
    // level that reaches 0) or of 6 N above.
    let local = prop_oneof![
        1 => Just(None),
        1 => (
            0.0f64..1.0,
            0.005f64..0.3,
            prop_oneof![1 => Just(-1.0), 2 => -1.0f64..0.0, 4 => 0.0f64..1.0],
        )
            .prop_map(Some),
    ];
    let limits = prop_oneof![
        Just((f64::NEG_INFINITY, f64::INFINITY)),
        (0.01f64..0.5).prop_map(|b| (f64::NEG_INFINITY, b)),
        (0.01f64..0.5).prop_map(|a| (-a, f64::INFINITY)),
        (0.01f64..0.5, 0.01f64..0.5).prop_map(|(a, b)| (-a, b)),
    ];
    (
        (any::<bool>(), 0.02f64..5.0, 0.2f64..5.0, -3.0f64..3.0),
        friction,
        position,
        (
            maybe_zero(1.0),
            prop_oneof![Just(0usize), 0..=MAX_DRIVE_DELAY_STEPS],
        ),
        limits,
        (extra, local),
    )
        .prop_map(
            |(
                (rot, inertia, gain, offset),
                (vp, vn, cp, cn, (sp, sn)),
                pf,
                (d, delay),
                (lo, hi),
                ((vs, mu), local),
            )| {
                let local_friction = match local {
                    None => LocalFriction::None,
                    Some((at, half_width, frac)) => {
                        // The start range of `run`.
                        let a = if lo.is_finite() { lo } else { -0.5 };
                        let b = if hi.is_finite() { hi } else { 0.5 };
                        let amplitude = if frac < 0.0 {
                            -frac * -cp.min(cn)
                        } else {
                            6.0 * frac
                        };
                        LocalFriction::Bump {
                            center: a + (b - a) * at,
                            half_width,
                            amplitude,
                        }
                    }
                };
                DriveParams {
                    motion: if rot { Motion::Rotary } else { Motion::Linear },
                    inertia,
                    gain,
                    viscous_pos: vp,
                    viscous_neg: vn,
                    kinetic_pos: cp,
                    kinetic_neg: cn,
                    breakaway_pos: cp * (1.0 + sp),
                    breakaway_neg: cn * (1.0 + sn),
                    offset,
                    position_force: pf,
                    deadband: d,
                    delay_steps: delay,
                    min: lo,
                    max: hi,
                    stribeck_velocity: vs,
                    load_friction: mu,
                    local_friction,
                }
            },
        )
}

/// A piece of an input program.
#[derive(Clone, Copy, Debug)]
enum Piece {
    Hold(f64),
    Ramp(f64, f64),
    /// amplitude, frequency [Hz], phase, offset
    Sine(f64, f64, f64, f64),
    /// amplitude, seed
    Noise(f64, u64),
    /// A non-finite or overflowing value once, then a hold.
    Bad(u8, f64),
}

fn piece_strategy() -> impl Strategy<Value = (Piece, usize)> {
    let piece = prop_oneof![
        3 => (-15.0f64..15.0).prop_map(Piece::Hold),
        3 => (-15.0f64..15.0, -15.0f64..15.0).prop_map(|(a, b)| Piece::Ramp(a, b)),
        3 => (0.0f64..15.0, 0.05f64..20.0, 0.0f64..6.3, -5.0f64..5.0)
            .prop_map(|(a, f, p, o)| Piece::Sine(a, f, p, o)),
        2 => (0.0f64..10.0, any::<u64>()).prop_map(|(a, s)| Piece::Noise(a, s)),
        1 => (0u8..4, -5.0f64..5.0).prop_map(|(k, a)| Piece::Bad(k, a)),
    ];
    (piece, 20usize..1500)
}

/// The program's inputs, `STEPS` of them.
fn inputs(pieces: &[(Piece, usize)], h: f64) -> Vec<f64> {
    let mut u = Vec::with_capacity(STEPS);
    'outer: loop {
        for &(p, len) in pieces {
            let mut rng = Rng::new(0);
            for j in 0..len {
                if u.len() == STEPS {
                    break 'outer;
                }
                let t = j as f64 * h;
                let frac = j as f64 / len as f64;
                let v = match p {
                    Piece::Hold(a) => a,
                    Piece::Ramp(a, b) => a + (b - a) * frac,
                    Piece::Sine(a, f, ph, o) => {
                        o + a * (2.0 * std::f64::consts::PI * f * t + ph).sin()
                    }
                    Piece::Noise(a, seed) => {
                        if j == 0 {
                            rng = Rng::new(seed);
                        }
                        a * rng.range(-1.0, 1.0)
                    }
                    Piece::Bad(k, a) if j == 0 => match k {
                        0 => f64::NAN,
                        1 => f64::INFINITY,
                        2 => f64::NEG_INFINITY,
                        _ => 1e308 * a.signum(),
                    },
                    Piece::Bad(_, a) => a,
                };
                u.push(v);
            }
        }
    }
    u
}

/// Runs model and reference side by side; panics (proptest shrinks) at the first difference.
fn run(
    p: &DriveParams,
    h: f64,
    x0_frac: f64,
    pieces: &[(Piece, usize)],
    reset: Option<(usize, f64, f64)>,
) {
    let lo = if p.min.is_finite() { p.min } else { -0.5 };
    let hi = if p.max.is_finite() { p.max } else { 0.5 };
    let x0 = (lo + (hi - lo) * x0_frac).clamp(p.min, p.max);
    let mut m: Drive = Drive::new(p, h, x0).expect("valid parameters");
    let mut r = RefDrive::new(to_ref(p), h, x0).expect("valid start");
    let u = inputs(pieces, h);
    for (n, &un) in u.iter().enumerate() {
        if let Some((at, xf, v)) = reset {
            if at == n {
                let x = lo + (hi - lo) * xf;
                let a = m.set_state(x, v).is_ok();
                let b = r.set_state(x, v);
                assert_eq!(a, b, "set_state({x}, {v}) accepted differently");
            }
        }
        let a = m.step(un);
        let b = r.step(un);
        match (a, b) {
            (Ok(ra), Ok(rb)) => {
                assert_eq!(u32::from(ra.events), rb.events, "events at step {n}");
                assert_eq!(
                    u32::from(ra.late_resets),
                    rb.late_resets,
                    "late resets at step {n}"
                );
            }
            (Err(ea), Err(eb)) => assert_eq!(ref_error(ea), eb, "error at step {n}"),
            (a, b) => panic!("step {n} (u = {un}): model {a:?}, reference {b:?}"),
        }
        assert_eq!(
            m.x().to_bits(),
            r.x.to_bits(),
            "x at step {n}: {} vs {}",
            m.x(),
            r.x
        );
        assert_eq!(
            m.v().to_bits(),
            r.v.to_bits(),
            "v at step {n}: {} vs {}",
            m.v(),
            r.v
        );
        assert_eq!(ref_mode(m.mode()), r.mode, "mode at step {n}");
        assert_eq!(m.time().to_bits(), r.time().to_bits(), "time at step {n}");
        let o = m.output();
        let [ra, rf, rp, rapp] = r.output();
        assert_eq!(
            o.acceleration.to_bits(),
            ra.to_bits(),
            "acceleration at step {n}"
        );
        assert_eq!(o.friction.to_bits(), rf.to_bits(), "friction at step {n}");
        assert_eq!(
            o.position_force.to_bits(),
            rp.to_bits(),
            "position force at step {n}"
        );
        assert_eq!(
            o.applied.to_bits(),
            rapp.to_bits(),
            "applied force at step {n}"
        );
        assert!(
            m.x() >= p.min && m.x() <= p.max,
            "x = {} outside the stops",
            m.x()
        );
        assert!(m.x().is_finite() && m.v().is_finite());
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: CASES, ..ProptestConfig::default() })]

    #[test]
    fn drive_matches_reference_bit_for_bit(
        p in params_strategy(),
        h in prop_oneof![Just(1e-3), 1e-4f64..5e-3],
        x0 in prop_oneof![Just(0.0), Just(1.0), 0.0f64..1.0],
        pieces in prop::collection::vec(piece_strategy(), 1..8),
        reset in prop::option::of((0usize..STEPS, 0.0f64..1.0, -2.0f64..2.0)),
    ) {
        run(&p, h, x0, &pieces, reset);
    }
}

/// The random cases exercise what they claim: over fixed seeds of the same generators, the
/// drive sticks, slips, reverses through `Stopped`, hits end stops and rejects bad inputs,
/// and the Stribeck and load terms are on in a good share of the cases (the Stribeck one with
/// stiction, on steps that move slower than `2 vs`, where its weakening is not negligible), and
/// so is a bump that the axis crosses and rests on.
#[test]
fn random_programs_cover_sticking_slipping_stops_and_rejections() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::TestRunner;
    let mut runner = TestRunner::deterministic();
    let (mut events, mut stuck_steps, mut at_stop, mut rejected, mut stiction) =
        (0u64, 0u64, 0u64, 0u64, 0u64);
    let (mut stribeck, mut stribeck_slow_steps, mut load, mut loaded_steps) =
        (0u64, 0u64, 0u64, 0u64);
    let (mut bumps, mut dips, mut in_bump_moving, mut in_bump_stuck, mut crossings) =
        (0u64, 0u64, 0u64, 0u64, 0u64);
    for _ in 0..64 {
        let p = params_strategy()
            .new_tree(&mut runner)
            .expect("tree")
            .current();
        let pieces = prop::collection::vec(piece_strategy(), 1..8)
            .new_tree(&mut runner)
            .expect("tree")
            .current();
        if p.breakaway_pos > p.kinetic_pos {
            stiction += 1;
        }
        let weakens = p.stribeck_velocity > 0.0
            && (p.breakaway_pos > p.kinetic_pos || p.breakaway_neg > p.kinetic_neg);
        stribeck += u64::from(weakens);
        load += u64::from(p.load_friction > 0.0);
        let inside = |x: f64| match p.local_friction {
            LocalFriction::Bump {
                center, half_width, ..
            } => (x - center).abs() < half_width,
            LocalFriction::None => false,
        };
        if let LocalFriction::Bump { amplitude, .. } = p.local_friction {
            bumps += 1;
            dips += u64::from(amplitude < 0.0);
        }
        let mut m: Drive = Drive::new(&p, 1e-3, 0.0f64.clamp(p.min, p.max)).expect("valid");
        let mut was_inside = inside(m.x());
        for u in inputs(&pieces, 1e-3) {
            match m.step(u) {
                Ok(r) => events += u64::from(r.events),
                Err(_) => rejected += 1,
            }
            if m.mode() == Mode::Stopped {
                stuck_steps += 1;
            }
            if m.x() == p.min || m.x() == p.max {
                at_stop += 1;
            }
            let moving = m.mode() != Mode::Stopped;
            if weakens && moving && m.v().abs() < 2.0 * p.stribeck_velocity {
                stribeck_slow_steps += 1;
            }
            if p.load_friction > 0.0 && m.output().applied != p.offset {
                loaded_steps += 1;
            }
            let now_inside = inside(m.x());
            if now_inside {
                if moving {
                    in_bump_moving += 1;
                } else {
                    in_bump_stuck += 1;
                }
            }
            crossings += u64::from(now_inside != was_inside);
            was_inside = now_inside;
        }
    }
    eprintln!("events {events}, stuck steps {stuck_steps}, at a stop {at_stop}, rejected {rejected}, stiction cases {stiction}");
    eprintln!("Stribeck cases with stiction {stribeck} (moving steps below 2 vs: {stribeck_slow_steps}), load-friction cases {load} (steps with a drive effort: {loaded_steps})");
    assert!(events > 100, "located events: {events}");
    assert!(stuck_steps > 1000, "stuck steps: {stuck_steps}");
    assert!(at_stop > 100, "steps at an end stop: {at_stop}");
    assert!(rejected > 0, "rejected steps: {rejected}");
    assert!(stiction > 10, "cases with stiction: {stiction}");
    assert!(stribeck > 10, "Stribeck cases with stiction: {stribeck}");
    assert!(
        stribeck_slow_steps > 1000,
        "moving steps below 2 vs: {stribeck_slow_steps}"
    );
    eprintln!("bump cases {bumps} (dips {dips}): steps inside moving {in_bump_moving}, stuck {in_bump_stuck}, entries and exits {crossings}");
    assert!(load > 16, "load-friction cases: {load}");
    assert!(bumps > 16 && dips > 4, "bump cases: {bumps}, dips {dips}");
    assert!(
        in_bump_moving > 10_000,
        "moving steps in a bump: {in_bump_moving}"
    );
    assert!(
        in_bump_stuck > 1000,
        "stuck steps in a bump: {in_bump_stuck}"
    );
    assert!(crossings > 30, "bump entries and exits: {crossings}");
    assert!(loaded_steps > 10_000, "loaded steps: {loaded_steps}");
}
