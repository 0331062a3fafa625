//! PWM channels of a timer whose compare registers are preloaded (written values take effect
//! at the next update event, as on every STM32 timer in PWM mode): a zero duty is made
//! effective at once, so [`crate::hal::HBridge`]'s "duty 0, then switch the direction pins"
//! really switches with the bridge off.
//!
//! Without it, `set_duty_cycle(0)` only schedules the zero: the old duty keeps running until
//! the counter overflows (up to one PWM period, 25 us at 40 kHz) while the direction pins
//! already point the other way. `twin/tests/preload.rs` checks both on a model of the timer.

use embedded_hal::pwm::{ErrorType, SetDutyCycle};

/// A timer with preloaded compare registers.
pub trait PreloadedTimer {
    /// Full-scale compare value (the auto-reload + 1, in ticks).
    fn max_compare(&self) -> u16;
    /// Writes the preload compare register of channel `ch` (0-based).
    fn set_compare(&mut self, ch: usize, value: u16);
    /// Generates an update event now: every preloaded register becomes effective (on STM32:
    /// `EGR.UG`; it also restarts the counter, one shortened PWM period on every channel).
    fn force_update(&mut self);
}

/// Channel `ch` of a [`PreloadedTimer`] whose zero duty takes effect immediately; a non-zero
/// duty takes effect at the next update event (glitch-free).
#[derive(Debug)]
pub struct ZeroNowChannel<'a, T> {
    timer: &'a core::cell::RefCell<T>,
    ch: usize,
}

impl<'a, T: PreloadedTimer> ZeroNowChannel<'a, T> {
    /// Channel `ch` of `timer` (shared by the channels of one timer).
    pub fn new(timer: &'a core::cell::RefCell<T>, ch: usize) -> Self {
        ZeroNowChannel { timer, ch }
    }
}

/// The timer was busy (a `RefCell` borrowed elsewhere: cannot happen in a single-threaded
/// loop; reported instead of a panic).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimerBusy;

impl embedded_hal::pwm::Error for TimerBusy {
    fn kind(&self) -> embedded_hal::pwm::ErrorKind {
        embedded_hal::pwm::ErrorKind::Other
    }
}

impl<T: PreloadedTimer> ErrorType for ZeroNowChannel<'_, T> {
    type Error = TimerBusy;
}

impl<T: PreloadedTimer> SetDutyCycle for ZeroNowChannel<'_, T> {
    fn max_duty_cycle(&self) -> u16 {
        self.timer
            .try_borrow()
            .map(|t| t.max_compare())
            .unwrap_or(0)
    }

    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Self::Error> {
        let mut t = self.timer.try_borrow_mut().map_err(|_| TimerBusy)?;
        t.set_compare(self.ch, duty);
        if duty == 0 {
            t.force_update();
        }
        Ok(())
    }
}
