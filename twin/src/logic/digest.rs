//! FNV-1a (64 bit) over the exact bits of every step, and the per-step record.

use crane_model::{Mode, Real, State};

/// FNV-1a, 64 bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fnv(pub u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Mixes one byte.
    pub fn byte(&mut self, b: u8) {
        self.0 ^= u64::from(b);
        self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
    }

    /// Mixes a `u64`, little-endian.
    pub fn u64(&mut self, v: u64) {
        for b in v.to_le_bytes() {
            self.byte(b);
        }
    }

    /// Mixes the bits of a state (each component widened exactly to f64), the modes and a
    /// result code.
    pub fn step<R: Real>(&mut self, s: &State<R>, modes: &[Mode; 3], code: u8) {
        for v in s.q.iter().chain(s.qd.iter()) {
            self.u64(v.to_f64().to_bits());
        }
        for m in modes {
            self.byte(mode_digit(*m));
        }
        self.byte(code);
    }
}

/// `0` Negative, `1` Stopped, `2` Positive.
pub fn mode_digit(m: Mode) -> u8 {
    match m {
        Mode::Negative => 0,
        Mode::Stopped => 1,
        Mode::Positive => 2,
    }
}

/// Writes `" {modes} {10 x 16 hex digits}"` (the exact bits of the state, widened to f64).
pub fn write_state<R: Real, W: core::fmt::Write>(
    out: &mut W,
    s: &State<R>,
    modes: &[Mode; 3],
) -> core::fmt::Result {
    write!(
        out,
        " {}{}{}",
        mode_digit(modes[0]),
        mode_digit(modes[1]),
        mode_digit(modes[2])
    )?;
    for v in s.q.iter().chain(s.qd.iter()) {
        write!(out, " {:016x}", v.to_f64().to_bits())?;
    }
    Ok(())
}
