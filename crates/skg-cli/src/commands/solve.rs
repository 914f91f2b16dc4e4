//! The default command: solve one scene and write its trajectory and summary.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Result;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use skg_core::output::{self, Written};
use skg_core::scene::{Backend, Overrides, Scene};
use skg_core::solve;
use skg_core::solve::backend::SolverStatus;
use skg_core::stepping::verify::VerifyStatus;

use super::{load, SceneArgs, EXIT_NOT_CONVERGED, EXIT_NOT_VERIFIED};
use crate::stdio::{note, out};

#[derive(Args)]
pub struct SolveArgs {
    /// Scene file (TOML), e.g. scenarios/rolling_disk.toml.
    #[arg(required = true, value_name = "SCENARIO.toml")]
    pub scenario: Option<PathBuf>,
    /// Output directory [default: out/<scene file name without .toml>].
    #[arg(short, long, value_name = "DIR")]
    pub output: Option<PathBuf>,
    /// Number of time nodes N (overrides the scene's time.nodes).
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub nodes: Option<usize>,
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Solve to the verification's tolerance: while the solve is not verified, solve
    /// again on the next grid (and, unless --operator names one, with the operator)
    /// predicted to meet the tolerance at the least cost; the scene's N is the first
    /// grid. See docs/trust.md#refinement.
    #[arg(long)]
    pub refine: bool,
    /// The largest grid --refine may use [default: the scene's [verify] max_nodes, else
    /// the largest the available memory allows, at most 1048576].
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = clap::value_parser!(u64).range(2..=100_000_000))]
    pub max_nodes: Option<u64>,
    /// Seconds the whole solve may take (fallback ladder and refinement included),
    /// checked between attempts and inside each solve's iterations: the best attempt so
    /// far is then reported (exit 3 if the limit stopped it before it converged).
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true, value_parser = super::positive)]
    pub time_limit: Option<f64>,
}

/// The backend that finished, for the summary line: `Ipopt`, `Newton`, or
/// `Ipopt (after Newton failed)`.
fn solver_name(outcome: &solve::Outcome) -> &'static str {
    match (outcome.status.solver(), outcome.backend.handed_over_to_ipopt) {
        (SolverStatus::Newton(_) | SolverStatus::TimeLimitReached { backend: Backend::Newton, .. }, _) => "Newton",
        (_, false) => "Ipopt",
        (_, true) => "Ipopt (after Newton failed)",
    }
}

pub fn run(args: SolveArgs, quiet: bool) -> Result<ExitCode> {
    let path = args.scenario.clone().expect("clap requires the scenario");
    let mut scene = load(&path, &overrides(&args)?)?;
    if !quiet {
        for n in &scene.notes {
            note!("note: {n}");
        }
    }
    let dir = args.output.unwrap_or_else(|| {
        let stem = path.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from("out").join(stem)
    });
    let (outcome, written) = solve_with_progress(&dir, &mut scene, quiet)?;
    // With --quiet a trusted solve's notes are left out, as its ladder and refinement are.
    if !quiet || !outcome.trusted() {
        for n in &outcome.notes {
            note!("note: {n}");
        }
    }
    for w in &outcome.warnings {
        note!("warning: {w}");
    }
    print_attempts(&outcome, quiet);
    print_refinement(&outcome, quiet);
    if let Some(code) = report_untrusted(&outcome, &written) {
        return Ok(code);
    }
    if !quiet {
        print_report(&outcome, &scene, &written);
    }
    Ok(ExitCode::SUCCESS)
}

/// The scene's overrides: the shared options, the node count, and the refinement's.
fn overrides(args: &SolveArgs) -> Result<Overrides> {
    let mut ov = args.scene.overrides(args.nodes)?;
    ov.refine = args.refine;
    ov.max_nodes = args.max_nodes.map(|n| n as usize);
    ov.time_limit = args.time_limit;
    Ok(ov)
}

/// Solve the scene into `dir`, naming each attempt as it starts: on a terminal in the
/// spinner, elsewhere (a log, a pipe, a batch job) in one plain line per attempt, so
/// that a long solve is not silent. Nothing with `--quiet`.
fn solve_with_progress(dir: &Path, scene: &mut Scene, quiet: bool) -> Result<(solve::Outcome, Written)> {
    let spinner = progress_spinner(quiet, &scene.name);
    let lines = !quiet && !std::io::stderr().is_terminal();
    let name = scene.name.clone();
    let started = std::time::Instant::now();
    let solved = output::solve_into_with_progress(dir, scene, &mut |attempt| {
        if lines {
            note!("{name}: {attempt} ({:.1} s)", started.elapsed().as_secs_f64());
        }
        spinner.set_message(attempt.to_string())
    });
    spinner.finish_and_clear();
    Ok(solved?)
}

