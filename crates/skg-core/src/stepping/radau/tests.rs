//! Radau IIA against closed forms: stiff linear and nonlinear equations, the dense output,
//! the order, failures of the right-hand side, the caller's step test and a given
//! Jacobian.

use super::*;

fn opts(rtol: f64, atol: f64) -> OdeOptions {
    OdeOptions { rtol, atol, ..OdeOptions::default() }
}

fn no_check(_: f64, _: &[f64], _: f64, _: &[f64]) -> bool {
    true
}

/// `y' = −λ (y − cos t) − sin t`, `y(0) = 1`: the solution is `cos t` for every `λ`, and
/// with `λ = 10⁶` an explicit method's step is bounded by `3/λ`.
fn prothero_robinson(lambda: f64) -> impl FnMut(f64, &[f64], &mut [f64]) -> Result<(), RhsError> {
    move |t, y, dy| {
        dy[0] = -lambda * (y[0] - t.cos()) - t.sin();
        Ok(())
    }
}

#[test]
fn a_stiff_equation_is_solved_to_the_tolerance_in_few_steps() {
    let times: Vec<f64> = (0..=100).map(|k| k as f64 * 0.1).collect();
    for rtol in [1e-6, 1e-9, 1e-12] {
        let sol = integrate(prothero_robinson(1e6), None, &[1.0], &times, &opts(rtol, rtol), no_check).unwrap();
        let err = sol.states.iter().zip(&times).map(|(y, t)| (y[0] - t.cos()).abs()).fold(0.0, f64::max);
        // The error within the tolerance asked for; an explicit method would take 10⁷ steps.
        assert!(err < 10.0 * rtol, "rtol {rtol}: error {err:e}");
        assert!(sol.stats.accepted < 2000, "rtol {rtol}: {:?}", sol.stats);
        assert_eq!(sol.method, METHOD);
    }
}

/// `y' = A y` with `A = [−1, 1; 0, −10⁵]` from `(1, 1)`: `y₂ = e^{−10⁵ t}`,
/// `y₁ = e^{−t} + (e^{−t} − e^{−10⁵ t})/(10⁵ − 1)`; a fast initial layer, then slow decay.
#[test]
fn a_fast_layer_then_slow_decay_matches_the_exponentials() {
    let k = 1e5;
    let f = move |_: f64, y: &[f64], dy: &mut [f64]| {
        dy[0] = -y[0] + y[1];
        dy[1] = -k * y[1];
        Ok(())
    };
    let exact = |t: f64| [(-t).exp() + ((-t).exp() - (-k * t).exp()) / (k - 1.0), (-k * t).exp()];
    let times: Vec<f64> = [0.0, 1e-6, 1e-5, 1e-4, 1e-3, 0.01, 0.1, 1.0, 5.0].to_vec();
    let sol = integrate(f, None, &[1.0, 1.0], &times, &opts(1e-10, 1e-12), no_check).unwrap();
    for (y, &t) in sol.states.iter().zip(&times) {
        let e = exact(t);
        assert!((y[0] - e[0]).abs() < 1e-9 && (y[1] - e[1]).abs() < 1e-9, "t = {t}: {y:?} vs {e:?}");
    }
    assert!(sol.stats.jacobian_evals >= 1 && sol.stats.factorizations >= 1, "{:?}", sol.stats);
}

/// On a non-stiff oscillator the error falls with the tolerance and stays within it
/// (measured over 10 s: 1.4e-5, 1.3e-10, 6.9e-14 at 1e-4, 1e-8, 1e-12), and every
/// requested time is the end of a step.
#[test]
fn the_error_follows_the_tolerance_on_an_oscillator() {
    let f = |_: f64, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[1];
        dy[1] = -y[0];
        Ok(())
    };
    let times: Vec<f64> = (0..=100).map(|k| k as f64 * 0.1).collect();
    let mut errors = Vec::new();
    for rtol in [1e-4, 1e-8, 1e-12] {
        let sol = integrate(f, None, &[1.0, 0.0], &times, &opts(rtol, rtol), no_check).unwrap();
        let err = sol.states.iter().zip(&times).map(|(y, t)| (y[0] - t.cos()).abs().max((y[1] + t.sin()).abs())).fold(0.0, f64::max);
        assert!(err < 10.0 * rtol, "rtol {rtol}: error {err:e}");
        assert!(sol.stats.accepted >= times.len() - 1, "{:?}", sol.stats);
        errors.push(err);
    }
    assert!(errors[0] > errors[1] && errors[1] > errors[2], "{errors:?}");
}

