//! Newton's method for a square sparse system `F(x) = 0` with a sparse LU of its
//! Jacobian (docs/solver.md#the-newton-backend).
//!
//! The system is anything that implements [`SquareSystem`].
//!
//! **Linear algebra.** A [`SystemSolver`] is built once per sparsity structure: it makes
//! the sparse LU's symbolic analysis (`lu.rs`). Every Newton iteration then does one
//! numeric LU and one pair of triangular solves (or a few, to refine a single-precision
//! solution). The same value serves any number of solves of systems with the same
//! structure: successive iterations, successive time windows, sweep points.
//!
//! **Globalization.** The step `dx = −J(x)⁻¹ F(x)` is tried with `α = 1, ½, ¼, …`
//! until the Armijo condition on the residual norm
//! `‖F(x + α dx)‖₂ ≤ (1 − 10⁻⁴ α) ‖F(x)‖₂` holds (Dennis and Schnabel, *Numerical
//! Methods for Unconstrained Optimization and Nonlinear Equations*, §6.3, applied to
//! `½‖F‖₂²`, whose directional derivative along the Newton step is `−‖F‖₂²`). A step
//! whose residual is not finite counts as not decreasing. The iteration stops with
//! [`NewtonStatus::Converged`] when `max |F| ≤ tol`; with
//! [`NewtonStatus::ConvergedToRoundOff`] when `max |F|` is at most the round-off level
//! `4 ε max_i Σ_j |J_ij| |x_j|` of the last Jacobian (a residual below the rounding
//! error of the terms it sums cannot be told from zero; at large N this level exceeds
//! the default tol); with
//! [`NewtonStatus::LineSearchFailed`] when `α` falls below [`MIN_STEP`]; with
//! [`NewtonStatus::Stalled`] when the last 10 steps reduced `‖F‖₂` by less than half
//! in all (a line search that crawls: on the stiff dumbbell at 256 nodes every step
//! was cut to `α = 2⁻¹¹` and 100 steps took `max |F|` from 3.5e-4 to 3.1e-4, 0.3 s
//! before Ipopt solved the system in 8 iterations; no solve of the shipped and test
//! scenes took more than 8 steps to converge); with
//! [`NewtonStatus::SingularJacobian`] when the LU finds no pivot or the step is not
//! finite; with [`NewtonStatus::InvalidNumber`] when the starting residual or a
//! Jacobian cannot be evaluated or is not finite; and with [`NewtonStatus::MaximumIterationsExceeded`]. The caller decides
//! what to do on failure (the backend hands over to Ipopt).
//!
//! **Chord steps.** The last step of a converging solve rarely needs a new Jacobian: when
//! a full step (`α = 1`) reduced `‖F‖₂` by a factor `ρ ≤` [`CHORD_CONTRACTION`] and one
//! more step of that contraction would bring `max |F|` to the tolerance (or to the
//! round-off level, when that is larger), the next step solves with the factorization
//! already in hand, `J(x_old) dx = −F(x)` (a chord, or simplified Newton, step): one
//! pair of triangular solves and one residual, no Jacobian and no numeric LU. Near the
//! root it contracts at about the rate `ρ` of the step before it (Kelley, *Iterative
//! Methods for Linear and Nonlinear Equations*, §5.4), so it takes the place of the last
//! Newton step. It is accepted whole when it reaches the tolerance (or the round-off
//! level) or reduces `‖F‖₂` by [`CHORD_CONTRACTION`] (then the same test decides whether
//! the next step is again a chord step); otherwise it is discarded and a Newton step
//! with the line search is taken from the same point, as without chord steps. The chord
//! is tried only where one step is expected to finish, not to replace several quadratic
//! Newton steps by many linear ones, so a solve takes as many steps as without it (one
//! more where a first chord step lands between the tolerance and the round-off level and
//! a second one finishes, as on the chain of 32 rods at N = 512) and one factorization
//! fewer. On the chain of 16 rods at N = 1024 (n = 49 216) a numeric LU costs 10 to 15
//! times a chord step (0.15 to 0.23 s against 0.017 s); the solve goes from two
//! factorizations to one.
//! [`NewtonStats::chord_steps`] counts the accepted chord steps,
//! [`NewtonStats::chord_rejections`] the discarded ones.
//!
//! **Mixed precision.** With [`NewtonOptions::single_precision`] the Jacobian is factored
//! in single precision and each step's linear system refined in double precision
//! (`lu.rs`) until `max |J dx + F| ≤ max(10⁻⁶ · max |F|, 0.1 · max(tol, round-off
//! level))` — a step within a relative 10⁻⁶ of the Newton step, so that the iteration
//! takes the steps of double precision, and never finer than what can lower the
//! residual. Convergence is still judged on the residual in double precision, so the
//! answer is that of a double-precision solve (coordinates within 10⁻¹³ on the chain of
//! 16 rods; the multipliers, which the residual determines less well, within 2·10⁻⁷).
//! The backend asks for it where that pays (`backend::single_precision_pays`).
use std::fmt;
use std::time::{Duration, Instant};

use serde::Serialize;

use super::lu::{LuStats, SparseFactorization, SparseLu};
use super::roundoff::residual_roundoff_level;
use super::{max_abs, EvalError, IterationStat, SquareSystem};

/// Smallest step length of the line search: below it the iteration stops with
/// [`NewtonStatus::LineSearchFailed`] (15 halvings).
pub const MIN_STEP: f64 = 1.0 / 32768.0;

/// The sufficient-decrease constant of the Armijo condition.
const ARMIJO: f64 = 1e-4;

/// The contraction `‖F(x₊)‖₂ ≤ CHORD_CONTRACTION · ‖F(x)‖₂` that a full step must reach for
/// the next step to be tried as a chord step on the same factorization, and that a chord
/// step must reach to be accepted (module documentation, "Chord steps").
pub const CHORD_CONTRACTION: f64 = 0.1;

/// The relative accuracy of a step's linear system solved with a single-precision
/// factorization (`linear_target`).
const LINEAR_FORCING: f64 = 1e-6;

/// A solve stops as [`NewtonStatus::Stalled`] when its residual norm `‖F‖₂` is above
/// `STALL_FACTOR` times what it was `STALL_STEPS` steps before (module documentation).
const STALL_STEPS: usize = 10;
const STALL_FACTOR: f64 = 0.5;

/// How a Newton solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NewtonStatus {
    /// `max |F| ≤ tol`.
    Converged,
    /// `max |F|` is above `tol` but at the residual's round-off level
    /// ([`roundoff`](super::roundoff)): no step can reduce it further.
    ConvergedToRoundOff,
    /// The iteration limit was reached first.
    MaximumIterationsExceeded,
    /// The last 10 steps reduced the residual norm by less than half: the line search
    /// crawls (module documentation).
    Stalled,
    /// No step length down to [`MIN_STEP`] decreased the residual norm enough.
    LineSearchFailed,
    /// The LU found no pivot, or the step was not finite.
    SingularJacobian,
    /// A residual at the start, or a Jacobian, could not be evaluated or is not finite.
    InvalidNumber,
    /// The deadline ([`NewtonOptions::deadline`]) was reached before the next step.
    TimeLimitReached,
}

