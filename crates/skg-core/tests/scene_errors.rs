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
    let e = refusal(&pendulum("1e300*(x^2 + y^2 - l^2)", "\n\n[[constraints]]\nname = \"rod2\"\nexpression = \"1e-300*(x^2 + y^2 - l^2)\""));
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
