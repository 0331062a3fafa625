//! Helpers shared by the `crane` command-line tests (`mod support;` in each).

// Each test file uses its own subset of these helpers.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh, empty scratch folder for the test `name`: `<test file>-<name>` in Cargo's
/// scratch folder for integration tests (`target/tmp`, `CARGO_TARGET_TMPDIR`), not the
/// system's: anything there from an earlier run is removed first, so runs reuse one folder
/// per test instead of leaving one per process behind (a `demo` folder is 176 MB), and a
/// failed test's files stay there to be looked at until the next run.
pub fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("{}-{name}", env!("CARGO_CRATE_NAME"),));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// Runs the `crane` binary with `args` in the working folder `dir` and waits for it.
pub fn crane(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_crane"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run crane")
}

/// A run's standard output as text (invalid UTF-8 replaced).
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// A run's standard error as text (invalid UTF-8 replaced).
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}
