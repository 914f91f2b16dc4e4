//! The driver of a sweep run ([`run_sweep`]): it queues the points not yet in
//! `results.csv` (largest estimated cost first, equal structures together), hands them to
//! the worker processes ([`workers`]) and records each finished point, until the queue is
//! empty or a stop signal arrives.
//!
//! * **Results**: the driver alone appends to `results.csv`, one whole line per
//!   finished point, flushed and fsync'd, and holds the output directory's lock
//!   ([`output::OutputDir`]) meanwhile, so a second sweep into it is refused. On a rerun
//!   a trailing partial line (from a kill in the middle of a write) is cut off and points
//!   whose id is present are skipped: no row is lost or duplicated; with
//!   [`SweepOptions::retry_failed`] the rows of points that did not converge are removed
//!   first, so they run again.
//! * **Identity of the inputs**: rows carry the hashes of the base scene and of the
//!   reference file, `sweep.json` the [`RowSettings`]; a rerun with other inputs is
//!   refused ([`SweepOptions::new_results`] moves the old result set aside instead).

use std::collections::{HashSet, VecDeque};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use skg_core::output;
use skg_core::scene::SceneFile;

use crate::error::create_dir_err;
use crate::{
    csv_line, header_names, results, results_row, shards, stop_signal, workers, Column, Expanded, Job, Method, Point, PointStatus,
    Provenance, Record, ReferenceSpec, RowSettings, Shard, SweepError, SweepFile, SweepInfo,
};

/// Options of [`run_sweep`].
#[derive(Debug, Clone)]
pub struct SweepOptions {
    /// Output directory (results.csv, sweep.json, points/).
    pub out_dir: PathBuf,
    /// Worker processes at once.
    pub jobs: usize,
    /// Run only this shard's points.
    pub shard: Option<Shard>,
    /// The executable that runs `sweep-worker WORK` (the skg-solve binary, [`workers`]).
    pub worker_exe: PathBuf,
    /// Show a progress bar (hidden anyway when stderr is not a terminal).
    pub progress: bool,
    /// Run again the points whose rows say they did not converge (crashed, timed out,
    /// failed): their rows are replaced.
    pub retry_failed: bool,
    /// Start a new result set: move the output directory's results (results.csv,
    /// sweep.json, points/) into `superseded-<unix time>/` first.
    pub new_results: bool,
}

/// Summary of a sweep run.
#[derive(Debug, Clone, Default)]
pub struct SweepReport {
    /// Points of the whole sweep.
    pub total: usize,
    /// Points of this shard (all points without a shard).
    pub in_shard: usize,
    /// Already in results.csv when the run started.
    pub skipped: usize,
    /// Points computed by this run.
    pub ran: usize,
    /// Points of this run that did not converge (any status but converged).
    pub failed: usize,
    /// Identical points given twice in the sweep file (run once).
    pub duplicates: usize,
    /// The results file.
    pub results: PathBuf,
    /// Wall time of the run in seconds.
    pub wall_s: f64,
    /// Where the previous results went (`--new-results`).
    pub superseded: Option<PathBuf>,
}

/// Refuse to resume into `dir` when its `sweep.json` (if any) records other row settings.
fn check_row_settings(dir: &Path, settings: &RowSettings) -> Result<(), SweepError> {
    if !dir.join("sweep.json").is_file() {
        return Ok(());
    }
    let old = SweepInfo::read(dir)?;
    if old.settings == *settings {
        return Ok(());
    }
    Err(SweepError::Results {
        path: dir.join("sweep.json"),
        message: format!(
            "the results here were computed with other [sweep] settings ({}; now {}): restore them, use another output \
             directory, or start a new result set with --new-results",
            serde_json::to_string(&old.settings).unwrap_or_default(),
            serde_json::to_string(settings).unwrap_or_default()
        ),
    })
}

/// Move the results of `dir` (results.csv, sweep.json, points/) into
/// `dir/superseded-<unix time>/`; returns that directory if there was anything to move.
fn supersede_results(dir: &Path) -> Result<Option<PathBuf>, SweepError> {
    let present: Vec<&str> = ["results.csv", "sweep.json", "points"].into_iter().filter(|n| dir.join(n).exists()).collect();
    if present.is_empty() {
        return Ok(None);
    }
    let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let target = dir.join(format!("superseded-{secs}"));
    std::fs::create_dir_all(&target).map_err(create_dir_err(&target))?;
    for name in present {
        let (from, to) = (dir.join(name), target.join(name));
        std::fs::rename(&from, &to).map_err(|error| SweepError::Move { from, to, error })?;
    }
    Ok(Some(target))
}

