//! The worker processes of a sweep and the protocol between them and the driver.
//! Debian's Ipopt/MUMPS is not thread-safe (docs/solver.md), so points run in child
//! processes, at most `jobs` at once; a worker dies with the driver
//! (`PR_SET_PDEATHSIG`), and Ctrl-C reaches the whole process group.
//!
//! A worker is `skg-solve sweep-worker WORK` (the hidden subcommand, [`serve_points`]),
//! started by the driver (`Pool`) and kept alive for any number of points, so that
//! the points it runs one after the other share the process and, with the Newton
//! backend, the symbolic LU analysis of the previous point when their Jacobian
//! structure is equal (`skg_core::solve::backend`, "the kept analysis"). The protocol:
//!
//! 1. The driver writes the point's [`Job`] atomically to `WORK/<id>.job.json`, then the
//!    point's id (16 hex digits) and a newline to the worker's stdin.
//! 2. The worker reads the job, computes the point, and writes its [`Record`]
//!    atomically (temporary file, rename) to `WORK/<id>.result.json`: that file's
//!    appearance is the report, and it is complete whenever it exists. Then the worker
//!    reads the next line. At the end of its stdin it exits with status 0.
//! 3. The driver polls every few milliseconds: a result file is a finished point; a
//!    worker that exited with a point in flight and no result crashed (an abort, a
//!    panic, the kernel's out-of-memory kill), and the point is recorded
//!    [`PointStatus::Crashed`] with the last lines its worker wrote since the point was
//!    handed out; a point running past the sweep's `timeout` has its worker killed and
//!    is recorded [`PointStatus::TimedOut`]. Either way the worker is gone and a fresh
//!    one takes the next point: a crash or a timeout costs only the point in flight.
//!
//! **Stopping.** A command-line driver calls [`stop_on_signals`]: SIGTERM (Slurm's
//! `scancel`, a job past its time limit) and SIGINT (Ctrl-C) then only set a flag, and the
//! driver, between two rows, kills its workers and returns [`SweepError::Stopped`], so
//! `results.csv` ends with a whole row; the command then dies of the same signal
//! ([`die_of`]). Both signals usually reach the workers too (Slurm signals every process
//! of the job, a terminal its whole process group), and a worker may die of it before the
//! driver sees the flag: a point whose worker died of SIGTERM or SIGINT is therefore
//! recorded as crashed only if no stop follows within [`STOP_GRACE`]. Otherwise it stays
//! unrecorded and runs again on a resume.
//!
//! A worker's stderr goes to `WORK/worker-<k>.log` (its stdout, where Ipopt would
//! print, is discarded); the driver notes the file's length when it hands
//! out a point, so the log since then is that point's. A worker dies with the driver (`PR_SET_PDEATHSIG`, Linux); closing its
//! stdin ends it. The files are removed as the points and workers finish.
//!
//! Points go out largest [`estimated_cost`](crate::estimated_cost) first; among the
//! points as large as the largest one left, a worker takes one of the same structure
//! as its previous point if there is one (`next_point`), so runs of equal structure
//! stay on one worker without giving up the largest-first order.

use std::collections::VecDeque;
use std::fs::File;
use std::io::{BufRead, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicI32, Ordering};
use std::time::{Duration, Instant};

use skg_core::output;

use crate::error::read_err;
use crate::{run_job, Expanded, Job, Point, PointStatus, Record, SweepError};

/// Lines of a crashed worker's log quoted in its point's message.
const TAIL_LINES: usize = 3;

/// The signal that asked the driver to stop (0: none yet), set by [`on_stop_signal`].
static STOP_SIGNAL: AtomicI32 = AtomicI32::new(0);

/// How long the driver waits for its own stop signal after a worker died of SIGTERM or
/// SIGINT, before recording the worker's point as crashed.
pub const STOP_GRACE: Duration = Duration::from_secs(1);

extern "C" fn on_stop_signal(signal: libc::c_int) {
    // Only an atomic store: async-signal-safe.
    STOP_SIGNAL.store(signal, Ordering::SeqCst);
}

/// Make SIGTERM and SIGINT stop a sweep of this process between two rows instead of
/// killing it at once ([module documentation](self)). For the command line; a library
/// caller (the Python module) keeps its own handlers.
pub fn stop_on_signals() {
    for signal in [libc::SIGTERM, libc::SIGINT] {
        // SAFETY: the handler only stores into an atomic.
        unsafe {
            libc::signal(signal, on_stop_signal as extern "C" fn(libc::c_int) as libc::sighandler_t);
        }
    }
}

