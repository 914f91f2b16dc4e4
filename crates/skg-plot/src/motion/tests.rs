//! Tests of the pictures of the motion: the zero curves, and the walls drawn for scenes
//! of the repository.

use std::path::PathBuf;

use skg_core::check::Table;
use skg_core::scene::{Overrides, SceneFile};

use super::field::{zero_curves, GRID};
use super::scenery::{interpolate, thin, At, Scenery};
use super::*;

#[test]
fn zero_curves_of_a_circle_lie_on_it() {
    let n = 81;
    let (xr, yr) = ((-1.5, 1.5), (-1.2, 1.8));
    let mut f = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let x = xr.0 + (xr.1 - xr.0) * i as f64 / (n - 1) as f64;
            let y = yr.0 + (yr.1 - yr.0) * j as f64 / (n - 1) as f64;
            f.push(x * x + y * y - 1.0);
        }
    }
    let curves = zero_curves(&f, n, xr, yr);
    let points: Vec<(f64, f64)> = curves.into_iter().flatten().collect();
    assert!(points.len() > 100);
    let h = 3.0 / (n - 1) as f64;
    for (x, y) in &points {
        let r = (x * x + y * y).sqrt();
        assert!((r - 1.0).abs() < 0.02 * h, "point ({x}, {y}) at radius {r}");
    }
    // The whole circle: points in every quadrant.
    for (sx, sy) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
        assert!(points.iter().any(|(x, y)| x * sx > 0.5 && y * sy > 0.5));
    }
}

/// A scene of the repository with the regularized reference as its "solution".
fn motion_of(stem: &str) -> Motion {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios").join(format!("{stem}.toml"));
    let scene = SceneFile::load(&path).unwrap().resolve(&Overrides::default()).unwrap();
    let times = skg_core::solve::grid(&scene).0;
    let r = skg_core::stepping::reference::regularized(&scene, &times, &Default::default()).unwrap();
    let table = Table::of_trajectory(&scene, &r.trajectory);
    Motion::new(stem.into(), scene, table, None).unwrap()
}

fn view(m: &Motion) -> View {
    let (x, y) = m.default_axes();
    View { x, y, aspect: Aspect::Auto, title: String::new() }
}

#[test]
fn the_drum_is_drawn_once_as_its_circle() {
    let m = motion_of("tumbler");
    let s = Scenery::new(&m, view(&m)).unwrap();
    assert_eq!((s.view.x.as_str(), s.view.y.as_str()), ("x", "y"));
    assert_eq!(s.boundaries.len(), 1);
    assert!(s.boundaries[0].fixed && s.boundaries[0].wall);
    let (xr, yr) = s.ranges((600, 500));
    // equal aspect: the same units per pixel on both axes
    assert!((((xr.1 - xr.0) / 600.0) / ((yr.1 - yr.0) / 500.0) - 1.0).abs() < 1e-12);
    let curves = s.curves(&s.state(0), xr, yr);
    let points: Vec<(f64, f64)> = curves[0].iter().flatten().copied().collect();
    assert!(points.len() > 50);
    let h = (xr.1 - xr.0) / GRID as f64;
    for (x, y) in points {
        assert!(((x * x + y * y).sqrt() - 1.0).abs() < 0.05 * h, "({x}, {y}) is not on the drum R = 1");
    }
    // the bounces are contacts
    assert!(s.contact.iter().any(|&c| c) && !s.contact[0]);
}

#[test]
fn a_moving_wall_against_time_is_its_motion() {
    // vibrating_plate.toml: h = a sin(Ωt) − y with a = 0.05, Ω = 2π (one coordinate: t against y).
    let m = motion_of("vibrating_plate");
    let (a, omega) = (m.scene.parameters["a"], m.scene.parameters["Omega"]);
    let s = Scenery::new(&m, view(&m)).unwrap();
    assert_eq!((s.view.x.as_str(), s.view.y.as_str()), ("t", "y"));
    assert!(s.timeline() && s.boundaries[0].fixed);
    let (xr, yr) = s.ranges((600, 500));
    assert_eq!(xr, (0.0, 1.2));
    let points: Vec<(f64, f64)> = s.curves(&At::Timeline, xr, yr)[0].iter().flatten().copied().collect();
    let tol = 0.05 * (yr.1 - yr.0) / GRID as f64 + a * omega * (xr.1 - xr.0) / GRID as f64 * 0.05;
    assert!(points.len() > 50);
    for (t, y) in points {
        assert!((y - a * (omega * t).sin()).abs() < tol, "t = {t}: y = {y}, plate at {}", a * (omega * t).sin());
    }
}

