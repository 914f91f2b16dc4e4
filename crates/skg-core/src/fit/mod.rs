//! Inverse problems: the parameters and initial data of a scene estimated from measured
//! motion, with Ipopt as the optimizer ([`fit`]; docs/fitting.md).
//!
//! The discrete action turns a trajectory into the solution of one sparse system with
//! exact derivatives. A fit optimizes the whole trajectory and the free parameters at
//! once: unknowns `x = (P, θ)` (the plus block of the reduced system and the free
//! parameters), constraints the stationarity of the action `R(P; θ) = 0` (the same
//! equations and boundary conditions as a solve, with the exact sparse Jacobian in the
//! trajectory and in the parameters), objective the weighted least-squares misfit between
//! the trajectory at the data's times and the data, bounds on the parameters where the
//! physics needs them, and the exact Hessian of the Lagrangian from the derivative tapes
//! (or Ipopt's limited-memory approximation, as an option).
//!
//! In the order of a fit:
//! 1. the settings are checked against the scene: the free parameters are parameters,
//!    their starting values lie within their bounds, and they do not move the time grid
//!    ([`FitSettings`] and its checks, `settings.rs`; [`FreeParameter`], `free.rs`; the scene's `[fit]` table,
//!    read by `table.rs`, gives them when the caller does not); with `--refine` or
//!    `--operator auto` the refinement chooses the discretization at the starting values
//!    (`choose.rs`; again at the fitted values when the fitted motion does not verify);
//! 2. the data are read and checked against the scene ([`Data`], `data.rs`) and become
//!    rows of weights over the trajectory's unknowns, interpolated at the data's times
//!    consistently with the operator (`observe.rs`);
//! 3. the scene's model with the free parameters symbolic
//!    ([`Model::with_free_parameters`]) is solved at the starting values (by Newton,
//!    which hands over to Ipopt if it fails), and the start
//!    is that solve with the data in place of the coordinates they observe ([`FitStart`],
//!    `start.rs`);
//! 4. Ipopt minimizes the misfit under the constraints (`problem.rs`), from its own
//!    least-squares multipliers computed here (`multipliers.rs`); or, with
//!    [`FitMethod::Reduced`], in the parameters alone, the trajectory solved from the
//!    equations at every point (`reduced.rs`);
//! 5. at the solution the trajectory's sensitivities give the Gauss–Newton curvature,
//!    the covariance and the standard errors, and tell whether the data determine the
//!    parameters (`statistics.rs`; the same test runs on the start, so that a fit the
//!    data cannot determine is refused before it is attempted);
//! 6. the scene with the fitted values is solved from the fitted trajectory (by Newton,
//!    which hands over to Ipopt if it fails) and verified against time stepping like any
//!    solve: its [`Outcome`] is the fitted motion;
//! 7. the report ([`FitReport`], the `fit` object of `summary.json`), the fitted scene's
//!    text and the data beside the fitted values (`report.rs`), with what the result
//!    means in words: warnings and the remedy of a motion that did not verify
//!    (`advice.rs`).
//!
//! **Place in the flow.** After the solve and the output: it uses the scene, the model,
//! the discrete action (its parameter derivatives, the interpolation), the time stepping
//! (through the solve), the solve (a run, its outcome, the sparse LU) and the output (a
//! fit's files, `files.rs`). Only the command line and Python call it. It needs Ipopt: the
//! module is compiled with the `ipopt` feature only.

mod advice;
mod barrier;
mod choose;
mod data;
mod files;
mod free;
mod multipliers;
mod observe;
mod options;
mod problem;
mod reduced;
mod report;
mod settings;
mod start;
mod statistics;
mod table;

use std::cell::RefCell;
use std::sync::Arc;
use std::time::Instant;

use indexmap::IndexMap;
use nalgebra::DMatrix;
use skg_ipopt as ipopt;

use crate::discrete::action::Block;
use crate::discrete::trajectory::NodeSeries;
use crate::discrete::{Action, Discretization};
use crate::model::Model;
use crate::scene::{Overrides, Scene, SceneError};
use crate::solve::{action_on, outcome, point_from_states, solve_global, Deadline, Guess, Outcome, SolveError};
use advice::{beyond_the_noise, bound_warnings, converged, explains_little, with_remedy};
use observe::Observations;
use problem::{FitProblem, Plans, StopTest};
use reduced::ReducedFit;
use settings::check_settings;
use start::{put_data, start_states, Start};

