//! micromath's f32 `sin`/`cos` (`micromath::F32Ext`) against the twin's `fastmath`
//! (`F32x`, `twin/src/logic/fastmath.rs`) and libm's `sinf`/`cosf`: error against the
//! correctly rounded value (libm's f64 `sin`/`cos` rounded to f32) on a dense grid over the
//! arguments the twin uses and over +-100 rad, and the twin's trajectories with micromath's
//! sine and cosine swapped in (a test-only `Real`, the shipped `F32x` unchanged).
//! `cargo test -p host-tests --release --test micromath_sincos -- --nocapture --test-threads 1`
//! prints the tables of model/NUMERICS.md "nalgebra and micromath: measured, not used".

mod crates_common;

use core::ops::{Add, Div, Mul, Neg, Sub};
use crane_model::Real;
use crane_twin::logic::fastmath::F32x;
use crane_twin::logic::plant::{demo_plant, run_demo};
use crane_twin::logic::scenarios::{InputGen, Scenario, SCENARIOS};
use crates_common::{fastmath_sincos, micromath_sincos, SINCOS, TWIN_RANGE};
use std::cell::Cell;

/// Points of each grid.
const POINTS: u32 = 10_000_000;

/// Error statistics of one function over one grid, against the correctly rounded value.
#[derive(Clone, Copy, Debug, Default)]
struct Err {
    max_abs: f64,
    at: f32,
    sum_sq: f64,
    n: u32,
    /// Largest error in ulps of the correctly rounded result, and where.
    max_ulp: f64,
    at_ulp: f32,
    /// Results equal to the correctly rounded value.
    exact: u32,
}

impl Err {
    fn add(&mut self, x: f32, got: f32, want: f32) {
        let e = (f64::from(got) - f64::from(want)).abs();
        if e > self.max_abs {
            self.max_abs = e;
            self.at = x;
        }
        self.sum_sq += e * e;
        self.n += 1;
        self.exact += u32::from(got == want);
        let w = want.abs();
        let ulp = f64::from(f32::from_bits(w.to_bits() + 1)) - f64::from(w);
        if e / ulp > self.max_ulp {
            self.max_ulp = e / ulp;
            self.at_ulp = x;
        }
    }
    fn rms(&self) -> f64 {
        (self.sum_sq / f64::from(self.n)).sqrt()
    }
}

/// `(sin, cos)` errors of `f` over `POINTS` evenly spaced f32 in `[lo, hi]`.
fn grid_error(f: fn(f32) -> (f32, f32), lo: f32, hi: f32) -> (Err, Err) {
    let (mut es, mut ec) = (Err::default(), Err::default());
    let (lo64, span) = (f64::from(lo), f64::from(hi) - f64::from(lo));
    for k in 0..POINTS {
        let x = (lo64 + span * f64::from(k) / f64::from(POINTS - 1)) as f32;
        let (s, c) = f(x);
        let x64 = f64::from(x);
        es.add(x, s, libm::sin(x64) as f32);
        ec.add(x, c, libm::cos(x64) as f32);
    }
    (es, ec)
}

