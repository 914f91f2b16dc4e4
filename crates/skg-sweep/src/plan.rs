//! Before a run: what it will do and roughly how long it will take ([`plan`]), and the
//! defaults of a run (output directory, worker count). The time estimate is
//! [`estimated_cost`] per point, summed over the run's points and divided among the
//! workers ([`estimated_wall_s`]). A run of more than [`CONFIRM_ABOVE`] points is
//! refused unless confirmed.

use std::path::PathBuf;

use skg_core::sbp::OperatorKind;
use skg_core::scene::{Formulation, Scene};

use crate::{Expanded, Method, Point, SweepError, SweepFile, SweepOptions, MAX_POINTS};

/// Above this many points to run, a sweep starts only when confirmed (`--yes`).
pub const CONFIRM_ABOVE: usize = 10_000;

/// Rough relative cost of a point, used only to start the expensive points first (so
/// that a sweep does not end with one long point running alone): N × the operator's
/// stencil width × 2 for the full formulation; a time-stepping peer point counts N/10.
pub fn estimated_cost(scene: &Scene, method: &Method) -> f64 {
    let n = scene.nodes as f64;
    match method {
        Method::Ode { .. } => n / 10.0,
        Method::Skg => {
            let width = match scene.operator {
                OperatorKind::Sbp121 => 1.0,
                OperatorKind::Sbp242 | OperatorKind::Sbp121Ad => 2.0,
                OperatorKind::Sbp363 | OperatorKind::Sbp484 | OperatorKind::Sbp242Ad => 3.0,
                OperatorKind::Sbp363Ad | OperatorKind::Sbp484Ad => 4.0,
            };
            let full = if scene.formulation == Formulation::Full { 2.0 } else { 1.0 };
            n * width * full
        }
    }
}

/// Seconds of one worker per unit of [`estimated_cost`], and per point (process start,
/// scene setup): a rough fit to the release-build timings of docs/benchmarks.md. It
/// gives 0.08 s for the tumbler at N = 256 (measured: 0.01 s plus the process start),
/// 3.3 s at N = 16384 (1.5 s) and 0.85 s for the rolling disk at N = 4096 (1.7 s: the
/// cost of a scene with more unknowns per node grows faster), so within a factor of
/// about 2 for the shipped scenes: enough to tell minutes from days.
const SECONDS_PER_COST: f64 = 1.0e-4;
const SECONDS_PER_POINT: f64 = 0.03;

/// A rough estimate of the wall time of running `points` with `jobs` workers (only to
/// tell the user what a sweep will take before it starts).
pub fn estimated_wall_s(expanded: &Expanded, points: &[&Point], jobs: usize) -> f64 {
    let serial: f64 = points.iter().map(|p| SECONDS_PER_POINT + SECONDS_PER_COST * expanded.costs[p.index]).sum();
    serial / jobs.max(1) as f64
}

/// A sweep's output directory when none is given: `out/sweeps/<name>`.
pub fn default_out_dir(file: &SweepFile) -> PathBuf {
    PathBuf::from("out/sweeps").join(file.name())
}

/// Worker processes when no number is given: one per core.
pub fn default_jobs() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// What a run of a sweep will do, known before it starts ([`plan`]).
#[derive(Debug)]
pub struct Plan {
    /// The sweep's points, for [`run_sweep`](crate::run_sweep).
    pub expanded: Expanded,
    /// A rough estimate of the run's wall time in seconds ([`estimated_wall_s`]).
    pub estimate_s: f64,
    /// One line for the user: the points, the estimate, where the results go.
    pub text: String,
}

/// Expand a sweep and say what a run with `opts` will do. More than [`CONFIRM_ABOVE`]
/// points are refused ([`SweepError::Unconfirmed`]) unless `confirmed`.
pub fn plan(file: &SweepFile, opts: &SweepOptions, confirmed: bool) -> Result<Plan, SweepError> {
    // Count first: a sweep too large to start unconfirmed is refused at once, not after
    // every point's scene was resolved and its memory checked (30 s for 10⁶ points).
    if let (false, Some(listed)) = (confirmed, file.listed_points()) {
        let mine = opts.shard.map_or(listed, |s| listed / s.n + usize::from(s.k - 1 < listed % s.n));
        if mine > CONFIRM_ABOVE && listed <= MAX_POINTS {
            let text = format!(
                "{}: {mine} points{} as listed (not yet checked), roughly at least {} with {} worker(s)",
                file.name(),
                opts.shard.map_or(String::new(), |s| format!(" in shard {}/{} of {listed}", s.k, s.n)),
                duration_text(SECONDS_PER_POINT * mine as f64 / opts.jobs.max(1) as f64),
                opts.jobs.max(1)
            );
            return Err(SweepError::Unconfirmed { plan: text });
        }
    }
    let expanded = file.expand()?;
    let mine: Vec<&Point> = expanded.points.iter().filter(|p| opts.shard.is_none_or(|s| s.contains(p.index))).collect();
    let estimate_s = estimated_wall_s(&expanded, &mine, opts.jobs);
    let text = format!(
        "{}: {} points{}, roughly {} with {} worker(s) (points already in {} are skipped)",
        file.name(),
        mine.len(),
        opts.shard.map_or(String::new(), |s| format!(" in shard {}/{} of {}", s.k, s.n, expanded.points.len())),
        duration_text(estimate_s),
        opts.jobs.max(1),
        opts.out_dir.join("results.csv").display()
    );
    if mine.len() > CONFIRM_ABOVE && !confirmed {
        return Err(SweepError::Unconfirmed { plan: text });
    }
    Ok(Plan { expanded, estimate_s, text })
}

/// A duration in seconds as `12 s`, `3.5 min` or `2.1 h`.
fn duration_text(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.1} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
    }
}
