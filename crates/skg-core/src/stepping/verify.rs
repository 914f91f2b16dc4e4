//! Verification of a solve: is the trajectory right, not only converged?
//!
//! A converged solve is a critical point of the discrete action, which can still be far
//! from the motion: a parasitic odd-even mode of the centred SBP stencils that damping or
//! contraction amplifies toward the final time, a contact near the final time polluting
//! the run backward through the end closure, a spurious critical point of a wall scene,
//! or non-finite numbers. Every solve is therefore compared with an independent solution
//! of the *same regularized scene*: the Lagrange–d'Alembert equations integrated by
//! [`equations`](super::equations) (adaptive DOP853, index-reduced) at a tight tolerance,
//! sampled at the solve's own nodes. This costs milliseconds and catches every failure
//! class above.
//!
//! * `max_error` = max over coordinates and every node of |q − q_reference|, the end
//!   nodes included: the final state is what a user reads. (The accuracy studies of the
//!   documentation leave out the last two nodes, the SBP end closure, and say so; the
//!   verification does not: on every shipped scene the end nodes are within the
//!   tolerance too, and where they are not, the ladder's solve past the end time puts
//!   the closure outside the reported span.)
//! * The tolerance is absolute, in coordinate units: the scene's `[verify] tol` or
//!   `--verify-tol` for every coordinate, else one per coordinate,
//!   [`DEFAULT_RELATIVE_TOL`] × that coordinate's range over the reference trajectory,
//!   but at least [`DEFAULT_RELATIVE_TOL`] × [`STATIC_RANGE`] × the largest range (so
//!   that a coordinate that hardly moves is not held to round-off). Each coordinate is
//!   judged on its own scale: a small coordinate beside a large one (a nutation angle
//!   beside a spin angle of 500 rad) is not judged on the large one's.
//! * The odd-even amplitude of each coordinate is the amplitude of its (−1)^k component,
//!   measured by the fourth difference `|q[k−2] − 4q[k−1] + 6q[k] − 4q[k+1] + q[k+2]| / 16`
//!   (exactly 1 for `(−1)^k`, `Δt⁴ q''''/16` for a smooth q), maximized over the nodes
//!   whose stencil avoids the excluded end nodes. When it is at least a quarter of the
//!   error of a solve that failed, the reason names the parasitic mode of the centred
//!   stencils. Not for a dissipative operator (`SBP…-AD`): its dissipation damps that mode
//!   (the parasitic roots lie inside the unit circle), and what the fourth difference
//!   measures there is a fast, smooth transient. Measured on
//!   crates/skg-core/tests/scenes/overdamped_2d.toml at N = 724 (natural initial
//!   velocity): SBP242-AD has an amplitude of 1.4e-4 at node 3 (t = 0.08, the start's
//!   12 /s transient) and below 1e-9 after t = 2 s, beside an error of 2.3e-4; SBP242's
//!   1.2e-1 sits at t = 19.4, near the end, where the mode has grown.
//! * Any non-finite number in the trajectory or its derived columns fails verification,
//!   even when verification is switched off.

use std::fmt;
use std::time::Instant;

use indexmap::IndexMap;
use serde::Serialize;

use crate::discrete::contact::{self, WallResolution};
use crate::discrete::trajectory::{NodeSeries, States, Trajectory};
use crate::model::Model;
use crate::sbp::OperatorKind;
use crate::scene::{Scene, Stepper};
use crate::stepping::equations::{integrate_model, mean_spacing, step_budget, Stepped, STEPS_PER_NODE};
use crate::stepping::ode::{OdeError, OdeOptions, OdeStats};

/// Relative tolerance of the time-stepping reference.
pub const REFERENCE_RTOL: f64 = 1e-10;
/// Absolute tolerance of the time-stepping reference.
pub const REFERENCE_ATOL: f64 = 1e-12;
/// The tightest relative tolerance the reference is integrated with, for tight
/// verification tolerances ([`reference_rtol`]): DOP853 in double precision stops
/// gaining much below it.
pub const REFERENCE_RTOL_MIN: f64 = 1e-13;

