//! Reading a user's text input (a CSV run, `dataset.toml`, a parameter file): regular files
//! only, UTF-8 with the place of the first bad byte, any line ending.
//!
//! Guarantees of [`read_text`]:
//! - A path that is not a regular file once symbolic links are followed (a FIFO, a device, a
//!   directory, a socket) is refused before it is opened: opening a FIFO with no writer
//!   would wait forever, and a device has no end.
//! - Bytes that are not UTF-8 are refused with the 1-based line and column (in bytes) of the
//!   first one and its value: a `°` saved as Latin-1 is one byte 0xB0.
//! - Windows (`\r\n`) and old Mac (`\r`) line endings read as `\n`.

use std::io::{Error, ErrorKind};
use std::path::Path;

/// `Ok` when `path` is a regular file once symbolic links are followed; otherwise the error
/// [`read_text`] gives before opening it: the system's (a missing path: `NotFound`), or
/// `InvalidInput` naming what it is (`a directory is not a regular file`, a FIFO, a device,
/// a socket).
pub fn check_regular(path: &Path) -> std::io::Result<()> {
    let meta = std::fs::metadata(path)?;
    if meta.is_file() {
        Ok(())
    } else {
        Err(Error::new(
            ErrorKind::InvalidInput,
            format!("{} is not a regular file", kind_of(&meta)),
        ))
    }
}

/// The text of the regular file at `path` (see the module doc for what is refused).
pub fn read_text(path: &Path) -> std::io::Result<String> {
    check_regular(path)?;
    let bytes = std::fs::read(path)?;
    let text = match String::from_utf8(bytes) {
        Ok(t) => t,
        Err(e) => {
            let bytes = e.as_bytes();
            let k = e.utf8_error().valid_up_to();
            let line = 1 + bytes[..k].iter().filter(|&&b| b == b'\n').count();
            let line_start = bytes[..k]
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |p| p + 1);
            return Err(Error::new(
                ErrorKind::InvalidData,
                format!(
                    "line {line}, column {}: byte 0x{:02X} is not UTF-8 (a Latin-1 or \
                     Windows-1252 file? save it as UTF-8)",
                    k - line_start + 1,
                    bytes[k]
                ),
            ));
        }
    };
    Ok(if text.contains('\r') {
        text.replace("\r\n", "\n").replace('\r', "\n")
    } else {
        text
    })
}

/// What a non-regular file is, for the error.
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    let ft = meta.file_type();
    if ft.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if ft.is_char_device() || ft.is_block_device() {
            return "a device";
        }
        if ft.is_socket() {
            return "a socket";
        }
    }
    "this"
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("crane-input-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn latin1_byte_is_named_with_its_line_and_column() {
        let d = dir("latin1");
        let p = d.join("run.csv");
        std::fs::write(&p, b"# rig\nt,u,x\n# 20 \xb0C\n0,0,0\n").unwrap();
        let e = read_text(&p).unwrap_err();
        let m = e.to_string();
        assert!(m.contains("line 3, column 6") && m.contains("0xB0"), "{m}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn any_line_ending_reads_as_newline() {
        let d = dir("cr");
        let p = d.join("a.csv");
        std::fs::write(&p, "t,x\r0,1\r1,2\r").unwrap();
        assert_eq!(read_text(&p).unwrap(), "t,x\n0,1\n1,2\n");
        std::fs::write(&p, "t,x\r\n0,1\r\n").unwrap();
        assert_eq!(read_text(&p).unwrap(), "t,x\n0,1\n");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn fifo_and_directory_are_refused_without_waiting() {
        let d = dir("fifo");
        let fifo = d.join("run.csv");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success());
        if made {
            // (opening it would block forever: no writer)
            let e = read_text(&fifo).unwrap_err();
            assert!(e.to_string().contains("FIFO"), "{e}");
        }
        let e = read_text(&d).unwrap_err();
        assert!(e.to_string().contains("directory"), "{e}");
        std::fs::remove_dir_all(&d).unwrap();
    }
}
