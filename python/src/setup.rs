//! What defines a simulator before its first step ([`Setup`]), and the CSV code of a mode.

use crane_model::{Config, Crane, Extensions, Mode, Params, State};

/// Everything that defines a simulator before its first step.
#[derive(Clone, Debug)]
pub struct Setup {
    /// Physical parameters (validated by [`Setup::build`]).
    pub params: Params,
    /// Step and friction law.
    pub config: Config,
    /// Model extensions (stiction...).
    pub ext: Extensions,
    /// Initial state.
    pub init: State,
}

impl Setup {
    /// The simulator, or the first rejected field.
    pub fn build(&self) -> Result<Crane, crane_model::Error> {
        Crane::new(&self.params, self.config, self.init)?.with_extensions(&self.ext)
    }
}

/// Mode as the CSV code: -1 negative, 0 stopped, 1 positive.
pub fn mode_code(m: Mode) -> i8 {
    match m {
        Mode::Negative => -1,
        Mode::Stopped => 0,
        Mode::Positive => 1,
    }
}
