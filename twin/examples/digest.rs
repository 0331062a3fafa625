//! Prints on the host the digest the firmware prints under QEMU (the lines that
//! `host-tests/tests/qemu_cross.rs` compares): `cargo run -p crane-twin --release --example digest`.
use crane_twin::logic::fastmath::F32x;
use crane_twin::logic::plant::{demo_plant, run_demo};
use crane_twin::logic::scenarios::{run, SCENARIOS};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut out = String::new();
    for sc in SCENARIOS.iter() {
        run::<f64, _>(sc, "f64", &mut out)?;
        run::<f32, _>(sc, "f32", &mut out)?;
        run::<F32x, _>(sc, "f32x", &mut out)?;
    }
    run_demo::<f64, _, _>(
        &mut demo_plant().map_err(|e| e.to_string())?,
        "f64",
        &mut out,
    )?;
    run_demo::<f32, _, _>(
        &mut demo_plant().map_err(|e| e.to_string())?,
        "f32",
        &mut out,
    )?;
    run_demo::<F32x, _, _>(
        &mut demo_plant().map_err(|e| e.to_string())?,
        "f32x",
        &mut out,
    )?;
    print!("{out}");
    Ok(())
}
