//! The friction map of one drive axis and one direction of motion: what the twin's friction
//! model gets wrong while the axis slides, per position bin.
//!
//! A sample is the residual friction `r = -d sign(v)` [N]: the observer's disturbance `d`
//! against the motion, i.e. friction the plant has beyond the model's (negative: less). Each
//! bin keeps
//! - the *current* level: an exponentially forgetting mean (weight `max(1/n, FAST)`, about one
//!   or two passes over the bin) and the scatter of the samples around it;
//! - the *reference*: the mean of the samples while the bin warms (`warm` samples), then,
//!   until it is judged (`judged` samples), the mean of its current level, and then it tracks
//!   slow changes (weight [`MapSettings::slow`]) while no alarm of this map stands;
//! - the learned scatter of the current level around the reference (the band): from `warm`
//!   to `judged` samples the variance of the current level around that same mean (Welford),
//!   then tracking slowly like the reference. The band is the scatter of the passes, not of
//!   a reference's own error: with the reference the mean of the first `warm` samples (two to
//!   four passes) and the band the current level's variance around it over the next ones,
//!   every band also held that reference's error squared, a different one per bin (measured
//!   on the rig, held-out seed 1006: the bump's bin had a band of 0.148 N where its passes
//!   scatter by 0.083 N, and the bump took 6 passes to be raised);
//! - the sample count `n` (saturating).
//!
//! - the mean speed of the recent samples, for the viscous correction ([`SlidingMap::add`]).
//!
//! - the move in which the bin last got a sample (its age, so evaluations judge fresh bins).
//!
//! Memory: `BINS * (5 * 4 + 2 * 2)` bytes plus 28 (1,564 bytes at 64 bins), all `f32`/`u16`
//! whatever the twin's scalar type, so the maps cost the same in the f64 and f32 builds and
//! give the same bits on the host and the Cortex-M4F (IEEE single, no fused operations).
//! Work per sample: one bin, O(1).

/// Position bins per map.
pub const BINS: usize = 64;

/// Forgetting of the current level per sample: at 2 ms periods and 0.1-0.3 m/s an 8 mm bin
/// sees 15-40 samples per pass, so the current level follows within one or two passes.
pub const FAST: f32 = 1.0 / 16.0;

/// Least weight of a sample in the viscous correction: 65,536 samples, minutes of sliding.
pub const VISCOUS: f32 = 1.0 / 65536.0;

/// How the map learns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapSettings {
    /// Samples a bin needs before its reference and band learn from its current level (until
    /// then the reference is the plain mean of its samples).
    pub warm: u16,
    /// Samples a bin needs (warm ones included) before it is judged.
    pub judged: u16,
    /// Weight of a sample in the reference and band once learned (slow tracking).
    pub slow: f32,
    /// Squared alarm threshold in band units (`k^2`): a learned bin whose current level is
    /// further from its reference than this does not teach its reference or band.
    pub gate: f32,
}

impl Default for MapSettings {
    /// 64 warm samples (three or four passes), judged from 512 (the band learned over about
    /// 25 passes: the samples of one pass are correlated, the passes much less), slow tracking
    /// over 4,096 samples of a bin (minutes of operation at a pass every few seconds), gate
    /// at 5 band deviations (the monitor's `k`).
    fn default() -> Self {
        MapSettings {
            warm: 64,
            judged: 512,
            slow: 1.0 / 4096.0,
            gate: 25.0,
        }
    }
}

/// The bins of a map out of band against a travel level, from one pass over the map
/// ([`SlidingMap::out_of_band`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OutOfBand {
    /// Bit `b` set: bin `b` is out of band.
    pub mask: u64,
    /// Bins out of band (the bits set in `mask`).
    pub count: usize,
    /// The bin furthest out of band (the lowest of equals) and its change beyond the level
    /// [N] (signed, never 0), if any bin is out.
    pub peak: Option<(usize, f32)>,
}

/// What [`SlidingMap::judged_bands`] found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JudgedBands {
    /// Sum of the judged bins' bands [N^2], in bin order.
    pub sum: f32,
    /// Judged bins.
    pub judged: usize,
    /// Judged bins in the range whose deviation's key is below the pivot: `keys[..below]`.
    pub below: usize,
    /// The other judged bins in the range: `keys[BINS - above..]`.
    pub above: usize,
}

/// The key of `x` whose `i32` order is [`f32::total_cmp`]'s order (the sign-magnitude bits
/// turned into two's complement, as `total_cmp` compares them); [`from_total_key`] inverts it.
pub fn total_key(x: f32) -> i32 {
    let b = x.to_bits() as i32;
    b ^ (((b >> 31) as u32) >> 1) as i32
}

/// The `f32` of a [`total_key`] (bit for bit).
pub fn from_total_key(k: i32) -> f32 {
    f32::from_bits((k ^ (((k >> 31) as u32) >> 1) as i32) as u32)
}