pub use choose::ChosenDiscretization;
pub use data::{Data, DataError, DataPlace, Observation, SIGMA_PREFIX};
pub use files::{fit_into, write_fit, FitIntoError, FitWritten, DATA_FILE, FITTED_SCENE_FILE};
pub use free::{split_list, FreeParameter, FreeParameterError};
pub use reduced::InnerWork;
pub use report::{CovarianceReport, DataReport, FitReport, MisfitReport, ParameterReport};
pub use settings::{
    FitHessian, FitMethod, FitSettings, FitStart, ParseFitSettingError, ACCEPTABLE_ITER, DEFAULT_MAX_ITER, DEFAULT_TOL, MUMPS_PIVTOL,
    MUMPS_PIVTOL_LINEAR,
};
pub use statistics::{covariance, undetermined, SINGULAR};
pub use table::{data_of_scene, free_of_scene};

/// Why a fit could not be attempted or completed (a fit that did not converge is not an
/// error: its [`FitReport`] says so).
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// The scene, an override or the scene's `[fit]` table is invalid.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The data cannot be used.
    #[error(transparent)]
    Data(#[from] DataError),
    /// The settings do not fit the scene (a free parameter, a bound, the operator).
    #[error("{0}")]
    Settings(String),
    /// A solve (at the starting values, or at the fitted ones) could not run.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// Ipopt could not run the fit.
    #[error("the fit could not run: {0}")]
    Ipopt(#[from] ipopt::SolveError),
    /// The data do not determine the free parameters: which combination, in words.
    #[error("{0}")]
    NotIdentifiable(String),
    /// The fit converged to a stationary point of the misfit whose motion does not
    /// describe the data and whose curvature is singular there (a fit not converged).
    #[error("{0}")]
    NotAMinimum(String),
}

impl FitError {
    /// Why the fit did not converge, when Ipopt ended because the fit could not be
    /// evaluated at a point it tried (the equations of motion not solvable there, a
    /// derivative not finite), or at a stationary point that is not the misfit's
    /// minimum: a fit not converged (exit 3), where the other errors are the input's
    /// (exit 1).
    pub fn not_converged(&self) -> Option<String> {
        match self {
            FitError::Ipopt(ipopt::SolveError::Eval(e)) => Some(format!("Ipopt tried a point where the fit cannot be evaluated: {e}")),
            FitError::NotAMinimum(why) => Some(why.clone()),
            _ => None,
        }
    }
}

/// A fit's result.
#[derive(Debug, Clone)]
pub struct Fit {
    /// The solve of the scene with the fitted values, from the fitted trajectory, with
    /// its verification: its trajectory is the fitted motion.
    pub outcome: Outcome,
    /// The scene with the fitted values.
    pub fitted: Scene,
    /// What the fit did and found (the `fit` object of `summary.json`).
    pub report: FitReport,
    /// The scene file's text with the fitted values (`fitted.toml`).
    pub fitted_toml: String,
    /// The data beside the fitted motion at the data's times: header and rows
    /// (`data.csv`).
    pub data_table: (Vec<String>, Vec<Vec<f64>>),
}

impl Fit {
    /// The fit converged, and the solve at the fitted values converged and verified:
    /// exit status 0.
    pub fn trusted(&self) -> bool {
        self.report.converged && self.outcome.trusted()
    }

    /// Converged: the fit and the solve at the fitted values.
    pub fn converged(&self) -> bool {
        self.report.converged && self.outcome.converged()
    }

    /// Converged, but the fitted motion failed its verification (a discretization too
    /// coarse for it, where a finer one is the remedy).
    fn failed_verification(&self) -> bool {
        self.converged() && self.outcome.verification.status == crate::stepping::verify::VerifyStatus::Failed
    }
}

/// Fit the free parameters of `scene` (resolved from its file with `overrides`, at the
/// starting values) to `data` (module documentation): the start, Ipopt's optimization,
/// the statistics at its solution, and the fitted scene solved and verified.
///
/// With `--operator auto` or a refinement asked for, the discretization is the one the
/// refinement chooses at the starting values (`choose.rs`); when the fitted motion fails
/// its verification on it, the refinement chooses again at the fitted values, and the
/// fit starts again from them on that discretization, once.
pub fn fit(scene: &Scene, overrides: &Overrides, data: &Data, settings: &FitSettings) -> Result<Fit, FitError> {
    let deadline = Deadline::after(scene.solver.time_limit);
    if !(scene.choose_operator || scene.verify.refine) {
        return fit_on(scene, overrides, data, settings, &Round { deadline, ..Round::default() }).map(with_remedy);
    }
    let started = Instant::now();
    let mut named = scene.clone();
    choose::fixed(&mut named);
    check_settings(&named, overrides, settings)?;
    let (chosen, ov, first) = choose::discretization(scene, overrides, "the starting values", deadline)?;
    let mut choosing = started.elapsed();
    let fit = fit_on(&chosen, &ov, data, settings, &Round { chosen: std::slice::from_ref(&first), initial: None, deadline })?;
    let fit = if fit.failed_verification() && !deadline.is_some_and(|d| d.passed()) {
        let names = settings.names();
        let theta: Vec<f64> = fit.report.parameters.values().map(|p| p.value).collect();
        let (at_fitted, ov_fitted) = fitted_scene(scene, overrides, &names, &theta)?;
        let t = Instant::now();
        let (chosen, ov, second) = choose::discretization(&at_fitted, &ov_fitted, "the fitted values of a first fit", deadline)?;
        choosing += t.elapsed();
        if second.same_as(&first) {
            fit
        } else {
            let initial: Vec<f64> = names.iter().map(|n| scene.parameters[n]).collect();
            fit_on(&chosen, &ov, data, settings, &Round { chosen: &[first, second], initial: Some(&initial), deadline })?
        }
    } else {
        fit
    };
    let mut fit = with_remedy(fit);
    fit.report.timings.discretization_s = choosing.as_secs_f64();
    fit.report.timings.total_s = started.elapsed().as_secs_f64();
    Ok(fit)
}

/// What one fit on one discretization is given besides the scene and the data.
#[derive(Default)]
struct Round<'a> {
    /// How the refinement chose the discretization (empty: as the scene and the command
    /// line name it).
    chosen: &'a [ChosenDiscretization],
    /// The starting values to report when the scene's are not them (a fit started again
    /// from a first fit's).
    initial: Option<&'a [f64]>,
    /// The user's time limit, from the start of the whole fit.
    deadline: Option<Deadline>,
}

