//! Minimal firmware: steps the crane model and reports through semihosting.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use crane_model::{Config, Crane, Params, State};
use panic_semihosting as _;

#[entry]
fn main() -> ! {
    let q = [0.2, 0.3, 0.4, core::f64::consts::FRAC_PI_2 + 0.1, 0.0];
    let ok = match Crane::<f64>::new(
        &Params::default(),
        Config::default(),
        State { q, qd: [0.0; 5] },
    ) {
        Ok(mut crane) => {
            for k in 0..2000u32 {
                let u = if k < 1000 { 6.0 } else { -6.0 };
                if crane.step([u, u, 0.0]).is_err() {
                    break;
                }
            }
            let s = crane.state();
            hprintln!(
                "x={:?} y={:?} bits={:016x}",
                s.q[0],
                s.q[1],
                s.q[0].to_bits()
            );
            true
        }
        Err(_) => false,
    };
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}
