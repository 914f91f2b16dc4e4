//! Messages of the commands: each names the file it is about and says what happened in
//! words, never in a library's Debug form; options that cannot take effect are refused
//! rather than ignored.

mod common;

use std::path::Path;
use std::process::Command;

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
/// line of the wall that moves.
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

/// Run the binary with a file-size limit of `kib` KiB and SIGXFSZ ignored, so that a
/// write beyond it fails with EFBIG, as a full disk fails with ENOSPC.
fn run_with_file_limit(args: &[&str], dir: &Path, kib: u32) -> (Option<i32>, String) {
    let script = format!("trap '' XFSZ; ulimit -f {kib}; exec \"$0\" \"$@\"");
    let o = Command::new("sh").arg("-c").arg(script).arg(env!("CARGO_BIN_EXE_skg-solve")).args(args).current_dir(dir).output().unwrap();
    (o.status.code(), common::text(&o))
}

/// A picture that cannot be written (the disk is full, the file too large) says so in
/// the system's words, naming the file, not in the drawing library's Debug form
/// (`GifEncodingError(Io(Os { code: 27, kind: FileTooLarge, … }))`).
#[test]
fn a_picture_that_cannot_be_written_says_why_in_words() {
    let dir = tempfile::tempdir().unwrap();
    let out = solved_tumbler(dir.path(), "tumbler");
    let out = out.to_str().unwrap();
    for (args, file) in [
        (vec!["animate", out, "-o", "a.gif", "-q", "--frames", "40"], "a.gif"),
        (vec!["animate", out, "-o", "a.png", "-q", "--size", "2000x2000"], "a.png"),
        (vec!["plot", "path", out, "-o", "p"], "p."),
    ] {
        let (code, t) = run_with_file_limit(&args, dir.path(), 40);
        assert_eq!(code, Some(1), "{args:?}: {t}");
        assert!(t.contains(&format!("error: drawing {file}")) && t.contains("File too large (os error 27)"), "{args:?}: {t}");
        assert!(!t.contains("Os {") && !t.contains("Error("), "{args:?}: {t}");
    }
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Two shards of a four-point free-fall sweep, in `dir/sh_1` and `dir/sh_2`.
fn two_shards(dir: &Path) -> (std::path::PathBuf, std::path::PathBuf, std::path::PathBuf) {
    let sweep = common::sweep_file(dir, &common::scenario("free_fall"), "[[grid]]\nnodes = [16, 17, 18, 19]\n");
    let shard = |k: usize| {
        let out = dir.join(format!("sh_{k}"));
        let (code, t) = run(&["sweep", s(&sweep), "-o", s(&out), "--shard", &format!("{k}/2"), "-q"], dir);
        assert_eq!(code, Some(0), "{t}");
        out
    };
    let (one, two) = (shard(1), shard(2));
    (sweep, one, two)
}

/// A shard whose last line was cut by a kill: merge leaves the torn row out and says
/// which point is missing and that running the shard again completes it (before: a
/// bare CSV error about field counts).
#[test]
fn merging_a_shard_with_a_cut_last_line_names_the_missing_point() {
    let dir = tempfile::tempdir().unwrap();
    let (sweep, one, two) = two_shards(dir.path());
    let results = two.join("results.csv");
    let text = std::fs::read_to_string(&results).unwrap();
    std::fs::write(&results, &text[..text.len() - 30]).unwrap();
    let merged = dir.path().join("merged");
    let (code, t) = run(&["merge", "-o", s(&merged), s(&one), s(&two)], dir.path());
    assert_ne!(code, Some(0), "{t}");
    assert!(t.contains("missing:") && t.contains("Run the missing shards"), "{t}");
    assert!(!t.contains("CSV error") && !merged.exists(), "{t}");
    // Rerunning the shard repairs it; the merge then succeeds.
    let (code, t) = run(&["sweep", s(&sweep), "-o", s(&two), "--shard", "2/2", "-q"], dir.path());
    assert_eq!(code, Some(0), "{t}");
    let (code, t) = run(&["merge", "-o", s(&merged), s(&one), s(&two)], dir.path());
    assert_eq!(code, Some(0), "{t}");
}

/// `merge -o sh_1 sh_1 sh_2` would replace shard 1's own results.csv and sweep.json with
/// the merge: refused, and shard 1 is left as it was.
#[test]
fn merging_into_one_of_the_inputs_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (_, one, two) = two_shards(dir.path());
    let before = (std::fs::read(one.join("results.csv")).unwrap(), std::fs::read(one.join("sweep.json")).unwrap());
    for output in [s(&one).to_string(), format!("{}/.", s(&one)), format!("{}/../sh_1", s(&two))] {
        let (code, t) = run(&["merge", "-o", &output, s(&one), s(&two)], dir.path());
        assert_eq!(code, Some(1), "{output}: {t}");
        assert!(t.contains("is also an input of the merge"), "{output}: {t}");
    }
    let (code, t) = run(&["merge", "-o", "sh_2", "sh_1", "sh_2/results.csv"], dir.path());
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("is also an input of the merge"), "{t}");
    assert_eq!((std::fs::read(one.join("results.csv")).unwrap(), std::fs::read(one.join("sweep.json")).unwrap()), before);
}

