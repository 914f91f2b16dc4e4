//! Closed and full standard streams (crates/skg-cli/src/stdio.rs): a closed pipe on
//! stdout or stderr ends the command quietly with its own status (0 when it succeeded),
//! a full device is an I/O error (status 1) whose message names the stream, and nothing
//! panics (a `println!` would: "failed printing to stdout", status 101).
//!
//! A closed pipe is one whose reading end is closed before the command starts, so that
//! every write fails with EPIPE, whatever the timing; a full device is `/dev/full`
//! (ENOSPC on every write; the tests that need it return early where it is missing).

mod common;

use std::fs::OpenOptions;
use std::io::Write;
use std::path::Path;
use std::process::{Command, Output, Stdio};

/// The writing end of a pipe whose reading end is already closed.
fn closed_pipe() -> Stdio {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    Stdio::from(writer)
}

/// `/dev/full`, where it exists.
fn full() -> Option<Stdio> {
    OpenOptions::new().write(true).open("/dev/full").ok().map(Stdio::from)
}

/// Run `skg-solve args` in `dir` with the given stdout and stderr (a stream given as
/// `None` is captured), stdin empty.
fn run(args: &[&str], dir: &Path, stdout: Option<Stdio>, stderr: Option<Stdio>) -> Output {
    Command::new(env!("CARGO_BIN_EXE_skg-solve"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(stdout.unwrap_or_else(Stdio::piped))
        .stderr(stderr.unwrap_or_else(Stdio::piped))
        .output()
        .unwrap()
}

/// What a run printed on the streams that were captured.
fn printed(o: &Output) -> String {
    common::text(o)
}

/// A sweep of two free-fall points run in `dir/sweep`, for `status`.
fn small_sweep(dir: &Path) -> String {
    let file = common::sweep_file(dir, &common::scenario("free_fall"), "[[grid]]\nnodes = [16, 20]\n");
    let out = dir.join("sweep");
    let o = common::skg(&["sweep", file.to_str().unwrap(), "-o", out.to_str().unwrap(), "-j", "1", "-q"], dir);
    assert!(o.status.success(), "{}", common::text(&o));
    out.to_str().unwrap().to_string()
}

#[test]
fn a_closed_stdout_ends_quietly_with_the_commands_status() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = small_sweep(dir.path());
    for args in [vec!["--help"], vec!["--version"], vec!["sweep", "--help"], vec!["status", &sweep]] {
        let o = run(&args, dir.path(), Some(closed_pipe()), None);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", printed(&o));
        assert!(o.stderr.is_empty(), "{args:?}: quiet, but printed {}", printed(&o));
    }
    // A solve still writes its files, and its progress lines still reach stderr.
    let scene = common::scenario("free_fall");
    let o = run(&[scene.to_str().unwrap(), "-o", "solved"], dir.path(), Some(closed_pipe()), None);
    assert_eq!(o.status.code(), Some(0), "{}", printed(&o));
    assert!(!printed(&o).contains("panicked") && !printed(&o).contains("error"), "{}", printed(&o));
    assert!(dir.path().join("solved/summary.json").is_file());
    // A usage error keeps its status 2.
    let o = run(&["--no-such-option"], dir.path(), Some(closed_pipe()), None);
    assert_eq!(o.status.code(), Some(2), "{}", printed(&o));
}

#[test]
fn a_closed_stderr_ends_quietly_with_the_commands_status() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::scenario("free_fall");
    let scene = scene.to_str().unwrap();
    // The solve's progress lines go to the closed stderr; the report to stdout.
    let o = run(&[scene, "-o", "solved"], dir.path(), None, Some(closed_pipe()));
    assert_eq!(o.status.code(), Some(0), "{}", printed(&o));
    assert!(printed(&o).contains("converged") && printed(&o).contains("wrote"), "{}", printed(&o));
    // Both streams closed, as `skg-solve SCENE 2>&1 | head -c 10` once head has exited.
    let o = run(&[scene, "-o", "solved2"], dir.path(), Some(closed_pipe()), Some(closed_pipe()));
    assert_eq!(o.status.code(), Some(0));
    assert!(dir.path().join("solved2/summary.json").is_file());
    // A failure keeps its status although its message is lost: 1 for an input error,
    // 2 for a usage error, 3 for a solve that did not converge.
    let o = run(&["no_such_scene.toml"], dir.path(), None, Some(closed_pipe()));
    assert_eq!(o.status.code(), Some(1));
    let o = run(&["--no-such-option"], dir.path(), None, Some(closed_pipe()));
    assert_eq!(o.status.code(), Some(2));
    let tumbler = common::scenario("tumbler");
    let args = [tumbler.to_str().unwrap(), "-o", "short", "--max-iter", "0", "--no-fallback"];
    let o = run(&args, dir.path(), Some(closed_pipe()), Some(closed_pipe()));
    assert_eq!(o.status.code(), Some(3));
}

