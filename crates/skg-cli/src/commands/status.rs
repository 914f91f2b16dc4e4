//! `skg-solve status DIR`: the points of a sweep directory (sharded or not) that are
//! converged, failed and missing, per shard, and the Slurm jobs' states while Slurm
//! knows them.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Result};
use clap::Args;

use crate::stdio::out;
use skg_sweep::shards::{self, ShardLayout, ShardState};
use skg_sweep::slurm::{self, JobState, JobsFile};
use skg_sweep::SweepInfo;

#[derive(Args)]
pub struct StatusArgs {
    /// A sweep's output directory (of `skg-solve sweep`, with or without --slurm).
    #[arg(value_name = "DIR")]
    pub dir: PathBuf,
}

pub fn run(args: StatusArgs, quiet: bool) -> Result<ExitCode> {
    let dir = &args.dir;
    let lines = match ShardLayout::read(dir)? {
        Some(layout) => sharded(dir, &layout)?,
        None if dir.join("sweep.json").is_file() => unsharded(dir)?,
        None => bail!("{}: not a sweep directory (no sweep.json and no {})", dir.display(), shards::LAYOUT_FILE),
    };
    if !quiet {
        for line in lines {
            out!("{line}");
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// The report on a sweep run without --slurm (one results.csv, maybe one shard's).
fn unsharded(dir: &Path) -> Result<Vec<String>> {
    let info = SweepInfo::read(dir)?;
    let state = shards::results_state(dir)?;
    let mut lines = vec![format!("{}: {} points in {}", info.name, state.points, dir.display()), format!("  {}", counts(&state))];
    if let Some(s) = &info.shard {
        lines.push(format!("  (shard {s} of the sweep's {} points)", info.total_points));
    }
    Ok(lines)
}

/// `9 converged, 1 failed (1 not_converged), 2 missing`.
fn counts(s: &ShardState) -> String {
    let failed: Vec<String> = s.statuses.iter().filter(|(k, _)| k.as_str() != "converged").map(|(k, n)| format!("{n} {k}")).collect();
    format!(
        "{} converged, {} failed{}, {} missing",
        s.converged,
        s.failed,
        if failed.is_empty() { String::new() } else { format!(" ({})", failed.join(", ")) },
        s.missing
    )
}

/// The report on a sweep run with --slurm: the totals, whether it is merged, the latest
/// submission's jobs, and a table of the shards.
fn sharded(dir: &Path, layout: &ShardLayout) -> Result<Vec<String>> {
    let states = shards::shard_states(dir, layout)?;
    let mut lines = vec![
        format!(
            "{}: {} points in {} shards in {} ({})",
            layout.name,
            layout.total_points,
            layout.shards,
            dir.display(),
            layout.sweep_file.display()
        ),
        format!("  {}", counts(&total(layout, &states))),
        if shards::merged(dir) {
            format!("  merged: {} holds every point", dir.join("results.csv").display())
        } else {
            format!("  not merged yet ({})", super::sweep::slurm::incomplete_text(layout, &states))
        },
    ];
    let jobs = slurm_jobs(dir)?;
    lines.extend(jobs.line);
    lines.push(format!("  {:>5} {:>7} {:>9} {:>7} {:>8}  slurm", "shard", "points", "converged", "failed", "missing"));
    for s in &states {
        lines.push(format!(
            "  {:>5} {:>7} {:>9} {:>7} {:>8}  {}",
            s.k,
            s.points,
            s.converged,
            s.failed,
            s.missing,
            jobs.tasks.get(&s.k).map_or("", String::as_str)
        ));
    }
    Ok(lines)
}

/// The counts of every shard together.
fn total(layout: &ShardLayout, states: &[ShardState]) -> ShardState {
    let mut total = ShardState { points: layout.total_points, ..ShardState::default() };
    for s in states {
        total.converged += s.converged;
        total.failed += s.failed;
        total.missing += s.missing;
        for (k, n) in &s.statuses {
            *total.statuses.entry(k.clone()).or_insert(0) += n;
        }
    }
    total
}

/// The Slurm jobs of the latest submission, while Slurm knows them: a line on the
/// submission (none before the first), and the state of each shard's array task.
struct SlurmJobs {
    line: Option<String>,
    tasks: BTreeMap<usize, String>,
}

fn slurm_jobs(dir: &Path) -> Result<SlurmJobs> {
    let jobs = JobsFile::read(dir)?;
    let mut tasks: BTreeMap<usize, String> = BTreeMap::new();
    let Some(last) = jobs.submissions.last() else { return Ok(SlurmJobs { line: None, tasks }) };
    let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let when = ago(now.saturating_sub(last.submitted_unix));
    let states = match slurm::job_states(&last.job_ids()) {
        Ok(states) => states,
        Err(e) => return Ok(SlurmJobs { line: Some(format!("  Slurm states not shown: {e}")), tasks }),
    };
    let find = |id: &Option<String>| -> String {
        id.as_ref().map_or("not submitted".into(), |id| {
            states.iter().find(|s| &s.id == id).map_or("ended (no longer known to Slurm)".into(), describe)
        })
    };
    if let Some(a) = &last.array_job {
        for s in &states {
            if let Some(k) = s.task_of(a) {
                tasks.insert(k, describe(s));
            }
        }
    }
    let line = format!(
        "  Slurm, submission {} ({when}): array job {} (shards {}), merge job {}: {}",
        jobs.submissions.len(),
        last.array_job.as_deref().unwrap_or("none"),
        if last.shards.is_empty() { "none".into() } else { slurm::array_spec(&last.shards) },
        last.merge_job.as_deref().unwrap_or("none"),
        find(&last.merge_job)
    );
    Ok(SlurmJobs { line: Some(line), tasks })
}

/// `RUNNING`, `PENDING (Dependency)`.
fn describe(s: &JobState) -> String {
    if s.reason.is_empty() || s.reason == "None" {
        s.state.clone()
    } else {
        format!("{} ({})", s.state, s.reason)
    }
}

/// `12 s ago`, `3 min ago`, `2.5 h ago`, `4.0 days ago`.
fn ago(s: u64) -> String {
    match s {
        0..=119 => format!("{s} s ago"),
        120..=7199 => format!("{} min ago", s / 60),
        7200..=172_799 => format!("{:.1} h ago", s as f64 / 3600.0),
        _ => format!("{:.1} days ago", s as f64 / 86400.0),
    }
}
