//! Implicit time stepping for stiff equations: the three-stage Radau IIA method of order
//! 5 with step-size control and dense output.
//!
//! # Method
//! Radau IIA (s = 3) is a collocation method at the Radau right points: stiffly
//! accurate and L-stable, so a step is bounded by the accuracy of the motion, not by
//! the fastest decay in it (a damper of rate 10⁴ s⁻¹, a spring of 10⁸ N/m), where an
//! explicit method's step is bounded by stability. The scheme follows Hairer and
//! Wanner, *Solving Ordinary Differential Equations II*, 2nd ed., Springer (1996),
//! Sec. IV.8 (their code RADAU5): the stage equations `Z = h (A ⊗ I) F(y₀ + Z)` are
//! solved by a simplified Newton iteration with one Jacobian `J = ∂f/∂y` per step (or
//! fewer: it is kept while the iteration converges fast), transformed by the
//! eigen-decomposition of `A⁻¹` (`coefficients.rs`) into one real system with
//! `γ/h − J` and one complex system with `(α − iβ)/h − J`; the error is estimated by the
//! embedded formula of order 3, filtered by `(γ/h − J)⁻¹` so that it stays bounded for
//! stiff components; the step size follows the estimate with Gustafsson's predictive
//! controller. The tolerances apply to the estimate as given: RADAU5 loosens them
//! (`0.1 rtol^{2/3}`) because its estimate is of order 3 for a method of order 5, but on
//! stiff equations with a forcing, where the stage order 3 shows, the error then
//! reached 200–1000 times the tolerance (the Prothero–Robinson equation
//! `y' = −λ (y − cos t) − sin t` at `λ = 10⁴` and `10⁷`, rtol 1e-12: 2.1e-10 and
//! 1.2e-9); as given it stays within 2 times (1.8e-13 and 7.3e-13), at about five times
//! the steps on a non-stiff oscillator, which the automatic choice gives to the explicit
//! method anyway. Every requested time is the end of a step: the
//! collocation polynomial (cubic) is only of order 3 between the nodes (stage order 3),
//! while the step's end is of order 5, and on a stiff equation the error estimate
//! accepts steps far longer than the polynomial can follow (the Prothero–Robinson
//! equation `y' = −10⁶ (y − cos t) − sin t` in steps of 1.5 s: exact to 1e-6 at their
//! ends, off by 0.5 between them). The polynomial extrapolates the starting values of
//! the next step's iteration.
//!
//! The systems are small (twice the coordinates: at most a few hundred unknowns), so
//! `J` is dense and the systems are factored by nalgebra's LU (real, and complex for the
//! conjugate pair). `J` is the caller's when it gives one: for a scene's equations the
//! model's exact Jacobian, the saddle-point solve for the accelerations differentiated
//! ([`Model::state_jacobian`](crate::model::Model::state_jacobian),
//! docs/mathematics.md#11-the-jacobian-of-the-time-stepping), which costs about one
//! evaluation of `f` and one solve with many right-hand sides instead of one evaluation
//! of `f` per unknown.
//! Without one (a plain right-hand side that is not a model's, as in this module's
//! tests), `J` is taken by forward differences of `f`, as RADAU5 does. Either way `J`
//! affects only the iteration's speed, never the converged stages.
//!
//! # Why not a crate
//! `diffsol` (BDF and ESDIRK methods) was evaluated (docs/benchmarks.md#stiff-scenes):
//! its right-hand side cannot fail (the accelerations of a constrained model come from a
//! saddle-point solve that can), and at the reference's tolerances (1e-10 … 1e-12) its
//! methods of order ≤ 5 (BDF) and 3–4 (ESDIRK) take many more steps than a fifth-order
//! Radau method. The method is a few hundred lines; failures of the right-hand side
//! and the walls' step test work exactly as in the explicit integrator
//! ([`ode`](super::ode)).
//!
//! # Failures
//! A failing right-hand side in a stage, a diverging Newton iteration or a step the
//! caller's test rejects shortens the step (by half, or as the iteration's contraction
//! predicts); below the round-off limit the step fails with
//! [`OdeError::StepTooSmall`] or [`OdeError::Rhs`], as the explicit integrator does.

