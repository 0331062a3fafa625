//! Helpers shared by the diagnosis integration tests (`mod support;` in each).

use crane_diagnose::Report;
use crane_ident::rng::Rng;
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

/// Trapezoidal pulses of alternating sign (or one sign when `one_sign`), amplitudes uniform in
/// `[lo, hi]`, `dur` long each (10 % ramps), with `rest` of zero input after each and 0.2 s
/// of it first; plus a constant `bias`.
#[allow(clippy::too_many_arguments)]
pub fn pulses(
    rng: &mut Rng,
    dt: f64,
    n: usize,
    lo: f64,
    hi: f64,
    dur: f64,
    rest: f64,
    bias: f64,
    one_sign: bool,
) -> Vec<f64> {
    let mut u = vec![bias; (0.2 / dt) as usize];
    for k in 0..n {
        let a = rng.range(lo, hi) * if one_sign || k % 2 == 0 { 1.0 } else { -1.0 };
        let m = (dur / dt).round() as usize;
        let r = (0.1 * m as f64).max(1.0) as usize;
        for i in 0..m {
            let s = if i < r {
                i as f64 / r as f64
            } else if i + r > m {
                (m - i) as f64 / r as f64
            } else {
                1.0
            };
            u.push(bias + a * s);
        }
        u.extend(std::iter::repeat_n(bias, (rest / dt) as usize));
    }
    u
}
