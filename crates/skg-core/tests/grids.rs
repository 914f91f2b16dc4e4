//! Grids that follow the motion: a brief fast part of a motion (a contact with a thin
//! wall, a fast initial layer) solved and verified on an adaptive grid of a few thousand
//! nodes where a uniform grid needs hundreds of thousands, checked against independent
//! truth: closed forms, the event-driven hard-wall reference (itself checked against the
//! tumbler's closed form in `reference.rs`), and scipy's Radau on hand-derived equations.

mod common;

use skg_core::sbp::OperatorKind;
use skg_core::scene::{GridChoice, InitialVelocity, Overrides};
use skg_core::solve;
use skg_core::stepping::reference::{self, ReferenceOptions};

/// `--refine --operator auto`.
fn refined() -> Overrides {
    Overrides { refine: true, auto_operator: true, ..Overrides::default() }
}

/// The paper's tumbler with a wall 1e-4 thin: refined with the operator chosen, it is
/// verified on an adaptive grid of at most 8192 nodes (a uniform one needs about 600 000)
/// and within 1e-4 m of the hard-wall motion, the limit σ → 0.
#[test]
fn the_tumbler_with_a_thin_wall_is_verified_on_an_adaptive_grid() {
    let ov = Overrides { set: vec![("sigma".into(), "1e-4".into())], ..refined() };
    let scene = common::load("tumbler", &ov);
    let o = solve::solve_scene(&scene).unwrap();
    assert!(o.trusted(), "{} / {}", o.status, o.verification.reason);
    assert_eq!(o.settings.grid, "adaptive");
    assert!(o.settings.nodes <= 8192, "{} nodes", o.settings.nodes);
    let hard = reference::hard_wall(&scene, &o.trajectory.t, &ReferenceOptions::default()).unwrap();
    assert!(hard.impacts.len() >= 2, "{:?}", hard.impacts);
    let far = o.trajectory.q.iter().zip(&hard.trajectory.q).map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1])).fold(0.0, f64::max);
    assert!(far < 1e-4, "{far:e} m from the hard-wall motion");
    // The nodes are dense in the contacts: the finest spacing is far below the mean.
    let t = &o.trajectory.t;
    let finest = t.windows(2).map(|w| w[1] - w[0]).fold(f64::INFINITY, f64::min);
    assert!(finest < 0.1 * (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64, "finest spacing {finest:e}");
}

/// A ball dropped on a floor 1e-4 thin: verified on an adaptive grid of at most 8192
/// nodes, and within 3σ of the closed-form bounces of a hard floor.
#[test]
fn a_ball_on_a_thin_floor_is_verified_on_an_adaptive_grid() {
    let scene = common::load_test_scene("ball_on_thin_floor", &refined());
    let o = solve::solve_scene(&scene).unwrap();
    assert!(o.trusted(), "{} / {}", o.status, o.verification.reason);
    assert_eq!(o.settings.grid, "adaptive");
    assert!(o.settings.nodes <= 8192, "{} nodes", o.settings.nodes);
    let error = common::max_error(&o, &[0], 0, hard_floor);
    assert!(error < 3e-4, "{error:e} from the hard floor");
}

/// The ball on a floor 1e-4 thin on the adaptive grid at node counts the user sets
/// (`--grid adaptive --nodes N`, no refinement): the map does not depend on N, so more
/// nodes put more of them into the contacts, and each grid is verified and within 3σ of
/// the hard floor. (The map's step bound was the scene's spacing: at N = 1517 free flight
/// then took the nodes and the ball was not verified.)
#[test]
fn an_adaptive_grid_of_any_node_count_follows_the_contacts() {
    for nodes in [1517, 2049] {
        let ov = Overrides { grid: Some(GridChoice::Adaptive), nodes: Some(nodes), ..Overrides::default() };
        let o = solve::solve_scene(&common::load_test_scene("ball_on_thin_floor", &ov)).unwrap();
        assert!(o.trusted(), "{nodes} nodes: {} / {}", o.status, o.verification.reason);
        assert_eq!((o.settings.grid, o.settings.nodes), ("adaptive", nodes));
        let error = common::max_error(&o, &[0], 0, hard_floor);
        assert!(error < 3e-4, "{nodes} nodes: {error:e} from the hard floor");
    }
}

/// The ball on a floor 1e-4 thin: the hard floor's closed form, free fall until
/// `t_f = √(2/g)`, then elastic bounces of period `2 t_f`.
fn hard_floor(t: f64) -> Vec<f64> {
    let g = 9.8_f64;
    let fall = (2.0 / g).sqrt();
    if t < fall {
        return vec![1.0 - g * t * t / 2.0];
    }
    let u = (t - fall) % (2.0 * fall);
    vec![g * fall * u - g * u * u / 2.0]
}

