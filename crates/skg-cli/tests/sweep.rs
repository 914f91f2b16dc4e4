//! Sweeps from the command line: clear errors on bad sweep files, sharding and merge,
//! resume after a killed run, the results' columns, and the `tune` command. (The
//! expansion of a sweep file is tested in crates/skg-sweep/tests/grid.rs, the choice of
//! σ in crates/skg-core/tests/tune.rs.)

mod common;

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use skg_sweep::{PointStatus, Results, Shard, SweepFile};

/// Write a sweep file into `dir` whose base scene is the shipped `scene`.
fn sweep_file(dir: &Path, scene: &str, body: &str) -> PathBuf {
    common::sweep_file(dir, &common::scenario(scene), body)
}

#[test]
fn bad_sweep_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&str, &[&str])] = &[
        ("[[grid]]\nnodes = [64]\nbogus = 1\n", &["`bogus`", "sigma", "sweep.toml:5:1"]),
        ("colour = 1\n[[grid]]\nnodes = [64]\n", &["sweep.toml:3:1", "colour"]),
        ("[[grid]]\noperator = [\"SBP999\"]\n", &["SBP999"]),
        ("[[grid]]\nnodes = [1]\n", &["nodes"]),
        ("[[grid]]\nsigma = [\"1/\"]\n", &["sigma"]),
        ("[grid]\nnodes = [64]\n", &["[[grid]]", "must be an array, got [grid] …"]),
        ("", &["no points"]),
        ("[peer]\ntolerances = [2.0]\n", &["tolerances", "sweep.toml:4:1"]),
        ("timeout = -1\n[[grid]]\nnodes = [64]\n", &["sweep.toml:3:11", "timeout"]),
        ("artifact_tol = 0\n[[grid]]\nnodes = [64]\n", &["sweep.toml:3:16", "artifact_tol"]),
    ];
    for (body, needles) in cases {
        let p = sweep_file(dir.path(), "tumbler", body);
        let err = SweepFile::load(&p).and_then(|f| f.expand()).unwrap_err().to_string();
        for n in *needles {
            assert!(err.contains(n), "expected `{n}` in the error for\n{body}\ngot: {err}");
        }
        // The CLI reports it with exit status 1 and no panic.
        let o = common::skg(&["sweep", p.to_str().unwrap(), "-o", dir.path().join("out").to_str().unwrap()], Path::new("."));
        assert_eq!(o.status.code(), Some(1), "{}", common::text(&o));
        assert!(!common::text(&o).contains("panicked"), "{}", common::text(&o));
    }
    // A missing base scene names the sweep file's line.
    let p = dir.path().join("missing.toml");
    std::fs::write(&p, "[sweep]\nscene = \"nope.toml\"\n[[grid]]\nnodes = [64]\n").unwrap();
    let err = SweepFile::load(&p).unwrap().expand().unwrap_err().to_string();
    assert!(err.contains("missing.toml:2:9") && err.contains("nope.toml"), "{err}");
}

