//! Kill tests: a solve and a sweep are killed (SIGKILL) at seeded random moments and
//! run again. After every kill the files that are there must obey the pairing rule
//! (a `summary.json` describes exactly the `trajectory.csv` beside it), the Ipopt log
//! must be a complete one, and the complete lines of `results.csv` must hold each point
//! at most once; after the final run every point is there exactly once and no
//! temporary file is left. The moments are drawn from a fixed seed over the measured
//! duration of an uninterrupted run, so a slow machine shifts them but every assertion
//! holds at any moment.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::Rng;
use sha2::{Digest, Sha256};

fn skg(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_skg-solve"));
    c.args(args).stdout(Stdio::null()).stderr(Stdio::null());
    c
}

/// Run to completion; the wall time.
fn complete(args: &[&str]) -> Duration {
    let start = Instant::now();
    let status = skg(args).status().unwrap();
    assert!(status.success(), "{args:?}: {status}");
    start.elapsed()
}

/// Start, wait `delay`, SIGKILL; whether the process was still running when killed.
fn kill_after(args: &[&str], delay: Duration) -> bool {
    let mut child = skg(args).spawn().unwrap();
    std::thread::sleep(delay);
    let running = child.try_wait().unwrap().is_none();
    child.kill().unwrap();
    child.wait().unwrap();
    running
}

/// The pairing rule in `dir`, checked with an independent SHA-256: a summary.json lists
/// the trajectory.csv beside it with its exact bytes and row count.
fn assert_paired(dir: &Path) {
    let Ok(text) = std::fs::read_to_string(dir.join("summary.json")) else { return };
    let summary: serde_json::Value = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    let bytes = std::fs::read(dir.join("trajectory.csv")).expect("a summary is written after its trajectory");
    let hex: String = Sha256::digest(&bytes).iter().map(|b| format!("{b:02x}")).collect();
    let listed = &summary["files"]["trajectory.csv"];
    assert_eq!(listed["sha256"], format!("sha256:{hex}"), "{}", dir.display());
    let rows = String::from_utf8_lossy(&bytes).lines().filter(|l| !l.starts_with('#')).count() - 1;
    assert_eq!(listed["rows"], rows, "{}", dir.display());
}

/// Temporary files (`.skg-tmp-*`) anywhere under `dir`.
fn temporaries(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if e.file_name().to_string_lossy().starts_with(".skg-tmp-") {
                found.push(p);
            }
        }
    }
    found
}

