//! Direction changes happen with the bridge really off on a timer with preloaded compare
//! registers (`crane_twin::preload`), checked on a model of the timer; a plain channel that
//! only writes the preload register is shown to violate it (the test can fail).

use core::cell::{Cell, RefCell};
use crane_ident::rng::Rng;
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

/// A timer whose update events (every PWM period, 25 us) arrive at any point between the
/// bridge's register writes and pin changes, and the H-bridge's two direction pins. It
/// records every time the bridge would drive a non-zero duty in a direction other than the
/// one that duty was commanded with.
struct AsyncBridge {
    preload: u16,
    /// direction of the command that wrote `preload`
    preload_dir: Option<bool>,
    effective: u16,
    effective_dir: Option<bool>,
    /// IN1, IN2
    pins: [bool; 2],
    /// direction of the command being applied (set by the test)
    command_dir: Option<bool>,
    rng: Rng,
    updates: u32,
    reversals_under_load: u32,
}

impl AsyncBridge {
    fn new(seed: u64) -> Self {
        AsyncBridge {
            preload: 0,
            preload_dir: None,
            effective: 0,
            effective_dir: None,
            pins: [false; 2],
            command_dir: None,
            rng: Rng::new(seed),
            updates: 0,
            reversals_under_load: 0,
        }
    }
    fn pin_dir(&self) -> Option<bool> {
        match self.pins {
            [true, false] => Some(true),
            [false, true] => Some(false),
            _ => None,
        }
    }
    fn update_event(&mut self) {
        self.effective = self.preload;
        self.effective_dir = self.preload_dir;
        self.updates += 1;
        self.audit();
    }
    /// An update event with probability 1/2.
    fn maybe_update(&mut self) {
        if self.rng.below(2) == 1 {
            self.update_event();
        }
    }
    /// A non-zero duty in effect must be driven in its own command's direction.
    fn audit(&mut self) {
        if self.effective != 0 && self.pin_dir() != self.effective_dir {
            self.reversals_under_load += 1;
        }
    }
    fn set_pin(&mut self, k: usize, level: bool) {
        self.pins[k] = level;
        self.audit();
        self.maybe_update();
    }
}

impl PreloadedTimer for AsyncBridge {
    fn max_compare(&self) -> u16 {
        4200
    }
    fn set_compare(&mut self, _ch: usize, value: u16) {
        self.preload = value;
        self.preload_dir = self.command_dir;
        self.maybe_update();
    }
    fn force_update(&mut self) {
        self.update_event();
    }
}

struct AsyncPin<'a>(&'a RefCell<AsyncBridge>, usize);

impl ErrorType for AsyncPin<'_> {
    type Error = Infallible;
}
impl OutputPin for AsyncPin<'_> {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.0.borrow_mut().set_pin(self.1, false);
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.0.borrow_mut().set_pin(self.1, true);
        Ok(())
    }
}

/// A channel of the asynchronous timer that only writes the preload register.
struct AsyncPlain<'a>(&'a RefCell<AsyncBridge>);

impl embedded_hal::pwm::ErrorType for AsyncPlain<'_> {
    type Error = Infallible;
}
impl SetDutyCycle for AsyncPlain<'_> {
    fn max_duty_cycle(&self) -> u16 {
        4200
    }
    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
        self.0.borrow_mut().set_compare(0, duty);
        Ok(())
    }
}

/// Runs [`COMMANDS`] through an H-bridge on `timer`; returns the reversals commanded.
fn one_schedule<P: SetDutyCycle>(timer: &RefCell<AsyncBridge>, pwm: P) -> u32 {
    let mut bridge = HBridge::new(pwm, AsyncPin(timer, 0), AsyncPin(timer, 1));
    let mut reversals = 0;
    let mut last = None;
    for u in COMMANDS {
        let dir = (u != 0.0).then_some(u > 0.0);
        if dir.is_some() && last.is_some() && dir != last {
            reversals += 1;
        }
        last = dir.or(last);
        timer.borrow_mut().command_dir = dir;
        bridge.set_voltage(u).map_err(|_| ()).expect("no error");
        // the PWM runs on: several periods before the next command
        for _ in 0..3 {
            timer.borrow_mut().update_event();
        }
    }
    reversals
}

/// 500 schedules of update events, with [`ZeroNowChannel`] or a plain channel; returns
/// (reversals, update events, non-zero duties in effect against their direction).
fn run_async(zero_now: bool) -> (u32, u32, u32) {
    let (mut reversals, mut updates, mut bad) = (0, 0, 0);
    for seed in 1..=500u64 {
        let timer = RefCell::new(AsyncBridge::new(seed));
        reversals += if zero_now {
            one_schedule(&timer, ZeroNowChannel::new(&timer, 0))
        } else {
            one_schedule(&timer, AsyncPlain(&timer))
        };
        let t = timer.borrow();
        updates += t.updates;
        bad += t.reversals_under_load;
    }
    (reversals, updates, bad)
}

#[test]
fn a_reversal_never_drives_a_duty_in_the_new_direction_before_the_zero_is_latched() {
    // update events anywhere between the bridge's writes: the zero is latched (by the channel's
    // own update event) before a pin moves, and a non-zero duty only takes effect with the
    // pins of its own command
    let (reversals, updates, bad) = run_async(true);
    assert!(reversals >= 500 * 4, "{reversals} reversals");
    assert!(updates > 500 * 12 * 3, "{updates} update events");
    assert_eq!(bad, 0);
    // the same schedules with a channel that only preloads the zero: caught
    let (_, _, plain_bad) = run_async(false);
    assert!(plain_bad >= 500, "plain channel: {plain_bad}");
}
