//! Direction changes happen with the bridge really off on a timer with preloaded compare
//! registers (`crane_twin::preload`), checked on a model of the timer; a plain channel that
//! only writes the preload register is shown to violate it (the test can fail).

use core::cell::{Cell, RefCell};
use crane_twin::hal::{HBridge, MotorDrive};
use crane_twin::preload::{PreloadedTimer, ZeroNowChannel};
use embedded_hal::digital::{ErrorType, OutputPin};
use embedded_hal::pwm::SetDutyCycle;
use std::convert::Infallible;

/// Preload and effective (shadow) compare registers of three channels.
#[derive(Default)]
struct Timer {
    preload: [u16; 3],
    effective: [u16; 3],
    updates: u32,
}

impl Timer {
    fn update_event(&mut self) {
        self.effective = self.preload;
        self.updates += 1;
    }
}

impl PreloadedTimer for Timer {
    fn max_compare(&self) -> u16 {
        4200
    }
    fn set_compare(&mut self, ch: usize, value: u16) {
        self.preload[ch] = value;
    }
    fn force_update(&mut self) {
        self.update_event();
    }
}

/// A channel that only writes the preload register (what a plain HAL channel does).
struct PlainChannel<'a>(&'a RefCell<Timer>, usize);

impl embedded_hal::pwm::ErrorType for PlainChannel<'_> {
    type Error = Infallible;
}
impl SetDutyCycle for PlainChannel<'_> {
    fn max_duty_cycle(&self) -> u16 {
        4200
    }
    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
        self.0.borrow_mut().preload[self.1] = duty;
        Ok(())
    }
}

/// A direction pin that records a level change while the channel's effective duty is not 0.
struct Pin<'a> {
    timer: &'a RefCell<Timer>,
    ch: usize,
    level: bool,
    changes: &'a Cell<u32>,
    violations: &'a Cell<u32>,
}

impl Pin<'_> {
    fn set(&mut self, level: bool) {
        if level != self.level {
            self.changes.set(self.changes.get() + 1);
            if self.timer.borrow().effective[self.ch] != 0 {
                self.violations.set(self.violations.get() + 1);
            }
            self.level = level;
        }
    }
}
impl ErrorType for Pin<'_> {
    type Error = Infallible;
}
impl OutputPin for Pin<'_> {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.set(false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.set(true);
        Ok(())
    }
}

/// Voltages with reversals, zero crossings and holds.
const COMMANDS: [f64; 12] = [
    3.0, 6.0, -4.0, -4.0, 0.0, 2.0, -12.0, 12.0, 0.5, 0.0, -0.5, 7.0,
];

/// Drives a bridge through [`COMMANDS`] with an update event between commands (the PWM
/// period, 25 us, is much shorter than the 2 ms control period); returns (pin changes,
/// changes with a non-zero effective duty).
fn run<P: SetDutyCycle>(timer: &RefCell<Timer>, pwm: P) -> (u32, u32) {
    let changes = Cell::new(0);
    let violations = Cell::new(0);
    let pin = |level| Pin {
        timer,
        ch: 1,
        level,
        changes: &changes,
        violations: &violations,
    };
    let mut bridge = HBridge::new(pwm, pin(false), pin(false));
    for u in COMMANDS {
        let applied = bridge.set_voltage(u).map_err(|_| ()).expect("no error");
        assert!((applied - u).abs() < 12.0 / 4200.0, "{applied} for {u}");
        timer.borrow_mut().update_event();
        // after the update event the commanded duty is in effect
        let eff = timer.borrow().effective[1];
        assert_eq!(eff, (u.abs() * 4200.0 / 12.0).round() as u16);
    }
    (changes.get(), violations.get())
}

#[test]
fn direction_changes_only_with_the_zero_duty_in_effect() {
    let timer = RefCell::new(Timer::default());
    let (changes, violations) = run(&timer, ZeroNowChannel::new(&timer, 1));
    assert!(
        changes >= 8,
        "the commands reverse often: {changes} pin changes"
    );
    assert_eq!(violations, 0);
}

#[test]
fn a_channel_that_only_preloads_the_zero_switches_under_load() {
    let timer = RefCell::new(Timer::default());
    let (changes, violations) = run(&timer, PlainChannel(&timer, 1));
    assert!(changes >= 8);
    assert!(
        violations >= 3,
        "the old duty is still in effect at a reversal: {violations}"
    );
}

#[test]
fn zero_now_channel_reports_the_timer_scale() {
    let timer = RefCell::new(Timer::default());
    let mut ch = ZeroNowChannel::new(&timer, 2);
    assert_eq!(ch.max_duty_cycle(), 4200);
    ch.set_duty_cycle(100).expect("free");
    assert_eq!(
        timer.borrow().effective[2],
        0,
        "non-zero waits for the update"
    );
    assert_eq!(timer.borrow().updates, 0);
    ch.set_duty_cycle(0).expect("free");
    assert_eq!(timer.borrow().updates, 1, "zero forces the update");
    assert_eq!(timer.borrow().effective[2], 0);
}
