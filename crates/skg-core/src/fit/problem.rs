//! The problem a fit hands to Ipopt ([`FitProblem`]): unknowns `x = (P, θ)`, the plus
//! block of the trajectory and the free parameters; constraints `R(P; θ) = 0`, the
//! reduced system of a solve, with its exact sparse Jacobian `(∂R/∂P, ∂R/∂θ)`; objective
//! the misfit `½ Σ w_i (e_i·P − d_i)²`; bounds on `θ` where the user gave them; and the
//! exact Hessian of Ipopt's Lagrangian `σ f + yᵀR`, which is `σ Σ w_i e_i e_iᵀ` plus the
//! Hessian of `S(P, y; θ)` in `(P, θ)`: the action is linear in its minus block, so
//! `yᵀR(P; θ) = S(P, M = y; θ)` (docs/fitting.md). With the limited-memory option no
//! Hessian is given and Ipopt builds its own quasi-Newton approximation.
//!
//! **Stopping.** The fit stops Ipopt itself, from its intermediate callback, once the
//! iterate is a KKT point to the fit's tolerances: outside the restoration phase, after
//! at least one step, the dual infeasibility (unscaled, stricter than Ipopt's scaled
//! test) at most the fit's `tol`, the constraints at most the scene's `tol` or their
//! round-off level `4 ε maxᵢ Σⱼ |Jᵢⱼ| |xⱼ|` (the square solve's test,
//! docs/solver.md#how-ipopt-is-stopped), and, when a parameter is bounded, the barrier's
//! displacement of the parameters at most `tol` relative to their size (`barrier.rs`:
//! the slack of a parameter on its bound, the barrier's force through the misfit's
//! curvature for the others). Or, with the constraints so held, once Newton's step on the
//! misfit of the motions, `−(AᵀA)⁻¹ ∇F` with the reduced gradient `∇F = Sᵀ ∇_P f`, moves
//! every parameter off its bounds by at most `tol` relative (the reduced fit's test,
//! `reduced.rs`): with noisy data weighted by `1/σ²` the dual infeasibility stalls at the
//! gradient's rounding above `tol` (a damped pendulum, σ = 0.01: at 1e-9, and Ipopt went
//! on to its acceptable level, 11 iterations where this test stops after 6). The
//! constraints of every shipped fit stagnate at their round-off level above the scene's
//! `tol`, so Ipopt's own test never held: it went on until its acceptable level,
//! [`ACCEPTABLE_ITER`](super::ACCEPTABLE_ITER) iterations more, each a factorization or
//! several, at the same point (docs/benchmarks.md#fitting);
//! and Ipopt's barrier parameter needs several more iterations to reach `tol` after the
//! parameters have stopped moving.
//!
//! The intermediate callback is given Ipopt's statistics only (Ipopt 3.11's C interface),
//! not its iterate: the problem keeps the last point Ipopt asked the objective's gradient
//! at, which is the current iterate (Ipopt evaluates the gradients at an accepted point
//! for its own convergence test, just before the callback; trial points of the line
//! search get the objective and the constraints only: in the 406 callbacks of the fit
//! tests the misfit at that point was the objective Ipopt reported, to the last bit).

use nalgebra::DMatrix;
use std::cell::{RefCell, RefMut};
use std::time::Instant;

use skg_ipopt::{EvalError, IterationStat, Problem, INFINITY_BOUND};

use super::barrier;
use super::free::FreeParameter;
use super::observe::Observations;
use super::statistics;
use crate::discrete::action::{Action, MatrixPlan};
use crate::discrete::ParameterPlan;
use crate::model::Workspace;
use crate::solve::backend;
use crate::solve::linalg::roundoff::residual_roundoff_level;
use crate::solve::linalg::SparseFactorization;
use crate::solve::Deadline;

/// The plans of the derivatives a fit's problem fills.
pub(super) struct Plans {
    /// `∂R/∂P`: a solve's reduced Jacobian.
    pub jacobian: MatrixPlan,
    /// The Hessian block `(P, P)` of `yᵀR`: a solve's reduced Hessian (exact Hessian only).
    pub hessian: Option<MatrixPlan>,
    /// `∂R/∂θ` and the Hessian blocks `(θ, P)`, `(θ, θ)`.
    pub parameters: ParameterPlan,
    /// The last LU of `∂R/∂P` ([`Plans::factor_jacobian`]).
    pub jacobian_lu: RefCell<Option<SparseFactorization>>,
}