/// Run (or resume) a sweep whose points `expanded` are ([`SweepFile::expand`]).
pub fn run_sweep(file: &SweepFile, expanded: &Expanded, opts: &SweepOptions) -> Result<SweepReport, SweepError> {
    let started = Instant::now();
    let columns = expanded.columns();
    let provenance = Provenance::current(expanded.scene_hash.clone(), expanded.reference_hash.clone());
    let dir = &opts.out_dir;
    let _lock = output::OutputDir::lock(dir)?;
    refuse_sharded_dir(dir)?;
    if file.sweep.keep_trajectories {
        output::refuse_links(dir, Path::new("points"))?;
    }
    let superseded = if opts.new_results { supersede_results(dir)? } else { None };
    let settings = file.row_settings();
    check_row_settings(dir, &settings)?;
    let work = fresh_work_dir(dir)?;
    let results_path = dir.join("results.csv");
    let (results, done) = results::open_results(&results_path, &header_names(&columns), &provenance, opts.retry_failed)?;
    let mine: Vec<&Point> = expanded.points.iter().filter(|p| opts.shard.is_none_or(|s| s.contains(p.index))).collect();
    let info = sweep_info(file, expanded, opts.shard, &provenance, settings, &mine);
    output::write_json(&dir.join("sweep.json"), &info)?;
    let mut queue = queue(&mine, &done, expanded);
    let mut report = SweepReport {
        total: expanded.points.len(),
        in_shard: mine.len(),
        skipped: mine.len() - queue.len(),
        duplicates: expanded.duplicates,
        results: results_path.clone(),
        superseded,
        ..SweepReport::default()
    };
    let bar = progress_bar(opts.progress, mine.len(), report.skipped);
    let jobs = JobTemplate::new(file, dir);
    let mut recorder = Recorder {
        base: SceneFile::load(&jobs.scene).ok(),
        file: results,
        path: results_path,
        columns,
        provenance,
        artifact_tol: file.artifact_tol(),
    };
    let pool = workers::Pool::new(&opts.worker_exe, &work, opts.jobs, file.sweep.timeout.as_ref().map(|t| *t.get_ref()));
    let ran = run_points(pool, &mut queue, expanded, &jobs, &mut recorder, &mut report, &bar);
    bar.finish_and_clear();
    ran?;
    let _ = std::fs::remove_dir(&work);
    report.wall_s = started.elapsed().as_secs_f64();
    Ok(report)
}

/// Refuse a sharded directory ([`shards`]): its results.csv is the merge's alone.
fn refuse_sharded_dir(dir: &Path) -> Result<(), SweepError> {
    if !dir.join(shards::LAYOUT_FILE).exists() {
        return Ok(());
    }
    Err(SweepError::Results {
        path: dir.to_path_buf(),
        message: format!(
            "is the directory of a sweep split into shards ({}): its results.csv is written only by the merge of \
             its shards. Run it as it was started (`skg-solve sweep FILE --slurm -o DIR`, or skg.sweep(..., \
             executor=...)), see `skg-solve status DIR`, or use another output directory",
            shards::LAYOUT_FILE
        ),
    })
}

/// An empty work directory `dir/.work` for the workers' files (those left by an
/// interrupted run are stale).
fn fresh_work_dir(dir: &Path) -> Result<PathBuf, SweepError> {
    let work = dir.join(".work");
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).map_err(create_dir_err(&work))?;
    Ok(work)
}

/// The `sweep.json` of a run over the points `mine` of `expanded`.
fn sweep_info(
    file: &SweepFile,
    expanded: &Expanded,
    shard: Option<Shard>,
    provenance: &Provenance,
    settings: RowSettings,
    mine: &[&Point],
) -> SweepInfo {
    SweepInfo {
        name: file.name(),
        sweep_file: file.origin.path.clone(),
        scene: file.scene_path().display().to_string(),
        provenance: provenance.clone(),
        total_points: expanded.points.len(),
        shard: shard.map(|s| format!("{}/{}", s.k, s.n)),
        settings,
        ids: mine.iter().map(|p| p.id()).collect(),
        all_ids: expanded.points.iter().map(Point::id).collect(),
    }
}

/// The points of `mine` not yet `done`, in the order they go out: largest estimated cost
/// first, equal structures together (stable: the file's order otherwise; rows carry
/// their index).
fn queue(mine: &[&Point], done: &HashSet<String>, expanded: &Expanded) -> VecDeque<Point> {
    let mut todo: Vec<Point> = mine.iter().filter(|p| !done.contains(&p.id())).map(|&p| p.clone()).collect();
    let (costs, structures) = (&expanded.costs, &expanded.structures);
    todo.sort_by(|a, b| costs[b.index].total_cmp(&costs[a.index]).then_with(|| structures[a.index].cmp(&structures[b.index])));
    todo.into()
}

