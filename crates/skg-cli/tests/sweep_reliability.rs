//! Reliability of sweeps: no lost, mixed or duplicated results (the merge of shards,
//! resumption after changed inputs, a locked directory, retries, workers that cannot
//! write), names and sizes checked before anything runs, output directories whose
//! symbolic links are not followed, and Slurm commands that hang or print no job id.
//! No panics, and exit codes a script can rely on.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use common::{run, s};
use skg_sweep::Results;

/// Rows per id of a results directory (every row once is the invariant).
fn ids(dir: &Path) -> HashMap<String, usize> {
    common::rows_by_id(dir).1
}

/// A free-fall sweep of `points` points (node counts 16, 17, …; fast to solve).
fn free_fall_sweep(dir: &Path, points: usize, extra: &str) -> PathBuf {
    let nodes: Vec<String> = (0..points).map(|k| (16 + k).to_string()).collect();
    common::sweep_file(dir, &common::scenario("free_fall"), &format!("{extra}[[grid]]\nnodes = [{}]\n", nodes.join(", ")))
}

/// `text` as a TOML basic string, control characters as `\uXXXX` escapes.
fn toml_string(text: &str) -> String {
    let body: String = text
        .chars()
        .map(|c| match c {
            '"' => "\\\"".to_string(),
            '\\' => "\\\\".to_string(),
            c if c.is_control() => format!("\\u{:04X}", c as u32),
            c => c.to_string(),
        })
        .collect();
    format!("\"{body}\"")
}

#[test]
fn merge_of_incomplete_shards_lists_the_missing_points_and_exits_1() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = free_fall_sweep(dir.path(), 9, "");
    let shard = |k: usize| {
        let out = dir.path().join(format!("shard{k}"));
        let (code, t) = run(&["sweep", s(&sweep), "-o", s(&out), "--shard", &format!("{k}/3"), "-j", "2", "-q"], Path::new("."));
        assert_eq!(code, Some(0), "{t}");
        out
    };
    let (one, two) = (shard(1), shard(2));
    let merged = dir.path().join("merged");
    let (code, t) = run(&["merge", "-o", s(&merged), s(&one), s(&two)], Path::new("."));
    assert_eq!(code, Some(1), "{t}");
    // Shard 3/3 holds the points whose index is 2 mod 3.
    assert!(t.contains("hold 6 of the sweep's 9 points") && t.contains("1/3, 2/3"), "{t}");
    for k in [2, 5, 8] {
        assert!(t.contains(&format!("index {k} (id ")), "index {k} not listed: {t}");
    }
    assert!(!merged.join("results.csv").exists(), "an incomplete merge writes nothing");
    // --partial merges what there is and still names what is missing.
    let (code, t) = run(&["merge", "--partial", "-o", s(&merged), s(&one), s(&two)], Path::new("."));
    assert_eq!(code, Some(0), "{t}");
    assert!(t.contains("3 of the sweep's 9 points are missing"), "{t}");
    assert_eq!(ids(&merged).len(), 6);
    // With the last shard the merge is complete.
    let three = shard(3);
    let (code, t) = run(&["merge", "-o", s(&merged), s(&one), s(&two), s(&three)], Path::new("."));
    assert_eq!(code, Some(0), "{t}");
    assert!(t.contains("every point of the sweep (9) is present"), "{t}");
    let all = ids(&merged);
    assert_eq!(all.len(), 9);
    assert!(all.values().all(|&c| c == 1));
    // A results.csv without its sweep.json cannot be checked for completeness.
    std::fs::remove_file(three.join("sweep.json")).unwrap();
    let (code, t) = run(&["merge", "-o", s(&merged), s(&one), s(&two), s(&three)], Path::new("."));
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("sweep.json"), "{t}");
}