mod coefficients;
#[cfg(test)]
mod tests;

use std::time::Instant;

use nalgebra::{Complex, DMatrix, DVector};

use self::coefficients::{ALPHA, BETA, C, ERROR_WEIGHTS, GAMMA, T, T_INV};
use super::ode::{OdeError, OdeOptions, OdeSolution, OdeStats, RhsError};

/// Name of the method reported in [`OdeSolution::method`].
pub const METHOD: &str = "Radau IIA of order 5 (three stages, L-stable; Hairer-Wanner RADAU5 scheme; built-in implementation)";

/// Most Newton iterations of one step.
const MAX_NEWTON: usize = 7;
/// Safety factor of the step-size control.
const SAFETY: f64 = 0.9;
/// Bounds of the step-size ratio of one step: at most 5 times larger, 8 times smaller.
const MAX_GROWTH: f64 = 5.0;
const MAX_SHRINK: f64 = 8.0;
/// The Jacobian is kept for the next step when the iteration contracted by this or more.
const KEEP_JACOBIAN: f64 = 1e-3;
/// The step size is kept (and the factorizations with it) when the new one is within
/// this band of it.
const KEEP_STEP: (f64, f64) = (1.0, 1.2);

/// The Jacobian `∂f/∂y` of a right-hand side at `(t, y)`, written into `jac` (n × n).
pub type Jacobian<'a> = dyn FnMut(f64, &[f64], &mut DMatrix<f64>) -> Result<(), RhsError> + 'a;

/// Integrate `y' = f(t, y)` from `times[0]` with `y(times[0]) = y0` by Radau IIA and
/// return the state at every requested time (the contract of
/// [`ode::integrate_checked`](super::ode::integrate_checked): `times` sorted, the last
/// one hit exactly, `accept(t, y, t_new, y_new)` a test every step must pass besides the
/// error estimate). `jacobian` is `∂f/∂y`, or `None` for forward differences of `f`.
pub fn integrate<F, C>(
    mut f: F,
    jacobian: Option<&mut Jacobian<'_>>,
    y0: &[f64],
    times: &[f64],
    opts: &OdeOptions,
    accept: C,
) -> Result<OdeSolution, OdeError>
where
    F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
    C: FnMut(f64, &[f64], f64, &[f64]) -> bool,
{
    check_input(y0, times, opts)?;
    let mut stats = OdeStats::default();
    let mut f0 = vec![0.0; y0.len()];
    evaluate(&mut f, times[0], y0, &mut f0, &mut stats).map_err(|error| OdeError::Rhs { t: times[0], error })?;
    let mut stepper = Stepper::new(y0, times[0], f0, opts);
    stepper.run(&mut f, jacobian, times, accept, stats)
}

/// The arguments [`integrate`] refuses.
fn check_input(y0: &[f64], times: &[f64], opts: &OdeOptions) -> Result<(), OdeError> {
    if times.is_empty() {
        return Err(OdeError::BadInput("no output times".into()));
    }
    if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] < w[0]) {
        return Err(OdeError::BadInput("output times must be finite and sorted ascending".into()));
    }
    if y0.iter().any(|v| !v.is_finite()) {
        return Err(OdeError::BadInput("the initial state is not finite".into()));
    }
    if !(opts.rtol > 0.0 && opts.atol >= 0.0 && opts.rtol.is_finite() && opts.atol.is_finite()) {
        return Err(OdeError::BadInput(format!("tolerances must be positive and finite (rtol {}, atol {})", opts.rtol, opts.atol)));
    }
    Ok(())
}

/// `f(t, y)` into `dy` (zero-filled first), counted; a non-finite value is a failure.
fn evaluate<F>(f: &mut F, t: f64, y: &[f64], dy: &mut [f64], stats: &mut OdeStats) -> Result<(), RhsError>
where
    F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
{
    dy.fill(0.0);
    stats.rhs_evals += 1;
    f(t, y, dy)?;
    if dy.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(RhsError(format!("the derivative at t = {t} is not finite")))
    }
}

