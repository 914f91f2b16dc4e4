//! The integration of `y' = f(t, y)` by the stepper the options name
//! ([`Stepper`]): DOP853 ([`ode`]), Radau IIA ([`radau`]), or automatically — DOP853 until it finds the equation
//! stiff (or its steps run out or underflow), then Radau IIA from where it stopped, for
//! the rest of the requested times. Explicit stepping is far cheaper per step, and on
//! smooth motion needs few steps; where the explicit step is limited by stability
//! instead of accuracy (a stiff damper or spring, a fast initial layer), the implicit
//! one takes steps as long as the motion allows. The automatic choice never fails for
//! stiffness: the implicit stepping goes on where the explicit one stopped.

use super::ode::{self, OdeError, OdeOptions, OdeSolution, RhsError, Stepper};
use super::radau::{self, Jacobian};

/// Integrate `y' = f(t, y)` from `times[0]` with `y(times[0]) = y0` by `opts.stepper`,
/// returning the state at every requested time; `accept` is a test every step must pass
/// besides the error estimate ([`ode::integrate_checked`]), `jacobian` the Jacobian
/// `∂f/∂y` for the implicit stepper (a model's is exact, [`Model::state_jacobian`](crate::model::Model::state_jacobian); forward differences without one). The statistics
/// add up both steppers' work, and the method names what ran.
pub fn integrate_with<F, C>(
    mut f: F,
    jacobian: Option<&mut Jacobian<'_>>,
    y0: &[f64],
    times: &[f64],
    opts: &OdeOptions,
    mut accept: C,
) -> Result<Integrated, OdeError>
where
    F: FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError>,
    C: FnMut(f64, &[f64], f64, &[f64]) -> bool,
{
    match opts.stepper {
        Stepper::Implicit => {
            let solution = radau::integrate(&mut f, jacobian, y0, times, opts, &mut accept)?;
            Ok(Integrated { solution, switched: None })
        }
        Stepper::Dop853 | Stepper::Auto => {
            let mut solution = if opts.stepper == Stepper::Auto {
                ode::integrate_until_stiff(&mut f, y0, times, opts, &mut accept)?
            } else {
                ode::integrate_checked(&mut f, y0, times, opts, &mut accept)?
            };
            let Some(stop) = solution.stopped.take() else { return Ok(Integrated { solution, switched: None }) };
            // Implicitly on from the last accepted state, over the times not reached.
            let done = solution.states.len();
            let rest: Vec<f64> = std::iter::once(stop.t).chain(times[done..].iter().copied()).collect();
            // The implicit stepper has a budget of its own: running out of explicit steps
            // is one of the reasons to switch.
            let implicit = radau::integrate(&mut f, jacobian, &stop.y, &rest, opts, &mut accept)?;
            solution.states.extend(implicit.states.into_iter().skip(1));
            solution.stats.add(&implicit.stats);
            Ok(Integrated { solution, switched: Some(Switch { t: stop.t, reason: stop.reason }) })
        }
    }
}

/// An integration and, when it changed steppers, where and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Integrated {
    /// The states at the requested times and the work of both steppers.
    pub solution: OdeSolution,
    /// Where the automatic choice went on implicitly, if it did.
    pub switched: Option<Switch>,
}

impl Integrated {
    /// What ran, in words: the explicit method, the implicit one, or the explicit one up
    /// to where it went on implicitly.
    pub fn method(&self) -> String {
        match &self.switched {
            None => self.solution.method.to_string(),
            Some(sw) => format!("{} to t = {:.6}, then {} ({})", ode::METHOD, sw.t, radau::METHOD, sw.reason),
        }
    }
}

/// Where an automatic integration went on implicitly, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Switch {
    /// The time.
    pub t: f64,
    /// Why DOP853 stopped.
    pub reason: String,
}