impl NewtonStatus {
    /// A stable name, e.g. `"Newton_Converged"` (written where Ipopt's status names go).
    pub fn name(&self) -> &'static str {
        match self {
            NewtonStatus::Converged => "Newton_Converged",
            NewtonStatus::ConvergedToRoundOff => "Newton_Converged_To_Round_Off",
            NewtonStatus::MaximumIterationsExceeded => "Newton_Maximum_Iterations_Exceeded",
            NewtonStatus::Stalled => "Newton_Stalled",
            NewtonStatus::LineSearchFailed => "Newton_Line_Search_Failed",
            NewtonStatus::SingularJacobian => "Newton_Singular_Jacobian",
            NewtonStatus::InvalidNumber => "Newton_Invalid_Number",
            NewtonStatus::TimeLimitReached => "Newton_Time_Limit_Reached",
        }
    }

    /// Whether the residual reached the tolerance or its round-off level.
    pub fn is_success(&self) -> bool {
        matches!(self, NewtonStatus::Converged | NewtonStatus::ConvergedToRoundOff)
    }
}

impl fmt::Display for NewtonStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            NewtonStatus::Converged => "Newton's method converged to the requested tolerance",
            NewtonStatus::ConvergedToRoundOff => {
                "Newton's method converged to the round-off level of the residual (above the requested tolerance)"
            }
            NewtonStatus::MaximumIterationsExceeded => "Newton's method: maximum number of iterations exceeded",
            NewtonStatus::Stalled => "Newton's method stalled: the residual fell by less than half in 10 steps",
            NewtonStatus::LineSearchFailed => "Newton's method: the line search found no step that decreases the residual",
            NewtonStatus::SingularJacobian => "Newton's method: the Jacobian is singular (no pivot, or a non-finite step)",
            NewtonStatus::InvalidNumber => "Newton's method: the residual at the start or a Jacobian is not finite",
            NewtonStatus::TimeLimitReached => "Newton's method: stopped at the time limit",
        })
    }
}

impl Serialize for NewtonStatus {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name())
    }
}

/// Why a [`SystemSolver`] cannot be built or used.
#[derive(Debug, thiserror::Error)]
pub enum NewtonError {
    /// The structure is not square or has an index out of range.
    #[error("invalid Jacobian structure: {0}")]
    Structure(String),
    /// The system's Jacobian structure differs from the one the solver was built for.
    #[error("the system's Jacobian structure differs from the one this solver was analysed for")]
    OtherStructure,
    /// The symbolic analysis failed (out of memory).
    #[error("symbolic LU analysis failed: {0}")]
    Analysis(String),
}

/// Options of a Newton solve.
#[derive(Debug, Clone, Copy)]
pub struct NewtonOptions {
    /// Converged when `max |F| ≤ tol`.
    pub tol: f64,
    /// Iteration limit (steps: Newton steps and chord steps).
    pub max_iter: u32,
    /// Whether a step may reuse the last factorization (a chord step) after a full step
    /// that contracted the residual by [`CHORD_CONTRACTION`] (module documentation).
    pub chord: bool,
    /// Whether the Jacobian is factored in single precision first, with the solutions
    /// refined in double precision (module documentation, "Mixed precision").
    pub single_precision: bool,
    /// When the solve must end, if ever: checked before every step (a solve that has not
    /// converged by then, or whose next step would end past it if it took as long as the
    /// last one, ends with [`NewtonStatus::TimeLimitReached`]).
    pub deadline: Option<Instant>,
}

/// Counts and wall times of a Newton solve, in seconds.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct NewtonStats {
    /// Residual evaluations (line-search trials included).
    pub residual_evaluations: usize,
    /// Jacobian evaluations (= numeric factorizations).
    pub jacobian_evaluations: usize,
    /// Accepted chord steps (steps on an earlier factorization, without a Jacobian).
    pub chord_steps: usize,
    /// Chord steps tried and rejected (each followed by a Newton step from the same point).
    pub chord_rejections: usize,
    /// The LU's factorizations and solves.
    #[serde(flatten)]
    pub lu: LuStats,
    /// Time in the residual and Jacobian evaluations.
    pub evaluation_s: f64,
}

/// The result of a Newton solve (whatever its status).
#[derive(Debug, Clone)]
pub struct NewtonSolution {
    /// How it ended.
    pub status: NewtonStatus,
    /// The last accepted point (the starting point if no step was accepted).
    pub x: Vec<f64>,
    /// `max |F(x)|` at that point.
    pub max_residual: f64,
    /// Steps taken (Newton steps and chord steps).
    pub iterations: usize,
    /// One entry per iteration, iteration 0 the start ([`IterationStat`]).
    pub history: Vec<IterationStat>,
    /// Counts and times.
    pub stats: NewtonStats,
    /// Wall time of the solve.
    pub total_s: f64,
}

/// Newton's method for the systems of one sparsity structure: the structure and its
/// sparse LU's analysis. Build it once with [`SystemSolver::new`] and call
/// [`SystemSolver::solve`] for every system of that structure.
pub struct SystemSolver {
    n: usize,
    /// The (row, column) structure this solver was built for, in the system's order.
    structure: Vec<(u32, u32)>,
    lu: SparseLu,
    /// Seconds the symbolic analysis took.
    analysis_s: f64,
}

impl SystemSolver {
    /// Analyse the `n × n` structure `structure` ((row, column) pairs, 0-based,
    /// duplicates summed): the compressed-column pattern and the symbolic LU.
    pub fn new(n: usize, structure: &[(u32, u32)]) -> Result<SystemSolver, NewtonError> {
        let start = Instant::now();
        if let Some(&(r, c)) = structure.iter().find(|&&(r, c)| r as usize >= n || c as usize >= n) {
            return Err(NewtonError::Structure(format!("entry ({r}, {c}) outside the {n} × {n} matrix")));
        }
        if structure.len() > u32::MAX as usize {
            return Err(NewtonError::Structure(format!("{} entries, more than 2³² − 1", structure.len())));
        }
        let lu = SparseLu::analyse(n, structure).map_err(NewtonError::Analysis)?;
        Ok(SystemSolver { n, structure: structure.to_vec(), lu, analysis_s: start.elapsed().as_secs_f64() })
    }

    /// A solver for the `n × n` systems of `structure` on the analysis of `factored`, a
    /// factorization of that structure's matrix: no second analysis of one structure (a
    /// reduced fit's Newton steps beside its factorizations of `∂R/∂P`). `None` when
    /// `factored` is of another structure.
    pub fn on_analysis_of(factored: &SparseFactorization, n: usize, structure: &[(u32, u32)]) -> Option<SystemSolver> {
        let lu = factored.sharing_analysis(n, structure)?;
        Some(SystemSolver { n, structure: structure.to_vec(), lu, analysis_s: 0.0 })
    }

    /// The factorization of the matrix of this solver's structure with `entries` (one
    /// per structure entry), on its analysis: what a fit factors after its start solve
    /// made the analysis. `None` when the matrix is singular or `entries` has another
    /// length.
    pub fn factorization(&self, entries: &[f64]) -> Option<SparseFactorization> {
        SparseFactorization::factor_on(self.n, self.lu.sharing(), entries)
    }

    /// The size `n` of the systems this solver handles.
    pub fn size(&self) -> usize {
        self.n
    }

