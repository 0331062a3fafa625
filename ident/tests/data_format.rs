//! The data format: loading, defaults and located errors, on small files in a temp dir.

use crane_ident::data::{
    load_dataset, parse_table, write_crane_run, CraneRun, DataError, Problem, RunKind, Samples,
};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

static N: AtomicUsize = AtomicUsize::new(0);

fn temp_dir(tag: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "ident-test-{}-{}",
        tag,
        N.fetch_add(1, Ordering::SeqCst)
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).unwrap();
}

const GOOD: &str = "# a comment\n\
beta,alpha,l,y,x,u_l,u_y,u_x,t,extra\n\
0,1.5707963,0.4,0.3,0.2,0,1,2,0,99\n\
# comment between rows\n\
0.01,1.57,0.41,0.31,0.21,0,1,2,0.002,98\n\
\n\
0.02,1.56,0.42,0.32,0.22,-1,1,-2,0.004,97\n";

#[test]
fn minimal_dataset_loads_every_csv_with_columns_in_any_order() {
    let d = temp_dir("minimal");
    write(&d, "dataset.toml", "payload_kg = 0.064\n");
    write(&d, "b.csv", GOOD);
    write(&d, "a.csv", "t,x,force\n0,0.1,3\n0.001,0.1,4\n");
    write(&d, "notes.txt", "not a run");
    let ds = load_dataset(&d).unwrap();
    assert_eq!(ds.runs.len(), 2);
    assert_eq!(ds.runs[0].name, "a.csv");
    assert_eq!(ds.runs[1].name, "b.csv");
    assert!(ds.runs.iter().all(|r| r.kind == RunKind::Other));
    assert!(ds.runs.iter().all(|r| r.payload_kg == 0.064));
    let c = ds.runs[1].crane().unwrap();
    assert_eq!(c.t, vec![0.0, 0.002, 0.004]);
    assert_eq!(c.u[0], vec![2.0, 2.0, -2.0]);
    assert_eq!(c.x, vec![0.2, 0.21, 0.22]);
    assert_eq!(c.beta, vec![0.0, 0.01, 0.02]);
    let a = ds.runs[0].axis().unwrap();
    assert_eq!(a.force, vec![3.0, 4.0]);
    // documented defaults
    assert_eq!(ds.spec.constants.pulley_radius_l_m, 0.015);
    assert_eq!(ds.spec.breakaway_noise_var.x_pos, 0.026);
    assert_eq!(ds.spec.gain_n_per_v, None);
}

#[test]
fn full_dataset_description_with_kinds_payloads_gain_and_renames() {
    let d = temp_dir("full");
    write(
        &d,
        "dataset.toml",
        r#"
payload_kg = 0.064
gain_n_per_v = 2.0

[constants]
trolley_mass_kg = 1.2

[[runs]]
file = "rope.csv"
kind = "rope_loaded"
payload_kg = 0.457

[[runs]]
file = "axis.csv"
kind = "motion_x"
gain_n_per_v = 10.0
[runs.columns]
x = "qm"
u = "vir"
"#,
    );
    write(&d, "rope.csv", GOOD);
    write(
        &d,
        "axis.csv",
        "t,qm,vir,pulses\n0,0.1,0.5,0\n0.001,0.1002,-0.5,5\n",
    );
    let ds = load_dataset(&d).unwrap();
    assert_eq!(ds.runs[0].kind, RunKind::RopeLoaded);
    assert_eq!(ds.runs[0].payload_kg, 0.457);
    assert_eq!(ds.runs[1].payload_kg, 0.064);
    assert_eq!(ds.spec.constants.trolley_mass_kg, 1.2);
    assert_eq!(ds.spec.constants.rail_mass_kg, 2.20);
    match &ds.runs[1].samples {
        Samples::Axis(a) => {
            assert_eq!(a.force, vec![5.0, -5.0]);
            assert_eq!(a.x, vec![0.1, 0.1002]);
        }
        _ => panic!("axis run expected"),
    }
}

fn load_err(csv: &str) -> DataError {
    let d = temp_dir("err");
    write(&d, "dataset.toml", "payload_kg = 0.1\n");
    write(&d, "run.csv", csv);
    let e = load_dataset(&d).unwrap_err();
    assert_eq!(e.location.file, d.join("run.csv"), "{e}");
    e
}

