//! The command line: outputs, exit codes and clear errors for bad input (never a panic).

mod common;

use std::path::Path;

/// A variant of a shipped scene, written to `dir/scene.toml`.
fn variant(dir: &Path, name: &str, replacements: &[(&str, &str)]) -> String {
    common::variant(dir, name, "scene.toml", replacements).display().to_string()
}

/// Run on a bad scene: exit code 1, no panic, message contains every `needle`.
fn expect_error(dir: &Path, scene: &str, extra: &[&str], needles: &[&str]) {
    let mut args = vec![scene];
    args.extend_from_slice(extra);
    let o = common::skg(&args, dir);
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(!t.contains("panicked"), "{t}");
    for n in needles {
        assert!(t.contains(n), "expected `{n}` in:\n{t}");
    }
    assert!(!dir.join("out").exists(), "no output for a failed input");
}

#[test]
fn solve_writes_csv_and_summary() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::scenario("rolling_disk");
    let o = common::skg(&[scene.to_str().unwrap(), "-o", "res"], dir.path());
    assert!(o.status.success(), "{}", common::text(&o));
    let csv = std::fs::read_to_string(dir.path().join("res/trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next().unwrap(), "t,x,x_dot,y,y_dot,theta,theta_dot,phi,phi_dot,lambda_g1,lambda_g2,energy,residual_g1,residual_g2");
    assert_eq!(lines.count(), 64);
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("res/summary.json")).unwrap()).unwrap();
    assert_eq!(summary["converged"], true);
    assert_eq!(summary["status"], "Solve_Succeeded");
    assert_eq!(summary["sizes"]["nodes"], 64);
    assert!(summary["iterations"].as_u64().unwrap() > 0);
    assert!(summary["timings"]["solver_s"].as_f64().unwrap() > 0.0);
    assert!(summary["diagnostics"]["max_residual"].as_f64().unwrap() < 1e-8);
    assert!(common::text(&o).contains("trajectory.csv"), "prints where the output went");
    assert!(!common::text(&o).contains("not conserved"), "the disk conserves its energy: {}", common::text(&o));
}

/// The energy line says why the energy is not conserved when the scene has declared
/// forces (damping) or friction.
#[test]
fn the_energy_line_says_when_declared_forces_do_not_conserve_it() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["damped_oscillator", "incline_friction"] {
        let scene = common::scenario(name);
        let o = common::skg(&[scene.to_str().unwrap(), "-o", name], dir.path());
        assert!(o.status.success(), "{}", common::text(&o));
        assert!(common::text(&o).contains("not conserved: the scene has declared forces or friction"), "{name}: {}", common::text(&o));
    }
}

/// summary.json says which program and which scene produced it, and keys per-wall
/// diagnostics by the wall's name.
#[test]
fn summary_carries_provenance_and_per_wall_entries_by_name() {
    use sha2::{Digest, Sha256};
    let dir = tempfile::tempdir().unwrap();
    let scene = common::scenario("tumbler");
    let o = common::skg(&[scene.to_str().unwrap(), "-o", "res", "-q"], dir.path());
    assert!(o.status.success(), "{}", common::text(&o));
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("res/summary.json")).unwrap()).unwrap();
    assert_eq!(summary["skg_solve_version"], skg_core::scene::provenance::VERSION);
    assert_eq!(summary["skg_solve_version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(summary["schema_version"], skg_core::scene::provenance::SCHEMA_VERSION);
    let digest = Sha256::digest(std::fs::read(&scene).unwrap());
    let hex: String = digest.iter().map(|b| format!("{b:02x}")).collect();
    assert_eq!(summary["scene_hash"], format!("sha256:{hex}"));
    let d = &summary["diagnostics"];
    assert!(d["max_wall_gap"]["drum"].as_f64().unwrap() < 0.0, "{d}");
    assert_eq!(d["contact_episodes"], serde_json::json!({ "drum": 2 }));
    assert_eq!(d["contact_episodes_time_stepping"], serde_json::json!({ "drum": 2 }));
    assert_eq!(summary["solve_status"], "converged");
    assert_eq!(summary["status_text"], "solved to the requested tolerance");
}

#[test]
fn non_converged_solve_exits_3_and_marks_the_summary() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::scenario("rolling_disk");
    let o = common::skg(&[scene.to_str().unwrap(), "-o", "res", "--max-iter", "0"], dir.path());
    assert_eq!(o.status.code(), Some(3), "{}", common::text(&o));
    assert!(common::text(&o).contains("did not converge"), "{}", common::text(&o));
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("res/summary.json")).unwrap()).unwrap();
    assert_eq!(summary["converged"], false);
    assert_eq!(summary["status"], "Maximum_Iterations_Exceeded");
    assert_eq!(summary["solve_status"], "not_converged");
    assert_eq!(summary["status_text"], "maximum number of iterations exceeded");
}

