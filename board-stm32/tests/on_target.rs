//! On-target tests for a real STM32F405/407 board (Nucleo/Discovery class, 8 MHz HSE), run by
//! `probe-rs run` as the cargo runner:
//!
//! ```sh
//! cargo test -p board-stm32 --target thumbv7em-none-eabihf --features board,probe --test on_target
//! ```
//!
//! They check what QEMU cannot: the clock tree and the ART, the real preload behaviour of TIM1
//! (a zero duty takes effect at once, observed on the pin), the safe state on TIM1, the 2 ms
//! period in DWT cycles, and the cycle count of the `F32x` control period. CI only builds
//! them (`scripts/test.sh`).
#![no_std]
#![no_main]

use defmt_rtt as _;
use panic_probe as _;

/// Core clock [Hz].
pub const SYSCLK: u32 = 168_000_000;
/// Cycles of the 2 ms period.
pub const PERIOD_CYCLES: u32 = SYSCLK / 500;

/// What `init` hands to the tests.
pub struct State {
    sysclk: u32,
    acr: u32,
}

/// Samples PA8 (TIM1 CH1) `n` times; returns how often it was high.
pub fn pa8_high(n: u32) -> u32 {
    let mut high = 0;
    for _ in 0..n {
        // SAFETY: a volatile read of GPIOA_IDR (0x4002_0010).
        let idr = unsafe { core::ptr::read_volatile(0x4002_0010 as *const u32) };
        high += (idr >> 8) & 1;
    }
    high
}

#[defmt_test::tests]
mod tests {
    use super::{pa8_high, State, PERIOD_CYCLES, SYSCLK};
    use board_stm32::debug_freeze;
    use board_stm32::regs::{self, PwmTimer};
    use core::cell::RefCell;
    use cortex_m::peripheral::DWT;
    use crane_model::Params;
    use crane_twin::logic::control::{Controller, Io, LoopConfig, DEMO};
    use crane_twin::logic::fastmath::F32x;
    use crane_twin::logic::plant::{demo_plant, demo_twin_init};
    use crane_twin::logic::safety::extend_count;
    use crane_twin::preload::ZeroNowChannel;
    use embedded_hal::pwm::SetDutyCycle;
    use stm32f4xx_hal::pac;
    use stm32f4xx_hal::prelude::*;
    use stm32f4xx_hal::rcc::{Config, Enable, Reset};

    #[init]
    fn init() -> State {
        let Some(dp) = pac::Peripherals::take() else {
            defmt::panic!("peripherals")
        };
        let Some(mut cp) = cortex_m::Peripherals::take() else {
            defmt::panic!("core peripherals")
        };
        dp.FLASH.acr().modify(|_, w| unsafe {
            w.latency().bits(5);
            w.prften().set_bit();
            w.icen().set_bit();
            w.dcen().set_bit()
        });
        let mut rcc = dp.RCC.freeze(
            Config::hse(8.MHz())
                .sysclk(168.MHz())
                .pclk1(42.MHz())
                .pclk2(84.MHz()),
        );
        cp.DCB.enable_trace();
        cp.DWT.enable_cycle_counter();
        pac::TIM1::enable(&mut rcc);
        pac::TIM1::reset(&mut rcc);
        pac::TIM7::enable(&mut rcc);
        pac::TIM7::reset(&mut rcc);
        let gpioa = dp.GPIOA.split(&mut rcc);
        // PA8 as TIM1 CH1 (AF1); the mode stays set when the pin value is dropped.
        let _pa8 = gpioa.pa8.into_alternate::<1>();
        State {
            sysclk: rcc.clocks.sysclk().raw(),
            acr: dp.FLASH.acr().read().bits(),
        }
    }

    #[test]
    fn clock_is_168_mhz_with_5_wait_states_and_the_art_on(s: &mut State) {
        defmt::assert_eq!(s.sysclk, SYSCLK);
        defmt::assert_eq!(s.acr & 0xF, 5, "flash latency");
        // PRFTEN (8), ICEN (9), DCEN (10)
        defmt::assert_eq!(s.acr & (0b111 << 8), 0b111 << 8, "prefetch and ART caches");
    }

    #[test]
    fn a_zero_duty_takes_effect_at_once_on_the_pin() {
        let timer = RefCell::new(PwmTimer::init());
        let mut ch = ZeroNowChannel::new(&timer, 0);
        defmt::unwrap!(ch.set_duty_cycle(4000).ok());
        cortex_m::asm::delay(20_000); // > 4 PWM periods: the 95 % duty is in effect
        let high = pa8_high(2_000);
        defmt::assert!(high > 1_000, "95 % duty reads high {=u32} of 2000", high);
        defmt::unwrap!(ch.set_duty_cycle(0).ok());
        // at once, and for longer than a PWM period (25 us = 4200 cycles)
        defmt::assert_eq!(pa8_high(4_000), 0);
        regs::force_safe();
    }

