//! Sweeps on a Slurm cluster (`skg-solve sweep FILE --slurm -o DIR`): the shards of a
//! sharded directory ([`crate::shards`]) run as the tasks of one job array, and a merge
//! job that depends on the array (`afterany`) merges them into `DIR/results.csv`.
//!
//! ```text
//! DIR/slurm/shard.sh      the array job: task k runs `skg-solve sweep FILE --shard k/K -o DIR/shards/k`
//! DIR/slurm/merge.sh      the merge job: `skg-solve sweep-merge DIR` (shards::merge_shards)
//! DIR/slurm/jobs.json     every submission: array job id, shards, merge job id, sbatch arguments
//! DIR/slurm/logs/         shard-<array id>_<k>.out, merge-<job id>.out
//! ```
//!
//! What Slurm does is taken from its commands only (`sbatch --parsable`, `squeue`, and
//! `scancel` when a merge job cannot be submitted), never from its accounting (`sacct`),
//! which many clusters do not keep; Slurm forgets a finished job after `MinJobAge`
//! (5 minutes by default), so whether a shard is done comes from the shard's files, and
//! job states are only shown while Slurm knows them. `sbatch --wait` is not used: it
//! polls at 2 s, 10 s, 42 s…; [`wait_for_merge`] polls `squeue` itself. A dependency is
//! only ever on a job id that sbatch has just returned (Slurm treats a dependency on an
//! id it no longer knows as satisfied).
//!
//! Every path in the scripts is absolute (the skg-solve executable that submitted them,
//! the sweep file, DIR), and each script changes into DIR itself and fails if it cannot
//! (Slurm runs a job in /tmp when its working directory is missing). DIR must therefore
//! be on a file system that the compute nodes share with the submitting machine.
//!
//! This module writes the scripts and submits them; `commands.rs` runs Slurm's
//! commands (their time limits, job ids and states, the wait for the merge job).

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use skg_core::output;

use crate::shards::{self, PrepareOptions, Runner, ShardLayout, ShardState};
use crate::{Expanded, SweepError, SweepFile};

mod commands;

use commands::{command_text, merge_not_submitted, sbatch_job_id, unconfirmed};
pub use commands::{job_states, shell_quote, wait_for_merge, JobState, WaitOutcome, TIMEOUT_VAR};

/// Options of sbatch that skg-solve sets itself (an `--sbatch-arg` with one of them is
/// refused): long names, and their short forms.
const RESERVED: &[(&str, Option<&str>)] = &[
    ("--array", Some("-a")),
    ("--dependency", Some("-d")),
    ("--output", Some("-o")),
    ("--error", Some("-e")),
    ("--parsable", None),
    ("--wait", Some("-W")),
];

