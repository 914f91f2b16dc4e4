//! Sharded sweep directories: a sweep split into K shards that run as separate jobs (a
//! Slurm job array, [`crate::slurm`]; the tasks of a Python executor) and are merged into
//! one `results.csv`.
//!
//! ```text
//! DIR/shards.json        the layout (ShardLayout): sweep file, K, points, who runs the shards
//! DIR/shards/<k>/        shard k/K: results.csv, sweep.json (a sweep run with --shard k/K)
//! DIR/results.csv        the merge of every shard, written only when every point is there
//! DIR/sweep.json         (merge_shards, the single writer of these two files)
//! ```
//!
//! Whether a shard is complete comes from its own files, as a resume decides which points
//! to run: its `sweep.json` and the whole rows of its `results.csv` ([`shard_states`]). A
//! shard directory that is missing or partial is incomplete; running the shard again
//! resumes it, so the points it holds are not run twice. A scheduler's job states are
//! never needed for this (Slurm forgets finished jobs after a few minutes).

use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use skg_core::output;

use crate::error::{create_dir_err, read_err};
use crate::merge::collect_rows;
use crate::{Expanded, MergeReport, PointStatus, Provenance, Results, SweepError, SweepFile, SweepInfo};

/// The layout file of a sharded directory.
pub const LAYOUT_FILE: &str = "shards.json";

/// The most shards of one sweep: Slurm's default `MaxArraySize` (1001) allows array
/// indices up to 1000, and shard k is array index k.
pub const MAX_SHARDS: usize = 1000;

/// Shards when none are asked for: one per 10 points, at least 1, at most 100
/// ([`default_shards`]).
pub const DEFAULT_MAX_SHARDS: usize = 100;

/// Points per shard that the default aims at, at least.
pub const DEFAULT_POINTS_PER_SHARD: usize = 10;

/// How long [`merge_shards`] waits for the directory's lock (held briefly by a
/// submission) before it gives up.
const LOCK_WAIT: Duration = Duration::from_secs(120);

/// The default number of shards of a sweep of `points` points: one shard per
/// [`DEFAULT_POINTS_PER_SHARD`] points, at most [`DEFAULT_MAX_SHARDS`]. At least ten
/// points per shard share a shard's fixed costs (queue wait, process start) and give a
/// shard with several CPUs work for each of them; a hundred shards, each using all the
/// CPUs it is given, keep a large sweep's queue entries and `DIR/shards` small.
pub fn default_shards(points: usize) -> usize {
    points.div_ceil(DEFAULT_POINTS_PER_SHARD).clamp(1, DEFAULT_MAX_SHARDS)
}

/// What runs the shards of a directory (recorded so that two kinds of runs never share
/// one directory).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Runner {
    /// Slurm job arrays (`skg-solve sweep --slurm`).
    Slurm,
    /// The tasks of a Python `concurrent.futures.Executor` (`skg.sweep(executor=…)`).
    Executor,
}

impl std::fmt::Display for Runner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Runner::Slurm => "Slurm (skg-solve sweep --slurm)",
            Runner::Executor => "a Python executor (skg.sweep(executor=...))",
        })
    }
}

/// `DIR/shards.json`: the sweep a sharded directory holds and how it is split.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShardLayout {
    /// The sweep's name.
    pub name: String,
    /// The sweep file (absolute path).
    pub sweep_file: PathBuf,
    /// The number of shards K; shard k runs in `DIR/shards/<k>`.
    pub shards: usize,
    /// Points of the whole sweep.
    pub total_points: usize,
    /// What runs the shards.
    pub runner: Runner,
}

impl ShardLayout {
    /// Read `DIR/shards.json`; None if the directory has none.
    pub fn read(dir: &Path) -> Result<Option<ShardLayout>, SweepError> {
        let path = dir.join(LAYOUT_FILE);
        if !path.exists() {
            return Ok(None);
        }
        let text = std::fs::read_to_string(&path).map_err(read_err(&path))?;
        serde_json::from_str(&text)
            .map(Some)
            .map_err(|e| SweepError::Results { path, message: format!("not a shards.json of this skg-solve: {e}") })
    }

    /// Points of shard `k` (those whose index is k−1 mod K).
    pub fn points_in(&self, k: usize) -> usize {
        if k == 0 || k > self.total_points {
            return 0;
        }
        (self.total_points - k) / self.shards + 1
    }
}

