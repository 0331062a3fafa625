//! A finer ladder than `crane study`'s work-precision sweep, the same for both sides: the
//! hybrid adaptive integrator and the strongest `tanh` peer (`diffsol` BDF) at half-decade
//! tolerances `rtol` 1e-2 .. 1e-5 (hybrid) and 1e-2 .. 1e-7 (BDF, gamma 1e3 .. 1e6), plus the
//! hybrid without the largest step [`tolerances`] sets for a sinusoidal input (which the
//! breakaway guards need: they are sampled at the stages only, so that row is not a valid
//! setting, only a measure of what the bound costs).
//!
//! Prints one line per run: RMSE of the compared velocity on the 1 ms grid against the 10 us
//! reference, and the fastest wall time of repeated runs (`time_best`, 0.3 s budget).
//! Run: `cargo run --release -p crane-tools --example workprec_ladder`.

use crane_tools::adaptive_run::{hybrid_adaptive, tolerances};
use crane_tools::cases::Case;
use crane_tools::ode45::Options;
use crane_tools::reference;
use crane_tools::timing::time_best;
use crane_tools::workprec::tanh_bdf;

/// Hybrid tolerances, half-decades.
const HYBRID: [f64; 13] = [
    1e-2, 5e-3, 3e-3, 2e-3, 1e-3, 5e-4, 3e-4, 2e-4, 1e-4, 5e-5, 3e-5, 2e-5, 1e-5,
];
/// BDF tolerances, half-decades.
const BDF: [f64; 11] = [
    1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7,
];

fn main() -> Result<(), crane_tools::error::Error> {
    for case in Case::all() {
        let refr = reference::reference(&case, 1e-3, 100)?;
        println!("== {}", case.name);
        for unbounded in [false, true] {
            for &r in &HYBRID {
                let mut tol = tolerances(&case, r);
                if unbounded {
                    if tol.hmax.is_infinite() {
                        break;
                    }
                    tol.hmax = f64::INFINITY;
                }
                let (t, (tr, st)) = time_best(0.3, || hybrid_adaptive(&case, &tol))?;
                println!(
                    "hybrid{} rtol {r:.0e}: rmse {:.2e} m/s, {:.3} ms, {} steps, {} rejected, {} events, {} evaluations",
                    if unbounded { " (no hmax)" } else { "" },
                    reference::rmse(&case, &tr, &refr),
                    t * 1e3,
                    st.accepted, st.rejected, st.events, st.evals
                );
            }
        }
        for g in [1e3, 1e4, 1e5, 1e6] {
            for &r in &BDF {
                let o = Options {
                    rtol: r,
                    atol: r * 1e-2,
                    hmax: f64::INFINITY,
                };
                let (t, (tr, _)) = time_best(0.3, || tanh_bdf(&case, g, &o))?;
                println!(
                    "tanh({g:.0e} v) BDF rtol {r:.0e}: rmse {:.2e} m/s, {:.3} ms",
                    reference::rmse(&case, &tr, &refr),
                    t * 1e3
                );
            }
        }
    }
    Ok(())
}