/// Errors of a submission to Slurm.
#[derive(Debug, thiserror::Error)]
pub enum SlurmError {
    /// The sweep, its shards or its files.
    #[error(transparent)]
    Sweep(#[from] SweepError),
    /// Writing the scripts or `jobs.json`.
    #[error(transparent)]
    Output(#[from] output::OutputError),
    /// A Slurm command is not on `PATH`.
    #[error("`{program}` is not on PATH: --slurm needs Slurm's commands (sbatch, squeue); run it where they are, e.g. on the cluster's login node (--dry-run writes the scripts without them)")]
    Missing {
        /// The command.
        program: String,
    },
    /// A Slurm command could not be started or waited for.
    #[error("cannot run `{command}`: {error}")]
    Run {
        /// The command line.
        command: String,
        /// What the system said.
        error: std::io::Error,
    },
    /// A Slurm command failed; its message is quoted.
    #[error("`{command}` failed ({status}): {message}")]
    Failed {
        /// The command line.
        command: String,
        /// Its exit status.
        status: String,
        /// What it printed on stderr (or stdout).
        message: String,
    },
    /// A Slurm command did not finish in time (it was killed).
    #[error("`{command}` did not finish within {seconds} s (is the Slurm controller reachable? {TIMEOUT_VAR} sets the limit)")]
    TimedOut {
        /// The command line.
        command: String,
        /// The limit.
        seconds: f64,
    },
    /// sbatch succeeded but printed no job id; the submission is recorded in jobs.json
    /// with what it printed.
    #[error(
        "`{command}` printed no job id ({stdout:?}): a job named {job_name} may have been submitted; find it \
         (squeue --me --name={job_name}) and cancel it (scancel) before running the command again"
    )]
    NoJobId {
        /// The command line.
        command: String,
        /// What it printed (at most 200 characters).
        stdout: String,
        /// The job's name (`--job-name`).
        job_name: String,
    },
    /// Jobs of an earlier submission into the directory still run or wait.
    #[error(
        "jobs of an earlier submission into {} are still queued or running ({jobs}): a shard or the merge would run twice. \
         Wait until they end (squeue -j {ids}; skg-solve status {}), or cancel them (scancel {ids}), then run the command again",
        dir.display(),
        dir.display()
    )]
    Active {
        /// The sweep directory.
        dir: PathBuf,
        /// The active jobs with their states.
        jobs: String,
        /// Their ids, comma-separated.
        ids: String,
    },
    /// The submission's jobs cannot be checked without squeue.
    #[error("{} records earlier submissions ({ids}), and whether they still run cannot be checked: {reason}", dir.display())]
    Unchecked {
        /// The sweep directory.
        dir: PathBuf,
        /// The recorded job ids.
        ids: String,
        /// Why (squeue's error).
        reason: String,
    },
    /// An `--sbatch-arg` that skg-solve sets itself.
    #[error("--sbatch-arg {arg}: skg-solve sets {option} itself (the array of shards, the merge's dependency, the logs in DIR/slurm/logs); leave it out")]
    Reserved {
        /// The argument.
        arg: String,
        /// The option it sets.
        option: String,
    },
    /// A path that Slurm's file name patterns or the scripts cannot hold.
    #[error("{}: a path with {what} cannot be given to Slurm (sbatch expands % in file names); use another output directory", path.display())]
    Path {
        /// The path.
        path: PathBuf,
        /// What is wrong.
        what: &'static str,
    },
    /// The array was submitted but its merge job was not.
    #[error("submitted the shards as array job {array}, but the merge job could not be submitted: {error}; {cancelled}")]
    MergeNotSubmitted {
        /// The array job id.
        array: String,
        /// The merge submission's error.
        error: Box<SlurmError>,
        /// What became of the array job.
        cancelled: String,
    },
}

impl SlurmError {
    /// Whether the error is a usage error of the command line (an `--sbatch-arg` that
    /// skg-solve sets itself).
    pub fn is_usage(&self) -> bool {
        matches!(self, SlurmError::Reserved { .. })
    }
}

/// One submission into a directory (`DIR/slurm/jobs.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Submission {
    /// When (seconds since 1970).
    pub submitted_unix: u64,
    /// The array job's id, if shards were submitted.
    pub array_job: Option<String>,
    /// The shards submitted (the array's indices).
    pub shards: Vec<usize>,
    /// The merge job's id (None if its submission failed).
    pub merge_job: Option<String>,
    /// The `--sbatch-arg` arguments given.
    pub sbatch_args: Vec<String>,
    /// Why a job of this submission is not known by its id although sbatch may have
    /// submitted it (sbatch printed no job id, or did not finish in time).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unconfirmed: Option<String>,
}

impl Submission {
    /// The job ids of this submission.
    pub fn job_ids(&self) -> Vec<String> {
        self.array_job.iter().chain(self.merge_job.iter()).cloned().collect()
    }
}

/// `DIR/slurm/jobs.json`: every submission into the directory, oldest first.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct JobsFile {
    /// The submissions.
    pub submissions: Vec<Submission>,
}

impl JobsFile {
    /// The jobs file of the sweep directory `dir`.
    pub fn path(dir: &Path) -> PathBuf {
        dir.join("slurm").join("jobs.json")
    }

    /// Read the jobs file of `dir` (empty if there is none).
    pub fn read(dir: &Path) -> Result<JobsFile, SweepError> {
        let path = Self::path(dir);
        if !path.exists() {
            return Ok(JobsFile::default());
        }
        let text = std::fs::read_to_string(&path).map_err(crate::error::read_err(&path))?;
        serde_json::from_str(&text).map_err(|e| SweepError::Results { path, message: format!("not a jobs.json of this skg-solve: {e}") })
    }
}

