//! One solve of one action's discrete system (the whole span, or one window): build the
//! discrete action, make a physical initial guess, hand the square system to the
//! backend ([`backend`](super::backend): Ipopt, or Newton with a sparse LU), and turn
//! the critical point into a trajectory ([`solve_piece`], [`Piece`]).
//!
//! Initial guess: the Lagrange–d'Alembert equations of the same scene are integrated
//! by [`equations`](crate::stepping::equations) (adaptive high-order Runge–Kutta, index-reduced:
//! accelerations and multipliers from `[W Gᵀ; G 0]`, see [`Model::accelerations`]) at a
//! moderate tolerance and sampled at the nodes (when the solve will be verified, at the
//! verification's tolerance and steps, so that the verification need not step again:
//! [`NodeStepping`]); the minus variables start at zero and the
//! boundary multipliers at the values that make their rows vanish. A global-in-time
//! Newton solve started there converges in a few iterations (docs/solver.md: constant
//! velocity extrapolation did not converge on the disk). If time stepping fails, the
//! guess falls back to constant-velocity extrapolation and the summary says so.

use std::sync::Arc;
use std::time::Instant;

#[cfg(feature = "ipopt")]
use super::backend::{BackendError, SolverStatus};
use super::backend::{BackendReport, SquareSolver};
use super::error::SolveError;
use super::outcome::{Timings, Work};
use super::status::{SolveStatus, CONVERGED_RESIDUAL};
use crate::discrete::trajectory::{NodeSeries, States, Trajectory};
use crate::discrete::{Action, Discretization};
use crate::model::{Model, Physical};
#[cfg(feature = "ipopt")]
use crate::scene::IpoptValue;
use crate::scene::{Formulation, Scene, SceneError};
use crate::solve::linalg::IterationStat;
use crate::stepping::equations::{integrate_model, mean_spacing, step_budget, Stepped};
use crate::stepping::ode::{OdeError, OdeOptions, OdeStats};
use crate::stepping::verify::{self, NodeStepping};
#[cfg(feature = "ipopt")]
use skg_ipopt as ipopt;

/// Node times of a scene's own uniform grid, and their spacing.
pub fn grid(scene: &Scene) -> (Vec<f64>, f64) {
    let disc = Discretization::of(scene);
    (disc.times(scene), disc.spacing(scene))
}

/// Build the discrete action of a resolved scene on its own grid, with a model of its
/// own.
pub fn build_action(scene: &Scene) -> Result<Action, SolveError> {
    let disc = Discretization::of(scene);
    action_on(&Arc::new(Model::build(scene)?), scene, &disc, &disc.times(scene))
}

/// The discrete action of `model` (the scene's) with `disc`'s operator and
/// initial-velocity condition on the nodes `times`, from the scene's initial state (a
/// window re-targets it with [`Action::set_window`]).
pub fn action_on(model: &Arc<Model>, scene: &Scene, disc: &Discretization, times: &[f64]) -> Result<Action, SolveError> {
    let op = disc.operator_on(times)?;
    Ok(Action::new(Arc::clone(model), op, disc.initial_velocity, times, scene.initial_q.clone(), scene.initial_v.clone()))
}

/// How the initial guess of one solve is made.
#[derive(Debug, Clone)]
pub enum Guess {
    /// Time stepping of the Lagrange–d'Alembert equations from the action's initial
    /// state, sampled at its nodes.
    TimeStepping,
    /// Coordinates and multipliers at the action's nodes, e.g. a coarser solve
    /// interpolated onto this grid, or the solve of a wider wall.
    States {
        /// `q[k][i]` at the action's nodes.
        q: NodeSeries,
        /// `λ[k][a]` at the action's nodes.
        lambda: NodeSeries,
        /// Where they came from (for the summary).
        description: String,
    },
}

