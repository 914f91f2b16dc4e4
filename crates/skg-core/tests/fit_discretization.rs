//! A fit's discretization (docs/fitting.md#the-discretization): chosen by the refinement
//! at the starting and at the fitted values, adaptive grids, the initial-velocity
//! condition over an initial layer, and a discretization error too large for the data's
//! standard deviations; each against a closed form.
#![cfg(feature = "ipopt")]

mod common;
mod fitting;

use fitting::*;

use skg_core::fit::{Fit, FitMethod};
use skg_core::scene::Overrides;

/// A discretization too coarse for the fitted motion (SBP121 on 64 nodes; the data of
/// an oscillator three times faster than at the starting values): the fit converges but
/// its motion fails the verification, and the remedy names `--refine`. With the
/// refinement, the nodes are chosen at the starting values (too few for the fitted
/// motion), then again at the fitted values, and the second fit verifies; its values
/// are within the verification's tolerance (1e-4 of the motion's range) of the closed
/// form's, where the coarse grid's are 3 % off.
#[test]
fn the_refinement_chooses_the_nodes_at_the_starting_and_at_the_fitted_values() {
    let coarse = OSCILLATOR.replace("nodes = 512", "nodes = 64").replace("\"SBP484\"", "\"SBP121\"");
    let (k, c, x0, v0) = (9.0, 0.3, 1.2, -0.5);
    let data = csv(&oscillator_times(), &[("x", &|t| oscillator(t, 1.0, k, c, x0, v0))]);
    let mut settings = free(&["k", "c", "x0", "v0"]);
    settings.method = FitMethod::Reduced;
    let truth = [("k", k), ("c", c), ("x0", x0), ("v0", v0)];

    let ov = Overrides::default();
    let f = run(&scene_of(&coarse, &ov), &ov, &data, &settings).unwrap();
    assert!(f.report.converged && !f.trusted(), "{}", f.outcome.verification.reason);
    assert!((f.report.parameters["k"].value - k).abs() > 0.01 * k, "k = {}", f.report.parameters["k"].value);
    let remedy = f.outcome.remedy.as_deref().unwrap_or_default();
    assert!(remedy.contains("--refine"), "{remedy}");
    assert!(f.report.discretization.is_empty());

    let ov = Overrides { refine: true, ..Overrides::default() };
    let f = run(&scene_of(&coarse, &ov), &ov, &data, &settings).unwrap();
    assert!(f.trusted(), "{}", f.outcome.verification.reason);
    assert_recovered(&f, &truth, 1e-3);
    let chosen = &f.report.discretization;
    assert_eq!(chosen.len(), 2, "{chosen:?}");
    assert!(chosen[0].nodes < chosen[1].nodes && chosen.iter().all(|d| d.operator == "SBP121"), "{chosen:?}");
    assert_eq!((f.fitted.nodes, f.fitted.operator.name()), (chosen[1].nodes, "SBP121"));
    // The starting values reported are the scene's, not the first fit's.
    assert_eq!(f.report.parameters["k"].initial, 3.0);
    assert!(f.fitted_toml.contains(&format!("--operator SBP121 --initial-velocity strong --nodes {}", chosen[1].nodes)));
}

/// `--grid adaptive`: the fit runs on the grid whose map follows the motion at the
/// starting values (nodes not equally spaced), keeps it, and recovers the closed form's
/// values within the verification's tolerance (1e-4 of the motion's range; v0 is 8e-6
/// off on it, within 1e-6 on the uniform grid of as many nodes: the test above).
#[test]
fn a_fit_on_an_adaptive_grid_recovers_the_closed_form() {
    let ov = Overrides { grid: Some(skg_core::scene::GridChoice::Adaptive), ..Overrides::default() };
    let scene = scene_of(OSCILLATOR, &ov);
    let (k, c, x0, v0) = (4.0, 0.3, 1.2, -0.5);
    let data = csv(&oscillator_times(), &[("x", &|t| oscillator(t, 1.0, k, c, x0, v0))]);
    let f = run(&scene, &ov, &data, &free(&["k", "c", "x0", "v0"])).unwrap();
    assert!(f.trusted(), "{}", f.outcome.verification.reason);
    assert_recovered(&f, &[("k", k), ("c", c), ("x0", x0), ("v0", v0)], 1e-4);
    assert_eq!(f.outcome.settings.grid, "adaptive");
    let t = &f.outcome.trajectory.t;
    let spacings: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let (lo, hi) = spacings.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), &h| (lo.min(h), hi.max(h)));
    assert!(hi / lo > 1.01, "spacings from {lo} to {hi}: not the motion's map");
    assert!(f.report.warnings.iter().any(|w| w.contains("the adaptive grid's map follows the motion")), "{:?}", f.report.warnings);
}