/// Refuse an `--sbatch-arg` that sets what skg-solve sets itself.
fn check_sbatch_args(args: &[String]) -> Result<(), SlurmError> {
    for arg in args {
        let name = arg.split('=').next().unwrap_or(arg);
        for (long, short) in RESERVED {
            // getopt also takes an unambiguous abbreviation of a long option (--arr, --dep).
            let is_long = name == *long || (name.len() >= 5 && name.starts_with("--") && long.starts_with(name));
            let is_short = short.is_some_and(|s| arg.starts_with(s) && !arg.starts_with("--"));
            if is_long || is_short {
                return Err(SlurmError::Reserved { arg: arg.clone(), option: long.to_string() });
            }
        }
    }
    Ok(())
}

/// The array specification of the shards `ks` (sorted): `1-3,7,9-12`.
pub fn array_spec(ks: &[usize]) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < ks.len() {
        let mut j = i;
        while j + 1 < ks.len() && ks[j + 1] == ks[j] + 1 {
            j += 1;
        }
        parts.push(if j == i { ks[i].to_string() } else { format!("{}-{}", ks[i], ks[j]) });
        i = j + 1;
    }
    parts.join(",")
}

/// The scripts of a submission into `dir`.
struct Scripts {
    shard: PathBuf,
    merge: PathBuf,
    logs: PathBuf,
}

/// Write `DIR/slurm/shard.sh` and `merge.sh` (every path absolute) and create
/// `DIR/slurm/logs` (Slurm fails a task whose output file cannot be opened, silently).
fn write_scripts(dir: &Path, layout: &ShardLayout, exe: &Path) -> Result<Scripts, SlurmError> {
    let slurm = dir.join("slurm");
    let logs = slurm.join("logs");
    std::fs::create_dir_all(&logs).map_err(|error| SweepError::CreateDir { path: logs.clone(), error })?;
    let (q_dir, q_exe, q_file) =
        (shell_quote(&dir.to_string_lossy()), shell_quote(&exe.to_string_lossy()), shell_quote(&layout.sweep_file.to_string_lossy()));
    let shards_dir = shell_quote(&format!("{}/", dir.join("shards").display()));
    let version = skg_core::scene::provenance::VERSION;
    let shard = format!(
        "#!/bin/bash\n\
         # Written by skg-solve {version} (`skg-solve sweep --slurm`). Task k of the array job runs shard\n\
         # k/{k} of the sweep {name} into {dir}/shards/k with one worker per CPU that Slurm\n\
         # gives it (--cpus-per-task, else the CPUs of its allocation). Submitted with\n\
         # --array=<the incomplete shards>: see {dir}/slurm/jobs.json.\n\
         cd {q_dir} || exit 1\n\
         k=${{SLURM_ARRAY_TASK_ID:?this script runs as a task of a Slurm array job}}\n\
         jobs=${{SLURM_CPUS_PER_TASK:-${{SLURM_CPUS_ON_NODE:-1}}}}\n\
         exec {q_exe} sweep {q_file} --shard \"$k/{k}\" -o {shards_dir}\"$k\" --jobs \"$jobs\" --yes\n",
        k = layout.shards,
        name = comment_text(&layout.name),
        dir = comment_text(&dir.to_string_lossy()),
    );
    let merge = format!(
        "#!/bin/bash\n\
         # Written by skg-solve {version} (`skg-solve sweep --slurm`). Runs after the array job of the\n\
         # shards has ended (--dependency=afterany): merges {dir}/shards/* into\n\
         # {dir}/results.csv if every point is there (else exits 1 naming the\n\
         # incomplete shards; running the same skg-solve sweep --slurm again submits only them).\n\
         cd {q_dir} || exit 1\n\
         exec {q_exe} sweep-merge {q_dir}\n",
        dir = comment_text(&dir.to_string_lossy()),
    );
    let paths = Scripts { shard: slurm.join("shard.sh"), merge: slurm.join("merge.sh"), logs };
    for (path, text) in [(&paths.shard, shard), (&paths.merge, merge)] {
        output::write_atomic(path, |w| w.write_all(text.as_bytes()))?;
        use std::os::unix::fs::PermissionsExt;
        let _ = std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755));
    }
    Ok(paths)
}