/// One solve of one action's discrete system: the whole span, or one window of it.
#[derive(Debug, Clone)]
pub struct Piece {
    /// How the backend ended, checked against the unscaled residual.
    pub status: SolveStatus,
    /// Iterations of the backend that finished.
    pub iterations: usize,
    /// Its iteration table.
    pub history: Vec<IterationStat>,
    /// Which backend ran, and Newton's own outcome.
    pub backend: BackendReport,
    /// The solution at the action's nodes.
    pub trajectory: Trajectory,
    /// max |c| of the system (unscaled) at the returned point.
    pub max_residual: f64,
    /// max |equation of motion| at interior nodes.
    pub max_eom_residual: f64,
    /// max |q-|, |λ-| for the full formulation.
    pub max_minus_variable: Option<f64>,
    /// The time-stepping coordinates at the nodes, when the guess made them.
    pub time_stepping_q: Option<NodeSeries>,
    /// The guess's time stepping when it is the verification's (from the scene's initial
    /// state, with the verification's options), for the verification to take.
    pub reference_stepping: Option<Arc<NodeStepping>>,
    /// How the initial guess was made.
    pub guess: String,
    /// Time of the guess and of the backend (setup and output are not a piece's).
    pub timings: Timings,
    /// Its work: the backends' counts and the guess's time stepping (the verification's
    /// is added by [`outcome`](crate::solve::outcome)).
    pub work: Work,
}

/// Solve the discrete system of `action` (nodes at `times`) from `guess` with `solver`,
/// which was built for this action (or one of equal structure) and keeps its sparsity
/// plans and LU analysis for the next piece.
pub fn solve_piece(scene: &Scene, action: &Action, solver: &mut SquareSolver, times: &[f64], guess: &Guess) -> Result<Piece, SolveError> {
    let t_guess = Instant::now();
    let mut warnings = Vec::new();
    // The Newton backend's LU analysis needs only the structure: it runs beside the
    // guess, on a second thread (its time is the solver's, `analysis_s`).
    let deadline = solver.deadline().map(|d| d.at);
    let (made, guess_s, analysed) = std::thread::scope(|s| {
        let analysing = solver.needs_analysis(action).then(|| s.spawn(|| solver.analyse(action)));
        let made = initial_guess(scene, action, times, guess, deadline, &mut warnings);
        let guess_s = t_guess.elapsed().as_secs_f64();
        (made, guess_s, analysing.map(|a| a.join().expect("the LU analysis panicked")))
    });
    let Made { z0, description: guess_desc, time_stepping_q: ts_q, steps: guess_steps, reference_stepping } = made;
    let t_check = Instant::now();
    check_initial_guess(scene, action, times, &z0, &guess_desc, &warnings)?;
    let initial_guess_s = guess_s + t_check.elapsed().as_secs_f64();
    if let Some(analysed) = analysed {
        analysed.map_err(|e| rejected_option(scene, e.into()))?;
    }

    let solution = solver.solve(action, &z0).map_err(|e| rejected_option(scene, e.into()))?;
    #[cfg(feature = "ipopt")]
    if solution.status == SolverStatus::Ipopt(ipopt::Status::InvalidOption) {
        return Err(unusable_option(scene));
    }
    let z = &solution.z;

    let t_post = Instant::now();
    let (trajectory, max_eom_residual) = evaluate(action, times, z);
    let lay = &action.layout;
    let max_minus_variable = (scene.formulation == Formulation::Full)
        .then(|| lay.qm.iter().chain(&lay.lm).map(|&i| z[i as usize].abs()).fold(0.0_f64, f64::max));
    let max_residual = solution.max_residual;
    // Only a residual above CONVERGED_RESIDUAL needs the equation-by-equation test.
    let at_round_off =
        max_residual.is_finite() && max_residual > CONVERGED_RESIDUAL && solver.equations_at_round_off(action, z, CONVERGED_RESIDUAL);
    Ok(Piece {
        work: Work::of_system(&solution.report, guess_steps),
        status: SolveStatus::classify(solution.status, max_residual, at_round_off),
        iterations: solution.iterations,
        history: solution.history,
        backend: solution.report,
        trajectory,
        max_residual,
        max_eom_residual,
        max_minus_variable,
        time_stepping_q: ts_q,
        reference_stepping,
        guess: match warnings.first() {
            Some(w) => format!("{guess_desc} ({w})"),
            None => guess_desc,
        },
        timings: Timings {
            initial_guess_s,
            solver_s: solution.total_s,
            evaluation_s: solution.evaluation_s,
            solver_internal_s: solution.total_s - solution.evaluation_s,
            postprocess_s: t_post.elapsed().as_secs_f64(),
            ..Timings::zero()
        },
    })
}

/// An initial guess: the point, how it was made, the time-stepping coordinates when
/// the guess made them (for the spurious-solution check), the work of that time
/// stepping, and the stepping itself when it is the verification's.
struct Made {
    z0: Vec<f64>,
    description: String,
    time_stepping_q: Option<NodeSeries>,
    steps: OdeStats,
    reference_stepping: Option<Arc<NodeStepping>>,
}