#[test]
fn a_full_stdout_is_an_io_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let Some(_) = full() else { return };
    let sweep = small_sweep(dir.path());
    let scene = common::scenario("free_fall");
    for args in [vec!["--help"], vec!["--version"], vec!["status", &sweep], vec![scene.to_str().unwrap(), "-o", "solved"]] {
        let o = run(&args, dir.path(), full(), None);
        let t = printed(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {t}");
        assert!(t.contains("error: writing to stdout: No space left on device"), "{args:?}: {t}");
        assert!(!t.contains("panicked"), "{args:?}: {t}");
    }
    // The solve's files are written all the same.
    assert!(dir.path().join("solved/summary.json").is_file());
}

#[test]
fn a_full_stderr_is_an_io_error() {
    let dir = tempfile::tempdir().unwrap();
    let Some(_) = full() else { return };
    let scene = common::scenario("free_fall");
    // The progress lines cannot be written: status 1; the report still reaches stdout.
    let o = run(&[scene.to_str().unwrap(), "-o", "solved"], dir.path(), None, full());
    assert_eq!(o.status.code(), Some(1), "{}", printed(&o));
    assert!(printed(&o).contains("wrote"), "{}", printed(&o));
    // Nothing to write on stderr: a quiet success stays a success.
    let o = run(&[scene.to_str().unwrap(), "-o", "quiet", "-q"], dir.path(), None, full());
    assert_eq!(o.status.code(), Some(0), "{}", printed(&o));
    // Both full: status 1, no panic (status 101).
    let o = run(&["--help"], dir.path(), full(), full());
    assert_eq!(o.status.code(), Some(1));
}

/// The hidden `sweep-worker` reports through its JSON files and prints only an error;
/// with its stdout and stderr full or closed it still exits 1 on an error and 0 when
/// stdin ends, without a panic.
#[test]
fn a_sweep_worker_with_full_or_closed_streams_does_not_panic() {
    let dir = tempfile::tempdir().unwrap();
    let work = dir.path().join("work");
    std::fs::create_dir(&work).unwrap();
    let stream = |name: &str| match name {
        "closed" => Some(closed_pipe()),
        "full" => full(),
        _ => None,
    };
    for name in ["closed", "full", "captured"] {
        if name == "full" && full().is_none() {
            continue;
        }
        for (stdin, status) in [("", 0), ("0123456789abcdef\n", 1), ("not a point\n", 1)] {
            let mut child = Command::new(env!("CARGO_BIN_EXE_skg-solve"))
                .args(["sweep-worker", work.to_str().unwrap()])
                .stdin(Stdio::piped())
                .stdout(stream(name).unwrap_or_else(Stdio::piped))
                .stderr(stream(name).unwrap_or_else(Stdio::piped))
                .spawn()
                .unwrap();
            child.stdin.take().unwrap().write_all(stdin.as_bytes()).unwrap();
            let o = child.wait_with_output().unwrap();
            assert_eq!(o.status.code(), Some(status), "{name} streams, stdin {stdin:?}: {}", printed(&o));
            assert!(!printed(&o).contains("panicked"), "{}", printed(&o));
        }
    }
}