#[test]
fn shards_partition_the_grid_and_merge_joins_them() {
    let dir = tempfile::tempdir().unwrap();
    let p = sweep_file(
        dir.path(),
        "free_fall",
        "[[grid]]\nnodes = [16, 20, 24, 28, 32]\noperator = [\"SBP121\", \"SBP242\"]\n[peer]\ntolerances = [1e-6]\n",
    );
    let f = SweepFile::load(&p).unwrap();
    let all = f.expand().unwrap().points;
    assert_eq!(all.len(), 11);
    for n in 1..=4 {
        let mut seen = HashSet::new();
        for k in 1..=n {
            let s: Shard = format!("{k}/{n}").parse().unwrap();
            for pt in all.iter().filter(|pt| s.contains(pt.index)) {
                assert!(seen.insert(pt.id()), "point {} in two shards of {n}", pt.index);
            }
        }
        assert_eq!(seen.len(), all.len(), "the shards of {n} cover the grid");
    }
    // Run two shards through the CLI and merge them.
    let mut dirs = Vec::new();
    for k in 1..=2 {
        let d = dir.path().join(format!("shard{k}"));
        let o = common::skg(
            &["sweep", p.to_str().unwrap(), "-o", d.to_str().unwrap(), "--shard", &format!("{k}/2"), "-j", "2"],
            Path::new("."),
        );
        assert!(o.status.success(), "{}", common::text(&o));
        let (_, ids) = common::rows_by_id(&d);
        assert_eq!(ids.len(), if k == 1 { 6 } else { 5 });
        dirs.push(d);
    }
    let merged = dir.path().join("merged");
    let mut args = vec!["merge", "-o", merged.to_str().unwrap()];
    args.extend(dirs.iter().map(|d| d.to_str().unwrap()));
    let o = common::skg(&args, Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    assert!(common::text(&o).contains("every point of the sweep (11) is present"), "{}", common::text(&o));
    let (r, ids) = common::rows_by_id(&merged);
    assert_eq!(ids.len(), all.len());
    assert!(ids.values().all(|&c| c == 1));
    let idx = r.column_index("index").unwrap();
    let order: Vec<usize> = r.rows.iter().map(|row| row[idx].parse().unwrap()).collect();
    assert_eq!(order, (0..all.len()).collect::<Vec<_>>(), "merged rows are in point order");
    // Free fall is exact on SBP242; the peer row is the time-stepping integrator.
    let (conv, m) = (r.column_index("converged").unwrap(), r.column_index("method").unwrap());
    assert!(r.rows.iter().all(|row| row[conv] == "true"));
    assert_eq!(r.rows.iter().filter(|row| row[m] == "ode").count(), 1);
    // A shard whose driver was killed while writing its last row: the partial line is
    // no row, even when cut inside its last field (as many fields as a whole row).
    let text = std::fs::read_to_string(dirs[1].join("results.csv")).unwrap();
    let last = text[..text.len() - 1].rfind('\n').unwrap() + 1;
    let torn = format!("{}{}", &text[..last], &text[last..text.len() - 3]);
    std::fs::write(dirs[1].join("results.csv"), torn).unwrap();
    let o = common::skg(
        &["merge", "--partial", "-o", merged.to_str().unwrap(), dirs[0].to_str().unwrap(), dirs[1].to_str().unwrap()],
        Path::new("."),
    );
    assert!(o.status.success(), "{}", common::text(&o));
    assert!(common::text(&o).contains("1 of the sweep's 11 points are missing"), "{}", common::text(&o));
    assert_eq!(common::rows_by_id(&merged).1.len(), 10);
    // Merging shards of different sweeps is refused.
    let other = sweep_file(dir.path(), "tumbler", "[[grid]]\nsigma = [\"1/80\"]\nnodes = [64]\n");
    let d3 = dir.path().join("other");
    assert!(common::skg(&["sweep", other.to_str().unwrap(), "-o", d3.to_str().unwrap(), "-q"], Path::new(".")).status.success());
    let o = common::skg(
        &["merge", "-o", dir.path().join("bad").to_str().unwrap(), dirs[0].to_str().unwrap(), d3.to_str().unwrap()],
        Path::new("."),
    );
    assert_eq!(o.status.code(), Some(1), "{}", common::text(&o));
    assert!(common::text(&o).contains("not shards of one sweep"), "{}", common::text(&o));
}

/// Start `skg-solve sweep SWEEP -o OUT -j 1 -q` in the background.
fn start_sweep(sweep: &Path, out: &Path) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_skg-solve"))
        .args(["sweep", sweep.to_str().unwrap(), "-o", out.to_str().unwrap(), "-j", "1", "-q"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap()
}

#[test]
fn killed_sweep_resumes_without_lost_or_duplicated_rows() {
    let dir = tempfile::tempdir().unwrap();
    let p = sweep_file(
        dir.path(),
        "tumbler",
        "[[grid]]\noperator = [\"SBP242\", \"SBP363\"]\nsigma = [\"1/60\", \"1/80\", \"1/110\"]\nnodes = [128, 160, 192, 224, 256]\n",
    );
    let total = SweepFile::load(&p).unwrap().expand().unwrap().points.len();
    assert_eq!(total, 30);
    let out = dir.path().join("out");
    let results = out.join("results.csv");
    let mut child = start_sweep(&p, &out);
    let start = Instant::now();
    let rows = |path: &Path| std::fs::read_to_string(path).map_or(0, |t| t.lines().count().saturating_sub(1));
    while rows(&results) < 4 {
        assert!(start.elapsed() < Duration::from_secs(60), "no rows appeared");
        assert!(child.try_wait().unwrap().is_none(), "the sweep finished before it could be killed");
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let before = rows(&results);
    assert!(before < total, "killed part-way ({before} of {total} rows)");
    // Simulate a kill in the middle of a write: a trailing partial line.
    let mut f = std::fs::OpenOptions::new().append(true).open(&results).unwrap();
    std::io::Write::write_all(&mut f, b"0123456789abcdef,3,skg,,12").unwrap();
    drop(f);
    let o = common::skg(&["sweep", p.to_str().unwrap(), "-o", out.to_str().unwrap(), "-j", "2"], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    let t = common::text(&o);
    assert!(t.contains(&format!("{before} already done")), "{t}");
    let (r, ids) = common::rows_by_id(&out);
    assert_eq!(r.rows.len(), total, "one row per point");
    assert_eq!(ids.len(), total);
    assert!(ids.values().all(|&c| c == 1), "no duplicated rows");
    let expected: HashSet<String> = SweepFile::load(&p).unwrap().expand().unwrap().points.iter().map(|p| p.id()).collect();
    assert_eq!(ids.keys().cloned().collect::<HashSet<_>>(), expected);
    // A third run has nothing to do.
    let o = common::skg(&["sweep", p.to_str().unwrap(), "-o", out.to_str().unwrap()], Path::new("."));
    assert!(common::text(&o).contains(&format!("{total} already done, 0 run")), "{}", common::text(&o));
    assert!(!out.join(".work").exists(), "worker files are cleaned up");
}

#[test]
fn failed_points_are_recorded_and_the_sweep_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    // max_iter = 0 cannot converge the tumbler; the other point does.
    let p = sweep_file(dir.path(), "tumbler", "[[grid]]\nnodes = [256]\nmax_iter = [0, 100]\n");
    let out = dir.path().join("out");
    let o = common::skg(&["sweep", p.to_str().unwrap(), "-o", out.to_str().unwrap()], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    assert!(common::text(&o).contains("(1 failed)"), "{}", common::text(&o));
    let r = Results::read(&out).unwrap();
    let (c, s, ss) = (r.column_index("converged").unwrap(), r.column_index("status").unwrap(), r.column_index("solver_status").unwrap());
    let mut states: Vec<(&str, &str, &str)> = r.rows.iter().map(|row| (row[c].as_str(), row[s].as_str(), row[ss].as_str())).collect();
    states.sort();
    assert_eq!(states[0], ("false", "not_converged", "Maximum_Iterations_Exceeded"));
    assert_eq!(states[1], ("true", "converged", "Solve_Succeeded"));
    assert_eq!(r.status(&r.rows[0]).unwrap().is_converged(), r.rows[0][c] == "true");
}

/// Run `skg-solve sweep SWEEP -o OUT` with `extra` arguments, which must succeed; its
/// results.
fn run_sweep(sweep: &Path, out: &Path, extra: &[&str]) -> Results {
    let args = [&["sweep", sweep.to_str().unwrap(), "-o", out.to_str().unwrap()], extra].concat();
    let o = common::skg(&args, Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    Results::read(out).unwrap()
}

/// `sha256:<hex>` of a file's bytes, computed here with the `sha2` crate.
fn sha256_of(path: &Path) -> String {
    use sha2::{Digest, Sha256};
    let hex: String = Sha256::digest(std::fs::read(path).unwrap()).iter().map(|b| format!("{b:02x}")).collect();
    format!("sha256:{hex}")
}

/// The cells of column `name` in every row.
fn column<'a>(r: &'a Results, name: &str) -> Vec<&'a str> {
    let i = r.column_index(name).unwrap_or_else(|| panic!("no column {name} in {:?}", r.header));
    r.rows.iter().map(|row| row[i].as_str()).collect()
}

#[test]
fn results_hold_axis_numbers_expressions_and_provenance() {
    let dir = tempfile::tempdir().unwrap();
    // A copy of the tumbler (R = 1), so that its content can change below.
    let scene = dir.path().join("tumbler.toml");
    std::fs::copy(common::scenario("tumbler"), &scene).unwrap();
    let p = common::sweep_file(dir.path(), &scene, "[[grid]]\nnodes = 128\nsigma = [\"1/110\", 0.005, \"R/100\"]\nV0 = [10, 12]\n");
    let out = dir.path().join("out");
    let o = common::skg(&["sweep", p.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    let r = Results::read(&out).unwrap();
    assert_eq!(r.rows.len(), 6);
    // The expressions' column follows its axis; an axis of plain numbers has none.
    let sigma = r.column_index("sigma").unwrap();
    assert_eq!(r.header[sigma + 1], "sigma_expr");
    assert!(r.column_index("V0").is_some() && r.column_index("V0_expr").is_none(), "{:?}", r.header);
    // Each sigma cell is the double the expression denotes (R = 1 in the scene).
    for (cell, written) in column(&r, "sigma").into_iter().zip(column(&r, "sigma_expr")) {
        let expected = match written {
            "1/110" => 1.0 / 110.0,
            "0.005" => 0.005,
            "R/100" => 1.0 / 100.0,
            other => panic!("sigma_expr {other}"),
        };
        assert_eq!(cell.parse::<f64>().unwrap(), expected, "sigma {cell} for {written}");
    }
    for cell in column(&r, "V0") {
        assert!([10.0, 12.0].contains(&cell.parse::<f64>().unwrap()), "V0 {cell}");
    }
    // Statuses are stable names; `converged` says the same.
    for (status, converged) in column(&r, "status").into_iter().zip(column(&r, "converged")) {
        assert_eq!(status.parse::<PointStatus>().unwrap().is_converged().to_string(), converged);
    }
    // Provenance: this build's version and schema, and the SHA-256 of the scene's bytes.
    let hash = sha256_of(&scene);
    assert!(column(&r, "scene_hash").iter().all(|h| *h == hash), "{:?} vs {hash}", column(&r, "scene_hash"));
    assert!(column(&r, "skg_solve_version").iter().all(|v| *v == env!("CARGO_PKG_VERSION")));
    let schema = skg_core::scene::provenance::SCHEMA_VERSION.to_string();
    assert!(column(&r, "schema_version").iter().all(|v| *v == schema));
    let info: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("sweep.json")).unwrap()).unwrap();
    assert_eq!(info["scene_hash"], hash.as_str());
    assert_eq!(info["skg_solve_version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(info["schema_version"].as_u64(), Some(skg_core::scene::provenance::SCHEMA_VERSION as u64));

    // Charts filter by value: the expression, the number, or an expression of scene
    // parameters (matched as written) each select one sigma, so each (N, V0) cell has one point.
    let stem = dir.path().join("map");
    let map = |filter: &str| {
        let mut args = vec!["plot", "stability", out.to_str().unwrap(), "-o", stem.to_str().unwrap(), "--x", "nodes", "--y", "V0"];
        if !filter.is_empty() {
            args.extend(["--where", filter]);
        }
        common::skg(&args, Path::new("."))
    };
    for filter in ["sigma=1/110", "sigma=0.00909090909090909", "sigma=R/100", "sigma=1/200", "sigma=1/300"] {
        let o = map(filter);
        let found = filter != "sigma=1/300"; // 1/200 is the point written 0.005
        assert_eq!(o.status.success(), found, "--where {filter}: {}", common::text(&o));
    }
    let o = map("");
    assert!(!o.status.success() && common::text(&o).contains("several points share"), "{}", common::text(&o));

    // A rerun after the base scene changed refuses to mix its rows with the old ones.
    std::fs::write(&scene, std::fs::read_to_string(&scene).unwrap() + "# edited\n").unwrap();
    let o = common::skg(&["sweep", p.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"], Path::new("."));
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("results.csv") && t.contains(&hash) && t.contains(&sha256_of(&scene)), "{t}");
    // Nor does merge join the rows of the two scene contents.
    let edited = dir.path().join("edited");
    assert!(common::skg(&["sweep", p.to_str().unwrap(), "-o", edited.to_str().unwrap(), "-q"], Path::new(".")).status.success());
    let merged = dir.path().join("merged");
    let o = common::skg(&["merge", "-o", merged.to_str().unwrap(), out.to_str().unwrap(), edited.to_str().unwrap()], Path::new("."));
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("not shards of one sweep") && t.contains(&hash) && t.contains(&sha256_of(&scene)), "{t}");
}

#[test]
fn results_of_another_schema_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let old = dir.path().join("results.csv");
    // The layout before schema versions: Ipopt's status names, no provenance columns.
    std::fs::write(
        &old,
        "id,index,method,rtol,nodes,operator,formulation,sigma,converged,status,iterations,wall_s,error_max\n\
         0123456789abcdef,0,skg,,128,SBP242,reduced,1/110,true,Solve_Succeeded,6,0.01,1e-3\n",
    )
    .unwrap();
    let o = common::skg(&["plot", "convergence", old.to_str().unwrap(), "-o", dir.path().join("c").to_str().unwrap()], Path::new("."));
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains(old.to_str().unwrap()) && t.contains("schema_version") && t.contains("schema 1"), "{t}");
    let e = merge_error(dir.path(), &old);
    assert!(e.contains("schema 1"), "{e}");
}

/// The error of merging one results file.
fn merge_error(dir: &Path, input: &Path) -> String {
    let o = common::skg(&["merge", "-o", dir.join("merged").to_str().unwrap(), input.to_str().unwrap()], Path::new("."));
    assert_eq!(o.status.code(), Some(1), "{}", common::text(&o));
    common::text(&o)
}

/// The `tune` command reports its choice of σ on the tumbler at N = 256 (the choice
/// itself is tested against the paper's in crates/skg-core/tests/tune.rs).
#[test]
fn tune_command_reports_the_choice() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("tune.json");
    let o = common::skg(
        &[
            "tune",
            common::scenario("tumbler").to_str().unwrap(),
            "--lo",
            "0.00625",
            "--hi",
            "0.0111",
            "--rel",
            "0.1",
            "-o",
            json.to_str().unwrap(),
        ],
        Path::new("."),
    );
    assert!(o.status.success(), "{}", common::text(&o));
    assert!(common::text(&o).contains("sigma = "), "{}", common::text(&o));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!(v["chosen"].as_f64().unwrap() > 1.0 / 125.0);
}

/// A point that converges but does not verify is recorded as such, with the verdict and
/// the verification error; with `fallback = true` the same point is solved as
/// `skg-solve SCENE` would (windows) and verifies.
#[test]
fn unverified_points_are_recorded_and_fallback_cures_them() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::test_scene("damped_oscillator");
    for (fallback, status, verification, solved_as) in
        [("false", "not_verified", "failed", "global"), ("true", "converged", "passed", "windows")]
    {
        let body = format!("fallback = {fallback}\n[[grid]]\nnodes = [512]\n");
        let p = common::sweep_file(dir.path(), &scene, &body);
        let out = dir.path().join(format!("fallback-{fallback}"));
        let o = common::skg(&["sweep", p.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"], Path::new("."));
        assert!(o.status.success(), "{}", common::text(&o));
        let r = Results::read(&out).unwrap();
        assert_eq!(column(&r, "status"), [status]);
        assert_eq!(column(&r, "converged"), ["true"]);
        assert_eq!(column(&r, "verification"), [verification]);
        assert!(column(&r, "solved_as")[0].starts_with(solved_as), "{:?}", column(&r, "solved_as"));
        let e: f64 = column(&r, "verify_error")[0].parse().unwrap();
        // The plain solve's odd-even mode (4.6e-2) or the windows' 6e-5.
        assert!(if fallback == "false" { e > 1e-2 } else { e < 1e-4 }, "{e:e}");
    }
}

/// A scene of my own: a damped oscillator with a cubic spring, `c` the damping.
const DUFFING: &str = r#"
[scene]
name = "damped duffing"
lagrangian = "1/2*x_dot^2 - 1/2*x^2 - 1/4*x^4"

[parameters]
c = 1

[[coordinates]]
name = "x"
initial = 1
velocity = 0

[forces]
x = "-c*x_dot"

[time]
start = 0
end = 4
nodes = 64

[discretization]
operator = "SBP242"

[solver]
backend = "newton"

[verify]
tol = 1e-2
"#;

/// The cells of `name` in a row.
fn cell<'a>(r: &Results, row: &'a [String], name: &str) -> &'a str {
    &row[r.column_index(name).unwrap_or_else(|| panic!("no column {name}"))]
}

/// With `--jobs 1` one worker runs every point: the points of equal structure (one N, a
/// damping axis) follow each other and reuse the first one's LU analysis, a point of
/// another N analyses anew; every trajectory is the one a separate one-point solve
/// (a fresh process, a fresh analysis) finds, to 1e-12.
#[test]
fn one_worker_reuses_the_lu_analysis_of_equal_structures_and_changes_no_value() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("duffing.toml");
    std::fs::write(&scene, DUFFING).unwrap();
    let p = common::sweep_file(
        dir.path(),
        &scene,
        "keep_trajectories = true\n[[grid]]\nnodes = 48\nc = [0.5, 2]\n[[grid]]\nnodes = 96\nc = [0.25, 0.5, 1, 2]\n",
    );
    let out = dir.path().join("out");
    let r = run_sweep(&p, &out, &["-j", "1"]);
    // Rows in the order the worker ran them: the larger N first.
    let runs: Vec<(&str, &str, &str)> =
        r.rows.iter().map(|row| (cell(&r, row, "nodes"), cell(&r, row, "lu_analysis"), cell(&r, row, "status"))).collect();
    let expected = [("96", "computed"), ("96", "reused"), ("96", "reused"), ("96", "reused"), ("48", "computed"), ("48", "reused")];
    assert_eq!(runs.iter().map(|&(n, a, _)| (n, a)).collect::<Vec<_>>(), expected, "{runs:?}");
    assert!(runs.iter().all(|&(_, _, s)| s == "converged"), "{runs:?}");
    for row in &r.rows {
        let (nodes, c, id) = (cell(&r, row, "nodes"), cell(&r, row, "c"), cell(&r, row, "id"));
        let single = dir.path().join(format!("single-{id}"));
        let args =
            [scene.to_str().unwrap(), "--nodes", nodes, "--set", &format!("c={c}"), "--no-fallback", "-q", "-o", single.to_str().unwrap()];
        let o = common::skg(&args, Path::new("."));
        assert!(o.status.success(), "{}", common::text(&o));
        let swept = skg_core::check::Table::read(&out.join("points").join(id).join("trajectory.csv")).unwrap();
        let alone = skg_core::check::Table::read(&single.join("trajectory.csv")).unwrap();
        assert_eq!((swept.columns.len(), swept.rows.len()), (alone.columns.len(), alone.rows.len()));
        let d = swept.rows.iter().flatten().zip(alone.rows.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(d <= 1e-12, "N = {nodes}, c = {c}: the swept trajectory differs from a one-point solve by {d:e}");
        let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(single.join("summary.json")).unwrap()).unwrap();
        let residual = summary["diagnostics"]["max_residual"].as_f64().unwrap();
        let swept_residual: f64 = cell(&r, row, "max_residual").parse().unwrap();
        assert!((residual - swept_residual).abs() <= 1e-12, "{residual:e} against {swept_residual:e}");
        assert_eq!(summary["backend"]["newton"]["analysis_reused"], false, "a one-point solve analyses");
    }
}