/// The initial point of `action` on the nodes `times` from `guess`, its time stepping
/// given up at `deadline` (the backend then stops before its first step).
fn initial_guess(
    scene: &Scene,
    action: &Action,
    times: &[f64],
    guess: &Guess,
    deadline: Option<Instant>,
    warnings: &mut Vec<String>,
) -> Made {
    let (q, lambda, description, time_stepping_q, steps, reference_stepping) = match guess {
        Guess::States { q, lambda, description } => (q.clone(), lambda.clone(), description.clone(), None, OdeStats::default(), None),
        Guess::TimeStepping => match time_stepping(scene, action, times, deadline) {
            Ok(TimeStepped { q, lambda, description, steps, reference }) => (q.clone(), lambda, description, Some(q), steps, reference),
            Err(e) => {
                warnings.push(format!("time stepping for the initial guess failed ({e}); using constant-velocity extrapolation"));
                let (d, n) = (action.layout.d, action.layout.n);
                let (q0, v0) = (action.q0(), action.v0());
                let q: NodeSeries = times.iter().map(|t| (0..d).map(|i| q0[i] + v0[i] * (t - times[0])).collect()).collect();
                (q, vec![vec![0.0; n]; times.len()], "constant-velocity extrapolation".to_string(), None, OdeStats::default(), None)
            }
        },
    };
    Made { z0: point_from_states(action, &q, &lambda), description, time_stepping_q, steps, reference_stepping }
}

/// A time stepping of an action's equations at its nodes: the coordinates and
/// multipliers, how it was made, its work, and the stepping itself when it is the
/// verification's.
struct TimeStepped {
    q: NodeSeries,
    lambda: NodeSeries,
    description: String,
    steps: OdeStats,
    reference: Option<Arc<NodeStepping>>,
}

/// The time stepping of `action` from its initial state sampled at `times`. For a solve
/// of the whole span that will be verified from the same start, the verification's own
/// (its tolerance, steps at most the node spacing), which the verification then takes
/// instead of stepping again (not a window's, nor the ladder's solve past the end);
/// else at rtol 1e-8. With walls, steps at most the node spacing: a larger step can
/// jump across a thin wall that the error estimate never sees (free flight is
/// integrated exactly). Without walls the step is left to the error control: at
/// N = 16384 the capped guess cost as much as the whole Newton solve, the uncapped one a
/// tenth, with the same Newton iterations on every shipped scene
/// (docs/benchmarks.md#the-initial-guess).
fn time_stepping(scene: &Scene, action: &Action, times: &[f64], deadline: Option<Instant>) -> Result<TimeStepped, OdeError> {
    let (q0, v0) = (action.q0(), action.v0());
    if scene.verify.enabled && whole_span(scene, times) && q0 == scene.initial_q.as_slice() && v0 == scene.initial_v.as_slice() {
        let ns = verify::default_reference_stepping(scene, &action.model, times, deadline)?;
        let States { q, lambda, .. } = ns.stepped.states.clone();
        let description = format!("the verification's time stepping ({}) sampled at the nodes", ns.stepped.method);
        return Ok(TimeStepped { q, lambda, description, steps: ns.stepped.stats, reference: Some(Arc::new(ns)) });
    }
    let max_step = if action.model.walls.is_empty() { None } else { mean_spacing(times) };
    let max_steps = step_budget(times.len());
    let stepper = scene.verify.stepper;
    let opts = OdeOptions { rtol: 1e-8, atol: 1e-10, max_step, max_steps, stepper, deadline, ..OdeOptions::default() };
    let Stepped { states: States { q, lambda, .. }, stats, .. } = integrate_model(&action.model, q0, v0, times, &opts)?;
    let description =
        "time stepping of the Lagrange–d'Alembert equations (adaptive Runge–Kutta, rtol 1e-8) sampled at the nodes".to_string();
    Ok(TimeStepped { q, lambda, description, steps: stats, reference: None })
}

/// Whether `times` are nodes from the scene's start to its end (to the rounding of a
/// grid's last node).
fn whole_span(scene: &Scene, times: &[f64]) -> bool {
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * (scene.t_end - scene.t_start).abs();
    matches!((times.first(), times.last()), (Some(&a), Some(&b)) if close(a, scene.t_start) && close(b, scene.t_end))
}

