//! Atomic file writes: the bytes go to a temporary file in the destination's directory, are
//! flushed to disk, and the temporary file is renamed over the destination. A reader sees the
//! old file or the new one, never a truncated mix; a full disk or a crash leaves the old file
//! in place (and at worst a stray `.<name>.tmp-<pid>-<n>` file, removed on the error paths we
//! see).
//!
//! **Only a regular file or a missing path is ever replaced** ([`Destination`]). A character
//! device or a FIFO (`/dev/null`, `/dev/full`, a named pipe a reader waits on) is written
//! through, in place: renaming over it would turn the device node into a regular file (as
//! root) or cut the pipe's reader off. A symbolic link is refused with an error that names
//! its target (replacing it would break the link; following it silently would write
//! somewhere the user did not name). A directory, a block device or a socket is refused.
//!
//! **Several outputs of one command** go through a [`Transaction`]: every output is staged
//! beside its target and all are renamed into place together at the end, or none is.
//!
//! **Interrupted:** every temporary file or folder this module makes is registered until it
//! is renamed into place or removed; [`remove_pending`] removes them all, and a program's
//! Ctrl-C (SIGINT, SIGTERM) handler calls it before exiting, so a kill leaves no
//! `.<name>.tmp-*` behind (a `SIGKILL` cannot be caught: then they stay).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

mod transaction;
pub use transaction::Transaction;

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// What a registered temporary path is, and so how [`remove_pending`] removes it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pending {
    /// A temporary file: removed.
    File,
    /// A scratch folder of ours: moved aside, then removed with its contents.
    Dir,
    /// A folder created for an output: removed only if empty.
    EmptyDir,
}

/// Temporary paths not yet renamed into place or removed, in the order they were made.
static PENDING: Mutex<Vec<(PathBuf, Pending)>> = Mutex::new(Vec::new());

/// Registers `path` for [`remove_pending`].
fn track(path: &Path, kind: Pending) {
    if let Ok(mut list) = PENDING.lock() {
        list.push((path.to_path_buf(), kind));
    }
}

/// Forgets `path` (renamed into place, or removed).
fn untrack(path: &Path) {
    if let Ok(mut list) = PENDING.lock() {
        if let Some(i) = list.iter().rposition(|(p, _)| p == path) {
            list.remove(i);
        }
    }
}

/// Removes a scratch folder whole. It is first renamed to a fresh name beside it, so a
/// thread still writing into it by path (an interrupted virtual rig) can add nothing more,
/// and the removal cannot race with new entries.
fn remove_tree(dir: &Path) {
    let gone = temp_beside(dir);
    let target = match std::fs::rename(dir, &gone) {
        Ok(()) => gone,
        Err(_) => dir.to_path_buf(),
    };
    let _ = std::fs::remove_dir_all(target);
}

/// Removes every temporary file and scratch folder this process made and has not yet
/// renamed into place, newest first (and the output folders it created for them, when
/// empty). For a program's interrupt handler; safe to call from any thread, at any time:
/// nothing but the module's own temporary paths is touched.
pub fn remove_pending() {
    let list = match PENDING.lock() {
        Ok(mut l) => std::mem::take(&mut *l),
        Err(_) => return,
    };
    for (path, kind) in list.iter().rev() {
        match kind {
            Pending::File => {
                let _ = std::fs::remove_file(path);
            }
            Pending::Dir => remove_tree(path),
            Pending::EmptyDir => {
                let _ = std::fs::remove_dir(path);
            }
        }
    }
}

/// A fresh temporary path beside `path` (same directory, so the rename stays on one file
/// system): `.<name>.tmp-<pid>-<n>`.
pub fn temp_beside(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp = format!(".{name}.tmp-{}-{n}", std::process::id());
    match path.parent() {
        Some(dir) => dir.join(tmp),
        None => PathBuf::from(tmp),
    }
}

/// What is at a destination path, and so how it is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Destination {
    /// Nothing, or a regular file: written atomically (temporary file, rename).
    Replace,
    /// A character device or a FIFO: written through in place (never renamed over).
    WriteThrough,
}

