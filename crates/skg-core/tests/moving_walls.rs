//! Walls whose gap depends on time: the ball on a vibrating plate against its hard-wall
//! limit (bisection on the closed-form free fall, independent of any integrator) and
//! against its regularized reference, and a piston moving at constant velocity, off
//! which the ball bounces with exactly the reflected relative velocity (docs/scenes.md).

mod common;

use common::G;
use skg_core::check::{self, CheckOptions, Table};
use skg_core::scene::{Overrides, SceneFile};
use skg_core::solve::{self, Outcome};
use skg_core::tune::{self, TuneOptions};

/// a, Ω and the drop height of scenarios/vibrating_plate.toml.
const A: f64 = 0.05;
const OMEGA: f64 = 4.0 * std::f64::consts::PI;
const Y0: f64 = 0.5;

/// The first impact of the hard-wall limit: the first time the free fall
/// `Y0 − g t²/2` meets the plate `a sin Ωt` (a sign change on a fine scan, then
/// bisection), and the velocity after it, `v+ = 2u − v-` with `u = aΩ cos Ωt`.
fn first_impact() -> (f64, f64) {
    let f = |t: f64| Y0 - 0.5 * G * t * t - A * (OMEGA * t).sin();
    let (mut lo, mut hi) = (0.0, 0.0);
    for i in 1..=100_000 {
        let t = i as f64 * 1e-5;
        if f(t) <= 0.0 {
            (lo, hi) = (t - 1e-5, t);
            break;
        }
    }
    assert!(hi > 0.0, "no impact within 1 s");
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let u = A * OMEGA * (OMEGA * hi).cos();
    (hi, 2.0 * u + G * hi)
}

/// The velocity after the first bounce, read off the free flight before the second:
/// `ẏ + g (t − t1)` over the nodes in 0.5…0.8 s (constant in free flight). Returns its
/// mean and its spread.
fn exit_velocity(o: &Outcome, t1: f64) -> (f64, f64) {
    let tr = &o.trajectory;
    let v: Vec<f64> = tr.t.iter().zip(&tr.v).filter(|(t, _)| (0.5..=0.8).contains(*t)).map(|(t, v)| v[0] + G * (t - t1)).collect();
    let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    (v.iter().sum::<f64>() / v.len() as f64, hi - lo)
}

#[test]
fn ball_on_a_vibrating_plate_bounces_off_the_moving_wall() {
    let o = common::solve("vibrating_plate", &Overrides::default());
    let scene = common::load("vibrating_plate", &Overrides::default());
    // Discretization error against the checked-in regularized reference (measured 3.3e-5).
    let r = Table::read(&common::root().join("references/vibrating_plate.csv")).unwrap();
    let opts = CheckOptions { skip_last: 2, columns: Some(vec!["y".into()]) };
    let cmp = check::compare(&Table::of_trajectory(&scene, &o.trajectory), &r, &opts).unwrap();
    assert!(cmp.max_abs < 5e-5, "{:e}", cmp.max_abs);
    // Two bounces, as in the hard-wall limit (impacts at 0.333 s and 0.872 s).
    assert_eq!(o.diagnostics.contact_episodes["plate"], 2);
    assert!(o.warnings.is_empty(), "{:?}", o.warnings);
    assert!(o.diagnostics.depends_on_time);
    // Model error: the exit velocity tends to the hard-wall 2u − v- linearly in σ; the
    // plate moves on during the finite contact. Measured 2.7572 (σ = 1/100, N = 512) and
    // 2.6916 (σ = 1/200, N = 1024) against 2.6293.
    let (t1, v_plus) = first_impact();
    assert!((t1 - 0.33295).abs() < 1e-5 && (v_plus - 2.6293).abs() < 1e-4, "closed form {t1} {v_plus}");
    let (v100, spread) = exit_velocity(&o, t1);
    // Free flight: constant up to the discretization error of Dq (measured 1.4e-5).
    assert!(spread < 3e-5, "not a free flight: spread {spread:e}");
    let stiffer = common::solve(
        "vibrating_plate",
        &Overrides { set: vec![("sigma".into(), "1/200".into())], nodes: Some(1024), ..Default::default() },
    );
    let (v200, _) = exit_velocity(&stiffer, t1);
    let (e100, e200) = (v100 - v_plus, v200 - v_plus);
    assert!(e100 > 0.0 && e100 < 0.14, "σ = 1/100: exit velocity {v100} vs {v_plus}");
    let ratio = e200 / e100;
    assert!((0.45..0.55).contains(&ratio), "σ = 1/200: {v200}, error ratio {ratio} (expected ≈ ½)");
    // The energy is not conserved between contacts, so `tune` has nothing to measure.
    let file = SceneFile::load(&common::scenario("vibrating_plate")).unwrap();
    let e = tune::tune_width(&file, &Overrides::default(), &TuneOptions::default(), |_| {}).unwrap_err().to_string();
    assert!(e.contains("depends on the time t"), "{e}");
}

/// A wall moving at constant velocity u, no gravity: in the wall's frame the Gaussian
/// potential is static, so the ball leaves with the reversed relative velocity exactly,
/// v+ = 2u − v-, whatever σ, and gains the kinetic energy ½ m (v+² − v-²) from the wall.
#[test]
fn a_piston_at_constant_velocity_reflects_the_relative_velocity() {
    let text = r#"
[scene]
name = "piston"
lagrangian = "1/2*m*y_dot^2"
[parameters]
m = 1
u = -1
Y = 1
[[coordinates]]
name = "y"
initial = 0
velocity = 2
[[walls]]
name = "piston"
h = "y - (Y + u*t)"
strength = 10
width = 0.05
[time]
start = 0
end = 1
nodes = 256
"#;
    let scene = SceneFile::parse(text, "piston.toml").unwrap().resolve(&Overrides::default()).unwrap();
    let o = solve::solve_scene(&scene).unwrap();
    assert!(o.converged(), "{}", o.status);
    let tr = &o.trajectory;
    // The contact is around t = 1/3 (2t = 1 − t); from 0.6 s on the gap is below −16σ and
    // the ball flies freely, which SBP242 integrates exactly. Measured 2.3e-12 (and 9.4e-6
    // at N = 128, where the contact spans too few nodes).
    let after: Vec<usize> = (0..tr.t.len() - 2).filter(|&k| tr.t[k] > 0.6).collect();
    let (u, v_in) = (-1.0, 2.0);
    let v_out = after.iter().map(|&k| (tr.v[k][0] - (2.0 * u - v_in)).abs()).fold(0.0, f64::max);
    assert!(v_out < 1e-9, "exit velocity off by {v_out:e}");
    let gained = tr.energy[after[after.len() - 1]] - tr.energy[0];
    let expected = 0.5 * ((2.0 * u - v_in).powi(2) - v_in * v_in);
    assert!((gained - expected).abs() < 1e-8, "energy gained {gained}, expected {expected}");
    assert!(o.diagnostics.depends_on_time);
}
