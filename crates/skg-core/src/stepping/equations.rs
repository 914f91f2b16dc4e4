//! Time stepping of the Lagrange–d'Alembert equations of a model, independent of the SBP
//! discretization: used for the verification of a solve, for the reference solutions
//! and, by its callers, for initial guesses.
//!
//! The equations are integrated index-reduced: at each state (t, q, v) the accelerations
//! and multipliers solve `[W Gᵀ; G 0] [q̈; λ] = [f + F − (∂p/∂q) v − ∂p/∂t; −(∂g/∂q) v − ∂g/∂t]`
//! ([`Model::accelerations`]), and the state `y = (q, v)` is advanced by the stepper the
//! options name ([`integrate_with`]: DOP853, Radau IIA, or DOP853 until the equations
//! turn out stiff and Radau IIA from there) and sampled at the requested times. Times are
//! absolute: the model is evaluated at the integrator's time, so an explicitly
//! time-dependent scene can be integrated from any start time. The implicit stepper gets
//! the exact Jacobian of the right-hand side from the model ([`Model::state_jacobian`]:
//! the saddle-point solve differentiated), not forward differences. The constraints `g = 0`
//! (and a position constraint's `h = 0`) then hold only up to the integrator's drift.
//!
//! Regularized walls bound every step ([`wall_step_accepted`]): a step may change a
//! wall's gap by at most half of its distance from the wall plus the wall's width. The
//! error estimate of a step sees only what its stages sample, so without this bound a
//! wall much thinner than the step (σ = 1e-5 at 1 m/s on a grid of 64 nodes) would be
//! crossed unhindered by the verification and the guess alike, and a solve that never
//! bounced would be verified against a reference that did not bounce either.

use nalgebra::DMatrix;

use crate::discrete::trajectory::States;
use crate::model::{DynamicsError, Model, WallModel, Workspace};
use crate::stepping::integrate::integrate_with;
use crate::stepping::ode::{OdeError, OdeOptions, OdeStats, RhsError};

/// Step attempts per node allowed to the time stepping of the initial guess and of the
/// verification ([`step_budget`]). On the shipped scenes these take one to two steps per
/// node (the step is capped at the node spacing where it matters); a motion that needs
/// a hundred per node is far finer than the grid can represent.
pub const STEPS_PER_NODE: usize = 100;

/// The step budget of a grid is at least this many attempts, whatever its node count.
pub const MIN_STEPS: usize = 100_000;

/// The step attempts allowed to a time stepping sampled at `nodes` nodes: it bounds the
/// cost of the guess and the verification by the grid's size (a scene whose time span
/// dwarfs its motion, e.g. a span of 10⁹ periods, would otherwise take seconds per
/// attempt of the fallback ladder and still fail).
pub fn step_budget(nodes: usize) -> usize {
    STEPS_PER_NODE.saturating_mul(nodes).max(MIN_STEPS)
}

/// The mean spacing of increasing node times (None for fewer than two): the longest step
/// a time stepping sampled at a grid's nodes takes. On a uniform grid it is the spacing;
/// on an adaptive one the short spacings are where the motion is fast, where the
/// stepper's own error control shortens its steps (and, near a wall, its test of the
/// gap, [`wall_step_accepted`]): bounding every step by the shortest spacing would make
/// it take that step over the whole span.
pub fn mean_spacing(times: &[f64]) -> Option<f64> {
    (times.len() >= 2).then(|| (times[times.len() - 1] - times[0]) / (times.len() - 1) as f64).filter(|d| *d > 0.0)
}

/// Smallest spacing of increasing sample times (None for fewer than two samples).
pub fn min_spacing(times: &[f64]) -> Option<f64> {
    times.windows(2).map(|w| w[1] - w[0]).filter(|d| *d > 0.0).reduce(f64::min)
}

/// What a time stepping found at the requested times, its work and what ran.
#[derive(Debug, Clone)]
pub struct Stepped<S> {
    /// The states at the requested times.
    pub states: S,
    /// The steppers' work.
    pub stats: OdeStats,
    /// The method that ran, in words (both, when the automatic choice went on
    /// implicitly).
    pub method: String,
}

/// Integrate the index-reduced Lagrange–d'Alembert equations of `model` from the state
/// `(q0, v0)` at the absolute time `times[0]` and sample `(q, v, λ)` at `times`
/// (increasing).
pub fn integrate_model(model: &Model, q0: &[f64], v0: &[f64], times: &[f64], opts: &OdeOptions) -> Result<Stepped<States>, OdeError> {
    let Stepped { states, stats, method } = integrate_states(model, q0, v0, times, opts)?;
    Ok(Stepped { states: split_states(model, &states, times, &mut model.workspace())?, stats, method })
}

/// [`integrate_model`] without the multipliers: the integrator's states `(q, v)` at
/// `times`, one vector of `2d` numbers each.
pub fn integrate_states(
    model: &Model,
    q0: &[f64],
    v0: &[f64],
    times: &[f64],
    opts: &OdeOptions,
) -> Result<Stepped<Vec<Vec<f64>>>, OdeError> {
    let y0: Vec<f64> = q0.iter().chain(v0).copied().collect();
    let mut jws = model.workspace();
    let mut jacobian = state_jacobian(model, &mut jws);
    let integrated = integrate_with(rhs(model, &mut model.workspace()), Some(&mut jacobian), &y0, times, opts, wall_test(model))?;
    let method = integrated.method();
    Ok(Stepped { states: integrated.solution.states, stats: integrated.solution.stats, method })
}

