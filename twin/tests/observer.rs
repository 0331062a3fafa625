//! Host tests of the twin: observer convergence (f64 and f32), the disturbance estimate, the
//! residual as a "model is wrong here" signal, rejection of non-finite inputs and
//! measurements, the embedded-hal board against the direct plant, the H-bridge driver and the
//! feedforward.
#![allow(clippy::needless_range_loop)]

use core::f64::consts::FRAC_PI_2;
use crane_model::{Mode, Params, Real, State};
use crane_twin::board::SimBus;
use crane_twin::hal::{HBridge, MotorDrive};
use crane_twin::logic::control::{Controller, Io, LoopConfig, Trajectory, DEMO};
use crane_twin::logic::feedforward::{saturate, voltages, Reference};
use crane_twin::logic::io::{pwm_command, pwm_volts, Channel, EncoderScale, PWM_MAX};
use crane_twin::logic::observer::{Gains, Observer, Rejected};
use crane_twin::logic::plant::{demo_plant, rig_params, run_demo, run_loop, SimPlant};

const T: f64 = 2e-3;

/// Per period: estimation error of positions and of velocities.
type Errors = Vec<([f64; 5], [f64; 5])>;

fn hanging(x: f64, y: f64, l: f64) -> State<f64> {
    State {
        q: [x, y, l, FRAC_PI_2, 0.0],
        qd: [0.0; 5],
    }
}

/// Open-loop run: plant and observer under the same applied voltages `u(k)`; returns the
/// per-period estimation errors (position, velocity) of each channel.
fn open_loop<R: Real>(
    plant_params: &Params,
    plant_init: State<f64>,
    twin_init: State<f64>,
    gains: &Gains,
    periods: u32,
    u: impl Fn(u32) -> [f64; 3],
) -> (Observer<R>, Errors) {
    let mut plant = SimPlant::new(plant_params, plant_init, T, 2).expect("plant");
    let mut obs = Observer::<R>::new(&Params::default(), T, twin_init, gains).expect("observer");
    let scale = EncoderScale::RIG;
    let mut applied = [0.0; 3];
    let mut errs = Vec::new();
    for k in 0..periods {
        let c = plant.counts();
        let y = Channel::ALL.map(|ch| R::from_f64(scale.position(ch, c[ch.index()])));
        obs.update(applied.map(R::from_f64), y).expect("update");
        let (e, t) = (obs.state().to_f64(), plant.state());
        let mut dq = [0.0; 5];
        let mut dv = [0.0; 5];
        for i in 0..5 {
            dq[i] = e.q[i] - t.q[i];
            dv[i] = e.qd[i] - t.qd[i];
        }
        errs.push((dq, dv));
        applied = Io::write(&mut plant, u(k)).expect("write");
        plant.advance();
    }
    (obs, errs)
}

fn max_abs(errs: &[([f64; 5], [f64; 5])], from: usize, vel: bool, i: usize) -> f64 {
    errs[from..]
        .iter()
        .map(|(q, v)| if vel { v[i].abs() } else { q[i].abs() })
        .fold(0.0, f64::max)
}

fn drive_program(k: u32) -> [f64; 3] {
    let t = f64::from(k) * T;
    // Moves, reversals and rests on every axis.
    let sq = |p: f64| if (t / p).fract() < 0.5 { 1.0 } else { -1.0 };
    [
        5.0 * sq(1.2),
        -4.0 * sq(0.9),
        if t < 1.0 { -4.0 } else { 3.0 },
    ]
}