/// The factorizations of the two systems of the transformed Newton iteration for one
/// step size `h`: `γ/h − J` and `(α − iβ)/h − J`.
struct Factored {
    h: f64,
    real: nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>,
    complex: nalgebra::LU<Complex<f64>, nalgebra::Dyn, nalgebra::Dyn>,
}

impl Factored {
    /// Factor both systems; `None` when one is singular.
    fn new(jac: &DMatrix<f64>, h: f64) -> Option<Factored> {
        let n = jac.nrows();
        let mut real = -jac.clone();
        let mut complex = DMatrix::from_fn(n, n, |i, j| Complex::new(-jac[(i, j)], 0.0));
        let shift = Complex::new(ALPHA / h, -BETA / h);
        for i in 0..n {
            real[(i, i)] += GAMMA / h;
            complex[(i, i)] += shift;
        }
        let (real, complex) = (real.lu(), complex.lu());
        (real.is_invertible() && complex.is_invertible()).then_some(Factored { h, real, complex })
    }

    /// `(γ/h − J)⁻¹ b` in place.
    fn solve_real(&self, b: &mut [f64]) {
        let mut v = DVector::from_column_slice(b);
        self.real.solve_mut(&mut v);
        b.copy_from_slice(v.as_slice());
    }

    /// `((α − iβ)/h − J)⁻¹ (re + i im)` in place.
    fn solve_complex(&self, re: &mut [f64], im: &mut [f64]) {
        let mut v = DVector::from_iterator(re.len(), re.iter().zip(im.iter()).map(|(&r, &i)| Complex::new(r, i)));
        self.complex.solve_mut(&mut v);
        for ((r, i), c) in re.iter_mut().zip(im.iter_mut()).zip(v.iter()) {
            *r = c.re;
            *i = c.im;
        }
    }
}

/// Why a step attempt failed, and by what factor the step is shrunk for the next.
enum Failure {
    /// The Newton iteration diverged or is predicted not to converge in time.
    Diverged(f64),
    /// The right-hand side failed at a stage (retried at half the step).
    Rhs(RhsError),
}

/// A converged step: its stages `Z_i = Y_i − y`, its scaled error and how many Newton
/// iterations it took, and the iteration's last contraction.
struct Step {
    z: [Vec<f64>; 3],
    error: f64,
    iterations: usize,
    contraction: f64,
}

/// The state of an integration between steps.
struct Stepper<'o> {
    opts: &'o OdeOptions,
    n: usize,
    t: f64,
    y: Vec<f64>,
    /// `f(t, y)`.
    f0: Vec<f64>,
    /// The step size of the next attempt.
    h: f64,
    /// The tolerances.
    rtol: f64,
    atol: f64,
    /// The Newton iteration's convergence tolerance (scaled).
    newton_tol: f64,
    jac: DMatrix<f64>,
    /// Whether the next attempt needs a new Jacobian.
    need_jacobian: bool,
    /// Whether `jac` was computed at the current state.
    jacobian_fresh: bool,
    factored: Option<Factored>,
    /// The stages and step of the last accepted step, whose collocation polynomial gives
    /// the next step's starting values.
    last: Option<([Vec<f64>; 3], f64)>,
    /// The Newton contraction estimate carried from step to step (Hairer's `faccon`).
    faccon: f64,
    /// The last accepted step size and its error (Gustafsson's controller).
    accepted: Option<(f64, f64)>,
    /// Whether the last attempt was rejected (for the error estimate's second filter).
    rejected: bool,
}

impl<'o> Stepper<'o> {
    fn new(y0: &[f64], t0: f64, f0: Vec<f64>, opts: &'o OdeOptions) -> Self {
        let n = y0.len();
        let (rtol, atol) = (opts.rtol, opts.atol);
        Stepper {
            opts,
            n,
            t: t0,
            y: y0.to_vec(),
            f0,
            h: 0.0,
            rtol,
            atol,
            newton_tol: (10.0 * f64::EPSILON / rtol).max(0.03_f64.min(rtol.sqrt())),
            jac: DMatrix::zeros(n, n),
            need_jacobian: true,
            jacobian_fresh: false,
            factored: None,
            last: None,
            faccon: f64::EPSILON,
            accepted: None,
            rejected: false,
        }
    }

