//! Adaptive high-order time stepping with output at requested times.
//!
//! Used (a) to build a physical initial guess for the global-in-time Newton solve and
//! (b) as the tight-tolerance reference integrator of the Lagrange–d'Alembert equations.
//!
//! # Method
//! [`integrate`] is an explicit Runge–Kutta method of order 8 with embedded 5th- and
//! 3rd-order error estimators and a 7th-order continuous extension: DOP853 of
//! E. Hairer, S. P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*,
//! 2nd ed., Springer (1993), Sec. II.10, following the structure of Hairer's Fortran code
//! `dop853.f` (step-size control with safety factor 0.9, step ratio limited to [1/3, 6],
//! the combined 5th/3rd-order error norm, the automatic initial step of `hinit`, and the
//! dense output `contd8`). Requested sample times inside a step are filled from the dense
//! output (three extra right-hand-side evaluations in a step that contains one); the final
//! time is hit exactly by the last step.
//!
//! This module holds the options, the errors, the step-size control and the requested
//! times; one step of the method (its stages, error estimate, dense output and event
//! location) is `stepper.rs`, its coefficients `tableau.rs`, its tests `tests.rs`.
//!
//! # Why not a crate
//! The two maintained Rust crates with DOP853 were evaluated (`cargo info`, their sources):
//! * `ode_solvers` 0.6: the right-hand side is `fn system(&self, x, &y, &mut dy)` with no
//!   way to report an error; output only at a fixed spacing `dx` or at the solver's own
//!   steps; it depends on nalgebra 0.34 (this crate uses 0.33, so two nalgebras would be
//!   built).
//! * `differential-equations` 0.7: the right-hand side is `fn diff(&self, t, &y, &mut dy)`,
//!   again without an error path; the crate is edition 2024 (Rust ≥ 1.85, this crate
//!   declares 1.80) and brings a large dependency tree.
//!
//! Re-checked when the references needed event location: `differential-equations` 0.7 builds
//! here (rustc 1.95, 17 s) and has dense output and Brent event location, but its
//! right-hand side is still infallible (`diff(&self, …)`, so our model's workspace would
//! need a `RefCell` and failures a NaN convention), and it pulls simba 0.10 beside this
//! crate's nalgebra 0.33 / simba 0.9. Event location ([`integrate_to_event`]) was the only
//! missing piece and is ~40 lines on top of the dense output below, so one integrator
//! (this one) serves the initial guess, the regularized and the hard-wall references.
//!
//! A failing right-hand side (e.g. a singular mass matrix) must come back as an error, not
//! a panic or a silently wrong NaN; threading that through either crate would need interior
//! mutability plus NaN poisoning of the state, whose handling by the step-size controller
//! is unspecified. The method itself is ~200 lines, so it is implemented here.
//!
//! # Failures of the right-hand side
//! `f` may return `Err(RhsError)`, and a non-finite derivative counts as a failure too. A
//! failure at the very first evaluation (the initial state) is returned at once as
//! [`OdeError::Rhs`]. A failure in a trial stage of a step rejects the step and retries it
//! with half the step size (a trial stage may leave the region where `f` is defined while
//! the true solution does not); once the step size has shrunk below the round-off limit
//! the last failure is returned as [`OdeError::Rhs`], whose `t` is then the time where the
//! right-hand side stops being defined along the solution (to about `1e-14` relative).

mod stepper;
mod tableau;

pub use crate::scene::Stepper;
use std::time::Instant;

use stepper::{Dop853, Rejection, Stage};

/// Name of the method reported in [`OdeSolution::method`].
pub const METHOD: &str = "DOP853 (Hairer-Norsett-Wanner 8(5,3) with 7th-order dense output; built-in implementation)";

