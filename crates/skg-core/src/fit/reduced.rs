//! The reduced fit: Ipopt optimizes the free parameters alone, the trajectory eliminated
//! through the equations of motion (docs/fitting.md#two-ways-to-hand-the-fit-to-ipopt).
//!
//! Unknowns `θ` with their bounds, no constraints, objective the misfit
//! `F(θ) = f(P(θ))` of the trajectory `P(θ)` that solves `R(P; θ) = 0`: from Ipopt's
//! iterate moved along its sensitivities, by chord steps on the iterate's factorization
//! of `∂R/∂P`, and by Newton's method where they stall. Its derivatives are exact:
//! - the gradient `∇F = Sᵀ ∇_P f`, `S = dP/dθ = −(∂R/∂P)⁻¹ ∂R/∂θ` (`statistics.rs`);
//! - the Hessian: with the adjoint `y` of `(∂R/∂P)ᵀ y = −∇_P f`, the Lagrangian
//!   `L = f + yᵀR` is stationary in `P`, `F(θ) = L(P(θ), θ)` for every `y`, and
//!   differentiating twice, `∇²F = Zᵀ ∇²L Z` with `Z = (S; I)` (the term
//!   `∇_P L · d²P/dθ²` vanishes). `∇²L` in `(P, θ)` is the Hessian the all-at-once fit
//!   hands Ipopt (`problem.rs`) at the multipliers `y`: the misfit's `Σ wᵢ eᵢeᵢᵀ` plus
//!   the action's second derivatives, from the same derivative tapes.
//!
//! Each Ipopt iteration then costs one sparse LU of `∂R/∂P` (the derivatives at the
//! iterate), `k + 1` pairs of triangular solves, a few chord steps and the Hessian's
//! evaluation, instead of MUMPS's factorization of the KKT matrix of the whole
//! trajectory (the rolling disk at 512 nodes: 3082 unknowns and 3080 constraints, a
//! factor of 1.0 M entries, about 30 ms each, against 6.4 ms). This is single shooting on
//! the discrete equations: from the same start it follows the misfit of motions that
//! satisfy the equations, where the all-at-once fit may cross infeasible trajectories on
//! its way (docs/fitting.md).
//!
//! **Stopping.** From the intermediate callback, once Newton's step on the misfit
//! alone, `δθ = −(∇²F)⁻¹ ∇F` over the parameters off their bounds (those within their
//! tolerance of a bound held there), moves each by at most `tol · max(|θ|, 1)`: the
//! unbarriered minimum is then that close (`barrier.rs`, whose displacement by the
//! barrier's forces this is, with the whole gradient as the force: at Ipopt's iterate
//! `∇F` is the barrier's force plus Ipopt's dual infeasibility). Ipopt's own test, the
//! dual infeasibility at most `tol`, asks for more than the gradient's precision here:
//! `∇F = Sᵀ ∇_P f` carries the trajectory's rounding error through the weights and
//! sensitivities (the noisy oscillator, weights 10⁴: `|∇F|` went up and down between
//! 1e-9 and 5e-6 at the minimum, and the fit stopped at Ipopt's acceptable level after
//! 17 iterations where the displacement test stops after 11). The equations hold at
//! every point Ipopt sees, to the scene's `tol` or their round-off level.
//!
//! **The acceptable level** is the same test at [`ACCEPTABLE_TOL`]: met by
//! [`ACCEPTABLE_ITER`] successive iterates, it stops the fit there (with a warning, as
//! Ipopt's acceptable level does). Ipopt's own acceptable level is switched off for the
//! reduced fit: it judges the gradient in absolute terms, and a parameter of size `10⁴`
//! has a small gradient far from the minimum (the overdamped spring's damping fitted from
//! noise-free data, a misfit of order 1e-4: Ipopt stopped at `c = 9955`, 45 from the
//! truth and still taking steps of 358, where the displacement test goes on to
//! `c = 10⁴`).

use nalgebra::{DMatrix, DVector};
use serde::Serialize;

use skg_ipopt::{EvalError, IterationStat, Problem, INFINITY_BOUND};

use super::barrier;
use super::free::FreeParameter;
use super::observe::Observations;
use super::problem::{Clock, KktStop, Plans, StopTest};
use super::settings::ACCEPTABLE_ITER;
use super::statistics;
use crate::discrete::action::Action;
use crate::model::Workspace;
use crate::solve::backend::Reduced;
use crate::solve::linalg::{max_abs, NewtonOptions, NewtonStatus, SparseFactorization, SystemSolver};