/// The relative tolerance of a reference that checks `tolerances` on a motion `q`: a
/// hundredth of the tightest tolerance relative to the motion's size (max |q|, at least
/// 1), between [`REFERENCE_RTOL_MIN`] and [`REFERENCE_RTOL`]. At the default tolerances
/// (1e-4 of each coordinate's range) it is [`REFERENCE_RTOL`]; a tolerance of 1e-8 on
/// the rolling disk, whose spin angle grows to 31 rad, needs 3e-12 (at 1e-10 the
/// reference's own error there is 3e-9).
pub fn reference_rtol(tolerances: &[f64], q: &[Vec<f64>]) -> f64 {
    let size = q.iter().flatten().fold(1.0_f64, |m, x| m.max(x.abs()));
    let tightest = tolerances.iter().copied().fold(f64::INFINITY, f64::min);
    (0.01 * tightest / size).clamp(REFERENCE_RTOL_MIN, REFERENCE_RTOL)
}
/// Default verification tolerance, relative to each coordinate's range.
pub const DEFAULT_RELATIVE_TOL: f64 = 1e-4;
/// A coordinate whose range is below this fraction of the largest range is judged as if
/// its range were this fraction (see the module documentation).
pub const STATIC_RANGE: f64 = 1e-3;
/// End nodes left out of the verification's error: none (see the module documentation).
pub const SKIP_LAST: usize = 0;
/// End nodes left out of the odd-even amplitude: the end closure's rows are not
/// smooth, and their fourth difference is not a parasitic mode.
pub const ODD_EVEN_SKIP_LAST: usize = 2;

/// The verdict of a verification.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum VerifyStatus {
    /// Every number is finite and the error is within the tolerance.
    Passed,
    /// A non-finite number, or an error above the tolerance.
    Failed,
    /// The reference could not be computed (the reason says why).
    Unverified,
    /// Verification was switched off (`--no-verify`); the numbers are finite.
    Skipped,
}

impl VerifyStatus {
    /// Whether a solve with this verdict may exit 0 (passed, or skipped on request).
    pub fn is_acceptable(self) -> bool {
        matches!(self, VerifyStatus::Passed | VerifyStatus::Skipped)
    }
}

impl fmt::Display for VerifyStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            VerifyStatus::Passed => "passed",
            VerifyStatus::Failed => "failed",
            VerifyStatus::Unverified => "unverified",
            VerifyStatus::Skipped => "skipped",
        })
    }
}

/// The result of verifying a trajectory (the `verification` object of `summary.json`).
#[derive(Debug, Clone, Serialize)]
pub struct Verification {
    /// The verdict.
    pub status: VerifyStatus,
    /// max |q − q_reference| over coordinates and nodes (every node: [`SKIP_LAST`] is 0).
    pub max_error: Option<f64>,
    /// The same per coordinate.
    pub errors: IndexMap<String, f64>,
    /// The coordinate that decides the verdict, furthest beyond its tolerance (or least
    /// within it), and the time of its largest error. With one tolerance for every
    /// coordinate it is the coordinate of the largest error.
    pub worst: Option<(String, f64)>,
    /// The absolute tolerance applied (coordinate units): the given one, or the largest
    /// of the default per-coordinate tolerances.
    pub tolerance: Option<f64>,
    /// The tolerance applied to each coordinate.
    pub tolerances: IndexMap<String, f64>,
    /// Where the tolerance came from.
    pub tolerance_source: String,
    /// Amplitude of the (−1)^k component of each coordinate.
    pub odd_even: IndexMap<String, f64>,
    /// The largest odd-even amplitude.
    pub odd_even_max: f64,
    /// End nodes left out of the error (0: every node is compared).
    pub skip_last: usize,
    /// How the reference was computed.
    pub reference: String,
    /// The verdict in words.
    pub reason: String,
    /// How finely the nodes resolve each wall's contacts in the reference, for the walls
    /// it comes near ([`contact::resolution`]): the ladder's remedy names a finer grid
    /// when a failed solve's walls are under-resolved.
    pub wall_resolution: IndexMap<String, WallResolution>,
    /// The reference at the nodes (written as `reference.csv`).
    #[serde(skip)]
    pub reference_trajectory: Option<Trajectory>,
    /// The work of the reference's time stepping (zero when it did not run or failed);
    /// summary.json reports it in the solve's `work` ([`Work`](crate::solve::Work)).
    #[serde(skip)]
    pub steps: OdeStats,
}