/// `solved` for a row whose solve converged (verified or not: the small tumbler grids
/// need the fallback ladder to verify), else its status.
fn solved<'a>(r: &Results, row: &'a [String]) -> &'a str {
    if cell(r, row, "converged") == "true" && !cell(r, row, "solver_status").is_empty() {
        "solved"
    } else {
        cell(r, row, "status")
    }
}

/// Every row as (N, [`solved`], the cell of `column`), sorted by N.
fn by_nodes<'a>(r: &'a Results, column: &str) -> Vec<(usize, &'a str, &'a str)> {
    let mut rows: Vec<_> =
        r.rows.iter().map(|row| (cell(r, row, "nodes").parse().unwrap(), solved(r, row), cell(r, row, column))).collect();
    rows.sort();
    rows
}

/// Pids of the child processes of `pid` (Linux's /proc).
fn children(pid: u32) -> Vec<u32> {
    let text = std::fs::read_to_string(format!("/proc/{pid}/task/{pid}/children")).unwrap_or_default();
    text.split_whitespace().map(|p| p.parse().unwrap()).collect()
}

/// A worker killed (as by the kernel's out-of-memory killer) while it runs a point costs
/// only that point, recorded as crashed; a fresh worker runs the rest.
#[test]
fn a_killed_worker_costs_only_its_point() {
    let dir = tempfile::tempdir().unwrap();
    let p = sweep_file(dir.path(), "tumbler", "[[grid]]\nnodes = [128, 160, 192]\n[[points]]\nnodes = 8192\n");
    let out = dir.path().join("out");
    let mut sweep = start_sweep(&p, &out);
    // The largest point goes first: kill its worker while it computes.
    let start = Instant::now();
    let worker = loop {
        if let Some(&w) = children(sweep.id()).first() {
            break w;
        }
        assert!(start.elapsed() < Duration::from_secs(30), "no worker started");
        std::thread::sleep(Duration::from_millis(2));
    };
    std::thread::sleep(Duration::from_millis(100));
    assert!(!out.join("results.csv").exists() || Results::read(&out).unwrap().rows.is_empty(), "the first point finished too soon");
    assert!(Command::new("kill").args(["-KILL", &worker.to_string()]).status().unwrap().success());
    assert!(sweep.wait().unwrap().success());
    let r = Results::read(&out).unwrap();
    let rows = by_nodes(&r, "message");
    assert_eq!(
        rows.iter().map(|&(n, s, _)| (n, s)).collect::<Vec<_>>(),
        [(128, "solved"), (160, "solved"), (192, "solved"), (8192, "crashed")]
    );
    assert!(rows[3].2.contains("SIGKILL"), "{}", rows[3].2);
    assert!(!out.join(".work").exists(), "worker files are cleaned up");
}

