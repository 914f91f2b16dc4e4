//! Exact derivatives against central finite differences, on random points of every
//! shipped scene, and the squareness / nonsingularity of the discrete systems, with both
//! ways of imposing the initial velocity.

mod common;

use nalgebra::DMatrix;
use skg_core::discrete::action::{Action, Block};
use skg_core::scene::{InitialVelocity, Overrides};
use skg_core::solve::build_action;

/// Dense matrix from a planned block.
fn dense(action: &Action, block: Block, z: &[f64], rows: usize, cols: usize) -> DMatrix<f64> {
    let plan = action.plan(block);
    let mut vals = vec![0.0; plan.structure.len()];
    let mut ws = action.model.workspace();
    action.matrix_values(&plan, z, &mut vals, &mut ws);
    let mut m = DMatrix::zeros(rows, cols);
    for (&(r, c), v) in plan.structure.iter().zip(&vals) {
        m[(r as usize, c as usize)] += v;
        if block == Block::ReducedHessian && r != c {
            m[(c as usize, r as usize)] += v;
        }
    }
    m
}

/// Scale rows, then columns, to unit max-norm: the rank is unchanged, and the
/// singular values no longer mix the stiff wall rows with the mass rows.
fn equilibrate(mut m: DMatrix<f64>) -> DMatrix<f64> {
    for mut r in m.row_iter_mut() {
        let s = r.amax();
        if s > 0.0 {
            r /= s;
        }
    }
    for mut c in m.column_iter_mut() {
        let s = c.amax();
        if s > 0.0 {
            c /= s;
        }
    }
    m
}

const INITIAL_VELOCITIES: [InitialVelocity; 2] = [InitialVelocity::Strong, InitialVelocity::Natural];

fn small_action(name: &str, initial_velocity: InitialVelocity) -> Action {
    // Nodes: the smallest grid on which every operator of the test has interior rows.
    let ov = Overrides { nodes: Some(12), initial_velocity: Some(initial_velocity), ..Default::default() };
    build_action(&common::load(name, &ov)).unwrap()
}

fn check_close(what: &str, exact: f64, fd: f64, scale: f64) {
    let tol = 1e-6 * scale.max(1.0);
    assert!((exact - fd).abs() <= tol, "{what}: exact {exact:e} vs finite difference {fd:e} (tol {tol:e})");
}

#[test]
fn gradient_matches_finite_differences_of_the_action() {
    for (name, iv) in common::SHIPPED.iter().flat_map(|n| INITIAL_VELOCITIES.map(|iv| (n, iv))) {
        let action = small_action(name, iv);
        let name = format!("{name} ({iv})");
        let mut rng = common::Rng(0x9e3779b97f4a7c15);
        let mut ws = action.model.workspace();
        let z = common::random_point(&action, &mut rng);
        let mut grad = vec![0.0; z.len()];
        action.gradient(&z, false, &mut grad, &mut ws);
        let scale = grad.iter().fold(0.0_f64, |m, g| m.max(g.abs()));
        for i in 0..z.len() {
            let h = 1e-6 * (1.0 + z[i].abs());
            let mut zp = z.clone();
            zp[i] += h;
            let mut zm = z.clone();
            zm[i] -= h;
            let fd = (action.value(&zp, &mut ws) - action.value(&zm, &mut ws)) / (2.0 * h);
            check_close(&format!("{name}: dS/dz[{i}]"), grad[i], fd, scale);
        }
        // The reduced residual is the minus rows of the full gradient.
        let mut r = vec![0.0; action.layout.n_m];
        action.gradient(&z, true, &mut r, &mut ws);
        assert_eq!(r, grad[action.layout.n_p..].to_vec(), "{name}: reduced residual");
    }
}

#[test]
fn jacobians_and_hessian_match_finite_differences_of_the_gradient() {
    for (name, iv) in common::SHIPPED.iter().flat_map(|n| INITIAL_VELOCITIES.map(|iv| (n, iv))) {
        let action = small_action(name, iv);
        let name = format!("{name} ({iv})");
        let lay = &action.layout;
        let (n_p, len) = (lay.n_p, lay.len());
        let mut rng = common::Rng(0x2545f4914f6cdd1d);
        let mut ws = action.model.workspace();
        let z = common::random_point(&action, &mut rng);
        let full = dense(&action, Block::FullJacobian, &z, len, len);
        let mut fd = DMatrix::zeros(len, len);
        for j in 0..len {
            let h = 1e-6 * (1.0 + z[j].abs());
            let (mut zp, mut zm) = (z.clone(), z.clone());
            zp[j] += h;
            zm[j] -= h;
            let (mut gp, mut gm) = (vec![0.0; len], vec![0.0; len]);
            action.gradient(&zp, false, &mut gp, &mut ws);
            action.gradient(&zm, false, &mut gm, &mut ws);
            for i in 0..len {
                fd[(i, j)] = (gp[i] - gm[i]) / (2.0 * h);
            }
        }
        let scale = fd.amax();
        for i in 0..len {
            for j in 0..len {
                check_close(&format!("{name}: d2S/dz[{i}]dz[{j}]"), full[(i, j)], fd[(i, j)], scale);
            }
        }
        // The full Jacobian is the Hessian of S: symmetric.
        assert!((&full - full.transpose()).amax() <= 1e-12 * scale.max(1.0), "{name}: asymmetric Hessian");
        // Reduced Jacobian = the (M, P) block; reduced Hessian = the (P, P) block at M = y.
        let jac = dense(&action, Block::ReducedJacobian, &z, lay.n_m, n_p);
        assert!((&jac - full.view((n_p, 0), (lay.n_m, n_p))).amax() <= 1e-12 * scale.max(1.0), "{name}: reduced Jacobian");
        let hess = dense(&action, Block::ReducedHessian, &z, n_p, n_p);
        assert!((&hess - full.view((0, 0), (n_p, n_p))).amax() <= 1e-12 * scale.max(1.0), "{name}: reduced Hessian");
    }
}

