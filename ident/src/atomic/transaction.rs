//! [`Transaction`]: the outputs of one command, committed together at the end or not at all.
//!
//! Guarantees:
//! - **Staging changes no target.** Each output is written to a temporary file (or filled
//!   into a scratch folder) beside its target, on the same file system, and flushed to disk.
//!   Every target is checked as it is staged ([`super::destination`]: only a regular file or a
//!   missing path is replaced; a folder output only a folder or a missing path), and one
//!   target cannot be staged twice.
//! - **[`Transaction::commit`] is all or nothing.** It checks every target again (a target
//!   that became a directory or a link since is refused before anything is replaced), then
//!   writes the outputs that go to a character device or a FIFO (they cannot be taken back,
//!   so they go first: `/dev/full` failing replaces nothing), then renames every staged output
//!   over its target, in staging order. If a rename fails, the renames already done are
//!   undone: a replaced file comes back from a hard link kept of it (a copy where the file
//!   system has no hard links), a new file is removed, a replaced folder is moved back. On
//!   success the kept old versions are removed.
//! - **Dropped without a commit** (an error on the way, a panic unwinding), every temporary
//!   file and scratch folder is removed, and so is every output folder the transaction
//!   created, when empty: the command leaves every earlier output as it was.
//! - **Interrupted** (Ctrl-C with [`super::remove_pending`] in the handler), the same.
//!   A kill within the commit's renames themselves (microseconds) can leave some targets new
//!   and others old, each one whole.

use super::{
    destination, open_through, remove_tree, temp_beside, track, untrack, AtomicFile, Destination,
    Pending,
};
use std::io::{Error, ErrorKind, Result, Write};
use std::path::{Path, PathBuf};

/// How a staged output reaches its target.
#[derive(Debug)]
enum Kind {
    /// A temporary file renamed over the target.
    File(PathBuf),
    /// A scratch folder renamed over the target folder.
    Dir(PathBuf),
    /// Bytes for a character device or FIFO, written at commit.
    Through(Vec<u8>),
    /// Already written through to a device or FIFO (a streamed [`AtomicFile`]).
    Done,
}

/// One staged output.
#[derive(Debug)]
struct Staged {
    target: PathBuf,
    kind: Kind,
}

/// How to take back one rename of a commit.
#[derive(Debug)]
enum Undo {
    /// Nothing was renamed (a device or FIFO output).
    Nothing,
    /// The target was missing: remove the new file or folder.
    Created { target: PathBuf, dir: bool },
    /// The target was replaced; its old version is kept at `backup`.
    Replaced {
        target: PathBuf,
        backup: PathBuf,
        dir: bool,
    },
}

impl Undo {
    /// Puts the old version back.
    fn undo(self) {
        match self {
            Undo::Nothing => {}
            Undo::Created { target, dir: false } => {
                let _ = std::fs::remove_file(target);
            }
            Undo::Created { target, dir: true } => remove_tree(&target),
            Undo::Replaced {
                target,
                backup,
                dir,
            } => {
                if dir {
                    remove_tree(&target);
                }
                let _ = std::fs::rename(&backup, &target);
                untrack(&backup);
            }
        }
    }

    /// Drops the old version (the commit succeeded).
    fn forget(self) {
        if let Undo::Replaced { backup, dir, .. } = self {
            if dir {
                remove_tree(&backup);
            } else {
                let _ = std::fs::remove_file(&backup);
            }
            untrack(&backup);
        }
    }
}

/// The outputs of one command: staged beside their targets, renamed into place together by
/// [`Transaction::commit`], or all removed when dropped uncommitted (module documentation).
#[derive(Debug, Default)]
pub struct Transaction {
    staged: Vec<Staged>,
    /// Output folders this transaction created, outermost first.
    made: Vec<PathBuf>,
    /// Scratch folders for [`Transaction::adopt`]ed files, removed when it ends.
    scratch: Vec<PathBuf>,
}

