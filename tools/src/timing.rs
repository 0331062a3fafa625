//! Timing a whole run for the work-precision and study tables.

use crate::error::Result;
use std::time::Instant;

/// Runs `f` until `budget` seconds are spent (3 to 50 runs); returns the fastest time and
/// the last result.
pub fn time_best<T>(budget: f64, mut f: impl FnMut() -> Result<T>) -> Result<(f64, T)> {
    let start = Instant::now();
    let mut best = f64::INFINITY;
    let mut runs = 0;
    loop {
        let t0 = Instant::now();
        let r = f()?;
        best = best.min(t0.elapsed().as_secs_f64());
        runs += 1;
        if runs >= 50 || (runs >= 3 && start.elapsed().as_secs_f64() >= budget) {
            return Ok((best, r));
        }
    }
}
