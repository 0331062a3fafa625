//! The monitor's frames in a log, into a [`Report`]. A line is a frame when its first word is
//! `MBEGIN`, `MEND`, `MALARM`, `MSUM` or `MMAP` (a trailing `\r` is tolerated); every other
//! line is ignored. A malformed frame is an error naming the file, the line and the field.
//!
//! Rules beyond each frame's fields: an `MMAP` row follows an `MSUM` of the same period, axis
//! and direction (each of `ref`, `cur`, `band` once) and has exactly `bins` values; `MEND`
//! closes the open `MBEGIN` of the same tag; frames outside `MBEGIN` .. `MEND` form a section
//! tagged [`IMPLICIT_TAG`]; an `MBEGIN` while a section is open ends that one without a hash.
//! Floats are parsed as `f32`, so the firmware's shortest round-trip form gives its exact bits.

use super::{
    report, Alarm, AlarmKind, Axis, Coverage, Dir, Error, Map, Report, Section, IMPLICIT_TAG,
};
use std::io::Read;
use std::path::Path;

/// Largest log read [bytes] (1 GiB; a day of frames at a few per second is far smaller).
pub const MAX_BYTES: u64 = 1 << 30;

/// Largest number of bins in a map (the firmware has 64; a 512-byte line holds at most 256).
pub const MAX_BINS: usize = 4096;