/// The acceptable level of the displacement test: Ipopt's default `acceptable_tol`,
/// relative to the parameters' size as the test's `tol` (module documentation).
const ACCEPTABLE_TOL: f64 = 1e-6;

/// The warning of a reduced fit stopped at its acceptable level.
pub(super) fn acceptable_warning() -> String {
    format!(
        "the reduced fit stopped at its acceptable level (Solved_To_Acceptable_Level): Newton's step on the misfit moved each \
         parameter by at most {ACCEPTABLE_TOL:e} of its size for {ACCEPTABLE_ITER} iterations, where the misfit's rounding kept \
         Ipopt's line search from the requested tolerance (--tol)"
    )
}

/// The iteration limit of each solve of the equations of motion.
const NEWTON_MAX_ITER: u32 = 20;

/// At most this many chord steps begin a solve (`ReducedFit::chord_steps`), each
/// reducing `max |R|` at least by [`CHORD_CONTRACTION`].
const CHORD_STEPS: usize = 12;
const CHORD_CONTRACTION: f64 = 0.5;

/// The trajectory solved at one point `θ`.
struct Solved {
    theta: Vec<f64>,
    /// `(P, θ)`: the trajectory's unknowns, then the parameters.
    x: Vec<f64>,
    /// `max |R|` there, and whether that is the round-off level above the tolerance.
    residual: f64,
    at_roundoff: bool,
}

/// The last point whose derivatives were asked for: Ipopt's iterate. The solves of the
/// points Ipopt tries next start from it (its trial points lie on a line from it; a
/// rejected trial farther away is no start for a shorter one: on the double pendulum
/// Newton's method failed from one).
struct Anchor {
    theta: Vec<f64>,
    /// Its trajectory's unknowns `P`.
    p: Vec<f64>,
    /// `∇F` and `∇²F` (module documentation).
    gradient: DVector<f64>,
    hessian: DMatrix<f64>,
    /// The sensitivities `S = dP/dθ`.
    sensitivities: DMatrix<f64>,
    /// The round-off level of `R` at `∂R/∂P` there, and whether its solve ended there.
    roundoff: f64,
    at_roundoff: bool,
}

/// The reduced fit's solves of the equations of motion (`equations_of_motion` in the
/// `fit` object of `summary.json`).
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct InnerWork {
    /// Solves: one per point Ipopt evaluated.
    pub solves: usize,
    /// Their chord steps, on the factorization of the last point's derivatives.
    pub chord_steps: usize,
    /// Their Newton steps, each a factorization.
    pub newton_steps: usize,
    /// Points at which the solve failed (Ipopt then shortened its step).
    pub failures: usize,
    /// Evaluations of the gradient and Hessian (each one sparse LU of `∂R/∂P`).
    pub derivatives: usize,
    /// Seconds in the solves.
    pub solve_s: f64,
    /// Seconds in the derivatives.
    pub derivatives_s: f64,
}

/// A fit as Ipopt's problem in the parameters alone (module documentation).
pub(super) struct ReducedFit<'a> {
    action: &'a mut Action,
    plans: &'a Plans,
    observations: &'a Observations,
    free: &'a [FreeParameter],
    /// Newton's method, for a solve the chord steps do not finish (made at the first, on
    /// the analysis of the factorizations of `∂R/∂P`: an analysis costs as much as a
    /// factorization).
    newton: Option<SystemSolver>,
    options: NewtonOptions,
    ws: Option<Workspace>,
    /// The last point solved.
    solved: Solved,
    anchor: Option<Anchor>,
    hessian: Vec<(u32, u32)>,
    stop: StopTest,
    stopped: Option<KktStop>,
    /// Successive iterates within [`ACCEPTABLE_TOL`] of the minimum (module documentation).
    acceptable_iterates: usize,
    pub(super) clock: Clock,
    pub(super) work: InnerWork,
}