#[test]
fn resuming_after_the_inputs_changed_is_refused_or_starts_a_new_result_set() {
    let dir = tempfile::tempdir().unwrap();
    // A reference file of the free fall (its closed form is a parabola; any table will do
    // for the identity), sampled finely.
    let reference = dir.path().join("ref.csv");
    let mut text = String::from("t,x,x_dot\n");
    for k in 0..=400 {
        let t = 2.0 * k as f64 / 400.0;
        text.push_str(&format!("{t:?},{:?},{:?}\n", 10.0 + 3.0 * t - 4.9 * t * t, 3.0 - 9.8 * t));
    }
    std::fs::write(&reference, &text).unwrap();
    let sweep = free_fall_sweep(dir.path(), 2, "reference = \"ref.csv\"\n");
    let out = dir.path().join("out");
    let (code, t) = run(&["sweep", s(&sweep), "-o", s(&out), "-q"], Path::new("."));
    assert_eq!(code, Some(0), "{t}");
    let r = Results::read(&out).unwrap();
    let hash = |p: &Path| skg_core::scene::provenance::content_hash(&std::fs::read(p).unwrap());
    let old_hash = hash(&reference);
    assert!(r.rows.iter().all(|row| row[r.column_index("reference_hash").unwrap()] == old_hash));
    // The closed form is the reference: free fall on SBP242 is exact.
    let e = r.column_index("error_max").unwrap();
    assert!(r.rows.iter().all(|row| row[e].parse::<f64>().unwrap() < 1e-9), "{:?}", r.rows);

    // An edited reference file: a plain rerun refuses, naming both contents.
    std::fs::write(&reference, text.replace("t,x,x_dot\n", "# edited\nt,x,x_dot\n")).unwrap();
    let (code, t) = run(&["sweep", s(&sweep), "-o", s(&out), "-q"], Path::new("."));
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains(&old_hash) && t.contains(&hash(&reference)) && t.contains("--new-results"), "{t}");
    // Other [sweep] settings that change a row's values are refused too.
    let edited = std::fs::read_to_string(&sweep).unwrap().replace("reference = \"ref.csv\"\n", "reference = \"ref.csv\"\nskip_last = 5\n");
    std::fs::write(&sweep, edited).unwrap();
    std::fs::write(&reference, &text).unwrap();
    let (code, t) = run(&["sweep", s(&sweep), "-o", s(&out), "-q"], Path::new("."));
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("other [sweep] settings") && t.contains("\"skip_last\":5"), "{t}");
    // --new-results moves the old result set aside and starts over.
    let (code, t) = run(&["sweep", s(&sweep), "-o", s(&out), "--new-results"], Path::new("."));
    assert_eq!(code, Some(0), "{t}");
    assert!(t.contains("moved the previous results to"), "{t}");
    let old: Vec<PathBuf> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir() && p.to_string_lossy().contains("superseded-"))
        .collect();
    assert_eq!(old.len(), 1);
    assert_eq!(ids(&old[0]).len(), 2, "the old rows are kept");
    assert_eq!(ids(&out).len(), 2);
}

#[test]
fn a_second_sweep_into_a_locked_directory_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = free_fall_sweep(dir.path(), 3, "");
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    // Hold the directory's lock as a running sweep does.
    let lock = std::fs::OpenOptions::new().create(true).truncate(false).write(true).open(out.join(".skg-lock")).unwrap();
    lock.try_lock().unwrap();
    let (code, t) = run(&["sweep", s(&sweep), "-o", s(&out), "-q"], Path::new("."));
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("another skg-solve is writing into"), "{t}");
    assert!(!out.join("results.csv").exists());
    // A solve into that directory is refused the same way.
    let (code, t) = run(&[s(&common::scenario("free_fall")), "-o", s(&out), "-q"], Path::new("."));
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("another skg-solve is writing into"), "{t}");
    drop(lock);
    // Two sweeps started at once: each point has exactly one row, and a run that found
    // the directory locked says so.
    let start = || {
        Command::new(env!("CARGO_BIN_EXE_skg-solve"))
            .args(["sweep", s(&sweep), "-o", s(&out), "-q", "-j", "1"])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (start(), start());
    for o in [a.wait_with_output().unwrap(), b.wait_with_output().unwrap()] {
        let t = common::text(&o);
        assert!(o.status.success() || (o.status.code() == Some(1) && t.contains("another skg-solve")), "{t}");
    }
    let rows = ids(&out);
    assert_eq!(rows.len(), 3);
    assert!(rows.values().all(|&c| c == 1), "{rows:?}");
}