// `SlidingMap::out_of_band` takes the bins 32 at a time.
const _: () = assert!(BINS % 32 == 0 && BINS.is_power_of_two());

/// One direction's map over the travel `[lo, hi]` [m].
#[derive(Clone, Debug, PartialEq)]
pub struct SlidingMap {
    lo: f32,
    scale: f32,
    cur: [f32; BINS],
    scatter: [f32; BINS],
    reference: [f32; BINS],
    band: [f32; BINS],
    n: [u16; BINS],
    speed: [f32; BINS],
    seen: [u16; BINS],
    moves: u16,
    slope: f32,
    v0: f32,
    sxx: f32,
    reg_n: u32,
}

/// A bin's deviation from its reference, as seen by an evaluation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BinView {
    /// Current level minus reference [N].
    pub deviation: f32,
    /// Learned variance of the current level around the reference [N^2].
    pub band: f32,
    /// Whether the bin has enough samples to be judged.
    pub judged: bool,
    /// Moves of this map since the bin last got a sample (0: the current or last move).
    pub age: u16,
}

impl SlidingMap {
    /// An empty map over `[lo, hi]` [m] (`hi > lo`; an empty range maps everything to bin 0).
    pub fn new(lo: f32, hi: f32) -> Self {
        let span = hi - lo;
        let scale = if span > 0.0 { BINS as f32 / span } else { 0.0 };
        SlidingMap {
            lo,
            scale,
            cur: [0.0; BINS],
            scatter: [0.0; BINS],
            reference: [0.0; BINS],
            band: [0.0; BINS],
            n: [0; BINS],
            speed: [0.0; BINS],
            seen: [0; BINS],
            moves: 0,
            slope: 0.0,
            v0: 0.0,
            sxx: 0.0,
            reg_n: 0,
        }
    }

    /// The travel `[lo, hi]` [m] the bins cover.
    pub fn travel(&self) -> (f32, f32) {
        (self.lo, self.lo + BINS as f32 * self.bin_width())
    }

    /// Bin of position `x` [m], clamped to the travel.
    pub fn bin(&self, x: f32) -> usize {
        let b = (x - self.lo) * self.scale;
        if b.is_nan() || b < 0.0 {
            0
        } else if b >= BINS as f32 {
            BINS - 1
        } else {
            b as usize
        }
    }

    /// Centre [m] of bin `b`.
    pub fn center(&self, b: usize) -> f32 {
        if self.scale > 0.0 {
            self.lo + (b as f32 + 0.5) / self.scale
        } else {
            self.lo
        }
    }

    /// Width of a bin [m].
    pub fn bin_width(&self) -> f32 {
        if self.scale > 0.0 {
            1.0 / self.scale
        } else {
            0.0
        }
    }

    /// Adds a residual-friction sample `r` [N] at position `x` [m]. `track` lets the
    /// reference and bands follow slowly (off while an alarm of this map stands). Returns the
    /// bin.
    pub fn add(&mut self, x: f32, speed: f32, r: f32, s: &MapSettings, track: bool) -> usize {
        let b = self.bin(x);
        self.seen[b] = self.moves;
        let n = self.n[b].saturating_add(1);
        self.n[b] = n;
        let inv = 1.0 / f32::from(n);
        let w = if inv > FAST { inv } else { FAST };
        let r = self.viscous(b, speed, r, w, track);
        // Current level and the scatter of the samples around it (West's weighted update).
        let delta = r - self.cur[b];
        self.cur[b] += w * delta;
        self.scatter[b] = (1.0 - w) * (self.scatter[b] + w * delta * delta);
        // Once learned, reference and band follow only a bin that is in its band: a change
        // beyond the alarm threshold is never taught to the map, however slowly it comes.
        let e = self.cur[b] - self.reference[b];
        let learned = n > s.judged;
        let follow = track && e * e <= s.gate * self.band[b];
        // Reference: plain mean while warming; then, until the bin is judged, the mean of the
        // current level and the band its variance around that mean over the same samples
        // (Welford); then slow tracking (or frozen).
        if n <= s.warm {
            self.reference[b] += inv * (r - self.reference[b]);
        } else if !learned {
            let wb = 1.0 / f32::from(n - s.warm);
            let before = self.cur[b] - self.reference[b];
            self.reference[b] += wb * before;
            let after = self.cur[b] - self.reference[b];
            self.band[b] += wb * (before * after - self.band[b]);
        } else if follow {
            self.reference[b] += s.slow * (r - self.reference[b]);
            self.band[b] += s.slow * (e * e - self.band[b]);
        }
        b
    }

