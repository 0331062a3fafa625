//! Issue 22, "Trust, round 2", against the `crane` binary: the outputs of one command are
//! published together at its end or not at all (a failure or Ctrl-C leaves every earlier
//! output as it was, and no temporary behind); positions in milliradians or millimetres, or
//! seconds declared as milliseconds, get an error or a warning naming the unit key; errors
//! name the file and the key, say each cause once, and print numbers short.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod support;
use support::{crane, stderr, tmp};

/// The entries of `dir` whose names start with a dot: temporaries and scratch folders.
fn hidden(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .map(|r| {
            r.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with('.'))
                .collect()
        })
        .unwrap_or_default()
}

/// Identity of the file or folder at `p` (replaced by a rename, it changes).
#[cfg(unix)]
fn inode(p: &Path) -> u64 {
    use std::os::unix::fs::MetadataExt;
    std::fs::symlink_metadata(p)
        .unwrap_or_else(|e| panic!("{}: {e}", p.display()))
        .ino()
}

/// Sends SIGINT to `child` once `ready` holds (or after 20 s), and waits for it.
#[cfg(unix)]
fn interrupt_when(
    child: &mut std::process::Child,
    ready: impl Fn() -> bool,
) -> std::process::ExitStatus {
    let t0 = Instant::now();
    while !ready() && t0.elapsed() < Duration::from_secs(20) {
        std::thread::sleep(Duration::from_millis(10));
    }
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    child.wait().expect("wait")
}