fn converges<R: Real>() {
    let plant0 = hanging(0.25, 0.30, 0.30);
    let mut twin0 = plant0;
    twin0.q[0] += 0.01;
    twin0.q[1] -= 0.008;
    twin0.q[2] += 0.005;
    twin0.q[3] += 0.04;
    twin0.q[4] -= 0.03;
    twin0.qd[0] = 0.05;
    let (obs, errs) = open_loop::<R>(
        &rig_params(),
        plant0,
        twin0,
        &Gains::default(),
        1000,
        drive_program,
    );
    let res = EncoderScale::RIG.res;
    // From 0.4 s on (20 time constants): within a few encoder counts, velocities within
    // a few mm/s (rad/s for the swing).
    for i in 0..5 {
        let q = max_abs(&errs, 200, false, i);
        assert!(
            q < 4.0 * res[i],
            "channel {i}: position error {q} >= 4 counts"
        );
    }
    for i in 0..3 {
        let v = max_abs(&errs, 200, true, i);
        assert!(v < 0.01, "axis {i}: velocity error {v} m/s");
    }
    for i in 3..5 {
        let v = max_abs(&errs, 200, true, i);
        assert!(v < 0.08, "swing {i}: velocity error {v} rad/s");
    }
    assert_eq!(obs.counters().twin_errors, 0);
    assert!(obs.state().is_finite());
}

#[test]
fn observer_converges_from_a_wrong_state_f64() {
    converges::<f64>();
}

#[test]
fn observer_converges_from_a_wrong_state_f32() {
    converges::<f32>();
}

/// Without correction the nominal twin drifts away from the perturbed plant: the observer
/// is what keeps it on the rig.
#[test]
fn uncorrected_twin_drifts() {
    let plant0 = hanging(0.25, 0.30, 0.30);
    let none = Gains {
        alpha: 0.0,
        beta: 0.0,
        gamma: 0.0,
        swing_alpha: 0.0,
        swing_beta: 0.0,
        ..Gains::default()
    };
    let (_, errs) = open_loop::<f64>(&rig_params(), plant0, plant0, &none, 1000, drive_program);
    let worst = (0..3)
        .map(|i| max_abs(&errs, 0, false, i))
        .fold(0.0, f64::max);
    // 20 times the corrected twin's bound (4 counts, 0.25 mm).
    assert!(worst > 0.005, "open-loop twin error only {worst} m");
}

/// The disturbance estimate recovers the friction the model gets wrong: the plant's X dry
/// friction is 40 % higher and its rope dry friction 1.5 N higher; moving steadily, the
/// estimate approaches minus the difference.
#[test]
fn disturbance_estimate_finds_the_friction_error() {
    let nominal = Params::default();
    let mut p = nominal;
    p.x.dry_pos = p.x.dry_pos.map(|c| 1.4 * c);
    p.x.dry_neg = p.x.dry_neg.map(|c| 1.4 * c);
    p.rope.dry_pos[0] += 1.5;
    p.rope.dry_neg[0] += 1.5;
    let plant0 = hanging(0.05, 0.30, 0.20);
    let (obs, _) = open_loop::<f64>(&p, plant0, plant0, &Gains::default(), 600, |_| {
        [2.0, 0.0, 4.0]
    });
    let s = obs.state();
    assert_eq!(obs.modes()[0], Mode::Positive);
    assert_eq!(obs.modes()[2], Mode::Positive);
    let c = crane_model::friction::dry(&nominal.x.dry_pos, s.q[0]);
    let d = obs.disturbance();
    let want_x = -0.4 * c;
    assert!(
        (d[0] - want_x).abs() < 0.25 * want_x.abs(),
        "X: estimate {} N, friction error {want_x} N",
        d[0]
    );
    assert!(
        (d[2] + 1.5).abs() < 0.3,
        "rope: estimate {} N, error -1.5 N",
        d[2]
    );
    assert!(d[1].abs() < 0.1, "Y (right model, at rest): {} N", d[1]);
}

