//! Before a run: what it will do and roughly how long it will take ([`plan`]), and the
//! defaults of a run (output directory, worker count). The time estimate is
//! [`estimated_cost`] per point, summed over the run's points and divided among the
//! workers ([`estimated_wall_s`]); its model of a solve's cost is skg-core's,
//! [`skg_core::solve::cost`], the one the refinement chooses discretizations by. A run
//! of more than [`CONFIRM_ABOVE`] points is refused unless confirmed.

use std::path::PathBuf;

use skg_core::sbp::OperatorKind;
use skg_core::scene::{Backend, Formulation, Scene};
use skg_core::solve::cost::{relative_cost, seconds_per_cost};

use crate::{Expanded, Method, Point, SweepError, SweepFile, SweepOptions, MAX_POINTS};

/// Above this many points to run, a sweep starts only when confirmed (`--yes`).
pub const CONFIRM_ABOVE: usize = 10_000;

/// Estimated seconds of one worker computing a point: the same model of a solve's cost
/// as the refinement's choice of discretization, [`skg_core::solve::cost`] (the
/// measured time per node of the point's operator on its backend,
/// [`relative_cost`], times the seconds per unit, [`seconds_per_cost`]), twice that for
/// the full formulation (`FULL_FACTOR`); a time-stepping peer point counts
/// `PEER_SHARE` of a Newton `SBP242` solve of its grid. The driver starts the points
/// with the largest estimate first, so that a sweep does not end with one long point
/// running alone, and [`estimated_wall_s`] sums them. A point solved to its tolerance
/// (`[sweep] refine`, `operator = "auto"`) is estimated on the grid it starts from.
pub fn estimated_cost(scene: &Scene, method: &Method) -> f64 {
    let newton_sbp242 = || relative_cost(OperatorKind::Sbp242, Backend::Newton, scene.nodes) * seconds_per_cost(Backend::Newton);
    match method {
        Method::Ode { .. } => PEER_SHARE * newton_sbp242(),
        Method::Skg => {
            let backend = scene.solver.backend;
            let full = if scene.formulation == Formulation::Full { FULL_FACTOR } else { 1.0 };
            relative_cost(scene.operator, backend, scene.nodes) * seconds_per_cost(backend) * full
        }
    }
}

/// The time of a solve in the full formulation (twice the unknowns) over the reduced
/// one's. Measured as sweep points with `SBP242` at N = 4096: 3.1 (Ipopt) and 3.3
/// (Newton) on the rolling disk, 1.46 and 1.33 on the tumbler.
const FULL_FACTOR: f64 = 2.0;

/// The time of a time-stepping peer point over a Newton `SBP242` solve of the same grid:
/// the peer integrates onto the grid with its step capped at the node spacing, as a
/// solve's verification does, so its time hardly depends on its tolerance (1e-4 and
/// 1e-12 within 15 %). Measured as sweep points: 0.52 on the rolling disk at N = 16384
/// (0.354 s against 0.683 s), 0.58 on the tumbler (0.314 s against 0.543 s); 0.6 and
/// 0.43 at N = 4096.
const PEER_SHARE: f64 = 0.5;

/// Seconds of one worker per point besides its [`estimated_cost`]: handing the point
/// out, reading its result, the model built for the energy artifact, writing its row.
/// Measured as the sweep's wall time less the points' own (`wall_s`), per point: 0.010 s
/// on the tumbler and 0.011 s on the rolling disk (25 points each, N = 1024 … 16384).
const SECONDS_PER_POINT: f64 = 0.01;

/// A rough estimate of the wall time of running `points` with `jobs` workers (only to
/// tell the user what a sweep will take before it starts): `SECONDS_PER_POINT` and
/// [`estimated_cost`] per point, shared evenly among the workers.
pub fn estimated_wall_s(expanded: &Expanded, points: &[&Point], jobs: usize) -> f64 {
    let serial: f64 = points.iter().map(|p| SECONDS_PER_POINT + expanded.costs[p.index]).sum();
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
