//! Solving to the accuracy asked for (`--refine`, `--operator auto`) on scenes the tool
//! does not ship, each checked against independent truth: closed forms, or a classical
//! Runge–Kutta integration of the hand-derived equations written in this file.

mod common;

use skg_core::scene::{Backend, Overrides, Scene, SceneFile};
use skg_core::solve::backend::SolverStatus;
use skg_core::solve::deadline::Bound;
use skg_core::solve::{self, Outcome};
use skg_core::stepping::verify::VerifyStatus;

fn resolve(text: &str, ov: &Overrides) -> Scene {
    SceneFile::parse(text, "unseen.toml").unwrap().resolve(ov).unwrap()
}

fn refined(tol: f64) -> Overrides {
    Overrides { refine: true, verify_tol: Some(tol), ..Overrides::default() }
}

/// max over nodes and coordinates of |q − exact(t)|.
fn max_error(o: &Outcome, exact: impl Fn(f64) -> Vec<f64>) -> f64 {
    let tr = &o.trajectory;
    tr.t.iter().zip(&tr.q).flat_map(|(&t, q)| q.iter().zip(exact(t)).map(|(a, b)| (a - b).abs()).collect::<Vec<_>>()).fold(0.0, f64::max)
}

/// An underdamped oscillator, x'' + x' + 9x = 0 from x = 1 at rest, over 15 s.
const UNDERDAMPED: &str = r#"
[scene]
name = "underdamped"
lagrangian = "1/2*x_dot^2 - 9/2*x^2"
[[coordinates]]
name = "x"
initial = 1
velocity = 0
[forces]
x = "-x_dot"
[time]
start = 0
end = 15
nodes = 17
"#;

fn underdamped_exact(t: f64) -> Vec<f64> {
    let w = (9.0_f64 - 0.25).sqrt();
    vec![(-t / 2.0).exp() * ((w * t).cos() + (w * t).sin() / (2.0 * w))]
}

/// With the operator chosen and the grid refined, a damped oscillator meets 1e-3 … 1e-7
/// against its closed form, on the grid and operator the refinement reports; the
/// prediction is within a factor 4 of the measured error on the reported grid.
#[test]
fn the_chosen_discretization_meets_the_tolerance_against_the_closed_form() {
    for tol in [1e-3, 1e-5, 1e-7] {
        let scene = resolve(UNDERDAMPED, &refined(tol));
        assert!(scene.choose_operator, "a refinement with no operator named chooses one");
        let o = solve::solve_scene(&scene).unwrap();
        let r = o.refinement.as_ref().expect("the refinement is recorded");
        assert!(o.trusted(), "tol {tol}: {:?} {:?}", r.result, r.grids);
        let err = max_error(&o, underdamped_exact);
        assert!(err <= tol, "tol {tol}: error {err:.3e} against the closed form ({} on {} nodes)", o.settings.operator, o.settings.nodes);
        let last = r.grids.last().unwrap();
        assert_eq!((last.nodes, last.verdict.as_str()), (o.settings.nodes, "verified"));
        let (p, m) = (last.predicted.unwrap(), last.measured.unwrap());
        assert!(p / m < 4.0 && m / p < 4.0, "tol {tol}: predicted {p:.3} against measured {m:.3}");
        assert!(r.grids.len() <= 3, "tol {tol}: {} grids: {:?}", r.grids.len(), r.grids);
    }
}

/// A named operator is kept and only the grid refined: the rolling disk on SBP242 from
/// 33 nodes to 1e-5 against its closed form. The next grid is predicted from the error
/// (not doubled: from 33 nodes, SBP242's error of 7.6e-2 needs about 640).
#[test]
fn a_named_operator_is_refined_on_predicted_grids() {
    let ov = Overrides { nodes: Some(33), operator: Some("SBP242".parse().unwrap()), ..refined(1e-5) };
    let scene = common::load("rolling_disk", &ov);
    assert!(!scene.choose_operator);
    let o = solve::solve_scene(&scene).unwrap();
    let r = o.refinement.as_ref().unwrap();
    assert!(o.trusted(), "{:?}", r.grids);
    assert!(r.grids.iter().all(|g| g.operator == "SBP242"), "{:?}", r.grids);
    assert!(max_error(&o, common::rolling_disk_exact) <= 1e-5);
    let second = r.grids.get(1).map_or(r.grids[0].nodes, |g| g.nodes);
    assert!(second > 400 && second < 1500, "the second grid is predicted: {} nodes ({:?})", second, r.grids);
    assert!(r.grids.len() <= 3, "{:?}", r.grids);
}

