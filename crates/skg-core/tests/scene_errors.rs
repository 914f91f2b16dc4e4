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
