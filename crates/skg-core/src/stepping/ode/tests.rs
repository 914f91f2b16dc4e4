//! Tests of the integrator against closed forms: orders, dense output, events, failing
//! right-hand sides, step budgets.

use super::*;

fn tight() -> OdeOptions {
    OdeOptions { rtol: 1e-12, atol: 1e-14, ..OdeOptions::default() }
}

fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n).map(|i| a + (b - a) * i as f64 / (n - 1) as f64).collect()
}

#[test]
fn tableau_consistency() {
    use tableau::*;
    for i in 1..16 {
        let s: f64 = A[i].iter().sum();
        assert!((s - C[i]).abs() < 1e-13, "row {i}: Σa = {s}, c = {}", C[i]);
        assert_eq!(A[i].len(), i);
    }
    // Quadrature conditions of the 8th-order weights: Σ b_j c_j^q = 1/(q+1), q ≤ 7.
    for q in 0..8 {
        let s: f64 = A[12].iter().zip(&C).map(|(b, c)| b * c.powi(q)).sum();
        assert!((s - 1.0 / (q + 1) as f64).abs() < 1e-13, "q = {q}: {s}");
    }
    // The error estimators vanish on constants.
    assert!(ER.iter().sum::<f64>().abs() < 1e-14);
    assert!((BHH.iter().sum::<f64>() - 1.0).abs() < 1e-15);
}

#[test]
fn exponential_decay() {
    let times = linspace(0.0, 5.0, 37);
    let y0 = [1.0, -2.0];
    let lam = [-1.0, -0.3];
    let sol = integrate(
        |_t, y, dy| {
            dy[0] = lam[0] * y[0];
            dy[1] = lam[1] * y[1];
            Ok(())
        },
        &y0,
        &times,
        &tight(),
    )
    .unwrap();
    assert_eq!(sol.method, METHOD);
    for (t, y) in sol.times.iter().zip(&sol.states) {
        for c in 0..2 {
            let exact = y0[c] * (lam[c] * t).exp();
            assert!((y[c] - exact).abs() <= 1e-10, "t = {t}: {} vs {exact}", y[c]);
        }
    }
    assert!(sol.stats.accepted > 0 && sol.stats.rhs_evals >= 12 * sol.stats.accepted);
}

#[test]
fn harmonic_oscillator_dense_samples() {
    let w = 2.0;
    let times = linspace(0.0, 10.0, 1001);
    let sol = integrate(
        |_t, y, dy| {
            dy[0] = y[1];
            dy[1] = -w * w * y[0];
            Ok(())
        },
        &[1.0, 0.0],
        &times,
        &tight(),
    )
    .unwrap();
    assert_eq!(sol.states.len(), times.len());
    let mut worst: f64 = 0.0;
    for (t, y) in sol.times.iter().zip(&sol.states) {
        worst = worst.max((y[0] - (w * t).cos()).abs());
        worst = worst.max((y[1] + w * (w * t).sin()).abs());
    }
    assert!(worst <= 1e-10, "max error {worst:e}");
    // Far fewer steps than samples: the samples come from the dense output.
    assert!(sol.stats.accepted < 500, "{:?}", sol.stats);
}

#[test]
fn sample_times_hit_exactly() {
    let times = vec![0.25, 0.25, 0.3, 1.0 / 3.0, 0.7, 0.7, 1.9, 2.0];
    let sol = integrate(
        |t, y, dy| {
            dy[0] = t.cos() * y[0];
            Ok(())
        },
        &[1.5],
        &times,
        &OdeOptions::default(),
    )
    .unwrap();
    assert_eq!(sol.times, times);
    assert_eq!(sol.states.len(), times.len());
    assert_eq!(sol.states[0], vec![1.5]);
    assert_eq!(sol.states[1], vec![1.5]);
    assert_eq!(sol.states[4], sol.states[5]);
    for (t, y) in times.iter().zip(&sol.states) {
        let exact = 1.5 * (t.sin() - 0.25f64.sin()).exp();
        assert!((y[0] - exact).abs() < 1e-9, "t = {t}");
    }
    // Only the start time: nothing to do.
    let sol = integrate(|_, _, _| Err("never called".into()), &[1.0], &[3.0], &OdeOptions::default()).unwrap();
    assert_eq!(sol.states, vec![vec![1.0]]);
    assert_eq!(sol.stats.rhs_evals, 0);
}

