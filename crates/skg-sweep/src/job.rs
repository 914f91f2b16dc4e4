//! The job a worker runs: one point ([`Job`]) computed in this process ([`run_job`]):
//! its scene resolved, solved (or integrated, for the time-stepping peer), its errors
//! against the sweep's reference measured, its files kept if asked; the outcome as a
//! [`Record`], the columns of its row in results.csv. A point that cannot be computed is
//! a record with status `error` and the error's text, never an error of the worker.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use skg_core::check::{self, CheckOptions, Comparison, Table};
use skg_core::discrete::Trajectory;
use skg_core::output;
use skg_core::scene::{Scene, SceneError, SceneFile};
use skg_core::solve::Outcome;

use crate::{AxisError, Method, Point, PointStatus, ReferenceSpec};

/// What a worker process is asked to do.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Job {
    /// The base scene file (absolute path).
    pub scene: PathBuf,
    /// The point to compute.
    pub point: Point,
    /// Where errors are measured against, if anywhere.
    pub reference: Option<ReferenceSpec>,
    /// Columns compared with the reference (None: the scene's coordinates).
    pub compare: Option<Vec<String>>,
    /// End nodes left out of errors and the energy artifact.
    pub skip_last: usize,
    /// Where to keep trajectory.csv and summary.json (None: not kept).
    pub keep_dir: Option<PathBuf>,
    /// Whether the point may use the fallback ladder.
    pub fallback: bool,
    /// Whether the point is solved to its tolerance (`[sweep] refine`).
    #[serde(default)]
    pub refine: bool,
}

/// What a worker reports about one point (the columns of its row in results.csv).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Record {
    /// How the point ended.
    pub status: PointStatus,
    /// The solver's own status name: the finishing backend's (Ipopt's `Solve_Succeeded`,
    /// `Maximum_Iterations_Exceeded`, …, or `Newton_…`) or `ODE_Succeeded` for the
    /// time-stepping peer;
    /// empty when the solver did not finish.
    pub solver_status: String,
    /// Iterations of the backend that finished.
    pub iterations: Option<usize>,
    /// Wall time of the computation inside the worker (scene setup, guess, solve).
    pub wall_s: Option<f64>,
    /// The Newton backend's symbolic LU analysis: `computed` for this point, `reused`
    /// from the worker's previous solve of equal structure, empty when Newton did not
    /// run ([`skg_core::solve::backend::NewtonReport::lu_analysis`]).
    #[serde(default)]
    pub lu_analysis: String,
    /// Node count of the resolved scene.
    pub nodes: Option<usize>,
    /// SBP operator of the resolved scene (SKG points).
    pub operator: Option<String>,
    /// Formulation of the resolved scene (SKG points).
    pub formulation: Option<String>,
    /// Largest max-abs error against the reference over the compared columns.
    pub error_max: Option<f64>,
    /// RMS error of that column.
    pub error_rms: Option<f64>,
    /// The column with the largest error.
    pub error_column: Option<String>,
    /// max |E_k − E_1| over all but the last two nodes.
    pub energy_drift: Option<f64>,
    /// The relative energy artifact ([`skg_core::tune::energy_artifact`]).
    pub energy_artifact: Option<f64>,
    /// Unscaled max residual of the square system.
    pub max_residual: Option<f64>,
    /// SHA-256 of the base scene file as the worker read it (None: not read).
    pub scene_hash: Option<String>,
    /// The verification verdict of a converged SKG point (`passed`, `failed`,
    /// `unverified`), empty otherwise.
    #[serde(default)]
    pub verification: String,
    /// Its max |q − q_reference| against time stepping of the same scene.
    #[serde(default)]
    pub verify_error: Option<f64>,
    /// How the reported trajectory covered the span (`global`, or `windows L s`).
    #[serde(default)]
    pub solved_as: String,
    /// Warnings and errors.
    pub message: String,
}

impl Record {
    /// A record with this status and nothing measured yet.
    pub fn new(status: PointStatus, message: String) -> Record {
        Record {
            status,
            solver_status: String::new(),
            iterations: None,
            wall_s: None,
            lu_analysis: String::new(),
            nodes: None,
            operator: None,
            formulation: None,
            error_max: None,
            error_rms: None,
            error_column: None,
            energy_drift: None,
            energy_artifact: None,
            max_residual: None,
            scene_hash: None,
            verification: String::new(),
            verify_error: None,
            solved_as: String::new(),
            message,
        }
    }
}

