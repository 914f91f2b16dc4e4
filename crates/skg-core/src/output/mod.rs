//! Output files: the trajectory CSV and the JSON summary of a solve, the CSV of a
//! reference, each written atomically (a temporary file `.skg-tmp-*` in the target
//! directory, flushed, then renamed over the target), so an interrupted or failed run
//! never leaves a half-written file. The end of the data flow: it reads what
//! [`solve`](crate::solve) and [`reference`](crate::stepping::reference) produced and
//! writes it.
//!
//! **The pairing rule.** A run's files belong together: `summary.json` lists every data
//! file of its run under `files` (name → row count and SHA-256 of the bytes), and it is
//! written last. [`write_outcome`] first removes the old `summary.json`, then writes the
//! data files, then the new summary. So at every moment, also after a kill, a
//! `summary.json` describes exactly the files beside it that it lists; a data file
//! without a summary is the remains of an interrupted run. Every reader of a data file
//! ([`verify_pairing`], which the readers of trajectories call) checks it against the
//! summary beside it and refuses a file that does not belong to it: a `trajectory.csv`
//! or `reference.csv` the summary does not list, a file whose bytes are not the listed
//! ones, and any file of a run whose summary lists a file that is missing. A third file
//! of the same run (a reference beside the trajectory) joins the rule by being listed
//! too. A CSV with no summary beside it is read as it is ([`Pairing::NoSummary`]); the
//! command line warns that it cannot be checked against a run.
//!
//! **Temporary files** are named `.skg-tmp-<pid>-…`; every atomic write first removes
//! those of processes that no longer run in its directory, so the remains of a killed
//! write disappear with the next write there.
//!
//! **Output directories** ([`OutputDir`]): a command that writes a set of files into a
//! directory (a solve, a sweep, a merge) holds an exclusive lock on its `.skg-lock`
//! file for as long as it writes; a second skg-solve writing into the same directory is
//! refused with a message. The lock is `std::fs::File::try_lock` (an advisory `flock`
//! on Unix, released by the kernel when the process dies, so a killed run never leaves
//! a stale lock). Symbolic links inside an output directory are not followed: the lock
//! file is opened with `O_NOFOLLOW`, and a link where a log's directory or a sweep's
//! `points/` would be is refused ([`refuse_links`]), so that a link placed there cannot
//! make a run write elsewhere. (Files that are written by a rename replace a link of
//! their name.)
//!
//! **What it holds**, one part per file: `atomic.rs` (atomic writes, temporary files),
//! `pairing.rs` (the pairing rule's check), `lock.rs` (locked output directories),
//! `solution.rs` (a solve's files and a reference's, a solve into a locked directory).
//!
//! **Place in the flow.** After the solve: it uses [`scene`](crate::scene) (provenance),
//! [`discrete`](crate::discrete) (the CSV layout of a trajectory),
//! [`stepping`](crate::stepping) (references) and [`solve`](crate::solve) (the outcome,
//! [`solve_into`]). Its callers (the comparison with a reference, the command line,
//! sweeps, Python) read and write through it.

mod atomic;
mod lock;
mod pairing;
mod solution;

use std::path::{Path, PathBuf};

pub use atomic::{remove_stale_temporaries, temporary_beside, write_atomic, write_csv, write_csv_with_gaps, write_json};
pub use lock::OutputDir;
pub use pairing::{verify_pairing, DataFile, Pairing};
pub use solution::{
    solve_into, solve_into_with_progress, summary_json, write_outcome, write_outcome_with, write_reference, CsvTable, RunExtras,
    SolveIntoError, Written,
};

/// Why an output file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Creating, writing or renaming the file failed.
    #[error("cannot write {path}: {error}")]
    Io {
        /// The target file or directory.
        path: PathBuf,
        /// Why (part of the message, not its `source`).
        error: std::io::Error,
    },
    /// The value could not be serialized.
    #[error("cannot write {path}: {message}")]
    Format {
        /// The target file.
        path: PathBuf,
        /// The serializer's message.
        message: String,
    },
    /// Another process holds the output directory's lock.
    #[error(
        "another skg-solve is writing into {dir} (it holds {dir}/{LOCK_FILE}): wait for it to finish, or choose another output directory"
    )]
    Busy {
        /// The output directory.
        dir: PathBuf,
    },
    /// A symbolic link where a command would write inside its output directory (a
    /// directory of `log_file`, a sweep's `points/`, the lock file): following it would
    /// write wherever it points.
    #[error(
        "{path} is a symbolic link: skg-solve does not follow links inside an output directory (it would write \
         wherever the link points); remove it, or choose another output directory"
    )]
    Symlink {
        /// The link.
        path: PathBuf,
    },
    /// A data file does not belong to the `summary.json` beside it (the pairing rule).
    #[error("{file}: {message}")]
    Unpaired {
        /// The data file.
        file: PathBuf,
        /// What does not match.
        message: String,
    },
}

/// Name prefix of the temporary files of atomic writes (and of staged logs).
pub const TEMP_PREFIX: &str = ".skg-tmp-";
/// The lock file of an output directory ([`OutputDir`]).
pub const LOCK_FILE: &str = ".skg-lock";
/// A solve's trajectory file.
pub const TRAJECTORY_FILE: &str = "trajectory.csv";
/// A solve's verification reference: the same scene integrated by time stepping at the
/// trajectory's nodes.
pub const REFERENCE_FILE: &str = "reference.csv";
/// A solve's summary, written last ([the pairing rule](self)).
pub const SUMMARY_FILE: &str = "summary.json";

/// Refuse a symbolic link at any of the paths `base/a`, `base/a/b`, … of `relative`'s
/// components ([`OutputError::Symlink`]); paths that do not exist yet are fine. `base`
/// itself may be a link: the user chose it.
pub fn refuse_links(base: &Path, relative: &Path) -> Result<(), OutputError> {
    let mut path = base.to_path_buf();
    for part in relative.components() {
        path.push(part);
        match std::fs::symlink_metadata(&path) {
            Ok(m) if m.file_type().is_symlink() => return Err(OutputError::Symlink { path }),
            Ok(_) => {}
            Err(_) => break,
        }
    }
    Ok(())
}

pub(super) fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |error| OutputError::Io { path: path.to_path_buf(), error }
}
