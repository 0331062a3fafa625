//! The plot of `crane monitor --plot`: one panel per axis and direction with the last map of
//! the log's last section against position [m]: the reference and the current level [N]
//! through the bin centres, the band (reference ± one standard deviation) as a shaded box per
//! bin, the alarm threshold (reference ± `OUT_OF_BAND_K` bands) as thin lines, the positions
//! of that axis's `local_friction` alarms as vertical lines and its other alarms (of that
//! direction or both) as notes.

use super::{report, Alarm, AlarmKind, Dir, Map, Report, Section, OUT_OF_BAND_K};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

type Dyn = Box<dyn std::error::Error>;
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Widest axis span a panel accepts [m or N] (plotters' tick search needs a finite, sane one).
const MAX_SPAN: f64 = 1e9;

/// Pixel size of one panel (width, height).
const PANEL: (u32, u32) = (640, 420);

/// The SVG of the last maps of `r`'s last section (an error message when drawing fails).
pub fn svg(r: &Report) -> Result<String, String> {
    let mut text = String::new();
    let Some(section) = r.sections.last() else {
        return Err("no section to plot".to_string());
    };
    draw(&mut text, section).map_err(|e| e.to_string())?;
    Ok(text)
}

fn draw(text: &mut String, s: &Section) -> Result<(), Dyn> {
    let maps = s.last_maps();
    let n = maps.len().max(1);
    let cols = n.min(2);
    let rows = n.div_ceil(2);
    let size = (PANEL.0 * cols as u32, PANEL.1 * rows as u32 + 40);
    let root = SVGBackend::with_string(text, size).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(
        &format!("friction monitor, section {}: last maps", s.tag),
        ("sans-serif", 22),
    )?;
    if maps.is_empty() {
        root.draw(&Text::new(
            format!("no friction maps in section {}", s.tag),
            (20, 20),
            ("sans-serif", 18),
        ))?;
        // its alarms as text (the panel's height holds about 20)
        for (i, a) in s.alarms.iter().take(20).enumerate() {
            let line = format!(
                "t = {:.3} s: {} axis {} dir {}: {}",
                a.time_s,
                a.kind.name(),
                a.axis.name(),
                a.dir.name(),
                report::size(&a.kind)
            );
            root.draw(&Text::new(
                line,
                (20, 50 + 18 * i as i32),
                ("sans-serif", 14),
            ))?;
        }
        root.present()?;
        return Ok(());
    }
    let panels = root.split_evenly((rows, cols));
    for (m, area) in maps.iter().zip(panels.iter()) {
        panel(area, m, &s.alarms)?;
    }
    root.present()?;
    Ok(())
}

/// Newtons of a row value [mN].
fn newtons(v: i32) -> f64 {
    f64::from(v) / 1000.0
}

/// The values of a row per bin [N] (`None` for an empty bin or a missing row).
fn row(m: &Map, r: &Option<Vec<Option<i32>>>) -> Vec<Option<f64>> {
    (0..m.bins)
        .map(|b| {
            r.as_ref()
                .and_then(|r| r.get(b).copied().flatten())
                .map(newtons)
        })
        .collect()
}

/// A checked axis range with 6 % padding, `below` times that under it (room for the legend);
/// a unit range around an empty set.
fn range(
    vals: impl Iterator<Item = f64>,
    below: f64,
    what: &str,
) -> Result<std::ops::Range<f64>, Dyn> {
    let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
        (l.min(v), h.max(v))
    });
    let (lo, hi) = if lo > hi { (-1.0, 1.0) } else { (lo, hi) };
    let pad = ((hi - lo) * 0.06).max(1e-3);
    let (lo, hi) = (lo - pad * below, hi + pad);
    if !(lo.is_finite() && hi.is_finite() && hi - lo <= MAX_SPAN) {
        return Err(format!("{what} range {lo}..{hi} is not plottable").into());
    }
    Ok(lo..hi)
}

/// A tick label of `v` on an axis spanning `span`, with the decimals of its tick step and
/// no `-0`.
fn tick(v: f64, span: f64) -> String {
    let step = span / 10.0;
    let decimals = (-step.log10().floor()).clamp(0.0, 6.0) as usize;
    let s = format!("{v:.decimals$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_string(),
        _ => s,
    }
}

/// Contiguous runs of bins with a value, as `(position [m], value)` polylines.
fn runs(m: &Map, vals: &[Option<f64>]) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut open = false;
    for (b, v) in vals.iter().enumerate() {
        match v {
            Some(v) if open => out
                .last_mut()
                .into_iter()
                .for_each(|r| r.push((m.centre(b), *v))),
            Some(v) => {
                out.push(vec![(m.centre(b), *v)]);
                open = true;
            }
            None => open = false,
        }
    }
    out
}

