//! The monitor's frames on the UART log: one text line each, `key=value` fields, numbers in
//! `core::fmt`'s shortest round-trip form (so a host decoding them gets the `f32` bits the
//! firmware had). `crane monitor LOG` decodes them (docs: `twin/README.md`, "Frames").
//!
//! - `MALARM period=<u64> kind=<name> axis=<X|Y> dir=<+|-|+-> <size fields>`: an alarm; the
//!   size fields are those of [`AlarmKind`]: `change=<N>`; `position=<m> width=<m>
//!   change=<N>`; `ratio=<1> learned=<1>`; `mean_square=<m^2> learned=<m^2>`.
//! - `MSUM period=<u64> axis=<X|Y> dir=<+|-> lo=<m> hi=<m> bins=<n> level=<N>
//!   level_sd=<N> slope=<N s/m> v0=<m/s> ready=<0|1> restarts=<n> moves=<n> judged=<n>`: a
//!   map's summary; `ready` is the monitor's ([`Monitor::ready`]: commissioning is over, it
//!   judges), `restarts`, `moves` and `judged` what commissioning has seen of this axis and
//!   direction ([`super::Coverage`]: restarts learned, moves that gave the travel's level,
//!   bins with enough samples to be judged);
//! - `MMAP period=<u64> axis=<X|Y> dir=<+|-> what=<ref|cur|band> mN=<v0>,<v1>,...`: one row
//!   of a map in millinewtons, rounded and saturated to ±99,999 (`band` is the band's standard
//!   deviation), `_` for a bin with no sample yet.
//!
//! Every line stays under 512 bytes (the firmware's line buffer, one defmt frame with `probe`).

use super::alarm::{Alarm, AlarmKind};
use super::map::{SlidingMap, BINS};
use super::{Monitor, AXES};
use core::fmt::{self, Write};
use crane_model::{Axis, Direction};

fn axis_name(a: Axis) -> &'static str {
    match a {
        Axis::X => "X",
        Axis::Y => "Y",
        Axis::Rope => "L",
    }
}

fn dir_name(d: Direction) -> &'static str {
    match d {
        Direction::Positive => "+",
        Direction::Negative => "-",
        Direction::Both => "+-",
    }
}

/// Writes one `MALARM` line.
pub fn write_alarm<W: Write>(out: &mut W, a: &Alarm) -> fmt::Result {
    write!(
        out,
        "MALARM period={} kind={} axis={} dir={}",
        a.period,
        a.kind.name(),
        axis_name(a.axis),
        dir_name(a.direction)
    )?;
    match a.kind {
        AlarmKind::FrictionDrift { change } => writeln!(out, " change={change}"),
        AlarmKind::LocalFriction {
            position,
            width,
            change,
        } => writeln!(out, " position={position} width={width} change={change}"),
        AlarmKind::StictionRise { ratio, learned } => {
            writeln!(out, " ratio={ratio} learned={learned}")
        }
        AlarmKind::ModelMismatch {
            mean_square,
            learned,
        } => writeln!(out, " mean_square={mean_square} learned={learned}"),
    }
}

/// Largest magnitude of a map value in a frame [mN] (100 N: beyond any trolley's friction),
/// so that a row of 64 values stays under the 512-byte line.
pub const MN_LIMIT: i32 = 99_999;

/// Millinewtons of `v` [N], rounded half away from zero, saturated to `±MN_LIMIT` (NaN: 0).
fn mn(v: f32) -> i32 {
    let x = v * 1000.0;
    let r = if x < 0.0 { x - 0.5 } else { x + 0.5 };
    if r.is_nan() {
        0
    } else if r >= MN_LIMIT as f32 {
        MN_LIMIT
    } else if r <= -(MN_LIMIT as f32) {
        -MN_LIMIT
    } else {
        r as i32
    }
}

