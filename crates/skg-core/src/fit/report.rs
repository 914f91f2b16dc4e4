//! What a fit reports: the `fit` object of `summary.json` ([`FitReport`]: the
//! parameters with their standard errors, starting values and bounds, the covariance,
//! the misfit, the data used, Ipopt's iterations and status), the scene's text with the
//! fitted values (`fitted.toml`), and the data beside the fitted motion (`data.csv`).

use indexmap::IndexMap;
use nalgebra::DMatrix;
use serde::Serialize;

use super::data::{Data, SIGMA_PREFIX, WRITTEN_PREFIXES};
use super::free::FreeParameter;
use super::observe::Observations;
use super::{rows, ChosenDiscretization, FitHessian, FitMethod, FitStart, InnerWork};
use crate::discrete::interpolate::hermite;
use crate::discrete::{Discretization, Trajectory};
use crate::scene::provenance;
use crate::scene::{NumOrExpr, Overrides, Scene};
use skg_ipopt::IterationStat;

/// One fitted parameter.
#[derive(Debug, Clone, Serialize)]
pub struct ParameterReport {
    /// The fitted value.
    pub value: f64,
    /// Its standard error (the square root of the covariance's diagonal); `null` when
    /// the covariance is undefined.
    pub std_error: Option<f64>,
    /// The starting value (the scene's).
    pub initial: f64,
    /// The bounds, `null` for a side without one.
    pub bound: [Option<f64>; 2],
    /// Whether the value ended on a bound (within 1e-6 of its size).
    pub at_bound: bool,
}

/// The covariance of the fitted parameters.
#[derive(Debug, Clone, Serialize)]
pub struct CovarianceReport {
    /// The parameters, in the order of the rows and columns.
    pub names: Vec<String>,
    /// The covariance matrix.
    pub matrix: Vec<Vec<f64>>,
    /// The correlation matrix `C_ij / √(C_ii C_jj)`.
    pub correlation: Vec<Vec<f64>>,
}

impl CovarianceReport {
    /// The report of the covariance `c` of the parameters `names`.
    pub fn new(names: &[String], c: &DMatrix<f64>) -> CovarianceReport {
        let corr = DMatrix::from_fn(c.nrows(), c.ncols(), |i, j| c[(i, j)] / (c[(i, i)] * c[(j, j)]).sqrt());
        CovarianceReport { names: names.to_vec(), matrix: rows(c), correlation: rows(&corr) }
    }
}

/// The misfit at the fitted values.
#[derive(Debug, Clone, Serialize)]
pub struct MisfitReport {
    /// `Σ w_i r_i²`, the residuals `r_i` (model − data) weighted by `1/σ_i²` (the
    /// chi-square) when the data give standard deviations, plain otherwise.
    pub sum_of_squares: f64,
    /// Whether the residuals are weighted by standard deviations.
    pub weighted: bool,
    /// The values fitted, `m`.
    pub points: usize,
    /// The free parameters, `p`.
    pub parameters: usize,
    /// The degrees of freedom `m − p`.
    pub dof: usize,
    /// Without standard deviations: `Σ r_i²/(m − p)`, which scales the covariance
    /// (`null` with standard deviations, or without degrees of freedom).
    pub residual_variance: Option<f64>,
    /// With standard deviations: the chi-square per degree of freedom (about 1 when the
    /// model and the standard deviations describe the data).
    pub reduced_chi_square: Option<f64>,
    /// `√(Σ r_i²/m)`, unweighted, in the coordinates' units.
    pub rms_residual: f64,
    /// The largest `|r_i|`, unweighted.
    pub max_abs_residual: f64,
}

impl MisfitReport {
    /// Whether a covariance can be given: with standard deviations always, without them
    /// only when there are more values than parameters.
    pub fn defines_covariance(&self) -> bool {
        self.weighted || self.dof > 0
    }

    /// The reduced chi-square and its spread `√(2/ν)` when the data's standard
    /// deviations do not explain it: above 2 and more than five spreads above 1 (the
    /// chi-square per degree of freedom of data the model and the standard deviations
    /// describe is 1 ± `√(2/ν)`).
    pub fn beyond_the_noise(&self) -> Option<(f64, f64)> {
        let x = self.reduced_chi_square?;
        let spread = (2.0 / self.dof as f64).sqrt();
        (x > 2.0 && x > 1.0 + 5.0 * spread).then_some((x, spread))
    }
}

