//! The work-precision diagram of one case (SVG): wall time against velocity RMSE, log-log,
//! one line per method and setting ladder, and the speed-up at each error level.
//!
//! Layout: the plot on the left, and beside it (not on it) a panel with the legend and the
//! speed-up of each level against the goal. The legend inside the plot covered the data
//! (most series end in the upper right, where the slow, accurate runs are), and the goal
//! labels written beside each level's hybrid point ("4.9x (goal 10x: missed by 2.04x)", about
//! 250 px) overlapped each other where levels lie one decade (about 100 px) apart. On the
//! plot each level now carries only its speed-up ("4.9x", about 35 px), coloured by the goal;
//! the panel says by how much the goal is missed. Both properties are tested on the SVG.

use crate::error::{Error, Result};
use crate::output::Outputs;
use crate::tanh_run::tanh_name;
use crate::workprec::{Level, Method, Point, GOAL, TANH_GAMMAS};
use plotters::prelude::*;
use std::path::Path;

/// Size of the figure [px].
const SIZE: (u32, u32) = (1100, 750);
/// Width of the plot; the panel takes the rest [px].
const PLOT_W: u32 = 760;
/// Font size of the legend and of the speed-up labels [px].
const FONT: u32 = 13;
/// Height of one legend row [px].
const ROW: i32 = 17;

type Dyn = Box<dyn std::error::Error>;