impl<'a> ReducedFit<'a> {
    /// The problem from `x0 = (P, θ)`, a solution of the equations at the starting values
    /// (the derivatives there are computed first, so that Ipopt's first point, its start
    /// pushed into the bounds, is solved by chord steps too).
    pub(super) fn new(
        action: &'a mut Action,
        plans: &'a Plans,
        observations: &'a Observations,
        free: &'a [FreeParameter],
        x0: &[f64],
        stop: StopTest,
    ) -> Result<Self, String> {
        let n_p = action.layout.n_p;
        let options = NewtonOptions {
            tol: stop.constraints,
            max_iter: NEWTON_MAX_ITER,
            chord: true,
            single_precision: false,
            deadline: stop.deadline.map(|d| d.at),
        };
        let k = free.len() as u32;
        let hessian = (0..k).flat_map(|i| (0..=i).map(move |j| (i, j))).collect();
        let theta0 = x0[n_p..].to_vec();
        let mut ws = action.model.workspace();
        action.set_parameters(&theta0, &mut ws);
        let mut z = vec![0.0; action.layout.len()];
        z[..n_p].copy_from_slice(&x0[..n_p]);
        let mut r = vec![0.0; n_p];
        action.gradient(&z, true, &mut r, &mut ws);
        let residual = max_abs(&r);
        let solved = Solved { theta: theta0.clone(), x: x0.to_vec(), residual, at_roundoff: residual > options.tol };
        let work = InnerWork::default();
        let mut fit = ReducedFit {
            action,
            plans,
            observations,
            free,
            newton: None,
            options,
            ws: Some(ws),
            solved,
            anchor: None,
            hessian,
            stop,
            stopped: None,
            acceptable_iterates: 0,
            clock: Clock::new(stop.deadline),
            work,
        };
        fit.derivatives_at(&theta0).map_err(|e| e.0)?;
        Ok(fit)
    }

    /// `(P, θ)` at `theta`: the last point solved, with `max |R|` there.
    pub(super) fn point(&mut self, theta: &[f64]) -> Result<(Vec<f64>, f64), EvalError> {
        self.solve_at(theta)?;
        Ok((self.solved.x.clone(), self.solved.residual))
    }

    /// How the callback stopped Ipopt at a KKT point, if it did.
    pub(super) fn stopped_at_kkt_point(&self) -> Option<KktStop> {
        self.stopped
    }

    /// Solve the equations of motion at `theta` (nothing to do when the last point solved
    /// was `theta`): from Ipopt's iterate moved along its sensitivities (`predicted`), by
    /// chord steps, then Newton's method where they stall.
    fn solve_at(&mut self, theta: &[f64]) -> Result<(), EvalError> {
        if self.solved.theta == theta {
            return Ok(());
        }
        let n_p = self.action.layout.n_p;
        let mut ws = self.ws.take().expect("the workspace is returned after each solve");
        self.action.set_parameters(theta, &mut ws);
        let t = std::time::Instant::now();
        self.work.solves += 1;
        let mut z = self.predicted(theta);
        let chord = self.chord_steps(&mut z, &mut ws);
        let (x, residual, at_roundoff) = match chord {
            Some(end) => (z[..n_p].to_vec(), end.0, end.1),
            None => {
                let mut system = Reduced::with_workspace(self.action, &z, &self.plans.jacobian, None, ws);
                let newton = match self.newton.as_mut() {
                    Some(newton) => Ok(newton),
                    None => {
                        // On the analysis of the anchor's factorization, when there is one.
                        let structure = &self.plans.jacobian.structure;
                        let shared = self.plans.jacobian_lu.borrow().as_ref().and_then(|f| SystemSolver::on_analysis_of(f, n_p, structure));
                        shared.map_or_else(|| SystemSolver::new(n_p, structure), Ok).map(|s| self.newton.insert(s))
                    }
                };
                let result = newton.and_then(|newton| newton.solve(&mut system, &z[..n_p], &self.options));
                ws = system.into_workspace();
                let solution = match result {
                    Ok(s) if s.status.is_success() => s,
                    other => {
                        self.ws = Some(ws);
                        self.work.failures += 1;
                        let why = other.map_or_else(|e| e.to_string(), |s| s.status.to_string());
                        return Err(EvalError(format!("the equations of motion at θ = {theta:?}: {why}")));
                    }
                };
                self.work.newton_steps += solution.iterations;
                (solution.x, solution.max_residual, solution.status == NewtonStatus::ConvergedToRoundOff)
            }
        };
        self.ws = Some(ws);
        self.work.solve_s += t.elapsed().as_secs_f64();
        self.solved = Solved { theta: theta.to_vec(), x: x.into_iter().chain(theta.iter().copied()).collect(), residual, at_roundoff };
        Ok(())
    }