    /// The viscous correction: what the model's viscous friction gets wrong makes the residual
    /// grow with speed, and the passes over a bin differ in speed, so it would widen every
    /// band. The map learns that slope (residual against speed, both centred on the bin's
    /// recent means, so the friction's change along the travel does not enter it) by
    /// recursive least squares, and files each sample at the map's mean speed `v0`: the bins
    /// hold the friction at one speed. Learned while `track` (no alarm of the map stands).
    /// Returns the corrected sample [N].
    fn viscous(&mut self, b: usize, speed: f32, r: f32, w: f32, track: bool) -> f32 {
        let rc = r - self.slope * (speed - self.v0);
        if track {
            let dx = speed - self.speed[b];
            let dy = rc - self.cur[b];
            self.reg_n = self.reg_n.saturating_add(1);
            let wr = 1.0 / self.reg_n as f32;
            let wr = if wr > VISCOUS { wr } else { VISCOUS };
            self.v0 += wr * (speed - self.v0);
            self.sxx += wr * (dx * dx - self.sxx);
            if self.sxx > 0.0 && self.n[b] > 1 {
                self.slope += wr * dx * dy / self.sxx;
            }
        }
        self.speed[b] += w * (speed - self.speed[b]);
        rc
    }

    /// A move (one slide in this map's direction) ended: ages every bin by one move
    /// (wrapping: ages are compared within a few moves).
    pub fn end_move(&mut self) {
        self.moves = self.moves.wrapping_add(1);
    }

    /// The learned viscous correction [N s/m] (residual friction per speed) and the speed the
    /// bins are filed at [m/s].
    pub fn viscous_slope(&self) -> (f32, f32) {
        (self.slope, self.v0)
    }

    /// Bin `b` as an evaluation sees it.
    pub fn view(&self, b: usize, s: &MapSettings) -> BinView {
        BinView {
            deviation: self.cur[b] - self.reference[b],
            band: self.band[b],
            judged: self.n[b] >= s.judged,
            age: self.moves.wrapping_sub(self.seen[b]),
        }
    }

    /// Current level minus reference of bin `b` [N]: [`BinView::deviation`], alone.
    pub fn deviation(&self, b: usize) -> f32 {
        self.cur[b] - self.reference[b]
    }

    /// One pass over the judged bins ([`BinView::judged`]), in bin order: the sum of their
    /// bands [N^2] (added in bin order, the same bits as a loop over [`SlidingMap::view`]),
    /// their number, and the deviations [N] of those in `lo..=hi` as [`total_key`]s in
    /// `keys`, split around `pivot` (a key): those below it at the front of `keys`, the
    /// others at its back ([`JudgedBands`]).
    #[inline(never)]
    pub fn judged_bands(
        &self,
        s: &MapSettings,
        lo: usize,
        hi: usize,
        pivot: i32,
        keys: &mut [i32; BINS],
    ) -> JudgedBands {
        let hi = hi.min(BINS - 1);
        let lo = lo.min(hi + 1);
        let mut sum = 0.0f32;
        let mut judged = 0usize;
        let mut below = 0usize;
        let mut above = 0usize;
        // Three stretches, in bin order: before `lo`, `lo..=hi`, after `hi`.
        for b in 0..lo {
            if self.n[b] >= s.judged {
                sum += self.band[b];
                judged += 1;
            }
        }
        for b in lo..hi + 1 {
            if self.n[b] >= s.judged {
                sum += self.band[b];
                judged += 1;
                let key = total_key(self.cur[b] - self.reference[b]);
                if key < pivot {
                    keys[below & (BINS - 1)] = key;
                    below += 1;
                } else {
                    above += 1;
                    keys[(BINS - above) & (BINS - 1)] = key;
                }
            }
        }
        for b in hi + 1..BINS {
            if self.n[b] >= s.judged {
                sum += self.band[b];
                judged += 1;
            }
        }
        JudgedBands {
            sum,
            judged,
            below,
            above,
        }
    }

