//! What a rejected FMI call returns ([`Failure`]: status and message) and where an instance
//! is in the FMI 2.0 co-simulation state machine ([`Phase`]); read by the instance and by its
//! snapshots.

/// FMI 2.0 status codes the instance reports (`fmi2Status`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// `fmi2Warning` (1).
    Warning = 1,
    /// `fmi2Discard` (2).
    Discard = 2,
    /// `fmi2Error` (3).
    Error = 3,
    /// `fmi2Fatal` (4).
    Fatal = 4,
}

/// A rejected call: the status to return and the message for the logger.
#[derive(Clone, Debug, PartialEq)]
pub struct Failure {
    /// Status to return.
    pub status: Status,
    /// Message (one line).
    pub message: String,
}

impl Failure {
    /// An `fmi2Error` with `message`.
    pub fn error(message: impl Into<String>) -> Self {
        Failure {
            status: Status::Error,
            message: message.into(),
        }
    }
}

/// Where the instance is in the FMI 2.0 co-simulation state machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// After `fmi2Instantiate` or `fmi2Reset` (and `fmi2SetupExperiment`).
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    Initialization,
    /// Stepping.
    StepComplete,
    /// After `fmi2Terminate`.
    Terminated,
    /// A step or a parameter change failed: only get, reset, terminate and free are allowed.
    Failed,
}
