//! Whether a cause's fitted parameters are physical, whether it can be told apart from the
//! rest of the dry friction, and the accessors of the position force and the bump they read.

use super::estimate::{Dir, Estimate};
use crate::Cause;
use crane_model::drive::PositionForce;

/// How closely a delay is placed [samples]: to about one sample (whole samples on the grid
/// at short delays; the fraction refined after them moves with the inertia's error, which it
/// trades against). A delay within this of the log's own timing uncertainty is not told
/// apart from it ([`delay_resolved`]).
pub const DELAY_RESOLUTION: f64 = 1.0;

/// Whether a delay of `delay` samples lies beyond the log's own timing uncertainty `timing`
/// [samples] (see [`super::select::Context::timing`]) by more than [`DELAY_RESOLUTION`]. A
/// delay at the uncertainty is what the log's timing alone produces: on the independent
/// plant (`tools/strangers`, seed 11, case s069: a force offset, a log whose position and
/// input are refreshed every 3 rows) a delay of 3.00001 samples was named, with the
/// uncertainty 3.
pub(super) fn delay_resolved(delay: f64, timing: usize) -> bool {
    delay > timing as f64 + DELAY_RESOLUTION
}

/// Whether a cause's fitted parameters are physical; otherwise why not. `timing`: the log's
/// own timing uncertainty [samples] (see [`super::select::Context::timing`]).
pub(super) fn physical(
    cause: Cause,
    est: &Estimate,
    before: &Estimate,
    umax: f64,
    timing: usize,
) -> (bool, Option<String>) {
    let p = &est.params;
    match cause {
        Cause::RestoringForce => {
            let k = stiffness(&p.position_force);
            if k > 0.0 {
                (true, None)
            } else {
                (
                    false,
                    Some("restoring_force: the fitted stiffness is 0 (no restoring force in the sliding phases)".into()),
                )
            }
        }
        Cause::Stiction | Cause::StribeckFriction => stiction(cause, est),
        Cause::DirectionAsymmetry => (true, None),
        Cause::ForceOffset if est.structure.asymmetric => {
            // With a dry level per direction a constant force o is exactly those levels
            // shifted, moving or at rest: F = u + o against Fk+ / Fs+ is u against Fk+ - o /
            // Fs+ - o, and against Fk- / Fs- it is u against Fk- + o / Fs- + o. The offset-free
            // model with the shifted levels simulates every run identically, so the offset is
            // identifiable only where that model does not exist: a shifted level below 0, the
            // load alone moving the axis. (A fitted offset that simulates better than the
            // baseline then says the baseline's estimate of the levels, inertia or viscous
            // friction moved, not that a load was found: on the CICESE joint-1 ramps such an
            // offset came and went with the sample rate.)
            let (pos, neg) = (p.kinetic_pos - p.offset, p.kinetic_neg + p.offset);
            if !p.offset.is_finite() {
                (false, None)
            } else if pos >= 0.0 && neg >= 0.0 {
                (
                    false,
                    Some(format!(
                        "force_offset not named: not identifiable with a dry level per direction; the fitted constant force {:.4} is exactly the levels shifted (kinetic +: {:.4} -> {pos:.4}, -: {:.4} -> {neg:.4}, both still >= 0), which simulate every run the same; a load would be identifiable only if it exceeded a level (the load alone moving the axis)",
                        p.offset, p.kinetic_pos, p.kinetic_neg
                    )),
                )
            } else {
                (true, None)
            }
        }
        Cause::ForceOffset => (p.offset.is_finite(), None),
        Cause::InputDeadzone => (est.structure.deadband > before.structure.deadband, None),
        Cause::InputDelay if !delay_resolved(est.structure.delay, timing) => (
            false,
            Some(format!(
                "input_delay: {:.2} sample(s) is within a sample of the log's own timing uncertainty ({timing}: the zero-order hold's sample, and the rows between fresh positions): the recorded input and position cannot place a delay that short",
                est.structure.delay
            )),
        ),
        Cause::InputDelay => (true, None),
        Cause::LoadDependentFriction => {
            let mu = p.load_friction;
            if mu > 0.0 && mu < 1.0 {
                (true, None)
            } else {
                (
                    false,
                    Some(format!(
                        "load_dependent_friction: the fitted load share {mu:.4} is not between 0 and 1 (0: the dry friction does not grow with the drive effort; 1 or more: it would grow faster than the effort, and the axis could never be driven)"
                    )),
                )
            }
        }
        Cause::InputSaturation => saturation(est, umax),
        Cause::LocalizedFriction => {
            let a = bump_amplitude(p);
            let lowest = p.kinetic_pos.min(p.kinetic_neg);
            if a > 0.0 || (a < 0.0 && lowest + a >= 0.0) {
                (true, None)
            } else {
                (
                    false,
                    Some(format!(
                        "localized_friction: the fitted amplitude {a:.4} is no bump (0, or a dip deeper than the sliding friction {lowest:.4})"
                    )),
                )
            }
        }
        // a crane-only cause is never tried on a drive
        Cause::PayloadMass => (false, None),
    }
}