/// Options of [`submit`].
#[derive(Debug, Clone)]
pub struct SubmitOptions {
    /// The number of shards (None: the directory's, or [`shards::default_shards`]).
    pub shards: Option<usize>,
    /// Extra arguments for both sbatch commands (`--partition=…`, `--time=…`).
    pub sbatch_args: Vec<String>,
    /// The skg-solve executable the jobs run (absolute).
    pub exe: PathBuf,
    /// Write the scripts and say what would be submitted, without submitting.
    pub dry_run: bool,
}

/// What [`submit`] did.
#[derive(Debug, Clone)]
pub struct SubmitReport {
    /// The sweep directory (absolute).
    pub dir: PathBuf,
    /// Its layout.
    pub layout: ShardLayout,
    /// Each shard's state before the submission.
    pub states: Vec<ShardState>,
    /// The shards submitted (or that a dry run would submit).
    pub submitted: Vec<usize>,
    /// The array job's id (None: no shard to run, or a dry run).
    pub array_job: Option<String>,
    /// The merge job's id (None: nothing to do, or a dry run).
    pub merge_job: Option<String>,
    /// The sbatch command lines, as a shell would read them (a dry run's merge command
    /// depends on `<array job id>`).
    pub commands: Vec<String>,
    /// Whether `DIR/results.csv` already holds every point (nothing submitted).
    pub merged: bool,
    /// Things the user should know (a check that could not be made in a dry run).
    pub notes: Vec<String>,
}

/// Submit the incomplete shards of the sweep `file` into `dir` as one array job and a
/// merge job after it (the module documentation); on a directory with every shard
/// complete but no merge, only the merge job; with every point merged, nothing. Refused
/// while jobs of an earlier submission into `dir` are queued or running. The directory's
/// lock is held while it is inspected and the jobs are submitted (the merge job waits for
/// it).
pub fn submit(file: &SweepFile, expanded: &Expanded, dir: &Path, opts: &SubmitOptions) -> Result<SubmitReport, SlurmError> {
    check_sbatch_args(&opts.sbatch_args)?;
    let dir = std::path::absolute(dir).map_err(crate::error::read_err(dir))?;
    check_dir_path(&dir)?;
    let lock = output::OutputDir::lock(&dir).map_err(SweepError::from)?;
    let (layout, states) = shards::prepare(file, expanded, &dir, &PrepareOptions { shards: opts.shards, runner: Runner::Slurm })?;
    let mut report = SubmitReport {
        dir: dir.clone(),
        layout: layout.clone(),
        submitted: states.iter().filter(|s| !s.complete()).map(|s| s.k).collect(),
        states,
        array_job: None,
        merge_job: None,
        commands: Vec::new(),
        merged: shards::merged(&dir),
        notes: Vec::new(),
    };
    let mut jobs = JobsFile::read(&dir)?;
    check_earlier_jobs(&jobs, &dir, opts.dry_run, &mut report.notes)?;
    if report.submitted.is_empty() && report.merged {
        return Ok(report);
    }
    let scripts = write_scripts(&dir, &layout, &opts.exe)?;
    let sbatch = SbatchArgs::new(&layout, &scripts, &report.submitted, &opts.sbatch_args);
    if opts.dry_run {
        report.commands.extend(sbatch.array.as_ref().map(|a| command_text("sbatch", a)));
        report.commands.push(command_text("sbatch", &sbatch.merge(sbatch.array.as_ref().map(|_| "<array job id>"))));
        drop(lock);
        return Ok(report);
    }
    let mut submission = Submission {
        submitted_unix: std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs()),
        array_job: None,
        shards: report.submitted.clone(),
        merge_job: None,
        sbatch_args: opts.sbatch_args.clone(),
        unconfirmed: None,
    };
    if let Some(args) = &sbatch.array {
        report.commands.push(command_text("sbatch", args));
        match sbatch_job_id(args, &sbatch.job_name) {
            Ok(id) => submission.array_job = Some(id),
            Err(e) => {
                // The array may exist without its id: recorded, and the error says how to
                // find it. An sbatch that refused the job submitted nothing: nothing recorded.
                submission.unconfirmed = unconfirmed(&e);
                if submission.unconfirmed.is_some() {
                    jobs.submissions.push(submission);
                    output::write_json(&JobsFile::path(&dir), &jobs)?;
                }
                return Err(e);
            }
        }
    }
    let args = sbatch.merge(submission.array_job.as_deref());
    report.commands.push(command_text("sbatch", &args));
    let merge = sbatch_job_id(&args, &format!("{}-merge", sbatch.job_name));
    submission.merge_job = merge.as_ref().ok().cloned();
    submission.unconfirmed = merge.as_ref().err().and_then(unconfirmed);
    jobs.submissions.push(submission.clone());
    output::write_json(&JobsFile::path(&dir), &jobs)?;
    drop(lock);
    if let Err(e) = merge {
        return Err(merge_not_submitted(e, submission.array_job));
    }
    report.array_job = submission.array_job;
    report.merge_job = submission.merge_job;
    Ok(report)
}

