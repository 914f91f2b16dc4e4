//! `sweep.json`, written beside `results.csv` ([`SweepInfo`]): what was swept, from which
//! inputs, by which skg-solve, which points this run owns and which the whole sweep has;
//! and the `[sweep]` settings that change a row's values ([`RowSettings`]), which a
//! resume and a merge compare.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::read_err;
use crate::{Provenance, SweepError, SweepFile};

/// The settings of `[sweep]` that change the values of a row (recorded in `sweep.json`;
/// a resumed run with other settings is refused).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RowSettings {
    /// `reference` as written.
    pub reference: Option<String>,
    /// `compare` as written.
    pub compare: Option<Vec<String>>,
    /// `skip_last`, resolved.
    pub skip_last: usize,
    /// `artifact_tol`, resolved.
    pub artifact_tol: f64,
}

/// `sweep.json`, written beside results.csv: what was swept, from which scene content,
/// by which skg-solve (read by [`merge`](crate::merge()) to find missing points).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SweepInfo {
    /// The sweep's name.
    pub name: String,
    /// The sweep file as given.
    pub sweep_file: String,
    /// The base scene file.
    pub scene: String,
    /// skg-solve version, schema version and the base scene's content hash.
    #[serde(flatten)]
    pub provenance: Provenance,
    /// Points of the whole sweep.
    pub total_points: usize,
    /// `k/n` when run as a shard.
    pub shard: Option<String>,
    /// The settings that change a row's values.
    pub settings: RowSettings,
    /// Ids of this run's points (the shard's, or all).
    pub ids: Vec<String>,
    /// Ids of every point of the whole sweep, in index order (what [`merge`](crate::merge()) checks for
    /// completeness).
    pub all_ids: Vec<String>,
}

impl SweepInfo {
    /// Read `sweep.json` from a results directory.
    pub fn read(dir: &Path) -> Result<SweepInfo, SweepError> {
        let path = dir.join("sweep.json");
        let text = std::fs::read_to_string(&path).map_err(read_err(&path))?;
        serde_json::from_str(&text).map_err(|e| SweepError::Results { path, message: format!("not a sweep.json of this skg-solve: {e}") })
    }
}

impl SweepFile {
    /// The settings of this file that change a row's values.
    pub fn row_settings(&self) -> RowSettings {
        RowSettings {
            reference: self.sweep.reference.as_ref().map(|r| r.get_ref().clone()),
            compare: self.sweep.compare.as_ref().map(|c| c.get_ref().clone()),
            skip_last: self.skip_last(),
            artifact_tol: self.artifact_tol(),
        }
    }
}
