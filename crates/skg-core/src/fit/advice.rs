//! What a fit tells its user about its result, in words: whether Ipopt's status counts
//! as converged, the warnings of a misfit too large for the data (against their standard
//! deviations, or without them against their own spread) and of parameters on their
//! bounds, and the remedy of a fitted motion that did not verify.
//!
//! **Place in the flow.** After the optimization and the statistics (`mod.rs`): it reads
//! their results and writes text; nothing here changes a number.

use indexmap::IndexMap;
use skg_ipopt as ipopt;

use super::data::Data;
use super::report::{self, MisfitReport};
use super::{Fit, FitMethod};
use crate::stepping::verify::Verification;

/// `fit` with the fitted motion's remedy when the fit converged but the motion failed
/// its verification: what to fit on instead.
pub(super) fn with_remedy(mut fit: Fit) -> Fit {
    if !fit.failed_verification() {
        return fit;
    }
    let nodes = 2 * fit.fitted.nodes - 1;
    fit.outcome.remedy = Some(match fit.report.discretization.last() {
        None => format!(
            "let the refinement choose the discretization: --refine (the nodes and the operator, chosen at the starting values \
             and again at the fitted values when the motion does not verify there); or fit on a finer one (--nodes {nodes}, or \
             an -AD operator, which damps the odd-even mode)"
        ),
        Some(last) if !last.refinement.as_ref().is_some_and(|r| r.refine) => {
            format!("the operator was chosen at {} for the scene's {} nodes: --refine chooses the nodes too", last.chosen_at, last.nodes)
        }
        Some(last) if !last.verified => format!(
            "at {} the refinement found no discretization that verifies ({}): let it use more nodes (--max-nodes), or state \
             the accuracy you need (--verify-tol)",
            last.chosen_at,
            last.refinement.as_ref().map_or("see fit.discretization in summary.json", |r| r.result.as_str())
        ),
        Some(last) => format!(
            "the discretization chosen at {} ({}) verified there but not at the fitted values: fit on a finer one \
             (--operator {} --initial-velocity {} --nodes {nodes})",
            last.chosen_at,
            last.describe(),
            last.operator,
            last.initial_velocity
        ),
    });
    fit
}

/// A warning when the data's standard deviations do not explain the misfit
/// ([`MisfitReport::beyond_the_noise`]): a local minimum, or a model or standard
/// deviations that do not describe the data.
pub(super) fn beyond_the_noise(misfit: &MisfitReport, method: FitMethod) -> Option<String> {
    let clause = noise_clause(misfit)?;
    Some(format!("{clause}: {}, or the model or the standard deviations do not describe the data", local_minimum(method)))
}

/// The weighted misfit against what the standard deviations explain, in words, when
/// they do not explain it.
fn noise_clause(misfit: &MisfitReport) -> Option<String> {
    let (x, spread) = misfit.beyond_the_noise()?;
    let times = if x >= 10.0 { format!("{x:.0}") } else { format!("{x:.1}") };
    Some(format!(
        "the weighted misfit is {times} times what the data's standard deviations explain (the reduced chi-square over {} degrees \
         of freedom, 1 ± {spread:.2} for data the model and the standard deviations describe)",
        misfit.dof
    ))
}

/// How the fitted motion fails to describe the data, in words, when it does (the
/// clause of [`beyond_the_noise`] or of [`explains_little`]); `None` when it does not.
pub(super) fn misdescription(misfit: &MisfitReport, data: &Data) -> Option<String> {
    noise_clause(misfit).or_else(|| share_clause(misfit, data))
}

/// A warning when the fitted motion's discretization error, as its verification measured
/// it against time stepping, can move the estimates by a standard error or more: an
/// error `e` in a coordinate observed `n` times with standard deviation `σ` (the data's
/// smallest for it) shifts a fit by up to about `e √n / σ` standard errors, a bias the
/// standard errors do not include. Only with standard deviations in the data: without
/// them the residuals, which hold that error, are the only measure of the noise. A knife
/// edge fitted with `--refine` under its scene's `[verify] tol = 0.015` from data with
/// σ = 0.001 was chosen `SBP121` on 400 nodes, 2.7e-3 from time stepping, and its drag
/// came out 6 standard errors from the truth.
pub(super) fn discretization_bias(verification: &Verification, data: &Data, coordinates: &[String]) -> Option<String> {
    if !data.sigma_given {
        return None;
    }
    let mut worst: Option<(&str, f64, usize, f64, f64)> = None;
    for &c in &data.coordinates {
        let name = coordinates[c].as_str();
        let Some(&error) = verification.errors.get(name) else { continue };
        let sigmas: Vec<f64> = data.observations.iter().filter(|o| o.coordinate == c).map(|o| o.sigma).collect();
        let sigma = sigmas.iter().copied().fold(f64::INFINITY, f64::min);
        let shift = error * (sigmas.len() as f64).sqrt() / sigma;
        if shift > 1.0 && worst.is_none_or(|w| shift > w.4) {
            worst = Some((name, error, sigmas.len(), sigma, shift));
        }
    }
    let (name, error, n, sigma, shift) = worst?;
    Some(format!(
        "the fitted motion's discretization error in {name} ({error:.1e}, measured by its verification) can move the estimates \
         by up to about {shift:.0} standard errors ({n} values with standard deviations from {sigma:.1e}), a bias the \
         standard errors do not include: fit on a finer discretization (--nodes, a higher-order operator; with --refine, a \
         --verify-tol below the data's standard deviations)"
    ))
}

