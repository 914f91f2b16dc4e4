//! Windowed solves: the span is covered by successive windows, each a global solve of
//! the scene's action over `length` seconds that starts from the state the previous
//! window reached and keeps all but its last `overlap` seconds.
//!
//! Why: the centred SBP stencils carry a parasitic odd-even mode, and damping or
//! contraction of the dynamics amplifies it toward the end of a solve like
//! `exp(∫ rate dt)`; the end closure also carries errors backward (a contact just before
//! the final time pollutes the run). A window bounds the amplification to one window's
//! length, and discarding its tail keeps every reported node away from an end closure —
//! including the last window's, which is solved past the scene's end time. The cost is
//! linear in the span: every window has the same number of nodes, so on a uniform grid
//! one action (and its sparsity plans) serves all of them; only the initial state
//! changes.
//!
//! Grid: the scene's nodes `t_k = t_start + k Δt` extended past `t_end` as far as the
//! last window needs. A window of `n_w = round(length/Δt) + 1` nodes starting at global
//! node `s` keeps nodes `s … s + r − 1` with `r ≤ n_w − 1 − round(overlap/Δt)`; the next
//! window starts at node `s + r` from this window's `(q, Dq)` there. `r` is the largest
//! such index whose node and its two neighbours on each side are out of contact with
//! every wall ([`contact`]), searched down to half the window, so that no window
//! starts inside a bounce (else the largest). Each window's initial guess is time
//! stepping from its own initial state.
//!
//! **On a mapped grid** (`grid = "adaptive"`, docs/grids.md) the windows are the same
//! runs of nodes of the grid that follows the motion: its `N` nodes over the span,
//! continued past the end at its last spacing, `Δt` the mean spacing; the window's
//! length and overlap count nodes at that mean spacing, so a window is short in time
//! where the nodes crowd (a contact) and long where they are sparse. Each window's
//! operator is made on its own nodes (`SbpOperator::on_times`), so each gets its action
//! and its solver's plans (their boundary constants hold the operator's first row); the
//! structure is the same, and Newton's LU analysis passes from one to the next.
//!
//! A window that does not converge ends the run: the nodes after its start are not
//! computed (NaN in the trajectory) and the run's status is that window's.

use std::sync::Arc;
use std::time::Instant;

use super::assess::sizes;
use super::backend::{BackendReport, SquareSolver};
use super::deadline::Deadline;
use super::error::{SolveError, WindowError};
use super::global::Run;
use super::outcome::{Method, Timings, Work};
use super::piece::{action_on, solve_piece, Guess, Piece};
use super::status::SolveStatus;
use crate::discrete::contact;
use crate::discrete::trajectory::{NodeSeries, Trajectory};
use crate::discrete::Discretization;
use crate::model::Model;
use crate::scene::{Scene, Windows};
use crate::solve::linalg::IterationStat;

/// Nodes and restart of the windows of a scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowGrid {
    /// Node spacing Δt (the scene's; on a mapped grid its mean).
    pub dt: f64,
    /// Nodes of each window's solve.
    pub nodes: usize,
    /// Nodes each window keeps at most; the next window starts at this local index or,
    /// to avoid starting in contact, earlier.
    pub keep: usize,
    /// Number of windows covering the scene's nodes if every window keeps `keep` nodes.
    pub count: usize,
}

impl WindowGrid {
    /// The windows of `scene` discretized by `disc` for `windows`, or why they do not fit
    /// its grid (too few nodes per window for the operator, nothing kept).
    pub fn new(scene: &Scene, disc: &Discretization, windows: Windows) -> Result<WindowGrid, WindowError> {
        let dt = disc.spacing(scene);
        let nodes = (windows.length / dt).round() as usize + 1;
        let dropped = (windows.overlap / dt).round() as usize;
        let min = disc.operator.min_nodes();
        if nodes < min {
            return Err(WindowError::TooFewNodes { length: windows.length, nodes, dt, operator: disc.operator, min });
        }
        if dropped + 1 >= nodes {
            return Err(WindowError::NothingKept { overlap: windows.overlap, length: windows.length });
        }
        let keep = nodes - 1 - dropped;
        let count = (disc.nodes.saturating_sub(nodes)).div_ceil(keep) + 1;
        Ok(WindowGrid { dt, nodes, keep, count })
    }
}