#[test]
fn help_explains_the_options() {
    let o = common::skg(&["--help"], Path::new("."));
    let t = common::text(&o);
    for needle in ["SCENARIO.toml", "--set", "--operator", "--formulation", "--nodes", "trajectory.csv", "Exit status"] {
        assert!(t.contains(needle), "--help lacks {needle}");
    }
}

/// The default verification tolerance is stated twice in `--help` (the overview and
/// `--verify-tol`); both must say the value the code uses.
#[test]
fn help_states_the_default_verification_tolerance_the_code_uses() {
    let t = common::text(&common::skg(&["--help"], Path::new(".")));
    let stated = format!("{:e}", skg_core::stepping::verify::DEFAULT_RELATIVE_TOL);
    let flat = t.split_whitespace().collect::<Vec<_>>().join(" ");
    let starts: Vec<usize> = flat.match_indices("each coordinate's range").map(|(i, _)| i).collect();
    assert!(starts.len() >= 2, "expected the default in the overview and under --verify-tol:\n{t}");
    for i in starts {
        let before = &flat[..i];
        let stated_just_before = before.rfind(&stated).is_some_and(|p| i - p <= stated.len() + 4);
        assert!(stated_just_before, "--help states another default than {stated} before \"each coordinate's range\" at byte {i}:\n{t}");
    }
}

/// A usage error (clap) exits 2, distinct from input errors (1), a solve that did not
/// converge (3) and an exceeded tolerance (4), so a script can tell them apart.
#[test]
fn usage_errors_exit_2() {
    // Out-of-range option values too, negative numbers included (taken as the value,
    // not as an unknown option).
    let bad_values =
        [&["x.toml", "--verify-tol", "-1"][..], &["x.toml", "--verify-tol=0"], &["x.toml", "--window", "-3"], &["x.toml", "--overlap=nan"]];
    for args in bad_values {
        let o = common::skg(args, Path::new("."));
        let t = common::text(&o);
        assert!(o.status.code() == Some(2) && t.contains("invalid value") && !t.contains("unexpected argument"), "{args:?}: {t}");
    }
    for args in [&["--nodes"][..], &["check", "only-one.csv"], &["--no-such-option", "x.toml"], &["plot"]] {
        let o = common::skg(args, Path::new("."));
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", common::text(&o));
    }
}

#[test]
fn toml_syntax_error_names_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let s = variant(dir.path(), "free_fall", &[("m = 2", "m = = 2")]);
    expect_error(dir.path(), &s, &[], &["scene.toml:11:5", "invalid string"]);
}

#[test]
fn unknown_key_names_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let s = variant(dir.path(), "free_fall", &[("velocity = 3", "velocity = 3\nmass = 1")]);
    expect_error(dir.path(), &s, &[], &["scene.toml:17:1", "mass"]);
}

#[test]
fn unknown_symbol_in_expression_shows_expression_and_position() {
    let dir = tempfile::tempdir().unwrap();
    let s = variant(dir.path(), "free_fall", &[("- m*g*x", "- m*gg*x")]);
    expect_error(dir.path(), &s, &[], &["scene.lagrangian", "gg", "1/2*m*x_dot^2 - m*gg*x", "^", "known names"]);
}

#[test]
fn expression_syntax_error_shows_position() {
    let dir = tempfile::tempdir().unwrap();
    let s = variant(dir.path(), "rolling_disk", &[("x_dot*sin(phi) - y_dot*cos(phi)", "x_dot*sin(phi - y_dot*cos(phi)")]);
    expect_error(dir.path(), &s, &[], &["constraints.g2.expression", "x_dot*sin(phi - y_dot*cos(phi)"]);
}

#[test]
fn too_few_nodes_for_the_operator() {
    let dir = tempfile::tempdir().unwrap();
    let s = variant(dir.path(), "free_fall", &[("nodes = 32", "nodes = 5")]);
    expect_error(dir.path(), &s, &[], &["SBP242 needs at least", "got 5"]);
    let s = common::scenario("free_fall");
    expect_error(dir.path(), s.to_str().unwrap(), &["--nodes", "3", "--operator", "SBP363"], &["SBP363 needs at least"]);
}