#[test]
fn retry_failed_runs_crashed_and_failed_points_again() {
    let dir = tempfile::tempdir().unwrap();
    // max_iter = 0 cannot converge the tumbler; max_iter = 100 does (and verifies at N = 256).
    let sweep = common::sweep_file(dir.path(), &common::scenario("tumbler"), "[[grid]]\nnodes = [256]\nmax_iter = [0, 100]\n");
    let out = dir.path().join("out");
    let (code, t) = run(&["sweep", s(&sweep), "-o", s(&out), "-q"], Path::new("."));
    assert_eq!(code, Some(0), "{t}");
    // Mark the converged point as crashed, as a killed worker leaves it.
    let path = out.join("results.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let crashed = text.replacen(",true,converged,", ",false,crashed,", 1);
    assert_ne!(crashed, text);
    std::fs::write(&path, crashed).unwrap();
    // A plain rerun keeps both rows; --retry-failed runs both points again.
    let (_, t) = run(&["sweep", s(&sweep), "-o", s(&out)], Path::new("."));
    assert!(t.contains("2 already done, 0 run"), "{t}");
    let (code, t) = run(&["sweep", s(&sweep), "-o", s(&out), "--retry-failed"], Path::new("."));
    assert_eq!(code, Some(0), "{t}");
    assert!(t.contains("0 already done, 2 run (1 failed)"), "{t}");
    let r = Results::read(&out).unwrap();
    let status = r.column_index("status").unwrap();
    let mut statuses: Vec<&str> = r.rows.iter().map(|row| row[status].as_str()).collect();
    statuses.sort();
    assert_eq!(statuses, ["converged", "not_converged"]);
}

#[test]
fn sweep_names_and_compare_columns_are_checked_before_anything_runs() {
    let dir = tempfile::tempdir().unwrap();
    let long = "n".repeat(201);
    for name in ["../../x", "", ".", "..", "a/b", "q\necho INJECTED > PWNED #", "tab\there", "\u{1b}[2Jclear", ".hidden", &long] {
        let sweep = free_fall_sweep(dir.path(), 1, &format!("name = {}\n", toml_string(name)));
        for args in [vec!["sweep", s(&sweep)], vec!["sweep", s(&sweep), "--slurm", "--dry-run"]] {
            let (code, t) = run(&args, dir.path());
            assert_eq!(code, Some(1), "{name:?} {args:?}: {t}");
            assert!(t.contains("sweep.toml:3:8") && t.contains("plain file name"), "{name:?}: {t}");
            // The name is quoted with its escapes: no raw control character reaches the terminal.
            assert!(!t.chars().any(|c| c.is_control() && c != '\n'), "{name:?}: {t:?}");
        }
    }
    // A sweep file whose own name would be the sweep's (no `[sweep] name`) is refused alike.
    let named = dir.path().join("q\necho INJECTED > PWNED #.toml");
    std::fs::copy(free_fall_sweep(dir.path(), 1, ""), &named).unwrap();
    let (code, t) = run(&["sweep", s(&named), "--slurm", "--dry-run"], dir.path());
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("control character") && t.contains("give the file another name"), "{t}");
    std::fs::remove_file(&named).unwrap();
    let written: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(written, ["sweep.toml"], "nothing written anywhere");
    let sweep = free_fall_sweep(dir.path(), 1, "reference = \"integrate\"\ncompare = [\"x\", \"y\"]\n");
    let (code, t) = run(&["sweep", s(&sweep), "-o", "out"], dir.path());
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("sweep.toml:4:11") && t.contains("no column `y`") && t.contains("x, x_dot, energy"), "{t}");
    assert!(!dir.path().join("out").exists(), "no point ran");
}