impl Verification {
    /// Whether the verdict lets a converged solve exit 0.
    pub fn is_acceptable(&self) -> bool {
        self.status.is_acceptable()
    }

    /// Fail the verification for a reason found outside the comparison (e.g. a kinetic
    /// matrix that is not positive definite at some node), keeping the measured errors.
    pub fn fail(&mut self, reason: String) {
        self.status = VerifyStatus::Failed;
        self.reason = if self.reason.is_empty() { reason } else { format!("{reason}; {}", self.reason) };
    }
}

/// Verify `tr`, a solution of `scene` with model `model` by the SBP operator `operator`,
/// against time stepping of the same scene from its initial state, sampled at `tr.t`.
pub fn verify(scene: &Scene, model: &Model, tr: &Trajectory, operator: OperatorKind) -> Verification {
    verify_until(scene, model, tr, operator, None, None)
}

/// The time stepping of a scene from its initial state `(q0, v0)`, sampled at `times`
/// with the verification's options at `rtol` ([`reference_options`]): the initial guess
/// of a solve makes it when the solve will be verified, and the verification takes it
/// instead of stepping again when it would have stepped the same way (the same start,
/// nodes and tolerance).
#[derive(Debug, Clone)]
pub struct NodeStepping {
    /// The initial positions stepped from.
    pub q0: Vec<f64>,
    /// The initial velocities.
    pub v0: Vec<f64>,
    /// The nodes sampled.
    pub times: Vec<f64>,
    /// The relative tolerance.
    pub rtol: f64,
    /// What the stepping found and did.
    pub stepped: Stepped<States>,
}

/// The options of the verification's time stepping sampled at `times` at the relative
/// tolerance `rtol`: the absolute one in the same proportion as
/// [`REFERENCE_ATOL`] to [`REFERENCE_RTOL`], steps at most the mean node spacing, the
/// step budget of the grid, given up at `deadline`.
pub fn reference_options(times: &[f64], rtol: f64, stepper: Stepper, deadline: Option<Instant>) -> OdeOptions {
    let (max_step, max_steps) = (mean_spacing(times), step_budget(times.len()));
    OdeOptions { rtol, atol: rtol * (REFERENCE_ATOL / REFERENCE_RTOL), max_step, max_steps, stepper, deadline, ..OdeOptions::default() }
}

/// The time stepping of `scene` from its initial state at `times` that the verification
/// of a solve on those nodes starts with, at [`REFERENCE_RTOL`]: always with the default
/// tolerances, and with a given one unless it is tight ([`reference_rtol`], from the
/// solution's size; the verification then steps again itself).
pub fn default_reference_stepping(
    scene: &Scene,
    model: &Model,
    times: &[f64],
    deadline: Option<Instant>,
) -> Result<NodeStepping, OdeError> {
    let opts = reference_options(times, REFERENCE_RTOL, scene.verify.stepper, deadline);
    let stepped = integrate_model(model, &scene.initial_q, &scene.initial_v, times, &opts)?;
    Ok(NodeStepping { q0: scene.initial_q.clone(), v0: scene.initial_v.clone(), times: times.to_vec(), rtol: REFERENCE_RTOL, stepped })
}

