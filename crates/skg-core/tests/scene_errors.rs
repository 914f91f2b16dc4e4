//! Scenes that must be refused, and the messages that refuse them (issue 21 items 5
//! and 9): each names the place in the file, the key and the offending value, and says
//! what is wrong in the scene's own terms, never in a library's.

mod common;

use skg_core::model::Model;
use skg_core::scene::{Overrides, SceneFile};

/// A shipped scene with each `(from, to)` replaced once (each `from` must occur).
fn variant(scene: &str, replacements: &[(&str, &str)]) -> String {
    let mut text = std::fs::read_to_string(common::scenario(scene)).unwrap();
    for (from, to) in replacements {
        assert!(text.contains(from), "{from} not in {scene}");
        text = text.replacen(from, to, 1);
    }
    text
}

/// The error of parsing, resolving and building the model of `text` (as `s.toml`).
fn refusal(text: &str) -> String {
    let result = SceneFile::parse(text, "s.toml").and_then(|f| f.resolve(&Overrides::default())).and_then(|s| Model::build(&s));
    match result {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// The 1-based line of the first line of `text` that contains `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap_or_else(|| panic!("{needle} not in the text")) + 1
}

/// A wall whose `h` depends on no coordinate pushes on nothing: like a constraint that
/// constrains nothing, it is refused at its `h` (before the fix the tumbler with
/// `h = "t - 2"` ran past t = 2 and exited 0 on the forbidden side).
#[test]
fn a_wall_that_depends_on_no_coordinate_is_refused_at_its_h() {
    for h in ["t - 2", "-1", "R - 2*R", "x - x + t"] {
        let text = variant("tumbler", &[("h = \"x^2 + y^2 - R^2\"", &format!("h = \"{h}\"")), ("end = 0.5", "end = 3")]);
        let e = refusal(&text);
        let at = format!("s.toml:{}:5:", line_of(&text, "h = \""));
        assert!(e.starts_with(&at) && e.contains("wall `drum`") && e.contains("depends on no coordinate"), "h = {h}: {e}");
    }
    // A moving wall (h depends on t and a coordinate) is still accepted.
    let plate = std::fs::read_to_string(common::scenario("vibrating_plate")).unwrap();
    let scene = SceneFile::parse(&plate, "p.toml").unwrap().resolve(&Overrides::default()).unwrap();
    Model::build(&scene).unwrap();
}

/// The pendulum with its rod's expression replaced, and more constraints appended.
fn pendulum(rod: &str, more: &str) -> String {
    variant("pendulum", &[("expression = \"x^2 + y^2 - l^2\"", &format!("expression = \"{rod}\"{more}"))])
}

/// A constraint whose gradient is zero at the initial state is said to be so, not
/// "a combination of those of" an empty list of constraints.
#[test]
fn a_constraint_with_a_zero_gradient_is_named_as_such() {
    for rod in ["(x^2 + y^2 - l^2)^2", "x_dot^2 + y_dot^2"] {
        let e = refusal(&pendulum(rod, ""));
        assert!(e.contains("constraint `rod`") && e.contains("is zero at the initial state"), "{rod}: {e}");
        assert!(!e.contains("combination of those of"), "{rod}: {e}");
    }
}

/// Scaling a constraint by any factor changes nothing about its rank: the rod times
/// 1e300 or 1e-300 is not redundant (it was, before the fix, by overflow and underflow).
#[test]
fn a_constraint_scaled_by_a_huge_or_tiny_factor_is_not_called_redundant() {
    for factor in ["1e300", "1e-300", "1e200", "1e-200"] {
        let text = pendulum(&format!("{factor}*(x^2 + y^2 - l^2)"), "");
        let scene = SceneFile::parse(&text, "s.toml").unwrap().resolve(&Overrides::default()).unwrap();
        if let Err(e) = Model::build(&scene) {
            panic!("{factor}: {e}");
        }
    }
    // Two rods, one scaled by 1e300 and one by 1e-300, independent: accepted.
    let two = pendulum("1e300*(x^2 + y^2 - l^2)", "\n\n[[constraints]]\nname = \"rod2\"\nexpression = \"1e-300*(x*y - x0*y0)\"");
    let two = two.replace("[parameters]", "[parameters]\nx0 = \"l*sin(theta0)\"\ny0 = \"-l*cos(theta0)\"");
    let scene = SceneFile::parse(&two, "s.toml").unwrap().resolve(&Overrides::default()).unwrap();
    if let Err(e) = Model::build(&scene) {
        panic!("two scaled rods: {e}");
    }
    // A truly redundant pair stays redundant at any scale.
    let e =
        refusal(&pendulum("1e300*(x^2 + y^2 - l^2)", "\n\n[[constraints]]\nname = \"rod2\"\nexpression = \"1e-300*(x^2 + y^2 - l^2)\""));
    assert!(e.contains("constraint `rod2` is redundant") && e.contains("combination of those of `rod`"), "{e}");
}

/// Two rods of different lengths from one point cannot both hold: the message says which
/// one the initial position violates (before the fix: "redundant").
#[test]
fn two_contradictory_rods_name_the_one_the_initial_position_violates() {
    let text = pendulum("x^2 + y^2 - l^2", "\n\n[[constraints]]\nname = \"rod2\"\nexpression = \"x^2 + y^2 - 4*l^2\"");
    let e = refusal(&text);
    let at = format!("s.toml:{}:", line_of(&text, "4*l^2"));
    assert!(e.starts_with(&at) && e.contains("the initial position violates position constraint `rod2`"), "{e}");
}

/// The error of parsing `text` (as `s.toml`).
fn parse_error(text: &str) -> String {
    match SceneFile::parse(text, "s.toml") {
        Ok(_) => panic!("parsed:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// A value of the wrong type names the key, what was expected and the value as written,
/// at its line and column, instead of serde's "data did not match any variant of
/// untagged enum NumOrExpr" or "invalid type: …, expected f64".
#[test]
fn values_of_the_wrong_type_name_the_key_the_expected_type_and_the_value() {
    let oscillator = |extra: &str| variant("damped_oscillator", &[("nodes = 512", &format!("nodes = 512\n{extra}"))]);
    let tumbler = |from: &str, to: &str| variant("tumbler", &[(from, to)]);
    let number = "must be a number or an expression in quotes, got";
    let cases = [
        (tumbler("tol = 1e-4", "tol = true"), "tol = true", 7, format!("verify.tol {number} true")),
        (tumbler("tol = 1e-4", "tol = [1, 2]"), "tol = [1", 7, format!("verify.tol {number} [1, 2]")),
        (oscillator("window = true"), "window = true", 10, format!("time.window {number} true")),
        (oscillator("window = 2\noverlap = {a = 1}"), "overlap = {", 11, format!("time.overlap {number} {{a = 1}}")),
        (tumbler("initial = -0.5", "initial = false"), "initial = false", 11, format!("coordinates.initial {number} false")),
        (tumbler("V0 = 10", "V0 = 1979-05-27"), "V0 = 1979", 6, format!("parameters.V0 {number} 1979-05-27")),
        (tumbler("strength = \"V0/2\"", "strength = [1]"), "strength = [1]", 12, format!("walls.strength {number} [1]")),
        (
            tumbler("tol = 1e-4", "tol = 1e-4\n\n[solver.ipopt]\nmu_init = true"),
            "mu_init = true",
            11,
            "solver.ipopt.mu_init must be an integer, a number or a string in quotes (the type of the Ipopt option), got true".into(),
        ),
        (
            tumbler("tol = 1e-4", "tol = 1e-4\n\n[solver]\ntol = \"1e-8\""),
            "tol = \"1e-8\"",
            7,
            "solver.tol must be a number, got \"1e-8\"".into(),
        ),
        (
            tumbler("tol = 1e-4", "tol = 1e-4\n\n[solver]\nmax_iter = -3"),
            "max_iter = -3",
            12,
            "solver.max_iter must be a whole number from 0 to 4294967295, got -3".into(),
        ),
        (
            tumbler("tol = 1e-4", "tol = 1e-4\n\n[solver]\nfallback = \"no\""),
            "fallback = \"no\"",
            12,
            "solver.fallback must be true or false, got \"no\"".into(),
        ),
        (tumbler("nodes = 256", "nodes = \"256\""), "nodes = \"256\"", 9, "time.nodes must be a whole number, got \"256\"".into()),
        (tumbler("nodes = 256", "nodes = 256.5"), "nodes = 256.5", 9, "time.nodes must be a whole number, got 256.5".into()),
        (
            tumbler("nodes = 256", "nodes = 99999999999999999999999"),
            "nodes = 9999",
            9,
            "time.nodes must be a whole number from −9223372036854775808 to 9223372036854775807, got 99999999999999999999999".into(),
        ),
        (
            tumbler("tol = 1e-4", "tol = 1e-4\n\n[solver]\nhessian = 3"),
            "hessian = 3",
            11,
            "solver.hessian must be a string in quotes, got 3".into(),
        ),
    ];
    for (text, needle, col, message) in cases {
        let e = parse_error(&text);
        assert_eq!(e, format!("s.toml:{}:{col}: {message}", line_of(&text, needle)), "{needle}");
    }
}

/// The names of settings are case-insensitive in a scene file, as on the command line
/// and in a sweep's grid (before the fix `backend = "Newton"` was refused in a scene
/// file and accepted in a sweep).
#[test]
fn setting_names_are_case_insensitive_in_a_scene_file() {
    use skg_core::scene::{Backend, Formulation, HessianMode, InitialVelocity};
    let text =
        variant("tumbler", &[("operator = \"SBP424\"", "operator = \"sbp424\"\nformulation = \"Full\"\ninitial_velocity = \"NATURAL\"")])
            + "\n[solver]\nbackend = \"Newton\"\nhessian = \"Zero\"\n";
    let scene = SceneFile::parse(&text, "s.toml").unwrap().resolve(&Overrides::default()).unwrap();
    assert_eq!(scene.solver.backend, Backend::Newton);
    assert_eq!(scene.formulation, Formulation::Full);
    assert_eq!(scene.initial_velocity, InitialVelocity::Natural);
    assert_eq!(scene.solver.hessian, HessianMode::Zero);
    let e = parse_error(&text.replace("\"Newton\"", "\"newtonian\""));
    assert!(e.contains("unknown backend `newtonian` (expected `ipopt` or `newton`)"), "{e}");
}

/// The error of resolving `text` (as `s.toml`) with `ov`.
fn resolve_error(text: &str, ov: &Overrides) -> String {
    match SceneFile::parse(text, "s.toml").unwrap().resolve(ov) {
        Ok(_) => panic!("resolved:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// Windows that do not fit the grid are refused when the scene is read, at the key's
/// line and column (before the fix: at solve time, with the file alone), and huge or
/// tiny numbers are printed in exponent form (before: a window of 1e-300 s printed 300
/// digits).
#[test]
fn windows_that_do_not_fit_are_refused_at_their_line_with_readable_numbers() {
    // The damped oscillator: 10 s on 512 nodes, Δt = 10/511 s.
    let oscillator = |extra: &str| variant("damped_oscillator", &[("nodes = 512", &format!("nodes = 512\n{extra}"))]);
    let no = Overrides::default();
    for (extra, needle, key, expect) in [
        ("window = 1e-300", "window = 1e-300", "window", "a window of 1e-300 s has 1 nodes"),
        ("window = 0.05", "window = 0.05", "window", "a window of 0.05 s has 4 nodes"),
        ("window = 2\noverlap = 1e300", "overlap = 1e300", "overlap", "shorter than the window (2 s), got 1e300"),
        ("window = 2\noverlap = 1.999", "overlap = 1.999", "overlap", "an overlap of 1.999 s leaves nothing to keep of a 2 s window"),
        ("window = -1e300", "window = -1e300", "window", "time.window must be a positive number of seconds, got -1e300"),
    ] {
        let text = oscillator(extra);
        let e = resolve_error(&text, &no);
        let at = format!("s.toml:{}:{}: ", line_of(&text, needle), key.len() + 4);
        assert!(e.starts_with(&at) && e.contains(expect), "{extra}: {e}");
        assert!(e.len() < 400, "{extra}: {e}");
    }
    // From the command line: the option and its value.
    let text = std::fs::read_to_string(common::scenario("damped_oscillator")).unwrap();
    let e = resolve_error(&text, &Overrides { window: Some(1e-300), ..Overrides::default() });
    assert!(e.starts_with("--window 1e-300: a window of 1e-300 s has 1 nodes"), "{e}");
}

/// An overlap without a window does nothing: it is refused (before the fix it was
/// accepted without a word); `--window 0`, which turns the scene's windows off, keeps
/// its overlap quiet.
#[test]
fn an_overlap_without_a_window_is_refused() {
    let text = variant("damped_oscillator", &[("nodes = 512", "nodes = 512\noverlap = 0.5")]);
    let e = resolve_error(&text, &Overrides::default());
    let at = format!("s.toml:{}:11: ", line_of(&text, "overlap = 0.5"));
    assert!(e.starts_with(&at) && e.contains("without a window"), "{e}");
    let plain = std::fs::read_to_string(common::scenario("damped_oscillator")).unwrap();
    let e = resolve_error(&plain, &Overrides { overlap: Some(0.5), ..Overrides::default() });
    assert!(e.starts_with("--overlap 0.5: ") && e.contains("without a window"), "{e}");
    let windowed = variant("damped_oscillator", &[("nodes = 512", "nodes = 512\nwindow = 2\noverlap = 0.5")]);
    let off = Overrides { window: Some(0.0), ..Overrides::default() };
    let scene = SceneFile::parse(&windowed, "s.toml").unwrap().resolve(&off).unwrap();
    assert!(scene.windows.is_none() && scene.notes.is_empty());
    // --overlap with --window 0 is an overlap without a window.
    let e = resolve_error(&windowed, &Overrides { window: Some(0.0), overlap: Some(0.5), ..Overrides::default() });
    assert!(e.starts_with("--overlap 0.5: ") && e.contains("without a window"), "{e}");
}

/// A window not shorter than the span is one global solve, and the scene says so in a
/// note (before the fix: not a word).
#[test]
fn a_window_longer_than_the_span_is_one_solve_with_a_note() {
    let text = variant("damped_oscillator", &[("nodes = 512", "nodes = 512\nwindow = 30")]);
    let scene = SceneFile::parse(&text, "s.toml").unwrap().resolve(&Overrides::default()).unwrap();
    assert_eq!(scene.windows, None);
    assert_eq!(scene.notes.len(), 1, "{:?}", scene.notes);
    assert!(scene.notes[0].contains("time.window = 30 s is not shorter than the time span (10 s)"), "{:?}", scene.notes);
    let text = variant("damped_oscillator", &[("nodes = 512", "nodes = 512\nwindow = 2.5")]);
    let scene = SceneFile::parse(&text, "s.toml").unwrap().resolve(&Overrides::default()).unwrap();
    assert!(scene.windows.is_some() && scene.notes.is_empty());
}

/// A linear solver Ipopt cannot load is an input error at the key that names it, with
/// the hint that Debian's Ipopt has only MUMPS, in `[solver]` and in `[solver.ipopt]`
/// (before the fix the latter gave a generic Invalid_Option for the whole file).
#[cfg(feature = "ipopt")]
#[test]
fn a_linear_solver_ipopt_cannot_load_is_refused_at_its_line_with_the_mumps_hint() {
    for (table, key) in [("[solver]", "[solver] linear_solver"), ("[solver.ipopt]", "[solver.ipopt] linear_solver")] {
        let text = std::fs::read_to_string(common::scenario("tumbler")).unwrap() + &format!("\n{table}\nlinear_solver = \"ma57\"\n");
        let mut scene = SceneFile::parse(&text, "s.toml").unwrap().resolve(&Overrides::default()).unwrap();
        scene.solver.print_level = 0;
        let e = match skg_core::solve::solve_scene(&scene) {
            Ok(o) => panic!("{table}: solved: {}", o.status),
            Err(e) => e.to_string(),
        };
        let at = format!("s.toml:{}:17: ", line_of(&text, "linear_solver = \"ma57\""));
        assert!(e.starts_with(&at) && e.contains(&format!("{key} = \"ma57\"")) && e.contains("only MUMPS"), "{table}: {e}");
    }
}

/// Numbers in messages are printed in exponent form when huge or tiny (before the fix a
/// strength of -1e300 printed 301 digits), as the neighbours of the window's message.
#[test]
fn huge_numbers_in_messages_are_printed_in_exponent_form() {
    let tumbler = |from: &str, to: &str| variant("tumbler", &[(from, to)]);
    for (text, expect) in [
        (tumbler("strength = \"V0/2\"", "strength = -1e300"), "strength must be ≥ 0, got -1e300"),
        (tumbler("width = \"sigma\"", "width = -1e300"), "width σ must be > 0, got -1e300"),
        (tumbler("tol = 1e-4", "tol = -1e300"), "the verification tolerance must be a positive number, got -1e300"),
        (tumbler("tol = 1e-4", "tol = 1e-4\n[solver]\ntol = -1e300"), "solver.tol must be a positive number, got -1e300"),
        (tumbler("initial = -0.5", "initial = -1e300"), "(x = -1e300, y = -0.75"),
    ] {
        let e = refusal(&text);
        assert!(e.contains(expect) && e.len() < 300, "{e}");
    }
}
