//! Sweeps on a real Slurm: a single-node cluster started by `ci/slurm-local.sh` (Debian's
//! slurmctld, slurmd and munge, installed by the script if missing; it needs root) for
//! this test file and stopped at its end, also when a check fails.
//!
//! Without a cluster (not root, no apt, a start that fails) the test is skipped with a
//! message, unless `SKG_REQUIRE_SLURM` is set (ci/test.sh sets it), which makes it a
//! failure. The checks run one after the other in one test, sharing the cluster: a
//! second test function would run in parallel on the same two CPUs and could not stop
//! the cluster after the last one ends.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// A running single-node cluster, stopped when dropped.
struct Cluster {
    dir: tempfile::TempDir,
    script: PathBuf,
}

impl Cluster {
    /// Start one, or say why not.
    fn start() -> Result<Cluster, String> {
        let uid = Command::new("id").arg("-u").output().map_err(|e| format!("cannot run id: {e}"))?;
        if String::from_utf8_lossy(&uid.stdout).trim() != "0" {
            return Err("ci/slurm-local.sh needs root (SlurmUser=root, package installs)".into());
        }
        let script = common::root().join("ci/slurm-local.sh");
        // Short: the cluster's UNIX sockets live below it (at most 80 bytes).
        let dir = tempfile::Builder::new().prefix("skg-slurm.").tempdir_in("/tmp").map_err(|e| e.to_string())?;
        let started = Instant::now();
        let out = Command::new("bash").arg(&script).arg("start").arg(dir.path()).output().map_err(|e| format!("cannot run bash: {e}"))?;
        let cluster = Cluster { dir, script };
        if !out.status.success() {
            return Err(format!("ci/slurm-local.sh start failed ({}): {}", out.status, common::text(&out)));
        }
        eprintln!("Slurm cluster up in {:.1} s", started.elapsed().as_secs_f64());
        Ok(cluster)
    }

    fn conf(&self) -> PathBuf {
        self.dir.path().join("etc/slurm.conf")
    }

    /// `skg-solve ARGS` in `cwd`, as a user of this cluster.
    fn skg(&self, args: &[&str], cwd: &Path) -> Output {
        Command::new(env!("CARGO_BIN_EXE_skg-solve")).args(args).current_dir(cwd).env("SLURM_CONF", self.conf()).output().unwrap()
    }

    /// A Slurm command of this cluster; its stdout.
    fn slurm(&self, program: &str, args: &[&str]) -> String {
        let out = Command::new(program).args(args).env("SLURM_CONF", self.conf()).output().unwrap();
        assert!(out.status.success(), "{program} {args:?}: {}", common::text(&out));
        String::from_utf8_lossy(&out.stdout).into_owned()
    }

    /// The state of job (or task) `id`, None once it has ended.
    fn active_state(&self, id: &str) -> Option<String> {
        let state = self.slurm("squeue", &["-h", "-r", "-j", id, "-o", "%T"]);
        let state = state.trim();
        (!state.is_empty()).then(|| state.to_string())
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let out = Command::new("bash").arg(&self.script).arg("stop").arg(self.dir.path()).output();
        if let Some(o) = out.ok().filter(|o| !o.status.success()) {
            eprintln!("ci/slurm-local.sh stop failed: {}", common::text(&o));
        }
    }
}

/// The cluster, or None when the test is to be skipped.
fn cluster() -> Option<Cluster> {
    match Cluster::start() {
        Ok(c) => Some(c),
        Err(why) if std::env::var_os("SKG_REQUIRE_SLURM").is_some_and(|v| !v.is_empty() && v != "0") => {
            panic!("SKG_REQUIRE_SLURM is set but no Slurm cluster could be started: {why}")
        }
        Err(why) => {
            eprintln!("skipping the Slurm tests: {why} (set SKG_REQUIRE_SLURM=1 to make this a failure)");
            None
        }
    }
}

