//! Output files: the trajectory CSV and the JSON summary of a solve, the CSV of a
//! reference, each written atomically (a temporary file `.skg-tmp-*` in the target
//! directory, flushed, then renamed over the target), so an interrupted or failed run
//! never leaves a half-written file. The end of the data flow: it reads what
//! [`crate::solve`] and [`crate::stepping::reference`] produced and writes it.
//!
//! **The pairing rule.** A run's files belong together: `summary.json` lists every data
//! file of its run under `files` (name → row count and SHA-256 of the bytes), and it is
//! written last. [`write_outcome`] first removes the old `summary.json`, then writes the
//! data files, then the new summary. So at every moment, also after a kill, a
//! `summary.json` describes exactly the files beside it that it lists; a data file
//! without a summary is the remains of an interrupted run. Every reader of a data file
//! ([`verify_pairing`], called by [`crate::check::Table::read`]) checks it against the
//! summary beside it and refuses a file that does not belong to it. A third file of the
//! same run (a reference beside the trajectory) joins the rule by being listed too.
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
//! a stale lock).

use std::io::Write;
use std::path::{Path, PathBuf};

use indexmap::IndexMap;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::discrete::trajectory::{trajectory_header, trajectory_rows};
use crate::scene::provenance;
use crate::scene::Scene;
use crate::solve::{self, Outcome, SolveError};
use crate::stepping::reference::{self, Reference};

/// Why an output file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// Creating, writing or renaming the file failed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The target file or directory.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
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

/// The prefix of this process's temporary files: `.skg-tmp-<pid>-`.
fn temp_prefix() -> String {
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

/// What `summary.json` says about one data file of its run.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct DataFile {
    /// Data rows (without comments and the header).
    pub rows: usize,
    /// SHA-256 of the file's bytes, `sha256:<hex>`.
    pub sha256: String,
}

/// The part of `summary.json` a reader needs to check the pairing rule.
#[derive(Deserialize)]
struct ListedFiles {
    #[serde(default)]
    files: Option<IndexMap<String, DataFile>>,
}

/// Check the pairing rule for a data file read as `bytes` from `path`: if a
/// `summary.json` beside it lists the file, the bytes must be the ones it lists. A file
/// that no summary lists (a reference, a copied file, the remains of an interrupted
/// run, a summary written before the rule) passes.
pub fn verify_pairing(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let Some(name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else { return Ok(()) };
    let summary = path.with_file_name(SUMMARY_FILE);
    let text = match std::fs::read_to_string(&summary) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(io_err(&summary)(e)),
    };
    let unpaired = |message: String| OutputError::Unpaired { file: path.to_path_buf(), message };
    let listed = serde_json::from_str::<ListedFiles>(&text)
        .map_err(|e| unpaired(format!("the {} beside it cannot be read ({e}): run the solve again", summary.display())))?;
    let Some(expected) = listed.files.and_then(|mut f| f.swap_remove(&name)) else { return Ok(()) };
    let actual = provenance::content_hash(bytes);
    if actual == expected.sha256 {
        return Ok(());
    }
    Err(unpaired(format!(
        "is not the file that {} describes ({} rows, {}; this file is {actual}): the two come from different runs \
         (a write was interrupted or a file was replaced); run the solve again",
        summary.display(),
        expected.rows,
        expected.sha256
    )))
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

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError::Io { path: path.to_path_buf(), source }
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
    tmp.persist(path).map_err(|e| OutputError::Io { path: path.to_path_buf(), source: e.error })?;
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
            csv.write_record(row.iter().map(|x| format!("{x:?}"))).map_err(std::io::Error::other)?;
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

/// What `summary.json` holds: where it came from ([`crate::scene::provenance`]), the data files
/// of its run ([the pairing rule](self)), then the fields of the [`Outcome`].
#[derive(Serialize)]
struct Summary<'a> {
    /// The skg-solve version that wrote the file.
    skg_solve_version: &'static str,
    /// The version of the file's layout.
    schema_version: u32,
    /// SHA-256 of the scene file's text (`sha256:<hex>`).
    scene_hash: String,
    /// The scene file as the user named it (relative to the directory the solve ran in),
    /// which `plot path` and `animate` read for the walls.
    scene_file: String,
    /// The data files of this run, by name.
    files: IndexMap<&'static str, DataFile>,
    #[serde(flatten)]
    outcome: &'a Outcome,
}

/// Remove a file if it exists.
fn remove_if_present(path: &Path) -> Result<(), OutputError> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(io_err(path)(e)),
        _ => Ok(()),
    }
}

/// The files a solve wrote.
#[derive(Debug, Clone)]
pub struct Written {
    /// `trajectory.csv`.
    pub trajectory: PathBuf,
    /// `reference.csv`: the verification's time-stepping reference at the same nodes
    /// (absent when verification did not compute one).
    pub reference: Option<PathBuf>,
    /// `summary.json`, written last.
    pub summary: PathBuf,
    /// The data files as `summary.json` lists them.
    pub files: IndexMap<&'static str, DataFile>,
}

impl Written {
    /// Every file written, in the order written.
    pub fn paths(&self) -> impl Iterator<Item = &PathBuf> {
        std::iter::once(&self.trajectory).chain(&self.reference).chain(std::iter::once(&self.summary))
    }
}

fn summary<'a>(outcome: &'a Outcome, scene: &Scene, files: IndexMap<&'static str, DataFile>) -> Summary<'a> {
    Summary {
        skg_solve_version: provenance::VERSION,
        schema_version: provenance::SCHEMA_VERSION,
        scene_hash: scene.file.origin.content_hash(),
        scene_file: scene.file.origin.path.clone(),
        files,
        outcome,
    }
}