/// Options of [`integrate`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct OdeOptions {
    /// Relative tolerance (per component, scaled by `max(|y_old|, |y_new|)`). Default `1e-10`.
    pub rtol: f64,
    /// Absolute tolerance (per component). Default `1e-12`.
    pub atol: f64,
    /// Maximum number of step attempts (accepted + rejected). Default `1_000_000`.
    pub max_steps: usize,
    /// First trial step; `None` picks one automatically (Hairer's `hinit`).
    pub initial_step: Option<f64>,
    /// Largest step. An error estimate cannot see a force it steps over: in free flight
    /// (a parabola, integrated exactly) the step grows until it jumps across a thin
    /// Gaussian wall. Callers that sample on a grid cap the step at the grid spacing.
    pub max_step: Option<f64>,
    /// Which integrator steps ([`Stepper`]), for
    /// [`integrate_with`](super::integrate::integrate_with), which chooses by it; the
    /// DOP853 functions of this module step with DOP853 whatever it says. Default `Auto`.
    pub stepper: Stepper,
    /// When to give up, if ever ([`OdeError::TimeLimit`]): checked before every step, by
    /// both integrators. Default `None`. Not part of the options' record (a moment of
    /// this process).
    #[serde(skip)]
    pub deadline: Option<Instant>,
}

impl Default for OdeOptions {
    fn default() -> Self {
        OdeOptions {
            rtol: 1e-10,
            atol: 1e-12,
            max_steps: 1_000_000,
            initial_step: None,
            max_step: None,
            stepper: Stepper::Auto,
            deadline: None,
        }
    }
}

/// Work statistics of one [`integrate`] call.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct OdeStats {
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected steps (error too large, or a failing right-hand side in a trial stage).
    pub rejected: usize,
    /// Evaluations of the right-hand side, failed ones included.
    pub rhs_evals: usize,
    /// Evaluations of the Jacobian `∂f/∂y` (implicit stepping only; forward differences
    /// count their right-hand sides in `rhs_evals` too).
    pub jacobian_evals: usize,
    /// LU factorizations of the implicit stepping's iteration matrices (one real and one
    /// complex each).
    pub factorizations: usize,
    /// Of the accepted steps, those of the implicit stepping (Radau IIA).
    pub implicit_accepted: usize,
}

impl OdeStats {
    /// Add another integration's counts (the pieces of one time stepping, or the time
    /// steppings of one solve).
    pub fn add(&mut self, other: &OdeStats) {
        self.accepted += other.accepted;
        self.rejected += other.rejected;
        self.rhs_evals += other.rhs_evals;
        self.jacobian_evals += other.jacobian_evals;
        self.factorizations += other.factorizations;
        self.implicit_accepted += other.implicit_accepted;
    }
}

/// Why the right-hand side `f(t, y)` could not be evaluated: the caller's message (e.g.
/// "the constrained mass matrix is singular"), or a non-finite derivative.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct RhsError(pub String);

impl From<&str> for RhsError {
    fn from(message: &str) -> Self {
        RhsError(message.to_string())
    }
}

impl From<String> for RhsError {
    fn from(message: String) -> Self {
        RhsError(message)
    }
}

/// Failure of [`integrate`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OdeError {
    /// The right-hand side returned an error (or a non-finite value) at time `t`, and
    /// shrinking the step did not get past it.
    #[error("the right-hand side failed at t = {t}: {error}")]
    Rhs {
        /// Where the right-hand side failed.
        t: f64,
        /// Why.
        error: RhsError,
    },
    /// The step size fell below the round-off limit at time `t` (stiffness or a
    /// singularity of the solution).
    #[error("step size underflow at t = {t}")]
    StepTooSmall {
        /// Where the step size underflowed.
        t: f64,
    },
    /// `max_steps` step attempts were used up at time `t`.
    #[error("maximum number of steps ({steps}) reached at t = {t}")]
    MaxSteps {
        /// Where the integration stopped.
        t: f64,
        /// The step attempts made.
        steps: usize,
    },
    /// The deadline ([`OdeOptions::deadline`]) was reached at time `t`.
    #[error("stopped at the time limit at t = {t}")]
    TimeLimit {
        /// Where the integration stopped.
        t: f64,
    },
    /// Invalid arguments (times, initial state, options).
    #[error("bad input: {0}")]
    BadInput(String),
}

/// Result of [`integrate`]: the state at every requested time.
#[derive(Debug, Clone, PartialEq)]
pub struct OdeSolution {
    /// The requested times (a copy of the `times` argument).
    pub times: Vec<f64>,
    /// `states[i]` is the state at `times[i]`.
    pub states: Vec<Vec<f64>>,
    /// Work statistics.
    pub stats: OdeStats,
    /// The method used ([`METHOD`], or [`radau::METHOD`](super::radau::METHOD)).
    pub method: &'static str,
    /// Where DOP853 stopped before the end ([`integrate_until_stiff`] only): `states`
    /// holds the requested times before it, and the integration is to go on implicitly
    /// from it.
    pub stopped: Option<Stopped>,
}