/// Reads and decodes the log at `path`; times use the control period `period_s` [s].
pub fn read(path: &Path, period_s: f64) -> Result<Report, Error> {
    let read_err = |source| Error::Read {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(read_err)?;
    let mut bytes = Vec::new();
    file.take(MAX_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(read_err)?;
    if bytes.len() as u64 > MAX_BYTES {
        return Err(Error::TooLarge {
            path: path.to_path_buf(),
        });
    }
    parse(&bytes, path, period_s)
}

/// Decodes the log `bytes`; `path` names it in errors and in the report, times use the
/// control period `period_s` [s].
pub fn parse(bytes: &[u8], path: &Path, period_s: f64) -> Result<Report, Error> {
    let mut p = Parser {
        period_s,
        sections: Vec::new(),
        open: None,
        last_sum: None,
    };
    let mut frames = 0usize;
    // a final newline ends the last line rather than starting an empty one
    let body = bytes.strip_suffix(b"\n").unwrap_or(bytes);
    for (i, raw) in body.split(|&b| b == b'\n').enumerate() {
        let line = i + 1;
        // A UART capture carries noise and other programs' bytes: only frame lines must be
        // text; anything else is skipped, whatever its bytes.
        let framed = [
            b"MALARM ".as_slice(),
            b"MSUM ",
            b"MMAP ",
            b"MBEGIN ",
            b"MEND ",
        ]
        .iter()
        .any(|p| raw.starts_with(p));
        if !framed {
            continue;
        }
        let text = std::str::from_utf8(raw).map_err(|e| Error::NotUtf8 {
            path: path.to_path_buf(),
            line,
            column: e.valid_up_to() + 1,
        })?;
        let text = text.strip_suffix('\r').unwrap_or(text);
        let mut words = text.split_ascii_whitespace();
        let Some(frame) = words.next().and_then(frame_name) else {
            continue;
        };
        frames += 1;
        p.frame(frame, words).map_err(|message| Error::Frame {
            path: path.to_path_buf(),
            line,
            frame,
            message,
        })?;
    }
    if frames == 0 {
        return Err(Error::NoFrames {
            path: path.to_path_buf(),
        });
    }
    for s in &mut p.sections {
        for m in &mut s.maps {
            m.out_of_band = report::out_of_band(m);
        }
    }
    Ok(Report {
        log: super::shown(path),
        period_s,
        sections: p.sections,
    })
}

/// The frame name of a line's first word, if it is one.
fn frame_name(word: &str) -> Option<&'static str> {
    ["MBEGIN", "MEND", "MALARM", "MSUM", "MMAP"]
        .into_iter()
        .find(|&f| f == word)
}

/// Where the open section came from.
#[derive(Clone, Copy, PartialEq)]
enum Open {
    /// An `MBEGIN` frame.
    Begun,
    /// Frames without `MBEGIN`.
    Implicit,
}

struct Parser {
    period_s: f64,
    sections: Vec<Section>,
    open: Option<Open>,
    /// Index of the last `MSUM`'s map in the open section.
    last_sum: Option<usize>,
}

impl Parser {
    /// One frame; the error is the message after `file:line: FRAME: `.
    fn frame<'a>(
        &mut self,
        frame: &'static str,
        mut words: impl Iterator<Item = &'a str>,
    ) -> Result<(), String> {
        match frame {
            "MBEGIN" => {
                let tag = words.next().filter(|t| !t.contains('='));
                let tag = tag.ok_or("missing the tag after MBEGIN")?.to_string();
                let mut f = Fields::new(words)?;
                let seed = f.parse::<u32>("seed", "an unsigned 32-bit integer")?;
                let duration = f.parse::<f64>("duration", "a number of seconds")?;
                if !(duration.is_finite() && duration >= 0.0) {
                    return Err(format!("field duration: {duration} s is not a duration"));
                }
                f.finish()?;
                self.sections.push(Section {
                    tag,
                    seed: Some(seed),
                    duration: Some(duration),
                    hash: None,
                    alarms: Vec::new(),
                    maps: Vec::new(),
                });
                self.open = Some(Open::Begun);
                self.last_sum = None;
            }
            "MEND" => self.end(words)?,
            "MALARM" => {
                let alarm = self.alarm(Fields::new(words)?)?;
                self.section().alarms.push(alarm);
            }
            "MSUM" => {
                let map = self.summary(Fields::new(words)?)?;
                let s = self.section();
                s.maps.push(map);
                self.last_sum = Some(s.maps.len() - 1);
            }
            _ => self.row(Fields::new(words)?)?,
        }
        Ok(())
    }

    /// The open section, opening an implicit one if none is.
    fn section(&mut self) -> &mut Section {
        if self.open.is_none() {
            self.sections.push(Section {
                tag: IMPLICIT_TAG.to_string(),
                seed: None,
                duration: None,
                hash: None,
                alarms: Vec::new(),
                maps: Vec::new(),
            });
            self.open = Some(Open::Implicit);
            self.last_sum = None;
        }
        let n = self.sections.len();
        &mut self.sections[n - 1]
    }

    fn end<'a>(&mut self, mut words: impl Iterator<Item = &'a str>) -> Result<(), String> {
        let tag = words.next().filter(|t| !t.contains('='));
        let tag = tag.ok_or("missing the tag after MEND")?;
        let mut f = Fields::new(words)?;
        let hash = f.get("hash")?;
        if hash.len() != 16 || !hash.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(format!("field hash: `{hash}` is not 16 hex digits"));
        }
        let hash = hash.to_string();
        f.finish()?;
        let open = self
            .sections
            .last_mut()
            .filter(|_| self.open == Some(Open::Begun));
        let Some(s) = open else {
            return Err(format!("MEND {tag} without an open MBEGIN"));
        };
        if s.tag != tag {
            return Err(format!(
                "MEND {tag} but the open section is MBEGIN {}",
                s.tag
            ));
        }
        s.hash = Some(hash);
        self.open = None;
        self.last_sum = None;
        Ok(())
    }

    fn alarm(&self, mut f: Fields<'_>) -> Result<Alarm, String> {
        let period = f.period()?;
        let kind = f.get("kind")?;
        let axis = f.axis()?;
        let dir = f.dir(true)?;
        let kind = match kind {
            "friction_drift" => AlarmKind::FrictionDrift {
                change: f.f32("change")?,
            },
            "local_friction" => AlarmKind::LocalFriction {
                position: f.f32("position")?,
                width: f.f32("width")?,
                change: f.f32("change")?,
            },
            "stiction_rise" => AlarmKind::StictionRise {
                ratio: f.f32("ratio")?,
                learned: f.f32("learned")?,
            },
            "model_mismatch" => AlarmKind::ModelMismatch {
                mean_square: f.f32("mean_square")?,
                learned: f.f32("learned")?,
            },
            other => {
                return Err(format!(
                    "field kind: unknown kind `{other}` (expected one of {})",
                    AlarmKind::NAMES.join(", ")
                ))
            }
        };
        f.finish()?;
        Ok(Alarm {
            period,
            time_s: period as f64 * self.period_s,
            axis,
            dir,
            kind,
        })
    }

    fn summary(&self, mut f: Fields<'_>) -> Result<Map, String> {
        let period = f.period()?;
        let axis = f.axis()?;
        let dir = f.dir(false)?;
        let (lo, hi) = (f.f32("lo")?, f.f32("hi")?);
        if hi <= lo {
            return Err(format!("fields lo={lo} hi={hi}: the travel needs hi > lo"));
        }
        let bins = f.parse::<usize>("bins", "a number of bins")?;
        if !(1..=MAX_BINS).contains(&bins) {
            return Err(format!("field bins: {bins} is not in 1..={MAX_BINS}"));
        }
        let map = Map {
            axis,
            dir,
            period,
            time_s: period as f64 * self.period_s,
            lo,
            hi,
            bins,
            level: f.f32("level")?,
            level_sd: f.f32("level_sd")?,
            slope: f.f32("slope")?,
            v0: f.f32("v0")?,
            ready: f.flag("ready")?,
            coverage: coverage(&mut f)?,
            ref_mn: None,
            cur_mn: None,
            band_mn: None,
            out_of_band: Vec::new(),
        };
        f.finish()?;
        Ok(map)
    }

    /// An `MMAP` row, into the last summary's map.
    fn row(&mut self, mut f: Fields<'_>) -> Result<(), String> {
        let period = f.period()?;
        let axis = f.axis()?;
        let dir = f.dir(false)?;
        let what = f.get("what")?;
        let values = f.get("mN")?;
        f.finish()?;
        let head = format!("period={period} axis={} dir={}", axis.name(), dir.name());
        let map = match (self.open, self.last_sum) {
            (Some(_), Some(i)) => self.sections.last_mut().and_then(|s| s.maps.get_mut(i)),
            _ => None,
        };
        let Some(map) = map else {
            return Err(format!("row {head} does not follow an MSUM frame"));
        };
        if (map.period, map.axis, map.dir) != (period, axis, dir) {
            return Err(format!(
                "row {head} follows MSUM period={} axis={} dir={} (the same period, axis and \
                 direction are needed)",
                map.period,
                map.axis.name(),
                map.dir.name()
            ));
        }
        let slot = match what {
            "ref" => &mut map.ref_mn,
            "cur" => &mut map.cur_mn,
            "band" => &mut map.band_mn,
            other => {
                return Err(format!(
                    "field what: unknown row `{other}` (expected ref, cur or band)"
                ))
            }
        };
        if slot.is_some() {
            return Err(format!("a second what={what} row for MSUM {head}"));
        }
        *slot = Some(row_values(values, map.bins)?);
        Ok(())
    }
}

