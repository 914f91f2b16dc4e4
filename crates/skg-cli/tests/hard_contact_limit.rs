//! The hard-contact limit as a sweep (`[sweep] reference = "hard_walls"`): each point's
//! `error_max` is measured against the event-driven hard-wall reference on the point's
//! own grid (its model error), beside `verify_error` (its discretization error); checked
//! against the closed-form bounces of a ball on a hard floor, and `plot errors` charts
//! both. A scene the hard-wall reference does not model is refused before any point runs.

mod common;

use std::path::Path;

use skg_core::check::Table;
use skg_sweep::{Results, SweepFile};

/// Standard gravity of the test scene.
const G: f64 = 9.8;

/// The ball of `ball_on_thin_floor.toml` (dropped at rest from 1 m) on a hard elastic
/// floor: free fall until `t_f = √(2/g)`, then bounces of period `2 t_f` with the impact
/// speed `g t_f`.
fn hard_floor(t: f64) -> f64 {
    let fall = (2.0 / G).sqrt();
    if t < fall {
        return 1.0 - G * t * t / 2.0;
    }
    let u = (t - fall) % (2.0 * fall);
    G * fall * u - G * u * u / 2.0
}

/// The cell of `row` in column `name`.
fn cell<'a>(r: &Results, row: &'a [String], name: &str) -> &'a str {
    &row[r.column_index(name).unwrap_or_else(|| panic!("no column {name} in {:?}", r.header))]
}

fn number(r: &Results, row: &[String], name: &str) -> f64 {
    cell(r, row, name).parse().unwrap_or_else(|_| panic!("{name} = {:?} is not a number", cell(r, row, name)))
}

/// Two wall widths of the ball on a thin floor, each refined to a loose tolerance: every
/// row's `error_max` is the distance of its kept trajectory from the closed-form hard
/// bounces (the end nodes left out as `skip_last` says), the model error falls with σ and
/// stays far above the discretization error, which meets the tolerance.
#[test]
fn a_hard_walls_sweep_measures_the_model_error_against_the_closed_form_bounce() {
    let dir = tempfile::tempdir().unwrap();
    let body = "reference = \"hard_walls\"\nrefine = true\nkeep_trajectories = true\n\
                [[grid]]\noperator = \"auto\"\nverify_tol = 1e-3\nsigma = [1e-2, 1e-3]\n";
    let sweep = common::sweep_file(dir.path(), &common::test_scene("ball_on_thin_floor"), body);
    let out = dir.path().join("out");
    let (code, text) = common::run(&["sweep", common::s(&sweep), "-o", common::s(&out), "-q"], Path::new("."));
    assert_eq!(code, Some(0), "{text}");
    let r = Results::read(&out).unwrap();
    assert_eq!(r.rows.len(), 2);
    let mut model_errors = Vec::new();
    for row in &r.rows {
        assert_eq!(cell(&r, row, "status"), "converged", "{row:?}");
        let solution = Table::read(&out.join("points").join(cell(&r, row, "id")).join("trajectory.csv")).unwrap();
        let y = solution.columns.iter().position(|c| c == "y").unwrap();
        let compared = solution.rows.len() - 2;
        let truth = solution.rows[..compared].iter().map(|v| (v[y] - hard_floor(v[0])).abs()).fold(0.0, f64::max);
        let (model, discretization) = (number(&r, row, "error_max"), number(&r, row, "verify_error"));
        assert!(
            (model - truth).abs() <= 1e-7 * (1.0 + truth),
            "sigma {}: error_max {model:e}, closed form {truth:e}",
            cell(&r, row, "sigma")
        );
        assert_eq!(cell(&r, row, "error_column"), "y");
        assert!(discretization <= 1e-3, "verify_error {discretization:e}");
        model_errors.push((number(&r, row, "sigma"), model, discretization));
    }
    model_errors.sort_by(|a, b| a.0.total_cmp(&b.0));
    let [(_, thin, thin_discretization), (_, wide, _)] = model_errors[..] else { unreachable!() };
    assert!(thin < 0.3 * wide, "model error {thin:e} at σ = 1e-3 against {wide:e} at 1e-2");
    assert!(thin > 3.0 * thin_discretization, "model error {thin:e}, discretization error {thin_discretization:e}");

    // The chart of both against σ.
    let stem = dir.path().join("limit");
    let (code, text) = common::run(&["plot", "errors", common::s(&out), "--x", "sigma", "-o", common::s(&stem)], Path::new("."));
    assert_eq!(code, Some(0), "{text}");
    let svg = std::fs::read_to_string(stem.with_extension("svg")).unwrap();
    assert!(svg.contains("model error") && svg.contains("verify_error"), "{}", &svg[..svg.len().min(400)]);
    assert!(stem.with_extension("png").is_file());
}

/// `reference = "hard_walls"` on a scene without walls is refused before any point runs,
/// at the `reference` key of the sweep file, naming the scene's reason; exit status 1.
#[test]
fn a_hard_walls_sweep_of_a_scene_without_walls_is_refused_where_it_is_asked() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = common::sweep_file(dir.path(), &common::scenario("free_fall"), "reference = \"hard_walls\"\n[[grid]]\nnodes = [16]\n");
    let err = SweepFile::load(&sweep).unwrap().expand().unwrap_err().to_string();
    let at = format!("{}:3:13", sweep.display());
    assert!(err.starts_with(&at) && err.contains("has no walls"), "expected `{at}: … has no walls`, got: {err}");
    let out = dir.path().join("out");
    let (code, text) = common::run(&["sweep", common::s(&sweep), "-o", common::s(&out)], Path::new("."));
    assert_eq!(code, Some(1), "{text}");
    assert!(text.contains("sweep.toml:3:13") && text.contains("no walls"), "{text}");
    assert!(!out.join("results.csv").exists(), "no point may run");
}