/// Where a fit whose misfit is too large may have stopped, and what to try.
pub(super) fn local_minimum(method: FitMethod) -> &'static str {
    match method {
        FitMethod::Reduced => "the reduced fit may have stopped in a local minimum, as single shooting does (--fit-method all-at-once)",
        FitMethod::AllAtOnce => {
            "the fit may have stopped in a local minimum (other starting values; --start data where the data observe the motion)"
        }
    }
}

/// Without standard deviations, a warning when the fitted motion explains less than
/// half of the data's variation about each observed coordinate's mean, `1 − Σ r² /
/// Σ (d − d̄)²` (the coefficient of determination): the misfit cannot be weighed against
/// a noise, but residuals as large as the data's own spread are not a fit.
pub(super) fn explains_little(misfit: &MisfitReport, data: &Data, method: FitMethod) -> Option<String> {
    let clause = share_clause(misfit, data)?;
    Some(format!("{clause}: {}, or the model does not describe the data", local_minimum(method)))
}

/// The share of the data's variation the fitted motion explains, in words, when it is
/// below [`EXPLAINED_AT_LEAST`] and the data give no standard deviations.
fn share_clause(misfit: &MisfitReport, data: &Data) -> Option<String> {
    if data.sigma_given || misfit.weighted {
        return None;
    }
    let mut total = 0.0;
    for &c in &data.coordinates {
        let values: Vec<f64> = data.observations.iter().filter(|o| o.coordinate == c).map(|o| o.value).collect();
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        total += values.iter().map(|d| (d - mean).powi(2)).sum::<f64>();
    }
    let share = 1.0 - misfit.sum_of_squares / total;
    (total > 0.0 && share < EXPLAINED_AT_LEAST).then(|| {
        format!(
            "the fitted motion explains {:.0} % of the data's variation about their means (1 − Σ r²/Σ (d − d̄)² = {share:.2})",
            100.0 * share.max(0.0)
        )
    })
}

/// The share of the data's variation below which a fit without standard deviations is
/// warned of ([`explains_little`]).
pub(super) const EXPLAINED_AT_LEAST: f64 = 0.5;

/// A warning for each parameter that ended on its bound.
pub(super) fn bound_warnings(parameters: &IndexMap<String, report::ParameterReport>) -> Vec<String> {
    parameters
        .iter()
        .filter(|(_, p)| p.at_bound)
        .map(|(name, p)| {
            format!("`{name}` ended on its bound ({}): its standard error describes the curvature there, not a symmetric interval", p.value)
        })
        .collect()
}

/// Whether Ipopt's fit converged: `Solve_Succeeded`; or, with a warning, its acceptable
/// level, or a search direction too small to make progress (the misfit of noisy data
/// stalls there short of the tight default `tol`) with the constraints held to 1e-8 or
/// the scene's `tol` (the solve at the fitted values then solves them to `tol`).
pub(super) fn converged(solution: &ipopt::Solution, tol: f64, warnings: &mut Vec<String>) -> bool {
    match solution.status {
        ipopt::Status::SolveSucceeded => true,
        ipopt::Status::SolvedToAcceptableLevel => {
            warnings.push("Ipopt stopped at its acceptable level (Solved_To_Acceptable_Level), not at the requested tolerance".into());
            true
        }
        ipopt::Status::SearchDirectionBecomesTooSmall if solution.max_constraint_violation <= tol.max(1e-8) => {
            warnings.push(format!(
                "Ipopt stopped because its search direction became too small (Search_Direction_Becomes_Too_Small) with the \
                 equations of motion held to {:.1e}: the misfit cannot decrease further at this precision",
                solution.max_constraint_violation
            ));
            true
        }
        _ => false,
    }
}