/// The signal received since [`stop_on_signals`], if any.
pub fn stop_signal() -> Option<i32> {
    match STOP_SIGNAL.load(Ordering::SeqCst) {
        0 => None,
        s => Some(s),
    }
}

/// End this process by `signal` with its default action (after a sweep stopped on it), so
/// that the caller (a shell, Slurm) sees the process killed by that signal.
pub fn die_of(signal: i32) -> ! {
    // SAFETY: restoring the default action and raising a signal in this process.
    unsafe {
        libc::signal(signal, libc::SIG_DFL);
        libc::raise(signal);
    }
    // Not reached for SIGTERM and SIGINT; for anything else, the conventional status.
    std::process::exit(128 + signal)
}

/// Whether a worker that exited with `exit` was killed by SIGTERM or SIGINT.
fn killed_by_stop_signal(exit: &ExitStatus) -> bool {
    use std::os::unix::process::ExitStatusExt;
    matches!(exit.signal(), Some(libc::SIGTERM | libc::SIGINT))
}

/// After a worker died of SIGTERM or SIGINT: whether this driver is being stopped too
/// (its own signal arrives within [`STOP_GRACE`]).
fn stop_follows() -> bool {
    let deadline = Instant::now() + STOP_GRACE;
    while stop_signal().is_none() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(10));
    }
    stop_signal().is_some()
}

/// The job and result files of the point `id` in the work directory.
fn point_files(work: &Path, id: &str) -> (PathBuf, PathBuf) {
    (work.join(format!("{id}.job.json")), work.join(format!("{id}.result.json")))
}

/// Whether `id` is a point id (16 hex digits, [`Point::id`]): only such lines name files.
fn is_point_id(id: &str) -> bool {
    id.len() == 16 && id.bytes().all(|b| b.is_ascii_hexdigit())
}

/// The body of `skg-solve sweep-worker WORK`: for every point id read from `ids`, run
/// `WORK/<id>.job.json` and write `WORK/<id>.result.json` (module documentation).
pub fn serve_points(work: &Path, ids: impl BufRead) -> Result<(), SweepError> {
    for line in ids.lines() {
        let line = line.map_err(read_err(Path::new("<stdin>")))?;
        let id = line.trim();
        if !is_point_id(id) {
            return Err(SweepError::Results { path: work.to_path_buf(), message: format!("`{id}` on stdin is not a point id") });
        }
        let (job_path, result_path) = point_files(work, id);
        let text = std::fs::read_to_string(&job_path).map_err(read_err(&job_path))?;
        let job: Job = serde_json::from_str(&text)
            .map_err(|e| SweepError::Results { path: job_path.clone(), message: format!("not a job of this skg-solve: {e}") })?;
        output::write_json(&result_path, &run_job(&job))?;
    }
    Ok(())
}

/// A point handed to a worker.
struct InFlight {
    point: Point,
    started: Instant,
    job: PathBuf,
    result: PathBuf,
    /// Length of the worker's log when the point was handed out.
    log_offset: u64,
}

/// One worker process.
struct Worker {
    child: Child,
    /// Its stdin (None once closed).
    stdin: Option<ChildStdin>,
    log: PathBuf,
    /// The structure key ([`Expanded::structures`]) of the last point it was given.
    structure: Option<String>,
    busy: Option<InFlight>,
}

/// The driver's worker processes: at most `jobs` alive, each running one point at a time.
pub(crate) struct Pool {
    exe: PathBuf,
    work: PathBuf,
    jobs: usize,
    timeout_s: Option<f64>,
    workers: Vec<Worker>,
    started: usize,
}

impl Pool {
    /// No workers yet; they start when points are handed out.
    pub(crate) fn new(exe: &Path, work: &Path, jobs: usize, timeout_s: Option<f64>) -> Pool {
        Pool { exe: exe.to_path_buf(), work: work.to_path_buf(), jobs: jobs.max(1), timeout_s, workers: Vec::new(), started: 0 }
    }

    /// Points in flight.
    pub(crate) fn busy(&self) -> usize {
        self.workers.iter().filter(|w| w.busy.is_some()).count()
    }

