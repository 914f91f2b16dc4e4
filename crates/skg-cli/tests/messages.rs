//! Messages of the commands (issue 21 items 9 and 10): each names the file it is about
//! and says what happened in words, never in a library's Debug form; options that
//! cannot take effect are refused rather than ignored. Each test failed before its fix.

mod common;

use std::path::Path;

/// Run the binary in `dir`; (exit code, everything it printed). Never a panic.
fn run(args: &[&str], dir: &Path) -> (Option<i32>, String) {
    let o = common::skg(args, dir);
    let t = common::text(&o);
    assert!(!t.contains("panicked"), "{args:?} panicked: {t}");
    (o.status.code(), t)
}

/// A solve of the tumbler into `dir/name` (its trajectory, summary and reference).
fn solved_tumbler(dir: &Path, name: &str) -> std::path::PathBuf {
    let out = dir.join(name);
    let (code, t) = run(&[common::scenario("tumbler").to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"], dir);
    assert_eq!(code, Some(0), "{t}");
    out
}

/// `reference --hard-walls` on a scene it cannot model names the scene file, and the
/// line of the wall that moves (before the fix: no file at all).
#[test]
fn the_hard_wall_reference_names_the_file_and_the_moving_wall() {
    let dir = tempfile::tempdir().unwrap();
    let plate = common::scenario("vibrating_plate");
    let (code, t) = run(&["reference", plate.to_str().unwrap(), "--hard-walls", "-o", "r.csv", "-q"], dir.path());
    let line = std::fs::read_to_string(&plate).unwrap().lines().position(|l| l.starts_with("h = ")).unwrap() + 1;
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains(&format!("vibrating_plate.toml:{line}:5: hard-wall reference: wall `plate` moves")), "{t}");
    let pendulum = common::scenario("pendulum");
    let (code, t) = run(&["reference", pendulum.to_str().unwrap(), "--hard-walls", "-o", "r.csv", "-q"], dir.path());
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("pendulum.toml: hard-wall reference: scene `pendulum` has no walls"), "{t}");
}