#[test]
fn errors_name_file_line_and_column() {
    // missing column
    let e =
        load_err("t,u_x,u_y,u_l,x,y,l,alpha\n0,0,0,0,0.1,0.1,0.3,1.5\n0.1,0,0,0,0.1,0.1,0.3,1.5\n");
    assert!(
        matches!(&e.problem, Problem::MissingColumn(m)
            if m.wanted.contains("beta") && m.found.len() == 8),
        "{e}"
    );
    assert!(e.to_string().contains("run.csv"), "{e}");

    // non-numeric, line 3 (comment on line 1), column 5 `x`
    let e = load_err("# c\nt,u_x,u_y,u_l,x,y,l,alpha,beta\n0,0,0,0,abc,0.1,0.3,1.5,0\n");
    assert_eq!(e.location.line, Some(3));
    assert_eq!(e.location.column, Some(("x".to_string(), 5)));
    assert!(matches!(&e.problem, Problem::NotNumeric(s) if s == "abc"));
    let msg = e.to_string();
    assert!(msg.contains("run.csv:3") && msg.contains("`x`"), "{msg}");

    // non-finite, even in an ignored extra column
    let e = load_err("t,x,force,junk\n0,0,0,1\n1,0,0,NaN\n");
    assert_eq!(e.location.line, Some(3));
    assert_eq!(e.location.column, Some(("junk".to_string(), 4)));
    assert!(matches!(e.problem, Problem::NotFinite(_)));
    let e = load_err("t,x,force\n0,0,0\n1,inf,0\n");
    assert!(matches!(e.problem, Problem::NotFinite(_)));

    // time going back (a repeated stamp is an asynchronous log's: rows at one instant are
    // merged if they agree, refused if not; `loader_rules.rs`)
    let e = load_err("t,x,force\n0,0,0\n1,0,0\n0.5,0,0\n");
    assert_eq!(e.location.line, Some(4));
    assert_eq!(e.location.column, Some(("t".to_string(), 1)));
    assert!(matches!(e.problem, Problem::TimeNotIncreasing { .. }));

    // unit out of range: rope length in mm, angle in degrees, voltage beyond saturation
    let e = load_err(
        "t,u_x,u_y,u_l,x,y,l,alpha,beta\n0,0,0,0,0.1,0.1,300,1.5,0\n0.1,0,0,0,0.1,0.1,0.3,1.5,0\n",
    );
    assert_eq!(e.location.line, Some(2));
    assert_eq!(e.location.column, Some(("l".to_string(), 7)));
    assert!(matches!(e.problem, Problem::OutOfRange { .. }));
    let e = load_err(
        "t,u_x,u_y,u_l,x,y,l,alpha,beta\n0,0,0,0,0.1,0.1,0.3,1.5,0\n0.1,0,0,0,0.1,0.1,0.3,90,0\n",
    );
    assert_eq!(e.location.column, Some(("alpha".to_string(), 8)));
    let e = load_err(
        "t,u_x,u_y,u_l,x,y,l,alpha,beta\n0,13,0,0,0.1,0.1,0.3,1.5,0\n0.1,0,0,0,0.1,0.1,0.3,1.5,0\n",
    );
    assert_eq!(e.location.column, Some(("u_x".to_string(), 2)));

    // a short row is an error, not dropped
    let e = load_err("t,x,force\n0,0,0\n1,0\n");
    assert_eq!(e.location.line, Some(3));
    assert!(matches!(
        e.problem,
        Problem::FieldCount {
            expected: 3,
            found: 2
        }
    ));
}

#[test]
fn bad_dataset_toml_is_located() {
    let d = temp_dir("toml");
    write(&d, "dataset.toml", "payload = 0.1\n");
    let e = load_dataset(&d).unwrap_err();
    assert_eq!(e.location.file, d.join("dataset.toml"));
    assert!(matches!(e.problem, Problem::Toml(_)), "{e}");
    write(&d, "dataset.toml", "payload_kg = -1\n");
    assert!(matches!(
        load_dataset(&d).unwrap_err().problem,
        Problem::BadValue(_)
    ));
    write(
        &d,
        "dataset.toml",
        "payload_kg = 0.1\n[[runs]]\nfile = \"x.csv\"\nkind = \"nonsense\"\n",
    );
    let e = load_dataset(&d).unwrap_err();
    assert_eq!(e.location.line, Some(4), "{e}");
    write(
        &d,
        "dataset.toml",
        "payload_kg = 0.1\n[[runs]]\nfile = \"missing.csv\"\n",
    );
    let e = load_dataset(&d).unwrap_err();
    // named at the run's `file` key, with the path looked for
    assert_eq!(e.location.file, d.join("dataset.toml"));
    assert_eq!(e.location.line, Some(3), "{e}");
    assert!(matches!(e.problem, Problem::Io(_)));
    assert!(
        e.to_string()
            .contains(&d.join("missing.csv").display().to_string()),
        "{e}"
    );
}

#[test]
fn written_runs_read_back_bit_for_bit() {
    let d = temp_dir("roundtrip");
    let run = CraneRun {
        t: vec![0.0, 0.002, 0.004],
        u: [vec![0.1, -12.0, 1.0 / 3.0], vec![0.0; 3], vec![2.0; 3]],
        x: vec![0.1, 0.2, 0.30000000000000004],
        y: vec![0.0; 3],
        l: vec![0.4; 3],
        alpha: vec![core::f64::consts::FRAC_PI_2; 3],
        beta: vec![1e-300, -0.0, 0.01],
    };
    write_crane_run(&d.join("r.csv"), &run, "virtual rig\nseed 1").unwrap();
    let t = parse_table(
        &d.join("r.csv"),
        &std::fs::read_to_string(d.join("r.csv")).unwrap(),
    )
    .unwrap();
    let back = t.crane_run(&Default::default()).unwrap();
    assert_eq!(back, run);
}
