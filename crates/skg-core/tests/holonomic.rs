//! Position (holonomic) constraints: the pendulum in Cartesian coordinates with the rod
//! `x² + y² − l² = 0` against the angle equation `θ̈ = −(g/l) sin θ`, integrated here
//! independently of the scene (docs/scenes.md).

mod common;

use common::G;
use skg_core::check::Table;
use skg_core::scene::Overrides;
use skg_core::solve::Outcome;
use skg_core::stepping::ode::{self, OdeOptions};

/// l, θ0 and m of scenarios/pendulum.toml.
const L: f64 = 1.0;
const THETA0: f64 = 1.0;
const M: f64 = 1.0;

/// θ and θ̇ at `times` from `θ̈ = −(g/l) sin θ`, released at rest from θ0: the 1-DOF
/// equation, integrated by DOP853 at rtol = atol = 1e-13 (nothing of the scene or its
/// model is used).
fn angle(times: &[f64]) -> Vec<[f64; 2]> {
    let rhs = |_: f64, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[1];
        dy[1] = -G / L * y[0].sin();
        Ok(())
    };
    let opts = OdeOptions { rtol: 1e-13, atol: 1e-13, ..OdeOptions::default() };
    let sol = ode::integrate(rhs, &[THETA0, 0.0], times, &opts).unwrap();
    sol.states.iter().map(|s| [s[0], s[1]]).collect()
}

/// max over nodes 0..N−skip of |(x, y) − l (sin θ, −cos θ)|.
fn position_error(t: &[f64], q: &[Vec<f64>], skip: usize) -> f64 {
    let exact = angle(t);
    let n = t.len() - skip;
    (0..n).map(|k| (q[k][0] - L * exact[k][0].sin()).abs().max((q[k][1] + L * exact[k][0].cos()).abs())).fold(0.0, f64::max)
}

/// The rod's tension over 2l: the multiplier of `h = x² + y² − l²` (∇h = 2(x, y)), in the
/// action's sign convention `d/dt p = f − λ ∇h`, is `λ = m (l θ̇² + g cos θ)/(2l)`.
fn multiplier(theta: [f64; 2]) -> f64 {
    M * (L * theta[1] * theta[1] + G * theta[0].cos()) / (2.0 * L)
}

#[test]
fn reference_of_the_pendulum_matches_the_angle_equation() {
    let r = Table::read(&common::root().join("references/pendulum.csv")).unwrap();
    let t = r.times();
    let exact = angle(&t);
    let (x, y, lambda, drift) =
        (r.column("x").unwrap(), r.column("y").unwrap(), r.column("lambda_rod").unwrap(), r.column("drift_rod").unwrap());
    for k in 0..t.len() {
        assert!((x[k] - L * exact[k][0].sin()).abs() < 1e-10, "x at t = {}", t[k]);
        assert!((y[k] + L * exact[k][0].cos()).abs() < 1e-10, "y at t = {}", t[k]);
        assert!((lambda[k] - multiplier(exact[k])).abs() < 1e-8, "λ at t = {}", t[k]);
        assert!(drift[k].abs() < 1e-12, "drift at t = {}", t[k]);
    }
}

#[test]
fn pendulum_with_a_rod_constraint_follows_the_angle_equation() {
    let o = common::solve("pendulum", &Overrides::default());
    let tr = &o.trajectory;
    // Measured (scene file): 4.0e-5 at N = 256, 4.7e-6 at N = 512 (order ≈ 3.1).
    let coarse = position_error(&tr.t, &tr.q, 2);
    assert!(coarse < 6e-5, "N = 256: {coarse:e}");
    let fine = common::solve("pendulum", &Overrides { nodes: Some(512), ..Default::default() });
    let fine_error = position_error(&fine.trajectory.t, &fine.trajectory.q, 2);
    assert!(fine_error < coarse / 6.0, "N = 512: {fine_error:e} (N = 256: {coarse:e})");
    check_drift(&o, 5e-5);
    // The enforced constraint is the time derivative 2(x ẋ + y ẏ), to the solver's
    // tolerance inside: its equation is the constraint times the node's quadrature weight,
    // solved to 1e-11, so |ġ| ≤ 1e-11 / (43/48 Δt) = 9.5e-10 wherever the last step lands
    // (measured far below: quadratic convergence overshoots the tolerance).
    assert!(o.diagnostics.max_constraint_interior < 2e-9, "{}", o.diagnostics.max_constraint_interior);
    // The multiplier is the tension over 2l (interior nodes, last two excluded); measured
    // 2.4e-3 against values from 2.6 to 9.4.
    let exact = angle(&tr.t);
    let n = tr.t.len() - 2;
    let dl = (1..n).map(|k| (tr.lambda[k][0] - multiplier(exact[k])).abs()).fold(0.0, f64::max);
    assert!(dl < 3.5e-3, "λ: {dl:e}");
    // Nothing depends on t and no force acts: the energy is conserved to the
    // discretization error (measured drift 2.0e-4 of |E| = 5.3 J).
    assert!(!o.diagnostics.depends_on_time);
    assert!(o.diagnostics.energy_drift < 3e-4, "{}", o.diagnostics.energy_drift);
}

