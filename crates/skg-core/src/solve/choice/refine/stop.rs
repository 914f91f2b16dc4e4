//! When the refinement stops without a verified solve: a grid that failed for a reason
//! more nodes will not cure, the time limit or the budget in time, and no discretization
//! predicted to meet the tolerance within the budget of nodes; with what to do.

use super::{Refiner, AIM};
use crate::solve::run::deadline;
use crate::solve::run::outcome::Outcome;
use crate::solve::run::status::{SolveStatus, CONVERGED_RESIDUAL};
use crate::stepping::verify::VerifyStatus;

impl Refiner<'_> {
    /// Why the grid just solved (`outcome`, the last of `grids`) failed for a reason more
    /// nodes will not cure, if it did: its verification could not run; the backend
    /// stopped above the residual a converged solve needs (a loose `[solver] tol`); or its
    /// error relative to the tolerance did not fall from the grid before it with the same
    /// candidate. (A grid that did not converge may converge on a finer one: a wall's
    /// contacts can need it.)
    /// With the reason, what to do (`None`: the grid's own remedy).
    pub(super) fn incurable(&self, outcome: &Outcome) -> Option<(String, Option<String>)> {
        if outcome.converged() && outcome.verification.status == VerifyStatus::Unverified {
            return Some(("its verification could not run".to_string(), None));
        }
        // Stopped above that residual at the solver's acceptable level with a tolerance
        // that is not loose, the solve may converge on another discretization.
        let loose = self.scene.solver.tol > CONVERGED_RESIDUAL;
        if let (SolveStatus::ResidualTooLarge { residual, .. }, true) = (outcome.status, loose) {
            let reason = format!(
                "the solver stopped at its tolerance ([solver] tol) with a residual of {residual:.1e}, above the 1e-8 a converged solve needs"
            );
            return Some((reason, Some("tighten `[solver] tol` (the default is 1e-11)".to_string())));
        }
        let [.., before, last] = self.grids.as_slice() else { return None };
        let same_candidate = before.operator == last.operator && before.initial_velocity == last.initial_velocity;
        match (before.measured, last.measured) {
            (Some(b), Some(l)) if same_candidate && last.nodes > before.nodes && l >= b => Some((
                format!(
                    "its error did not fall from {} to {} nodes ({} and {} times the tolerance)",
                    before.nodes,
                    last.nodes,
                    ratio_text(b),
                    ratio_text(l)
                ),
                Some("let `--operator auto` choose another operator, or loosen the tolerance".to_string()),
            )),
            _ => None,
        }
    }

    /// Why the next grid, of `nodes` nodes, would end past the time limit (or, without
    /// one, the refinement's budget), if it would: its time is estimated from the last
    /// grid's, in proportion to the nodes.
    pub(super) fn beyond_time(&self, nodes: usize) -> Option<String> {
        let last = self.grids.last()?;
        let estimate = last.wall_s * nodes as f64 / last.nodes as f64;
        let d = self.limits.solve()?;
        let left = d.left_s();
        (estimate > left).then(|| format!("it would take about {estimate:.1} s, and {} leaves {left:.1} s", d.describe()))
    }

    /// What stopped the grid just solved (`outcome`) or stops the refinement now, if a
    /// deadline did: the time limit, or the refinement's budget.
    pub(super) fn stopped_at(&self, outcome: &Outcome) -> Option<String> {
        if let Some(d) = self.limits.time_limit.filter(|d| d.passed()) {
            return Some(d.describe());
        }
        if let crate::solve::backend::SolverStatus::TimeLimitReached { bound, limit_s, .. } = outcome.status.solver() {
            return Some(deadline::describe(bound, limit_s));
        }
        self.limits.budget.filter(|d| d.passed()).map(|d| d.describe())
    }

    /// Why the refinement stopped without a verified solve at the budget.
    pub(super) fn out_of_budget(&mut self) -> (String, Option<String>) {
        let budget = format!("the budget of {} nodes ({})", self.max_nodes, self.max_nodes_source);
        let finer = "raise --max-nodes, choose a higher-order operator, or loosen the tolerance".to_string();
        let Ok(_) = &self.predictor else {
            let why = self.predictor.as_ref().err().cloned().unwrap_or_default();
            return (format!("no finer grid within {budget}; the error could not be predicted ({why})"), None);
        };
        let c = self.candidates.first().copied();
        let beyond = c.and_then(|c| self.predicted(c, self.max_nodes).map(|r| (c, r)));
        match beyond {
            Some((c, r)) if r.is_finite() && r <= 1.0 => (
                format!(
                    "no discretization within {budget} is predicted to meet the tolerance with the margin the refinement \
                     aims at ({AIM} of it): {} there is predicted at {} of the tolerance",
                    c.describe(),
                    ratio_text(r)
                ),
                Some(finer),
            ),
            Some((c, r)) if r.is_finite() => (
                format!(
                    "no discretization is predicted to meet the tolerance within {budget}: {} there is predicted at {} times \
                     the tolerance",
                    c.describe(),
                    ratio_text(r)
                ),
                Some(finer),
            ),
            _ => (
                format!(
                    "no discretization is predicted to meet the tolerance within {budget}: the predicted error stops \
                     decreasing (round-off or the reference's own accuracy)"
                ),
                Some("loosen the tolerance".to_string()),
            ),
        }
    }
}

/// An error relative to the tolerance in words: three significant digits, in exponent
/// form when it is huge or tiny.
fn ratio_text(r: f64) -> String {
    if (1e-3..1e4).contains(&r.abs()) {
        format!("{r:.3}")
    } else {
        format!("{r:.2e}")
    }
}