/// [`verify`], its time stepping given up at `deadline` (if any): the solve is then
/// unverified, and the reason says so. `prior` is a time stepping already made (by the
/// initial guess), taken where it is the one the verification would make.
pub fn verify_until(
    scene: &Scene,
    model: &Model,
    tr: &Trajectory,
    operator: OperatorKind,
    deadline: Option<Instant>,
    prior: Option<&NodeStepping>,
) -> Verification {
    let base = not_compared(scene, tr);
    if let Some(bad) = first_non_finite(scene, tr) {
        return Verification { status: VerifyStatus::Failed, reason: bad, ..base };
    }
    if !scene.verify.enabled {
        return Verification { reason: "verification switched off (--no-verify); every number is finite".into(), ..base };
    }
    let (integrated, reference) = time_stepping_at_nodes(scene, model, tr, deadline, prior);
    match integrated {
        Ok(Stepped { states, stats: steps, .. }) => {
            let reference_trajectory = Trajectory::with_physical_columns(model, &tr.t, states);
            Verification { reference, steps, ..compare_with_reference(scene, model, tr, operator, reference_trajectory, base) }
        }
        Err(e) => {
            Verification { status: VerifyStatus::Unverified, reference, reason: time_stepping_failure(&e, scene.verify.stepper), ..base }
        }
    }
}

/// The verification of `tr` before any comparison (skipped, with the odd-even amplitudes
/// of its coordinates).
fn not_compared(scene: &Scene, tr: &Trajectory) -> Verification {
    let odd_even = odd_even_amplitudes(&scene.coordinates, &tr.q);
    let odd_even_max = odd_even.values().copied().fold(0.0, f64::max);
    Verification {
        status: VerifyStatus::Skipped,
        max_error: None,
        errors: IndexMap::new(),
        worst: None,
        tolerance: scene.verify.tol,
        tolerances: IndexMap::new(),
        tolerance_source: String::new(),
        odd_even,
        odd_even_max,
        skip_last: SKIP_LAST,
        reference: String::new(),
        reason: String::new(),
        wall_resolution: IndexMap::new(),
        reference_trajectory: None,
        steps: OdeStats::default(),
    }
}

/// Time stepping of `scene` from its initial state, sampled at `tr.t`, with the
/// description of the reference. A tight tolerance needs a tighter reference: a given
/// tolerance is judged on the motion's size as the solve found it; the default ones,
/// relative to the ranges, only once the reference has them (then a second pass, whose
/// work adds to the first's, if they are tight). The first pass is `prior` where that
/// is the same time stepping (its work then counted by whoever made it).
fn time_stepping_at_nodes(
    scene: &Scene,
    model: &Model,
    tr: &Trajectory,
    deadline: Option<Instant>,
    prior: Option<&NodeStepping>,
) -> (Result<Stepped<States>, OdeError>, String) {
    let stepper = scene.verify.stepper;
    let describe = |method: &str, rtol: f64, atol: f64| {
        format!(
            "time stepping of the same scene ({method}; rtol {rtol:e}, atol {atol:e}, step at most the node spacing) at the solve's nodes"
        )
    };
    let integrate = |rtol: f64| {
        let opts = reference_options(&tr.t, rtol, stepper, deadline);
        let integrated = integrate_model(model, &scene.initial_q, &scene.initial_v, &tr.t, &opts);
        let method = match &integrated {
            Ok(stepped) => stepped.method.clone(),
            Err(_) => format!("stepper {stepper}"),
        };
        (integrated, describe(&method, opts.rtol, opts.atol))
    };
    let first_rtol = match scene.verify.tol {
        Some(tol) => reference_rtol(&[tol], &tr.q),
        None => REFERENCE_RTOL,
    };
    let same = |p: &&NodeStepping| p.rtol == first_rtol && p.times == tr.t && p.q0 == scene.initial_q && p.v0 == scene.initial_v;
    let (mut integrated, mut reference) = match prior.filter(same) {
        Some(p) => {
            let atol = p.rtol * (REFERENCE_ATOL / REFERENCE_RTOL);
            let reused = Stepped { stats: OdeStats::default(), ..p.stepped.clone() };
            (Ok(reused), format!("{} (the initial guess's)", describe(&p.stepped.method, p.rtol, atol)))
        }
        None => integrate(first_rtol),
    };
    if let Ok(stepped) = &integrated {
        let rtol = reference_rtol(&tolerances(scene, &stepped.states.q).0, &stepped.states.q);
        if rtol < 0.5 * first_rtol {
            let first = stepped.stats;
            (integrated, reference) = integrate(rtol);
            if let Ok(stepped) = &mut integrated {
                stepped.stats.add(&first);
            }
        }
    }
    (integrated, reference)
}

