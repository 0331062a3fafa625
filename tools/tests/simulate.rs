//! `crane simulate`: the default scenario writes a run that loads back in the data format and
//! moves every drive, and a valid SVG plot beside it; a bad scenario gets an error naming the
//! field.

use std::path::PathBuf;
use std::process::Command;

fn tmp(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("simulate-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

#[test]
fn default_scenario_writes_a_loadable_run_with_motion() {
    let dir = tmp("ok");
    let csv = dir.join("sim.csv");
    let out = Command::new(env!("CARGO_BIN_EXE_crane"))
        .args(["simulate", "--out"])
        .arg(&csv)
        .output()
        .expect("run crane");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let spec = crane_ident::data::DatasetSpec::minimal(0.064);
    let rs = crane_ident::data::RunSpec {
        file: "sim.csv".into(),
        ..Default::default()
    };
    let run = crane_ident::data::load_run(&dir, &spec, &rs).expect("loads as a crane run");
    let c = run.crane().expect("crane run");
    assert_eq!(c.len(), 10_001);
    for (name, v) in [("x", &c.x), ("y", &c.y), ("l", &c.l)] {
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        assert!(hi - lo > 1e-3, "{name} did not move: range {}", hi - lo);
    }
    // the plot beside the CSV: a well-formed SVG with three lines in each of the three
    // panels (positions, velocities, voltages) and mode bands of all three modes
    let svg = dir.join("sim.svg");
    let text = std::fs::read_to_string(&svg).expect("sim.svg beside sim.csv");
    let doc = roxmltree::Document::parse(&text).expect("well-formed SVG (XML)");
    assert_eq!(doc.root_element().tag_name().name(), "svg");
    let count = |tag: &str| {
        doc.descendants()
            .filter(|n| n.tag_name().name() == tag)
            .count()
    };
    assert!(count("polyline") >= 9, "{} lines", count("polyline"));
    let texts: String = doc
        .descendants()
        .filter(|n| n.is_text())
        .filter_map(|n| n.text())
        .collect::<Vec<_>>()
        .join("|");
    for title in ["drive positions", "drive velocities", "voltages", "modes"] {
        assert!(texts.contains(title), "no panel `{title}`");
    }
    // the default multisine drives X both ways and stops it: red, yellow and green bands
    let fills: Vec<&str> = doc
        .descendants()
        .filter(|n| n.tag_name().name() == "rect")
        .filter_map(|n| n.attribute("fill"))
        .collect();
    for colour in ["#F09696", "#FAE178", "#96D796"] {
        assert!(
            fills.iter().any(|f| f.eq_ignore_ascii_case(colour)),
            "no mode band of colour {colour}: {:?}",
            &fills[..fills.len().min(8)]
        );
    }
}

#[test]
fn bad_scenario_names_the_field() {
    let dir = tmp("bad");
    let sc = dir.join("bad.toml");
    std::fs::write(
        &sc,
        "duration_s = 1.0\n[[input]]\naxis = \"z\"\namplitude_v = 1.0\n",
    )
    .expect("write");
    let out = Command::new(env!("CARGO_BIN_EXE_crane"))
        .arg("simulate")
        .arg(&sc)
        .args(["--out"])
        .arg(dir.join("x.csv"))
        .output()
        .expect("run crane");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("input[0].axis"), "{err}");
}