/// The row of a point whose worker was killed (here by the sweep's timeout) still says
/// the point's node count, operator and formulation, also those the point's grid does
/// not name.
#[test]
fn the_row_of_a_timed_out_point_names_its_nodes_operator_and_formulation() {
    let dir = tempfile::tempdir().unwrap();
    // Points of 10⁴ nodes take about a second: far beyond the timeout of 1 ms.
    let sweep = common::sweep_file(dir.path(), &common::scenario("tumbler"), "timeout = 0.001\n[[grid]]\nnodes = [10000, 10001]\n");
    let out = dir.path().join("out");
    let (code, t) = run(&["sweep", s(&sweep), "-o", s(&out), "-q"], dir.path());
    assert_eq!(code, Some(0), "{t}");
    let r = skg_sweep::Results::read(&out).unwrap();
    let col = |name: &str| r.column_index(name).unwrap();
    assert_eq!(r.rows.len(), 2);
    for row in &r.rows {
        assert_eq!(row[col("status")], "timeout", "{row:?}");
        assert!(row[col("nodes")].starts_with("1000"), "{row:?}");
        assert_eq!((row[col("operator")].as_str(), row[col("formulation")].as_str()), ("SBP242", "reduced"), "{row:?}");
    }
}

/// An animation or strip beyond its bounds is refused at once, before the solution is
/// read, with the bound: `--frames 1000000` would run for hours, its file growing by
/// megabytes a second, and `--strip 100000` would overflow the picture's width.
#[test]
fn animations_and_strips_beyond_their_bounds_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let out = solved_tumbler(dir.path(), "tumbler");
    let out = out.to_str().unwrap();
    for (args, expect) in [
        (vec!["--frames", "1000000"], "1000000 frames are more than the 10000 an animation may have"),
        (vec!["--frames", "10000", "--size", "4096x4096"], "more than the 4000000000 an animation may have"),
        (vec!["--frames", "0"], "at least 1"),
        (vec!["-o", "s.png", "--strip", "100000"], "a strip of 100000 frames is more than the 100"),
        (vec!["-o", "s.png", "--strip", "50", "--size", "4096x4096"], "more than the 100000000 a strip may have"),
    ] {
        let mut all = vec!["animate", out, "-q"];
        if !args.contains(&"-o") {
            all.extend(["-o", "a.gif"]);
        }
        all.extend(&args);
        let started = std::time::Instant::now();
        let (code, t) = run(&all, dir.path());
        assert_eq!(code, Some(2), "{args:?}: {t}");
        assert!(t.contains(expect), "{args:?}: {t}");
        // A watchdog, not a timing: each refusal takes well under a second; producing the
        // frames first would take minutes to hours.
        assert!(started.elapsed().as_secs() < 60, "{args:?} took {:?}", started.elapsed());
    }
    assert!(!dir.path().join("a.gif").exists() && !dir.path().join("s.png").exists());
}