/// A discretization whose error is large against the data's standard deviations biases
/// the estimates beyond their standard errors, though its verification passes a loose
/// tolerance: the oscillator on 60 nodes of SBP242 under `[verify] tol = 0.05`, data
/// from the closed form (k = 4, c = 0.3) with σ = 1e-4 stated. The fit warns, with the
/// remedy; on the scene's 512 nodes of SBP484 it does not, and recovers the closed form's
/// values within their standard errors.
#[test]
fn a_discretization_error_large_against_the_data_s_deviations_is_warned() {
    let mut data = String::from("t,x,sigma_x\n");
    for t in oscillator_times() {
        data += &format!("{t:?},{:?},1e-4\n", oscillator(t, 1.0, 4.0, 0.3, 1.0, 0.0));
    }
    let settings = free(&["k", "c"]);
    let coarse = Overrides { nodes: Some(60), operator: Some("SBP242".parse().unwrap()), verify_tol: Some(0.05), ..Default::default() };
    let f = run(&scene_of(OSCILLATOR, &coarse), &coarse, &data, &settings).unwrap();
    assert!(f.trusted(), "{}: {}", f.report.status, f.outcome.verification.reason);
    let warned = |f: &Fit| f.report.warnings.iter().any(|w| w.contains("discretization error in x") && w.contains("--verify-tol"));
    assert!(warned(&f), "{:?}", f.report.warnings);
    let k = &f.report.parameters["k"];
    assert!((k.value - 4.0).abs() > 3.0 * k.std_error.unwrap(), "k = {} ± {:?}: not biased, the test shows nothing", k.value, k.std_error);
    let ov = Overrides::default();
    let f = run(&scene_of(OSCILLATOR, &ov), &ov, &data, &settings).unwrap();
    assert!(f.trusted() && !warned(&f), "{:?}", f.report.warnings);
    for (name, truth) in [("k", 4.0), ("c", 0.3)] {
        let p = &f.report.parameters[name];
        assert!((p.value - truth).abs() <= p.std_error.unwrap().max(1e-9 * truth), "{name} = {} ± {:?}", p.value, p.std_error);
    }
}

/// A fit takes the discretization a solve takes: on the stiff overdamped spring
/// (c = 1e4, 64 nodes, no condition named) the natural initial-velocity condition, since
/// the motion starts with a fast layer; with the strong one the fitted motion failed its
/// verification (1.1e-4 against a tolerance of 1e-6) where the solve passes. The data
/// are the closed form at c = 1e4, the fit starts from 5000.
#[test]
fn a_fit_imposes_the_initial_velocity_as_a_solve_does_over_an_initial_layer() {
    let ov = Overrides { set: vec![("c".into(), "5000".into())], ..Overrides::default() };
    let scene = common::load_test_scene("stiff_overdamped", &ov);
    let (c, k) = (1e4_f64, 1.0_f64);
    let d = (c * c - 4.0 * k).sqrt();
    let (r1, r2) = ((-c + d) / 2.0, (-c - d) / 2.0);
    let exact = |t: f64| (r2 * (r1 * t).exp() - r1 * (r2 * t).exp()) / (r2 - r1);
    let times: Vec<f64> = (0..40).map(|i| 1.0 + 2.5 * i as f64).collect();
    let data = csv(&times, &[("x", &exact)]);
    let f = run(&scene, &ov, &data, &free(&["c>=0"])).unwrap();
    assert!(f.trusted(), "{}", f.outcome.verification.reason);
    assert_recovered(&f, &[("c", c)], 1e-4);
    assert_eq!(f.outcome.settings.initial_velocity, skg_core::scene::InitialVelocity::Natural);
    assert!(f.report.warnings.iter().any(|w| w.contains("natural condition")), "{:?}", f.report.warnings);
    assert!(f.fitted_toml.contains("--initial-velocity natural --nodes 64"));
    // The reduced fit reaches the same damping: c = 1e4, with the misfit's curvature in
    // it about 1e-11, passed Ipopt's absolute tests far from the minimum (its acceptable
    // level at c = 9955, then its `tol` at c = 9999.4, each 6 of the reported standard
    // errors off) before the reduced fit stopped by its own, relative, test alone.
    let mut reduced = free(&["c>=0"]);
    reduced.method = FitMethod::Reduced;
    let r = run(&scene, &ov, &data, &reduced).unwrap();
    assert!(r.trusted(), "{}", r.outcome.verification.reason);
    assert_recovered(&r, &[("c", c)], 1e-6);
    assert!(!r.report.warnings.iter().any(|w| w.contains("acceptable level")), "{:?}", r.report.warnings);
}
