//! Wall time of whole single-axis diagnoses (issue 20's speed figures; the fitting and
//! held-out runs are simulated in parallel on rayon's pool, one thread per core):
//! - `cicese_joint1`: the real direct-drive arm, joint 1 (`examples/cicese_joint1`, read from
//!   `../shared`; skipped with a line when absent). Goal: under 5 s.
//! - `long_10khz_120s`: a 10 kHz x 120 s log (two 60 s runs of pulses, 1.2 M rows, 1 um
//!   encoder) of a carriage with Coulomb and viscous friction, written as CSV and diagnosed
//!   from the files (load included). Goal: under 60 s.
//! - `long_10khz_120s_delayed`: the same carriage driven 0.1 s (1,000 samples) after each
//!   command. Goal: under 60 s (the same goal: issue 20 names a 10 kHz x 120 s log, any).
//!
//! `cargo bench -p crane-diagnose --bench diagnose` (10 samples each: about 1 and 7
//! minutes on 2026-11-27; not run under criterion since the change below). Measured
//! 2026-11-27 on this 2-core machine, idle, before the runs were simulated in parallel (one
//! thread): `cicese_joint1` 0.641 s, `long_10khz_120s` 38.6 s; both goals met then.
//! 2026-11-28, idle:
//! `cicese_joint1` 0.741 s; the long case 93.1 s for one `crane diagnose` of the bench's files
//! (criterion estimated 101 s a sample), 67.5 s once the estimate's medians were selected
//! instead of sorted: over the 60 s goal. Bisected (each commit's user time over that of
//! `8ce3599` run beside it, 2026-11-28 08:09-08:17 UTC, load average under 2): the own-log
//! floor (`aae8c02`..`0658246`: 1.14), then small steps (`ecf18a7` 1.17, `a8546c8` 1.22,
//! `7909d40` 1.19), then the 1.2-ratio grids with the fractional delay (`004e28f`: 1.83; dead
//! band 8 -> 27 and load share 8 -> 25 points before 10 refining steps each, each point two
//! fits and three simulations of the 60 s fitting run; `d06cc58` put the Stribeck grid back
//! to 9 points: `89e4a0f` 1.66). This change: 0.76.
//! Since, each grid point costs two simulations (the chosen level's fitting error is kept,
//! not simulated again), both dry levels share the first least squares and are fitted and
//! simulated side by side, and the normal equations are summed in one pass: the same
//! reports, bit for bit. 2026-11-28 08:06 UTC, the machine nearly idle (load average about
//! 1, the run included), one `crane diagnose DIR --json F` of the bench's files: **36.0 s**
//! wall, 41.1 s user (`663c068` right after it: 60.1 s wall, 59.7 s user); `cicese_joint1`
//! 0.54 s (`663c068`: 0.74 s). Earlier, shared (load 4-5): 63.0 s wall against 108.5 s.
//! README's table.
//! 2026-11-28 17:10 UTC, idle, one `crane diagnose` of a Python-written log like the bench's
//! (the same carriage and pulses, 10 kHz x 2 x 60 s): 12.0 s (12.3 s before the delay's
//! output-error refinement); the same log with a 0.1 s input delay: 137 s (62 s before; the
//! delay's valley scan and Nelder-Mead restarts, each iteration a simulation of the 60 s
//! fitting run): over the 60 s goal for a delayed log of that length (not benchmarked here).
//! 2026-11-28 19:55 UTC, idle (load average 1.1-1.5), one `crane diagnose` of a Python-written
//! log like the bench's (`tools/strangers/plant.py`, the same carriage and pulses, 0.1 s
//! delay): **57.9 s** wall, 60.9 s user, delay 0.1000 s, since a delayed model is refined on
//! the fitting run's first 150,000 samples (`REFINE_SAMPLES`, at least 20 starts) and judged
//! on the whole run; 98.4 s wall for the binary before (`4928209`), run beside it; 14.5 s for
//! the same log without the delay. That log is now benchmarked here as
//! `long_10khz_120s_delayed` (this model, the command applied 1,000 samples late).
//! 2026-11-28 20:05-20:24 UTC, idle, criterion: `cicese_joint1` 0.589 s, `long_10khz_120s`
//! **45.3 s** (36.0 s at 08:06 the same day: the rise came with the later sessions' changes,
//! not bisected); `long_10khz_120s_delayed` about 83 s (criterion's warm-up estimate, run
//! stopped there) and **75.0 s** for one `crane diagnose` of its files (delay 0.09997 s):
//! **over the 60 s goal** on this model's log, under it (57.9 s) on the Python-written one.
//! Where the time goes (`perf record` of that run): simulation 57 % (`rk4`,
//! `simulate_drive`, `step`), the sliding least squares 30 % (`Sliding::estimate`,
//! `moments`, `gram`, `ls_pass`): every candidate's grid simulates the 600,000 fitting
//! samples at each point, and once the delay is named every candidate is tried again on top
//! of it. Choosing the grids' values on the heads too is the next step (not done).
//! 2026-11-28 23:28-23:33 UTC, idle, one `crane diagnose DIR --json F` each, beside main
//! `52c3a9a`: the candidates' grids (dead band, saturation, load share, Stribeck velocity,
//! the delay's whole samples) are now chosen on the same heads and the chosen structure fitted
//! on the whole runs (`drive/trial.rs`, `Search::heads`): this bench's delayed files
//! **69.9 s** wall, 74.8 s user (80.3 s, 89.1 s before): **still over the 60 s goal**; the
//! Python-written delayed log 36.7 s (62.8 s before). Reports byte-identical on both.
//! 2026-11-29 02:05-02:12 UTC, idle, release, one `crane diagnose` each: with a round's
//! candidates judged side by side (`drive/select.rs`; a log with one fitting run simulates on
//! one core) this bench's delayed files **53.8 s and 54.6 s** wall, against 62.3 s for
//! `aca9d0f` beside them; the same report. About 33 s of that is the named delay's
//! output-error refinement on the heads (1,686 simulations of 150,000 samples, one after
//! another; its Nelder-Mead polish about 870 iterations). Criterion, 2026-11-29 03:48-04:00
//! UTC, idle, `2a93aec`: `long_10khz_120s_delayed` **50.8 s** (49.6-52.0 s): under the goal.

