//! What the friction monitor reports, and the debounce that decides when it does.
//!
//! An alarm is raised once when its condition has held in [`Debounce::CONFIRM`] consecutive
//! evaluations that each saw fresh data, and it stands (it is not raised again) until the
//! condition has been clear in [`Debounce::RELEASE`] consecutive ones. While an alarm of an axis and
//! direction stands, that map's reference stops tracking slow changes, so a fault is never
//! learned as the new normal.

use crane_model::{Axis, Direction};

/// Kind of change, with its size. Forces are in N along the motion (positive: more friction
/// than the reference), positions in m along the axis.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AlarmKind {
    /// The sliding friction over the whole travel moved from its reference by `change` [N].
    FrictionDrift {
        /// Change of the friction level [N] (positive: higher).
        change: f32,
    },
    /// A stretch of the travel (a few bins) left its band while the rest stayed.
    LocalFriction {
        /// Centre of the stretch [m] (excess-weighted centre of the bins out of band).
        position: f32,
        /// Width of the stretch [m] (number of bins out of band times the bin width).
        width: f32,
        /// Largest change in the stretch [N] beyond the travel's common change.
        change: f32,
    },
    /// Breakaway from rest rose above the sliding friction more than commissioning saw.
    StictionRise {
        /// Recent breakaway over sliding friction (smoothed over the last restarts).
        ratio: f32,
        /// The ratio commissioning learned.
        learned: f32,
    },
    /// The observer's residual is large and the friction map shows no pattern that explains it.
    ModelMismatch {
        /// Residual mean square of the axis now [m^2].
        mean_square: f32,
        /// Its commissioning level [m^2].
        learned: f32,
    },
}

impl AlarmKind {
    /// Short name used in the UART frames and reports.
    pub fn name(&self) -> &'static str {
        match self {
            AlarmKind::FrictionDrift { .. } => "friction_drift",
            AlarmKind::LocalFriction { .. } => "local_friction",
            AlarmKind::StictionRise { .. } => "stiction_rise",
            AlarmKind::ModelMismatch { .. } => "model_mismatch",
        }
    }
}

/// One alarm: what, where and when.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Alarm {
    /// Kind and size.
    pub kind: AlarmKind,
    /// Drive axis.
    pub axis: Axis,
    /// Direction of motion it was seen in (`Both` for the residual).
    pub direction: Direction,
    /// Control period it was raised in (period index since start).
    pub period: u64,
}

#[cfg(feature = "defmt")]
impl defmt::Format for Alarm {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(
            f,
            "Alarm {{ kind: {}, axis: {}, direction: {}, period: {} }}",
            self.kind,
            self.axis.index(),
            match self.direction {
                Direction::Positive => "+",
                Direction::Negative => "-",
                Direction::Both => "+-",
            },
            self.period
        )
    }
}

/// Debounce and latch of one condition: [`Debounce::CONFIRM`] consecutive fresh evaluations
/// to raise, [`Debounce::RELEASE`] clear ones to release.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Debounce {
    run: u8,
    clear: u8,
    standing: bool,
}

impl Debounce {
    /// Consecutive fresh evaluations a condition must hold (or be clear) to change state. Two:
    /// one evaluation can be a transient, two with fresh data in between are a pattern.
    pub const CONFIRM: u8 = 2;
    /// Consecutive clear evaluations that release a standing alarm: a change near the
    /// threshold must not be raised again at every other pass.
    pub const RELEASE: u8 = 8;

    /// Feeds one evaluation; returns `true` exactly when the alarm is to be raised now.
    pub fn feed(&mut self, condition: bool) -> bool {
        if condition {
            self.clear = 0;
            self.run = self.run.saturating_add(1);
            if !self.standing && self.run >= Self::CONFIRM {
                self.standing = true;
                return true;
            }
        } else {
            self.run = 0;
            self.clear = self.clear.saturating_add(1);
            if self.standing && self.clear >= Self::RELEASE {
                self.standing = false;
            }
        }
        false
    }

    /// Whether the alarm stands.
    pub fn standing(&self) -> bool {
        self.standing
    }

    /// Whether the condition held in the last evaluation (a raise may be pending).
    pub fn pending(&self) -> bool {
        self.run > 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raises_once_after_confirmation_and_releases_after_as_many_clear() {
        let mut d = Debounce::default();
        assert!(!d.feed(true));
        assert!(d.feed(true));
        assert!(d.standing());
        assert!(!d.feed(true));
        for _ in 1..Debounce::RELEASE {
            assert!(!d.feed(false));
            assert!(d.standing());
        }
        assert!(!d.feed(false));
        assert!(!d.standing());
        assert!(!d.feed(true));
        assert!(d.feed(true));
    }

    #[test]
    fn an_interrupted_run_starts_again() {
        let mut d = Debounce::default();
        assert!(!d.feed(true));
        assert!(!d.feed(false));
        assert!(!d.feed(true));
        assert!(d.feed(true));
    }
}
