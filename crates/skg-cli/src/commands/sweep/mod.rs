//! `skg-solve sweep` (local worker processes), `merge` and the hidden `sweep-worker`;
//! the arguments of `sweep`, which [`slurm`] (`sweep --slurm` and the hidden
//! `sweep-merge`) shares. This module only declares [`slurm`]: `main` dispatches
//! `sweep --slurm` there, and the child uses the parent's [`SweepArgs`], not the other
//! way round.
//!
//! The layout of `results.csv` and `sweep.json` is documented in the `skg_sweep` crate;
//! [`sweep_long_about`] is its summary in `skg-solve sweep --help`. In short: a
//! scene-parameter axis's column holds the evaluated number (`sigma = "1/110"` →
//! `0.00909090909090909`), and an axis with any value written as an expression also
//! gets `<axis>_expr` with the values as written (`1/110`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;

use crate::stdio::{note, out};
use skg_sweep as sweep;

pub mod slurm;

/// `skg-solve sweep --help`: what the command writes (column lists from `skg_sweep`).
pub fn sweep_long_about() -> String {
    let statuses: Vec<&str> = sweep::PointStatus::ALL.iter().map(|s| s.name()).collect();
    format!(
        "Run a parameter sweep: the points of the sweep file's grid in up to --jobs worker processes, each finished \
         point appended to DIR/results.csv. A worker runs one point after another, points of equal structure (node \
         count, operator, formulation, backend) in a row, so that the Newton backend reuses the symbolic LU analysis \
         (column lu_analysis); a worker that crashes or exceeds the sweep's timeout costs only its point. Rerunning resumes (points already in results.csv are skipped; --retry-failed runs \
         the failed ones again). A rerun after the base scene, the reference file or the [sweep] settings that \
         change a row were edited is refused (--new-results starts a new result set). A second sweep into the same \
         DIR is refused. Above {} points the sweep starts only with --yes.\n\n\
         results.csv is a plain CSV, one row per point, with the columns {}; one column per grid axis; {}; and the \
         provenance {}. status is one of {} (converged is true exactly for `converged`); solver_status is the \
         finishing backend's status name (Ipopt's, Newton_..., ODE_Succeeded for a peer point); scene_hash and \
         reference_hash are the SHA-256 of the base scene file's and the reference file's content.

\
         A grid axis that is a scene parameter holds the number the point's scene has (sigma = \"1/110\" gives \
         0.00909090909090909, the shortest text that reads back to the same double). If any of its values is \
         written as an expression, the column <axis>{} follows it with every value as written (1/110); an axis of \
         plain numbers has none. `skg-solve plot ... --where sigma=1/110` matches either.\n\n\
         DIR/sweep.json records the sweep's name, the sweep file, the base scene, the same provenance, the settings \
         that change a row, the number of points, the shard, the ids of the shard's points and of every point (merge \
         uses them to find missing points).",
        sweep::CONFIRM_ABOVE,
        sweep::LEADING_COLUMNS.join(", "),
        sweep::RESULT_COLUMNS.join(", "),
        sweep::PROVENANCE_COLUMNS.join(", "),
        statuses.join(", "),
        sweep::EXPR_SUFFIX,
    )
}

#[derive(Args)]
pub struct SweepArgs {
    /// Sweep file (TOML), e.g. scenarios/sweeps/tumbler_sigma_ladder.toml.
    #[arg(value_name = "SWEEP.toml")]
    pub sweep: PathBuf,
    /// Output directory [default: out/sweeps/<sweep file name without .toml>].
    #[arg(short, long, value_name = "DIR")]
    pub output: Option<PathBuf>,
    /// Worker processes at once [default: the number of cores].
    #[arg(short, long, value_name = "K")]
    pub jobs: Option<usize>,
    /// Run only the points whose index is k−1 mod n (1 ≤ k ≤ n), e.g. `--shard 3/8`.
    #[arg(long, value_name = "k/n")]
    pub shard: Option<sweep::Shard>,
    /// Run again the points that did not converge in an earlier run (crashed, timed out,
    /// errors, not converged): their rows in results.csv are replaced.
    #[arg(long)]
    pub retry_failed: bool,
    /// Start a new result set in DIR: the old results.csv, sweep.json and points/ move
    /// to DIR/superseded-<unix time>/ (needed after the base scene, the reference file
    /// or the [sweep] settings changed; a plain rerun refuses to mix them).
    #[arg(long)]
    pub new_results: bool,
    /// Start even when more than 10000 points would run (the point count and a rough
    /// time estimate are printed first).
    #[arg(short, long)]
    pub yes: bool,
    /// Run the sweep on a Slurm cluster: write DIR/slurm/shard.sh (an array job whose
    /// task k runs shard k/K into DIR/shards/k, with one worker per CPU Slurm gives it) and
    /// DIR/slurm/merge.sh (a job after the array that merges the shards into
    /// DIR/results.csv), submit both with sbatch, print the job ids. Run again, it submits
    /// only the incomplete shards (they resume). DIR must be on a file system the nodes
    /// share.
    #[arg(long, conflicts_with_all = ["shard", "jobs", "retry_failed", "new_results"])]
    pub slurm: bool,
    /// Shards of a --slurm sweep (the array's tasks), 1 to 1000 [default: one per 10
    /// points, at most 100; a directory keeps the number it was started with].
    #[arg(long, value_name = "K", requires = "slurm", value_parser = clap::value_parser!(u64).range(1..=1000))]
    pub shards: Option<u64>,
    /// An argument for sbatch, for the array and the merge job (repeatable), e.g.
    /// `--sbatch-arg=--partition=short --sbatch-arg=--time=2:00:00 --sbatch-arg=--cpus-per-task=8`.
    #[arg(long = "sbatch-arg", value_name = "ARG", requires = "slurm", allow_hyphen_values = true)]
    pub sbatch_args: Vec<String>,
    /// With --slurm: wait until the merge job has ended; exit 0 when DIR/results.csv holds
    /// every point, else 1.
    #[arg(long, requires = "slurm", conflicts_with = "dry_run")]
    pub wait: bool,
    /// With --slurm: write the scripts and print the sbatch commands without submitting.
    #[arg(long, requires = "slurm")]
    pub dry_run: bool,
}