/// Classifies `path` without following a symbolic link: a missing path or a regular file is
/// [`Destination::Replace`], a character device or a FIFO [`Destination::WriteThrough`];
/// anything else (a symbolic link, a directory, a block device, a socket) is an error that
/// says what it is.
pub fn destination(path: &Path) -> std::io::Result<Destination> {
    let meta = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Destination::Replace),
        Err(e) if e.kind() == std::io::ErrorKind::NotADirectory => {
            let why = match path.parent().and_then(blocking_ancestor) {
                Some(file) => format!(
                    "{} exists and is not a directory, so nothing can be written below it",
                    file.display()
                ),
                None => e.to_string(),
            };
            return Err(std::io::Error::new(std::io::ErrorKind::NotADirectory, why));
        }
        Err(e) => return Err(e),
    };
    let ft = meta.file_type();
    if ft.is_file() {
        return Ok(Destination::Replace);
    }
    let refuse = |what: String| {
        Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("{} is {what}; refusing to replace it", path.display()),
        ))
    };
    if ft.is_symlink() {
        let target = std::fs::read_link(path)
            .map(|t| t.display().to_string())
            .unwrap_or_else(|_| "?".into());
        return refuse(format!(
            "a symbolic link to {target} (name the target itself, or another path)"
        ));
    }
    if ft.is_dir() {
        return refuse("a directory (name a file)".into());
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_char_device() || ft.is_fifo() {
            return Ok(Destination::WriteThrough);
        }
        if ft.is_block_device() {
            return refuse("a block device".into());
        }
        if ft.is_socket() {
            return refuse("a socket".into());
        }
    }
    refuse("not a regular file".into())
}

/// Creates the output directory `dir` and its parents; an existing path that is not a
/// directory is an error that says so (`create_dir_all` says only "File exists").
/// A parent that is a file names that file ("out/F exists and is not a directory"), not
/// "Not a directory (os error 20)".
pub fn create_dir(dir: &Path) -> std::io::Result<()> {
    if let Some(file) = blocking_ancestor(dir) {
        let why = if file == dir {
            "exists and is not a directory: an output folder is needed here".to_string()
        } else {
            format!(
                "{} exists and is not a directory: an output folder is needed there",
                file.display()
            )
        };
        return Err(std::io::Error::new(std::io::ErrorKind::AlreadyExists, why));
    }
    std::fs::create_dir_all(dir)
}

/// The nearest existing path among `path` and its ancestors, when it is not a directory
/// (then nothing can be created below it).
fn blocking_ancestor(path: &Path) -> Option<&Path> {
    path.ancestors()
        .filter(|a| !a.as_os_str().is_empty())
        .find(|a| a.exists())
        .filter(|a| !a.is_dir())
}

/// Opens a device or FIFO for writing in place (no create, no truncate of anything else).
fn open_through(path: &Path) -> std::io::Result<std::fs::File> {
    std::fs::OpenOptions::new().write(true).open(path)
}

/// Writes `bytes` to `path` atomically (temporary file in the same directory, `fsync`,
/// rename). The parent directory must exist. On error the destination is unchanged and the
/// temporary file is removed. A character device or FIFO is written through in place, and
/// anything that is not a regular file or a missing path is refused ([`destination`]).
pub fn write(path: &Path, bytes: impl AsRef<[u8]>) -> std::io::Result<()> {
    if destination(path)? == Destination::WriteThrough {
        let mut f = open_through(path)?;
        f.write_all(bytes.as_ref())?;
        return f.flush();
    }
    let tmp = temp_beside(path);
    track(&tmp, Pending::File);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes.as_ref())?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    untrack(&tmp);
    result
}

/// A file written in pieces and published atomically: the pieces go to a temporary file
/// beside the destination; [`AtomicFile::commit`] flushes it to disk and renames it over the
/// destination. Dropped without `commit` (an error on the way), the temporary file is removed
/// and the destination is untouched.
/// A character device or a FIFO is written through in place instead ([`destination`]): no
/// temporary file, `commit` only flushes.
#[derive(Debug)]
pub struct AtomicFile {
    path: PathBuf,
    /// The temporary file; `None` when writing through to a device or FIFO.
    tmp: Option<PathBuf>,
    file: Option<std::io::BufWriter<std::fs::File>>,
}

impl AtomicFile {
    /// Starts writing `path` (its directory must exist); refuses what [`destination`]
    /// refuses.
    pub fn create(path: &Path) -> std::io::Result<AtomicFile> {
        let (tmp, file) = match destination(path)? {
            Destination::WriteThrough => (None, open_through(path)?),
            Destination::Replace => {
                let tmp = temp_beside(path);
                let file = std::fs::File::create(&tmp)?;
                track(&tmp, Pending::File);
                (Some(tmp), file)
            }
        };
        Ok(AtomicFile {
            path: path.to_path_buf(),
            tmp,
            file: Some(std::io::BufWriter::new(file)),
        })
    }

