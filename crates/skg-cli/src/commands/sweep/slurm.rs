//! `skg-solve sweep FILE --slurm -o DIR`: the sweep's shards as a Slurm job array and a
//! merge job after it (`skg_sweep::slurm`), `--wait` for the merge, and the hidden
//! `sweep-merge DIR` that the merge job runs. Uses its parent's [`SweepArgs`]; `status`
//! uses [`incomplete_text`].

use std::path::Path;
use std::process::ExitCode;

use anyhow::{Context, Result};

use skg_sweep as sweep;
use skg_sweep::shards::{self, ShardLayout, ShardState};
use skg_sweep::slurm::{self, SubmitOptions, SubmitReport};

use super::SweepArgs;
use crate::commands::UsageError;
use crate::stdio::{note, out};

/// `skg-solve sweep FILE --slurm`: write the scripts, submit them, and with `--wait`
/// wait for the merge.
pub fn run(args: SweepArgs, quiet: bool) -> Result<ExitCode> {
    let report = submit(&args)?;
    if report.submitted.is_empty() && report.merged {
        if !quiet {
            out!(
                "{}: every point of the sweep ({}) is in {}: nothing to submit",
                report.layout.name,
                report.layout.total_points,
                report.dir.join("results.csv").display()
            );
        }
        return Ok(ExitCode::SUCCESS);
    }
    for note in &report.notes {
        note!("note: {note}");
    }
    if args.dry_run {
        if !quiet {
            print_dry_run(&report);
        }
        return Ok(ExitCode::SUCCESS);
    }
    let merge = report.merge_job.clone().unwrap_or_default();
    if !quiet {
        print_submitted(&report, &merge);
    }
    if !args.wait {
        return Ok(ExitCode::SUCCESS);
    }
    let outcome = slurm::wait_for_merge(report.array_job.as_deref(), &merge, |line| {
        if !quiet {
            note!("  {line}")
        }
    })?;
    finish(&report, outcome.merge.as_ref(), quiet)
}

/// Check the sweep as a local run would (every point valid, --yes above 10000 points),
/// write the scripts and submit the incomplete shards (or, with --dry-run, only say
/// how). An sbatch argument that skg-solve sets itself is a usage error.
fn submit(args: &SweepArgs) -> Result<SubmitReport> {
    let file = &sweep::SweepFile::load(&args.sweep)?;
    let out = args.output.clone().unwrap_or_else(|| sweep::default_out_dir(file));
    let exe = std::env::current_exe().context("locating the skg-solve executable for the jobs")?;
    let plan_opts = sweep::SweepOptions {
        out_dir: out.clone(),
        jobs: 1,
        shard: None,
        worker_exe: exe.clone(),
        progress: false,
        retry_failed: false,
        new_results: false,
    };
    let plan = sweep::plan(file, &plan_opts, args.yes)?;
    let opts = SubmitOptions { shards: args.shards.map(|k| k as usize), sbatch_args: args.sbatch_args.clone(), exe, dry_run: args.dry_run };
    match slurm::submit(file, &plan.expanded, &out, &opts) {
        Err(e) if e.is_usage() => Err(UsageError(e.to_string()).into()),
        r => Ok(r?),
    }
}

/// What a dry run would submit, and the sbatch commands.
fn print_dry_run(report: &SubmitReport) {
    out!(
        "{}: {} points in {} shards; would submit {} (dry run: nothing submitted). Scripts in {}:",
        report.layout.name,
        report.layout.total_points,
        report.layout.shards,
        submitted_text(report),
        report.dir.join("slurm").display()
    );
    for c in &report.commands {
        out!("  {c}");
    }
}

/// What was submitted, and how to follow it.
fn print_submitted(report: &SubmitReport, merge: &str) {
    let ids: Vec<&str> = report.array_job.iter().map(String::as_str).chain([merge]).collect();
    out!(
        "{}: {} points in {} shards; submitted {}: {}",
        report.layout.name,
        report.layout.total_points,
        report.layout.shards,
        submitted_text(report),
        match &report.array_job {
            Some(a) => format!("array job {a} and merge job {merge} (after the array)"),
            None => format!("merge job {merge}"),
        }
    );
    out!("  scripts and logs: {}", report.dir.join("slurm").display());
    out!("  follow them: squeue -j {}   or   skg-solve status {}", ids.join(","), report.dir.display());
    out!(
        "  when the merge has ended, {} holds every point; if a shard did not finish, run the same command again: only the incomplete shards run",
        report.dir.join("results.csv").display()
    );
}

/// `skg-solve sweep-merge DIR` (hidden): the merge job of a sweep on Slurm.
pub fn run_merge_job(dir: &Path, quiet: bool) -> Result<ExitCode> {
    let r = shards::merge_shards(dir)?;
    if quiet {
        return Ok(ExitCode::SUCCESS);
    }
    out!("merged {} rows into {}: every point of the sweep ({}) is present", r.rows, dir.join("results.csv").display(), r.total);
    Ok(ExitCode::SUCCESS)
}

/// `shards 1-4 (4 of 4) and their merge`, or `the merge of the complete shards`.
fn submitted_text(report: &SubmitReport) -> String {
    if report.submitted.is_empty() {
        "the merge of the complete shards".into()
    } else {
        let word = if report.submitted.len() == 1 { "shard" } else { "shards" };
        format!("{word} {} ({} of {}) and their merge", slurm::array_spec(&report.submitted), report.submitted.len(), report.layout.shards)
    }
}

/// After the merge job of `--wait` has ended: 0 if DIR/results.csv holds every point,
/// else 1 with the incomplete shards.
fn finish(report: &SubmitReport, merge: Option<&slurm::JobState>, quiet: bool) -> Result<ExitCode> {
    let dir = &report.dir;
    let merge_id = report.merge_job.as_deref().unwrap_or("?");
    let log = dir.join("slurm").join("logs").join(format!("merge-{merge_id}.out"));
    if shards::merged(dir) {
        let state = shards::results_state(dir)?;
        if quiet {
            return Ok(ExitCode::SUCCESS);
        }
        out!(
            "merged: {} holds every point ({}): {} converged, {} failed",
            dir.join("results.csv").display(),
            state.points,
            state.converged,
            state.failed
        );
        return Ok(ExitCode::SUCCESS);
    }
    let states = shards::shard_states(dir, &report.layout)?;
    note!(
        "error: the merge job {merge_id} ended ({}) without merging: {}; its log: {}. Run the same command again to submit the incomplete shards (they resume)",
        merge.map_or("state no longer known to Slurm".into(), |s| s.state.clone()),
        incomplete_text(&report.layout, &states),
        log.display()
    );
    Ok(ExitCode::FAILURE)
}

/// `2 of 4 shards incomplete (2: 3 of 3 points missing, …)`.
pub fn incomplete_text(layout: &ShardLayout, states: &[ShardState]) -> String {
    let incomplete = shards::Incomplete(states.iter().filter(|s| !s.complete()).map(|s| (s.k, s.missing, s.points)).collect());
    if incomplete.0.is_empty() {
        return format!("every shard of {} is complete", layout.shards);
    }
    format!("{} of {} shards incomplete: {incomplete}", incomplete.0.len(), layout.shards)
}
