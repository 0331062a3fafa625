//! The safety supervisor of a board beside the motor drivers, as pure logic (host-tested in
//! `twin/tests/safety.rs`; the STM32 board crate `board-stm32` feeds it the pins and the
//! period clock and writes what it decides).
//!
//! - [`Supervisor`]: a latching state machine. It starts [`State::Safe`] (power-on) and
//!   enters [`State::Run`] only through [`Supervisor::arm`] with every input clear. Any active
//!   input (e-stop, a limit switch, the driver's fault line) or too many missed periods force
//!   [`State::Safe`] with the first [`Cause`]; it stays there, whatever the inputs do, until
//!   re-armed. In the safe state every commanded voltage is 0 V, the driver is disabled and
//!   the hoist's brake is applied ([`Outputs`]).
//! - [`TickLatch`]: the period clock shared by the timer interrupt (one [`TickLatch::on_tick`]
//!   per 2 ms) and the loop ([`TickLatch::take`]), counting overruns (a tick that arrives while
//!   the previous one has not been taken). `u64` counters: they never wrap.
//! - [`extend_count`]: a 16-bit hardware encoder counter extended to `i32`.
//! - [`OnAlarm`]: what the supervisor does when the friction monitor raises an alarm: report
//!   only (the default), or derate the drives until the operator acknowledges.

/// Why the supervisor is in the safe state (the first cause; later ones do not replace it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Cause {
    /// Not armed yet since power-on (or reset).
    PowerOn,
    /// The emergency-stop input is active.
    EStop,
    /// A limit switch is active: drive axis (0 X, 1 Y, 2 rope) and end (`true` = positive).
    Limit {
        /// Drive axis 0 X, 1 Y, 2 rope.
        axis: u8,
        /// `true` for the limit at the positive end of travel.
        positive: bool,
    },
    /// The motor driver reports a fault (over-current, over-temperature, under-voltage).
    DriverFault,
    /// The loop missed more than [`Supervisor::MAX_MISSED`] periods in a row: its commands
    /// are stale.
    Overrun,
    /// The last reset came from the independent watchdog (the loop hung): the board stays
    /// safe until power-cycled.
    WatchdogReset,
}

/// The safety inputs sampled at a tick, each `true` when active (tripped). On the board the
/// contacts are normally closed to ground with pull-ups, so a broken wire reads active.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Inputs {
    /// Emergency stop.
    pub estop: bool,
    /// Motor-driver fault line.
    pub driver_fault: bool,
    /// Limit switches `[axis][end]`, end 0 negative, 1 positive; axes X, Y, rope.
    pub limits: [[bool; 2]; 3],
}

impl Inputs {
    /// The first active input as a cause (e-stop first, then the driver fault, then the
    /// limits in axis order), or `None` if all are clear.
    pub fn active(&self) -> Option<Cause> {
        if self.estop {
            return Some(Cause::EStop);
        }
        if self.driver_fault {
            return Some(Cause::DriverFault);
        }
        for (axis, ends) in self.limits.iter().enumerate() {
            for (end, &on) in ends.iter().enumerate() {
                if on {
                    return Some(Cause::Limit {
                        axis: axis as u8,
                        positive: end == 1,
                    });
                }
            }
        }
        None
    }
}

/// Supervisor state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum State {
    /// The loop's commands go to the drivers.
    Run,
    /// Outputs forced off, latched with the first cause.
    Safe(Cause),
}

/// What the board must drive in a state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outputs {
    /// Voltages [V] for the three H-bridges (the loop's command in `Run`, 0 in `Safe`).
    pub volts: [f64; 3],
    /// Driver enable line.
    pub driver_enable: bool,
    /// Hoist brake released (`false`: the spring-applied brake holds the load).
    pub brake_release: bool,
}

/// The outputs of the safe state: PWM 0, driver disabled, brake applied.
pub const SAFE_OUTPUTS: Outputs = Outputs {
    volts: [0.0; 3],
    driver_enable: false,
    brake_release: false,
};

/// What the supervisor does when the friction monitor raises an alarm (a setting).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum OnAlarm {
    /// The alarm is reported (its frame on the log) and the drives run on unchanged.
    #[default]
    ReportOnly,
    /// From the alarm on, every commanded voltage is limited to `percent` % of the supply
    /// (a slower, weaker crane on a worn part) until [`Supervisor::acknowledge`].
    Derate {
        /// Share of the supply voltage still allowed, 1..=99 (see [`OnAlarm::derate`]).
        percent: u8,
    },
}

impl OnAlarm {
    /// Derating to `percent` % of the supply; `None` outside 1..=99 (0 would stop the crane:
    /// that is the safe state's job; 100 would change nothing).
    pub fn derate(percent: u8) -> Option<Self> {
        (1..=99)
            .contains(&percent)
            .then_some(OnAlarm::Derate { percent })
    }
}

/// The latching safety state machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Supervisor {
    state: State,
    on_alarm: OnAlarm,
    derated: bool,
}

impl Default for Supervisor {
    fn default() -> Self {
        Self::new()
    }
}

impl Supervisor {
    /// Missed periods tolerated in one go (an overrun of up to 2 periods); more trips
    /// [`Cause::Overrun`]. The independent watchdog (about 10 ms) catches a loop that hangs.
    pub const MAX_MISSED: u64 = 2;

    /// A supervisor in the safe state ([`Cause::PowerOn`]).
    pub const fn new() -> Self {
        Supervisor {
            state: State::Safe(Cause::PowerOn),
            on_alarm: OnAlarm::ReportOnly,
            derated: false,
        }
    }