/// `text` as it may stand in a `#` comment of a script: every control character (a line
/// break would end the comment and start a command) written as its escape. Names and
/// paths are checked before they get here (`name_problem`, [`check_dir_path`]); this
/// keeps the scripts safe whatever reaches them.
fn comment_text(text: &str) -> String {
    text.chars().flat_map(|c| if c.is_control() { c.escape_default().collect::<Vec<_>>() } else { vec![c] }).collect()
}

/// Refuse a directory whose path the scripts or Slurm's file name patterns cannot hold.
fn check_dir_path(dir: &Path) -> Result<(), SlurmError> {
    let text = dir.to_string_lossy();
    if text.contains('%') || text.contains('\\') {
        return Err(SlurmError::Path { path: dir.to_path_buf(), what: "`%` or `\\`" });
    }
    if text.chars().any(char::is_control) {
        return Err(SlurmError::Path { path: dir.to_path_buf(), what: "a line break or another control character" });
    }
    Ok(())
}

/// Refuse a submission while jobs of an earlier one into `dir` (`jobs`) are queued or
/// running, or when squeue cannot tell; a dry run only notes the latter in `notes`.
fn check_earlier_jobs(jobs: &JobsFile, dir: &Path, dry_run: bool, notes: &mut Vec<String>) -> Result<(), SlurmError> {
    let earlier: Vec<String> = jobs.submissions.iter().flat_map(Submission::job_ids).collect();
    if earlier.is_empty() {
        return Ok(());
    }
    match job_states(&earlier) {
        Ok(states) => {
            let active: Vec<&JobState> = states.iter().filter(|s| s.active()).collect();
            if !active.is_empty() {
                let list: Vec<String> = active.iter().map(|s| format!("{} {}", s.id, s.state)).collect();
                return Err(SlurmError::Active { dir: dir.to_path_buf(), jobs: list.join(", "), ids: earlier.join(",") });
            }
        }
        Err(e) if dry_run => notes.push(format!("not checked whether the earlier jobs ({}) still run: {e}", earlier.join(","))),
        Err(e) => return Err(SlurmError::Unchecked { dir: dir.to_path_buf(), ids: earlier.join(","), reason: e.to_string() }),
    }
    Ok(())
}

/// The sbatch arguments of a submission: the array job's (None when no shard is to run)
/// and the merge job's ([`SbatchArgs::merge`]).
struct SbatchArgs {
    array: Option<Vec<String>>,
    job_name: String,
    merge_output: String,
    merge_script: String,
    extra: Vec<String>,
}

impl SbatchArgs {
    fn new(layout: &ShardLayout, scripts: &Scripts, shards: &[usize], extra: &[String]) -> SbatchArgs {
        let job_name = format!("skg-{}", layout.name);
        let array = (!shards.is_empty()).then(|| {
            let mut a = vec![
                "--parsable".to_string(),
                format!("--array={}", array_spec(shards)),
                format!("--job-name={job_name}"),
                format!("--output={}", scripts.logs.join("shard-%A_%a.out").display()),
            ];
            a.extend(extra.iter().cloned());
            a.push(scripts.shard.display().to_string());
            a
        });
        SbatchArgs {
            array,
            job_name,
            merge_output: scripts.logs.join("merge-%j.out").display().to_string(),
            merge_script: scripts.merge.display().to_string(),
            extra: extra.to_vec(),
        }
    }