    /// An idle live worker, or a new one if fewer than `jobs` are alive; None when all
    /// are busy. A worker that died while idle is reaped here.
    fn idle_worker(&mut self) -> Result<Option<usize>, SweepError> {
        self.workers.retain_mut(|w| {
            let dead = w.busy.is_none() && !matches!(w.child.try_wait(), Ok(None));
            if dead {
                end_worker(w);
            }
            !dead
        });
        if let Some(k) = self.workers.iter().position(|w| w.busy.is_none()) {
            return Ok(Some(k));
        }
        if self.workers.len() >= self.jobs {
            return Ok(None);
        }
        let log = self.work.join(format!("worker-{}.log", self.started));
        self.started += 1;
        let mut child = spawn_worker(&self.exe, &self.work, &log)?;
        let stdin = child.stdin.take();
        self.workers.push(Worker { child, stdin, log, structure: None, busy: None });
        Ok(Some(self.workers.len() - 1))
    }

    /// Hand the next point of `queue` ([`next_point`]) to an idle worker; false when
    /// every worker is busy or the queue is empty.
    pub(crate) fn hand_out(
        &mut self,
        queue: &mut VecDeque<Point>,
        expanded: &Expanded,
        job_of: impl FnOnce(Point) -> Job,
    ) -> Result<bool, SweepError> {
        if queue.is_empty() {
            return Ok(false);
        }
        let Some(k) = self.idle_worker()? else { return Ok(false) };
        let point = next_point(queue, expanded, self.workers[k].structure.as_deref()).expect("the queue is not empty");
        let job = job_of(point);
        let id = job.point.id();
        let (job_path, result_path) = point_files(&self.work, &id);
        let _ = std::fs::remove_file(&result_path);
        output::write_json(&job_path, &job)?;
        let w = &mut self.workers[k];
        let log_offset = std::fs::metadata(&w.log).map_or(0, |m| m.len());
        // A worker that died meanwhile cannot read the line: its exit is then seen by
        // `finished` and the point recorded as crashed.
        if let Some(stdin) = w.stdin.as_mut() {
            let _ = stdin.write_all(format!("{id}\n").as_bytes()).and_then(|()| stdin.flush());
        }
        w.structure = Some(expanded.structures[job.point.index].clone());
        w.busy = Some(InFlight { point: job.point, started: Instant::now(), job: job_path, result: result_path, log_offset });
        Ok(true)
    }

    /// Close the stdin of the idle workers (no more points for them) and reap them.
    pub(crate) fn close_idle(&mut self) {
        self.workers.retain_mut(|w| {
            if w.busy.is_some() {
                return true;
            }
            end_worker(w);
            false
        });
    }

    /// The points that finished since the last call, with their records: reported
    /// results, crashed workers, points past the timeout (whose workers are killed).
    pub(crate) fn finished(&mut self) -> Result<Vec<(Point, Record)>, SweepError> {
        let mut done = Vec::new();
        let mut k = 0;
        while k < self.workers.len() {
            let w = &mut self.workers[k];
            let Some(flight) = &w.busy else {
                k += 1;
                continue;
            };
            let reported = read_record(&flight.result);
            let exit = match reported {
                Some(_) => None,
                None => w.child.try_wait().map_err(|error| SweepError::Spawn { exe: self.exe.clone(), error })?,
            };
            let elapsed = flight.started.elapsed().as_secs_f64();
            let rec = match (reported, exit) {
                (Some(rec), _) => rec,
                // The whole sweep is being stopped: the point is not recorded (the
                // driver stops before recording anything more).
                (None, Some(exit)) if killed_by_stop_signal(&exit) && stop_follows() => return Ok(done),
                (None, Some(exit)) => crashed_record(&w.log, flight.log_offset, exit),
                (None, None) => match self.timeout_s {
                    Some(limit) if elapsed > limit => {
                        let _ = w.child.kill();
                        let _ = w.child.wait();
                        let message = format!("killed after the sweep's timeout of {limit} s");
                        Record { wall_s: Some(elapsed), ..Record::new(PointStatus::TimedOut, message) }
                    }
                    _ => {
                        k += 1;
                        continue;
                    }
                },
            };
            let flight = w.busy.take().expect("a point in flight");
            for p in [&flight.job, &flight.result] {
                let _ = std::fs::remove_file(p);
            }
            // A worker that crashed, was killed or wrote no record of ours is ended.
            if rec.status == PointStatus::Crashed || rec.status == PointStatus::TimedOut {
                let mut gone = self.workers.swap_remove(k);
                end_worker(&mut gone);
            } else {
                k += 1;
            }
            done.push((flight.point, rec));
        }
        Ok(done)
    }
}

impl Drop for Pool {
    /// End every worker: the idle ones by closing their stdin; the busy ones (only when
    /// the driver stops on an error, which loses their points anyway) are killed.
    fn drop(&mut self) {
        for w in &mut self.workers {
            if w.busy.is_some() {
                let _ = w.child.kill();
            }
            end_worker(w);
        }
    }
}