    /// Flushes, syncs and renames the temporary file over the destination (a device or FIFO:
    /// flushes).
    pub fn commit(mut self) -> std::io::Result<()> {
        self.finish()?;
        match &self.tmp {
            Some(tmp) => std::fs::rename(tmp, &self.path),
            None => Ok(()),
        }
    }

    /// The destination.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Flushes the writer and syncs the temporary file to disk (a device or FIFO: flushes).
    fn finish(&mut self) -> std::io::Result<()> {
        if let Some(w) = self.file.take() {
            let f = w.into_inner().map_err(|e| e.into_error())?;
            if self.tmp.is_some() {
                f.sync_all()?;
            }
        }
        Ok(())
    }

    /// Finishes the file ([`AtomicFile::finish`]) and hands its temporary file over to a
    /// [`Transaction`] instead of renaming it: `(destination, Some(temporary))`, or
    /// `(destination, None)` when it was written through to a device or FIFO.
    fn into_staged(mut self) -> std::io::Result<(PathBuf, Option<PathBuf>)> {
        self.finish()?;
        let tmp = self.tmp.take();
        // registered as pending still: the transaction now owns it
        Ok((self.path.clone(), tmp))
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match &mut self.file {
            Some(f) => f.write(buf),
            None => Err(std::io::Error::other("atomic file already committed")),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match &mut self.file {
            Some(f) => f.flush(),
            None => Ok(()),
        }
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        // not committed (or the rename failed): the temporary file goes
        if let Some(tmp) = &self.tmp {
            let _ = std::fs::remove_file(tmp);
            untrack(tmp);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_whole_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("crane-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.txt");
        write(&p, "old contents, longer").unwrap();
        write(&p, "new").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "new");
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().collect();
        assert_eq!(names.len(), 1, "a temporary file was left behind");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn streamed_file_appears_only_on_commit() {
        let dir = std::env::temp_dir().join(format!("crane-atomic-stream-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("run.csv");
        write(&p, "old").unwrap();
        {
            let mut f = AtomicFile::create(&p).unwrap();
            f.write_all(b"half").unwrap();
            // dropped: an error on the way
        }
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "old");
        let mut f = AtomicFile::create(&p).unwrap();
        f.write_all(b"new").unwrap();
        f.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "new");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failed_write_keeps_the_old_file() {
        let dir = std::env::temp_dir().join(format!("crane-atomic-fail-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.txt");
        write(&p, "old").unwrap();
        // a directory in place of the destination: the rename fails
        let d = dir.join("sub");
        std::fs::create_dir_all(d.join("x")).unwrap();
        assert!(write(&d, "new").is_err());
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "old");
        let n = std::fs::read_dir(&dir).unwrap().count();
        assert_eq!(n, 2, "a temporary file was left behind");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn devices_are_written_through_and_links_refused() {
        use std::os::unix::fs::FileTypeExt;
        // /dev/null stays a character device (renamed over, as root it became a file)
        write(Path::new("/dev/null"), "x").unwrap();
        let mut f = AtomicFile::create(Path::new("/dev/null")).unwrap();
        f.write_all(b"y").unwrap();
        f.commit().unwrap();
        let ft = std::fs::symlink_metadata("/dev/null").unwrap().file_type();
        assert!(ft.is_char_device(), "/dev/null is no longer a device");
        // a full device reports its error instead of being replaced
        if Path::new("/dev/full").exists() {
            let e = write(Path::new("/dev/full"), "x").unwrap_err();
            assert_eq!(e.raw_os_error(), Some(28), "{e}");
            let ft = std::fs::symlink_metadata("/dev/full").unwrap().file_type();
            assert!(ft.is_char_device());
        }
        let dir = std::env::temp_dir().join(format!("crane-atomic-dev-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("target.txt");
        write(&target, "kept").unwrap();
        let link = dir.join("link.txt");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let e = write(&link, "new").unwrap_err();
        assert!(e.to_string().contains("symbolic link"), "{e}");
        assert!(AtomicFile::create(&link).is_err());
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "kept");
        // a FIFO with a reader gets the bytes, and stays a FIFO
        let fifo = dir.join("pipe");
        let ok = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success());
        if ok {
            let f2 = fifo.clone();
            let reader = std::thread::spawn(move || std::fs::read_to_string(f2).unwrap());
            write(&fifo, "through").unwrap();
            assert_eq!(reader.join().unwrap(), "through");
            let ft = std::fs::symlink_metadata(&fifo).unwrap().file_type();
            assert!(ft.is_fifo(), "the FIFO was replaced");
        }
        let e = write(&dir, "x").unwrap_err();
        assert!(e.to_string().contains("directory"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
