//! The merge of shards ([`merge`]): the `results.csv` files of the shards of one sweep
//! (one set of points, one input content, one schema, one set of `[sweep]` settings)
//! joined into one, sorted by point index, duplicates dropped; refused while points are
//! missing unless a partial merge is asked for. [`shards::merge_shards`](crate::shards::merge_shards)
//! uses the same reading and writing for a sharded directory.

use std::collections::{BTreeSet, HashSet};
use std::path::{Path, PathBuf};

use skg_core::output;

use crate::{csv_line, Results, SweepError, SweepInfo};

/// Summary of [`merge`].
#[derive(Debug, Clone, Default)]
pub struct MergeReport {
    /// Rows written.
    pub rows: usize,
    /// Rows whose id appeared in an earlier input (dropped).
    pub duplicates: usize,
    /// Points of the whole sweep.
    pub total: usize,
    /// Points of the sweep without a row (index, id), in index order; empty unless
    /// merged with `partial`.
    pub missing: Vec<(usize, String)>,
}

/// Join shards' results (each a results.csv or a directory holding one, with the
/// `sweep.json` beside it) into `output_dir` (writes `results.csv` and `sweep.json`
/// there), sorted by point index. The inputs must be shards of one sweep (same columns,
/// same inputs, same points) and together hold every point, else nothing is written and
/// the error lists the missing points; with `partial` the rows present are merged
/// anyway and [`MergeReport::missing`] lists the others.
pub fn merge(inputs: &[PathBuf], output_dir: &Path, partial: bool) -> Result<MergeReport, SweepError> {
    let merged = collect_rows(inputs, output_dir)?;
    if !merged.report.missing.is_empty() && !partial {
        return Err(merged.incomplete());
    }
    let lock = output::OutputDir::lock(output_dir)?;
    merged.write(&lock, output_dir)
}

/// The rows of shards read for a merge, not yet written.
pub(crate) struct Merged {
    /// The first input's results (its header and path; its rows are in `rows`).
    first: Results,
    /// The first input's sweep.json.
    info: SweepInfo,
    /// Every distinct row, sorted by point index.
    rows: Vec<Vec<String>>,
    /// The shards given (`k/n`).
    shards: BTreeSet<String>,
    pub(crate) report: MergeReport,
}

impl Merged {
    /// The error of a merge with points missing.
    fn incomplete(self) -> SweepError {
        SweepError::Incomplete {
            present: self.report.total - self.report.missing.len(),
            total: self.report.total,
            shards: self.shards.into_iter().collect(),
            missing: self.report.missing,
        }
    }

    /// Write `results.csv` and `sweep.json` into `output_dir`, whose lock the caller holds.
    pub(crate) fn write(self, _lock: &output::OutputDir, output_dir: &Path) -> Result<MergeReport, SweepError> {
        let Merged { first, info, rows, mut report, .. } = self;
        report.rows = rows.len();
        output::write_atomic(&output_dir.join("results.csv"), |w| {
            w.write_all(&csv_line(&first.header))?;
            rows.iter().try_for_each(|r| w.write_all(&csv_line(r)))
        })?;
        let id_col = first.require_column("id")?;
        let merged = SweepInfo { shard: None, ids: rows.iter().map(|r| r[id_col].clone()).collect(), ..info };
        output::write_json(&output_dir.join("sweep.json"), &merged)?;
        Ok(report)
    }
}

/// Read the whole rows of the shards `inputs` (each a results.csv or its directory, with
/// its sweep.json), check that they are shards of one sweep, drop duplicate rows and sort
/// the rest by point index; `output_dir` names the merge in an error about no input.
pub(crate) fn collect_rows(inputs: &[PathBuf], output_dir: &Path) -> Result<Merged, SweepError> {
    let mut first: Option<(Results, SweepInfo)> = None;
    let mut rows: Vec<Vec<String>> = Vec::new();
    let mut ids = HashSet::new();
    let mut shards = BTreeSet::new();
    let mut report = MergeReport::default();
    refuse_output_among_inputs(inputs, output_dir)?;
    for input in inputs {
        // A shard's torn last line (its run killed mid-write) is left out: that point is
        // missing from the merge, and the shard's rerun computes it.
        let res = Results::read_whole_rows(input)?;
        let path = res.path.clone();
        let info = SweepInfo::read(path.parent().unwrap_or(Path::new(".")))?;
        match &first {
            Some((r0, i0)) => check_same_sweep(r0, i0, &res, &info)?,
            None => {
                if let Some(other) = res.conflict(&info.provenance) {
                    return Err(SweepError::Results { path, message: format!("has rows computed from {other}, unlike its sweep.json") });
                }
            }
        }
        shards.extend(info.shard.clone());
        let id_col = res.require_column("id")?;
        for row in &res.rows {
            if ids.insert(row[id_col].clone()) {
                rows.push(row.clone());
            } else {
                report.duplicates += 1;
            }
        }
        first.get_or_insert((res, info));
    }
    let (first, info) = first.ok_or_else(|| SweepError::Results { path: output_dir.to_path_buf(), message: "nothing to merge".into() })?;
    report.total = info.all_ids.len();
    report.missing = info.all_ids.iter().enumerate().filter(|(_, id)| !ids.contains(*id)).map(|(k, id)| (k, id.clone())).collect();
    let idx = first.require_column("index")?;
    rows.sort_by_key(|r| r[idx].parse::<usize>().unwrap_or(usize::MAX));
    report.rows = rows.len();
    Ok(Merged { first, info, rows, shards, report })
}

/// Refuse an output directory that is one of the inputs: its sweep.json and results.csv
/// would be replaced by the merge, and the shard's own files lost.
fn refuse_output_among_inputs(inputs: &[PathBuf], output_dir: &Path) -> Result<(), SweepError> {
    let Some(output_id) = std::fs::canonicalize(output_dir).ok() else { return Ok(()) };
    for input in inputs {
        let dir = if input.is_dir() { input.clone() } else { input.parent().map(Path::to_path_buf).unwrap_or_default() };
        if std::fs::canonicalize(&dir).ok().as_ref() == Some(&output_id) {
            return Err(SweepError::Results {
                path: output_dir.to_path_buf(),
                message: format!(
                    "is also an input of the merge ({}): merging into it would replace that shard's results.csv and \
                     sweep.json; merge into a new directory",
                    input.display()
                ),
            });
        }
    }
    Ok(())
}

/// Refuse a shard (`res` with its sweep.json `info`) of another sweep than the first
/// input (`r0`, `i0`): other input content, columns, points or `[sweep]` settings.
fn check_same_sweep(r0: &Results, i0: &SweepInfo, res: &Results, info: &SweepInfo) -> Result<(), SweepError> {
    let not_shards =
        |message: String| SweepError::Results { path: res.path.clone(), message: format!("{message}: not shards of one sweep") };
    if let Some(other) = res.conflict(&i0.provenance).or_else(|| r0.conflict(&info.provenance)) {
        return Err(not_shards(format!("has rows computed from {other}")));
    }
    if r0.header != res.header {
        return Err(not_shards("its columns differ from the first input's".into()));
    }
    if i0.all_ids != info.all_ids {
        return Err(not_shards(format!("its sweep.json lists other points than {}'s", r0.path.display())));
    }
    if i0.settings != info.settings {
        return Err(not_shards(format!("its sweep.json records other [sweep] settings than {}'s", r0.path.display())));
    }
    Ok(())
}
