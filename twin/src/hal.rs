//! The hardware boundary on embedded-hal 1.0.
//!
//! A board crate provides, per drive axis, a PWM channel (`embedded_hal::pwm::SetDutyCycle`)
//! and two direction pins (`embedded_hal::digital::OutputPin`, IN1/IN2 of an H-bridge such
//! as the TB6612FNG or the rig's power interface), five quadrature counters behind
//! [`Encoder`] (embedded-hal has no encoder trait), and a [`Ticker`] that returns at the start
//! of each control period. [`HalIo`] turns them into the loop's [`Io`].

use crate::logic::control::{Io, IoError};
use crate::logic::io::{pwm_command_for, pwm_volts_for};
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::OutputPin;
use embedded_hal::pwm::SetDutyCycle;

/// A position counter (quadrature encoder), in counts since its zero.
pub trait Encoder {
    /// Error of a read.
    type Error;
    /// Current count.
    fn count(&mut self) -> Result<i32, Self::Error>;
}

/// Something that sets an axis voltage.
pub trait MotorDrive {
    /// Error of a write.
    type Error;
    /// Applies voltage `u` [V] (saturated to +-12 V; non-finite switches the motor off) and
    /// returns the voltage really applied after PWM quantisation.
    fn set_voltage(&mut self, u: f64) -> Result<f64, Self::Error>;
}

/// Error of an [`HBridge`], naming the part that failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriverError<P, A, B> {
    /// The PWM channel.
    Pwm(P),
    /// Direction pin IN1.
    In1(A),
    /// Direction pin IN2.
    In2(B),
}

/// One H-bridge: PWM duty for the magnitude, IN1/IN2 for the direction (IN1 high = positive
/// voltage; both low at zero duty).
#[derive(Debug)]
pub struct HBridge<PWM, IN1, IN2> {
    pwm: PWM,
    in1: IN1,
    in2: IN2,
    forward: Option<bool>,
}

impl<PWM, IN1, IN2> HBridge<PWM, IN1, IN2>
where
    PWM: SetDutyCycle,
    IN1: OutputPin,
    IN2: OutputPin,
{
    /// Takes the PWM channel and the two direction pins.
    pub fn new(pwm: PWM, in1: IN1, in2: IN2) -> Self {
        HBridge {
            pwm,
            in1,
            in2,
            forward: None,
        }
    }

    /// Gives the parts back.
    pub fn release(self) -> (PWM, IN1, IN2) {
        (self.pwm, self.in1, self.in2)
    }
}

impl<PWM, IN1, IN2> MotorDrive for HBridge<PWM, IN1, IN2>
where
    PWM: SetDutyCycle,
    IN1: OutputPin,
    IN2: OutputPin,
{
    type Error = DriverError<PWM::Error, IN1::Error, IN2::Error>;

    fn set_voltage(&mut self, u: f64) -> Result<f64, Self::Error> {
        let max = self.pwm.max_duty_cycle();
        let cmd = pwm_command_for(u, max);
        let dir = if cmd.duty == 0 {
            None
        } else {
            Some(cmd.forward)
        };
        if dir != self.forward {
            // Switch off before changing direction (no shoot-through, no glitch).
            self.pwm.set_duty_cycle(0).map_err(DriverError::Pwm)?;
            match dir {
                Some(true) => {
                    self.in2.set_low().map_err(DriverError::In2)?;
                    self.in1.set_high().map_err(DriverError::In1)?;
                }
                Some(false) => {
                    self.in1.set_low().map_err(DriverError::In1)?;
                    self.in2.set_high().map_err(DriverError::In2)?;
                }
                None => {
                    self.in1.set_low().map_err(DriverError::In1)?;
                    self.in2.set_low().map_err(DriverError::In2)?;
                }
            }
            self.forward = dir;
        }
        self.pwm
            .set_duty_cycle(cmd.duty)
            .map_err(DriverError::Pwm)?;
        Ok(pwm_volts_for(cmd, max))
    }
}

/// Waits for the start of the next control period.
pub trait Ticker {
    /// Returns at the start of the next period.
    fn wait(&mut self);
    /// The true plant state, on a simulated board only (there the ticker advances the plant).
    fn truth(&self) -> Option<crane_model::State<f64>> {
        None
    }
}

/// A [`Ticker`] from an embedded-hal delay: sleeps a fixed time (the computation time is not
/// subtracted; a real board should use a timer interrupt instead).
#[derive(Debug)]
pub struct DelayTicker<D> {
    /// The delay.
    pub delay: D,
    /// Sleep per period [ns].
    pub period_ns: u32,
}

impl<D: DelayNs> Ticker for DelayTicker<D> {
    fn wait(&mut self) {
        self.delay.delay_ns(self.period_ns);
    }
}

/// The five encoders `x, y, L, alpha, beta` (any five types).
pub trait EncoderSet {
    /// Reads all five; a failed channel is reported on its own.
    fn read_all(&mut self) -> [Result<i32, IoError>; 5];
}

impl<A: Encoder, B: Encoder, C: Encoder, D: Encoder, E: Encoder> EncoderSet for (A, B, C, D, E) {
    fn read_all(&mut self) -> [Result<i32, IoError>; 5] {
        [
            self.0.count().map_err(|_| IoError::Encoder(0)),
            self.1.count().map_err(|_| IoError::Encoder(1)),
            self.2.count().map_err(|_| IoError::Encoder(2)),
            self.3.count().map_err(|_| IoError::Encoder(3)),
            self.4.count().map_err(|_| IoError::Encoder(4)),
        ]
    }
}

/// The three drives X, Y, rope (any three types).
pub trait DriveSet {
    /// Sets the three voltages; returns the applied ones. On an error the remaining axes are
    /// still written; the first failing axis is reported.
    fn write_all(&mut self, u: [f64; 3]) -> Result<[f64; 3], IoError>;
}

impl<A: MotorDrive, B: MotorDrive, C: MotorDrive> DriveSet for (A, B, C) {
    fn write_all(&mut self, u: [f64; 3]) -> Result<[f64; 3], IoError> {
        let a = self.0.set_voltage(u[0]).map_err(|_| IoError::Driver(0));
        let b = self.1.set_voltage(u[1]).map_err(|_| IoError::Driver(1));
        let c = self.2.set_voltage(u[2]).map_err(|_| IoError::Driver(2));
        Ok([a?, b?, c?])
    }
}

/// Drives, encoders and ticker as the loop's [`Io`].
#[derive(Debug)]
pub struct HalIo<D, E, T> {
    /// The three motor drives.
    pub drives: D,
    /// The five encoders.
    pub encoders: E,
    /// The period ticker.
    pub ticker: T,
}

impl<D: DriveSet, E: EncoderSet, T: Ticker> Io for HalIo<D, E, T> {
    fn read(&mut self) -> [Result<i32, IoError>; 5] {
        self.encoders.read_all()
    }

    fn write(&mut self, u: [f64; 3]) -> Result<[f64; 3], IoError> {
        self.drives.write_all(u)
    }

    fn wait(&mut self) {
        self.ticker.wait();
    }

    fn truth(&self) -> Option<crane_model::State<f64>> {
        self.ticker.truth()
    }
}
