//! Newton's method for a square sparse system `F(x) = 0` with a sparse LU of its
//! Jacobian (docs/solver.md#the-newton-backend).
//!
//! The system is anything that implements [`Problem`] (the same adapters Ipopt is
//! given): its residual is [`Problem::constraints`], its Jacobian
//! [`Problem::jacobian_values`] on the fixed [`Problem::jacobian_structure`].
//!
//! **Linear algebra.** A [`SystemSolver`] is built once per sparsity structure: it turns
//! the structure into a compressed-column pattern and computes the symbolic LU analysis
//! (a COLAMD fill-reducing column order and the elimination structure) with faer's
//! sparse LU. Every Newton iteration then does one numeric LU (threshold partial
//! pivoting by rows, on the stored analysis and into the stored buffers; in single
//! precision where asked, see "Mixed precision" below) and one pair of triangular
//! solves (or a few, to refine a single-precision solution). The same value serves any
//! number of solves of systems with the same structure: successive iterations,
//! successive time windows, sweep points.
//! faer was chosen over SuiteSparse's KLU/UMFPACK by measurement (docs/benchmarks.md):
//! it is fast enough on these matrices and needs no system library or FFI.
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
//! in single precision (`f32`) on the same analysis, and each linear system `A x = b`
//! of a step is solved by iterative refinement in double precision: `x ← x + M⁻¹ r`,
//! `r = b − A x` computed with the double-precision `A`, until `max |r|` is at most
//! `max(10⁻⁶ · max |F|, 0.1 · max(tol, round-off level))` — a step within a relative
//! 10⁻⁶ of the Newton step, so that the iteration takes the steps of double precision,
//! and never finer than what can lower the residual. Convergence is still judged on the
//! residual in double precision, so the answer is that of a double-precision solve
//! (coordinates within 10⁻¹³ on the chain of 16 rods; the multipliers, which the
//! residual determines less well, within 2·10⁻⁷). Each refinement step contracts `r` by
//! about `κ(A) · 2⁻²⁴`; when one contracts by less than one half (single precision no
//! longer resolves the matrix), or an entry is beyond single precision's
//! range, the matrix is factored again in double precision, and the structure stays in
//! double precision for the rest of this solver's life. This is the scheme of LAPACK's
//! `DSGESV` (Langou et al., *Exploiting the performance of 32 bit floating point
//! arithmetic in obtaining 64 bit accuracy*, 2006), with a stopping test suited to a
//! Newton step. A single-precision LU moves half the bytes and fits twice the numbers in
//! a SIMD register: on the chain of 16 rods at N = 1024 it takes 0.17 s against 0.24 s,
//! and the process's peak memory falls from 273 to 182 MB. The backend asks for it where
//! that pays (`backend::single_precision_pays`).

use std::fmt;
use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, LuSymbolicParams, NumericLu, SymbolicLu};
use faer::sparse::linalg::{SupernodalThreshold, SymbolicSupernodalParams};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par};
use serde::Serialize;

use skg_ipopt::{EvalError, IterationStat, Problem};

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

/// A refinement step must reduce `max |A x − b|` at least by this factor, or the
/// refinement is abandoned for a factorization in double precision. With `κ(A)` the
/// condition number, a step contracts by about `κ(A) · 2⁻²⁴`; at 0.5 the refinement
/// stops where single precision no longer resolves the matrix.
const REFINEMENT_CONTRACTION: f64 = 0.5;

/// The most triangular solves of one refinement (the first solve included).
const MAX_REFINEMENT_SOLVES: usize = 10;

/// The residual's round-off level is taken as `ROUNDOFF · ε · max_i Σ_j |J_ij| |x_j|`.
/// Measured: at N = 16384 (disk) and 65536 (tumbler) the residual stagnated at 0.4 of
/// `ε · max_i Σ_j |J_ij| |x_j|` (1.1e-11 and 3.2e-11, above the default tol 1e-11), with
/// Newton steps that no longer decreased it.
pub const ROUNDOFF: f64 = 4.0;

/// The round-off level of a residual `F(x)` whose Jacobian has the entries (row,
/// column, value): `ROUNDOFF · ε · max_i Σ_j |J_ij| |x_j|` over `rows` rows. No step
/// computed in floating point can bring `max |F|` much below it. Used as a stopping
/// test by Newton and by the Ipopt path alike (`backend::solve_problem`).
pub fn residual_roundoff_level(entries: impl Iterator<Item = (usize, usize, f64)>, x: &[f64], rows: usize) -> f64 {
    row_roundoff_levels(entries, x, rows).into_iter().fold(0.0, f64::max)
}

