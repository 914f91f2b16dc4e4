//! A fit's model, whose free parameters stay symbolic (`Model::with_free_parameters`),
//! against independent truth: at other parameter values its residual is the residual of
//! the scene resolved with those values (`--set`, where every parameter is a number
//! folded into the expressions), and its derivatives in the parameters (the residual's
//! Jacobian, the Hessian blocks (θ, P) and (θ, θ)) are the central finite differences of
//! its residual and of its exact derivatives in the trajectory. The parameters reach the
//! action through every path: the Lagrangian, a force, a velocity constraint, a
//! position constraint, a wall's gap, numbers and friction direction, a parameter
//! defined through a free one, and the initial state (both initial-velocity conditions).

mod common;

use std::sync::Arc;

use nalgebra::DMatrix;
use skg_core::discrete::action::{Action, Block};
use skg_core::discrete::Discretization;
use skg_core::model::Model;
use skg_core::scene::{InitialVelocity, Overrides, Scene, SceneFile};
use skg_core::solve::{action_on, build_action};

/// A damped, driven oscillator whose initial state, mass, stiffness, damping and drive
/// frequency are parameters; the drive's frequency is a parameter defined through two
/// others.
const OSCILLATOR: &str = r#"
[scene]
name = "oscillator"
lagrangian = "1/2*m*x_dot^2 - 1/2*k*x^2 + A*x*cos(w*t)"
[parameters]
m = 1.3
k = 4
c = 0.3
A = 0.5
w = "sqrt(k/m)/2"
x0 = 0.7
v0 = -0.4
[[coordinates]]
name = "x"
initial = "x0"
velocity = "2*v0"
[forces]
x = "-c*x_dot"
[time]
start = 0.5
end = 3
nodes = 12
"#;

/// A point sliding on a rough incline of angle alpha with a Gaussian wall: the angle is
/// in the gap, the friction direction and the initial position.
fn incline() -> (&'static str, Vec<&'static str>) {
    ("incline_friction", vec!["mu", "alpha", "sigma", "V0"])
}

/// The scenes of the test: a scene (file or text), its free parameters.
fn cases() -> Vec<(String, Vec<String>)> {
    let (incline, free) = incline();
    vec![
        (OSCILLATOR.to_string(), ["m", "k", "c", "x0", "v0", "w"].map(String::from).to_vec()),
        (OSCILLATOR.to_string(), ["k", "v0"].map(String::from).to_vec()),
        (incline.to_string(), free.into_iter().map(String::from).collect()),
        ("rolling_disk".to_string(), ["alpha", "IS", "g"].map(String::from).to_vec()),
        ("pendulum".to_string(), ["theta0", "l", "g"].map(String::from).to_vec()),
        // Friction against the velocity (no declared direction).
        (std::fs::read_to_string(common::test_scene("friction_stop")).unwrap(), ["mu", "A"].map(String::from).to_vec()),
    ]
}

fn load(scene: &str, ov: &Overrides) -> Scene {
    if scene.contains('\n') {
        SceneFile::parse(scene, "oscillator.toml").unwrap().resolve(ov).unwrap()
    } else {
        common::load(scene, ov)
    }
}

fn overrides(iv: InitialVelocity, set: Vec<(String, String)>) -> Overrides {
    Overrides { nodes: Some(12), initial_velocity: Some(iv), set, ..Default::default() }
}

/// The action of the fit's model of `scene` with `free` symbolic.
fn fit_action(scene: &Scene, free: &[String]) -> Action {
    let model = Arc::new(Model::with_free_parameters(scene, free).unwrap());
    let disc = Discretization::of(scene);
    action_on(&model, scene, &disc, &disc.times(scene)).unwrap()
}

fn residual(action: &Action, z: &[f64], ws: &mut skg_core::model::Workspace) -> Vec<f64> {
    let mut r = vec![0.0; action.layout.n_m];
    action.gradient(z, true, &mut r, ws);
    r
}

fn max_abs(v: impl IntoIterator<Item = f64>) -> f64 {
    v.into_iter().fold(0.0, |m, x| m.max(x.abs()))
}

#[test]
fn the_symbolic_model_at_other_values_is_the_scene_resolved_with_them() {
    for (scene_text, free) in cases() {
        for iv in [InitialVelocity::Strong, InitialVelocity::Natural] {
            let scene = load(&scene_text, &overrides(iv, vec![]));
            let mut action = fit_action(&scene, &free);
            let mut ws = action.model.workspace();
            let z = common::random_point(&action, &mut common::Rng(0x9e3779b97f4a7c15));
            // At the scene's own values the two models agree; so they do at other values.
            for scale in [1.0, 1.1, 0.93] {
                let theta: Vec<f64> = free.iter().map(|n| scene.parameters[n] * scale).collect();
                action.set_parameters(&theta, &mut ws);
                let set = free.iter().zip(&theta).map(|(n, x)| (n.clone(), format!("{x:?}"))).collect();
                let resolved = build_action(&load(&scene_text, &overrides(iv, set))).unwrap();
                let mut ws_resolved = resolved.model.workspace();
                let (a, b) = (residual(&action, &z, &mut ws), residual(&resolved, &z, &mut ws_resolved));
                let diff = max_abs(a.iter().zip(&b).map(|(x, y)| x - y));
                // Measured at most 1.8e-15 relative (the same arithmetic in another order); margin 50x.
                assert!(diff <= 1e-13 * max_abs(b.iter().copied()).max(1.0), "{} {free:?} ({iv}) at {scale}: {diff:e}", scene.name);
                assert_eq!(action.q0(), resolved.q0(), "{} ({iv}): initial positions", scene.name);
                assert_eq!(action.v0(), resolved.v0(), "{} ({iv}): initial velocities", scene.name);
            }
        }
    }
}