/// The sweep's timeout kills the worker of the late point only; a fresh worker runs the
/// others.
#[test]
fn a_timeout_kills_only_the_late_point() {
    let dir = tempfile::tempdir().unwrap();
    // The small points take well under 0.2 s in a test build; the large one well over
    // 20 s (at 65536 nodes it took several seconds, its guess and verification alone),
    // so a 2 s limit separates them by a factor of ten either way, on a loaded machine
    // as on a fast one.
    let p = sweep_file(dir.path(), "tumbler", "timeout = 2\n[[grid]]\nnodes = [128, 160, 192]\n[[points]]\nnodes = 262144\n");
    let r = run_sweep(&p, &dir.path().join("out"), &["-j", "1"]);
    let rows = by_nodes(&r, "converged");
    assert_eq!(
        rows.iter().map(|&(n, s, _)| (n, s)).collect::<Vec<_>>(),
        [(128, "solved"), (160, "solved"), (192, "solved"), (262144, "timeout")]
    );
    assert_eq!(rows[3].2, "false");
}

/// A results.csv of an earlier layout (here: without `lu_analysis`) is not resumed; the
/// error names what differs.
#[test]
fn resuming_a_results_file_without_a_newer_column_names_it() {
    let dir = tempfile::tempdir().unwrap();
    let p = sweep_file(dir.path(), "free_fall", "[[grid]]\nnodes = [32]\n");
    let out = dir.path().join("out");
    let r = run_sweep(&p, &out, &[]);
    let results = out.join("results.csv");
    let drop_at = r.column_index("lu_analysis").unwrap();
    let without = |fields: &[String]| {
        let kept: Vec<String> = fields.iter().enumerate().filter(|(k, _)| *k != drop_at).map(|(_, f)| f.clone()).collect();
        skg_sweep::csv_line(&kept)
    };
    let mut old = without(&r.header);
    r.rows.iter().for_each(|row| old.extend(without(row)));
    std::fs::write(&results, old).unwrap();
    let o = common::skg(&["sweep", p.to_str().unwrap(), "-o", out.to_str().unwrap()], Path::new("."));
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("results.csv") && t.contains("it lacks lu_analysis") && t.contains("--new-results"), "{t}");
}

