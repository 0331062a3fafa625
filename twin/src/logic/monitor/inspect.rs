//! A read-only view of the monitor's local check, for a diagnosis of what it missed (the
//! independent plant's tests print it): never called on the control period's path, so it
//! costs the firmware nothing. A child module of `monitor`, it reads the monitor's private
//! state without widening it.

use super::local::{local_pattern, Judged, FRESH_MOVES};
use super::{Monitor, AXES};
use crane_model::{Axis, Direction};

/// What the local check of one map sees ([`Monitor::local_state`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalState {
    /// Bin of the local candidate, if any.
    pub candidate: Option<usize>,
    /// Complete passes over the candidate since the check was last fed.
    pub passes: u16,
    /// The local confirmation: (pending, standing).
    pub local: (bool, bool),
    /// The drift confirmation: (pending, standing); either blocks the axis' local check.
    pub drift: (bool, bool),
    /// The pattern the map shows now.
    pub pattern: LocalPattern,
    /// Mean band of the judged bins at the last move's end [N^2].
    pub pooled: f32,
    /// The fresh judged bins out of band against the travel's level (bit `b`: bin `b`); more
    /// than [`Settings::local_bins`] beyond the stretch make no local change.
    pub out_of_band: u64,
}

/// The local pattern a map shows ([`LocalState::pattern`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LocalPattern {
    /// A stretch out of band.
    Local {
        /// The bin furthest out of band.
        peak: usize,
        /// The stretch's change beyond the travel's level [N].
        change: f32,
    },
    /// None (nothing out of band, too wide, or not standing out against its flanks).
    Clear,
    /// A stretch out of band whose flanks the same pass has not both crossed.
    Unjudged,
}

impl Monitor {
    /// What the local check of `axis` and `dir` sees now, for a diagnosis (read only, off the
    /// control period's path): its candidate bin and the complete passes over it since it was
    /// last fed, whether a local or a drift confirmation is pending or standing, the pattern
    /// the map shows against the travel's level now, and the mean band of the judged bins
    /// [N^2]. `None` for an axis not watched.
    pub fn local_state(&self, axis: Axis, dir: Direction) -> Option<LocalState> {
        let i = AXES.iter().position(|a| *a == axis)?;
        let d = usize::from(dir != Direction::Negative);
        let c = &self.checks[i][d];
        let k2 = self.settings.k_local * self.settings.k_local;
        let s = &self.settings.map;
        let pattern = match local_pattern(
            &self.maps[i][d],
            s,
            c.level,
            c.pooled,
            k2,
            self.settings.local_bins,
        ) {
            Judged::Local(l) => LocalPattern::Local {
                peak: l.peak,
                change: l.change,
            },
            Judged::Clear => LocalPattern::Clear,
            Judged::Unjudged => LocalPattern::Unjudged,
        };
        let scan = self.maps[i][d].out_of_band(s, FRESH_MOVES, c.level, c.pooled, k2);
        Some(LocalState {
            out_of_band: scan.mask,
            candidate: c.candidate,
            passes: c.passes,
            local: (c.local.pending(), c.local.standing()),
            drift: (c.drift.pending(), c.drift.standing()),
            pattern,
            pooled: c.pooled,
        })
    }
}
