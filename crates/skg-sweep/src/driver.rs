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

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use skg_core::output;
use skg_core::scene::SceneFile;

use crate::error::create_dir_err;
use crate::{
    csv_line, header_names, results, results_row, shards, stop_signal, workers, Expanded, Job, Method, Point, Provenance, Record,
    RowSettings, Shard, SweepError, SweepFile, SweepInfo,
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
        std::fs::rename(&from, &to).map_err(|source| SweepError::Move { from, to, source })?;
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
    if dir.join(shards::LAYOUT_FILE).exists() {
        return Err(SweepError::Results {
            path: dir.clone(),
            message: format!(
                "is the directory of a sweep split into shards ({}): its results.csv is written only by the merge of \
                 its shards. Run it as it was started (`skg-solve sweep FILE --slurm -o DIR`, or skg.sweep(..., \
                 executor=...)), see `skg-solve status DIR`, or use another output directory",
                shards::LAYOUT_FILE
            ),
        });
    }
    let superseded = if opts.new_results { supersede_results(dir)? } else { None };
    let settings = file.row_settings();
    check_row_settings(dir, &settings)?;
    // Worker files left by an interrupted run are stale: start from an empty .work.
    let work = dir.join(".work");
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).map_err(create_dir_err(&work))?;
    let results_path = dir.join("results.csv");
    let (mut results, done) = results::open_results(&results_path, &header_names(&columns), &provenance, opts.retry_failed)?;

    let mine: Vec<&Point> = expanded.points.iter().filter(|p| opts.shard.is_none_or(|s| s.contains(p.index))).collect();
    let info = SweepInfo {
        name: file.name(),
        sweep_file: file.origin.path.clone(),
        scene: file.scene_path().display().to_string(),
        provenance: provenance.clone(),
        total_points: expanded.points.len(),
        shard: opts.shard.map(|s| format!("{}/{}", s.k, s.n)),
        settings,
        ids: mine.iter().map(|p| p.id()).collect(),
        all_ids: expanded.points.iter().map(Point::id).collect(),
    };
    output::write_json(&dir.join("sweep.json"), &info)?;
    // Largest first, equal structures together (stable: the file's order otherwise);
    // rows carry their index.
    let mut todo: Vec<Point> = mine.iter().filter(|p| !done.contains(&p.id())).map(|&p| p.clone()).collect();
    let (costs, structures) = (&expanded.costs, &expanded.structures);
    todo.sort_by(|a, b| costs[b.index].total_cmp(&costs[a.index]).then_with(|| structures[a.index].cmp(&structures[b.index])));
    let mut queue: VecDeque<Point> = todo.into();
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
    let artifact_tol = file.artifact_tol();
    let reference = file.reference();
    let scene_path = std::path::absolute(file.scene_path()).unwrap_or(file.scene_path());
    let job_of = |point: Point| Job {
        scene: scene_path.clone(),
        keep_dir: file.sweep.keep_trajectories.then(|| dir.join("points").join(point.id())),
        point,
        reference: reference.clone(),
        compare: file.sweep.compare.as_ref().map(|c| c.get_ref().clone()),
        skip_last: file.skip_last(),
        fallback: file.sweep.fallback,
        refine: file.sweep.refine,
    };
    let mut pool = workers::Pool::new(&opts.worker_exe, &work, opts.jobs, file.sweep.timeout.as_ref().map(|t| *t.get_ref()));
    // For the rows of points whose worker crashed or timed out (see fill_point_settings).
    let base = SceneFile::load(&scene_path).ok();
    loop {
        if let Some(signal) = stop_signal() {
            // Every row written is whole; the points in flight are lost with their workers.
            drop(pool);
            bar.finish_and_clear();
            return Err(SweepError::Stopped { signal, recorded: report.ran, results: results_path });
        }
        while pool.hand_out(&mut queue, expanded, job_of)? {}
        if queue.is_empty() {
            pool.close_idle();
            if pool.busy() == 0 {
                break;
            }
        }
        std::thread::sleep(Duration::from_millis(5));
        for (point, mut rec) in pool.finished()? {
            fill_point_settings(&mut rec, &point, base.as_ref());
            let line = csv_line(&results_row(&columns, &point, &rec, artifact_tol, &provenance));
            results::append(&mut results, &results_path, &line)?;
            report.ran += 1;
            if !rec.status.is_converged() {
                report.failed += 1;
                bar.set_message(format!("{} failed", report.failed));
            }
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    let _ = std::fs::remove_dir(&work);
    report.wall_s = started.elapsed().as_secs_f64();
    Ok(report)
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
