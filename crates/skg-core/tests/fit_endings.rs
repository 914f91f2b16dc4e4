//! How a fit ends when it does not simply converge (docs/fitting.md): at its time limit,
//! at a point it cannot evaluate, at a degenerate point or a local minimum that misses
//! the data (warned or not converged), at Ipopt's acceptable level (taken on by the
//! reduced fit); each against a closed form.
#![cfg(feature = "ipopt")]

mod common;
mod fitting;

use fitting::*;

use skg_core::fit::{self, Fit, FitHessian, FitMethod};
use skg_core::scene::Overrides;

/// Standard deviations that explain the residuals give no warning; ten times too small,
/// the misfit is a hundred times what they explain, and the fit says so (a local minimum,
/// or a model or standard deviations that do not describe the data).
#[test]
fn a_misfit_the_standard_deviations_do_not_explain_is_warned() {
    let ov = Overrides::default();
    let scene = scene_of(OSCILLATOR, &ov);
    // Residuals of rms 0.01/√2 about the closed form: deterministic, not fitted away.
    let noisy = |t: f64| oscillator(t, 1.0, 4.0, 0.3, 1.2, -0.5) + 0.01 * (37.0 * t).sin();
    for (sigma, warned) in [(0.01, false), (0.001, true)] {
        let data = csv(&oscillator_times(), &[("x", &noisy), ("sigma_x", &|_| sigma)]);
        let f = run(&scene, &ov, &data, &free(&["k", "c", "x0", "v0"])).unwrap();
        let chi2 = f.report.misfit.reduced_chi_square.unwrap();
        let warning = f.report.warnings.iter().find(|w| w.contains("times what the data's standard deviations explain"));
        assert_eq!(warning.is_some(), warned, "σ = {sigma}: reduced chi-square {chi2}, {:?}", f.report.warnings);
        if let Some(w) = warning {
            assert!(w.contains("local minimum") && chi2 > 20.0, "{w}");
        }
    }
}

/// The user's time limit ends a fit as not converged, with its status and the limit
/// named, also while the refinement chooses the discretization: here a limit already
/// passed when Ipopt first calls back.
#[test]
fn a_fit_ends_at_its_time_limit() {
    let data = csv(&oscillator_times(), &[("x", &|t| oscillator(t, 1.0, 4.0, 0.3, 1.2, -0.5))]);
    for (refine, method) in [(false, FitMethod::AllAtOnce), (false, FitMethod::Reduced), (true, FitMethod::Reduced)] {
        let ov = Overrides { time_limit: Some(1e-6), refine, ..Overrides::default() };
        let mut settings = free(&["k", "c", "x0", "v0"]);
        settings.method = method;
        let f = run(&scene_of(OSCILLATOR, &ov), &ov, &data, &settings).unwrap();
        let what = format!("refine {refine}, {method:?}");
        assert!(!f.report.converged && !f.trusted(), "{what}");
        assert_eq!(f.report.status, fit::TIME_LIMIT_REACHED, "{what}");
        assert!(f.report.status_text.contains("the time limit of 0.000001 s"), "{what}: {}", f.report.status_text);
        assert!(f.report.iterations <= 1, "{what}: {} iterations", f.report.iterations);
    }
}

/// A damping `√(c − 0.295)` undefined below c = 0.295, the reduced fit started on the
/// bound c ≤ 0.3, which Ipopt's first point moves inside: the equations of motion cannot
/// be evaluated there, and the error says the fit did not converge (exit 3), not that
/// its input was wrong.
#[test]
fn a_point_where_the_fit_cannot_be_evaluated_is_a_fit_not_converged() {
    let text = OSCILLATOR.replace("x = \"-c*x_dot\"", "x = \"-sqrt(c - 0.295)*x_dot\"").replace("c = 0.2", "c = 0.3");
    let ov = Overrides::default();
    let data = csv(&oscillator_times(), &[("x", &|t| oscillator(t, 1.0, 4.0, 0.3, 1.2, -0.5))]);
    let mut settings = free(&["k", "c<=0.3"]);
    settings.method = FitMethod::Reduced;
    let e = run(&scene_of(&text, &ov), &ov, &data, &settings).unwrap_err();
    let why = e.not_converged().unwrap_or_else(|| panic!("an input error: {e}"));
    assert!(why.starts_with("Ipopt tried a point where the fit cannot be evaluated"), "{why}");
    // An input error is not.
    let e = run(&scene_of(OSCILLATOR, &ov), &ov, &data, &free(&["kk"])).unwrap_err();
    assert!(e.not_converged().is_none(), "{e}");
}

