//! The numbers at the hardware boundary: PWM duty for a voltage, the voltage a duty really
//! applies, encoder counts of a position and the position estimate of a count. The embedded-hal
//! drivers and the simulated board both use these, so the QEMU board and the host agree to the
//! bit.

use core::f64::consts::{FRAC_PI_2, PI};

/// Supply / saturation voltage of the motor drivers [V].
pub const U_MAX: f64 = 12.0;
/// PWM period in timer ticks (168 MHz timer clock, 40 kHz PWM, no prescaler).
pub const PWM_MAX: u16 = 4200;

/// A motor-driver command: duty in `0..=PWM_MAX` and direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pwm {
    /// Duty in timer ticks.
    pub duty: u16,
    /// `true` for a positive voltage (IN1 high, IN2 low).
    pub forward: bool,
}

/// The PWM command closest to voltage `u` [V] for a timer whose full duty is `PWM_MAX`.
pub fn pwm_command(u: f64) -> Pwm {
    pwm_command_for(u, PWM_MAX)
}

/// The voltage [V] a command applies on a timer whose full duty is `PWM_MAX`.
pub fn pwm_volts(p: Pwm) -> f64 {
    pwm_volts_for(p, PWM_MAX)
}

/// The PWM command closest to voltage `u` [V], saturated to `U_MAX`, for a timer whose full
/// duty is `max` ticks. A non-finite `u` gives duty 0 (the motor is switched off).
pub fn pwm_command_for(u: f64, max: u16) -> Pwm {
    if !u.is_finite() || max == 0 {
        return Pwm::default();
    }
    let a = if u < 0.0 { -u } else { u };
    let ticks = a * (f64::from(max) / U_MAX) + 0.5;
    let duty = if ticks >= f64::from(max) {
        max
    } else {
        ticks as u16
    };
    Pwm {
        duty,
        forward: u >= 0.0 || duty == 0,
    }
}

/// The (average) voltage [V] a PWM command applies on a timer whose full duty is `max`.
pub fn pwm_volts_for(p: Pwm, max: u16) -> f64 {
    if max == 0 {
        return 0.0;
    }
    let v = f64::from(p.duty) * U_MAX / f64::from(max);
    if p.forward {
        v
    } else {
        -v
    }
}

/// Encoder scale and zero of the five channels `x, y, L, alpha, beta`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EncoderScale {
    /// Position per count [m or rad].
    pub res: [f64; 5],
    /// Position of count 0 [m or rad].
    pub zero: [f64; 5],
}

/// One of the five encoder channels, in model order. A channel is a type, not an index, so
/// [`EncoderScale`] cannot be asked for a sixth one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    /// Rail position `x` [m].
    X,
    /// Trolley position `y` [m].
    Y,
    /// Rope length `L` [m].
    L,
    /// Swing angle `alpha` [rad].
    Alpha,
    /// Swing angle `beta` [rad].
    Beta,
}

impl Channel {
    /// The five channels in model order `x, y, L, alpha, beta`.
    pub const ALL: [Channel; 5] = [
        Channel::X,
        Channel::Y,
        Channel::L,
        Channel::Alpha,
        Channel::Beta,
    ];

    /// Index of the channel in model order (0..5).
    pub const fn index(self) -> usize {
        self as usize
    }
}

/// Encoder counts per revolution of the INTECO rig.
pub const COUNTS_PER_REV: f64 = 4096.0;

impl EncoderScale {
    /// The INTECO 3D-Crane: 4096 counts per revolution on pulleys of radius 40 mm (X, Y) and
    /// 15 mm (rope), on the swing axes directly; angles count from the hanging position.
    pub const RIG: EncoderScale = EncoderScale {
        res: [
            2.0 * PI * 0.040 / COUNTS_PER_REV,
            2.0 * PI * 0.040 / COUNTS_PER_REV,
            2.0 * PI * 0.015 / COUNTS_PER_REV,
            2.0 * PI / COUNTS_PER_REV,
            2.0 * PI / COUNTS_PER_REV,
        ],
        zero: [0.0, 0.0, 0.0, FRAC_PI_2, 0.0],
    };

    /// Count an ideal encoder reports at position `q` of channel `ch` (floor of the cell),
    /// saturated to the `i32` range (NaN gives 0): no overflow whatever `q`.
    pub fn counts(&self, ch: Channel, q: f64) -> i32 {
        let i = ch.index();
        let x = (q - self.zero[i]) / self.res[i];
        // `as` truncates towards zero, saturates and maps NaN to 0; one below for the floor
        let c = x as i32;
        if f64::from(c) > x {
            c.saturating_sub(1)
        } else {
            c
        }
    }

    /// Position estimate of count `c` on channel `ch`: the centre of its cell.
    pub fn position(&self, ch: Channel, c: i32) -> f64 {
        let i = ch.index();
        self.zero[i] + (f64::from(c) + 0.5) * self.res[i]
    }
}