#[test]
fn sweeps_run_on_a_real_slurm() {
    let Some(cluster) = cluster() else { return };
    let work = tempfile::tempdir().unwrap();
    let t = Instant::now();
    dry_run_writes_scripts_with_absolute_paths_and_submits_nothing(&cluster, work.path());
    a_bad_sbatch_arg_is_a_clear_error(&cluster, work.path());
    eprintln!("dry run and bad arguments: {:.1} s", t.elapsed().as_secs_f64());
    let t = Instant::now();
    a_shipped_sweep_on_slurm_gives_the_rows_of_a_local_run(&cluster, work.path());
    eprintln!("a shipped sweep, local and on Slurm: {:.1} s", t.elapsed().as_secs_f64());
    let t = Instant::now();
    a_cancelled_task_is_completed_by_the_second_command(&cluster, work.path());
    eprintln!("a cancelled task and the resubmission: {:.1} s", t.elapsed().as_secs_f64());
}

/// The sweep file of the shipped quick sweep.
fn quick_sweep() -> PathBuf {
    common::root().join("scenarios/sweeps/damped_quick.toml")
}

fn dry_run_writes_scripts_with_absolute_paths_and_submits_nothing(cluster: &Cluster, work: &Path) {
    // Relative paths from the working directory: the scripts must not depend on it.
    let rel_sweep = PathBuf::from("sweeps").join("damped_quick.toml");
    std::fs::create_dir_all(work.join("sweeps")).unwrap();
    let text = std::fs::read_to_string(quick_sweep())
        .unwrap()
        .replace("../damped_oscillator.toml", &common::scenario("damped_oscillator").display().to_string());
    std::fs::write(work.join(&rel_sweep), text).unwrap();
    let o = cluster.skg(&["sweep", rel_sweep.to_str().unwrap(), "--slurm", "-o", "dry", "--shards", "3", "--dry-run"], work);
    assert!(o.status.success(), "{}", common::text(&o));
    let printed = common::text(&o);
    assert!(printed.contains("dry run: nothing submitted"), "{printed}");
    let dir = work.canonicalize().unwrap().join("dry");
    let shard = std::fs::read_to_string(dir.join("slurm/shard.sh")).unwrap();
    let merge = std::fs::read_to_string(dir.join("slurm/merge.sh")).unwrap();
    let exe = env!("CARGO_BIN_EXE_skg-solve");
    let sweep_abs = work.canonicalize().unwrap().join(&rel_sweep);
    for needle in [format!("cd {} || exit 1", dir.display()), format!("exec {exe} sweep {} --shard \"$k/3\"", sweep_abs.display())] {
        assert!(shard.contains(&needle), "shard.sh lacks `{needle}`:\n{shard}");
    }
    assert!(shard.contains("-o ") && shard.contains(&format!("{}/shards/", dir.display())), "{shard}");
    assert!(shard.contains("SLURM_CPUS_PER_TASK") && shard.contains("SLURM_CPUS_ON_NODE"), "{shard}");
    assert!(merge.contains(&format!("exec {exe} sweep-merge {}", dir.display())), "{merge}");
    for script in ["shard.sh", "merge.sh"] {
        let ok = Command::new("bash").arg("-n").arg(dir.join("slurm").join(script)).status().unwrap();
        assert!(ok.success(), "{script} is valid bash");
    }
    // The printed commands: the array of shards 1-3 and the merge after it.
    assert!(printed.contains("--array=1-3") && printed.contains("--dependency=afterany:<array job id>"), "{printed}");
    assert!(dir.join("slurm/logs").is_dir());
    assert!(!dir.join("slurm/jobs.json").exists(), "a dry run records no submission");
    assert!(!dir.join("shards/1").exists());
    let queued = cluster.slurm("squeue", &["-h", "-t", "all", "-o", "%j"]);
    assert!(!queued.contains("skg-damped_quick"), "a dry run submits nothing: {queued}");
}

