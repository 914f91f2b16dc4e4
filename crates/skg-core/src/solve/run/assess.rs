//! The assessment of a [`Run`]: its [`Outcome`] with the verification against time
//! stepping, the diagnostics (residuals, constraints, energy, walls, contact episodes)
//! and the warnings.

use std::time::Instant;

use indexmap::IndexMap;

use super::backend::{IpoptReport, SolverStatus, SquareSolver};
use super::deadline::{self, Deadline};
use super::global::Run;
use super::outcome::{counted, Diagnostics, KineticLoss, Outcome, Settings, Sizes};
use super::piece::Piece;
use super::status::SolveStatus;
use crate::discrete::contact;
use crate::discrete::Trajectory;
use crate::discrete::{Action, Discretization};
use crate::model::Model;
use crate::sbp::OperatorKind;
use crate::scene::{ConstraintKind, Formulation, Scene, Wall};
use crate::stepping::verify::{self, Verification, VerifyStatus};

/// A solution farther than this fraction of the coordinates' range from the
/// time-stepping solution gets a warning. Discretization errors of usable grids are
/// below 1 % (disk N=32 SBP242: 0.4 %); the spurious solutions seen were 35 % (tumbler
/// N=48) and 100 %+ (knife edge on SBP121, an odd-even mode).
const FAR_FROM_TIME_STEPPING: f64 = 0.1;

/// The outcome of a run: its diagnostics, verification (given up at `time_limit`, if
/// any) and warnings (the ladder adds the attempts and a remedy).
pub fn outcome(scene: &Scene, model: &Model, run: Run, time_limit: Option<Deadline>) -> Outcome {
    let Run { method, discretization: disc, sizes, solution: run } = run;
    let t = Instant::now();
    let mut verification = match run.status.solver() {
        SolverStatus::TimeLimitReached { bound, limit_s, .. } if !run.status.is_converged() => {
            not_verified_after_time_limit(scene, model, &run.trajectory, disc.operator, &deadline::describe(bound, limit_s))
        }
        _ => {
            verify::verify_until(scene, model, &run.trajectory, disc.operator, time_limit.map(|d| d.at), run.reference_stepping.as_deref())
        }
    };
    let mut timings = run.timings.clone();
    timings.verification_s = t.elapsed().as_secs_f64();
    let mut work = run.work;
    work.verification_steps.add(&verification.steps);
    let diagnostics = diagnose(model, disc.operator, &run);
    let mut warnings = suspicions(&diagnostics, run.time_stepping_q.as_deref(), run.status);
    if let Some(newton) = run.backend.newton.as_ref().filter(|_| run.backend.handed_over_to_ipopt) {
        warnings.push(format!(
            "Newton's method did not converge ({}, {} iterations, residual {:.3e}); Ipopt solved the system from the same initial guess",
            newton.status.name(),
            newton.iterations,
            newton.max_residual
        ));
    }
    warnings.extend(run.backend.ipopt.as_ref().and_then(factorization_note));
    if let Some(loss) = &diagnostics.kinetic_loss {
        verification.fail(loss.to_string());
        warnings.push(loss.to_string());
    }
    Outcome {
        scene: scene.name.clone(),
        status: run.status,
        verification,
        method,
        ipopt_version: ipopt_version(),
        backend: run.backend,
        iterations: run.iterations,
        settings: settings(scene, &disc, &run.trajectory.t, run.guess),
        sizes,
        timings,
        work,
        diagnostics,
        warnings,
        notes: Vec::new(),
        attempts: Vec::new(),
        remedy: None,
        refinement: None,
        history: run.history,
        trajectory: run.trajectory,
    }
}

/// The verification of a run whose backend was stopped at a deadline (`what`): not run
/// (its time stepping would take the solve further past it, and the run did not
/// converge); only the checks of the numbers themselves (finite, odd-even amplitudes).
fn not_verified_after_time_limit(scene: &Scene, model: &Model, tr: &Trajectory, operator: OperatorKind, what: &str) -> Verification {
    let mut unchecked = scene.clone();
    unchecked.verify.enabled = false;
    let mut verification = verify::verify(&unchecked, model, tr, operator);
    if verification.status == VerifyStatus::Skipped {
        verification.status = VerifyStatus::Unverified;
        verification.reason = format!("not run: the solve was stopped at {what} before it converged");
    }
    verification
}

/// The Newton backend's factorization must be at least this many times faster than
/// Ipopt's work per iteration for [`factorization_note`] to suggest it.
const NOTE_MIN_SPEEDUP: f64 = 2.0;

