//! Helpers shared by the diagnosis integration tests (`mod support;` in each).

use crane_diagnose::Report;
use std::fmt::Write as _;

/// A report's held-out position NMAE (baseline -> final, [%]) and its final model's
/// parameters on one line, for the tables the tests print: `; held-out NMAE a -> b %; J ..
/// Fk +/- Fs +/- D +/- k off db delay` (units of the data set).
pub fn model_line(r: &Report) -> String {
    let mut s = String::new();
    if let Some(h) = &r.heldout_simulation {
        let _ = write!(
            s,
            "; held-out NMAE {:.2} -> {:.2} %",
            h.nmae_before, h.nmae_after
        );
    }
    if let Some(m) = &r.final_model {
        let _ = write!(
            s,
            "; J {:.3e} Fk {:.3e}/{:.3e} Fs {:.3e}/{:.3e} D {:.3e}/{:.3e} k {:.3e} off {:.3e} db {:.3e} delay {}",
            m.inertia,
            m.kinetic_pos,
            m.kinetic_neg,
            m.breakaway_pos,
            m.breakaway_neg,
            m.viscous_pos,
            m.viscous_neg,
            m.stiffness,
            m.offset,
            m.deadband,
            m.delay_samples
        );
    }
    s
}