    /// The root-mean-square of `v` scaled by the tolerances at the current state.
    fn norm(&self, v: &[f64]) -> f64 {
        let sum: f64 = v.iter().zip(&self.y).map(|(vi, yi)| (vi / (self.atol + self.rtol * yi.abs())).powi(2)).sum();
        (sum / self.n.max(1) as f64).sqrt()
    }

    fn run<F, C>(
        &mut self,
        f: &mut F,
        mut jacobian: Option<&mut Jacobian<'_>>,
        times: &[f64],
        mut accept: C,
        mut stats: OdeStats,
    ) -> Result<OdeSolution, OdeError>
    where
        F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
        C: FnMut(f64, &[f64], f64, &[f64]) -> bool,
    {
        let (t_start, t_end) = (times[0], *times.last().expect("checked"));
        let mut states = Vec::with_capacity(times.len());
        let mut next = 0;
        while next < times.len() && times[next] <= self.t {
            states.push(self.y.clone());
            next += 1;
        }
        if self.t < t_end {
            self.h = self.initial_step(f, t_end, &mut stats);
        }
        let mut last_failure: Option<RhsError> = None;
        while self.t < t_end {
            if stats.accepted + stats.rejected >= self.opts.max_steps {
                return Err(OdeError::MaxSteps { t: self.t, steps: stats.accepted + stats.rejected });
            }
            if self.opts.deadline.is_some_and(|d| Instant::now() >= d) {
                return Err(OdeError::TimeLimit { t: self.t });
            }
            let h = self.bounded_step(times[next]);
            if h <= f64::EPSILON * (self.t.abs() + (t_end - t_start).abs()) {
                return Err(match last_failure {
                    Some(error) => OdeError::Rhs { t: self.t, error },
                    None => OdeError::StepTooSmall { t: self.t },
                });
            }
            self.h = h;
            if self.need_jacobian {
                self.update_jacobian(f, jacobian.as_deref_mut(), &mut stats).map_err(|error| OdeError::Rhs { t: self.t, error })?;
            }
            if self.factored.as_ref().is_none_or(|fa| fa.h != h) {
                stats.factorizations += 1;
                self.factored = Factored::new(&self.jac, h);
                if self.factored.is_none() {
                    // Singular at this step size: a smaller one shifts the spectrum.
                    self.reject(2.0, &mut stats);
                    continue;
                }
            }
            let step = match self.attempt(f, &mut stats) {
                Ok(step) => step,
                Err(Failure::Diverged(shrink)) => {
                    self.reject(shrink, &mut stats);
                    continue;
                }
                Err(Failure::Rhs(error)) => {
                    last_failure = Some(error);
                    self.reject(2.0, &mut stats);
                    continue;
                }
            };
            if step.error > 1.0 {
                let quot = self.quotient(step.error, step.iterations);
                self.reject(quot, &mut stats);
                continue;
            }
            // A step sized to reach the next requested time ends on it exactly: `t + (target
            // − t)` may fall an ulp short, and the next step would be that ulp, an underflow.
            let t_new = if h == times[next] - self.t { times[next] } else { self.t + h };
            let y_new: Vec<f64> = self.y.iter().zip(&step.z[2]).map(|(y, z)| y + z).collect();
            if !accept(self.t, &self.y, t_new, &y_new) {
                self.reject(2.0, &mut stats);
                continue;
            }
            let mut f_new = vec![0.0; self.n];
            if let Err(error) = evaluate(f, t_new, &y_new, &mut f_new, &mut stats) {
                last_failure = Some(error);
                self.reject(2.0, &mut stats);
                continue;
            }
            while next < times.len() && times[next] <= t_new {
                states.push(y_new.clone());
                next += 1;
            }
            stats.accepted += 1;
            stats.implicit_accepted += 1;
            last_failure = None;
            self.advance(t_new, y_new, f_new, step);
        }
        while next < times.len() {
            states.push(self.y.clone());
            next += 1;
        }
        Ok(OdeSolution { times: times.to_vec(), states, stats, method: METHOD, stopped: None })
    }

