//! Command-line interface of skg-solve.

mod commands;
mod stdio;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use commands::{animate, bench, check, fit, gallery, plot, reference, solve, status, sweep, tune};

#[derive(Parser)]
#[command(
    name = "skg-solve",
    version,
    about = "Motion of mechanical systems with velocity constraints, walls and friction \
             from the critical point of the discretized Schwinger–Keldysh–Galley action",
    long_about = "Solves a mechanical scene written in TOML: the classical Schwinger–Keldysh–Galley \
action of the scene is discretized in time with summation-by-parts operators and its critical point \
— the whole trajectory at once — is found by Ipopt with exact sparse derivatives.\n\n\
Writes DIR/trajectory.csv (t, each coordinate and its velocity Dq, each multiplier, the energy, the \
walls' potential energy, each constraint residual, each position constraint's drift, each wall gap), \
DIR/reference.csv (the same scene integrated by time stepping at the same nodes) and, last, DIR/summary.json \
(status, verification, attempts, iterations, timings, sizes, residuals, and the SHA-256 of the files it \
belongs with: check and plot refuse a trajectory that its summary does not describe). A second skg-solve \
writing into the same DIR is refused.\n\n\
Every solve is verified: the trajectory must be within the scene's [verify] tol (or --verify-tol; default \
1e-4 x each coordinate's range, at least 1e-7 x the largest one) of time stepping of the same scene, every number finite and the \
kinetic matrix positive definite at every node. When the solve does not converge or verify, the fallback \
ladder tries a coarse-to-fine guess, wall-width continuation, a solve past the end time and windows of \
halving length (--no-fallback to skip it).\n\n\
Exit status, the same for every command: 0 success (a solve: converged and verified); 1 an error in the \
input or while reading or writing files (the message names the file, line and column); 2 a command-line \
usage error; 3 the solve did not converge (the summary is still written, marked \"converged\": false); 4 a \
solve converged but did not verify (the message says why and names the remedy), or a tolerance was \
exceeded (check).",
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    solve: solve::SolveArgs,
    /// Print only errors and warnings: no progress, no summary lines, no tables. Every
    /// command takes it after its name, e.g. `skg-solve sweep FILE -q`.
    #[arg(short, long, global = true)]
    quiet: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Time solves of one scene over a ladder of node counts and print a table
    /// (wall time split into setup, initial guess, evaluations and the solver; the
    /// verification in its own column; peak memory).
    Bench(bench::BenchArgs),
    /// Run a parameter sweep: the points of the sweep file's grid in worker processes,
    /// each finished point appended to DIR/results.csv. Rerunning resumes.
    #[command(long_about = sweep::sweep_long_about())]
    Sweep(sweep::SweepArgs),
    /// Join the results of a sweep's shards into one results.csv.
    Merge(sweep::MergeArgs),
    /// The points of a sweep directory that are converged, failed and missing, per shard
    /// for a sweep run with --slurm, with the Slurm jobs' states while Slurm knows them.
    Status(status::StatusArgs),
    /// Find the smallest wall width σ whose energy artifact stays below a tolerance
    /// at the scene's N (bisection over solves).
    Tune(tune::TuneArgs),
    /// An animation of a solution's motion in the plane of two coordinates (GIF, MP4
    /// with ffmpeg, or a PNG strip of frames), with the walls and a time stamp.
    Animate(animate::AnimateArgs),
    /// Solve every shipped scene and write a Markdown page with its path, a strip of
    /// frames, the verification's error and the time (how docs/gallery.md is made).
    Gallery(gallery::GalleryArgs),
    /// Charts (SVG and PNG) from a sweep's results.csv or from solutions.
    #[command(subcommand)]
    Plot(plot::PlotKind),
    /// Worker process of a sweep (internal): runs the points whose ids arrive on stdin
    /// (protocol: the `skg_sweep::workers` module).
    #[command(hide = true)]
    SweepWorker { work: PathBuf },
    /// The merge job of a sweep on Slurm (internal): merges DIR/shards/* into
    /// DIR/results.csv when every point is there.
    #[command(hide = true)]
    SweepMerge { dir: PathBuf },
    /// Integrate the Lagrange–d'Alembert equations of a scene with a tight-tolerance
    /// adaptive integrator (DOP853) and write a reference CSV with the solver's columns.
    Reference(reference::ReferenceArgs),
    /// Fit scene parameters and initial data to measured motion (Ipopt minimizes the
    /// weighted least-squares misfit under the discrete equations of motion); writes the
    /// fitted motion, data.csv, fitted.toml and summary.json with a `fit` object
    /// (docs/fitting.md). Exit status 0 only when the fit converged and the fitted motion
    /// verified; 3 not converged; 4 not verified.
    Fit(fit::FitArgs),
    /// Compare a trajectory CSV with a reference CSV column by column (exit status 4 when
    /// a tolerance is exceeded).
    Check(check::CheckArgs),
}

fn main() -> ExitCode {
    stdio::finish(run())
}

/// Parse the command line and run the command; its exit status, with an error printed.
fn run() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return stdio::clap_message(&e),
    };
    let quiet = cli.quiet;
    let result = match cli.command {
        Some(Command::Bench(a)) => bench::run(a, quiet),
        Some(Command::Sweep(a)) if a.slurm => sweep::slurm::run(a, quiet),
        Some(Command::Sweep(a)) => sweep::run(a, quiet),
        Some(Command::Merge(a)) => sweep::run_merge(a, quiet),
        Some(Command::Status(a)) => status::run(a, quiet),
        Some(Command::SweepMerge { dir }) => sweep::slurm::run_merge_job(&dir, quiet),
        Some(Command::Tune(a)) => tune::run(a, quiet),
        Some(Command::Plot(k)) => plot::run(k, quiet),
        Some(Command::Animate(a)) => animate::run(a, quiet),
        Some(Command::Gallery(a)) => gallery::run(a, quiet),
        Some(Command::SweepWorker { work }) => sweep::run_worker(&work),
        Some(Command::Reference(a)) => reference::run(a, quiet),
        Some(Command::Check(a)) => check::run(a, quiet),
        Some(Command::Fit(a)) => fit::run(a, quiet),
        None => solve::run(cli.solve, quiet),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            stdio::note!("error: {}", describe(&e));
            match e.downcast_ref::<commands::UsageError>() {
                Some(_) => ExitCode::from(2),
                None => ExitCode::FAILURE,
            }
        }
    }
}

/// The error and its causes ([`skg_core::error_text`]).
fn describe(e: &anyhow::Error) -> String {
    skg_core::error_text(e.as_ref())
}
