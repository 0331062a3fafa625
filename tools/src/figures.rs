//! The paper's two figures of the simulation section, as SVG (plotters).
//!
//! - `case1_trolley_velocity.svg`: trolley velocity, hybrid (1 ms) against `tanh(1000 v)`
//!   (ode45), with the reference.
//! - `case2_rope.svg`: rope forces (drive force, net force `F_l + m_p g`, friction force of the
//!   hybrid model, thresholds `+-Cbar_l`), rope length, rope velocity of the hybrid model and
//!   of every `tanh` model; backgrounds show the hybrid rope mode (red: negative, yellow:
//!   stopped, green: positive).

use crate::error::{Error, Result};
use crate::output::Outputs;
use crate::study::CaseData;
use crate::tanh_run::tanh_name;
use crane_model::Mode;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

type Dyn = Box<dyn std::error::Error>;

fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
        (l.min(v), h.max(v))
    });
    let pad = ((hi - lo) * 0.06).max(1e-6);
    (lo - pad, hi + pad)
}

/// Writes both figures into `dir` (staged in `outputs`, published by its commit); returns their
/// paths.
pub fn write(
    dir: &Path,
    case1: &CaseData,
    case2: &CaseData,
    outputs: &mut Outputs,
) -> Result<Vec<PathBuf>> {
    let p1 = dir.join("case1_trolley_velocity.svg");
    let mut svg = String::new();
    case1_fig(&mut svg, case1).map_err(|e| Error::Plot {
        path: p1.clone(),
        message: e.to_string(),
    })?;
    outputs.stage(&p1, svg)?;
    let p2 = dir.join("case2_rope.svg");
    let mut svg = String::new();
    case2_fig(&mut svg, case2).map_err(|e| Error::Plot {
        path: p2.clone(),
        message: e.to_string(),
    })?;
    outputs.stage(&p2, svg)?;
    Ok(vec![p1, p2])
}

fn case1_fig(svg: &mut String, d: &CaseData) -> std::result::Result<(), Dyn> {
    let c = &d.case;
    let i = c.observed;
    let root = SVGBackend::with_string(svg, (1000, 800)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((2, 1));
    let hyb: Vec<(f64, f64)> = d
        .hybrid
        .states
        .iter()
        .enumerate()
        .map(|(j, s)| (d.hybrid.time(c, j), s.qd[i]))
        .collect();
    let tanh: Vec<(f64, f64)> = d
        .tanh
        .iter()
        .find(|(g, _)| *g == 1000.0)
        .map(|(_, tr)| {
            tr.states
                .iter()
                .enumerate()
                .map(|(j, s)| (tr.time(c, j), s.qd[i]))
                .collect()
        })
        .unwrap_or_default();
    // Top: the whole run. Bottom: the tail, zoomed to the tanh model's creep.
    let t_zoom = 0.25 * c.duration;
    let tail = |v: &[(f64, f64)]| -> Vec<(f64, f64)> {
        v.iter().copied().filter(|p| p.0 >= t_zoom).collect()
    };
    let (zlo, zhi) = range(tail(&tanh).iter().chain(tail(&hyb).iter()).map(|p| p.1));
    let (flo, fhi) = range(hyb.iter().chain(tanh.iter()).map(|p| p.1));
    let specs = [
        (
            "Case 1: trolley velocity, hybrid vs tanh(1000 v)".to_string(),
            0.0,
            flo,
            fhi,
        ),
        (
            format!("zoom: t >= {t_zoom} s (hybrid exactly 0 when stopped; tanh creeps)"),
            t_zoom,
            zlo,
            zhi,
        ),
    ];
    for (area, (title, t0, lo, hi)) in panels.iter().zip(specs) {
        let clip = |v: &[(f64, f64)]| -> Vec<(f64, f64)> {
            v.iter().copied().filter(|p| p.0 >= t0).collect()
        };
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(80)
            .build_cartesian_2d(t0..c.duration, lo..hi)?;
        chart
            .configure_mesh()
            .x_desc("t [s]")
            .y_desc("trolley velocity [m/s]")
            .draw()?;
        chart
            .draw_series(LineSeries::new(clip(&tanh), RED.stroke_width(2)))?
            .label("tanh(1000 v), ode45")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
        chart
            .draw_series(LineSeries::new(clip(&hyb), BLUE.stroke_width(1)))?
            .label("hybrid, h = 1 ms")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE)
            .draw()?;
    }
    root.present()?;
    Ok(())
}

fn mode_color(m: Mode) -> RGBColor {
    match m {
        Mode::Negative => RGBColor(255, 205, 205),
        Mode::Stopped => RGBColor(255, 245, 190),
        Mode::Positive => RGBColor(205, 240, 205),
    }
}

/// Maximal runs of equal rope mode: `(t_start, t_end, mode)`.
fn bands(d: &CaseData) -> Vec<(f64, f64, Mode)> {
    let c = &d.case;
    let mut out: Vec<(f64, f64, Mode)> = Vec::new();
    for (j, m) in d.hybrid.modes.iter().enumerate() {
        let t = d.hybrid.time(c, j);
        match out.last_mut() {
            Some(last) if last.2 == m[2] => last.1 = t,
            _ => out.push((t, t, m[2])),
        }
    }
    out
}