#[test]
fn failing_rhs_reports_time() {
    let res = integrate(
        |t, y, dy| {
            if t > 0.5 {
                return Err("mass matrix is singular".into());
            }
            dy[0] = -y[0];
            Ok(())
        },
        &[1.0],
        &[0.0, 0.2, 1.0],
        &OdeOptions::default(),
    );
    match res {
        Err(OdeError::Rhs { t, error }) => {
            assert!((t - 0.5).abs() < 1e-9, "t = {t}");
            assert_eq!(error, RhsError::from("mass matrix is singular"));
        }
        other => panic!("expected OdeError::Rhs, got {other:?}"),
    }
    // A non-finite derivative is a failure too.
    let res = integrate(
        |t, _y, dy| {
            dy[0] = if t > 0.5 { f64::NAN } else { 1.0 };
            Ok(())
        },
        &[0.0],
        &[0.0, 1.0],
        &OdeOptions::default(),
    );
    assert!(matches!(res, Err(OdeError::Rhs { t, .. }) if (t - 0.5).abs() < 1e-9), "{res:?}");
    // Failing at the initial state: reported at once.
    let mut calls = 0;
    let res = integrate(
        |_t, _y, _dy| {
            calls += 1;
            Err("bad state".into())
        },
        &[1.0],
        &[0.0, 1.0],
        &OdeOptions::default(),
    );
    assert!(matches!(res, Err(OdeError::Rhs { t, .. }) if t == 0.0));
    assert_eq!(calls, 1);
}

#[test]
fn van_der_pol_mu_1() {
    let vdp = |_t: f64, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[1];
        dy[1] = (1.0 - y[0] * y[0]) * y[1] - y[0];
        Ok(())
    };
    let times = linspace(0.0, 20.0, 201);
    let fine = integrate(vdp, &[2.0, 0.0], &times, &tight()).unwrap();
    let coarse = integrate(vdp, &[2.0, 0.0], &times, &OdeOptions { rtol: 1e-7, atol: 1e-9, ..OdeOptions::default() }).unwrap();
    let diff = fine.states.iter().zip(&coarse.states).flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs())).fold(0.0, f64::max);
    assert!(diff < 1e-4, "coarse vs fine: {diff:e}");
    assert!(coarse.stats.rhs_evals < fine.stats.rhs_evals);
    // The limit cycle has amplitude ≈ 2.
    let amp = fine.states.iter().map(|y| y[0].abs()).fold(0.0, f64::max);
    assert!((amp - 2.0).abs() < 0.05, "amplitude {amp}");
}

#[test]
fn a_rejecting_check_bounds_the_steps_and_keeps_the_accuracy() {
    // y' = -y: without the check a handful of steps cover [0, 10]; a check that
    // accepts no step longer than 0.01 forces at least 1000, and the result is as
    // accurate.
    let f = |_t: f64, y: &[f64], dy: &mut [f64]| -> Result<(), RhsError> {
        dy[0] = -y[0];
        Ok(())
    };
    let o = OdeOptions::default();
    let free = integrate(f, &[1.0], &[0.0, 10.0], &o).unwrap();
    let checked = integrate_checked(f, &[1.0], &[0.0, 10.0], &o, |t, _, t_new, _| t_new - t <= 0.01).unwrap();
    assert!(free.stats.accepted < 200, "{:?}", free.stats);
    assert!(checked.stats.accepted >= 1000 && checked.stats.rejected > 0, "{:?}", checked.stats);
    assert!((checked.states[1][0] - (-10.0_f64).exp()).abs() < 1e-12);
    // A check that accepts nothing ends at the round-off limit of the step.
    let never = integrate_checked(f, &[1.0], &[0.0, 1.0], &o, |_, _, _, _| false);
    assert!(matches!(never, Err(OdeError::StepTooSmall { .. })), "{never:?}");
}

