//! Breakaway from rest, per drive axis: the largest force an axis withstood at rest, at each
//! restart, over the sliding friction at that place.
//!
//! Rest and restart are judged on the *measured* motion, not on the twin's mode: an axis rests
//! once the twin has held it stopped for `min_stop` periods (the braking force of the move
//! that ended is then over), at the position it had then; it restarts when its position
//! estimate leaves that place by more than `band` (the observer's stick band, a few encoder
//! steps). In between the watch keeps the largest force pushed each way: the drive force
//! `K u` plus the payload's pull on the trolley. A plant that sticks harder than the twin's
//! model withstands more before it moves, whatever the twin predicted meanwhile.
//!
//! The ratio of that force to the sliding friction there (the model's dry level plus what the
//! map's reference adds) is one sample of the stiction ratio. Per direction: the
//! commissioning mean and variance of the ratio over the first `WARM` restarts (Welford),
//! then an exponentially forgetting current ratio (weight [`RECENT`]). Memory: 56 bytes per
//! axis.

/// Restarts over which commissioning learns the ratio's mean and scatter before it is judged
/// (the default of [`super::Settings::restarts_learn`]).
pub const WARM: u16 = 32;
/// Weight of a restart in the current ratio (about the last eight restarts).
pub const RECENT: f32 = 0.125;
/// Weight of a restart in the learned mean and scatter after [`WARM`] (slow tracking while
/// no stiction alarm stands): the tails of the ratio are learned over hours.
pub const SLOW: f32 = 1.0 / 256.0;

/// The breakaway watch of one axis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BreakawayWatch {
    stopped_for: u32,
    resting: bool,
    anchor: f32,
    push: [f32; 2],
    mean: [f32; 2],
    var: [f32; 2],
    current: [f32; 2],
    n: [u16; 2],
    fresh: [bool; 2],
}

impl BreakawayWatch {
    /// One period: whether the twin holds the axis `stopped`, its position estimate `x` [m],
    /// the force pushing it `force` [N] (positive along the axis). Returns the direction of a
    /// restart (0 negative, 1 positive) and the largest force pushed that way during the
    /// rest [N].
    pub fn period(
        &mut self,
        stopped: bool,
        x: f32,
        force: f32,
        band: f32,
        min_stop: u32,
    ) -> Option<(usize, f32)> {
        self.stopped_for = if stopped {
            self.stopped_for.saturating_add(1)
        } else {
            0
        };
        if !self.resting {
            if self.stopped_for >= min_stop && x.is_finite() {
                self.resting = true;
                self.anchor = x;
                self.push = [0.0; 2];
            }
            return None;
        }
        // A non-finite force (a failed driver read-back) is no push.
        if force.is_finite() {
            if force > self.push[1] {
                self.push[1] = force;
            }
            if -force > self.push[0] {
                self.push[0] = -force;
            }
        }
        let dx = x - self.anchor;
        if dx > band || dx < -band {
            self.resting = false;
            let dir = usize::from(dx > 0.0);
            return Some((dir, self.push[dir]));
        }
        None
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

    /// Whether a restart in direction `dir` was recorded since the last call, and clears it.
    pub fn take_fresh(&mut self, dir: usize) -> bool {
        match self.fresh.get_mut(dir) {
            Some(f) => core::mem::take(f),
            None => false,
        }
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

    #[test]
    fn the_breakaway_is_the_largest_push_toward_the_start_direction() {
        let mut w = BreakawayWatch::default();
        let band = 1e-4;
        // Braking at the stop (not counted), then a rest with pushes, then motion.
        for f in [-9.0, 9.0] {
            assert_eq!(w.period(true, 0.3, f, band, 2), None);
        }
        assert!(w.resting());
        for f in [0.5, -1.0, 2.0, 3.0] {
            assert_eq!(w.period(true, 0.3, f, band, 2), None);
        }
        // The twin flickers into a sliding mode, the plant has not moved: still resting.
        assert_eq!(w.period(false, 0.30005, 3.5, band, 2), None);
        assert_eq!(w.period(false, 0.3002, 3.2, band, 2), Some((1, 3.5)));
        assert!(!w.resting());
        // A stop too brief to be a rest gives no breakaway.
        assert_eq!(w.period(true, 0.31, 1.0, band, 2), None);
        assert_eq!(w.period(false, 0.30, -1.0, band, 2), None);
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
