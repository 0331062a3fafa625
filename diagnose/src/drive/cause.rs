//! The causes the single-axis workbench tries, in order (a subset of [`crate::Cause`]).

use crate::Cause;

/// Every cause tried on single-axis open-loop data, in the order they are tried.
pub const DRIVE_CAUSES: [Cause; 10] = [
    Cause::RestoringForce,
    Cause::Stiction,
    Cause::StribeckFriction,
    Cause::DirectionAsymmetry,
    Cause::ForceOffset,
    Cause::InputDeadzone,
    Cause::InputSaturation,
    Cause::InputDelay,
    Cause::LoadDependentFriction,
    Cause::LocalizedFriction,
];
