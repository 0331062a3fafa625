//! Running a firmware image under `qemu-system-arm` for the cross-check tests: one runner
//! for the `firmware/` (mps2-an386) and `board-stm32` (netduinoplus2) images.

use std::io::Read;
use std::process::{Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// What a QEMU run left: its exit status, its standard output (raw bytes) and standard error.
pub struct QemuRun {
    /// QEMU's exit status (the semihosting exit code of the image).
    pub status: ExitStatus,
    /// Standard output, as bytes.
    pub stdout: Vec<u8>,
    /// Standard error, lossily decoded.
    pub stderr: String,
}

/// Runs `qemu` (a `qemu-system-arm` command with its arguments set) with no standard input,
/// both outputs captured, killing it after `deadline`.
///
/// # Panics
/// When QEMU cannot be started (with how to install it) or runs past `deadline`: this is a
/// test helper.
pub fn run(mut qemu: Command, deadline: Duration) -> QemuRun {
    let mut child = qemu
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start qemu-system-arm ({e}); install it with `apt-get install -y --no-install-recommends qemu-system-arm`"));
    let mut stdout = child.stdout.take().expect("piped stdout");
    let mut stderr = child.stderr.take().expect("piped stderr");
    let reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        stdout.read_to_end(&mut s).map(|_| s)
    });
    let err_reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stderr.read_to_string(&mut s);
        s
    });
    let start = Instant::now();
    let status = loop {
        if let Some(st) = child.try_wait().expect("wait for qemu") {
            break st;
        }
        if start.elapsed() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("QEMU did not finish within {deadline:?}");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    QemuRun {
        status,
        stdout: reader.join().expect("reader").expect("read stdout"),
        stderr: err_reader.join().unwrap_or_default(),
    }
}
