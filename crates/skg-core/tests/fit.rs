//! Fits against independent truth: data generated from closed forms or tight-tolerance
//! integrations with known parameters, fitted from other starting values (docs/fitting.md).
//! How a fit chooses its discretization: tests/fit_discretization.rs; how it ends when it
//! cannot converge, and its warnings: tests/fit_endings.rs.
#![cfg(feature = "ipopt")]

mod common;
mod fitting;

use fitting::*;

use std::f64::consts::PI;

use skg_core::fit::{self, fit, Data, FitError, FitMethod, FitSettings};
use skg_core::scene::{Overrides, SceneFile};

#[test]
fn an_oscillators_stiffness_damping_and_initial_state_are_recovered() {
    let ov = Overrides::default();
    let scene = scene_of(OSCILLATOR, &ov);
    let (k, c, x0, v0) = (4.0, 0.3, 1.2, -0.5);
    let data = csv(&oscillator_times(), &[("x", &|t| oscillator(t, 1.0, k, c, x0, v0))]);
    let f = run(&scene, &ov, &data, &free(&["k", "c", "x0", "v0"])).unwrap();
    assert_recovered(&f, &[("k", k), ("c", c), ("x0", x0), ("v0", v0)], 1e-6);
    assert!(f.trusted(), "verification: {}", f.outcome.verification.reason);
    assert!(f.report.parameters.values().all(|p| p.std_error.is_some_and(|s| s > 0.0)));
    assert_eq!((f.report.misfit.points, f.report.misfit.dof), (40, 36));
    assert_stopped_at_a_kkt_point(&f, 30);
    // The fitted scene holds the fitted values.
    for (name, value) in [("k", k), ("c", c)] {
        assert!((f.fitted.parameters[name] - value).abs() < 1e-6 * value, "{name} in the fitted scene");
    }
    assert!(f.fitted_toml.starts_with("# Fitted by skg-solve"));
    let refit = scene_of(&f.fitted_toml, &ov);
    assert_eq!(refit.parameters["k"], f.report.parameters["k"].value);
}

