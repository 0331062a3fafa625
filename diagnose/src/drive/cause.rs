//! The candidate causes of a single-axis discrepancy, as a type.

use serde::{Deserialize, Serialize};
use std::fmt;

/// A hidden effect the single-axis workbench can name. Each adds parameters to the baseline
/// (Coulomb + viscous friction per direction, breakaway at first motion, no position force).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DriveCause {
    /// A position-dependent restoring force (gravity on a joint, a spring, a cable):
    /// `stiffness`, `center`.
    RestoringForce,
    /// Breakaway above the sliding friction (static > kinetic): `breakaway_pos`,
    /// `breakaway_neg`, `ratio_pos`, `ratio_neg`.
    Stiction,
    /// Direction-dependent kinetic and viscous friction (only against a symmetric baseline).
    DirectionAsymmetry,
    /// A constant force on the axis: `offset`.
    ForceOffset,
    /// An input dead band: `deadband` [input units].
    InputDeadzone,
    /// An input delay: `delay_s` [s].
    InputDelay,
}

impl DriveCause {
    /// Every cause, in the order they are tried.
    pub const ALL: [DriveCause; 6] = [
        DriveCause::RestoringForce,
        DriveCause::Stiction,
        DriveCause::DirectionAsymmetry,
        DriveCause::ForceOffset,
        DriveCause::InputDeadzone,
        DriveCause::InputDelay,
    ];

    /// The report name.
    pub fn as_str(self) -> &'static str {
        match self {
            DriveCause::RestoringForce => "restoring_force",
            DriveCause::Stiction => "stiction",
            DriveCause::DirectionAsymmetry => "direction_asymmetry",
            DriveCause::ForceOffset => "force_offset",
            DriveCause::InputDeadzone => "input_deadzone",
            DriveCause::InputDelay => "input_delay",
        }
    }
}

impl fmt::Display for DriveCause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}
