//! Plots as plain SVG (no font or system library): the simulated position error against time,
//! position and velocity, per axis, before (red) and after (blue) the strongest extension.

use crate::DiagnoseError;
use std::fmt::Write as _;
use std::path::Path;

/// One axis of one held-out run.
#[derive(Clone, Debug, Default)]
pub struct Series {
    /// File stem.
    pub name: String,
    /// Time [s].
    pub t: Vec<f64>,
    /// Position [m].
    pub q: Vec<f64>,
    /// Velocity [m/s].
    pub v: Vec<f64>,
    /// Residual before (measured - simulated, or force residual).
    pub before: Vec<f64>,
    /// Residual after.
    pub after: Vec<f64>,
}

fn scatter(x: &[f64], ys: &[(&[f64], &str)], title: &str) -> String {
    let (w, h, m) = (600.0, 300.0, 40.0);
    let lo = |v: &[f64]| {
        v.iter()
            .cloned()
            .filter(|x| x.is_finite())
            .fold(f64::INFINITY, f64::min)
    };
    let hi = |v: &[f64]| {
        v.iter()
            .cloned()
            .filter(|x| x.is_finite())
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let (x0, x1) = (lo(x), hi(x));
    let mut y0 = f64::INFINITY;
    let mut y1 = f64::NEG_INFINITY;
    for (y, _) in ys {
        y0 = y0.min(lo(y));
        y1 = y1.max(hi(y));
    }
    if x1.partial_cmp(&x0) != Some(std::cmp::Ordering::Greater)
        || y1.partial_cmp(&y0) != Some(std::cmp::Ordering::Greater)
    {
        return String::new();
    }
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\"><title>{title}</title>\
         <rect x=\"{m}\" y=\"{m}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"black\"/>\
         <text x=\"{m}\" y=\"20\" font-size=\"12\">{title} (x {x0:.3}..{x1:.3}, y {y0:.4}..{y1:.4})</text>",
        w - 2.0 * m,
        h - 2.0 * m
    );
    let stride = (x.len() / 3000).max(1);
    for (y, color) in ys {
        for k in (0..x.len().min(y.len())).step_by(stride) {
            let px = m + (x[k] - x0) / (x1 - x0) * (w - 2.0 * m);
            let py = h - m - (y[k] - y0) / (y1 - y0) * (h - 2.0 * m);
            let _ = write!(
                s,
                "<circle cx=\"{px:.1}\" cy=\"{py:.1}\" r=\"0.8\" fill=\"{color}\"/>"
            );
        }
    }
    s.push_str("</svg>");
    s
}

/// Writes `<name>_vs_{time,position,velocity}.svg` per series (crane axes, or the single-axis
/// closed-loop force residuals).
pub fn crane_plots(dir: &Path, series: &[Series]) -> Result<(), DiagnoseError> {
    crane_ident::atomic::create_dir(dir)
        .map_err(|e| DiagnoseError::Io(format!("{}: {e}", dir.display())))?;
    for s in series {
        let ys: Vec<(&[f64], &str)> = [(s.before.as_slice(), "red"), (s.after.as_slice(), "blue")]
            .into_iter()
            .filter(|(y, _)| !y.is_empty())
            .collect();
        for (tag, x) in [("time", &s.t), ("position", &s.q), ("velocity", &s.v)] {
            let svg = scatter(x, &ys, &format!("{} residual vs {tag}", s.name));
            let path = dir.join(format!("{}_vs_{tag}.svg", s.name));
            crane_ident::atomic::write(&path, crate::mark_plot(&svg))
                .map_err(|e| DiagnoseError::Io(format!("{}: {e}", path.display())))?;
        }
    }
    Ok(())
}