/// The plan's entries as a dense matrix (`symmetric`: the lower triangle mirrored).
fn dense(structure: &[(u32, u32)], values: &[f64], rows: usize, cols: usize, symmetric: bool) -> DMatrix<f64> {
    let mut m = DMatrix::zeros(rows, cols);
    for (&(r, c), v) in structure.iter().zip(values) {
        m[(r as usize, c as usize)] += v;
        if symmetric && r != c {
            m[(c as usize, r as usize)] += v;
        }
    }
    m
}

fn assert_close(what: &str, exact: &DMatrix<f64>, fd: &DMatrix<f64>) {
    let scale = fd.amax().max(1.0);
    let diff = (exact - fd).amax();
    // Central differences with steps of 1e-6 relative: truncation and round-off about
    // 1e-8 of the scale on these scenes (measured at most 2.6e-9); margin 40x.
    assert!(diff <= 1e-7 * scale, "{what}: max |exact − finite difference| = {diff:e} (scale {scale:e})\nexact {exact}\nfd {fd}");
}

#[test]
fn parameter_derivatives_match_finite_differences() {
    for (scene_text, free) in cases() {
        for iv in [InitialVelocity::Strong, InitialVelocity::Natural] {
            let scene = load(&scene_text, &overrides(iv, vec![]));
            let what = format!("{} {free:?} ({iv})", scene.name);
            let mut action = fit_action(&scene, &free);
            let mut ws = action.model.workspace();
            let lay = action.layout.clone();
            let (n_p, n_m, nt) = (lay.n_p, lay.n_m, free.len());
            let z = common::random_point(&action, &mut common::Rng(0x2545f4914f6cdd1d));
            let theta0: Vec<f64> = free.iter().map(|n| scene.parameters[n] * 1.05).collect();
            let plan = action.parameter_plan();
            let jac_plan = action.plan(Block::ReducedJacobian);
            // Exact: ∂R/∂θ, and the Hessian blocks of yᵀR at the minus block of z.
            action.set_parameters(&theta0, &mut ws);
            let mut values = vec![0.0; plan.jacobian.len()];
            action.parameter_jacobian(&plan, &z, &mut values, &mut ws);
            let jac_theta = dense(&plan.jacobian, &values, n_m, nt, false);
            let mut values = vec![0.0; plan.hessian.len()];
            action.parameter_hessian(&plan, &z, &mut values, &mut ws);
            let hess = dense(&plan.hessian, &values, n_p + nt, n_p + nt, true);
            // Finite differences in each parameter of R, of (∂R/∂P)ᵀy and of (∂R/∂θ)ᵀy.
            let y = &z[n_p..];
            let (mut fd_jac, mut fd_theta_p, mut fd_theta_theta) =
                (DMatrix::zeros(n_m, nt), DMatrix::zeros(nt, n_p), DMatrix::zeros(nt, nt));
            for j in 0..nt {
                let h = 1e-6 * theta0[j].abs().max(1e-3);
                let mut at = |delta: f64| {
                    let mut theta = theta0.clone();
                    theta[j] += delta;
                    action.set_parameters(&theta, &mut ws);
                    let r = residual(&action, &z, &mut ws);
                    let mut jv = vec![0.0; jac_plan.structure.len()];
                    action.matrix_values(&jac_plan, &z, &mut jv, &mut ws);
                    let jp = dense(&jac_plan.structure, &jv, n_m, n_p, false);
                    let mut tv = vec![0.0; plan.jacobian.len()];
                    action.parameter_jacobian(&plan, &z, &mut tv, &mut ws);
                    let jt = dense(&plan.jacobian, &tv, n_m, nt, false);
                    let yv = nalgebra::DVector::from_column_slice(y);
                    (nalgebra::DVector::from_vec(r), jp.transpose() * &yv, jt.transpose() * &yv)
                };
                let (rp, gp, tp) = at(h);
                let (rm, gm, tm) = at(-h);
                fd_jac.set_column(j, &((rp - rm) / (2.0 * h)));
                fd_theta_p.set_row(j, &((gp - gm) / (2.0 * h)).transpose());
                fd_theta_theta.set_row(j, &((tp - tm) / (2.0 * h)).transpose());
            }
            assert_close(&format!("{what}: ∂R/∂θ"), &jac_theta, &fd_jac);
            assert_close(&format!("{what}: Hessian (θ, P)"), &hess.view((n_p, 0), (nt, n_p)).into_owned(), &fd_theta_p);
            assert_close(&format!("{what}: Hessian (θ, θ)"), &hess.view((n_p, n_p), (nt, nt)).into_owned(), &fd_theta_theta);
            assert!(jac_theta.amax() > 0.0, "{what}: the residual depends on the parameters");
        }
    }
}

/// A name that is not a parameter cannot be free; a model without free parameters has
/// no parameter tapes and an empty plan.
#[test]
fn free_names_must_be_parameters() {
    let scene = load(OSCILLATOR, &Overrides::default());
    let err = Model::with_free_parameters(&scene, &["kk".to_string()]).err().expect("refused");
    assert!(err.to_string().contains("`kk` is not a parameter of the scene"), "{err}");
    let action = build_action(&scene).unwrap();
    assert!(action.model.parameters.is_none());
    assert!(action.parameter_plan().jacobian.is_empty());
}
