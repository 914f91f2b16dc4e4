//! Output files: the trajectory CSV and the JSON summary of a solve, the CSV of a
//! reference, each written atomically (a temporary file in the target directory,
//! flushed, then renamed over the target), so an interrupted or failed run never leaves
//! a half-written file. The end of the data flow: it reads what [`crate::solve`] and
//! [`crate::reference`] produced and writes it.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::provenance;
use crate::reference::{self, Reference};
use crate::scenario::Scene;
use crate::solve::Outcome;
use crate::trajectory::{trajectory_header, trajectory_rows};

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
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError::Io { path: path.to_path_buf(), source }
}

/// Write `path` atomically with the bytes produced by `fill`.
pub fn write_atomic(path: &Path, fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> Result<(), OutputError> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(io_err(&dir))?;
    let mut builder = tempfile::Builder::new();
    builder.prefix(".skg-tmp-");
    // Like any new file (0666 minus the umask), not tempfile's private 0600.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let mut tmp = builder.tempfile_in(&dir).map_err(io_err(path))?;
    {
        let mut w = std::io::BufWriter::new(tmp.as_file_mut());
        fill(&mut w).map_err(io_err(path))?;
        w.flush().map_err(io_err(path))?;
    }
    tmp.as_file().sync_all().map_err(io_err(path))?;
    tmp.persist(path).map_err(|e| OutputError::Io { path: path.to_path_buf(), source: e.error })?;
    Ok(())
}

/// Write a numeric table as CSV, full precision (shortest round-trip representation).
pub fn write_csv(path: &Path, comment: Option<&str>, header: &[String], rows: &[Vec<f64>]) -> Result<(), OutputError> {
    write_atomic(path, |w| {
        if let Some(c) = comment {
            for line in c.lines() {
                writeln!(w, "# {line}")?;
            }
        }
        let mut csv = csv::Writer::from_writer(w);
        csv.write_record(header).map_err(std::io::Error::other)?;
        for row in rows {
            csv.write_record(row.iter().map(|x| format!("{x:?}"))).map_err(std::io::Error::other)?;
        }
        csv.flush()?;
        Ok(())
    })
}

/// Write a value as pretty JSON.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), OutputError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| OutputError::Format { path: path.to_path_buf(), message: e.to_string() })?;
    write_atomic(path, |w| {
        w.write_all(text.as_bytes())?;
        w.write_all(b"\n")
    })
}

/// What `summary.json` holds: where it came from ([`crate::provenance`]), then the
/// fields of the [`Outcome`].
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
    #[serde(flatten)]
    outcome: &'a Outcome,
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
}

impl Written {
    /// Every file written, in the order written.
    pub fn paths(&self) -> impl Iterator<Item = &PathBuf> {
        std::iter::once(&self.trajectory).chain(&self.reference).chain(std::iter::once(&self.summary))
    }
}

fn summary<'a>(outcome: &'a Outcome, scene: &Scene) -> Summary<'a> {
    Summary {
        skg_solve_version: provenance::VERSION,
        schema_version: provenance::SCHEMA_VERSION,
        scene_hash: scene.file.origin.content_hash(),
        scene_file: scene.file.origin.path.clone(),
        outcome,
    }
}

/// The content of `summary.json` of a solve of `scene` (as [`write_outcome`] writes it),
/// as a JSON value.
pub fn summary_json(outcome: &Outcome, scene: &Scene) -> Result<serde_json::Value, serde_json::Error> {
    serde_json::to_value(summary(outcome, scene))
}

/// Write `trajectory.csv`, `reference.csv` (the verification's reference, when there is
/// one; a stale one is removed) and, last, `summary.json` of a solve of `scene` into `dir`.
pub fn write_outcome(dir: &Path, outcome: &mut Outcome, scene: &Scene) -> Result<Written, OutputError> {
    let t = std::time::Instant::now();
    let csv_path = dir.join("trajectory.csv");
    let json_path = dir.join("summary.json");
    let reference_path = dir.join("reference.csv");
    let header = trajectory_header(scene);
    write_csv(&csv_path, None, &header, &trajectory_rows(&outcome.trajectory))?;
    let reference = match &outcome.verification.reference_trajectory {
        Some(r) => {
            let comment = format!(
                "skg-solve {} verification reference of {}: {}",
                provenance::VERSION,
                scene.file.origin.path,
                outcome.verification.reference
            );
            write_csv(&reference_path, Some(&comment), &header, &trajectory_rows(r))?;
            Some(reference_path)
        }
        None => {
            match std::fs::remove_file(&reference_path) {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(io_err(&reference_path)(e)),
            }
            None
        }
    };
    outcome.timings.output_s = t.elapsed().as_secs_f64();
    write_json(&json_path, &summary(outcome, scene))?;
    Ok(Written { trajectory: csv_path, reference, summary: json_path })
}

/// Write a reference as a trajectory CSV with its provenance ([`reference::provenance`])
/// as `#` lines; `scene_path` is the scene file as the user named it.
pub fn write_reference(path: &Path, scene: &Scene, scene_path: &str, r: &Reference) -> Result<(), OutputError> {
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
