//! (a) Time per model step: one hybrid step against one RK4 step of the bare continuous
//! dynamics (same equations through `dynamics::eval`, no friction, no modes, no events).
//! Target of issue 4: hybrid / bare <= 1.3 for the usual step.

use crane_model::{Config, Crane, FrictionLaw, Params, State};
use crane_tools::smooth::{pack, rk4_bare, Smooth};
use criterion::{black_box, criterion_group, criterion_main, BatchSize, Criterion};
use std::time::Duration;

const H: f64 = 1e-3;

/// Mid-range, all three drive axes moving, payload swinging: the usual step (no event).
fn moving() -> State<f64> {
    State {
        q: [0.25, 0.30, 0.35, 1.45, 0.08],
        qd: [0.10, -0.08, 0.05, 0.2, -0.1],
    }
}

/// At rest, hanging: all axes stopped, the guards evaluated and not met.
fn resting() -> State<f64> {
    State {
        q: [0.25, 0.30, 0.35, core::f64::consts::FRAC_PI_2, 0.0],
        qd: [0.0; 5],
    }
}

fn crane(s: State<f64>, law: FrictionLaw) -> Crane {
    Crane::new(&Params::default(), Config { h: H, law }, s).expect("valid")
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("step");
    g.sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    let u_move = [6.0, -5.0, 2.0];
    let p = Params::default();
    let bare = Smooth::bare(&p);

    let cm = crane(moving(), FrictionLaw::Hybrid);
    g.bench_function("hybrid/moving", |b| {
        b.iter_batched_ref(
            || cm.clone(),
            |c| c.step(black_box(u_move)),
            BatchSize::SmallInput,
        )
    });
    let cr = crane(resting(), FrictionLaw::Hybrid);
    g.bench_function("hybrid/stopped", |b| {
        b.iter_batched_ref(
            || cr.clone(),
            |c| c.step(black_box([0.0; 3])),
            BatchSize::SmallInput,
        )
    });
    let ct = crane(moving(), FrictionLaw::Tanh { gamma: 1000.0 });
    g.bench_function("model_tanh_rk4/moving", |b| {
        b.iter_batched_ref(
            || ct.clone(),
            |c| c.step(black_box(u_move)),
            BatchSize::SmallInput,
        )
    });
    // Same harness as the hybrid single steps (a fresh copy of the state per iteration).
    let y = pack(&moving());
    g.bench_function("bare_rk4/moving", |b| {
        b.iter_batched_ref(
            || y,
            |y| *y = rk4_bare(&bare, y, H, black_box(&u_move)).expect("step"),
            BatchSize::SmallInput,
        )
    });
    // 1000 consecutive steps (1 s) with all three axes moving and no event: per-step cost
    // without the clone of the single-step benches.
    let n = 1000;
    g.bench_function("hybrid/1000_moving_steps", |b| {
        b.iter(|| {
            let mut c = cm.clone();
            for _ in 0..n {
                let r = c.step(black_box(u_move)).expect("step");
                debug_assert_eq!(r.events, 0);
            }
            c.state()
        })
    });
    g.bench_function("bare_rk4/1000_moving_steps", |b| {
        b.iter(|| {
            let mut y = pack(&moving());
            for _ in 0..n {
                y = rk4_bare(&bare, &y, H, black_box(&u_move)).expect("step");
            }
            y
        })
    });
    let y = pack(&resting());
    g.bench_function("bare_rk4/resting", |b| {
        b.iter_batched_ref(
            || y,
            |y| *y = rk4_bare(&bare, y, H, black_box(&[0.0; 3])).expect("step"),
            BatchSize::SmallInput,
        )
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