/// Draws `runs` as lines of `style`, labelled once as `label` (if any).
fn lines(
    chart: &mut Chart<'_, '_>,
    runs: Vec<Vec<(f64, f64)>>,
    style: ShapeStyle,
    label: Option<&str>,
) -> Result<(), Dyn> {
    for (i, r) in runs.into_iter().enumerate() {
        let s = chart.draw_series(LineSeries::new(r, style))?;
        if let (0, Some(label)) = (i, label) {
            s.label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        }
    }
    Ok(())
}

/// One panel: the map `m` and the alarms of its axis.
fn panel(
    area: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
    m: &Map,
    alarms: &[Alarm],
) -> Result<(), Dyn> {
    let (rf, cur, band) = (row(m, &m.ref_mn), row(m, &m.cur_mn), row(m, &m.band_mn));
    let both = |k: f64| -> Vec<Option<f64>> {
        rf.iter()
            .zip(&band)
            .map(|(r, b)| Some(r.as_ref()? + k * b.as_ref()?))
            .collect()
    };
    let (up1, lo1, up_k, lo_k) = (
        both(1.0),
        both(-1.0),
        both(OUT_OF_BAND_K),
        both(-OUT_OF_BAND_K),
    );
    let all = [&rf, &cur, &up_k, &lo_k];
    let y = range(
        all.iter().flat_map(|v| v.iter().flatten().copied()),
        8.0,
        "force",
    )?;
    let x = range(
        [f64::from(m.lo), f64::from(m.hi)].into_iter(),
        1.0,
        "position",
    )?;
    let (y0, y1) = (y.start, y.end);
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!(
                "axis {}, moving {} (t = {:.2} s)",
                m.axis.name(),
                m.dir.name(),
                m.time_s
            ),
            ("sans-serif", 18),
        )
        .margin(10)
        .x_label_area_size(36)
        .y_label_area_size(56)
        .build_cartesian_2d(x, y)?;
    chart
        .configure_mesh()
        .x_desc("position [m]")
        .y_desc("friction map [N]")
        .y_label_formatter(&|v| tick(*v, y1 - y0))
        .draw()?;
    let shade = RGBColor(120, 160, 230).mix(0.3).filled();
    let half = m.bin_width() / 2.0;
    chart
        .draw_series(up1.iter().zip(&lo1).enumerate().filter_map(|(b, (u, l))| {
            let (u, l) = (u.as_ref()?, l.as_ref()?);
            let c = m.centre(b);
            Some(Rectangle::new([(c - half, *l), (c + half, *u)], shade))
        }))?
        .label("ref ± band (1 sd)")
        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], shade));
    let thin = RGBColor(150, 150, 150).stroke_width(1);
    let threshold = format!("ref ± {OUT_OF_BAND_K} band");
    lines(&mut chart, runs(m, &up_k), thin, Some(&threshold))?;
    lines(&mut chart, runs(m, &lo_k), thin, None)?;
    lines(
        &mut chart,
        runs(m, &rf),
        BLUE.stroke_width(2),
        Some("reference"),
    )?;
    lines(
        &mut chart,
        runs(m, &cur),
        RED.stroke_width(2),
        Some("current"),
    )?;
    markers(&mut chart, m, alarms, (y0, y1))?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()?;
    Ok(())
}

/// Vertical lines at the `local_friction` alarms of `m`'s axis (either direction); notes for
/// its other alarms in `m`'s direction or both.
fn markers(
    chart: &mut Chart<'_, '_>,
    m: &Map,
    alarms: &[Alarm],
    (y0, y1): (f64, f64),
) -> Result<(), Dyn> {
    let mine = alarms.iter().filter(|a| a.axis == m.axis);
    let mut notes = Vec::new();
    let mut first = true;
    let style = RGBColor(200, 0, 160).stroke_width(2);
    for a in mine {
        match a.kind {
            AlarmKind::LocalFriction { position, .. } => {
                let x = f64::from(position);
                let s = chart.draw_series(LineSeries::new([(x, y0), (x, y1)], style))?;
                if first {
                    s.label("local_friction alarm")
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
                    first = false;
                }
                let label = format!("{:.3} m, t = {:.1} s", position, a.time_s);
                chart.draw_series(std::iter::once(Text::new(
                    label,
                    (x, y1),
                    ("sans-serif", 12),
                )))?;
            }
            _ if a.dir != m.dir && a.dir != Dir::Both => {}
            _ => notes.push(format!(
                "{} dir {} at t = {:.1} s: {}",
                a.kind.name(),
                a.dir.name(),
                a.time_s,
                report::size(&a.kind)
            )),
        }
    }
    let x0 = f64::from(m.lo) + 0.02 * (f64::from(m.hi) - f64::from(m.lo));
    for (i, n) in notes.iter().enumerate() {
        let y = y1 - (0.08 + 0.06 * i as f64) * (y1 - y0);
        chart.draw_series(std::iter::once(Text::new(
            n.clone(),
            (x0, y),
            ("sans-serif", 12),
        )))?;
    }
    Ok(())
}