#[derive(Args)]
pub struct MergeArgs {
    /// The shards' output directories (or their results.csv files).
    #[arg(required = true, value_name = "SHARD")]
    pub inputs: Vec<PathBuf>,
    /// Output directory of the merged results.csv.
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,
    /// Merge even when points of the sweep are missing (they are listed); without it an
    /// incomplete merge writes nothing and exits 1.
    #[arg(long)]
    pub partial: bool,
}

/// `skg-solve sweep FILE` without `--slurm`: the points in local worker processes.
pub fn run(args: SweepArgs, quiet: bool) -> Result<ExitCode> {
    let file = sweep::SweepFile::load(&args.sweep)?;
    let opts = sweep::SweepOptions {
        out_dir: args.output.unwrap_or_else(|| sweep::default_out_dir(&file)),
        jobs: args.jobs.unwrap_or_else(sweep::default_jobs).max(1),
        shard: args.shard,
        worker_exe: std::env::current_exe().context("locating the skg-solve executable for the workers")?,
        progress: !quiet,
        retry_failed: args.retry_failed,
        new_results: args.new_results,
    };
    let plan = sweep::plan(&file, &opts, args.yes)?;
    if !quiet {
        note!("{}", plan.text);
    }
    // SIGTERM (scancel, a Slurm time limit) and Ctrl-C stop the sweep between two rows;
    // then this process dies of the same signal.
    sweep::stop_on_signals();
    let r = match sweep::run_sweep(&file, &plan.expanded, &opts) {
        Err(e @ sweep::SweepError::Stopped { signal, .. }) => {
            note!("{e}");
            sweep::die_of(signal)
        }
        r => r?,
    };
    if !quiet {
        if let Some(old) = &r.superseded {
            out!("  moved the previous results to {}", old.display());
        }
        out!(
            "{}: {} points{}, {} already done, {} run ({} failed) with {} worker(s) in {:.1} s{}",
            file.name(),
            r.total,
            args.shard.map_or(String::new(), |s| format!(" ({} in shard {}/{})", r.in_shard, s.k, s.n)),
            r.skipped,
            r.ran,
            r.failed,
            opts.jobs,
            r.wall_s,
            if r.duplicates > 0 { format!("; {} duplicate points dropped", r.duplicates) } else { String::new() }
        );
        out!("  wrote {}", r.results.display());
    }
    Ok(ExitCode::SUCCESS)
}

pub fn run_worker(work: &Path) -> Result<ExitCode> {
    sweep::serve_points(work, std::io::stdin().lock())?;
    Ok(ExitCode::SUCCESS)
}

pub fn run_merge(args: MergeArgs, quiet: bool) -> Result<ExitCode> {
    let r = sweep::merge(&args.inputs, &args.output, args.partial)?;
    if !quiet {
        out!(
            "merged {} rows into {}{}",
            r.rows,
            args.output.join("results.csv").display(),
            if r.duplicates > 0 { format!("; {} duplicate rows dropped", r.duplicates) } else { String::new() },
        );
    }
    if r.missing.is_empty() {
        if !quiet {
            out!("every point of the sweep ({}) is present", r.total);
        }
    } else {
        note!("warning: {} of the sweep's {} points are missing (--partial): {}", r.missing.len(), r.total, sweep::list_points(&r.missing));
    }
    Ok(ExitCode::SUCCESS)
}
