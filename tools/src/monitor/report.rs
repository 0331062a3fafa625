//! The table `crane monitor` prints, and the bins whose current level left its band.

use super::{AlarmKind, Map, OutOfBand, Report, Section, OUT_OF_BAND_K};
use std::fmt::Write;

/// Out-of-band bins listed per map in the table (the JSON report has them all).
const LISTED: usize = 6;

/// Bins of `m` with a reference, a current level and a band where
/// `|cur - ref| > OUT_OF_BAND_K * band` (all in mN).
pub fn out_of_band(m: &Map) -> Vec<OutOfBand> {
    let (Some(r), Some(c), Some(b)) = (&m.ref_mn, &m.cur_mn, &m.band_mn) else {
        return Vec::new();
    };
    (0..m.bins)
        .filter_map(|i| {
            let (r, c, b) = (
                r.get(i).copied()??,
                c.get(i).copied()??,
                b.get(i).copied()??,
            );
            let dev = (f64::from(c) - f64::from(r)).abs();
            (dev > OUT_OF_BAND_K * f64::from(b)).then(|| OutOfBand {
                bin: i,
                position: m.centre(i),
                ref_mn: r,
                cur_mn: c,
                band_mn: b,
            })
        })
        .collect()
}

/// The size fields of an alarm with their units.
pub fn size(kind: &AlarmKind) -> String {
    match *kind {
        AlarmKind::FrictionDrift { change } => format!("change {change} N"),
        AlarmKind::LocalFriction {
            position,
            width,
            change,
        } => format!("position {position} m, width {width} m, change {change} N"),
        AlarmKind::StictionRise { ratio, learned } => {
            format!("ratio {ratio} (learned {learned})")
        }
        AlarmKind::ModelMismatch {
            mean_square,
            learned,
        } => format!("mean square {mean_square:e} m^2 (learned {learned:e} m^2)"),
    }
}

/// The out-of-band column of a map.
fn out_of_band_cell(m: &Map) -> String {
    if m.ref_mn.is_none() || m.cur_mn.is_none() || m.band_mn.is_none() {
        return "rows missing in the log".to_string();
    }
    if m.out_of_band.is_empty() {
        return "none".to_string();
    }
    // cur - ref [mN] and the band [mN] of each bin out of band
    let mut s = m
        .out_of_band
        .iter()
        .take(LISTED)
        .map(|o| {
            format!(
                "bin {} @ {:.3} m: {:+} mN (band {})",
                o.bin,
                o.position,
                i64::from(o.cur_mn) - i64::from(o.ref_mn),
                o.band_mn
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    if m.out_of_band.len() > LISTED {
        let _ = write!(s, "; and {} more", m.out_of_band.len() - LISTED);
    }
    s
}

/// One section of the table.
fn section(t: &mut String, s: &Section) {
    let mut head = format!("section {}", s.tag);
    if let (Some(seed), Some(d)) = (s.seed, s.duration) {
        let _ = write!(head, ": seed {seed}, duration {d} s");
    }
    match &s.hash {
        Some(h) => {
            let _ = write!(head, ", hash {h}");
        }
        None if s.seed.is_some() => head.push_str(", no MEND"),
        None => {}
    }
    let _ = writeln!(t, "{head}");
    if s.alarms.is_empty() {
        let _ = writeln!(t, "  alarms: none");
    } else {
        let _ = writeln!(t, "  alarms: {}", s.alarms.len());
        let _ = writeln!(
            t,
            "    {:>10}  {:<15} {:<4} {:<3}  size",
            "time [s]", "kind", "axis", "dir"
        );
        for a in &s.alarms {
            let _ = writeln!(
                t,
                "    {:>10.3}  {:<15} {:<4} {:<3}  {}",
                a.time_s,
                a.kind.name(),
                a.axis.name(),
                a.dir.name(),
                size(&a.kind)
            );
        }
    }
    let maps = s.last_maps();
    if maps.is_empty() {
        let _ = writeln!(t, "  maps: none");
        return;
    }
    let _ = writeln!(
        t,
        "  maps (last summary per axis and direction; out of band: |cur - ref| > {OUT_OF_BAND_K} band):"
    );
    let _ = writeln!(
        t,
        "    {:>10}  {:<4} {:<3}  {:>9}  {:>12}  {:>13}  {:>5}  {:>5}  {:>20}  out of band",
        "time [s]",
        "axis",
        "dir",
        "level [N]",
        "level_sd [N]",
        "slope [N s/m]",
        "bins",
        "ready",
        "restarts/moves/judged"
    );
    for m in maps {
        let _ = writeln!(
            t,
            "    {:>10.3}  {:<4} {:<3}  {:>9.4}  {:>12.4}  {:>13.4}  {:>5}  {:>5}  {:>20}  {}",
            m.time_s,
            m.axis.name(),
            m.dir.name(),
            m.level,
            m.level_sd,
            m.slope,
            format!("{}/{}", m.bins_with_data(), m.bins),
            match m.ready {
                Some(true) => "yes",
                Some(false) => "no",
                None => "-",
            },
            m.coverage.map_or("-".to_string(), |c| format!(
                "{}/{}/{}",
                c.restarts, c.moves, c.judged
            )),
            out_of_band_cell(m)
        );
    }
}

/// The table of `r`: per section its alarms (time, kind, axis, direction, size with units)
/// and the last summary of each map (level, its band, viscous slope, bins with data, the
/// bins out of band with their positions).
pub fn table(r: &Report) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "{}: {} section{}, control period {} s",
        r.log,
        r.sections.len(),
        if r.sections.len() == 1 { "" } else { "s" },
        r.period_s
    );
    for s in &r.sections {
        t.push('\n');
        section(&mut t, s);
    }
    t
}
