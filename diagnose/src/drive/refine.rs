//! Output-error refinement of a fitted model: its inertia, viscous and dry friction tuned so
//! that it simulates the fitting runs best, its structure and other parameters kept.
//!
//! The least squares of [`super::estimate`] regress the recorded input on accelerations and
//! velocities differentiated from the positions. Where the encoder count is coarse against
//! the motion, or the derivative window long, those derivatives are smoothed and quantised,
//! and the inertia, viscous and dry levels come out biased (a 1 mm count at 1 kHz: inertia
//! 0.536 against 0.5, viscous 1.9 / 2.3 against 2.0): the model then drifts in simulation
//! although its structure is right. Minimising the simulated error itself (output error, the
//! usual last step of an identification) removes that bias without any derivative.
//!
//! Used by the selection (`select.rs`): a first cause must cut the held-out error of the
//! refined baseline when refined the same way (else it stands in for the least squares'
//! bias), and above the `none` level, with no cause named, the refined baseline is the final
//! model.
//! Fitting runs only: the held-out runs score the result, they never steer it.
//!
//! Work: [`SWEEPS`] x (parameters tuned, at most 5) x ([`STEPS`] + 2) simulations of the
//! fitting runs (140 for a direction-dependent model with friction both ways), and as many
//! again per further sweep (at most [`MAX_WIDEN`]) while a parameter sits at the edge of its
//! range.

use super::estimate::Estimate;

/// Golden-section steps per parameter and sweep (the bracket shrinks to 0.618^12 = 0.3 % of
/// its width: a factor of 1.003 on the parameter).
pub const STEPS: usize = 12;
/// Sweeps over the parameters (the inertia and the viscous coefficients trade against each
/// other a little; a second sweep settles them).
pub const SWEEPS: usize = 2;
/// Each parameter is searched within this factor of its least-squares value, both ways, at
/// first; one whose best value reaches that edge gets its range widened by this factor again
/// on the next sweep (a best value at the edge of what was tried is no result: the
/// derivative-based least squares can be further off than this, as on asynchronous logs
/// whose held positions made the inertia 4-9 times low).
pub const RANGE: f64 = 1.6;
/// Further sweeps while a parameter's best value sits at the edge of its widened range: the
/// range grows to at most `RANGE^(1 + MAX_WIDEN)` (about 17 for 1.6 and 5) of the least-squares
/// value.
pub const MAX_WIDEN: usize = 5;

/// A parameter the refinement tunes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Tuned {
    /// The inertia.
    Inertia,
    /// Both viscous coefficients by one factor (a symmetric model, or one direction unseen).
    Viscous,
    /// The viscous coefficient for positive velocity.
    ViscousPos,
    /// The viscous coefficient for negative velocity.
    ViscousNeg,
    /// The dry friction moving positive (kinetic and breakaway levels by one factor).
    DryPos,
    /// The dry friction moving negative (kinetic and breakaway levels by one factor).
    DryNeg,
}

/// `est` with parameter `p` multiplied by `factor`.
fn scaled(est: &Estimate, p: Tuned, factor: f64) -> Estimate {
    let mut e = est.clone();
    let q = &mut e.params;
    match p {
        Tuned::Inertia => q.inertia *= factor,
        Tuned::Viscous => {
            q.viscous_pos *= factor;
            q.viscous_neg *= factor;
        }
        Tuned::ViscousPos => q.viscous_pos *= factor,
        Tuned::ViscousNeg => q.viscous_neg *= factor,
        Tuned::DryPos => {
            q.kinetic_pos *= factor;
            q.breakaway_pos *= factor;
        }
        Tuned::DryNeg => {
            q.kinetic_neg *= factor;
            q.breakaway_neg *= factor;
        }
    }
    e
}

