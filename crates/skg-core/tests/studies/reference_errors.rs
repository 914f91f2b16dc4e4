//! The errors of the accuracy studies of docs/validation.md, shared by
//! `tests/regression.rs` and `examples/reference_convergence_study.rs` (each includes
//! this file by its path, beside `tests/common/mod.rs` as `common`): the discretization
//! error of a solve against the regularized reference, and the tumbler's model error
//! against the hard-wall reference.
#![allow(dead_code)]

use skg_core::check::{self, CheckOptions, Table};
use skg_core::scene::{Overrides, Scene};
use skg_core::solve::{self, Outcome};
use skg_core::stepping::reference::{self, ReferenceOptions};

use crate::common;

/// The solver's trajectory as a [`Table`] (the CSV it would write).
pub fn table(scene: &Scene, o: &Outcome) -> Table {
    Table::of_trajectory(scene, &o.trajectory)
}

/// A reference's trajectory as a [`Table`].
pub fn ref_table(scene: &Scene, r: &reference::Reference) -> Table {
    Table::of_trajectory(scene, &r.trajectory)
}

/// Max error of the coordinates (not velocities) of a solve of `name` on `nodes` with
/// `op` against the regularized reference on the same grid, last two nodes excluded (the
/// end nodes' benign boundary error), with the outcome; NaN if the solve did not converge.
pub fn try_discretization_error(name: &str, nodes: usize, op: &str) -> (f64, Outcome) {
    let ov = common::grid(nodes, op);
    let scene = common::load(name, &ov);
    let o = solve::solve_scene(&scene).unwrap();
    if !o.converged() {
        return (f64::NAN, o);
    }
    let (times, _) = solve::grid(&scene);
    let r = reference::regularized(&scene, &times, &ReferenceOptions::default()).unwrap();
    let cmp = check::compare(
        &table(&scene, &o),
        &ref_table(&scene, &r),
        &CheckOptions { skip_last: 2, columns: Some(scene.coordinates.clone()) },
    )
    .unwrap();
    assert_eq!(cmp.rows_interpolated, 0);
    (cmp.max_abs, o)
}

/// Max error of the tumbler's x, y at `sigma` on `nodes` (one solve, no fallback ladder)
/// against its hard-wall reference (the model error) and against its regularized
/// reference (the discretization error), in that order.
pub fn model_error(sigma: &str, nodes: usize) -> (f64, f64) {
    let ov = Overrides { set: vec![("sigma".into(), sigma.into())], nodes: Some(nodes), no_fallback: true, ..Default::default() };
    let scene = common::load("tumbler", &ov);
    let o = common::solve("tumbler", &ov);
    let (times, _) = solve::grid(&scene);
    let hard = reference::hard_wall(&scene, &times, &ReferenceOptions::default()).unwrap();
    let reg = reference::regularized(&scene, &times, &ReferenceOptions::default()).unwrap();
    let opts = CheckOptions { skip_last: 0, columns: Some(vec!["x".into(), "y".into()]) };
    let sol = table(&scene, &o);
    let m = check::compare(&sol, &ref_table(&scene, &hard), &opts).unwrap().max_abs;
    let d = check::compare(&sol, &ref_table(&scene, &reg), &opts).unwrap().max_abs;
    (m, d)
}
