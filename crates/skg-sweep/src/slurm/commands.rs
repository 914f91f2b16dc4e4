//! The running of Slurm's commands: each with a time limit (120 s for sbatch, 60 s for
//! squeue and scancel, or [`TIMEOUT_VAR`]) and its output read beside it; sbatch's job
//! ids, squeue's job states ([`job_states`]), the cancellation of an array job whose
//! merge job could not be submitted, and the polling of squeue until the merge job has
//! ended ([`wait_for_merge`]).

use std::io::Read;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use super::SlurmError;

/// How long sbatch may take (it retries an unreachable controller for about 10 s).
const SBATCH_TIMEOUT: Duration = Duration::from_secs(120);
/// How long squeue and scancel may take.
const QUERY_TIMEOUT: Duration = Duration::from_secs(60);
/// How long [`wait_for_merge`] keeps polling while squeue fails (a controller
/// restarting), in multiples of the query timeout (10 minutes by default).
const QUERY_FAILURES_FOR: u32 = 10;
/// The environment variable that sets, in seconds, how long every Slurm command may take
/// (instead of 120 s for sbatch, 60 s for squeue and scancel).
pub const TIMEOUT_VAR: &str = "SKG_SLURM_TIMEOUT";

/// How long a Slurm command may take: [`TIMEOUT_VAR`] if it holds a positive number of
/// seconds, else `default`.
fn timeout(default: Duration) -> Duration {
    std::env::var(TIMEOUT_VAR)
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|s| *s > 0.0)
        .and_then(|s| Duration::try_from_secs_f64(s).ok())
        .unwrap_or(default)
}

/// Job states in which a job still runs or may run (`squeue`'s `%T`).
const ACTIVE_STATES: &[&str] = &[
    "PENDING",
    "RUNNING",
    "CONFIGURING",
    "COMPLETING",
    "SUSPENDED",
    "REQUEUED",
    "REQUEUE_FED",
    "REQUEUE_HOLD",
    "RESIZING",
    "SIGNALING",
    "STAGE_OUT",
    "STOPPED",
];

/// A job (or array task, `A_k`) as squeue shows it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct JobState {
    /// The job id, `A_k` for an array task.
    pub id: String,
    /// The state (`PENDING`, `RUNNING`, `COMPLETED`, `FAILED`, `CANCELLED`, `TIMEOUT`, …).
    pub state: String,
    /// The reason squeue gives (`None`, `Dependency`, `Resources`, …).
    pub reason: String,
}

impl JobState {
    /// Whether the job still runs or may run.
    pub fn active(&self) -> bool {
        ACTIVE_STATES.contains(&self.state.as_str())
    }

    /// The shard of an array task `A_k` of the array `array`.
    pub fn task_of(&self, array: &str) -> Option<usize> {
        self.id.strip_prefix(array)?.strip_prefix('_')?.parse().ok()
    }
}

/// A word for a shell command line: as it is when it has no special characters, else in
/// single quotes.
pub fn shell_quote(word: &str) -> String {
    let plain = !word.is_empty() && word.bytes().all(|b| b.is_ascii_alphanumeric() || b"_./:=@%+,-".contains(&b));
    if plain {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

pub(super) fn command_text(program: &str, args: &[String]) -> String {
    std::iter::once(program.to_string()).chain(args.iter().map(|a| shell_quote(a))).collect::<Vec<_>>().join(" ")
}

/// Run `program args` and wait at most `timeout`; its stdout, or an error quoting what it
/// printed when it fails.
fn run(program: &str, args: &[String], timeout: Duration) -> Result<String, SlurmError> {
    let command = command_text(program, args);
    let mut child =
        Command::new(program).args(args).stdin(Stdio::null()).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().map_err(|error| {
            if error.kind() == std::io::ErrorKind::NotFound {
                SlurmError::Missing { program: program.to_string() }
            } else {
                SlurmError::Run { command: command.clone(), error }
            }
        })?;
    // Read both pipes in threads, so that a long answer cannot block the command.
    let reader = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut text = String::new();
            if let Some(mut p) = pipe {
                let _ = p.read_to_string(&mut text);
            }
            text
        })
    };
    let out = reader(child.stdout.take().map(|p| Box::new(p) as Box<dyn Read + Send>));
    let err = reader(child.stderr.take().map(|p| Box::new(p) as Box<dyn Read + Send>));
    let deadline = Instant::now() + timeout;
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(20)),
            Ok(None) => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(SlurmError::TimedOut { command, seconds: timeout.as_secs_f64() });
            }
            Err(error) => return Err(SlurmError::Run { command, error }),
        }
    };
    let (stdout, stderr) = (out.join().unwrap_or_default(), err.join().unwrap_or_default());
    if status.success() {
        return Ok(stdout);
    }
    let message = if stderr.trim().is_empty() { stdout } else { stderr };
    let message = message.lines().map(str::trim).filter(|l| !l.is_empty()).collect::<Vec<_>>().join(" / ");
    Err(SlurmError::Failed { command, status: status.to_string(), message })
}

/// The states of the jobs `ids` (array jobs as one line per task, `A_k`) that Slurm still
/// knows; jobs it has forgotten are left out.
pub fn job_states(ids: &[String]) -> Result<Vec<JobState>, SlurmError> {
    if ids.is_empty() {
        return Ok(Vec::new());
    }
    let args: Vec<String> = ["-h", "-r", "-t", "all", "-j", &ids.join(","), "-o", "%i|%T|%r"].map(String::from).to_vec();
    let out = match run("squeue", &args, timeout(QUERY_TIMEOUT)) {
        Ok(out) => out,
        // Every id unknown (finished and forgotten): squeue says so and exits 1.
        Err(SlurmError::Failed { message, .. }) if message.contains("Invalid job id") => return Ok(Vec::new()),
        Err(e) => return Err(e),
    };
    Ok(out
        .lines()
        .filter_map(|line| {
            let mut f = line.trim().splitn(3, '|');
            let (id, state, reason) = (f.next()?, f.next()?, f.next().unwrap_or(""));
            Some(JobState { id: id.to_string(), state: state.to_string(), reason: reason.to_string() })
        })
        .collect())
}