/// θ'' = −w sin θ − c θ' released at rest from `a`, by RK4 with a step far below the
/// fit's discretization error: θ at `times`.
fn damped_pendulum(w: f64, c: f64, a: f64, times: &[f64]) -> Vec<f64> {
    let f = |s: [f64; 2]| [s[1], -w * s[0].sin() - c * s[1]];
    let (mut s, mut t, h) = ([a, 0.0], 0.0, 1e-4_f64);
    times
        .iter()
        .map(|&end| {
            while t < end - 1e-12 {
                let h = h.min(end - t);
                let k1 = f(s);
                let k2 = f([s[0] + h / 2.0 * k1[0], s[1] + h / 2.0 * k1[1]]);
                let k3 = f([s[0] + h / 2.0 * k2[0], s[1] + h / 2.0 * k2[1]]);
                let k4 = f([s[0] + h * k3[0], s[1] + h * k3[1]]);
                for i in 0..2 {
                    s[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
                }
                t += h;
            }
            s[0]
        })
        .collect()
}

/// Noisy data weighted by 1/σ² = 1e4: the dual infeasibility stalls at the gradient's
/// rounding above `tol`, and the fit stops where Newton's step on the misfit no longer
/// moves the parameters (Ipopt went on to its acceptable level: 11 iterations on this
/// scene's first version), with the reduced fit reaching the same values.
#[test]
fn a_noisy_fit_stops_where_the_parameters_stop_moving() {
    let text = "[scene]\nname = \"damped pendulum\"\nlagrangian = \"1/2*th_dot^2 + w*cos(th)\"\n\
                [parameters]\nw = 7\nc = 0.1\na = 1\n[[coordinates]]\nname = \"th\"\ninitial = \"a\"\nvelocity = 0\n\
                [forces]\nth = \"-c*th_dot\"\n[time]\nstart = 0\nend = 6\nnodes = 400\n[discretization]\noperator = \"SBP484\"\n";
    let ov = Overrides::default();
    let scene = scene_of(text, &ov);
    let times: Vec<f64> = (0..50).map(|i| 0.1 + i as f64 * 5.9 / 49.0).collect();
    let th = damped_pendulum(9.0, 0.4, 1.2, &times);
    let rows: String =
        times.iter().zip(&th).enumerate().map(|(i, (t, v))| format!("{t:?},{:?},0.01\n", v + 0.01 * (1.7 * i as f64).sin())).collect();
    let data = format!("t,th,sigma_th\n{rows}");
    let f = run(&scene, &ov, &data, &free(&["w>=0", "c>=0", "a"])).unwrap();
    assert_stopped_at_a_kkt_point(&f, 8);
    for (name, truth, within) in [("w", 9.0, 0.05), ("c", 0.4, 0.02), ("a", 1.2, 0.02)] {
        let p = &f.report.parameters[name];
        assert!((p.value - truth).abs() < within, "{name} = {} ± {:?}", p.value, p.std_error);
    }
    let mut reduced = free(&["w>=0", "c>=0", "a"]);
    reduced.method = FitMethod::Reduced;
    let r = run(&scene, &ov, &data, &reduced).unwrap();
    assert_stopped_at_a_kkt_point(&r, 12);
    for name in ["w", "c", "a"] {
        let (a, b) = (f.report.parameters[name].value, r.report.parameters[name].value);
        assert!((a - b).abs() <= 1e-8 * a.abs(), "{name}: all at once {a}, reduced {b}");
    }
}

#[test]
fn the_limited_memory_hessian_reaches_the_same_values() {
    let ov = Overrides::default();
    let scene = scene_of(OSCILLATOR, &ov);
    let data = csv(&oscillator_times(), &[("x", &|t| oscillator(t, 1.0, 4.0, 0.3, 1.0, 0.0))]);
    let mut settings = free(&["k", "c"]);
    settings.hessian = "limited-memory".parse().unwrap();
    settings.max_iter = 1000;
    let f = run(&scene, &ov, &data, &settings).unwrap();
    assert_recovered(&f, &[("k", 4.0), ("c", 0.3)], 1e-5);
}

#[test]
fn a_bound_the_data_push_against_holds_and_is_reported() {
    let ov = Overrides { set: vec![("c".into(), "0.6".into())], ..Default::default() };
    let scene = scene_of(OSCILLATOR, &ov);
    let data = csv(&oscillator_times(), &[("x", &|t| oscillator(t, 1.0, 3.0, 0.3, 1.0, 0.0))]);
    let f = run(&scene, &ov, &data, &free(&["k", "c>=0.5"])).unwrap();
    let c = &f.report.parameters["c"];
    assert!(f.report.converged, "{}", f.report.status);
    assert!((c.value - 0.5).abs() < 1e-6, "c = {}", c.value);
    assert!(c.at_bound && c.bound == [Some(0.5), None]);
    assert!(f.report.warnings.iter().any(|w| w.contains("`c` ended on its bound")), "{:?}", f.report.warnings);
    // The reduced fit holds the same bound.
    let mut reduced = free(&["k", "c>=0.5"]);
    reduced.method = FitMethod::Reduced;
    let r = run(&scene, &ov, &data, &reduced).unwrap();
    let (k, rc) = (&r.report.parameters["k"], &r.report.parameters["c"]);
    assert!(r.report.converged && rc.at_bound && (rc.value - 0.5).abs() < 1e-6, "{}: c = {}", r.report.status, rc.value);
    assert!((k.value - f.report.parameters["k"].value).abs() < 1e-6, "k = {} against {}", k.value, f.report.parameters["k"].value);
    // A starting value outside the bounds is refused before the fit.
    let e = run(&scene, &ov, &data, &free(&["c in [0, 0.4]"])).unwrap_err();
    assert!(e.to_string().contains("the starting value of `c` (0.6) is outside its bounds [0, 0.4]"), "{e}");
}

#[test]
fn a_mass_and_a_stiffness_together_are_refused_as_undetermined() {
    let ov = Overrides::default();
    let scene = scene_of(OSCILLATOR, &ov);
    let data = csv(&oscillator_times(), &[("x", &|t| oscillator(t, 1.0, 4.0, 0.3, 1.0, 0.0))]);
    // x'' = −(k/m) x − (c/m) x': only the ratios are determined.
    let e = run(&scene, &ov, &data, &free(&["m", "k", "c"])).unwrap_err();
    assert!(matches!(e, FitError::NotIdentifiable(_)), "{e}");
    let text = e.to_string();
    assert!(text.contains("`m`, `k`, `c` cannot all be determined from the data"), "{text}");
    assert!(text.contains("δm/m = 1.000, δk/k = 1.000, δc/c = 1.000"), "{text}");
    // A parameter the data do not see at all.
    let unseen = OSCILLATOR.replace("v0 = 0\n", "v0 = 0\nunused = 2\n");
    let scene = scene_of(&unseen, &ov);
    let e = run(&scene, &ov, &data, &free(&["k", "unused"])).unwrap_err();
    assert!(e.to_string().starts_with("`unused` cannot be determined from the data"), "{e}");
}

#[test]
fn settings_that_do_not_fit_the_scene_are_refused() {
    let ov = Overrides::default();
    let scene = scene_of(OSCILLATOR, &ov);
    let data = csv(&[0.5, 1.0, 2.0], &[("x", &|t| t)]);
    for (items, expected) in [
        (&["kk"][..], "free parameter `kk` is not a parameter of the scene (its parameters: m, k, c, x0, v0)"),
        (&["k", "k"][..], "free parameter `k` is named twice"),
        (&[][..], "no free parameter"),
    ] {
        let e = run(&scene, &ov, &data, &free(items)).unwrap_err();
        assert!(e.to_string().contains(expected), "{items:?}: {e}");
    }
    // What only the all-at-once fit does.
    for (hessian, start, expected) in [
        ("limited-memory", "auto", "the reduced fit gives Ipopt the exact Hessian"),
        ("exact", "data", "starting from the data is for the all-at-once fit"),
    ] {
        let mut settings = free(&["k"]);
        (settings.method, settings.hessian, settings.start) = (FitMethod::Reduced, hessian.parse().unwrap(), start.parse().unwrap());
        let e = run(&scene, &ov, &data, &settings).unwrap_err();
        assert!(e.to_string().contains(expected), "{hessian}, {start}: {e}");
    }
}

/// The plane pendulum θ'' = −(g/l) sin θ released at rest from θ0, by RK4 with a step
/// far below the fit's discretization error: (x, y) at `t`.
fn pendulum_at(theta0: f64, t: f64) -> (f64, f64) {
    let (g, l) = (common::G, 1.0);
    let steps = 60_000;
    let h = t / steps as f64;
    let f = |s: [f64; 2]| [s[1], -(g / l) * s[0].sin()];
    let mut s = [theta0, 0.0];
    for _ in 0..steps {
        let k1 = f(s);
        let k2 = f([s[0] + h / 2.0 * k1[0], s[1] + h / 2.0 * k1[1]]);
        let k3 = f([s[0] + h / 2.0 * k2[0], s[1] + h / 2.0 * k2[1]]);
        let k4 = f([s[0] + h * k3[0], s[1] + h * k3[1]]);
        for i in 0..2 {
            s[i] += h / 6.0 * ([k1[i], k2[i], k3[i], k4[i]].iter().zip([1.0, 2.0, 2.0, 1.0]).map(|(k, w)| k * w).sum::<f64>());
        }
    }
    (l * s[0].sin(), -l * s[0].cos())
}

#[test]
fn the_release_angle_that_puts_a_pendulum_at_a_point_is_found() {
    let text = std::fs::read_to_string(common::scenario("pendulum")).unwrap();
    let ov = Overrides { nodes: Some(512), operator: Some("SBP484".parse().unwrap()), ..Default::default() };
    let scene = scene_of(&text, &ov);
    let truth = 1.15;
    let (x, y) = pendulum_at(truth, 3.0);
    let data = format!("t,x,y\n3,{x:?},{y:?}\n");
    let f = run(&scene, &ov, &data, &free(&["theta0 in [0, 3]"])).unwrap();
    assert_recovered(&f, &[("theta0", truth)], 1e-6);
    assert!(f.trusted(), "verification: {}", f.outcome.verification.reason);
}

#[test]
fn a_rolling_disks_incline_and_speed_are_recovered_from_its_track() {
    let text = std::fs::read_to_string(common::scenario("rolling_disk"))
        .unwrap()
        .replace("ID = 0.25\n", "ID = 0.25\nv0 = 4\n")
        .replace("alpha = \"pi/6\"", "alpha = 0.4")
        .replace("velocity = 5\n\n[[coordinates]]\nname = \"y\"", "velocity = \"v0\"\n\n[[coordinates]]\nname = \"y\"")
        .replace("name = \"theta\"\ninitial = 0\nvelocity = 5", "name = \"theta\"\ninitial = 0\nvelocity = \"v0/R\"");
    let ov = Overrides { nodes: Some(512), operator: Some("SBP484".parse().unwrap()), ..Default::default() };
    let scene = scene_of(&text, &ov);
    assert_eq!(scene.initial_v[0], 4.0, "the speed is a parameter");
    // x'' etc. of the disk rolling with φ = t: k = g sin α M/(M + IS/R²).
    let (alpha, v0) = (PI / 6.0, 5.0);
    let k = common::G * alpha.sin() / 1.5;
    let times: Vec<f64> = (1..=30).map(|i| i as f64 * 2.0 * PI / 30.0).collect();
    let x = |t: f64| v0 * t.sin() + k * t.sin().powi(2) / 2.0;
    let y = |t: f64| v0 * (1.0 - t.cos()) + k * (t / 2.0 - (2.0 * t).sin() / 4.0);
    let data = csv(&times, &[("x", &x), ("y", &y)]);
    // A scene with constraints starts from the solve at the starting values (FitStart::Auto).
    let f = run(&scene, &ov, &data, &free(&["alpha in [0, 1.5]", "v0"])).unwrap();
    assert_recovered(&f, &[("alpha", alpha), ("v0", v0)], 1e-6);
    assert!(f.trusted(), "verification: {}", f.outcome.verification.reason);
    assert_stopped_at_a_kkt_point(&f, 10);
    assert_eq!(f.report.method, FitMethod::AllAtOnce);

    // The reduced fit: the same discrete optimum, each Ipopt iterate one factorization of
    // ∂R/∂P for its derivatives (and none for its solves, which chord steps on that
    // factorization finish).
    let mut reduced = free(&["alpha in [0, 1.5]", "v0"]);
    reduced.method = FitMethod::Reduced;
    let r = run(&scene, &ov, &data, &reduced).unwrap();
    assert_recovered(&r, &[("alpha", alpha), ("v0", v0)], 1e-6);
    assert!(r.trusted(), "verification: {}", r.outcome.verification.reason);
    assert_stopped_at_a_kkt_point(&r, 12);
    for name in ["alpha", "v0"] {
        let (a, b) = (f.report.parameters[name].value, r.report.parameters[name].value);
        assert!((a - b).abs() <= 1e-9 * a.abs(), "{name}: all at once {a}, reduced {b}");
    }
    let work = r.report.equations_of_motion.expect("the reduced fit's solves");
    assert_eq!((r.report.sizes.variables, r.report.sizes.constraints), (2, 0));
    assert!(work.solves >= r.report.iterations && work.failures == 0, "{work:?}");
    assert!(work.derivatives <= r.report.iterations + 2, "{work:?}");
}

/// The shipped example where single shooting from the same start stops in a wrong
/// minimum (docs/benchmarks.md#fitting): a double pendulum's release angles from both
/// masses' positions at 100 times over 5 s, the data a tight scipy integration of
/// hand-derived equations (examples/fit/shooting.py). The scene's [fit] table names the
/// free angles and the data file, beside the scene.
#[test]
fn a_double_pendulums_release_angles_are_recovered_where_shooting_stops_short() {
    let path = common::root().join("examples/fit/double_pendulum.toml");
    let file = SceneFile::load(&path).unwrap();
    let settings = FitSettings::new(fit::free_of_scene(&file).unwrap());
    let data_path = fit::data_of_scene(&file).unwrap().unwrap();
    assert_eq!(data_path, path.with_file_name("double_pendulum.csv"));
    let ov = Overrides::default();
    let scene = file.resolve(&ov).unwrap();
    let data = Data::read(&data_path, &scene).unwrap();
    assert_eq!((scene.parameters["a1"], scene.parameters["a2"]), (1.9, 2.4), "the starting values");
    let f = fit(&scene, &ov, &data, &settings).unwrap();
    assert_recovered(&f, &[("a1", 2.0), ("a2", 2.5)], 1e-6);
    assert!(f.trusted(), "verification: {}", f.outcome.verification.reason);
    // fitted.toml's [fit] table names the copy of the data written beside it.
    let fitted = SceneFile::parse(&f.fitted_toml, "fitted.toml").unwrap();
    assert_eq!(fitted.fit.as_ref().and_then(|t| t.data.as_ref()).map(|d| d.get_ref().as_str()), Some("data.csv"));
}

/// The reduced fit is single shooting on the discrete equations: on the double
/// pendulum it stops in the wrong minimum where scipy's shooting stops (a1 = 2.1656,
/// a2 = 2.3065, docs/benchmarks.md#fitting), and verifies there; its trial points far
/// from Ipopt's iterate, where Newton's method fails, cost a bounded number of solves
/// (each trial starts from the iterate, not from a rejected farther trial).
#[test]
fn the_reduced_fit_of_the_double_pendulum_stops_where_shooting_does() {
    let path = common::root().join("examples/fit/double_pendulum.toml");
    let file = SceneFile::load(&path).unwrap();
    let mut settings = FitSettings::new(fit::free_of_scene(&file).unwrap());
    settings.method = FitMethod::Reduced;
    let data_path = fit::data_of_scene(&file).unwrap().unwrap();
    let scene = file.resolve(&Overrides::default()).unwrap();
    let data = Data::read(&data_path, &scene).unwrap();
    let f = fit(&scene, &Overrides::default(), &data, &settings).unwrap();
    assert_recovered(&f, &[("a1", 2.1656), ("a2", 2.3065)], 5e-3);
    assert!(f.report.misfit.sum_of_squares > 100.0, "misfit {}", f.report.misfit.sum_of_squares);
    let work = f.report.equations_of_motion.unwrap();
    assert!(work.solves <= 400 && work.failures <= 60, "{work:?}");
}

#[test]
fn a_friction_coefficient_is_recovered_from_a_sliding_block() {
    // The block of friction_stop observed while it slides (the span ends before it stops).
    let text = std::fs::read_to_string(common::test_scene("friction_stop")).unwrap().replace("end = 1.5", "end = 0.5");
    let ov = Overrides { set: vec![("mu".into(), "0.25".into())], ..Default::default() };
    let scene = scene_of(&text, &ov);
    // While it slides: x = v0 t − μ g t²/2 (it stops at v0/(μ g) = 0.58 s for μ = 0.35).
    let mu = 0.35;
    let times: Vec<f64> = (1..=20).map(|i| i as f64 * 0.025).collect();
    let data = csv(&times, &[("x", &|t| 2.0 * t - mu * common::G * t * t / 2.0)]);
    let f = run(&scene, &ov, &data, &free(&["mu in [0, 2]"])).unwrap();
    // The regularized friction μ N v/√(v² + ε²) is μ N to (ε/v)²/2 ≤ 2e-5 while v ≥ 0.2.
    assert_recovered(&f, &[("mu", mu)], 1e-4);
}

#[test]
fn bad_data_files_are_refused_with_their_line() {
    let ov = Overrides::default();
    let scene = scene_of(OSCILLATOR, &ov);
    let dir = std::env::temp_dir().join(format!("skg-fit-bad-data-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text, expected) in [
        ("no_t.csv", "x\n1\n", "no_t.csv:1: no column `t`"),
        ("unknown.csv", "t,z\n0,1\n", "unknown.csv:1: column `z`: is not a coordinate of the scene"),
        ("late.csv", "t,x\n1,1\n7,2\n", "late.csv:3: column `t`: t = 7 is outside the scene's span [0, 6]"),
        ("nan.csv", "t,x\n1,1\n2,nan\n", "nan.csv:3: column `x`: nan is not a finite number"),
        ("unsorted.csv", "# c\nt,x\n2,1\n1,2\n", "unsorted.csv:4: column `t`: t = 1 does not come after the previous row's 2"),
        ("short.csv", "t,x\n1\n", "short.csv:2: 1 fields, the header has 2 columns"),
        ("text.csv", "t,x\n1,abc\n", "text.csv:2: column `x`: `abc` is not a number"),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let e = Data::read(&path, &scene).unwrap_err().to_string();
        assert!(e.starts_with(&path.display().to_string()) && e.contains(expected), "{name}: {e}");
    }
    let missing = Data::read(&dir.join("absent.csv"), &scene).unwrap_err().to_string();
    assert!(missing.contains("absent.csv: cannot read the data file"), "{missing}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Repeated fits of noisy data: the estimates scatter around the truth as the standard
/// errors say (inside three of them, and the errors within 30 % of the observed spread;
/// with 40 fits the spread itself is known to about 11 %).
#[test]
fn standard_errors_describe_the_scatter_of_repeated_noisy_fits() {
    let ov = Overrides::default();
    let scene = scene_of(OSCILLATOR, &ov);
    let (k, c, sigma) = (4.0, 0.3, 0.01);
    let mut rng = Normal(0x05ee_df17);
    let (mut estimates, mut errors) = (vec![], vec![]);
    for _ in 0..40 {
        let mut text = String::from("t,x,sigma_x\n");
        for t in oscillator_times() {
            text += &format!("{t:?},{:?},{sigma}\n", oscillator(t, 1.0, k, c, 1.0, 0.0) + sigma * rng.next());
        }
        let f = run(&scene, &ov, &text, &free(&["k", "c"])).unwrap();
        assert!(f.report.converged, "{} (constraint violation {:e})", f.report.status, f.report.max_constraint_violation);
        let p = &f.report.parameters;
        estimates.push([p["k"].value, p["c"].value]);
        errors.push([p["k"].std_error.unwrap(), p["c"].std_error.unwrap()]);
    }
    for (j, truth) in [k, c].into_iter().enumerate() {
        let inside = estimates.iter().zip(&errors).filter(|(e, s)| (e[j] - truth).abs() <= 3.0 * s[j]).count();
        assert!(inside >= 38, "parameter {j}: {inside} of 40 inside three standard errors");
        let mean = estimates.iter().map(|e| e[j]).sum::<f64>() / 40.0;
        let spread = (estimates.iter().map(|e| (e[j] - mean).powi(2)).sum::<f64>() / 39.0).sqrt();
        let se = errors.iter().map(|s| s[j]).sum::<f64>() / 40.0;
        assert!((se / spread - 1.0).abs() < 0.3, "parameter {j}: standard error {se:e}, Monte-Carlo spread {spread:e}");
    }
}

/// `fitted.toml` names its directory's `data.csv` as its data, and a fit reads that file
/// back: the data with their gaps (a row that does not observe `y` is an empty cell, not
/// NaN) and the fitted and residual columns passed over. Fitted again from there, the
/// fit starts at its solution and ends there.
#[test]
fn a_fitted_scene_is_fitted_again_from_its_own_directory() {
    let text = r#"
[scene]
name = "two damped oscillators"
lagrangian = "1/2*(x_dot^2 + y_dot^2) - 1/2*k*(x^2 + 4*y^2)"
[parameters]
k = 3.0
c = 0.2
[[coordinates]]
name = "x"
initial = 1
velocity = 0
[[coordinates]]
name = "y"
initial = 0.5
velocity = 0
[forces]
x = "-c*x_dot"
y = "-c*y_dot"
[time]
start = 0
end = 6
nodes = 400
[discretization]
operator = "SBP484"
[fit]
free = ["k>=0", "c>=0"]
data = "data.csv"
"#;
    let (k, c) = (4.0, 0.3);
    let dir = tempfile::tempdir().unwrap();
    let mut data = String::from("t,x,y\n");
    for (i, t) in oscillator_times().into_iter().enumerate() {
        let y = if i % 3 == 0 { String::new() } else { format!("{:?}", oscillator(t, 1.0, 4.0 * k, c, 0.5, 0.0)) };
        data += &format!("{t:?},{:?},{y}\n", oscillator(t, 1.0, k, c, 1.0, 0.0));
    }
    std::fs::write(dir.path().join("data.csv"), data).unwrap();
    std::fs::write(dir.path().join("scene.toml"), text).unwrap();
    let first = dir.path().join("first");
    let fit_dir = |scene_path: &std::path::Path, out: &std::path::Path| {
        let ov = Overrides::default();
        let mut scene = SceneFile::load(scene_path).unwrap().resolve(&ov).unwrap();
        let data = Data::read(&fit::data_of_scene(&scene.file).unwrap().unwrap(), &scene).unwrap();
        let settings = FitSettings::new(fit::free_of_scene(&scene.file).unwrap());
        fit::fit_into(out, &mut scene, &ov, &data, &settings).unwrap().0
    };
    let f = fit_dir(&dir.path().join("scene.toml"), &first);
    assert!(f.trusted(), "{}", f.outcome.verification.reason);
    assert_recovered(&f, &[("k", k), ("c", c)], 1e-6);
    let written = std::fs::read_to_string(first.join(fit::DATA_FILE)).unwrap();
    let row: Vec<&str> = written.lines().nth(1).unwrap().split(',').collect();
    // t, x, fitted_x, residual_x, y, fitted_y, residual_y: no y, no residual of it.
    assert!(row.len() == 7 && row[4].is_empty() && row[6].is_empty() && !row[5].is_empty(), "a row without y: {row:?}");
    assert!(!written.contains("NaN"));

    let again = fit_dir(&first.join(fit::FITTED_SCENE_FILE), &dir.path().join("again"));
    assert!(again.trusted(), "{}", again.outcome.verification.reason);
    assert_eq!(again.report.misfit.points, f.report.misfit.points);
    for name in ["k", "c"] {
        let (a, b) = (again.report.parameters[name].value, f.report.parameters[name].value);
        assert!((a - b).abs() <= 1e-9 * b, "{name}: {a} against {b}");
    }
}

/// Five masses on springs in a row, the first damped, the last tied to a wall by a
/// second spring: `k`, `k2` and `c` fitted from the first mass alone (the data: RK4 of
/// the linear equations, step 5e-4, at 60 times over 15 s, with seeded noise of the
/// standard deviation 0.002 the file states; from k = 3, k2 = 1, c = 0.2), each within
/// three standard errors of the truth. Each of the three is in the equations of many
/// nodes: with other noise (scipy's, seed 9) and MUMPS's AMF ordering the fit took 73 s
/// and ended on a spurious discrete solution (exit 4), with PORD, which the fit now
/// takes for two or more such columns, 2.7 s to the true values
/// (docs/benchmarks.md#fitting); on these data both orderings reach them.
#[test]
fn a_fit_with_several_parameters_in_every_equation_reaches_the_truth() {
    const FIVE: &str = "[scene]\nname = \"five masses\"\n\
        lagrangian = \"1/2*(x1_dot^2 + x2_dot^2 + x3_dot^2 + x4_dot^2 + x5_dot^2) - 1/2*k*(x1^2 + (x2-x1)^2 + (x3-x2)^2 + (x4-x3)^2 + (x5-x4)^2) - 1/2*k2*x5^2\"\n\
        [parameters]\nk = 3\nk2 = 1\nc = 0.2\n\
        [[coordinates]]\nname = \"x1\"\ninitial = 0\nvelocity = 0\n[[coordinates]]\nname = \"x2\"\ninitial = 0\nvelocity = 0\n\
        [[coordinates]]\nname = \"x3\"\ninitial = 0\nvelocity = 0\n[[coordinates]]\nname = \"x4\"\ninitial = 0\nvelocity = 0\n\
        [[coordinates]]\nname = \"x5\"\ninitial = 1\nvelocity = 0\n\
        [forces]\nx1 = \"-c*x1_dot\"\n[time]\nstart = 0\nend = 15\nnodes = 600\n[discretization]\noperator = \"SBP363\"\n";
    let (k, k2, c) = (4.0, 1.5, 0.5);
    let accel = |x: &[f64; 5], v: &[f64; 5]| {
        let mut a = [0.0; 5];
        a[0] = -k * x[0] - k * (x[0] - x[1]) - c * v[0];
        for i in 1..4 {
            a[i] = -k * (x[i] - x[i - 1]) - k * (x[i] - x[i + 1]);
        }
        a[4] = -k * (x[4] - x[3]) - k2 * x[4];
        a
    };
    let (mut x, mut v) = ([0.0, 0.0, 0.0, 0.0, 1.0], [0.0; 5]);
    let h = 5e-4;
    let mut noise = Normal(0x5eed_0f05);
    let mut data = String::from("t,x1,sigma_x1\n");
    for step in 1..=30_000 {
        let shift = |x: &[f64; 5], d: &[f64; 5], s: f64| std::array::from_fn::<f64, 5, _>(|i| x[i] + s * d[i]);
        let (k1x, k1v) = (v, accel(&x, &v));
        let (k2x, k2v) = (shift(&v, &k1v, h / 2.0), accel(&shift(&x, &k1x, h / 2.0), &shift(&v, &k1v, h / 2.0)));
        let (k3x, k3v) = (shift(&v, &k2v, h / 2.0), accel(&shift(&x, &k2x, h / 2.0), &shift(&v, &k2v, h / 2.0)));
        let (k4x, k4v) = (shift(&v, &k3v, h), accel(&shift(&x, &k3x, h), &shift(&v, &k3v, h)));
        for i in 0..5 {
            x[i] += h / 6.0 * (k1x[i] + 2.0 * k2x[i] + 2.0 * k3x[i] + k4x[i]);
            v[i] += h / 6.0 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i]);
        }
        if step % 500 == 0 {
            data += &format!("{:?},{:?},0.002\n", step as f64 * h, x[0] + 0.002 * noise.next());
        }
    }
    let ov = Overrides::default();
    let scene = scene_of(FIVE, &ov);
    let f = run(&scene, &ov, &data, &free(&["k>=0", "k2>=0", "c>=0"])).unwrap();
    assert!(f.trusted(), "{}: {}", f.report.status, f.outcome.verification.reason);
    for (name, truth) in [("k", k), ("k2", k2), ("c", c)] {
        let p = &f.report.parameters[name];
        assert!((p.value - truth).abs() <= 3.0 * p.std_error.unwrap(), "{name} = {} ± {:?}, truth {truth}", p.value, p.std_error);
    }
}
