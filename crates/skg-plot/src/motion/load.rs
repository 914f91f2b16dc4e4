//! Reading a solve's output directory (or its trajectory CSV) into a [`Motion`]: the
//! trajectory, the scene that `summary.json` records (resolved with the parameters the
//! solve used, with a note when the file changed since), the reference beside it.

use std::path::{Path, PathBuf};

use skg_core::check::Table;
use skg_core::output::{REFERENCE_FILE, SUMMARY_FILE, TRAJECTORY_FILE};
use skg_core::scene::{Overrides, SceneFile};

use super::{data_err, Motion};
use crate::PlotError;

impl Motion {
    /// Load a solve's output directory (or its trajectory CSV, with summary.json and
    /// reference.csv beside it). The scene is `scene`, else the `scene_file` that
    /// summary.json records, resolved with the parameters the solve used; the reference
    /// is `reference`, else the directory's reference.csv when there is one.
    pub fn load(input: &Path, scene: Option<&Path>, reference: Option<&Path>) -> Result<Motion, PlotError> {
        let (dir, file) = if input.is_dir() {
            (input.to_path_buf(), input.join(TRAJECTORY_FILE))
        } else {
            (input.parent().map(Path::to_path_buf).unwrap_or_default(), input.to_path_buf())
        };
        let (solution, pairing) = Table::read_paired(&file)?;
        let summary_path = dir.join(SUMMARY_FILE);
        let summary = read_summary(&summary_path)?;
        let scene_path = scene_path(scene, summary.as_ref(), &summary_path, &file)?;
        let scene_file = SceneFile::load(&scene_path)?;
        let (set, notes) = summary.as_ref().map_or_else(Default::default, |s| solve_parameters(s, &scene_file, &scene_path));
        let resolved = scene_file.resolve(&Overrides { set, ..Overrides::default() })?;
        let reference = match reference {
            Some(p) => Some(Table::read(p)?),
            None => Some(dir.join(REFERENCE_FILE)).filter(|p| p.is_file()).map(|p| Table::read(&p)).transpose()?,
        };
        let label = if input.is_dir() { input } else { dir.as_path() }
            .file_name()
            .map_or_else(|| file.display().to_string(), |n| n.to_string_lossy().into_owned());
        let mut m = Motion::new(label, resolved, solution, reference)?;
        m.notes = notes;
        m.warnings.extend(pairing.warning(&file));
        Ok(m)
    }
}

/// The solve's summary.json, when there is one.
fn read_summary(path: &Path) -> Result<Option<serde_json::Value>, PlotError> {
    if !path.is_file() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(path).map_err(|error| PlotError::Io { path: path.to_path_buf(), error })?;
    Ok(Some(serde_json::from_str(&text).map_err(|error| PlotError::Summary { path: path.to_path_buf(), error })?))
}

/// The scene file: `scene` (--scene), else the one the summary records; an error when
/// there is neither or the file is not there.
fn scene_path(scene: Option<&Path>, summary: Option<&serde_json::Value>, summary_path: &Path, file: &Path) -> Result<PathBuf, PlotError> {
    let recorded = summary.and_then(|s| s["scene_file"].as_str()).map(PathBuf::from);
    let scene_path = match (scene, recorded) {
        (Some(p), _) => p.to_path_buf(),
        (None, Some(p)) => p,
        (None, None) if summary.is_some() => {
            return Err(data_err(format!(
                "{} names no scene file (`scene_file`, written since skg-solve 0.2 with this field): name the scene with --scene",
                summary_path.display()
            )))
        }
        (None, None) => {
            return Err(data_err(format!("no summary.json beside {}: name the scene with --scene", file.display())));
        }
    };
    if !scene_path.is_file() {
        return Err(data_err(format!(
            "the scene file {} (from {}) does not exist here; run from the directory the solve ran in, or name it with --scene",
            scene_path.display(),
            if scene.is_some() { "--scene".to_string() } else { summary_path.display().to_string() }
        )));
    }
    Ok(scene_path)
}

/// The parameters the solve used (its --set overrides included) that the scene declares,
/// as `--set` assignments; and a note when the scene file changed since the solve.
fn solve_parameters(summary: &serde_json::Value, scene_file: &SceneFile, scene_path: &Path) -> (Vec<(String, String)>, Vec<String>) {
    let mut set = Vec::new();
    if let Some(params) = summary["settings"]["parameters"].as_object() {
        for (k, v) in params {
            if let (true, Some(x)) = (scene_file.parameters.contains_key(k), v.as_f64()) {
                set.push((k.clone(), format!("{x:?}")));
            }
        }
    }
    let mut notes = Vec::new();
    if let Some(h) = summary["scene_hash"].as_str() {
        if h != scene_file.origin.content_hash() {
            notes.push(format!(
                "{} has changed since the solve (its hash differs from summary.json's scene_hash): the walls drawn are today's",
                scene_path.display()
            ));
        }
    }
    (set, notes)
}