/// Kill the solve of the scene `text` (written as `dir/name`, with an Ipopt log) at
/// moments drawn from `seed` over the duration of an uninterrupted run, until 12 kills
/// have hit a running solve; after every kill and at the end the files are paired and the
/// log whole.
fn kill_a_solve(name: &str, text: &str, seed: u64) {
    let dir = tempfile::tempdir().unwrap();
    let text = text.to_string() + "\n[solver]\nlog_file = \"ipopt.log\"\n";
    let scene = dir.path().join(name);
    std::fs::write(&scene, text).unwrap();
    let out = dir.path().join("out");
    let args = [scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"];
    // The faster of two runs: the first may pay for a cold start.
    let full = complete(&args).min(complete(&args));
    let log_is_whole = || std::fs::read_to_string(out.join("ipopt.log")).unwrap().contains("\nEXIT: ");
    let mut rng = Rng(seed);
    // Twelve kills that hit a running solve. A kill that comes after the solve ended
    // (a run faster than the measured one) does not count: the later moments are drawn
    // from a shorter span, so that the test kills running solves on any machine.
    let (mut killed_running, mut span) = (0, 1.0);
    for _ in 0..48 {
        let running = kill_after(&args, full.mul_f64(span * rng.uniform()));
        assert_paired(&out);
        assert!(log_is_whole(), "a kill leaves the previous complete log");
        if running {
            killed_running += 1;
        } else {
            span *= 0.8;
        }
        if killed_running == 12 {
            break;
        }
    }
    eprintln!("{name}: {killed_running} kills hit a running solve");
    assert_eq!(killed_running, 12, "{name}: only {killed_running} kills hit a running solve");
    complete(&args);
    assert_paired(&out);
    assert!(log_is_whole());
    assert_eq!(temporaries(&out), Vec::<PathBuf>::new(), "the rerun removes the killed runs' temporary files");
}

#[test]
fn a_solve_killed_at_random_moments_keeps_its_files_paired_and_its_log_whole() {
    let text = std::fs::read_to_string(common::scenario("tumbler")).unwrap().replace("nodes = 256", "nodes = 1024");
    kill_a_solve("tumbler.toml", &text, 0x5eed_0014);
}

/// The same for a solve in windows (the keys `window` and `overlap`): every window
/// writes into the staged log, and the files are written once, at the end.
#[test]
fn a_windowed_solve_killed_at_random_moments_keeps_its_files_paired_and_its_log_whole() {
    let text = std::fs::read_to_string(common::scenario("drum_long"))
        .unwrap()
        .replace("end = 20", "end = 4")
        .replace("nodes = 20481", "nodes = 4097")
        .replace("window = 1", "window = 1\noverlap = 0.3");
    assert!(text.contains("overlap = 0.3") && text.contains("end = 4"));
    kill_a_solve("drum_windows.toml", &text, 0x5eed_0021);
}

/// Ids of the complete lines of `results.csv` (a kill may leave a partial last line).
fn complete_row_ids(dir: &Path) -> HashMap<String, usize> {
    let Ok(text) = std::fs::read_to_string(dir.join("results.csv")) else { return HashMap::new() };
    let complete = &text[..text.rfind('\n').map_or(0, |i| i + 1)];
    let mut ids = HashMap::new();
    for line in complete.lines().skip(1) {
        *ids.entry(line.split(',').next().unwrap().to_string()).or_insert(0) += 1;
    }
    ids
}

#[test]
fn a_sweep_killed_at_random_moments_and_resumed_has_each_point_once() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = common::sweep_file(
        dir.path(),
        &common::scenario("tumbler"),
        "keep_trajectories = true\n[[grid]]\nnodes = [128, 160, 192, 224, 256, 288]\nsigma = [\"1/80\", \"1/110\"]\n",
    );
    let points = skg_sweep::SweepFile::load(&sweep).unwrap().expand().unwrap().points;
    assert_eq!(points.len(), 12);
    // An uninterrupted run elsewhere gives the time scale of the kill moments.
    let scratch = dir.path().join("scratch");
    let full = complete(&["sweep", sweep.to_str().unwrap(), "-o", scratch.to_str().unwrap(), "-j", "2", "-q"]);
    let out = dir.path().join("out");
    let args = ["sweep", sweep.to_str().unwrap(), "-o", out.to_str().unwrap(), "-j", "2", "-q"];
    let mut rng = Rng(0x5eed_0141);
    // Six kills that hit a running sweep; one that comes after the sweep ended (a run
    // faster than the measured one) does not count, and the later moments are drawn from
    // a shorter span.
    let (mut killed_running, mut span) = (0, 0.9);
    for _ in 0..24 {
        // Each resumed run has less to do: kill within the time its remaining points take.
        let remaining = (points.len() - complete_row_ids(&out).len()) as f64 / points.len() as f64;
        if remaining == 0.0 {
            break;
        }
        let running = kill_after(&args, full.mul_f64(span * remaining * rng.uniform()));
        let ids = complete_row_ids(&out);
        assert!(ids.values().all(|&c| c == 1), "a point twice after a kill: {ids:?}");
        for id in ids.keys() {
            assert_paired(&out.join("points").join(id));
        }
        if running {
            killed_running += 1;
        } else {
            span *= 0.8;
        }
        if killed_running == 6 {
            break;
        }
    }
    eprintln!("{killed_running} kills hit a running sweep");
    assert!(killed_running >= 2, "only {killed_running} kills hit a running sweep");
    complete(&args);
    let ids = complete_row_ids(&out);
    assert_eq!(ids.len(), points.len(), "{ids:?}");
    assert!(ids.values().all(|&c| c == 1), "{ids:?}");
    for p in &points {
        assert_paired(&out.join("points").join(p.id()));
    }
    assert!(!out.join(".work").exists());
    assert_eq!(temporaries(&out), Vec::<PathBuf>::new());
}

