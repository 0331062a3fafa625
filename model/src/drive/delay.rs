//! The drive's input delay line: a fixed-capacity ring of past inputs, no heap.

use super::params::MAX_DRIVE_DELAY_STEPS;
use crate::real::Real;

/// The last [`MAX_DRIVE_DELAY_STEPS`] accepted inputs (zeros before the first step).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DelayLine<R> {
    buf: [R; MAX_DRIVE_DELAY_STEPS],
    /// Slot of the most recent accepted input.
    head: usize,
}

impl<R: Real> DelayLine<R> {
    /// An empty line: every past input is 0.
    pub(crate) fn new() -> Self {
        DelayLine {
            buf: [R::ZERO; MAX_DRIVE_DELAY_STEPS],
            head: 0,
        }
    }

    /// The input to apply now when the current input is `u` and the delay is `k` steps
    /// (`k <= MAX_DRIVE_DELAY_STEPS`): `u` for 0, else the input accepted `k` steps ago.
    /// Does not change the line (a rejected step must not shift it).
    #[inline]
    pub(crate) fn delayed(&self, u: R, k: usize) -> R {
        if k == 0 {
            return u;
        }
        let n = MAX_DRIVE_DELAY_STEPS;
        let idx = (self.head + n - (k - 1) % n) % n;
        self.buf.get(idx).copied().unwrap_or(R::ZERO)
    }

    /// Records an accepted input, overwriting the oldest.
    #[inline]
    pub(crate) fn push(&mut self, u: R) {
        self.head = (self.head + 1) % MAX_DRIVE_DELAY_STEPS;
        if let Some(slot) = self.buf.get_mut(self.head) {
            *slot = u;
        }
    }
}
