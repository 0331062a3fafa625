//! The time-base thresholds a refused run's message quotes ([`super::timebase`] applies them,
//! [`super::error::Timing`] names them; one place, so neither module imports the other).

/// Largest relative deviation of a time step from the median step for a run to count as
/// uniformly sampled (5 %).
pub const JITTER_TOLERANCE: f64 = 0.05;

/// Largest step of an irregular run that is still resampled, in median steps: beyond it rows
/// were lost and the run is refused.
pub const MAX_GAP_STEPS: f64 = 4.0;

/// Plausible median sample rates of a log [Hz], both ends excluded: at 1 Hz or below no drive's friction or inertia
/// shows (and stamps in milliseconds or sample indices read as seconds land there); above
/// 1 MHz no position encoder is read (seconds declared as milliseconds at 1 kHz land there).
pub const RATE_RANGE_HZ: (f64, f64) = (1.0, 1e6);