/// Solve `scene` with its model `model` and the discretization `disc` in windows, the
/// backend stopped at `deadline` (if any; the windows after one that did not converge
/// are not solved).
pub fn solve_windows(
    scene: &Scene,
    model: &Arc<Model>,
    disc: &Discretization,
    windows: Windows,
    deadline: Option<Deadline>,
) -> Result<Run, SolveError> {
    let grid =
        WindowGrid::new(scene, disc, windows).map_err(|error| SolveError::Windows { scene: scene.file.origin.path.clone(), error })?;
    let t_setup = Instant::now();
    let at = NodeTimes::of(scene, disc, grid.dt);
    let mut action = action_on(model, scene, disc, &at.window(0, grid.nodes))?;
    // One solver for all windows of a uniform grid: the sparsity plans and Newton's LU
    // analysis are made once and reused by every window.
    let mut solver = SquareSolver::new(scene, &action);
    solver.set_deadline(deadline);
    let sizes = sizes(scene, &action, &solver);
    let total = disc.nodes;
    let mut joined = Joined::new(total, t_setup.elapsed().as_secs_f64());
    let (mut q0, mut v0) = (scene.initial_q.clone(), scene.initial_v.clone());
    let mut start = 0;
    loop {
        let times = at.window(start, grid.nodes);
        if at.mapped.is_none() {
            action.set_window(times[0], &q0, &v0);
        } else if start > 0 {
            // A mapped window's operator is made on its own nodes, and so are the
            // boundary constants of the plans made from it: a new action and solver (of
            // the same structure: Newton's LU analysis is handed over, as the solver's
            // module documentation says, once the old solver is dropped).
            action = action_on(model, scene, disc, &times)?;
            action.set_initial_state(&q0, &v0);
            drop(solver);
            solver = SquareSolver::new(scene, &action);
            solver.set_deadline(deadline);
        }
        let piece = solve_piece(scene, &action, &mut solver, &times, &Guess::TimeStepping)?;
        let last = start + grid.nodes >= total;
        let keep = if last { total - start } else { restart_node(scene, &piece.trajectory, grid.keep) };
        let restart = (!last).then(|| (piece.trajectory.q[keep].clone(), piece.trajectory.v[keep].clone()));
        let converged = piece.status.is_converged();
        joined.add(piece, keep);
        if !converged {
            joined.not_computed((start + keep..total).map(|k| at.time(k)));
            break;
        }
        let Some((q, v)) = restart else { break };
        (q0, v0) = (q, v);
        start += keep;
    }
    let length = (grid.nodes - 1) as f64 * grid.dt;
    let method =
        Method::Windows { length, overlap: length - grid.keep as f64 * grid.dt, nodes_per_window: grid.nodes, count: joined.count };
    Ok(Run { method, discretization: disc.clone(), sizes, solution: joined.into_piece() })
}

/// The node times of a windowed run by global index: the discretization's over the
/// scene's span, continued past its end as far as the last window reaches, at the
/// uniform spacing, or on a mapped grid at its last spacing.
struct NodeTimes {
    t_start: f64,
    dt: f64,
    /// The mapped grid's nodes over the span (`None`: uniform).
    mapped: Option<Vec<f64>>,
}

impl NodeTimes {
    fn of(scene: &Scene, disc: &Discretization, dt: f64) -> NodeTimes {
        let mapped = (!disc.grid.is_uniform()).then(|| disc.times(scene));
        NodeTimes { t_start: scene.t_start, dt, mapped }
    }

    /// The time of global node `k`.
    fn time(&self, k: usize) -> f64 {
        match &self.mapped {
            None => self.t_start + k as f64 * self.dt,
            Some(t) => {
                let last = t.len() - 1;
                if k <= last {
                    t[k]
                } else {
                    t[last] + (k - last) as f64 * (t[last] - t[last - 1])
                }
            }
        }
    }

    /// The times of the `nodes` nodes from global node `start` on.
    fn window(&self, start: usize, nodes: usize) -> Vec<f64> {
        (start..start + nodes).map(|k| self.time(k)).collect()
    }
}

/// The windows' pieces joined into the run's (see [`Run::solution`]).
struct Joined {
    count: usize,
    trajectory: Trajectory,
    /// The time-stepping coordinates at the kept nodes, while every window has them.
    time_stepping_q: Option<NodeSeries>,
    /// The first window's status, or the first that did not converge.
    status: Option<SolveStatus>,
    iterations: usize,
    history: Vec<IterationStat>,
    /// The first window's backend report (it made the LU analysis), or the first that
    /// handed over to Ipopt.
    backend: Option<BackendReport>,
    max_residual: f64,
    max_eom_residual: f64,
    max_minus_variable: Option<f64>,
    timings: Timings,
    work: Work,
}

impl Joined {
    /// Nothing joined yet, of a run of `total` nodes whose setup took `setup_s`.
    fn new(total: usize, setup_s: f64) -> Joined {
        Joined {
            count: 0,
            trajectory: Trajectory::empty(),
            time_stepping_q: Some(Vec::with_capacity(total)),
            status: None,
            iterations: 0,
            history: Vec::new(),
            backend: None,
            max_residual: 0.0,
            max_eom_residual: 0.0,
            max_minus_variable: None,
            timings: Timings { setup_s, ..Timings::zero() },
            work: Work::default(),
        }
    }