#[test]
fn non_positive_or_non_finite_time_span() {
    let dir = tempfile::tempdir().unwrap();
    let s = variant(dir.path(), "free_fall", &[("end = 2", "end = 0")]);
    expect_error(dir.path(), &s, &[], &["time span must be positive"]);
    let s = variant(dir.path(), "free_fall", &[("end = 2", "end = \"1/0\"")]);
    expect_error(dir.path(), &s, &[], &["not finite"]);
}

#[test]
fn non_positive_wall_width_and_mass() {
    let dir = tempfile::tempdir().unwrap();
    let s = common::scenario("tumbler");
    expect_error(dir.path(), s.to_str().unwrap(), &["--set", "sigma=0"], &["width σ must be > 0"]);
    expect_error(dir.path(), s.to_str().unwrap(), &["--set", "sigma=-1/100"], &["width σ must be > 0"]);
    expect_error(dir.path(), s.to_str().unwrap(), &["--set", "m=-1"], &["not positive definite", "masses"]);
    expect_error(dir.path(), s.to_str().unwrap(), &["--set", "m=0"], &["not positive definite"]);
}

#[test]
fn initial_velocity_violating_a_constraint_says_by_how_much() {
    let dir = tempfile::tempdir().unwrap();
    let s = variant(dir.path(), "rolling_disk", &[("initial = 0\nvelocity = 0", "initial = 0\nvelocity = 0.5")]);
    // y_dot = 0.5: g1 = 25 + 0.25 − 25 = 0.25, g2 = −0.5 at φ = 0.
    expect_error(dir.path(), &s, &[], &["violates constraint `g1`", "2.500000e-1"]);
}

#[test]
fn bad_override_and_operator_names() {
    let dir = tempfile::tempdir().unwrap();
    let s = common::scenario("free_fall");
    expect_error(dir.path(), s.to_str().unwrap(), &["--set", "nope=1"], &["no parameter `nope`"]);
    expect_error(dir.path(), s.to_str().unwrap(), &["--set", "g"], &["expected name=value"]);
    // An unknown name is not a cycle, even when a parameter's name is part of it ("gabc").
    let o = common::skg(&[s.to_str().unwrap(), "--set", "g=gabc"], dir.path());
    let t = common::text(&o);
    assert!(o.status.code() == Some(1) && t.contains("unknown symbol `gabc`") && !t.contains("cycle"), "{t}");
    // A real cycle is called one.
    let cyc = variant(dir.path(), "free_fall", &[("[parameters]", "[parameters]\na = \"b + 1\"\nb = \"2*a\"")]);
    expect_error(dir.path(), &cyc, &[], &["cycle", "a, b"]);
    let o = common::skg(&[s.to_str().unwrap(), "--operator", "SBP999"], dir.path());
    assert_eq!(o.status.code(), Some(2), "clap usage error");
    assert!(common::text(&o).contains("SBP242"), "lists the valid operators: {}", common::text(&o));
    let o = common::skg(&["missing.toml"], dir.path());
    assert_eq!(o.status.code(), Some(1));
    let t = common::text(&o);
    assert!(t.contains("cannot read scene file missing.toml"), "{t}");
    assert_eq!(t.matches("No such file").count(), 1, "the cause is printed once: {t}");
}

#[test]
fn ipopt_log_file_and_pass_through_options() {
    let dir = tempfile::tempdir().unwrap();
    let s = variant(
        dir.path(),
        "rolling_disk",
        &[(
            "[discretization]",
            "[solver]\nlog_file = \"ipopt.log\"\n[solver.ipopt]\nmumps_pivtol = 1e-4\nprint_user_options = \"yes\"\n\n[discretization]",
        )],
    );
    let o = common::skg(&[&s, "-o", "res"], dir.path());
    assert!(o.status.success(), "{}", common::text(&o));
    let log = std::fs::read_to_string(dir.path().join("res/ipopt.log")).unwrap();
    assert!(log.contains("iter"), "{log}");
    assert!(log.contains("mumps_pivtol") && log.contains("0.0001"), "pass-through option not in the log's option list");
    // Stopped from the intermediate callback once converged: Ipopt does not factor the
    // KKT matrix once more to recompute the multipliers of the square system (which
    // it reports failing, "Cannot recompute multipliers for feasibility problem").
    assert!(!log.contains("Cannot recompute multipliers"), "Ipopt's final multiplier recomputation ran: {log}");
    assert!(log.contains("Stopping optimization at current point as requested by user"), "{log}");
    // An option Ipopt does not know is an error that names it, not a panic.
    let s = variant(dir.path(), "free_fall", &[("[time]", "[solver.ipopt]\nno_such_option = 3\n\n[time]")]);
    let o = common::skg(&[&s, "-o", "res2"], dir.path());
    let t = common::text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("no_such_option") && !t.contains("panicked"), "{t}");
}

