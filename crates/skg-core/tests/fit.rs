//! Fits against independent truth: data generated from closed forms or tight-tolerance
//! integrations with known parameters, fitted from other starting values (docs/fitting.md).
#![cfg(feature = "ipopt")]

mod common;

use std::f64::consts::PI;

use skg_core::fit::{self, fit, Data, Fit, FitError, FitHessian, FitMethod, FitSettings, FreeParameter};
use skg_core::scene::{Overrides, Scene, SceneFile};

/// A damped oscillator with its initial state as parameters.
const OSCILLATOR: &str = r#"
[scene]
name = "damped oscillator"
lagrangian = "1/2*m*x_dot^2 - 1/2*k*x^2"
[parameters]
m = 1
k = 3.0
c = 0.2
x0 = 1
v0 = 0
[[coordinates]]
name = "x"
initial = "x0"
velocity = "v0"
[forces]
x = "-c*x_dot"
[time]
start = 0
end = 6
nodes = 512
[discretization]
operator = "SBP484"
"#;

/// The underdamped oscillator `m x'' = −k x − c x'` from `x(0) = x0`, `x'(0) = v0`.
fn oscillator(t: f64, m: f64, k: f64, c: f64, x0: f64, v0: f64) -> f64 {
    let w0 = (k / m).sqrt();
    let g = c / (2.0 * m);
    let wd = (w0 * w0 - g * g).sqrt();
    (-g * t).exp() * (x0 * (wd * t).cos() + (v0 + g * x0) / wd * (wd * t).sin())
}

/// A CSV text with a column `t` and one column per named function of time.
fn csv(times: &[f64], columns: &[(&str, &dyn Fn(f64) -> f64)]) -> String {
    let mut text = String::from("t");
    for (name, _) in columns {
        text += &format!(",{name}");
    }
    text.push('\n');
    for &t in times {
        text += &format!("{t:?}");
        for (_, f) in columns {
            text += &format!(",{:?}", f(t));
        }
        text.push('\n');
    }
    text
}

fn scene_of(text: &str, ov: &Overrides) -> Scene {
    SceneFile::parse(text, "scene.toml").unwrap().resolve(ov).unwrap()
}

fn free(items: &[&str]) -> FitSettings {
    FitSettings::new(items.iter().map(|t| FreeParameter::parse(t).unwrap()).collect())
}

fn run(scene: &Scene, ov: &Overrides, data_text: &str, settings: &FitSettings) -> Result<Fit, FitError> {
    let data = Data::parse(data_text, "data.csv", scene)?;
    fit(scene, ov, &data, settings)
}

fn assert_recovered(f: &Fit, truth: &[(&str, f64)], rel: f64) {
    assert!(f.report.converged, "status {}", f.report.status);
    for (name, value) in truth {
        let got = f.report.parameters[*name].value;
        assert!((got - value).abs() <= rel * value.abs().max(1e-3), "{name}: fitted {got}, truth {value}");
    }
}

fn oscillator_times() -> Vec<f64> {
    (0..40).map(|i| 0.07 + i as f64 * 0.147).collect()
}

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

/// The fit stopped itself at a KKT point (docs/fitting.md, "Stopping") within `most`
/// iterations, not at Ipopt's acceptable level: the equations of motion of these fits
/// stagnate at their round-off level above the scene's `tol`, where Ipopt alone went on
/// for 5 more iterations (the disk: 9 then, 6 or 7 now, whatever the BLAS kernels).
fn assert_stopped_at_a_kkt_point(f: &Fit, most: usize) {
    let status = f.report.status.as_str();
    assert!(matches!(status, "Solve_Succeeded" | "Ipopt_Converged_To_Round_Off"), "status {status}");
    assert!(f.report.iterations <= most, "{} iterations", f.report.iterations);
    assert!(f.report.warnings.iter().all(|w| !w.contains("acceptable level")), "{:?}", f.report.warnings);
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

/// Seeded standard normal numbers (xorshift64 and Box–Muller).
struct Normal(u64);
impl Normal {
    fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn next(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * PI * v).cos()
    }
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