#[test]
fn large_sweeps_state_their_size_and_need_yes() {
    let dir = tempfile::tempdir().unwrap();
    let body = "[[grid]]\nnodes = [16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26]\ng = [".to_string()
        + &(0..1000).map(|k| format!("{}", 9.0 + k as f64 / 1000.0)).collect::<Vec<_>>().join(", ")
        + "]\n";
    let sweep = common::sweep_file(dir.path(), &common::scenario("free_fall"), &body);
    let (code, t) = run(&["sweep", s(&sweep), "-o", "out"], dir.path());
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("11000 points") && t.contains("roughly") && t.contains("--yes"), "{t}");
    assert!(!dir.path().join("out").exists());
    // A grid beyond what one sweep file may hold is refused before it is materialized.
    let huge = "[[grid]]\nnodes = [16, 17, 18, 19, 20, 21, 22, 23, 24, 25]\n".to_string()
        + &(0..7).map(|k| format!("x{k} = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]\n")).collect::<String>();
    let sweep = common::sweep_file(dir.path(), &common::scenario("free_fall"), &huge.replace("x0", "g").replace("x1", "m"));
    let (code, t) = run(&["sweep", s(&sweep), "-o", "out", "--yes"], dir.path());
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("more than the 10000000"), "{t}");
}

/// Symbolic links placed inside an output directory are not followed: a link where the
/// log's directory, a sweep's `points/` or the lock file would be is refused (exit 1,
/// naming the link) and nothing is written where it points.
#[test]
fn symbolic_links_inside_output_directories_are_not_followed() {
    use std::os::unix::fs::symlink;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let elsewhere = d.join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    let refused = |args: &[&str], link: &str| {
        let (code, t) = run(args, d);
        assert_eq!(code, Some(1), "{args:?}: {t}");
        assert!(t.contains(&format!("{link} is a symbolic link")), "{args:?}: {t}");
        assert_eq!(std::fs::read_dir(&elsewhere).unwrap().count(), 0, "{args:?} wrote through {link}");
    };
    // `log_file = "logs/ipopt.log"` with OUT/logs a link to another directory.
    let scene = common::variant(d, "free_fall", "log.toml", &[("[verify]", "[solver]\nlog_file = \"logs/ipopt.log\"\n\n[verify]")]);
    std::fs::create_dir(d.join("out")).unwrap();
    symlink(&elsewhere, d.join("out/logs")).unwrap();
    refused(&[s(&scene), "-o", "out"], "out/logs");
    // OUT/.skg-lock a link to a file that does not exist yet: it is not created.
    std::fs::create_dir(d.join("locked")).unwrap();
    symlink(elsewhere.join("victim"), d.join("locked/.skg-lock")).unwrap();
    refused(&[s(&common::scenario("free_fall")), "-o", "locked"], "locked/.skg-lock");
    // A sweep that keeps its trajectories, with DIR/points a link.
    let sweep = free_fall_sweep(d, 2, "keep_trajectories = true\n");
    std::fs::create_dir(d.join("sweep")).unwrap();
    symlink(&elsewhere, d.join("sweep/points")).unwrap();
    refused(&["sweep", s(&sweep), "-o", "sweep", "-q"], "sweep/points");
    // A link at a point's own directory DIR/points/<id> fails that point (its row says
    // why); the ids are those of the same sweep run without links.
    let (code, t) = run(&["sweep", s(&sweep), "-o", "plain", "-q"], d);
    assert_eq!(code, Some(0), "{t}");
    std::fs::create_dir_all(d.join("linked/points")).unwrap();
    for id in ids(&d.join("plain")).keys() {
        symlink(&elsewhere, d.join("linked/points").join(id)).unwrap();
    }
    let (_, t) = run(&["sweep", s(&sweep), "-o", "linked", "-q"], d);
    assert_eq!(std::fs::read_dir(&elsewhere).unwrap().count(), 0, "{t}");
    let results = std::fs::read_to_string(d.join("linked/results.csv")).unwrap();
    assert!(results.contains("is a symbolic link"), "{results}");
}