#[test]
fn walls_against_time_follow_the_trajectory_and_velocity_axes_have_none() {
    // The plate against (y, y_dot) has no boundaries; the tumbler's drum seen in the
    // plane (x, t) moves with y: drawn along the trajectory's y(t).
    let m = motion_of("vibrating_plate");
    let s = Scenery::new(&m, View { x: "y".into(), y: "y_dot".into(), aspect: Aspect::Fill, title: String::new() }).unwrap();
    assert!(s.boundaries.is_empty());
    let m = motion_of("tumbler");
    let s = Scenery::new(&m, View { x: "t".into(), y: "x".into(), aspect: Aspect::Auto, title: String::new() }).unwrap();
    assert!(s.timeline());
    let (xr, yr) = s.ranges((600, 500));
    let ys = m.solution.column("y").unwrap();
    let times = m.solution.times();
    for (t, x) in s.curves(&At::Timeline, xr, yr)[0].iter().flatten() {
        let y = interpolate(&times, &ys.iter().map(|v| vec![*v]).collect::<Vec<_>>(), *t)[0];
        assert!((x * x + y * y - 1.0).abs() < 0.05, "t = {t}: x = {x}, y = {y}");
    }
}

const BOWL: &str = r#"
[scene]
name = "ball in a sphere"
lagrangian = "1/2*(x_dot^2 + y_dot^2 + z_dot^2) - g*y"
[parameters]
g = 9.8
[[coordinates]]
name = "x"
initial = -0.5
velocity = 0.4
[[coordinates]]
name = "y"
initial = -0.7
velocity = 0
[[coordinates]]
name = "z"
initial = 0.3
velocity = 0.5
[[walls]]
name = "sphere"
h = "x^2 + y^2 + z^2 - 1"
strength = 5
width = 0.01
[time]
start = 0
end = 0.6
nodes = 300
"#;

#[test]
fn a_wall_of_an_unplotted_coordinate_is_drawn_at_each_contact() {
    // A sphere seen in the plane (x, y): its section at the contact's z, the circle
    // x² + y² = 1 − z².
    let scene = SceneFile::parse(BOWL, "bowl.toml").unwrap().resolve(&Overrides::default()).unwrap();
    let times = skg_core::solve::grid(&scene).0;
    let r = skg_core::stepping::reference::regularized(&scene, &times, &Default::default()).unwrap();
    let table = Table::of_trajectory(&scene, &r.trajectory);
    let m = Motion::new("bowl".into(), scene, table, None).unwrap();
    let s = Scenery::new(&m, view(&m)).unwrap();
    let b = &s.boundaries[0];
    assert!(!b.fixed && !b.snapshots.is_empty() && b.snapshots.len() <= MAX_SNAPSHOTS, "{b:?}");
    let (xr, yr) = s.ranges((600, 500));
    let zs = m.solution.column("z").unwrap();
    for &k in &b.snapshots {
        assert!(s.contact[k]);
        let radius = (1.0 - zs[k] * zs[k]).sqrt();
        let points: Vec<(f64, f64)> = s.curves(&s.state(k), xr, yr)[0].iter().flatten().copied().collect();
        assert!(!points.is_empty());
        for (x, y) in points {
            assert!(((x * x + y * y).sqrt() - radius).abs() < 0.05 * (xr.1 - xr.0) / GRID as f64, "node {k}: ({x}, {y})");
        }
    }
}

#[test]
fn interpolation_and_thinning() {
    let t = [0.0, 1.0, 3.0];
    let rows = vec![vec![0.0, 10.0], vec![1.0, 20.0], vec![5.0, 20.0]];
    assert_eq!(interpolate(&t, &rows, 0.5), vec![0.5, 15.0]);
    assert_eq!(interpolate(&t, &rows, 2.0), vec![3.0, 20.0]);
    assert_eq!(interpolate(&t, &rows, 3.0), vec![5.0, 20.0]);
    assert_eq!(interpolate(&t, &rows, -1.0), vec![0.0, 10.0]);
    assert_eq!(thin(&[1, 2, 3], 6), vec![1, 2, 3]);
    assert_eq!(thin(&(0..11).collect::<Vec<_>>(), 3), vec![0, 5, 10]);
}