/// What to record of a failed sbatch that may have submitted its job all the same: one
/// that printed no job id, or did not finish in time.
pub(super) fn unconfirmed(e: &SlurmError) -> Option<String> {
    matches!(e, SlurmError::NoJobId { .. } | SlurmError::TimedOut { .. }).then(|| e.to_string())
}

/// Submit a job named `job_name` with `sbatch args`; its id.
pub(super) fn sbatch_job_id(args: &[String], job_name: &str) -> Result<String, SlurmError> {
    let out = run("sbatch", args, timeout(SBATCH_TIMEOUT))?;
    parse_job_id(&out).ok_or_else(|| SlurmError::NoJobId {
        command: command_text("sbatch", args),
        stdout: out.trim().chars().take(200).collect(),
        job_name: job_name.to_string(),
    })
}

/// The job id sbatch printed: `N`, or `N;cluster` on a federation, on the last line that
/// holds one (a site's wrapper may print other lines; one that ignores `--parsable`
/// prints `Submitted batch job N`).
pub(super) fn parse_job_id(out: &str) -> Option<String> {
    out.lines().rev().find_map(|line| {
        let line = line.trim();
        let id = line.strip_prefix("Submitted batch job ").unwrap_or(line).split(';').next()?.trim();
        (!id.is_empty() && id.bytes().all(|b| b.is_ascii_digit())).then(|| id.to_string())
    })
}

/// The error of a merge job that could not be submitted (`error`): after an array job,
/// that job is cancelled, so that no shard runs without its merge.
pub(super) fn merge_not_submitted(error: SlurmError, array: Option<String>) -> SlurmError {
    let Some(array) = array else { return error };
    let cancelled = match run("scancel", std::slice::from_ref(&array), timeout(QUERY_TIMEOUT)) {
        Ok(_) => format!("cancelled array job {array}; run the command again"),
        Err(c) => format!("cancelling array job {array} failed too ({c}): cancel it yourself (scancel {array})"),
    };
    SlurmError::MergeNotSubmitted { array, error: Box::new(error), cancelled }
}

/// What [`wait_for_merge`] saw last.
#[derive(Debug, Clone, PartialEq)]
pub struct WaitOutcome {
    /// The merge job's last state seen (None if Slurm had already forgotten it).
    pub merge: Option<JobState>,
}

/// Poll squeue until the merge job `merge` has ended (every 0.5 s at first, then less
/// often, up to every 30 s), calling `progress` with a line on the jobs whenever it
/// changes. squeue failing (a controller restarting) is reported through `progress` and
/// tolerated for 10 minutes in a row.
pub fn wait_for_merge(array: Option<&str>, merge: &str, mut progress: impl FnMut(&str)) -> Result<WaitOutcome, SlurmError> {
    let ids: Vec<String> = array.into_iter().map(str::to_string).chain([merge.to_string()]).collect();
    let started = Instant::now();
    let mut last_text = String::new();
    let mut last_merge = None;
    let mut failing_since: Option<Instant> = None;
    loop {
        match job_states(&ids) {
            Ok(states) => {
                failing_since = None;
                let merge_state = states.iter().find(|s| s.id == merge).cloned();
                let text = progress_text(array, merge, &states);
                if text != last_text {
                    progress(&text);
                    last_text = text;
                }
                match merge_state {
                    Some(s) if s.active() => last_merge = Some(s),
                    Some(s) => return Ok(WaitOutcome { merge: Some(s) }),
                    // Forgotten: it ended more than MinJobAge ago (or was never known).
                    None => return Ok(WaitOutcome { merge: last_merge.filter(|s: &JobState| !s.active()) }),
                }
            }
            Err(e) => {
                let since = *failing_since.get_or_insert_with(Instant::now);
                if since.elapsed() > timeout(QUERY_TIMEOUT) * QUERY_FAILURES_FOR {
                    return Err(e);
                }
                progress(&format!("squeue failed ({e}); trying again"));
            }
        }
        let pause = (started.elapsed() / 20).clamp(Duration::from_millis(500), Duration::from_secs(30));
        std::thread::sleep(pause);
    }
}

/// `array 17: 2 RUNNING, 1 PENDING; merge 18: PENDING (Dependency)`.
fn progress_text(array: Option<&str>, merge: &str, states: &[JobState]) -> String {
    let mut parts = Vec::new();
    if let Some(a) = array {
        let mut counts: std::collections::BTreeMap<&str, usize> = Default::default();
        for s in states.iter().filter(|s| s.task_of(a).is_some()) {
            *counts.entry(s.state.as_str()).or_insert(0) += 1;
        }
        let text: Vec<String> = counts.iter().map(|(state, n)| format!("{n} {state}")).collect();
        parts.push(format!("array job {a}: {}", if text.is_empty() { "ended".into() } else { text.join(", ") }));
    }
    let m = states.iter().find(|s| s.id == merge);
    parts.push(match m {
        Some(s) if s.reason.is_empty() || s.reason == "None" => format!("merge job {merge}: {}", s.state),
        Some(s) => format!("merge job {merge}: {} ({})", s.state, s.reason),
        None => format!("merge job {merge}: ended"),
    });
    parts.join("; ")
}