/// The round-off level of each row `i` of a residual `F(x)`, `ROUNDOFF · ε · Σ_j |J_ij| |x_j|`
/// ([`residual_roundoff_level`] is their largest): what one equation's rounding error
/// can reach, so that a solve stopped at the largest level can be checked equation by
/// equation (`backend::SquareSolver::equations_at_round_off`).
pub fn row_roundoff_levels(entries: impl Iterator<Item = (usize, usize, f64)>, x: &[f64], rows: usize) -> Vec<f64> {
    let mut sums = vec![0.0_f64; rows];
    for (r, c, v) in entries {
        sums[r] += v.abs() * x[c].abs();
    }
    sums.iter_mut().for_each(|s| *s *= ROUNDOFF * f64::EPSILON);
    sums
}

/// How a Newton solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NewtonStatus {
    /// `max |F| ≤ tol`.
    Converged,
    /// `max |F|` is above `tol` but at the residual's round-off level
    /// `ROUNDOFF · ε · max_i Σ_j |J_ij| |x_j|` ([`ROUNDOFF`]): no step can reduce it further.
    ConvergedToRoundOff,
    /// The iteration limit was reached first.
    MaximumIterationsExceeded,
    /// No step length down to [`MIN_STEP`] decreased the residual norm enough.
    LineSearchFailed,
    /// The LU found no pivot, or the step was not finite.
    SingularJacobian,
    /// A residual at the start, or a Jacobian, could not be evaluated or is not finite.
    InvalidNumber,
}

impl NewtonStatus {
    /// A stable name, e.g. `"Newton_Converged"` (written where Ipopt's status names go).
    pub fn name(&self) -> &'static str {
        match self {
            NewtonStatus::Converged => "Newton_Converged",
            NewtonStatus::ConvergedToRoundOff => "Newton_Converged_To_Round_Off",
            NewtonStatus::MaximumIterationsExceeded => "Newton_Maximum_Iterations_Exceeded",
            NewtonStatus::LineSearchFailed => "Newton_Line_Search_Failed",
            NewtonStatus::SingularJacobian => "Newton_Singular_Jacobian",
            NewtonStatus::InvalidNumber => "Newton_Invalid_Number",
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
            NewtonStatus::LineSearchFailed => "Newton's method: the line search found no step that decreases the residual",
            NewtonStatus::SingularJacobian => "Newton's method: the Jacobian is singular (no pivot, or a non-finite step)",
            NewtonStatus::InvalidNumber => "Newton's method: the residual at the start or a Jacobian is not finite",
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
    /// The problem's Jacobian structure differs from the one the solver was built for.
    #[error("the problem's Jacobian structure differs from the one this solver was analysed for")]
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
    /// Numeric LU factorizations in single precision (module documentation, "Mixed
    /// precision"); the others of the `jacobian_evaluations` are in double precision.
    pub single_precision_factorizations: usize,
    /// Triangular solves with a single-precision factorization, each followed by the
    /// residual of the linear system in double precision (the refinement steps).
    pub refinement_solves: usize,
    /// Times the refinement did not converge and the matrix was factored again in double
    /// precision (the structure then stays in double precision).
    pub single_precision_fallbacks: usize,
    /// Time in the residual and Jacobian callbacks.
    pub evaluation_s: f64,
    /// Time in numeric LU factorizations.
    pub factorization_s: f64,
    /// Time in the triangular solves (and the refinement's residuals).
    pub triangular_solve_s: f64,
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
    /// One entry per iteration, iteration 0 the start, in Ipopt's layout: `inf_pr` is
    /// `max |F|`, `d_norm` the step's max-norm, `alpha_pr` the step length, `ls_trials`
    /// the residual evaluations from that iteration's point (a rejected chord trial and
    /// the line search's trials); the other fields are 0.
    pub history: Vec<IterationStat>,
    /// Counts and times.
    pub stats: NewtonStats,
    /// Wall time of the solve.
    pub total_s: f64,
}

/// The sparse LU machinery of one sparsity structure: the compressed-column pattern,
/// the symbolic analysis, the numeric factorization's storage and the work buffers.
/// Build it once with [`SystemSolver::new`] and call [`SystemSolver::solve`] for every
/// system of that structure.
pub struct SystemSolver {
    n: usize,
    /// The (row, column) structure this solver was built for, in the problem's order.
    structure: Vec<(u32, u32)>,
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    /// Position in the compressed values of each structure entry (duplicates share one).
    slot: Vec<usize>,
    symbolic: SymbolicLu<u32>,
    numeric: NumericLu<u32, f64>,
    factor_work: MemBuffer,
    solve_work: MemBuffer,
    /// The single-precision factorization and its buffers (empty until used).
    single: SingleLu,
    /// The precision of the last successful factorization.
    factored: Factored,
    /// Whether a single-precision factorization of this structure failed or did not
    /// refine: later factorizations are in double precision.
    single_failed: bool,
    /// Seconds the symbolic analysis took.
    analysis_s: f64,
}

/// The precision of the factorization in hand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Factored {
    None,
    Double,
    Single,
}

