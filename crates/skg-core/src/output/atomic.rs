//! Atomic writes: a temporary file `.skg-tmp-<pid>-…` beside the target, flushed,
//! synced and renamed over it ([`write_atomic`], [`write_csv`], [`write_json`]); the
//! temporaries of killed runs are removed by the next write in their directory
//! ([`remove_stale_temporaries`]); [`temporary_beside`] names one for a file that another
//! program writes.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::Serialize;
use sha2::{Digest, Sha256};

use super::pairing::DataFile;
use super::{io_err, OutputError, TEMP_PREFIX};
use crate::scene::provenance;

/// The prefix of this process's temporary files: `.skg-tmp-<pid>-`.
pub(super) fn temp_prefix() -> String {
    format!("{TEMP_PREFIX}{}-", std::process::id())
}

/// Whether a temporary file's name says it belongs to a process that no longer runs:
/// `.skg-tmp-<pid>-…` with no such process (or a name without a pid).
fn is_stale_temporary(name: &str) -> bool {
    let Some(rest) = name.strip_prefix(TEMP_PREFIX) else { return false };
    match rest.split('-').next().and_then(|pid| pid.parse::<u32>().ok()) {
        Some(pid) => pid != std::process::id() && !process_is_running(pid),
        None => true,
    }
}

/// Whether a process with this id runs (on Linux: `/proc/<pid>/stat` exists and is not
/// a zombie's, which stays listed until someone reaps it; elsewhere assumed, so nothing
/// is removed).
fn process_is_running(pid: u32) -> bool {
    if !cfg!(target_os = "linux") {
        return true;
    }
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        // `pid (comm) S …`: the state follows the last `)`.
        Ok(stat) => stat.rsplit_once(')').is_none_or(|(_, rest)| !matches!(rest.trim_start().chars().next(), Some('Z' | 'X'))),
        Err(_) => false,
    }
}

/// Remove the temporary files in `dir` left by killed runs: `.skg-tmp-<pid>-*` whose
/// process no longer runs (files of running writers are never touched). Best effort:
/// a file that cannot be removed is left. Returns how many were removed.
pub fn remove_stale_temporaries(dir: &Path) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else { return 0 };
    let stale =
        entries.flatten().filter(|e| e.file_type().is_ok_and(|t| t.is_file()) && is_stale_temporary(&e.file_name().to_string_lossy()));
    stale.filter(|e| std::fs::remove_file(e.path()).is_ok()).count()
}

/// A temporary path beside `path` for a file that another library or program writes
/// itself (a picture, a video), to be renamed over `path` when complete. It is named
/// like the temporaries of [`write_atomic`] (`.skg-tmp-<pid>-<file name of path>`, so it
/// ends like `path` for writers that go by the extension), and one left by a kill is
/// removed by the next write in that directory. Creates the directory and removes its
/// stale temporaries first.
pub fn temporary_beside(path: &Path) -> Result<PathBuf, OutputError> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(io_err(dir))?;
    remove_stale_temporaries(dir);
    let name = path.file_name().map_or("file".into(), |n| n.to_string_lossy().into_owned());
    Ok(dir.join(format!("{}{name}", temp_prefix())))
}

/// Write `path` atomically with the bytes produced by `fill`, through a temporary file
/// `.skg-tmp-<pid>-…` beside it; first removes the stale temporary files of killed runs
/// in that directory ([`remove_stale_temporaries`]).
pub fn write_atomic(path: &Path, fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> Result<(), OutputError> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(io_err(&dir))?;
    remove_stale_temporaries(&dir);
    let mut builder = tempfile::Builder::new();
    let prefix = temp_prefix();
    builder.prefix(&prefix);
    // Like any new file (0666 minus the umask), not tempfile's private 0600.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    // tempfile's error repeats the temporary file's path: keep the system's error only.
    let plain = |e: std::io::Error| e.raw_os_error().map_or(e, std::io::Error::from_raw_os_error);
    let mut tmp = builder.tempfile_in(&dir).map_err(|e| io_err(path)(plain(e)))?;
    {
        let mut w = std::io::BufWriter::new(tmp.as_file_mut());
        fill(&mut w).map_err(io_err(path))?;
        w.flush().map_err(io_err(path))?;
    }
    tmp.as_file().sync_all().map_err(io_err(path))?;
    tmp.persist(path).map_err(|e| OutputError::Io { path: path.to_path_buf(), error: e.error })?;
    Ok(())
}

/// A writer that passes bytes through and hashes them.
struct Digesting<'a> {
    inner: &'a mut dyn Write,
    hasher: Sha256,
}