/// Without standard deviations, a fitted motion whose residuals are as large as the
/// data's own spread is warned of: the oscillator with only its damping free (k = 3)
/// against data oscillating at ω = 3 explains little of them; the same scene with k free
/// explains them and is not warned of.
#[test]
fn a_fit_that_explains_little_of_the_data_is_warned() {
    let ov = Overrides::default();
    let scene = scene_of(OSCILLATOR, &ov);
    let data = csv(&oscillator_times(), &[("x", &|t| oscillator(t, 1.0, 9.0, 0.3, 1.0, 0.0))]);
    let warned = |f: &Fit| f.report.warnings.iter().any(|w| w.contains("of the data's variation about their means"));
    let f = run(&scene, &ov, &data, &free(&["c>=0"])).unwrap();
    assert!(warned(&f), "c = {}: {:?}", f.report.parameters["c"].value, f.report.warnings);
    let f = run(&scene, &ov, &data, &free(&["k", "c>=0"])).unwrap();
    assert_recovered(&f, &[("k", 9.0), ("c", 0.3)], 1e-6);
    assert!(!warned(&f), "{:?}", f.report.warnings);
}

/// A driven, damped oscillator `x'' = −k x − c x' + A cos(w t)` whose drive's amplitude
/// and frequency are fitted with `k` and `c` (the data: the closed form at k = 2.5,
/// c = 0.3, A = 1, w = 1.5, at 80 times over 30 s, standard deviations 0.01 stated).
/// From k = 2, c = 0.1, A = 0.8, w = 1.3 the all-at-once fit converges to the undamped
/// resonance `c = 0`, `w = √k`, where the drive's amplitude and frequency trade against
/// the stiffness and the curvature is singular; the misfit there is thousands of times
/// what the standard deviations explain. That is a fit not converged, which says where
/// it ended (before: "cannot all be determined from the data", exit 1, no values). From
/// nearer values the same fit recovers the closed form's.
#[test]
fn a_fit_that_ends_at_a_degenerate_point_that_misses_the_data_is_not_converged_and_says_where() {
    const DRIVEN: &str = "[scene]\nname = \"driven\"\nlagrangian = \"1/2*x_dot^2 - 1/2*k*x^2\"\n\
                          [parameters]\nk = 2.0\nc = 0.1\nA = 0.8\nw = 1.3\n\
                          [[coordinates]]\nname = \"x\"\ninitial = 0.5\nvelocity = 0\n\
                          [forces]\nx = \"-c*x_dot + A*cos(w*t)\"\n\
                          [time]\nstart = 0\nend = 30\nnodes = 1200\n[discretization]\noperator = \"SBP484\"\n";
    let (k, c, a, w) = (2.5_f64, 0.3_f64, 1.0_f64, 1.5_f64);
    // Steady response X cos wt + Y sin wt, and the decaying free motion from x = 0.5, v = 0.
    let d = (k - w * w).powi(2) + (c * w).powi(2);
    let (x_s, y_s) = (a * (k - w * w) / d, a * c * w / d);
    let (g, wd) = (c / 2.0, (k - c * c / 4.0).sqrt());
    let (p, q) = (0.5 - x_s, (0.0 - y_s * w + g * (0.5 - x_s)) / wd);
    let exact = |t: f64| (-g * t).exp() * (p * (wd * t).cos() + q * (wd * t).sin()) + x_s * (w * t).cos() + y_s * (w * t).sin();
    let mut data = String::from("t,x,sigma_x\n");
    for i in 0..80 {
        let t = 0.5 + 29.5 * i as f64 / 79.0;
        data += &format!("{t:?},{:?},0.01\n", exact(t));
    }
    let ov = Overrides::default();
    let scene = scene_of(DRIVEN, &ov);
    let settings = free(&["k>=0", "c>=0", "A", "w>=0"]);
    let e = run(&scene, &ov, &data, &settings).unwrap_err();
    let why = e.not_converged().unwrap_or_else(|| panic!("not a fit not converged: {e}"));
    for part in
        ["the fit ended at k = ", "c = 0", "times what the data's standard deviations explain", "`w`", "a local minimum or a saddle point"]
    {
        assert!(why.contains(part), "{part:?} not in: {why}");
    }
    let near = Overrides { set: vec![("k".into(), "2.4".into()), ("w".into(), "1.45".into())], ..Overrides::default() };
    let scene = scene_of(DRIVEN, &near);
    let f = run(&scene, &near, &data, &settings).unwrap();
    assert!(f.trusted(), "{}: {}", f.report.status, f.outcome.verification.reason);
    assert_recovered(&f, &[("k", k), ("c", c), ("A", a), ("w", w)], 1e-6);
}

