//! Locked output directories ([`OutputDir`]): an exclusive advisory lock on `.skg-lock`
//! for as long as a command writes there, and files staged in the directory for another
//! library to write.

use std::path::{Path, PathBuf};

use super::atomic::{remove_stale_temporaries, temp_prefix};
use super::{io_err, OutputError, LOCK_FILE};

/// An output directory locked by this process for as long as the value lives.
#[derive(Debug)]
pub struct OutputDir {
    path: PathBuf,
    /// The outermost directory that [`OutputDir::lock`] created (`dir` or an ancestor).
    created: Option<PathBuf>,
    /// Holds the lock; the kernel releases it when the file is closed or the process dies.
    _lock: std::fs::File,
}

impl OutputDir {
    /// Create `dir` if needed and take its lock (or fail with [`OutputError::Busy`]).
    pub fn lock(dir: &Path) -> Result<OutputDir, OutputError> {
        let created = dir.ancestors().take_while(|a| !a.as_os_str().is_empty() && !a.exists()).last().map(Path::to_path_buf);
        std::fs::create_dir_all(dir).map_err(io_err(dir))?;
        let lock_path = dir.join(LOCK_FILE);
        let file = std::fs::OpenOptions::new().create(true).truncate(false).write(true).open(&lock_path).map_err(io_err(&lock_path))?;
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => return Err(OutputError::Busy { dir: dir.to_path_buf() }),
            Err(std::fs::TryLockError::Error(e)) => return Err(io_err(&lock_path)(e)),
        }
        remove_stale_temporaries(dir);
        Ok(OutputDir { path: dir.to_path_buf(), created, _lock: file })
    }

    /// Release the lock of a run that wrote nothing (an input error found late): the
    /// directories that [`OutputDir::lock`] created are removed again if they hold
    /// nothing but the lock file.
    pub fn abandon(self) {
        let Some(outermost) = &self.created else { return };
        let _ = std::fs::remove_file(self.path.join(LOCK_FILE));
        for dir in self.path.ancestors() {
            if std::fs::remove_dir(dir).is_err() || dir == outermost {
                break;
            }
        }
    }

    /// A temporary path in this directory for a file that another library writes
    /// directly (Ipopt's log), to be moved over `target` by [`OutputDir::commit`]; a kill
    /// before that leaves the old `target` complete and the temporary file to the next
    /// run's cleanup.
    pub fn staged(&self, target: &Path) -> PathBuf {
        let name = target.file_name().map_or("file".into(), |n| n.to_string_lossy().into_owned());
        self.path.join(format!("{}log-{name}", temp_prefix()))
    }

    /// Move a staged file over its target (nothing to do if it was never created).
    pub fn commit(&self, staged: &Path, target: &Path) -> Result<(), OutputError> {
        if !staged.exists() {
            return Ok(());
        }
        if let Some(parent) = target.parent() {
            std::fs::create_dir_all(parent).map_err(io_err(parent))?;
        }
        std::fs::rename(staged, target).map_err(io_err(target))
    }
}
