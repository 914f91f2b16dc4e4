//! Locked output directories ([`OutputDir`]): an exclusive advisory lock on `.skg-lock`
//! for as long as a command writes there, and files staged in the directory for another
//! library to write.

use std::path::{Path, PathBuf};

use super::atomic::{remove_stale_temporaries, temp_prefix};
use super::{io_err, OutputError, LOCK_FILE};

/// Why `dir`, which exists, cannot be an output directory (the system's "File exists"
/// says neither): a file, or a symbolic link to a file or to nothing.
fn not_a_directory(dir: &Path) -> Option<std::io::Error> {
    let meta = std::fs::symlink_metadata(dir).ok()?;
    let why = if meta.file_type().is_symlink() {
        let target = std::fs::read_link(dir).ok()?;
        let what = if target.exists() || dir.exists() { "not a directory" } else { "does not exist" };
        format!("it is a symbolic link to {}, which {what}", target.display())
    } else if !meta.is_dir() {
        "it exists and is not a directory".into()
    } else {
        return None;
    };
    Some(std::io::Error::other(why))
}

/// Open (or create) the lock file without following a symbolic link in its place.
fn open_lock_file(lock_path: &Path) -> Result<std::fs::File, OutputError> {
    use std::os::unix::fs::OpenOptionsExt;
    let opened = std::fs::OpenOptions::new().create(true).truncate(false).write(true).custom_flags(libc::O_NOFOLLOW).open(lock_path);
    match opened {
        Err(e) if e.raw_os_error() == Some(libc::ELOOP) => Err(OutputError::Symlink { path: lock_path.to_path_buf() }),
        other => other.map_err(io_err(lock_path)),
    }
}

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
        std::fs::create_dir_all(dir).map_err(|e| io_err(dir)(not_a_directory(dir).unwrap_or(e)))?;
        let lock_path = dir.join(LOCK_FILE);
        let file = open_lock_file(&lock_path)?;
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
        if let Ok(relative) = target.strip_prefix(&self.path) {
            super::refuse_links(&self.path, relative.parent().unwrap_or(Path::new("")))?;
        }
        if let Some(parent) = target.parent() {
            std::fs::create_dir_all(parent).map_err(io_err(parent))?;
        }
        std::fs::rename(staged, target).map_err(io_err(target))
    }
}