/// The processes whose parent is `pid` (from `/proc/*/stat`).
fn children(pid: u32) -> Vec<u32> {
    let mut found = Vec::new();
    for e in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(stat) = std::fs::read_to_string(e.path().join("stat")) else { continue };
        // The fields after "(comm) ": state, ppid, …
        let Some(rest) = stat.rsplit_once(") ").map(|(_, r)| r) else { continue };
        if rest.split(' ').nth(1).and_then(|p| p.parse::<u32>().ok()) == Some(pid) {
            found.extend(e.file_name().to_str().and_then(|n| n.parse::<u32>().ok()));
        }
    }
    found
}

/// Sends SIGTERM to each of `pids` that still exists; the number signalled.
fn signal_running(pids: &[u32]) -> usize {
    pids.iter().filter(|p| Command::new("kill").arg("-TERM").arg(p.to_string()).stderr(Stdio::null()).status().unwrap().success()).count()
}

fn send(signal: &str, pids: &[u32]) {
    let pids: Vec<String> = pids.iter().map(u32::to_string).collect();
    let status = Command::new("kill").arg(format!("-{signal}")).args(&pids).status().unwrap();
    assert!(status.success(), "kill -{signal} {pids:?}");
}

/// SIGTERM (what Slurm's `scancel` sends to every process of a job at once) stops a
/// sweep between two rows: the driver dies of SIGTERM, results.csv ends with a whole row,
/// and the points whose workers died of the same SIGTERM are not recorded as crashed:
/// the resume runs them. Here the workers get the signal 0.05 s before the driver (well
/// inside the driver's one-second grace for its own signal, on a loaded machine too), the
/// worst order for the driver (without the grace for its own signal it records them as
/// crashed rows, which a resume would keep).
#[test]
fn a_sweep_stopped_by_sigterm_leaves_whole_rows_and_no_crashed_point() {
    let dir = tempfile::tempdir().unwrap();
    let sweep =
        // Points of about a second each (debug build), so that the workers still run
        // them when the signal comes.
        common::sweep_file(dir.path(), &common::scenario("damped_oscillator"), "[[grid]]\nc = [0.25, 0.5, 1, 2]\nnodes = [40000, 100000]\n");
    let out = dir.path().join("out");
    let args = ["sweep", sweep.to_str().unwrap(), "-o", out.to_str().unwrap(), "-j", "2", "-q"];
    let child = skg(&args).stderr(Stdio::piped()).spawn().unwrap();
    // Wait until both workers run points.
    let deadline = Instant::now() + Duration::from_secs(60);
    let workers = loop {
        let w = children(child.id());
        if w.len() == 2 || Instant::now() > deadline {
            break w;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(workers.len(), 2, "two workers started");
    std::thread::sleep(Duration::from_millis(100));
    // A worker may have finished its point in between: signal those running now.
    let deadline = Instant::now() + Duration::from_secs(60);
    while signal_running(&children(child.id())) == 0 {
        assert!(Instant::now() < deadline, "no worker ran a point");
        std::thread::sleep(Duration::from_millis(5));
    }
    std::thread::sleep(Duration::from_millis(50));
    send("TERM", &[child.id()]);
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(output.status.signal(), Some(15), "the driver dies of SIGTERM: {:?} {stderr}", output.status);
    assert!(stderr.contains("stopped by signal 15 (SIGTERM)") && stderr.contains("run the same command again"), "{stderr}");
    let text = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert!(text.ends_with('\n'), "whole rows only: {text}");
    assert!(!text.contains(",crashed,"), "a point stopped by SIGTERM is no crashed point: {text}");
    let before = complete_row_ids(&out).len();
    assert!(before < 8, "stopped before the end ({before} rows)");
    complete(&args);
    let ids = complete_row_ids(&out);
    assert_eq!(ids.len(), 8, "{ids:?}");
    assert!(ids.values().all(|&c| c == 1), "{ids:?}");
    let text = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert!(!text.contains(",crashed,"), "{text}");
}
