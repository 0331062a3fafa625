//! Figures (SVG, plotters): measured against simulated payload position (validation), the
//! identified friction curves with their bands, and `crane simulate` runs.

use anyhow::{Context, Result};
use crane_ident::data::{CraneRun, Dataset};
use crane_ident::identify::{DryFit, Identified};
use crane_ident::validate::ValidationReport;
use crane_model::Mode;
use crane_tools::output::Outputs;
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
pub fn validation(
    ds: &Dataset,
    report: &ValidationReport,
    dir: &Path,
    outputs: &mut Outputs,
) -> Result<Vec<PathBuf>> {
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
        let mut svg = String::new();
        draw(&mut svg, &run.t, &meas, &sim, &rv.nmae_pct)
            .map_err(|e| anyhow::anyhow!("{e}"))
            .with_context(|| format!("plot {}", path.display()))?;
        outputs.stage_plot(&path, "validate", &svg)?;
        files.push(path);
    }
    Ok(files)
}

fn draw(
    svg: &mut String,
    t: &[f64],
    meas: &[[f64; 3]],
    sim: &[[f64; 3]],
    nmae: &[f64; 3],
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::with_string(svg, (1000, 900)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((3, 1));
    let t_span = span(0.0, t.last().copied().unwrap_or(1.0), "time")?;
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
            .build_cartesian_2d(t_span.clone(), span(lo - pad, hi + pad, name)?)?;
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

type Dyn = Box<dyn std::error::Error>;

/// Widest axis span [units of the axis] a plot accepts: beyond it (or with a non-finite
/// end) plotters' tick search does not terminate (`x_range_m = [-1e308, 1e308]` hung
/// `crane identify`), and no physical quantity of this crane gets near it.
pub const MAX_SPAN: f64 = 1e12;

/// The range `lo..hi` of a plot axis, or an error naming the quantity when it is not
/// plottable (non-finite, empty, or wider than [`MAX_SPAN`]).
pub fn span(lo: f64, hi: f64, what: &str) -> std::result::Result<std::ops::Range<f64>, Dyn> {
    let width = hi - lo;
    if !(lo.is_finite() && hi.is_finite() && width > 0.0 && width <= MAX_SPAN) {
        return Err(format!(
            "cannot plot {what} over [{lo:e}, {hi:e}]: the range must be finite, non-empty and at most {MAX_SPAN:e} wide"
        )
        .into());
    }
    Ok(lo..hi)
}

/// Lowest and highest of `vals`, padded by 5 % (at least `min_pad`).
fn padded(vals: impl Iterator<Item = f64>, min_pad: f64) -> (f64, f64) {
    let (lo, hi) = vals
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05).max(min_pad);
    (lo - pad, hi + pad)
}

/// One SVG per drive axis (`friction_x.svg`, `friction_y.svg`), a panel per direction: the
/// identified dry-friction curve `Cbar(p)` [N] over the position [m], its simultaneous 95 %
/// band (shaded), its pointwise 95 % band (thin lines), the breakaway probes, and the true
/// curve when `truth` is known (virtual rig).
pub fn friction(
    id: &Identified,
    truth: Option<&crane_model::Params>,
    dir: &Path,
    outputs: &mut Outputs,
) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for (name, d, t) in [
        ("x", &id.x, truth.map(|t| &t.x)),
        ("y", &id.y, truth.map(|t| &t.y)),
    ] {
        let path = dir.join(format!("friction_{name}.svg"));
        let truths = t.map(|t| [t.dry_pos, t.dry_neg]);
        let mut svg = String::new();
        draw_friction(&mut svg, name, [&d.dry_pos, &d.dry_neg], truths)
            .map_err(|e| anyhow::anyhow!("{e}"))
            .with_context(|| format!("plot {}", path.display()))?;
        outputs.stage_plot(&path, "identify", &svg)?;
        files.push(path);
    }
    Ok(files)
}

