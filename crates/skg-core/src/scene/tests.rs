//! Tests of reading and resolving scene files.

use super::*;
use crate::sbp::OperatorKind;

const MINIMAL: &str = r#"
[scene]
name = "free fall"
lagrangian = "1/2*m*x_dot^2 - m*g*x"

[parameters]
m = 1
g = 9.8
h0 = "2*g"

[[coordinates]]
name = "x"
initial = "h0"
velocity = 0

[time]
start = 0
end = 1
nodes = 16
"#;

#[test]
fn parameters_resolve_in_dependency_order_and_overrides_apply() {
    let f = SceneFile::parse(MINIMAL, "mem.toml").unwrap();
    let s = f.clone().resolve(&Overrides::default()).unwrap();
    assert_eq!(s.initial_q, vec![19.6]);
    let ov = Overrides { set: vec![("g".into(), "pi".into())], ..Default::default() };
    let s = f.resolve(&ov).unwrap();
    assert!((s.initial_q[0] - 2.0 * std::f64::consts::PI).abs() < 1e-15);
    assert_eq!(s.operator, OperatorKind::Sbp242);
    assert_eq!(s.formulation, Formulation::Reduced);
}

#[test]
fn unknown_key_reports_line_and_column() {
    let text = MINIMAL.replace("velocity = 0", "velocity = 0\nmass = 3");
    let err = SceneFile::parse(&text, "mem.toml").unwrap_err().to_string();
    assert!(err.contains("mem.toml:15:1"), "{err}");
    assert!(err.contains("mass"), "{err}");
}

#[test]
fn cyclic_and_unknown_parameters_are_errors() {
    let text = MINIMAL.replace("h0 = \"2*g\"", "h0 = \"2*k\"\nk = \"h0\"");
    let err = SceneFile::parse(&text, "mem.toml").unwrap().resolve(&Overrides::default()).unwrap_err();
    assert!(err.to_string().contains("cycle"), "{err}");
    let text = MINIMAL.replace("h0 = \"2*g\"", "h0 = \"2*gg\"");
    let err = SceneFile::parse(&text, "mem.toml").unwrap().resolve(&Overrides::default()).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("mem.toml:9:"), "{msg}");
    assert!(msg.contains("gg"), "{msg}");
}

#[test]
fn constraints_are_classified_by_whether_they_use_velocities() {
    let with = |expr: &str| {
        let text = MINIMAL.replace("[time]", &format!("[[constraints]]\nname = \"c\"\nexpression = \"{expr}\"\n\n[time]"));
        SceneFile::parse(&text, "mem.toml").unwrap().resolve(&Overrides::default())
    };
    assert_eq!(with("x_dot - t").unwrap().constraints[0].kind, ConstraintKind::Velocity);
    assert_eq!(with("x - sin(t)").unwrap().constraints[0].kind, ConstraintKind::Position);
    // x_dot − x_dot simplifies to 0: no coordinate, no velocity.
    let msg = with("x_dot - x_dot + t").unwrap_err().to_string();
    assert!(msg.contains("mem.toml:18:14") && msg.contains("depends on neither"), "{msg}");
    let msg = with("x + tt").unwrap_err().to_string();
    assert!(msg.contains("unknown symbol `tt`") && msg.contains("known names: x, x_dot, t, m, g, h0"), "{msg}");
}

#[test]
fn override_of_unknown_parameter_is_an_error() {
    let f = SceneFile::parse(MINIMAL, "mem.toml").unwrap();
    let ov = Overrides { set: vec![("nope".into(), "1".into())], ..Default::default() };
    let msg = f.resolve(&ov).unwrap_err().to_string();
    assert!(msg.contains("no parameter `nope`") && msg.contains("m, g, h0"), "{msg}");
}

