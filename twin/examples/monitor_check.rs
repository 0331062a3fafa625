//! Prints on the host the friction monitor's frames that the firmware prints under QEMU (its
//! `MBEGIN`..`MEND` sections): `cargo run -p crane-twin --release --example monitor_check`.
//! `crane monitor` decodes this output as it decodes a UART capture.
use crane_twin::logic::fastmath::F32x;
use crane_twin::logic::monitor_rig::run_check;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut out = String::new();
    run_check::<f64, _, _>("f64", &mut out, |_| {})?;
    run_check::<F32x, _, _>("f32x", &mut out, |_| {})?;
    print!("{out}");
    Ok(())
}