impl Write for Digesting<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hasher.update(&buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// Write a numeric table as CSV, full precision (shortest round-trip representation).
/// Returns its row count and hash, as a summary lists it.
pub fn write_csv(path: &Path, comment: Option<&str>, header: &[String], rows: &[Vec<f64>]) -> Result<DataFile, OutputError> {
    write_table(path, comment, header, rows, false)
}

/// [`write_csv`] with each NaN written as an empty cell: a table with gaps (a fit's
/// data where a coordinate was not observed), which a fit's data file and pandas read
/// back as gaps.
pub fn write_csv_with_gaps(path: &Path, comment: Option<&str>, header: &[String], rows: &[Vec<f64>]) -> Result<DataFile, OutputError> {
    write_table(path, comment, header, rows, true)
}

fn write_table(path: &Path, comment: Option<&str>, header: &[String], rows: &[Vec<f64>], gaps: bool) -> Result<DataFile, OutputError> {
    let mut digest = None;
    write_atomic(path, |w| {
        let mut w = Digesting { inner: w, hasher: Sha256::new() };
        if let Some(c) = comment {
            for line in c.lines() {
                writeln!(w, "# {line}")?;
            }
        }
        let mut csv = csv::Writer::from_writer(&mut w);
        csv.write_record(header).map_err(std::io::Error::other)?;
        for row in rows {
            let cell = |x: &f64| if gaps && x.is_nan() { String::new() } else { format!("{x:?}") };
            csv.write_record(row.iter().map(cell)).map_err(std::io::Error::other)?;
        }
        csv.flush()?;
        drop(csv);
        digest = Some(w.hasher.finalize());
        Ok(())
    })?;
    let digest = digest.expect("set when the write succeeded");
    Ok(DataFile { rows: rows.len(), sha256: provenance::hex_digest(&digest) })
}

/// Write a value as pretty JSON.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), OutputError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| OutputError::Format { path: path.to_path_buf(), message: e.to_string() })?;
    write_atomic(path, |w| {
        w.write_all(text.as_bytes())?;
        w.write_all(b"\n")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_leaves_old_file_when_writer_fails() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        std::fs::write(&p, "old").unwrap();
        let r = write_atomic(&p, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("boom"))
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "old");
        // No temporary file is left behind.
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names.len(), 1, "{names:?}");
    }

    #[test]
    fn the_reason_of_a_failed_write_is_said_once() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("file");
        std::fs::write(&file, "").unwrap();
        let e = write_atomic(&file.join("a.txt"), |_| Ok(())).unwrap_err();
        let text = e.to_string();
        assert!(text.starts_with(&format!("cannot write {}: ", file.display())) && text.contains("(os error "), "{text}");
        assert!(std::error::Error::source(&e).is_none(), "{text}");
    }

    #[test]
    fn temporaries_beside_a_file_keep_its_extension_and_are_cleaned_up() {
        let dir = tempfile::tempdir().unwrap();
        let stale = dir.path().join(".skg-tmp-4194304-old.gif");
        std::fs::write(&stale, "left by a kill").unwrap();
        let target = dir.path().join("sub").join("motion.gif");
        let tmp = temporary_beside(&target).unwrap();
        assert_eq!(tmp.parent(), target.parent());
        let name = tmp.file_name().unwrap().to_string_lossy().into_owned();
        assert!(name.starts_with(&temp_prefix()) && name.ends_with("motion.gif"), "{name}");
        assert!(!is_stale_temporary(&name), "this process's own");
        temporary_beside(&dir.path().join("x.png")).unwrap();
        assert!(!stale.exists(), "a dead process's temporary is removed");
    }

    #[test]
    fn temporary_files_of_dead_processes_are_stale() {
        assert!(!is_stale_temporary(&format!("{}x", temp_prefix())), "this process's own");
        assert!(is_stale_temporary(".skg-tmp-4194304-x"), "no pid reaches 2^22 on Linux");
        assert!(is_stale_temporary(".skg-tmp-AbCdEf"), "no pid in the name");
        assert!(!is_stale_temporary("trajectory.csv"));
        assert!(process_is_running(1) || !cfg!(target_os = "linux"), "pid 1 runs");
    }

    #[test]
    fn csv_round_trips_full_precision() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        let x = 0.1 + 0.2;
        write_csv(&p, Some("provenance"), &["t".into(), "x".into()], &[vec![1.0, x]]).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.starts_with("# provenance\nt,x\n"), "{text}");
        let last = text.lines().last().unwrap();
        let v: f64 = last.split(',').nth(1).unwrap().parse().unwrap();
        assert_eq!(v, x);
    }
}