    /// The (row, column) structure this solver was built for.
    pub fn structure(&self) -> &[(u32, u32)] {
        &self.structure
    }

    /// Whether this solver serves the `n × n` system with the Jacobian structure
    /// `structure`: the same size and the same (row, column) entries in the same order
    /// (the order matters: the solver maps each entry to its compressed position).
    pub fn fits(&self, n: usize, structure: &[(u32, u32)]) -> bool {
        self.n == n && self.structure == structure
    }

    /// Seconds the symbolic analysis took (once, in [`SystemSolver::new`]).
    pub fn analysis_seconds(&self) -> f64 {
        self.analysis_s
    }

    /// Nonzeros of the compressed pattern (duplicates merged).
    pub fn pattern_nonzeros(&self) -> usize {
        self.lu.pattern().nonzeros()
    }

    /// Seconds of one numeric LU factorization, in double precision, of `system`'s
    /// Jacobian at `x` on this solver's analysis: what a Newton step pays for its
    /// factorization, for comparing with another solver's. `None` when the system does
    /// not fit this solver or its Jacobian cannot be evaluated or factored.
    pub fn time_factorization<S: SquareSystem + ?Sized>(&mut self, system: &mut S, x: &[f64]) -> Option<f64> {
        if !self.fits(system.size(), system.jacobian_structure()) || x.len() != self.n {
            return None;
        }
        let mut entries = vec![0.0; self.structure.len()];
        system.jacobian_values(x, &mut entries).ok()?;
        let mut values = vec![0.0; self.lu.pattern().nonzeros()];
        self.lu.pattern().gather(&entries, &mut values);
        let start = Instant::now();
        self.lu.factor(&values, false, &mut LuStats::default()).then(|| start.elapsed().as_secs_f64())
    }

    /// Solve `system`'s `F(x) = 0` from `x0` by Newton's method with the line search and
    /// the chord steps of the module documentation. Errors only when the system does not
    /// fit this solver (size, structure); a failed iteration is a [`NewtonSolution`]
    /// whose status says why.
    pub fn solve<S: SquareSystem + ?Sized>(
        &mut self,
        system: &mut S,
        x0: &[f64],
        options: &NewtonOptions,
    ) -> Result<NewtonSolution, NewtonError> {
        let n = self.n;
        if system.size() != n || x0.len() != n {
            return Err(NewtonError::Structure(format!(
                "a system of {} unknowns and a start of {} entries for a solver of size {n}",
                system.size(),
                x0.len()
            )));
        }
        if !self.fits(n, system.jacobian_structure()) {
            return Err(NewtonError::OtherStructure);
        }
        let mut it = Iteration::start(system, x0, self.structure.len(), self.lu.pattern().nonzeros());
        let status = loop {
            if let Some(status) = it.stop(options) {
                break status;
            }
            let step_start = Instant::now();
            // Residual evaluations from this point (a rejected chord trial, line-search trials).
            let mut trials = 0;
            if it.chord_next {
                if self.chord_step(&mut it, options, &mut trials) {
                    it.last_step_s = step_start.elapsed().as_secs_f64();
                    continue;
                }
                if it.residual() <= it.floor {
                    break NewtonStatus::ConvergedToRoundOff;
                }
            }
            if let Err(status) = self.newton_step(&mut it, options, &mut trials) {
                break status;
            }
            it.last_step_s = step_start.elapsed().as_secs_f64();
        };
        Ok(it.finish(status))
    }

    /// The chord step `J(x_old) dx = −F(x)` on the factorization in hand, taken whole if
    /// it reaches the tolerance (or the round-off level) or contracts `‖F‖₂` by
    /// [`CHORD_CONTRACTION`]; `false` when it is rejected (counted; the iterate stays).
    fn chord_step<S: SquareSystem + ?Sized>(&mut self, it: &mut Iteration<'_, S>, options: &NewtonOptions, trials: &mut i32) -> bool {
        let residual = it.residual();
        it.step.iter_mut().zip(&it.f).for_each(|(s, fi)| *s = -fi);
        if self.lu.solve(&it.values, &mut it.step, linear_target(residual, options.tol, it.floor), &mut it.stats.lu) {
            let trial_norm = it.try_step(1.0, trials);
            let target = options.tol.max(it.floor);
            let contraction = trial_norm / it.norm;
            if trial_norm.is_finite() && (contraction <= CHORD_CONTRACTION || max_abs(&it.f_trial) <= target) {
                it.accept(trial_norm, 1.0, *trials);
                it.stats.chord_steps += 1;
                it.chord_next = chord_may_finish(contraction, max_abs(&it.f), target);
                return true;
            }
        }
        it.stats.chord_rejections += 1;
        false
    }

    /// The Newton step `J dx = −F` with a new Jacobian and factorization, damped by the
    /// backtracking line search on `‖F‖₂`; the status that ends the solve when there is
    /// no step.
    fn newton_step<S: SquareSystem + ?Sized>(
        &mut self,
        it: &mut Iteration<'_, S>,
        options: &NewtonOptions,
        trials: &mut i32,
    ) -> Result<(), NewtonStatus> {
        let residual = it.residual();
        if !it.evaluate_jacobian(self.lu.pattern()) {
            return Err(NewtonStatus::InvalidNumber);
        }
        it.floor = residual_roundoff_level(self.lu.pattern().entries(&it.values), &it.x, self.n);
        it.step.iter_mut().zip(&it.f).for_each(|(s, fi)| *s = -fi);
        let target = linear_target(residual, options.tol, it.floor);
        if !self.lu.factor(&it.values, options.single_precision, &mut it.stats.lu)
            || !self.lu.solve(&it.values, &mut it.step, target, &mut it.stats.lu)
        {
            return Err(NewtonStatus::SingularJacobian);
        }
        // No step decreases a residual already at the round-off level of this Jacobian:
        // that is convergence (`stop` says so from the second step on, once the level is
        // known; a start at that level learns it here).
        let failed = if residual <= it.floor { NewtonStatus::ConvergedToRoundOff } else { NewtonStatus::LineSearchFailed };
        let (alpha, trial_norm) = line_search(it, trials).ok_or(failed)?;
        let last_norm = it.norm;
        it.accept(trial_norm, alpha, *trials);
        // A full step that contracted well: the Jacobian changed little along it, so
        // the next step may reuse this factorization if one more such step converges.
        it.chord_next = options.chord && alpha == 1.0 && chord_may_finish(it.norm / last_norm, max_abs(&it.f), options.tol.max(it.floor));
        Ok(())
    }
}

/// The state of one Newton solve: the iterate and its residual, the last Jacobian's
/// values and round-off level, the work vectors, the counts and the iteration table.
struct Iteration<'s, S: SquareSystem + ?Sized> {
    system: &'s mut S,
    start: Instant,
    x: Vec<f64>,
    f: Vec<f64>,
    /// `‖F(x)‖₂`, NaN when the start could not be evaluated.
    norm: f64,
    /// The Jacobian's entries in the system's order, and compressed.
    jacobian: Vec<f64>,
    values: Vec<f64>,
    step: Vec<f64>,
    trial: Vec<f64>,
    f_trial: Vec<f64>,
    iterations: usize,
    /// The residual's round-off level, from the last Jacobian (none before the first).
    floor: f64,
    /// Whether the next step is tried as a chord step on the stored factorization.
    chord_next: bool,
    /// Seconds the last step took (0 before the first).
    last_step_s: f64,
    /// `‖F‖₂` at the start and after each step.
    norms: Vec<f64>,
    stats: NewtonStats,
    history: Vec<IterationStat>,
}