/// The comma-separated values of an `mN` field: integers [mN] or `_`, exactly `bins`.
fn row_values(text: &str, bins: usize) -> Result<Vec<Option<i32>>, String> {
    let items: Vec<&str> = text.split(',').collect();
    if items.len() != bins {
        return Err(format!("field mN has {} values, bins={bins}", items.len()));
    }
    items
        .iter()
        .enumerate()
        .map(|(b, v)| match *v {
            "_" => Ok(None),
            v => v.parse::<i32>().map(Some).map_err(|_| {
                format!("field mN: value `{v}` of bin {b} is not an integer [mN] or `_`")
            }),
        })
        .collect()
}

/// The coverage fields of an `MSUM` (`restarts`, `moves`, `judged`): all or none.
fn coverage(f: &mut Fields<'_>) -> Result<Option<Coverage>, String> {
    let keys = ["restarts", "moves", "judged"];
    let n = keys.iter().filter(|k| f.has(k)).count();
    if n == 0 {
        return Ok(None);
    }
    if n < keys.len() {
        return Err("fields restarts, moves and judged come together".to_string());
    }
    let mut v = [0u32; 3];
    for (x, k) in v.iter_mut().zip(keys) {
        *x = f.parse(k, "a count (unsigned integer)")?;
    }
    Ok(Some(Coverage {
        restarts: v[0],
        moves: v[1],
        judged: v[2],
    }))
}

/// The `key=value` words of a frame; each key must appear once and be used.
struct Fields<'a> {
    pairs: Vec<(&'a str, &'a str, bool)>,
}

impl<'a> Fields<'a> {
    fn new(words: impl Iterator<Item = &'a str>) -> Result<Self, String> {
        let mut pairs: Vec<(&'a str, &'a str, bool)> = Vec::new();
        for w in words {
            let (k, v) = w
                .split_once('=')
                .ok_or_else(|| format!("`{w}` is not a key=value field"))?;
            if pairs.iter().any(|p| p.0 == k) {
                return Err(format!("field {k} appears twice"));
            }
            pairs.push((k, v, false));
        }
        Ok(Fields { pairs })
    }