/// Fake Slurm commands in `bin` (each a shell script with the given body), for
/// `sweep --slurm` without a cluster.
fn fake_slurm(bin: &Path, commands: &[(&str, &str)]) {
    use std::os::unix::fs::PermissionsExt;
    std::fs::create_dir_all(bin).unwrap();
    for (name, body) in commands {
        let path = bin.join(name);
        std::fs::write(&path, format!("#!/bin/sh\n{body}\n")).unwrap();
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
}

/// `skg-solve args` with the fake Slurm commands of `bin` first on PATH and every Slurm
/// command limited to `timeout` seconds; killed (and the test failed) after 60 s.
fn run_with_slurm(args: &[&str], dir: &Path, bin: &Path, timeout: &str) -> (Option<i32>, String) {
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let mut command = Command::new(env!("CARGO_BIN_EXE_skg-solve"));
    command.args(args).current_dir(dir).env("PATH", path).env("SKG_SLURM_TIMEOUT", timeout);
    let o = common::with_watchdog(command, &format!("{args:?} (a hanging Slurm command hangs skg-solve)"));
    let t = common::text(&o);
    assert!(!t.contains("panicked"), "{t}");
    (o.status.code(), t)
}

/// A hanging sbatch or squeue ends `sweep --slurm` (and `--wait`) with exit 1 after the
/// commands' time limit; a submission whose job id cannot be read is recorded in
/// jobs.json and its error says how to find the job; an array whose merge job's id
/// cannot be read is cancelled.
#[test]
fn slurm_commands_that_hang_or_print_no_job_id_end_in_exit_1() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sweep = free_fall_sweep(d, 4, "");
    let jobs = |out: &str| std::fs::read_to_string(d.join(out).join("slurm/jobs.json")).unwrap_or_default();
    // sbatch hangs.
    let bin = d.join("hang");
    fake_slurm(&bin, &[("sbatch", "exec sleep 600"), ("squeue", "exit 0"), ("scancel", "exit 0")]);
    let (code, t) = run_with_slurm(&["sweep", s(&sweep), "--slurm", "-o", "a"], d, &bin, "1");
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("did not finish within 1 s") && t.contains("SKG_SLURM_TIMEOUT"), "{t}");
    assert!(jobs("a").contains("unconfirmed"), "the submission is recorded: {}", jobs("a"));
    // squeue hangs under --wait: tolerated for ten time limits, then exit 1.
    let bin = d.join("squeue");
    fake_slurm(&bin, &[("sbatch", "echo 4242"), ("squeue", "exec sleep 600"), ("scancel", "exit 0")]);
    let (code, t) = run_with_slurm(&["sweep", s(&sweep), "--slurm", "--wait", "-o", "b"], d, &bin, "0.5");
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("squeue") && t.contains("did not finish within 0.5 s"), "{t}");
    // sbatch prints no job id for the array.
    let bin = d.join("garbage");
    fake_slurm(&bin, &[("sbatch", "echo 'queue is busy, try later'"), ("squeue", "exit 0"), ("scancel", "exit 0")]);
    let (code, t) = run_with_slurm(&["sweep", s(&sweep), "--slurm", "-o", "c"], d, &bin, "5");
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("printed no job id") && t.contains("squeue --me --name=skg-"), "{t}");
    assert!(jobs("c").contains("queue is busy"), "{}", jobs("c"));
    // sbatch gives the array's id but none for the merge: the array is cancelled, and
    // both are recorded.
    let bin = d.join("merge");
    let log = d.join("scancel.log");
    let script = "case \"$*\" in *merge.sh*) echo oops ;; *) echo 'Submitted batch job 777' ;; esac";
    fake_slurm(&bin, &[("sbatch", script), ("squeue", "exit 0"), ("scancel", &format!("echo \"$@\" >> {}", log.display()))]);
    let (code, t) = run_with_slurm(&["sweep", s(&sweep), "--slurm", "-o", "e"], d, &bin, "5");
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("array job 777") && t.contains("cancelled"), "{t}");
    assert_eq!(std::fs::read_to_string(&log).unwrap().trim(), "777");
    assert!(jobs("e").contains("\"777\"") && jobs("e").contains("unconfirmed"), "{}", jobs("e"));
}

