//! `skg-solve status DIR`: the points of a sweep directory (sharded or not) that are
//! converged, failed and missing, per shard, and the Slurm jobs' states while Slurm
//! knows them.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Result};
use clap::Args;

use skg_sweep::shards::{self, ShardLayout, ShardState};
use skg_sweep::slurm::{self, JobState, JobsFile};
use skg_sweep::SweepInfo;

#[derive(Args)]
pub struct StatusArgs {
    /// A sweep's output directory (of `skg-solve sweep`, with or without --slurm).
    #[arg(value_name = "DIR")]
    pub dir: PathBuf,
}

pub fn run(args: StatusArgs) -> Result<ExitCode> {
    let dir = &args.dir;
    match ShardLayout::read(dir)? {
        Some(layout) => sharded(dir, &layout)?,
        None if dir.join("sweep.json").is_file() => {
            let info = SweepInfo::read(dir)?;
            let state = shards::results_state(dir)?;
            println!("{}: {} points in {}", info.name, state.points, dir.display());
            println!("  {}", counts(&state));
            if let Some(s) = &info.shard {
                println!("  (shard {s} of the sweep's {} points)", info.total_points);
            }
        }
        None => bail!("{}: not a sweep directory (no sweep.json and no {})", dir.display(), shards::LAYOUT_FILE),
    }
    Ok(ExitCode::SUCCESS)
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

fn sharded(dir: &std::path::Path, layout: &ShardLayout) -> Result<()> {
    let states = shards::shard_states(dir, layout)?;
    let mut total = ShardState { points: layout.total_points, ..ShardState::default() };
    for s in &states {
        total.converged += s.converged;
        total.failed += s.failed;
        total.missing += s.missing;
        for (k, n) in &s.statuses {
            *total.statuses.entry(k.clone()).or_insert(0) += n;
        }
    }
    println!(
        "{}: {} points in {} shards in {} ({})",
        layout.name,
        layout.total_points,
        layout.shards,
        dir.display(),
        layout.sweep_file.display()
    );
    println!("  {}", counts(&total));
    if shards::merged(dir) {
        println!("  merged: {} holds every point", dir.join("results.csv").display());
    } else {
        println!("  not merged yet ({})", super::sweep::slurm::incomplete_text(layout, &states));
    }
    // The Slurm jobs of the latest submission, while Slurm knows them.
    let jobs = JobsFile::read(dir)?;
    let mut task_state: BTreeMap<usize, String> = BTreeMap::new();
    if let Some(last) = jobs.submissions.last() {
        let ids = last.job_ids();
        let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
        let when = ago(now.saturating_sub(last.submitted_unix));
        match slurm::job_states(&ids) {
            Ok(states) => {
                let find = |id: &Option<String>| -> String {
                    id.as_ref().map_or("not submitted".into(), |id| {
                        states.iter().find(|s| &s.id == id).map_or("ended (no longer known to Slurm)".into(), describe)
                    })
                };
                if let Some(a) = &last.array_job {
                    for s in &states {
                        if let Some(k) = s.task_of(a) {
                            task_state.insert(k, describe(s));
                        }
                    }
                }
                println!(
                    "  Slurm, submission {} ({when}): array job {} (shards {}), merge job {}: {}",
                    jobs.submissions.len(),
                    last.array_job.as_deref().unwrap_or("none"),
                    if last.shards.is_empty() { "none".into() } else { slurm::array_spec(&last.shards) },
                    last.merge_job.as_deref().unwrap_or("none"),
                    find(&last.merge_job)
                );
            }
            Err(e) => println!("  Slurm states not shown: {e}"),
        }
    }
    println!("  {:>5} {:>7} {:>9} {:>7} {:>8}  slurm", "shard", "points", "converged", "failed", "missing");
    for s in &states {
        println!(
            "  {:>5} {:>7} {:>9} {:>7} {:>8}  {}",
            s.k,
            s.points,
            s.converged,
            s.failed,
            s.missing,
            task_state.get(&s.k).map_or("", String::as_str)
        );
    }
    Ok(())
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