/// Close a worker's stdin, wait for its exit (it may have been killed already) and
/// remove its log.
fn end_worker(w: &mut Worker) {
    w.stdin = None;
    let _ = w.child.wait();
    let _ = std::fs::remove_file(&w.log);
}

/// A result file's record, if the file is there (it is complete whenever it exists); a
/// file that is not a record (a worker of another skg-solve) makes a crashed record.
fn read_record(path: &Path) -> Option<Record> {
    let text = std::fs::read_to_string(path).ok()?;
    Some(serde_json::from_str(&text).unwrap_or_else(|e| {
        Record::new(PointStatus::Crashed, format!("the worker's result {} is not a record of this skg-solve: {e}", path.display()))
    }))
}

/// The record of a point whose worker exited without a result: the exit status and the
/// last lines the worker wrote since the point was handed out.
fn crashed_record(log: &Path, offset: u64, exit: ExitStatus) -> Record {
    let mut text = String::new();
    if let Ok(mut f) = File::open(log) {
        let _ = f.seek(SeekFrom::Start(offset)).and_then(|_| f.read_to_string(&mut text));
    }
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let tail = &lines[lines.len().saturating_sub(TAIL_LINES)..];
    Record::new(PointStatus::Crashed, format!("worker exited with {exit} without a result: {}", tail.join(" | ")))
}

/// The next point for a worker whose previous point had the structure `previous`: among
/// the queued points as costly as the first, the first of that structure, else the
/// first. The queue is sorted by cost, largest first.
pub(crate) fn next_point(queue: &mut VecDeque<Point>, expanded: &Expanded, previous: Option<&str>) -> Option<Point> {
    let largest = expanded.costs[queue.front()?.index];
    let same = previous
        .and_then(|s| queue.iter().take_while(|p| expanded.costs[p.index] == largest).position(|p| expanded.structures[p.index] == s));
    queue.remove(same.unwrap_or(0))
}

/// Start `exe sweep-worker WORK` with its stdin a pipe and its stderr `log`.
fn spawn_worker(exe: &Path, work: &Path, log: &Path) -> Result<Child, SweepError> {
    let spawn_err = |error| SweepError::Spawn { exe: exe.to_path_buf(), error };
    let err = File::create(log).map_err(spawn_err)?;
    let mut cmd = Command::new(exe);
    cmd.arg("sweep-worker").arg(work).stdin(Stdio::piped()).stdout(Stdio::null()).stderr(err);
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt;
        // SAFETY: prctl is async-signal-safe; the closure allocates nothing.
        unsafe {
            cmd.pre_exec(|| {
                if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
    }
    cmd.spawn().map_err(spawn_err)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Method;

    fn point(index: usize) -> Point {
        Point { index, values: vec![("k".into(), index.to_string())], evaluated: Vec::new(), method: Method::Skg }
    }

    /// A worker stays on its structure among the largest points, never skipping to a
    /// smaller one.
    #[test]
    fn next_point_keeps_a_workers_structure_among_the_largest_points() {
        let structures = ["a", "b", "a", "c", "c"].map(String::from).to_vec();
        let costs = vec![4.0, 4.0, 4.0, 1.0, 1.0];
        let expanded = Expanded {
            points: (0..5).map(point).collect(),
            costs,
            structures,
            axes: Vec::new(),
            expression_axes: Vec::new(),
            duplicates: 0,
            scene_hash: String::new(),
            reference_hash: None,
        };
        let mut queue: VecDeque<Point> = expanded.points.iter().cloned().collect();
        let take = |q: &mut VecDeque<Point>, s: Option<&str>| next_point(q, &expanded, s).map(|p| p.index);
        assert_eq!(take(&mut queue, Some("b")), Some(1), "the same structure among the largest");
        assert_eq!(take(&mut queue, Some("c")), Some(0), "no smaller point before the larger ones");
        assert_eq!(take(&mut queue, None), Some(2));
        assert_eq!(take(&mut queue, Some("a")), Some(3));
        assert_eq!(take(&mut queue, Some("c")), Some(4));
        assert_eq!(take(&mut queue, Some("c")), None);
    }

    #[test]
    fn only_point_ids_name_files() {
        assert!(is_point_id("0123456789abcdef"));
        for bad in ["", "../../etc/passwd", "0123456789abcdeg", "0123456789abcdef0"] {
            assert!(!is_point_id(bad), "{bad}");
        }
    }
}