/// `path` with its folder made absolute and canonical, for comparing targets.
fn key(path: &Path) -> PathBuf {
    match (path.parent(), path.file_name()) {
        (Some(dir), Some(name)) => {
            let dir = if dir.as_os_str().is_empty() {
                Path::new(".")
            } else {
                dir
            };
            dir.canonicalize()
                .map(|d| d.join(name))
                .unwrap_or_else(|_| path.to_path_buf())
        }
        _ => path.to_path_buf(),
    }
}

/// An error about `path` that names it.
fn about(path: &Path, e: Error) -> Error {
    Error::new(e.kind(), format!("{}: {e}", path.display()))
}

/// Refuses a folder target that is neither a folder nor missing (a symbolic link, a file).
fn check_folder_target(target: &Path) -> Result<()> {
    match std::fs::symlink_metadata(target) {
        Ok(m) if m.is_dir() => Ok(()),
        Ok(m) if m.file_type().is_symlink() => Err(Error::new(
            ErrorKind::InvalidInput,
            format!(
                "{} is a symbolic link; refusing to replace it (name the folder itself)",
                target.display()
            ),
        )),
        Ok(_) => Err(Error::new(
            ErrorKind::AlreadyExists,
            format!(
                "{} exists and is not a directory: an output folder is needed here",
                target.display()
            ),
        )),
        Err(e) if e.kind() == ErrorKind::NotFound => Ok(()),
        Err(e) => Err(about(target, e)),
    }
}

/// Keeps the old version of a regular file `target` beside it (a hard link, or a copy).
fn keep_old(target: &Path) -> Result<PathBuf> {
    let backup = temp_beside(target);
    if std::fs::hard_link(target, &backup).is_err() {
        std::fs::copy(target, &backup)?;
    }
    track(&backup, Pending::File);
    Ok(backup)
}

impl Transaction {
    /// An empty transaction.
    pub fn new() -> Transaction {
        Transaction::default()
    }

    /// The targets staged so far, in staging order.
    pub fn targets(&self) -> impl Iterator<Item = &Path> {
        self.staged.iter().map(|s| s.target.as_path())
    }

    /// Refuses a second output to the same target.
    fn refuse_twice(&self, target: &Path) -> Result<()> {
        let k = key(target);
        if self.staged.iter().any(|s| key(&s.target) == k) {
            return Err(Error::new(
                ErrorKind::AlreadyExists,
                format!(
                    "{} is written twice by this command (two of its outputs name the same file)",
                    target.display()
                ),
            ));
        }
        Ok(())
    }

    /// Creates the output folder `dir` and its missing parents now; the folders it creates
    /// are removed again, when empty, unless the transaction is committed. A path on the way
    /// that is not a directory is an error that names it ([`super::create_dir`]).
    pub fn create_dir(&mut self, dir: &Path) -> Result<()> {
        let missing: Vec<PathBuf> = dir
            .ancestors()
            .take_while(|a| !a.as_os_str().is_empty() && !a.exists())
            .map(Path::to_path_buf)
            .collect();
        super::create_dir(dir)?;
        for d in missing.into_iter().rev() {
            track(&d, Pending::EmptyDir);
            self.made.push(d);
        }
        Ok(())
    }

    /// Stages `bytes` for `path` (its folder must exist): a temporary file beside it now,
    /// renamed over it at commit; a character device or FIFO gets the bytes at commit.
    pub fn write(&mut self, path: &Path, bytes: impl AsRef<[u8]>) -> Result<()> {
        self.refuse_twice(path)?;
        if destination(path)? == Destination::WriteThrough {
            self.staged.push(Staged {
                target: path.to_path_buf(),
                kind: Kind::Through(bytes.as_ref().to_vec()),
            });
            return Ok(());
        }
        let mut f = AtomicFile::create(path)?;
        f.write_all(bytes.as_ref())?;
        self.add(f)
    }

    /// Takes a file written in pieces ([`AtomicFile::create`], then written) into the
    /// transaction: its temporary file is renamed at commit instead of by
    /// [`AtomicFile::commit`]. (A device or FIFO has had its bytes already.)
    pub fn add(&mut self, file: AtomicFile) -> Result<()> {
        self.refuse_twice(file.path())?;
        let (target, tmp) = file.into_staged()?;
        let kind = match tmp {
            Some(tmp) => Kind::File(tmp),
            None => Kind::Done,
        };
        self.staged.push(Staged { target, kind });
        Ok(())
    }