impl Plans {
    /// `∂R/∂P` (`n_p × n_p`) with `values` factored, on one symbolic analysis of its
    /// structure for the whole fit: the starting multipliers, the stopping test's
    /// curvature and the statistics each factor it at another point, and each analysis
    /// (its COLAMD ordering) cost as much as the numeric factorization (the rolling
    /// disk's fit: 7–12 ms each of four). That analysis is the start solve's, kept on
    /// this thread by Newton's solver (`solve::backend`), when it is of the same
    /// structure; a second factorization at the same point is skipped
    /// ([`SparseFactorization::refactor`]). `None` when it is singular.
    pub fn factor_jacobian(&self, n_p: usize, values: &[f64]) -> Option<RefMut<'_, SparseFactorization>> {
        let mut slot = self.jacobian_lu.borrow_mut();
        match slot.as_mut() {
            Some(lu) => {
                if !lu.refactor(values) {
                    return None;
                }
            }
            None => {
                let structure = &self.jacobian.structure;
                let kept = backend::factorization_on_kept_analysis(n_p, structure, values);
                *slot = Some(kept.or_else(|| SparseFactorization::new(n_p, structure, values))?);
            }
        }
        RefMut::filter_map(slot, Option::as_mut).ok()
    }
}

/// How far, relative to `max(|θ|, 1)`, the parameters may have moved since the misfit's
/// curvature was computed for the stopping test to use it again: the test needs the
/// curvature's size, not its digits.
const CURVATURE_REUSE: f64 = 1e-3;

/// A fit as Ipopt's problem (module documentation).
pub(super) struct FitProblem<'a> {
    action: &'a mut Action,
    plans: &'a Plans,
    observations: &'a Observations,
    free: &'a [FreeParameter],
    ws: Workspace,
    /// The whole unknown vector of the action: `P` from `x`, the minus block zero (or the
    /// Hessian's weights).
    z: Vec<f64>,
    /// The parameters the action was last set to.
    theta: Vec<f64>,
    jacobian: Vec<(u32, u32)>,
    hessian: Vec<(u32, u32)>,
    stop: StopTest,
    /// The round-off level of the constraints at the last Jacobian.
    roundoff: f64,
    /// The last point of the objective's gradient: Ipopt's iterate in its intermediate
    /// callback (module documentation).
    iterate: Vec<f64>,
    /// The misfit's curvature at the parameters of an earlier iterate (`curvature`).
    curvature: Option<(Vec<f64>, DMatrix<f64>)>,
    /// Set when the callback stopped Ipopt at a KKT point (module documentation).
    stopped: Option<KktStop>,
    pub(super) clock: Clock,
}

/// How the callback stopped Ipopt at a KKT point: the constraints within the scene's
/// `tol`, or at their round-off level above it; or, in the reduced fit, at the
/// acceptable level of its own displacement test (`reduced.rs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum KktStop {
    Tolerance,
    RoundOff,
    Acceptable,
}

impl KktStop {
    /// The status reported: Ipopt's name for a success, or the solve's for one at the
    /// round-off level (docs/solver.md#how-ipopt-is-stopped).
    pub(super) fn status(self) -> &'static str {
        match self {
            KktStop::Tolerance => "Solve_Succeeded",
            KktStop::RoundOff => "Ipopt_Converged_To_Round_Off",
            KktStop::Acceptable => "Solved_To_Acceptable_Level",
        }
    }

    /// The status in words.
    pub(super) fn text(self) -> &'static str {
        match self {
            KktStop::Tolerance => "converged to the requested tolerances",
            KktStop::RoundOff => "converged, with the equations of motion at their round-off level above the scene's tol",
            KktStop::Acceptable => "converged to the acceptable level",
        }
    }
}

/// The tolerances of the fit's own stopping test (module documentation).
#[derive(Debug, Clone, Copy)]
pub(super) struct StopTest {
    /// The fit's `tol`: the dual infeasibility and, with bounds, the barrier's
    /// displacement of the parameters relative to their size (`barrier.rs`).
    pub tol: f64,
    /// The tolerance on the constraints, the smaller of the scene's and the fit's `tol`
    /// (as Ipopt's own test); below their round-off level, that level.
    pub constraints: f64,
    /// Ipopt's `bound_relax_factor`: its barrier acts from the bounds moved out by this
    /// factor times `max(1, |bound|)`.
    pub bound_relax_factor: f64,
    /// The user's time limit (`--time-limit`, `[solver] time_limit`), at which Ipopt's
    /// iterations ([`Clock`]) and the reduced fit's Newton solves end.
    pub deadline: Option<Deadline>,
}

/// The time limit at Ipopt's iterations: Ipopt is stopped before an iteration that would
/// end past the deadline if it took as long as the last one (as a solve's backends are,
/// `solve/run/deadline.rs`).
#[derive(Debug)]
pub(super) struct Clock {
    deadline: Option<Deadline>,
    last: Option<Instant>,
    /// Set when the time limit stopped Ipopt.
    pub ran_out: bool,
}