    /// One pass over the map: the bins judged ([`BinView::judged`]), at most `fresh` moves old
    /// ([`BinView::age`]), whose change beyond the travel's level `e = deviation - level` [N]
    /// is out of band, `e^2 > k2 max(band, pooled)` (`pooled` [N^2] the floor of every
    /// bin's band, `k2` the squared threshold in standard deviations): that test on each
    /// bin's [`SlidingMap::view`], bin by bin, the same decisions and values.
    ///
    /// Most bins are in band, and a bin is out only if `e^2 - k2 pooled > 0` (for `k2 > 0`:
    /// `k2 b` does not decrease with `b`, rounding included; otherwise every bin is a
    /// candidate): a first pass takes that difference's sign bit for every bin, without a
    /// branch, and the full test runs on the candidates only, in bin order.
    #[inline(never)]
    pub fn out_of_band(
        &self,
        s: &MapSettings,
        fresh: u16,
        level: f32,
        pooled: f32,
        k2: f32,
    ) -> OutOfBand {
        let floor = if k2 > 0.0 {
            k2 * pooled
        } else {
            f32::NEG_INFINITY
        };
        let mut out = OutOfBand::default();
        // |e| of the peak so far: any out bin's |e| (>= 0) is above it at first.
        let mut worst = -1.0f32;
        for half in 0..BINS / 32 {
            let first = 32 * half;
            // Bit 31 - j: bin first + j is below the floor (the sign of e^2 - floor).
            let mut below = 0u32;
            for b in first..first + 32 {
                let e = (self.cur[b] - self.reference[b]) - level;
                below = (below << 1) | ((e * e - floor).to_bits() >> 31);
            }
            let mut candidates = !below;
            while candidates != 0 {
                let j = candidates.leading_zeros() as usize;
                candidates &= !(0x8000_0000u32 >> j);
                let b = (first + j) & (BINS - 1);
                let e = (self.cur[b] - self.reference[b]) - level;
                let band = if self.band[b] > pooled {
                    self.band[b]
                } else {
                    pooled
                };
                let judged = self.n[b] >= s.judged;
                let age = self.moves.wrapping_sub(self.seen[b]);
                if judged && age <= fresh && e * e > k2 * band {
                    out.mask |= 1u64.checked_shl(b as u32).unwrap_or(0);
                    out.count += 1;
                    let a = if e < 0.0 { -e } else { e };
                    if a > worst {
                        worst = a;
                        out.peak = Some((b, e));
                    }
                }
            }
        }
        out
    }

    /// Reference level of bin `b` [N] (residual friction commissioning saw there).
    pub fn reference(&self, b: usize) -> f32 {
        self.reference[b]
    }

    /// Current level of bin `b` [N].
    pub fn current(&self, b: usize) -> f32 {
        self.cur[b]
    }

    /// Scatter (variance) of the recent samples of bin `b` [N^2].
    pub fn scatter(&self, b: usize) -> f32 {
        self.scatter[b]
    }

    /// Samples seen by bin `b` (saturating at 65,535).
    pub fn count(&self, b: usize) -> u16 {
        self.n[b]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_cover_the_travel_and_clamp_outside() {
        let m = SlidingMap::new(0.0, 0.64);
        assert_eq!(m.bin(-1.0), 0);
        assert_eq!(m.bin(0.0), 0);
        assert_eq!(m.bin(0.0101), 1);
        assert_eq!(m.bin(0.639), BINS - 1);
        assert_eq!(m.bin(5.0), BINS - 1);
        assert_eq!(m.bin(f32::NAN), 0);
        assert!((m.center(1) - 0.015).abs() < 1e-6);
    }

    #[test]
    fn the_reference_is_the_commissioning_mean_and_a_step_shows_in_the_current_level() {
        let s = MapSettings::default();
        let mut m = SlidingMap::new(0.0, 0.64);
        for i in 0..600 {
            let r = if i % 2 == 0 { 0.9 } else { 1.1 };
            m.add(0.3, 0.2, r, &s, true);
        }
        let b = m.bin(0.3);
        assert!((m.reference(b) - 1.0).abs() < 0.02, "{}", m.reference(b));
        let before = m.view(b, &s);
        assert!(before.judged);
        assert!(before.deviation.abs() < 0.2);
        for _ in 0..40 {
            m.add(0.3, 0.2, 2.0, &s, false);
        }
        let after = m.view(b, &s);
        assert!((after.deviation - 1.0).abs() < 0.1, "{after:?}");
        assert!(
            (m.reference(b) - 1.0).abs() < 0.02,
            "frozen while an alarm stands"
        );
    }

    /// The band is the scatter of the passes around their mean, not the error of the first
    /// passes' mean: passes of 32 samples alternate between 0.9 and 1.1 N (0.1 N from their
    /// mean), after a first pass at 1.4 N while the bin warms.
    #[test]
    fn the_band_is_the_scatter_of_the_passes_not_the_first_passes_error() {
        let s = MapSettings::default();
        let mut m = SlidingMap::new(0.0, 0.64);
        let b = m.bin(0.3);
        let mut pass = 0;
        while m.count(b) < s.judged {
            let r = if pass == 0 {
                1.4
            } else if pass % 2 == 0 {
                0.9
            } else {
                1.1
            };
            for _ in 0..32 {
                m.add(0.3, 0.2, r, &s, true);
            }
            m.end_move();
            pass += 1;
        }
        let v = m.view(b, &s);
        assert!(v.judged);
        assert!((m.reference(b) - 1.0).abs() < 0.05, "{}", m.reference(b));
        // The current level swings by up to 0.1 N around the mean: a band within it. Around
        // the first 64 samples' mean (1.25 N) the band would be about 0.3 N.
        let sd = v.band.sqrt();
        assert!(sd > 0.05 && sd < 0.1, "band sd {sd}");
    }
}
