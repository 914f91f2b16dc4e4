//! The `reference` and `check` command lines: the checked-in reference CSVs against a
//! fresh regeneration by the command of `ci/regenerate-references.sh`, and the exit
//! statuses and messages of `check` and `reference`. (The references' physics, against
//! closed forms, is tested in crates/skg-core/tests/reference.rs.)

mod common;

use skg_core::check::Table;

fn checked_in(file: &str) -> Table {
    Table::read(&common::root().join("references").join(file)).unwrap()
}

/// The checked-in files cannot silently rot: regenerating two of them with the command
/// of `ci/regenerate-references.sh` gives the same provenance and the same numbers.
#[test]
fn regenerated_references_match_the_checked_in_files() {
    let dir = tempfile::tempdir().unwrap();
    for (scene, file, hard) in [("rolling_disk", "rolling_disk.csv", false), ("tumbler", "tumbler.hard.csv", true)] {
        let out = dir.path().join(file);
        let out_s = out.display().to_string();
        let scene_path = format!("scenarios/{scene}.toml");
        let mut args = vec!["reference", scene_path.as_str(), "-o", out_s.as_str(), "--rtol", "1e-12", "--quiet"];
        if hard {
            args.push("--hard-walls");
        }
        let o = common::skg(&args, &common::root());
        assert!(o.status.success(), "{}", common::text(&o));
        let fresh = Table::read(&out).unwrap();
        let old = checked_in(file);
        // The tool's version is provenance, not content: a new release with the same
        // numbers does not need new files. Nor are the reference's own diagnostics (its
        // constraint and energy drift, at the rounding level) compared digit by digit:
        // another processor or another order of the same sums changes their last digits.
        let unversioned = |t: &Table| -> Vec<String> {
            t.comments.iter().map(|c| without_diagnostics(c.split_once(" reference (").map_or(c.as_str(), |(_, rest)| rest))).collect()
        };
        assert_eq!(unversioned(&fresh), unversioned(&old), "{file}: provenance changed; run ci/regenerate-references.sh");
        for (name, value) in fresh.comments.iter().flat_map(|c| diagnostics(c)) {
            assert!(value <= 1e-9, "{file}: the regenerated reference's {name} is {value:e}");
        }
        assert_eq!(fresh.columns, old.columns);
        assert_eq!(fresh.rows.len(), old.rows.len());
        // Within 1e-9, not to the last bit: the files were made on another machine, and
        // another libm (glibc picks FMA variants of sin and cos by processor) can move
        // one of the integrator's step-size decisions, which moves the numbers by about
        // the integration's own error (rtol 1e-12 per step). A change of the equations,
        // the method or its tolerance moves them by far more.
        for (a, b) in fresh.rows.iter().zip(&old.rows) {
            for (x, y) in a.iter().zip(b) {
                assert!((x - y).abs() <= 1e-9 * x.abs().max(1.0), "{file}: {x} vs {y}; run ci/regenerate-references.sh");
            }
        }
    }
}

#[test]
fn check_command_exit_codes_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let m = common::root();
    let disk = m.join("scenarios/rolling_disk.toml").display().to_string();
    let o = common::skg(&[&disk, "-o", "run", "-q"], d);
    assert!(o.status.success(), "{}", common::text(&o));
    let reference = m.join("references/rolling_disk.csv").display().to_string();
    // Within tolerance: exit 0, JSON written next to the solution.
    let o = common::skg(&["check", "run/trajectory.csv", &reference, "--skip-last", "2", "--columns", "x,y,theta,phi", "--tol", "0.02"], d);
    assert_eq!(o.status.code(), Some(0), "{}", common::text(&o));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("run/trajectory.check.json")).unwrap()).unwrap();
    assert_eq!(json["passed"], true);
    let max = json["comparison"]["max_abs"].as_f64().unwrap();
    // The solver's own test pins this at 0.0152 (docs/errata.md, erratum 4); the reference agrees.
    assert!((max - 0.0152).abs() < 0.001, "{max}");
    // Exceeded: exit 4 (2 is clap's usage error), the column is named.
    let o = common::skg(
        &["check", "run/trajectory.csv", &reference, "--skip-last", "2", "--tol", "1e-3", "--tol-column", "phi=1e-12", "--json", "c.json"],
        d,
    );
    assert_eq!(o.status.code(), Some(4), "{}", common::text(&o));
    assert!(common::text(&o).contains("tolerance exceeded: x"), "{}", common::text(&o));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.join("c.json")).unwrap()).unwrap();
    assert_eq!(json["passed"], false);
    // Bad input: exit 1, a clear message, never a panic.
    let tumbler_ref = m.join("references/tumbler.csv").display().to_string();
    std::fs::write(d.join("bad.csv"), "t,x\n0,1\n0.5,2\n0.25,3\n").unwrap();
    for (args, needle) in [
        (vec!["check", "missing.csv", reference.as_str()], "missing.csv"),
        (vec!["check", "run/trajectory.csv", tumbler_ref.as_str()], "outside the reference's time range"),
        (vec!["check", "bad.csv", reference.as_str()], "bad.csv:4: times must increase strictly"),
        (vec!["check", "run/trajectory.csv", reference.as_str(), "--columns", "nope"], "`nope` is not in the solution"),
        (vec!["check", "run/trajectory.csv", reference.as_str(), "--tol-column", "x"], "expected COLUMN=TOL"),
    ] {
        let o = common::skg(&args, d);
        let t = common::text(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {t}");
        assert!(t.contains(needle) && !t.contains("panicked"), "{args:?}: {t}");
    }
}

#[test]
fn reference_command_samples_a_given_grid() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let m = common::root();
    let scene = m.join("scenarios/free_fall.toml").display().to_string();
    std::fs::write(d.join("grid.csv"), "# my grid\nt,x\n0,0\n0.3,0\n1.7,0\n2,0\n").unwrap();
    let o = common::skg(&["reference", &scene, "--grid-from", "grid.csv", "-o", "r.csv"], d);
    assert!(o.status.success(), "{}", common::text(&o));
    let t = Table::read(&d.join("r.csv")).unwrap();
    assert_eq!(t.times(), vec![0.0, 0.3, 1.7, 2.0]);
    assert!(t.comments[0].contains("4 samples"));
    let o = common::skg(&["reference", &scene, "--hard-walls", "-o", "h.csv"], d);
    assert_eq!(o.status.code(), Some(1));
    assert!(common::text(&o).contains("no walls"), "{}", common::text(&o));
    assert!(!d.join("h.csv").exists());
    let o = common::skg(&["reference", "nope.toml"], d);
    assert_eq!(o.status.code(), Some(1));
    assert!(common::text(&o).contains("nope.toml"));
}

/// The diagnostics a reference's provenance ends with, as `(name, value)`: `max |g|` and
/// `max |E - E0|`.
fn diagnostics(comment: &str) -> Vec<(&'static str, f64)> {
    ["max |g| ", "max |E - E0| "]
        .into_iter()
        .filter_map(|name| {
            let rest = &comment[comment.find(name)? + name.len()..];
            let number = rest.split([',', ' ', ';']).next()?;
            Some((name.trim_end(), number.parse().ok()?))
        })
        .collect()
}

/// A provenance line with the values of its [`diagnostics`] left out.
fn without_diagnostics(comment: &str) -> String {
    let mut out = comment.to_string();
    for (name, _) in diagnostics(comment) {
        let start = out.find(name).expect("found by diagnostics") + name.len() + 1;
        let end = out[start..].find([',', ' ', ';']).map_or(out.len(), |e| start + e);
        out.replace_range(start..end, "…");
    }
    out
}