    /// The next step size, within `max_step`, ending exactly at the next requested time
    /// `target` when it is within reach.
    fn bounded_step(&self, target: f64) -> f64 {
        let remaining = target - self.t;
        let h = self.h.min(self.opts.max_step.unwrap_or(f64::INFINITY));
        // A last sliver below a hundredth of the step is taken into this one.
        if h >= remaining || remaining - h < 0.01 * h {
            remaining
        } else {
            h
        }
    }

    /// A first step size from the size of `f` and of its change along a small explicit
    /// step (Hairer's estimate for a method of order 5), at most a tenth of the span.
    fn initial_step<F>(&self, f: &mut F, t_end: f64, stats: &mut OdeStats) -> f64
    where
        F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
    {
        let span = t_end - self.t;
        if let Some(h) = self.opts.initial_step {
            return h.min(span);
        }
        let (d0, d1) = (self.norm(&self.y), self.norm(&self.f0));
        let h0 = if d0 < 1e-5 || d1 < 1e-5 { 1e-6 * span.max(1e-6) } else { (0.01 * d0 / d1).min(span) };
        let y1: Vec<f64> = self.y.iter().zip(&self.f0).map(|(y, f)| y + h0 * f).collect();
        let mut f1 = vec![0.0; self.n];
        if evaluate(f, self.t + h0, &y1, &mut f1, stats).is_err() {
            return h0;
        }
        let diff: Vec<f64> = f1.iter().zip(&self.f0).map(|(a, b)| a - b).collect();
        let d2 = self.norm(&diff) / h0;
        let h1 = if d1.max(d2) <= 1e-15 { (h0 * 1e-3).max(1e-6 * span) } else { (0.01 / d1.max(d2)).powf(1.0 / 6.0) };
        (100.0 * h0).min(h1).min(0.1 * span).max(1e-12 * span)
    }

