//! The single-axis workbench: what a hybrid model of one drive gets wrong in measured runs,
//! the cause, and the gain proved by simulating held-out runs.
//!
//! The pipeline, [`pipeline::diagnose_drive`], in stages (one file each):
//! 1. [`prep`]: runs on a uniform grid, Savitzky-Golay velocity and acceleration over a window
//!    chosen from the data's noise, motion thresholds from the data (relative to the fastest
//!    motion, floored at the encoder step); `checks` refuses runs that cannot be diagnosed
//!    (no fitting motion, a direction only held out, a reversed sign), saying what to change.
//! 2. [`estimate`]: one estimator for every model structure (sliding least squares with
//!    physical bounds, breakaway at first motion, breakaway >= kinetic); [`refine`] tunes a
//!    baseline by output error; [`experiment`] fits and scores a structure on the runs.
//! 3. [`score`]: every structure is simulated from the recorded input with the hybrid
//!    single-axis model (`crane_ident::simulate`) and scored by the position NMAE of the
//!    held-out runs. A simulation that leaves the measured range tenfold is "diverged", never
//!    a figure. [`floor`]: what a right model leaves on this log (the encoder's count, and
//!    the baseline's own replayed log).
//! 4. [`select`]: forward selection of the [`cause::DRIVE_CAUSES`]: a cause is kept when it cuts the
//!    held-out simulated NMAE by at least [`select::MIN_GAIN`] and its parameters are physical
//!    (`physical`). [`trial`] fits one cause; the dead band, saturation, load share and delay
//!    are searched on grids ([`grid`]), the bump's site from the residual ([`local`]); a value
//!    at a grid's edge is never named.
//! 5. `verdict`: the final model and the verdict (`none` only within the data's own floors).
//! 6. `report`: the report (`evidence`: a finding's parameters and force residual; [`info`]:
//!    what the data set says about the axis), and [`plots`]: measured vs simulated runs, residuals, stick/slip
//!    marks, force vs velocity.

pub mod breakaway;
pub mod cause;
mod checks;
pub mod estimate;
mod evidence;
pub mod experiment;
pub mod floor;
pub mod grid;
pub mod info;
pub mod local;
mod physical;
pub mod pipeline;
pub mod plots;
pub mod prep;
pub mod refine;
mod report;
pub mod score;
pub mod select;
pub mod trial;
mod verdict;

pub use cause::DRIVE_CAUSES;
pub use estimate::{Dir, Estimate, Flag, Structure};
pub use info::DriveInfo;
pub use pipeline::diagnose_drive;
pub use prep::{DriveRun, Prepared, Thresholds};