/// Refuse an initial guess with a value that is not finite, naming the node, the state
/// and the scene's expression that is undefined there (Ipopt would only say "starting
/// point x0[i] = NaN").
/// `guess` says how the guess was made and `notes` why (a failed time stepping).
fn check_initial_guess(scene: &Scene, action: &Action, times: &[f64], z0: &[f64], guess: &str, notes: &[String]) -> Result<(), SolveError> {
    let Some(bad) = z0.iter().position(|x| !x.is_finite()) else { return Ok(()) };
    let names: Vec<String> = scene.constraints.iter().map(|c| c.name.clone()).collect();
    let (k, what) = action.layout.describe(bad, &scene.coordinates, &names);
    let q = action.layout.coordinates(z0);
    let v = apply_d(&action.op, &q);
    let source = action.model.non_finite_expression(scene, times[k], &q[k], &v[k]);
    let state = |xs: &[f64]| xs.iter().map(|x| format!("{x:.6e}")).collect::<Vec<_>>().join(", ");
    let message = format!(
        "the initial guess ({guess}) is not finite: {what} at node {k} (t = {}) is {}; \
         at that node q = ({}), q̇ = ({}){}{}",
        times[k],
        z0[bad],
        state(&q[k]),
        state(&v[k]),
        match &source {
            Some((expr, _)) => format!(", where {expr} is not finite (e.g. sqrt or log of a negative number, a division by zero)"),
            None => String::new(),
        },
        notes.iter().map(|n| format!("; {n}")).collect::<String>()
    );
    let location = source.map_or_else(|| scene.file.origin.whole(), |(_, at)| at);
    Err(SceneError::Invalid { location, message }.into())
}

/// An option Ipopt refused when it was set, as an input error at the option's place in
/// the scene file; other errors pass through.
/// Without Ipopt no option is refused by it.
#[cfg(not(feature = "ipopt"))]
fn rejected_option(_: &Scene, e: SolveError) -> SolveError {
    e
}

#[cfg(feature = "ipopt")]
fn rejected_option(scene: &Scene, e: SolveError) -> SolveError {
    let SolveError::Backend(BackendError::Ipopt(ipopt::SolveError::BadOption { name, value })) = &e else { return e };
    let message = format!(
        "Ipopt refused the option {name} = {value}: it has no such option, or the value has the wrong type or is outside \
         the option's range (Ipopt prints its reason on stdout)"
    );
    SceneError::Invalid { location: scene.file.solver_option_location(name), message }.into()
}

/// Ipopt's `Invalid_Option` at the start of a solve (an option value it accepted but
/// cannot use, e.g. a linear solver whose library it cannot load), as an input error at
/// the `linear_solver` Ipopt was given: `[solver.ipopt]`'s, which is passed last and so
/// wins, else `[solver]`'s.
#[cfg(feature = "ipopt")]
fn unusable_option(scene: &Scene) -> SolveError {
    let file = &scene.file.solver;
    let passed = match (scene.solver.ipopt.get("linear_solver"), file.ipopt.get("linear_solver")) {
        (Some(IpoptValue::Str(name)), Some(spanned)) => Some(("[solver.ipopt] linear_solver", name.clone(), spanned.span())),
        _ => None,
    };
    let named = passed.or_else(|| {
        let spanned = file.linear_solver.as_ref()?;
        Some(("[solver] linear_solver", spanned.get_ref().clone(), spanned.span()))
    });
    let (location, message) = match named {
        Some((key, solver, span)) => (
            scene.file.origin.locate(span.start),
            format!(
                "Ipopt cannot use {key} = \"{solver}\" (Invalid_Option: its library could not be loaded); Debian's \
                 Ipopt has only MUMPS: use linear_solver = \"mumps\" or remove the key"
            ),
        ),
        None => {
            (scene.file.origin.whole(), "Ipopt stopped with Invalid_Option: an option of [solver.ipopt] has a value it cannot use".into())
        }
    };
    SceneError::Invalid { location, message }.into()
}

