//! The loader's rules for real logs, one test per rule: units, gains, declared controllers,
//! irregular time stamps, held channels, gaps, BOM, header hints, ranges and clipped errors.

use crane_ident::data::asynchronous::fill_blanks;
use crane_ident::data::{
    load_dataset, parse_table, DataError, Dataset, Gain, InputUnit, LoadNote, PositionUnit,
    Problem, RunKind, Timing,
};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

static N: AtomicUsize = AtomicUsize::new(0);

fn temp_dir(tag: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "ident-rules-{}-{}",
        tag,
        N.fetch_add(1, Ordering::SeqCst)
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn set(toml: &str, csv: &str) -> PathBuf {
    let d = temp_dir("set");
    std::fs::write(d.join("dataset.toml"), toml).unwrap();
    std::fs::write(d.join("run.csv"), csv).unwrap();
    d
}

fn ok(toml: &str, csv: &str) -> Dataset {
    load_dataset(&set(toml, csv)).unwrap_or_else(|e| panic!("{e}"))
}

fn fails(toml: &str, csv: &str) -> (PathBuf, DataError) {
    let d = set(toml, csv);
    let e = load_dataset(&d).expect_err("must be refused");
    (d, e)
}

/// `n` rows of `t,x,u` at period `dt`, x a slow sine, u a ramp.
fn axis_csv(n: usize, dt: f64) -> String {
    let mut s = String::from("t,x,u\n");
    for k in 0..n {
        let t = k as f64 * dt;
        let _ = writeln!(s, "{t},{},{}", 0.1 * (t * 2.0).sin(), 0.5 * t);
    }
    s
}

#[test]
fn single_axis_needs_no_payload_and_works_in_input_units_without_a_gain() {
    let ds = ok("", &axis_csv(50, 0.01));
    let a = ds.runs[0].axis().unwrap();
    assert_eq!(a.gain, Gain::Unknown);
    assert_eq!(a.input_unit, InputUnit::Volt);
    assert_eq!(a.position_unit, PositionUnit::Metre);
    assert_eq!(a.force, a.u);
    assert_eq!(a.effort_unit(), "V");
    assert!(a.notes.is_empty());
    assert_eq!(ds.runs[0].payload_kg, 0.0);
}

#[test]
fn gain_key_and_its_alias_scale_the_input() {
    for key in ["gain", "gain_n_per_v"] {
        let ds = ok(&format!("{key} = 2.5\n"), &axis_csv(10, 0.01));
        let a = ds.runs[0].axis().unwrap();
        assert_eq!(a.gain, Gain::Known(2.5));
        assert_eq!(a.effort_unit(), "N");
        for (f, u) in a.force.iter().zip(&a.u) {
            assert_eq!(*f, 2.5 * u);
        }
    }
    // both at once is a duplicate
    let (d, e) = fails("gain = 2\ngain_n_per_v = 2\n", &axis_csv(10, 0.01));
    assert_eq!(e.location.file, d.join("dataset.toml"));
    // per-run gain overrides the data set's
    let ds = ok(
        "gain = 2\n[[runs]]\nfile = \"run.csv\"\ngain = 3\n",
        &axis_csv(10, 0.01),
    );
    assert_eq!(ds.runs[0].axis().unwrap().gain, Gain::Known(3.0));
}

#[test]
fn rotary_torque_input_has_gain_one_and_nm_is_accepted() {
    for unit in ["N m", "Nm"] {
        let ds = ok(
            &format!("position_unit = \"rad\"\ninput_unit = \"{unit}\"\n"),
            &axis_csv(10, 0.01),
        );
        let a = ds.runs[0].axis().unwrap();
        assert_eq!(a.input_unit, InputUnit::NewtonMetre);
        assert_eq!(a.position_unit, PositionUnit::Radian);
        assert_eq!(a.gain, Gain::Known(1.0));
        assert_eq!(a.effort_unit(), "N m");
    }
    // a force on a rotary axis, or a gain on an effort, is a contradiction
    let (_, e) = fails(
        "position_unit = \"rad\"\ninput_unit = \"N\"\n",
        &axis_csv(10, 0.01),
    );
    assert!(e.to_string().contains("rotary"), "{e}");
    assert_eq!(e.location.line, Some(2), "{e}");
    let (_, e) = fails("input_unit = \"N\"\ngain = 3\n", &axis_csv(10, 0.01));
    assert!(e.to_string().contains("gain"), "{e}");
    // other units keep their name and range
    let ds = ok("input_unit = \"%\"\n", &axis_csv(10, 0.01));
    assert_eq!(ds.runs[0].axis().unwrap().input_unit, InputUnit::Percent);
    let (_, e) = fails("input_unit = \"%\"\n", "t,x,u\n0,0,50\n0.01,0,150\n");
    assert!(matches!(e.problem, Problem::OutOfRange { .. }), "{e}");
    assert_eq!(e.location.line, Some(3));
}

#[test]
fn unknown_units_are_refused_with_the_known_ones() {
    let (d, e) = fails("input_unit = \"furlongs\"\n", &axis_csv(10, 0.01));
    assert_eq!(e.location.file, d.join("dataset.toml"));
    assert_eq!(e.location.line, Some(1));
    let msg = e.to_string();
    for u in ["`V`", "`N m`", "`A`", "`PWM`", "`%`"] {
        assert!(msg.contains(u), "{msg}");
    }
    let (_, e) = fails("position_unit = \"deg\"\n", &axis_csv(10, 0.01));
    assert!(e.to_string().contains("`rad`"), "{e}");
}

#[test]
fn crane_runs_still_need_a_payload() {
    let crane =
        "t,u_x,u_y,u_l,x,y,l,alpha,beta\n0,0,0,0,0.1,0.1,0.3,1.5,0\n0.01,0,0,0,0.1,0.1,0.3,1.5,0\n";
    let (d, e) = fails("", crane);
    assert_eq!(e.location.file, d.join("run.csv"));
    assert!(e.to_string().contains("payload_kg"), "{e}");
    assert_eq!(ok("payload_kg = 0.2\n", crane).runs[0].payload_kg, 0.2);
}

#[test]
fn irregular_stamps_are_resampled_by_zero_order_hold_and_said() {
    // 10 ms nominal with +-30 % jitter on every other row
    let mut s = String::from("t,x,u\n");
    let mut rows = Vec::new();
    for k in 0..200 {
        let t = k as f64 * 0.01 + if k % 2 == 1 { 0.003 } else { 0.0 };
        rows.push((t, k as f64 * 1e-3, k as f64));
        let _ = writeln!(s, "{t},{},{}", k as f64 * 1e-3, k as f64);
    }
    let ds = ok("", &s);
    let a = ds.runs[0].axis().unwrap();
    assert!(a.resampled());
    match &a.notes[0] {
        LoadNote::Resampled {
            rows_in,
            rows_out,
            step_s,
            why,
            exact,
        } => {
            assert_eq!(*rows_in, 200);
            // the grid step is the mean of the ordinary steps (7 and 13 ms here), not the
            // median (13 ms) and not the file's span over its rows
            assert!((step_s - 0.01).abs() < 1e-4, "{step_s}");
            assert_eq!(*rows_out, a.t.len());
            assert!(why.irregular_steps > 90, "{why:?}");
            assert!(*exact, "a position fresh on every row is interpolated");
        }
        other => panic!("{other:?}"),
    }
    // uniform grid, never the mean step of the file; the position read at each instant
    // between the rows around it, the input averaged over the period it is applied
    let h = a.t[1] - a.t[0];
    for (k, w) in a.t.windows(2).enumerate() {
        assert!((w[1] - w[0] - h).abs() < 1e-9, "{k}");
    }
    for (k, &g) in a.t.iter().enumerate() {
        let j = rows.iter().rposition(|r| r.0 <= g + 1e-12).unwrap();
        let x = match rows.get(j + 1) {
            Some(next) => {
                let r = rows[j];
                r.1 + (next.1 - r.1) * (g - r.0) / (next.0 - r.0)
            }
            None => rows[j].1,
        };
        assert!((a.x[k] - x).abs() < 1e-12, "{k}: {} {x}", a.x[k]);
        // the held input's mean over [g, g + h)
        let mut area = 0.0;
        for (i, r) in rows.iter().enumerate() {
            let end = rows.get(i + 1).map_or(f64::INFINITY, |n| n.0);
            let (lo, hi) = (r.0.max(g), end.min(g + h));
            if hi > lo {
                area += r.2 * (hi - lo);
            }
        }
        assert!(
            (a.u[k] - area / h).abs() < 1e-9,
            "{k}: {} {}",
            a.u[k],
            area / h
        );
        // read at the grid instant itself
        assert_eq!(a.source_t[k], g, "{k}");
    }
    assert!(a.notes[0].to_string().contains("interpolated linearly"));
}

#[test]
fn a_held_position_keeps_the_rows_zero_order_hold() {
    // the same jittered stamps, the position refreshed only every 3 rows: the rows' values
    // and stamps are kept (the held channel is rebuilt from its fresh rows later)
    let mut s = String::from("t,x,u\n");
    let mut rows = Vec::new();
    for k in 0..200 {
        let t = k as f64 * 0.01 + if k % 2 == 1 { 0.003 } else { 0.0 };
        // a swing, so that its changes are not single counts of a slow motion
        let x = (0.05 * (3 * (k / 3)) as f64).sin();
        rows.push((t, x, k as f64));
        let _ = writeln!(s, "{t},{x},{}", k as f64);
    }
    let ds = ok("", &s);
    let a = ds.runs[0].axis().unwrap();
    assert!(
        matches!(a.notes[0], LoadNote::Resampled { exact: false, .. }),
        "{:?}",
        a.notes
    );
    for (k, &g) in a.t.iter().enumerate() {
        let last = rows.iter().rev().find(|r| r.0 <= g + 1e-12).unwrap();
        assert_eq!(a.x[k], last.1, "{k}");
        assert_eq!(a.u[k], last.2, "{k}");
        // and when that row was taken: its own stamp, never the grid instant
        assert_eq!(a.source_t[k], last.0, "{k}");
    }
    assert!(a.source_t.iter().zip(&a.t).any(|(s, t)| s != t));
    assert!(a.notes[0].to_string().contains("zero-order hold"));
}

#[test]
fn gaps_and_backward_time_are_refused_at_their_line() {
    // rows lost: a gap of 50 steps
    let mut s = String::from("t,x,u\n");
    for k in (0..100).chain(150..200) {
        let _ = writeln!(s, "{},{},0", k as f64 * 0.01, k as f64 * 1e-3);
    }
    let (d, e) = fails("", &s);
    assert_eq!(e.location.file, d.join("run.csv"));
    assert_eq!(e.location.line, Some(102), "{e}");
    assert!(
        matches!(e.problem, Problem::Timing(Timing::Gap { .. })),
        "{e}"
    );
    assert!(e.to_string().contains("rows missing"), "{e}");
    let (_, e) = fails("", "t,x,u\n0,0,0\n0.01,0,0\n0.005,0,0\n");
    assert_eq!(e.location.line, Some(4));
    assert!(matches!(e.problem, Problem::TimeNotIncreasing { .. }));
}

#[test]
fn crane_run_with_rows_dropped_midway_is_refused() {
    // issue 11: half the rows dropped in the second half was accepted
    let mut s = String::from("t,u_x,u_y,u_l,x,y,l,alpha,beta\n");
    for k in (0..100).chain((100..200).step_by(2)) {
        let _ = writeln!(s, "{},0,0,0,0.1,0.1,0.3,1.5,0", k as f64 * 0.002);
    }
    let (d, e) = fails("payload_kg = 0.1\n", &s);
    assert_eq!(e.location.file, d.join("run.csv"));
    assert_eq!(e.location.column, Some(("t".to_string(), 1)));
    assert!(
        matches!(e.problem, Problem::Timing(Timing::IrregularCrane { .. })),
        "{e}"
    );
    assert!(e.to_string().contains("uniformly sampled"), "{e}");
    assert!(e.location.line.is_some_and(|l| l >= 102), "{e}");
}

#[test]
fn held_channels_are_noted() {
    // the position refreshed every 4 rows of a 100 Hz log
    let mut s = String::from("t,x,u\n");
    for k in 0..400 {
        let fresh = (k - k % 4) as f64;
        let _ = writeln!(
            s,
            "{},{},{}",
            k as f64 * 0.01,
            0.2 * (fresh * 0.03).sin(),
            k
        );
    }
    let ds = ok("", &s);
    let a = ds.runs[0].axis().unwrap();
    assert_eq!(a.refresh_rows(), 4);
    assert!(!a.resampled());
    // not resampled: every value was taken at its own row's instant
    assert_eq!(a.source_t, a.t);
    match &a.notes[..] {
        [LoadNote::HeldChannel {
            column,
            rows_per_refresh,
            repeated_share,
        }] => {
            assert_eq!(column, "x");
            assert_eq!(*rows_per_refresh, 4);
            assert!((repeated_share - 0.75).abs() < 0.01);
        }
        other => panic!("{other:?}"),
    }
    // the same signal refreshed every row is not
    let ds = ok("", &axis_csv(400, 0.01));
    assert_eq!(ds.runs[0].axis().unwrap().refresh_rows(), 1);
}

#[test]
fn bom_crlf_and_header_units() {
    let d = set(
        "\u{feff}gain = 2\r\n",
        "\u{feff}t,x,u\r\n0,0,1\r\n0.01,0,2\r\n",
    );
    let ds = load_dataset(&d).unwrap();
    assert_eq!(ds.runs[0].axis().unwrap().force, vec![2.0, 4.0]);
    let (_, e) = fails("", "t [s],x,u\n0,0,0\n0.01,0,0\n");
    let msg = e.to_string();
    assert!(msg.contains("`t [s]`") && msg.contains("unit"), "{msg}");
    assert!(msg.contains("the header has `t [s]`, `x`, `u`"), "{msg}");
}

#[test]
fn unknown_key_is_reported_on_its_own_line() {
    let (d, e) = fails("gain = 2\n\nbogus = 1\n", &axis_csv(10, 0.01));
    assert_eq!(e.location.file, d.join("dataset.toml"));
    assert_eq!(e.location.line, Some(3), "{e}");
    let (_, e) = fails(
        "[[runs]]\nfile = \"run.csv\"\nkind = \"validation\"\nbogus = 1\n",
        &axis_csv(10, 0.01),
    );
    assert_eq!(e.location.line, Some(4), "{e}");
}

#[test]
fn long_fields_are_clipped_in_messages() {
    let huge = "9".repeat(100) + "x" + &"y".repeat(10_000);
    let (_, e) = fails("", &format!("t,x,u\n0,0,0\n0.01,{huge},0\n"));
    let msg = e.to_string();
    assert!(msg.len() < 300, "{} chars", msg.len());
    assert!(msg.contains("10101 characters"), "{msg}");
    let long_name = "n".repeat(5000);
    let (_, e) = fails("", &format!("{long_name},x,u\n0,0,0\n0.01,0,0\n"));
    assert!(e.to_string().len() < 600, "{}", e.to_string().len());
    let (_, e) = fails(&format!("input_unit = \"{}\"\n", "V".repeat(5000)), "t\n");
    assert!(e.to_string().len() < 1000, "{}", e.to_string().len());
}

#[test]
fn long_user_text_in_dataset_toml_checks_is_clipped() {
    // a [columns] key that is no canonical name, and a run file listed twice: both echo the
    // user's text, clipped like every other message (10,000 characters in, a few hundred out)
    let long = "p".repeat(10_000);
    let (d, e) = fails(&format!("[columns]\n{long} = \"x\"\n"), &axis_csv(10, 0.01));
    let m = e.to_string();
    assert!(m.len() < 600, "{} chars: {}", m.len(), &m[..600]);
    assert!(
        m.contains("10000 characters") && m.contains("canonical"),
        "{m}"
    );
    assert_eq!(e.location.line, Some(2), "{m}");
    std::fs::remove_dir_all(d).unwrap();
    let (d, e) = fails(
        &format!(
            "[[runs]]\nfile = \"{long}\"\n[[runs]]\nfile = \"{long}\"\nkind = \"validation\"\n"
        ),
        &axis_csv(10, 0.01),
    );
    let m = e.to_string();
    assert!(m.len() < 400, "{} chars: {}", m.len(), &m[..400]);
    assert!(
        m.contains("10000 characters") && m.contains("listed twice"),
        "{m}"
    );
    assert_eq!(e.location.line, Some(4), "{m}");
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn gain_times_input_cannot_overflow() {
    // issue 11: `gain * u` overflowing to infinity was accepted; the gain's and the input's
    // ranges now bound the product (1e9 * 1e9 counts), and a gain beyond is refused
    let ds = ok(
        "gain = 1e9\ninput_unit = \"counts\"\n",
        "t,x,u\n0,0,0\n0.01,0,-1e9\n",
    );
    assert_eq!(ds.runs[0].axis().unwrap().force, vec![0.0, -1e18]);
    let (d, e) = fails(
        "input_unit = \"counts\"\ngain = 1e300\n",
        "t,x,u\n0,0,0\n0.01,0,1e300\n",
    );
    assert_eq!(e.location.file, d.join("dataset.toml"));
    assert_eq!(e.location.line, Some(2));
    let (d, e) = fails("input_unit = \"counts\"\n", "t,x,u\n0,0,0\n0.01,0,1e300\n");
    assert_eq!(e.location.file, d.join("run.csv"));
    assert!(matches!(e.problem, Problem::OutOfRange { .. }), "{e}");
}

#[test]
fn constants_have_plausible_ranges() {
    for (toml, key) in [
        ("[constants]\ngravity = 1e308\n", "constants.gravity"),
        (
            "[constants]\nencoder_pulses = 1e-300\n",
            "constants.encoder_pulses",
        ),
        (
            "[constants]\nx_range_m = [0, 1e-300]\n",
            "constants.x_range_m",
        ),
        (
            "[constants]\nx_range_m = [-1e308, 1e308]\n",
            "constants.x_range_m",
        ),
        ("[constants]\nl_range_m = [0, 0.5]\n", "constants.l_range_m"),
        (
            "[constants]\ntrolley_mass_kg = 1e9\n",
            "constants.trolley_mass_kg",
        ),
        (
            "[constants]\npulley_radius_x_m = 1e-9\n",
            "constants.pulley_radius_x_m",
        ),
        ("payload_kg = 1e300\n", "payload_kg"),
        ("gain = 1e300\n", "gain"),
        (
            "[breakaway_noise_var]\nx_pos = 0\n",
            "breakaway_noise_var.x_pos",
        ),
    ] {
        let (d, e) = fails(toml, &axis_csv(10, 0.01));
        assert_eq!(e.location.file, d.join("dataset.toml"));
        assert!(e.to_string().contains(key), "{toml}: {e}");
        assert_eq!(e.location.line, Some(toml.lines().count()), "{toml}: {e}");
    }
}

const EMPS_LIKE: &str =
    "t,qm,qg,vir,pulses_N\n0,0,0,0,0\n0.001,0,0.001,0.1,5\n0.002,0.0001,0.002,0.2,0\n";

#[test]
fn declared_controller_gives_the_loop_signals() {
    let toml = "gain = 35\n[columns]\nx = \"qm\"\nu = \"vir\"\n[controller]\nreference = \"qg\"\nkp = 160.18\nkv = 243.45\nvelocity = \"averaged_difference\"\ndelay_samples = 1\nsaturation = 10.0\nadded_input = \"pulses_N\"\n";
    let ds = ok(toml, EMPS_LIKE);
    let a = ds.runs[0].axis().unwrap();
    let cl = a.closed_loop.as_ref().unwrap();
    assert_eq!(cl.reference, vec![0.0, 0.001, 0.002]);
    assert_eq!(cl.added_input, vec![0.0, 5.0, 0.0]);
    let spec = ds.spec.controller.as_ref().unwrap();
    assert!((spec.p_gain() - 160.18 * 243.45).abs() < 1e-9);
    assert_eq!(spec.d_gain(), 243.45);
    let ctl = crane_ident::emps::Controller::from_declared(spec, a.gain).unwrap();
    assert_eq!(ctl.gtau, 35.0);
    assert_eq!(ctl.delay_samples, 1);
    // saturation, then the added input
    assert_eq!(spec.command(1.0, 0.0, 0.0, 0.0, 0.001, true, 5.0), 15.0);
    // parallel form, P loop
    let ds = ok(
        "[columns]\nx = \"qm\"\nu = \"vir\"\n[controller]\nreference = \"qg\"\nkp = 3\nkd = 0\n",
        EMPS_LIKE,
    );
    let spec = ds.spec.controller.as_ref().unwrap();
    assert_eq!(spec.command(1.0, 0.5, 0.0, 0.0, 0.001, false, 0.0), 1.5);
    assert!(crane_ident::emps::Controller::from_declared(spec, Gain::Unknown).is_err());
}

#[test]
fn controller_declaration_errors() {
    let base = "[columns]\nx = \"qm\"\nu = \"vir\"\n[controller]\nreference = \"qg\"\n";
    for (extra, needle, line) in [
        ("kp = 1\nkv = 1\nkd = 1\n", "not both", Some(8)),
        ("kp = 1\n", "give `kv`", Some(6)),
        ("kp = -1\nkv = 1\n", "controller.kp", Some(6)),
        ("kp = 1\nkv = nan\n", "controller.kv", Some(7)),
        (
            "kp = 1\nkv = 1\nsaturation = 0\n",
            "controller.saturation",
            Some(8),
        ),
        (
            "kp = 1\nkv = 1\ndelay_samples = 100000\n",
            "delay_samples",
            Some(8),
        ),
        (
            "kp = 1\nkv = 1\nvelocity = \"psychic\"\n",
            "averaged_difference",
            Some(8),
        ),
        ("kp = 1\nkv = 1\nintegral = 3\n", "unknown field", Some(8)),
    ] {
        let (d, e) = fails(&format!("{base}{extra}"), EMPS_LIKE);
        assert_eq!(e.location.file, d.join("dataset.toml"), "{extra}");
        assert!(e.to_string().contains(needle), "{extra}: {e}");
        assert_eq!(e.location.line, line, "{extra}: {e}");
    }
    // a reference column the run does not have
    let (d, e) = fails(
        "[columns]\nx = \"qm\"\nu = \"vir\"\n[controller]\nreference = \"r\"\nkp = 1\nkv = 1\n",
        EMPS_LIKE,
    );
    assert_eq!(e.location.file, d.join("run.csv"));
    assert!(e.to_string().contains("missing column `r`"), "{e}");
}

#[test]
fn duplicate_columns_in_a_huge_header_are_found() {
    // 200k columns: linear check (was quadratic, 81 s)
    let mut h: Vec<String> = (0..200_000).map(|k| format!("c{k}")).collect();
    h.push("c17".into());
    let text = format!("{}\n", h.join(","));
    let e = parse_table(Path::new("wide.csv"), &text).unwrap_err();
    assert!(matches!(e.problem, Problem::DuplicateColumn));
    assert_eq!(e.location.column, Some(("c17".to_string(), 200_001)));
}

#[test]
fn validation_kind_is_held_out() {
    let ds = ok(
        "[[runs]]\nfile = \"run.csv\"\nkind = \"validation\"\nnote = \"held out\"\n",
        &axis_csv(10, 0.01),
    );
    assert_eq!(ds.runs[0].kind, RunKind::Validation);
    assert_eq!(ds.spec.runs[0].note.as_deref(), Some("held out"));
}

#[test]
fn asynchronous_two_topic_log_is_resampled_and_its_slow_channel_noted() {
    // a ROS-like log: rows at the union of a 100 Hz position topic and a 33 Hz input topic
    // (offset 3 ms), each column holding its last message
    let mut stamps: Vec<(f64, bool)> = (0..300).map(|k| (k as f64 * 0.01, true)).collect();
    stamps.extend((0..100).map(|k| (k as f64 * 0.03 + 0.003, false)));
    stamps.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (mut x, mut u) = (0.0, 0.0);
    let mut s = String::from("t,x,u\n");
    for (t, is_x) in &stamps {
        if *is_x {
            x = 0.1 * (t * 3.0).sin();
        } else {
            u = 2.0 * (t * 1.7).cos() + t;
        }
        let _ = writeln!(s, "{t},{x},{u}");
    }
    let ds = ok("", &s);
    let a = ds.runs[0].axis().unwrap();
    assert!(a.resampled(), "{:?}", a.notes);
    let LoadNote::Resampled { rows_in, .. } = &a.notes[0] else {
        panic!("{:?}", a.notes)
    };
    assert_eq!(*rows_in, 400);
    // the grid is uniform and covers the log
    let h = a.t[1] - a.t[0];
    assert!(a.t.windows(2).all(|w| (w[1] - w[0] - h).abs() < 1e-9));
    assert!((a.t[a.t.len() - 1] - 2.99).abs() <= h);
    // the 33 Hz input repeats on the grid: noted as held
    assert!(
        a.notes
            .iter()
            .any(|n| matches!(n, LoadNote::HeldChannel { column, .. } if column == "u")),
        "{:?}",
        a.notes
    );
}

/// An asynchronous log: one row per message, the other channel's field empty, the position
/// and the input stamped apart (sometimes at one instant). Loaded as one complete row per
/// instant, each empty field held at its column's last value, the leading row without an
/// input dropped, and said.
#[test]
fn asynchronous_logs_with_empty_fields_are_merged_and_held() {
    let mut s = String::from("t,x,u\n");
    // x every 10 ms, u every 30 ms at 5 ms past; at t = 0.09 both at one stamp, two rows
    let _ = writeln!(s, "0,0.0,");
    for k in 1..20 {
        let t = k as f64 * 0.01;
        if k == 9 {
            let _ = writeln!(s, "{t},{},", k as f64 * 1e-3);
            let _ = writeln!(s, "{t},,{}", 7.0);
            continue;
        }
        let _ = writeln!(s, "{t},{},", k as f64 * 1e-3);
        if k % 3 == 0 {
            let _ = writeln!(s, "{},,{}", t + 0.005, k as f64 / 3.0);
        }
    }
    let ds = ok("", &s);
    let a = ds.runs[0].axis().unwrap();
    let LoadNote::Filled(f) = &a.notes[0] else {
        panic!("{:?}", a.notes)
    };
    assert_eq!(f.merged, 1, "{f:?}");
    // rows 0.00 .. 0.03 have no input yet: the first row with one is the one at 0.035
    assert_eq!(f.dropped_leading, 4, "{f:?}");
    assert!(
        a.notes[0].to_string().contains("asynchronous log"),
        "{}",
        a.notes[0]
    );
    // every sample complete and finite, the input held between its messages
    assert!(a.x.iter().chain(&a.u).all(|v| v.is_finite()));
    assert_eq!(a.u[0], 1.0);
    assert!(a.t[0] > 0.03 && a.t[0] < 0.04, "{}", a.t[0]);
    // before resampling (the merged stamps are irregular): the instant 0.09 carries both of
    // its rows' values, each empty field its column's last value
    let table = parse_table(Path::new("async.csv"), &s).unwrap();
    let (m, _, _) = fill_blanks(&table, 0, &[1, 2]).unwrap();
    let k = m.columns[0].iter().position(|&t| t == 0.09).unwrap();
    assert_eq!((m.columns[1][k], m.columns[2][k]), (9.0 * 1e-3, 7.0));
    assert_eq!(m.lines[k], 13, "the merged row's line is its first row's");
    let k = m.columns[0].iter().position(|&t| t == 0.065).unwrap();
    assert_eq!((m.columns[1][k], m.columns[2][k]), (6.0 * 1e-3, 2.0));
}

/// An asynchronous log with jittered stamps whose position comes on some rows only (empty
/// fields elsewhere): the position is read at the grid instants between the rows that gave
/// it, not held from the last of them (which reads it up to a refresh late), and the run says
/// how many grid samples one given position spans (`x_refresh`, for derivative windows).
#[test]
fn a_position_given_on_some_rows_is_interpolated_between_them() {
    let mut s = String::from("t,x,u\n");
    // rows every 5 ms +- 1.5 ms; x (a ramp, 0.2 m/s) on every 4th row, u on every 3rd
    let mut given = Vec::new();
    for k in 0..400 {
        let t = k as f64 * 0.005 + [0.0, 0.0015, -0.001, 0.0007][k % 4] + 0.002;
        let x = (k % 4 == 0).then_some(0.2 * t);
        let u = (k % 3 == 0).then_some(k as f64);
        if x.is_none() && u.is_none() {
            continue;
        }
        if let Some(x) = x {
            given.push((t, x));
        }
        let f = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
        let _ = writeln!(s, "{t},{},{}", f(x), f(u));
    }
    let ds = ok("", &s);
    let a = ds.runs[0].axis().unwrap();
    assert!(
        a.notes
            .iter()
            .any(|n| matches!(n, LoadNote::Resampled { exact: true, .. })),
        "{:?}",
        a.notes
    );
    let last = given.last().unwrap().0;
    for (k, &g) in a.t.iter().enumerate() {
        let want = 0.2 * g.min(last);
        assert!((a.x[k] - want).abs() < 1e-12, "{k}: {} {want}", a.x[k]);
        assert_eq!(a.source_t[k], g);
    }
    let per_given = a.t.len() as f64 / given.len() as f64;
    assert!(per_given > 1.5, "{per_given}");
    assert_eq!(a.x_refresh, per_given.round() as usize);
}

#[test]
fn asynchronous_rows_at_one_stamp_may_not_disagree() {
    let (d, e) = fails("", "t,x,u\n0,0,0\n0.01,0.1,\n0.01,0.2,1\n0.02,0.3,1\n");
    assert_eq!(e.location.file, d.join("run.csv"));
    assert_eq!(e.location.line, Some(4), "{e}");
    assert_eq!(e.location.column, Some(("x".to_string(), 2)), "{e}");
    assert!(
        matches!(e.problem, Problem::SameStampConflict { first_line: 3, .. }),
        "{e}"
    );
}

#[test]
fn empty_fields_where_a_value_is_needed_are_refused_at_their_line_and_column() {
    // a blank time stamp
    let (_, e) = fails("", "t,x,u\n0,0,0\n,0.1,1\n0.02,0.3,1\n");
    assert_eq!(e.location.line, Some(3), "{e}");
    assert_eq!(e.location.column, Some(("t".to_string(), 1)), "{e}");
    assert!(matches!(e.problem, Problem::BlankField(_)), "{e}");
    // a used column never given a value
    let (_, e) = fails("", "t,x,u\n0,0,\n0.01,0.1,\n0.02,0.3,\n");
    assert_eq!(e.location.column, Some(("u".to_string(), 3)), "{e}");
    assert!(e.to_string().contains("no value on any row"), "{e}");
    // a crane run is never filled
    let mut s = String::from("t,u_x,u_y,u_l,x,y,l,alpha,beta\n");
    for k in 0..20 {
        let ux = if k == 7 { String::new() } else { "0".into() };
        let _ = writeln!(s, "{},{ux},0,0,0.1,0.1,0.3,1.5,0", k as f64 * 0.002);
    }
    let (_, e) = fails("payload_kg = 0.1\n", &s);
    assert_eq!(e.location.line, Some(9), "{e}");
    assert_eq!(e.location.column, Some(("u_x".to_string(), 2)), "{e}");
    assert!(e.to_string().contains("empty field"), "{e}");
    // "NaN" written out is still refused as not finite (an empty field is the only blank)
    let (_, e) = fails("", "t,x,u\n0,0,0\n0.01,NaN,1\n0.02,0.3,1\n");
    assert!(matches!(e.problem, Problem::NotFinite(_)), "{e}");
}

#[test]
fn identical_duplicate_rows_are_merged_and_said() {
    let ds = ok(
        "",
        "t,x,u\n0,0,0\n0.01,0.1,1\n0.01,0.1,1\n0.02,0.3,1\n0.03,0.4,1\n",
    );
    let a = ds.runs[0].axis().unwrap();
    assert_eq!(a.t.len(), 4);
    assert!(matches!(&a.notes[0], LoadNote::Filled(f) if f.merged == 1));
}

/// Stamps in milliseconds, microseconds, nanoseconds or Unix seconds; positions in
/// millimetres or degrees through `position_scale` (the controller's reference with them).
#[test]
fn time_units_and_position_scale_convert_on_load() {
    let mut ms = String::from("t,x,u\n");
    let mut ns = String::from("t,x,u\n");
    let mut epoch = String::from("t,x,u\n");
    for k in 0..50 {
        let t = k as f64 * 0.01;
        let _ = writeln!(ms, "{},{},{}", k * 10, 10.0 * k as f64, 0.5 * t);
        let _ = writeln!(ns, "{},{},{}", k * 10_000_000, 10.0 * k as f64, 0.5 * t);
        let _ = writeln!(epoch, "{},{},{}", 1.7e9 + t, 10.0 * k as f64, 0.5 * t);
    }
    for (toml, csv) in [
        ("time_unit = \"ms\"\nposition_scale = 0.001\n", &ms),
        ("time_unit = \"ns\"\nposition_scale = 0.001\n", &ns),
        ("position_scale = 0.001\n", &epoch),
    ] {
        let ds = ok(toml, csv);
        let a = ds.runs[0].axis().unwrap();
        assert!((a.dt() - 0.01).abs() < 1e-9, "{toml}: {}", a.dt());
        assert!((a.x[10] - 0.1).abs() < 1e-12, "{toml}: {}", a.x[10]);
        assert!(!a.resampled(), "{toml}");
    }
    // degrees on a rotary axis, the reference converted with x
    let mut deg = String::from("t,x,u,r\n");
    for k in 0..50 {
        let _ = writeln!(deg, "{},{},0,{}", k as f64 * 0.01, k as f64, 90.0);
    }
    let ds = ok(
        "position_unit = \"rad\"\ninput_unit = \"A\"\nposition_scale = 0.017453292519943295\n\
         [controller]\nreference = \"r\"\nkp = 10.0\nkd = 1.0\n",
        &deg,
    );
    let a = ds.runs[0].axis().unwrap();
    assert!((a.x[45] - 45f64.to_radians()).abs() < 1e-12);
    let r = &a.closed_loop.as_ref().unwrap().reference;
    assert!((r[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    // bad values are refused at their key
    let (_, e) = fails("time_unit = \"min\"\n", &axis_csv(10, 0.01));
    assert!(
        e.to_string().contains("time_unit") || e.to_string().contains("min"),
        "{e}"
    );
    assert_eq!(e.location.line, Some(1), "{e}");
    let (_, e) = fails("\nposition_scale = 0.0\n", &axis_csv(10, 0.01));
    assert_eq!(e.location.line, Some(2), "{e}");
    assert!(e.to_string().contains("position_scale"), "{e}");
}

/// Files written by spreadsheets and DAQ software in other locales: tab-separated, or
/// semicolon-separated with decimal commas. The separator is the header's.
#[test]
fn tab_and_semicolon_files_with_decimal_commas_read_as_the_comma_file() {
    let comma = axis_csv(40, 0.01);
    let tab = comma.replace(',', "\t");
    let semi = comma.replace(',', ";").replace('.', ",");
    let want = ok("", &comma);
    for (what, csv) in [("tab", &tab), ("semicolon", &semi)] {
        let got = ok("", csv);
        let (a, b) = (want.runs[0].axis().unwrap(), got.runs[0].axis().unwrap());
        assert_eq!((&a.t, &a.x, &a.u), (&b.t, &b.x, &b.u), "{what}");
    }
    // a decimal comma is only read with semicolons, and never twice in a field
    let (_, e) = fails("", "t;x;u\n0;0;0\n0,01;0,1,2;1\n");
    assert!(matches!(e.problem, Problem::NotNumeric(_)), "{e}");
    assert_eq!(e.location.column, Some(("x".to_string(), 2)), "{e}");
}

/// A folder of logs without a `dataset.toml`: the error names the file and says what to
/// write (and that an empty one takes every CSV in m and V), instead of a bare "not found".
#[test]
fn a_folder_of_logs_without_a_description_says_what_to_write() {
    let d = temp_dir("nodesc");
    std::fs::write(d.join("run.csv"), axis_csv(10, 0.01)).unwrap();
    let e = load_dataset(&d).expect_err("no dataset.toml");
    assert_eq!(e.location.file, d.join("dataset.toml"));
    let m = e.to_string();
    assert!(
        m.contains("position_unit") && m.contains("DATA_FORMAT.md"),
        "{m}"
    );
    // an empty one loads the CSV
    std::fs::write(d.join("dataset.toml"), "").unwrap();
    assert_eq!(
        load_dataset(&d)
            .unwrap_or_else(|e| panic!("{e}"))
            .runs
            .len(),
        1
    );
    // a path that is not a directory at all keeps the plain message
    let e = load_dataset(&d.join("nowhere")).expect_err("no directory");
    assert!(!e.to_string().contains("DATA_FORMAT.md"), "{e}");
}

// ---- issue 22: inputs a user gets wrong without a word ------------------------------------

#[test]
fn a_run_listed_as_fitting_and_held_out_is_refused() {
    let (d, e) = fails(
        "[[runs]]\nfile = \"run.csv\"\nkind = \"other\"\n[[runs]]\nfile = \"./run.csv\"\nkind = \"validation\"\n",
        &axis_csv(50, 0.01),
    );
    let m = e.to_string();
    assert!(m.contains("listed twice") && m.contains("held out"), "{m}");
    assert_eq!(e.location.line, Some(5), "{m}");
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn an_explicit_empty_run_list_is_refused() {
    let (d, e) = fails("runs = []\n", &axis_csv(50, 0.01));
    let m = e.to_string();
    assert!(m.contains("runs = []") && m.contains("[[runs]]"), "{m}");
    std::fs::remove_dir_all(d).unwrap();
    // left out, every *.csv is a run (as documented)
    assert_eq!(ok("", &axis_csv(50, 0.01)).runs.len(), 1);
}

#[test]
fn an_unknown_canonical_column_name_is_refused_with_the_known_ones() {
    let (d, e) = fails("[columns]\npos = \"x\"\n", &axis_csv(50, 0.01));
    let m = e.to_string();
    assert!(m.contains("`pos`") && m.contains("force"), "{m}");
    assert_eq!(e.location.line, Some(2), "{m}");
    std::fs::remove_dir_all(d).unwrap();
    let (d, e) = fails(
        "[[runs]]\nfile = \"run.csv\"\ncolumns = { position = \"x\" }\n",
        &axis_csv(50, 0.01),
    );
    assert!(e.to_string().contains("`position`"), "{e}");
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn every_runs_key_is_named_at_its_own_line_in_every_form_of_the_file() {
    // (case, dataset.toml, line of the bad key, text the message must hold); each bad key is
    // in the second run, and a key of the same name comes earlier in the file
    let cases = [
        (
            "gain spelled `gain` in the run, `gain_n_per_v` at the top",
            "gain_n_per_v = 2\n[[runs]]\nfile = \"run.csv\"\ngain = 3\n\
             [[runs]]\nfile = \"run.csv\"\ngain = 1e99\n",
            7,
            "gain must be in",
        ),
        (
            "a run's inline columns table",
            "[columns]\nx = \"x\"\n[[runs]]\nfile = \"run.csv\"\n\
             [[runs]]\nfile = \"run.csv\"\ncolumns = { pos = \"x\" }\n",
            7,
            "`pos`",
        ),
        (
            "a run's [runs.columns] sub-table",
            "[[runs]]\nfile = \"run.csv\"\n[runs.columns]\nx = \"x\"\n\
             [[runs]]\nfile = \"run.csv\"\n[runs.columns]\npos = \"x\"\n",
            8,
            "`pos`",
        ),
        (
            "a columns key named like the first run's `kind`",
            "[[runs]]\nfile = \"run.csv\"\nkind = \"other\"\n\
             [[runs]]\nfile = \"run.csv\"\ncolumns = { kind = \"x\" }\n",
            6,
            "`kind`",
        ),
        (
            "an inline array of runs",
            "payload_kg = 0.5\nruns = [\n  { file = \"run.csv\", payload_kg = 0.2 },\n\
             { file = \"run.csv\", payload_kg = 1e99 },\n]\n",
            4,
            "payload_kg must be in",
        ),
        (
            "spaced [[ runs ]] headers",
            "payload_kg = 0.5\n[[ runs ]]\nfile = \"run.csv\"\npayload_kg = 0.2\n\
             [[ runs ]]\nfile = \"run.csv\"\npayload_kg = 1e99\n",
            7,
            "payload_kg must be in",
        ),
        (
            "a quoted key",
            "payload_kg = 0.5\n[[runs]]\nfile = \"run.csv\"\npayload_kg = 0.2\n\
             [[runs]]\nfile = \"run.csv\"\n\"payload_kg\" = 1e99\n",
            7,
            "payload_kg must be in",
        ),
        (
            "a run listed twice in an inline array",
            "runs = [\n  { file = \"run.csv\" },\n  { file = \"./run.csv\", kind = \"validation\" },\n]\n",
            3,
            "listed twice",
        ),
    ];
    for (case, toml, line, says) in cases {
        let (d, e) = fails(toml, &axis_csv(10, 0.01));
        assert_eq!(e.location.file, d.join("dataset.toml"), "{case}: {e}");
        assert_eq!(e.location.line, Some(line), "{case}: {e}");
        assert!(e.to_string().contains(says), "{case}: {e}");
        std::fs::remove_dir_all(d).unwrap();
    }
    // the data set's own gain, spelled `gain`, while a run spells it `gain_n_per_v`: the
    // top-level key, by its own name
    let (d, e) = fails(
        "gain = 1e99\n[[runs]]\nfile = \"run.csv\"\ngain_n_per_v = 3\n",
        &axis_csv(10, 0.01),
    );
    assert_eq!(e.location.line, Some(1), "{e}");
    assert!(e.to_string().contains("gain must be in"), "{e}");
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn every_table_key_is_named_at_its_own_line_in_every_form_of_the_file() {
    // (case, dataset.toml, line of the bad key, text the message must hold); where a line of
    // the same name comes earlier (in a multi-line description), a scan for `key =` found that
    // one; inline tables, dotted and quoted keys and spaced headers it did not find at all
    let earlier = "description = \"\"\"\ngravity = 9.81 on Earth\nx_pos = 0.02\n\
                   the [controller] gains were\nkp = 2\nruns = two, listed below\n\"\"\"\n";
    let ctl = "[columns]\nx = \"qm\"\nu = \"vir\"\n";
    let cases = [
        (
            "[constants] after a description line `gravity = ...`",
            format!("{earlier}[constants]\ngravity = 1e308\n"),
            9,
            "constants.gravity must be in",
        ),
        (
            "an inline constants table",
            "payload_kg = 0.5\nconstants = { gravity = 1e308 }\n".into(),
            2,
            "constants.gravity must be in",
        ),
        (
            "a dotted key",
            "payload_kg = 0.5\nconstants.trolley_mass_kg = 1e9\n".into(),
            2,
            "constants.trolley_mass_kg must be in",
        ),
        (
            "a quoted key under a spaced header",
            "[ constants ]\ngravity = 9.81\n\"encoder_pulses\" = 0\n".into(),
            3,
            "constants.encoder_pulses must be in",
        ),
        (
            "a bad travel range after the description",
            format!("{earlier}[constants]\n\"x_range_m\" = [0, 0]\n"),
            9,
            "constants.x_range_m must be [min, max]",
        ),
        (
            "[breakaway_noise_var] after a description line `x_pos = ...`",
            format!("{earlier}[breakaway_noise_var]\nx_pos = 0\n"),
            9,
            "breakaway_noise_var.x_pos must be in",
        ),
        (
            "[controller] after a description line `kp = ...`",
            format!("{earlier}{ctl}[controller]\nreference = \"qg\"\nkp = -1\nkv = 1\n"),
            13,
            "controller.kp must be in",
        ),
        (
            "a spaced [ controller ] header",
            format!("{ctl}[ controller ]\nreference = \"qg\"\nkp = 1\nkv = nan\n"),
            7,
            "controller.kv must be in",
        ),
        (
            "an inline controller table",
            format!("controller = {{ reference = \"qg\", kp = 1, kv = 1, kd = 1 }}\n{ctl}"),
            1,
            "not both",
        ),
        (
            "`runs = []` after a description line `runs = ...`",
            format!("{earlier}runs = []\n"),
            8,
            "lists no run",
        ),
    ];
    for (case, toml, line, says) in cases {
        let (d, e) = fails(&toml, &axis_csv(10, 0.01));
        assert_eq!(e.location.file, d.join("dataset.toml"), "{case}: {e}");
        assert_eq!(e.location.line, Some(line), "{case}: {e}");
        assert!(e.to_string().contains(says), "{case}: {e}");
        std::fs::remove_dir_all(d).unwrap();
    }
}

#[test]
fn a_latin1_byte_is_refused_at_its_line_and_old_mac_endings_read() {
    let d = temp_dir("latin1");
    std::fs::write(d.join("dataset.toml"), "").unwrap();
    let mut csv = b"# lab at 20 \xb0C\n".to_vec();
    csv.extend_from_slice(axis_csv(50, 0.01).as_bytes());
    std::fs::write(d.join("run.csv"), csv).unwrap();
    let m = load_dataset(&d).expect_err("Latin-1").to_string();
    assert!(m.contains("line 1, column 13") && m.contains("0xB0"), "{m}");
    std::fs::remove_dir_all(d).unwrap();
    let ds = ok("", &axis_csv(50, 0.01).replace('\n', "\r"));
    assert_eq!(ds.runs[0].axis().unwrap().t.len(), 50);
}

#[cfg(unix)]
#[test]
fn a_run_file_that_is_a_fifo_is_refused_instead_of_waiting_forever() {
    let d = temp_dir("fifo");
    std::fs::write(d.join("dataset.toml"), "[[runs]]\nfile = \"pipe.csv\"\n").unwrap();
    let made = std::process::Command::new("mkfifo")
        .arg(d.join("pipe.csv"))
        .status()
        .is_ok_and(|s| s.success());
    if made {
        let e = load_dataset(&d).expect_err("a FIFO");
        let m = e.to_string();
        assert!(m.contains("FIFO") && m.contains("pipe.csv"), "{m}");
        // named at its `file` key in dataset.toml
        assert_eq!(e.location.file, d.join("dataset.toml"), "{m}");
        assert_eq!(e.location.line, Some(2), "{m}");
    }
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn a_missing_run_file_or_a_directory_is_named_at_its_file_key_with_the_path() {
    // the second run's file is the bad one; the first run's `file` key comes earlier
    for (case, toml, line) in [
        (
            "[[runs]] tables",
            "[[runs]]\nfile = \"run.csv\"\n[[runs]]\nkind = \"validation\"\nfile = \"BAD\"\n",
            5,
        ),
        (
            "an inline array",
            "runs = [\n  { file = \"run.csv\" },\n  { file = \"BAD\" },\n]\n",
            3,
        ),
    ] {
        for (bad, says) in [("missing.csv", "No such file"), ("sub.csv", "a directory")] {
            let d = set(&toml.replace("BAD", bad), &axis_csv(10, 0.01));
            std::fs::create_dir(d.join("sub.csv")).unwrap();
            let e = load_dataset(&d).expect_err("must be refused");
            let m = e.to_string();
            assert_eq!(e.location.file, d.join("dataset.toml"), "{case}: {m}");
            assert_eq!(e.location.line, Some(line), "{case}: {m}");
            assert!(matches!(e.problem, Problem::Io(_)), "{case}: {m}");
            let path = d.join(bad).display().to_string();
            assert!(m.contains(&path) && m.contains(says), "{case}: {m}");
            std::fs::remove_dir_all(d).unwrap();
        }
    }
}

#[test]
fn an_unlisted_csv_that_is_a_directory_says_why_it_was_read() {
    // no [[runs]]: every *.csv is a run, and a folder named `sub.csv` has no `file` line to
    // be named at; the error names its path and why it was taken as a run
    let d = set("", &axis_csv(10, 0.01));
    std::fs::create_dir(d.join("sub.csv")).unwrap();
    let e = load_dataset(&d).expect_err("a directory");
    let m = e.to_string();
    assert_eq!(e.location.file, d.join("sub.csv"), "{m}");
    assert!(matches!(e.problem, Problem::Io(_)), "{m}");
    assert!(
        m.contains("a directory") && m.contains("lists no [[runs]]"),
        "{m}"
    );
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn time_in_another_unit_than_declared_is_refused_naming_time_unit() {
    // 1 kHz stamps in milliseconds read as seconds: 1 Hz
    let ms: String = axis_csv(200, 0.001)
        .lines()
        .enumerate()
        .map(|(k, l)| {
            if k == 0 {
                format!("{l}\n")
            } else {
                let (t, rest) = l.split_once(',').unwrap();
                format!("{},{rest}\n", t.parse::<f64>().unwrap() * 1e3)
            }
        })
        .collect();
    let (d, e) = fails("", &ms);
    let m = e.to_string();
    assert!(m.contains("time_unit") && m.contains("Hz"), "{m}");
    std::fs::remove_dir_all(d).unwrap();
    // the same stamps declared as milliseconds: fine
    assert_eq!(
        ok("time_unit = \"ms\"\n", &ms).runs[0]
            .axis()
            .unwrap()
            .t
            .len(),
        200
    );
    // seconds declared as milliseconds (1 kHz becomes 1 MHz): refused
    let (d, e) = fails("time_unit = \"ms\"\n", &axis_csv(200, 0.001));
    assert!(e.to_string().contains("time_unit"), "{e}");
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn millimetres_declared_as_metres_are_refused_naming_position_scale() {
    // a 0.3 m/s axis logged in millimetres: 300 "m/s"
    let mut mm = String::from("t,x,u\n");
    for k in 0..400 {
        let t = k as f64 * 0.001;
        let _ = writeln!(mm, "{t},{},{}", 300.0 * t, 1.0);
    }
    let (d, e) = fails("", &mm);
    let m = e.to_string();
    assert!(m.contains("position_scale") && m.contains("m/s"), "{m}");
    std::fs::remove_dir_all(d).unwrap();
    let ds = ok("position_scale = 0.001\n", &mm);
    let x = &ds.runs[0].axis().unwrap().x;
    assert!((x[399] - 0.3 * 0.399).abs() < 1e-12);
}

#[test]
fn a_runs_bad_value_is_named_at_its_own_line_and_printed_short() {
    // the data set's `payload_kg` comes first in the file; the bad one is the second run's
    // (before: line 1, and the value printed as a 100-digit integer)
    let toml = "payload_kg = 0.5\n[[runs]]\nfile = \"run.csv\"\npayload_kg = 0.2\n\
                [[runs]]\nfile = \"run.csv\"\npayload_kg = 1e99\n";
    let (d, e) = fails(toml, &axis_csv(10, 0.01));
    assert_eq!(e.location.file, d.join("dataset.toml"));
    assert_eq!(e.location.line, Some(7), "{e}");
    let msg = e.to_string();
    assert!(msg.contains("got 1e99") && msg.len() < 300, "{msg}");
    // an empty file name of the first run: its own line too
    let toml = "[[runs]]\nfile = \"run.csv\"\n[[runs]]\nfile = \" \"\n";
    let (_, e) = fails(toml, &axis_csv(10, 0.01));
    assert_eq!(e.location.line, Some(4), "{e}");
}