/// The drift max |h| of summary.json is the largest |drift_rod| of the trajectory, and
/// it vanishes with the discretization error (measured 3.7e-5 at N = 256).
fn check_drift(o: &Outcome, bound: f64) {
    let drift = o.diagnostics.max_position_drift["rod"];
    let column = o.trajectory.drift.iter().map(|h| h[0].abs()).fold(0.0, f64::max);
    assert_eq!(drift, column);
    assert!(drift > 0.0 && drift < bound, "drift {drift:e}");
    // h = x² + y² − l², recomputed from the coordinates.
    for (q, h) in o.trajectory.q.iter().zip(&o.trajectory.drift) {
        assert!((q[0] * q[0] + q[1] * q[1] - L * L - h[0]).abs() < 1e-14);
    }
}

/// A position constraint may depend on t: a bead on a hoop whose radius grows,
/// `x² + y² − (R + u t)² = 0`, without gravity, released with the angular velocity ω0.
/// The radial force does no torque, so the angular momentum r² φ̇ is conserved:
/// φ̇ = ω0 R²/r(t)², φ = ω0 R t/(R + u t). The enforced constraint is
/// `2(x ẋ + y ẏ) − 2 u (R + u t) = 0`, so the initial velocity must carry the radial u.
#[test]
fn a_time_dependent_position_constraint_moves_the_bead() {
    let dir = tempfile::tempdir().unwrap();
    let text = r#"
[scene]
name = "bead on a growing hoop"
lagrangian = "1/2*m*(x_dot^2 + y_dot^2)"
[parameters]
m = 1
R = 1
u = 0.5
w0 = 2
[[coordinates]]
name = "x"
initial = "R"
velocity = "u"
[[coordinates]]
name = "y"
initial = 0
velocity = "w0*R"
[[constraints]]
name = "hoop"
expression = "x^2 + y^2 - (R + u*t)^2"
[time]
start = 0
end = 2
nodes = 256
"#;
    let path = dir.path().join("hoop.toml");
    std::fs::write(&path, text).unwrap();
    let scene = skg_core::scene::SceneFile::load(&path).unwrap().resolve(&Overrides::default()).unwrap();
    let o = skg_core::solve::solve_scene(&scene).unwrap();
    assert!(o.converged(), "{}", o.status);
    let (r0, u, w0) = (1.0, 0.5, 2.0);
    let tr = &o.trajectory;
    let n = tr.t.len() - 2;
    let e = (0..n)
        .map(|k| {
            let t = tr.t[k];
            let r = r0 + u * t;
            let phi = w0 * r0 * t / r;
            (tr.q[k][0] - r * phi.cos()).abs().max((tr.q[k][1] - r * phi.sin()).abs())
        })
        .fold(0.0, f64::max);
    // Measured 4.6e-4, 5.7e-5 and 7.2e-6 at N = 128, 256, 512 (order 3); drift 8.9e-5.
    assert!(e < 8e-5, "solve: {e:e}");
    assert!(o.diagnostics.depends_on_time);
    assert!(o.diagnostics.max_position_drift["hoop"] < 1.2e-4);
    // The time stepping differentiates the constraint twice, ∂g/∂t included.
    let (times, _) = skg_core::solve::grid(&scene);
    let r = skg_core::stepping::reference::regularized(&scene, &times, &Default::default()).unwrap();
    let e = r.trajectory.t.iter().zip(&r.trajectory.q).map(|(&t, q)| {
        let rad = r0 + u * t;
        let phi = w0 * r0 * t / rad;
        (q[0] - rad * phi.cos()).abs().max((q[1] - rad * phi.sin()).abs())
    });
    let e = e.fold(0.0, f64::max);
    assert!(e < 1e-10, "reference: {e:e}");
}