/// An all-at-once fit that Ipopt ends at its acceptable level is taken on to the fit's
/// tolerance by the reduced fit. The damping of an overdamped spring, c = 1e6, from
/// 3e5 (x over 1e4 s, noise-free, 64 nodes, so that the fit's minimum carries the
/// discretization's error, 7.6e-6 relative): Ipopt's acceptable level, which bounds the
/// gradient absolutely, had stopped it at c = 999992.3255, 6e-8 relative from the
/// minimum the reduced fit finds (999992.3856), with a standard error 2000 times the
/// minimum's.
#[test]
fn an_all_at_once_fit_stopped_at_the_acceptable_level_is_taken_on_to_the_minimum() {
    let text = "[scene]\nname = \"overdamped\"\nlagrangian = \"1/2*x_dot^2 - 1/2*x^2\"\n[parameters]\nc = 3e5\n\
                [[coordinates]]\nname = \"x\"\ninitial = 1\nvelocity = 0\n[forces]\nx = \"-c*x_dot\"\n\
                [time]\nstart = 0\nend = 1e4\nnodes = 64\n";
    let ov = Overrides::default();
    let scene = scene_of(text, &ov);
    let c = 1e6_f64;
    let d = (c * c - 4.0).sqrt();
    let (r1, r2) = ((-c + d) / 2.0, (-c - d) / 2.0);
    let exact = |t: f64| (r2 * (r1 * t).exp() - r1 * (r2 * t).exp()) / (r2 - r1);
    let times: Vec<f64> = (1..=40).map(|i| 250.0 * i as f64).collect();
    let data = csv(&times, &[("x", &exact)]);
    let all_at_once = run(&scene, &ov, &data, &free(&["c>=0"])).unwrap();
    let mut settings = free(&["c>=0"]);
    settings.method = FitMethod::Reduced;
    let reduced = run(&scene, &ov, &data, &settings).unwrap();
    for f in [&all_at_once, &reduced] {
        assert!(f.trusted(), "{}: {}", f.report.status, f.outcome.verification.reason);
        assert_recovered(f, &[("c", c)], 2e-5);
    }
    let (a, b) = (all_at_once.report.parameters["c"].value, reduced.report.parameters["c"].value);
    assert!((a - b).abs() <= 1e-8 * c, "all at once c = {a}, reduced c = {b}");
    // With the limited-memory Hessian the reduced fit, which needs the exact one, does
    // not go on: the fit ends as Ipopt left it (it panicked there).
    let mut limited = free(&["c>=0"]);
    limited.hessian = FitHessian::LimitedMemory;
    let l = run(&scene, &ov, &data, &limited).unwrap();
    assert!(l.report.converged, "{}", l.report.status);
    assert_recovered(&l, &[("c", c)], 1e-4);
}