/// A shard whose sweep.json was removed is incomplete for `status`, for the
/// resubmission and for the merge alike; running it again completes it without running
/// its points again.
#[test]
fn a_shard_without_its_sweep_json_is_incomplete_everywhere() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sweep = free_fall_sweep(d, 4, "");
    let (code, t) = run(&["sweep", s(&sweep), "--slurm", "--dry-run", "--shards", "2", "-o", "sh"], d);
    assert_eq!(code, Some(0), "{t}");
    let shard = |k: usize| run(&["sweep", s(&sweep), "--shard", &format!("{k}/2"), "-o", &format!("sh/shards/{k}"), "-q"], d);
    for k in [1, 2] {
        assert_eq!(shard(k).0, Some(0));
    }
    std::fs::remove_file(d.join("sh/shards/2/sweep.json")).unwrap();
    // status: shard 2's points are missing.
    let (code, t) = run(&["status", "sh"], d);
    assert_eq!(code, Some(0), "{t}");
    assert!(t.contains("2 missing") || t.lines().any(|l| l.split_whitespace().collect::<Vec<_>>() == ["2", "2", "0", "0", "2"]), "{t}");
    // The resubmission would submit shard 2.
    let (_, t) = run(&["sweep", s(&sweep), "--slurm", "--dry-run", "-o", "sh"], d);
    assert!(t.contains("--array=2 "), "{t}");
    // The merge names it (it said "incomplete shards: ;").
    let (code, t) = run(&["sweep-merge", "sh"], d);
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("2 (2 of 2 missing)"), "{t}");
    // Run again, the shard writes its sweep.json and runs nothing; then the merge is complete.
    let (code, t) = run(&["sweep", s(&sweep), "--shard", "2/2", "-o", "sh/shards/2"], d);
    assert_eq!(code, Some(0), "{t}");
    assert!(t.contains("2 already done"), "{t}");
    let (code, t) = run(&["sweep-merge", "sh"], d);
    assert_eq!(code, Some(0), "{t}");
}

/// Sweep workers whose files cannot be written (a file-size limit with SIGXFSZ ignored:
/// EFBIG, as a full disk gives ENOSPC) record the point as an error in the system's
/// words; none exits 101 ("failed printing to stdout", "worker exited … without a
/// result").
#[test]
fn sweep_workers_that_cannot_write_record_an_error_not_a_crash() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let body = "keep_trajectories = true\n[[grid]]\nnodes = [100, 1200, 1600, 2000]\n";
    let sweep = common::sweep_file(d, &common::scenario("free_fall"), body);
    let script = format!("trap '' XFSZ; ulimit -f 40; exec \"$0\" sweep {} -o out -j 2", s(&sweep));
    let o = Command::new("sh").args(["-c", &script, env!("CARGO_BIN_EXE_skg-solve")]).current_dir(d).output().unwrap();
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(0), "{t}");
    let results = std::fs::read_to_string(d.join("out/results.csv")).unwrap();
    assert!(results.contains("File too large"), "{results}");
    assert!(!results.contains("crashed") && !results.contains("status: 101") && !t.contains("panicked"), "{results}\n{t}");
}