/// An option the output's format does not use is refused, not ignored: `--strip 10`
/// with a .gif, or `--frames 50` with a .png strip.
#[test]
fn animate_options_the_format_does_not_use_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = solved_tumbler(dir.path(), "tumbler");
    for (args, expect) in [
        (vec!["-o", "a.gif", "--strip", "10"], "--strip applies to a .png strip"),
        (vec!["-o", "a.mp4", "--strip", "10"], "--strip applies to a .png strip"),
        (vec!["-o", "s.png", "--frames", "50"], "--frames and --fps apply to a .gif or .mp4"),
        (vec!["-o", "s.png", "--fps", "10"], "--frames and --fps apply to a .gif or .mp4"),
    ] {
        let mut all = vec!["animate", s(&out), "-q"];
        all.extend(&args);
        let (code, t) = run(&all, dir.path());
        assert_eq!(code, Some(2), "{args:?}: {t}");
        assert!(t.contains(expect), "{args:?}: {t}");
    }
    let (code, t) = run(&["animate", s(&out), "-q", "-o", "s.png", "--strip", "3", "--size", "100x100"], dir.path());
    assert_eq!(code, Some(0), "{t}");
}

/// More `--label`s than inputs: the extra ones would label nothing, so the command is
/// refused as a usage error rather than ignored.
#[test]
fn more_labels_than_inputs_is_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = solved_tumbler(dir.path(), "tumbler");
    let (code, t) = run(&["plot", "trajectory", s(&out), "--label", "a", "--label", "b", "-o", "p"], dir.path());
    assert_eq!(code, Some(2), "{t}");
    assert!(t.contains("2 --label given for 1 input(s)") && t.contains("\"b\""), "{t}");
    assert!(!dir.path().join("p.svg").exists());
    let (code, t) = run(&["plot", "trajectory", s(&out), "--label", "a", "-o", "p"], dir.path());
    assert_eq!(code, Some(0), "{t}");
}

/// `bench --repeat 0` is a usage error (there is no fastest of no repetitions).
#[test]
fn bench_with_zero_repetitions_is_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::scenario("free_fall");
    let (code, t) = run(&["bench", s(&scene), "--nodes", "64", "--repeat", "0"], dir.path());
    assert_eq!(code, Some(2), "{t}");
    assert!(t.contains("--repeat") && t.contains("0"), "{t}");
}

/// The readers of a solution (check, plot path, plot trajectory, animate) keep the
/// pairing rule: a summary.json that does not list trajectory.csv, or lists a
/// reference.csv that is gone, is refused with a message naming both files (before the
/// fix both were read); a trajectory with no summary at all is read, with a warning that
/// it cannot be checked against a run.
#[test]
fn readers_refuse_what_the_pairing_rule_refuses_and_warn_about_a_lone_trajectory() {
    let dir = tempfile::tempdir().unwrap();
    let reference = common::root().join("references/tumbler.csv");
    let readers = |out: &Path| -> Vec<Vec<String>> {
        let sol = s(&out.join("trajectory.csv")).to_string();
        let scene = s(&common::scenario("tumbler")).to_string();
        [
            vec!["check", &sol, s(&reference), "--json", "c.json", "-q"],
            vec!["plot", "trajectory", &sol, "-o", "pt"],
            vec!["plot", "path", &sol, "-o", "pp", "--scene", &scene],
            vec!["animate", &sol, "-o", "a.gif", "--frames", "3", "-q", "--scene", &scene],
        ]
        .into_iter()
        .map(|a| a.into_iter().map(String::from).collect())
        .collect()
    };
    let run_all = |sol: &Path| -> Vec<(Option<i32>, String)> {
        readers(sol).iter().map(|a| run(&a.iter().map(String::as_str).collect::<Vec<_>>(), dir.path())).collect()
    };
    // A summary that does not list trajectory.csv.
    let out = solved_tumbler(dir.path(), "unlisted");
    let summary = out.join("summary.json");
    let mut json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&summary).unwrap()).unwrap();
    json["files"].as_object_mut().unwrap().remove("trajectory.csv");
    std::fs::write(&summary, json.to_string()).unwrap();
    for (code, t) in run_all(&out) {
        assert_eq!(code, Some(1), "{t}");
        assert!(
            t.contains(&format!("{}: the {} beside it does not list trajectory.csv", s(&out.join("trajectory.csv")), s(&summary))),
            "{t}"
        );
    }
    // A reference.csv listed in the summary but deleted.
    let out = solved_tumbler(dir.path(), "deleted");
    std::fs::remove_file(out.join("reference.csv")).unwrap();
    for (code, t) in run_all(&out) {
        assert_eq!(code, Some(1), "{t}");
        assert!(t.contains(&format!("lists {}, which is missing", s(&out.join("reference.csv")))) && t.contains("summary.json"), "{t}");
    }
    // A trajectory with no summary: read, with a warning.
    let out = solved_tumbler(dir.path(), "lone");
    std::fs::remove_file(out.join("summary.json")).unwrap();
    std::fs::remove_file(out.join("reference.csv")).unwrap();
    for (code, t) in run_all(&out) {
        assert_eq!(code, Some(0), "{t}");
        assert!(t.contains("warning: ") && t.contains("has no summary.json beside it") && t.contains("cannot be checked against"), "{t}");
    }
}

