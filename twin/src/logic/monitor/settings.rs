//! The monitor's settings: thresholds, learning lengths and the rig's scales, all derived
//! from the control loop ([`Settings::for_loop`]).

use super::super::control::LoopConfig;
use super::breakaway;
use super::map::MapSettings;
use super::N;

/// Monitor settings, all derived from the loop (period, observer gains, encoder) by
/// [`Settings::for_loop`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// How the maps learn.
    pub map: MapSettings,
    /// Alarm threshold in standard deviations of the learned scatter. 5: a Gaussian level
    /// passes it with probability 2.9e-7; the maps give about 10^4 independent looks an hour
    /// (64 bins, 6 maps, about 25 passes), and two confirmations are needed.
    pub k: f32,
    /// Threshold of the local check in standard deviations of a bin's band. Lower than `k`:
    /// a local change is confirmed by a second, independent pass over the same bins (or by
    /// the other direction's map), so the chance of a false one is about the square of a
    /// single tail (4: 3.2e-5 squared).
    pub k_local: f32,
    /// The control period [s].
    pub period: f32,
    /// Least periods of commissioning (nothing judged); it ends on coverage
    /// ([`Monitor::commissioned`](super::Monitor::commissioned)), not before this.
    pub commissioning: u64,
    /// Periods an axis must have slid before its samples are used (observer transient).
    pub settle: u32,
    /// Lag [s] of the disturbance estimate behind the plant: a sample taken at `x` moving at
    /// `v` is filed at `x - v lag`, so both directions' maps put a rough spot at its place.
    pub lag: f32,
    /// Least speed [m/s] of a sample per axis: two encoder steps per period.
    pub v_min: [f32; N],
    /// Periods the twin must hold an axis stopped before it rests (a reversal is no rest).
    pub min_stop: u32,
    /// Distance [m] per axis the position must leave its place at rest to count as a restart:
    /// the observer's stick band (quantisation and count noise stay within it).
    pub band: [f32; N],
    /// The encoder's step [m] per axis: a reading out of the count of the place at rest is
    /// the onset of a breakaway ([`breakaway`]).
    pub quantum: [f32; N],
    /// `1 - alpha`, the observer's position gain's complement: the encoder reading is the
    /// position estimate plus this times the observer's innovation.
    pub reading_gain: f32,
    /// Most bins out of band that still make a local change (more is a travel-wide one).
    pub local_bins: usize,
    /// Moves of a map over which the travel level's band is learned before it is judged.
    pub level_learn: u32,
    /// Restarts per direction over which the breakaway ratio is learned before it is judged.
    pub restarts_learn: u16,
}

impl Settings {
    /// Settings for a loop `cfg`: the settle time from the observer's pole (`theta^3 = 1 -
    /// alpha`, the transient below 1 %), the least speed from the encoder step, commissioning
    /// on coverage alone (no least time), 50 ms at rest for a breakaway, and a local change up to 4 bins wide
    /// (3 cm on X: a rough spot, not a region).
    pub fn for_loop(cfg: &LoopConfig) -> Self {
        let t3 = 1.0 - cfg.gains.alpha;
        let mut p = 1.0;
        let mut settle = 0u32;
        while p > 1e-6 && settle < 10_000 && t3 > 0.0 && t3 < 1.0 {
            p *= t3;
            settle += 1;
        }
        let per = if cfg.period > 0.0 { cfg.period } else { 2e-3 };
        let v = |i: usize| (2.0 * cfg.scale.res[i] / per) as f32;
        let k = 5.0;
        Settings {
            map: MapSettings {
                gate: k * k,
                ..MapSettings::default()
            },
            k,
            k_local: 4.5,
            period: per as f32,
            commissioning: 0,
            settle,
            lag: lag_periods(cube_root(t3)) as f32 * per as f32,
            v_min: [v(0), v(1)],
            min_stop: (0.05 / per) as u32,
            band: [
                cfg.gains.stick_band[0] as f32,
                cfg.gains.stick_band[1] as f32,
            ],
            quantum: [cfg.scale.res[0] as f32, cfg.scale.res[1] as f32],
            reading_gain: t3 as f32,
            local_bins: 4,
            level_learn: 16,
            restarts_learn: breakaway::WARM,
        }
    }
}

impl Settings {
    /// A short commissioning for the QEMU cross-check: at least 20 s, bins judged from 64
    /// samples (the band learned over the 48 after the first 16: two passes at the map's mean
    /// speed, about 26 samples each on X; over 32, one pass could hold them all and the band was
    /// the scatter within it, a few hundredths of a newton, against which `CHECK`'s 2 N bump
    /// was out of band over 5 bins, too wide for a local change), the travel level from 1
    /// move, the breakaway from 4 restarts (on the rig's `CHECK` run every direction has them
    /// by 15 s; with 3 moves X's positive direction had only 2 in the 45 s). It trades the
    /// statistics' quality for a run short enough to simulate under QEMU; it is not for a rig.
    pub fn quick(cfg: &LoopConfig) -> Self {
        let per = if cfg.period > 0.0 { cfg.period } else { 2e-3 };
        let s = Settings::for_loop(cfg);
        Settings {
            map: MapSettings {
                warm: 16,
                judged: 64,
                ..s.map
            },
            commissioning: (20.0 / per) as u64,
            level_learn: 1,
            restarts_learn: 4,
            ..s
        }
    }
}

/// Cube root of `x` in `[0, 1]` by Newton's iteration (no libm in this path).
fn cube_root(x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let mut y = 1.0;
    for _ in 0..60 {
        y -= (y * y * y - x) / (3.0 * y * y);
    }
    y
}

/// Lag of the disturbance estimate in periods for an observer pole `theta`: the mean delay
/// of its response to a force, `LAG_POLES theta / (1 - theta)`, the time constant of one
/// pole times the number of poles the estimate goes through. The alpha-beta-gamma filter
/// has three at `theta`: a force impulse shows in its disturbance estimate with the centroid
/// 27.7 periods later at the default gains (3 x 9.06 + 0.5: the impulse response of the
/// filter's recursion, computed), 55 ms. (With one pole, 18 ms, the two directions' maps
/// put the bump of the rig 12 mm apart at 0.2 m/s: the 37 ms missing, each way.)
fn lag_periods(theta: f64) -> f64 {
    if theta <= 0.0 || theta >= 1.0 {
        return 0.0;
    }
    LAG_POLES * theta / (1.0 - theta)
}

/// Poles of the observer the disturbance estimate goes through (see [`lag_periods`]).
const LAG_POLES: f64 = 3.0;