/// [`fit`] on the discretization `scene` names.
fn fit_on(scene: &Scene, overrides: &Overrides, data: &Data, settings: &FitSettings, round: &Round) -> Result<Fit, FitError> {
    let started = Instant::now();
    let mut warnings = check_settings(scene, overrides, settings)?;
    let names = settings.names();
    let starting: Vec<f64> = names.iter().map(|n| scene.parameters[n]).collect();
    let model = Arc::new(Model::with_free_parameters(scene, &names)?);
    // The scene's own discretization, as a solve takes it (the natural initial-velocity
    // condition over a fast initial layer when none is named; an adaptive grid's map made
    // from the motion at the values the fit starts from, and kept while the parameters
    // move).
    let (disc, note) = crate::solve::scene_discretization(scene, &model);
    warnings.extend(note);
    let times = disc.times(scene);
    let mut action = action_on(&model, scene, &disc, &times)?;
    let plans = Plans {
        jacobian: action.plan(Block::ReducedJacobian),
        hessian: (settings.hessian == FitHessian::Exact).then(|| action.plan(Block::ReducedHessian)),
        parameters: action.parameter_plan(),
        jacobian_lu: RefCell::new(None),
    };
    let observations = Observations::new(&action, &times, data);
    let problem = Problem { scene, model: &model, plans: &plans, observations: &observations, names: &names };

    let (x0, start) = problem.starting_point(&action, &disc, &times, data, settings, &starting, &mut warnings)?;
    let start_s = started.elapsed().as_secs_f64();

    let t_opt = Instant::now();
    let bound_relax_factor =
        scene.solver.ipopt.get("bound_relax_factor").and_then(options::ipopt_number).unwrap_or(barrier::BOUND_RELAX_FACTOR);
    let stop =
        StopTest { tol: settings.tol, constraints: scene.solver.tol.min(settings.tol), bound_relax_factor, deadline: round.deadline };
    let (solution, at_kkt_point, inner, ran_out) = match settings.method {
        FitMethod::Reduced => problem.optimize_reduced(&mut action, settings, &x0, stop)?,
        FitMethod::AllAtOnce => {
            let all_at_once = problem.optimize_all_at_once(&mut action, settings, &x0, stop)?;
            problem.polished(&mut action, settings, all_at_once, stop, &mut warnings)
        }
    };
    let optimization_s = t_opt.elapsed().as_secs_f64();
    let timed_out = ran_out && at_kkt_point.is_none();
    if at_kkt_point == Some(problem::KktStop::Acceptable) {
        warnings.push(reduced::acceptable_warning());
    }
    let converged = !timed_out && (at_kkt_point.is_some() || converged(&solution, scene.solver.tol, &mut warnings));

    let t_stat = Instant::now();
    let at = problem.statistics_at(&mut action, &solution, converged, data, &mut warnings)?;
    warnings.extend(beyond_the_noise(&at.misfit, settings.method));
    warnings.extend(explains_little(&at.misfit, data, settings.method));
    let statistics_s = t_stat.elapsed().as_secs_f64();

    let t_verify = Instant::now();
    let (fitted, fitted_overrides) = fitted_scene(scene, overrides, &names, &at.theta)?;
    let mut outcome = solved_from_the_fit(&fitted, &action, &disc, &at.z, round.deadline)?;
    warnings.extend(advice::discretization_bias(&outcome.verification, data, &scene.coordinates));
    outcome.warnings.extend(warnings.iter().cloned());
    let verification_s = t_verify.elapsed().as_secs_f64();

    let parameters = report::parameters(&settings.free, &at.theta, round.initial.unwrap_or(&starting), at.covariance.as_ref());
    warnings.extend(bound_warnings(&parameters));
    let timings = report::Timings {
        start_s,
        optimization_s,
        ipopt_internal_s: solution.ipopt_seconds,
        statistics_s,
        verification_s,
        discretization_s: 0.0,
        total_s: started.elapsed().as_secs_f64(),
    };
    let status = match (at_kkt_point, round.deadline.filter(|_| timed_out)) {
        (Some(stop), _) => (stop.status().to_string(), stop.text().to_string()),
        (None, Some(d)) => (TIME_LIMIT_REACHED.to_string(), format!("{} was reached", d.describe())),
        (None, None) => (solution.status.name().to_string(), solution.status.to_string()),
    };
    let mut report =
        problem.report(&action, &solution, (converged, status), settings, start, parameters, at, data, timings, inner, warnings);
    report.discretization = round.chosen.to_vec();
    let fitted_toml = report::fitted_toml(scene, &disc, &fitted_overrides, &report);
    let data_table = report::data_table(scene, data, &outcome.trajectory);
    Ok(Fit { outcome, fitted, report, fitted_toml, data_table })
}

