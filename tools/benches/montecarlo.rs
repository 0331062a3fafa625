//! (c) Monte Carlo throughput over friction uncertainty (case 1, trolley friction +-30 %):
//! simulations per second on all cores (rayon) and on one, and the cost against the number
//! of simulations and against the simulated duration (both should be linear).

use crane_tools::montecarlo;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::time::Duration;

const H: f64 = 1e-3;

fn bench(c: &mut Criterion) {
    let all = rayon::ThreadPoolBuilder::new().build().expect("pool");
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");

    let mut g = c.benchmark_group("mc_sims");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    for n in [8usize, 16, 32, 64] {
        g.throughput(Throughput::Elements(n as u64));
        g.bench_with_input(BenchmarkId::new("all_cores_2s", n), &n, |b, &n| {
            b.iter(|| all.install(|| montecarlo::run(n, 2.0, H, 1).expect("runs")))
        });
    }
    g.throughput(Throughput::Elements(32));
    g.bench_function(BenchmarkId::new("one_core_2s", 32), |b| {
        b.iter(|| one.install(|| montecarlo::run(32, 2.0, H, 1).expect("runs")))
    });
    g.finish();

    let mut g = c.benchmark_group("mc_duration");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    for d in [1.0f64, 2.0, 4.0, 8.0] {
        g.throughput(Throughput::Elements(16));
        g.bench_with_input(BenchmarkId::new("all_cores_16sims", d), &d, |b, &d| {
            b.iter(|| all.install(|| montecarlo::run(16, d, H, 1).expect("runs")))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