/// Why a solve could not be checked when the time stepping by `stepper` failed with `e`.
fn time_stepping_failure(e: &OdeError, stepper: Stepper) -> String {
    let failed = format!("time stepping of the same scene failed, so the solve could not be checked: {e}");
    match e {
        OdeError::MaxSteps { .. } if stepper == Stepper::Dop853 => format!(
            "{failed} (more than {STEPS_PER_NODE} steps per node: the motion is far finer than the grid, or the scene is \
             stiff and explicit steps are far shorter than the motion; refine N, shorten the span, or let the stepping go on \
             implicitly: --stepper auto)"
        ),
        OdeError::MaxSteps { .. } => format!(
            "{failed} (more than {STEPS_PER_NODE} steps per node: the motion is far finer than the grid; refine N or \
             shorten the span)"
        ),
        OdeError::TimeLimit { t } => {
            format!("the time stepping that checks the solve was stopped at the time limit at t = {t}, so the solve could not be checked")
        }
        _ => failed,
    }
}

/// The verdict on `tr` against the time stepping `reference_trajectory` at its nodes
/// (every node but the last [`SKIP_LAST`]): each coordinate's error within its
/// tolerance, the worst coordinate named, and the contacts' resolution measured on the
/// reference.
fn compare_with_reference(
    scene: &Scene,
    model: &Model,
    tr: &Trajectory,
    operator: OperatorKind,
    reference_trajectory: Trajectory,
    base: Verification,
) -> Verification {
    let (tolerances, tolerance_source) = tolerances(scene, &reference_trajectory.q);
    let tolerance = tolerances.iter().copied().fold(0.0, f64::max);
    let compared = tr.t.len().saturating_sub(SKIP_LAST).max(1);
    let errors = coordinate_errors(&scene.coordinates, &tr.q[..compared], &reference_trajectory.q[..compared]);
    let max_error = errors.values().map(|&(_, e)| e).fold(0.0_f64, f64::max);
    let (worst_name, worst_node, worst_error, worst_tol) = worst_coordinate(&errors, &tolerances, tolerance);
    let worst_t = tr.t[worst_node];
    let passed = errors.values().zip(&tolerances).all(|(&(_, e), &tol)| e <= tol);
    let own = if scene.verify.tol.is_none() && scene.coordinates.len() > 1 { format!(" of {worst_name}") } else { String::new() };
    let reason = if passed {
        format!("max |q − q_ref| = {worst_error:.3e} ({worst_name} at t = {worst_t:.6}) is within the tolerance{own} {worst_tol:.3e}")
    } else {
        let mut r =
            format!("max |q − q_ref| = {worst_error:.3e} ({worst_name} at t = {worst_t:.6}) exceeds the tolerance{own} {worst_tol:.3e}");
        if base.odd_even_max >= 0.25 * max_error && !operator.is_dissipative() {
            r.push_str(&format!(
                "; the odd-even (−1)^k component of the solution is {:.3e}: the parasitic mode of centred SBP stencils, \
                 which damping, contraction or a long contact amplifies",
                base.odd_even_max
            ));
        }
        r
    };
    Verification {
        status: if passed { VerifyStatus::Passed } else { VerifyStatus::Failed },
        max_error: Some(max_error),
        errors: errors.into_iter().map(|(name, (_, e))| (name, e)).collect(),
        worst: Some((worst_name, worst_t)),
        tolerance: Some(tolerance),
        tolerances: scene.coordinates.iter().cloned().zip(tolerances).collect(),
        tolerance_source,
        reason,
        wall_resolution: contact::resolution(model, &reference_trajectory),
        reference_trajectory: Some(reference_trajectory),
        ..base
    }
}

