//! The motion mode of a drive axis (also its direction of motion): the hybrid automaton's
//! discrete state per axis. A type of its own, below the friction laws, the dynamics and the
//! guards that all use it.

/// Motion mode of one drive axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Moving towards decreasing coordinate (`qd < 0`; for the rope: hoisting).
    Negative,
    /// At rest: `qd = 0` and `qdd = 0` exactly; friction holds the axis.
    Stopped,
    /// Moving towards increasing coordinate (`qd > 0`; for the rope: lowering).
    Positive,
}

impl Mode {
    /// The mode that an axis moving with velocity `v` is in (0 is `Stopped`).
    pub fn of_velocity(v: f64) -> Mode {
        if v > 0.0 {
            Mode::Positive
        } else if v < 0.0 {
            Mode::Negative
        } else {
            Mode::Stopped
        }
    }
}
