//! A fit's files: a solve's `trajectory.csv` and `reference.csv` (the fitted motion and
//! its verification's time stepping), `data.csv` (the data beside the fitted motion),
//! `fitted.toml` (the scene with the fitted values) and, last, `summary.json` with the
//! `fit` object, by the pairing rule ([`write_fit`]); a fit into a locked directory
//! ([`fit_into`]), as `skg-solve fit` and `skg.fit(out=…)` run it.

use std::path::{Path, PathBuf};

use super::{fit, Data, Fit, FitError, FitSettings};
use crate::output::{self, OutputDir, OutputError, RunExtras, Written, REFERENCE_FILE, SUMMARY_FILE, TRAJECTORY_FILE};
use crate::scene::provenance;
use crate::scene::{Overrides, Scene, SceneError};

/// The data beside the fitted motion.
pub const DATA_FILE: &str = "data.csv";
/// The scene with the fitted values.
pub const FITTED_SCENE_FILE: &str = "fitted.toml";

/// The files a fit wrote.
#[derive(Debug, Clone)]
pub struct FitWritten {
    /// A solve's files (`trajectory.csv`, `reference.csv`, `summary.json`).
    pub written: Written,
    /// `data.csv`.
    pub data: PathBuf,
    /// `fitted.toml`.
    pub fitted_scene: PathBuf,
}

impl FitWritten {
    /// Every file written, in the order written (the summary last).
    pub fn paths(&self) -> Vec<&PathBuf> {
        let w = &self.written;
        let mut paths = vec![&w.trajectory];
        paths.extend(&w.reference);
        paths.extend([&self.data, &self.fitted_scene, &w.summary]);
        paths
    }
}

/// Why [`fit_into`] failed.
#[derive(Debug, thiserror::Error)]
pub enum FitIntoError {
    /// The fit could not be attempted or completed.
    #[error(transparent)]
    Fit(#[from] FitError),
    /// The output directory is locked by another process, or a file could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// Write a fit's files into `dir` (module documentation); the report records the
/// fitted scene's file and hash.
pub fn write_fit(dir: &Path, fit: &mut Fit) -> Result<FitWritten, OutputError> {
    fit.report.fitted_scene = Some(super::report::FittedSceneFile {
        file: FITTED_SCENE_FILE.to_string(),
        sha256: provenance::content_hash(fit.fitted_toml.as_bytes()),
    });
    let report =
        serde_json::to_value(&fit.report).map_err(|e| OutputError::Format { path: dir.join(SUMMARY_FILE), message: e.to_string() })?;
    let extras = RunExtras {
        csv: vec![(DATA_FILE, fit.data_table.clone())],
        texts: vec![(FITTED_SCENE_FILE, fit.fitted_toml.clone())],
        fields: [("fit".to_string(), report)].into_iter().collect(),
    };
    let written = output::write_outcome_with(dir, &mut fit.outcome, &fit.fitted, &extras)?;
    Ok(FitWritten { written, data: dir.join(DATA_FILE), fitted_scene: dir.join(FITTED_SCENE_FILE) })
}

/// Fit `scene` to `data` and write the files into `dir` as `skg-solve fit` does: the
/// directory is locked for the whole fit, Ipopt's log (the scene's `log_file`) is staged
/// there and moved over the old one when the fit returns, then [`write_fit`]. A fit that
/// cannot run leaves no directory it created.
pub fn fit_into(
    dir: &Path,
    scene: &mut Scene,
    overrides: &Overrides,
    data: &Data,
    settings: &FitSettings,
) -> Result<(Fit, FitWritten), FitIntoError> {
    refuse_log_over_run_files(scene)?;
    let out = OutputDir::lock(dir)?;
    let log = scene.solver.log_file.as_ref().map(|name| (dir.join(name), out.staged(name)));
    scene.solver.ipopt_log = log.as_ref().map(|(_, staged)| staged.clone());
    let result = fit(scene, overrides, data, settings);
    scene.solver.ipopt_log = None;
    if let Some((target, staged)) = &log {
        out.commit(staged, target)?;
    }
    let mut fitted = match result {
        Ok(f) => f,
        Err(e) => {
            out.abandon();
            return Err(e.into());
        }
    };
    let written = write_fit(dir, &mut fitted)?;
    Ok((fitted, written))
}

/// A scene's `log_file` may not name one of the files the fit writes.
fn refuse_log_over_run_files(scene: &Scene) -> Result<(), FitError> {
    let (Some(name), Some(spanned)) = (&scene.solver.log_file, &scene.file.solver.log_file) else { return Ok(()) };
    if [TRAJECTORY_FILE, REFERENCE_FILE, SUMMARY_FILE, DATA_FILE, FITTED_SCENE_FILE].iter().any(|f| name == Path::new(f)) {
        let message = format!("solver.log_file may not be {}, which the fit itself writes", name.display());
        return Err(SceneError::Invalid { location: scene.file.origin.locate_in(spanned, None), message }.into());
    }
    Ok(())
}
