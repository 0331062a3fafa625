//! A tiny deterministic integer PRNG (xorshift32) and exact integer-to-float conversions, so
//! the firmware and the host generate the same input sequences bit for bit.
//!
//! It stays apart from the host's generator (`crane_ident::rng`, `rand_xoshiro`): it runs in
//! the `no_std` firmware on the Cortex-M4 (32-bit state, no heap, no float), and the QEMU
//! cross-checks compare the twin's scenario and rig inputs drawn here against the host's bit
//! for bit.

/// xorshift32 (Marsaglia). Never zero.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Prng(u32);

impl Prng {
    /// Seeds the generator (a zero seed is replaced by a fixed nonzero one).
    pub const fn new(seed: u32) -> Self {
        Prng(if seed == 0 { 0x9E37_79B9 } else { seed })
    }

    /// Next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        x
    }

    /// Uniform in `[-1, 1)` on a grid of `2^-23`: 24 random bits, converted and scaled
    /// exactly (no rounding anywhere, in f64 or f32).
    pub fn uniform(&mut self) -> f64 {
        f64::from(self.next_u32() >> 8) / 8_388_608.0 - 1.0
    }

    /// Uniform integer in `lo..=hi` (`hi >= lo`), by modulo (the bias is irrelevant here).
    pub fn range(&mut self, lo: u32, hi: u32) -> u32 {
        let span = hi.wrapping_sub(lo).wrapping_add(1);
        if span == 0 {
            self.next_u32()
        } else {
            lo + self.next_u32() % span
        }
    }
}