/// The data a fit used.
#[derive(Debug, Clone, Serialize)]
pub struct DataReport {
    /// Where they came from (a file's path as given, or a label).
    pub origin: String,
    /// The values fitted.
    pub points: usize,
    /// The rows (times) of the table.
    pub rows: usize,
    /// The values of each observed coordinate.
    pub coordinates: IndexMap<String, usize>,
    /// The first and the last time.
    pub t_first: f64,
    /// The last time.
    pub t_last: f64,
    /// Whether the data give standard deviations (else: equal weights, the covariance
    /// scaled by the residual variance).
    pub sigma_given: bool,
}

impl DataReport {
    /// The report of `data` for `scene`.
    pub fn new(data: &Data, scene: &Scene) -> DataReport {
        DataReport {
            origin: data.origin.clone(),
            points: data.observations.len(),
            rows: data.times.len(),
            coordinates: data.coordinates.iter().map(|&i| (scene.coordinates[i].clone(), data.count(i))).collect(),
            t_first: data.times[0],
            t_last: data.times[data.times.len() - 1],
            sigma_given: data.sigma_given,
        }
    }
}

/// The sizes of the problem handed to Ipopt.
#[derive(Debug, Clone, Serialize)]
pub struct Sizes {
    /// Unknowns: the trajectory's and the free parameters (the parameters alone in the
    /// reduced fit, whose constraints and Jacobian are then empty).
    pub variables: usize,
    /// Equality constraints: the stationarity equations.
    pub constraints: usize,
    /// Nonzeros of the constraints' Jacobian.
    pub jacobian_nonzeros: usize,
    /// Nonzeros of the Hessian of the Lagrangian (0 with the limited-memory Hessian).
    pub hessian_nonzeros: usize,
    /// The values fitted.
    pub observations: usize,
}

/// The evaluations Ipopt asked for.
#[derive(Debug, Clone, Serialize)]
pub struct Work {
    /// Of the constraints (the final recomputation included).
    pub constraint_evaluations: usize,
    /// Of their Jacobian.
    pub jacobian_evaluations: usize,
    /// Of the Hessian of the Lagrangian.
    pub hessian_evaluations: usize,
    /// Of the objective and its gradient.
    pub objective_evaluations: usize,
}

/// Where a fit's wall time went, in seconds.
#[derive(Debug, Clone, Serialize)]
pub struct Timings {
    /// Checks, the model, the plans and the solve at the starting values.
    pub start_s: f64,
    /// Ipopt's optimization.
    pub optimization_s: f64,
    /// Of it, Ipopt's own time (mostly MUMPS).
    pub ipopt_internal_s: f64,
    /// The sensitivities, the covariance and the identifiability test.
    pub statistics_s: f64,
    /// The solve at the fitted values and its verification.
    pub verification_s: f64,
    /// The refinements that chose the discretization (`--refine`, `--operator auto`);
    /// 0 where it was named.
    pub discretization_s: f64,
    /// The whole fit (with a first fit, when the discretization was chosen again at its
    /// fitted values).
    pub total_s: f64,
}