/// For a solve that did not converge or did not verify: say why, where the summary is
/// and the remedy, and give the exit status (3 or 4). None for a trusted solve.
fn report_untrusted(outcome: &solve::Outcome, written: &Written) -> Option<ExitCode> {
    let v = &outcome.verification;
    let code = if !outcome.converged() {
        note!(
            "error: {}: the solve did not converge: {} ({} iterations, residual {:.3e}); summary in {}",
            outcome.scene,
            outcome.status,
            outcome.iterations,
            outcome.diagnostics.max_residual,
            written.summary.display()
        );
        EXIT_NOT_CONVERGED
    } else if !outcome.trusted() {
        let verdict = match v.status {
            VerifyStatus::Unverified => "could not run",
            _ => "failed",
        };
        note!(
            "error: {}: the solve converged but its verification {verdict}: {}; summary in {}",
            outcome.scene,
            v.reason,
            written.summary.display()
        );
        EXIT_NOT_VERIFIED
    } else {
        return None;
    };
    if let Some(r) = &outcome.remedy {
        note!("  remedy: {r}");
    }
    Some(ExitCode::from(code))
}

/// The report of a trusted solve on stdout: iterations, backend, discretization and
/// time; how the span was solved (in windows); the verification; the residual and the
/// energy drift; each position constraint's drift; the files written.
fn print_report(outcome: &solve::Outcome, scene: &Scene, written: &Written) {
    let d = &outcome.diagnostics;
    out!(
        "{}: converged in {} {} iterations ({}), {} {} N={}{}, {:.3} s",
        outcome.scene,
        outcome.iterations,
        solver_name(outcome),
        outcome.status,
        outcome.settings.operator,
        outcome.settings.formulation,
        outcome.settings.nodes,
        if scene.constraints.is_empty() { String::new() } else { format!(", max |g| interior {:.1e}", d.max_constraint_interior) },
        outcome.timings.total()
    );
    if let solve::Method::Windows { .. } = outcome.method {
        out!("  solved as {}", outcome.method);
    }
    out!("  verified: {} ({})", outcome.verification.status, outcome.verification.reason);
    out!("  residual {:.1e}, energy drift {:.3e} ({})", d.max_residual, d.energy_drift, energy_drift_note(outcome, scene));
    for (name, drift) in &d.max_position_drift {
        out!("  position constraint {name}: drift max |h| {drift:.1e}");
    }
    for path in written.paths() {
        out!("  wrote {}", path.display());
    }
}

/// Which nodes the energy drift leaves out, and why the energy is not conserved when it
/// is not: `last two nodes excluded; not conserved: the scene depends on t`.
fn energy_drift_note(outcome: &solve::Outcome, scene: &Scene) -> String {
    let d = &outcome.diagnostics;
    let excluded = match d.energy_drift_skip {
        2 => "last two nodes excluded".to_string(),
        k => format!("last {k} nodes excluded: the end layer of {}", outcome.settings.operator),
    };
    let conserved = if d.depends_on_time {
        "; not conserved: the scene depends on t"
    } else if scene.has_non_conservative_forces() {
        "; not conserved: the scene has declared forces or friction"
    } else {
        ""
    };
    format!("{excluded}{conserved}")
}

/// A spinner on stderr naming the attempt under way, with the time so far (drawn only
/// when stderr is a terminal and not `--quiet`): a fallback ladder that fails can take
/// a minute.
pub(super) fn progress_spinner(quiet: bool, scene: &str) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let spinner = ProgressBar::new_spinner();
    let scene = scene.replace('{', "{{").replace('}', "}}");
    let style =
        ProgressStyle::with_template(&format!("{{spinner}} {scene}: {{msg}} ({{elapsed}})")).unwrap_or(ProgressStyle::default_spinner());
    spinner.set_style(style);
    spinner.enable_steady_tick(Duration::from_millis(200));
    spinner
}

/// When the fallback ladder ran, one line per attempt (on stderr, as notes).
fn print_attempts(outcome: &solve::Outcome, quiet: bool) {
    if outcome.attempts.len() < 2 || (quiet && outcome.trusted()) {
        return;
    }
    note!("note: the scene's own solve was not trusted; the fallback ladder tried:");
    for (i, a) in outcome.attempts.iter().enumerate() {
        note!("  {}. {}{} ({:.2} s): {}", i + 1, a.method, if a.chosen { " [reported]" } else { "" }, a.wall_s, a.result);
    }
}

/// When the grid was refined or the operator chosen, one line per discretization solved
/// (on stderr, as notes).
fn print_refinement(outcome: &solve::Outcome, quiet: bool) {
    let Some(r) = &outcome.refinement else { return };
    if quiet && outcome.trusted() {
        return;
    }
    let what = match (r.refine, r.operator_chosen) {
        (true, true) => "refined the grid and chose the operator",
        (true, false) => "refined the grid",
        (false, _) => "chose the operator",
    };
    note!("note: {what} for the tolerance ({}):", r.tolerance);
    for (i, g) in r.grids.iter().enumerate() {
        // Two decimals up to 10⁴, in exponent form beyond (a far-off grid's ratio has
        // hundreds of digits).
        let ratio = |x: Option<f64>| {
            x.map_or("–".to_string(), |x| if x.abs() < 1e4 || !x.is_finite() { format!("{x:.2}") } else { format!("{x:.2e}") })
        };
        note!(
            "  {}. {} ({}{}) on {} nodes: {} (error/tolerance {}, predicted {}) ({:.2} s)",
            i + 1,
            g.operator,
            g.initial_velocity,
            if g.grid == "adaptive" { ", adaptive grid" } else { "" },
            g.nodes,
            g.verdict,
            ratio(g.measured),
            ratio(g.predicted),
            g.wall_s
        );
    }
    note!("  {}", r.result);
}
