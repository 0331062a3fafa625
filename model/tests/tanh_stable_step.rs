//! The `tanh` law's fixed-step stability limit as documented (`model/NUMERICS.md`, the FMU
//! and Python READMEs): measured by `examples/tanh_stable_step.rs`, whose functions these
//! checks call.

#[allow(dead_code)] // `main` and the table's constants are the example's
#[path = "../examples/tanh_stable_step.rs"]
mod example;

use crane_model::Params;
use example::{creep, damps, estimate_h};

/// gamma = 1e4 s/m: the documented 0.599 ms is the limit to 5 % either way, on every drive
/// axis kicked alone, and the rope's estimate `2.785 M / (Dbar + gamma Cbar)` gives it to
/// 1 %.
#[test]
fn the_documented_limit_at_gamma_1e4_holds() {
    let p = Params::default();
    let limit = 0.599e-3;
    for axis in 0..3 {
        assert!(damps(&p, 1e4, 0.95 * limit, axis), "axis {axis} at 0.95 x");
        assert!(!damps(&p, 1e4, 1.05 * limit, axis), "axis {axis} at 1.05 x");
    }
    let rope = estimate_h(&p, 1e4, 2);
    assert!((rope / limit - 1.0).abs() < 0.01, "estimate {rope}");
}

/// Above the limit the crane at rest creeps (13 um in 0.5 s at gamma = 1e4 and the default
/// 1 ms); below it, it stays put.
#[test]
fn above_the_limit_the_crane_at_rest_creeps() {
    let p = Params::default();
    let (_, moved) = creep(&p, 1e4, 1e-3).expect("steps");
    assert!(moved > 5e-6, "moved {moved} m");
    let (v, moved) = creep(&p, 1e4, 0.5e-3).expect("steps");
    assert!(moved < 1e-9 && v < 1e-9, "moved {moved} m, |qd| {v} m/s");
    // the default gamma at the default step: at rest
    let (_, moved) = creep(&p, 1e3, 1e-3).expect("steps");
    assert!(moved < 1e-8, "moved {moved} m");
}