/// The three ways a grid fails in floating point, each with its message as the scene
/// error states it (the text is unchanged from when the check returned a `String`).
#[test]
fn time_grids_not_resolved_by_floating_point_are_refused_with_their_reason() {
    use super::time::check_time_resolution;
    assert_eq!(check_time_resolution(0.0, 1.0, 16), Ok(()));
    let zero = check_time_resolution(1.0, 1.0, 3).unwrap_err();
    assert_eq!(
        zero.to_string(),
        "the time span end − start = 0e0 divided into 2 steps gives a zero time step: lengthen the span or use fewer nodes"
    );
    // 2e-100 / 2 is the double nearest 1e-100, the smallest step allowed.
    let tiny = check_time_resolution(0.0, 2e-100, 3).unwrap_err();
    assert_eq!(tiny.to_string(), "the time step Δt = 1e-100 is below 1e-100: the SBP derivative (∝ 1/Δt) would overflow; rescale time");
    // Near 2^52 the doubles are 1 apart: a step of 1 is not 4 units in the last place.
    let coarse = check_time_resolution(4503599627370494.0, 4503599627370496.0, 3).unwrap_err();
    assert_eq!(
        coarse.to_string(),
        "the time step Δt = (4.503599627370496e15 − 4.503599627370494e15)/2 = 1e0 is not resolved by floating-point numbers \
         near 4.503599627370496e15 (their spacing there is 1e0), so the 3 node times would not be distinct: measure time \
         from 0 (shift start and end), or use a longer span or fewer nodes"
    );
}

/// A scene built in code (as Python's `skg.Scene(mapping)`) reads as its file does,
/// and its errors name the field instead of a line of the generated text.
#[test]
fn a_scene_built_as_a_table_names_fields_in_errors() {
    let table: toml::Table = MINIMAL.parse().unwrap();
    let file = SceneFile::from_table(&table, "<python>").unwrap();
    let from_text = SceneFile::parse(MINIMAL, "mem.toml").unwrap();
    let (a, b) = (file.clone().resolve(&Overrides::default()).unwrap(), from_text.resolve(&Overrides::default()).unwrap());
    assert_eq!((a.initial_q, a.coordinates), (b.initial_q, b.coordinates));
    // the generated text is what the provenance hashes, and reads back as the same table
    assert_eq!(file.origin.text.parse::<toml::Table>().unwrap(), table);
    assert_eq!(file.origin.content_hash(), provenance::content_hash(file.origin.text.as_bytes()));

    let with = |edit: &dyn Fn(&mut toml::Table)| {
        let mut t = table.clone();
        edit(&mut t);
        SceneFile::from_table(&t, "<python>").and_then(|f| f.resolve(&Overrides::default())).unwrap_err().to_string()
    };
    let coordinate = |t: &mut toml::Table| t["coordinates"].as_array_mut().unwrap()[0].as_table_mut().unwrap().clone();
    let set_coordinates = |t: &mut toml::Table, c: Vec<toml::Table>| {
        t.insert("coordinates".into(), toml::Value::Array(c.into_iter().map(toml::Value::Table).collect()));
    };
    // an unknown parameter in the second coordinate's initial value (resolution)
    let msg = with(&|t| {
        let mut y = coordinate(t);
        y.insert("name".into(), "y".into());
        y.insert("initial".into(), "2*gg".into());
        let x = coordinate(t);
        set_coordinates(t, vec![x, y]);
    });
    assert!(msg.starts_with("<python>: coordinates[1].initial: "), "{msg}");
    assert!(msg.contains("gg"), "{msg}");
    // a value of the wrong type (the TOML parser)
    let msg = with(&|t| {
        t["time"].as_table_mut().unwrap().insert("nodes".into(), "many".into());
    });
    assert!(msg.starts_with("<python>: time.nodes: "), "{msg}");
    // an unknown key, and a missing one (located at the table)
    let msg = with(&|t| {
        t["scene"].as_table_mut().unwrap().insert("lagrangain".into(), "0".into());
    });
    assert!(msg.starts_with("<python>: scene.lagrangain: ") && msg.contains("unknown field"), "{msg}");
    let msg = with(&|t| {
        let mut x = coordinate(t);
        x.remove("velocity");
        set_coordinates(t, vec![x]);
    });
    assert!(msg.starts_with("<python>: coordinates[0]: ") && msg.contains("velocity"), "{msg}");
    // a constraint's expression: the field, then the expression with its caret
    let msg = with(&|t| {
        let mut c = toml::Table::new();
        c.insert("name".into(), "c".into());
        c.insert("expression".into(), "x + tt".into());
        t.insert("constraints".into(), toml::Value::Array(vec![toml::Value::Table(c)]));
    });
    assert!(msg.starts_with("<python>: constraints[0].expression: ") && msg.contains("unknown symbol `tt`"), "{msg}");
}

#[test]
fn the_reason_a_scene_file_cannot_be_read_is_said_once() {
    let e = SceneFile::load(std::path::Path::new("/nonexistent/scene.toml")).unwrap_err();
    assert_eq!(e.to_string(), "cannot read scene file /nonexistent/scene.toml: No such file or directory (os error 2)");
    assert!(std::error::Error::source(&e).is_none(), "{e}");
}