    /// Join a window's piece, of which the first `keep` nodes are kept.
    fn add(&mut self, piece: Piece, keep: usize) {
        self.count += 1;
        self.timings.add(&piece.timings);
        self.work.add(&piece.work);
        self.iterations += piece.iterations;
        self.history.extend(piece.history);
        if self.backend.as_ref().is_none_or(|b| piece.backend.handed_over_to_ipopt && !b.handed_over_to_ipopt) {
            self.backend = Some(piece.backend);
        }
        self.max_residual = self.max_residual.max(piece.max_residual);
        self.max_eom_residual = self.max_eom_residual.max(piece.max_eom_residual);
        self.max_minus_variable = piece.max_minus_variable.map(|m| m.max(self.max_minus_variable.unwrap_or(0.0)));
        self.trajectory.extend_from(&piece.trajectory, 0..keep);
        self.time_stepping_q = match (self.time_stepping_q.take(), &piece.time_stepping_q) {
            (Some(mut acc), Some(ts)) => {
                acc.extend_from_slice(&ts[..keep]);
                Some(acc)
            }
            _ => None,
        };
        if !piece.status.is_converged() || self.status.is_none() {
            self.status = Some(piece.status);
        }
    }

    /// The nodes at `times`, after a window that did not converge, are not computed.
    fn not_computed(&mut self, times: impl Iterator<Item = f64>) {
        times.for_each(|t| self.trajectory.push_not_computed(t));
        self.time_stepping_q = None;
    }

    fn into_piece(self) -> Piece {
        Piece {
            status: self.status.expect("at least one window"),
            iterations: self.iterations,
            history: self.history,
            backend: self.backend.expect("at least one window"),
            trajectory: self.trajectory,
            max_residual: self.max_residual,
            max_eom_residual: self.max_eom_residual,
            max_minus_variable: self.max_minus_variable,
            time_stepping_q: self.time_stepping_q,
            // The windows' guesses start from each window's state: none is the
            // verification's time stepping of the whole span.
            reference_stepping: None,
            guess: "time stepping of the Lagrange–d'Alembert equations (adaptive Runge–Kutta, rtol 1e-8) from each window's initial \
                    state"
                .into(),
            timings: self.timings,
            work: self.work,
        }
    }
}

/// Neighbours on each side of a restart node that must be out of contact too.
const RESTART_CLEARANCE: usize = 2;

/// The local node the next window starts from: the largest `k ≤ keep`, down to `keep / 2`,
/// with nodes `k − 2 … k + 2` out of contact with every wall; `keep` if there is none.
fn restart_node(scene: &Scene, tr: &Trajectory, keep: usize) -> usize {
    let free = |k: usize| {
        (k - RESTART_CLEARANCE..=k + RESTART_CLEARANCE)
            .all(|m| scene.walls.iter().enumerate().all(|(j, w)| !contact::in_contact(tr.h[m][j], w.width)))
    };
    (keep / 2..=keep).rev().find(|&k| k >= RESTART_CLEARANCE && k + RESTART_CLEARANCE < tr.t.len() && free(k)).unwrap_or(keep)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Overrides, SceneFile};

    fn scene(nodes: usize, end: f64) -> Scene {
        let text = format!(
            "[scene]\nname = \"s\"\nlagrangian = \"x_dot^2/2 - x^2/2\"\n[[coordinates]]\nname = \"x\"\ninitial = 1\nvelocity = 0\n\
             [time]\nstart = 0\nend = {end}\nnodes = {nodes}\n"
        );
        SceneFile::parse(&text, "s.toml").unwrap().resolve(&Overrides::default()).unwrap()
    }

    #[test]
    fn windows_cover_the_nodes_with_equal_sizes() {
        // Δt = 0.01: 101 nodes per 1 s window, 25 dropped, 75 kept (nodes 0…74), next at 75.
        let s = scene(1001, 10.0);
        let g = WindowGrid::new(&s, &Discretization::of(&s), Windows { length: 1.0, overlap: 0.25 }).unwrap();
        assert_eq!((g.nodes, g.keep), (101, 75));
        // Starts 0, 75, …, 900 (the window at 900 reaches node 1000, the last).
        assert_eq!(g.count, 13);
        assert_eq!(12 * g.keep + g.nodes, 1001);
    }

    #[test]
    fn windows_too_short_for_the_operator_or_the_overlap_are_refused() {
        let s = scene(1001, 10.0);
        let e = WindowGrid::new(&s, &Discretization::of(&s), Windows { length: 0.05, overlap: 0.0 }).unwrap_err();
        assert_eq!(e.to_string(), "a window of 0.05 s has 6 nodes at the scene's spacing Δt = 0.01 s; SBP242 needs at least 8");
        let e = WindowGrid::new(&s, &Discretization::of(&s), Windows { length: 1.0, overlap: 0.995 }).unwrap_err();
        assert_eq!(e.to_string(), "an overlap of 0.995 s leaves nothing to keep of a 1 s window");
    }
}