/// Where and why DOP853 stopped before the end ([`integrate_until_stiff`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Stopped {
    /// The time of the last accepted state.
    pub t: f64,
    /// That state.
    pub y: Vec<f64>,
    /// Why, in words ("stiff: h·λ = 12.3 in 15 steps in a row", "the steps ran out").
    pub reason: String,
}

/// Integrate `y' = f(t, y)` from `times[0]` with `y(times[0]) = y0` and return the state
/// at every requested time.
///
/// `times` must be finite and sorted ascending (repeated values are allowed); the first
/// entry is the start time and the last one the end time, which the integration hits
/// exactly. Intermediate times are filled from the 7th-order dense output, so requesting
/// many of them costs little. `f(t, y, dy)` writes the derivative into `dy` (zero-filled
/// before each call) and may fail with an [`RhsError`]; see the module documentation for
/// how failures are handled.
pub fn integrate<F>(f: F, y0: &[f64], times: &[f64], opts: &OdeOptions) -> Result<OdeSolution, OdeError>
where
    F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
{
    integrate_checked(f, y0, times, opts, |_, _, _, _| true)
}

/// Like [`integrate`], with a test every step must pass besides the error estimate:
/// `accept(t, y, t_new, y_new)` returning false rejects the step from `(t, y)` to
/// `(t_new, y_new)`, which is retried at half the size (down to the round-off limit:
/// [`OdeError::StepTooSmall`]). The error estimate alone cannot see a feature that no
/// stage of a step samples, such as a Gaussian wall far thinner than the step, which the
/// solution would then cross unhindered; `accept` can (the time stepping of a model with
/// walls checks that no step jumps across a wall).
pub fn integrate_checked<F, C>(f: F, y0: &[f64], times: &[f64], opts: &OdeOptions, accept: C) -> Result<OdeSolution, OdeError>
where
    F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
    C: FnMut(f64, &[f64], f64, &[f64]) -> bool,
{
    run(f, y0, times, opts, None::<fn(f64, &[f64]) -> f64>, accept, false).map(|(sol, _)| sol)
}

/// Like [`integrate_checked`], but where the problem has become stiff (Hairer's test of
/// `h·λ`, module `stepper`), or the steps run out or underflow, the integration stops
/// instead of failing and says where and why ([`OdeSolution::stopped`]), for an
/// implicit stepper to go on from there ([`integrate_with`](super::integrate::integrate_with)).
pub fn integrate_until_stiff<F, C>(f: F, y0: &[f64], times: &[f64], opts: &OdeOptions, accept: C) -> Result<OdeSolution, OdeError>
where
    F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
    C: FnMut(f64, &[f64], f64, &[f64]) -> bool,
{
    run(f, y0, times, opts, None::<fn(f64, &[f64]) -> f64>, accept, true).map(|(sol, _)| sol)
}

/// A terminal event located by [`integrate_to_event`].
#[derive(Debug, Clone, PartialEq)]
pub struct EventHit {
    /// Time of the zero crossing.
    pub t: f64,
    /// State at `t` (from the dense output).
    pub y: Vec<f64>,
}

/// Like [`integrate`], but stops at the first time where `event(t, y)` crosses zero
/// upwards (from `< 0` to `≥ 0`).
///
/// The event function is evaluated at the end of every accepted step and at three
/// interior points of it (on the 7th-order dense output, so an excursion that goes out
/// and back within one step is caught if it lasts longer than about a quarter of the
/// step; shorter grazes can be missed); a sign change is bracketed and
/// the crossing located by bisection on the dense output down to a bracket of a few
/// units in the last place of `t`. The crossing is then as accurate as the dense output
/// (for a transversal crossing, the time error is about the position error divided by
/// the crossing speed). A crossing at the very start (event value `≥ 0` at `times[0]`)
/// is not reported.
///
/// Returns the states at the requested times before the event (`states.len()` may be
/// shorter than `times.len()`) and the event, or every requested state and `None` if
/// no crossing happens before the last time.
pub fn integrate_to_event<F, E>(
    f: F,
    y0: &[f64],
    times: &[f64],
    opts: &OdeOptions,
    event: E,
) -> Result<(OdeSolution, Option<EventHit>), OdeError>
where
    F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
    E: FnMut(f64, &[f64]) -> f64,
{
    run(f, y0, times, opts, Some(event), |_, _, _, _| true, false)
}