/// The note of an Ipopt solve whose own linear algebra took most of a long solve
/// (the solve then timed the Newton backend's factorization of the same Jacobian,
/// [`IpoptReport::newton_lu_s`](super::backend::IpoptReport::newton_lu_s)): both
/// figures as this solve measured them, when the Newton backend's is at least
/// [`NOTE_MIN_SPEEDUP`] times less than Ipopt's work per iteration. `None` otherwise.
pub fn factorization_note(ipopt: &IpoptReport) -> Option<String> {
    let lu_s = ipopt.newton_lu_s?;
    let per_iteration = ipopt.internal_s / ipopt.iterations.max(1) as f64;
    let speedup = per_iteration / lu_s.max(1e-6);
    (speedup >= NOTE_MIN_SPEEDUP).then(|| {
        format!(
            "Ipopt's own work (mostly MUMPS's factorizations of its KKT matrix) took {:.1} s of this solve, {per_iteration:.2} s per iteration ({} {}); \
             one factorization of the same Jacobian by the sparse LU of --backend newton, timed after this solve, took {lu_s:.3} s, {:.0}× less \
             (docs/solver.md#the-newton-backend)",
            ipopt.internal_s,
            ipopt.iterations,
            if ipopt.iterations == 1 { "iteration" } else { "iterations" },
            speedup
        )
    })
}

/// The settings a scene is solved with: its own, and the discretization `disc` on the
/// grid `times`.
fn settings(scene: &Scene, disc: &Discretization, times: &[f64], initial_guess: String) -> Settings {
    Settings {
        operator: disc.operator.name().to_string(),
        nodes: disc.nodes,
        grid: disc.grid.name(),
        t_start: times[0],
        t_end: times[times.len() - 1],
        formulation: scene.formulation,
        initial_velocity: disc.initial_velocity,
        backend: scene.solver.backend,
        hessian: scene.solver.hessian,
        tol: scene.solver.tol,
        max_iter: scene.solver.max_iter,
        parameters: scene.parameters.clone(),
        initial_guess,
    }
}

/// The sizes of the system handed to the backend for one piece (the whole span, or one
/// window).
pub fn sizes(scene: &Scene, action: &Action, solver: &SquareSolver) -> Sizes {
    let (lay, model) = (&action.layout, &action.model);
    let (variables, equations) = match scene.formulation {
        Formulation::Reduced => (lay.n_p, lay.n_m),
        Formulation::Full => (lay.len(), lay.len()),
    };
    Sizes {
        nodes: lay.nodes,
        coordinates: lay.d,
        constraints: lay.n,
        walls: model.walls.len(),
        variables,
        equations,
        jacobian_nonzeros: solver.jacobian_plan().structure.len(),
        hessian_nonzeros: solver.hessian_plan().map_or(0, |h| h.structure.len()),
        tape_instructions: model.minus_gradient.len() + model.mixed.tape.len(),
    }
}

/// Warnings about a solution: far from time stepping, a contact episode more or less
/// than time stepping (a spurious critical point or a grid too coarse), or the backend's
/// success contradicted by the unscaled residual.
fn suspicions(diagnostics: &Diagnostics, ts_q: Option<&[Vec<f64>]>, status: SolveStatus) -> Vec<String> {
    let mut warnings = Vec::new();
    if let (Some(dist), Some(ts)) = (diagnostics.distance_from_time_stepping, ts_q) {
        let scale = verify::coordinate_scale(ts);
        if dist > FAR_FROM_TIME_STEPPING * scale {
            warnings.push(format!(
                "the solution is {dist:.3e} away from time stepping of the same scene ({} % of the coordinates' range): \
                 a spurious critical point, an odd-even mode of the operator, or a grid too coarse (refine N or change the operator)",
                crate::scene::readable_number((100.0 * dist / scale).round())
            ));
        }
    }
    if let Some(ts) = &diagnostics.contact_episodes_time_stepping {
        for ((wall, a), b) in diagnostics.contact_episodes.iter().zip(ts.values()) {
            if a != b {
                warnings.push(format!(
                    "wall `{wall}`: the solution has {}, time stepping of the same scene has {b}: \
                     possibly a spurious critical point or a grid too coarse for the wall width (refine N)",
                    counted(*a, "contact episode")
                ));
            }
        }
    }
    if let SolveStatus::ResidualTooLarge { residual, .. } = status {
        warnings
            .push(format!("the solver reported success but the unscaled residual is {residual:.3e} (> 1e-8): not counted as converged"));
    }
    warnings
}

/// End nodes left out of `energy_drift`: the last two, whose equations are the boundary
/// closure; for a dissipative operator its boundary rows (2, 4, 6, 8), where the end
/// closure of `D+` carries a layer in the velocity (the positions there are as accurate
/// as elsewhere). Measured, SBP242-AD on the pendulum at N = 256: 3.0e-3 over every node,
/// 6.7e-4 without the last two, 1.9e-4 without the last four (SBP242: 2.0e-4).
pub fn energy_drift_skip(operator: OperatorKind) -> usize {
    if operator.is_dissipative() {
        operator.boundary_rows().max(2)
    } else {
        2
    }
}