    /// The whole unknown vector at `theta` predicted from Ipopt's iterate (the anchor): its
    /// trajectory moved along its sensitivities (off by `O(|δθ|²)` instead of `O(|δθ|)`).
    fn predicted(&self, theta: &[f64]) -> Vec<f64> {
        let n_p = self.action.layout.n_p;
        let mut z = vec![0.0; self.action.layout.len()];
        match &self.anchor {
            Some(a) => {
                let step = DVector::from_iterator(theta.len(), theta.iter().zip(&a.theta).map(|(t, t0)| t - t0));
                z[..n_p].iter_mut().zip(a.p.iter().zip((&a.sensitivities * step).iter())).for_each(|(z, (p, d))| *z = p + d);
            }
            None => z[..n_p].copy_from_slice(&self.solved.x[..n_p]),
        }
        z
    }

    /// Chord steps `J₀ δP = −R(P)` from `z` on the factorization of `∂R/∂P` the
    /// derivatives at Ipopt's iterate made (`J₀`, the Jacobian there): near that
    /// point they converge without a new factorization, linearly. They go on while each
    /// at least halves `max |R|`, as far as they take it: a solve ends as Newton's method
    /// ends, at the tolerance or where `R` stops decreasing below its round-off level
    /// (a step from a residual there lands on rounding noise, which the fit's parameters
    /// still feel: stopping at the level itself moved the rolling disk's `α` by 250 of
    /// its standard errors). The end `(max |R|, at the round-off level)`, `z` the better
    /// of the last two points; `None` for Newton's method to go on from `z`.
    fn chord_steps(&mut self, z: &mut [f64], ws: &mut Workspace) -> Option<(f64, bool)> {
        let roundoff = self.anchor.as_ref()?.roundoff;
        let n_p = self.action.layout.n_p;
        let tol = self.options.tol;
        let mut lu = self.plans.jacobian_lu.borrow_mut();
        let lu = lu.as_mut()?;
        let mut r = vec![0.0; n_p];
        let mut last: Option<(Vec<f64>, f64)> = None;
        for step in 0..=CHORD_STEPS {
            self.action.gradient(z, true, &mut r, ws);
            let residual = max_abs(&r);
            if residual <= tol {
                return Some((residual, false));
            }
            if !residual.is_finite() {
                return None;
            }
            if let Some((before, last_residual)) = &last {
                if residual > CHORD_CONTRACTION * last_residual {
                    if residual > *last_residual {
                        z[..n_p].copy_from_slice(before);
                    }
                    let end = residual.min(*last_residual);
                    return (end <= roundoff).then_some((end, true));
                }
            }
            if step == CHORD_STEPS || !lu_step(lu, &mut r) {
                return None;
            }
            last = Some((z[..n_p].to_vec(), residual));
            z[..n_p].iter_mut().zip(&r).for_each(|(p, d)| *p += d);
            self.work.chord_steps += 1;
        }
        None
    }

    /// The derivatives at `theta`, which becomes the anchor (module documentation).
    fn derivatives_at(&mut self, theta: &[f64]) -> Result<&Anchor, EvalError> {
        self.solve_at(theta)?;
        if self.anchor.as_ref().is_none_or(|a| a.theta != theta) {
            let t = std::time::Instant::now();
            let found = self.derivatives();
            self.work.derivatives += 1;
            self.work.derivatives_s += t.elapsed().as_secs_f64();
            self.anchor = Some(found.ok_or_else(|| EvalError("∂R/∂P is singular at the solved trajectory".into()))?);
        }
        Ok(self.anchor.as_ref().expect("just set"))
    }

    /// The derivatives at the last point solved, `None` where `∂R/∂P` is singular.
    fn derivatives(&mut self) -> Option<Anchor> {
        let lay = &self.action.layout;
        let n_p = lay.n_p;
        let mut ws = self.ws.take().expect("the workspace is returned after each solve");
        let mut z = vec![0.0; lay.len()];
        z[..n_p].copy_from_slice(&self.solved.x[..n_p]);
        let found = statistics::factored_sensitivities(self.action, self.plans, &z, &mut ws).and_then(|(s, mut lu, roundoff)| {
            let (gradient, mut y) = statistics::misfit_gradient(self.observations, &s, &self.solved.x);
            y.iter_mut().for_each(|g| *g = -*g);
            if !lu.solve_transposed(&mut y) {
                return None;
            }
            drop(lu);
            z[n_p..].copy_from_slice(&y);
            let hessian = self.reduced_hessian(&s, &z, &mut ws);
            let (theta, p) = (self.solved.theta.clone(), self.solved.x[..n_p].to_vec());
            Some(Anchor { theta, p, gradient, hessian, sensitivities: s, roundoff, at_roundoff: self.solved.at_roundoff })
        });
        self.ws = Some(ws);
        found
    }