impl Clock {
    pub fn new(deadline: Option<Deadline>) -> Clock {
        Clock { deadline, last: None, ran_out: false }
    }

    /// At an iteration: whether the time limit stops Ipopt here.
    pub fn out_of_time(&mut self) -> bool {
        let Some(d) = self.deadline else { return false };
        let now = Instant::now();
        let last_s = self.last.replace(now).map_or(0.0, |t| now.duration_since(t).as_secs_f64());
        self.ran_out = d.would_pass(last_s);
        self.ran_out
    }
}

impl<'a> FitProblem<'a> {
    pub(super) fn new(
        action: &'a mut Action,
        plans: &'a Plans,
        observations: &'a Observations,
        free: &'a [FreeParameter],
        stop: StopTest,
    ) -> Self {
        let n_p = action.layout.n_p as u32;
        let mut jacobian = plans.jacobian.structure.clone();
        jacobian.extend(plans.parameters.jacobian.iter().map(|&(r, j)| (r, n_p + j)));
        let mut hessian = Vec::new();
        if let Some(h) = &plans.hessian {
            hessian.extend(&h.structure);
            hessian.extend(&observations.hessian);
            hessian.extend(&plans.parameters.hessian);
        }
        let ws = action.model.workspace();
        let z = vec![0.0; action.layout.len()];
        FitProblem {
            action,
            plans,
            observations,
            free,
            ws,
            z,
            theta: Vec::new(),
            jacobian,
            hessian,
            stop,
            roundoff: 0.0,
            iterate: Vec::new(),
            curvature: None,
            stopped: None,
            clock: Clock::new(stop.deadline),
        }
    }

    /// How the callback stopped Ipopt at a KKT point, if it did (module documentation).
    pub(super) fn stopped_at_kkt_point(&self) -> Option<KktStop> {
        self.stopped
    }

    /// Whether Ipopt's iterate is a KKT point to the fit's tolerances, and how.
    fn at_kkt_point(&mut self, stat: &IterationStat) -> Option<KktStop> {
        let stop = if stat.restoration || stat.iter < 1 {
            None
        } else if stat.inf_pr <= self.stop.constraints {
            Some(KktStop::Tolerance)
        } else if stat.inf_pr <= self.roundoff {
            Some(KktStop::RoundOff)
        } else {
            None
        };
        stop.filter(|_| (stat.inf_du <= self.stop.tol && self.barrier_negligible(stat.mu)) || self.near_the_minimum(stat.mu))
    }

    /// Whether the iterate's parameters lie within their tolerances of the misfit's
    /// minimum, its equations holding (module documentation): Newton's step on the
    /// misfit of the motions, `−(AᵀA)⁻¹ ∇F` with the reduced gradient `∇F = Sᵀ ∇_P f` at
    /// the iterate, moves each parameter off its bounds by at most `tol · max(|θ|, 1)`
    /// (`barrier.rs` with the whole gradient as the force, as the reduced fit's test).
    /// One sparse LU of `∂R/∂P`.
    fn near_the_minimum(&mut self, mu: f64) -> bool {
        let n_p = self.action.layout.n_p;
        if self.iterate.len() != n_p + self.free.len() {
            return false;
        }
        let x = std::mem::take(&mut self.iterate);
        self.set(&x, None);
        self.iterate = x;
        let Some((gradient, curvature)) =
            statistics::reduced_gradient(self.action, self.plans, self.observations, &self.iterate, &mut self.ws)
        else {
            return false;
        };
        let mut hold = barrier::hold(self.free, &self.iterate[n_p..], mu, self.stop.tol, self.stop.bound_relax_factor);
        hold.force = gradient.iter().copied().collect();
        hold.negligible(&curvature)
    }

    /// Whether Ipopt's barrier at `mu` displaces the parameters of its iterate by at most
    /// their tolerances (`barrier.rs`): always without bounds; judged with the misfit's
    /// Gauss–Newton curvature only when a parameter off its bounds feels a force.
    fn barrier_negligible(&mut self, mu: f64) -> bool {
        let n_p = self.action.layout.n_p;
        if self.free.iter().all(|p| p.lower.is_none() && p.upper.is_none()) {
            return true;
        }
        if self.iterate.len() != n_p + self.free.len() {
            return false;
        }
        let hold = barrier::hold(self.free, &self.iterate[n_p..], mu, self.stop.tol, self.stop.bound_relax_factor);
        hold.free_of_force() || self.curvature().is_some_and(|c| hold.negligible(&c))
    }