    /// The merge job's arguments, after the job `dependency` if any.
    fn merge(&self, dependency: Option<&str>) -> Vec<String> {
        let mut a = vec!["--parsable".to_string()];
        a.extend(dependency.map(|id| format!("--dependency=afterany:{id}")));
        a.push(format!("--job-name={}-merge", self.job_name));
        a.push(format!("--output={}", self.merge_output));
        a.extend(self.extra.iter().cloned());
        a.push(self.merge_script.clone());
        a
    }
}

#[cfg(test)]
mod tests {
    use super::commands::parse_job_id;
    use super::*;

    #[test]
    fn array_specs_and_quoting() {
        assert_eq!(array_spec(&[1, 2, 3, 7, 9, 10, 11, 12]), "1-3,7,9-12");
        assert_eq!(array_spec(&[4]), "4");
        assert_eq!(shell_quote("/a/b-c_d.toml"), "/a/b-c_d.toml");
        assert_eq!(shell_quote("/my dir/it's"), r"'/my dir/it'\''s'");
        assert_eq!(shell_quote(""), "''");
    }

    #[test]
    fn options_that_skg_solve_sets_are_refused() {
        for bad in
            ["--array=1-3", "--array", "--arr=2", "-a", "-a1", "--dependency=afterok:3", "--output=x", "-o", "--parsable", "--wait", "-W"]
        {
            assert!(check_sbatch_args(&[bad.to_string()]).is_err(), "{bad}");
        }
        for good in
            ["--partition=debug", "-p", "debug", "--time=1:00:00", "--mem=4G", "-c", "4", "--cpus-per-task=8", "--account=x", "--qos=long"]
        {
            assert!(check_sbatch_args(&[good.to_string()]).is_ok(), "{good}");
        }
    }

    /// A name that reached the scripts with a line break (the sweep file refuses such
    /// names: this is the second line of defence) stays inside its comment: no line of
    /// the script runs it, and the script's commands are the ones it always has.
    #[test]
    fn a_line_break_in_a_name_stays_inside_the_comment() {
        let dir = tempfile::tempdir().unwrap();
        let layout = ShardLayout {
            name: "q\necho INJECTED > PWNED #".into(),
            sweep_file: dir.path().join("s.toml"),
            shards: 2,
            total_points: 4,
            runner: Runner::Slurm,
        };
        let scripts = write_scripts(dir.path(), &layout, Path::new("/usr/bin/skg-solve")).unwrap();
        for path in [&scripts.shard, &scripts.merge] {
            let text = std::fs::read_to_string(path).unwrap();
            assert!(text.lines().all(|l| !l.starts_with("echo")), "{text}");
            let commands: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).collect();
            assert!(commands.iter().all(|l| ["cd ", "k=", "jobs=", "exec "].iter().any(|p| l.starts_with(p))), "{commands:?}");
        }
        assert!(std::fs::read_to_string(&scripts.shard).unwrap().contains(r"sweep q\necho INJECTED > PWNED # into"));
    }

    #[test]
    fn task_ids_name_their_shard() {
        let s = JobState { id: "17_3".into(), state: "RUNNING".into(), reason: "None".into() };
        assert_eq!(s.task_of("17"), Some(3));
        assert_eq!(s.task_of("1"), None);
        assert!(s.active());
        assert!(!JobState { state: "CANCELLED".into(), ..s }.active());
    }

    #[test]
    fn job_ids_are_read_from_what_sbatch_prints() {
        assert_eq!(parse_job_id("4242\n").as_deref(), Some("4242"));
        assert_eq!(parse_job_id("4242;cluster2\n").as_deref(), Some("4242"));
        assert_eq!(parse_job_id("Submitted batch job 777\n").as_deref(), Some("777"));
        assert_eq!(parse_job_id("note: using partition short\n4243\n").as_deref(), Some("4243"));
        for garbage in ["", "\n", "queue is busy", "12a", "-1", ";cluster"] {
            assert_eq!(parse_job_id(garbage), None, "{garbage:?}");
        }
    }
}
