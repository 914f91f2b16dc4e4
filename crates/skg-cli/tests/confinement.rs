//! A scene file writes only inside its output directory.
//!
//! Scene files are shared and downloaded, so none of their keys may make the tool open
//! a file elsewhere: Ipopt options that name files are refused at their line, and
//! `[solver] log_file` is confined to the output directory. The cases are the files a
//! log file could overwrite: the scene itself, an earlier run's summary, an earlier
//! run's trajectory while another skg-solve holds that directory's lock.

mod common;

use std::path::Path;

/// `scenarios/tumbler.toml` with `extra` inserted before `[discretization]`, as `name`
/// in `dir`.
fn tumbler_with(dir: &Path, name: &str, extra: &str) -> String {
    let text = std::fs::read_to_string(common::scenario("tumbler")).unwrap();
    assert!(text.contains("\n[discretization]"), "the insertion point exists");
    let text = text.replacen("\n[discretization]", &format!("\n{extra}\n[discretization]"), 1);
    std::fs::write(dir.join(name), text).unwrap();
    name.to_string()
}

/// Line (1-based) of the first line of `file` that contains `needle`.
fn line_of(file: &Path, needle: &str) -> usize {
    let text = std::fs::read_to_string(file).unwrap();
    1 + text.lines().position(|l| l.contains(needle)).unwrap_or_else(|| panic!("{needle} not in {}", file.display()))
}

/// Run, expect exit 1 with a message naming `file:line` and every needle, and no
/// output directory.
fn refused(dir: &Path, scene: &str, out: &str, needle_line: &str, needles: &[&str]) {
    let o = common::skg(&[scene, "-o", out], dir);
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    let at = format!("{scene}:{}:", line_of(&dir.join(scene), needle_line));
    assert!(t.contains(&at), "the message names {at}: {t}");
    for n in needles {
        assert!(t.contains(n), "expected `{n}` in: {t}");
    }
    assert!(!dir.join(out).exists(), "nothing written for a refused scene");
}

#[test]
fn ipopt_options_that_name_files_are_refused_at_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // The scene named itself as Ipopt's output file: it was truncated to 0 bytes.
    let s = tumbler_with(d, "s.toml", "[solver.ipopt]\noutput_file = \"s.toml\"");
    let before = std::fs::read(d.join(&s)).unwrap();
    refused(d, &s, "A", "output_file", &["output_file", "names a file", "log_file"]);
    assert_eq!(std::fs::read(d.join(&s)).unwrap(), before, "the scene file is untouched");
    // Ipopt would read any file as its options.
    let c = tumbler_with(d, "c.toml", "[solver.ipopt]\noption_file_name = \"/etc/passwd\"");
    refused(d, &c, "B", "option_file_name", &["option_file_name", "names a file"]);
    // A library path of a later Ipopt (3.14's hsllib) is a file too.
    let h = tumbler_with(d, "h.toml", "[solver.ipopt]\nhsllib = \"libhsl.so\"");
    refused(d, &h, "C", "hsllib", &["hsllib", "names a file"]);
    // file_print_level names a level, not a file: accepted.
    let ok = tumbler_with(d, "ok.toml", "[solver]\nlog_file = \"ipopt.log\"\n[solver.ipopt]\nfile_print_level = 3");
    let o = common::skg(&[&ok, "-o", "D"], d);
    assert!(o.status.success(), "{}", common::text(&o));
    assert!(d.join("D/ipopt.log").is_file());
}

#[test]
fn an_earlier_runs_files_cannot_be_overwritten_through_the_ipopt_log() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let plain = tumbler_with(d, "plain.toml", "");
    let o = common::skg(&[&plain, "-o", "A"], d);
    assert!(o.status.success(), "{}", common::text(&o));
    let summary = std::fs::read(d.join("A/summary.json")).unwrap();
    let trajectory = std::fs::read(d.join("A/trajectory.csv")).unwrap();
    // output_file into another run's directory emptied its summary.
    let b = tumbler_with(d, "b.toml", "[solver.ipopt]\noutput_file = \"A/summary.json\"");
    refused(d, &b, "B", "output_file", &["output_file"]);
    // log_file up and over into another run's directory replaced its trajectory.
    for (i, name) in
        ["../A/trajectory.csv", "/tmp/skg-confinement-test.log", ".skg-lock", "./ipopt.log", "logs/../ipopt.log", ""].iter().enumerate()
    {
        let scene = tumbler_with(d, &format!("l{i}.toml"), &format!("[solver]\nlog_file = {name:?}"));
        refused(d, &scene, &format!("out{i}/B"), "log_file", &["log_file", "inside the output directory"]);
    }
    assert!(!Path::new("/tmp/skg-confinement-test.log").exists());
    // Nor the run's own files.
    for (i, name) in ["summary.json", "trajectory.csv", "reference.csv"].iter().enumerate() {
        let scene = tumbler_with(d, &format!("r{i}.toml"), &format!("[solver]\nlog_file = {name:?}"));
        refused(d, &scene, &format!("own{i}"), "log_file", &["log_file", "which the solve itself writes"]);
    }
    assert_eq!(std::fs::read(d.join("A/summary.json")).unwrap(), summary, "A's summary untouched");
    assert_eq!(std::fs::read(d.join("A/trajectory.csv")).unwrap(), trajectory, "A's trajectory untouched");
    // A log in a subdirectory of the output directory is fine.
    let sub = tumbler_with(d, "sub.toml", "[solver]\nlog_file = \"logs/ipopt.log\"");
    let o = common::skg(&[&sub, "-o", "E"], d);
    assert!(o.status.success(), "{}", common::text(&o));
    assert!(std::fs::read_to_string(d.join("E/logs/ipopt.log")).unwrap().contains("iter"));
}

/// Commands that solve without an output directory of their own (bench, sweeps) write
/// no Ipopt log at all: before, they handed the scene's `log_file` to Ipopt as is,
/// relative to the current directory.
#[test]
fn solves_without_an_output_directory_write_no_log() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = tumbler_with(d, "s.toml", "[solver]\nlog_file = \"ipopt.log\"");
    let o = common::skg(&["bench", &s, "--nodes", "64"], d);
    assert!(o.status.code().is_some_and(|c| c != 1 && c != 2), "{}", common::text(&o));
    let sweep = common::sweep_file(d, &d.join(&s), "[[grid]]\nnodes = [64]\n");
    let o = common::skg(&["sweep", sweep.to_str().unwrap(), "-o", "sw"], d);
    assert!(o.status.success(), "{}", common::text(&o));
    let stray: Vec<_> = walk(d).into_iter().filter(|p| p.ends_with("ipopt.log")).collect();
    assert!(stray.is_empty(), "no log written: {stray:?}");
}

fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut found = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        if p.is_dir() {
            found.extend(walk(&p));
        } else {
            found.push(p);
        }
    }
    found
}

/// Non-finite Ipopt option values are errors at their line.
#[test]
fn non_finite_ipopt_values_are_refused_at_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (i, (key, value)) in [("tol", "inf"), ("bound_push", "nan"), ("mu_init", "-inf")].iter().enumerate() {
        let s = tumbler_with(d, &format!("n{i}.toml"), &format!("[solver.ipopt]\n{key} = {value}"));
        refused(d, &s, &format!("n{i}"), key, &[key, "finite"]);
    }
}