    /// The misfit's Gauss–Newton curvature `AᵀA` (`statistics.rs`) near the iterate: the
    /// one computed at an earlier iterate whose parameters were within
    /// [`CURVATURE_REUSE`] of these (the fit's last iterations move them far less), else
    /// computed here, one sparse LU of `∂R/∂P`; `None` when that is singular.
    fn curvature(&mut self) -> Option<DMatrix<f64>> {
        let n_p = self.action.layout.n_p;
        let theta = &self.iterate[n_p..];
        let close = |(at, c): &(Vec<f64>, DMatrix<f64>)| {
            at.iter().zip(theta).all(|(a, t)| (a - t).abs() <= CURVATURE_REUSE * t.abs().max(1.0)).then(|| c.clone())
        };
        if let Some(c) = self.curvature.as_ref().and_then(close) {
            return Some(c);
        }
        let x = std::mem::take(&mut self.iterate);
        self.set(&x, None);
        self.iterate = x;
        let c = statistics::curvature(self.action, self.plans, self.observations, &self.z, &mut self.ws)?;
        self.curvature = Some((self.iterate[n_p..].to_vec(), c.clone()));
        Some(c)
    }

    /// Set the action to `x`'s parameters (when they changed) and `z` to its plus block,
    /// with the minus block `minus` (the Hessian's weights) or zero.
    fn set(&mut self, x: &[f64], minus: Option<&[f64]>) {
        let n_p = self.action.layout.n_p;
        if self.theta.as_slice() != &x[n_p..] {
            self.theta = x[n_p..].to_vec();
            self.action.set_parameters(&self.theta, &mut self.ws);
        }
        self.z[..n_p].copy_from_slice(&x[..n_p]);
        match minus {
            Some(y) => self.z[n_p..].copy_from_slice(y),
            None => self.z[n_p..].fill(0.0),
        }
    }
}

impl Problem for FitProblem<'_> {
    fn num_variables(&self) -> usize {
        self.action.layout.n_p + self.free.len()
    }
    fn num_constraints(&self) -> usize {
        self.action.layout.n_m
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(-INFINITY_BOUND);
        upper.fill(INFINITY_BOUND);
        let n_p = self.action.layout.n_p;
        for (j, p) in self.free.iter().enumerate() {
            lower[n_p + j] = p.lower.unwrap_or(-INFINITY_BOUND);
            upper[n_p + j] = p.upper.unwrap_or(INFINITY_BOUND);
        }
    }
    fn objective(&mut self, x: &[f64]) -> Result<f64, EvalError> {
        Ok(self.observations.misfit(x))
    }
    fn objective_gradient(&mut self, x: &[f64], grad: &mut [f64]) -> Result<(), EvalError> {
        self.observations.gradient(x, grad);
        self.iterate.clear();
        self.iterate.extend_from_slice(x);
        Ok(())
    }
    fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
        self.set(x, None);
        self.action.gradient(&self.z, true, c, &mut self.ws);
        Ok(())
    }
    fn jacobian_structure(&self) -> &[(u32, u32)] {
        &self.jacobian
    }
    fn jacobian_values(&mut self, x: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        self.set(x, None);
        let (solve, params) = values.split_at_mut(self.plans.jacobian.structure.len());
        self.action.matrix_values(&self.plans.jacobian, &self.z, solve, &mut self.ws);
        self.action.parameter_jacobian(&self.plans.parameters, &self.z, params, &mut self.ws);
        let entries = self.jacobian.iter().zip(values.iter()).map(|(&(r, c), &v)| (r as usize, c as usize, v));
        self.roundoff = residual_roundoff_level(entries, x, self.action.layout.n_m);
        Ok(())
    }
    fn hessian_structure(&self) -> &[(u32, u32)] {
        &self.hessian
    }
    fn hessian_values(&mut self, x: &[f64], obj_factor: f64, lambda: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        let Some(plan) = &self.plans.hessian else { return Ok(()) };
        self.set(x, Some(lambda));
        let (solve, rest) = values.split_at_mut(plan.structure.len());
        let (misfit, params) = rest.split_at_mut(self.observations.hessian.len());
        self.action.matrix_values(plan, &self.z, solve, &mut self.ws);
        self.observations.hessian_values(obj_factor, misfit);
        self.action.parameter_hessian(&self.plans.parameters, &self.z, params, &mut self.ws);
        Ok(())
    }
    fn intermediate(&mut self, stat: &IterationStat) -> bool {
        self.stopped = self.at_kkt_point(stat);
        self.stopped.is_none() && !self.clock.out_of_time()
    }
}
