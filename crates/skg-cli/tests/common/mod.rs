//! Helpers shared by the integration tests of the `skg-solve` binary: running it, and
//! (from skg-sweep's test helpers, which include skg-core's) the scenes, sweep files
//! and results.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

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