fn draw_friction(
    svg: &mut String,
    axis: &str,
    fits: [&DryFit; 2],
    truth: Option<[[f64; 5]; 2]>,
) -> std::result::Result<(), Dyn> {
    let root = SVGBackend::with_string(svg, (900, 800)).into_drawing_area();
    root.fill(&WHITE)?;
    let panels = root.split_evenly((2, 1));
    for (i, (area, fit)) in panels.iter().zip(fits).enumerate() {
        let c = &fit.curve;
        let dir = ["+", "-"][i];
        let colour = [BLUE, RED][i];
        let truth_c = truth.map(|t| t[i]);
        let truth_pts: Vec<(f64, f64)> = truth_c
            .map(|tc| {
                c.position
                    .iter()
                    .map(|&p| (p, crane_model::friction::dry(&tc, p)))
                    .collect()
            })
            .unwrap_or_default();
        let (lo, hi) = padded(
            c.simultaneous_lower
                .iter()
                .chain(&c.simultaneous_upper)
                .chain(&fit.forces)
                .copied()
                .chain(truth_pts.iter().map(|p| p.1)),
            0.01,
        );
        let (x0, x1) = (
            c.position.first().copied().unwrap_or(0.0),
            c.position.last().copied().unwrap_or(1.0),
        );
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!(
                    "{} dry friction Cbar{dir}(p): {} probes, simultaneous band mean ± {:.2} std",
                    axis.to_uppercase(),
                    fit.positions.len(),
                    c.simultaneous_multiplier
                ),
                ("sans-serif", 18),
            )
            .margin(8)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d(
                span(x0, x1, &format!("{axis} position"))?,
                span(lo, hi, "friction")?,
            )?;
        chart
            .configure_mesh()
            .light_line_style(TRANSPARENT)
            .x_desc(format!("{axis} [m]"))
            .y_desc(format!("Cbar{dir} [N]"))
            .draw()?;
        let band: Vec<(f64, f64)> = c
            .position
            .iter()
            .zip(&c.simultaneous_upper)
            .map(|(&p, &v)| (p, v))
            .chain(
                c.position
                    .iter()
                    .zip(&c.simultaneous_lower)
                    .rev()
                    .map(|(&p, &v)| (p, v)),
            )
            .collect();
        chart
            .draw_series(std::iter::once(Polygon::new(
                band,
                colour.mix(0.18).filled(),
            )))?
            .label("95 % band over the axis (simultaneous)")
            .legend(move |(x, y)| {
                Rectangle::new([(x, y - 5), (x + 20, y + 5)], colour.mix(0.18).filled())
            });
        for (k, edge) in [&c.lower, &c.upper].into_iter().enumerate() {
            let s = chart.draw_series(LineSeries::new(
                c.position.iter().zip(edge).map(|(&p, &v)| (p, v)),
                colour.mix(0.6).stroke_width(1),
            ))?;
            if k == 0 {
                s.label("pointwise 95 % band").legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], colour.mix(0.6))
                });
            }
        }
        chart
            .draw_series(LineSeries::new(
                c.position.iter().zip(&c.mean).map(|(&p, &v)| (p, v)),
                colour.stroke_width(2),
            ))?
            .label("estimate (posterior mean)")
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
        chart
            .draw_series(
                fit.positions
                    .iter()
                    .zip(&fit.forces)
                    .map(|(&p, &f)| Circle::new((p, f), 3, BLACK.filled())),
            )?
            .label("breakaway probes")
            .legend(|(x, y)| Circle::new((x + 10, y), 3, BLACK.filled()));
        if !truth_pts.is_empty() {
            chart
                .draw_series(DashedLineSeries::new(
                    truth_pts,
                    6,
                    4,
                    BLACK.stroke_width(1),
                ))?
                .label("truth (virtual rig)")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
    }
    root.present()?;
    Ok(())
}

/// What `crane simulate` recorded, one entry per CSV sample.
#[derive(Clone, Debug, Default)]
pub struct SimulationRecord {
    /// Time [s].
    pub t: Vec<f64>,
    /// Voltages `u_x, u_y, u_l` [V].
    pub u: Vec<[f64; 3]>,
    /// Drive positions `x, y, L` [m].
    pub q: Vec<[f64; 3]>,
    /// Drive velocities `xd, yd, Ld` [m/s].
    pub qd: Vec<[f64; 3]>,
    /// Modes of X, Y and the rope.
    pub modes: Vec<[Mode; 3]>,
}

/// Fill colour of a mode band (red: negative, yellow: stopped, green: positive).
fn mode_colour(m: Mode) -> RGBColor {
    match m {
        Mode::Negative => RGBColor(240, 150, 150),
        Mode::Stopped => RGBColor(250, 225, 120),
        Mode::Positive => RGBColor(150, 215, 150),
    }
}

