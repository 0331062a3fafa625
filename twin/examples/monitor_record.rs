//! Records the monitor's rig with a fault as a crane data set, with the monitor's frames of
//! the same run beside it, so that `crane monitor` and `crane diagnose` can be run on one
//! recorded run: `cargo run -p crane-twin --release --example monitor_record -- DIR`.
//! The run: the 1 N bump on X at 0.31 m appearing at 600 s (after the monitor's
//! commissioning), 900 s in all; the data set holds the 300 s after the onset as ten runs of
//! 30 s (six to fit, four held out), positions as the encoders read them.
use crane_twin::logic::control::LoopConfig;
use crane_twin::logic::monitor::Settings;
use crane_twin::logic::monitor_rig::{run, Event, Fault, Run};
use std::fmt::Write as _;
use std::path::PathBuf;

const ONSET: f64 = 600.0;
const RUN_S: f64 = 30.0;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(std::env::args().nth(1).ok_or("usage: monitor_record DIR")?);
    if dir.exists() {
        return Err(format!("{} exists: give a new folder", dir.display()).into());
    }
    std::fs::create_dir_all(&dir)?;
    let rig = Run {
        fault: Fault::Bump {
            center: 0.31,
            width: 0.015,
            amplitude: 1.0,
        },
        onset: ONSET,
        duration: ONSET + 10.0 * RUN_S,
        seed: 1,
        reset_at: None,
        substeps: 2,
        maps_every: 30_000,
        record: true,
    };
    let mut frames = String::new();
    let mut runs: Vec<String> = vec![String::new(); 10];
    let mut last_y: Option<[f64; 5]> = None;
    let settings = Settings::for_loop(&LoopConfig::default());
    run::<f64, _, _>(&rig, &settings, "record", &mut frames, |e| {
        if let Event::Period { t, u, y } = e {
            // a row: positions at t (the end of the last period), voltages held from t
            if let (Some(p), true) = (last_y, t >= ONSET) {
                let k = (((t - ONSET) / RUN_S) as usize).min(9);
                let csv = &mut runs[k];
                if csv.is_empty() {
                    csv.push_str("t,u_x,u_y,u_l,x,y,l,alpha,beta\n");
                }
                let _ = writeln!(
                    csv,
                    "{t},{},{},{},{},{},{},{},{}",
                    u[0], u[1], u[2], p[0], p[1], p[2], p[3], p[4]
                );
            }
            last_y = Some(y);
        }
    })?;
    std::fs::write(dir.join("monitor.log"), &frames)?;
    let data = dir.join("dataset");
    std::fs::create_dir_all(&data)?;
    let mut toml = String::from(
        "description = \"friction monitor rig, 1 N bump on X at 0.31 m from 600 s\"\npayload_kg = 0.5\n",
    );
    for (k, csv) in runs.iter().enumerate() {
        let file = format!("run{k:02}.csv");
        std::fs::write(data.join(&file), csv)?;
        let kind = if k < 6 { "other" } else { "validation" };
        let _ = write!(toml, "\n[[runs]]\nfile = \"{file}\"\nkind = \"{kind}\"\n");
    }
    std::fs::write(data.join("dataset.toml"), toml)?;
    println!(
        "wrote {} (frames) and {} (10 runs)",
        dir.join("monitor.log").display(),
        data.display()
    );
    Ok(())
}
