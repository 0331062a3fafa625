//! Breakaway from rest, per drive axis: the force an axis withstood at rest just before it
//! started to move, at each restart, over the sliding friction at that place.
//!
//! Rest and restart are judged on the *measured* motion, not on the twin's mode: an axis rests
//! once the twin has held it stopped for `min_stop` periods (the braking force of the move
//! that ended is then over), at the position it had then (the anchor); it restarts when its
//! position estimate leaves the anchor by more than `band` (the observer's stick band, a few
//! encoder steps). Meanwhile the watch keeps the largest force pushed each way: the drive
//! force `K u` plus the payload's pull on the trolley.
//!
//! The breakaway is the force held at the *onset* of motion, not at the restart's detection:
//! an axis that breaks away creeps (its net force grows from zero), so it takes tens of
//! periods to leave the stick band, and the controller pushes harder all that time (measured
//! on the independent plant: 23-122 periods, and the largest push up to the detection 1.2-3.5
//! times the force at the onset, a scatter that hid a stiction ratio of 1.8). The onset is
//! read on the encoder: the first period of the last run of readings out of the anchor's
//! count (`|reading - anchor| > quantum / 2`), a run of at least [`CONFIRM`] periods (a single
//! read of encoder noise is no onset), and not ended by [`CONFIRM`] readings back at the
//! anchor. The reading is an interval: the plant held the largest push up to the period before
//! the onset (the lower end, [`Breakaway::held`]), and moved at the latest at the onset, with
//! the largest push up to it (the upper end, [`Breakaway::onset`], the value used).
//!
//! The ratio of that force to the sliding friction there (the model's dry level plus what the
//! map's reference adds) is one sample of the stiction ratio. Per direction: the
//! commissioning mean and variance of the ratio over the first `WARM` restarts (Welford),
//! then an exponentially forgetting current ratio (weight [`RECENT`]). Memory: 88 bytes per
//! axis.

/// Consecutive encoder readings out of the anchor's count that make an onset, and back at it
/// that cancel one: a single read of encoder noise is neither.
pub const CONFIRM: u8 = 2;

/// What the watch sees of an axis in one period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sense {
    /// The twin holds the axis stopped.
    pub stopped: bool,
    /// The twin's position estimate [m].
    pub x: f32,
    /// The encoder's reading of the position this period [m].
    pub reading: f32,
    /// The force pushing the axis [N] (positive along the axis).
    pub force: f32,
}

/// The watch's limits, from the loop and the encoder.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Distance [m] the estimate must leave the anchor to be a restart (the stick band).
    pub band: f32,
    /// The encoder's step [m].
    pub quantum: f32,
    /// Periods the twin must hold the axis stopped before it rests.
    pub min_stop: u32,
}

/// One breakaway: the direction it moved and the forces [N] it held that way.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Breakaway {
    /// Direction of the restart (0 negative, 1 positive).
    pub dir: usize,
    /// The largest push that way up to the onset [N]: the breakaway at most.
    pub onset: f32,
    /// The largest push that way before the onset [N]: the breakaway at least.
    pub held: f32,
}

impl Breakaway {
    /// The breakaway [N]: the push at the onset less what the drive added while the axis crept
    /// to the encoder's next count. From rest, a net force growing at `ramp` [N/s] moves a
    /// mass `mass` [kg] by `ramp t^3 / (6 mass)`; the next count is half a `quantum` [m] away
    /// on average, reached after `t = (3 mass quantum / ramp)^(1/3)`, when the push has grown
    /// by `ramp t`. The ramp is the push's growth over the onset's period (`onset - held` in
    /// `period` [s]). Measured on the independent plant (ratio 1.0, seed 1, 94 restarts of X):
    /// the push at the onset over the sliding friction 1.73-1.76 with a scatter of 0.45-0.50,
    /// this estimate 0.99-1.10 with 0.22-0.31 (the plant's own: 1.07, 0.08-0.10).
    pub fn estimate(&self, mass: f32, quantum: f32, period: f32) -> f32 {
        let grown = self.onset - self.held;
        let usable = grown > 0.0 && period > 0.0 && mass > 0.0 && quantum > 0.0;
        if !usable {
            return self.onset;
        }
        let ramp = grown / period;
        let excess = ramp * cube_root(3.0 * mass * quantum / ramp);
        if excess.is_finite() {
            (self.onset - excess).max(0.0)
        } else {
            self.onset
        }
    }
}