/// What a fit did and found: the `fit` object of `summary.json` (docs/output.md).
#[derive(Debug, Clone, Serialize)]
pub struct FitReport {
    /// Whether Ipopt converged (`Solve_Succeeded`, or `Solved_To_Acceptable_Level` with a
    /// warning).
    pub converged: bool,
    /// Ipopt's status.
    pub status: String,
    /// The status in words.
    pub status_text: String,
    /// Ipopt's iterations.
    pub iterations: usize,
    /// How the fit was handed to Ipopt.
    pub method: FitMethod,
    /// The reduced fit's solves of the equations of motion (`null` all at once).
    pub equations_of_motion: Option<InnerWork>,
    /// The Hessian given to Ipopt.
    pub hessian: FitHessian,
    /// Where the trajectory started.
    pub start: FitStart,
    /// How the start's solve went.
    pub start_solve: String,
    /// The fitted parameters by name, in the order they were named.
    pub parameters: IndexMap<String, ParameterReport>,
    /// Their covariance (`null` when undefined).
    pub covariance: Option<CovarianceReport>,
    /// The smallest eigenvalue of the scaled Gauss–Newton curvature relative to its
    /// largest (docs/fitting.md#identifiability): near 0, the data barely determine a
    /// combination of the parameters.
    pub curvature_condition: Option<f64>,
    /// The misfit at the fitted values.
    pub misfit: MisfitReport,
    /// The data used.
    pub data: DataReport,
    /// The largest residual of the stationarity equations at Ipopt's solution.
    pub max_constraint_violation: f64,
    /// Ipopt's objective at its solution, `½ Σ w_i r_i²`.
    pub objective: f64,
    /// The problem's sizes.
    pub sizes: Sizes,
    /// The evaluations Ipopt asked for.
    pub work: Work,
    /// Where the time went.
    pub timings: Timings,
    /// Ipopt's iteration table.
    pub history: Vec<IterationStat>,
    /// What the user should know (a bound reached, an acceptable level, …).
    pub warnings: Vec<String>,
    /// The fitted scene's file and its SHA-256, once written.
    pub fitted_scene: Option<FittedSceneFile>,
    /// How the refinement chose the discretization (`--operator auto`, `--refine`): at
    /// the starting values, and again at the fitted values of a first fit whose motion
    /// did not verify; empty where the scene and the command line name it.
    pub discretization: Vec<ChosenDiscretization>,
}

/// The fitted scene as written beside the run.
#[derive(Debug, Clone, Serialize)]
pub struct FittedSceneFile {
    /// The file's name in the output directory.
    pub file: String,
    /// SHA-256 of its bytes, `sha256:<hex>`.
    pub sha256: String,
}

impl FitReport {
    /// The fitted values by name.
    pub fn values(&self) -> IndexMap<String, f64> {
        self.parameters.iter().map(|(n, p)| (n.clone(), p.value)).collect()
    }
}

/// The misfit report of the residuals `r` of `observations`, fitted with `parameters`
/// free parameters.
pub(super) fn misfit(observations: &Observations, r: &[f64], parameters: usize, weighted: bool) -> MisfitReport {
    let m = r.len();
    let sum_of_squares: f64 = r.iter().zip(&observations.weights).map(|(r, w)| w * r * r).sum();
    let plain: f64 = r.iter().map(|r| r * r).sum();
    let dof = m.saturating_sub(parameters);
    MisfitReport {
        sum_of_squares,
        weighted,
        points: m,
        parameters,
        dof,
        residual_variance: (!weighted && dof > 0).then(|| plain / dof as f64),
        reduced_chi_square: (weighted && dof > 0).then(|| sum_of_squares / dof as f64),
        rms_residual: (plain / m as f64).sqrt(),
        max_abs_residual: r.iter().fold(0.0_f64, |a, x| a.max(x.abs())),
    }
}

/// The report of each free parameter at the fitted values `theta`.
pub(super) fn parameters(
    free: &[FreeParameter],
    theta: &[f64],
    initial: &[f64],
    cov: Option<&DMatrix<f64>>,
) -> IndexMap<String, ParameterReport> {
    let near = |x: f64, b: Option<f64>| b.is_some_and(|b| (x - b).abs() <= 1e-6 * b.abs().max(1.0));
    free.iter()
        .enumerate()
        .map(|(j, p)| {
            let value = theta[j];
            let report = ParameterReport {
                value,
                std_error: cov.map(|c| c[(j, j)].max(0.0).sqrt()),
                initial: initial[j],
                bound: [p.lower, p.upper],
                at_bound: near(value, p.lower) || near(value, p.upper),
            };
            (p.name.clone(), report)
        })
        .collect()
}

/// The smallest eigenvalue of the curvature scaled to a unit diagonal, relative to its
/// largest (0 when a diagonal entry vanishes).
pub(super) fn scaled_condition(f: &DMatrix<f64>) -> f64 {
    let n = f.nrows();
    if (0..n).any(|j| f[(j, j)].is_nan() || f[(j, j)] <= 0.0) {
        return 0.0;
    }
    let c = DMatrix::from_fn(n, n, |i, j| f[(i, j)] / (f[(i, i)] * f[(j, j)]).sqrt());
    let e = c.symmetric_eigenvalues();
    let (lo, hi) = (e.iter().copied().fold(f64::INFINITY, f64::min), e.iter().copied().fold(f64::NEG_INFINITY, f64::max));
    (lo / hi).max(0.0)
}