    /// `Zᵀ ∇²L Z`, `Z = (S; I)`, with the multipliers in `z`'s minus block.
    fn reduced_hessian(&self, s: &DMatrix<f64>, z: &[f64], ws: &mut Workspace) -> DMatrix<f64> {
        let n_p = self.action.layout.n_p;
        let k = self.free.len();
        let plan = self.plans.hessian.as_ref().expect("the reduced fit has the exact Hessian");
        let mut solve = vec![0.0; plan.structure.len()];
        self.action.matrix_values(plan, z, &mut solve, ws);
        let mut misfit = vec![0.0; self.observations.hessian.len()];
        self.observations.hessian_values(1.0, &mut misfit);
        let mut params = vec![0.0; self.plans.parameters.hessian.len()];
        self.action.parameter_hessian(&self.plans.parameters, z, &mut params, ws);
        let entries = plan
            .structure
            .iter()
            .zip(&solve)
            .chain(self.observations.hessian.iter().zip(&misfit))
            .chain(self.plans.parameters.hessian.iter().zip(&params));
        // Row `i` of Z.
        let row = |i: usize, j: usize| {
            if i < n_p {
                s[(i, j)]
            } else if i - n_p == j {
                1.0
            } else {
                0.0
            }
        };
        let mut h = DMatrix::zeros(k, k);
        for (&(r, c), &v) in entries {
            let (r, c) = (r as usize, c as usize);
            for a in 0..k {
                for b in 0..k {
                    let term = row(r, a) * row(c, b);
                    h[(a, b)] += if r == c { v * term } else { v * (term + row(c, a) * row(r, b)) };
                }
            }
        }
        h
    }
}

impl Problem for ReducedFit<'_> {
    fn num_variables(&self) -> usize {
        self.free.len()
    }
    fn num_constraints(&self) -> usize {
        0
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        for (j, p) in self.free.iter().enumerate() {
            lower[j] = p.lower.unwrap_or(-INFINITY_BOUND);
            upper[j] = p.upper.unwrap_or(INFINITY_BOUND);
        }
    }
    fn objective(&mut self, theta: &[f64]) -> Result<f64, EvalError> {
        self.solve_at(theta)?;
        Ok(self.observations.misfit(&self.solved.x))
    }
    fn objective_gradient(&mut self, theta: &[f64], grad: &mut [f64]) -> Result<(), EvalError> {
        grad.copy_from_slice(self.derivatives_at(theta)?.gradient.as_slice());
        Ok(())
    }
    fn constraints(&mut self, _theta: &[f64], _c: &mut [f64]) -> Result<(), EvalError> {
        Ok(())
    }
    fn jacobian_structure(&self) -> &[(u32, u32)] {
        &[]
    }
    fn jacobian_values(&mut self, _theta: &[f64], _values: &mut [f64]) -> Result<(), EvalError> {
        Ok(())
    }
    fn hessian_structure(&self) -> &[(u32, u32)] {
        &self.hessian
    }
    fn hessian_values(&mut self, theta: &[f64], obj_factor: f64, _lambda: &[f64], values: &mut [f64]) -> Result<(), EvalError> {
        self.derivatives_at(theta)?;
        let h = &self.anchor.as_ref().expect("just computed").hessian;
        for (v, &(i, j)) in values.iter_mut().zip(&self.hessian) {
            *v = obj_factor * h[(i as usize, j as usize)];
        }
        Ok(())
    }
    fn intermediate(&mut self, stat: &IterationStat) -> bool {
        self.stopped = None;
        // Ipopt's iterate is the last point of the gradient: the anchor.
        if let Some(a) = self.anchor.as_ref().filter(|_| !stat.restoration && stat.iter >= 1) {
            let within = |tol: f64| {
                let mut hold = barrier::hold(self.free, &a.theta, stat.mu, tol, self.stop.bound_relax_factor);
                hold.force = a.gradient.iter().copied().collect();
                hold.negligible(&a.hessian)
            };
            if within(self.stop.tol) {
                self.stopped = Some(if a.at_roundoff { KktStop::RoundOff } else { KktStop::Tolerance });
            } else {
                self.acceptable_iterates = if within(ACCEPTABLE_TOL) { self.acceptable_iterates + 1 } else { 0 };
                if self.acceptable_iterates >= ACCEPTABLE_ITER as usize {
                    self.stopped = Some(KktStop::Acceptable);
                }
            }
        }
        self.stopped.is_none() && !self.clock.out_of_time()
    }
}