impl<'s, S: SquareSystem + ?Sized> Iteration<'s, S> {
    /// The start at `x0`, with room for a Jacobian of `entries` entries and `nonzeros`
    /// compressed values.
    fn start(system: &'s mut S, x0: &[f64], entries: usize, nonzeros: usize) -> Self {
        let n = x0.len();
        let mut it = Iteration {
            system,
            start: Instant::now(),
            x: x0.to_vec(),
            f: vec![0.0; n],
            norm: f64::NAN,
            jacobian: vec![0.0; entries],
            values: vec![0.0; nonzeros],
            step: vec![0.0; n],
            trial: vec![0.0; n],
            f_trial: vec![0.0; n],
            iterations: 0,
            floor: 0.0,
            chord_next: false,
            last_step_s: 0.0,
            norms: Vec::new(),
            stats: NewtonStats::default(),
            history: Vec::new(),
        };
        if evaluate_residual(it.system, &it.x, &mut it.f, &mut it.stats).is_ok() {
            it.norm = norm2(&it.f);
        }
        it.norms.push(it.norm);
        it.history.push(iteration_stat(0, max_abs(&it.f), 0.0, 0.0, 0));
        it
    }

    /// `max |F(x)|`.
    fn residual(&self) -> f64 {
        max_abs(&self.f)
    }

    /// Whether the last [`STALL_STEPS`] steps reduced `‖F‖₂` by less than
    /// [`STALL_FACTOR`].
    fn stalled(&self) -> bool {
        self.norms.len() > STALL_STEPS && self.norm > STALL_FACTOR * self.norms[self.norms.len() - 1 - STALL_STEPS]
    }

    /// The status that ends the solve before the next step, if any: a residual that is
    /// not finite, at the tolerance, at the round-off level (unless a chord step may
    /// still contract it: cheap enough to be tried first), the iteration limit, or the deadline
    /// (reached, or to be passed by a step as long as the last one).
    fn stop(&self, options: &NewtonOptions) -> Option<NewtonStatus> {
        if !self.norm.is_finite() {
            return Some(NewtonStatus::InvalidNumber);
        }
        let residual = self.residual();
        if residual <= options.tol {
            Some(NewtonStatus::Converged)
        } else if residual <= self.floor && !self.chord_next {
            Some(NewtonStatus::ConvergedToRoundOff)
        } else if self.iterations >= options.max_iter as usize {
            Some(NewtonStatus::MaximumIterationsExceeded)
        } else if self.stalled() {
            Some(NewtonStatus::Stalled)
        } else if options.deadline.is_some_and(|d| Instant::now() + Duration::from_secs_f64(self.last_step_s) >= d) {
            Some(NewtonStatus::TimeLimitReached)
        } else {
            None
        }
    }

    /// The Jacobian at `x`, compressed into `values`; `false` when it cannot be
    /// evaluated or is not finite.
    fn evaluate_jacobian(&mut self, pattern: &super::pattern::CompressedPattern) -> bool {
        let t = Instant::now();
        let evaluated = self.system.jacobian_values(&self.x, &mut self.jacobian);
        self.stats.evaluation_s += t.elapsed().as_secs_f64();
        self.stats.jacobian_evaluations += 1;
        if evaluated.is_err() || self.jacobian.iter().any(|v| !v.is_finite()) {
            return false;
        }
        pattern.gather(&self.jacobian, &mut self.values);
        true
    }

    /// The residual at `x + alpha · step` into `trial`, `f_trial`; its norm, or NaN when
    /// it cannot be evaluated. Counts one trial.
    fn try_step(&mut self, alpha: f64, trials: &mut i32) -> f64 {
        for ((xt, xi), si) in self.trial.iter_mut().zip(&self.x).zip(&self.step) {
            *xt = xi + alpha * si;
        }
        *trials += 1;
        match evaluate_residual(self.system, &self.trial, &mut self.f_trial, &mut self.stats) {
            Ok(()) => norm2(&self.f_trial),
            Err(_) => f64::NAN,
        }
    }

    /// Take the trial point as the next iterate (a step of length `alpha`, whose residual
    /// norm is `norm`, after `trials` residual evaluations), and record it.
    fn accept(&mut self, norm: f64, alpha: f64, trials: i32) {
        std::mem::swap(&mut self.x, &mut self.trial);
        std::mem::swap(&mut self.f, &mut self.f_trial);
        self.norm = norm;
        self.norms.push(norm);
        self.iterations += 1;
        self.history.push(iteration_stat(self.iterations as i32, max_abs(&self.f), max_abs(&self.step), alpha, trials));
    }

    fn finish(self, status: NewtonStatus) -> NewtonSolution {
        NewtonSolution {
            status,
            max_residual: max_abs(&self.f),
            x: self.x,
            iterations: self.iterations,
            history: self.history,
            stats: self.stats,
            total_s: self.start.elapsed().as_secs_f64(),
        }
    }
}

/// Backtracking on `‖F‖₂` along the step in hand: `α = 1, ½, ¼, …` until the Armijo
/// condition holds; the step length and the trial's residual norm, or `None` below
/// [`MIN_STEP`].
fn line_search<S: SquareSystem + ?Sized>(it: &mut Iteration<'_, S>, trials: &mut i32) -> Option<(f64, f64)> {
    let mut alpha = 1.0;
    loop {
        let trial_norm = it.try_step(alpha, trials);
        if trial_norm.is_finite() && trial_norm <= (1.0 - ARMIJO * alpha) * it.norm {
            return Some((alpha, trial_norm));
        }
        alpha *= 0.5;
        if alpha < MIN_STEP {
            return None;
        }
    }
}

/// The accuracy to which a step's linear system `J dx = −F` is solved with a
/// single-precision factorization: `max |J dx + F| ≤ max(LINEAR_FORCING · max |F|,
/// 0.1 · max(tol, floor))` (`floor` the residual's round-off level). The first term
/// keeps the step a Newton step to within a relative 10⁻⁶, far below what a step from
/// a usable initial guess contracts by, so the iteration counts are those of double
/// precision; the second stops refining where the step cannot bring the residual lower.
fn linear_target(residual: f64, tol: f64, floor: f64) -> f64 {
    (LINEAR_FORCING * residual).max(0.1 * tol.max(floor))
}

/// Whether the next step is tried as a chord step, after a full step (Newton or chord)
/// that reduced `‖F‖₂` by the factor `contraction` to a point with `max |F| = residual`:
/// when the step contracted by [`CHORD_CONTRACTION`] or more and one more step of the
/// same contraction would bring the residual to `target` (the tolerance, or the round-off
/// level when that is larger). A chord step contracts at about the rate of the step
/// before it, so it then replaces the last Newton step of the solve, without the last
/// factorization; it is not used to replace several Newton steps by many linearly
/// converging ones (module documentation, "Chord steps").
fn chord_may_finish(contraction: f64, residual: f64, target: f64) -> bool {
    contraction <= CHORD_CONTRACTION && contraction * residual <= target
}