/// Draws the work-precision diagram (time against error, log-log) of one case as SVG into
/// `path` (staged in `outputs`, published by its commit).
pub fn diagram(
    path: &Path,
    title: &str,
    pts: &[Point],
    levels: &[Level],
    outputs: &mut Outputs,
) -> Result<()> {
    let svg = render(title, pts, levels).map_err(|e| Error::Plot {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    outputs.stage(path, svg)?;
    Ok(())
}

/// One line of the diagram: label, colour, points (error, time), drawn bold.
struct Series {
    label: String,
    colour: RGBColor,
    points: Vec<(f64, f64)>,
    bold: bool,
}

/// The series of the diagram, in legend order; empty ones left out.
fn series(pts: &[&Point]) -> Vec<Series> {
    let line = |m: Method, g: Option<f64>| -> Vec<(f64, f64)> {
        let mut v: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.method == m && p.gamma == g)
            .map(|p| (p.rmse, p.time_s))
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        v
    };
    let one = |label: String, colour, points, bold| Series {
        label,
        colour,
        points,
        bold,
    };
    let mut out = vec![
        one(
            "hybrid fixed step (200 ms .. 0.05 ms)".into(),
            RGBColor(0, 0, 0),
            line(Method::HybridFixed, None),
            true,
        ),
        one(
            "hybrid adaptive DP45 (rtol 1e-3 .. 1e-10)".into(),
            RGBColor(200, 0, 0),
            line(Method::HybridAdaptive, None),
            true,
        ),
    ];
    let blues = [
        (120, 170, 255),
        (70, 120, 230),
        (30, 70, 200),
        (10, 40, 150),
        (0, 10, 90),
    ];
    let greens = [
        (120, 220, 120),
        (60, 180, 60),
        (20, 140, 20),
        (0, 100, 0),
        (0, 60, 0),
    ];
    for (k, &g) in TANH_GAMMAS.iter().enumerate() {
        let (b, gr) = (blues[k % 5], greens[k % 5]);
        out.push(one(
            format!("{} DP45", tanh_name(g)),
            RGBColor(b.0, b.1, b.2),
            line(Method::TanhDp45, Some(g)),
            false,
        ));
        out.push(one(
            format!("{} Rosenbrock 2(3)", tanh_name(g)),
            RGBColor(gr.0, gr.1, gr.2),
            line(Method::TanhRosenbrock, Some(g)),
            false,
        ));
        // BDF: oranges, light (gamma 1e2) to dark (1e6)
        let k = (k % 5) as u8;
        out.push(one(
            format!("{} BDF", tanh_name(g)),
            RGBColor(255, 190 - 35 * k, 60 - 12 * k),
            line(Method::TanhBdf, Some(g)),
            false,
        ));
    }
    out.retain(|s| !s.points.is_empty());
    out
}

/// Green where the speed-up meets [`GOAL`], red where it misses it.
fn goal_colour(speedup: f64) -> RGBColor {
    if speedup >= GOAL {
        RGBColor(0, 130, 0)
    } else {
        RGBColor(200, 0, 0)
    }
}

/// The SVG text of the diagram.
fn render(title: &str, pts: &[Point], levels: &[Level]) -> std::result::Result<String, Dyn> {
    let ok: Vec<&Point> = pts
        .iter()
        .filter(|p| p.rmse.is_finite() && p.rmse > 0.0 && p.time_s > 0.0)
        .collect();
    let (mut elo, mut ehi, mut tlo, mut thi) = (1e-9f64, 1e-2f64, f64::INFINITY, 0.0f64);
    for p in &ok {
        elo = elo.min(p.rmse);
        ehi = ehi.max(p.rmse);
        tlo = tlo.min(p.time_s);
        thi = thi.max(p.time_s);
    }
    if !(tlo.is_finite() && thi > 0.0) {
        (tlo, thi) = (1e-4, 1.0);
    }
    let (elo, ehi) = (elo / 2.0, ehi * 2.0);
    let (tlo, thi) = (tlo / 2.0, thi * 2.0);
    let lines = series(&ok);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE)?;
        let (plot, panel) = root.split_horizontally(PLOT_W);
        let mut ch = ChartBuilder::on(&plot)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d((elo..ehi).log_scale(), (tlo..thi).log_scale())?;
        ch.configure_mesh()
            .x_desc("RMSE of the compared velocity against the 10 us reference [m/s]")
            .y_desc("wall time of the run [s]")
            .x_label_formatter(&|v| format!("{v:.0e}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()?;
        for s in &lines {
            let w = if s.bold { 3 } else { 1 };
            let col = s.colour;
            ch.draw_series(LineSeries::new(s.points.clone(), col.stroke_width(w)))?;
            ch.draw_series(
                s.points
                    .iter()
                    .map(|&(x, y)| Circle::new((x, y), 3, col.filled())),
            )?;
        }
        // each level's speed-up below its hybrid point, coloured by the goal
        for l in levels {
            if let (Some(h), Some(s)) = (&l.hybrid, l.speedup) {
                ch.draw_series(std::iter::once(Text::new(
                    format!("{s:.1}x"),
                    (l.level, h.time_s / 1.6),
                    ("sans-serif", FONT).into_font().color(&goal_colour(s)),
                )))?;
            }
        }
        draw_panel(&panel, &lines, levels)?;
        root.present()?;
    }
    Ok(svg)
}

/// The panel beside the plot: the legend, then the speed-up per level against the goal.
fn draw_panel<DB: DrawingBackend>(
    panel: &DrawingArea<DB, plotters::coord::Shift>,
    lines: &[Series],
    levels: &[Level],
) -> std::result::Result<(), Dyn>
where
    DB::ErrorType: 'static,
{
    let font = ("sans-serif", FONT).into_font();
    let mut y = 60;
    panel.draw(&Text::new(
        "series",
        (10, y - ROW),
        font.clone().color(&BLACK),
    ))?;
    for s in lines {
        let w = if s.bold { 3 } else { 2 };
        panel.draw(&PathElement::new(
            vec![(10, y + 6), (34, y + 6)],
            s.colour.stroke_width(w),
        ))?;
        panel.draw(&Text::new(
            s.label.clone(),
            (40, y),
            font.clone().color(&BLACK),
        ))?;
        y += ROW;
    }
    y += ROW;
    panel.draw(&Text::new(
        format!("fastest hybrid against fastest tanh (goal {GOAL:.0}x)"),
        (10, y),
        font.clone().color(&BLACK),
    ))?;
    y += ROW;
    for l in levels {
        let text = match l.speedup {
            Some(s) if s >= GOAL => format!("{:.0e} m/s: {s:.1}x", l.level),
            Some(s) => format!("{:.0e} m/s: {s:.1}x, missed by {:.2}x", l.level, GOAL / s),
            None => format!("{:.0e} m/s: not reached by both", l.level),
        };
        let col = l.speedup.map_or(RGBColor(90, 90, 90), goal_colour);
        panel.draw(&Text::new(text, (10, y), font.clone().color(&col)))?;
        y += ROW;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::workprec::{compare, LEVELS};

    /// Synthetic points shaped like a case's sweep: hybrid lines fast at every level, tanh
    /// lines slower, each line's slow accurate end in the upper right.
    fn sweep() -> Vec<Point> {
        let mut v = Vec::new();
        let mut add = |method, gamma, k: usize, time_s: f64, rmse: f64| {
            v.push(Point {
                method,
                gamma,
                setting: 10f64.powi(-(k as i32) - 3),
                time_s,
                rmse,
                steps: 100,
            })
        };
        for k in 0..8 {
            let e = 10f64.powi(-(k as i32) - 3);
            add(
                Method::HybridAdaptive,
                None,
                k,
                1e-4 * 1.3f64.powi(k as i32),
                e,
            );
            add(
                Method::HybridFixed,
                None,
                k,
                1e-3 * 2f64.powi(k as i32),
                e * 3.0,
            );
        }
        for (j, &g) in TANH_GAMMAS.iter().enumerate() {
            for k in 0..6 {
                let e = 10f64.powi(-(k as i32) - 2 - j as i32 / 2);
                let t = 1e-3 * 3f64.powi(k as i32 + j as i32);
                add(Method::TanhDp45, Some(g), k, t, e);
                add(Method::TanhRosenbrock, Some(g), k, t * 0.7, e);
                add(Method::TanhBdf, Some(g), k, t * 0.5, e);
            }
        }
        v
    }

    /// A `<text>` element: x, y [px], its text.
    type Label = (f64, f64, String);

    /// Every `<text>` element, and `(x, y)` of every `<circle>`.
    fn parse(svg: &str) -> (Vec<Label>, Vec<(f64, f64)>) {
        let attr = |tag: &str, name: &str| -> f64 {
            let key = format!(" {name}=\"");
            tag.find(&key)
                .and_then(|i| {
                    let rest = &tag[i + key.len()..];
                    rest[..rest.find('"')?].parse().ok()
                })
                .unwrap_or(f64::NAN)
        };
        let mut texts = Vec::new();
        let mut circles = Vec::new();
        for (i, _) in svg.match_indices("<text") {
            let tag = &svg[i..i + svg[i..].find('>').unwrap_or(0)];
            let body_start = i + tag.len() + 1;
            let body =
                &svg[body_start..body_start + svg[body_start..].find("</text>").unwrap_or(0)];
            texts.push((attr(tag, "x"), attr(tag, "y"), body.trim().to_string()));
        }
        for (i, _) in svg.match_indices("<circle") {
            let tag = &svg[i..i + svg[i..].find('>').unwrap_or(0)];
            circles.push((attr(tag, "cx"), attr(tag, "cy")));
        }
        (texts, circles)
    }

    #[test]
    fn the_legend_is_beside_the_data_not_on_it() {
        let pts = sweep();
        let levels = compare(&pts);
        let svg = render("case", &pts, &levels).expect("renders");
        let (texts, circles) = parse(&svg);
        assert!(circles.len() >= pts.len(), "{} circles", circles.len());
        let right = circles.iter().map(|c| c.0).fold(0.0f64, f64::max);
        assert!(right < f64::from(PLOT_W), "a data point at x = {right}");
        // every series label is in the panel, right of every data point
        for s in series(&pts.iter().collect::<Vec<_>>()) {
            let t = texts.iter().find(|t| t.2 == s.label);
            let t = t.unwrap_or_else(|| panic!("legend entry {} missing", s.label));
            assert!(
                t.0 > right,
                "{} at x = {} (data up to {right})",
                s.label,
                t.0
            );
        }
    }

    #[test]
    fn the_speedup_labels_on_the_plot_do_not_overlap() {
        let pts = sweep();
        let levels = compare(&pts);
        assert!(levels.iter().filter(|l| l.speedup.is_some()).count() >= 3);
        let svg = render("case", &pts, &levels).expect("renders");
        let (texts, _) = parse(&svg);
        // the labels on the plot: "<n>x" left of the panel
        let labels: Vec<&Label> = texts
            .iter()
            .filter(|t| t.0 < f64::from(PLOT_W) && t.2.ends_with('x') && t.2.len() <= 8)
            .collect();
        assert_eq!(
            labels.len(),
            levels.iter().filter(|l| l.speedup.is_some()).count(),
            "{labels:?}"
        );
        // a glyph is at most 0.65 em wide; boxes [x, x + w] x [y - FONT, y] must not meet
        let width = |t: &str| 0.65 * f64::from(FONT) * t.chars().count() as f64;
        for (i, a) in labels.iter().enumerate() {
            for b in &labels[i + 1..] {
                let apart_x = a.0 + width(&a.2) <= b.0 || b.0 + width(&b.2) <= a.0;
                let apart_y = (a.1 - b.1).abs() >= f64::from(FONT);
                assert!(apart_x || apart_y, "{a:?} overlaps {b:?}");
            }
        }
        // the panel says by how much the goal is missed, one line per level
        for l in &levels {
            let head = format!("{:.0e} m/s: ", l.level);
            assert!(texts.iter().any(|t| t.2.starts_with(&head)), "{head}");
        }
        assert_eq!(LEVELS.len(), levels.len());
    }
}