/// The fit's status when the user's time limit stopped Ipopt (`summary.json`'s
/// `fit.status`).
pub const TIME_LIMIT_REACHED: &str = "Time_Limit_Reached";

/// What Ipopt's optimization returns: its solution (`x = (P, θ)`), how the fit's own
/// test stopped it, the reduced fit's solves of the equations of motion, and whether the
/// time limit stopped it.
type Optimized = (ipopt::Solution, Option<problem::KktStop>, Option<InnerWork>, bool);

/// What the steps of a fit share: the scene at the starting values, its model with the
/// free parameters symbolic, the derivative plans, the observations and the free
/// parameters' names.
struct Problem<'a> {
    scene: &'a Scene,
    model: &'a Arc<Model>,
    plans: &'a Plans,
    observations: &'a Observations,
    names: &'a [String],
}

/// The statistics at the fit's solution.
struct AtSolution {
    /// The fitted parameters.
    theta: Vec<f64>,
    /// The whole unknown vector of the action (the minus block zero).
    z: Vec<f64>,
    /// The curvature `AᵀA` of the misfit (Gauss–Newton), if the sensitivities exist.
    curvature: Option<DMatrix<f64>>,
    /// The parameters' covariance, where the misfit defines it.
    covariance: Option<DMatrix<f64>>,
    misfit: MisfitReport,
}

