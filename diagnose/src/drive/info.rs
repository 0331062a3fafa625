//! What a data set says about its axis: motion, units, the input's gain, what the loader did.

use crane_model::drive::Motion;

/// What the data set says about the axis.
#[derive(Clone, Debug, PartialEq)]
pub struct DriveInfo {
    /// Linear or rotary.
    pub motion: Motion,
    /// Position unit (`m` or `rad`).
    pub position_unit: String,
    /// Unit of forces and friction: `N`, `N m`, or the input unit when the gain is unknown.
    pub force_unit: String,
    /// Unit of the recorded input `u` (`V`, `A`, or the effort's own unit).
    pub input_unit: String,
    /// Effort per unit of recorded input [`force_unit` / `input_unit`]: the declared gain, 1
    /// when it is unknown (then every force is in input units). A dead band acts on the input,
    /// so its width is reported in `input_unit` by dividing by this.
    pub effort_per_input: f64,
    /// Start from a symmetric baseline (one kinetic and one viscous coefficient).
    pub symmetric: bool,
    /// What the loader noticed or did to the runs (resampling, held channels), one line
    /// each; reported with the final model's flags.
    pub load_notes: Vec<String>,
}