use crane_diagnose::{diagnose, DiagnoseOptions};
use crane_ident::rng::Rng;
use crane_model::{Drive, DriveParams};
use criterion::{criterion_group, criterion_main, Criterion};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Two 60 s runs at 10 kHz: pulses of both signs (8-20 N, 0.4 s on, 0.3 s off) on a 2 kg
/// carriage (Coulomb 4 N, viscous 8 N s/m), positions quantised to 1 um; the second run
/// held out. The carriage is driven by the command logged `delay` samples before (none
/// before the log begins).
fn write_long_log(dir: &Path, delay: usize) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let p = DriveParams {
        inertia: 2.0,
        kinetic_pos: 4.0,
        kinetic_neg: 4.0,
        breakaway_pos: 4.0,
        breakaway_neg: 4.0,
        viscous_pos: 8.0,
        viscous_neg: 8.0,
        ..DriveParams::default()
    };
    let dt = 1e-4;
    let mut toml = String::from("position_unit = \"m\"\ninput_unit = \"N\"\n");
    let mut rng = Rng::new(1);
    for run in 0..2 {
        let name = format!("run{run}.csv");
        toml.push_str(&format!(
            "[[runs]]\nfile = \"{name}\"\nkind = \"{}\"\n",
            if run == 1 { "validation" } else { "other" }
        ));
        let mut d =
            Drive::<f64>::new(&p, dt, 0.0).map_err(|e| std::io::Error::other(format!("{e:?}")))?;
        let mut f = std::io::BufWriter::new(std::fs::File::create(dir.join(&name))?);
        writeln!(f, "t,x,u")?;
        let (mut u, mut left) = (0.0, 0usize);
        let mut sent = Vec::with_capacity(600_000);
        for k in 0..600_000usize {
            if left == 0 {
                let bits = rng.next_u64();
                let r = (bits >> 11) as f64 / (1u64 << 53) as f64;
                u = if u != 0.0 {
                    0.0
                } else {
                    let a = 8.0 + 12.0 * r;
                    if (bits >> 3) & 1 == 0 {
                        a
                    } else {
                        -a
                    }
                };
                left = if u != 0.0 { 4000 } else { 3000 };
            }
            left -= 1;
            let x = (d.x() / 1e-6).round() * 1e-6;
            writeln!(f, "{},{x},{u}", k as f64 * dt)?;
            sent.push(u);
            d.step(if k >= delay { sent[k - delay] } else { 0.0 })
                .map_err(|e| std::io::Error::other(format!("{e:?}")))?;
        }
    }
    std::fs::write(dir.join("dataset.toml"), toml)
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("diagnose");
    g.sample_size(10).measurement_time(Duration::from_secs(60));
    let cicese = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/cicese_joint1");
    if crane_ident::shared_data::require("cicese").is_some() {
        g.bench_function("cicese_joint1", |b| {
            b.iter(|| diagnose(&cicese, &DiagnoseOptions::default()).expect("report"))
        });
    }
    let dir: PathBuf =
        std::env::temp_dir().join(format!("crane_bench_10khz_{}", std::process::id()));
    write_long_log(&dir, 0).expect("the long log is written");
    g.bench_function("long_10khz_120s", |b| {
        b.iter(|| diagnose(&dir, &DiagnoseOptions::default()).expect("report"))
    });
    // the same carriage 0.1 s late: the delay's refinement (on the fitting run's heads)
    write_long_log(&dir, 1_000).expect("the delayed log is written");
    g.bench_function("long_10khz_120s_delayed", |b| {
        b.iter(|| diagnose(&dir, &DiagnoseOptions::default()).expect("report"))
    });
    g.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench);
criterion_main!(benches);
