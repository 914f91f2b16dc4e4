//! What the fit tests share: the damped oscillator and its closed form, data tables, the
//! fit of a scene's text, and the checks of a fit's values and stop.
#![allow(dead_code)]

use std::f64::consts::PI;

use skg_core::fit::{fit, Data, Fit, FitError, FitSettings, FreeParameter};
use skg_core::scene::{Overrides, Scene, SceneFile};

/// A damped oscillator with its initial state as parameters.
pub const OSCILLATOR: &str = r#"
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
pub fn oscillator(t: f64, m: f64, k: f64, c: f64, x0: f64, v0: f64) -> f64 {
    let w0 = (k / m).sqrt();
    let g = c / (2.0 * m);
    let wd = (w0 * w0 - g * g).sqrt();
    (-g * t).exp() * (x0 * (wd * t).cos() + (v0 + g * x0) / wd * (wd * t).sin())
}

/// A CSV text with a column `t` and one column per named function of time.
pub fn csv(times: &[f64], columns: &[(&str, &dyn Fn(f64) -> f64)]) -> String {
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

pub fn scene_of(text: &str, ov: &Overrides) -> Scene {
    SceneFile::parse(text, "scene.toml").unwrap().resolve(ov).unwrap()
}

pub fn free(items: &[&str]) -> FitSettings {
    FitSettings::new(items.iter().map(|t| FreeParameter::parse(t).unwrap()).collect())
}

pub fn run(scene: &Scene, ov: &Overrides, data_text: &str, settings: &FitSettings) -> Result<Fit, FitError> {
    let data = Data::parse(data_text, "data.csv", scene)?;
    fit(scene, ov, &data, settings)
}

pub fn assert_recovered(f: &Fit, truth: &[(&str, f64)], rel: f64) {
    assert!(f.report.converged, "status {}", f.report.status);
    for (name, value) in truth {
        let got = f.report.parameters[*name].value;
        assert!((got - value).abs() <= rel * value.abs().max(1e-3), "{name}: fitted {got}, truth {value}");
    }
}

pub fn oscillator_times() -> Vec<f64> {
    (0..40).map(|i| 0.07 + i as f64 * 0.147).collect()
}

/// The fit stopped itself at a KKT point (docs/fitting.md, "Stopping") within `most`
/// iterations, not at Ipopt's acceptable level: the equations of motion of these fits
/// stagnate at their round-off level above the scene's `tol`, where Ipopt alone went on
/// for 5 more iterations (the disk: 9 then, 6 or 7 now, whatever the BLAS kernels).
pub fn assert_stopped_at_a_kkt_point(f: &Fit, most: usize) {
    let status = f.report.status.as_str();
    assert!(matches!(status, "Solve_Succeeded" | "Ipopt_Converged_To_Round_Off"), "status {status}");
    assert!(f.report.iterations <= most, "{} iterations", f.report.iterations);
    assert!(f.report.warnings.iter().all(|w| !w.contains("acceptable level")), "{:?}", f.report.warnings);
}

/// Seeded standard normal numbers (xorshift64 and Box–Muller).
pub struct Normal(pub u64);
impl Normal {
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub fn next(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * PI * v).cos()
    }
}