/// A sweep of 10⁶ points is refused at once, counted from its grid before any point's
/// scene is resolved (resolving them all takes 30 s and more).
#[test]
fn a_sweep_of_a_million_points_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let values = |n: usize, from: f64| (0..n).map(|k| format!("{}", from + k as f64 / n as f64)).collect::<Vec<_>>().join(", ");
    let body =
        format!("[[grid]]\nnodes = [16, 17, 18, 19, 20, 21, 22, 23, 24, 25]\ng = [{}]\nm = [{}]\n", values(1000, 9.0), values(100, 1.0));
    let sweep = common::sweep_file(dir.path(), &common::scenario("free_fall"), &body);
    let started = std::time::Instant::now();
    let (code, t) = run(&["sweep", s(&sweep), "-o", "out"], dir.path());
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("1000000 points as listed") && t.contains("--yes"), "{t}");
    // A watchdog, not a timing: the refusal takes well under a second; planning the
    // million points first would take minutes.
    assert!(started.elapsed().as_secs_f64() < 60.0, "took {:?}", started.elapsed());
    // A shard is counted as the shard: 10⁶/300 points need no confirmation, 10⁶/50 do.
    let (code, t) = run(&["sweep", s(&sweep), "-o", "out", "--shard", "7/50"], dir.path());
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("20000 points in shard 7/50 of 1000000 as listed"), "{t}");
    assert!(!dir.path().join("out").exists());
}

/// `scenarios/free_fall.toml` with `extra` inserted before its `[verify]` table, as
/// `dir/name`; the 1-based line of the first inserted line.
fn free_fall_with(dir: &Path, name: &str, extra: &str) -> (std::path::PathBuf, usize) {
    let text = std::fs::read_to_string(common::scenario("free_fall")).unwrap();
    let line = text.lines().position(|l| l == "[verify]").unwrap() + 1;
    let path = dir.join(name);
    std::fs::write(&path, text.replacen("\n[verify]", &format!("\n{extra}\n\n[verify]"), 1)).unwrap();
    (path, line)
}