/// With the disturbance estimate switched off, the residual itself flags the axis whose
/// model is grossly wrong: same voltages on X and Y, but the plant's X is jammed (dry
/// friction x20) while the model lets it move; Y's residual stays at the quantisation floor.
/// (Small friction errors stay far below one encoder count per period: the disturbance
/// estimate is the sensitive signal for those, see above.)
#[test]
fn residual_flags_the_axis_whose_model_is_wrong() {
    let mut p = Params::default();
    p.x.dry_pos = p.x.dry_pos.map(|c| 20.0 * c);
    p.x.dry_neg = p.x.dry_neg.map(|c| 20.0 * c);
    let plant0 = hanging(0.10, 0.10, 0.30);
    let gains = Gains {
        gamma: 0.0,
        ..Gains::default()
    };
    let (obs, _) = open_loop::<f64>(&p, plant0, plant0, &gains, 800, |k| {
        let s = if (k / 150) % 2 == 0 { 3.0 } else { -3.0 };
        [s, s, 0.0]
    });
    let ms = obs.residual_mean_square();
    let floor = EncoderScale::RIG.res[1].powi(2) / 12.0;
    assert!(ms[1] < 3.0 * floor, "Y {} vs floor {floor}", ms[1]);
    assert!(ms[0] > 10.0 * ms[1], "X {} vs Y {}", ms[0], ms[1]);
}

#[test]
fn non_finite_input_and_measurement_are_rejected() {
    let init = hanging(0.2, 0.3, 0.3);
    let mut obs = Observer::<f64>::new(&Params::default(), T, init, &Gains::default()).unwrap();
    let y = init.q;
    obs.update([1.0, 0.0, 0.0], y).unwrap();
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let before = obs.state();
        assert_eq!(
            obs.update([1.0, bad, 0.0], y),
            Err(Rejected::InputNotFinite { axis: 1 })
        );
        assert_eq!(obs.state(), before, "a rejected input changes nothing");
        let mut ybad = y;
        ybad[3] = bad;
        assert_eq!(
            obs.update([1.0, 0.0, 0.0], ybad),
            Err(Rejected::MeasurementNotFinite { channel: 3 })
        );
        assert!(obs.state().is_finite());
    }
    // Huge but finite measurements are clamped into the limits and the domain.
    let wild = [1e6, -1e6, 1e6, 1e6, -1e6];
    let _ = obs.update([12.0, -12.0, 12.0], wild);
    assert!(obs.state().is_finite());
    obs.update([0.0; 3], y).unwrap();
    assert!(obs.state().is_finite());
    let c = obs.counters();
    assert_eq!((c.bad_inputs, c.bad_measurements), (3, 3));
    // The controller never commands a non-finite voltage, whatever the reference.
    let mut ctrl =
        Controller::<f64>::new(&Params::default(), init, &LoopConfig::default()).unwrap();
    let r = Reference {
        pos: [f64::NAN, f64::INFINITY, 0.3],
        vel: [f64::NAN; 3],
        acc: [f64::NEG_INFINITY, 0.0, f64::NAN],
    };
    let p = ctrl.period(y, &r);
    assert!(p.command.iter().all(|u| u.is_finite() && u.abs() <= 12.0));
    ctrl.applied([f64::NAN, 1.0, 2.0]);
    let p = ctrl.period(y, &DEMO.at(0.0));
    assert!(p.update.is_ok(), "a NaN applied voltage is stored as 0 V");
    assert_eq!(saturate(f64::NAN), 0.0);
    assert_eq!(saturate(f64::INFINITY), 12.0);
}

/// A failing encoder on the board: the observer runs open loop for those periods and the
/// loop carries on; when the encoder comes back the twin is corrected again.
#[test]
fn encoder_fault_on_the_board_is_survived() {
    let bus = SimBus::new(demo_plant().unwrap());
    let mut io = bus.io();
    let cfg = LoopConfig::default();
    let init = hanging(0.10, 0.15, 0.30);
    let mut ctrl = Controller::<f64>::new(&Params::default(), init, &cfg).unwrap();
    let mut rejected = 0;
    for k in 0..1500u32 {
        bus.set_encoder_fault(3, (500..600).contains(&k));
        let p = ctrl.run_period(&mut io, &DEMO.at(f64::from(k) * cfg.period));
        if p.update == Err(Rejected::MeasurementNotFinite { channel: 3 }) {
            rejected += 1;
        }
        assert!(ctrl.observer().state().is_finite());
        assert!(p.command.iter().all(|u| u.is_finite()));
        io.wait();
    }
    assert_eq!(rejected, 100);
    let truth = io.truth().unwrap();
    let est = ctrl.observer().state();
    assert!((est.q[0] - truth.q[0]).abs() < 4.0 * EncoderScale::RIG.res[0]);
}