/// Shard `k`'s directory in the sharded directory `dir`.
pub fn shard_dir(dir: &Path, k: usize) -> PathBuf {
    dir.join("shards").join(k.to_string())
}

/// What the files of one shard say.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ShardState {
    /// The shard's number k (1-based).
    pub k: usize,
    /// Its points.
    pub points: usize,
    /// Rows with the status `converged`.
    pub converged: usize,
    /// Rows with any other status (not verified, not converged, error, crashed, timeout).
    pub failed: usize,
    /// Points without a row.
    pub missing: usize,
    /// The rows by status name.
    pub statuses: BTreeMap<String, usize>,
}

impl ShardState {
    /// Whether every point of the shard has a row.
    pub fn complete(&self) -> bool {
        self.missing == 0
    }
}

/// The rows (whole rows, distinct ids) of the results file of the directory `dir`, if
/// any: converged, failed and by status.
fn count_rows(dir: &Path, state: &mut ShardState) -> Result<(), SweepError> {
    if !dir.join("results.csv").is_file() {
        return Ok(());
    }
    let res = Results::read_whole_rows(dir)?;
    let (id, status) = (res.require_column("id")?, res.require_column("status")?);
    let mut seen = HashSet::new();
    for row in res.rows.iter().filter(|row| seen.insert(row[id].clone())) {
        *state.statuses.entry(row[status].clone()).or_insert(0) += 1;
        if row[status] == PointStatus::Converged.name() {
            state.converged += 1;
        } else {
            state.failed += 1;
        }
    }
    Ok(())
}

/// Every shard's state, from its files alone (`DIR/shards/<k>/results.csv`; a missing
/// directory is a shard with every point missing). A shard without its `sweep.json`
/// counts as having no rows: the merge cannot check its rows against the sweep, and
/// running the shard again writes it (its rows are kept and not run again), so that
/// `status`, the resubmission and the merge agree that it is incomplete.
pub fn shard_states(dir: &Path, layout: &ShardLayout) -> Result<Vec<ShardState>, SweepError> {
    (1..=layout.shards)
        .map(|k| {
            let mut state = ShardState { k, points: layout.points_in(k), ..ShardState::default() };
            let shard = shard_dir(dir, k);
            if shard.join("sweep.json").is_file() {
                count_rows(&shard, &mut state)?;
            }
            state.missing = state.points.saturating_sub(state.converged + state.failed);
            Ok(state)
        })
        .collect()
}

/// The points of an unsharded results directory (a plain sweep, or the merge of a
/// sharded one) as one [`ShardState`] (k = 0), with the sweep's point count from its
/// sweep.json.
pub fn results_state(dir: &Path) -> Result<ShardState, SweepError> {
    let info = SweepInfo::read(dir)?;
    let mut state = ShardState { points: info.ids.len(), ..ShardState::default() };
    count_rows(dir, &mut state)?;
    state.missing = state.points.saturating_sub(state.converged + state.failed);
    Ok(state)
}

/// Whether `DIR/results.csv` holds the merge of every point (its sweep.json lists every
/// point of the sweep, which [`merge_shards`] writes only then).
pub fn merged(dir: &Path) -> bool {
    dir.join("results.csv").is_file()
        && SweepInfo::read(dir).is_ok_and(|info| info.shard.is_none() && !info.all_ids.is_empty() && info.ids.len() == info.all_ids.len())
}

/// Options of [`prepare`].
#[derive(Debug, Clone)]
pub struct PrepareOptions {
    /// The number of shards asked for (None: the directory's, or [`default_shards`]).
    pub shards: Option<usize>,
    /// What runs the shards.
    pub runner: Runner,
}

/// Make `dir` a sharded directory of the sweep `file` (writing `DIR/shards.json`), or
/// check that it already is one of the same sweep, the same number of shards and the
/// same runner; then each shard's state. The shards' own files must belong to this
/// sweep: the same points, the same base scene and reference content, the same
/// `[sweep]` settings (a rerun after an edit is refused, as a resume refuses it).
pub fn prepare(
    file: &SweepFile,
    expanded: &Expanded,
    dir: &Path,
    opts: &PrepareOptions,
) -> Result<(ShardLayout, Vec<ShardState>), SweepError> {
    let sweep_file = std::path::absolute(&file.origin.path).map_err(read_err(Path::new(&file.origin.path)))?;
    let total = expanded.points.len();
    check_shard_count(opts.shards, total, dir)?;
    let layout = match ShardLayout::read(dir)? {
        Some(old) => check_layout(old, &sweep_file, total, opts, dir)?,
        None => new_layout(file, sweep_file, total, opts, dir)?,
    };
    check_shard_files(file, expanded, dir, &layout)?;
    let states = shard_states(dir, &layout)?;
    Ok((layout, states))
}