impl Problem<'_> {
    /// The all-at-once fit from `x0 = (P, θ)` (`problem.rs`), with its own least-squares
    /// starting multipliers (`multipliers.rs`).
    fn optimize_all_at_once(&self, action: &mut Action, settings: &FitSettings, x0: &[f64], stop: StopTest) -> Result<Optimized, FitError> {
        let (scene, plans) = (self.scene, self.plans);
        let largest =
            scene.solver.ipopt.get("constr_mult_init_max").and_then(options::ipopt_number).unwrap_or(multipliers::CONSTR_MULT_INIT_MAX);
        let y0 = multipliers::starting_multipliers(action, plans, self.observations, &settings.free, x0, largest);
        let options = options::all_at_once(scene, settings, plans, action.layout.n_p);
        let mut problem = FitProblem::new(action, plans, self.observations, &settings.free, stop);
        let solution = ipopt::solve_warm(&mut problem, x0, &y0, &options)?;
        Ok((solution, problem.stopped_at_kkt_point(), None, problem.clock.ran_out))
    }

    /// The all-at-once fit `optimized` as it is, unless Ipopt stopped it at its acceptable
    /// level: then the reduced fit goes on from there to the fit's tolerance. Ipopt's
    /// acceptable level bounds the gradient absolutely, and a parameter of size 10⁶ (the
    /// overdamped spring's damping) had passed it 6 of its standard errors from the
    /// minimum; the reduced fit's test is relative to each parameter's size (`reduced.rs`).
    /// Where the reduced fit cannot go on (its solve fails there, or it does not stop at a
    /// KKT point), and with the limited-memory Hessian (the reduced fit needs the exact
    /// one), the all-at-once fit's result stands, with its warning.
    fn polished(
        &self,
        action: &mut Action,
        settings: &FitSettings,
        optimized: Optimized,
        stop: StopTest,
        warnings: &mut Vec<String>,
    ) -> Optimized {
        let (solution, stopped, _, ran_out) = &optimized;
        let exact = self.plans.hessian.is_some();
        if !exact || stopped.is_some() || *ran_out || solution.status != ipopt::Status::SolvedToAcceptableLevel {
            return optimized;
        }
        // Within the fit's iteration limit, the all-at-once fit's iterations counted.
        let left = settings.max_iter.saturating_sub(solution.iterations as u32);
        if left == 0 {
            return optimized;
        }
        let reduced = FitSettings { method: FitMethod::Reduced, max_iter: left, ..settings.clone() };
        match self.optimize_reduced(action, &reduced, &solution.x, stop) {
            Ok((mut polished, Some(kkt), _, ran_out)) => {
                warnings.push(format!(
                    "Ipopt stopped the all-at-once fit at its acceptable level after {} iterations; the reduced fit went on \
                     from there ({} iterations, --fit-method reduced)",
                    solution.iterations, polished.iterations
                ));
                polished.iterations += solution.iterations;
                polished.ipopt_seconds += solution.ipopt_seconds;
                (polished, Some(kkt), None, ran_out)
            }
            _ => optimized,
        }
    }

    /// The reduced fit from `x0 = (P, θ)`, a solution at the starting values
    /// (`reduced.rs`): Ipopt's point is the parameters, and the trajectory solved there is
    /// put beside them.
    fn optimize_reduced(&self, action: &mut Action, settings: &FitSettings, x0: &[f64], stop: StopTest) -> Result<Optimized, FitError> {
        let theta0 = x0[action.layout.n_p..].to_vec();
        let mut reduced = ReducedFit::new(action, self.plans, self.observations, &settings.free, x0, stop)
            .map_err(|e| FitError::Settings(format!("the reduced fit cannot start: {e}")))?;
        let mut solution = ipopt::solve(&mut reduced, &theta0, &options::reduced(self.scene, settings))?;
        let (x, residual) = reduced.point(&solution.x).map_err(|e| FitError::Settings(format!("the reduced fit's last point: {e}")))?;
        solution.x = x;
        solution.max_constraint_violation = residual;
        Ok((solution, reduced.stopped_at_kkt_point(), Some(reduced.work), reduced.clock.ran_out))
    }

    /// The starting point of the optimization, the trajectory's unknowns and then the
    /// parameters: a solve at the starting values (refused if the data cannot determine
    /// the parameters there), with the data in place of what they observe where the
    /// scene's start says so.
    #[allow(clippy::too_many_arguments)]
    fn starting_point(
        &self,
        action: &Action,
        disc: &Discretization,
        times: &[f64],
        data: &Data,
        settings: &FitSettings,
        initial: &[f64],
        warnings: &mut Vec<String>,
    ) -> Result<(Vec<f64>, Start), FitError> {
        let start = start_states(self.scene, self.model, disc, times)?;
        match &start.solution {
            Some(z) => {
                let mut ws = self.model.workspace();
                if let Some(f) = statistics::curvature(action, self.plans, self.observations, z, &mut ws) {
                    if let Some(message) = undetermined(&f, self.names, initial) {
                        return Err(FitError::NotIdentifiable(format!("{message} (at the starting values)")));
                    }
                }
            }
            None => warnings.push(format!(
                "the solve at the starting values did not converge ({}); the fit starts from time stepping",
                start.description
            )),
        }
        if settings.method == FitMethod::Reduced && start.solution.is_none() {
            return Err(FitError::Settings(format!(
                "the reduced fit starts from the solve at the starting values, which did not converge ({}): choose other \
                 starting values, or fit all at once (--fit-method all-at-once)",
                start.description
            )));
        }
        let mut q = start.q.clone();
        let start_from_data = match settings.start {
            // The reduced fit's trajectory solves the equations at every point.
            _ if settings.method == FitMethod::Reduced => false,
            FitStart::Auto => self.scene.constraints.is_empty() || data.coordinates.len() == self.scene.coordinates.len(),
            FitStart::Data => true,
            FitStart::Solve => false,
        };
        if start_from_data {
            put_data(&mut q, times, data);
        }
        let mut x0 = point_from_states(action, &q, &start.lambda)[..action.layout.n_p].to_vec();
        x0.extend(initial);
        Ok((x0, start))
    }

    /// The fitted parameters, the misfit, its curvature and the covariance at Ipopt's
    /// `solution`; a converged fit whose curvature leaves a combination of parameters
    /// undetermined is refused naming it, and, where its motion does not describe the
    /// data, as a stationary point of the misfit that is not its minimum.
    fn statistics_at(
        &self,
        action: &mut Action,
        solution: &ipopt::Solution,
        converged: bool,
        data: &Data,
        warnings: &mut Vec<String>,
    ) -> Result<AtSolution, FitError> {
        let n_p = action.layout.n_p;
        let theta = solution.x[n_p..].to_vec();
        let mut ws = self.model.workspace();
        action.set_parameters(&theta, &mut ws);
        let mut z = vec![0.0; action.layout.len()];
        z[..n_p].copy_from_slice(&solution.x[..n_p]);
        let residuals = self.observations.residuals(&solution.x);
        let curvature = statistics::curvature(action, self.plans, self.observations, &z, &mut ws);
        let misfit = report::misfit(self.observations, &residuals, self.names.len(), data.sigma_given);
        if converged {
            if let Some(message) = curvature.as_ref().and_then(|f| statistics::undetermined_where(f, self.names, &theta, "")) {
                let at: Vec<String> = self.names.iter().zip(&theta).map(|(n, v)| format!("{n} = {v}")).collect();
                let at = at.join(", ");
                // Where the fitted motion does not describe the data either, the
                // singular curvature is the point's, not the data's.
                return Err(match advice::misdescription(&misfit, data) {
                    Some(why) => FitError::NotAMinimum(format!(
                        "the fit ended at {at}, where {why} and {message}: a local minimum or a saddle point of the misfit, or \
                         a model that does not describe the data"
                    )),
                    None => FitError::NotIdentifiable(format!("at the fitted values {at}, {message}")),
                });
            }
        }
        let covariance =
            curvature.as_ref().and_then(|f| if misfit.defines_covariance() { covariance(f, misfit.residual_variance) } else { None });
        if !misfit.defines_covariance() {
            warnings.push(format!(
                "{} values for {} parameters and no standard deviations: the residual variance, and with it the standard errors, is undefined",
                self.observations.values.len(),
                self.names.len()
            ));
        }
        Ok(AtSolution { theta, z, curvature, covariance, misfit })
    }

    /// The fit's report.
    #[allow(clippy::too_many_arguments)]
    fn report(
        &self,
        action: &Action,
        solution: &ipopt::Solution,
        (converged, (status, status_text)): (bool, (String, String)),
        settings: &FitSettings,
        start: Start,
        parameters: IndexMap<String, report::ParameterReport>,
        at: AtSolution,
        data: &Data,
        timings: report::Timings,
        inner: Option<InnerWork>,
        warnings: Vec<String>,
    ) -> FitReport {
        let plans = self.plans;
        let k = self.names.len();
        let sizes = match settings.method {
            FitMethod::AllAtOnce => report::Sizes {
                variables: action.layout.n_p + k,
                constraints: action.layout.n_m,
                jacobian_nonzeros: plans.jacobian.structure.len() + plans.parameters.jacobian.len(),
                hessian_nonzeros: plans
                    .hessian
                    .as_ref()
                    .map_or(0, |h| h.structure.len() + self.observations.hessian.len() + plans.parameters.hessian.len()),
                observations: self.observations.values.len(),
            },
            FitMethod::Reduced => report::Sizes {
                variables: k,
                constraints: 0,
                jacobian_nonzeros: 0,
                hessian_nonzeros: k * (k + 1) / 2,
                observations: self.observations.values.len(),
            },
        };
        FitReport {
            converged,
            status,
            status_text,
            iterations: solution.iterations,
            method: settings.method,
            equations_of_motion: inner,
            hessian: settings.hessian,
            start: settings.start,
            start_solve: start.description,
            parameters,
            covariance: at.covariance.map(|c| CovarianceReport::new(self.names, &c)),
            curvature_condition: at.curvature.as_ref().map(report::scaled_condition),
            misfit: at.misfit,
            data: DataReport::new(data, self.scene),
            max_constraint_violation: solution.max_constraint_violation,
            objective: solution.objective,
            sizes,
            work: report::Work {
                constraint_evaluations: solution.eval.constraints.calls as usize,
                jacobian_evaluations: solution.eval.jacobian.calls as usize,
                hessian_evaluations: solution.eval.hessian.calls as usize,
                objective_evaluations: solution.eval.objective.calls as usize,
            },
            timings,
            history: solution.history.clone(),
            warnings,
            fitted_scene: None,
            discretization: Vec::new(),
        }
    }
}

