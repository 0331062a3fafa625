//! Time per step of the single-axis drive (`crane_model::Drive`).
//!
//! The diagnosis simulates thousands of candidate parameter sets over logs of about 2,000
//! samples at about 15 steps per sample, so the figure that matters is the cost of a whole
//! such run: each bench below is one 30,000-step run (divide by 30,000 for ns/step).
//! - `stick_slip`: a joint with gravity (pendulum force) and stiction under a slow torque
//!   ramp and a sine: sticking, slips, located stops, reversals.
//! - `sliding`: always moving (spring, viscous and kinetic friction), no event.
//! - `stuck`: at rest below breakaway the whole run.
//! - `sliding_f32`: `sliding` in f32.
//! - `sliding_stribeck_load`: `sliding` with Stribeck weakening and load friction (one `exp`
//!   per evaluation, the step's levels once per step): the extra cost of the two effects
//!   (the same run, no event; `vs` large enough that no `exp` takes a shortcut).
//! - `stick_slip_stribeck_load`: `stick_slip` with both effects.

use crane_model::{Drive, DriveParams, Motion, PositionForce};
use criterion::{black_box, criterion_group, criterion_main, Criterion};
use std::time::Duration;

const H: f64 = 1e-3 / 15.0;
const STEPS: usize = 30_000;

fn joint() -> DriveParams {
    DriveParams {
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
        deadband: 0.05,
        delay_steps: 3,
        ..DriveParams::default()
    }
}

fn inputs(f: impl Fn(f64) -> f64) -> Vec<f64> {
    (0..STEPS).map(|n| f(n as f64 * H)).collect()
}

fn run<R: crane_model::Real>(d: &Drive<R>, u: &[R]) -> R {
    let mut d = d.clone();
    for &v in u {
        let _ = d.step(black_box(v));
    }
    d.x()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("drive_30000_steps");
    g.sample_size(30)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));

    let p = joint();
    // 2 s: a 15 N m/s ramp with a 3 N m, 5 Hz ripple: several slips and sticks.
    let ramp = inputs(|t| 15.0 * t + 3.0 * (2.0 * std::f64::consts::PI * 5.0 * t).sin());
    let d: Drive = Drive::new(&p, H, 0.0).expect("valid");
    g.bench_function("stick_slip", |b| b.iter(|| run(&d, &ramp)));

    let slide = DriveParams {
        breakaway_pos: 8.0,
        breakaway_neg: 9.0,
        position_force: PositionForce::Spring {
            stiffness: 5.0,
            center: 0.0,
        },
        deadband: 0.0,
        delay_steps: 0,
        ..p
    };
    let push = inputs(|_| 30.0);
    let mut d: Drive = Drive::new(&slide, H, 0.0).expect("valid");
    d.set_state(0.0, 1.0).expect("state");
    g.bench_function("sliding", |b| b.iter(|| run(&d, &push)));

    // `vs` of the order of the speed (1 to 70 m/s here), so that every `exp` takes libm's
    // general path: far above `vs` its argument is below -745 and it returns 0 early.
    let both = DriveParams {
        stribeck_velocity: 20.0,
        load_friction: 0.1,
        ..slide
    };
    let mut d: Drive = Drive::new(&both, H, 0.0).expect("valid");
    d.set_state(0.0, 1.0).expect("state");
    g.bench_function("sliding_stribeck_load", |b| b.iter(|| run(&d, &push)));

    let push32: Vec<f32> = push.iter().map(|&v| v as f32).collect();
    let mut d32: Drive<f32> = Drive::new(&slide, H, 0.0).expect("valid");
    d32.set_state(0.0, 1.0).expect("state");
    g.bench_function("sliding_f32", |b| b.iter(|| run(&d32, &push32)));

    let rest = inputs(|t| 5.0 * (t * 3.0).sin());
    let d: Drive = Drive::new(&p, H, 0.0).expect("valid");
    g.bench_function("stuck", |b| b.iter(|| run(&d, &rest)));

    let joint_both = DriveParams {
        stribeck_velocity: 0.05,
        load_friction: 0.1,
        ..p
    };
    let d: Drive = Drive::new(&joint_both, H, 0.0).expect("valid");
    g.bench_function("stick_slip_stribeck_load", |b| b.iter(|| run(&d, &ramp)));
    g.finish();

    // What the runs contain (printed once, so the figures can be read against it).
    for (name, q) in [("stick_slip", p), ("stick_slip_stribeck_load", joint_both)] {
        let mut d: Drive = Drive::new(&q, H, 0.0).expect("valid");
        let (mut events, mut stuck) = (0u32, 0usize);
        for &u in &ramp {
            events += u32::from(d.step(u).expect("step").events);
            stuck += usize::from(d.mode() == crane_model::Mode::Stopped);
        }
        println!("{name} run: {events} located events, {stuck} of {STEPS} steps stuck");
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