fn write_row<W: Write>(
    out: &mut W,
    head: (u64, Axis, Direction),
    what: &str,
    map: &SlidingMap,
    value: impl Fn(usize) -> f32,
) -> fmt::Result {
    let (period, axis, dir) = head;
    write!(
        out,
        "MMAP period={period} axis={} dir={} what={what} mN=",
        axis_name(axis),
        dir_name(dir)
    )?;
    for b in 0..BINS {
        if b > 0 {
            out.write_char(',')?;
        }
        if map.count(b) == 0 {
            out.write_char('_')?;
        } else {
            write!(out, "{}", mn(value(b)))?;
        }
    }
    writeln!(out)
}

/// Writes the summary of every map: an `MSUM` line and three `MMAP` rows (reference, current
/// level, band) per watched axis and direction.
pub fn write_maps<W: Write>(out: &mut W, m: &Monitor) -> fmt::Result {
    let period = m.period();
    for axis in AXES {
        for dir in [Direction::Negative, Direction::Positive] {
            let (Some(map), Some((level, band)), Some(cov)) =
                (m.map(axis, dir), m.level(axis, dir), m.coverage(axis, dir))
            else {
                continue;
            };
            let (slope, v0) = map.viscous_slope();
            let (lo, hi) = map.travel();
            writeln!(
                out,
                "MSUM period={period} axis={} dir={} lo={lo} hi={hi} bins={BINS} level={level} level_sd={} slope={slope} v0={v0} ready={} restarts={} moves={} judged={}",
                axis_name(axis),
                dir_name(dir),
                sqrt(band),
                u8::from(m.ready()),
                cov.restarts,
                cov.moves,
                cov.judged,
            )?;
            let head = (period, axis, dir);
            write_row(out, head, "ref", map, |b| map.reference(b))?;
            write_row(out, head, "cur", map, |b| {
                map.reference(b) + map.view(b, &m.settings().map).deviation
            })?;
            write_row(out, head, "band", map, |b| {
                sqrt(map.view(b, &m.settings().map).band)
            })?;
        }
    }
    Ok(())
}

/// Square root of `x >= 0` by Newton's iteration (no libm in this path; for reporting only).
fn sqrt(x: f32) -> f32 {
    if x <= 0.0 || !x.is_finite() {
        return 0.0;
    }
    let mut y = if x > 1.0 { x } else { 1.0 };
    for _ in 0..40 {
        y = 0.5 * (y + x / y);
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Buf {
        b: [u8; 600],
        n: usize,
    }

    impl Write for Buf {
        fn write_str(&mut self, s: &str) -> fmt::Result {
            let end = self.n + s.len();
            self.b
                .get_mut(self.n..end)
                .ok_or(fmt::Error)?
                .copy_from_slice(s.as_bytes());
            self.n = end;
            Ok(())
        }
    }

    #[test]
    fn an_alarm_is_one_line_with_its_fields() {
        let mut buf = Buf { b: [0; 600], n: 0 };
        let a = Alarm {
            kind: AlarmKind::LocalFriction {
                position: 0.31,
                width: 0.0158,
                change: 0.5,
            },
            axis: Axis::X,
            direction: Direction::Both,
            period: 42,
        };
        write_alarm(&mut buf, &a).unwrap_or(());
        let s = core::str::from_utf8(&buf.b[..buf.n]).unwrap_or("");
        assert_eq!(
            s,
            "MALARM period=42 kind=local_friction axis=X dir=+- position=0.31 width=0.0158 change=0.5\n"
        );
    }

    #[test]
    fn millinewtons_round_and_saturate() {
        assert_eq!(mn(0.0015), 2);
        assert_eq!(mn(-0.0015), -2);
        assert_eq!(mn(f32::NAN), 0);
        assert_eq!(mn(1e12), MN_LIMIT);
        assert_eq!(mn(-1e12), -MN_LIMIT);
        assert!((sqrt(2.0) - core::f32::consts::SQRT_2).abs() < 1e-6);
    }
}
