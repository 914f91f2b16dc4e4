//! The reference solutions against independent truth (closed forms derived here, a
//! root finder independent of the integrator), and the checked-in reference CSVs
//! against the closed forms and the scenes' grids. (Their regeneration by the
//! `reference` command and the `check` command line are tested in
//! crates/skg-cli/tests/reference_commands.rs.)

mod common;

use common::G;

use skg_core::check::Table;
use skg_core::scene::Overrides;
use skg_core::solve;
use skg_core::stepping::reference::{self, ReferenceOptions};

fn checked_in(file: &str) -> Table {
    Table::read(&common::root().join("references").join(file)).unwrap()
}

fn col(t: &Table, name: &str) -> Vec<f64> {
    t.column(name).unwrap_or_else(|| panic!("no column {name} in {:?}", t.columns))
}

/// Scenes with fixed walls get a hard-wall reference too (it refuses moving walls).
fn has_walls(name: &str) -> bool {
    let model = skg_core::model::Model::build(&common::load(name, &Overrides::default())).unwrap();
    !model.walls.is_empty() && (0..model.walls.len()).all(|j| !model.wall_moves(j))
}

#[test]
fn every_shipped_scene_has_its_reference_files() {
    for name in common::SHIPPED {
        let scene = common::load(name, &Overrides::default());
        let header = skg_core::discrete::trajectory::trajectory_header(&scene);
        let (times, _) = solve::grid(&scene);
        let mut files = vec![format!("{name}.csv")];
        if has_walls(name) {
            files.push(format!("{name}.hard.csv"));
        }
        for f in files {
            let t = checked_in(&f);
            assert_eq!(t.columns, header, "{f}: the solver's columns");
            assert_eq!(t.times(), times, "{f}: sampled on the scene's grid");
            let p = &t.comments[0];
            assert!(p.starts_with("skg-solve ") && p.contains("DOP853") && p.contains("rtol 1e-12"), "{f}: provenance {p}");
            assert!(p.contains(&format!("scenarios/{name}.toml")), "{f}: {p}");
        }
    }
}

#[test]
fn rolling_disk_reference_matches_closed_form() {
    let t = checked_in("rolling_disk.csv");
    let q = [col(&t, "x"), col(&t, "y"), col(&t, "theta"), col(&t, "phi")];
    let mut e = 0.0_f64;
    for (i, tt) in t.times().into_iter().enumerate() {
        for (c, exact) in common::rolling_disk_exact(tt).into_iter().enumerate() {
            e = e.max((q[c][i] - exact).abs());
        }
    }
    assert!(e < 2e-10, "max error {e:e}");
    // Constraint drift of the index-reduced integration stays at the tolerance level.
    let g = col(&t, "residual_g1").into_iter().chain(col(&t, "residual_g2")).fold(0.0_f64, |m, v| m.max(v.abs()));
    assert!(g < 1e-8, "drift {g:e}");
}

#[test]
fn knife_edge_reference_matches_closed_form() {
    // scenarios/knife_edge.toml: the coordinates' closed form, and the multiplier
    // λ = m (u ω + g sin α sin ωt) with the speed along the blade u = u0 + (g sin α/ω) sin ωt.
    let (w, u0, gs) = (2.0, 1.0, G * 0.5);
    let t = checked_in("knife_edge.csv");
    let (q, lam) = ([col(&t, "x"), col(&t, "y"), col(&t, "phi")], col(&t, "lambda_blade"));
    let mut e = 0.0_f64;
    for (i, tt) in t.times().into_iter().enumerate() {
        for (c, exact) in common::knife_edge_exact(tt).into_iter().enumerate() {
            e = e.max((q[c][i] - exact).abs());
        }
        let s = (w * tt).sin();
        e = e.max((lam[i] - ((u0 + gs / w * s) * w + gs * s)).abs());
    }
    assert!(e < 1e-9, "max error {e:e}");
}

#[test]
fn free_fall_reference_is_exact() {
    let t = checked_in("free_fall.csv");
    let x = col(&t, "x");
    for (i, tt) in t.times().into_iter().enumerate() {
        assert!((x[i] - (10.0 + 3.0 * tt - 0.5 * G * tt * tt)).abs() < 1e-12);
    }
}