/// What every job of a run shares: the base scene and the sweep file's settings.
struct JobTemplate<'a> {
    file: &'a SweepFile,
    /// The output directory (a kept point's files go to `points/<id>` in it).
    dir: &'a Path,
    /// The base scene file, as an absolute path.
    scene: PathBuf,
    reference: Option<ReferenceSpec>,
}

impl<'a> JobTemplate<'a> {
    fn new(file: &'a SweepFile, dir: &'a Path) -> JobTemplate<'a> {
        let scene = std::path::absolute(file.scene_path()).unwrap_or(file.scene_path());
        JobTemplate { file, dir, scene, reference: file.reference() }
    }

    /// The job of `point`.
    fn job(&self, point: Point) -> Job {
        let sweep = &self.file.sweep;
        Job {
            scene: self.scene.clone(),
            keep_dir: sweep.keep_trajectories.then(|| self.dir.join("points").join(point.id())),
            point,
            reference: self.reference.clone(),
            compare: sweep.compare.as_ref().map(|c| c.get_ref().clone()),
            skip_last: self.file.skip_last(),
            fallback: sweep.fallback,
            refine: sweep.refine,
        }
    }
}

/// Where a run records finished points: `results.csv`, open for appending, and what its
/// rows need.
struct Recorder {
    file: std::fs::File,
    path: PathBuf,
    columns: Vec<Column>,
    provenance: Provenance,
    artifact_tol: f64,
    /// The base scene, for the rows of points whose worker crashed or timed out
    /// ([`fill_point_settings`]).
    base: Option<SceneFile>,
}

impl Recorder {
    /// Append the row of `point`, finished with `rec`; its status.
    fn record(&mut self, point: &Point, mut rec: Record) -> Result<PointStatus, SweepError> {
        fill_point_settings(&mut rec, point, self.base.as_ref());
        let line = csv_line(&results_row(&self.columns, point, &rec, self.artifact_tol, &self.provenance));
        results::append(&mut self.file, &self.path, &line)?;
        Ok(rec.status)
    }
}

/// Hand the points of `queue` to the workers of `pool` and record each finished one,
/// until every point is recorded or a stop signal arrives ([`SweepError::Stopped`]: every
/// row written is whole; the points in flight are lost with their workers, which end
/// with the pool).
fn run_points(
    mut pool: workers::Pool,
    queue: &mut VecDeque<Point>,
    expanded: &Expanded,
    jobs: &JobTemplate,
    recorder: &mut Recorder,
    report: &mut SweepReport,
    bar: &indicatif::ProgressBar,
) -> Result<(), SweepError> {
    loop {
        if let Some(signal) = stop_signal() {
            return Err(SweepError::Stopped { signal, recorded: report.ran, results: recorder.path.clone() });
        }
        while pool.hand_out(queue, expanded, |point| jobs.job(point))? {}
        if queue.is_empty() {
            pool.close_idle();
            if pool.busy() == 0 {
                return Ok(());
            }
        }
        std::thread::sleep(Duration::from_millis(5));
        for (point, rec) in pool.finished()? {
            let status = recorder.record(&point, rec)?;
            report.ran += 1;
            if !status.is_converged() {
                report.failed += 1;
                bar.set_message(format!("{} failed", report.failed));
            }
            bar.inc(1);
        }
    }
}

/// The progress bar of a run over `len` points of which `done` are already done.
fn progress_bar(visible: bool, len: usize, done: usize) -> indicatif::ProgressBar {
    let bar = if visible { indicatif::ProgressBar::new(len as u64) } else { indicatif::ProgressBar::hidden() };
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} points, {msg}, {elapsed} elapsed, ETA {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_position(done as u64);
    bar.reset_eta();
    bar.set_message("0 failed");
    bar
}

/// The node count, operator and formulation of a point whose record lacks them (its
/// worker crashed or timed out before it said), from its scene resolved here as the
/// expansion resolved it, so that no row leaves these columns blank.
fn fill_point_settings(rec: &mut Record, point: &Point, base: Option<&SceneFile>) {
    if rec.nodes.is_some() && rec.operator.is_some() && rec.formulation.is_some() {
        return;
    }
    let Some(scene) = base.and_then(|b| b.clone().resolve(&point.overrides().ok()?).ok()) else { return };
    rec.nodes.get_or_insert(scene.nodes);
    if point.method == Method::Skg {
        rec.operator.get_or_insert_with(|| scene.operator.name().to_string());
        rec.formulation.get_or_insert_with(|| scene.formulation.to_string());
    }
}