/// `identify` and `demo` fail on their last output (a plot whose path is a folder): the
/// parameter file, the other plots and the data set are not replaced (they were, before the
/// fix: one output after the other). An output on a full device fails before any file is
/// replaced, and the plots folder it would have created is not left behind.
#[cfg(unix)]
#[test]
fn a_failed_command_leaves_every_earlier_output_as_it_was() {
    let d = tmp("transaction");
    let o = crane(&d, &["demo"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (params, fx, ds) = (
        d.join("out/params.toml"),
        d.join("out/plots/friction_x.svg"),
        d.join("out/dataset"),
    );
    // identify: friction_y.svg is a folder, so its plot fails after friction_x's
    let fy = d.join("out/plots/friction_y.svg");
    std::fs::remove_file(&fy).unwrap();
    std::fs::create_dir(&fy).unwrap();
    let before = [inode(&params), inode(&fx)];
    let o = crane(&d, &["identify"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("friction_y.svg"), "{}", stderr(&o));
    assert_eq!(
        [inode(&params), inode(&fx)],
        before,
        "an output was replaced"
    );
    std::fs::remove_dir(&fy).unwrap();
    // (one of the tool's own plots, which a later run may replace)
    std::fs::write(&fy, "<svg><!-- written by crane identify --></svg>").unwrap();
    // demo: its very last output (the validation plot) is a folder
    let val = d.join("out/plots/validation_078_validation_multisine.svg");
    std::fs::remove_file(&val).unwrap();
    std::fs::create_dir(&val).unwrap();
    let before = [inode(&ds), inode(&params), inode(&fx), inode(&fy)];
    let o = crane(&d, &["demo"]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("validation_078_validation_multisine.svg"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        [inode(&ds), inode(&params), inode(&fx), inode(&fy)],
        before,
        "the data set, the parameter file or a plot was replaced"
    );
    for dir in [d.join("out"), d.join("out/plots")] {
        assert!(hidden(&dir).is_empty(), "left behind: {:?}", hidden(&dir));
    }
    // a full device: reported once, nothing replaced, no plots folder made
    if Path::new("/dev/full").exists() {
        let o = crane(
            &d,
            &["identify", "--out", "/dev/full", "--plots", "new_plots"],
        );
        assert!(!o.status.success());
        assert_eq!(
            stderr(&o).matches("No space left").count(),
            1,
            "{}",
            stderr(&o)
        );
        assert!(!d.join("new_plots").exists(), "the plots were written");
    }
    // parameters whose travel excludes the run's first state: said once, by the run's
    // column and the parameter file
    let lim = std::fs::read_to_string(&params)
        .unwrap()
        .replacen("max = 0.505", "max = 0.2", 1);
    std::fs::write(d.join("lim.toml"), lim).unwrap();
    let o = crane(&d, &["validate", "--params", "lim.toml", "--plots", "vl"]);
    let e = stderr(&o);
    assert!(!o.status.success());
    assert_eq!(e.matches("outside the axis limits").count(), 1, "{e}");
    assert!(e.contains("lim.toml") && e.contains("first `x`"), "{e}");
    // a parent that is a file is named
    std::fs::write(d.join("F"), "a file").unwrap();
    let o = crane(&d, &["identify", "--out", "F/p.toml", "--plots", "p"]);
    assert!(
        stderr(&o).contains("F exists and is not a directory"),
        "{}",
        stderr(&o)
    );
    // seconds declared as milliseconds in the crane data set: an error naming time_unit
    let spec = d.join("out/dataset/dataset.toml");
    let text = std::fs::read_to_string(&spec).unwrap();
    std::fs::write(&spec, format!("time_unit = \"ms\"\n{text}")).unwrap();
    let o = crane(&d, &["identify", "--out", "ms.toml", "--plots", "ms"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("time_unit"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&d);
}

/// A plot is written over the tool's own plot of the same name, never over a user's file
/// without `--force` (issue 22: `identify` replaced a user's `friction_x.svg`); the command
/// then fails before any of its outputs is written, and names the file.
#[test]
fn plots_replace_only_the_tools_own() {
    let d = tmp("plots_own");
    let o = crane(&d, &["demo"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (params, fx) = (
        d.join("out/params.toml"),
        d.join("out/plots/friction_x.svg"),
    );
    // the tool's own plots are replaced by a run again
    let o = crane(&d, &["identify"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::read_to_string(&fx)
        .unwrap()
        .contains("<!-- written by crane identify -->"));
    // a user's figure of the same name is not, and nothing else is written
    let mine = "<svg xmlns=\"http://www.w3.org/2000/svg\"><text>my figure</text></svg>";
    std::fs::write(&fx, mine).unwrap();
    let before = inode(&params);
    let o = crane(&d, &["identify"]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("friction_x.svg") && e.contains("not written by crane") && e.contains("--force"),
        "{e}"
    );
    assert_eq!(std::fs::read_to_string(&fx).unwrap(), mine);
    assert_eq!(inode(&params), before, "params.toml was replaced");
    // validate and simulate likewise (simulate's plot goes beside its CSV)
    let val = d.join("out/plots/validation_078_validation_multisine.svg");
    std::fs::write(&val, mine).unwrap();
    let o = crane(&d, &["validate"]);
    assert!(
        !o.status.success() && stderr(&o).contains("validation_078"),
        "{}",
        stderr(&o)
    );
    assert_eq!(std::fs::read_to_string(&val).unwrap(), mine);
    std::fs::write(d.join("out/simulation.svg"), mine).unwrap();
    let o = crane(&d, &["simulate"]);
    assert!(
        !o.status.success() && stderr(&o).contains("simulation.svg"),
        "{}",
        stderr(&o)
    );
    assert!(
        !d.join("out/simulation.csv").exists(),
        "the CSV was written"
    );
    // with --force the user asked for it
    let o = crane(&d, &["identify", "--force"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_ne!(std::fs::read_to_string(&fx).unwrap(), mine);
    let _ = std::fs::remove_dir_all(&d);
}

/// Ctrl-C while `simulate` streams its CSV: exit 130, no `.s.csv.tmp-*` and no output folder
/// left (before the fix the temporary file stayed, growing to hundreds of MB). Ctrl-C during
/// `demo` leaves the earlier outputs as they were, with nothing hidden beside them.
#[cfg(unix)]
#[test]
fn an_interrupted_command_leaves_no_temporary_behind() {
    let d = tmp("interrupt");
    std::fs::write(
        d.join("long.toml"),
        "duration_s = 80000\nh = 0.001\nsample_s = 0.1\n",
    )
    .unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_crane"))
        .current_dir(&d)
        .args(["simulate", "long.toml", "--out", "o/s.csv"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn");
    let o = d.join("o");
    let status = interrupt_when(&mut child, || !hidden(&o).is_empty());
    assert_eq!(status.code(), Some(130), "{status:?}");
    assert!(!o.exists(), "left behind: {:?}", hidden(&o));

    let o = crane(&d, &["demo"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let params = d.join("out/params.toml");
    let before = [inode(&d.join("out/dataset")), inode(&params)];
    let mut child = Command::new(env!("CARGO_BIN_EXE_crane"))
        .current_dir(&d)
        .args(["demo"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn");
    // interrupt once the new data set is being written
    let out = d.join("out");
    let status = interrupt_when(&mut child, || !hidden(&out).is_empty());
    if status.code() == Some(130) {
        assert_eq!(
            [inode(&d.join("out/dataset")), inode(&params)],
            before,
            "an interrupted demo replaced an output"
        );
    }
    for dir in [d.join("out"), d.join("out/plots")] {
        assert!(hidden(&dir).is_empty(), "left behind: {:?}", hidden(&dir));
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// A single-axis data set of one back-and-forth run: `t` [s] at 100 Hz, position `scale *
/// amp * sin(t)`, input `u`.
fn axis_set(dir: &Path, spec: &str, amp: f64, scale: f64) {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("dataset.toml"), spec).unwrap();
    let mut csv = String::from("t,x,u\n");
    for k in 0..1000 {
        let t = k as f64 * 0.01;
        csv.push_str(&format!("{t},{},{}\n", scale * amp * t.sin(), t.cos()));
    }
    std::fs::write(dir.join("run.csv"), csv).unwrap();
}

/// The unit check of the loader, consistent for linear and rotary axes: beyond the plausible
/// speed an error, beyond the typical one a note, both naming the unit keys; right units
/// give neither. Before the fix a joint logged in milliradians loaded without a word.
#[test]
fn wrong_position_and_time_units_are_named() {
    let d = tmp("units");
    // the loader's notes that name a unit key
    let note = |dir: &Path| -> Option<String> {
        let ds = crane_ident::data::load_dataset(dir).expect("loads");
        let a = ds.runs[0].axis().expect("single-axis");
        a.notes
            .iter()
            .map(|n| n.to_string())
            .find(|n| n.contains("_unit") || n.contains("position_scale"))
    };
    let rad = "position_unit = \"rad\"\ninput_unit = \"N m\"\n";
    // a joint at up to 1 rad/s: nothing to say
    axis_set(&d.join("joint"), rad, 1.0, 1.0);
    assert_eq!(note(&d.join("joint")), None);
    // the same joint in milliradians: a note naming position_unit and position_scale
    axis_set(&d.join("mrad"), rad, 1.0, 1000.0);
    let n = note(&d.join("mrad")).expect("milliradians read as radians pass without a word");
    assert!(
        n.contains("position_scale = 0.001") && n.contains("position_unit"),
        "{n}"
    );
    // ... and said so, the scale set: nothing
    let scaled = format!("{rad}position_scale = 0.001\n");
    axis_set(&d.join("mrad_scaled"), &scaled, 1.0, 1000.0);
    assert_eq!(note(&d.join("mrad_scaled")), None);
    // seconds declared as milliseconds: 1000 times faster, the note names time_unit
    axis_set(
        &d.join("ms"),
        &format!("{rad}time_unit = \"ms\"\n"),
        1.0,
        1.0,
    );
    let n = note(&d.join("ms")).expect("seconds declared as ms pass without a word");
    assert!(n.contains("time_unit"), "{n}");
    // a linear axis at 5 cm/s, then in millimetres (50 m/s: an error), then a slow one in
    // millimetres (5 mm/s read as 5 m/s: a note)
    axis_set(&d.join("lin"), "", 0.05, 1.0);
    assert_eq!(note(&d.join("lin")), None);
    axis_set(&d.join("mm"), "", 0.05, 1000.0);
    let e = crane_ident::data::load_dataset(&d.join("mm")).unwrap_err();
    assert!(e.to_string().contains("position_scale"), "{e}");
    axis_set(&d.join("slow_mm"), "", 0.005, 1000.0);
    let n = note(&d.join("slow_mm")).expect("slow millimetres pass without a word");
    assert!(n.contains("millimetres"), "{n}");
    let _ = std::fs::remove_dir_all(&d);
}

/// CICESE joint 1 with its angles in milliradians: `crane diagnose` says which key to look
/// at (on the real data of `../shared/data/cicese`; skipped without them). Its report and
/// plots are published together: a report on a full device leaves no plots folder.
#[test]
fn cicese_in_milliradians_names_the_unit_key() {
    let Some(root) = crane_ident::shared_data::require("cicese") else {
        return;
    };
    let d = tmp("cicese");
    let ds = d.join("mrad");
    std::fs::create_dir_all(&ds).unwrap();
    let example = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/cicese_joint1");
    let spec = std::fs::read_to_string(example.join("dataset.toml")).unwrap();
    std::fs::write(
        ds.join("dataset.toml"),
        spec.replace("../../../shared/data/cicese/cicese_dd_joint1/", ""),
    )
    .unwrap();
    for e in std::fs::read_dir(root.join("cicese_dd_joint1"))
        .unwrap()
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "csv"))
    {
        let text = std::fs::read_to_string(e.path()).unwrap();
        let mut out = String::new();
        for (i, line) in text.lines().enumerate() {
            let f: Vec<&str> = line.split(',').collect();
            match (i, f.as_slice()) {
                (0, _) => out.push_str(line),
                (_, [t, u, x]) => {
                    let x: f64 = x.parse().unwrap();
                    out.push_str(&format!("{t},{u},{}", x * 1000.0));
                }
                _ => out.push_str(line),
            }
            out.push('\n');
        }
        std::fs::write(ds.join(e.file_name()), out).unwrap();
    }
    let o = crane(&d, &["diagnose", "mrad"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("position_scale = 0.001") && text.contains("warning"),
        "{text}"
    );
    if Path::new("/dev/full").exists() {
        let o = crane(
            &d,
            &["diagnose", "mrad", "--plots", "P", "--report", "/dev/full"],
        );
        assert!(!o.status.success());
        assert!(
            !d.join("P").exists(),
            "the plots were published without the report"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Errors that say what to do: `crane diagnose --json .` takes `.` as the data set; numbers
/// print short; a scenario's bad first state names the scenario's key and the parameter
/// file's limits; a stiff parameter file is named with its key; a cause is said once.
#[test]
fn errors_name_the_file_and_the_key_once() {
    let d = tmp("errors");
    // `.` is the data set (here: one without dataset.toml), not the report file
    let o = crane(&d, &["diagnose", "--json", "."]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("dataset.toml"), "{}", stderr(&o));
    let o = crane(&d, &["diagnose"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    // 1e308, not 309 digits
    let o = crane(&d, &["mc", "--duration", "1e308"]);
    assert!(
        stderr(&o).contains("1e308") && stderr(&o).len() < 300,
        "{}",
        stderr(&o)
    );
    std::fs::write(d.join("r.toml"), "qd0 = [1e300, 0.0, 0.0, 0.0, 0.0]\n").unwrap();
    let o = crane(&d, &["simulate", "r.toml", "--out", "r.csv"]);
    assert!(
        stderr(&o).contains("r.toml: qd0[0] = 1e300"),
        "{}",
        stderr(&o)
    );
    // a parameter file: the built-in parameters with changes
    let params = |name: &str, from: &str, to: &str| {
        let text = builtin_params();
        assert!(text.contains(from), "{from}");
        std::fs::write(d.join(name), text.replacen(from, to, 1)).unwrap();
    };
    params("lim.toml", "max = 0.505", "max = 0.2");
    std::fs::write(
        d.join("s_lim.toml"),
        "params = \"lim.toml\"\nduration_s = 1\n",
    )
    .unwrap();
    let o = crane(&d, &["simulate", "s_lim.toml", "--out", "l.csv"]);
    let e = stderr(&o);
    assert!(
        e.contains("s_lim.toml: q0[0]") && e.contains("x.max") && e.contains("lim.toml"),
        "{e}"
    );
    assert!(!e.contains("state.q"), "{e}");
    params("big.toml", "viscous_pos = ", "viscous_pos = 1e308 #");
    std::fs::write(d.join("s_big.toml"), "params = \"big.toml\"\n").unwrap();
    let o = crane(&d, &["simulate", "s_big.toml", "--out", "b.csv"]);
    let e = stderr(&o);
    assert!(
        e.contains("big.toml") && e.contains("viscous_pos` = 1e308") && e.len() < 400,
        "{e}"
    );
    params("stiff.toml", "viscous_pos = ", "viscous_pos = 1e5 #");
    std::fs::write(
        d.join("s_stiff.toml"),
        "params = \"stiff.toml\"\nduration_s = 1\n",
    )
    .unwrap();
    let o = crane(&d, &["simulate", "s_stiff.toml", "--out", "st.csv"]);
    let e = stderr(&o);
    assert!(
        !o.status.success() && e.contains("stiff.toml") && e.contains("x.viscous"),
        "{e}"
    );
    assert!(!d.join("st.csv").exists());
    // `diagnose --params` whose travel excludes where the runs start: the file, the run and
    // the key (before: "model: the baseline simulation failed")
    let o = crane(&d, &["rig", "--out", "ds"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = crane(&d, &["diagnose", "ds", "--params", "lim.toml"]);
    let e = stderr(&o);
    assert!(
        !o.status.success()
            && e.contains("lim.toml")
            && e.contains("does not simulate run 0")
            && e.contains("[x.min, x.max] = [0, 0.2]"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The built-in parameters as a parameter file.
fn builtin_params() -> String {
    crane_ident::params_file::to_toml(&crane_model::Params::default())
}