fn draw_bands<DB: DrawingBackend>(
    chart: &mut ChartContext<
        '_,
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    bands: &[(f64, f64, Mode)],
    lo: f64,
    hi: f64,
) -> std::result::Result<(), Dyn>
where
    DB::ErrorType: 'static,
{
    chart.draw_series(
        bands
            .iter()
            .map(|&(a, b, m)| Rectangle::new([(a, lo), (b, hi)], mode_color(m).filled())),
    )?;
    Ok(())
}

fn case2_fig(svg: &mut String, d: &CaseData) -> std::result::Result<(), Dyn> {
    let c = &d.case;
    let root = SVGBackend::with_string(svg, (1000, 1100)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((3, 1));
    let bands = bands(d);
    let th = c.rope_threshold();
    let mg = c.params.payload_mass * c.params.gravity;

    // Forces.
    let t: Vec<f64> = (0..d.hybrid.states.len())
        .map(|j| d.hybrid.time(c, j))
        .collect();
    let drive: Vec<(f64, f64)> = t.iter().map(|&t| (t, c.rope_force(t))).collect();
    let net: Vec<(f64, f64)> = t.iter().map(|&t| (t, c.rope_force(t) + mg)).collect();
    let fric: Vec<(f64, f64)> = t
        .iter()
        .zip(&d.hybrid.friction)
        .map(|(&t, f)| (t, f[2]))
        .collect();
    let (lo, hi) = range(
        drive
            .iter()
            .chain(net.iter())
            .chain(fric.iter())
            .map(|p| p.1)
            .chain([th, -th]),
    );
    let mut ch = ChartBuilder::on(&panels[0])
        .caption(
            "Case 2: forces on the rope axis (hybrid)",
            ("sans-serif", 18),
        )
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..c.duration, lo..hi)?;
    draw_bands(&mut ch, &bands, lo, hi)?;
    ch.configure_mesh()
        .x_desc("t [s]")
        .y_desc("force [N]")
        .draw()?;
    ch.draw_series(LineSeries::new(drive, BLUE.stroke_width(2)))?
        .label("drive force F_l = K_l u_l")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
    ch.draw_series(LineSeries::new(net, BLACK.stroke_width(2)))?
        .label("net force F_l + m_p g")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    ch.draw_series(LineSeries::new(fric, MAGENTA.stroke_width(1)))?
        .label("friction (holding force when stopped)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], MAGENTA));
    for s in [th, -th] {
        ch.draw_series(LineSeries::new(
            vec![(0.0, s), (c.duration, s)],
            BLACK.mix(0.5),
        ))?;
    }
    ch.configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE)
        .draw()?;

    // Length.
    let len: Vec<(f64, f64)> = t
        .iter()
        .zip(&d.hybrid.states)
        .map(|(&t, s)| (t, s.q[2]))
        .collect();
    let (lo, hi) = range(len.iter().map(|p| p.1));
    let mut ch = ChartBuilder::on(&panels[1])
        .caption("rope length (hybrid)", ("sans-serif", 18))
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..c.duration, lo..hi)?;
    draw_bands(&mut ch, &bands, lo, hi)?;
    ch.configure_mesh().x_desc("t [s]").y_desc("L [m]").draw()?;
    ch.draw_series(LineSeries::new(len, BLUE.stroke_width(2)))?;

    // Velocity.
    let hyb: Vec<(f64, f64)> = t
        .iter()
        .zip(&d.hybrid.states)
        .map(|(&t, s)| (t, s.qd[2]))
        .collect();
    let (lo, hi) = range(hyb.iter().map(|p| p.1));
    let (lo, hi) = (lo * 1.6, hi * 1.6);
    let mut ch = ChartBuilder::on(&panels[2])
        .caption(
            "rope velocity: hybrid and tanh(gamma v)",
            ("sans-serif", 18),
        )
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..c.duration, lo..hi)?;
    draw_bands(&mut ch, &bands, lo, hi)?;
    ch.configure_mesh()
        .x_desc("t [s]")
        .y_desc("dL/dt [m/s]")
        .draw()?;
    let colors = [CYAN, RED, GREEN, MAGENTA, RGBColor(255, 140, 0)];
    for (k, (g, tr)) in d.tanh.iter().enumerate() {
        let col = colors[k % colors.len()];
        let pts = tr
            .states
            .iter()
            .enumerate()
            .map(|(j, s)| (tr.time(c, j), s.qd[2].clamp(lo, hi)));
        ch.draw_series(LineSeries::new(pts, col.stroke_width(1)))?
            .label(tanh_name(*g))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col));
    }
    ch.draw_series(LineSeries::new(hyb, BLUE.stroke_width(2)))?
        .label("hybrid, h = 1 ms")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
    ch.configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE)
        .draw()?;
    root.present()?;
    Ok(())
}