/// The ball on a floor 1e-4 thin in windows of (on average) 0.5 s with `SBP242-AD` and
/// the natural initial velocity, the fallback ladder off: refined on the adaptive grid,
/// each window takes the motion's nodes, and the run is verified and within 3σ of the
/// closed-form bounces of a hard floor; in windows of as many nodes spread evenly the
/// contacts fall between nodes and it is not.
#[test]
fn windows_on_an_adaptive_grid_follow_the_motion() {
    let windowed = |grid: GridChoice, nodes: Option<usize>| {
        let ov = Overrides {
            grid: Some(grid),
            nodes,
            refine: nodes.is_none(),
            operator: Some("SBP242-AD".parse().unwrap()),
            initial_velocity: Some(InitialVelocity::Natural),
            window: Some(0.5),
            no_fallback: true,
            ..Overrides::default()
        };
        let o = solve::solve_scene(&common::load_test_scene("ball_on_thin_floor", &ov)).unwrap();
        assert!(matches!(o.method, solve::Method::Windows { count, .. } if count >= 3), "{grid}: {:?}", o.method);
        assert_eq!(o.settings.grid, grid.name());
        o
    };
    let adaptive = windowed(GridChoice::Adaptive, None);
    assert!(adaptive.trusted(), "{} / {}", adaptive.status, adaptive.verification.reason);
    assert!(adaptive.settings.nodes <= 8192, "{} nodes", adaptive.settings.nodes);
    let error = common::max_error(&adaptive, &[0], 0, hard_floor);
    assert!(error < 3e-4, "{error:e} from the hard floor");
    let uniform = windowed(GridChoice::Uniform, Some(adaptive.settings.nodes));
    let uniform_error = common::max_error(&uniform, &[0], 0, hard_floor);
    assert!(!uniform.trusted(), "uniform windows on {} nodes: {}", adaptive.settings.nodes, uniform.status);
    assert!(uniform_error > 1e-2, "uniform windows: {uniform_error:e} from the hard floor");
}

/// An overdamped oscillator `x'' + c x' + x = 0`, c = 200, whose velocity relaxes in a
/// layer of 1/c: on the same number of nodes and operator, the adaptive grid is far
/// closer to the closed form than the uniform one.
#[test]
fn an_initial_layer_is_resolved_by_the_adaptive_grid() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("layer.toml");
    std::fs::write(
        &path,
        "[scene]\nname = \"layer\"\nlagrangian = \"1/2*x_dot^2 - 1/2*x^2\"\n[parameters]\nc = 200\n\
         [[coordinates]]\nname = \"x\"\ninitial = 1\nvelocity = 3\n[forces]\nx = \"-c*x_dot\"\n\
         [time]\nstart = 0\nend = 5\nnodes = 129\n[discretization]\noperator = \"SBP242-AD\"\n",
    )
    .unwrap();
    let c = 200.0_f64;
    let root = (c * c - 4.0).sqrt();
    let (r1, r2) = ((-c + root) / 2.0, (-c - root) / 2.0);
    // x(0) = 1, x'(0) = 3.
    let (a, b) = ((3.0 - r2) / (r1 - r2), (r1 - 3.0) / (r1 - r2));
    let exact = |t: f64| vec![a * (r1 * t).exp() + b * (r2 * t).exp()];
    let error_on = |grid: GridChoice| {
        let ov = Overrides { grid: Some(grid), no_fallback: true, ..Overrides::default() };
        let scene = skg_core::scene::SceneFile::load(&path).unwrap().resolve(&ov).unwrap();
        let o = solve::solve_scene(&scene).unwrap();
        assert!(o.status.is_converged(), "{grid}: {}", o.status);
        assert_eq!(o.settings.grid, grid.name());
        common::max_error(&o, &[0], 0, exact)
    };
    let (uniform, adaptive) = (error_on(GridChoice::Uniform), error_on(GridChoice::Adaptive));
    assert!(adaptive < 0.1 * uniform, "adaptive {adaptive:e} against uniform {uniform:e}");
}

/// `SBP484`'s boundary closures need a smoother grid than the lower orders: on the
/// adaptive grid of the thin wall's 64 nodes its stretch is negative at node 2, where
/// `SBP363` takes the same nodes. The solve says which operator and what avoids it,
/// instead of a bare "stretch" (it was an error without a remedy).
#[test]
fn an_adaptive_grid_too_uneven_for_a_high_order_operator_is_refused_with_a_remedy() {
    let with = |operator: OperatorKind| Overrides { grid: Some(GridChoice::Adaptive), operator: Some(operator), ..Overrides::default() };
    let scene = common::load_test_scene("thin_wall", &with(OperatorKind::Sbp484));
    let message = solve::solve_scene(&scene).expect_err("SBP484 on the thin wall's adaptive 64 nodes").to_string();
    for part in ["SBP484", "node 2", "more nodes", "lower-order operator", "uniform grid"] {
        assert!(message.contains(part), "{part:?} not in: {message}");
    }
    let scene = common::load_test_scene("thin_wall", &with(OperatorKind::Sbp363));
    assert!(solve::solve_scene(&scene).is_ok(), "SBP363 on the same nodes");
}

/// A rung of the fallback ladder whose grid the operator cannot take ends the ladder with
/// a warning, not the solve with an error: the damped yaw disk with `SBP484-AD` on its
/// adaptive grid of 128 nodes converges and fails its verification, and the windows of
/// 1.57 s, each with its own boundary closures, are too uneven for `SBP484-AD` at the
/// first window's node 2 (it was exit 1, the solve's answer and its verdict lost).
#[test]
fn a_fallback_rung_whose_grid_the_operator_cannot_take_ends_the_ladder() {
    let ov = Overrides { grid: Some(GridChoice::Adaptive), operator: Some(OperatorKind::Sbp484Ad), ..Overrides::default() };
    let path = common::root().join("crates/skg-core/tests/scenes/stiff/damped_yaw_disk.toml");
    let scene = skg_core::scene::SceneFile::load(&path).unwrap().resolve(&ov).unwrap();
    let o = solve::solve_scene(&scene).expect("an outcome, not an error");
    assert!(o.status.is_converged(), "{}", o.status);
    // Its error is 1.2 times the tolerance (theta): the discretization's, not rounding.
    assert!(!o.trusted(), "{}", o.verification.reason);
    let warning = o.warnings.iter().find(|w| w.contains("fallback ladder stopped before windows"));
    assert!(warning.is_some_and(|w| w.contains("SBP484-AD") && w.contains("spread too unevenly")), "warnings: {:?}", o.warnings);
}