/// The scene file's text with the fitted values in place of the free parameters'
/// definitions (and the command line's `--set` values in place of theirs), with a
/// comment at the top saying what was fitted and on which discretization `disc`.
pub(super) fn fitted_toml(scene: &Scene, disc: &Discretization, overrides: &Overrides, report: &FitReport) -> String {
    let file = &scene.file;
    let text = &file.origin.text;
    let mut edits: Vec<(std::ops::Range<usize>, String)> = Vec::new();
    for (name, value) in &overrides.set {
        if let Some(spanned) = file.parameters.get(name) {
            let new = match value.parse::<f64>() {
                Ok(x) => format!("{x:?}"),
                Err(_) => format!("{:?}", NumOrExpr::Expr(value.clone()).to_string()),
            };
            edits.push((spanned.span(), new));
        }
    }
    // The data are written beside fitted.toml: its `[fit] data` names that copy, so that
    // the fitted scene can be fitted again from its own directory.
    if let Some(data) = file.fit.as_ref().and_then(|f| f.data.as_ref()) {
        edits.push((data.span(), format!("{:?}", super::files::DATA_FILE)));
    }
    edits.sort_by_key(|e| std::cmp::Reverse(e.0.start));
    let mut out = text.clone();
    for (span, new) in edits {
        if span.end <= out.len() && out.is_char_boundary(span.start) && out.is_char_boundary(span.end) {
            out.replace_range(span, &new);
        }
    }
    let lines: Vec<String> = report
        .parameters
        .iter()
        .map(|(n, p)| {
            let se = p.std_error.map_or(String::new(), |s| format!(" ± {s:.3e}"));
            format!("#   {n} = {:?}{se} (from {:?})", p.value, p.initial)
        })
        .collect();
    let grid = match disc.grid.name() {
        "adaptive" => "an adaptive grid (its map from the motion at the starting values)",
        _ => "a uniform grid",
    };
    let (operator, velocity, nodes) = (disc.operator.name(), disc.initial_velocity, disc.nodes);
    let on = format!(
        "#   on {operator} ({velocity} initial velocity), {nodes} nodes of {grid}: skg-solve {} --operator {operator} \
         --initial-velocity {velocity} --nodes {nodes} --grid {} solves it",
        super::FITTED_SCENE_FILE,
        disc.grid.name()
    );
    format!(
        "# Fitted by skg-solve {} to {} ({} values; Ipopt: {}, {} iterations):\n{}\n{on}\n{out}",
        provenance::VERSION,
        report.data.origin,
        report.data.points,
        report.status,
        report.iterations,
        lines.join("\n")
    )
}

/// The data beside the fitted motion at the data's times: `t`, then for each observed
/// coordinate `c` its data `c`, their standard deviation `sigma_c` (when given), the
/// fitted motion `fitted_c` (the trajectory's cubic Hermite interpolation, as the fit
/// compared them) and the residual `residual_c` (fitted − data); NaN where a coordinate
/// was not observed (an empty cell in `data.csv`, which a fit reads back as data, the
/// fitted and residual columns passed over).
pub(super) fn data_table(scene: &Scene, data: &Data, tr: &Trajectory) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut header = vec!["t".to_string()];
    for &i in &data.coordinates {
        let c = &scene.coordinates[i];
        header.push(c.clone());
        if data.sigma_given {
            header.push(format!("{SIGMA_PREFIX}{c}"));
        }
        header.extend(WRITTEN_PREFIXES.iter().map(|p| format!("{p}{c}")));
    }
    let fitted = hermite(tr, &data.times);
    let rows = data
        .times
        .iter()
        .enumerate()
        .map(|(r, &t)| {
            let mut row = vec![t];
            for &i in &data.coordinates {
                let o = data.observations.iter().find(|o| o.row == r && o.coordinate == i);
                row.push(o.map_or(f64::NAN, |o| o.value));
                if data.sigma_given {
                    row.push(o.map_or(f64::NAN, |o| o.sigma));
                }
                row.push(fitted[r][i]);
                row.push(o.map_or(f64::NAN, |o| fitted[r][i] - o.value));
            }
            row
        })
        .collect();
    (header, rows)
}