/// Cube root of `x > 0` (0 otherwise): an initial guess from the exponent's bits, then Newton's
/// iteration (no libm, the same bits on every IEEE target).
pub fn cube_root(x: f32) -> f32 {
    if x.is_nan() || x <= 0.0 || !x.is_finite() {
        return 0.0;
    }
    let mut y = f32::from_bits(x.to_bits() / 3 + 0x2a51_67d8);
    for _ in 0..4 {
        y -= (y - x / (y * y)) / 3.0;
    }
    y
}

/// Restarts over which commissioning learns the ratio's mean and scatter before it is judged
/// (the default of [`super::Settings::restarts_learn`]).
pub const WARM: u16 = 32;
/// Weight of a restart in the current ratio (about the last eight restarts).
pub const RECENT: f32 = 0.125;
/// Weight of a restart in the learned mean and scatter after [`WARM`] (slow tracking while
/// no stiction alarm stands): the tails of the ratio are learned over hours.
pub const SLOW: f32 = 1.0 / 256.0;

/// Variance [1] of the recent ratio (forgetting [`RECENT`] per restart) for independent
/// restarts whose ratio has the variance `var` [1]: `var RECENT / (2 - RECENT)`.
pub fn recent_band(var: f32) -> f32 {
    var * RECENT / (2.0 - RECENT)
}

/// The breakaway watch of one axis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BreakawayWatch {
    stopped_for: u32,
    resting: bool,
    anchor: f32,
    push: [f32; 2],
    /// Push before the current run of readings out of the anchor's count, and at its start.
    before: [f32; 2],
    at_out: [f32; 2],
    /// The confirmed onset's pushes (before, at), if one stands.
    onset: Option<([f32; 2], [f32; 2])>,
    out_run: u8,
    in_run: u8,
    mean: [f32; 2],
    var: [f32; 2],
    current: [f32; 2],
    n: [u16; 2],
    fresh: [bool; 2],
}

impl BreakawayWatch {
    /// One period of the axis (`sense`), within `limits`. Returns the breakaway of a restart
    /// detected in this period, if any.
    pub fn period(&mut self, sense: Sense, limits: Limits) -> Option<Breakaway> {
        let Sense {
            stopped,
            x,
            reading,
            force,
        } = sense;
        self.stopped_for = if stopped {
            self.stopped_for.saturating_add(1)
        } else {
            0
        };
        if !self.resting {
            if self.stopped_for >= limits.min_stop && x.is_finite() {
                self.resting = true;
                self.anchor = x;
                self.push = [0.0; 2];
                self.onset = None;
                self.out_run = 0;
                self.in_run = 0;
            }
            return None;
        }
        let before = self.push;
        // A non-finite force (a failed driver read-back) is no push.
        if force.is_finite() {
            if force > self.push[1] {
                self.push[1] = force;
            }
            if -force > self.push[0] {
                self.push[0] = -force;
            }
        }
        self.onset_reading(reading, before, limits.quantum);
        let dx = x - self.anchor;
        if dx > limits.band || dx < -limits.band {
            self.resting = false;
            let dir = usize::from(dx > 0.0);
            let (held, at) = self.onset.unwrap_or((before, self.push));
            return Some(Breakaway {
                dir,
                onset: at[dir],
                held: held[dir],
            });
        }
        None
    }