/// The integration behind [`integrate`], [`integrate_checked`] and
/// [`integrate_to_event`]: attempts of steps ([`Dop853::attempt`]) under Hairer's
/// step-size control ([`Controller`]), the requested times filled from each accepted
/// step, and the integration stopped at the first crossing of `event`
/// ([`Dop853::first_crossing`]), or, when `until_stiff`, where the problem has become
/// stiff or the steps run out or underflow.
fn run<F, E, C>(
    f: F,
    y0: &[f64],
    times: &[f64],
    opts: &OdeOptions,
    mut event: Option<E>,
    mut accept: C,
    until_stiff: bool,
) -> Result<(OdeSolution, Option<EventHit>), OdeError>
where
    F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
    E: FnMut(f64, &[f64]) -> f64,
    C: FnMut(f64, &[f64], f64, &[f64]) -> bool,
{
    validate(y0, times, opts)?;
    let t0 = times[0];
    let t_end = times[times.len() - 1];
    let mut samples = Samples::new(times, y0);
    if samples.done() || y0.is_empty() {
        // Nothing to integrate: no time span, or an empty state.
        return Ok((samples.constant(y0), None));
    }

    let mut s = Dop853::new(f, y0, opts);
    let mut t = t0;
    s.eval(t, Stage::Y, 0).map_err(|error| OdeError::Rhs { t, error })?;
    let mut control = Controller::new(&mut s, t0, t_end, opts);
    let mut stiffness = until_stiff.then(Stiffness::default);
    loop {
        let (h, t_new) = match control.next_step(t) {
            Ok(step) => step,
            Err(e @ (OdeError::MaxSteps { .. } | OdeError::StepTooSmall { .. })) if stiffness.is_some() => {
                let reason = e.to_string();
                return Ok((samples.stopped(s.stats, Stopped { t, y: s.state().to_vec(), reason }), None));
            }
            Err(e) => return Err(e),
        };
        // The dense output is needed when a requested time or the event's samples lie inside.
        let dense_wanted = samples.next_time() < t_new || event.is_some();
        let fac11 = match s.attempt(t, h, t_new, dense_wanted, &mut accept) {
            Ok(fac11) => fac11,
            Err(rejection) => {
                s.stats.rejected += 1;
                control.rejected(rejection);
                continue;
            }
        };
        s.stats.accepted += 1;
        if let Some(hit) = event.as_mut().and_then(|ev| s.first_crossing(ev, t, h, t_new)) {
            samples.fill(&s, (t, h, t_new), |ts| ts < hit.t);
            return Ok((samples.solution(s.stats), Some(hit)));
        }
        samples.fill(&s, (t, h, t_new), |ts| ts <= t_new);
        s.commit();
        t = t_new;
        if samples.done() {
            break;
        }
        if let Some(reason) = stiffness.as_mut().and_then(|st| st.after_step(s.h_lambda)) {
            return Ok((samples.stopped(s.stats, Stopped { t, y: s.state().to_vec(), reason }), None));
        }
        control.accepted(fac11);
    }
    Ok((samples.solution(s.stats), None))
}

/// The requested times of [`run`] and the states found for them so far, in order.
struct Samples<'a> {
    /// The requested times.
    times: &'a [f64],
    /// The states at `times[..states.len()]`.
    states: Vec<Vec<f64>>,
}

