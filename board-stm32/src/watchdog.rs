//! The independent watchdog (IWDG) and the reset cause, as pure values (host-tested in
//! `host-tests/tests/board_pure.rs`; the register writes are in [`crate::regs`]).
//!
//! The IWDG counts the LSI oscillator, which RM0090 / the STM32F405 datasheet only bound to
//! 17-47 kHz (32 kHz typical): a timeout of [`TIMEOUT_US`] nominal is 6.8-18.8 ms on a given
//! chip. The prescaler and reload are computed here rather than by `stm32f4xx-hal`'s
//! `IndependentWatchdog::start`, whose computation is private (so its values cannot be
//! checked against the LSI range) and coarse (for 10 ms it picks /64 with 5 counts of 2 ms).
//!
//! After a watchdog reset the board must stay safe until power-cycled: the reset flags in
//! `RCC_CSR` survive every reset but a power-on one, so the firmware does not clear them
//! after a watchdog reset ([`ResetCause::clear_flags`]), and a later pin or software reset
//! still reads as a watchdog reset.

use crane_twin::logic::safety::{Cause, Inputs, Supervisor};

/// LSI frequency range [Hz] (STM32F405/407 datasheet, "LSI oscillator characteristics").
pub const LSI_HZ_MIN: u32 = 17_000;
/// Typical LSI frequency [Hz], the nominal the configuration is computed for.
pub const LSI_HZ_TYP: u32 = 32_000;
/// LSI frequency range [Hz], upper bound.
pub const LSI_HZ_MAX: u32 = 47_000;
/// The nominal watchdog timeout [us] (at [`LSI_HZ_TYP`]).
pub const TIMEOUT_US: u32 = 10_000;

/// `IWDG_PR` and `IWDG_RLR` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IwdgConfig {
    /// Prescaler code `PR[2:0]`: divider 4 << pr (0..=6).
    pub pr: u8,
    /// Reload value `RL[11:0]`: the counter counts `rlr + 1` prescaled LSI periods.
    pub rlr: u16,
}

impl IwdgConfig {
    /// The finest prescaler whose 12-bit reload reaches `timeout_us` at [`LSI_HZ_TYP`]
    /// (rounded to the nearest count); `None` if no prescaler reaches it or it is below one
    /// count.
    pub const fn for_timeout_us(timeout_us: u32) -> Option<IwdgConfig> {
        let mut pr = 0u8;
        while pr <= 6 {
            let div = 4u64 << pr;
            // counts = timeout * LSI / div, rounded
            let counts =
                (timeout_us as u64 * LSI_HZ_TYP as u64 + div * 500_000) / (div * 1_000_000);
            if counts >= 1 && counts <= 4096 {
                return Some(IwdgConfig {
                    pr,
                    rlr: (counts - 1) as u16,
                });
            }
            pr += 1;
        }
        None
    }

    /// The prescaler's divider of the LSI.
    pub const fn divider(&self) -> u32 {
        4 << self.pr
    }

    /// The timeout [us] on a chip whose LSI runs at `lsi_hz` (rounded down).
    pub const fn timeout_us(&self, lsi_hz: u32) -> u32 {
        ((self.rlr as u64 + 1) * self.divider() as u64 * 1_000_000 / lsi_hz as u64) as u32
    }
}

/// The board's watchdog configuration ([`TIMEOUT_US`] nominal).
pub const IWDG: IwdgConfig = match IwdgConfig::for_timeout_us(TIMEOUT_US) {
    Some(c) => c,
    None => IwdgConfig { pr: 6, rlr: 0xFFF },
};

/// `RCC_CSR.IWDGRSTF`: the last reset came from the independent watchdog.
pub const RCC_CSR_IWDGRSTF: u32 = 1 << 29;
/// `RCC_CSR.WWDGRSTF`: from the window watchdog (not used; treated the same).
pub const RCC_CSR_WWDGRSTF: u32 = 1 << 30;

/// What the firmware makes of `RCC_CSR` at start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ResetCause {
    /// A watchdog reset (now or at any reset since the last power-on).
    pub watchdog: bool,
    /// Whether to clear the reset flags (`RMVF`): only after a clean reset, so a watchdog
    /// reset stays visible across later non-power resets.
    pub clear_flags: bool,
}

impl ResetCause {
    /// Decodes `RCC_CSR`.
    pub const fn from_rcc_csr(csr: u32) -> ResetCause {
        let watchdog = csr & (RCC_CSR_IWDGRSTF | RCC_CSR_WWDGRSTF) != 0;
        ResetCause {
            watchdog,
            clear_flags: !watchdog,
        }
    }

    /// Arms `sup` at start: after a watchdog reset it latches [`Cause::WatchdogReset`] (and
    /// [`Supervisor::arm`] refuses from then on); otherwise it arms if every input is clear.
    pub fn arm(&self, sup: &mut Supervisor, inputs: &Inputs) -> Result<(), Cause> {
        if self.watchdog {
            sup.trip(Cause::WatchdogReset);
            return Err(Cause::WatchdogReset);
        }
        sup.arm(inputs)
    }
}