/// The fitted scene solved from the fit's trajectory (`z`, on `action`'s grid) and
/// verified like any solve, by Newton's method (which hands over to Ipopt if it fails):
/// the guess is a solution already, at the equations' round-off level, which Newton
/// accepts after one step; Ipopt's filter line search can fail to decrease a residual at
/// that level, and on the double pendulum it then went through its restoration phase
/// (8 iterations, 1.6 s) where Newton takes one step (docs/benchmarks.md#fitting).
/// The fit's time limit bounds it and its verification, as it bounds a solve's.
fn solved_from_the_fit(
    fitted: &Scene,
    action: &Action,
    disc: &Discretization,
    z: &[f64],
    deadline: Option<Deadline>,
) -> Result<Outcome, FitError> {
    let fitted = on_newton(fitted);
    let fitted_model = Arc::new(Model::build(&fitted)?);
    let (q, lambda) = states_of(action, z);
    let guess = Guess::States { q, lambda, description: "the fit's trajectory".into() };
    let run = solve_global(&fitted, &fitted_model, disc, &guess, deadline)?;
    Ok(outcome(&fitted, &fitted_model, run, deadline))
}

/// `scene` solved by Newton's method (which hands over to Ipopt if it fails): the fit's
/// square solves, whose guesses are close (module docs, steps 2 and 6).
fn on_newton(scene: &Scene) -> Scene {
    let mut newton = scene.clone();
    newton.solver.backend = crate::scene::Backend::Newton;
    newton
}