/// An overdamped oscillator `x'' = −c x' − x` with `c = 10⁴` from rest at 1: a fast
/// layer of rate `c` and a slow creep of rate `1/c` over `10⁴` s, against the closed form
/// (its roots in the stable form `s₁ = −2/(c + √(c² − 4))`). An explicit method would
/// take about 10⁸ steps.
#[test]
fn an_overdamped_oscillator_creeps_as_its_closed_form() {
    let c = 1e4;
    let f = move |_: f64, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[1];
        dy[1] = -c * y[1] - y[0];
        Ok(())
    };
    let root = (c * c - 4.0_f64).sqrt();
    let (s1, s2) = (-2.0 / (c + root), -(c + root) / 2.0);
    let exact = |t: f64| (s2 * (s1 * t).exp() - s1 * (s2 * t).exp()) / (s2 - s1);
    let times: Vec<f64> = (0..=10).map(|k| k as f64 * 1000.0).collect();
    for rtol in [1e-6, 1e-10] {
        let sol = integrate(f, None, &[1.0, 0.0], &times, &opts(rtol, rtol), no_check).unwrap();
        let err = sol.states.iter().zip(&times).map(|(y, &t)| (y[0] - exact(t)).abs()).fold(0.0, f64::max);
        assert!(err < 10.0 * rtol, "rtol {rtol}: error {err:e}");
        assert!(sol.stats.accepted < 500, "{:?}", sol.stats);
    }
}

/// A given Jacobian serves as well as forward differences (they change only the
/// iteration: both solutions are within the tolerance of the exact one), with no
/// right-hand sides spent on differences.
#[test]
fn a_given_jacobian_replaces_the_differences() {
    let lambda = 1e4;
    let times: Vec<f64> = vec![0.0, 1.0, 2.0];
    let fd = integrate(prothero_robinson(lambda), None, &[1.0], &times, &opts(1e-10, 1e-10), no_check).unwrap();
    let mut jac = |_: f64, _: &[f64], j: &mut DMatrix<f64>| {
        j[(0, 0)] = -lambda;
        Ok(())
    };
    let given = integrate(prothero_robinson(lambda), Some(&mut jac), &[1.0], &times, &opts(1e-10, 1e-10), no_check).unwrap();
    for sol in [&fd, &given] {
        let err = sol.states.iter().zip(&times).map(|(y, t)| (y[0] - t.cos()).abs()).fold(0.0, f64::max);
        assert!(err < 1e-9, "error {err:e}");
    }
    assert!(given.stats.rhs_evals < fd.stats.rhs_evals, "{:?} vs {:?}", given.stats, fd.stats);
}

/// A right-hand side undefined beyond `t = 1` (as a singular mass matrix would be): the
/// integration fails there with the caller's message, not before.
#[test]
fn a_failing_right_hand_side_is_reported_where_it_fails() {
    let f = |t: f64, y: &[f64], dy: &mut [f64]| {
        if t > 1.0 {
            return Err(RhsError::from("the constrained mass matrix is singular"));
        }
        dy[0] = -y[0];
        Ok(())
    };
    let e = integrate(f, None, &[1.0], &[0.0, 2.0], &opts(1e-8, 1e-8), no_check).unwrap_err();
    match e {
        OdeError::Rhs { t, error } => {
            assert!((t - 1.0).abs() < 1e-6, "t = {t}");
            assert!(error.0.contains("singular"), "{error}");
        }
        other => panic!("{other:?}"),
    }
}

/// The caller's step test bounds the steps: a test that refuses steps longer than 0.01
/// makes every accepted step at most that long.
#[test]
fn the_callers_test_bounds_every_step() {
    let f = |_: f64, y: &[f64], dy: &mut [f64]| {
        dy[0] = -y[0];
        Ok(())
    };
    let short = |t: f64, _: &[f64], t_new: f64, _: &[f64]| t_new - t <= 0.01;
    let sol = integrate(f, None, &[1.0], &[0.0, 1.0], &opts(1e-6, 1e-6), short).unwrap();
    assert!(sol.stats.accepted >= 100, "{:?}", sol.stats);
    assert!((sol.states[1][0] - (-1f64).exp()).abs() < 1e-6);
}

#[test]
fn bad_input_and_the_step_budget_are_errors() {
    let f = prothero_robinson(1.0);
    assert!(matches!(integrate(f, None, &[1.0], &[1.0, 0.0], &opts(1e-6, 1e-6), no_check), Err(OdeError::BadInput(_))));
    let f = prothero_robinson(1.0);
    let budget = OdeOptions { max_steps: 3, ..opts(1e-12, 1e-12) };
    assert!(matches!(integrate(f, None, &[1.0], &[0.0, 100.0], &budget, no_check), Err(OdeError::MaxSteps { .. })));
}

/// A step sized to reach a requested time ends on it exactly. From `t` below half of the
/// target `T`, `t + (T − t)` can round an ulp short of `T`; the step after it would be
/// that ulp, reported as a step-size underflow (the damped yaw disk at rtol 1e-12 stopped
/// so at its first node, `2π/127`). A fast layer, then long steps: targets `2πj/127`.
#[test]
fn a_step_sized_to_a_requested_time_ends_on_it() {
    let f = |_: f64, y: &[f64], dy: &mut [f64]| {
        dy[0] = -4000.0 * y[0];
        dy[1] = 5.0;
        Ok(())
    };
    for j in 1..=127 {
        let target = 2.0 * std::f64::consts::PI * j as f64 / 127.0;
        let sol = integrate(f, None, &[1.0, 0.0], &[0.0, target], &opts(1e-12, 1e-12), no_check)
            .unwrap_or_else(|e| panic!("target {target}: {e}"));
        assert!((sol.states[1][1] - 5.0 * target).abs() < 1e-11, "target {target}: {:?}", sol.states[1]);
    }
}