/// The embedded-hal board (H-bridges, direction pins, encoders) gives the same bits as the
/// plant driven directly: the QEMU run and the host cross-check are comparable.
#[test]
fn board_matches_direct_plant_bit_for_bit() {
    let mut a = String::new();
    let mut b = String::new();
    let bus = SimBus::new(demo_plant().unwrap());
    let sa = run_demo::<f64, _, _>(&mut bus.io(), "f64", &mut a)
        .unwrap()
        .unwrap();
    let mut plant = demo_plant().unwrap();
    let sb = run_demo::<f64, _, _>(&mut plant, "f64", &mut b)
        .unwrap()
        .unwrap();
    assert_eq!(a, b);
    assert_eq!(sa.hash, sb.hash);
}

/// The demonstration loop tracks the reference and the twin follows the (perturbed) plant,
/// in f64 and in f32; the f32 twin stays within a few encoder counts of the f64 one.
#[test]
fn closed_loop_tracks_and_estimates() {
    let mut sink = String::new();
    let mut p64 = demo_plant().unwrap();
    let s64 = run_demo::<f64, _, _>(&mut p64, "f64", &mut sink)
        .unwrap()
        .unwrap();
    let mut p32 = demo_plant().unwrap();
    let s32 = run_demo::<f32, _, _>(&mut p32, "f32", &mut sink)
        .unwrap()
        .unwrap();
    let res = EncoderScale::RIG.res;
    for s in [&s64, &s32] {
        for i in 0..3 {
            assert!(s.track_err_max[i] < 0.01, "{s:?}");
            assert!(s.pos_err_rms[i] < res[i], "{s:?}");
            assert!(s.vel_err_rms[i] < 2e-3, "{s:?}");
        }
        for i in 3..5 {
            assert!(s.pos_err_rms[i] < res[i], "{s:?}");
        }
        assert_eq!(s.counters.twin_errors + s.counters.correction_errors, 0);
    }
    // Final plant positions of the two runs (f32 and f64 controllers).
    let (a, b) = (p64.state(), p32.state());
    for i in 0..3 {
        assert!(
            (a.q[i] - b.q[i]).abs() < 4.0 * res[i],
            "axis {i}: {} vs {}",
            a.q[i],
            b.q[i]
        );
    }
}

/// The gains put every pole of the correction at `theta`: characteristic polynomial of
/// `(I - K H) F` for the triple integrator is `(z - theta)^3`.
#[test]
fn gains_place_all_poles_at_theta() {
    for theta in [0.8, 0.9, 0.95] {
        let g = Gains::fading_memory(theta, theta);
        let t = T;
        let k = [g.alpha, g.beta / t, 2.0 * g.gamma / (t * t)];
        let f = [[1.0, t, t * t / 2.0], [0.0, 1.0, t], [0.0, 0.0, 1.0]];
        let mut a = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                let ikh = |r: usize, c: usize| {
                    let id = if r == c { 1.0 } else { 0.0 };
                    id - if c == 0 { k[r] } else { 0.0 }
                };
                a[i][j] = (0..3).map(|m| ikh(i, m) * f[m][j]).sum();
            }
        }
        let tr = a[0][0] + a[1][1] + a[2][2];
        let m2: f64 = [(0, 1), (0, 2), (1, 2)]
            .iter()
            .map(|&(i, j)| a[i][i] * a[j][j] - a[i][j] * a[j][i])
            .sum();
        let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
        assert!((tr - 3.0 * theta).abs() < 1e-9);
        assert!((m2 - 3.0 * theta * theta).abs() < 1e-9);
        assert!((det - theta * theta * theta).abs() < 1e-9);
        // Swing: alpha-beta, (z - theta)^2.
        let (sa, sb) = (g.swing_alpha, g.swing_beta);
        let b = [[1.0 - sa, (1.0 - sa) * t], [-sb / t, 1.0 - sb]];
        assert!((b[0][0] + b[1][1] - 2.0 * theta).abs() < 1e-12);
        assert!((b[0][0] * b[1][1] - b[0][1] * b[1][0] - theta * theta).abs() < 1e-12);
    }
}

