//! Helpers shared by the integration tests of the `skg-solve` binary: running it, and
//! (from skg-sweep's test helpers, which include skg-core's) the scenes, sweep files
//! and results.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

#[path = "../../../skg-sweep/tests/common/mod.rs"]
mod sweeps;

pub use sweeps::*;

/// Run the `skg-solve` binary with `args` in the working directory `dir`.
pub fn skg(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_skg-solve")).args(args).current_dir(dir).output().unwrap()
}

/// Run the binary in `dir`; returns (exit code, everything it printed), failing the test
/// if it panicked.
pub fn run(args: &[&str], dir: &Path) -> (Option<i32>, String) {
    let o: Output = skg(args, dir);
    let t = text(&o);
    assert!(!t.contains("panicked"), "{args:?} panicked: {t}");
    (o.status.code(), t)
}

/// A path as text (the tests' paths are UTF-8).
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Everything a run printed: stdout, then stderr.
pub fn text(o: &Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// Run `command` to its end, its output collected, killing it (and failing the test with
/// `what`) if it is still running after 60 s: a watchdog, not a timing. The output is
/// read while it runs, so that a child that prints much cannot block on a full pipe.
pub fn with_watchdog(mut command: Command, what: &str) -> Output {
    let mut child = command.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    let (mut stdout, mut stderr) = (child.stdout.take().unwrap(), child.stderr.take().unwrap());
    let out = std::thread::spawn(move || {
        let mut buf = Vec::new();
        std::io::Read::read_to_end(&mut stdout, &mut buf).map(|_| buf)
    });
    let err = std::thread::spawn(move || {
        let mut buf = Vec::new();
        std::io::Read::read_to_end(&mut stderr, &mut buf).map(|_| buf)
    });
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > Duration::from_secs(60) {
            let _ = child.kill();
            panic!("{what}: still running after 60 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    Output { status, stdout: out.join().unwrap().unwrap(), stderr: err.join().unwrap().unwrap() }
}
