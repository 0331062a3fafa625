//! The extensions the crane pipeline fits: one per cause, with its parameters in SI units and
//! how it changes the model.

use crate::Cause;
use crane_model::{Axis, Bump, Direction, Extensions, Params, Stiction};
use std::collections::BTreeMap;

/// A fitted extension.
#[derive(Clone, Debug, PartialEq)]
pub enum Ext {
    /// Localised dry-friction bump.
    Bump {
        /// Centre [m].
        center: f64,
        /// Half-width of the support [m].
        width: f64,
        /// Amplitude [N].
        amplitude: f64,
        /// Directions.
        direction: Direction,
    },
    /// Stribeck stiction.
    Stiction {
        /// Breakaway / sliding.
        ratio: f64,
        /// Stribeck velocity [m/s].
        velocity: f64,
    },
    /// Direction-dependent changes of dry magnitude and viscous coefficient.
    Asymmetry {
        /// Added to `dry_pos[0]` [N].
        dry_pos: f64,
        /// Added to `dry_neg[0]` [N].
        dry_neg: f64,
        /// Added to `viscous_pos` [N s/m].
        viscous_pos: f64,
        /// Added to `viscous_neg` [N s/m].
        viscous_neg: f64,
    },
    /// Constant bias force along the axis [N].
    Offset(f64),
    /// Input dead band [V].
    Deadzone(f64),
    /// Input delay [s].
    Delay(f64),
    /// Payload mass change [kg] (true = declared + this).
    Payload(f64),
}

impl Ext {
    /// Reported cause.
    pub fn cause(&self) -> Cause {
        match self {
            Ext::Bump { .. } => Cause::LocalizedFriction,
            Ext::Stiction { .. } => Cause::Stiction,
            Ext::Asymmetry { .. } => Cause::DirectionAsymmetry,
            Ext::Offset(_) => Cause::ForceOffset,
            Ext::Deadzone(_) => Cause::InputDeadzone,
            Ext::Delay(_) => Cause::InputDelay,
            Ext::Payload(_) => Cause::PayloadMass,
        }
    }

    /// Extra parameters.
    pub fn k(&self) -> usize {
        match self {
            Ext::Bump { .. } => 3,
            Ext::Stiction { .. } => 2,
            Ext::Asymmetry { .. } => 4,
            _ => 1,
        }
    }

    /// SI parameters for the report.
    pub fn parameters(&self) -> BTreeMap<String, f64> {
        let mut m = BTreeMap::new();
        let mut put = |k: &str, v: f64| {
            m.insert(k.to_string(), v);
        };
        match *self {
            Ext::Bump {
                center,
                width,
                amplitude,
                direction,
            } => {
                put("center_m", center);
                put("width_m", width);
                put("amplitude_n", amplitude);
                put(
                    "direction",
                    match direction {
                        Direction::Both => 0.0,
                        Direction::Positive => 1.0,
                        Direction::Negative => -1.0,
                    },
                );
            }
            Ext::Stiction { ratio, velocity } => {
                put("ratio", ratio);
                put("velocity_m_per_s", velocity);
            }
            Ext::Asymmetry {
                dry_pos,
                dry_neg,
                viscous_pos,
                viscous_neg,
            } => {
                put("delta_dry_pos_n", dry_pos);
                put("delta_dry_neg_n", dry_neg);
                put("delta_viscous_pos_n_s_per_m", viscous_pos);
                put("delta_viscous_neg_n_s_per_m", viscous_neg);
            }
            Ext::Offset(b) => put("offset_n", b),
            Ext::Deadzone(d) => put("deadzone_v", d),
            Ext::Delay(d) => put("delay_s", d),
            Ext::Payload(dm) => put("delta_mass_kg", dm),
        }
        m
    }

    /// Applies the extension on drive `axis` to the parameters and model extensions.
    pub fn apply(&self, axis: usize, p: &mut Params, ext: &mut Extensions) {
        let ax = [Axis::X, Axis::Y, Axis::Rope][axis.min(2)];
        match *self {
            Ext::Bump {
                center,
                width,
                amplitude,
                direction,
            } => {
                let _ = ext.bumps.push(Bump {
                    axis: ax,
                    center,
                    width,
                    amplitude,
                    direction,
                });
            }
            Ext::Stiction { ratio, velocity } => {
                ext.stiction[axis] = Some(Stiction {
                    ratio: ratio.max(1.0),
                    velocity: velocity.max(1e-6),
                });
            }
            Ext::Asymmetry {
                dry_pos,
                dry_neg,
                viscous_pos,
                viscous_neg,
            } => {
                let a = match axis {
                    0 => &mut p.x,
                    1 => &mut p.y,
                    _ => &mut p.rope,
                };
                a.dry_pos[0] += dry_pos;
                a.dry_neg[0] += dry_neg;
                a.viscous_pos = (a.viscous_pos + viscous_pos).max(0.0);
                a.viscous_neg = (a.viscous_neg + viscous_neg).max(0.0);
            }
            Ext::Offset(b) => ext.force_offset[axis] += b,
            Ext::Deadzone(d) => ext.deadzone[axis] = d.max(0.0),
            Ext::Delay(d) => ext.delay[axis] = d.max(0.0),
            Ext::Payload(dm) => p.payload_mass = (p.payload_mass + dm).max(1e-3),
        }
    }
}