/// `[solver] backend` and `--backend` choose Newton; the summary line and summary.json
/// say which backend ran; an unknown backend is an error naming the valid ones.
#[test]
fn backend_key_and_flag() {
    let dir = tempfile::tempdir().unwrap();
    let s = variant(dir.path(), "knife_edge", &[("[discretization]", "[solver]\nbackend = \"newton\"\n\n[discretization]")]);
    let o = common::skg(&[&s, "-o", "res"], dir.path());
    let t = common::text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("Newton iterations"), "{t}");
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.path().join("res/summary.json")).unwrap()).unwrap();
    assert_eq!((summary["status"].as_str(), summary["settings"]["backend"].as_str()), (Some("Newton_Converged"), Some("newton")));
    assert_eq!(summary["backend"]["handed_over_to_ipopt"], false);
    // The flag overrides the scene's key.
    let o = common::skg(&[&s, "-o", "res2", "--backend", "ipopt"], dir.path());
    assert!(common::text(&o).contains("Ipopt iterations"), "{}", common::text(&o));
    // A Newton solve that does not converge exits 3 like an Ipopt one.
    let o = common::skg(&[&s, "-o", "res3", "--max-iter", "0"], dir.path());
    assert_eq!(o.status.code(), Some(3), "{}", common::text(&o));
    let o = common::skg(&[&s, "--backend", "lu"], dir.path());
    assert_eq!(o.status.code(), Some(2));
    assert!(common::text(&o).contains("newton"), "{}", common::text(&o));
    let bad = variant(dir.path(), "knife_edge", &[("[discretization]", "[solver]\nbackend = \"lu\"\n\n[discretization]")]);
    let o = common::skg(&[&bad], dir.path());
    assert_eq!(o.status.code(), Some(1), "{}", common::text(&o));
    let t = common::text(&o);
    assert!(t.contains("scene.toml:") && t.contains("`lu`") && t.contains("`ipopt` or `newton`"), "names the place and the choices: {t}");
}

/// `line:col` (1-based) of the first occurrence of `needle` in the file at `path`.
fn position_of(path: &str, needle: &str) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    let offset = text.find(needle).unwrap_or_else(|| panic!("{needle} not in {path}"));
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().unwrap().chars().count() + 1;
    format!("{line}:{col}")
}

#[test]
fn time_is_a_reserved_name_and_constants_cannot_use_it() {
    let dir = tempfile::tempdir().unwrap();
    let s = variant(dir.path(), "free_fall", &[("m = 2", "m = 2\nt = 1")]);
    expect_error(dir.path(), &s, &[], &["parameter `t` clashes with the time `t`"]);
    let s = variant(dir.path(), "free_fall", &[("name = \"x\"", "name = \"t\""), ("1/2*m*x_dot^2 - m*g*x", "1/2*m*t_dot^2 - m*g*t")]);
    expect_error(dir.path(), &s, &[], &[&position_of(&s, "\"t\""), "`t` clashes with the time `t`"]);
    let hint = "the time `t` may appear in the Lagrangian, constraints, forces and walls only";
    let s = variant(dir.path(), "free_fall", &[("initial = 10", "initial = \"10 + t\"")]);
    expect_error(dir.path(), &s, &[], &["coordinates.x.initial", "unknown symbol `t`", hint]);
    let s = variant(dir.path(), "free_fall", &[("m = 2", "m = \"2*t\"")]);
    expect_error(dir.path(), &s, &[], &["parameters.m", "unknown symbol `t`", hint]);
    let s = variant(dir.path(), "free_fall", &[("end = 2", "end = \"2 + t\"")]);
    expect_error(dir.path(), &s, &[], &["time.end", hint]);
}