fn a_bad_sbatch_arg_is_a_clear_error(cluster: &Cluster, work: &Path) {
    let out = work.join("bad");
    let sweep = quick_sweep();
    let o = cluster
        .skg(&["sweep", sweep.to_str().unwrap(), "--slurm", "-o", out.to_str().unwrap(), "--sbatch-arg=--partition=nonexistent"], work);
    let text = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{text}");
    // Names what failed, with sbatch's own message.
    assert!(text.contains("sbatch ") && text.contains("--partition=nonexistent"), "{text}");
    assert!(text.contains("invalid partition specified: nonexistent"), "{text}");
    assert!(!out.join("slurm/jobs.json").exists(), "nothing submitted");
    // An option that skg-solve sets itself is a usage error, before anything runs.
    let o = cluster.skg(&["sweep", sweep.to_str().unwrap(), "--slurm", "-o", out.to_str().unwrap(), "--sbatch-arg=--array=1-3"], work);
    assert_eq!(o.status.code(), Some(2), "{}", common::text(&o));
    assert!(common::text(&o).contains("skg-solve sets --array itself"), "{}", common::text(&o));
    // So is an option of --slurm without it.
    let o = cluster.skg(&["sweep", sweep.to_str().unwrap(), "-o", out.to_str().unwrap(), "--shards", "2"], work);
    assert_eq!(o.status.code(), Some(2), "{}", common::text(&o));
}

/// The columns that must agree between a local run and a run on Slurm: the point, its
/// status, the solver's result and the errors (not the times, nor lu_analysis, which
/// depends on which worker ran which point before).
const SAME: &[&str] = &[
    "index",
    "nodes",
    "c",
    "converged",
    "status",
    "solver_status",
    "verification",
    "verify_error",
    "iterations",
    "error_max",
    "error_rms",
    "error_column",
    "message",
];

/// Rows of `dir/results.csv` by id, each as the `SAME` columns.
fn rows(dir: &Path) -> HashMap<String, Vec<String>> {
    let (r, count) = common::rows_by_id(dir);
    assert!(count.values().all(|&c| c == 1), "a point twice in {}: {count:?}", dir.display());
    let id = r.column_index("id").unwrap();
    let cols: Vec<usize> = SAME.iter().map(|c| r.column_index(c).unwrap_or_else(|| panic!("no column {c}"))).collect();
    r.rows.iter().map(|row| (row[id].clone(), cols.iter().map(|&c| row[c].clone()).collect())).collect()
}

fn a_shipped_sweep_on_slurm_gives_the_rows_of_a_local_run(cluster: &Cluster, work: &Path) {
    let sweep = quick_sweep();
    let local = work.join("quick-local");
    let o = common::skg(&["sweep", sweep.to_str().unwrap(), "-o", local.to_str().unwrap(), "-j", "2", "-q"], work);
    assert!(o.status.success(), "{}", common::text(&o));
    let on_slurm = work.join("quick-slurm");
    let o = cluster.skg(&["sweep", sweep.to_str().unwrap(), "--slurm", "-o", on_slurm.to_str().unwrap(), "--shards", "4", "--wait"], work);
    let text = common::text(&o);
    assert!(o.status.success(), "{text}");
    assert!(text.contains("merged:") && text.contains("holds every point (12)"), "{text}");
    let (expected, got) = (rows(&local), rows(&on_slurm));
    assert_eq!(expected.len(), 12);
    assert_eq!(got, expected, "the rows on Slurm are those of the local run");
    // Several statuses, so that the comparison means something.
    let statuses: std::collections::HashSet<&String> = expected.values().map(|r| &r[4]).collect();
    assert!(statuses.len() >= 2, "{statuses:?}");
    // Each task's log, and the merge's.
    let jobs: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(on_slurm.join("slurm/jobs.json")).unwrap()).unwrap();
    let array = jobs["submissions"][0]["array_job"].as_str().unwrap().to_string();
    for k in 1..=4 {
        let log = std::fs::read_to_string(on_slurm.join(format!("slurm/logs/shard-{array}_{k}.out"))).unwrap();
        assert!(log.contains(&format!("in shard {k}/4")), "{log}");
    }
    let status = cluster.skg(&["status", on_slurm.to_str().unwrap()], work);
    assert!(status.status.success(), "{}", common::text(&status));
    assert!(common::text(&status).contains("merged:"), "{}", common::text(&status));
    // Nothing is left to do: the same command submits nothing.
    let o = cluster.skg(&["sweep", sweep.to_str().unwrap(), "--slurm", "-o", on_slurm.to_str().unwrap(), "--wait"], work);
    assert!(o.status.success() && common::text(&o).contains("nothing to submit"), "{}", common::text(&o));
}