/// First root τ > τ_min of the free-flight circle equation
/// (x0 + vx τ)² + (y0 + vy τ − g τ²/2)² − R² = 0 below τ_max: a sign change found by a
/// fine scan, then bisection to adjacent doubles (independent of any ODE integrator).
fn circle_hit(p: [f64; 4], tau_min: f64, tau_max: f64) -> Option<f64> {
    let [x0, y0, vx, vy] = p;
    let f = |tau: f64| (x0 + vx * tau).powi(2) + (y0 + vy * tau - 0.5 * G * tau * tau).powi(2) - 1.0;
    let steps = 200_000;
    let dt = (tau_max - tau_min) / steps as f64;
    let mut a = tau_min;
    for i in 1..=steps {
        let b = tau_min + i as f64 * dt;
        if f(a) < 0.0 && f(b) >= 0.0 {
            let (mut lo, mut hi) = (a, b);
            loop {
                let m = 0.5 * (lo + hi);
                if m <= lo || m >= hi {
                    return Some(hi);
                }
                if f(m) < 0.0 {
                    lo = m;
                } else {
                    hi = m;
                }
            }
        }
        a = b;
    }
    None
}

/// The tumbler with a hard wall in closed form: parabolas between specular reflections
/// on the unit circle. Returns the impact times and the state (x, y, vx, vy) after each.
fn tumbler_closed_form(t_end: f64) -> Vec<(f64, [f64; 4])> {
    let mut out = Vec::new();
    let (mut t0, mut s) = (0.0, [-0.5, -0.75, 0.0, 0.0]);
    while let Some(tau) = circle_hit(s, 1e-9, t_end - t0) {
        let [x0, y0, vx, vy] = s;
        let (x, y) = (x0 + vx * tau, y0 + vy * tau - 0.5 * G * tau * tau);
        let (vx1, vy1) = (vx, vy - G * tau);
        let r = (x * x + y * y).sqrt();
        let (nx, ny) = (x / r, y / r);
        let vn = vx1 * nx + vy1 * ny;
        t0 += tau;
        s = [x, y, vx1 - 2.0 * vn * nx, vy1 - 2.0 * vn * ny];
        out.push((t0, s));
    }
    out
}