/// The verdict's coordinate: the one furthest beyond (or least within) its tolerance,
/// as (name, node, error, tolerance); `tolerance` when there is no coordinate.
fn worst_coordinate(errors: &IndexMap<String, (usize, f64)>, tolerances: &[f64], tolerance: f64) -> (String, usize, f64, f64) {
    errors
        .iter()
        .zip(tolerances)
        .map(|((name, &(k, e)), &tol)| (name.clone(), k, e, tol))
        .fold(None, |best: Option<(String, usize, f64, f64)>, cur| match best {
            Some(b) if b.2 / b.3 >= cur.2 / cur.3 => Some(b),
            _ => Some(cur),
        })
        .unwrap_or((String::new(), 0, 0.0, tolerance))
}

/// The tolerance of each coordinate and where they came from: the scene's or the command
/// line's for every coordinate, else the default relative to each coordinate's range over
/// the reference, at least [`STATIC_RANGE`] of the largest range (1 if every coordinate
/// stays constant).
pub fn tolerances(scene: &Scene, reference_q: &[Vec<f64>]) -> (Vec<f64>, String) {
    let d = scene.coordinates.len();
    if let Some(t) = scene.verify.tol {
        return (vec![t; d], "given ([verify] tol or --verify-tol)".into());
    }
    let ranges = coordinate_ranges(reference_q);
    let scale = ranges.iter().copied().fold(0.0, f64::max);
    let scale = if scale > 0.0 { scale } else { 1.0 };
    let tolerances = ranges.iter().map(|r| DEFAULT_RELATIVE_TOL * r.max(STATIC_RANGE * scale)).collect();
    let source =
        format!("default: {DEFAULT_RELATIVE_TOL:e} × each coordinate's range, at least {STATIC_RANGE:e} × the largest range {scale:.6e}");
    (tolerances, source)
}

/// The range (max − min) of each coordinate over the nodes.
pub fn coordinate_ranges(q: &[Vec<f64>]) -> Vec<f64> {
    let d = q.first().map_or(0, Vec::len);
    (0..d)
        .map(|i| {
            let (lo, hi) = q.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), qk| (lo.min(qk[i]), hi.max(qk[i])));
            hi - lo
        })
        .collect()
}

/// The largest range (max − min) of a coordinate over the nodes.
pub fn coordinate_scale(q: &[Vec<f64>]) -> f64 {
    coordinate_ranges(q).into_iter().fold(0.0, f64::max)
}

/// Per coordinate: the node and value of max |a − b|.
fn coordinate_errors(names: &[String], a: &[Vec<f64>], b: &[Vec<f64>]) -> IndexMap<String, (usize, f64)> {
    names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let worst =
                a.iter()
                    .zip(b)
                    .enumerate()
                    .map(|(k, (x, y))| (k, (x[i] - y[i]).abs()))
                    .fold((0, 0.0), |m, c| if c.1 > m.1 { c } else { m });
            (name.clone(), worst)
        })
        .collect()
}

/// Amplitude of the (−1)^k component of each coordinate: max |Δ⁴q| / 16 over the nodes
/// whose five-point stencil leaves out the last [`ODD_EVEN_SKIP_LAST`] nodes.
pub fn odd_even_amplitudes(names: &[String], q: &NodeSeries) -> IndexMap<String, f64> {
    let usable = q.len().saturating_sub(ODD_EVEN_SKIP_LAST);
    names
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let amp = (2..usable.saturating_sub(2))
                .map(|k| (q[k - 2][i] - 4.0 * q[k - 1][i] + 6.0 * q[k][i] - 4.0 * q[k + 1][i] + q[k + 2][i]).abs() / 16.0)
                .fold(0.0, f64::max);
            (name.clone(), amp)
        })
        .collect()
}

