//! The single-axis workbench: what a hybrid model of one drive gets wrong in measured runs,
//! the cause, and the gain proved by simulating held-out runs.
//!
//! Stages (one file each):
//! 1. [`prep`]: runs on a uniform grid, Savitzky-Golay velocity and acceleration over a window
//!    chosen from the data's noise, motion thresholds from the data (relative to the fastest
//!    motion, floored at the encoder step).
//! 2. [`estimate`]: one estimator for every model structure (sliding least squares with
//!    physical bounds, breakaway at first motion, breakaway >= kinetic).
//! 3. [`score`]: every structure is simulated from the recorded input with the hybrid
//!    single-axis model (`crane_ident::simulate`) and scored by the position NMAE of the
//!    held-out runs.
//!    A simulation that leaves the measured range tenfold is "diverged", never a figure.
//! 4. [`select`]: forward selection of the [`cause::DRIVE_CAUSES`]: a cause is kept when it cuts the
//!    held-out simulated NMAE by at least [`select::MIN_GAIN`] and its parameters are physical.
//!    The dead band, saturation and delay are searched on grids ([`grid`]); a value at a
//!    grid's edge is never named.
//! 5. [`plots`]: measured vs simulated runs, residuals, stick/slip marks, force vs velocity.

pub mod cause;
pub mod estimate;
pub mod experiment;
pub mod floor;
pub mod grid;
pub mod local;
pub mod plots;
pub mod prep;
pub mod refine;
pub mod score;
pub mod select;

pub use cause::DRIVE_CAUSES;
pub use estimate::{Dir, Estimate, Flag, Structure};
pub use prep::{DriveRun, Prepared, Thresholds};
pub use select::{diagnose_drive, DriveInfo};
