//! How far the single-precision builds (`f32` with libm's sinf/cosf, `F32x` with FPU-only
//! sine/cosine) drift from f64: open loop over each cross-check scenario, and in the closed
//! loop (twin estimate against the f64 twin's). Prints the table quoted in firmware/README.md
//! (`cargo test -p crane-twin --test precision -- --nocapture`).

use crane_model::Real;
use crane_twin::logic::fastmath::F32x;
use crane_twin::logic::plant::{demo_plant, run_demo};
use crane_twin::logic::scenarios::{InputGen, Scenario, SCENARIOS};

/// Largest |x_R - x_f64| of the drive positions [m] and swing angles [rad] over the first
/// `steps` steps of `sc` (same inputs, rounded to R).
fn open_loop_dev<R: Real>(sc: &Scenario, steps: u32) -> (f64, f64) {
    let mut a = sc.crane::<f64>().unwrap();
    let mut b = sc.crane::<R>().unwrap();
    let mut gen = InputGen::new(sc);
    let (mut dp, mut da) = (0.0f64, 0.0f64);
    for k in 0..steps {
        let u = gen.input(sc, k);
        let _ = a.step(u);
        let _ = b.step(u.map(R::from_f64));
        let (x, y) = (a.state(), b.state().to_f64());
        for i in 0..3 {
            dp = dp.max((x.q[i] - y.q[i]).abs());
        }
        for i in 3..5 {
            da = da.max((x.q[i] - y.q[i]).abs());
        }
    }
    (dp, da)
}

#[test]
fn single_precision_deviation_from_f64() {
    println!("open loop, max |R - f64| over the whole scenario: positions [m], angles [rad]");
    for sc in SCENARIOS.iter() {
        let (p32, a32) = open_loop_dev::<f32>(sc, sc.steps);
        let (px, ax) = open_loop_dev::<F32x>(sc, sc.steps);
        let (p1, a1) = open_loop_dev::<F32x>(sc, (0.5 / sc.h) as u32);
        println!(
            "{:<11} f32 {p32:.2e} m {a32:.2e} rad | f32x {px:.2e} m {ax:.2e} rad | f32x first 0.5 s {p1:.2e} m {a1:.2e} rad",
            sc.name
        );
        // Measured: at most 1.0e-6 m and 1.2e-5 rad over 6 to 10 s of stick-slip, end stops
        // and reversals; guard with a margin (an encoder count is 6.1e-5 m, 1.5e-3 rad).
        for (p, a) in [(p32, a32), (px, ax), (p1, a1)] {
            assert!(p < 1e-5 && a < 1e-4, "{}: {p} m, {a} rad", sc.name);
        }
    }
    // Closed loop: the observer keeps every build on the plant; the estimates differ by
    // well under an encoder count.
    let mut sink = String::new();
    let mut s = Vec::new();
    for tag in ["f64", "f32", "f32x"] {
        let mut plant = demo_plant().unwrap();
        let sum = match tag {
            "f64" => run_demo::<f64, _, _>(&mut plant, tag, &mut sink),
            "f32" => run_demo::<f32, _, _>(&mut plant, tag, &mut sink),
            _ => run_demo::<F32x, _, _>(&mut plant, tag, &mut sink),
        }
        .unwrap()
        .unwrap();
        println!(
            "closed loop {tag:<4}: estimation error rms x {:.2e} y {:.2e} L {:.2e} m, alpha {:.2e} beta {:.2e} rad; track max {:.2e} {:.2e} {:.2e} m",
            sum.pos_err_rms[0],
            sum.pos_err_rms[1],
            sum.pos_err_rms[2],
            sum.pos_err_rms[3],
            sum.pos_err_rms[4],
            sum.track_err_max[0],
            sum.track_err_max[1],
            sum.track_err_max[2]
        );
        s.push(sum);
    }
    for sum in &s[1..] {
        for i in 0..3 {
            assert!(sum.pos_err_rms[i] < 2.0 * s[0].pos_err_rms[i] + 1e-6);
            assert!((sum.track_err_max[i] - s[0].track_err_max[i]).abs() < 1e-3);
        }
    }
}
