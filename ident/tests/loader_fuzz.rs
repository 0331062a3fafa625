//! Fuzzing the loaders: random and mutated CSV and `dataset.toml` files (real-looking seeds:
//! an EMPS-like closed-loop set, a CICESE-like rotary set, a crane run) through
//! `load_dataset`. Property: no panic, and every error names the file it is about.
//! Bounded: a few thousand cases, seconds in the test profile.

use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

static N: AtomicUsize = AtomicUsize::new(0);

const EMPS_TOML: &str = r#"# EMPS-like
description = "closed loop"
position_unit = "m"
input_unit = "V"
gain = 35.150651882485
[columns]
x = "qm"
u = "vir"
[controller]
reference = "qg"
kp = 160.18
kv = 243.45
velocity = "averaged_difference"
delay_samples = 1
saturation = 10.0
added_input = "pulses_N"
[[runs]]
file = "run.csv"
kind = "validation"
note = "held out"
"#;

const EMPS_CSV: &str = "# source: EMPS-like\nt,qm,qg,vir,pulses_N\n0,7.67e-06,0.000107,2.553,0\n0.001,7.9e-06,0.000215,2.6,5\n0.002,8.4e-06,0.000323,2.7,5\n0.003,9.1e-06,0.000431,2.65,0\n0.004,1.0e-05,0.000539,2.61,0\n0.005,1.1e-05,0.000647,2.6,0\n";

const CICESE_TOML: &str = "position_unit = \"rad\"\ninput_unit = \"Nm\"\n[[runs]]\nfile = \"run.csv\"\nkind = \"other\"\n";

const CICESE_CSV: &str = "t,u,x\n0.000000,0.0012,0.00022166\n0.014960,0.0087,0.00022166\n0.029920,0.0162,0.00022166\n0.044880,0.0237,0.00022166\n0.059840,0.0312,0.00023911\n0.074800,0.0387,0.00025656\n";

const CRANE_TOML: &str = "payload_kg = 0.064\n[constants]\ngravity = 9.81\nencoder_pulses = 4096\nx_range_m = [0.0, 0.505]\n";

const CRANE_CSV: &str = "# virtual rig\nt,u_x,u_y,u_l,x,y,l,alpha,beta\n0,0,0,0,0.25,0.3,0.35,1.5707963267948966,0\n0.002,0.0168,0.0132,0.0238,0.25,0.3,0.35,1.5707963267948966,0\n0.004,0.03,0.02,0.03,0.2501,0.3001,0.35,1.5707,0.0001\n";

const SEEDS: [(&str, &str); 3] = [
    (EMPS_TOML, EMPS_CSV),
    (CICESE_TOML, CICESE_CSV),
    (CRANE_TOML, CRANE_CSV),
];

const TOKENS: [&str; 16] = [
    "1e308",
    "-1e309",
    "NaN",
    "inf",
    "-inf",
    "99999999999999999999999999999",
    "",
    ",",
    "\n",
    "\u{feff}",
    "#",
    "\"",
    "[",
    "]]",
    "=",
    "0x10",
];