/// The first non-finite number of the trajectory, as a sentence naming the column, the
/// node and its time.
pub fn first_non_finite(scene: &Scene, tr: &Trajectory) -> Option<String> {
    let columns = crate::discrete::trajectory::trajectory_header(scene);
    let rows = crate::discrete::trajectory::trajectory_rows(tr);
    rows.iter().enumerate().find_map(|(k, row)| {
        row.iter().position(|x| !x.is_finite()).map(|c| {
            format!(
                "the solution has a non-finite value: {} = {} at node {} (t = {}); check the scene's expressions at that state",
                columns[c],
                row[c],
                k + 1,
                tr.t[k]
            )
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn odd_even_amplitude_is_one_for_the_checkerboard_and_small_for_smooth_data() {
        let names = vec!["x".to_string(), "y".to_string()];
        let n = 40;
        let dt = 0.01;
        let q: NodeSeries = (0..n).map(|k| vec![if k % 2 == 0 { 1.0 } else { -1.0 }, (k as f64 * dt).sin()]).collect();
        let a = odd_even_amplitudes(&names, &q);
        assert!((a["x"] - 1.0).abs() < 1e-15, "{a:?}");
        // Δt⁴ |sin''''| / 16 ≤ 1e-8 / 16.
        assert!(a["y"] <= 1e-8 / 16.0 * 1.0001, "{a:?}");
    }

    /// Free motion x = t: the exact trajectory passes; a NaN in a derived column fails,
    /// even with verification switched off, and the reason names the column and node.
    #[test]
    fn an_exact_trajectory_passes_and_a_non_finite_value_always_fails() {
        use crate::discrete::trajectory::States;
        use crate::model::Model;
        use crate::scene::{Overrides, SceneFile};
        let text = "[scene]\nname = \"s\"\nlagrangian = \"x_dot^2/2\"\n[[coordinates]]\nname = \"x\"\ninitial = 0\nvelocity = 1\n\
                    [time]\nstart = 0\nend = 1\nnodes = 8\n";
        let resolve = |ov: &Overrides| SceneFile::parse(text, "s.toml").unwrap().resolve(ov).unwrap();
        let scene = resolve(&Overrides::default());
        let model = Model::build(&scene).unwrap();
        let times: Vec<f64> = (0..8).map(|k| k as f64 / 7.0).collect();
        let states = States { q: times.iter().map(|&t| vec![t]).collect(), v: vec![vec![1.0]; 8], lambda: vec![vec![]; 8] };
        let mut tr = Trajectory::with_physical_columns(&model, &times, states);
        let v = verify(&scene, &model, &tr, scene.operator);
        assert_eq!(v.status, VerifyStatus::Passed, "{}", v.reason);
        assert!(v.max_error.unwrap() < 1e-12);
        // Its time stepping given up at a deadline already passed: unverified, saying why.
        let v = verify_until(&scene, &model, &tr, scene.operator, Some(Instant::now()), None);
        assert_eq!(v.status, VerifyStatus::Unverified, "{}", v.reason);
        assert!(v.reason.contains("stopped at the time limit at t = 0"), "{}", v.reason);
        tr.energy[5] = f64::NAN;
        for ov in [Overrides::default(), Overrides { no_verify: true, ..Default::default() }] {
            let v = verify(&resolve(&ov), &model, &tr, scene.operator);
            assert_eq!(v.status, VerifyStatus::Failed);
            assert!(v.reason.contains("energy = NaN at node 6"), "{}", v.reason);
        }
        tr.energy[5] = 0.5;
        let v = verify(&resolve(&Overrides { no_verify: true, ..Default::default() }), &model, &tr, scene.operator);
        assert_eq!(v.status, VerifyStatus::Skipped);
    }

    #[test]
    fn scale_is_the_largest_coordinate_range() {
        let q = vec![vec![0.0, 5.0], vec![2.0, 4.0], vec![-1.0, 4.5]];
        assert_eq!(coordinate_scale(&q), 3.0);
    }
}