/// Stiction, or velocity-weakening friction (`cause`), is named only when the mean gap between
/// the onset level of the slips and their sliding friction exceeds the run-to-run scatter of
/// the breakaway levels, over a sliding friction above 0.
fn stiction(cause: Cause, est: &Estimate) -> (bool, Option<String>) {
    let p = &est.params;
    // named only when the mean gap between the onset level of the slips and their
    // sliding friction exceeds the run-to-run scatter of the breakaway levels
    let mut named = false;
    let mut why = Vec::new();
    for (d, dir) in Dir::BOTH.iter().enumerate() {
        let g = &est.slip_gaps[d];
        if g.is_empty() {
            why.push(format!(
                "{dir}: no slip from rest to rest in the fitting runs"
            ));
            continue;
        }
        let gap = g.iter().sum::<f64>() / g.len() as f64;
        match est.breakaway_scatter[d] {
            Some(sc) if gap > sc => named = true,
            Some(sc) => why.push(format!(
                "{dir}: slips start {gap:.4} above their sliding friction ({} slips), within the scatter {sc:.4} of the breakaway levels",
                g.len()
            )),
            None => why.push(format!(
                "{dir}: one onset only, the scatter of the breakaway levels is unknown"
            )),
        }
    }
    if named && !(p.kinetic_pos > 0.0 && p.kinetic_neg > 0.0) {
        // a breakaway over a sliding friction of 0 is no ratio: the sliding level
        // went to its bound (the input effect or load it stands in for is elsewhere)
        (
            false,
            Some(format!(
                "{cause} not named: the sliding friction is at 0 (+{:.4} / -{:.4}), so static over kinetic friction is undefined",
                p.kinetic_pos, p.kinetic_neg
            )),
        )
    } else if named {
        (true, None)
    } else {
        (
            false,
            Some(format!(
                "{cause} not named: static and kinetic friction are equal within the run-to-run scatter ({})",
                why.join("; ")
            )),
        )
    }
}

/// A saturation level is physical between the dry friction (plus the scatter of the
/// breakaway levels) and the largest |input| `umax` of the fitting runs.
fn saturation(est: &Estimate, umax: f64) -> (bool, Option<String>) {
    let p = &est.params;
    let sat = est.structure.saturation;
    // the level must stand clear of the dry friction: within the run-to-run scatter
    // of the breakaway levels above them, a clamped effort leaves a net force that is
    // the dry level's own noise while the axis slides, and the level trades against
    // the friction (resampled CICESE joint-1 ramps: 13.16 N m against a breakaway of
    // 12.69, stiffness 49 -> 16 N m/rad)
    let dry = (0..2)
        .map(|d| [p.breakaway_pos, p.breakaway_neg][d] + est.breakaway_scatter[d].unwrap_or(0.0))
        .fold(0.0f64, f64::max);
    if sat > 0.0 && sat < umax && sat > dry {
        (true, None)
    } else if sat > 0.0 && sat < umax {
        (
            false,
            Some(format!(
                "input_saturation not named: the fitted level {sat:.4} lies within the run-to-run scatter above the breakaway levels ({:.4} / {:.4}, scatter {:.4} / {:.4}): while the axis slides a clamped effort there is not separable from the dry friction level",
                p.breakaway_pos,
                p.breakaway_neg,
                est.breakaway_scatter[0].unwrap_or(0.0),
                est.breakaway_scatter[1].unwrap_or(0.0)
            )),
        )
    } else {
        (
            false,
            Some(format!(
                "input_saturation: the fitted level {sat:.4} is not between 0 and the largest |input| {umax:.4} of the fitting runs (it would clip nothing)"
            )),
        )
    }
}

/// Whether a named cause can be told apart from the other dry-friction structure, and the
/// note saying why not. While the axis slides, a constant load `o` (gravity on a vertical
/// axis, a cable's pull) and direction-dependent dry friction are the same force:
/// `Fk+ sign(v) + o` is `Fk+ - (-o)` moving positive and `-(Fk- - o)` moving negative, so
/// sliding data fix only the two dry levels, not how they split into a load and a friction
/// asymmetry; at rest the two differ only if the load alone moves the axis (it exceeds the
/// breakaway), or on data with a known load change. The closed-loop path states the same
/// (`axis/select.rs`).
///
/// With a dry level per direction already in the model, an offset is named only when it
/// exceeds one of them ([`physical`]): then no shift of the levels reproduces it, and it is
/// identifiable.
pub(super) fn load_overlap(cause: Cause, est: &Estimate) -> (bool, Option<&'static str>) {
    match cause {
        Cause::ForceOffset if est.structure.asymmetric => (
            true,
            Some("identifiable apart from direction-dependent dry friction: the constant load exceeds the dry level of one direction (the load alone moves the axis), which no shift of the two levels (Fk+ by -o, Fk- by +o) reproduces"),
        ),
        Cause::ForceOffset => (
            false,
            Some("not identifiable apart from direction-dependent dry friction: while sliding, a constant load o is exactly the dry levels shifted (Fk+ by -o, Fk- by +o); sliding data fix the two levels, not their split into a load and an asymmetry (runs where the load alone moves the axis, or with a known load change, would)"),
        ),
        Cause::DirectionAsymmetry => (
            true,
            Some("the dry part of the asymmetry overlaps a constant load (force offset, e.g. gravity on a vertical axis): sliding data cannot split the two; the viscous part does not overlap"),
        ),
        _ => (true, None),
    }
}

/// The stiffness of a position force (0 without one) [force units per m or rad].
pub(super) fn stiffness(f: &PositionForce) -> f64 {
    match *f {
        PositionForce::None => 0.0,
        PositionForce::Spring { stiffness, .. } | PositionForce::Pendulum { stiffness, .. } => {
            stiffness
        }
    }
}

/// The centre of a position force (0 without one) [m or rad].
pub(super) fn center_of(f: &PositionForce) -> f64 {
    match *f {
        PositionForce::None => 0.0,
        PositionForce::Spring { center, .. } | PositionForce::Pendulum { center, .. } => center,
    }
}

/// The amplitude of a model's friction bump (0 without one) [force units].
pub(super) fn bump_amplitude(p: &crane_model::drive::DriveParams) -> f64 {
    match p.local_friction {
        crane_model::drive::LocalFriction::Bump { amplitude, .. } => amplitude,
        crane_model::drive::LocalFriction::None => 0.0,
    }
}