/// The model of `est`'s structure whose inertia, viscous coefficients and dry levels per
/// direction (kinetic and breakaway by one factor; each within a factor [`RANGE`] of its value
/// in `est`, widened by [`RANGE`] on each further sweep, at most [`MAX_WIDEN`] times, while its
/// best value sits at the edge; zero values left at zero) minimise `fit_error` (the fitting runs' mean simulated
/// NMAE [%]), by golden-section search on the logarithm of each in turn, and that error.
/// `None` when no tuned model simulates the fitting runs better than `est` (or `est` itself
/// does not simulate).
pub fn refine(est: &Estimate, fit_error: &dyn Fn(&Estimate) -> f64) -> Option<(Estimate, f64)> {
    let start = fit_error(est);
    if !start.is_finite() {
        return None;
    }
    let p = &est.params;
    let mut tuned = vec![Tuned::Inertia];
    match (p.viscous_pos > 0.0, p.viscous_neg > 0.0) {
        (true, true) if p.viscous_pos == p.viscous_neg => tuned.push(Tuned::Viscous),
        (pos, neg) => {
            if pos {
                tuned.push(Tuned::ViscousPos);
            }
            if neg {
                tuned.push(Tuned::ViscousNeg);
            }
        }
    }
    for (t, level) in [
        (Tuned::DryPos, p.breakaway_pos),
        (Tuned::DryNeg, p.breakaway_neg),
    ] {
        if level > 0.0 {
            tuned.push(t);
        }
    }
    let (mut best, mut err) = (est.clone(), start);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    // the log-factor each parameter has moved by so far, and how far it may move: the search
    // stays within `limit` (at first RANGE) of `est`
    let mut moved: Vec<f64> = vec![0.0; tuned.len()];
    let mut limit = vec![RANGE.ln(); tuned.len()];
    for sweep in 0..SWEEPS + MAX_WIDEN {
        if sweep >= SWEEPS {
            // widen the range of each parameter whose best value reached its edge (within a
            // golden-section step's resolution), and stop when none did
            let mut any = false;
            for (m, l) in moved.iter().zip(limit.iter_mut()) {
                if f64::abs(*m) >= *l - 0.01 {
                    *l += RANGE.ln();
                    any = true;
                }
            }
            if !any {
                break;
            }
        }
        for ((&t, moved), &limit) in tuned.iter().zip(moved.iter_mut()).zip(limit.iter()) {
            let f = |x: f64| {
                let e = scaled(&best, t, x.exp());
                let v = fit_error(&e);
                (if v.is_finite() { v } else { f64::INFINITY }, e, x)
            };
            let (mut a, mut b) = (-limit - *moved, limit - *moved);
            let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
            let (mut p1, mut p2) = (f(x1), f(x2));
            // the best point met (error, model, log-factor), if better than the current model
            let mut found: Option<(f64, Estimate, f64)> = None;
            let mut keep = |p: &(f64, Estimate, f64)| {
                if p.0 < err && found.as_ref().is_none_or(|q| p.0 < q.0) {
                    found = Some(p.clone());
                }
            };
            keep(&p1);
            keep(&p2);
            for _ in 0..STEPS {
                if p1.0 <= p2.0 {
                    b = x2;
                    (x2, p2) = (x1, p1);
                    x1 = b - g * (b - a);
                    p1 = f(x1);
                    keep(&p1);
                } else {
                    a = x1;
                    (x1, p1) = (x2, p2);
                    x2 = a + g * (b - a);
                    p2 = f(x2);
                    keep(&p2);
                }
            }
            if let Some((v, e, x)) = found {
                best = e;
                err = v;
                *moved += x;
            }
        }
    }
    (err < start).then_some((best, err))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drive::estimate::{DryLevel, Structure};
    use crane_model::drive::DriveParams;

    fn estimate(inertia: f64, viscous: [f64; 2], dry: [f64; 2]) -> Estimate {
        Estimate {
            params: DriveParams {
                inertia,
                viscous_pos: viscous[0],
                viscous_neg: viscous[1],
                kinetic_pos: dry[0],
                kinetic_neg: dry[1],
                breakaway_pos: dry[0],
                breakaway_neg: dry[1],
                ..DriveParams::default()
            },
            structure: Structure {
                restoring: false,
                stiction: false,
                asymmetric: true,
                offset: false,
                deadband: 0.0,
                delay: 0.0,
                saturation: 0.0,
                load: 0.0,
                bump: None,
                stribeck: 0.0,
            },
            flags: Vec::new(),
            first_motion: [Vec::new(), Vec::new()],
            breakaway_scatter: [None, None],
            kinetic_ls: dry,
            slip_gaps: [Vec::new(), Vec::new()],
            rows: 100,
            level: DryLevel::FirstMotion,
        }
    }

    /// A stand-in for the fitting runs' simulated error, smallest at the truth (J 0.5, D 2 /
    /// 3, dry 3 / 4) and coupled between the parameters as a simulation couples them.
    fn error(e: &Estimate) -> f64 {
        let p = &e.params;
        let (j, dp, dn) = (
            (p.inertia / 0.5).ln(),
            (p.viscous_pos / 2.0).ln(),
            (p.viscous_neg / 3.0).ln(),
        );
        let (fp, fn_) = ((p.kinetic_pos / 3.0).ln(), (p.kinetic_neg / 4.0).ln());
        1.0 + (j + 0.3 * dp).powi(2) + dp * dp + dn * dn + (fp - 0.2 * j).powi(2) + fn_ * fn_
    }

    #[test]
    fn biased_parameters_are_pulled_to_the_simulation_optimum() {
        // the least squares' bias: inertia 7 % high, viscous 5 % / 24 % off, dry 10 % low
        let start = estimate(0.536, [1.9, 2.28], [2.7, 4.0]);
        let (e, err) = refine(&start, &error).expect("improves");
        let p = &e.params;
        assert!(err < error(&start));
        assert!((p.inertia / 0.5 - 1.0).abs() < 0.01, "J {}", p.inertia);
        assert!(
            (p.viscous_pos / 2.0 - 1.0).abs() < 0.02,
            "D+ {}",
            p.viscous_pos
        );
        assert!(
            (p.viscous_neg / 3.0 - 1.0).abs() < 0.02,
            "D- {}",
            p.viscous_neg
        );
        assert!(
            (p.kinetic_pos / 3.0 - 1.0).abs() < 0.02,
            "Fk+ {}",
            p.kinetic_pos
        );
        // the breakaway moves with the kinetic level (no stiction is invented)
        assert_eq!(p.kinetic_pos, p.breakaway_pos);
        // the structure and what is not tuned stay
        assert_eq!(e.structure, start.structure);
        assert_eq!(p.offset, start.params.offset);
    }

    #[test]
    fn an_optimal_or_unsimulated_model_is_left_alone() {
        assert!(refine(&estimate(0.5, [2.0, 3.0], [3.0, 4.0]), &error).is_none());
        assert!(refine(&estimate(0.536, [1.9, 2.28], [2.7, 4.0]), &|_| f64::NAN).is_none());
    }

    #[test]
    fn the_range_widens_while_the_best_value_sits_at_its_edge() {
        // the optimum lies 3x away (beyond RANGE): the range widens until it is reached (to the
        // golden-section resolution of the widened bracket and the coupling, 3 %)
        let (e, _) = refine(&estimate(1.5, [2.0, 3.0], [3.0, 4.0]), &error).expect("improves");
        assert!(
            (e.params.inertia / 0.5 - 1.0).abs() < 0.03,
            "{}",
            e.params.inertia
        );
        // but never beyond RANGE^(1 + MAX_WIDEN) of the least-squares value: an optimum 100x
        // away stops at that bound
        let (e, _) = refine(&estimate(50.0, [2.0, 3.0], [3.0, 4.0]), &error).expect("improves");
        let bound = 50.0 / RANGE.powi(1 + MAX_WIDEN as i32);
        assert!(
            e.params.inertia >= bound * 0.999 && e.params.inertia < bound * 1.05,
            "{} (bound {bound})",
            e.params.inertia
        );
    }
}