#[test]
fn discrete_systems_are_square_and_nonsingular_at_small_n() {
    for (name, iv) in common::SHIPPED.iter().flat_map(|n| INITIAL_VELOCITIES.map(|iv| (n, iv))) {
        for (op, nodes) in [("SBP121", 8), ("SBP242", 8), ("SBP363", 12), ("SBP484", 16)] {
            let ov = Overrides { initial_velocity: Some(iv), ..common::grid(nodes, op) };
            let scene = common::load(name, &ov);
            let action = build_action(&scene).unwrap();
            let lay = &action.layout;
            let op = format!("{op} ({iv})");
            assert_eq!(lay.n_p, lay.n_m, "{name} {op}: not square");
            // The strong condition adds the multipliers ν_q1, ν_λ1 and ν_v and pins λ+[1].
            let boundary = match iv {
                InitialVelocity::Strong => 2 * lay.d,
                InitialVelocity::Natural => lay.d,
            };
            assert_eq!(lay.n_p, nodes * lay.d + nodes * lay.n + boundary, "{name} {op}: unknowns");
            // At the time-stepping solution (a point near the critical point).
            let (times, _) = skg_core::solve::grid(&scene);
            let states =
                skg_core::stepping::equations::integrate_model(&action.model, action.q0(), action.v0(), &times, &Default::default())
                    .unwrap()
                    .states;
            let (q, lam) = (states.q, states.lambda);
            let mut z = vec![0.0; lay.len()];
            for k in 0..nodes {
                for i in 0..lay.d {
                    z[lay.qp[k * lay.d + i] as usize] = q[k][i];
                }
                for a in 0..lay.n {
                    if lay.lp[k * lay.n + a] != u32::MAX {
                        z[lay.lp[k * lay.n + a] as usize] = lam[k][a];
                    }
                }
            }
            let jac = equilibrate(dense(&action, Block::ReducedJacobian, &z, lay.n_m, lay.n_p));
            let sv = jac.singular_values();
            let (smax, smin) = (sv.max(), sv.min());
            assert!(smin > 1e-10 * smax, "{name} {op}: reduced Jacobian singular (σ_min/σ_max = {:e})", smin / smax);
            let full = equilibrate(dense(&action, Block::FullJacobian, &z, lay.len(), lay.len()));
            let sv = full.singular_values();
            assert!(sv.min() > 1e-10 * sv.max(), "{name} {op}: full Jacobian singular");
        }
    }
}