impl<'a> Samples<'a> {
    /// The start state at every requested time equal to the start time.
    fn new(times: &'a [f64], y0: &[f64]) -> Samples<'a> {
        let mut states = Vec::with_capacity(times.len());
        states.resize(times.iter().take_while(|&&t| t == times[0]).count(), y0.to_vec());
        Samples { times, states }
    }

    /// Whether every requested time has its state.
    fn done(&self) -> bool {
        self.states.len() == self.times.len()
    }

    /// The first requested time without its state.
    fn next_time(&self) -> f64 {
        self.times[self.states.len()]
    }

    /// Push the states at the next requested times that the accepted step `(t, h,
    /// t_new)` of `s` covers and `wanted` admits (the first one not admitted ends it):
    /// the new state at its end, the dense output inside.
    fn fill<F>(&mut self, s: &Dop853<F>, (t, h, t_new): (f64, f64, f64), wanted: impl Fn(f64) -> bool)
    where
        F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
    {
        while !self.done() && wanted(self.next_time()) {
            let ts = self.next_time();
            self.states.push(if ts == t_new { s.ynew.clone() } else { s.dense((ts - t) / h) });
        }
    }

    /// The solution of a state that does not change: `y0` at every requested time.
    fn constant(mut self, y0: &[f64]) -> OdeSolution {
        self.states.resize(self.times.len(), y0.to_vec());
        self.solution(OdeStats::default())
    }

    /// The solution at the times filled so far, with the integration's statistics.
    fn solution(self, stats: OdeStats) -> OdeSolution {
        OdeSolution { times: self.times.to_vec(), states: self.states, stats, method: METHOD, stopped: None }
    }

    /// The solution at the times filled so far of an integration that stopped before
    /// the end ([`integrate_until_stiff`]).
    fn stopped(self, stats: OdeStats, stopped: Stopped) -> OdeSolution {
        OdeSolution { stopped: Some(stopped), ..self.solution(stats) }
    }
}

/// `h·λ` above which a DOP853 step is taken as limited by stability (its stability region
/// reaches about 6.1 along the negative real axis).
const STIFF_H_LAMBDA: f64 = 6.1;
/// Steps in a row at [`STIFF_H_LAMBDA`] that make an equation stiff.
const STIFF_STEPS: usize = 15;
/// Steps in a row below it that clear the count.
const NONSTIFF_STEPS: usize = 6;

/// Hairer's stiffness test of DOP853 (`dop853.f`), after every accepted step: stiff once
/// [`STIFF_STEPS`] steps in a row had `h·λ` above [`STIFF_H_LAMBDA`], the count cleared
/// by [`NONSTIFF_STEPS`] steps in a row below it.
#[derive(Default)]
struct Stiffness {
    stiff: usize,
    nonstiff: usize,
}

impl Stiffness {
    /// Count a step with `h_lambda`; the reason to stop when the equation is stiff.
    fn after_step(&mut self, h_lambda: f64) -> Option<String> {
        if h_lambda > STIFF_H_LAMBDA {
            self.nonstiff = 0;
            self.stiff += 1;
            if self.stiff >= STIFF_STEPS {
                return Some(format!(
                    "stiff: the steps were limited by stability (h·λ = {h_lambda:.1} > {STIFF_H_LAMBDA} in {STIFF_STEPS} steps in a row)"
                ));
            }
        } else {
            self.nonstiff += 1;
            if self.nonstiff >= NONSTIFF_STEPS {
                self.stiff = 0;
            }
        }
        None
    }
}

/// Hairer's step-size control between the attempts of [`run`]: the next step's size,
/// shrunk after a rejection and grown after an acceptance, and when to give up.
struct Controller {
    /// The size of the next attempt.
    h: f64,
    /// The largest step: the option, at most the span.
    hmax: f64,
    /// The end of the integration, which the last step hits exactly.
    t_end: f64,
    /// The most attempts allowed.
    max_steps: usize,
    /// When to give up, if ever.
    deadline: Option<Instant>,
    /// The attempts made.
    attempts: usize,
    /// Whether the last attempt was rejected (the next step may then not grow).
    after_rejection: bool,
    /// The failure of the right-hand side since the last accepted step, reported if the
    /// step shrinks to nothing.
    last_failure: Option<(f64, RhsError)>,
}

impl Controller {
    /// The control of an integration from `t0` to `t_end` of the stepper `s` (which
    /// holds `k[0] = f(t0, y0)`), starting with the option's initial step or `hinit`'s.
    fn new<F>(s: &mut Dop853<F>, t0: f64, t_end: f64, opts: &OdeOptions) -> Controller
    where
        F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
    {
        let hmax = opts.max_step.unwrap_or(f64::INFINITY).min(t_end - t0);
        let h = match opts.initial_step {
            Some(h0) => h0.min(hmax),
            None => s.hinit(t0, hmax),
        };
        Controller {
            h,
            hmax,
            t_end,
            max_steps: opts.max_steps,
            deadline: opts.deadline,
            attempts: 0,
            after_rejection: false,
            last_failure: None,
        }
    }