    /// The value of `key` (an error when missing).
    fn get(&mut self, key: &str) -> Result<&'a str, String> {
        let p = self
            .pairs
            .iter_mut()
            .find(|p| p.0 == key)
            .ok_or_else(|| format!("missing field {key}"))?;
        p.2 = true;
        Ok(p.1)
    }

    /// The value of `key` parsed as `T` (`what` describes `T` in the error).
    fn parse<T: std::str::FromStr>(&mut self, key: &str, what: &str) -> Result<T, String> {
        let v = self.get(key)?;
        v.parse()
            .map_err(|_| format!("field {key}: `{v}` is not {what}"))
    }

    /// A finite `f32` (the frames' shortest round-trip form gives the firmware's bits).
    fn f32(&mut self, key: &str) -> Result<f32, String> {
        let x: f32 = self.parse(key, "a number")?;
        if !x.is_finite() {
            return Err(format!("field {key}: `{x}` is not a finite number"));
        }
        Ok(x)
    }

    fn period(&mut self) -> Result<u64, String> {
        self.parse("period", "a period index (unsigned integer)")
    }

    fn axis(&mut self) -> Result<Axis, String> {
        match self.get("axis")? {
            "X" => Ok(Axis::X),
            "Y" => Ok(Axis::Y),
            other => Err(format!(
                "field axis: unknown axis `{other}` (expected X or Y)"
            )),
        }
    }

    /// The direction; `both` allows `+-` (alarms).
    fn dir(&mut self, both: bool) -> Result<Dir, String> {
        match self.get("dir")? {
            "+" => Ok(Dir::Positive),
            "-" => Ok(Dir::Negative),
            "+-" if both => Ok(Dir::Both),
            other => Err(format!(
                "field dir: unknown direction `{other}` (expected {})",
                if both { "+, - or +-" } else { "+ or -" }
            )),
        }
    }

    /// Whether `key` is there (an older firmware's frame may lack it).
    fn has(&self, key: &str) -> bool {
        self.pairs.iter().any(|p| p.0 == key)
    }

    /// An optional `0`/`1` field.
    fn flag(&mut self, key: &str) -> Result<Option<bool>, String> {
        if !self.has(key) {
            return Ok(None);
        }
        match self.get(key)? {
            "0" => Ok(Some(false)),
            "1" => Ok(Some(true)),
            other => Err(format!("field {key}: `{other}` is not 0 or 1")),
        }
    }

    /// Refuses fields that were not used.
    fn finish(self) -> Result<(), String> {
        match self.pairs.iter().find(|p| !p.2) {
            Some(p) => Err(format!("unexpected field {}", p.0)),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one(text: &str) -> Result<Report, Error> {
        parse(text.as_bytes(), Path::new("run.log"), 0.002)
    }

    #[test]
    fn a_summary_carries_readiness_and_coverage_or_neither() {
        let head = "MSUM period=5 axis=X dir=- lo=0 hi=1 bins=4 level=0 level_sd=0 slope=0 v0=0";
        let r = one(&format!("{head} ready=1 restarts=32 moves=16 judged=3\n")).unwrap();
        let m = &r.sections[0].maps[0];
        assert_eq!(m.ready, Some(true));
        let c = Coverage {
            restarts: 32,
            moves: 16,
            judged: 3,
        };
        assert_eq!(m.coverage, Some(c));
        // an older firmware's summary has neither
        let r = one(&format!("{head}\n")).unwrap();
        assert_eq!(
            (r.sections[0].maps[0].ready, r.sections[0].maps[0].coverage),
            (None, None)
        );
        let message = |t: String| one(&t).unwrap_err().to_string();
        assert!(message(format!("{head} ready=2\n")).contains("field ready: `2` is not 0 or 1"));
        assert!(message(format!("{head} restarts=1 moves=2\n")).contains("come together"));
        assert!(message(format!("{head} restarts=1 moves=2 judged=-1\n"))
            .contains("field judged: `-1` is not a count"));
    }

    #[test]
    fn an_alarm_round_trips_its_f32_bits() {
        let r = one(
            "boot\r\nMALARM period=21372 kind=local_friction axis=X dir=+- position=0.3116797 \
             width=0.007890625 change=0.45761326\r\n",
        )
        .unwrap();
        assert_eq!(r.sections.len(), 1);
        assert_eq!(r.sections[0].tag, IMPLICIT_TAG);
        let a = &r.sections[0].alarms[0];
        assert_eq!((a.period, a.axis, a.dir), (21372, Axis::X, Dir::Both));
        assert!((a.time_s - 42.744).abs() < 1e-9);
        let AlarmKind::LocalFriction {
            position,
            width,
            change,
        } = a.kind
        else {
            panic!("{:?}", a.kind);
        };
        assert_eq!(change.to_bits(), 0.457_613_26_f32.to_bits());
        assert_eq!(position.to_bits(), 0.311_679_7_f32.to_bits());
        assert_eq!(width.to_bits(), 0.007_890_625_f32.to_bits());
        // and back to the same text
        assert_eq!(
            format!("{change} {position} {width}"),
            "0.45761326 0.3116797 0.007890625"
        );
    }

    #[test]
    fn every_kind_parses() {
        let r = one(
            "MALARM period=1 kind=friction_drift axis=Y dir=- change=-0.25\n\
             MALARM period=2 kind=stiction_rise axis=X dir=+ ratio=1.5 learned=1.2\n\
             MALARM period=3 kind=model_mismatch axis=Y dir=+- mean_square=1e-8 learned=2e-9\n",
        )
        .unwrap();
        let names: Vec<_> = r.sections[0].alarms.iter().map(|a| a.kind.name()).collect();
        assert_eq!(names, ["friction_drift", "stiction_rise", "model_mismatch"]);
    }

    fn message(text: &str) -> String {
        one(text).unwrap_err().to_string()
    }

    #[test]
    fn errors_name_the_line_and_the_field() {
        let sum = "MSUM period=5 axis=X dir=- lo=0 hi=1 bins=4 level=0 level_sd=0 slope=0 v0=0\n";
        assert_eq!(
            message(&format!(
                "x\n{sum}MMAP period=5 axis=X dir=- what=ref mN=1,2,_\n"
            )),
            "run.log:3: MMAP: field mN has 3 values, bins=4"
        );
        assert!(message(&format!(
            "{sum}MMAP period=6 axis=X dir=- what=ref mN=1,2,3,4\n"
        ))
        .starts_with("run.log:2: MMAP: row period=6 axis=X dir=- follows MSUM period=5"));
        assert!(message("MMAP period=6 axis=X dir=- what=ref mN=1\n")
            .contains("does not follow an MSUM"));
        assert!(
            message("MALARM period=1 kind=wobble axis=X dir=+ change=1\n")
                .starts_with("run.log:1: MALARM: field kind: unknown kind `wobble`")
        );
        assert!(
            message("MALARM period=1 kind=friction_drift axis=Z dir=+ change=1\n")
                .contains("unknown axis `Z`")
        );
        assert!(
            message("MALARM period=1 kind=friction_drift axis=X dir=++ change=1\n")
                .contains("unknown direction `++`")
        );
        assert!(
            message("MALARM period=1 kind=friction_drift axis=X dir=+ change=abc\n")
                .contains("field change: `abc` is not a number")
        );
        assert!(
            message("MALARM period=1 kind=friction_drift axis=X dir=+ change=NaN\n")
                .contains("not a finite number")
        );
        assert!(
            message("MALARM period=1 kind=friction_drift axis=X dir=+\n")
                .contains("missing field change")
        );
        assert!(message(&sum.replace("dir=-", "dir=+-")).contains("expected + or -"));
        assert!(message(&sum.replace("bins=4", "bins=0")).contains("field bins"));
        assert!(message("MEND f64 hash=0123456789abcdef\n").contains("without an open MBEGIN"));
        assert!(
            message("MBEGIN a seed=1 duration=1\nMEND b hash=0123456789abcdef\n")
                .contains("MEND b but the open section is MBEGIN a")
        );
        assert_eq!(message("hello\n\n"), "no monitor frames in run.log");
        let e = parse(
            b"boot\n\xff\xfe noise\nMEND a\xffc\n",
            Path::new("run.log"),
            0.002,
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "run.log:3: not UTF-8 text (invalid byte at column 7)"
        );
    }

    #[test]
    fn a_map_gets_its_rows_and_out_of_band_bins() {
        let r = one("MBEGIN t seed=3 duration=2.5\n\
             MSUM period=5 axis=Y dir=+ lo=0 hi=1 bins=4 level=0 level_sd=0 slope=0 v0=0\n\
             MMAP period=5 axis=Y dir=+ what=ref mN=_,10,20,30\n\
             MMAP period=5 axis=Y dir=+ what=cur mN=_,10,20,80\n\
             MMAP period=5 axis=Y dir=+ what=band mN=_,1,1,10\n\
             MEND t hash=0123456789abcdef\n")
        .unwrap();
        let s = &r.sections[0];
        assert_eq!((s.seed, s.duration), (Some(3), Some(2.5)));
        let m = &s.maps[0];
        assert_eq!(m.bins_with_data(), 3);
        assert_eq!(m.out_of_band.len(), 1);
        assert_eq!(m.out_of_band[0].bin, 3);
        assert!((m.out_of_band[0].position - 0.875).abs() < 1e-12);
    }
}