/// x'' = −x − x³ − c x', y'' = −4y − (c + x) y' (crates/skg-core/tests/scenes/overdamped_2d.toml),
/// integrated by classical RK4 from each of `times` to the next in equal steps of at
/// most 10⁻⁴ s (its error is below 10⁻¹², far under the tolerances), sampled at `times`.
fn overdamped_rk4(times: &[f64]) -> Vec<Vec<f64>> {
    let c = 10.0;
    let f = |s: [f64; 4]| [s[2], s[3], -s[0] - s[0].powi(3) - c * s[2], -4.0 * s[1] - (c + s[0]) * s[3]];
    let add = |a: [f64; 4], b: [f64; 4], w: f64| [a[0] + w * b[0], a[1] + w * b[1], a[2] + w * b[2], a[3] + w * b[3]];
    let mut s = [2.0, -1.0, 0.0, 3.0];
    let mut out = vec![vec![s[0], s[1]]];
    for pair in times.windows(2) {
        let steps = ((pair[1] - pair[0]) / 1e-4).ceil() as usize;
        let h = (pair[1] - pair[0]) / steps as f64;
        for _ in 0..steps {
            let k1 = f(s);
            let k2 = f(add(s, k1, h / 2.0));
            let k3 = f(add(s, k2, h / 2.0));
            let k4 = f(add(s, k3, h));
            for i in 0..4 {
                s[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        out.push(vec![s[0], s[1]]);
    }
    out
}

/// The strongly contracting scene that the centred operators verify only on 4096
/// nodes in windows: with the operator chosen, one global solve on a dissipative
/// operator verifies, checked against RK4 of its equations.
#[test]
fn a_contracting_scene_is_solved_globally_on_a_chosen_dissipative_operator() {
    let text = std::fs::read_to_string(common::test_scene("overdamped_2d")).unwrap();
    let scene = resolve(&text, &Overrides { nodes: Some(257), refine: true, ..Overrides::default() });
    let o = solve::solve_scene(&scene).unwrap();
    let r = o.refinement.as_ref().unwrap();
    assert!(o.trusted(), "{:?}", r.grids);
    assert!(o.settings.operator.ends_with("-AD"), "a dissipative operator: {:?}", r.grids);
    assert!(matches!(o.method, skg_core::solve::Method::Global));
    let truth = overdamped_rk4(&o.trajectory.t);
    for (i, name) in ["x", "y"].iter().enumerate() {
        let err = o.trajectory.q.iter().zip(&truth).map(|(a, b)| (a[i] - b[i]).abs()).fold(0.0, f64::max);
        let tol = o.verification.tolerances[*name];
        assert!(err <= tol, "{name}: {err:.3e} against RK4, tolerance {tol:.3e}");
    }
}

/// A tolerance beyond double precision stops without solving more than the first grid,
/// says why, and is not trusted (the command line exits 4).
#[test]
fn an_unreachable_tolerance_stops_at_the_budget_with_the_reason() {
    let scene = resolve(UNDERDAMPED, &refined(1e-14));
    let o = solve::solve_scene(&scene).unwrap();
    let r = o.refinement.as_ref().unwrap();
    assert!(!o.trusted());
    assert!(o.converged(), "the best converged grid is reported");
    assert!(r.result.contains("no discretization is predicted to meet the tolerance"), "{}", r.result);
    // The remedy says what to do, without repeating the result.
    let remedy = o.remedy.as_deref().unwrap_or("");
    assert!(remedy.contains("loosen the tolerance") && !remedy.contains("no discretization is predicted"), "{remedy}");
    assert!(r.grids.len() <= 2, "{:?}", r.grids);
}

/// `--operator auto` without `--refine` keeps the scene's grid and chooses the cheapest
/// candidate predicted to meet the tolerance there.
#[test]
fn auto_without_refine_keeps_the_grid() {
    let ov = Overrides { auto_operator: true, nodes: Some(257), verify_tol: Some(1e-4), ..Overrides::default() };
    let scene = resolve(UNDERDAMPED, &ov);
    let o = solve::solve_scene(&scene).unwrap();
    let r = o.refinement.as_ref().unwrap();
    assert_eq!((r.grids.len(), o.settings.nodes), (1, 257), "{:?}", r.grids);
    assert!(!r.refine && r.operator_chosen);
    assert!(o.trusted(), "{:?}", r.grids);
    assert!(max_error(&o, underdamped_exact) <= 1e-4);
}

/// A time limit stops the backend inside its solve (here before its first step: the
/// limit has passed by then) and the fallback ladder after that attempt, as not
/// converged, unverified (the verification is not run), with a status that names the
/// limit and a remedy that raises it; with either backend.
#[test]
fn the_time_limit_stops_the_solve_and_the_ladder() {
    for backend in [Backend::Ipopt, Backend::Newton] {
        let ov = Overrides { time_limit: Some(1e-6), backend: Some(backend), ..Overrides::default() };
        let scene = common::load("damped_oscillator", &ov);
        let o = solve::solve_scene(&scene).unwrap();
        assert_eq!(o.attempts.len(), 1, "{backend:?}: {:?}", o.attempts);
        assert!(o.warnings.iter().any(|w| w.contains("stopped at the time limit")), "{backend:?}: {:?}", o.warnings);
        assert!(!o.converged(), "{backend:?}");
        let SolverStatus::TimeLimitReached { backend: stopped, bound, limit_s, elapsed_s } = o.status.solver() else {
            panic!("{backend:?}: {}", o.status)
        };
        assert_eq!((stopped, bound, limit_s), (backend, Bound::TimeLimit, 1e-6));
        assert!(elapsed_s >= limit_s, "{elapsed_s}");
        assert!(o.status.to_string().contains("time limit of 0.000001 s"), "{}", o.status);
        assert_eq!(o.verification.status, VerifyStatus::Unverified);
        assert!(o.verification.reason.contains("time limit"), "{}", o.verification.reason);
        assert!(o.remedy.as_deref().is_some_and(|r| r.contains("raise the time limit (--time-limit")), "{:?}", o.remedy);
        // Newton stopped at the limit is not handed over to Ipopt.
        assert!(!o.backend.handed_over_to_ipopt);
    }
}

/// A refinement ends at once, after its first grid, where more nodes would not cure the
/// failure: a solver tolerance so loose that the backend stops at the time-stepping
/// guess (residual about 1e-3, above the 1e-8 a converged solve needs), and a
/// verification that cannot run (the stiff test scene with the explicit stepper only,
/// whose steps run out). Before, both went on through grid after grid.
#[test]
fn a_failure_more_nodes_cannot_cure_ends_the_refinement_at_once() {
    let loose = UNDERDAMPED.replace("[time]", "[solver]\ntol = 2\n[time]");
    let o = solve::solve_scene(&resolve(&loose, &refined(1e-4))).unwrap();
    let r = o.refinement.as_ref().unwrap();
    assert_eq!(r.grids.len(), 1, "{:?}", r.grids);
    assert!(r.result.contains("[solver] tol") && r.result.contains("more nodes would not change that"), "{}", r.result);
    assert!(!o.trusted());

    let ov = Overrides { refine: true, stepper: Some(skg_core::scene::Stepper::Dop853), ..Overrides::default() };
    let o = solve::solve_scene(&common::load_test_scene("stiff_overdamped", &ov)).unwrap();
    let r = o.refinement.as_ref().unwrap();
    assert_eq!(r.grids.len(), 1, "{:?}", r.grids);
    assert!(r.result.contains("its verification could not run"), "{}", r.result);
    assert!(o.converged() && !o.trusted());
}

/// A contact of almost no grid steps (the tumbler with g = 2³² on 40 nodes, found by the
/// fuzz run) asks for more nodes than a usize holds: the refinement takes the budget's
/// word instead of overflowing.
#[test]
fn a_contact_of_almost_no_steps_does_not_overflow_the_nodes_it_asks_for() {
    let ov = Overrides { nodes: Some(40), refine: true, set: vec![("g".into(), "4294967296".into())], ..Overrides::default() };
    let o = solve::solve_scene(&common::load("tumbler", &ov)).unwrap();
    assert!(o.refinement.is_some());
}