/// Refuse a number of shards outside 1 … [`MAX_SHARDS`] or above the sweep's `total`
/// points.
fn check_shard_count(shards: Option<usize>, total: usize, dir: &Path) -> Result<(), SweepError> {
    let Some(k) = shards else { return Ok(()) };
    let bad = |message: String| SweepError::Results { path: dir.to_path_buf(), message };
    if k == 0 || k > MAX_SHARDS {
        return Err(bad(format!("--shards {k}: expected 1 to {MAX_SHARDS} (Slurm's default MaxArraySize)")));
    }
    if k > total {
        return Err(bad(format!("--shards {k}: the sweep has only {total} points (at most one shard per point)")));
    }
    Ok(())
}

/// The layout `old` of the sharded directory `dir`, if it is of the same runner, the same
/// sweep file with `total` points and the number of shards asked for (if any).
fn check_layout(old: ShardLayout, sweep_file: &Path, total: usize, opts: &PrepareOptions, dir: &Path) -> Result<ShardLayout, SweepError> {
    let bad = |message: String| SweepError::Results { path: dir.join(LAYOUT_FILE), message };
    if old.runner != opts.runner {
        return Err(bad(format!("its shards are run by {}, not by {}: use another output directory", old.runner, opts.runner)));
    }
    if old.sweep_file != sweep_file || old.total_points != total {
        return Err(bad(format!(
            "holds the {} points of {}, not the {total} points of {}: use another output directory",
            old.total_points,
            old.sweep_file.display(),
            sweep_file.display()
        )));
    }
    if let Some(k) = opts.shards.filter(|&k| k != old.shards) {
        return Err(bad(format!(
            "the sweep here is split into {} shards, not {k}: leave out --shards, or use another output directory",
            old.shards
        )));
    }
    Ok(old)
}

/// A new layout for `dir` (written to `DIR/shards.json`), unless `dir` holds the results
/// of a sweep run on one machine.
fn new_layout(file: &SweepFile, sweep_file: PathBuf, total: usize, opts: &PrepareOptions, dir: &Path) -> Result<ShardLayout, SweepError> {
    if dir.join("results.csv").exists() || dir.join("sweep.json").exists() {
        return Err(SweepError::Results {
            path: dir.to_path_buf(),
            message: "holds the results of a sweep run on one machine (results.csv, sweep.json): use another output directory".into(),
        });
    }
    let layout = ShardLayout {
        name: file.name(),
        sweep_file,
        shards: opts.shards.unwrap_or_else(|| default_shards(total)).min(total.max(1)),
        total_points: total,
        runner: opts.runner,
    };
    std::fs::create_dir_all(dir).map_err(create_dir_err(dir))?;
    output::write_json(&dir.join(LAYOUT_FILE), &layout)?;
    Ok(layout)
}

/// Refuse a shard directory whose sweep.json is of another shard, other points, other
/// input content or other `[sweep]` settings than the sweep `file` has now.
fn check_shard_files(file: &SweepFile, expanded: &Expanded, dir: &Path, layout: &ShardLayout) -> Result<(), SweepError> {
    let provenance = Provenance::current(expanded.scene_hash.clone(), expanded.reference_hash.clone());
    let all_ids: Vec<String> = expanded.points.iter().map(crate::Point::id).collect();
    let settings = file.row_settings();
    for k in 1..=layout.shards {
        let shard = shard_dir(dir, k);
        if !shard.join("sweep.json").is_file() {
            continue;
        }
        let info = SweepInfo::read(&shard)?;
        let bad = |message: String| SweepError::Results { path: shard.join("sweep.json"), message };
        let expected = format!("{k}/{}", layout.shards);
        if info.shard.as_deref() != Some(expected.as_str()) {
            return Err(bad(format!("is shard {:?}, not {expected}: not a shard of this directory", info.shard)));
        }
        if info.all_ids != all_ids {
            return Err(bad(
                "lists other points than the sweep file now has: the sweep file was edited; use another output directory".into()
            ));
        }
        if let Some(other) = provenance.conflict(&info.provenance) {
            return Err(bad(format!("records rows computed from {other}: the inputs changed since; use another output directory")));
        }
        if info.settings != settings {
            return Err(bad(
                "records other [sweep] settings than the sweep file now has: restore them, or use another output directory".into()
            ));
        }
    }
    Ok(())
}

