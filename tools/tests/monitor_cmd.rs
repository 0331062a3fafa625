//! `crane monitor LOG`: the friction monitor's frames of a log (the sample is the real output
//! of `cargo run -p crane-twin --example monitor_check`, which prints what the firmware
//! prints) decoded into a table, a JSON report and a plot; bad logs and outputs get an error
//! naming the file, the line and the field, never a panic.

use crane_tools::monitor::{AlarmKind, Axis, Dir, Report};
use std::path::{Path, PathBuf};

mod support;
use support::{crane, stderr, stdout, tmp};

fn sample() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/monitor_sample.log")
}

fn sample_text() -> String {
    std::fs::read_to_string(sample()).expect("sample log")
}

/// Runs `crane monitor` in `dir` and expects a clean failure (exit 1, no panic) whose message
/// contains every one of `needles`.
fn fails(dir: &Path, args: &[&str], needles: &[&str]) {
    let mut all = vec!["monitor"];
    all.extend_from_slice(args);
    let o = crane(dir, &all);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
    assert!(!e.contains("panicked"), "{args:?}: {e}");
    for n in needles {
        assert!(e.contains(n), "{args:?}: `{n}` not in: {e}");
    }
}

#[test]
fn the_sample_log_decodes_into_table_json_and_plot() {
    let d = tmp("sample");
    let log = sample();
    let o = crane(&d, &["monitor", log.to_str().unwrap(), "--out", "out"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = stdout(&o);
    assert!(
        table.contains("section f64") && table.contains("section f32x"),
        "{table}"
    );
    assert_eq!(table.matches("local_friction").count(), 2, "{table}");
    assert!(table.contains("position 0.31484163 m"), "{table}");
    assert!(table.contains("restarts/moves/judged"), "{table}");

    let json = std::fs::read_to_string(d.join("out/monitor.json")).expect("monitor.json");
    let r: Report = serde_json::from_str(&json).expect("the report parses back");
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["sections"][0]["alarms"][0]["kind"], "local_friction");
    assert_eq!(v["sections"][1]["maps"][0]["dir"], "-");
    let tags: Vec<_> = r.sections.iter().map(|s| s.tag.as_str()).collect();
    assert_eq!(tags, ["f64", "f32x"]);
    for s in &r.sections {
        assert_eq!((s.seed, s.duration), (Some(1), Some(45.0)), "{}", s.tag);
        assert_eq!(s.hash.as_deref().map(str::len), Some(16), "{}", s.tag);
        assert_eq!(s.alarms.len(), 1, "{}", s.tag);
        let a = &s.alarms[0];
        assert_eq!((a.period, a.axis, a.dir), (21432, Axis::X, Dir::Both));
        let AlarmKind::LocalFriction { position, .. } = a.kind else {
            panic!("{}: {:?}", s.tag, a.kind);
        };
        assert!((position - 0.31).abs() < 0.02, "{}: {position}", s.tag);
        // the frame's f32, bit for bit, through the JSON report
        let frame = if s.tag == "f64" {
            0.314_841_63
        } else {
            0.314_851_46
        };
        assert_eq!(position.to_bits(), f32::to_bits(frame), "{}", s.tag);
        // every summary holds 4 maps (X and Y, each direction), each with its 3 full rows
        let mut periods: Vec<u64> = s.maps.iter().map(|m| m.period).collect();
        periods.dedup();
        assert_eq!(periods, [7501, 15001, 22500], "{}", s.tag);
        for p in periods {
            let maps: Vec<_> = s.maps.iter().filter(|m| m.period == p).collect();
            assert_eq!(maps.len(), 4, "{} period {p}", s.tag);
            for m in maps {
                for row in [&m.ref_mn, &m.cur_mn, &m.band_mn] {
                    assert_eq!(row.as_ref().map(Vec::len), Some(m.bins));
                }
            }
        }
        assert_eq!(s.last_maps().len(), 4, "{}", s.tag);
        // readiness: commissioning (at least 20 s, then on coverage) is not over at 15 s nor
        // at 30 s (X moving + has no move over 9 judged bins yet), over at 45 s; the coverage
        // counts only grow
        for m in &s.maps {
            assert_eq!(
                m.ready,
                Some(m.period >= 22500),
                "{} period {}",
                s.tag,
                m.period
            );
            let c = m.coverage.expect("coverage fields");
            assert!(c.judged as usize <= m.bins, "{} {c:?}", s.tag);
            if m.ready == Some(true) {
                assert!(c.restarts >= 4 && c.moves >= 1, "{} {c:?}", s.tag);
            }
        }
        let ready = s.maps.iter().filter(|m| m.ready == Some(true)).count();
        assert_eq!(ready, 4, "{}", s.tag);
        // the local change shows in the last X maps, at the alarm's place
        for m in s.last_maps().iter().filter(|m| m.axis == Axis::X) {
            assert!(
                m.out_of_band
                    .iter()
                    .any(|o| (o.position - f64::from(position)).abs() < 0.02),
                "{} {:?}",
                s.tag,
                m.dir
            );
        }
    }
    let svg = std::fs::read_to_string(d.join("out/monitor.svg")).expect("monitor.svg");
    assert!(svg.starts_with("<svg"), "{}", &svg[..svg.len().min(80)]);
    assert!(svg.contains("position [m]") && svg.contains("axis X, moving +"));
    assert!(svg.contains("local_friction alarm"));
}

#[test]
fn json_and_plot_files_and_json_on_stdout() {
    let d = tmp("files");
    std::fs::copy(sample(), d.join("run.log")).unwrap();
    let o = crane(
        &d,
        &[
            "monitor", "run.log", "--json", "r.json", "--plot", "p/m.svg",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(serde_json::from_slice::<Report>(&std::fs::read(d.join("r.json")).unwrap()).is_ok());
    assert!(std::fs::read_to_string(d.join("p/m.svg"))
        .unwrap()
        .starts_with("<svg"));
    // bare --json: exactly one document on stdout
    let o = crane(&d, &["monitor", "run.log", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: Report = serde_json::from_slice(&o.stdout).expect("one JSON document");
    assert_eq!(r.sections.len(), 2);
    // another control period scales the times
    let o = crane(&d, &["monitor", "run.log", "--json", "--period-s", "0.001"]);
    let r: Report = serde_json::from_slice(&o.stdout).expect("one JSON document");
    assert!((r.sections[0].alarms[0].time_s - 21.432).abs() < 1e-9);
    let o = crane(&d, &["monitor", "run.log", "--period-s", "2"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("plausible range"), "{}", stderr(&o));
}

#[test]
fn a_capture_without_mbegin_is_one_section() {
    let d = tmp("capture");
    let text: String = sample_text()
        .lines()
        .filter(|l| !l.starts_with("MBEGIN") && !l.starts_with("MEND"))
        .take(30)
        .map(|l| format!("[INFO] boot ok\r\n{l}\r\n"))
        .collect();
    std::fs::write(d.join("board.log"), text).unwrap();
    let o = crane(&d, &["monitor", "board.log", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: Report = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r.sections.len(), 1);
    assert_eq!(r.sections[0].tag, "log");
    assert_eq!(r.sections[0].seed, None);
    assert_eq!(r.sections[0].maps.len(), 8);
}

#[test]
fn bad_logs_name_the_file_line_and_field() {
    let d = tmp("bad");
    let text = sample_text();
    // a truncated MMAP row (line 3): one value short
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    assert!(lines[2].starts_with("MMAP"));
    let cut = lines[2].rfind(',').unwrap();
    lines[2].truncate(cut);
    std::fs::write(d.join("run.log"), lines.join("\n") + "\n").unwrap();
    fails(
        &d,
        &["run.log"],
        &["run.log:3: MMAP: field mN has 63 values, bins=64"],
    );
    // an unknown kind
    let line = text.lines().position(|l| l.starts_with("MALARM")).unwrap() + 1;
    std::fs::write(
        d.join("kind.log"),
        text.replacen("kind=local_friction", "kind=wobble", 1),
    )
    .unwrap();
    fails(
        &d,
        &["kind.log"],
        &[&format!(
            "kind.log:{line}: MALARM: field kind: unknown kind `wobble`"
        )],
    );
    // an MMAP row without its MSUM
    let no_sum: String = text
        .lines()
        .filter(|l| !l.starts_with("MSUM"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(d.join("nosum.log"), no_sum).unwrap();
    fails(&d, &["nosum.log"], &["nosum.log:2: MMAP: ", "MSUM"]);
    // a missing file, a directory, an empty file, a log without frames, bytes not UTF-8
    fails(&d, &["nope.log"], &["read nope.log", "No such file"]);
    std::fs::create_dir_all(d.join("adir")).unwrap();
    fails(&d, &["adir"], &["read adir"]);
    std::fs::write(d.join("empty.log"), "").unwrap();
    fails(&d, &["empty.log"], &["no monitor frames in empty.log"]);
    std::fs::write(d.join("chat.log"), "booting\nMSUMMARY of nothing\n").unwrap();
    fails(&d, &["chat.log"], &["no monitor frames in chat.log"]);
    // noise between frames is skipped; a frame line that is not text is an error
    std::fs::write(
        d.join("bin.log"),
        b"\xff\xfe noise\nMBEGIN a seed=1 duration=1\nMSUM \xff\xfe\n",
    )
    .unwrap();
    fails(&d, &["bin.log"], &["bin.log:3: not UTF-8"]);
}

#[test]
fn outputs_never_replace_the_log() {
    let d = tmp("outputs");
    std::fs::copy(sample(), d.join("run.log")).unwrap();
    let before = std::fs::read(d.join("run.log")).unwrap();
    fails(
        &d,
        &["run.log", "--json", "run.log"],
        &["run.log", "is an input"],
    );
    fails(
        &d,
        &["run.log", "--plot", "./run.log"],
        &["run.log", "is an input"],
    );
    fails(
        &d,
        &["run.log", "--json", "same", "--plot", "same"],
        &["same", "same file"],
    );
    std::fs::write(d.join("afile"), "x").unwrap();
    fails(
        &d,
        &["run.log", "--out", "afile"],
        &["afile", "not a directory"],
    );
    assert_eq!(std::fs::read(d.join("run.log")).unwrap(), before);
    assert!(!d.join("same").exists());
}