#[test]
fn sine_and_cosine_error_on_dense_grids() {
    println!(
        "{POINTS} points per range; error against libm f64 sin/cos rounded to f32 \
         (max abs | rms | max ulps | correctly rounded | at max abs, at max ulps)"
    );
    let mut got = Vec::new();
    for (lo, hi) in [TWIN_RANGE, (-100.0, 100.0)] {
        for (name, f) in SINCOS {
            let (s, c) = grid_error(f, lo, hi);
            for (which, e) in [("sin", s), ("cos", c)] {
                println!(
                    "[{lo}, {hi}] {name:<14} {which}: {:.3e} | {:.3e} | {:.3e} | {:.1} % | {}, {}",
                    e.max_abs,
                    e.rms(),
                    e.max_ulp,
                    100.0 * f64::from(e.exact) / f64::from(e.n),
                    e.at,
                    e.at_ulp
                );
            }
            got.push((name, lo, s, c));
        }
    }
    // The measured bounds (max abs error, max ulps of sin and cos), with a margin of 10 %.
    let bound = |name: &str, lo: f32| match (name, lo == TWIN_RANGE.0) {
        ("fastmath", true) => (6.6e-8, 1.1),
        ("fastmath", false) => (6.6e-8, 15.4),
        ("libm sinf/cosf", _) => (6.6e-8, 1.1),
        (_, true) => (1.2e-3, 3.4e6),
        _ => (1.2e-3, 4.8e8),
    };
    for (name, lo, s, c) in &got {
        let (e, u) = (s.max_abs.max(c.max_abs), s.max_ulp.max(c.max_ulp));
        let (be, bu) = bound(name, *lo);
        assert!(e < be && u < bu, "{name} from {lo}: {e:e}, {u} ulps");
    }
    // The decision's premise: on the twin's range micromath is far less accurate.
    let max_abs = |n: &str| {
        got.iter()
            .filter(|g| g.0 == n && g.1 == TWIN_RANGE.0)
            .map(|g| g.2.max_abs.max(g.3.max_abs))
            .fold(0.0, f64::max)
    };
    assert!(max_abs("micromath") > 1000.0 * max_abs("fastmath"));
}

/// An `f32` `Real` like `F32x` with another sine and cosine (test-only).
macro_rules! f32_real {
    ($name:ident, $sincos:expr) => {
        #[derive(Clone, Copy, Debug, PartialEq, PartialOrd, Default)]
        struct $name(f32);
        impl Add for $name {
            type Output = Self;
            fn add(self, o: Self) -> Self {
                $name(self.0 + o.0)
            }
        }
        impl Sub for $name {
            type Output = Self;
            fn sub(self, o: Self) -> Self {
                $name(self.0 - o.0)
            }
        }
        impl Mul for $name {
            type Output = Self;
            fn mul(self, o: Self) -> Self {
                $name(self.0 * o.0)
            }
        }
        impl Div for $name {
            type Output = Self;
            fn div(self, o: Self) -> Self {
                $name(self.0 / o.0)
            }
        }
        impl Neg for $name {
            type Output = Self;
            fn neg(self) -> Self {
                $name(-self.0)
            }
        }
        impl Real for $name {
            const ZERO: Self = $name(0.0);
            const ONE: Self = $name(1.0);
            const TWO: Self = $name(2.0);
            const THREE: Self = $name(3.0);
            const SIX: Self = $name(6.0);
            const HALF: Self = $name(0.5);
            fn from_f64(x: f64) -> Self {
                $name(x as f32)
            }
            fn to_f64(self) -> f64 {
                f64::from(self.0)
            }
            fn sin(self) -> Self {
                $name(($sincos)(self.0).0)
            }
            fn cos(self) -> Self {
                $name(($sincos)(self.0).1)
            }
            fn tanh(self) -> Self {
                $name(libm::tanhf(self.0))
            }
            fn exp(self) -> Self {
                $name(libm::expf(self.0))
            }
            fn is_finite(self) -> bool {
                self.0.is_finite()
            }
        }
    };
}

// `F32x` with micromath's sine and cosine.
f32_real!(Micro, micromath_sincos);

thread_local! {
    /// Smallest and largest argument given to `Rec`'s sine and cosine.
    static SEEN: Cell<(f32, f32)> = const { Cell::new((f32::INFINITY, f32::NEG_INFINITY)) };
}

/// The twin's sine and cosine, recording the argument range.
fn recording_sincos(x: f32) -> (f32, f32) {
    SEEN.with(|s| {
        let (lo, hi) = s.get();
        s.set((lo.min(x), hi.max(x)));
    });
    fastmath_sincos(x)
}

// `F32x` (the same bits) that records its arguments.
f32_real!(Rec, recording_sincos);

/// Largest |x_R - x_f64| of the drive positions [m] and swing angles [rad] over the first
/// `steps` steps of `sc` (same inputs, rounded to R), and the final state's bits.
fn open_loop_dev<R: Real>(sc: &Scenario, steps: u32) -> (f64, f64, [u64; 10]) {
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
    let y = b.state().to_f64();
    let mut bits = [0u64; 10];
    for i in 0..5 {
        bits[i] = y.q[i].to_bits();
        bits[5 + i] = y.qd[i].to_bits();
    }
    (dp, da, bits)
}

