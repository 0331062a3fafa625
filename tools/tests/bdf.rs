//! The `diffsol` stiff peer ([`crane_tools::bdf`]): a stiff linear problem with a known
//! solution, convergence as the tolerance tightens, the `tanh` model of case 2 against
//! Dormand-Prince at a tight tolerance, and a failing right-hand side.

use crane_tools::bdf::{integrate, Failure};
use crane_tools::cases::Case;
use crane_tools::ode45::Options;
use crane_tools::reference;
use crane_tools::tanh_run::tanh_ode45;
use crane_tools::workprec::tanh_bdf;

const LAMBDA: f64 = 1e4;

/// Exact solution of `y' = -lambda (y - cos t)`, `y(0) = 1`.
fn exact(t: f64) -> f64 {
    let l2 = LAMBDA * LAMBDA;
    let a = l2 / (l2 + 1.0);
    let b = LAMBDA / (l2 + 1.0);
    a * t.cos() + b * t.sin() + (1.0 - a) * (-LAMBDA * t).exp()
}

fn opts(rtol: f64, atol: f64) -> Options {
    Options {
        rtol,
        atol,
        hmax: f64::INFINITY,
    }
}

/// Largest error on the 10 ms grid over 10 s, and the solver's work.
fn stiff_run(rtol: f64) -> (f64, crane_tools::ode45::Stats, usize) {
    let mut worst: f64 = 0.0;
    let mut seen = 0usize;
    let st = integrate(
        |t, y: &[f64; 1]| Some([-LAMBDA * (y[0] - t.cos())]),
        0.0,
        [1.0],
        0.01,
        1000,
        &opts(rtol, rtol * 1e-3),
        |k, t, y| {
            assert_eq!(k, seen + 1, "grid points in order");
            assert!((t - 0.01 * k as f64).abs() < 1e-12);
            seen = k;
            worst = worst.max((y[0] - exact(t)).abs());
        },
    )
    .unwrap();
    (worst, st, seen)
}

/// The stiff problem (explicit stability limit ~2.8e-4 s) to its tolerance, in far fewer
/// steps than an explicit solver needs for stability alone (10 s / 2.8e-4 s = 36,000).
/// Measured: error 2.9e-7 in 145 steps (218 evaluations).
#[test]
fn stiff_linear_problem_against_its_exact_solution() {
    let (worst, st, seen) = stiff_run(1e-6);
    assert_eq!(seen, 1000, "every grid point written");
    assert!(worst < 1e-6, "error {worst}");
    assert!(st.accepted < 1_000, "{st:?}");
    assert!(st.evals > st.accepted, "{st:?}");
}

/// Tightening the tolerance 10,000x lowers the error at least 1,000x (measured: 2.4e-5 at
/// rtol 1e-4, 2.9e-9 at rtol 1e-8), at more steps.
#[test]
fn error_decreases_with_the_tolerance() {
    let (coarse, st_coarse, _) = stiff_run(1e-4);
    let (fine, st_fine, _) = stiff_run(1e-8);
    assert!(fine < coarse / 1000.0, "{coarse} -> {fine}");
    assert!(fine < 1e-8, "{fine}");
    assert!(st_fine.accepted > st_coarse.accepted);
}

/// The `tanh(1000 v)` model of case 2 under BDF at rtol 1e-8 agrees with Dormand-Prince at
/// rtol 1e-10 on the compared velocity, and the loose BDF run is much further off (the
/// comparison can tell).
#[test]
fn tanh_case2_agrees_with_dp45_at_a_tight_tolerance() {
    let case = Case::all()
        .into_iter()
        .find(|c| c.observed != 1)
        .expect("case 2");
    let (dp, _) = tanh_ode45(&case, 1e3, &opts(1e-10, 1e-12)).unwrap();
    let (tight, st) = tanh_bdf(&case, 1e3, &opts(1e-8, 1e-10)).unwrap();
    let (loose, _) = tanh_bdf(&case, 1e3, &opts(1e-3, 1e-5)).unwrap();
    assert_eq!(tight.states.len(), case.samples() + 1);
    let e_tight = reference::rmse(&case, &tight, &dp);
    let e_loose = reference::rmse(&case, &loose, &dp);
    // Measured: 1.3e-8 m/s (rtol 1e-8) and 2.1e-3 m/s (rtol 1e-3).
    assert!(e_tight < 1e-7, "RMSE against DP45 {e_tight} m/s");
    assert!(e_tight < e_loose / 1000.0, "{e_loose} -> {e_tight}");
    assert!(st.accepted > 100, "{st:?}");
}

/// A right-hand side that fails is reported with its time, not integrated through.
#[test]
fn failing_rhs_is_an_error() {
    let mut last = 0.0;
    let r = integrate(
        |t, y: &[f64; 2]| (t < 0.5).then_some([y[1], -y[0]]),
        0.0,
        [0.0, 1.0],
        0.01,
        100,
        &opts(1e-6, 1e-9),
        |_, t, _| last = t,
    );
    match r {
        Err(Failure::Rhs(t)) => assert!((0.5..=1.0).contains(&t), "{t}"),
        other => panic!("{other:?}"),
    }
    assert!(last < 0.5, "wrote {last}");
    assert!(last > 0.2, "stopped at {last}");
}