/// One edit of a file's bytes.
#[derive(Clone, Debug)]
enum Mutation {
    Flip { at: usize, byte: u8 },
    Truncate { at: usize },
    DuplicateLine { line: usize },
    DeleteLine { line: usize },
    Insert { at: usize, token: usize },
    Bom,
    Crlf,
    Repeat { line: usize, times: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), any::<u8>()).prop_map(|(at, byte)| Mutation::Flip { at, byte }),
        any::<usize>().prop_map(|at| Mutation::Truncate { at }),
        any::<usize>().prop_map(|line| Mutation::DuplicateLine { line }),
        any::<usize>().prop_map(|line| Mutation::DeleteLine { line }),
        (any::<usize>(), 0..TOKENS.len()).prop_map(|(at, token)| Mutation::Insert { at, token }),
        Just(Mutation::Bom),
        Just(Mutation::Crlf),
        (any::<usize>(), 1..50usize).prop_map(|(line, times)| Mutation::Repeat { line, times }),
    ]
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    let n = bytes.len();
    let lines =
        |b: &[u8]| -> Vec<Vec<u8>> { b.split(|&c| c == b'\n').map(<[u8]>::to_vec).collect() };
    match *m {
        Mutation::Flip { at, byte } if n > 0 => bytes[at % n] = byte,
        Mutation::Truncate { at } => bytes.truncate(at % (n + 1)),
        Mutation::DuplicateLine { line } | Mutation::DeleteLine { line } => {
            let mut ls = lines(bytes);
            let i = line % ls.len();
            if matches!(m, Mutation::DuplicateLine { .. }) {
                let l = ls[i].clone();
                ls.insert(i, l);
            } else {
                ls.remove(i);
            }
            *bytes = ls.join(&b'\n');
        }
        Mutation::Repeat { line, times } => {
            let mut ls = lines(bytes);
            let i = line % ls.len();
            let l = ls[i].clone();
            for _ in 0..times {
                ls.insert(i, l.clone());
            }
            *bytes = ls.join(&b'\n');
        }
        Mutation::Insert { at, token } => {
            let at = at % (n + 1);
            bytes.splice(at..at, TOKENS[token].bytes());
        }
        Mutation::Bom => bytes.splice(0..0, "\u{feff}".bytes()).for_each(drop),
        Mutation::Crlf => {
            *bytes = String::from_utf8_lossy(bytes)
                .replace('\n', "\r\n")
                .into_bytes()
        }
        _ => {}
    }
}

fn dir() -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("ident-fuzz-{}", N.fetch_add(1, Ordering::SeqCst)));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Loads a data set made of `toml` and `csv`; an error must name one of the two files (or the
/// directory for a listing error) in its message.
fn check(d: &Path, toml: &[u8], csv: &[u8]) -> Result<(), TestCaseError> {
    std::fs::write(d.join("dataset.toml"), toml).unwrap();
    std::fs::write(d.join("run.csv"), csv).unwrap();
    match crane_ident::data::load_dataset(d) {
        Ok(ds) => {
            for r in &ds.runs {
                if let Some(a) = r.axis() {
                    prop_assert!(a.t.len() >= 2);
                    prop_assert!(a
                        .t
                        .iter()
                        .chain(&a.x)
                        .chain(&a.force)
                        .all(|v| v.is_finite()));
                    prop_assert!(a.t.windows(2).all(|w| w[1] > w[0]));
                }
            }
        }
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(
                msg.starts_with(&d.join("dataset.toml").display().to_string())
                    || msg.starts_with(&d.join("run.csv").display().to_string())
                    || msg.starts_with(&d.display().to_string()),
                "{}",
                msg
            );
            prop_assert!(msg.len() < 2000, "{} chars", msg.len());
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mutated_real_looking_files_never_panic(
        seed in 0..SEEDS.len(),
        on_toml in proptest::collection::vec(mutation(), 0..4),
        on_csv in proptest::collection::vec(mutation(), 0..4),
    ) {
        let (toml, csv) = SEEDS[seed];
        let (mut t, mut c) = (toml.as_bytes().to_vec(), csv.as_bytes().to_vec());
        for m in &on_toml {
            apply(&mut t, m);
        }
        for m in &on_csv {
            apply(&mut c, m);
        }
        let d = dir();
        check(&d, &t, &c)?;
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn random_csv_text_never_panics(
        seed in 0..SEEDS.len(),
        text in "[0-9eE+\\-.,#\n\r tuxNa\u{feff}]{0,300}",
        header in prop_oneof![Just("t,x,u\n"), Just("t,qm,qg,vir,pulses_N\n"), Just("t,u,x\n"), Just("")],
    ) {
        let d = dir();
        check(&d, SEEDS[seed].0.as_bytes(), format!("{header}{text}").as_bytes())?;
        let _ = std::fs::remove_dir_all(&d);
    }
}
