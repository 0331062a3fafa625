//! Host time per call of the crates the design card names against the project's own code
//! (model/NUMERICS.md "nalgebra and micromath: measured, not used"):
//! - `sincos_f32`: sine and cosine of one argument, 1024 arguments evenly spread over the
//!   twin's range (`TWIN_RANGE`): `fastmath` (`F32x`), libm `sinf` + `cosf` (the model's
//!   `f32`), micromath `F32Ext::sin` + `cos`;
//! - `solve_f64`: one 5x5 solve, 256 of the systems the model solves in the cross-check
//!   scenarios (`mass_systems`): `solve5` (the reference's, the model's operation order),
//!   nalgebra's `lu().solve` and `cholesky()` + `solve`.
//!
//! `cargo bench -p host-tests --bench numerics_crates`; the time per element is the figure.

#[path = "../tests/crates_common/mod.rs"]
mod crates_common;

use crates_common::{
    fastmath_sincos, libm_sincos, mass_systems, micromath_sincos, SINCOS, TWIN_RANGE,
};
use criterion::measurement::WallTime;
use criterion::{
    black_box, criterion_group, criterion_main, BenchmarkGroup, Criterion, Throughput,
};
use host_tests::reference::solve5;
use nalgebra::{SMatrix, SVector};
use std::time::Duration;

fn bench_sincos(
    g: &mut BenchmarkGroup<'_, WallTime>,
    name: &str,
    xs: &[f32],
    f: impl Fn(f32) -> (f32, f32),
) {
    g.bench_function(name, |b| {
        b.iter(|| {
            let mut acc = 0.0f32;
            for &x in black_box(xs) {
                let (s, c) = f(x);
                acc += s + c;
            }
            acc
        })
    });
}

fn sincos(c: &mut Criterion) {
    const N: usize = 1024;
    let (lo, hi) = TWIN_RANGE;
    let xs: Vec<f32> = (0..N)
        .map(|k| lo + (hi - lo) * k as f32 / (N - 1) as f32)
        .collect();
    let mut g = c.benchmark_group("sincos_f32");
    g.throughput(Throughput::Elements(N as u64))
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    // Function items, not the pointers of `SINCOS`: each call is inlined as in the twin.
    bench_sincos(&mut g, SINCOS[0].0, &xs, fastmath_sincos);
    bench_sincos(&mut g, SINCOS[1].0, &xs, libm_sincos);
    bench_sincos(&mut g, SINCOS[2].0, &xs, micromath_sincos);
    g.finish();
}

fn solve(c: &mut Criterion) {
    let all = mass_systems(1);
    // 256 systems spread over the five scenarios, evaluations and end-stop solves.
    let step = all.len() / 256;
    let sys: Vec<_> = all.iter().step_by(step).take(256).copied().collect();
    let mut g = c.benchmark_group("solve_f64");
    g.throughput(Throughput::Elements(sys.len() as u64))
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    g.bench_function("solve5", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for s in black_box(&sys[..]) {
                acc += solve5(s.a, s.r).unwrap()[4];
            }
            acc
        })
    });
    g.bench_function("nalgebra LU", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for s in black_box(&sys[..]) {
                let m = SMatrix::<f64, 5, 5>::from_fn(|i, j| s.a[i][j]);
                acc += m.lu().solve(&SVector::from(s.r)).unwrap()[4];
            }
            acc
        })
    });
    g.bench_function("nalgebra Cholesky", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for s in black_box(&sys[..]) {
                let m = SMatrix::<f64, 5, 5>::from_fn(|i, j| s.a[i][j]);
                acc += m.cholesky().unwrap().solve(&SVector::from(s.r))[4];
            }
            acc
        })
    });
    g.finish();
}

criterion_group!(benches, sincos, solve);
criterion_main!(benches);