/// The exact Jacobian `∂(v, q̈)/∂(q, v)` of the time stepping's right-hand side
/// (`Model::state_jacobian`, the saddle-point solve differentiated) against central
/// differences of the accelerations, at random states: every shipped scene (position
/// and velocity constraints, walls with friction, forces depending on time), a damped
/// spring, a chain of rigid links, and stiff scenes (a damped nonholonomic disk, a chain
/// on stiff springs). On a scene with walls, half the states are put inside a wall's
/// width, where its force acts.
#[test]
fn the_state_jacobian_matches_finite_differences_of_the_accelerations() {
    use skg_core::model::Model;
    let stiff = |name: &str| {
        let path = common::root().join("crates/skg-core/tests/scenes/stiff").join(format!("{name}.toml"));
        skg_core::scene::SceneFile::load(&path).unwrap().resolve(&Overrides::default()).unwrap()
    };
    let mut scenes: Vec<(String, _)> = common::SHIPPED.iter().map(|n| (n.to_string(), common::load(n, &Overrides::default()))).collect();
    for name in ["damped_oscillator", "chain4"] {
        scenes.push((name.to_string(), common::load(name, &Overrides::default())));
    }
    for name in ["damped_yaw_disk", "stiff_chain"] {
        scenes.push((name.to_string(), stiff(name)));
    }
    let mut rng = common::Rng(0x2545_f491_4f6c_dd1d);
    for (name, scene) in &scenes {
        let model = Model::build(scene).unwrap();
        let d = model.layout.d;
        let mut ws = model.workspace();
        for sample in 0..6 {
            let t = scene.t_start + rng.uniform() * (scene.t_end - scene.t_start);
            let mut q: Vec<f64> = scene.initial_q.iter().map(|x| x + 0.05 * rng.signed()).collect();
            let v: Vec<f64> = scene.initial_v.iter().map(|x| x + 0.5 * rng.signed()).collect();
            if !model.walls.is_empty() && sample % 2 == 1 {
                // One Newton step to a gap of −σ·u, u in [0, 2): inside the wall's width.
                let j = rng.below(model.walls.len());
                let target = -model.walls[j].width * 2.0 * rng.uniform();
                let h = model.wall_gaps(t, &q)[j];
                let n = model.wall_normal(j, t, &q);
                let nn: f64 = n.iter().map(|x| x * x).sum();
                q.iter_mut().zip(&n).for_each(|(x, ni)| *x -= (h - target) * ni / nn);
            }
            let mut jac = DMatrix::zeros(2 * d, 2 * d);
            model.state_jacobian(t, &q, &v, &mut ws, &mut jac).unwrap();
            for c in 0..2 * d {
                let x = if c < d { q[c] } else { v[c - d] };
                let step = 1e-6 * (1.0 + x.abs());
                let mut at = |delta: f64| {
                    let (mut qs, mut vs) = (q.clone(), v.clone());
                    if c < d {
                        qs[c] += delta;
                    } else {
                        vs[c - d] += delta;
                    }
                    model.accelerations(t, &qs, &vs, &mut ws).unwrap().0
                };
                let (plus, minus) = (at(step), at(-step));
                for i in 0..d {
                    let fd = (plus[i] - minus[i]) / (2.0 * step);
                    // Relative to the row's largest entry: a stiff row holds entries of order k.
                    let scale = (0..2 * d).map(|k| jac[(d + i, k)].abs()).fold(1.0, f64::max);
                    let exact = jac[(d + i, c)];
                    assert!(
                        (exact - fd).abs() <= 1e-6 * scale,
                        "{name}, state {sample}: ∂a_{i}/∂x_{c} exact {exact:e}, finite difference {fd:e} (row scale {scale:e})"
                    );
                }
                // The kinematic rows: ∂q̇/∂(q, v) = [0 I].
                for i in 0..d {
                    assert_eq!(jac[(i, c)], if c == d + i { 1.0 } else { 0.0 }, "{name}: ∂q̇_{i}/∂x_{c}");
                }
            }
        }
    }
}

/// The accelerations and multipliers the time stepping uses (`Model::accelerations`,
/// assembled and solved in place) satisfy the index-reduced system written out from the
/// physical quantities with nalgebra:
/// `W q̈ + Gᵀ λ = f + F − (∂p/∂q) v − ∂p/∂t` and `G q̈ = −(∂g/∂q) v − ∂g/∂t`, at random
/// states of every shipped scene, the rigid chain and a stiff scene.
#[test]
fn the_accelerations_solve_the_index_reduced_system() {
    let mut scenes: Vec<(String, _)> = common::SHIPPED.iter().map(|n| (n.to_string(), common::load(n, &Overrides::default()))).collect();
    scenes.push(("chain4".to_string(), common::load("chain4", &Overrides::default())));
    let path = common::root().join("crates/skg-core/tests/scenes/stiff/damped_yaw_disk.toml");
    scenes.push(("damped_yaw_disk".to_string(), skg_core::scene::SceneFile::load(&path).unwrap().resolve(&Overrides::default()).unwrap()));
    let mut rng = common::Rng(0x9e37_79b9_7f4a_7c15);
    for (name, scene) in &scenes {
        let model = skg_core::model::Model::build(scene).unwrap();
        let mut ws = model.workspace();
        for sample in 0..6 {
            let t = scene.t_start + rng.uniform() * (scene.t_end - scene.t_start);
            let q: Vec<f64> = scene.initial_q.iter().map(|x| x + 0.05 * rng.signed()).collect();
            let v: Vec<f64> = scene.initial_v.iter().map(|x| x + 0.5 * rng.signed()).collect();
            let (a, lambda) = model.accelerations(t, &q, &v, &mut ws).unwrap();
            let ph = model.physical(t, &q, &v, &mut ws);
            let (a, lambda) = (nalgebra::DVector::from_column_slice(&a), nalgebra::DVector::from_column_slice(&lambda));
            let dynamics = &ph.kinetic * &a + ph.gv.transpose() * &lambda - ph.free_force(&v);
            let constraints = &ph.gv * &a - ph.constraint_acceleration(&v);
            // Relative to the size of the terms of each row.
            let scale = 1.0 + ph.kinetic.abs().max() * a.amax() + ph.gv.abs().max() * (a.amax() + lambda.amax()) + ph.free_force(&v).amax();
            for (i, r) in dynamics.iter().chain(constraints.iter()).enumerate() {
                assert!(
                    r.abs() <= 1e-12 * scale,
                    "{name}, state {sample}: row {i} of [W Gᵀ; G 0] [q̈; λ] = rhs is off by {r:e} (scale {scale:e})"
                );
            }
        }
    }
}