#[test]
fn tumbler_hard_wall_impacts_match_closed_form() {
    let scene = common::load("tumbler", &Overrides::default());
    let (times, _) = solve::grid(&scene);
    let r = reference::hard_wall(&scene, &times, &ReferenceOptions::default()).unwrap();
    let exact = tumbler_closed_form(scene.t_end);
    assert!(exact.len() >= 2, "the closed form bounces {} times", exact.len());
    assert_eq!(r.impacts.len(), exact.len(), "{:?}", r.impacts);
    for (im, (te, _)) in r.impacts.iter().zip(&exact) {
        assert!((im.t - te).abs() < 1e-10, "impact at {} vs closed form {te} ({:e})", im.t, im.t - te);
        assert_eq!(im.wall, "drum");
    }
    // The checked-in file records the same impacts in its provenance.
    let file = checked_in("tumbler.hard.csv");
    let recorded: Vec<f64> = file
        .comments
        .iter()
        .filter_map(|c| c.strip_prefix("impact "))
        .map(|c| c.split("t = ").nth(1).unwrap().split(',').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(recorded.len(), exact.len());
    for (t, (te, _)) in recorded.iter().zip(&exact) {
        assert!((t - te).abs() < 1e-10);
    }
    // Positions at every sample: the parabola of the current flight.
    let tr = &r.trajectory;
    for (k, &t) in tr.t.iter().enumerate() {
        let (t0, s) = exact.iter().rev().find(|(ti, _)| *ti <= t).copied().unwrap_or((0.0, [-0.5, -0.75, 0.0, 0.0]));
        let tau = t - t0;
        let (x, y) = (s[0] + s[2] * tau, s[1] + s[3] * tau - 0.5 * G * tau * tau);
        assert!((tr.q[k][0] - x).abs() < 1e-10 && (tr.q[k][1] - y).abs() < 1e-10, "t = {t}");
        assert!((tr.v[k][1] - (s[3] - G * tau)).abs() < 1e-9, "t = {t}");
        // Energy is conserved by the elastic bounces.
        assert!((tr.energy[k] - tr.energy[0]).abs() < 1e-10);
    }
}

#[test]
fn incline_hard_wall_bounces_match_closed_form() {
    // Dropped from height δ above the plane y = x tan α: the first impact after
    // t1 = sqrt(2δ/g) with normal speed vn = sqrt(2gδ) cos α, then (elastic, the friction
    // impulse is tangential) one impact every T = 2 vn/(g cos α). Each impact adds the
    // friction impulse 2 μ vn up the slope, so the velocity along (cos α, sin α) is
    // s'(t) = −g sin α t + 2 μ vn k(t), k(t) = impacts before t.
    let (alpha, delta) = (std::f64::consts::PI / 6.0, 1.0 / 30.0);
    let t1 = (2.0 * delta / G).sqrt();
    let vn = (2.0 * G * delta).sqrt() * alpha.cos();
    let period = 2.0 * vn / (G * alpha.cos());
    for (name, mu) in [("incline_friction", 0.4), ("incline_frictionless", 0.0)] {
        let scene = common::load(name, &Overrides::default());
        let (times, _) = solve::grid(&scene);
        let r = reference::hard_wall(&scene, &times, &ReferenceOptions::default()).unwrap();
        let expected = ((scene.t_end - t1) / period).floor() as usize + 1;
        assert_eq!(r.impacts.len(), expected, "{name}");
        for (k, im) in r.impacts.iter().enumerate() {
            assert!((im.t - (t1 + k as f64 * period)).abs() < 1e-10, "{name}: impact {k} at {}", im.t);
            assert!((im.normal_speed - vn).abs() < 1e-10, "{name}: {}", im.normal_speed);
        }
        let tr = &r.trajectory;
        for (k, &t) in tr.t.iter().enumerate() {
            let hits = r.impacts.iter().filter(|im| im.t < t).count() as f64;
            let s_dot = tr.v[k][0] * alpha.cos() + tr.v[k][1] * alpha.sin();
            assert!((s_dot - (-G * alpha.sin() * t + 2.0 * mu * vn * hits)).abs() < 1e-10, "{name}: t = {t}");
            assert!(tr.h[k][0] <= 1e-12, "{name}: inside the wall at t = {t}");
        }
    }
}

#[test]
fn hard_walls_refuse_what_they_do_not_model() {
    let disk = common::load("rolling_disk", &Overrides::default());
    let (times, _) = solve::grid(&disk);
    let e = reference::hard_wall(&disk, &times, &ReferenceOptions::default()).unwrap_err().to_string();
    assert!(e.contains("no walls"), "{e}");
    let plate = common::load("vibrating_plate", &Overrides::default());
    let (times, _) = solve::grid(&plate);
    let e = reference::hard_wall(&plate, &times, &ReferenceOptions::default()).unwrap_err().to_string();
    assert!(e.contains("wall `plate` moves") && e.contains("regularized reference"), "{e}");
    let mut text = std::fs::read_to_string(common::scenario("pendulum")).unwrap();
    text.push_str("\n[[walls]]\nname = \"floor\"\nh = \"-y - 2\"\nstrength = 10\nwidth = 0.01\n");
    let with_wall = skg_core::scene::SceneFile::parse(&text, "pendulum+floor.toml").unwrap().resolve(&Overrides::default()).unwrap();
    let e = reference::hard_wall(&with_wall, &solve::grid(&with_wall).0, &ReferenceOptions::default()).unwrap_err().to_string();
    assert!(e.contains("walls and constraints"), "{e}");
    let tumbler = common::load("tumbler", &Overrides::default());
    let e = reference::regularized(&tumbler, &[0.1, 0.2], &ReferenceOptions::default()).unwrap_err().to_string();
    assert!(e.contains("start time"), "{e}");
    let e = reference::regularized(&tumbler, &[0.0, 0.2, 0.1], &ReferenceOptions::default()).unwrap_err().to_string();
    assert!(e.contains("increase strictly"), "{e}");
}

#[test]
fn hard_wall_sliding_from_rest_follows_newton() {
    // δ = 0: the mass starts on the plane at rest and slides with the uniform
    // acceleration g (sin α − μ cos α) along (cos α, sin α), downwards (docs/validation.md).
    let alpha = std::f64::consts::PI / 6.0;
    for (name, mu) in [("incline_friction", 0.4), ("incline_frictionless", 0.0)] {
        let ov = Overrides { set: vec![("delta".into(), "0".into())], ..Default::default() };
        let scene = common::load(name, &ov);
        let (times, _) = solve::grid(&scene);
        let r = reference::hard_wall(&scene, &times, &ReferenceOptions::default()).unwrap();
        assert!(r.impacts.is_empty(), "{name}: {:?}", r.impacts);
        assert_eq!(r.contacts.len(), 1);
        assert_eq!((r.contacts[0].t_start, r.contacts[0].t_end), (0.0, None));
        let a = G * (alpha.sin() - mu * alpha.cos());
        let tr = &r.trajectory;
        for (k, &t) in tr.t.iter().enumerate() {
            let s = -0.5 * a * t * t;
            assert!((tr.q[k][0] - (alpha.cos() + s * alpha.cos())).abs() < 1e-10, "{name} t = {t}");
            assert!((tr.q[k][1] - (alpha.sin() + s * alpha.sin())).abs() < 1e-10, "{name} t = {t}");
            assert!(tr.h[k][0].abs() < 1e-10);
        }
    }
}

#[test]
fn hard_wall_slide_inside_drum_lifts_off_where_the_normal_force_vanishes() {
    // Start at the bottom of the drum (on the wall) with v0² = 3.5 g R: sliding along
    // the circle, N = m v²/R + m g cos θ vanishes at cos θ = (2gR − v0²)/(3gR) = −1/2,
    // i.e. at height y = 1/2, with v² = g R / 2; then free flight and elastic impacts.
    let dir = tempfile::tempdir().unwrap();
    let mut text = std::fs::read_to_string(common::scenario("tumbler")).unwrap();
    let v0 = (3.5 * G).sqrt();
    for (from, to) in [
        ("initial = -0.5\nvelocity = 0", format!("initial = 0\nvelocity = {v0:?}")),
        ("initial = -0.75\nvelocity = 0", "initial = -1\nvelocity = 0".to_string()),
        ("end = 0.5", "end = 1.5".to_string()),
    ] {
        assert!(text.contains(from), "{from}");
        text = text.replacen(from, &to, 1);
    }
    let path = dir.path().join("slide.toml");
    std::fs::write(&path, text).unwrap();
    let scene = skg_core::scene::SceneFile::load(&path).unwrap().resolve(&Overrides::default()).unwrap();
    let (times, _) = solve::grid(&scene);
    let r = reference::hard_wall(&scene, &times, &ReferenceOptions::default()).unwrap();
    assert!(!r.contacts.is_empty());
    let c = &r.contacts[0];
    assert_eq!(c.t_start, 0.0);
    let t_off = c.t_end.expect("lifts off");
    // State at lift-off from a fresh run sampled there.
    let r2 = reference::hard_wall(&scene, &[0.0, t_off], &ReferenceOptions::default()).unwrap();
    let (q, v) = (&r2.trajectory.q[1], &r2.trajectory.v[1]);
    assert!((q[1] - 0.5).abs() < 1e-9, "lift-off height {}", q[1]);
    assert!((v[0] * v[0] + v[1] * v[1] - G / 2.0).abs() < 1e-8);
    assert!(!r.impacts.is_empty(), "free flight ends on the wall");
    // No friction: energy is conserved through sliding, flight and impacts.
    let e = &r.trajectory.energy;
    assert!(e.iter().all(|x| (x - e[0]).abs() < 1e-9), "energy drift");
    assert!(r.trajectory.h.iter().all(|h| h[0] < 1e-9));
}

/// An adaptive step grows without bound in free flight (a parabola is integrated
/// exactly) and, uncapped, jumped across the tumbler's thin wall at rtol 1e-8: the
/// particle left the drum (error 1.06). With the step capped at the sample spacing a
/// loose tolerance must stay close to the checked-in rtol-1e-12 reference, whose impact
/// times are checked against the closed form above.
#[test]
fn loose_tolerance_does_not_step_across_the_tumbler_wall() {
    let scene = common::load("tumbler", &Overrides::default());
    let reference_table = checked_in("tumbler.csv");
    let times = reference_table.times();
    let loose = reference::regularized(&scene, &times, &ReferenceOptions { rtol: 1e-8, atol: 1e-8, ..Default::default() }).unwrap();
    let (x, y) = (col(&reference_table, "x"), col(&reference_table, "y"));
    let e = loose.trajectory.q.iter().enumerate().fold(0.0_f64, |m, (k, q)| m.max((q[0] - x[k]).abs()).max((q[1] - y[k]).abs()));
    assert!(e < 1e-6, "rtol 1e-8 is {e:e} away from the reference");
    // Still inside the drum at the end.
    let last = loose.trajectory.h.last().unwrap()[0];
    assert!(last < 0.0, "final gap {last}");
}

/// The hard-wall reference integrates explicit time between impacts: a ball above a
/// fixed floor `h = −y` under gravity and the drive `A cos Ωt`, so
/// `y(t) = y₀ − g t²/2 + (A/Ω²)(1 − cos Ωt)` until it hits the floor (found here by a
/// scan and bisection), then the same with `ẏ` reversed.
#[test]
fn hard_wall_reference_follows_a_time_dependent_force() {
    let (a, w, y0) = (5.0, 3.0, 1.0);
    let text = format!(
        "[scene]\nname = \"driven ball\"\nlagrangian = \"1/2*y_dot^2 - g*y\"\n[parameters]\ng = {G:?}\nA = {a:?}\nW = {w:?}\n\
         [[coordinates]]\nname = \"y\"\ninitial = {y0:?}\nvelocity = 0\n[forces]\ny = \"A*cos(W*t)\"\n\
         [[walls]]\nname = \"floor\"\nh = \"-y\"\nstrength = 100\nwidth = 0.01\n[time]\nstart = 0\nend = 1\nnodes = 101\n"
    );
    let scene = skg_core::scene::SceneFile::parse(&text, "driven-ball.toml").unwrap().resolve(&Overrides::default()).unwrap();
    let (times, _) = solve::grid(&scene);
    let r = reference::hard_wall(&scene, &times, &ReferenceOptions::default()).unwrap();
    // The flight from (t_i, y_i = 0 after the first impact, or y0 at the start) with speed v_i.
    let flight = |ti: f64, yi: f64, vi: f64, t: f64| {
        let tau = t - ti;
        let y = yi + vi * tau - 0.5 * G * tau * tau + a / (w * w) * ((w * ti).cos() - (w * t).cos()) - a / w * (w * ti).sin() * tau;
        let v = vi - G * tau + a / w * ((w * t).sin() - (w * ti).sin());
        (y, v)
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    assert!(flight(0.0, y0, 0.0, hi).0 < 0.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if flight(0.0, y0, 0.0, mid).0 > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let t1 = hi;
    let v1 = -flight(0.0, y0, 0.0, t1).1;
    assert!(!r.impacts.is_empty());
    assert!((r.impacts[0].t - t1).abs() < 1e-10, "impact at {} vs {t1}", r.impacts[0].t);
    let t2 = r.impacts.get(1).map_or(f64::INFINITY, |im| im.t);
    for (k, &t) in r.trajectory.t.iter().enumerate() {
        let (y, v) = if t < t1 {
            flight(0.0, y0, 0.0, t)
        } else if t < t2 {
            flight(t1, 0.0, v1, t)
        } else {
            continue;
        };
        assert!((r.trajectory.q[k][0] - y).abs() < 1e-10 && (r.trajectory.v[k][0] - v).abs() < 1e-9, "t = {t}");
    }
}

/// A grid of uneven steps, as an adaptive solve's (here one step of 1e-9 s, then 255
/// of about 0.012 s): the reference's step is capped at the mean spacing, not the
/// smallest, which would ask for 3e9 steps against its budget of 2e7 (the damped spring
/// of scenarios/damped_spring_stiffness.toml on its adaptive grid at c = 1292 ran out of
/// them after 50 s). It agrees with the checked-in reference at the nodes they share.
#[test]
fn a_grid_with_one_tiny_step_is_sampled_without_tiny_steps() {
    let scene = common::load("pendulum", &Overrides::default());
    let table = checked_in("pendulum.csv");
    let uniform = table.times();
    let times: Vec<f64> = std::iter::once(0.0).chain(std::iter::once(1e-9)).chain(uniform[1..].iter().copied()).collect();
    let r = reference::regularized(&scene, &times, &ReferenceOptions::default()).unwrap();
    let steps = r.stats.accepted + r.stats.rejected;
    assert!(steps < 100_000, "{steps} steps");
    let x = col(&table, "x");
    let e = (1..uniform.len()).map(|k| (r.trajectory.q[k + 1][0] - x[k]).abs()).fold(0.0_f64, f64::max);
    assert!(e < 1e-9, "{e:e} from the checked-in reference");
}