#[test]
fn bad_input_and_limits() {
    let f = |_t: f64, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[0];
        Ok(())
    };
    let o = OdeOptions::default();
    let bad = |r: Result<OdeSolution, OdeError>| matches!(r, Err(OdeError::BadInput(_)));
    assert!(bad(integrate(f, &[1.0], &[], &o)));
    assert!(bad(integrate(f, &[1.0], &[0.0, 1.0, 0.5], &o)));
    assert!(bad(integrate(f, &[1.0], &[0.0, f64::NAN], &o)));
    assert!(bad(integrate(f, &[f64::INFINITY], &[0.0, 1.0], &o)));
    assert!(bad(integrate(f, &[1.0], &[0.0, 1.0], &OdeOptions { rtol: -1.0, ..o })));
    assert!(bad(integrate(f, &[1.0], &[0.0, 1.0], &OdeOptions { rtol: 0.0, atol: 0.0, ..o })));
    assert!(bad(integrate(f, &[1.0], &[0.0, 1.0], &OdeOptions { initial_step: Some(0.0), ..o })));
    let e = integrate(f, &[1.0], &[0.0, 100.0], &OdeOptions { max_steps: 5, ..o });
    assert!(matches!(e, Err(OdeError::MaxSteps { steps: 5, .. })), "{e:?}");
    // A given initial step is used (and the result is still accurate).
    let sol = integrate(f, &[1.0], &[0.0, 1.0], &OdeOptions { initial_step: Some(1e-3), ..o }).unwrap();
    assert!((sol.states[1][0] - 1f64.exp()).abs() < 1e-9);
    // Finite-time blow-up y' = y², y(0) = 1 at t = 1: the step size underflows.
    let e = integrate(
        |_t, y, dy| {
            dy[0] = y[0] * y[0];
            Ok(())
        },
        &[1.0],
        &[0.0, 2.0],
        &o,
    );
    match e {
        Err(OdeError::StepTooSmall { t }) | Err(OdeError::Rhs { t, .. }) => {
            assert!((t - 1.0).abs() < 1e-3, "t = {t}")
        }
        other => panic!("expected a failure near t = 1, got {other:?}"),
    }
    // An empty state is integrated trivially.
    let sol = integrate(f, &[], &[0.0, 1.0], &o).unwrap();
    assert_eq!(sol.states, vec![Vec::<f64>::new(); 2]);
}

#[test]
fn event_location() {
    // Drop from y = 1 with v = 0.5 under g: the floor y = 0 is reached at the root of
    // 1 + 0.5 t - g t²/2, event function -y (crossing upwards).
    let g = 9.8;
    let f = |_: f64, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[1];
        dy[1] = -g;
        Ok(())
    };
    let times = linspace(0.0, 2.0, 21);
    let (sol, hit) = integrate_to_event(f, &[1.0, 0.5], &times, &tight(), |_, y| -y[0]).unwrap();
    let hit = hit.expect("the floor is reached");
    let exact = (0.5 + (0.25 + 2.0 * g).sqrt()) / g;
    assert!((hit.t - exact).abs() < 1e-13, "{} vs {exact}", hit.t);
    assert!(hit.y[0].abs() < 1e-13);
    assert!((hit.y[1] - (0.5 - g * exact)).abs() < 1e-12);
    let before = times.iter().filter(|&&t| t < hit.t).count();
    assert_eq!(sol.states.len(), before);
    for (t, y) in times.iter().zip(&sol.states) {
        assert!((y[0] - (1.0 + 0.5 * t - 0.5 * g * t * t)).abs() < 1e-12);
    }
    // No crossing: every state, no event.
    let (sol, hit) = integrate_to_event(f, &[1.0, 20.0], &times, &tight(), |_, y| -y[0]).unwrap();
    assert!(hit.is_none());
    assert_eq!(sol.states.len(), times.len());
    // A short excursion inside one long step is still found: -y = sin t exceeds 0.99
    // for 0.28 s around π/2, shorter than the steps taken at rtol 1e-6.
    let osc = |_: f64, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[1];
        dy[1] = -y[0];
        Ok(())
    };
    let (_, hit) =
        integrate_to_event(osc, &[0.0, -1.0], &[0.0, 10.0], &OdeOptions { rtol: 1e-6, atol: 1e-8, ..OdeOptions::default() }, |_, y| {
            -y[0] - 0.99
        })
        .unwrap();
    let hit = hit.expect("graze found");
    let exact = std::f64::consts::PI / 2.0 - 0.99f64.acos();
    assert!((hit.t - exact).abs() < 1e-5, "{} vs {exact}", hit.t);
}