    /// The size and end time of the next attempt from `t` (the last step stretched or
    /// shrunk to end at `t_end`), or why there is none: the attempts are used up, or the
    /// step has shrunk below the round-off limit (the last failure of the right-hand
    /// side, if any, is the reason).
    fn next_step(&mut self, t: f64) -> Result<(f64, f64), OdeError> {
        if self.attempts >= self.max_steps {
            return Err(OdeError::MaxSteps { t, steps: self.attempts });
        }
        if self.deadline.is_some_and(|d| Instant::now() >= d) {
            return Err(OdeError::TimeLimit { t });
        }
        let hmin = 10.0 * f64::EPSILON * t.abs().max(self.t_end.abs());
        if self.h.is_nan() || self.h <= hmin {
            return Err(match self.last_failure.take() {
                Some((t, error)) => OdeError::Rhs { t, error },
                None => OdeError::StepTooSmall { t },
            });
        }
        let last = t + 1.01 * self.h >= self.t_end;
        if last {
            self.h = self.t_end - t;
        }
        self.attempts += 1;
        Ok((self.h, if last { self.t_end } else { t + self.h }))
    }

    /// After a rejected attempt: half the step after a failure or a refusal, or the step
    /// the error estimate asks for (shrinking by at most 3).
    fn rejected(&mut self, rejection: Rejection) {
        match rejection {
            Rejection::Failed(failure) => {
                self.last_failure = Some(failure);
                self.h *= 0.5;
            }
            Rejection::Refused => self.h *= 0.5,
            Rejection::TooLarge { fac11 } => self.h /= FAC_MAX.min(fac11 / SAFE),
        }
        self.after_rejection = true;
    }

    /// After an accepted step whose error gave `fac11` (`err^(1/8)`): the next step,
    /// changed by a factor in [1/3, 6], at most `hmax`, and not larger right after a
    /// rejection.
    fn accepted(&mut self, fac11: f64) {
        self.last_failure = None;
        let fac = (fac11 / SAFE).clamp(FAC_MIN, FAC_MAX);
        let mut hnew = (self.h / fac).min(self.hmax);
        if self.after_rejection {
            hnew = hnew.min(self.h);
        }
        self.after_rejection = false;
        self.h = hnew;
    }
}

/// Safety factor of the step-size controller.
const SAFE: f64 = 0.9;
/// Largest step reduction factor `h_old / h_new` (step may shrink to 1/3).
const FAC_MAX: f64 = 1.0 / 0.333;
/// Smallest `h_old / h_new` (step may grow by 6).
const FAC_MIN: f64 = 1.0 / 6.0;

fn validate(y0: &[f64], times: &[f64], opts: &OdeOptions) -> Result<(), OdeError> {
    let bad = |m: String| Err(OdeError::BadInput(m));
    if times.is_empty() {
        return bad("no output times given (the first one is the start time)".into());
    }
    if let Some(i) = times.iter().position(|t| !t.is_finite()) {
        return bad(format!("output time {i} is not finite ({})", times[i]));
    }
    if let Some(i) = times.windows(2).position(|w| w[1] < w[0]) {
        return bad(format!("output times must be sorted ascending: times[{}] = {} > times[{}] = {}", i, times[i], i + 1, times[i + 1]));
    }
    if let Some(i) = y0.iter().position(|y| !y.is_finite()) {
        return bad(format!("initial state component {i} is not finite ({})", y0[i]));
    }
    if !(opts.rtol.is_finite() && opts.rtol >= 0.0 && opts.atol.is_finite() && opts.atol >= 0.0) {
        return bad(format!("tolerances must be finite and non-negative (rtol = {}, atol = {})", opts.rtol, opts.atol));
    }
    if opts.rtol == 0.0 && opts.atol == 0.0 {
        return bad("rtol and atol are both zero".into());
    }
    if let Some(h0) = opts.initial_step {
        if !(h0.is_finite() && h0 > 0.0) {
            return bad(format!("initial step must be finite and positive, got {h0}"));
        }
    }
    if let Some(hm) = opts.max_step {
        if !(hm.is_finite() && hm > 0.0) {
            return bad(format!("maximum step must be finite and positive, got {hm}"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