#[test]
fn a_position_constraint_must_hold_at_the_start_with_a_tangent_velocity() {
    let dir = tempfile::tempdir().unwrap();
    // x0 = 1.01 l sin θ0: h = (1.01² − 1) sin²(1) = 1.4233e-2.
    let s = variant(dir.path(), "pendulum", &[("initial = \"l*sin(theta0)\"", "initial = \"1.01*l*sin(theta0)\"")]);
    let h = (1.01_f64.powi(2) - 1.0) * 1.0_f64.sin().powi(2);
    expect_error(
        dir.path(),
        &s,
        &[],
        &[&position_of(&s, "\"x^2 + y^2"), "violates position constraint `rod`", "h(q₀, t₀)", &format!("{h:.6e}")],
    );
    // ẋ0 = 1: the time derivative 2(x ẋ + y ẏ) = 2 sin(1) ≠ 0.
    let s = variant(dir.path(), "pendulum", &[("initial = \"l*sin(theta0)\"\nvelocity = 0", "initial = \"l*sin(theta0)\"\nvelocity = 1")]);
    let g = 2.0 * 1.0_f64.sin();
    expect_error(dir.path(), &s, &[], &["violates constraint `rod`", "∇h·q̇ + ∂h/∂t", &format!("{g:.6e}"), "tangent"]);
    // A constraint of parameters and t alone constrains nothing.
    let s = variant(dir.path(), "pendulum", &[("expression = \"x^2 + y^2 - l^2\"", "expression = \"l - 1 + t\"")]);
    expect_error(dir.path(), &s, &[], &[&position_of(&s, "\"l - 1"), "`rod` depends on neither the coordinates nor the velocities"]);
}

#[test]
fn a_start_not_strictly_inside_the_walls_is_refused_with_the_gap() {
    let dir = tempfile::tempdir().unwrap();
    // x0 = −1.5: h = 2.25 + 0.5625 − 1 = 1.8125.
    let s = variant(dir.path(), "tumbler", &[("initial = -0.5", "initial = -1.5")]);
    expect_error(dir.path(), &s, &[], &[&position_of(&s, "\"x^2 + y^2 - R^2\""), "wall `drum`", "1.812500e0", "need h < 0"]);
    // On the wall (h = 0 at (0, −1)): the Gaussian wall already pushes there.
    let s = variant(dir.path(), "tumbler", &[("initial = -0.5", "initial = 0"), ("initial = -0.75", "initial = -1")]);
    expect_error(dir.path(), &s, &[], &["wall `drum`", "h(q₀, t₀) = 0.000000e0", "strictly on the allowed side"]);
    // A moving wall is checked at the start time: the plate at t0 = 1/8 s is at y = a.
    let s = variant(dir.path(), "vibrating_plate", &[("initial = 0.5", "initial = 0.04"), ("start = 0", "start = 0.125")]);
    expect_error(dir.path(), &s, &[], &["wall `plate`", "1.000000e-2"]);
}

#[test]
fn a_friction_direction_of_the_wrong_length_is_refused_where_it_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let s = variant(dir.path(), "incline_friction", &[("friction_direction = [\"1\", \"tan(alpha)\"]", "friction_direction = [\"1\"]")]);
    expect_error(dir.path(), &s, &[], &[&position_of(&s, "\"1\"]"), "friction_direction has 1 components, the scene has 2 coordinates"]);
}

/// The same command gives the same bytes: three Ipopt solves of the tumbler at
/// N = 4096 in separate processes write identical trajectories. (With MUMPS's automatic
/// pivot order, SCOTCH, whose ordering varies from run to run, three runs gave two or three
/// different files; skg-solve sets AMF, docs/solver.md.)
#[test]
fn repeated_ipopt_solves_are_bitwise_identical() {
    let dir = tempfile::tempdir().unwrap();
    let s = common::scenario("tumbler");
    let files: Vec<Vec<u8>> = (0..3)
        .map(|i| {
            let out = format!("run{i}");
            let o = common::skg(&[s.to_str().unwrap(), "--nodes", "4096", "--no-verify", "-q", "-o", &out], dir.path());
            assert!(o.status.success(), "{}", common::text(&o));
            std::fs::read(dir.path().join(out).join("trajectory.csv")).unwrap()
        })
        .collect();
    assert!(files.iter().all(|f| f == &files[0]), "repeated solves of the same scene differ");
}