/// The times where the accepted steps of a time stepping of `model` from the state
/// `(q0, v0)` at `t0` to `t1` ended (the last `t1`), and its work: where an adaptive
/// stepper found the motion fast (short steps) or smooth (long ones). Only the span's
/// ends are requested, so that no step is cut to land on a sample time.
pub fn step_ends(model: &Model, q0: &[f64], v0: &[f64], (t0, t1): (f64, f64), opts: &OdeOptions) -> Result<(Vec<f64>, OdeStats), OdeError> {
    let y0: Vec<f64> = q0.iter().chain(v0).copied().collect();
    let mut test = wall_test(model);
    let mut ends: Vec<f64> = Vec::new();
    // A step that passed the tests may still be retried (the right-hand side failing at
    // its end): a later step from an earlier time replaces the ones after it.
    let logged = |t: f64, y: &[f64], t_new: f64, y_new: &[f64]| {
        let ok = test(t, y, t_new, y_new);
        if ok {
            while ends.last().is_some_and(|&e| e > t) {
                ends.pop();
            }
            ends.push(t_new);
        }
        ok
    };
    let mut jws = model.workspace();
    let mut jacobian = state_jacobian(model, &mut jws);
    let integrated = integrate_with(rhs(model, &mut model.workspace()), Some(&mut jacobian), &y0, &[t0, t1], opts, logged)?;
    Ok((ends, integrated.solution.stats))
}

/// The exact Jacobian `∂(v, q̈)/∂(q, v)` of [`rhs`] for the implicit stepper
/// ([`Model::state_jacobian`]).
fn state_jacobian<'a>(model: &'a Model, ws: &'a mut Workspace) -> impl FnMut(f64, &[f64], &mut DMatrix<f64>) -> Result<(), RhsError> + 'a {
    let d = model.layout.d;
    move |t: f64, y: &[f64], jac: &mut DMatrix<f64>| model.state_jacobian(t, &y[..d], &y[d..], ws, jac).map_err(RhsError::from)
}

/// The test every step of a time stepping of `model` must pass besides its error
/// estimate: with regularized walls, that no step changes a wall's gap by more than
/// [`wall_step_accepted`] allows (true for every step otherwise).
fn wall_test(model: &Model) -> impl FnMut(f64, &[f64], f64, &[f64]) -> bool + '_ {
    let d = model.layout.d;
    let regularized_walls = model.wall_model == WallModel::Gaussian && !model.walls.is_empty();
    // The gaps at the end of the last accepted step are those at the start of the next.
    let mut last_end: Option<(f64, Vec<f64>)> = None;
    move |t: f64, y: &[f64], t_new: f64, y_new: &[f64]| {
        if !regularized_walls {
            return true;
        }
        let before = match last_end.take() {
            Some((t_end, gaps)) if t_end == t => gaps,
            _ => model.wall_gaps(t, &y[..d]),
        };
        let after = model.wall_gaps(t_new, &y_new[..d]);
        let ok = wall_step_accepted(model, &before, &after);
        last_end = Some(if ok { (t_new, after) } else { (t, before) });
        ok
    }
}

/// Fraction of `|h| + σ` by which one step may change a wall's gap `h`.
pub const WALL_STEP: f64 = 0.5;

/// Whether a step that takes the walls' gaps from `before` to `after` changes every
/// regularized wall's gap by at most `WALL_STEP · (|h| + σ)` (`h` at the step's start).
/// Far from a wall the bound is generous (half the distance); approaching it, the steps
/// shrink geometrically to a fraction of σ, so that the Gaussian force is sampled however
/// thin the wall is, at a few dozen extra steps per approach.
pub fn wall_step_accepted(model: &Model, before: &[f64], after: &[f64]) -> bool {
    model.walls.iter().zip(before.iter().zip(after)).all(|(w, (&h, &h_new))| (h_new - h).abs() <= WALL_STEP * (h.abs() + w.width))
}

/// The right-hand side `(t, q, v) ↦ (v, q̈)` of the index-reduced equations.
pub fn rhs<'a>(model: &'a Model, ws: &'a mut Workspace) -> impl FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError> + 'a {
    let d = model.layout.d;
    let mut sol = vec![0.0; d + model.layout.n];
    move |t, y, dy| {
        model.accelerations_into(t, &y[..d], &y[d..], ws, &mut sol)?;
        dy[..d].copy_from_slice(&y[d..]);
        dy[d..].copy_from_slice(&sol[..d]);
        Ok(())
    }
}

/// Split integrator states `y = (q, v)` sampled at `times` into coordinates and
/// velocities, and compute the multipliers λ of the index-reduced equations at each.
pub fn split_states(model: &Model, states: &[Vec<f64>], times: &[f64], ws: &mut Workspace) -> Result<States, OdeError> {
    let d = model.layout.d;
    let mut out =
        States { q: Vec::with_capacity(states.len()), v: Vec::with_capacity(states.len()), lambda: Vec::with_capacity(states.len()) };
    for (y, &t) in states.iter().zip(times) {
        let (_, lambda) = model.accelerations(t, &y[..d], &y[d..], ws).map_err(|e| OdeError::Rhs { t, error: e.into() })?;
        out.q.push(y[..d].to_vec());
        out.v.push(y[d..].to_vec());
        out.lambda.push(lambda);
    }
    Ok(out)
}

/// A failure of the model's dynamics is a failure of the integrator's right-hand side.
impl From<DynamicsError> for RhsError {
    fn from(e: DynamicsError) -> Self {
        RhsError(e.to_string())
    }
}