    /// Follows the encoder's reading at rest: the onset of motion is the start of the last run
    /// of [`CONFIRM`] or more readings out of the anchor's count, not ended by as many back in
    /// it. `before` are the pushes up to the previous period.
    fn onset_reading(&mut self, reading: f32, before: [f32; 2], quantum: f32) {
        let off = reading - self.anchor;
        if !off.is_finite() {
            return;
        }
        if off > 0.5 * quantum || off < -0.5 * quantum {
            self.in_run = 0;
            if self.out_run == 0 {
                self.before = before;
                self.at_out = self.push;
            }
            self.out_run = self.out_run.saturating_add(1);
            if self.out_run >= CONFIRM && self.onset.is_none() {
                self.onset = Some((self.before, self.at_out));
            }
        } else {
            self.out_run = 0;
            self.in_run = self.in_run.saturating_add(1);
            if self.in_run >= CONFIRM {
                self.onset = None;
            }
        }
    }

    /// Whether the axis rests (a restart from here is a breakaway).
    pub fn resting(&self) -> bool {
        self.resting
    }

    /// Records a breakaway ratio for direction `dir`. `learn`: commissioning, or no stiction
    /// alarm stands (the learned statistics follow slowly); otherwise they are frozen. The
    /// first `warm` restarts are the commissioning average (weight `1/n`).
    pub fn record(&mut self, dir: usize, ratio: f32, learn: bool, warm: u16) {
        if dir > 1 || !ratio.is_finite() {
            return;
        }
        let n = self.n[dir];
        if n >= warm {
            self.current[dir] += RECENT * (ratio - self.current[dir]);
            self.fresh[dir] = true;
        }
        if learn {
            let n = n.saturating_add(1);
            self.n[dir] = n;
            let w = 1.0 / f32::from(n);
            let w = if w > SLOW { w } else { SLOW };
            let d = ratio - self.mean[dir];
            self.mean[dir] += w * d;
            // Variance per restart (West's weighted update).
            self.var[dir] = (1.0 - w) * (self.var[dir] + w * d * d);
            if n <= warm {
                self.current[dir] = self.mean[dir];
            }
        }
    }

    /// Whether the current ratio of direction `dir` is within `k2` (a squared number of
    /// standard deviations) of its learned mean, in the recent ratio's band
    /// ([`recent_band`]); `true` until `warm` restarts were seen.
    pub fn inside(&self, dir: usize, warm: u16, k2: f32) -> bool {
        match self.stats(dir, warm) {
            Some((mean, var, cur)) => {
                let e = cur - mean;
                e * e <= k2 * recent_band(var)
            }
            None => true,
        }
    }

    /// Whether a restart in direction `dir` was recorded since the last call, and clears it.
    pub fn take_fresh(&mut self, dir: usize) -> bool {
        match self.fresh.get_mut(dir) {
            Some(f) => core::mem::take(f),
            None => false,
        }
    }

    /// Restarts in direction `dir` whose ratio was learned (saturating).
    pub fn restarts(&self, dir: usize) -> u16 {
        self.n.get(dir).copied().unwrap_or(0)
    }