/// An `initial_velocity` axis: its own column in results.csv, each point solved with its
/// condition (the natural one more accurate on SBP484, as against the closed form in
/// crates/skg-core/tests/initial_velocity.rs), and the work-precision chart draws one
/// line per condition.
#[test]
fn an_initial_velocity_axis_gets_its_column_and_its_chart_lines() {
    let dir = tempfile::tempdir().unwrap();
    let body = "reference = \"integrate\"\nfallback = false\n[[grid]]\noperator = \"SBP484\"\nnodes = [128, 256]\n\
                initial_velocity = [\"strong\", \"natural\"]\n";
    let p = common::sweep_file(dir.path(), &common::scenario("rolling_disk"), body);
    let out = dir.path().join("out");
    let r = run_sweep(&p, &out, &["-q"]);
    assert_eq!(r.rows.len(), 4);
    let mut errors = std::collections::BTreeMap::new();
    for row in &r.rows {
        assert_eq!(cell(&r, row, "status"), "converged", "{row:?}");
        let key = (cell(&r, row, "nodes").to_string(), cell(&r, row, "initial_velocity").to_string());
        errors.insert(key, cell(&r, row, "error_max").parse::<f64>().unwrap());
    }
    for n in ["128", "256"] {
        let (s, nat) = (errors[&(n.to_string(), "strong".to_string())], errors[&(n.to_string(), "natural".to_string())]);
        assert!(nat < s / 3.0, "N = {n}: natural {nat:e}, strong {s:e}");
    }
    let stem = dir.path().join("wp");
    let o = common::skg(&["plot", "work-precision", out.to_str().unwrap(), "-o", stem.to_str().unwrap()], Path::new("."));
    assert!(o.status.success(), "{}", common::text(&o));
    let svg = std::fs::read_to_string(stem.with_extension("svg")).unwrap();
    assert!(svg.contains("SBP484 reduced strong") && svg.contains("SBP484 reduced natural"), "legend of {}", stem.display());
}
