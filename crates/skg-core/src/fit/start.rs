//! The start of a fit: the trajectory at the starting values (a solve, else time
//! stepping), and the data put in place of the coordinates they observe.

use std::sync::Arc;

use super::{Data, FitError};
use crate::discrete::interpolate::{segment, Hermite};
use crate::discrete::trajectory::NodeSeries;
use crate::discrete::Discretization;
use crate::model::Model;
use crate::scene::Scene;
use crate::solve::{action_on, point_from_states, solve_global, Guess};
use crate::stepping::equations::{integrate_model, Stepped};
use crate::stepping::ode::OdeOptions;

/// The start of a fit: coordinates and multipliers at the nodes, how they were made,
/// and the unknown vector of the discrete solution when the solve converged.
pub(super) struct Start {
    pub q: NodeSeries,
    pub lambda: NodeSeries,
    pub description: String,
    pub solution: Option<Vec<f64>>,
}

/// Solve the scene at its starting values (one global solve from time stepping, by
/// Newton's method, which hands over to Ipopt if it fails: one sparse LU of the square
/// Jacobian per step instead of MUMPS's analysis and factorizations of Ipopt's KKT
/// matrix); when that does not converge, the time stepping itself.
pub(super) fn start_states(scene: &Scene, model: &Arc<Model>, disc: &Discretization, times: &[f64]) -> Result<Start, FitError> {
    // Not verified: its guess need not be the verification's time stepping
    // (`solve::piece`), which would cost more than the solve.
    let mut newton = super::on_newton(scene);
    newton.verify.enabled = false;
    let run = solve_global(&newton, model, disc, &Guess::TimeStepping, None)?;
    if run.solution.status.is_converged() {
        let tr = &run.solution.trajectory;
        let action = action_on(model, scene, disc, times)?;
        let z = point_from_states(&action, &tr.q, &tr.lambda);
        let description = format!("the solve at the starting values ({} iterations)", run.solution.iterations);
        return Ok(Start { q: tr.q.clone(), lambda: tr.lambda.clone(), description, solution: Some(z) });
    }
    let opts = OdeOptions { rtol: 1e-8, atol: 1e-10, stepper: scene.verify.stepper, ..OdeOptions::default() };
    let Stepped { states, .. } = integrate_model(model, &scene.initial_q, &scene.initial_v, times, &opts).map_err(|e| {
        FitError::Settings(format!(
            "neither the solve nor time stepping at the starting values succeeded ({e}): choose other starting values"
        ))
    })?;
    Ok(Start { q: states.q, lambda: states.lambda, description: run.solution.status.to_string(), solution: None })
}

/// Put the data in place of the coordinates they observe: at each node between a
/// coordinate's first and last observation, the cubic Hermite polynomial through the
/// neighbouring observations with finite-difference slopes (linear between two).
pub(super) fn put_data(q: &mut NodeSeries, times: &[f64], data: &Data) {
    for &i in &data.coordinates {
        let (ts, ys): (Vec<f64>, Vec<f64>) = data.observations.iter().filter(|o| o.coordinate == i).map(|o| (o.t, o.value)).unzip();
        if ts.len() < 2 {
            continue;
        }
        let slope = |k: usize| -> f64 {
            if k == 0 {
                (ys[1] - ys[0]) / (ts[1] - ts[0])
            } else if k + 1 == ts.len() {
                (ys[k] - ys[k - 1]) / (ts[k] - ts[k - 1])
            } else {
                // The derivative of the parabola through three neighbours.
                let (h0, h1) = (ts[k] - ts[k - 1], ts[k + 1] - ts[k]);
                let (d0, d1) = ((ys[k] - ys[k - 1]) / h0, (ys[k + 1] - ys[k]) / h1);
                (h1 * d0 + h0 * d1) / (h0 + h1)
            }
        };
        for (k, &t) in times.iter().enumerate() {
            if t < ts[0] || t > ts[ts.len() - 1] {
                continue;
            }
            let s = segment(&ts, t);
            q[k][i] = if ts.len() == 2 {
                ys[0] + (t - ts[0]) / (ts[1] - ts[0]) * (ys[1] - ys[0])
            } else {
                Hermite::new(ts[s], ts[s + 1], t).eval(ys[s], slope(s), ys[s + 1], slope(s + 1))
            };
        }
    }
}
