//! Where the command line writes. Every output of a command goes through its [`Outputs`]:
//! - it never replaces an input of the command or a file of an existing data set (a
//!   directory holding `dataset.toml`) unless the user passed `--force`, and never anything
//!   but a regular file, a device, a FIFO or a missing path ([`crane_ident::atomic`]);
//! - it is checked and staged beside its target when the command produces it
//!   ([`Outputs::stage`]), and all the outputs of the command are published together by
//!   [`Outputs::commit`] at its end ([`crane_ident::atomic::Transaction`]): a command that
//!   fails, on any output or in its work, leaves every earlier output as it was.

use crane_ident::atomic::{AtomicFile, Transaction};
use crane_ident::data::DATASET_FILE;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why an output was refused or failed.
#[derive(Debug, Error)]
pub enum OutputError {
    /// The output is one of the command's inputs.
    #[error("{out} is an input of this command; refusing to replace it (choose another output, or pass --force)")]
    ReplacesInput {
        /// The output path.
        out: PathBuf,
    },
    /// The output would replace a file of an existing data set (or the data set itself).
    #[error("{out} would replace a file of the data set in {dataset}; refusing (choose another output, or pass --force)")]
    ReplacesDataset {
        /// The output path.
        out: PathBuf,
        /// The data set directory.
        dataset: PathBuf,
    },
    /// The output would replace an SVG file the command line did not write (a user's own
    /// figure of the same name).
    #[error("{out} was not written by crane; refusing to replace it with a plot (choose another output folder or file, or pass --force)")]
    ForeignPlot {
        /// The output path.
        out: PathBuf,
    },
    /// Two outputs of one command are the same file.
    #[error("{out}: {why}")]
    Clash {
        /// The output path.
        out: PathBuf,
        /// What collides.
        why: &'static str,
    },
    /// Publishing the staged outputs failed; every target holds what it held before.
    #[error("{cause} (so no output of this command was written: each is as it was)")]
    Commit {
        /// Why (names the output).
        cause: std::io::Error,
    },
    /// Creating a directory or writing failed.
    #[error("write {path}")]
    Io {
        /// The path being written.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

/// An absolute, normalised form of `p` for comparisons (canonical when it exists; its
/// canonical parent and its name when only the parent exists).
pub fn normalise(p: &Path) -> PathBuf {
    if let Ok(c) = p.canonicalize() {
        return c;
    }
    let abs = if p.is_absolute() {
        p.to_path_buf()
    } else {
        std::env::current_dir().unwrap_or_default().join(p)
    };
    match (abs.parent(), abs.file_name()) {
        (Some(dir), Some(name)) => match dir.canonicalize() {
            Ok(d) => d.join(name),
            Err(_) => abs,
        },
        _ => abs,
    }
}

/// Whether `dir` is a data set directory (holds `dataset.toml`).
pub fn is_dataset(dir: &Path) -> bool {
    dir.join(DATASET_FILE).is_file()
}

/// The outputs of one command: its policy (its inputs, and whether `--force` was given) and
/// the outputs staged so far, published together by [`Outputs::commit`] (module
/// documentation). Dropped uncommitted, it removes what it staged and changes nothing.
#[derive(Debug, Default)]
pub struct Outputs {
    inputs: Vec<PathBuf>,
    force: bool,
    staged: Transaction,
}

impl Outputs {
    /// A policy; `force` lets outputs replace inputs and data set files.
    pub fn new(force: bool) -> Self {
        Outputs {
            inputs: Vec::new(),
            force,
            staged: Transaction::new(),
        }
    }

    /// Records an input file of the command.
    pub fn input(mut self, p: &Path) -> Self {
        self.inputs.push(normalise(p));
        self
    }

    /// Whether `--force` was given.
    pub fn force(&self) -> bool {
        self.force
    }

    /// Refuses `out` if it is an input, or an existing file (or `dataset.toml`) of a data set
    /// directory; `--force` lifts both.
    /// Also refuses, `--force` or not, a destination that is not a regular file, a device,
    /// a FIFO or a missing path (a symbolic link, a directory: [`crane_ident::atomic`]).
    pub fn check(&self, out: &Path) -> Result<(), OutputError> {
        self.policy(out)?;
        crane_ident::atomic::destination(out)
            .map(|_| ())
            .map_err(|source| OutputError::Io {
                path: out.to_path_buf(),
                source,
            })
    }

    /// The input and data set rules of [`Outputs::check`].
    fn policy(&self, out: &Path) -> Result<(), OutputError> {
        if self.force {
            return Ok(());
        }
        let n = normalise(out);
        if self.inputs.contains(&n) {
            return Err(OutputError::ReplacesInput {
                out: out.to_path_buf(),
            });
        }
        if let Some(dir) = n.parent() {
            let is_spec = n.file_name().is_some_and(|f| f == DATASET_FILE);
            if is_dataset(dir) && (n.exists() || is_spec) {
                return Err(OutputError::ReplacesDataset {
                    out: out.to_path_buf(),
                    dataset: dir.to_path_buf(),
                });
            }
        }
        if n.is_dir() && is_dataset(&n) {
            return Err(OutputError::ReplacesDataset {
                out: out.to_path_buf(),
                dataset: n,
            });
        }
        Ok(())
    }

    /// Refuses an output folder `dir` that exists and is not a directory, before any work
    /// (and [`Outputs::check`]s it).
    pub fn check_dir(&self, dir: &Path) -> Result<(), OutputError> {
        self.policy(dir)?;
        if dir.exists() && !dir.is_dir() {
            return Err(OutputError::Clash {
                out: dir.to_path_buf(),
                why: "exists and is not a directory: an output folder is needed here",
            });
        }
        Ok(())
    }

    /// Checks `out` ([`Outputs::check`]), creates its folder and stages `bytes` for it: the
    /// file appears at [`Outputs::commit`], with every other output of the command.
    pub fn stage(&mut self, out: &Path, bytes: impl AsRef<[u8]>) -> Result<(), OutputError> {
        self.check(out)?;
        self.create_parent(out)?;
        self.staged
            .write(out, bytes)
            .map_err(|source| OutputError::Io {
                path: out.to_path_buf(),
                source,
            })
    }

    /// Stages the SVG plot `svg` of command `command` (`identify`, `validate`, ...) at `out`,
    /// marked as the tool's own ([`crane_diagnose::mark_plot_with`]). An existing file there
    /// that the tool did not write ([`crane_diagnose::is_crane_plot`]: a user's own figure of
    /// the same name) is refused without `--force`; the tool's own plots are replaced.
    pub fn stage_plot(&mut self, out: &Path, command: &str, svg: &str) -> Result<(), OutputError> {
        if !self.force && out.is_file() && !crane_diagnose::is_crane_plot(out) {
            return Err(OutputError::ForeignPlot {
                out: out.to_path_buf(),
            });
        }
        let mark = format!("<!-- written by crane {command} -->");
        self.stage(out, crane_diagnose::mark_plot_with(svg, &mark))
    }

    /// Checks `out` and creates its folder; returns a file to write in pieces, to be handed
    /// back with [`Outputs::stage_file`].
    pub fn create(&mut self, out: &Path) -> Result<AtomicFile, OutputError> {
        self.check(out)?;
        self.create_parent(out)?;
        AtomicFile::create(out).map_err(|source| OutputError::Io {
            path: out.to_path_buf(),
            source,
        })
    }

    /// Stages a file made by [`Outputs::create`] and written.
    pub fn stage_file(&mut self, file: AtomicFile) -> Result<(), OutputError> {
        let path = file.path().to_path_buf();
        self.staged
            .add(file)
            .map_err(|source| OutputError::Io { path, source })
    }

    /// Stages the folder `out` whole ([`Transaction::dir`]): returns the scratch folder to
    /// fill, which replaces `out` at the commit. Only a folder or a missing path is replaced;
    /// whether an existing data set there may be is the caller's rule (the virtual rig's).
    pub fn stage_dir(&mut self, out: &Path) -> Result<PathBuf, OutputError> {
        self.create_parent(out)?;
        self.staged.dir(out).map_err(|source| OutputError::Io {
            path: out.to_path_buf(),
            source,
        })
    }

    /// A scratch folder in the output folder `dir` (created, checked with
    /// [`Outputs::check_dir`]) for a library that writes its files itself; stage each file
    /// it wrote with [`Outputs::adopt`].
    pub fn scratch_in(&mut self, dir: &Path) -> Result<PathBuf, OutputError> {
        self.check_dir(dir)?;
        let io = |source| OutputError::Io {
            path: dir.to_path_buf(),
            source,
        };
        self.staged.create_dir(dir).map_err(io)?;
        self.staged.scratch_in(dir).map_err(io)
    }

    /// Stages the file `written` (in a [`Outputs::scratch_in`] folder) for `out`, after
    /// checking `out`.
    pub fn adopt(&mut self, out: &Path, written: &Path) -> Result<(), OutputError> {
        self.check(out)?;
        self.staged
            .adopt(out, written)
            .map_err(|source| OutputError::Io {
                path: out.to_path_buf(),
                source,
            })
    }

    /// Creates the folder `out` will be written in (removed again, when empty, if the
    /// command fails).
    fn create_parent(&mut self, out: &Path) -> Result<(), OutputError> {
        match out.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => {
                self.staged
                    .create_dir(dir)
                    .map_err(|source| OutputError::Io {
                        path: dir.to_path_buf(),
                        source,
                    })
            }
            _ => Ok(()),
        }
    }

    /// Publishes every staged output together, or none ([`Transaction::commit`]); returns
    /// their paths in staging order.
    pub fn commit(self) -> Result<Vec<PathBuf>, OutputError> {
        let written: Vec<PathBuf> = self.staged.targets().map(Path::to_path_buf).collect();
        self.staged
            .commit()
            .map_err(|cause| OutputError::Commit { cause })?;
        Ok(written)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("crane-output-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn refuses_inputs_and_data_set_files_unless_forced() {
        let d = tmp("policy");
        let ds = d.join("ds");
        std::fs::create_dir_all(&ds).unwrap();
        std::fs::write(ds.join(DATASET_FILE), "x").unwrap();
        std::fs::write(ds.join("run.csv"), "t").unwrap();
        let input = d.join("params.toml");
        std::fs::write(&input, "p").unwrap();
        let o = Outputs::new(false).input(&input);
        assert!(matches!(
            o.check(&input),
            Err(OutputError::ReplacesInput { .. })
        ));
        // the same file by another spelling
        let other = d.join(".").join("params.toml");
        assert!(o.check(&other).is_err());
        for p in [ds.join(DATASET_FILE), ds.join("run.csv"), ds.clone()] {
            assert!(
                matches!(o.check(&p), Err(OutputError::ReplacesDataset { .. })),
                "{}",
                p.display()
            );
        }
        assert!(o.check(&ds.join("new.toml")).is_ok());
        assert!(o.check(&d.join("out.toml")).is_ok());
        let f = Outputs::new(true).input(&input);
        assert!(f.check(&input).is_ok() && f.check(&ds.join(DATASET_FILE)).is_ok());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn writes_atomically_creating_the_directory() {
        let d = tmp("write");
        let p = d.join("a/b/c.txt");
        for text in ["one", "two"] {
            let mut o = Outputs::new(false);
            o.stage(&p, text).unwrap();
            assert_eq!(o.commit().unwrap(), vec![p.clone()]);
        }
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "two");
        assert_eq!(std::fs::read_dir(d.join("a/b")).unwrap().count(), 1);
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// Issue 22: a command that fails leaves every earlier output as it was, and the folders
    /// it created for its outputs are gone again.
    #[test]
    fn a_failed_command_changes_nothing() {
        let d = tmp("failed");
        let params = d.join("params.toml");
        std::fs::write(&params, "old").unwrap();
        {
            let mut o = Outputs::new(false);
            o.stage(&params, "new").unwrap();
            o.stage(&d.join("plots/x.svg"), "<svg/>").unwrap();
            // a later output is refused: the command ends with an error, uncommitted
            std::fs::create_dir_all(d.join("dir.svg")).unwrap();
            assert!(o.stage(&d.join("dir.svg"), "<svg/>").is_err());
        }
        assert_eq!(std::fs::read_to_string(&params).unwrap(), "old");
        let left: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(left.len(), 2, "{left:?}");
        std::fs::remove_dir_all(&d).unwrap();
    }
}