    /// Learned mean ratio, its variance per restart, and the current ratio of direction
    /// `dir`; `None` until `warm` restarts were seen.
    pub fn stats(&self, dir: usize, warm: u16) -> Option<(f32, f32, f32)> {
        let n = *self.n.get(dir)?;
        if n < warm {
            return None;
        }
        Some((self.mean[dir], self.var[dir], self.current[dir]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sense(stopped: bool, x: f32, reading: f32, force: f32) -> Sense {
        Sense {
            stopped,
            x,
            reading,
            force,
        }
    }

    const LIMITS: Limits = Limits {
        band: 1e-4,
        quantum: 4e-5,
        min_stop: 2,
    };

    #[test]
    fn the_breakaway_is_the_push_at_the_onset_read_on_the_encoder() {
        let mut w = BreakawayWatch::default();
        // Braking at the stop (not counted), then a rest with pushes, then motion.
        for f in [-9.0, 9.0] {
            assert_eq!(w.period(sense(true, 0.3, 0.3, f), LIMITS), None);
        }
        assert!(w.resting());
        // A single noisy read out of the anchor's count is no onset.
        for (f, y) in [(0.5, 0.3), (-1.0, 0.30004), (2.0, 0.3), (2.5, 0.3)] {
            assert_eq!(w.period(sense(true, 0.3, y, f), LIMITS), None);
        }
        // The encoder leaves the anchor's count at a push of 3.0 (held before: 2.5) and stays
        // out; the controller pushes on while the estimate creeps out of the stick band.
        for (f, y) in [(3.0, 0.30004), (3.4, 0.30004), (3.6, 0.30008)] {
            assert_eq!(w.period(sense(true, 0.30003, y, f), LIMITS), None);
        }
        let b = w.period(sense(false, 0.30011, 0.30012, 4.0), LIMITS);
        assert_eq!(
            b,
            Some(Breakaway {
                dir: 1,
                onset: 3.0,
                held: 2.5
            })
        );
        assert!(!w.resting());
        // A stop too brief to be a rest gives no breakaway.
        assert_eq!(w.period(sense(true, 0.31, 0.31, 1.0), LIMITS), None);
        assert_eq!(w.period(sense(false, 0.30, 0.30, -1.0), LIMITS), None);
    }

    #[test]
    fn readings_back_at_the_anchor_cancel_an_onset_and_without_one_the_last_push_counts() {
        let mut w = BreakawayWatch::default();
        for _ in 0..2 {
            w.period(sense(true, 0.3, 0.3, 0.0), LIMITS);
        }
        // Two reads out (an onset at 1.0), then two back at the anchor: cancelled.
        for (f, y) in [(1.0, 0.29996), (1.1, 0.29996), (1.2, 0.3), (1.3, 0.3)] {
            assert_eq!(w.period(sense(true, 0.3, y, -f), LIMITS), None);
        }
        // The estimate leaves the band with no reading out of the count (a reading lost):
        // the largest push up to the detection is the breakaway's upper end.
        let b = w.period(sense(false, 0.2998, f32::NAN, -1.5), LIMITS);
        assert_eq!(
            b,
            Some(Breakaway {
                dir: 0,
                onset: 1.5,
                held: 1.3
            })
        );
    }

    #[test]
    fn the_estimate_takes_off_the_creep_to_the_next_count() {
        for x in [1e-9f32, 3e-6, 0.5, 8.0, 1e6] {
            let c = cube_root(x);
            assert!((c * c * c - x).abs() <= 1e-5 * x, "{x}: {c}");
        }
        assert_eq!(cube_root(-1.0), 0.0);
        assert_eq!(cube_root(f32::NAN), 0.0);
        // 0.1 N a period (50 N/s), 6 kg, 61 um counts: t = (3 * 6 * 61e-6 / 50)^(1/3) = 28 ms,
        // 1.40 N of creep.
        let b = Breakaway {
            dir: 1,
            onset: 3.0,
            held: 2.9,
        };
        let e = b.estimate(6.0, 61e-6, 2e-3);
        assert!((e - (3.0 - 1.401)).abs() < 2e-3, "{e}");
        // No growth over the onset's period: nothing to take off.
        let flat = Breakaway { held: 3.0, ..b };
        assert_eq!(flat.estimate(6.0, 61e-6, 2e-3), 3.0);
    }

    #[test]
    fn commissioning_learns_then_the_current_ratio_follows() {
        let mut w = BreakawayWatch::default();
        for i in 0..WARM {
            w.record(1, if i % 2 == 0 { 1.1 } else { 1.3 }, true, WARM);
        }
        let (mean, var, cur) = w.stats(1, WARM).unwrap_or_default();
        assert!((mean - 1.2).abs() < 1e-5 && (cur - 1.2).abs() < 1e-5);
        assert!((var - 0.01).abs() < 1e-4, "{var}");
        for _ in 0..24 {
            w.record(1, 2.0, false, WARM);
        }
        let (mean, _, cur) = w.stats(1, WARM).unwrap_or_default();
        assert!(cur > 1.9, "{cur}");
        assert!((mean - 1.2).abs() < 1e-5, "frozen while an alarm stands");
        assert!(w.take_fresh(1) && !w.take_fresh(1));
    }
}
