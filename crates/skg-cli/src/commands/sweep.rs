//! `skg-solve sweep`, `merge` and the hidden `sweep-worker`.
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

use skg_core::output;
use skg_sweep as sweep;

/// `skg-solve sweep --help`: what the command writes (column lists from `skg_sweep`).
pub fn sweep_long_about() -> String {
    let statuses: Vec<&str> = sweep::PointStatus::ALL.iter().map(|s| s.name()).collect();
    format!(
        "Run a parameter sweep: every point of the sweep file's grid in its own worker process, each finished point \
         appended to DIR/results.csv. Rerunning resumes (points already in results.csv are skipped; rows of a base \
         scene whose content has changed since are refused).\n\n\
         results.csv is a plain CSV, one row per point, with the columns {}; one column per grid axis; {}; and the \
         provenance {}. status is one of {} (converged is true exactly for `converged`); solver_status is the \
         finishing backend's status name (Ipopt's, Newton_..., ODE_Succeeded for a peer point); scene_hash is the SHA-256 of the base scene file's content.\n\n\
         A grid axis that is a scene parameter holds the number the point's scene has (sigma = \"1/110\" gives \
         0.00909090909090909, the shortest text that reads back to the same double). If any of its values is \
         written as an expression, the column <axis>{} follows it with every value as written (1/110); an axis of \
         plain numbers has none. `skg-solve plot ... --where sigma=1/110` matches either.\n\n\
         DIR/sweep.json records the sweep's name, the sweep file, the base scene, the same provenance, the number \
         of points, the shard and the ids of the shard's points.",
        sweep::LEADING_COLUMNS.join(", "),
        sweep::RESULT_COLUMNS.join(", "),
        sweep::PROVENANCE_COLUMNS.join(", "),
        statuses.join(", "),
        sweep::EXPR_SUFFIX,
    )
}

#[derive(Args)]
pub struct SweepArgs {
    /// Sweep file (TOML), e.g. scenarios/sweeps/tumbler_sigma.toml.
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
    /// No progress bar and no summary line.
    #[arg(short, long)]
    pub quiet: bool,
}

#[derive(Args)]
pub struct MergeArgs {
    /// The shards' output directories (or their results.csv files).
    #[arg(required = true, value_name = "SHARD")]
    pub inputs: Vec<PathBuf>,
    /// Output directory of the merged results.csv.
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,
}

pub fn run(args: SweepArgs) -> Result<ExitCode> {
    let file = sweep::SweepFile::load(&args.sweep)?;
    let out = args.output.unwrap_or_else(|| PathBuf::from("out/sweeps").join(file.name()));
    let jobs = args.jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let opts = sweep::SweepOptions {
        out_dir: out,
        jobs,
        shard: args.shard,
        worker_exe: std::env::current_exe().context("locating the skg-solve executable for the workers")?,
        progress: !args.quiet,
    };
    let r = sweep::run_sweep(&file, &opts)?;
    if !args.quiet {
        println!(
            "{}: {} points{}, {} already done, {} run ({} failed) with {} worker(s) in {:.1} s{}",
            file.name(),
            r.total,
            args.shard.map_or(String::new(), |s| format!(" ({} in shard {}/{})", r.in_shard, s.k, s.n)),
            r.skipped,
            r.ran,
            r.failed,
            jobs,
            r.wall_s,
            if r.duplicates > 0 { format!("; {} duplicate points dropped", r.duplicates) } else { String::new() }
        );
        println!("  wrote {}", r.results.display());
    }
    Ok(ExitCode::SUCCESS)
}

pub fn run_worker(job: &Path, result: &Path) -> Result<ExitCode> {
    let text = std::fs::read_to_string(job).with_context(|| format!("reading {}", job.display()))?;
    let job: sweep::Job = serde_json::from_str(&text).with_context(|| format!("parsing {}", job.display()))?;
    let rec = sweep::run_job(&job);
    output::write_json(result, &rec)?;
    Ok(ExitCode::SUCCESS)
}

pub fn run_merge(args: MergeArgs) -> Result<ExitCode> {
    let r = sweep::merge(&args.inputs, &args.output)?;
    println!(
        "merged {} rows into {}{}{}",
        r.rows,
        args.output.join("results.csv").display(),
        if r.duplicates > 0 { format!("; {} duplicate rows dropped", r.duplicates) } else { String::new() },
        match r.missing {
            Some(0) => "; every point of the sweep is present".to_string(),
            Some(m) => format!("; {m} points of the sweep have no row yet"),
            None => String::new(),
        }
    );
    Ok(ExitCode::SUCCESS)
}
