//! Stage 5: plots of a single-axis diagnosis (SVG, plotters).
//!
//! - `heldout_<run>.svg` per held-out run: measured position against the simulated baseline
//!   and final model, the measured stick intervals shaded; below, the residual
//!   `simulated - measured` of both models.
//! - `force_velocity.svg`: the friction force seen in the data (inverse dynamics of the final
//!   model on the sliding samples, `F - J a - position force`) against velocity, with the
//!   fitted friction curves of the baseline and the final model and their breakaway levels.

use super::estimate::{applied_input, restoring_shape};
use super::info::DriveInfo;
use super::prep::{Prepared, Thresholds};
use super::score::Scored;
use crane_model::drive::{DriveParams, PositionForce};
use plotters::prelude::*;
use std::path::Path;

type Dyn = Box<dyn std::error::Error>;
/// Points of a curve `(x, y)`.
type Curve = Vec<(f64, f64)>;

fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = vals
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        return (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.06).max(1e-9 + 1e-9 * lo.abs());
    (lo - pad, hi + pad)
}

/// A file-name-safe version of a run name.
fn stem(name: &str) -> String {
    let base = Path::new(name)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    base.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Writes every plot into `dir` (created if missing).
pub fn write_all(
    dir: &Path,
    held: &[&Prepared],
    baseline: &Scored,
    final_: &Scored,
    th: &Thresholds,
    info: &DriveInfo,
) -> Result<(), Dyn> {
    crane_ident::atomic::create_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    for (i, r) in held.iter().enumerate() {
        let path = dir.join(format!("heldout_{}.svg", stem(&r.run.name)));
        write_svg(&path, |svg| {
            draw_run(svg, r, &baseline.sims[i], &final_.sims[i], th, info)
        })?;
    }
    write_svg(&dir.join("force_velocity.svg"), |svg| {
        draw_force_velocity(svg, held, baseline, final_, th, info)
    })
}

/// Draws a plot into a string and writes it atomically to `path`, with the tool's mark
/// ([`crate::mark_plot`]); an error names the file.
fn write_svg(path: &Path, draw: impl FnOnce(&mut String) -> Result<(), Dyn>) -> Result<(), Dyn> {
    let named = |e: &dyn std::fmt::Display| format!("plot {}: {e}", path.display());
    let mut svg = String::new();
    draw(&mut svg).map_err(|e| named(&e))?;
    crane_ident::atomic::write(path, crate::mark_plot(&svg)).map_err(|e| named(&e))?;
    Ok(())
}

/// Intervals `(t0, t1)` where the measured axis sticks (`|v| <= v_move`).
fn stick_intervals(r: &Prepared, th: &Thresholds) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    let mut start: Option<usize> = None;
    for (i, v) in r.v.iter().enumerate() {
        let stuck = v.abs() <= th.v_move;
        match (stuck, start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                out.push((s as f64 * r.run.dt, i as f64 * r.run.dt));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s as f64 * r.run.dt, r.v.len() as f64 * r.run.dt));
    }
    out
}

