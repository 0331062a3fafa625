//! The real data sets that live outside the repository: `../shared/data` beside the clone
//! (`emps/`: the EMPS benchmark of Janot, Gautier & Brunot 2019, nonlinear benchmark site;
//! `cicese/`: GitHub `jorgevchin/Friction-Identification`; see the README), or the directory
//! named by the environment variable `CRANE_SHARED_DATA`.
//!
//! Tests that need them call [`require`]: without the data they are skipped with a one-line
//! reason on stderr, naming the test, unless the environment variable `CI` is set, where a
//! missing data set is a failure (CI must run them).

use std::path::PathBuf;

/// The directory of the shared data sets: `$CRANE_SHARED_DATA`, else `../shared/data`
/// relative to the workspace root.
pub fn root() -> PathBuf {
    match std::env::var_os("CRANE_SHARED_DATA") {
        Some(p) => PathBuf::from(p),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data"),
    }
}

/// The shared data set `name` (e.g. `"emps"`) if present. When it is absent: `None` after a
/// one-line "skipped" note on stderr naming the current test, or a panic when `CI` is set.
pub fn require(name: &str) -> Option<PathBuf> {
    let dir = root().join(name);
    if dir.is_dir() {
        return Some(dir);
    }
    let test = std::thread::current()
        .name()
        .unwrap_or("this test")
        .to_string();
    let why = format!(
        "{test}: the real data set {} is absent (see the README for where to get it)",
        dir.display()
    );
    if std::env::var_os("CI").is_some() {
        panic!("{why}; CI is set, so this is a failure");
    }
    // straight to stderr, past the test harness's capture, so the skip shows in the log
    use std::io::Write as _;
    let _ = writeln!(std::io::stderr(), "skipped {why}");
    None
}
