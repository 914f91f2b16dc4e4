//! `skg-solve bench`: time solves over a ladder of node counts.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;

use skg_core::output;
use skg_core::solve::{self, Method, Outcome};
use skg_core::stepping::verify::VerifyStatus;

use super::{load, SceneArgs, EXIT_NOT_CONVERGED, EXIT_NOT_VERIFIED};
use crate::stdio::{note, out};

#[derive(Args)]
pub struct BenchArgs {
    /// Scene file (TOML).
    #[arg(value_name = "SCENARIO.toml")]
    pub scenario: PathBuf,
    /// Comma-separated node counts.
    #[arg(long, value_delimiter = ',', default_value = "256,512,1024,2048,4096,8192,16384")]
    pub nodes: Vec<usize>,
    /// Repetitions per node count (the fastest is reported; at least 1).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub repeat: u32,
    /// Also write the rows as CSV to this file (for `skg-solve plot scaling`).
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    #[command(flatten)]
    pub scene: SceneArgs,
}

/// One measured row: the fastest repetition at one N.
struct Row {
    nodes: usize,
    wall_s: f64,
    peak_mib: Option<f64>,
    outcome: Outcome,
}

impl Row {
    /// The backend that ran: `ipopt`, `newton`, or `newton→ipopt` after a hand-over.
    fn backend(&self) -> String {
        let b = &self.outcome.backend;
        if b.handed_over_to_ipopt {
            format!("{}→ipopt", b.requested)
        } else {
            b.requested.to_string()
        }
    }

    /// Wall seconds of the solve: the repetition's wall time without the verification
    /// (which every solve runs, [`skg_core::stepping::verify`], and which is timed in its own
    /// column).
    fn solve_s(&self) -> f64 {
        self.wall_s - self.outcome.timings.verification_s
    }

    /// How the solve ended: `verified`, `not verified` (converged, verification failed
    /// or impossible), `not converged`, or `converged` (verification skipped).
    fn result(&self) -> &'static str {
        let o = &self.outcome;
        match (o.converged(), o.verification.status) {
            (false, _) => "not converged",
            (true, VerifyStatus::Passed) => "verified",
            (true, VerifyStatus::Skipped) => "converged",
            (true, _) => "not verified",
        }
    }

    /// How the span was covered: `global`, or `K windows` (the sizes and iterations are
    /// then those of one window).
    fn solved_as(&self) -> String {
        match self.outcome.method {
            Method::Global => "global".into(),
            Method::Windows { count, .. } => format!("{count} windows"),
        }
    }

    /// The columns: N, sizes, backend, iterations, result, how the span was solved, the
    /// time split, the time per node and the peak memory.
    fn cells(&self) -> Vec<String> {
        let (o, t) = (&self.outcome, &self.outcome.timings);
        vec![
            self.nodes.to_string(),
            o.sizes.variables.to_string(),
            o.sizes.jacobian_nonzeros.to_string(),
            self.backend(),
            o.iterations.to_string(),
            self.result().to_string(),
            self.solved_as(),
            format!("{:.4}", t.setup_s),
            format!("{:.4}", t.initial_guess_s),
            format!("{:.4}", t.evaluation_s),
            format!("{:.4}", t.solver_internal_s),
            format!("{:.4}", self.solve_s()),
            format!("{:.2}", 1e6 * self.solve_s() / self.nodes as f64),
            format!("{:.4}", t.verification_s),
            self.peak_mib.map_or("–".into(), |m| format!("{m:.0}")),
        ]
    }
}

const HEADER: [&str; 15] = [
    "N",
    "variables",
    "Jacobian nnz",
    "backend",
    "iterations",
    "result",
    "solved as",
    "setup s",
    "guess s",
    "eval s",
    "solver internal s",
    "total s",
    "µs per node",
    "verify s",
    "peak MiB",
];
const CSV_HEADER: &str =
    "nodes,variables,jacobian_nonzeros,backend,iterations,result,solved_as,setup_s,guess_s,evaluation_s,solver_internal_s,total_s,us_per_node,verify_s,peak_mib";