fn draw_run(
    svg: &mut String,
    r: &Prepared,
    base: &[f64],
    fin: &[f64],
    th: &Thresholds,
    info: &DriveInfo,
) -> Result<(), Dyn> {
    let root = SVGBackend::with_string(svg, (1000, 760)).into_drawing_area();
    root.fill(&WHITE)?;
    let (top, bottom) = root.split_vertically(470);
    let t: Vec<f64> = (0..r.run.x.len()).map(|k| k as f64 * r.run.dt).collect();
    let t_end = t.last().copied().unwrap_or(1.0).max(r.run.dt);
    let series =
        |x: &[f64]| -> Vec<(f64, f64)> { t.iter().copied().zip(x.iter().copied()).collect() };
    let (lo, hi) = range(r.run.x.iter().chain(base).chain(fin).copied());
    let mut chart = ChartBuilder::on(&top)
        .caption(
            format!(
                "{}: measured vs simulated position (grey: measured sticking)",
                r.run.name
            ),
            ("sans-serif", 18),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..t_end, lo..hi)?;
    chart
        .configure_mesh()
        .x_desc("t [s]")
        .y_desc(format!("position [{}]", info.position_unit))
        .draw()?;
    chart.draw_series(
        stick_intervals(r, th)
            .into_iter()
            .map(|(a, b)| Rectangle::new([(a, lo), (b, hi)], RGBColor(228, 228, 228).filled())),
    )?;
    chart
        .draw_series(LineSeries::new(series(&r.run.x), BLACK.stroke_width(2)))?
        .label("measured")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    chart
        .draw_series(LineSeries::new(series(base), RED.stroke_width(1)))?
        .label("baseline (simulated)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
    chart
        .draw_series(LineSeries::new(series(fin), BLUE.stroke_width(2)))?
        .label("final model (simulated)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()?;
    let eb: Vec<f64> = base.iter().zip(&r.run.x).map(|(s, m)| s - m).collect();
    let ef: Vec<f64> = fin.iter().zip(&r.run.x).map(|(s, m)| s - m).collect();
    let (elo, ehi) = range(eb.iter().chain(&ef).copied().chain([0.0]));
    let mut res = ChartBuilder::on(&bottom)
        .caption("residual: simulated - measured", ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..t_end, elo..ehi)?;
    res.configure_mesh()
        .x_desc("t [s]")
        .y_desc(format!("residual [{}]", info.position_unit))
        .draw()?;
    res.draw_series(LineSeries::new(series(&eb), RED.stroke_width(1)))?
        .label("baseline")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
    res.draw_series(LineSeries::new(series(&ef), BLUE.stroke_width(2)))?
        .label("final model")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
    res.configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()?;
    root.present()?;
    Ok(())
}

fn friction_curve(p: &DriveParams, vmax: f64) -> (Curve, Curve) {
    let n = 60;
    let pos: Vec<(f64, f64)> = (0..=n)
        .map(|k| {
            let v = vmax * k as f64 / n as f64;
            (v, p.kinetic_pos + p.viscous_pos * v)
        })
        .collect();
    let neg: Vec<(f64, f64)> = (0..=n)
        .map(|k| {
            let v = -vmax * k as f64 / n as f64;
            (v, -p.kinetic_neg + p.viscous_neg * v)
        })
        .collect();
    (pos, neg)
}

fn draw_force_velocity(
    svg: &mut String,
    held: &[&Prepared],
    baseline: &Scored,
    final_: &Scored,
    th: &Thresholds,
    info: &DriveInfo,
) -> Result<(), Dyn> {
    let p = &final_.est.params;
    let (k, c) = match p.position_force {
        PositionForce::None => (0.0, 0.0),
        PositionForce::Spring { stiffness, center }
        | PositionForce::Pendulum { stiffness, center } => (stiffness, center),
    };
    let mut pts: Vec<(f64, f64)> = Vec::new();
    for r in held {
        for i in 0..r.run.x.len() {
            if r.v[i].abs() > th.v_move {
                let f = applied_input(&r.run.u, i, &final_.est.structure) + p.offset
                    - p.inertia * r.a[i]
                    - k * restoring_shape(p.motion, r.run.x[i], c);
                pts.push((r.v[i], f));
            }
        }
    }
    let vmax = pts.iter().fold(th.v_move, |m, q| m.max(q.0.abs()));
    let (bp, bn) = friction_curve(&baseline.est.params, vmax);
    let (fp, fneg) = friction_curve(p, vmax);
    let (lo, hi) = range(
        pts.iter()
            .map(|q| q.1)
            .chain(bp.iter().chain(&bn).chain(&fp).chain(&fneg).map(|q| q.1))
            .chain([p.breakaway_pos, -p.breakaway_neg]),
    );
    let root = SVGBackend::with_string(svg, (1000, 650)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "friction force vs velocity, held-out moving samples (inverse dynamics of the final model)",
            ("sans-serif", 17),
        )
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(-vmax * 1.05..vmax * 1.05, lo..hi)?;
    let vunit = if info.position_unit == "rad" {
        "rad/s"
    } else {
        "m/s"
    };
    chart
        .configure_mesh()
        .x_desc(format!("velocity [{vunit}]"))
        .y_desc(format!("friction force [{}]", info.force_unit))
        .draw()?;
    chart
        .draw_series(
            pts.iter()
                .map(|&q| Circle::new(q, 2, RGBColor(120, 120, 120).filled())),
        )?
        .label("data")
        .legend(|(x, y)| Circle::new((x + 10, y), 3, RGBColor(120, 120, 120).filled()));
    chart
        .draw_series(LineSeries::new(bp, RED.stroke_width(2)))?
        .label("baseline friction")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
    chart.draw_series(LineSeries::new(bn, RED.stroke_width(2)))?;
    chart
        .draw_series(LineSeries::new(fp, BLUE.stroke_width(2)))?
        .label("final model friction")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
    chart.draw_series(LineSeries::new(fneg, BLUE.stroke_width(2)))?;
    chart
        .draw_series(
            [p.breakaway_pos, -p.breakaway_neg]
                .into_iter()
                .map(|b| Circle::new((0.0, b), 5, BLUE.filled())),
        )?
        .label("final breakaway levels")
        .legend(|(x, y)| Circle::new((x + 10, y), 4, BLUE.filled()));
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()?;
    root.present()?;
    Ok(())
}