/// Feedforward at a hanging payload: moving, `K u = Dbar v + Cbar(p)` (+ inertia); from
/// standstill the breakaway threshold with its margin; at rest nothing on X/Y and the
/// payload's weight on the rope.
#[test]
fn feedforward_has_friction_breakaway_and_gravity() {
    let p = Params::default();
    let crane =
        crane_model::Crane::<f64>::new(&p, crane_model::Config::default(), hanging(0.2, 0.3, 0.3))
            .unwrap();
    let c = crane.coeffs();
    let est = crane.state();
    let moving = [Mode::Positive, Mode::Negative, Mode::Stopped];
    let r = Reference {
        pos: [0.2, 0.3, 0.3],
        vel: [0.05, -0.04, 0.0],
        acc: [0.0; 3],
    };
    let u = voltages(c, &est, &moving, &r, &[0.0; 3], 0.05);
    let fx = p.x.viscous_pos * 0.05 + crane_model::friction::dry(&p.x.dry_pos, 0.2);
    let fy = p.y.viscous_neg * -0.04 - crane_model::friction::dry(&p.y.dry_neg, 0.3);
    assert!(
        (u[0] * p.x.gain - fx).abs() < 1e-9,
        "{} vs {fx}",
        u[0] * p.x.gain
    );
    assert!((u[1] * p.y.gain - fy).abs() < 1e-9);
    let w = p.payload_mass * p.gravity;
    assert!(
        (u[2] * p.rope.gain + w).abs() < 1e-9,
        "rope holds the weight"
    );
    // From standstill: breakaway (+5 %).
    let stopped = [Mode::Stopped; 3];
    let u = voltages(c, &est, &stopped, &r, &[0.0; 3], 0.05);
    let bx = p.x.viscous_pos * 0.05 + 1.05 * crane_model::friction::dry(&p.x.dry_pos, 0.2);
    assert!((u[0] * p.x.gain - bx).abs() < 1e-9);
    // Acceleration from rest, v = 0: breakaway in the direction of the acceleration plus the
    // reduced inertia.
    let r = Reference {
        pos: [0.2, 0.3, 0.3],
        vel: [0.0; 3],
        acc: [0.5, 0.0, 0.0],
    };
    let u = voltages(c, &est, &stopped, &r, &[0.0; 3], 0.0);
    let m_red = c.m00 - p.payload_mass; // hanging straight down: the payload swings behind
    let want = m_red * 0.5 + crane_model::friction::dry(&p.x.dry_pos, 0.2);
    assert!(
        (u[0] * p.x.gain - want).abs() < 1e-9,
        "{} vs {want}",
        u[0] * p.x.gain
    );
    // Saturation.
    let r = Reference {
        pos: [0.2, 0.3, 0.3],
        vel: [5.0, -5.0, 0.0],
        acc: [0.0; 3],
    };
    let u = voltages(c, &est, &moving, &r, &[0.0; 3], 0.05);
    assert_eq!((u[0], u[1]), (12.0, -12.0));
}