/// The text of `summary.json` of a solve of `scene`: what [`write_outcome`] writes, with
/// the `files` it wrote (an empty map for a solve not written).
pub fn summary_json(outcome: &Outcome, scene: &Scene, written: Option<&Written>) -> Result<String, serde_json::Error> {
    serde_json::to_string_pretty(&summary(outcome, scene, written.map(|w| w.files.clone()).unwrap_or_default()))
}

/// Write `trajectory.csv`, `reference.csv` (the verification's reference, when there is
/// one; a stale one is removed) and `summary.json` of a solve of `scene` into `dir` by
/// the pairing rule: the old summary is removed first, the summary is written last and
/// lists the two data files.
pub fn write_outcome(dir: &Path, outcome: &mut Outcome, scene: &Scene) -> Result<Written, OutputError> {
    let t = std::time::Instant::now();
    let csv_path = dir.join(TRAJECTORY_FILE);
    let json_path = dir.join(SUMMARY_FILE);
    let reference_path = dir.join(REFERENCE_FILE);
    remove_if_present(&json_path)?;
    let header = trajectory_header(scene);
    let mut files = IndexMap::from([(TRAJECTORY_FILE, write_csv(&csv_path, None, &header, &trajectory_rows(&outcome.trajectory))?)]);
    let reference = match &outcome.verification.reference_trajectory {
        Some(r) => {
            let comment = format!(
                "skg-solve {} verification reference of {}: {}",
                provenance::VERSION,
                scene.file.origin.path,
                outcome.verification.reference
            );
            files.insert(REFERENCE_FILE, write_csv(&reference_path, Some(&comment), &header, &trajectory_rows(r))?);
            Some(reference_path)
        }
        None => {
            remove_if_present(&reference_path)?;
            None
        }
    };
    outcome.timings.output_s = t.elapsed().as_secs_f64();
    write_json(&json_path, &summary(outcome, scene, files.clone()))?;
    Ok(Written { trajectory: csv_path, reference, summary: json_path, files })
}

/// Why [`solve_into`] failed: the solve could not run, or its files not be written.
#[derive(Debug, thiserror::Error)]
pub enum SolveIntoError {
    /// The solve could not be attempted or completed.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The output directory is locked by another process, or a file could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// Solve `scene` and write its files into `dir` as `skg-solve SCENE -o DIR` does: the
/// directory is locked ([`OutputDir`]) for the whole solve; Ipopt writes the scene's
/// `log_file` (relative to `dir`) into a staged file that is moved over the old log when
/// the solve returns, so a killed run leaves the old log complete; the files are written
/// by [`write_outcome`]. A solve that cannot run leaves no directory it created.
pub fn solve_into(dir: &Path, scene: &mut Scene) -> Result<(Outcome, Written), SolveIntoError> {
    solve_into_with_progress(dir, scene, &mut |_| {})
}

/// [`solve_into`], telling `progress` what each attempt of the fallback ladder is about
/// to do.
pub fn solve_into_with_progress(
    dir: &Path,
    scene: &mut Scene,
    progress: &mut dyn FnMut(&str),
) -> Result<(Outcome, Written), SolveIntoError> {
    let out = OutputDir::lock(dir)?;
    let log = scene.solver.log_file.as_ref().map(|name| (dir.join(name), out.staged(name)));
    let named = std::mem::replace(&mut scene.solver.log_file, log.as_ref().map(|(_, staged)| staged.clone()));
    let outcome = solve::solve_scene_with_progress(scene, progress);
    scene.solver.log_file = named;
    if let Some((target, staged)) = &log {
        out.commit(staged, target)?;
    }
    let mut outcome = match outcome {
        Ok(outcome) => outcome,
        Err(e) => {
            out.abandon();
            return Err(e.into());
        }
    };
    let written = write_outcome(dir, &mut outcome, scene)?;
    Ok((outcome, written))
}

/// Write a reference as a trajectory CSV with its provenance ([`reference::provenance`])
/// as `#` lines; `scene_path` is the scene file as the user named it.
pub fn write_reference(path: &Path, scene: &Scene, scene_path: &str, r: &Reference) -> Result<DataFile, OutputError> {
    let comment = reference::provenance(scene, scene_path, r);
    write_csv(path, Some(&comment), &trajectory_header(scene), &trajectory_rows(&r.trajectory))
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
    fn readers_accept_only_the_file_a_summary_lists() {
        let dir = tempfile::tempdir().unwrap();
        let csv = dir.path().join(TRAJECTORY_FILE);
        let listed = write_csv(&csv, None, &["t".into()], &[vec![0.0], vec![1.0]]).unwrap();
        let bytes = std::fs::read(&csv).unwrap();
        assert_eq!(listed, DataFile { rows: 2, sha256: provenance::content_hash(b"t\n0.0\n1.0\n") });
        // No summary, or one that does not list the file (a summary of an older schema): unchecked.
        verify_pairing(&csv, b"anything").unwrap();
        std::fs::write(dir.path().join(SUMMARY_FILE), r#"{"converged": true}"#).unwrap();
        verify_pairing(&csv, b"anything").unwrap();
        let summary = serde_json::json!({ "files": { TRAJECTORY_FILE: listed } });
        std::fs::write(dir.path().join(SUMMARY_FILE), summary.to_string()).unwrap();
        verify_pairing(&csv, &bytes).unwrap();
        let e = verify_pairing(&csv, b"t\n0.0\n2.0\n").unwrap_err().to_string();
        assert!(e.contains("is not the file that") && e.contains("2 rows"), "{e}");
        verify_pairing(&dir.path().join("reference.csv"), b"other").unwrap();
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