/// A numeric LU in single precision on the same symbolic analysis, with its buffers.
#[derive(Default)]
struct SingleLu {
    numeric: NumericLu<u32, f32>,
    values: Vec<f32>,
    rhs: Vec<f32>,
    factor_work: Option<MemBuffer>,
    solve_work: Option<MemBuffer>,
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
        let (col_ptr, row_idx, slot) = compressed_columns(n, structure);
        let pattern = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
        let symbolic = factorize_symbolic_lu(pattern, lu_params()).map_err(|e| NewtonError::Analysis(format!("{e:?}")))?;
        let factor_req = symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default());
        let solve_req: StackReq = symbolic.solve_in_place_scratch::<f64>(1, Par::Seq);
        Ok(SystemSolver {
            n,
            structure: structure.to_vec(),
            col_ptr,
            row_idx,
            slot,
            symbolic,
            numeric: NumericLu::new(),
            factor_work: MemBuffer::new(factor_req),
            solve_work: MemBuffer::new(solve_req),
            single: SingleLu::default(),
            factored: Factored::None,
            single_failed: false,
            analysis_s: start.elapsed().as_secs_f64(),
        })
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
        self.row_idx.len()
    }

    /// Solve `problem`'s system `F(x) = 0` from `x0` by Newton's method with the line
    /// search of the module documentation. Errors only when the problem does not fit
    /// this solver (size, structure); a failed iteration is a [`NewtonSolution`] whose
    /// status says why.
    pub fn solve<P: Problem>(&mut self, problem: &mut P, x0: &[f64], options: &NewtonOptions) -> Result<NewtonSolution, NewtonError> {
        let n = self.n;
        if problem.num_variables() != n || problem.num_constraints() != n || x0.len() != n {
            return Err(NewtonError::Structure(format!(
                "{} variables, {} equations and a start of {} entries for a solver of size {n}",
                problem.num_variables(),
                problem.num_constraints(),
                x0.len()
            )));
        }
        if !self.fits(n, problem.jacobian_structure()) {
            return Err(NewtonError::OtherStructure);
        }
        let start = Instant::now();
        let mut stats = NewtonStats::default();
        let mut x = x0.to_vec();
        let mut f = vec![0.0; n];
        let mut norm = match evaluate_residual(problem, &x, &mut f, &mut stats) {
            Ok(()) => norm2(&f),
            Err(_) => f64::NAN,
        };
        let mut history = vec![iteration_stat(0, max_abs(&f), 0.0, 0.0, 0)];
        let mut jac = vec![0.0; self.structure.len()];
        let mut values = vec![0.0; self.row_idx.len()];
        let mut step = vec![0.0; n];
        let mut trial = vec![0.0; n];
        let mut f_trial = vec![0.0; n];
        let mut iterations = 0;
        // The residual's round-off level, from the last Jacobian (none before the first).
        let mut floor = 0.0;
        // Whether the next step is tried as a chord step on the stored factorization.
        let mut chord_next = false;
        let status = loop {
            if !norm.is_finite() {
                break NewtonStatus::InvalidNumber;
            }
            let residual = max_abs(&f);
            if residual <= options.tol {
                break NewtonStatus::Converged;
            }
            // At the round-off level a Newton step no longer decreases the residual; a
            // chord step that still contracts it is cheap enough to be tried first.
            if residual <= floor && !chord_next {
                break NewtonStatus::ConvergedToRoundOff;
            }
            if iterations >= options.max_iter as usize {
                break NewtonStatus::MaximumIterationsExceeded;
            }
            // Residual evaluations from this point (a rejected chord trial, line-search trials).
            let mut trials = 0;
            if chord_next {
                // The chord step: J(x_old) dx = −F(x), taken whole if it contracts enough.
                step.iter_mut().zip(&f).for_each(|(s, fi)| *s = -fi);
                if self.solve_linear(&values, &mut step, linear_target(residual, options.tol, floor), &mut stats) {
                    for ((xt, xi), si) in trial.iter_mut().zip(&x).zip(&step) {
                        *xt = xi + si;
                    }
                    trials += 1;
                    let ok = evaluate_residual(problem, &trial, &mut f_trial, &mut stats).is_ok();
                    let trial_norm = norm2(&f_trial);
                    let target = options.tol.max(floor);
                    let contraction = trial_norm / norm;
                    if ok && trial_norm.is_finite() && (contraction <= CHORD_CONTRACTION || max_abs(&f_trial) <= target) {
                        std::mem::swap(&mut x, &mut trial);
                        std::mem::swap(&mut f, &mut f_trial);
                        norm = trial_norm;
                        iterations += 1;
                        stats.chord_steps += 1;
                        chord_next = chord_may_finish(contraction, max_abs(&f), target);
                        history.push(iteration_stat(iterations as i32, max_abs(&f), max_abs(&step), 1.0, trials));
                        continue;
                    }
                }
                stats.chord_rejections += 1;
                if residual <= floor {
                    break NewtonStatus::ConvergedToRoundOff;
                }
            }
            // The Newton step: J dx = −F.
            let t = Instant::now();
            let evaluated = problem.jacobian_values(&x, &mut jac);
            stats.evaluation_s += t.elapsed().as_secs_f64();
            stats.jacobian_evaluations += 1;
            if evaluated.is_err() || jac.iter().any(|v| !v.is_finite()) {
                break NewtonStatus::InvalidNumber;
            }
            values.fill(0.0);
            for (&s, &v) in self.slot.iter().zip(&jac) {
                values[s] += v;
            }
            floor = residual_roundoff_level(self.entries(&values), &x, self.n);
            step.iter_mut().zip(&f).for_each(|(s, fi)| *s = -fi);
            let target = linear_target(residual, options.tol, floor);
            if !self.factor(&values, options.single_precision, &mut stats) || !self.solve_linear(&values, &mut step, target, &mut stats) {
                break NewtonStatus::SingularJacobian;
            }
            // Backtracking on ‖F‖₂.
            let mut alpha = 1.0;
            let accepted = loop {
                for ((xt, xi), si) in trial.iter_mut().zip(&x).zip(&step) {
                    *xt = xi + alpha * si;
                }
                trials += 1;
                let ok = evaluate_residual(problem, &trial, &mut f_trial, &mut stats).is_ok();
                let trial_norm = norm2(&f_trial);
                if ok && trial_norm.is_finite() && trial_norm <= (1.0 - ARMIJO * alpha) * norm {
                    break true;
                }
                alpha *= 0.5;
                if alpha < MIN_STEP {
                    break false;
                }
            };
            if !accepted {
                break NewtonStatus::LineSearchFailed;
            }
            std::mem::swap(&mut x, &mut trial);
            std::mem::swap(&mut f, &mut f_trial);
            let last_norm = norm;
            norm = norm2(&f);
            // A full step that contracted well: the Jacobian changed little along it, so
            // the next step may reuse this factorization if one more such step converges.
            chord_next = options.chord && alpha == 1.0 && chord_may_finish(norm / last_norm, max_abs(&f), options.tol.max(floor));
            iterations += 1;
            history.push(iteration_stat(iterations as i32, max_abs(&f), max_abs(&step), alpha, trials));
        };
        Ok(NewtonSolution { status, max_residual: max_abs(&f), x, iterations, history, stats, total_s: start.elapsed().as_secs_f64() })
    }

    /// The entries (row, column, value) of the compressed matrix with `values`.
    fn entries<'a>(&'a self, values: &'a [f64]) -> impl Iterator<Item = (usize, usize, f64)> + 'a {
        (0..self.n).flat_map(move |c| {
            (self.col_ptr[c] as usize..self.col_ptr[c + 1] as usize).map(move |k| (self.row_idx[k] as usize, c, values[k]))
        })
    }

    /// Factor the compressed matrix with `values`: in single precision when `single` and
    /// single precision has not failed on this structure (falling back to double
    /// precision when its LU fails, e.g. on an entry beyond single precision's range);
    /// `false` when the matrix is singular.
    fn factor(&mut self, values: &[f64], single: bool, stats: &mut NewtonStats) -> bool {
        if single && !self.single_failed {
            if self.factor_single(values, stats) {
                return true;
            }
            self.give_up_single(stats);
        }
        self.factor_double(values, stats)
    }

    /// The numeric LU in double precision.
    fn factor_double(&mut self, values: &[f64], stats: &mut NewtonStats) -> bool {
        let t = Instant::now();
        let pattern = SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx);
        let factored = self.symbolic.factorize_numeric_lu(
            &mut self.numeric,
            SparseColMatRef::new(pattern, values),
            Par::Seq,
            MemStack::new(&mut self.factor_work),
            Default::default(),
        );
        stats.factorization_s += t.elapsed().as_secs_f64();
        self.factored = if factored.is_ok() { Factored::Double } else { Factored::None };
        factored.is_ok()
    }

    /// The numeric LU in single precision; `false` when an entry is beyond its range or
    /// the LU finds no pivot.
    fn factor_single(&mut self, values: &[f64], stats: &mut NewtonStats) -> bool {
        let t = Instant::now();
        let single = &mut self.single;
        single.values.clear();
        single.values.extend(values.iter().map(|&v| v as f32));
        if single.values.iter().any(|v| !v.is_finite()) {
            return false;
        }
        let symbolic = &self.symbolic;
        let work = single
            .factor_work
            .get_or_insert_with(|| MemBuffer::new(symbolic.factorize_numeric_lu_scratch::<f32>(Par::Seq, Default::default())));
        let pattern = SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx);
        let factored = symbolic.factorize_numeric_lu(
            &mut single.numeric,
            SparseColMatRef::new(pattern, &single.values),
            Par::Seq,
            MemStack::new(work),
            Default::default(),
        );
        stats.factorization_s += t.elapsed().as_secs_f64();
        stats.single_precision_factorizations += 1;
        self.factored = if factored.is_ok() { Factored::Single } else { Factored::None };
        factored.is_ok()
    }

    /// Stop using single precision on this structure, and free its factorization.
    fn give_up_single(&mut self, stats: &mut NewtonStats) {
        stats.single_precision_fallbacks += 1;
        self.single_failed = true;
        self.single = SingleLu::default();
    }

    /// Overwrite `rhs` with the solution of the system of the last factorization, which
    /// was of the compressed matrix with `values` (the caller knows that it succeeded):
    /// directly in double precision; in single precision refined until
    /// `max |A x − rhs| ≤ target`, and when the refinement does not converge, factored
    /// again in double precision and solved directly. `false` when the solution is not
    /// finite or the matrix singular.
    fn solve_linear(&mut self, values: &[f64], rhs: &mut [f64], target: f64, stats: &mut NewtonStats) -> bool {
        if self.factored == Factored::Single {
            if self.refine(values, rhs, target, stats) {
                return true;
            }
            self.give_up_single(stats);
            if !self.factor_double(values, stats) {
                return false;
            }
        }
        self.solve_double(rhs, stats)
    }

    /// The direct solve with the double-precision factorization.
    fn solve_double(&mut self, rhs: &mut [f64], stats: &mut NewtonStats) -> bool {
        let t = Instant::now();
        LuRef::new_unchecked(&self.symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(rhs, self.n, 1),
            Par::Seq,
            MemStack::new(&mut self.solve_work),
        );
        stats.triangular_solve_s += t.elapsed().as_secs_f64();
        rhs.iter().all(|v| v.is_finite())
    }

    /// Iterative refinement with the single-precision factorization `M ≈ A`:
    /// `x ← x + M⁻¹ r`, `r = b − A x` in double precision, from `x = 0`, until
    /// `max |r| ≤ target` after at least one solve; each correction is solved for
    /// `r / max |r|`, which keeps the right-hand side within single precision's range.
    /// Fails (`false`, `rhs` unchanged) when a step does not reduce `max |r|` by
    /// [`REFINEMENT_CONTRACTION`], after [`MAX_REFINEMENT_SOLVES`] solves, or when `x` is
    /// not finite; on success `rhs` holds `x`.
    fn refine(&mut self, values: &[f64], rhs: &mut [f64], target: f64, stats: &mut NewtonStats) -> bool {
        let t = Instant::now();
        let n = self.n;
        let single = &mut self.single;
        let symbolic = &self.symbolic;
        let work = single.solve_work.get_or_insert_with(|| MemBuffer::new(symbolic.solve_in_place_scratch::<f32>(1, Par::Seq)));
        let mut x = vec![0.0; n];
        let mut r = rhs.to_vec();
        let mut last = max_abs(&r);
        // At least one solve, even when the right-hand side is already below the target.
        let mut converged = last == 0.0;
        for _ in 0..MAX_REFINEMENT_SOLVES {
            if converged || !last.is_finite() {
                break;
            }
            single.rhs.clear();
            single.rhs.extend(r.iter().map(|&ri| (ri / last) as f32));
            LuRef::new_unchecked(symbolic, &single.numeric).solve_in_place_with_conj(
                Conj::No,
                MatMut::from_column_major_slice_mut(&mut single.rhs, n, 1),
                Par::Seq,
                MemStack::new(work),
            );
            stats.refinement_solves += 1;
            x.iter_mut().zip(&single.rhs).for_each(|(xi, di)| *xi += last * f64::from(*di));
            // r = b − A x, column by column of the compressed matrix.
            r.copy_from_slice(rhs);
            for (c, xc) in x.iter().enumerate() {
                for k in self.col_ptr[c] as usize..self.col_ptr[c + 1] as usize {
                    r[self.row_idx[k] as usize] -= values[k] * xc;
                }
            }
            let now = max_abs(&r);
            if now.is_nan() || now > REFINEMENT_CONTRACTION * last {
                break;
            }
            last = now;
            converged = now <= target;
        }
        stats.triangular_solve_s += t.elapsed().as_secs_f64();
        // A solution with a non-finite entry fails too (`max_abs` can miss a NaN of `r`).
        let solved = converged && x.iter().all(|v| v.is_finite());
        if solved {
            rhs.copy_from_slice(&x);
        }
        solved
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

/// Supernode amalgamation of the supernodal LU: two adjacent supernodes of `n` columns
/// in all are merged when the merged block's explicit zeros are at most the given
/// fraction of its entries, for the first `n` bound they are within. faer's default is
/// `(4, 1.0), (16, 0.8), (48, 0.1), (∞, 0.05)`; these admit about twice the zeros in
/// larger blocks, which makes fewer, larger dense blocks for the blocked kernels. A chain
/// of 16 rods at N = 1024 (n = 49 216, the Jacobian's time blocks of 48 unknowns):
/// numeric LU 0.33 → 0.23 s, 375 → 267 MB peak (fewer supernodes, less bookkeeping);
/// 32 rods at N = 512: 0.42 → 0.37 s, 456 → 383 MB. The band-like systems of the other
/// shipped scenes (rolling disk, tumbler at N = 65536) keep faer's simplicial LU, which
/// this does not touch, and do not change beyond the noise of the measurement.
const SUPERNODE_RELAX: &[(usize, f64)] = &[(8, 1.0), (32, 0.8), (96, 0.2), (usize::MAX, 0.1)];

/// The choice between faer's simplicial (column by column) and supernodal (dense
/// blocks) numeric LU: supernodal when the analysis's estimate of flops per factor
/// nonzero exceeds `40 · SUPERNODAL_THRESHOLD` (faer's default threshold is 1). At 1 the
/// chain of 8 rods (24 unknowns per node) was factored simplicially, at 0.13 s per
/// numeric LU at N = 1024 where the supernodal LU takes 0.06 s (0.51 → 0.24 s at
/// N = 4096, for 24 % more memory: 74 → 91 MB, 261 → 324 MB peak); the chains of 16 and
/// 32 were supernodal already. The rolling disk (N = 16384, 65536), the tumbler, the
/// pendulum (65536), the knife edge (32768), chain4 and the drum stay simplicial (the
/// same peak memory; times within the noise of the measurement).
const SUPERNODAL_THRESHOLD: f64 = 0.5;

/// The symbolic LU's parameters: faer's defaults (COLAMD) with [`SUPERNODAL_THRESHOLD`]
/// and [`SUPERNODE_RELAX`].
fn lu_params() -> LuSymbolicParams<'static> {
    LuSymbolicParams {
        supernodal_flop_ratio_threshold: SupernodalThreshold(SUPERNODAL_THRESHOLD),
        supernodal_params: SymbolicSupernodalParams { relax: Some(SUPERNODE_RELAX) },
        ..Default::default()
    }
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

/// The compressed-column pattern of `structure` (rows sorted within each column,
/// duplicates merged) and the position of each structure entry in it.
fn compressed_columns(n: usize, structure: &[(u32, u32)]) -> (Vec<u32>, Vec<u32>, Vec<usize>) {
    // The entries bucketed by column (a counting sort), then each column's few entries
    // sorted by row. Linear in the entries but for the short sorts; two counting sorts
    // (by row, then by column) took 0.02 s on the 736 400 entries of a chain of 16 rods
    // at N = 1024, a comparison sort of all entries 0.03 s.
    let mut start = vec![0usize; n + 1];
    for &(_, c) in structure {
        start[c as usize + 1] += 1;
    }
    for c in 0..n {
        start[c + 1] += start[c];
    }
    // (row, entry) in column order.
    let mut bucketed = vec![(0u32, 0u32); structure.len()];
    let mut next = start.clone();
    for (e, &(r, c)) in structure.iter().enumerate() {
        bucketed[next[c as usize]] = (r, e as u32);
        next[c as usize] += 1;
    }
    let mut col_ptr = vec![0u32; n + 1];
    let mut row_idx = Vec::with_capacity(structure.len());
    let mut slot = vec![0usize; structure.len()];
    for c in 0..n {
        let column = &mut bucketed[start[c]..start[c + 1]];
        column.sort_unstable();
        let mut last = None;
        for &(r, e) in column.iter() {
            if last != Some(r) {
                row_idx.push(r);
                last = Some(r);
            }
            slot[e as usize] = row_idx.len() - 1;
        }
        col_ptr[c + 1] = row_idx.len() as u32;
    }
    (col_ptr, row_idx, slot)
}

/// `F(x)` into `f`, counting and timing the call; non-finite values are an error.
fn evaluate_residual<P: Problem>(problem: &mut P, x: &[f64], f: &mut [f64], stats: &mut NewtonStats) -> Result<(), EvalError> {
    let t = Instant::now();
    let result = problem.constraints(x, f);
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

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0_f64, |m, x| if x.is_nan() { f64::NAN } else { m.max(x.abs()) })
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

    /// `ROUNDOFF · ε · max_i Σ_j |J_ij| |x_j|`, duplicates counted separately (they are
    /// summed values whose rounding errors add up).
    #[test]
    fn roundoff_level_is_the_largest_weighted_row_sum() {
        // Rows: |2·1| + |−3·(−2)| = 8 and |0.5·1| + |1·(−2)| + |−1·(−2)| = 4.5.
        let entries = [(0, 0, 2.0), (0, 1, -3.0), (1, 0, 0.5), (1, 1, 1.0), (1, 1, -1.0)];
        let level = residual_roundoff_level(entries.into_iter(), &[1.0, -2.0], 2);
        assert_eq!(level, ROUNDOFF * f64::EPSILON * 8.0);
    }

    use super::*;

    /// `F(x) = (x0² + x1² − 4, x0 − x1)`: root (√2, √2); from (1, 0.5).
    struct Circle {
        jac: Vec<(u32, u32)>,
    }

    impl Problem for Circle {
        fn num_variables(&self) -> usize {
            2
        }
        fn num_constraints(&self) -> usize {
            2
        }
        fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
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
    impl Problem for Linear {
        fn num_variables(&self) -> usize {
            self.b.len()
        }
        fn num_constraints(&self) -> usize {
            self.b.len()
        }
        fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
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

    /// `F(x) = atan(x)`: one unknown, root 0; Newton's full step overshoots from |x| ≳ 1.39.
    struct Atan(Vec<(u32, u32)>);
    impl Problem for Atan {
        fn num_variables(&self) -> usize {
            1
        }
        fn num_constraints(&self) -> usize {
            1
        }
        fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
            c[0] = x[0].atan();
            Ok(())
        }
        fn jacobian_structure(&self) -> &[(u32, u32)] {
            &self.0
        }
        fn jacobian_values(&mut self, x: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
            v[0] = 1.0 / (1.0 + x[0] * x[0]);
            Ok(())
        }
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
        let opts = NewtonOptions { tol: 1e-14, max_iter: 20, chord: true, single_precision: false };
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
            let full =
                solver.solve(&mut p, &x0, &NewtonOptions { tol: 1e-10, max_iter: 20, chord: false, single_precision: false }).unwrap();
            let chord =
                solver.solve(&mut p, &x0, &NewtonOptions { tol: 1e-10, max_iter: 20, chord: true, single_precision: false }).unwrap();
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
        let mut p = Atan(vec![(0, 0)]);
        let mut solver = SystemSolver::new(1, &[(0, 0)]).unwrap();
        let full =
            solver.solve(&mut p, &[0.35], &NewtonOptions { tol: 3e-3, max_iter: 10, chord: false, single_precision: false }).unwrap();
        let chord =
            solver.solve(&mut p, &[0.35], &NewtonOptions { tol: 3e-3, max_iter: 10, chord: true, single_precision: false }).unwrap();
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
        let mut p = Atan(vec![(0, 0)]);
        let mut solver = SystemSolver::new(1, &[(0, 0)]).unwrap();
        let sol = solver.solve(&mut p, &[3.0], &NewtonOptions { tol: 1e-12, max_iter: 50, chord: true, single_precision: false }).unwrap();
        assert_eq!(sol.status, NewtonStatus::Converged);
        assert!(sol.x[0].abs() < 1e-12);
        assert!(sol.history[1].alpha_pr < 1.0, "the first step must be damped: {:?}", sol.history[1]);
        // Without damping the first step lands at 3 − (1 + 9)·atan(3) ≈ −9.49.
        assert!(sol.history[1].ls_trials > 1);
    }

    #[test]
    fn failures_are_statuses_and_misuse_is_an_error() {
        // A structurally singular Jacobian (column 1 empty): x0 − 1 = 0, x0 + 1 = 0.
        let mut p = Linear { structure: vec![(0, 0), (1, 0)], values: vec![1.0, 1.0], b: vec![1.0, -1.0] };
        let mut solver = SystemSolver::new(2, &p.structure.clone()).unwrap();
        let sol =
            solver.solve(&mut p, &[0.0, 0.0], &NewtonOptions { tol: 1e-12, max_iter: 10, chord: true, single_precision: false }).unwrap();
        assert_eq!(sol.status, NewtonStatus::SingularJacobian);
        assert!(!sol.status.is_success());
        assert_eq!(sol.status.name(), "Newton_Singular_Jacobian");

        let mut c = circle();
        let opts = NewtonOptions { tol: 1e-14, max_iter: 1, chord: true, single_precision: false };
        let mut solver = SystemSolver::new(2, &c.jac.clone()).unwrap();
        assert_eq!(solver.solve(&mut c, &[1.0, 0.5], &opts).unwrap().status, NewtonStatus::MaximumIterationsExceeded);
        assert_eq!(solver.solve(&mut c, &[f64::NAN, 0.5], &opts).unwrap().status, NewtonStatus::InvalidNumber);
        let mut other = SystemSolver::new(2, &[(0, 0), (1, 1)]).unwrap();
        assert!(matches!(other.solve(&mut c, &[1.0, 0.5], &opts), Err(NewtonError::OtherStructure)));
        assert!(matches!(SystemSolver::new(2, &[(0, 2)]), Err(NewtonError::Structure(_))));
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
            p.constraints(&root, &mut b).unwrap();
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

    impl Problem for Cubic {
        fn num_variables(&self) -> usize {
            self.n
        }
        fn num_constraints(&self) -> usize {
            self.n
        }
        fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
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
        let options = |single_precision| NewtonOptions { tol: 1e-12, max_iter: 20, chord: true, single_precision };
        let double = solver.solve(&mut p, &x0, &options(false)).unwrap();
        let mixed = solver.solve(&mut p, &x0, &options(true)).unwrap();
        for sol in [&double, &mixed] {
            assert_eq!(sol.status, NewtonStatus::Converged);
            // Measured: 1.0e-12 (double) and 5.2e-12 (single precision refined).
            assert!(max_error(&sol.x, &root) < 1e-10, "{}", max_error(&sol.x, &root));
        }
        assert_eq!(mixed.iterations, double.iterations);
        assert_eq!(mixed.stats.jacobian_evaluations, double.stats.jacobian_evaluations);
        assert_eq!(mixed.stats.single_precision_factorizations, mixed.stats.jacobian_evaluations);
        assert_eq!(mixed.stats.single_precision_fallbacks, 0);
        let linear_solves = mixed.stats.jacobian_evaluations + mixed.stats.chord_steps + mixed.stats.chord_rejections;
        assert!(mixed.stats.refinement_solves > linear_solves, "{:?}", mixed.stats);
        assert_eq!(double.stats.single_precision_factorizations + double.stats.refinement_solves, 0);
    }

    /// Entries beyond single precision's range (about 3.4e38): the structure falls back to
    /// double precision, once, and the solve reaches the root.
    #[test]
    fn entries_beyond_single_precision_fall_back_to_double() {
        let n = 200;
        let mut p = Cubic::new(n, 1e40, 4.0);
        let mut solver = SystemSolver::new(n, &p.jac.clone()).unwrap();
        let opts = NewtonOptions { tol: 1e28, max_iter: 20, chord: true, single_precision: true };
        let sol = solver.solve(&mut p, &vec![0.0; n], &opts).unwrap();
        assert!(sol.status.is_success(), "{:?}", sol.status);
        assert!(max_error(&sol.x, &Cubic::root(n)) < 1e-11);
        assert_eq!(sol.stats.single_precision_fallbacks, 1);
        assert_eq!(sol.stats.single_precision_factorizations, 0);
    }

    /// `x0 + x1 = 2`, `x0 + (1 + 10⁻⁹) x1 = 2 + 10⁻⁹` (root (1, 1)): in single precision
    /// the two rows are equal, so the refinement cannot converge; the matrix is factored
    /// again in double precision and later steps stay in double precision.
    #[test]
    fn a_matrix_single_precision_cannot_resolve_falls_back_to_double() {
        let mut p =
            Linear { structure: vec![(0, 0), (0, 1), (1, 0), (1, 1)], values: vec![1.0, 1.0, 1.0, 1.0 + 1e-9], b: vec![2.0, 2.0 + 1e-9] };
        let mut solver = SystemSolver::new(2, &p.structure.clone()).unwrap();
        let opts = NewtonOptions { tol: 1e-14, max_iter: 10, chord: true, single_precision: true };
        for _ in 0..2 {
            let sol = solver.solve(&mut p, &[0.0, 0.0], &opts).unwrap();
            assert!(sol.status.is_success(), "{:?}", sol.status);
            // κ ≈ 4·10⁹: the root to about κ·ε.
            assert!((sol.x[0] - 1.0).abs() < 1e-5 && (sol.x[1] - 1.0).abs() < 1e-5, "{:?}", sol.x);
            assert_eq!(sol.stats.single_precision_factorizations, sol.stats.single_precision_fallbacks);
        }
        // The second solve of the structure went to double precision directly.
        let sol = solver.solve(&mut p, &[0.0, 0.0], &opts).unwrap();
        assert_eq!((sol.stats.single_precision_factorizations, sol.stats.single_precision_fallbacks), (0, 0));
    }
}