/// `F(x)` into `f`, counting and timing the call; non-finite values are an error.
fn evaluate_residual<S: SquareSystem + ?Sized>(system: &mut S, x: &[f64], f: &mut [f64], stats: &mut NewtonStats) -> Result<(), EvalError> {
    let t = Instant::now();
    let result = system.residual(x, f);
    stats.evaluation_s += t.elapsed().as_secs_f64();
    stats.residual_evaluations += 1;
    result?;
    if f.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(EvalError("non-finite residual".into()))
    }
}

fn norm2(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn iteration_stat(iter: i32, inf_pr: f64, d_norm: f64, alpha: f64, ls_trials: i32) -> IterationStat {
    IterationStat {
        iter,
        objective: 0.0,
        inf_pr,
        inf_du: 0.0,
        mu: 0.0,
        d_norm,
        regularization: 0.0,
        alpha_pr: alpha,
        alpha_du: 0.0,
        ls_trials,
        restoration: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::linalg::IterationStat;

    /// `F(x) = (x0² + x1² − 4, x0 − x1)`: root (√2, √2); from (1, 0.5).
    struct Circle {
        jac: Vec<(u32, u32)>,
    }

    impl SquareSystem for Circle {
        fn size(&self) -> usize {
            2
        }
        fn residual(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
            c[0] = x[0] * x[0] + x[1] * x[1] - 4.0;
            c[1] = x[0] - x[1];
            Ok(())
        }
        fn jacobian_structure(&self) -> &[(u32, u32)] {
            &self.jac
        }
        fn jacobian_values(&mut self, x: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
            // The (0, 0) entry is split into two duplicates to check that they are summed.
            v.copy_from_slice(&[x[0], 2.0 * x[1], 1.0, -1.0, x[0]]);
            Ok(())
        }
    }

    /// `F(x) = A x − b` with the constant `A` given by its entries (`structure`, `values`).
    struct Linear {
        structure: Vec<(u32, u32)>,
        values: Vec<f64>,
        b: Vec<f64>,
    }
    impl SquareSystem for Linear {
        fn size(&self) -> usize {
            self.b.len()
        }
        fn residual(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
            c.iter_mut().zip(&self.b).for_each(|(ci, bi)| *ci = -bi);
            for (&(i, j), a) in self.structure.iter().zip(&self.values) {
                c[i as usize] += a * x[j as usize];
            }
            Ok(())
        }
        fn jacobian_structure(&self) -> &[(u32, u32)] {
            &self.structure
        }
        fn jacobian_values(&mut self, _x: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
            v.copy_from_slice(&self.values);
            Ok(())
        }
    }

    /// One equation in one unknown, `F(x) = f(x)` with its derivative `df`, each
    /// residual taking `delay`.
    struct Scalar {
        f: fn(f64) -> f64,
        df: fn(f64) -> f64,
        delay: Duration,
        structure: [(u32, u32); 1],
    }

    impl Scalar {
        fn new(f: fn(f64) -> f64, df: fn(f64) -> f64) -> Scalar {
            Scalar { f, df, delay: Duration::ZERO, structure: [(0, 0)] }
        }
    }

    impl SquareSystem for Scalar {
        fn size(&self) -> usize {
            1
        }
        fn residual(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
            if !self.delay.is_zero() {
                std::thread::sleep(self.delay);
            }
            c[0] = (self.f)(x[0]);
            Ok(())
        }
        fn jacobian_structure(&self) -> &[(u32, u32)] {
            &self.structure
        }
        fn jacobian_values(&mut self, x: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
            v[0] = (self.df)(x[0]);
            Ok(())
        }
    }

    /// `F(x) = x² − 2`: one unknown, root √2.
    fn sqrt2() -> Scalar {
        Scalar::new(|x| x * x - 2.0, |x| 2.0 * x)
    }

    /// A start whose residual is at its round-off level (the double nearest √2: `x² − 2`
    /// is 2.7e-16, below `4 ε |2x| |x|` = 3.6e-15, and no double decreases it) has
    /// converged, although no step passes the line search and the tolerance is below
    /// any residual: the fit's solve of its fitted motion starts there.
    #[test]
    fn a_start_at_the_round_off_level_is_converged() {
        let mut p = sqrt2();
        let mut solver = SystemSolver::new(1, &[(0, 0)]).unwrap();
        let x0 = 2f64.sqrt();
        assert!((x0 * x0 - 2.0).abs() > 0.0);
        let sol = solver
            .solve(&mut p, &[x0], &NewtonOptions { tol: 1e-30, max_iter: 20, chord: true, single_precision: false, deadline: None })
            .unwrap();
        assert_eq!(sol.status, NewtonStatus::ConvergedToRoundOff);
        assert_eq!(sol.x[0], x0);
    }

    /// `F(x) = atan(x)`: one unknown, root 0; Newton's full step overshoots from |x| ≳ 1.39.
    fn atan() -> Scalar {
        Scalar::new(f64::atan, |x| 1.0 / (1.0 + x * x))
    }

    /// `F(x) = x⁹`, whose every residual takes 0.3 s: Newton's steps contract it by
    /// (8/9)⁹ ≈ 0.35 (no chord steps), so it needs dozens.
    fn slow_power() -> Scalar {
        Scalar { delay: Duration::from_millis(300), ..Scalar::new(|x| x.powi(9), |x| 9.0 * x.powi(8)) }
    }

    /// Steps of at least 0.3 s against a deadline 1.05 s away: Newton stops before the
    /// step that would end past it (after 2 steps at the latest, at 0.9 s; a loaded
    /// machine, whose steps take longer, stops earlier), not at the first check past it
    /// (3 steps, 1.2 s).
    #[test]
    fn newton_stops_before_a_step_that_would_pass_the_deadline() {
        let mut p = slow_power();
        let mut solver = SystemSolver::new(1, &[(0, 0)]).unwrap();
        let deadline = Some(Instant::now() + Duration::from_millis(1050));
        let opts = NewtonOptions { tol: 1e-300, max_iter: 100, chord: true, single_precision: false, deadline };
        let sol = solver.solve(&mut p, &[1.0], &opts).unwrap();
        assert_eq!(sol.status, NewtonStatus::TimeLimitReached);
        assert!((1..=2).contains(&sol.iterations), "{} steps", sol.iterations);
    }

    fn circle() -> Circle {
        Circle { jac: vec![(0, 0), (0, 1), (1, 0), (1, 1), (0, 0)] }
    }

    #[test]
    fn converges_quadratically_on_a_small_system_and_is_reusable() {
        let mut p = circle();
        let mut solver = SystemSolver::new(2, &p.jac.clone()).unwrap();
        assert_eq!(solver.pattern_nonzeros(), 4);
        // At this tolerance no step is expected to finish at the rate of the one before
        // it, so every step is a Newton step even with chord steps allowed.
        let opts = NewtonOptions { tol: 1e-14, max_iter: 20, chord: true, single_precision: false, deadline: None };
        for x0 in [[1.0, 0.5], [3.0, 2.0]] {
            let sol = solver.solve(&mut p, &x0, &opts).unwrap();
            assert_eq!(sol.status, NewtonStatus::Converged);
            let r = 2f64.sqrt();
            assert!((sol.x[0] - r).abs() < 1e-14 && (sol.x[1] - r).abs() < 1e-14, "{:?}", sol.x);
            // Quadratic convergence: each residual at most a constant times the square of the last.
            let res: Vec<f64> = sol.history.iter().map(|h| h.inf_pr).collect();
            for w in res.windows(2).filter(|w| w[0] < 0.1 && w[1] > 1e-15) {
                assert!(w[1] <= 2.0 * w[0] * w[0], "not quadratic: {res:?}");
            }
            assert_eq!(sol.stats.jacobian_evaluations, sol.iterations);
            assert!(sol.history.iter().skip(1).all(|h| h.alpha_pr == 1.0), "{:?}", sol.history);
        }
    }

    /// With the tolerance 1e-10 the fourth step (max |F| ≈ 2.6e-7 after a contraction of
    /// ‖F‖₂ by ≈ 1e-4) leaves a residual that one more step of that contraction brings
    /// below the tolerance: the fifth step is a chord step on the fourth step's
    /// factorization. It reaches the tolerance in as many steps as Newton alone, with one
    /// factorization fewer, at the same root.
    #[test]
    fn a_chord_step_replaces_the_last_newton_step() {
        let mut p = circle();
        let mut solver = SystemSolver::new(2, &p.jac.clone()).unwrap();
        let r = 2f64.sqrt();
        for x0 in [[1.0, 0.5], [3.0, 2.0]] {
            let full = solver
                .solve(&mut p, &x0, &NewtonOptions { tol: 1e-10, max_iter: 20, chord: false, single_precision: false, deadline: None })
                .unwrap();
            let chord = solver
                .solve(&mut p, &x0, &NewtonOptions { tol: 1e-10, max_iter: 20, chord: true, single_precision: false, deadline: None })
                .unwrap();
            for sol in [&full, &chord] {
                assert_eq!(sol.status, NewtonStatus::Converged);
                assert!(sol.max_residual <= 1e-10);
                // The root itself, not only a small residual: |F| ≤ 1e-10 with |J⁻¹| ≈ 1.
                assert!((sol.x[0] - r).abs() < 1e-10 && (sol.x[1] - r).abs() < 1e-10, "{:?}", sol.x);
                let trials: i32 = sol.history.iter().map(|h| h.ls_trials).sum();
                assert_eq!(sol.stats.residual_evaluations, 1 + trials as usize, "{:?}", sol.history);
            }
            assert_eq!((full.stats.chord_steps, full.stats.jacobian_evaluations), (0, full.iterations));
            assert_eq!(chord.iterations, full.iterations, "{:?}", chord.history);
            assert_eq!((chord.stats.chord_steps, chord.stats.chord_rejections), (1, 0));
            assert_eq!(chord.stats.jacobian_evaluations, full.stats.jacobian_evaluations - 1);
            // The steps before the chord step are the same Newton steps.
            assert_eq!(chord.history[..full.iterations], full.history[..full.iterations]);
            let last = chord.history.last().unwrap();
            assert_eq!((last.alpha_pr, last.ls_trials), (1.0, 1));
            // A chord step contracts linearly, at about the rate of the step before it:
            // less than a Newton step, more than the 10× it must reach.
            let n = chord.iterations;
            let rate = |h: &[IterationStat], k: usize| h[k].inf_pr / h[k - 1].inf_pr;
            assert!(rate(&chord.history, n) <= 0.1 && rate(&chord.history, n) > rate(&full.history, n), "{:?}", chord.history);
        }
    }

    /// A chord step that neither reaches the tolerance nor contracts by 10× is discarded:
    /// `F(x) = atan(x)` from 0.35 with the tolerance 3e-3. The first Newton step contracts
    /// by 0.083 to max |F| = 0.028, so a chord step is tried (0.083 · 0.028 ≤ 3e-3); it
    /// contracts only by 0.12 (to 3.4e-3: the chord's rate is about `x0² − x1²` here, the
    /// Newton step's about `(2/3) x0²`) and is replaced by a Newton step from the same
    /// point: the same iterate as without chord steps, its trial counted in that step's
    /// `ls_trials`.
    #[test]
    fn a_chord_step_that_does_not_contract_is_replaced_by_a_newton_step() {
        let mut p = atan();
        let mut solver = SystemSolver::new(1, &[(0, 0)]).unwrap();
        let full = solver
            .solve(&mut p, &[0.35], &NewtonOptions { tol: 3e-3, max_iter: 10, chord: false, single_precision: false, deadline: None })
            .unwrap();
        let chord = solver
            .solve(&mut p, &[0.35], &NewtonOptions { tol: 3e-3, max_iter: 10, chord: true, single_precision: false, deadline: None })
            .unwrap();
        assert_eq!((full.status, chord.status), (NewtonStatus::Converged, NewtonStatus::Converged));
        assert_eq!((chord.stats.chord_steps, chord.stats.chord_rejections), (0, 1));
        assert_eq!(chord.iterations, 2);
        assert_eq!(chord.stats.jacobian_evaluations, 2);
        assert_eq!(chord.x, full.x, "the rejected trial must leave the iterate alone");
        assert_eq!(chord.history[1], full.history[1]);
        assert_eq!((chord.history[2].alpha_pr, chord.history[2].ls_trials), (1.0, 2));
        assert_eq!(chord.stats.residual_evaluations, full.stats.residual_evaluations + 1);
        // Atan's root is 0: Newton's second step lands at about (2/3)·0.028³.
        assert!(chord.x[0].abs() < 2e-5, "{:?}", chord.x);
    }

    /// `F(x) = atan(x)` from x0 = 3: the full Newton step overshoots to −9.5 and
    /// diverges; the line search must damp it and converge to 0.
    #[test]
    fn line_search_rescues_a_diverging_newton_iteration() {
        let mut p = atan();
        let mut solver = SystemSolver::new(1, &[(0, 0)]).unwrap();
        let sol = solver
            .solve(&mut p, &[3.0], &NewtonOptions { tol: 1e-12, max_iter: 50, chord: true, single_precision: false, deadline: None })
            .unwrap();
        assert_eq!(sol.status, NewtonStatus::Converged);
        assert!(sol.x[0].abs() < 1e-12);
        assert!(sol.history[1].alpha_pr < 1.0, "the first step must be damped: {:?}", sol.history[1]);
        // Without damping the first step lands at 3 − (1 + 9)·atan(3) ≈ −9.49.
        assert!(sol.history[1].ls_trials > 1);
    }

    /// `F(x) = (x0, K (x1 − sin x0))` with `K = 10⁴`, from (10, sin 10): a narrow curved
    /// valley. The Newton step follows the valley's tangent; along it the second equation
    /// grows as `K α² x0² sin x0 / 2`, so the line search cuts every step to about
    /// `α ≈ √(2/K)/|x0|` (5e-4 to 1e-3 here), and each step reduces `‖F‖₂` by about that
    /// fraction: thousands of steps to the root.
    struct Valley(Vec<(u32, u32)>);
    const VALLEY_K: f64 = 1e4;
    impl SquareSystem for Valley {
        fn size(&self) -> usize {
            2
        }
        fn residual(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
            c[0] = x[0];
            c[1] = VALLEY_K * (x[1] - x[0].sin());
            Ok(())
        }
        fn jacobian_structure(&self) -> &[(u32, u32)] {
            &self.0
        }
        fn jacobian_values(&mut self, x: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
            v.copy_from_slice(&[1.0, -VALLEY_K * x[0].cos(), VALLEY_K]);
            Ok(())
        }
    }

    /// `F(x) = ∛x`: the Newton step `−3x` overshoots, the line search halves it, and
    /// every step reduces `|F|` by `2^(−1/3)`: slow, linear, but steady.
    fn cube_root() -> Scalar {
        Scalar::new(f64::cbrt, |x| 1.0 / (3.0 * x.cbrt().powi(2)))
    }

    /// A line search that crawls stops after 10 steps as stalled (the backend then hands
    /// the system to Ipopt), where it used to run to the iteration limit; a slow but
    /// steady one (a factor 2^(−1/3) per step, 0.1 per 10) runs on and converges.
    #[test]
    fn a_crawling_line_search_stops_as_stalled_and_a_slow_one_does_not() {
        let structure = vec![(0, 0), (1, 0), (1, 1)];
        let mut valley = Valley(structure.clone());
        let mut solver = SystemSolver::new(2, &structure).unwrap();
        let opts = NewtonOptions { tol: 1e-10, max_iter: 100, chord: true, single_precision: false, deadline: None };
        let sol = solver.solve(&mut valley, &[10.0, 10.0_f64.sin()], &opts).unwrap();
        assert_eq!(sol.status, NewtonStatus::Stalled, "{:?}", sol.history.last());
        assert_eq!(sol.iterations, 10);
        assert!(!sol.status.is_success());
        assert_eq!(sol.status.name(), "Newton_Stalled");
        // Every step was cut by the line search, and together they moved x0 by little.
        assert!(sol.history[1..].iter().all(|h| h.alpha_pr < 1e-2), "{:?}", sol.history);
        assert!(sol.x[0] > 9.0, "{:?}", sol.x);

        let mut cube = cube_root();
        let mut solver = SystemSolver::new(1, &[(0, 0)]).unwrap();
        let opts = NewtonOptions { tol: 1e-10, max_iter: 200, chord: true, single_precision: false, deadline: None };
        let sol = solver.solve(&mut cube, &[1.0], &opts).unwrap();
        assert_eq!(sol.status, NewtonStatus::Converged, "{:?}", sol.history.last());
        // 2^(−k/3) ≤ 1e-10: k ≥ 100.
        assert!((95..=110).contains(&sol.iterations), "{} steps", sol.iterations);
    }

    #[test]
    fn failures_are_statuses_and_misuse_is_an_error() {
        // A structurally singular Jacobian (column 1 empty): x0 − 1 = 0, x0 + 1 = 0.
        let mut p = Linear { structure: vec![(0, 0), (1, 0)], values: vec![1.0, 1.0], b: vec![1.0, -1.0] };
        let mut solver = SystemSolver::new(2, &p.structure.clone()).unwrap();
        let sol = solver
            .solve(&mut p, &[0.0, 0.0], &NewtonOptions { tol: 1e-12, max_iter: 10, chord: true, single_precision: false, deadline: None })
            .unwrap();
        assert_eq!(sol.status, NewtonStatus::SingularJacobian);
        assert!(!sol.status.is_success());
        assert_eq!(sol.status.name(), "Newton_Singular_Jacobian");

        let mut c = circle();
        let opts = NewtonOptions { tol: 1e-14, max_iter: 1, chord: true, single_precision: false, deadline: None };
        let mut solver = SystemSolver::new(2, &c.jac.clone()).unwrap();
        assert_eq!(solver.solve(&mut c, &[1.0, 0.5], &opts).unwrap().status, NewtonStatus::MaximumIterationsExceeded);
        assert_eq!(solver.solve(&mut c, &[f64::NAN, 0.5], &opts).unwrap().status, NewtonStatus::InvalidNumber);
        let mut other = SystemSolver::new(2, &[(0, 0), (1, 1)]).unwrap();
        assert!(matches!(other.solve(&mut c, &[1.0, 0.5], &opts), Err(NewtonError::OtherStructure)));
        assert!(matches!(SystemSolver::new(2, &[(0, 2)]), Err(NewtonError::Structure(_))));
    }

    /// A solver on a factorization's analysis (the reduced fit's Newton steps) solves as
    /// one with an analysis of its own, and is refused for another structure: the same
    /// entries in another order, or another size.
    #[test]
    fn a_solver_on_a_factorizations_analysis_needs_its_structure() {
        let n = 5;
        let mut structure = Vec::new();
        let mut values = Vec::new();
        for i in 0..n as u32 {
            structure.push((i, i));
            values.push(4.0 + f64::from(i));
            if i + 1 < n as u32 {
                structure.extend([(i, i + 1), (i + 1, i)]);
                values.extend([1.0, -2.0]);
            }
        }
        let exact: Vec<f64> = (0..n).map(|i| (i as f64).cos()).collect();
        let mut b = vec![0.0; n];
        for (&(r, c), v) in structure.iter().zip(&values) {
            b[r as usize] += v * exact[c as usize];
        }
        let factored = SparseFactorization::new(n, &structure, &values).unwrap();
        let mut shared = SystemSolver::on_analysis_of(&factored, n, &structure).expect("its own structure");
        assert_eq!(shared.analysis_seconds(), 0.0);
        let mut p = Linear { structure: structure.clone(), values: values.clone(), b: b.clone() };
        let opts = NewtonOptions { tol: 1e-13, max_iter: 5, chord: true, single_precision: false, deadline: None };
        let sol = shared.solve(&mut p, &[0.0; 5], &opts).unwrap();
        let own = SystemSolver::new(n, &structure).unwrap().solve(&mut p, &[0.0; 5], &opts).unwrap();
        assert!(sol.status.is_success(), "{:?}", sol.status);
        assert_eq!(sol.x, own.x, "the same analysis as its own");
        assert!(sol.x.iter().zip(&exact).all(|(x, e)| (x - e).abs() < 1e-13), "{:?}", sol.x);
        let mut swapped = structure.clone();
        swapped.swap(0, 1);
        assert!(SystemSolver::on_analysis_of(&factored, n, &swapped).is_none(), "another order");
        assert!(SystemSolver::on_analysis_of(&factored, n + 1, &structure).is_none(), "another size");
    }

    /// An analysis is shared only by systems of the same pattern: equal sizes and equal
    /// nonzero counts are not enough.
    #[test]
    fn an_analysis_fits_only_the_same_pattern() {
        let lower = [(0, 0), (1, 0), (1, 1), (2, 1), (2, 2)];
        let upper = [(0, 0), (0, 1), (1, 1), (1, 2), (2, 2)];
        let solver = SystemSolver::new(3, &lower).unwrap();
        assert!(solver.fits(3, &lower));
        assert!(!solver.fits(3, &upper), "same size and nonzero count, other pattern");
        assert!(!solver.fits(4, &lower), "same entries, other size");
        let mut reordered = lower;
        reordered.swap(0, 4);
        assert!(!solver.fits(3, &reordered), "the entries' order maps them to their slots");
        assert!(!solver.fits(3, &lower[..4]));
    }

    /// `F(x) = s · (A x + x³/10 − b)` with a sparse, nonsymmetric, diagonally dominant `A`
    /// (4 on the diagonal, −1 and −1.5 beside it, 0.3 seven columns to the right) and
    /// `b` made from the root `x*_i = sin i`: a well-conditioned system of `n` unknowns
    /// whose root is known; `s` scales residual and Jacobian.
    struct Cubic {
        n: usize,
        scale: f64,
        diagonal: f64,
        b: Vec<f64>,
        jac: Vec<(u32, u32)>,
    }

    impl Cubic {
        fn new(n: usize, scale: f64, diagonal: f64) -> Cubic {
            let mut jac = Vec::new();
            for i in 0..n as u32 {
                jac.push((i, i));
                if i > 0 {
                    jac.push((i, i - 1));
                }
                if i + 1 < n as u32 {
                    jac.push((i, i + 1));
                }
                if i + 7 < n as u32 {
                    jac.push((i, i + 7));
                }
            }
            let mut p = Cubic { n, scale: 1.0, diagonal, b: vec![0.0; n], jac };
            let root = Cubic::root(n);
            let mut b = vec![0.0; n];
            p.residual(&root, &mut b).unwrap();
            p.b = b;
            p.scale = scale;
            p
        }
        fn root(n: usize) -> Vec<f64> {
            (0..n).map(|i| (i as f64).sin()).collect()
        }
        fn coefficient(&self, i: usize, j: usize) -> f64 {
            match j as isize - i as isize {
                0 => self.diagonal,
                -1 => -1.5,
                1 => -1.0,
                _ => 0.3,
            }
        }
    }

    impl SquareSystem for Cubic {
        fn size(&self) -> usize {
            self.n
        }
        fn residual(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
            c.iter_mut().zip(x).zip(&self.b).for_each(|((ci, xi), bi)| *ci = xi * xi * xi / 10.0 - bi);
            for &(i, j) in &self.jac {
                c[i as usize] += self.coefficient(i as usize, j as usize) * x[j as usize];
            }
            c.iter_mut().for_each(|ci| *ci *= self.scale);
            Ok(())
        }
        fn jacobian_structure(&self) -> &[(u32, u32)] {
            &self.jac
        }
        fn jacobian_values(&mut self, x: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
            for (vk, &(i, j)) in v.iter_mut().zip(&self.jac) {
                let (i, j) = (i as usize, j as usize);
                let cubic = if i == j { 0.3 * x[i] * x[i] } else { 0.0 };
                *vk = self.scale * (self.coefficient(i, j) + cubic);
            }
            Ok(())
        }
    }

    fn max_error(x: &[f64], root: &[f64]) -> f64 {
        x.iter().zip(root).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
    }

    /// Factored in single precision and refined in double, the solve reaches the same
    /// root in the same steps as in double precision, with every factorization in single
    /// precision. The diagonal 2 (rows not diagonally dominant) makes single precision
    /// too coarse for one solve per step: the refinement takes more solves than there are
    /// steps (9 for 6 measured).
    #[test]
    fn single_precision_factorizations_reach_the_root_in_the_same_steps() {
        let n = 3000;
        let mut p = Cubic::new(n, 1.0, 2.0);
        let root = Cubic::root(n);
        let mut solver = SystemSolver::new(n, &p.jac.clone()).unwrap();
        let x0: Vec<f64> = root.iter().enumerate().map(|(i, r)| r + 0.01 * (i as f64).cos()).collect();
        let options = |single_precision| NewtonOptions { tol: 1e-12, max_iter: 20, chord: true, single_precision, deadline: None };
        let double = solver.solve(&mut p, &x0, &options(false)).unwrap();
        let mixed = solver.solve(&mut p, &x0, &options(true)).unwrap();
        for sol in [&double, &mixed] {
            assert_eq!(sol.status, NewtonStatus::Converged);
            // Measured: 1.0e-12 (double) and 5.2e-12 (single precision refined).
            assert!(max_error(&sol.x, &root) < 1e-10, "{}", max_error(&sol.x, &root));
        }
        assert_eq!(mixed.iterations, double.iterations);
        assert_eq!(mixed.stats.jacobian_evaluations, double.stats.jacobian_evaluations);
        assert_eq!(mixed.stats.lu.single_precision_factorizations, mixed.stats.jacobian_evaluations);
        assert_eq!(mixed.stats.lu.single_precision_fallbacks, 0);
        let linear_solves = mixed.stats.jacobian_evaluations + mixed.stats.chord_steps + mixed.stats.chord_rejections;
        assert!(mixed.stats.lu.refinement_solves > linear_solves, "{:?}", mixed.stats);
        assert_eq!(double.stats.lu.single_precision_factorizations + double.stats.lu.refinement_solves, 0);
    }

    /// Entries beyond single precision's range (about 3.4e38): the structure falls back to
    /// double precision, once, and the solve reaches the root.
    #[test]
    fn entries_beyond_single_precision_fall_back_to_double() {
        let n = 200;
        let mut p = Cubic::new(n, 1e40, 4.0);
        let mut solver = SystemSolver::new(n, &p.jac.clone()).unwrap();
        let opts = NewtonOptions { tol: 1e28, max_iter: 20, chord: true, single_precision: true, deadline: None };
        let sol = solver.solve(&mut p, &vec![0.0; n], &opts).unwrap();
        assert!(sol.status.is_success(), "{:?}", sol.status);
        assert!(max_error(&sol.x, &Cubic::root(n)) < 1e-11);
        assert_eq!(sol.stats.lu.single_precision_fallbacks, 1);
        assert_eq!(sol.stats.lu.single_precision_factorizations, 0);
    }

    /// `x0 + x1 = 2`, `x0 + (1 + 10⁻⁹) x1 = 2 + 10⁻⁹` (root (1, 1)): in single precision
    /// the two rows are equal, so the refinement cannot converge; the matrix is factored
    /// again in double precision and later steps stay in double precision.
    #[test]
    fn a_matrix_single_precision_cannot_resolve_falls_back_to_double() {
        let mut p =
            Linear { structure: vec![(0, 0), (0, 1), (1, 0), (1, 1)], values: vec![1.0, 1.0, 1.0, 1.0 + 1e-9], b: vec![2.0, 2.0 + 1e-9] };
        let mut solver = SystemSolver::new(2, &p.structure.clone()).unwrap();
        let opts = NewtonOptions { tol: 1e-14, max_iter: 10, chord: true, single_precision: true, deadline: None };
        for _ in 0..2 {
            let sol = solver.solve(&mut p, &[0.0, 0.0], &opts).unwrap();
            assert!(sol.status.is_success(), "{:?}", sol.status);
            // κ ≈ 4·10⁹: the root to about κ·ε.
            assert!((sol.x[0] - 1.0).abs() < 1e-5 && (sol.x[1] - 1.0).abs() < 1e-5, "{:?}", sol.x);
            assert_eq!(sol.stats.lu.single_precision_factorizations, sol.stats.lu.single_precision_fallbacks);
        }
        // The second solve of the structure went to double precision directly.
        let sol = solver.solve(&mut p, &[0.0, 0.0], &opts).unwrap();
        assert_eq!((sol.stats.lu.single_precision_factorizations, sol.stats.lu.single_precision_fallbacks), (0, 0));
    }
}