/// Poll `done` every 0.1 s for at most `limit`.
fn wait_until(what: &str, limit: Duration, mut done: impl FnMut() -> bool) {
    let deadline = Instant::now() + limit;
    while !done() {
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(100));
    }
}

/// The whole lines of a shard's results.csv after the header.
fn whole_rows(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("results.csv")).unwrap_or_default();
    let whole = &text[..text.rfind('\n').map_or(0, |i| i + 1)];
    whole.lines().skip(1).map(str::to_string).collect()
}

fn a_cancelled_task_is_completed_by_the_second_command(cluster: &Cluster, work: &Path) {
    // 12 points of 0.3–0.7 s each (the test profile's build), 6 per shard: a task runs
    // for seconds after its first row, time enough to cancel it then.
    let sweep =
        common::sweep_file(work, &common::scenario("damped_oscillator"), "[[grid]]\nc = [0.25, 0.5, 1, 2, 3, 4]\nnodes = [8192, 16384]\n");
    let out = work.join("cancel");
    let args = ["sweep", sweep.to_str().unwrap(), "--slurm", "-o", out.to_str().unwrap(), "--shards", "2"];
    let o = cluster.skg(&args, work);
    assert!(o.status.success(), "{}", common::text(&o));
    let jobs: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("slurm/jobs.json")).unwrap()).unwrap();
    let (array, merge) = (
        jobs["submissions"][0]["array_job"].as_str().unwrap().to_string(),
        jobs["submissions"][0]["merge_job"].as_str().unwrap().to_string(),
    );
    // While they are queued or running, the same command submits nothing.
    let o = cluster.skg(&args, work);
    assert_eq!(o.status.code(), Some(1), "{}", common::text(&o));
    assert!(common::text(&o).contains("still queued or running"), "{}", common::text(&o));
    // Cancel task 2 after its first row.
    let shard2 = out.join("shards/2");
    wait_until("shard 2's first row", Duration::from_secs(120), || !whole_rows(&shard2).is_empty());
    cluster.slurm("scancel", &[&format!("{array}_2")]);
    wait_until("the merge job to end", Duration::from_secs(120), || cluster.active_state(&merge).is_none());
    let kept = whole_rows(&shard2);
    assert!(!kept.is_empty() && kept.len() < 6, "the cancel hit shard 2 while it ran ({} of 6 rows)", kept.len());
    assert!(!out.join("results.csv").exists(), "an incomplete merge writes nothing");
    let merge_log = std::fs::read_to_string(out.join(format!("slurm/logs/merge-{merge}.out"))).unwrap();
    assert!(merge_log.contains("incomplete shards: 2 ("), "{merge_log}");
    let status = common::text(&cluster.skg(&["status", out.to_str().unwrap()], work));
    assert!(status.contains(&format!("{} missing", 6 - kept.len())) && status.contains("CANCELLED"), "{status}");
    // The second command submits shard 2 alone, which resumes: its rows are kept, not
    // run again.
    let o = cluster.skg(&[&args[..], &["--wait"]].concat(), work);
    let text = common::text(&o);
    assert!(o.status.success(), "{text}");
    assert!(text.contains("submitted shard 2 (1 of 2)"), "{text}");
    let jobs: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("slurm/jobs.json")).unwrap()).unwrap();
    assert_eq!(jobs["submissions"][1]["shards"], serde_json::json!([2]));
    let after = whole_rows(&shard2);
    assert_eq!(after.len(), 6);
    assert_eq!(&after[..kept.len()], &kept[..], "the rows from before the cancel are kept as they were");
    let (_, count) = common::rows_by_id(&out);
    assert_eq!(count.len(), 12, "{count:?}");
    assert!(count.values().all(|&c| c == 1), "{count:?}");
}