    /// Stages a whole folder: returns a fresh scratch folder beside `target`, to be filled,
    /// that replaces the folder `target` (or takes its missing place) at commit. The folder
    /// holding `target` must exist.
    pub fn dir(&mut self, target: &Path) -> Result<PathBuf> {
        self.refuse_twice(target)?;
        check_folder_target(target)?;
        let tmp = temp_beside(target);
        std::fs::create_dir(&tmp).map_err(|e| about(&tmp, e))?;
        track(&tmp, Pending::Dir);
        self.staged.push(Staged {
            target: target.to_path_buf(),
            kind: Kind::Dir(tmp.clone()),
        });
        Ok(tmp)
    }

    /// A fresh, empty scratch folder inside the existing folder `dir`, for a library that
    /// writes files by itself: write them there, then [`Transaction::adopt`] each. Removed
    /// with what is left in it when the transaction ends, committed or not.
    pub fn scratch_in(&mut self, dir: &Path) -> Result<PathBuf> {
        let tmp = temp_beside(&dir.join("staged"));
        std::fs::create_dir(&tmp).map_err(|e| about(&tmp, e))?;
        track(&tmp, Pending::Dir);
        self.scratch.push(tmp.clone());
        Ok(tmp)
    }

    /// Stages the complete file `written` (in a [`Transaction::scratch_in`] folder on the
    /// file system of `target`) to be renamed over `target` at commit.
    pub fn adopt(&mut self, target: &Path, written: &Path) -> Result<()> {
        self.refuse_twice(target)?;
        let kind = match destination(target)? {
            Destination::Replace => Kind::File(written.to_path_buf()),
            Destination::WriteThrough => {
                Kind::Through(std::fs::read(written).map_err(|e| about(written, e))?)
            }
        };
        self.staged.push(Staged {
            target: target.to_path_buf(),
            kind,
        });
        Ok(())
    }

    /// Checks a staged target again just before the commit.
    fn recheck(s: &Staged) -> Result<()> {
        match &s.kind {
            Kind::Dir(_) => check_folder_target(&s.target),
            Kind::File(_) => match destination(&s.target)? {
                Destination::Replace => Ok(()),
                Destination::WriteThrough => Err(Error::new(
                    ErrorKind::InvalidInput,
                    format!(
                        "{} became a device or FIFO while this command ran; refusing to replace it",
                        s.target.display()
                    ),
                )),
            },
            Kind::Through(_) | Kind::Done => Ok(()),
        }
    }

    /// Renames staged output `s` over its target, keeping what it replaces.
    fn replace(s: &Staged) -> Result<Undo> {
        let target = &s.target;
        let exists = std::fs::symlink_metadata(target).is_ok();
        match &s.kind {
            Kind::Through(_) | Kind::Done => Ok(Undo::Nothing),
            Kind::File(tmp) => {
                let backup = if exists {
                    Some(keep_old(target)?)
                } else {
                    None
                };
                if let Err(e) = std::fs::rename(tmp, target) {
                    if let Some(b) = &backup {
                        let _ = std::fs::remove_file(b);
                        untrack(b);
                    }
                    return Err(e);
                }
                untrack(tmp);
                Ok(match backup {
                    Some(backup) => Undo::Replaced {
                        target: target.clone(),
                        backup,
                        dir: false,
                    },
                    None => Undo::Created {
                        target: target.clone(),
                        dir: false,
                    },
                })
            }
            Kind::Dir(tmp) => {
                if !exists {
                    std::fs::rename(tmp, target)?;
                    untrack(tmp);
                    return Ok(Undo::Created {
                        target: target.clone(),
                        dir: true,
                    });
                }
                let backup = temp_beside(target);
                std::fs::rename(target, &backup)?;
                if let Err(e) = std::fs::rename(tmp, target) {
                    let _ = std::fs::rename(&backup, target);
                    return Err(e);
                }
                untrack(tmp);
                // (registered only now: removing it on Ctrl-C loses nothing, the new one is in)
                track(&backup, Pending::Dir);
                Ok(Undo::Replaced {
                    target: target.clone(),
                    backup,
                    dir: true,
                })
            }
        }
    }