/// The unknown vector Z with the given coordinates and multipliers at the nodes, the
/// minus variables at zero and the boundary multipliers at the values that make their
/// rows vanish (a solve's initial guess; a fit's starting point).
pub fn point_from_states(action: &Action, q: &[Vec<f64>], lambda: &[Vec<f64>]) -> Vec<f64> {
    let lay = &action.layout;
    let (d, n) = (lay.d, lay.n);
    let mut z = vec![0.0; lay.len()];
    for k in 0..lay.nodes {
        for i in 0..d {
            z[lay.qp[k * d + i] as usize] = q[k][i];
        }
        for a in 0..n {
            let zi = lay.lp[k * n + a];
            if zi != u32::MAX {
                z[zi as usize] = lambda[k][a];
            }
        }
    }
    let mut ws = action.model.workspace();
    let mut r = vec![0.0; lay.n_m];
    action.gradient(&z, true, &mut r, &mut ws);
    let last = lay.nodes - 1;
    let row = |zi: u32| zi as usize - lay.n_p;
    for i in 0..d {
        z[lay.nu_qn[i] as usize] = -r[row(lay.qm[last * d + i])];
    }
    for a in 0..n {
        z[lay.nu_ln[a] as usize] = -r[row(lay.lm[last * n + a])];
    }
    // The first node's multipliers (strong initial velocity only).
    for (i, &nu) in lay.nu_q1.iter().enumerate() {
        z[nu as usize] = -r[row(lay.qm[i])];
    }
    for (a, &nu) in lay.nu_l1.iter().enumerate() {
        z[nu as usize] = -r[row(lay.lm[a])];
    }
    z
}

/// The trajectory and the largest equation-of-motion residual
/// |f + F − D−p − Gᵀλ| over interior nodes (force units). The velocities are `D q`, the
/// operator of the action; the equations of motion carry its SBP partner `D−`
/// (docs/mathematics.md §3: for a centred operator `D− = D`, for a dissipative one
/// `D− = D + ε H⁻¹ D_pᵀ D_p`).
fn evaluate(action: &Action, times: &[f64], z: &[f64]) -> (Trajectory, f64) {
    let lay = &action.layout;
    let (d, n, nodes) = (lay.d, lay.n, lay.nodes);
    let model = &action.model;
    let mut ws = model.workspace();
    let q: Vec<Vec<f64>> = (0..nodes).map(|k| (0..d).map(|i| z[lay.qp[k * d + i] as usize]).collect()).collect();
    let v = apply_d(&action.op, &q);
    let phys: Vec<_> = (0..nodes).map(|k| model.physical(times[k], &q[k], &v[k], &mut ws)).collect();
    let p: Vec<Vec<f64>> = phys.iter().map(|ph| ph.p.clone()).collect();
    let dp = apply_d(&action.op.partner(), &p);
    let mut lambda = vec![vec![0.0; n]; nodes];
    let mut max_eom = 0.0_f64;
    for k in 0..nodes {
        // λ+ is pinned where the node's row was absorbed: the last node, and the first
        // one with the strong initial velocity.
        let pinned = n > 0 && lay.lp[k * n] == u32::MAX;
        if pinned {
            lambda[k] = end_multipliers(&phys[k], &dp[k]);
        } else {
            for a in 0..n {
                lambda[k][a] = z[lay.lp[k * n + a] as usize];
            }
        }
        if k == 0 || k + 1 == nodes {
            continue;
        }
        for i in 0..d {
            let gl: f64 = (0..n).map(|a| lambda[k][a] * phys[k].gv[(a, i)]).sum();
            max_eom = max_eom.max((phys[k].force[i] - dp[k][i] - gl).abs());
        }
    }
    (Trajectory::from_physical(times, States { q, v, lambda }, &phys), max_eom)
}

/// An operator applied to each component of a node-major series.
fn apply_d(op: &crate::sbp::SbpOperator, series: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let nodes = series.len();
    let d = series.first().map_or(0, Vec::len);
    let mut out = vec![vec![0.0; d]; nodes];
    let mut col = vec![0.0; nodes];
    let mut dcol = vec![0.0; nodes];
    for i in 0..d {
        for k in 0..nodes {
            col[k] = series[k][i];
        }
        op.apply(&col, &mut dcol);
        for k in 0..nodes {
            out[k][i] = dcol[k];
        }
    }
    out
}

/// λ at an end node: least-squares solution of that node's equation of motion
/// `Gᵀ λ = f + F − (D−p)` (its row of ∂S/∂q- was absorbed by a boundary multiplier).
fn end_multipliers(ph: &Physical, dp: &[f64]) -> Vec<f64> {
    let rhs = nalgebra::DVector::from_iterator(dp.len(), ph.force.iter().zip(dp).map(|(f, d)| f - d));
    let g = &ph.gv; // n×d
    let normal = g * g.transpose();
    match normal.lu().solve(&(g * rhs)) {
        Some(l) => l.iter().copied().collect(),
        None => vec![f64::NAN; g.nrows()],
    }
}
