//! Cost on the Cortex-M4F of the candidates of model/NUMERICS.md "nalgebra and micromath:
//! measured, not used", under QEMU mps2-an386 with the firmware's plugins: each call of a
//! candidate is bracketed by `bench_start()`/`bench_stop()`, announced by a line
//! `BENCH label n` before its `n` intervals (the protocol of `scripts/firmware-cycles.sh`).
//! Run by `scripts/numerics-cycles.sh`.
#![no_std]
#![no_main]

use core::fmt::Write;
use core::hint::black_box;
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hio};
use crane_model::dynamics::{at_state, eval, Law};
use crane_model::Mode;
use crane_twin::logic::scenarios::{InputGen, SCENARIOS};
use m4_numerics::{
    bench_start, bench_stop, cholesky, fastmath_sincos, libm_sincos, lu, micromath_sincos, nothing,
    solve5,
};

/// Semihosting stdout, one `write_str` per piece.
struct Out(Option<hio::HostStream>);

impl Write for Out {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        if let Some(h) = self.0.as_mut() {
            let _ = h.write_all(s.as_bytes());
        }
        Ok(())
    }
}

/// Systems per scenario, and the step stride between them.
const PER_SCENARIO: usize = 20;
const STRIDE: u32 = 25;
const N_SYS: usize = 5 * PER_SCENARIO;

/// The arguments of the twin's sine and cosine: the swing angles between the swing stops
/// with a margin (host-tests/tests/crates_common `TWIN_RANGE`).
const TWIN_RANGE: (f32, f32) = (-1.5, 3.1);

/// `(matrix, right-hand side)` of the model's evaluation at every `STRIDE`-th state of the
/// first `PER_SCENARIO * STRIDE` steps of each cross-check scenario (f64), stopped axes held,
/// as host-tests/tests/crates_common `mass_systems` builds them.
fn systems() -> [([[f64; 5]; 5], [f64; 5]); N_SYS] {
    let mut out = [([[0.0; 5]; 5], [0.0; 5]); N_SYS];
    let mut n = 0;
    for sc in SCENARIOS.iter() {
        let Ok(mut crane) = sc.crane::<f64>() else {
            continue;
        };
        let mut gen = InputGen::new(sc);
        for k in 0..(PER_SCENARIO as u32 * STRIDE) {
            let u = gen.input(sc, k);
            let ok = crane.step(u).is_ok();
            if k % STRIDE != STRIDE - 1 || !ok {
                continue;
            }
            let u = u.map(|v| v.clamp(-12.0, 12.0));
            let (c, y, modes) = (crane.coeffs(), crane.state(), crane.modes());
            let Ok(ev) = eval(c, Law::Hybrid, &y, &modes, &u) else {
                continue;
            };
            let pre = at_state(c, &y);
            let mut r = [0.0; 5];
            for j in 0..5 {
                let q = if j < 3 {
                    c.axes[j].drive(u[j]) - ev.fric[j]
                } else if j == 3 {
                    -(c.damp_alpha * y.qd[3])
                } else {
                    -(c.damp_beta * y.qd[4])
                };
                r[j] = q - pre.hv[j] - pre.gv[j];
            }
            let mut a = pre.m;
            for i in 0..3 {
                if modes[i] == Mode::Stopped {
                    for row in a.iter_mut() {
                        row[i] = 0.0;
                    }
                    a[i] = [0.0; 5];
                    a[i][i] = 1.0;
                    r[i] = 0.0;
                }
            }
            if n < N_SYS {
                out[n] = (a, r);
                n += 1;
            }
        }
    }
    out
}

fn bench_sincos(out: &mut Out, label: &str, f: fn(f32) -> (f32, f32)) -> f32 {
    const N: u32 = 100;
    let _ = writeln!(out, "BENCH {label} {N}");
    let (lo, hi) = TWIN_RANGE;
    let mut acc = 0.0;
    for k in 0..N {
        let x = black_box(lo + (hi - lo) * k as f32 / (N - 1) as f32);
        bench_start();
        let (s, c) = f(x);
        bench_stop();
        acc += black_box(s) + black_box(c);
    }
    acc
}

type Solver<T> = fn([[T; 5]; 5], [T; 5]) -> Option<[T; 5]>;

fn bench_solve_f32(
    out: &mut Out,
    label: &str,
    f: Solver<f32>,
    sys: &[([[f64; 5]; 5], [f64; 5])],
) -> bool {
    let _ = writeln!(out, "BENCH {label} {}", sys.len());
    let mut ok = true;
    for (a, r) in sys {
        let a = black_box(a.map(|row| row.map(|v| v as f32)));
        let r = black_box(r.map(|v| v as f32));
        bench_start();
        let x = f(a, r);
        bench_stop();
        ok &= black_box(x).is_some();
    }
    ok
}

fn bench_solve_f64(
    out: &mut Out,
    label: &str,
    f: Solver<f64>,
    sys: &[([[f64; 5]; 5], [f64; 5])],
) -> bool {
    let _ = writeln!(out, "BENCH {label} {}", sys.len());
    let mut ok = true;
    for (a, r) in sys {
        let (a, r) = (black_box(*a), black_box(*r));
        bench_start();
        let x = f(a, r);
        bench_stop();
        ok &= black_box(x).is_some();
    }
    ok
}

#[entry]
fn main() -> ! {
    let mut out = Out(hio::hstdout().ok());
    let mut acc = 0.0;
    acc += bench_sincos(&mut out, "call_overhead", nothing);
    acc += bench_sincos(&mut out, "sincos_fastmath", fastmath_sincos);
    acc += bench_sincos(&mut out, "sincos_libm", libm_sincos);
    acc += bench_sincos(&mut out, "sincos_micromath", micromath_sincos);
    let sys = systems();
    let mut ok = acc.is_finite();
    ok &= bench_solve_f32(&mut out, "solve5_f32", solve5::<f32>, &sys);
    ok &= bench_solve_f32(&mut out, "nalgebra_lu_f32", lu::<f32>, &sys);
    ok &= bench_solve_f32(&mut out, "nalgebra_cholesky_f32", cholesky::<f32>, &sys);
    ok &= bench_solve_f64(&mut out, "solve5_f64", solve5::<f64>, &sys);
    ok &= bench_solve_f64(&mut out, "nalgebra_lu_f64", lu::<f64>, &sys);
    ok &= bench_solve_f64(&mut out, "nalgebra_cholesky_f64", cholesky::<f64>, &sys);
    let _ = writeln!(out, "DONE {}", if ok { "ok" } else { "FAILED" });
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}