    #[test]
    fn force_safe_zeroes_the_compares_and_disables_the_outputs() {
        let mut t = PwmTimer::init();
        for ch in 0..3 {
            crane_twin::preload::PreloadedTimer::set_compare(&mut t, ch, 3000);
        }
        crane_twin::preload::PreloadedTimer::force_update(&mut t);
        regs::force_safe();
        let (ccr, ccer) = regs::pwm_readback();
        defmt::assert_eq!(ccr, [0, 0, 0]);
        defmt::assert_eq!(ccer, 0);
        defmt::assert_eq!(pa8_high(4_000), 0);
    }

    #[test]
    fn force_safe_drops_the_driver_enable_and_the_brake_release() {
        // PC8 (driver enable) and PC13 (brake release) as outputs, driven high
        // SAFETY: volatile accesses to RCC_AHB1ENR (GPIOCEN) and GPIOC's MODER, BSRR, ODR.
        unsafe {
            let ahb1enr = 0x4002_3830 as *mut u32;
            ahb1enr.write_volatile(ahb1enr.read_volatile() | (1 << 2));
            let moder = regs::GPIOC as *mut u32;
            let m = moder.read_volatile() & !((0b11 << 16) | (0b11 << 26));
            moder.write_volatile(m | (0b01 << 16) | (0b01 << 26));
            ((regs::GPIOC + 0x18) as *mut u32).write_volatile((1 << 8) | (1 << 13));
        }
        let odr = || {
            // SAFETY: a volatile read of GPIOC_ODR.
            unsafe { ((regs::GPIOC + 0x14) as *const u32).read_volatile() }
        };
        defmt::assert_eq!(odr() & ((1 << 8) | (1 << 13)), (1 << 8) | (1 << 13));
        regs::force_safe();
        defmt::assert_eq!(
            odr() & ((1 << 8) | (1 << 13)),
            0,
            "enable and brake release low"
        );
    }

    #[test]
    fn a_debugger_halt_freezes_the_timers_and_the_watchdog() {
        regs::freeze_timers_in_debug();
        // SAFETY: volatile reads of DBGMCU_APB1_FZ and DBGMCU_APB2_FZ.
        let (apb1, apb2) = unsafe {
            (
                (regs::DBGMCU_APB1_FZ as *const u32).read_volatile(),
                (regs::DBGMCU_APB2_FZ as *const u32).read_volatile(),
            )
        };
        defmt::assert_eq!(apb1 & debug_freeze::APB1_FREEZE, debug_freeze::APB1_FREEZE);
        defmt::assert_eq!(apb2 & debug_freeze::APB2_FREEZE, debug_freeze::APB2_FREEZE);
    }

    #[test]
    fn the_period_timer_ticks_every_2_ms() {
        regs::start_period_timer(2_000);
        let mut at = [0u32; 3];
        for a in at.iter_mut() {
            while !regs::ack_period_timer() {}
            *a = DWT::cycle_count();
        }
        for w in at.windows(2) {
            let dt = w[1].wrapping_sub(w[0]);
            defmt::assert!(dt.abs_diff(PERIOD_CYCLES) < 200, "period {=u32} cycles", dt);
        }
    }

    #[test]
    fn an_f32x_control_period_takes_under_30_percent_of_2_ms() {
        let Ok(mut plant) = demo_plant() else {
            defmt::panic!("plant")
        };
        let cfg = LoopConfig::default();
        let Ok(mut ctrl) = Controller::<F32x>::new(&Params::default(), demo_twin_init(), &cfg)
        else {
            defmt::panic!("controller")
        };
        let (mut max, mut sum) = (0u32, 0u64);
        let n = 1_000u32;
        for k in 0..n {
            let r = DEMO.at::<F32x>(f64::from(k) * cfg.period);
            let t0 = DWT::cycle_count();
            let _ = ctrl.run_period(&mut plant, &r);
            let dt = DWT::cycle_count().wrapping_sub(t0);
            max = max.max(dt);
            sum += u64::from(dt);
            plant.wait();
        }
        defmt::println!(
            "F32x period: mean {=u64} max {=u32} cycles ({=u32} % of 2 ms)",
            sum / u64::from(n),
            max,
            max * 100 / PERIOD_CYCLES
        );
        defmt::assert!(max < PERIOD_CYCLES * 3 / 10);
    }

    #[test]
    fn sixteen_bit_counts_extend_across_the_wrap() {
        defmt::assert_eq!(extend_count(65_535, 2), 65_538);
        defmt::assert_eq!(extend_count(1, 65_534), -2);
    }
}