/// Maximal runs of equal mode of drive `i`: `(t_start, t_end, mode)`; a run ends where the
/// next begins.
fn mode_runs(rec: &SimulationRecord, i: usize) -> Vec<(f64, f64, Mode)> {
    let mut out: Vec<(f64, f64, Mode)> = Vec::new();
    for (k, m) in rec.modes.iter().enumerate() {
        let t = rec.t[k];
        match out.last_mut() {
            Some(last) if last.2 == m[i] => last.1 = t,
            Some(last) => {
                last.1 = t;
                out.push((t, t, m[i]));
            }
            None => out.push((t, t, m[i])),
        }
    }
    out
}

/// The run of `crane simulate` as one SVG: drive positions, velocities and voltages of X, Y
/// and the rope against time, and a panel of mode bands (Negative / Stopped / Positive per
/// drive).
pub fn simulation(rec: &SimulationRecord, path: &Path, outputs: &mut Outputs) -> Result<()> {
    let mut svg = String::new();
    draw_simulation(rec, &mut svg)
        .map_err(|e| anyhow::anyhow!("{e}"))
        .with_context(|| format!("plot {}", path.display()))?;
    outputs.stage_plot(path, "simulate", &svg)?;
    Ok(())
}

fn draw_simulation(rec: &SimulationRecord, svg: &mut String) -> std::result::Result<(), Dyn> {
    let root = SVGBackend::with_string(svg, (1000, 1100)).into_drawing_area();
    root.fill(&WHITE)?;
    let (top, bottom) = root.split_vertically(900);
    let panels = top.split_evenly((3, 1));
    let t_span = span(0.0, rec.t.last().copied().unwrap_or(1.0).max(1e-9), "time")?;
    // at most ~2000 points per line
    let stride = (rec.t.len() / 2000).max(1);
    let names = ["x", "y", "L"];
    let colours = [BLUE, RED, GREEN];
    type Series<'a> = (&'a str, &'a str, Box<dyn Fn(usize, usize) -> f64 + 'a>);
    let quantities: [Series; 3] = [
        ("drive positions", "[m]", Box::new(|k, i| rec.q[k][i])),
        ("drive velocities", "[m/s]", Box::new(|k, i| rec.qd[k][i])),
        ("voltages", "[V]", Box::new(|k, i| rec.u[k][i])),
    ];
    for (area, (title, unit, value)) in panels.iter().zip(quantities.iter()) {
        let (lo, hi) = padded(
            (0..rec.t.len())
                .flat_map(|k| (0..3).map(move |i| (k, i)))
                .map(|(k, i)| value(k, i)),
            1e-3,
        );
        let mut chart = ChartBuilder::on(area)
            .caption(*title, ("sans-serif", 18))
            .margin(8)
            .x_label_area_size(30)
            .y_label_area_size(60)
            .build_cartesian_2d(t_span.clone(), span(lo, hi, title)?)?;
        chart
            .configure_mesh()
            .light_line_style(TRANSPARENT)
            .x_desc("t [s]")
            .y_desc(*unit)
            .draw()?;
        for i in 0..3 {
            let c = colours[i];
            chart
                .draw_series(LineSeries::new(
                    (0..rec.t.len())
                        .step_by(stride)
                        .map(|k| (rec.t[k], value(k, i))),
                    c.stroke_width(2),
                ))?
                .label(names[i])
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
    }
    // Mode bands: one strip per drive (x top, L bottom).
    let mut chart = ChartBuilder::on(&bottom)
        .caption(
            "modes (red: Negative, yellow: Stopped, green: Positive)",
            ("sans-serif", 18),
        )
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(60)
        .build_cartesian_2d(t_span, -0.5..2.5)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .y_labels(3)
        .y_label_formatter(&|v: &f64| {
            match v.round() as i64 {
                2 => "x",
                1 => "y",
                0 => "L",
                _ => "",
            }
            .to_string()
        })
        .x_desc("t [s]")
        .draw()?;
    for i in 0..3 {
        let y = 2.0 - i as f64;
        chart.draw_series(mode_runs(rec, i).into_iter().map(|(a, b, m)| {
            Rectangle::new([(a, y - 0.4), (b, y + 0.4)], mode_colour(m).filled())
        }))?;
    }
    root.present()?;
    Ok(())
}
