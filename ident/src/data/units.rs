//! Units of a single-axis data set and the input gain.

use serde::{Deserialize, Serialize};

/// Unit of the position `x` of a single-axis run (and of its reference, if any).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum PositionUnit {
    /// Metre: a linear axis (screw, belt, carriage); efforts in N.
    #[default]
    #[serde(rename = "m")]
    Metre,
    /// Radian: a rotary axis (joint, motor shaft); efforts in N m.
    #[serde(rename = "rad")]
    Radian,
}

impl PositionUnit {
    /// Symbol, `m` or `rad`.
    pub fn symbol(self) -> &'static str {
        match self {
            PositionUnit::Metre => "m",
            PositionUnit::Radian => "rad",
        }
    }

    /// The effort unit of this kind of axis: `N` (linear) or `N m` (rotary).
    pub fn effort_unit(self) -> InputUnit {
        match self {
            PositionUnit::Metre => InputUnit::Newton,
            PositionUnit::Radian => InputUnit::NewtonMetre,
        }
    }

    /// Plausible range of a position [m or rad]: +-1 km of travel, +-10^6 rad (160 000 turns).
    pub fn range(self) -> (f64, f64) {
        match self {
            PositionUnit::Metre => (-1e3, 1e3),
            PositionUnit::Radian => (-1e6, 1e6),
        }
    }

    /// Plausible peak speed [m/s or rad/s]: 20 m/s (beyond the fastest linear motors and
    /// belt drives), 1e4 rad/s (95 000 rpm).
    pub fn max_speed(self) -> f64 {
        match self {
            PositionUnit::Metre => 20.0,
            PositionUnit::Radian => 1e4,
        }
    }

    /// Peak speed [m/s or rad/s] typical of the axes this tool is for: 2 m/s (screw, belt
    /// and carriage positioning axes, the crane's drives) and 20 rad/s (190 rpm: robot joints
    /// and direct drives). Faster data load, with a note naming the unit keys
    /// (`position_unit`, `position_scale`, `time_unit`): millimetres or milliradians read as
    /// metres or radians, or seconds declared as milliseconds, are 1000 times faster. A fast
    /// linear motor or a motor shaft can be this fast: then the note is to be ignored.
    pub fn typical_speed(self) -> f64 {
        match self {
            PositionUnit::Metre => 2.0,
            PositionUnit::Radian => 20.0,
        }
    }

    /// `true` for metre (the default, not written out).
    pub fn is_metre(&self) -> bool {
        *self == PositionUnit::Metre
    }
}

/// Unit of the time column `t` of every run (`time_unit` in `dataset.toml`; default `s`).
/// Loggers often stamp in milliseconds or microseconds; the loader converts to seconds before
/// any check, so every rule on time steps and every error message is in seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum TimeUnit {
    /// Second (the default).
    #[default]
    #[serde(rename = "s")]
    Second,
    /// Millisecond.
    #[serde(rename = "ms")]
    Millisecond,
    /// Microsecond (`us`; `µs` accepted).
    #[serde(rename = "us", alias = "µs")]
    Microsecond,
    /// Nanosecond (ROS and Linux clock stamps).
    #[serde(rename = "ns")]
    Nanosecond,
}

impl TimeUnit {
    /// Seconds per unit.
    pub fn seconds(self) -> f64 {
        match self {
            TimeUnit::Second => 1.0,
            TimeUnit::Millisecond => 1e-3,
            TimeUnit::Microsecond => 1e-6,
            TimeUnit::Nanosecond => 1e-9,
        }
    }

    /// `true` for seconds (the default, not written out).
    pub fn is_second(&self) -> bool {
        *self == TimeUnit::Second
    }
}

/// Unit of the recorded input `u` of a single-axis run. Unknown names are refused by the
/// loader with the list of these.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum InputUnit {
    /// Volt (a drive command or motor voltage).
    #[default]
    #[serde(rename = "V")]
    Volt,
    /// Millivolt.
    #[serde(rename = "mV")]
    Millivolt,
    /// Ampere (a current command).
    #[serde(rename = "A")]
    Ampere,
    /// Milliampere.
    #[serde(rename = "mA")]
    Milliampere,
    /// Newton: the input is already the force of a linear axis.
    #[serde(rename = "N")]
    Newton,
    /// Newton metre: the input is already the torque of a rotary axis (`Nm` accepted).
    #[serde(rename = "N m", alias = "Nm")]
    NewtonMetre,
    /// PWM counts or duty units of a hobby driver.
    #[serde(rename = "PWM")]
    Pwm,
    /// Percent of full scale (duty cycle), within +-100.
    #[serde(rename = "%")]
    Percent,
    /// Raw DAC or driver counts.
    #[serde(rename = "counts")]
    Counts,
}

impl InputUnit {
    /// Symbol as written in `dataset.toml`.
    pub fn symbol(self) -> &'static str {
        match self {
            InputUnit::Volt => "V",
            InputUnit::Millivolt => "mV",
            InputUnit::Ampere => "A",
            InputUnit::Milliampere => "mA",
            InputUnit::Newton => "N",
            InputUnit::NewtonMetre => "N m",
            InputUnit::Pwm => "PWM",
            InputUnit::Percent => "%",
            InputUnit::Counts => "counts",
        }
    }

    /// `true` when the input already is a force or torque (gain 1, known).
    pub fn is_effort(self) -> bool {
        matches!(self, InputUnit::Newton | InputUnit::NewtonMetre)
    }

    /// Plausible range of a recorded input in this unit (a value outside is almost surely a
    /// wrong unit): +-1 kV, +-10^4 A, +-10^7 N or N m, +-10^6 PWM, +-100 %, +-10^9 counts.
    pub fn range(self) -> (f64, f64) {
        match self {
            InputUnit::Volt => (-1e3, 1e3),
            InputUnit::Millivolt => (-1e6, 1e6),
            InputUnit::Ampere => (-1e4, 1e4),
            InputUnit::Milliampere => (-1e7, 1e7),
            InputUnit::Newton | InputUnit::NewtonMetre => (-1e7, 1e7),
            InputUnit::Pwm => (-1e6, 1e6),
            InputUnit::Percent => (-100.0, 100.0),
            InputUnit::Counts => (-1e9, 1e9),
        }
    }
}

/// The gain from the recorded input to the drive's effort, force per input unit (N/V, N m/A,
/// N/PWM, ...).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub enum Gain {
    /// Known: effort = gain * u [N or N m]; 1 when the input already is the effort.
    Known(f64),
    /// Not given: everything downstream (fits, reports) is in input units.
    #[default]
    Unknown,
}

impl Gain {
    /// Plausible range of a declared gain [effort per input unit].
    pub const RANGE: (f64, f64) = (1e-9, 1e9);

    /// The gain's value, if known.
    pub fn value(self) -> Option<f64> {
        match self {
            Gain::Known(g) => Some(g),
            Gain::Unknown => None,
        }
    }
}