/// Take the lock of `dir`, waiting up to [`LOCK_WAIT`] while another process holds it
/// (a submission holds it for a moment).
fn lock_waiting(dir: &Path) -> Result<output::OutputDir, SweepError> {
    let deadline = Instant::now() + LOCK_WAIT;
    loop {
        match output::OutputDir::lock(dir) {
            Err(output::OutputError::Busy { .. }) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(500)),
            r => return Ok(r?),
        }
    }
}

/// The shards of a sharded directory that do not hold all their points: (k, missing,
/// points).
#[derive(Debug, Clone, PartialEq)]
pub struct Incomplete(pub Vec<(usize, usize, usize)>);

impl std::fmt::Display for Incomplete {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        const LISTED: usize = 20;
        let mut parts: Vec<String> = self.0.iter().take(LISTED).map(|(k, m, p)| format!("{k} ({m} of {p} missing)")).collect();
        if self.0.len() > LISTED {
            parts.push(format!("and {} more", self.0.len() - LISTED));
        }
        f.write_str(&parts.join(", "))
    }
}

/// Merge the shards of the sharded directory `dir` into `DIR/results.csv` and
/// `DIR/sweep.json`, holding the directory's lock from the first read to the last write
/// (the single writer of these files). Only whole rows count (a shard killed while
/// writing a row leaves a partial line, which is not a row). Nothing is written unless
/// every point of the sweep is there: the error ([`SweepError::IncompleteShards`]) names
/// the incomplete shards and the missing points.
pub fn merge_shards(dir: &Path) -> Result<MergeReport, SweepError> {
    let layout = ShardLayout::read(dir)?.ok_or_else(|| SweepError::Results {
        path: dir.to_path_buf(),
        message: format!("not a sharded sweep directory (no {LAYOUT_FILE})"),
    })?;
    let lock = lock_waiting(dir)?;
    let states = shard_states(dir, &layout)?;
    let incomplete = Incomplete(states.iter().filter(|s| !s.complete()).map(|s| (s.k, s.missing, s.points)).collect());
    let inputs: Vec<PathBuf> = (1..=layout.shards)
        .map(|k| shard_dir(dir, k))
        .filter(|d| d.join("sweep.json").is_file() && d.join("results.csv").is_file())
        .collect();
    if inputs.is_empty() {
        return Err(SweepError::IncompleteShards {
            dir: dir.to_path_buf(),
            present: 0,
            total: layout.total_points,
            incomplete,
            missing: Vec::new(),
        });
    }
    let merged = collect_rows(&inputs, dir)?;
    if !merged.report.missing.is_empty() || !incomplete.0.is_empty() {
        return Err(SweepError::IncompleteShards {
            dir: dir.to_path_buf(),
            present: merged.report.total - merged.report.missing.len(),
            total: merged.report.total,
            incomplete,
            missing: merged.report.missing,
        });
    }
    merged.write(&lock, dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_sizes_add_up_and_the_default_is_bounded() {
        for (total, k) in [(1, 1), (11, 2), (11, 4), (1000, 100), (5, 5)] {
            let layout =
                ShardLayout { name: "s".into(), sweep_file: "/s.toml".into(), shards: k, total_points: total, runner: Runner::Slurm };
            let sizes: Vec<usize> = (1..=k).map(|j| layout.points_in(j)).collect();
            // Independent count: the indices i with i mod k = j − 1.
            let expected: Vec<usize> = (1..=k).map(|j| (0..total).filter(|i| i % k == j - 1).count()).collect();
            assert_eq!(sizes, expected, "{total} points in {k} shards");
        }
        assert_eq!([1, 10, 11, 95, 1000, 5000, 10_000_000].map(default_shards), [1, 1, 2, 10, 100, 100, 100]);
    }
}