    /// `J = ∂f/∂y` at the current state: the caller's, or forward differences.
    fn update_jacobian<F>(&mut self, f: &mut F, jacobian: Option<&mut Jacobian<'_>>, stats: &mut OdeStats) -> Result<(), RhsError>
    where
        F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
    {
        stats.jacobian_evals += 1;
        match jacobian {
            Some(jac) => {
                jac(self.t, &self.y, &mut self.jac)?;
                if self.jac.iter().any(|v| !v.is_finite()) {
                    return Err(RhsError(format!("the Jacobian at t = {} is not finite", self.t)));
                }
            }
            None => {
                let mut y = self.y.clone();
                let mut fy = vec![0.0; self.n];
                for j in 0..self.n {
                    let delta = (f64::EPSILON * self.y[j].abs().max(1e-5)).sqrt();
                    y[j] = self.y[j] + delta;
                    evaluate(f, self.t, &y, &mut fy, stats)?;
                    for i in 0..self.n {
                        self.jac[(i, j)] = (fy[i] - self.f0[i]) / delta;
                    }
                    y[j] = self.y[j];
                }
            }
        }
        self.need_jacobian = false;
        self.jacobian_fresh = true;
        self.factored = None;
        Ok(())
    }

    /// Solve the stage equations of a step of size `self.h` by the simplified Newton
    /// iteration and estimate the step's error.
    fn attempt<F>(&mut self, f: &mut F, stats: &mut OdeStats) -> Result<Step, Failure>
    where
        F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
    {
        let (n, h) = (self.n, self.h);
        let mut z = self.starting_values();
        let mut w = transform(&T_INV, &z);
        self.faccon = self.faccon.max(f64::EPSILON).powf(0.8);
        let (mut contraction, mut last_norm) = (KEEP_JACOBIAN, 0.0);
        let mut stage_f = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        let mut y_stage = vec![0.0; n];
        for k in 0..MAX_NEWTON {
            for (i, fi) in stage_f.iter_mut().enumerate() {
                y_stage.iter_mut().zip(&self.y).zip(&z[i]).for_each(|((ys, y), zi)| *ys = y + zi);
                evaluate(f, self.t + C[i] * h, &y_stage, fi, stats).map_err(Failure::Rhs)?;
            }
            let tf = transform(&T_INV, &stage_f);
            let mut dw = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
            for j in 0..n {
                dw[0][j] = tf[0][j] - GAMMA / h * w[0][j];
                dw[1][j] = tf[1][j] - (ALPHA * w[1][j] + BETA * w[2][j]) / h;
                dw[2][j] = tf[2][j] - (-BETA * w[1][j] + ALPHA * w[2][j]) / h;
            }
            let factored = self.factored.as_ref().expect("factored before the attempt");
            factored.solve_real(&mut dw[0]);
            let [_, dw1, dw2] = &mut dw;
            factored.solve_complex(dw1, dw2);
            let step_norm = (dw.iter().map(|d| self.norm(d).powi(2)).sum::<f64>() / 3.0).sqrt();
            if !step_norm.is_finite() {
                return Err(Failure::Diverged(2.0));
            }
            if k > 0 {
                contraction = step_norm / last_norm;
                if contraction >= 0.99 {
                    return Err(Failure::Diverged(2.0));
                }
                self.faccon = contraction / (1.0 - contraction);
                // Predicted not to converge within the iterations left: give up early.
                let predicted = self.faccon * step_norm * contraction.powi((MAX_NEWTON - 1 - k) as i32) / self.newton_tol;
                if predicted >= 1.0 {
                    let q = predicted.clamp(1e-4, 20.0);
                    return Err(Failure::Diverged(1.0 / (0.8 * q.powf(-1.0 / (4 + MAX_NEWTON - 1 - k) as f64))));
                }
            }
            last_norm = step_norm;
            for (wi, di) in w.iter_mut().zip(&dw) {
                wi.iter_mut().zip(di).for_each(|(a, b)| *a += b);
            }
            z = transform(&T, &w);
            if self.faccon * step_norm <= self.newton_tol {
                let error = self.error(f, &z, stats).map_err(Failure::Rhs)?;
                return Ok(Step { z, error, iterations: k + 1, contraction });
            }
        }
        Err(Failure::Diverged(2.0))
    }

    /// The scaled error of a step with stages `z`: the embedded formula filtered by
    /// `(γ/h − J)⁻¹` (module docs), filtered once more after a rejection or on the first
    /// step when it exceeds 1 (the first filter alone can overestimate it for stiff
    /// components).
    fn error<F>(&self, f: &mut F, z: &[Vec<f64>; 3], stats: &mut OdeStats) -> Result<f64, RhsError>
    where
        F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
    {
        let factored = self.factored.as_ref().expect("factored");
        let h = self.h;
        let weighted: Vec<f64> = (0..self.n).map(|j| (0..3).map(|i| ERROR_WEIGHTS[i] * z[i][j]).sum::<f64>() / h).collect();
        let mut e: Vec<f64> = self.f0.iter().zip(&weighted).map(|(a, b)| a + b).collect();
        factored.solve_real(&mut e);
        let mut error = self.norm(&e).max(1e-10);
        if error >= 1.0 && (self.accepted.is_none() || self.rejected) {
            let y: Vec<f64> = self.y.iter().zip(&e).map(|(a, b)| a + b).collect();
            let mut fe = vec![0.0; self.n];
            evaluate(f, self.t, &y, &mut fe, stats)?;
            let mut e2: Vec<f64> = fe.iter().zip(&weighted).map(|(a, b)| a + b).collect();
            factored.solve_real(&mut e2);
            error = self.norm(&e2).max(1e-10);
        }
        Ok(error)
    }

    /// The starting values of the stages: the last step's collocation polynomial
    /// extrapolated over this one, or zero on the first step.
    fn starting_values(&self) -> [Vec<f64>; 3] {
        let n = self.n;
        match &self.last {
            None => [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
            Some((z, h_last)) => {
                let r = self.h / h_last;
                let end = collocation(z, 1.0);
                C.map(|c| collocation(z, 1.0 + c * r).iter().zip(&end).map(|(a, b)| a - b).collect())
            }
        }
    }

    /// Take the accepted step to `(t_new, y_new)`, and choose the next step size and
    /// whether to keep the Jacobian and its factorizations.
    fn advance(&mut self, t_new: f64, y_new: Vec<f64>, f_new: Vec<f64>, step: Step) {
        let h = self.h;
        let mut quot = self.quotient(step.error, step.iterations);
        if let Some((h_acc, err_acc)) = self.accepted {
            // Gustafsson's predictive controller.
            let predictive = (h_acc / h) * (step.error * step.error / err_acc).powf(0.25) / SAFETY;
            quot = quot.max(predictive.clamp(1.0 / MAX_GROWTH, MAX_SHRINK));
        }
        self.accepted = Some((h, step.error.max(1e-2)));
        (self.t, self.y, self.f0) = (t_new, y_new, f_new);
        self.last = Some((step.z, h));
        self.rejected = false;
        self.jacobian_fresh = false;
        // A fast iteration keeps the Jacobian; a step size within a small band keeps the
        // factorizations too.
        self.need_jacobian = step.contraction > KEEP_JACOBIAN;
        let ratio = 1.0 / quot;
        if !self.need_jacobian && (KEEP_STEP.0..=KEEP_STEP.1).contains(&ratio) {
            return;
        }
        self.h = h / quot;
    }

    /// The quotient `h / h_new` after a step of scaled error `error` that took
    /// `iterations` Newton iterations (fewer iterations allow a bolder step).
    fn quotient(&self, error: f64, iterations: usize) -> f64 {
        let fac = SAFETY.min(SAFETY * (1 + 2 * MAX_NEWTON) as f64 / (iterations + 2 * MAX_NEWTON) as f64);
        (error.powf(0.25) / fac).clamp(1.0 / MAX_GROWTH, MAX_SHRINK)
    }

    /// Reject the attempt: shrink the step by `factor` (at least a little), count it, and
    /// ask for a new Jacobian unless the one in hand is at the current state.
    fn reject(&mut self, factor: f64, stats: &mut OdeStats) {
        stats.rejected += 1;
        self.rejected = true;
        let factor = if self.accepted.is_none() && factor > 1.0 { factor.max(10.0) } else { factor };
        self.h /= factor.max(1.0 + 1e-3);
        self.need_jacobian = !self.jacobian_fresh;
    }
}

/// `M v` for the 3 × 3 matrix `M` acting on stage vectors.
fn transform(m: &[[f64; 3]; 3], v: &[Vec<f64>; 3]) -> [Vec<f64>; 3] {
    let n = v[0].len();
    std::array::from_fn(|i| (0..n).map(|j| m[i][0] * v[0][j] + m[i][1] * v[1][j] + m[i][2] * v[2][j]).collect())
}

/// The collocation polynomial of a step with stages `z` at the fraction `s` of the step
/// (0 at its start, `z_i` at `c_i`), relative to the step's initial state: the cubic in
/// Newton's form on the nodes `0, c₁, c₂, 1`.
fn collocation(z: &[Vec<f64>; 3], s: f64) -> Vec<f64> {
    let (c1, c2) = (C[0], C[1]);
    (0..z[0].len())
        .map(|j| {
            let d1 = z[0][j] / c1;
            let d2 = (z[1][j] - z[0][j]) / (c2 - c1);
            let d3 = (z[2][j] - z[1][j]) / (1.0 - c2);
            let dd1 = (d2 - d1) / c2;
            let dd2 = (d3 - d2) / (1.0 - c1);
            let ddd = dd2 - dd1;
            s * (d1 + (s - c1) * (dd1 + (s - c2) * ddd))
        })
        .collect()
}
