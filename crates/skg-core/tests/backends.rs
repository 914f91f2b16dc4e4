#![cfg(feature = "ipopt")]
//! The two backends solve the same square system: Newton's method with a sparse LU
//! must find Ipopt's root (docs/solver.md#the-newton-backend), report its own statuses
//! in the same fields, reuse its symbolic analysis, and hand over to Ipopt when it fails.

mod common;

use skg_core::discrete::action::Block;
use skg_core::scene::{Backend, Formulation, Overrides};
use skg_core::solve;
use skg_core::solve::backend::{self, SolverStatus, SquareSolver};
use skg_core::solve::linalg::SparseFactorization;
use skg_core::solve::newton::NewtonStatus;

fn max_diff(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

fn with_backend(backend: Backend, formulation: Formulation) -> Overrides {
    Overrides { backend: Some(backend), formulation: Some(formulation), ..Default::default() }
}

#[test]
fn newton_and_ipopt_agree_on_every_shipped_scene() {
    for name in common::SHIPPED {
        for formulation in [Formulation::Reduced, Formulation::Full] {
            let ipopt = common::solve(name, &with_backend(Backend::Ipopt, formulation));
            let newton = common::solve(name, &with_backend(Backend::Newton, formulation));
            let ctx = format!("{name} ({formulation})");
            // Newton converged by itself, in about Ipopt's number of steps (both take full
            // Newton steps from the same guess; whether the last one lands below the
            // tolerance or one more is needed is decided by rounding, which differs
            // between processors and BLAS kernels).
            assert_eq!(newton.status.solver(), SolverStatus::Newton(NewtonStatus::Converged), "{ctx}");
            assert!(!newton.backend.handed_over_to_ipopt, "{ctx}");
            assert!(newton.iterations.abs_diff(ipopt.iterations) <= 1, "{ctx}: iterations {} and {}", newton.iterations, ipopt.iterations);
            assert_eq!(newton.history.len(), newton.iterations + 1, "{ctx}");
            let (a, b) = (&newton.trajectory, &ipopt.trajectory);
            for (what, x, y) in [("q", &a.q, &b.q), ("v", &a.v, &b.v), ("λ", &a.lambda, &b.lambda)] {
                let d = max_diff(x, y);
                assert!(d < 1e-9, "{ctx}: max |{what}_newton − {what}_ipopt| = {d:e}");
            }
            assert!(newton.diagnostics.max_residual <= 1e-11, "{ctx}: residual {:e}", newton.diagnostics.max_residual);
            // The same summary fields, honestly filled.
            let json = serde_json::to_value(&newton).unwrap();
            assert_eq!(json["status"], "Newton_Converged", "{ctx}");
            assert_eq!(json["settings"]["backend"], "newton", "{ctx}");
            assert_eq!(json["backend"]["requested"], "newton", "{ctx}");
            // One factorization per step, but for chord steps (the last step, where one
            // more step at the last rate converges, reuses the last factorization; a
            // second where the first lands between the tolerance and the round-off level,
            // newton.rs's module documentation).
            let counts = &json["backend"]["newton"];
            let (jacobians, chords) = (counts["jacobian_evaluations"].as_u64().unwrap(), counts["chord_steps"].as_u64().unwrap());
            assert_eq!(jacobians + chords, newton.iterations as u64, "{ctx}");
            assert!(chords <= 2, "{ctx}: {chords} chord steps");
            let ipopt_json = serde_json::to_value(&ipopt).unwrap();
            assert!(ipopt_json["backend"]["newton"].is_null() && ipopt_json["backend"]["requested"] == "ipopt", "{ctx}");
        }
    }
}

/// The shipped scenes solved in windows (the damped oscillator after the fallback
/// ladder, the long rolling disk by its own `[time] window`): both backends verify, cover
/// the span the same way and agree to 1e-9.
#[test]
fn newton_and_ipopt_agree_on_the_windowed_scenes() {
    for name in ["damped_oscillator", "rolling_disk_long"] {
        let ipopt = common::solve(name, &with_backend(Backend::Ipopt, Formulation::Reduced));
        let newton = common::solve(name, &with_backend(Backend::Newton, Formulation::Reduced));
        assert!(ipopt.trusted() && newton.trusted(), "{name}: {} / {}", ipopt.verification.reason, newton.verification.reason);
        assert_eq!(newton.method, ipopt.method, "{name}");
        assert!(matches!(newton.method, solve::Method::Windows { count, .. } if count > 1), "{name}: {}", newton.method);
        assert!(!newton.backend.handed_over_to_ipopt, "{name}");
        let d = max_diff(&newton.trajectory.q, &ipopt.trajectory.q);
        assert!(d < 1e-9, "{name}: max |q_newton − q_ipopt| = {d:e}");
        // The report is the first window's, which made the analysis the others reused.
        assert!(!newton.backend.newton.as_ref().unwrap().analysis_reused, "{name}");
    }
}

/// A tolerance below round-off: both backends stop once the residual stagnates at its
/// round-off level (Ipopt from its intermediate callback, instead of iterating on to its
/// acceptable-level test), count as converged and verified, and agree to 1e-9.
#[test]
fn an_unreachable_tolerance_stops_both_backends_at_the_round_off_level() {
    for name in ["tumbler", "rolling_disk"] {
        let solve_with = |backend| {
            let mut scene = common::load(name, &with_backend(backend, Formulation::Reduced));
            scene.solver.tol = 1e-20;
            solve::solve_scene(&scene).unwrap()
        };
        let (ipopt, newton) = (solve_with(Backend::Ipopt), solve_with(Backend::Newton));
        assert_eq!(ipopt.status.solver(), SolverStatus::IpoptConvergedToRoundOff, "{name}");
        assert_eq!(serde_json::to_value(&ipopt).unwrap()["status"], "Ipopt_Converged_To_Round_Off", "{name}");
        assert_eq!(newton.status.solver(), SolverStatus::Newton(NewtonStatus::ConvergedToRoundOff), "{name}");
        assert!(ipopt.trusted() && newton.trusted(), "{name}: {} / {}", ipopt.verification.reason, newton.verification.reason);
        // Quadratic convergence from the time-stepping start reaches round-off in a few
        // steps (without the round-off stop Ipopt takes 10 or more here).
        assert!(ipopt.iterations <= newton.iterations + 1 && ipopt.iterations <= 5, "{name}: {} Ipopt iterations", ipopt.iterations);
        let d = max_diff(&newton.trajectory.q, &ipopt.trajectory.q);
        assert!(d < 1e-9, "{name}: max |q_newton − q_ipopt| = {d:e}");
    }
}

/// One `SquareSolver` reused for a second initial state (a time window) keeps its
/// symbolic analysis and still finds that state's own root; the next solve of an action
/// with equal structure on the same thread takes the kept analysis over (a sweep
/// worker's next point, a ladder's next attempt) and finds exactly the root a fresh
/// analysis finds; a solve of another structure analyses anew.
#[test]
fn the_symbolic_analysis_is_reused_across_solves_of_equal_structure() {
    let scene = common::load("rolling_disk", &with_backend(Backend::Newton, Formulation::Reduced));
    let action = solve::build_action(&scene).unwrap();
    backend::discard_kept_analysis();
    let first = solve::solve_scene(&scene).unwrap();
    assert!(!first.backend.newton.as_ref().unwrap().analysis_reused);
    let z0 = guess_from(&first.trajectory.q, &action);
    let mut solver = SquareSolver::new(&scene, &action);
    for _ in 0..2 {
        let a = solver.solve(&action, &z0).unwrap();
        let newton = a.report.newton.as_ref().unwrap();
        assert!(newton.analysis_reused && newton.analysis_s == 0.0, "{newton:?}");
        assert!(a.max_residual <= 1e-11);
    }
    drop(solver);

    // A factorization on the kept analysis (a fit's `∂R/∂P` after its start solve):
    // the same solution as on an analysis of its own, and the kept analysis stays.
    let plan = action.plan(Block::ReducedJacobian);
    let n_p = action.layout.n_p;
    let mut values = vec![0.0; plan.structure.len()];
    action.matrix_values(&plan, &z0, &mut values, &mut action.model.workspace());
    let exact: Vec<f64> = (0..n_p).map(|i| (0.37 * i as f64).sin()).collect();
    let mut b = vec![0.0; n_p];
    for (&(r, c), v) in plan.structure.iter().zip(&values) {
        b[r as usize] += v * exact[c as usize];
    }
    let mut kept = backend::factorization_on_kept_analysis(n_p, &plan.structure, &values).expect("the kept analysis fits");
    let mut own = SparseFactorization::new(n_p, &plan.structure, &values).unwrap();
    let (mut x, mut y) = (b.clone(), b);
    assert!(kept.solve(&mut x) && own.solve(&mut y));
    assert_eq!(x, y, "the same analysis and values give the same solution");
    let err = max_diff(&[x], &[exact]);
    // Measured 4e-12 (the Jacobian's condition); margin 250x.
    assert!(err < 1e-9, "{err:e}");
    assert!(backend::factorization_on_kept_analysis(n_p, &plan.structure[1..], &values[1..]).is_none(), "another structure");

    // Same structure, different initial velocity: a different root, same analysis.
    let mut other = scene.clone();
    other.initial_v[2] = 5.1; // θ̇
    other.initial_v[0] = 5.1; // ẋ: keeps g1 = ẋ² + ẏ² − R²θ̇² = 0
    let reused = solve::solve_scene(&other).unwrap();
    let newton = reused.backend.newton.as_ref().unwrap();
    assert!(newton.analysis_reused && newton.analysis_s == 0.0, "{newton:?}");
    assert_eq!(reused.status.solver(), SolverStatus::Newton(NewtonStatus::Converged));
    backend::discard_kept_analysis();
    let fresh = solve::solve_scene(&other).unwrap();
    let newton = fresh.backend.newton.as_ref().unwrap();
    assert!(!newton.analysis_reused && newton.analysis_s > 0.0, "{newton:?}");
    let d = max_diff(&reused.trajectory.q, &fresh.trajectory.q);
    assert!(d <= 1e-12, "reused analysis: {d:e} from a fresh one");
    assert!(max_diff(&reused.trajectory.q, &first.trajectory.q) > 1e-3, "a different root");

    // Another node count: another structure, analysed anew.
    let coarser =
        common::load("rolling_disk", &Overrides { nodes: Some(scene.nodes / 2), ..with_backend(Backend::Newton, Formulation::Reduced) });
    let o = solve::solve_scene(&coarser).unwrap();
    assert!(!o.backend.newton.as_ref().unwrap().analysis_reused);
}

/// A start far from the solution on the coarse SBP121 incline: plain Newton fails
/// there, and the solve hands over to Ipopt, records that, and warns.
#[test]
fn a_failed_newton_solve_hands_over_to_ipopt() {
    let ov = Overrides { max_iter: Some(3), ..with_backend(Backend::Newton, Formulation::Reduced) };
    let scene = common::load("incline_frictionless", &Overrides { nodes: Some(64), operator: Some("SBP121".parse().unwrap()), ..ov });
    let o = solve::solve_scene(&scene).unwrap();
    assert!(o.backend.handed_over_to_ipopt, "Newton cannot converge in 3 steps here");
    let newton = o.backend.newton.as_ref().unwrap();
    assert!(!newton.status.is_success());
    assert!(matches!(o.status.solver(), SolverStatus::Ipopt(_)));
    assert!(
        o.warnings.iter().any(|w| w.contains("Newton's method did not converge") && w.contains(newton.status.name())),
        "{:?}",
        o.warnings
    );
    let json = serde_json::to_value(&o).unwrap();
    assert_eq!(json["backend"]["handed_over_to_ipopt"], true);
    assert_eq!(json["backend"]["newton"]["status"], newton.status.name());
}

/// Z with the plus block's coordinates from `q` (node-major) and everything else zero.
fn guess_from(q: &[Vec<f64>], action: &skg_core::discrete::action::Action) -> Vec<f64> {
    let lay = &action.layout;
    let mut z = vec![0.0; lay.len()];
    for (k, qk) in q.iter().enumerate() {
        for (i, v) in qk.iter().enumerate() {
            z[lay.qp[k * lay.d + i] as usize] = *v;
        }
    }
    z
}

/// A system with subnormal entries reaches Ipopt without crashing MUMPS: the pendulum of
/// length 1e-307 (1e-320 in the fuzz run that found it, seed 238), whose KKT matrix had entries below
/// the smallest normal number, made Debian's MUMPS corrupt its memory in the analysis
/// ("double free or corruption", a segmentation fault), with Ipopt asked for and after
/// Newton handed over. Now both return an outcome (one that cannot be trusted: the
/// constrained time stepping of so small a pendulum cannot run).
#[test]
fn a_system_with_subnormal_entries_does_not_crash_ipopt() {
    for backend in [Backend::Ipopt, Backend::Newton] {
        let ov = Overrides { backend: Some(backend), set: vec![("l".into(), "1e-307".into())], ..Default::default() };
        let o = solve::solve_scene(&common::load("pendulum", &ov)).unwrap();
        assert!(!o.trusted(), "{backend:?}: {}", o.status);
    }
}