/// The diagnostics of a run's solution, solved with `operator`.
fn diagnose(model: &Model, operator: OperatorKind, run: &Piece) -> Diagnostics {
    let tr = &run.trajectory;
    let nodes = tr.t.len();
    let max_abs = |rows: &[Vec<f64>]| rows.iter().flatten().fold(0.0_f64, |m, x| m.max(x.abs()));
    let max_constraint_interior = if nodes > 2 { max_abs(&tr.g[1..nodes - 1]) } else { 0.0 };
    let constraint_last_node = max_abs(&tr.g[nodes - 1..]);
    let total: Vec<f64> = tr.energy.iter().zip(&tr.wall_energy).map(|(e, w)| e + w).collect();
    let energy_skip = energy_drift_skip(operator);
    let drift = |es: &[f64]| es.iter().fold(0.0_f64, |m, e| m.max((e - total[0]).abs()));
    let positions = model.constraints.iter().filter(|c| c.kind == ConstraintKind::Position);
    let max_wall_gap = per_wall(model, |j, _| tr.h.iter().map(|h| h[j]).fold(f64::NEG_INFINITY, f64::max));
    let ts_q = run.time_stepping_q.as_deref();
    let contact_episodes_time_stepping = ts_q.map(|qs| {
        let h: Vec<Vec<f64>> = qs.iter().zip(&tr.t).map(|(q, &t)| model.wall_gaps(t, q)).collect();
        contact_episodes(model, &h)
    });
    let distance_from_time_stepping =
        ts_q.map(|qs| qs.iter().zip(&tr.q).flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs())).fold(0.0_f64, f64::max));
    Diagnostics {
        max_residual: run.max_residual,
        max_eom_residual: run.max_eom_residual,
        max_constraint_interior,
        constraint_last_node,
        max_position_drift: positions.map(|c| c.name.clone()).zip(tr.max_drift()).collect(),
        depends_on_time: model.depends_on_time,
        energy_drift: drift(&total[..nodes.saturating_sub(energy_skip).max(1)]),
        energy_drift_skip: energy_skip,
        energy_drift_all: drift(&total),
        max_wall_gap,
        distance_from_time_stepping,
        contact_episodes: contact_episodes(model, &tr.h),
        contact_episodes_time_stepping,
        max_minus_variable: run.max_minus_variable,
        kinetic_loss: model.kinetic_loss(&tr.t, &tr.q, &tr.v).map(|(node, min_eigenvalue)| KineticLoss {
            node,
            t: tr.t[node],
            min_eigenvalue,
        }),
    }
}

/// `value(j, wall)` for every wall of the model, keyed by the wall's name in the scene's order.
fn per_wall<T>(model: &Model, mut value: impl FnMut(usize, &Wall) -> T) -> IndexMap<String, T> {
    model.walls.iter().enumerate().map(|(j, w)| (w.name.clone(), value(j, w))).collect()
}

/// Number of contact episodes ([`contact::episodes`]) per wall, given the gaps `h[k][j]`.
fn contact_episodes(model: &Model, h: &[Vec<f64>]) -> IndexMap<String, usize> {
    per_wall(model, |j, w| contact::episodes(h.iter().map(|hk| hk[j]), w.width).len())
}

/// The version of the Ipopt library this process runs (for the summary), or `none` in a
/// build without Ipopt.
fn ipopt_version() -> String {
    #[cfg(feature = "ipopt")]
    return skg_ipopt::ipopt_version().to_string();
    #[cfg(not(feature = "ipopt"))]
    return "none".to_string();
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(iterations: usize, internal_s: f64, newton_lu_s: Option<f64>) -> IpoptReport {
        IpoptReport { iterations, residual_evaluations: 0, jacobian_evaluations: 0, hessian_evaluations: 0, internal_s, newton_lu_s }
    }

    #[test]
    fn the_factorization_note_states_what_this_solve_measured() {
        // 3 iterations of 1.2 s against one LU of 0.1 s: 12× less, from these figures alone.
        let note = factorization_note(&report(3, 3.6, Some(0.1))).unwrap();
        assert!(note.contains("took 3.6 s") && note.contains("1.20 s per iteration (3 iterations)"), "{note}");
        assert!(note.contains("took 0.100 s, 12× less") && note.contains("--backend newton"), "{note}");
        let note = factorization_note(&report(1, 10.0, Some(2.0))).unwrap();
        assert!(note.contains("5× less"), "{note}");
        // Not timed (a short solve, or Newton was asked for), or not clearly faster.
        assert!(factorization_note(&report(3, 3.6, None)).is_none());
        assert!(factorization_note(&report(2, 3.0, Some(1.0))).is_none(), "1.5× is no reason to switch");
    }
}
