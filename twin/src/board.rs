//! The QEMU "board": embedded-hal PWM channels, direction pins and encoders whose other side
//! is the simulated plant ([`SimPlant`], the model with perturbed parameters). The loop runs on
//! it exactly as on a real board (through [`HalIo`]); the ticker advances the plant by one
//! period. Single-threaded: the parts share the plant through `Cell`/`RefCell`, and a busy
//! `RefCell` is reported as an encoder error, never a panic.

use crate::hal::{Encoder, HBridge, HalIo, Ticker};
use crate::logic::io::{Pwm, PWM_MAX};
use crate::logic::plant::SimPlant;
use core::cell::{Cell, RefCell};
use core::convert::Infallible;
use crane_model::State;

/// The wires between the loop's hardware and the simulated plant.
#[derive(Debug)]
pub struct SimBus {
    plant: RefCell<SimPlant>,
    duty: [Cell<u16>; 3],
    in1: [Cell<bool>; 3],
    in2: [Cell<bool>; 3],
    fault: [Cell<bool>; 5],
}

/// A PWM channel of the simulated board (full duty [`PWM_MAX`]).
#[derive(Debug)]
pub struct SimPwm<'a> {
    bus: &'a SimBus,
    axis: usize,
}

/// A direction pin of the simulated board.
#[derive(Debug)]
pub struct SimPin<'a> {
    bus: &'a SimBus,
    axis: usize,
    second: bool,
}

/// An encoder of the simulated board.
#[derive(Debug)]
pub struct SimEncoder<'a> {
    bus: &'a SimBus,
    channel: usize,
}

/// The period timer of the simulated board: advances the plant.
#[derive(Debug)]
pub struct SimTicker<'a> {
    bus: &'a SimBus,
}

/// An encoder read that failed (injected fault or plant busy).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EncoderFault;

/// One H-bridge of the simulated board.
pub type SimBridge<'a> = HBridge<SimPwm<'a>, SimPin<'a>, SimPin<'a>>;

/// The simulated board as the loop's I/O.
pub type BoardIo<'a> = HalIo<
    (SimBridge<'a>, SimBridge<'a>, SimBridge<'a>),
    (
        SimEncoder<'a>,
        SimEncoder<'a>,
        SimEncoder<'a>,
        SimEncoder<'a>,
        SimEncoder<'a>,
    ),
    SimTicker<'a>,
>;

impl SimBus {
    /// Wires up `plant`.
    pub fn new(plant: SimPlant) -> Self {
        SimBus {
            plant: RefCell::new(plant),
            duty: Default::default(),
            in1: Default::default(),
            in2: Default::default(),
            fault: Default::default(),
        }
    }

    /// The board's parts, assembled as the loop's I/O (H-bridges, encoders, ticker).
    pub fn io(&self) -> BoardIo<'_> {
        let bridge = |axis| {
            HBridge::new(
                SimPwm { bus: self, axis },
                SimPin {
                    bus: self,
                    axis,
                    second: false,
                },
                SimPin {
                    bus: self,
                    axis,
                    second: true,
                },
            )
        };
        let enc = |channel| SimEncoder { bus: self, channel };
        HalIo {
            drives: (bridge(0), bridge(1), bridge(2)),
            encoders: (enc(0), enc(1), enc(2), enc(3), enc(4)),
            ticker: SimTicker { bus: self },
        }
    }

    /// Makes encoder `channel` fail (or work again).
    pub fn set_encoder_fault(&self, channel: usize, failing: bool) {
        if let Some(f) = self.fault.get(channel) {
            f.set(failing);
        }
    }

    /// The plant's true state (None while it is busy, which cannot happen between calls).
    pub fn plant_state(&self) -> Option<State<f64>> {
        self.plant.try_borrow().ok().map(|p| p.state())
    }

    /// The PWM command the pins currently express for `axis` (one pin high gives the
    /// direction; both low or both high apply nothing).
    fn command(&self, axis: usize) -> Pwm {
        let (a, b) = (self.in1[axis].get(), self.in2[axis].get());
        let duty = self.duty[axis].get();
        if duty == 0 || a == b {
            Pwm {
                duty: 0,
                forward: true,
            }
        } else {
            Pwm { duty, forward: a }
        }
    }
}

impl embedded_hal::pwm::ErrorType for SimPwm<'_> {
    type Error = Infallible;
}

impl embedded_hal::pwm::SetDutyCycle for SimPwm<'_> {
    fn max_duty_cycle(&self) -> u16 {
        PWM_MAX
    }

    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Self::Error> {
        self.bus.duty[self.axis].set(if duty > PWM_MAX { PWM_MAX } else { duty });
        Ok(())
    }
}

impl embedded_hal::digital::ErrorType for SimPin<'_> {
    type Error = Infallible;
}

impl embedded_hal::digital::OutputPin for SimPin<'_> {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        self.set(false);
        Ok(())
    }

    fn set_high(&mut self) -> Result<(), Self::Error> {
        self.set(true);
        Ok(())
    }
}

impl SimPin<'_> {
    fn set(&self, level: bool) {
        let pins = if self.second {
            &self.bus.in2
        } else {
            &self.bus.in1
        };
        pins[self.axis].set(level);
    }
}

impl Encoder for SimEncoder<'_> {
    type Error = EncoderFault;

    fn count(&mut self) -> Result<i32, EncoderFault> {
        if self.bus.fault[self.channel].get() {
            return Err(EncoderFault);
        }
        let plant = self.bus.plant.try_borrow().map_err(|_| EncoderFault)?;
        Ok(plant.counts()[self.channel])
    }
}

impl Ticker for SimTicker<'_> {
    fn wait(&mut self) {
        if let Ok(mut plant) = self.bus.plant.try_borrow_mut() {
            for axis in 0..3 {
                plant.set_pwm(axis, self.bus.command(axis));
            }
            plant.advance();
        }
    }

    fn truth(&self) -> Option<State<f64>> {
        self.bus.plant_state()
    }
}
