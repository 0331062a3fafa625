//! (b) Wall time of the paper's two cases: the hybrid model at its default step (1 ms) and at
//! the coarse steps that are as accurate as tanh(1000 v) and tanh(10^4 v), against tanh(gamma v)
//! by ode45 (rtol 1e-6, atol 1e-8) for gamma = 1 ... 10^4. RMSEs: `crane study`.

use crane_tools::cases::Case;
use crane_tools::reference;
use crane_tools::study::GAMMAS;
use crane_tools::tanh_run::tanh_ode45;
use criterion::{criterion_group, criterion_main, Criterion};
use std::time::Duration;

fn bench(c: &mut Criterion) {
    for case in Case::all() {
        let mut g = c.benchmark_group(format!("case{}", if case.observed == 1 { 1 } else { 2 }));
        g.sample_size(10)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(2));
        g.bench_function("hybrid_h1ms", |b| {
            b.iter(|| reference::hybrid(&case, 1e-3, false).expect("runs"))
        });
        // Coarse hybrid steps at least as accurate as tanh(1000 v) and tanh(10^4 v) (found by
        // `crane study`, RMSE on the 1 ms grid with Hermite interpolation between steps).
        let coarse: &[f64] = if case.observed == 1 {
            &[50e-3, 25e-3]
        } else {
            &[25e-3, 8e-3]
        };
        for &h in coarse {
            g.bench_function(format!("hybrid_h{}ms", h * 1e3), |b| {
                b.iter(|| {
                    reference::hybrid(&case, h, false)
                        .expect("runs")
                        .on_grid(&case)
                })
            });
        }
        for gamma in GAMMAS {
            g.bench_function(format!("tanh{gamma}_ode45"), |b| {
                b.iter(|| tanh_ode45(&case, gamma, &Default::default()).expect("runs"))
            });
        }
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
