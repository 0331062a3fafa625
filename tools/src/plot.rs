//! Figures (SVG, plotters): measured against simulated payload position.

use anyhow::{Context, Result};
use crane_ident::data::{CraneRun, Dataset};
use crane_ident::validate::ValidationReport;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Payload position `[x_p, y_p, z_p]` [m] of drive positions and swing angles.
fn payload(x: f64, y: f64, l: f64, a: f64, b: f64) -> [f64; 3] {
    let (sa, ca, sb, cb) = (libm::sin(a), libm::cos(a), libm::sin(b), libm::cos(b));
    [x + l * sb * sa, y + l * ca, -(l * sa * cb)]
}

fn measured(run: &CraneRun) -> Vec<[f64; 3]> {
    (0..run.len())
        .map(|k| payload(run.x[k], run.y[k], run.l[k], run.alpha[k], run.beta[k]))
        .collect()
}

/// One SVG per validation run: x_p, y_p, z_p against time, measured and simulated.
pub fn validation(ds: &Dataset, report: &ValidationReport, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("create {}", dir.display()))?;
    let mut files = Vec::new();
    for rv in &report.runs {
        let Some(run) = ds
            .runs
            .iter()
            .find(|r| r.name == rv.run)
            .and_then(|r| r.crane())
        else {
            continue;
        };
        let meas = measured(run);
        let sim: Vec<[f64; 3]> = rv
            .simulated
            .iter()
            .map(|s| payload(s[0], s[1], s[2], s[3], s[4]))
            .collect();
        let stem = Path::new(&rv.run)
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("run");
        let path = dir.join(format!("validation_{stem}.svg"));
        draw(&path, &run.t, &meas, &sim, &rv.nmae_pct)
            .map_err(|e| anyhow::anyhow!("{e}"))
            .with_context(|| format!("plot {}", path.display()))?;
        files.push(path);
    }
    Ok(files)
}

fn draw(
    path: &Path,
    t: &[f64],
    meas: &[[f64; 3]],
    sim: &[[f64; 3]],
    nmae: &[f64; 3],
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::new(path, (1000, 900)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((3, 1));
    let t_end = t.last().copied().unwrap_or(1.0);
    for (i, area) in panels.iter().enumerate() {
        let name = ["x_p [m]", "y_p [m]", "z_p [m]"][i];
        let vals = meas.iter().chain(sim.iter()).map(|p| p[i]);
        let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
        let pad = ((hi - lo) * 0.05).max(1e-4);
        let mut chart = ChartBuilder::on(area)
            .caption(format!("{name}: NMAE {:.2} %", nmae[i]), ("sans-serif", 18))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..t_end, (lo - pad)..(hi + pad))?;
        chart.configure_mesh().x_desc("t [s]").y_desc(name).draw()?;
        chart
            .draw_series(LineSeries::new(
                t.iter().zip(meas).map(|(&t, p)| (t, p[i])),
                &BLACK,
            ))?
            .label("measured")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
        chart
            .draw_series(LineSeries::new(
                t.iter().zip(sim).map(|(&t, p)| (t, p[i])),
                &RED,
            ))?
            .label("simulated")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
        chart.configure_series_labels().border_style(BLACK).draw()?;
    }
    root.present()?;
    Ok(())
}