#[test]
fn twin_arguments_stay_in_the_measured_range() {
    SEEN.with(|s| s.set((f32::INFINITY, f32::NEG_INFINITY)));
    for sc in SCENARIOS.iter() {
        let (.., rec) = open_loop_dev::<Rec>(sc, sc.steps);
        let (.., x) = open_loop_dev::<F32x>(sc, sc.steps);
        assert_eq!(rec, x, "{}: Rec is not F32x", sc.name);
    }
    let mut plant = demo_plant().unwrap();
    run_demo::<Rec, _, _>(&mut plant, "rec", &mut String::new())
        .unwrap()
        .unwrap();
    let (lo, hi) = SEEN.with(Cell::get);
    println!("the twin's sin/cos arguments (5 scenarios and the closed loop): [{lo}, {hi}]");
    assert!(lo >= TWIN_RANGE.0 && hi <= TWIN_RANGE.1, "[{lo}, {hi}]");
}

#[test]
fn twin_trajectories_with_micromath() {
    println!("open loop, max |R - f64| over the whole scenario: drive positions [m], angles [rad]");
    let mut worst = [(0.0f64, 0.0f64); 2];
    for sc in SCENARIOS.iter() {
        let (px, ax, _) = open_loop_dev::<F32x>(sc, sc.steps);
        let (pm, am, _) = open_loop_dev::<Micro>(sc, sc.steps);
        println!(
            "{:<11} fastmath (F32x) {px:.2e} m {ax:.2e} rad | micromath {pm:.2e} m {am:.2e} rad",
            sc.name
        );
        worst[0] = (worst[0].0.max(px), worst[0].1.max(ax));
        worst[1] = (worst[1].0.max(pm), worst[1].1.max(am));
    }
    println!(
        "worst: fastmath {:.2e} m {:.2e} rad | micromath {:.2e} m {:.2e} rad",
        worst[0].0, worst[0].1, worst[1].0, worst[1].1
    );
    let mut sink = String::new();
    let mut s = Vec::new();
    for tag in ["f64", "f32x", "micro"] {
        let mut plant = demo_plant().unwrap();
        let sum = match tag {
            "f64" => run_demo::<f64, _, _>(&mut plant, tag, &mut sink),
            "f32x" => run_demo::<F32x, _, _>(&mut plant, tag, &mut sink),
            _ => run_demo::<Micro, _, _>(&mut plant, tag, &mut sink),
        }
        .unwrap()
        .unwrap();
        println!(
            "closed loop {tag:<5}: estimation error rms x {:.2e} y {:.2e} L {:.2e} m, alpha {:.2e} beta {:.2e} rad; track max {:.2e} {:.2e} {:.2e} m",
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
    // Measured, with a margin of about 10 %: fastmath within 1.0e-6 m and 1.2e-5 rad of f64
    // (the bound of twin/tests/precision.rs); micromath's worst 200 (drives) and 2,400
    // (swing) times fastmath's worst.
    assert!(
        worst[0].0 < 1.1e-6 && worst[0].1 < 1.3e-5,
        "fastmath {:?}",
        worst[0]
    );
    assert!(
        worst[1].0 < 2.1e-4 && worst[1].1 < 2.9e-2,
        "micromath {:?}",
        worst[1]
    );
    assert!(worst[1].0 > 100.0 * worst[0].0 && worst[1].1 > 1000.0 * worst[0].1);
    // The closed loop hides most of it: the observer pulls every build back to the plant.
    // micromath's estimation errors (measured 9.03, 14.9, 4.26 um) within 10 %, tracking
    // maxima within 0.1 mm of f64's.
    let (f64s, micro) = (&s[0], &s[2]);
    for (i, b) in [9.9e-6, 1.64e-5, 4.7e-6].into_iter().enumerate() {
        assert!(
            micro.pos_err_rms[i] < b,
            "axis {i}: {:?}",
            micro.pos_err_rms
        );
        assert!((micro.track_err_max[i] - f64s.track_err_max[i]).abs() < 1e-4);
    }
}
