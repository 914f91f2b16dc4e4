//! `skg-solve check`: compare a trajectory CSV with a reference CSV.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;

use skg_core::check::{self, CheckOptions, Table, Tolerances};
use skg_core::output;
use skg_core::scene::readable_number;

use super::EXIT_TOLERANCE_EXCEEDED;
use crate::stdio::{note, out};

#[derive(Args)]
pub struct CheckArgs {
    /// The trajectory to check (e.g. out/tumbler/trajectory.csv).
    #[arg(value_name = "SOLUTION.csv")]
    pub solution: PathBuf,
    /// The reference (e.g. references/tumbler.csv).
    #[arg(value_name = "REFERENCE.csv")]
    pub reference: PathBuf,
    /// Leave out the last K rows of the solution (e.g. 2 for the SBP end nodes).
    #[arg(long, default_value_t = 0, value_name = "K")]
    pub skip_last: usize,
    /// Compare only these columns (comma-separated) [default: every shared column except t].
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    pub columns: Option<Vec<String>>,
    /// Tolerance on every compared column's max |error|.
    #[arg(long, allow_negative_numbers = true, value_name = "TOL")]
    pub tol: Option<f64>,
    /// Tolerance on every compared column's RMS error.
    #[arg(long, allow_negative_numbers = true, value_name = "TOL")]
    pub tol_rms: Option<f64>,
    /// Tolerance on one column's max |error| (repeatable; overrides --tol for it).
    #[arg(long, value_name = "COLUMN=TOL")]
    pub tol_column: Vec<String>,
    /// JSON report [default: <SOLUTION without .csv>.check.json].
    #[arg(long, value_name = "FILE.json")]
    pub json: Option<PathBuf>,
}

/// A tolerance from the command line: a number ≥ 0 (NaN would silently pass every
/// comparison).
fn tolerance(option: &str, value: f64) -> Result<f64> {
    if value >= 0.0 && !value.is_nan() {
        Ok(value)
    } else {
        anyhow::bail!("{option}: a tolerance must be a number ≥ 0, got {}", readable_number(value))
    }
}

#[derive(serde::Serialize)]
struct CheckReport<'a> {
    solution: String,
    reference: String,
    options: &'a CheckOptions,
    tolerances: &'a Tolerances,
    passed: bool,
    violations: Vec<String>,
    comparison: &'a check::Comparison,
}

pub fn run(args: CheckArgs, quiet: bool) -> Result<ExitCode> {
    let (solution, pairing) = Table::read_paired(&args.solution)?;
    if let Some(w) = pairing.warning(&args.solution) {
        note!("warning: {w}");
    }
    let reference = Table::read(&args.reference)?;
    let opts = CheckOptions { skip_last: args.skip_last, columns: args.columns.clone() };
    let tol = tolerances(&args)?;
    let cmp = check::compare(&solution, &reference, &opts)
        .with_context(|| format!("comparing {} with {}", args.solution.display(), args.reference.display()))?;
    let violations = cmp.violations(&tol)?;
    let json = args.json.clone().unwrap_or_else(|| args.solution.with_extension("check.json"));
    let report = CheckReport {
        solution: args.solution.display().to_string(),
        reference: args.reference.display().to_string(),
        options: &opts,
        tolerances: &tol,
        passed: violations.is_empty(),
        violations: violations.clone(),
        comparison: &cmp,
    };
    output::write_json(&json, &report)?;
    if !quiet {
        print_comparison(&cmp);
        out!("wrote {}", json.display());
    }
    if violations.is_empty() {
        Ok(ExitCode::SUCCESS)
    } else {
        for v in &violations {
            note!("tolerance exceeded: {v}");
        }
        Ok(ExitCode::from(EXIT_TOLERANCE_EXCEEDED))
    }
}

/// `--tol`, `--tol-rms` and each `--tol-column COLUMN=TOL`, each a number ≥ 0.
fn tolerances(args: &CheckArgs) -> Result<Tolerances> {
    let mut per_column = Vec::new();
    for a in &args.tol_column {
        let (name, value) = a.split_once('=').with_context(|| format!("--tol-column `{a}`: expected COLUMN=TOL"))?;
        let v: f64 = value.trim().parse().with_context(|| format!("--tol-column `{a}`: `{value}` is not a number"))?;
        per_column.push((name.trim().to_string(), tolerance(&format!("--tol-column {a}"), v)?));
    }
    Ok(Tolerances {
        max_abs: args.tol.map(|t| tolerance("--tol", t)).transpose()?,
        rms: args.tol_rms.map(|t| tolerance("--tol-rms", t)).transpose()?,
        per_column,
    })
}

/// The comparison on stdout: a Markdown table of each column's errors, the rows compared
/// and the worst column, and the columns the reference lacks.
fn print_comparison(cmp: &check::Comparison) {
    out!("| column | max abs error | at t | RMS error |");
    out!("|---|---:|---:|---:|");
    for c in &cmp.columns {
        out!("| {} | {:.3e} | {} | {:.3e} |", c.column, c.max_abs, c.at_t, c.rms);
    }
    out!(
        "{} rows compared ({} interpolated, last {} skipped); worst: {} {:.3e}",
        cmp.rows_compared,
        cmp.rows_interpolated,
        cmp.skipped_last,
        cmp.worst_column,
        cmp.max_abs
    );
    if !cmp.missing_in_reference.is_empty() {
        out!("not in the reference (not compared): {}", cmp.missing_in_reference.join(", "));
    }
}