/// `−J⁻¹ r` into `r`, on the factorization `lu` of `J`; `false` when not finite.
fn lu_step(lu: &mut SparseFactorization, r: &mut [f64]) -> bool {
    r.iter_mut().for_each(|v| *v = -*v);
    lu.solve(r)
}

#[cfg(test)]
mod tests {
    use std::cell::RefCell;
    use std::sync::Arc;

    use super::*;
    use crate::discrete::action::Block;
    use crate::discrete::Discretization;
    use crate::fit::start::start_states;
    use crate::fit::Data;
    use crate::model::Model;
    use crate::scene::{Overrides, SceneFile};
    use crate::solve::action_on;

    /// The misfit's gradient and Hessian in the parameters against central differences
    /// of the misfit of the solved trajectory (each difference a solve of its own), on a
    /// pendulum with a free frequency and release angle and data it does not fit (large
    /// residuals: the Hessian's terms in the action's second derivatives count).
    #[test]
    fn the_reduced_gradient_and_hessian_are_the_misfits_derivatives() {
        let text = "[scene]\nname = \"p\"\nlagrangian = \"th_dot^2/2 + w*cos(th)\"\n[parameters]\nw = 2\na = 0.8\n\
                    [[coordinates]]\nname = \"th\"\ninitial = \"a\"\nvelocity = 0\n\
                    [time]\nstart = 0\nend = 3\nnodes = 64\n[discretization]\noperator = \"SBP242\"\n";
        let scene = SceneFile::parse(text, "p.toml").unwrap().resolve(&Overrides::default()).unwrap();
        let names = vec!["w".to_string(), "a".to_string()];
        let free: Vec<FreeParameter> = names.iter().map(|n| FreeParameter::parse(n).unwrap()).collect();
        let model = Arc::new(Model::with_free_parameters(&scene, &names).unwrap());
        let disc = Discretization::of(&scene);
        let times = disc.times(&scene);
        let mut action = action_on(&model, &scene, &disc, &times).unwrap();
        let plans = Plans {
            jacobian: action.plan(Block::ReducedJacobian),
            hessian: Some(action.plan(Block::ReducedHessian)),
            parameters: action.parameter_plan(),
            jacobian_lu: RefCell::new(None),
        };
        let rows: String = (1..=12).map(|i| 0.25 * i as f64).map(|t| format!("{t},{}\n", 0.3 * (1.7 * t).cos() + 0.1)).collect();
        let data = Data::parse(&format!("t,th\n{rows}"), "d.csv", &scene).unwrap();
        let observations = Observations::new(&action, &times, &data);
        let start = start_states(&scene, &model, &disc, &times).unwrap();
        let mut x0 = start.solution.unwrap()[..action.layout.n_p].to_vec();
        x0.extend([2.0, 0.8]);
        let stop = StopTest { tol: 1e-10, constraints: 1e-12, bound_relax_factor: 1e-8, deadline: None };
        let mut fit = ReducedFit::new(&mut action, &plans, &observations, &free, &x0, stop).unwrap();

        let theta = [2.3, 0.7];
        let at = fit.derivatives_at(&theta).unwrap();
        let (g, h) = (at.gradient.clone(), at.hessian.clone());
        let mut misfit = |t: [f64; 2]| fit.objective(&t).unwrap();
        let step = 1e-5;
        for j in 0..2 {
            let (mut up, mut down) = (theta, theta);
            up[j] += step;
            down[j] -= step;
            let fd = (misfit(up) - misfit(down)) / (2.0 * step);
            assert!((g[j] - fd).abs() <= 1e-6 * g[j].abs().max(1.0), "gradient {j}: {} against {fd}", g[j]);
        }
        let mut gradient = |t: [f64; 2]| fit.derivatives_at(&t).unwrap().gradient.clone();

        for j in 0..2 {
            let (mut up, mut down) = (theta, theta);
            up[j] += step;
            down[j] -= step;
            let fd = (gradient(up) - gradient(down)) / (2.0 * step);
            for i in 0..2 {
                assert!(
                    (h[(i, j)] - fd[i]).abs() <= 1e-5 * h[(i, j)].abs().max(1.0),
                    "Hessian ({i}, {j}): {} against {}",
                    h[(i, j)],
                    fd[i]
                );
            }
        }
        // Residuals far from zero, so that the Hessian's terms beyond Gauss–Newton's count.
        let at = fit.objective(&theta).unwrap();
        assert!(at > 0.1, "misfit {at}");
    }
}
