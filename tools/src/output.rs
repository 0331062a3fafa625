//! Where the command line writes. Every output goes through [`Outputs`]: it is written
//! atomically (temporary file in the same directory, then rename: [`crane_ident::atomic`]),
//! and it never replaces an input of the command or a file of an existing data set (a
//! directory holding `dataset.toml`) unless the user passed `--force`.

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
    /// Two outputs of one command are the same file.
    #[error("{out}: {why}")]
    Clash {
        /// The output path.
        out: PathBuf,
        /// What collides.
        why: &'static str,
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

/// The output policy of one command: its inputs, and whether `--force` was given.
#[derive(Clone, Debug, Default)]
pub struct Outputs {
    inputs: Vec<PathBuf>,
    force: bool,
}

impl Outputs {
    /// A policy; `force` lets outputs replace inputs and data set files.
    pub fn new(force: bool) -> Self {
        Outputs {
            inputs: Vec::new(),
            force,
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

    /// Checks `out` ([`Outputs::check`]), creates its directory and writes `bytes`
    /// atomically.
    pub fn write(&self, out: &Path, bytes: impl AsRef<[u8]>) -> Result<(), OutputError> {
        self.check(out)?;
        create_parent(out)?;
        crane_ident::atomic::write(out, bytes).map_err(|source| OutputError::Io {
            path: out.to_path_buf(),
            source,
        })
    }
}

/// Creates the directory `out` will be written in.
pub fn create_parent(out: &Path) -> Result<(), OutputError> {
    match out.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => {
            crane_ident::atomic::create_dir(dir).map_err(|source| OutputError::Io {
                path: dir.to_path_buf(),
                source,
            })
        }
        _ => Ok(()),
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
        Outputs::new(false).write(&p, "one").unwrap();
        Outputs::new(false).write(&p, "two").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "two");
        assert_eq!(std::fs::read_dir(d.join("a/b")).unwrap().count(), 1);
        std::fs::remove_dir_all(&d).unwrap();
    }
}
