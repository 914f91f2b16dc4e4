//! Exit statuses of a solve: 0 only for a verified trajectory, 4 for a converged one that
//! failed verification, 3 for one that did not converge, 1 for an input error, 2 for a
//! usage error, on scenes written for the tests (crates/skg-core/tests/scenes; what the
//! solves find there is tested in crates/skg-core/tests/trust.rs).

mod common;

use std::path::Path;

#[test]
fn non_finite_numbers_at_the_start_are_an_input_error_naming_the_expression() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::test_scene("nan_at_start");
    let o = common::skg(&[scene.to_str().unwrap(), "-o", "out"], dir.path());
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("nan_at_start.toml:4:") && t.contains("not finite at the initial state") && t.contains("x = -1"), "{t}");
}

#[test]
fn exit_status_says_converged_and_verified() {
    let dir = tempfile::tempdir().unwrap();
    let damped = common::test_scene("damped_oscillator");
    let damped = damped.to_str().unwrap();
    let run = |args: &[&str]| common::skg(args, dir.path());

    let o = run(&[damped, "-o", "plain", "--no-fallback"]);
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(4), "{t}");
    assert!(t.contains("verification failed") && t.contains("remedy:") && t.contains("--window"), "{t}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("plain/summary.json")).unwrap()).unwrap();
    assert_eq!(summary["verification"]["status"], "failed");
    assert!(dir.path().join("plain/reference.csv").is_file());

    let o = run(&[damped, "-o", "cured"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::text(&o));
    let o = run(&[damped, "-o", "cured2", "--window", "1.25"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::text(&o));
    assert!(common::text(&o).contains("windows of 1.2"), "{}", common::text(&o));
    let o = run(&[damped, "-o", "unchecked", "--no-fallback", "--no-verify"]);
    assert_eq!(o.status.code(), Some(0), "{}", common::text(&o));
    assert!(!dir.path().join("unchecked/reference.csv").exists());

    let tumbler = common::scenario("tumbler");
    let o = run(&[tumbler.to_str().unwrap(), "-o", "short", "--max-iter", "0", "--no-fallback"]);
    assert_eq!(o.status.code(), Some(3), "{}", common::text(&o));
    // An option value out of range is a usage error.
    let o = run(&[damped, "-o", "x", "--verify-tol", "0"]);
    assert_eq!(o.status.code(), Some(2), "{}", common::text(&o));
    assert!(Path::new(dir.path()).join("short/summary.json").is_file());
}

/// A wall thinner than a step (crates/skg-core/tests/scenes/thin_wall.toml): the grid
/// cannot resolve it, the verification's reference bounces off it
/// (crates/skg-core/tests/trust.rs), so the solve exits 4.
#[test]
fn a_wall_thinner_than_a_step_exits_4() {
    let out = tempfile::tempdir().unwrap();
    let path = common::test_scene("thin_wall");
    let run = common::skg(&[path.to_str().unwrap(), "-o", out.path().to_str().unwrap()], Path::new("."));
    assert_eq!(run.status.code(), Some(4), "{}", common::text(&run));
}
