use skg_core::fit::{fit, Data, FitSettings, FreeParameter};
use skg_core::scene::{Overrides, SceneFile};

const OSC: &str = r#"
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
nodes = 256
[discretization]
operator = "SBP484"
"#;

fn exact(t: f64, m: f64, k: f64, c: f64, x0: f64, v0: f64) -> f64 {
    let w0 = (k / m).sqrt();
    let g = c / (2.0 * m);
    let wd = (w0 * w0 - g * g).sqrt();
    (-g * t).exp() * (x0 * (wd * t).cos() + (v0 + g * x0) / wd * (wd * t).sin())
}

#[test]
fn explore() {
    let scene = SceneFile::parse(OSC, "osc.toml").unwrap().resolve(&Overrides::default()).unwrap();
    let (k, c, x0, v0) = (4.0, 0.3, 1.2, -0.5);
    let mut text = String::from("t,x\n");
    for i in 0..40 {
        let t = 0.07 + i as f64 * 0.147;
        text += &format!("{t},{}\n", exact(t, 1.0, k, c, x0, v0));
    }
    let data = Data::parse(&text, "d.csv", &scene).unwrap();
    let settings = FitSettings::new(["k", "c", "x0", "v0"].iter().map(|n| FreeParameter::unbounded(n)).collect());
    let f = fit(&scene, &Overrides::default(), &data, &settings).unwrap();
    println!("{}", serde_json::to_string_pretty(&f.report).unwrap());
    println!("verify {} {:?}", f.outcome.verification.reason, f.outcome.status);
}