/// The coordinates and multipliers at the nodes of the unknown vector `z` (the pinned
/// multipliers as 0).
fn states_of(action: &Action, z: &[f64]) -> (NodeSeries, NodeSeries) {
    let lay = &action.layout;
    let q = lay.coordinates(z);
    let lambda = (0..lay.nodes)
        .map(|k| (0..lay.n).map(|a| if lay.lp[k * lay.n + a] == u32::MAX { 0.0 } else { z[lay.lp[k * lay.n + a] as usize] }).collect())
        .collect();
    (q, lambda)
}

/// The scene with the fitted values, and the overrides that resolve it.
fn fitted_scene(scene: &Scene, overrides: &Overrides, names: &[String], theta: &[f64]) -> Result<(Scene, Overrides), FitError> {
    let mut ov = overrides.clone();
    ov.set.retain(|(n, _)| !names.contains(n));
    ov.set.extend(names.iter().zip(theta).map(|(n, x)| (n.clone(), format!("{x:?}"))));
    let mut fitted = scene.file.clone().resolve(&ov)?;
    if !(scene.choose_operator || scene.verify.refine) {
        choose::fixed(&mut fitted);
    }
    Ok((fitted, ov))
}

/// The curvature's matrix of a fit as rows (for the report).
fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows()).map(|i| m.row(i).iter().copied().collect()).collect()
}