    /// The same supervisor acting on monitor alarms as `on_alarm` says.
    pub const fn with_on_alarm(mut self, on_alarm: OnAlarm) -> Self {
        self.on_alarm = on_alarm;
        self
    }

    /// The friction monitor raised an alarm: with [`OnAlarm::Derate`] the drives are derated
    /// from now on (whatever the state; the safe state still drives 0 V). Returns whether the
    /// outputs are derated.
    pub fn alarm(&mut self) -> bool {
        if let OnAlarm::Derate { .. } = self.on_alarm {
            self.derated = true;
        }
        self.derated
    }

    /// The operator acknowledged the alarms: full voltage again.
    pub fn acknowledge(&mut self) {
        self.derated = false;
    }

    /// Whether the outputs are derated.
    pub fn derated(&self) -> bool {
        self.derated
    }

    /// Current state.
    pub fn state(&self) -> State {
        self.state
    }

    /// Leaves the safe state if every input is clear; otherwise stays safe and returns the
    /// active cause (which replaces [`Cause::PowerOn`], never another latched cause). After a
    /// watchdog reset ([`Cause::WatchdogReset`] latched) it never arms: only a power-cycle
    /// (a new supervisor) does.
    pub fn arm(&mut self, inputs: &Inputs) -> Result<(), Cause> {
        if self.state == State::Safe(Cause::WatchdogReset) {
            return Err(Cause::WatchdogReset);
        }
        match inputs.active() {
            None => {
                self.state = State::Run;
                Ok(())
            }
            Some(c) => {
                if self.state == State::Safe(Cause::PowerOn) || self.state == State::Run {
                    self.state = State::Safe(c);
                }
                Err(c)
            }
        }
    }

    /// One tick: `inputs` sampled now and `missed` periods the loop missed since the last
    /// tick it took. Latches the first cause. Returns the new state.
    pub fn check(&mut self, inputs: &Inputs, missed: u64) -> State {
        if self.state == State::Run {
            if let Some(c) = inputs.active() {
                self.state = State::Safe(c);
            } else if missed > Self::MAX_MISSED {
                self.state = State::Safe(Cause::Overrun);
            }
        }
        self.state
    }

    /// Forces the safe state with `cause` (a fault path outside the inputs); replaces
    /// [`Cause::PowerOn`], keeps any other latched cause.
    pub fn trip(&mut self, cause: Cause) {
        if self.state == State::Run || self.state == State::Safe(Cause::PowerOn) {
            self.state = State::Safe(cause);
        }
    }

    /// Whether the period loop may feed the independent watchdog now (once per period, right
    /// after it took the tick and [`Supervisor::check`]ed it). A loop that lost its period
    /// ([`Cause::Overrun`] latched) is not healthy: it stops feeding, the watchdog resets the
    /// chip, and the reset latches [`Cause::WatchdogReset`] (safe until power-cycled). In any
    /// other state, safe ones included, the loop is alive and keeps its outputs driven off, so
    /// it feeds (a reset loop would leave the driver pins floating instead).
    pub fn feeds_watchdog(&self) -> bool {
        self.state != State::Safe(Cause::Overrun)
    }

    /// What to drive for the loop's command `volts` [V] in the current state (limited when
    /// derated; a NaN stays NaN and the PWM layer switches it off).
    pub fn outputs(&self, volts: [f64; 3]) -> Outputs {
        match self.state {
            State::Run => Outputs {
                volts: match (self.derated, self.on_alarm) {
                    (true, OnAlarm::Derate { percent }) => {
                        let limit = super::io::U_MAX * f64::from(percent) / 100.0;
                        volts.map(|v| {
                            if v > limit {
                                limit
                            } else if v < -limit {
                                -limit
                            } else {
                                v
                            }
                        })
                    }
                    _ => volts,
                },
                driver_enable: true,
                brake_release: true,
            },
            State::Safe(_) => SAFE_OUTPUTS,
        }
    }
}

/// The period clock between the timer interrupt and the loop.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TickLatch {
    ticks: u64,
    taken: u64,
    overruns: u64,
}

impl TickLatch {
    /// A clock with no tick yet.
    pub const fn new() -> Self {
        TickLatch {
            ticks: 0,
            taken: 0,
            overruns: 0,
        }
    }

    /// A tick (from the timer interrupt). Counts an overrun when the previous tick has not
    /// been taken by the loop.
    pub fn on_tick(&mut self) {
        if self.ticks > self.taken {
            self.overruns += 1;
        }
        self.ticks += 1;
    }

    /// Takes the latest tick: `None` if there is none since the last take, else the number of
    /// periods missed in between (0 when the loop kept up).
    pub fn take(&mut self) -> Option<u64> {
        if self.ticks == self.taken {
            return None;
        }
        let missed = self.ticks - self.taken - 1;
        self.taken = self.ticks;
        Some(missed)
    }

    /// Ticks since start.
    pub fn ticks(&self) -> u64 {
        self.ticks
    }

    /// Ticks that arrived before the loop took the previous one.
    pub fn overruns(&self) -> u64 {
        self.overruns
    }
}

/// Extends a 16-bit up/down counter read `raw` to `i32`, given the previous extended count
/// `last`: the difference is taken modulo 2^16 as a signed 16-bit step, so it is exact as long
/// as the counter moves less than 32768 counts between two reads (at 4096 counts per
/// revolution and a 2 ms period: 4000 rev/s). Wraps at the `i32` range.
pub fn extend_count(last: i32, raw: u16) -> i32 {
    let step = raw.wrapping_sub(last as u16) as i16;
    last.wrapping_add(i32::from(step))
}
