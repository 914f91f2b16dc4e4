//! A solve's files and a reference's: `trajectory.csv`, `reference.csv` and
//! `summary.json` written by the pairing rule ([`write_outcome`]), a solve into a locked
//! directory ([`solve_into`]), and a reference CSV with its provenance
//! ([`write_reference`]).

use std::path::{Path, PathBuf};

use indexmap::IndexMap;
use serde::Serialize;

use super::atomic::{write_atomic, write_csv, write_csv_with_gaps, write_json};
use super::lock::OutputDir;
use super::pairing::DataFile;
use super::{io_err, OutputError, REFERENCE_FILE, SUMMARY_FILE, TRAJECTORY_FILE};
use crate::discrete::trajectory::{trajectory_header, trajectory_rows};
use crate::scene::provenance;
use crate::scene::{Scene, SceneError};
use crate::solve::{self, Outcome, SolveError};
use crate::stepping::reference::{self, Reference};

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
    /// Fields of a run beyond a solve's (a fit's `fit`), after the outcome's.
    #[serde(flatten)]
    extra: &'a serde_json::Map<String, serde_json::Value>,
}

/// A CSV table: its header and its rows.
pub type CsvTable = (Vec<String>, Vec<Vec<f64>>);

/// What a run writes beyond a solve's files (a fit's): further CSV data files, listed in
/// `summary.json`'s `files` like the trajectory; further text files, written before the
/// summary; further top-level fields of the summary.
#[derive(Debug, Clone, Default)]
pub struct RunExtras {
    /// CSV files: name, header, rows (a NaN written as an empty cell).
    pub csv: Vec<(&'static str, CsvTable)>,
    /// Text files: name, text.
    pub texts: Vec<(&'static str, String)>,
    /// Fields of the summary, after the outcome's.
    pub fields: serde_json::Map<String, serde_json::Value>,
}

/// No extra fields (a solve's summary).
static NO_FIELDS: std::sync::LazyLock<serde_json::Map<String, serde_json::Value>> = std::sync::LazyLock::new(serde_json::Map::new);

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

fn summary<'a>(
    outcome: &'a Outcome,
    scene: &Scene,
    files: IndexMap<&'static str, DataFile>,
    extra: &'a serde_json::Map<String, serde_json::Value>,
) -> Summary<'a> {
    Summary {
        skg_solve_version: provenance::VERSION,
        schema_version: provenance::SCHEMA_VERSION,
        scene_hash: scene.file.origin.content_hash(),
        scene_file: scene.file.origin.path.clone(),
        files,
        outcome,
        extra,
    }
}

/// The text of `summary.json` of a solve of `scene`: what [`write_outcome`] writes, with
/// the `files` it wrote (an empty map for a solve not written).
pub fn summary_json(outcome: &Outcome, scene: &Scene, written: Option<&Written>) -> Result<String, serde_json::Error> {
    serde_json::to_string_pretty(&summary(outcome, scene, written.map(|w| w.files.clone()).unwrap_or_default(), &NO_FIELDS))
}

/// Write `trajectory.csv`, `reference.csv` (the verification's reference, when there is
/// one; a stale one is removed) and `summary.json` of a solve of `scene` into `dir` by
/// the pairing rule: the old summary is removed first, the summary is written last and
/// lists the two data files.
pub fn write_outcome(dir: &Path, outcome: &mut Outcome, scene: &Scene) -> Result<Written, OutputError> {
    write_outcome_with(dir, outcome, scene, &RunExtras::default())
}

/// [`write_outcome`] with a run's further files and summary fields ([`RunExtras`]):
/// the CSV files after the reference, listed in `files`, then the text files, then the
/// summary with the further fields.
pub fn write_outcome_with(dir: &Path, outcome: &mut Outcome, scene: &Scene, extras: &RunExtras) -> Result<Written, OutputError> {
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
    for (name, (header, rows)) in &extras.csv {
        files.insert(name, write_csv_with_gaps(&dir.join(name), None, header, rows)?);
    }
    for (name, text) in &extras.texts {
        let path = dir.join(name);
        write_atomic(&path, |w| w.write_all(text.as_bytes()))?;
    }
    outcome.timings.output_s = t.elapsed().as_secs_f64();
    write_json(&json_path, &summary(outcome, scene, files.clone(), &extras.fields))?;
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
    refuse_log_over_run_files(scene)?;
    let out = OutputDir::lock(dir)?;
    if let Some(parent) = scene.solver.log_file.as_ref().and_then(|name| name.parent()) {
        if let Err(e) = super::refuse_links(dir, parent) {
            out.abandon();
            return Err(e.into());
        }
    }
    let log = scene.solver.log_file.as_ref().map(|name| (dir.join(name), out.staged(name)));
    scene.solver.ipopt_log = log.as_ref().map(|(_, staged)| staged.clone());
    let outcome = solve::solve_scene_with_progress(scene, progress);
    scene.solver.ipopt_log = None;
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

/// A scene's `log_file` may not name one of the files the solve itself writes in the
/// output directory, nor a path inside one (`summary.json/x`) (the resolution of the scene already confined it to that directory).
fn refuse_log_over_run_files(scene: &Scene) -> Result<(), SolveError> {
    let (Some(name), Some(spanned)) = (&scene.solver.log_file, &scene.file.solver.log_file) else { return Ok(()) };
    let Some(first) = name.components().next().map(|c| Path::new(c.as_os_str())) else { return Ok(()) };
    if [TRAJECTORY_FILE, REFERENCE_FILE, SUMMARY_FILE].iter().any(|f| first == Path::new(f)) {
        let message = format!("solver.log_file may not be {}, which the solve itself writes, nor lie inside it", first.display());
        return Err(SceneError::Invalid { location: scene.file.origin.locate_in(spanned, None), message }.into());
    }
    Ok(())
}

/// Write a reference as a trajectory CSV with its provenance ([`reference::provenance`])
/// as `#` lines; `scene_path` is the scene file as the user named it.
pub fn write_reference(path: &Path, scene: &Scene, scene_path: &str, r: &Reference) -> Result<DataFile, OutputError> {
    let comment = reference::provenance(scene, scene_path, r);
    write_csv(path, Some(&comment), &trajectory_header(scene), &trajectory_rows(&r.trajectory))
}
