//! What a finding reports besides its held-out error: the cause's parameters in the data
//! set's units, how many it adds, and the inverse-dynamics force residual on the sliding
//! samples (the selection and the report both read them).

use super::estimate::Estimate;
use super::info::DriveInfo;
use super::physical::{center_of, stiffness};
use super::prep::{Prepared, Thresholds};
use crate::Cause;
use std::collections::BTreeMap;

/// The parameters a cause adds to the model.
pub(super) fn extra_parameters(cause: Cause) -> usize {
    match cause {
        Cause::RestoringForce => 1,
        Cause::Stiction => 2,
        Cause::DirectionAsymmetry => 2,
        Cause::ForceOffset => 1,
        Cause::InputDeadzone => 1,
        Cause::InputDelay => 1,
        Cause::InputSaturation => 1,
        Cause::LocalizedFriction => 3,
        Cause::PayloadMass => 1,
        Cause::LoadDependentFriction => 1,
        Cause::StribeckFriction => 3,
    }
}

/// A cause's parameters for the report; `dt` is the fitting runs' sample period [s]. Forces
/// are in `info.force_unit`; the dead band, which acts on the input, is in `info.input_unit`
/// (`deadband`) and as the effort it withholds (`deadband_effort`, `info.force_unit`).
pub(super) fn cause_parameters(
    cause: Cause,
    est: &Estimate,
    dt: f64,
    info: &DriveInfo,
) -> BTreeMap<String, f64> {
    let p = &est.params;
    let mut m = BTreeMap::new();
    let ratio = |b: f64, k: f64| if k > 0.0 { b / k } else { 0.0 };
    match cause {
        Cause::RestoringForce => {
            m.insert("stiffness".into(), stiffness(&p.position_force));
            m.insert("center".into(), center_of(&p.position_force));
        }
        Cause::Stiction => {
            m.insert("breakaway_pos".into(), p.breakaway_pos);
            m.insert("breakaway_neg".into(), p.breakaway_neg);
            m.insert("ratio_pos".into(), ratio(p.breakaway_pos, p.kinetic_pos));
            m.insert("ratio_neg".into(), ratio(p.breakaway_neg, p.kinetic_neg));
        }
        Cause::DirectionAsymmetry => {
            m.insert("kinetic_pos".into(), p.kinetic_pos);
            m.insert("kinetic_neg".into(), p.kinetic_neg);
            m.insert("viscous_pos".into(), p.viscous_pos);
            m.insert("viscous_neg".into(), p.viscous_neg);
        }
        Cause::ForceOffset => {
            m.insert("offset".into(), p.offset);
        }
        Cause::InputDeadzone => {
            m.insert(
                "deadband".into(),
                est.structure.deadband / info.effort_per_input,
            );
            m.insert("deadband_effort".into(), est.structure.deadband);
        }
        Cause::InputDelay => {
            m.insert("delay_s".into(), est.structure.delay * dt);
            m.insert("delay_samples".into(), est.structure.delay);
        }
        Cause::InputSaturation => {
            m.insert("saturation".into(), est.structure.saturation);
        }
        Cause::LoadDependentFriction => {
            m.insert("mu".into(), p.load_friction);
        }
        Cause::StribeckFriction => {
            m.insert("static_pos".into(), p.breakaway_pos);
            m.insert("static_neg".into(), p.breakaway_neg);
            m.insert("sliding_pos".into(), p.kinetic_pos);
            m.insert("sliding_neg".into(), p.kinetic_neg);
            m.insert("stribeck_velocity".into(), p.stribeck_velocity);
        }
        Cause::LocalizedFriction => {
            if let crane_model::drive::LocalFriction::Bump {
                center,
                half_width,
                amplitude,
            } = p.local_friction
            {
                m.insert("center_m".into(), center);
                m.insert("width_m".into(), half_width);
                m.insert("amplitude_n".into(), amplitude);
            }
        }
        Cause::PayloadMass => {}
    }
    m
}

/// Inverse-dynamics residual of a fitted model on the sliding samples [force units]:
/// `F - J a - position_force(x) - friction(v)`.
fn residuals(est: &Estimate, runs: &[&Prepared], th: &Thresholds) -> (f64, f64, usize) {
    let p = &est.params;
    let s = &est.structure;
    let (mut sse, mut ssf, mut n) = (0.0, 0.0, 0usize);
    for r in runs {
        for i in 0..r.run.x.len() {
            let v = r.v[i];
            if v.abs() <= th.v_slide {
                continue;
            }
            let f = super::estimate::applied_input(&r.run.u, i, s) + p.offset;
            let pos = stiffness(&p.position_force)
                * super::estimate::restoring_shape(
                    p.motion,
                    r.run.x[i],
                    center_of(&p.position_force),
                );
            let fr = if v > 0.0 {
                p.kinetic_pos + p.viscous_pos * v
            } else {
                -p.kinetic_neg + p.viscous_neg * v
            };
            let e = f - p.inertia * r.a[i] - pos - fr;
            sse += e * e;
            ssf += f * f;
            n += 1;
        }
    }
    (sse, ssf, n)
}

/// RMS inverse-dynamics residual on the sliding samples [force units].
pub(super) fn force_rms(est: &Estimate, runs: &[&Prepared], th: &Thresholds) -> f64 {
    let (sse, _, n) = residuals(est, runs, th);
    if n == 0 {
        0.0
    } else {
        (sse / n as f64).sqrt()
    }
}

/// The residual relative to the applied force on the sliding samples [%].
pub(super) fn force_rel(est: &Estimate, runs: &[&Prepared], th: &Thresholds) -> f64 {
    let (sse, ssf, n) = residuals(est, runs, th);
    if n == 0 || ssf <= 0.0 {
        0.0
    } else {
        100.0 * (sse / ssf).sqrt()
    }
}