    /// Publishes every staged output (module documentation: checked again, devices and
    /// FIFOs first, then the renames, undone if one fails). On an error every target holds
    /// what it held before, and the error names the target.
    pub fn commit(mut self) -> Result<()> {
        for s in &self.staged {
            Self::recheck(s)?;
        }
        for s in &mut self.staged {
            if let Kind::Through(bytes) = &s.kind {
                let mut f = open_through(&s.target).map_err(|e| about(&s.target, e))?;
                f.write_all(bytes)
                    .and_then(|()| f.flush())
                    .map_err(|e| about(&s.target, e))?;
                s.kind = Kind::Done;
            }
        }
        let mut done = Vec::with_capacity(self.staged.len());
        for s in &self.staged {
            match Self::replace(s) {
                Ok(u) => done.push(u),
                Err(e) => {
                    for u in done.into_iter().rev() {
                        u.undo();
                    }
                    return Err(about(&s.target, e));
                }
            }
        }
        for u in done {
            u.forget();
        }
        self.staged.clear();
        for d in std::mem::take(&mut self.made) {
            untrack(&d);
        }
        Ok(())
    }
}

impl Drop for Transaction {
    /// Not committed (or the commit failed and was undone): every temporary goes, and every
    /// output folder created for it, when empty.
    fn drop(&mut self) {
        for s in self.staged.drain(..) {
            match s.kind {
                Kind::File(tmp) => {
                    let _ = std::fs::remove_file(&tmp);
                    untrack(&tmp);
                }
                Kind::Dir(tmp) => {
                    remove_tree(&tmp);
                    untrack(&tmp);
                }
                Kind::Through(_) | Kind::Done => {}
            }
        }
        for d in self.scratch.drain(..) {
            remove_tree(&d);
            untrack(&d);
        }
        for d in self.made.drain(..).rev() {
            let _ = std::fs::remove_dir(&d);
            untrack(&d);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("crane-tx-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn nothing_is_published_before_the_commit_and_everything_after() {
        let d = dir("commit");
        std::fs::write(d.join("a.toml"), "old a").unwrap();
        let mut tx = Transaction::new();
        tx.write(&d.join("a.toml"), "new a").unwrap();
        tx.create_dir(&d.join("plots/deep")).unwrap();
        tx.write(&d.join("plots/deep/b.svg"), "new b").unwrap();
        let mut f = AtomicFile::create(&d.join("c.csv")).unwrap();
        f.write_all(b"t,x\n").unwrap();
        tx.add(f).unwrap();
        assert_eq!(std::fs::read_to_string(d.join("a.toml")).unwrap(), "old a");
        assert!(!d.join("c.csv").exists() && !d.join("plots/deep/b.svg").exists());
        tx.commit().unwrap();
        assert_eq!(std::fs::read_to_string(d.join("a.toml")).unwrap(), "new a");
        assert_eq!(
            std::fs::read_to_string(d.join("plots/deep/b.svg")).unwrap(),
            "new b"
        );
        assert_eq!(std::fs::read_to_string(d.join("c.csv")).unwrap(), "t,x\n");
        assert_eq!(
            names(&d),
            ["a.toml", "c.csv", "plots"],
            "a temporary was left"
        );
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn dropped_uncommitted_it_leaves_everything_as_it_was() {
        let d = dir("drop");
        std::fs::write(d.join("a.toml"), "old a").unwrap();
        {
            let mut tx = Transaction::new();
            tx.write(&d.join("a.toml"), "new a").unwrap();
            tx.create_dir(&d.join("plots/deep")).unwrap();
            tx.write(&d.join("plots/deep/b.svg"), "b").unwrap();
            let ds = tx.dir(&d.join("dataset")).unwrap();
            std::fs::write(ds.join("run.csv"), "t").unwrap();
            let s = tx.scratch_in(&d).unwrap();
            std::fs::write(s.join("p.svg"), "p").unwrap();
            tx.adopt(&d.join("p.svg"), &s.join("p.svg")).unwrap();
            // an error on the way: dropped
        }
        assert_eq!(std::fs::read_to_string(d.join("a.toml")).unwrap(), "old a");
        assert_eq!(names(&d), ["a.toml"], "left behind");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_target_that_changed_since_staging_stops_the_commit_before_any_rename() {
        let d = dir("recheck");
        std::fs::write(d.join("a.toml"), "old a").unwrap();
        let mut tx = Transaction::new();
        tx.write(&d.join("a.toml"), "new a").unwrap();
        tx.write(&d.join("b.svg"), "new b").unwrap();
        std::fs::create_dir(d.join("b.svg")).unwrap();
        let e = tx.commit().unwrap_err();
        assert!(
            e.to_string().contains("b.svg") && e.to_string().contains("directory"),
            "{e}"
        );
        assert_eq!(std::fs::read_to_string(d.join("a.toml")).unwrap(), "old a");
        assert_eq!(names(&d), ["a.toml", "b.svg"]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_failed_rename_undoes_the_ones_before() {
        let d = dir("undo");
        std::fs::write(d.join("a.toml"), "old a").unwrap();
        std::fs::create_dir(d.join("ds")).unwrap();
        std::fs::write(d.join("ds/old.csv"), "old run").unwrap();
        let mut tx = Transaction::new();
        tx.write(&d.join("a.toml"), "new a").unwrap();
        tx.write(&d.join("new.txt"), "new").unwrap();
        let ds = tx.dir(&d.join("ds")).unwrap();
        std::fs::write(ds.join("new.csv"), "new run").unwrap();
        tx.write(&d.join("c.svg"), "new c").unwrap();
        // the last temporary vanishes behind the transaction's back: its rename fails
        let tmp = names(&d)
            .into_iter()
            .find(|n| n.starts_with(".c.svg.tmp-"))
            .unwrap();
        std::fs::remove_file(d.join(tmp)).unwrap();
        let e = tx.commit().unwrap_err();
        assert!(e.to_string().contains("c.svg"), "{e}");
        assert_eq!(std::fs::read_to_string(d.join("a.toml")).unwrap(), "old a");
        assert_eq!(names(&d.join("ds")), ["old.csv"]);
        assert_eq!(names(&d), ["a.toml", "ds"], "not undone, or left behind");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_folder_is_replaced_whole_and_one_target_is_staged_once() {
        let d = dir("folder");
        std::fs::create_dir(d.join("ds")).unwrap();
        std::fs::write(d.join("ds/old.csv"), "old").unwrap();
        let mut tx = Transaction::new();
        let ds = tx.dir(&d.join("ds")).unwrap();
        std::fs::write(ds.join("new.csv"), "new").unwrap();
        let e = tx.write(&d.join("./ds"), "x").unwrap_err();
        assert!(e.to_string().contains("twice"), "{e}");
        tx.commit().unwrap();
        assert_eq!(names(&d.join("ds")), ["new.csv"]);
        assert_eq!(names(&d), ["ds"]);
        // a file where the folder goes is refused when staged
        std::fs::write(d.join("f"), "a file").unwrap();
        let e = Transaction::new().dir(&d.join("f")).unwrap_err();
        assert!(e.to_string().contains("not a directory"), "{e}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn a_failing_device_replaces_nothing() {
        if !Path::new("/dev/full").exists() {
            return;
        }
        let d = dir("device");
        std::fs::write(d.join("a.toml"), "old a").unwrap();
        let mut tx = Transaction::new();
        tx.write(&d.join("a.toml"), "new a").unwrap();
        tx.write(Path::new("/dev/full"), "report").unwrap();
        let e = tx.commit().unwrap_err();
        assert!(e.to_string().contains("/dev/full"), "{e}");
        assert_eq!(std::fs::read_to_string(d.join("a.toml")).unwrap(), "old a");
        assert_eq!(names(&d), ["a.toml"]);
        std::fs::remove_dir_all(&d).unwrap();
    }
}