/// Run one point in this process (the body of `skg-solve sweep-worker`).
pub fn run_job(job: &Job) -> Record {
    match compute_point(job) {
        Ok(r) => r,
        Err(e) => Record::new(PointStatus::Error, skg_core::error_text(&e)),
    }
}

/// Why one point could not be computed (the message of its `error` row), or why its
/// errors against the reference could not be measured.
#[derive(Debug, thiserror::Error)]
enum PointError {
    #[error(transparent)]
    Axis(#[from] AxisError),
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Solve(#[from] skg_core::solve::SolveError),
    #[error(transparent)]
    Reference(#[from] skg_core::stepping::reference::ReferenceError),
    #[error(transparent)]
    Check(#[from] skg_core::check::CheckError),
    #[error(transparent)]
    Output(#[from] output::OutputError),
}

/// The record of a point: its scene resolved, solved or integrated, its errors and energy
/// artifact measured, its files kept if asked.
fn compute_point(job: &Job) -> Result<Record, PointError> {
    let mut ov = job.point.overrides()?;
    ov.refine |= job.refine;
    let start = Instant::now();
    let file = SceneFile::load(&job.scene)?;
    let scene_hash = file.origin.content_hash();
    let mut scene = file.resolve(&ov)?;
    scene.solver.fallback &= job.fallback;
    let mut rec = Record { nodes: Some(scene.nodes), scene_hash: Some(scene_hash), ..Record::new(PointStatus::Error, String::new()) };
    let compare_cols = job.compare.clone().unwrap_or_else(|| scene.coordinates.clone());
    let (trajectory, ode_csv) = match job.point.method {
        Method::Skg => (solve_point(job, &mut scene, &mut rec, start)?, None),
        Method::Ode { rtol } => (step_point(&scene, rtol, &mut rec, start)?, Some(format!("time stepping, rtol {rtol:e}"))),
    };
    let model = skg_core::model::Model::build(&scene)?;
    if skg_core::tune::conserves_energy(&scene, &model) {
        rec.energy_artifact = Some(skg_core::tune::energy_artifact(&scene, &trajectory, job.skip_last).value);
    }
    let solution = Table::of_trajectory(&scene, &trajectory);
    if let Some(r) = &job.reference {
        record_reference_errors(&mut rec, reference_errors(&scene, r, &solution, &compare_cols, job.skip_last));
    }
    if let (Some(dir), Some(comment)) = (&job.keep_dir, ode_csv) {
        refuse_linked_keep_dir(dir)?;
        output::write_csv(&dir.join("trajectory.csv"), Some(&comment), &solution.columns, &solution.rows)?;
    }
    Ok(rec)
}

/// Solve the action of a point's `scene` as `skg-solve SCENE` does, into `rec`; the
/// scene takes the grid and operator a refinement ended on. Its files are written when
/// the job keeps them.
fn solve_point(job: &Job, scene: &mut Scene, rec: &mut Record, start: Instant) -> Result<Trajectory, PointError> {
    rec.operator = Some(scene.operator.name().to_string());
    rec.formulation = Some(scene.formulation.to_string());
    let mut outcome = skg_core::solve::solve_scene(scene)?;
    rec.wall_s = Some(start.elapsed().as_secs_f64());
    if outcome.refinement.is_some() {
        // The grid and operator the solve ended on, for the row and the errors.
        scene.nodes = outcome.settings.nodes;
        scene.operator = outcome.settings.operator.parse().unwrap_or(scene.operator);
        scene.initial_velocity = outcome.settings.initial_velocity;
        rec.nodes = Some(scene.nodes);
        rec.operator = Some(outcome.settings.operator.clone());
    }
    record_outcome(rec, &outcome);
    if let Some(dir) = &job.keep_dir {
        refuse_linked_keep_dir(dir)?;
        output::write_outcome(dir, &mut outcome, scene)?;
    }
    Ok(outcome.trajectory)
}

/// The columns of a solve's row: its status, the solver's, the verification, how it
/// covered the span, its work and diagnostics, its warnings.
fn record_outcome(rec: &mut Record, outcome: &Outcome) {
    rec.status = match (outcome.converged(), outcome.trusted()) {
        (true, true) => PointStatus::Converged,
        (true, false) => PointStatus::NotVerified,
        (false, _) => PointStatus::NotConverged,
    };
    rec.solver_status = outcome.status.solver().name().to_string();
    if outcome.converged() {
        rec.verification = outcome.verification.status.to_string();
        rec.verify_error = outcome.verification.max_error;
    }
    rec.solved_as = match outcome.method {
        skg_core::solve::Method::Global => "global".into(),
        skg_core::solve::Method::Windows { length, .. } => format!("windows {length:.4} s"),
    };
    rec.iterations = Some(outcome.iterations);
    rec.lu_analysis = outcome.backend.newton.as_ref().map_or("", |n| n.lu_analysis()).to_string();
    let d = &outcome.diagnostics;
    rec.energy_drift = Some(d.energy_drift);
    rec.max_residual = Some(d.max_residual);
    rec.message = outcome.warnings.join(" | ");
}

/// Integrate a peer point's `scene` by time stepping at `rtol` (= atol) onto its grid,
/// into `rec`.
fn step_point(scene: &Scene, rtol: f64, rec: &mut Record, start: Instant) -> Result<Trajectory, PointError> {
    let (times, _) = skg_core::solve::grid(scene);
    let opts = skg_core::stepping::reference::ReferenceOptions { rtol, atol: rtol, stepper: scene.verify.stepper };
    let r = skg_core::stepping::reference::regularized(scene, &times, &opts)?;
    rec.wall_s = Some(start.elapsed().as_secs_f64());
    rec.status = PointStatus::Converged;
    rec.solver_status = "ODE_Succeeded".into();
    Ok(r.trajectory)
}

/// The errors against the reference into `rec`, or why they could not be measured into
/// its message (the point is not failed for it).
fn record_reference_errors(rec: &mut Record, comparison: Result<Comparison, PointError>) {
    match comparison {
        Ok(c) => {
            rec.error_max = Some(c.max_abs);
            rec.error_rms = c.columns.iter().find(|e| e.column == c.worst_column).map(|e| e.rms);
            rec.error_column = Some(c.worst_column);
        }
        Err(e) => {
            if !rec.message.is_empty() {
                rec.message.push_str(" | ");
            }
            rec.message.push_str(&format!("reference comparison failed: {}", skg_core::error_text(&e)));
        }
    }
}

/// Errors of a solution against the sweep's reference on `columns`, the last
/// `skip_last` nodes excluded (errors go into the record's message, never abort the
/// point).
fn reference_errors(
    scene: &Scene,
    reference: &ReferenceSpec,
    solution: &Table,
    columns: &[String],
    skip_last: usize,
) -> Result<Comparison, PointError> {
    use skg_core::stepping::reference::{hard_wall, regularized, ReferenceOptions};
    let reference = match reference {
        ReferenceSpec::File(p) => Table::read(p)?,
        computed @ (ReferenceSpec::Integrate | ReferenceSpec::HardWalls) => {
            // Both references are integrated on the point's own grid, the same way.
            let integrate = if matches!(computed, ReferenceSpec::HardWalls) { hard_wall } else { regularized };
            let r = integrate(scene, &solution.times(), &ReferenceOptions::default())?;
            Table::of_trajectory(scene, &r.trajectory)
        }
    };
    let opts = CheckOptions { skip_last, columns: Some(columns.to_vec()) };
    Ok(check::compare(solution, &reference, &opts)?)
}

/// Refuse a symbolic link at a kept point's directory `DIR/points/<id>` or at
/// `DIR/points`: the point's files would be written wherever it points.
fn refuse_linked_keep_dir(dir: &Path) -> Result<(), output::OutputError> {
    let (Some(points), Some(id)) = (dir.parent(), dir.file_name()) else { return Ok(()) };
    let (Some(sweep_dir), Some(name)) = (points.parent(), points.file_name()) else { return Ok(()) };
    output::refuse_links(sweep_dir, &Path::new(name).join(id))
}