pub fn run(args: BenchArgs, quiet: bool) -> Result<ExitCode> {
    // The CSV's directory is made before the solves, so that a path that cannot be
    // written fails at once, not after minutes of solving.
    if let Some(dir) = args.csv.as_deref().and_then(|p| p.parent()).filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let rows = measure(&args, quiet)?;
    if !quiet {
        print_table(&rows);
    }
    if let Some(path) = &args.csv {
        let mut text = format!("{CSV_HEADER}\n");
        for row in &rows {
            text.push_str(&row.cells().join(","));
            text.push('\n');
        }
        output::write_atomic(path, |w| w.write_all(text.as_bytes()))?;
    }
    // Timings of solves that cannot be trusted are not benchmarks of the scene: say so,
    // and exit as a solve would (3 if any did not converge, else 4 if any did not verify).
    let untrusted: Vec<String> = rows.iter().filter(|r| !r.outcome.trusted()).map(|r| format!("N = {} {}", r.nodes, r.result())).collect();
    if untrusted.is_empty() {
        return Ok(ExitCode::SUCCESS);
    }
    note!(
        "warning: {}; their times are not those of a trustworthy solve (run the scene with `skg-solve` for the reason)",
        untrusted.join(", ")
    );
    let code = if rows.iter().any(|r| !r.outcome.converged()) { EXIT_NOT_CONVERGED } else { EXIT_NOT_VERIFIED };
    Ok(ExitCode::from(code))
}

/// Solve the scene `--repeat` times at each N, with a progress bar (none with
/// `--quiet`): the fastest repetition at each N.
fn measure(args: &BenchArgs, quiet: bool) -> Result<Vec<Row>> {
    let solves = args.nodes.len() as u64 * u64::from(args.repeat);
    let bar = if quiet { indicatif::ProgressBar::hidden() } else { indicatif::ProgressBar::new(solves) };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} solves, {elapsed} elapsed, ETA {eta} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut rows = Vec::new();
    for &n in &args.nodes {
        let ov = args.scene.overrides(Some(n))?;
        let scene = load(&args.scenario, &ov)?;
        let mut best: Option<Row> = None;
        for _ in 0..args.repeat {
            bar.set_message(format!("N={n}"));
            let peak = PeakMemory::reset();
            let start = Instant::now();
            let outcome = solve::solve_scene(&scene)?;
            let wall_s = start.elapsed().as_secs_f64();
            let peak_mib = peak.and_then(|p| p.read_mib());
            bar.inc(1);
            if best.as_ref().is_none_or(|b| wall_s < b.wall_s) {
                best = Some(Row { nodes: n, wall_s, peak_mib, outcome });
            }
        }
        rows.push(best.expect("at least one repetition"));
    }
    bar.finish_and_clear();
    Ok(rows)
}

/// The rows as a Markdown table on stdout.
fn print_table(rows: &[Row]) {
    out!("| {} |", HEADER.join(" | "));
    out!(
        "|{}",
        HEADER.iter().map(|h| if matches!(*h, "backend" | "result" | "solved as") { ":---:|" } else { "---:|" }).collect::<String>()
    );
    for row in rows {
        out!("| {} |", row.cells().join(" | "));
    }
}

/// The process's peak resident memory since a reset (Linux: `VmHWM` of
/// `/proc/self/status`, reset by writing 5 to `/proc/self/clear_refs`). Elsewhere, or
/// when the reset is refused, there is no measurement.
struct PeakMemory;

impl PeakMemory {
    fn reset() -> Option<PeakMemory> {
        std::fs::write("/proc/self/clear_refs", "5").ok().map(|_| PeakMemory)
    }

    fn read_mib(&self) -> Option<f64> {
        let status = std::fs::read_to_string("/proc/self/status").ok()?;
        let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
        let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kib / 1024.0)
    }
}