/// Small message fixes of the third hostile-input round, each at the line of the key it
/// is about and before any work: `max_iter` beyond Ipopt's `int`; `log_file` names
/// that only failed after the solve (naming a temporary file); `--refine --no-verify`;
/// clap's tip for a negative number; `-o` at a link; an expression echoed whole; serde's
/// "did not match any variant of untagged enum" in a sweep file.
#[test]
fn hostile_settings_are_refused_at_their_line_in_words() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // max_iter beyond i32 (Ipopt's wrapper refused it without a line, Newton took it).
    for backend in ["ipopt", "newton"] {
        let (scene, line) = free_fall_with(d, "m.toml", &format!("[solver]\nbackend = \"{backend}\"\nmax_iter = 2147483648"));
        let (code, t) = run(&[s(&scene), "-o", "m"], d);
        assert_eq!(code, Some(1), "{t}");
        assert!(t.contains(&format!("m.toml:{}:", line + 2)) && t.contains("from 0 to 2147483647"), "{t}");
        assert!(!d.join("m").exists(), "{t}");
    }
    let (code, t) = run(&[s(&common::scenario("free_fall")), "--max-iter", "2147483648"], d);
    assert_eq!(code, Some(2), "{t}");
    // log_file names that pass a check of components but not the file system.
    let long = "x".repeat(300);
    for name in ["a/.", "summary.json/x", "a//b", long.as_str()] {
        let (scene, line) = free_fall_with(d, "l.toml", &format!("[solver]\nlog_file = \"{name}\""));
        let (code, t) = run(&[s(&scene), "-o", "l"], d);
        assert_eq!(code, Some(1), "{name}: {t}");
        assert!(t.contains(&format!("l.toml:{}:", line + 1)) && t.contains("solver.log_file"), "{name}: {t}");
        assert!(!t.contains(".skg-tmp") && t.len() < 1000, "{name}: {t}");
        assert!(!d.join("l/summary.json").exists(), "{name}: refused before the solve");
    }
    // --refine with --no-verify contradict each other.
    let (code, t) = run(&[s(&common::scenario("free_fall")), "--refine", "--no-verify", "-o", "r"], d);
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("--refine with --no-verify") && !d.join("r").exists(), "{t}");
    // A negative number is a value, not an option: no tip to write `-- -1`.
    for option in ["--max-nodes", "--nodes", "--max-iter", "--time-limit"] {
        let (code, t) = run(&[s(&common::scenario("free_fall")), option, "-1"], d);
        assert_eq!(code, Some(2), "{option}: {t}");
        assert!(t.contains("'-1'") && !t.contains("-- -1") && !t.contains("unexpected argument"), "{option}: {t}");
    }
    // -o at a link to nothing says so, not "File exists".
    std::os::unix::fs::symlink(d.join("nowhere"), d.join("link")).unwrap();
    let (code, t) = run(&[s(&common::scenario("free_fall")), "-o", "link"], d);
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("symbolic link to") && t.contains("does not exist") && !t.contains("File exists"), "{t}");
    // A 400 kB expression with an unknown name is quoted around the error only.
    let huge = format!("1/2*m*x_dot^2 - m*g*x{}", " + 0*x".repeat(70_000) + " + q");
    let (scene, _) = free_fall_with(d, "e.toml", "");
    let text = std::fs::read_to_string(&scene).unwrap().replace("\"1/2*m*x_dot^2 - m*g*x\"", &format!("\"{huge}\""));
    std::fs::write(&scene, text).unwrap();
    let (code, t) = run(&[s(&scene), "-o", "e"], d);
    assert_eq!(code, Some(1), "{t:.2000}");
    assert!(t.contains("unknown symbol `q`") && t.len() < 2000, "{} bytes: {t:.2000}", t.len());
    // A note about a key says where the key is.
    let scene = common::variant(d, "free_fall", "w.toml", &[("nodes = 32", "nodes = 32\nwindow = 30")]);
    let (code, t) = run(&[s(&scene), "-o", "w"], d);
    assert_eq!(code, Some(0), "{t}");
    let line = std::fs::read_to_string(&scene).unwrap().lines().position(|l| l == "window = 30").unwrap() + 1;
    assert!(t.contains(&format!("note: {}:{line}:10: time.window = 30 s is not shorter", s(&scene))), "{t}");
    // A grid axis of the wrong shape says what an axis is.
    let sweep = common::sweep_file(d, &common::scenario("free_fall"), "[[grid]]\nnodes = [[16], 32]\n");
    let (code, t) = run(&["sweep", s(&sweep), "-o", "sw"], d);
    assert_eq!(code, Some(1), "{t}");
    assert!(t.contains("sweep.toml:4:") && t.contains("a grid axis is a value") && !t.contains("untagged enum"), "{t}");
}

/// `--quiet` prints only errors and warnings: a verified solve whose refinement chose
/// the natural initial-velocity condition says so in a note without it, and prints
/// nothing with it.
#[test]
fn a_quiet_verified_solve_prints_no_notes() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::test_scene("stiff/overdamped_1e5");
    let args = [s(&scene), "--refine", "--operator", "auto", "-o", "out"];
    let (code, t) = run(&args, dir.path());
    assert_eq!(code, Some(0), "{t}");
    assert!(t.contains("note: the initial velocity is imposed by the natural condition"), "{t}");
    let (code, t) = run(&[&args[..], &["-q"]].concat(), dir.path());
    assert_eq!(code, Some(0), "{t}");
    assert_eq!(t, "", "printed with --quiet");
}
