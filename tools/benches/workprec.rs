//! Work-precision in one criterion run: per case, the fastest hybrid and the fastest `tanh`
//! setting at each error level where both reach it (as found by `crane study`'s sweep,
//! BENCHMARKS.md "Work-precision"), and both defaults (hybrid: adaptive rtol 1e-7; tanh:
//! tanh(1000 v) under DP45 at rtol 1e-6, atol 1e-8, the paper's comparison). RMSEs: `crane
//! study` (the same runs). The `bdf` entries are the fastest `tanh` settings under the
//! `diffsol` BDF peer in `crane study`: case 1 levels 1e-3 / 1e-4 / 1e-5, case 2 levels
//! 1e-3 / 1e-4 and 1e-5. The hybrid settings: case 1 `rtol` 1e-3 / 1e-4 / 1e-5, case 2
//! 1e-3 / 1e-4 / 1e-6 (since the guard step bound, `rtol` 1e-5 no longer reaches 1e-5 m/s
//! in case 2: 1.07e-5).

use crane_tools::adaptive_run::{hybrid_adaptive, tolerances};
use crane_tools::cases::Case;
use crane_tools::ode45::Options;
use crane_tools::reference;
use crane_tools::tanh_run::tanh_ode45;
use crane_tools::workprec::{tanh_bdf, tanh_rosenbrock};
use criterion::{criterion_group, criterion_main, Criterion};
use std::time::Duration;

/// A timed setting.
enum Run {
    Fixed(f64),
    Adaptive(f64),
    Dp45(f64, f64),
    Rosenbrock(f64, f64),
    Bdf(f64, f64),
}

fn opts(rtol: f64) -> Options {
    Options {
        rtol,
        atol: rtol * 1e-2,
        hmax: f64::INFINITY,
    }
}

fn bench(c: &mut Criterion) {
    for case in Case::all() {
        let one = case.observed == 1;
        let mut g = c.benchmark_group(format!("workprec_case{}", if one { 1 } else { 2 }));
        g.sample_size(10)
            .warm_up_time(Duration::from_millis(200))
            .measurement_time(Duration::from_secs(2));
        let runs: Vec<(&str, Run)> = if one {
            vec![
                ("hybrid_fixed_50ms", Run::Fixed(0.05)),
                ("hybrid_adaptive_rtol1e-3", Run::Adaptive(1e-3)),
                ("hybrid_adaptive_rtol1e-4", Run::Adaptive(1e-4)),
                ("hybrid_adaptive_rtol1e-5", Run::Adaptive(1e-5)),
                ("hybrid_adaptive_rtol1e-7_default", Run::Adaptive(1e-7)),
                ("tanh1e3_dp45_rtol1e-5", Run::Dp45(1e3, 1e-5)),
                ("tanh1e4_rosenbrock_rtol1e-3", Run::Rosenbrock(1e4, 1e-3)),
                ("tanh1e6_rosenbrock_rtol1e-5", Run::Rosenbrock(1e6, 1e-5)),
                ("tanh1e3_bdf_rtol1e-4", Run::Bdf(1e3, 1e-4)),
                ("tanh1e5_bdf_rtol1e-5", Run::Bdf(1e5, 1e-5)),
                ("tanh1e6_bdf_rtol1e-7", Run::Bdf(1e6, 1e-7)),
            ]
        } else {
            vec![
                ("hybrid_adaptive_rtol1e-3", Run::Adaptive(1e-3)),
                ("hybrid_adaptive_rtol1e-4", Run::Adaptive(1e-4)),
                ("hybrid_adaptive_rtol1e-6", Run::Adaptive(1e-6)),
                ("hybrid_adaptive_rtol1e-7_default", Run::Adaptive(1e-7)),
                ("tanh1e4_rosenbrock_rtol1e-4", Run::Rosenbrock(1e4, 1e-4)),
                ("tanh1e6_rosenbrock_rtol1e-6", Run::Rosenbrock(1e6, 1e-6)),
                ("tanh1e6_rosenbrock_rtol1e-7", Run::Rosenbrock(1e6, 1e-7)),
                ("tanh1e5_bdf_rtol1e-4", Run::Bdf(1e5, 1e-4)),
                ("tanh1e6_bdf_rtol1e-5", Run::Bdf(1e6, 1e-5)),
            ]
        };
        for (name, run) in runs {
            g.bench_function(name, |b| match run {
                Run::Fixed(h) => b.iter(|| {
                    reference::hybrid(&case, h, false)
                        .expect("runs")
                        .on_grid(&case)
                }),
                Run::Adaptive(r) => {
                    let tol = tolerances(&case, r);
                    b.iter(|| hybrid_adaptive(&case, &tol).expect("runs"))
                }
                Run::Dp45(gm, r) => b.iter(|| tanh_ode45(&case, gm, &opts(r)).expect("runs")),
                Run::Rosenbrock(gm, r) => {
                    b.iter(|| tanh_rosenbrock(&case, gm, &opts(r)).expect("runs"))
                }
                Run::Bdf(gm, r) => b.iter(|| tanh_bdf(&case, gm, &opts(r)).expect("runs")),
            });
        }
        g.bench_function("tanh1e3_dp45_default", |b| {
            b.iter(|| tanh_ode45(&case, 1e3, &Options::default()).expect("runs"))
        });
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