/// H-bridge driver on recording pins: direction pins, duty, the applied voltage.
#[test]
fn hbridge_sets_pins_and_duty() {
    use core::cell::RefCell;
    use core::convert::Infallible;
    #[derive(Default)]
    struct Log {
        duty: u16,
        in1: bool,
        in2: bool,
        both_high_seen: bool,
    }
    struct P<'a>(&'a RefCell<Log>);
    struct Pin<'a>(&'a RefCell<Log>, bool);
    impl embedded_hal::pwm::ErrorType for P<'_> {
        type Error = Infallible;
    }
    impl embedded_hal::pwm::SetDutyCycle for P<'_> {
        fn max_duty_cycle(&self) -> u16 {
            1000
        }
        fn set_duty_cycle(&mut self, d: u16) -> Result<(), Infallible> {
            self.0.borrow_mut().duty = d;
            Ok(())
        }
    }
    impl embedded_hal::digital::ErrorType for Pin<'_> {
        type Error = Infallible;
    }
    impl embedded_hal::digital::OutputPin for Pin<'_> {
        fn set_low(&mut self) -> Result<(), Infallible> {
            let mut l = self.0.borrow_mut();
            if self.1 {
                l.in2 = false
            } else {
                l.in1 = false
            }
            Ok(())
        }
        fn set_high(&mut self) -> Result<(), Infallible> {
            let mut l = self.0.borrow_mut();
            if self.1 {
                l.in2 = true
            } else {
                l.in1 = true
            }
            l.both_high_seen |= l.in1 && l.in2;
            Ok(())
        }
    }
    let log = RefCell::new(Log::default());
    let mut hb = HBridge::new(P(&log), Pin(&log, false), Pin(&log, true));
    let v = hb.set_voltage(6.0).unwrap();
    assert_eq!(v, 6.0);
    assert_eq!(
        (log.borrow().duty, log.borrow().in1, log.borrow().in2),
        (500, true, false)
    );
    let v = hb.set_voltage(-3.0).unwrap();
    assert_eq!(v, -3.0);
    assert_eq!(
        (log.borrow().duty, log.borrow().in1, log.borrow().in2),
        (250, false, true)
    );
    let v = hb.set_voltage(100.0).unwrap();
    assert_eq!((v, log.borrow().duty), (12.0, 1000));
    let v = hb.set_voltage(f64::NAN).unwrap();
    assert_eq!(
        (v, log.borrow().duty, log.borrow().in1, log.borrow().in2),
        (0.0, 0, false, false)
    );
    assert!(!log.borrow().both_high_seen, "no shoot-through state");
    // The quantisation the loop predicts with.
    let q = pwm_volts(pwm_command(1.0));
    assert!((q - 1.0).abs() <= 0.5 * 12.0 / f64::from(PWM_MAX));
}

/// The reference is continuous in position and velocity and starts and ends at rest.
#[test]
fn demo_reference_is_smooth() {
    let tr: &Trajectory<'_> = &DEMO;
    let mut prev = tr.at::<f64>(0.0);
    for k in 1..4000 {
        let r = tr.at::<f64>(f64::from(k) * T);
        for i in 0..3 {
            assert!((r.pos[i] - prev.pos[i]).abs() < 0.5 * T, "position jump");
            assert!((r.vel[i] - prev.vel[i]).abs() < 2.0 * T, "velocity jump");
        }
        prev = r;
    }
    assert_eq!(prev.vel, [0.0; 3]);
    let _ = run_loop::<f64, SimPlant, String>;
}

/// Issue 11: the encoder scale takes a typed channel (no index out of `[_; 5]`) and saturates
/// its count instead of overflowing `c - 1` for far positions; the counters are `u64`.
#[test]
fn encoder_counts_saturate_and_counters_do_not_wrap() {
    let s = EncoderScale::RIG;
    for ch in Channel::ALL {
        assert_eq!(s.counts(ch, 1e300), i32::MAX);
        assert_eq!(s.counts(ch, -1e300), i32::MIN);
        assert_eq!(s.counts(ch, f64::NAN), 0);
        // floor of the cell, both sides of the zero
        let z = s.position(ch, 0) - 0.5 * s.res[ch.index()];
        assert_eq!(s.counts(ch, z + 0.25 * s.res[ch.index()]), 0);
        assert_eq!(s.counts(ch, z - 0.25 * s.res[ch.index()]), -1);
    }
    // 2^32 periods of 2 ms are 99.4 days: the counters hold more
    let c = crane_twin::logic::observer::Counters {
        updates: u64::from(u32::MAX) + 1,
        ..Default::default()
    };
    assert!(c.updates > u64::from(u32::MAX));
}
