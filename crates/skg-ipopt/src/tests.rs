//! Tests of [`crate::solve`] (and [`crate::solve_warm`]) on small problems with known solutions (a circle meeting a
//! line as a square system, Hock–Schittkowski 71 with bounds, inequalities and a
//! Hessian): convergence, panics, NaN and errors in callbacks, concurrency, options,
//! the log file, validation of sizes and structures, stopping and nesting.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use super::*;

/// How a [`Circle`] misbehaves.
#[derive(Clone, Copy, PartialEq)]
enum Mode {
    Normal,
    /// `jacobian_values` panics on its second call.
    PanicInJacobian,
    /// `constraints` panics on its first call (at the starting point).
    PanicInConstraints,
    /// `constraints` always yields NaN.
    NanConstraints,
    /// `constraints` always returns `Err`.
    ErrAlways,
    /// `constraints` returns `Err` for x[0] > 3 (outside its "domain").
    DomainError,
}

/// x² + y² − r² = 0, x − y = 0; root (r/√2, r/√2) from a positive start.
struct Circle {
    r: f64,
    mode: Mode,
    jac: Vec<(u32, u32)>,
    jac_calls: usize,
}

impl Circle {
    fn new(r: f64, mode: Mode) -> Self {
        Self { r, mode, jac: vec![(0, 0), (0, 1), (1, 0), (1, 1)], jac_calls: 0 }
    }
}

impl Problem for Circle {
    fn num_variables(&self) -> usize {
        2
    }
    fn num_constraints(&self) -> usize {
        2
    }
    fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
        match self.mode {
            Mode::PanicInConstraints => panic!("boom in constraints"),
            Mode::ErrAlways => return Err(EvalError("constraints unavailable".into())),
            Mode::DomainError if x[0] > 3.0 => return Err(EvalError(format!("x = {} outside the domain", x[0]))),
            _ => {}
        }
        c[0] = x[0] * x[0] + x[1] * x[1] - self.r * self.r;
        c[1] = x[0] - x[1];
        if self.mode == Mode::NanConstraints {
            c[0] = f64::NAN;
        }
        Ok(())
    }
    fn jacobian_structure(&self) -> &[(u32, u32)] {
        &self.jac
    }
    fn jacobian_values(&mut self, x: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
        self.jac_calls += 1;
        if self.mode == Mode::PanicInJacobian && self.jac_calls == 2 {
            panic!("boom in jacobian");
        }
        v.copy_from_slice(&[2.0 * x[0], 2.0 * x[1], 1.0, -1.0]);
        Ok(())
    }
}

#[test]
fn square_system_converges_with_zero_hessian() {
    let mut p = Circle::new(2.0, Mode::Normal);
    let sol = solve(&mut p, &[1.0, 0.5], &Options::default()).expect("solve runs");
    assert_eq!(sol.status, Status::SolveSucceeded, "{}", sol.status);
    let root = 2.0_f64.sqrt();
    assert!((sol.x[0] - root).abs() < 1e-12 && (sol.x[1] - root).abs() < 1e-12, "x = {:?}", sol.x);
    assert!(sol.max_constraint_violation < 1e-12, "viol = {}", sol.max_constraint_violation);
    assert!(sol.iterations >= 1 && sol.iterations <= 10, "iterations = {}", sol.iterations);
    assert_eq!(sol.history.len(), sol.iterations + 1);
    assert_eq!(sol.history[0].iter, 0);
    assert!(sol.history.iter().all(|s| !s.restoration));
    assert_eq!(sol.eval.hessian.calls, 0);
    assert!(sol.eval.constraints.calls >= 2 && sol.eval.jacobian.calls >= 1);
    assert!(sol.first_eval_error.is_none() && sol.failed_evaluations == 0);
    assert!(sol.ipopt_seconds <= sol.total_seconds);
    assert_eq!(sol.constraint_values.len(), 2);
    assert_eq!(sol.constraint_multipliers.len(), 2);
}

/// Hock–Schittkowski problem 71, Ipopt's standard example.
struct Hs071 {
    jac: Vec<(u32, u32)>,
    hess: Vec<(u32, u32)>,
}

impl Hs071 {
    fn new() -> Self {
        let jac = (0..2).flat_map(|r| (0..4).map(move |c| (r, c))).collect();
        let hess = (0..4).flat_map(|r| (0..=r).map(move |c| (r, c))).collect();
        Self { jac, hess }
    }
}

impl Problem for Hs071 {
    fn num_variables(&self) -> usize {
        4
    }
    fn num_constraints(&self) -> usize {
        2
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(1.0);
        upper.fill(5.0);
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.copy_from_slice(&[25.0, 40.0]);
        upper.copy_from_slice(&[2e19, 40.0]);
    }
    fn objective(&mut self, x: &[f64]) -> Result<f64, EvalError> {
        Ok(x[0] * x[3] * (x[0] + x[1] + x[2]) + x[2])
    }
    fn objective_gradient(&mut self, x: &[f64], g: &mut [f64]) -> Result<(), EvalError> {
        g[0] = x[0] * x[3] + x[3] * (x[0] + x[1] + x[2]);
        g[1] = x[0] * x[3];
        g[2] = x[0] * x[3] + 1.0;
        g[3] = x[0] * (x[0] + x[1] + x[2]);
        Ok(())
    }
    fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
        c[0] = x[0] * x[1] * x[2] * x[3];
        c[1] = x.iter().map(|v| v * v).sum();
        Ok(())
    }
    fn jacobian_structure(&self) -> &[(u32, u32)] {
        &self.jac
    }
    fn jacobian_values(&mut self, x: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
        v[0] = x[1] * x[2] * x[3];
        v[1] = x[0] * x[2] * x[3];
        v[2] = x[0] * x[1] * x[3];
        v[3] = x[0] * x[1] * x[2];
        for i in 0..4 {
            v[4 + i] = 2.0 * x[i];
        }
        Ok(())
    }
    fn hessian_structure(&self) -> &[(u32, u32)] {
        &self.hess
    }
    fn hessian_values(&mut self, x: &[f64], s: f64, l: &[f64], h: &mut [f64]) -> Result<(), EvalError> {
        // order: (0,0) (1,0) (1,1) (2,0) (2,1) (2,2) (3,0) (3,1) (3,2) (3,3)
        h[0] = s * 2.0 * x[3] + 2.0 * l[1];
        h[1] = s * x[3] + l[0] * x[2] * x[3];
        h[2] = 2.0 * l[1];
        h[3] = s * x[3] + l[0] * x[1] * x[3];
        h[4] = l[0] * x[0] * x[3];
        h[5] = 2.0 * l[1];
        h[6] = s * (2.0 * x[0] + x[1] + x[2]) + l[0] * x[1] * x[2];
        h[7] = s * x[0] + l[0] * x[0] * x[2];
        h[8] = s * x[0] + l[0] * x[0] * x[1];
        h[9] = 2.0 * l[1];
        Ok(())
    }
}

#[test]
fn hs071_reaches_known_optimum() {
    let mut p = Hs071::new();
    let opts = Options { tol: 1e-9, constr_viol_tol: 1e-9, ..Options::default() };
    let sol = solve(&mut p, &[1.0, 5.0, 5.0, 1.0], &opts).expect("solve runs");
    assert_eq!(sol.status, Status::SolveSucceeded);
    assert!((sol.objective - 17.014_017_3).abs() < 1e-6, "f = {}", sol.objective);
    let expected = [1.0, 4.742_999_63, 3.821_149_98, 1.379_408_29];
    for (a, b) in sol.x.iter().zip(expected) {
        assert!((a - b).abs() < 1e-6, "x = {:?}", sol.x);
    }
    assert!(sol.eval.hessian.calls > 0 && sol.eval.objective.calls > 0);
    // The active inequality x0 x1 x2 x3 >= 25 may be violated by Ipopt's bound
    // relaxation (bound_relax_factor 1e-8, relative): up to 25e-8.
    assert!(sol.max_constraint_violation < 1e-6, "viol = {}", sol.max_constraint_violation);
    assert!(sol.lower_bound_multipliers[0] > 0.1, "x0 sits on its lower bound");
}

/// HS071's optimum (Hock and Schittkowski's x* = (1, 4.743, 3.821, 1.379)) is reached
/// from a warm start too: from a point beside it with its multipliers (the KKT
/// conditions' `y`, `z_L` at x*: ∇f + Jᵀy − z_L = 0, solved by hand below), in fewer
/// iterations than from the textbook start; multipliers of the wrong length are refused.
#[test]
fn a_warm_start_from_the_multipliers_reaches_the_optimum() {
    let x_star = [1.0, 4.742_999_63, 3.821_149_98, 1.379_408_29];
    // Rows 1 and 2 of ∇f + Jᵀy = 0 (x1, x2 off their bounds) give y; row 0 gives z_L[0].
    let (a, b, c, d) = (x_star[0], x_star[1], x_star[2], x_star[3]);
    let g = [a * d + d * (a + b + c), a * d, a * d + 1.0, a * (a + b + c)];
    let (j1, j2) = ([b * c * d, a * c * d, a * b * d, a * b * c], [2.0 * a, 2.0 * b, 2.0 * c, 2.0 * d]);
    let det = j1[1] * j2[2] - j1[2] * j2[1];
    let y0 = (-g[1] * j2[2] + g[2] * j2[1]) / det;
    let y1 = (-g[2] * j1[1] + g[1] * j1[2]) / det;
    let z0 = g[0] + j1[0] * y0 + j2[0] * y1;
    assert!(z0 > 0.1, "x0 sits on its lower bound: z = {z0}");
    let multipliers = Multipliers { constraints: vec![y0, y1], lower: vec![z0, 0.0, 0.0, 0.0], upper: vec![0.0; 4] };
    let opts = Options { tol: 1e-9, constr_viol_tol: 1e-9, ..Options::default() };
    let cold = solve(&mut Hs071::new(), &[1.0, 5.0, 5.0, 1.0], &opts).expect("solve runs");
    let near: Vec<f64> = x_star.iter().map(|v| v * (1.0 + 1e-4)).collect();
    let warm = solve_warm(&mut Hs071::new(), &near, &multipliers, &opts).expect("solve runs");
    assert_eq!(warm.status, Status::SolveSucceeded);
    for (a, b) in warm.x.iter().zip(x_star) {
        assert!((a - b).abs() < 1e-6, "x = {:?}", warm.x);
    }
    assert!(warm.iterations < cold.iterations, "warm {} against cold {} iterations", warm.iterations, cold.iterations);
    let short = Multipliers { constraints: vec![y0], ..multipliers };
    assert!(matches!(solve_warm(&mut Hs071::new(), &near, &short, &opts), Err(SolveError::Size(_))));
}

#[test]
fn panic_in_callback_is_reraised_after_the_solve() {
    let mut p = Circle::new(2.0, Mode::PanicInJacobian);
    let caught = catch_unwind(AssertUnwindSafe(|| solve(&mut p, &[1.0, 0.5], &Options::default())));
    let payload = match caught {
        Ok(result) => panic!("expected the panic to be re-raised, got {:?}", result.map(|s| s.status)),
        Err(payload) => payload,
    };
    let message = payload.downcast_ref::<&str>().copied().unwrap_or("<not a &str>");
    assert_eq!(message, "boom in jacobian");
    // Same from the constraints callback, whose failure path differs (see eval_g).
    let mut p = Circle::new(2.0, Mode::PanicInConstraints);
    let caught = catch_unwind(AssertUnwindSafe(|| solve(&mut p, &[1.0, 0.5], &Options::default())));
    let payload = caught.expect_err("panic re-raised");
    assert_eq!(payload.downcast_ref::<&str>().copied(), Some("boom in constraints"));
    // The problem was freed and the lock released: the next solve works.
    let sol = solve(&mut Circle::new(2.0, Mode::Normal), &[1.0, 0.5], &Options::default()).expect("runs");
    assert!(sol.status.is_success());
}

#[test]
fn nan_constraints_give_a_failure_status_not_a_crash() {
    let mut p = Circle::new(2.0, Mode::NanConstraints);
    let sol = solve(&mut p, &[1.0, 0.5], &Options::default()).expect("NaN is not an Err");
    assert!(!sol.status.is_success(), "status {}", sol.status);
    assert!(sol.non_finite_evaluations > 0);
    assert!(sol.max_constraint_violation.is_nan());
}

#[test]
fn callback_error_is_returned_when_ipopt_fails() {
    let mut p = Circle::new(2.0, Mode::ErrAlways);
    match solve(&mut p, &[1.0, 0.5], &Options::default()) {
        Err(SolveError::Eval(e)) => assert_eq!(e.0, "constraints unavailable"),
        other => panic!("expected SolveError::Eval, got {:?}", other.map(|s| s.status)),
    }
}

#[test]
fn callback_error_at_a_trial_point_is_recorded_when_ipopt_recovers() {
    // The first Newton step from (0.3, 0.3) lands at x ≈ 3.48, outside the domain.
    let mut p = Circle::new(2.0, Mode::DomainError);
    let sol = solve(&mut p, &[0.3, 0.3], &Options::default()).expect("Ipopt recovers");
    assert!(sol.status.is_success(), "status {}", sol.status);
    assert!(sol.failed_evaluations >= 1);
    let err = sol.first_eval_error.as_ref().expect("error recorded");
    assert!(err.0.contains("outside the domain"), "{err}");
    assert!((sol.x[0] - 2.0_f64.sqrt()).abs() < 1e-10);
}

/// [`Circle`] with the domain error, stopped by its intermediate callback at iteration 3.
struct StoppedAfterAnError(Circle);
impl Problem for StoppedAfterAnError {
    fn num_variables(&self) -> usize {
        self.0.num_variables()
    }
    fn num_constraints(&self) -> usize {
        self.0.num_constraints()
    }
    fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
        self.0.constraints(x, c)
    }
    fn jacobian_structure(&self) -> &[(u32, u32)] {
        self.0.jacobian_structure()
    }
    fn jacobian_values(&mut self, x: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
        self.0.jacobian_values(x, v)
    }
    fn intermediate(&mut self, stat: &IterationStat) -> bool {
        stat.iter < 3
    }
}

#[test]
fn a_stop_the_callback_asks_for_returns_the_iterate_after_a_callback_error() {
    let sol = solve(&mut StoppedAfterAnError(Circle::new(2.0, Mode::DomainError)), &[0.3, 0.3], &Options::default())
        .expect("the caller's stop is not an error");
    assert_eq!(sol.status, Status::UserRequestedStop);
    assert!(sol.first_eval_error.as_ref().is_some_and(|e| e.0.contains("outside the domain")), "{:?}", sol.first_eval_error);
    assert!(sol.x.iter().all(|v| v.is_finite() && *v < 3.0), "{:?}", sol.x);
}

#[test]
fn concurrent_solves_are_serialized_and_correct() {
    let failures = AtomicUsize::new(0);
    std::thread::scope(|scope| {
        for t in 0..4 {
            let failures = &failures;
            scope.spawn(move || {
                for k in 0..20 {
                    let r = 1.0 + t as f64 + 0.1 * k as f64;
                    let mut p = Circle::new(r, Mode::Normal);
                    let ok = match solve(&mut p, &[r, 0.5 * r], &Options::default()) {
                        Ok(sol) => {
                            sol.status.is_success()
                                && (sol.x[0] - r / 2.0_f64.sqrt()).abs() < 1e-10
                                && (sol.x[1] - r / 2.0_f64.sqrt()).abs() < 1e-10
                        }
                        Err(_) => false,
                    };
                    if !ok {
                        failures.fetch_add(1, Ordering::Relaxed);
                    }
                }
            });
        }
    });
    assert_eq!(failures.load(Ordering::Relaxed), 0);
}

const CHILD_ENV: &str = "SKG_IPOPT_TEST_STRAY_OPT_CHILD";

/// The current directory is process-global, so the check runs in a child process (this
/// same test binary, filtered to this test) started inside a temporary directory that
/// holds an `ipopt.opt` with `max_iter 0`. The child also checks that the file does
/// bite when named explicitly; the parent checks that the child printed nothing.
#[test]
fn stray_ipopt_opt_file_is_ignored() {
    let module = module_path!();
    let test_name = format!("{}::stray_ipopt_opt_file_is_ignored", module.split_once("::").map_or(module, |(_, rest)| rest));
    if std::env::var_os(CHILD_ENV).is_some() {
        assert!(Path::new("ipopt.opt").is_file(), "child runs next to ipopt.opt");
        let sol = solve(&mut Circle::new(2.0, Mode::Normal), &[1.0, 0.5], &Options::default()).expect("runs");
        assert_eq!(sol.status, Status::SolveSucceeded);
        assert!(sol.iterations > 0);
        let naming_it = Options { extra: vec![("option_file_name".into(), OptionValue::Str("ipopt.opt".into()))], ..Options::default() };
        let sol = solve(&mut Circle::new(2.0, Mode::Normal), &[1.0, 0.5], &naming_it).expect("runs");
        assert_eq!(sol.status, Status::MaximumIterationsExceeded, "the file is read when named");
        println!("CHILD-CHECKS-PASSED");
        return;
    }
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("ipopt.opt"), "max_iter 0\n").expect("write ipopt.opt");
    let exe = std::env::current_exe().expect("test binary path");
    let out = std::process::Command::new(exe)
        .args([test_name.as_str(), "--exact", "--nocapture", "--test-threads=1"])
        .env(CHILD_ENV, "1")
        .current_dir(dir.path())
        .output()
        .expect("spawn child test");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "child failed:\n{stdout}\n{stderr}");
    assert!(stdout.contains("CHILD-CHECKS-PASSED"), "child did not run the checks:\n{stdout}");
    // print_level 0 + sb yes: Ipopt printed nothing at all (banner included).
    assert!(!stdout.contains("Ipopt") && !stdout.contains("EXIT"), "Ipopt printed:\n{stdout}");
}

#[test]
fn output_file_gets_a_log() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("ipopt.log");
    let opts = Options { output_file: Some(path.clone()), ..Options::default() };
    let sol = solve(&mut Circle::new(2.0, Mode::Normal), &[1.0, 0.5], &opts).expect("runs");
    assert!(sol.status.is_success());
    let log = std::fs::read_to_string(&path).expect("log written");
    assert!(!log.is_empty());
    assert!(log.contains("EXIT"), "log:\n{log}");
    let bad = Options { output_file: Some(dir.path().join("missing-dir").join("x.log")), ..Options::default() };
    assert!(matches!(solve(&mut Circle::new(2.0, Mode::Normal), &[1.0, 0.5], &bad), Err(SolveError::Create(_))));
}

#[test]
fn sizes_and_structures_are_validated() {
    let mut p = Circle::new(2.0, Mode::Normal);
    assert!(matches!(solve(&mut p, &[1.0], &Options::default()), Err(SolveError::Size(_))));
    assert!(matches!(solve(&mut p, &[1.0, f64::NAN], &Options::default()), Err(SolveError::Input(_))));
    p.jac.push((2, 0)); // row out of range
    match solve(&mut p, &[1.0, 0.5], &Options::default()) {
        Err(SolveError::Size(msg)) => assert!(msg.contains("(2, 0)"), "{msg}"),
        other => panic!("expected Size error, got {:?}", other.map(|s| s.status)),
    }
    let mut h = Hs071::new();
    h.hess[1] = (0, 1); // upper triangle
    assert!(matches!(solve(&mut h, &[1.0, 5.0, 5.0, 1.0], &Options::default()), Err(SolveError::Size(_))));
}

#[test]
fn bad_options_are_rejected() {
    let mut p = Circle::new(2.0, Mode::Normal);
    let opts = Options { extra: vec![("no_such_option".into(), OptionValue::Int(3))], ..Options::default() };
    match solve(&mut p, &[1.0, 0.5], &opts) {
        Err(SolveError::BadOption { name, .. }) => assert_eq!(name, "no_such_option"),
        other => panic!("expected BadOption, got {:?}", other.map(|s| s.status)),
    }
    let opts = Options { print_level: 99, ..Options::default() };
    assert!(matches!(solve(&mut p, &[1.0, 0.5], &opts), Err(SolveError::BadOption { .. })));
    // Options pass through: max_iter 1 stops early.
    let opts = Options { max_iter: 1, ..Options::default() };
    let sol = solve(&mut p, &[1.0, 0.5], &opts).expect("runs");
    assert_eq!(sol.status, Status::MaximumIterationsExceeded);
    assert_eq!(sol.iterations, 1);
}

/// Stops via the intermediate callback; and a nested solve is refused, not deadlocked.
struct Stopper {
    inner: Circle,
    /// What the solve started inside the callback returned (its status, or the error).
    nested: Option<Result<Status, SolveError>>,
}

impl Problem for Stopper {
    fn num_variables(&self) -> usize {
        2
    }
    fn num_constraints(&self) -> usize {
        2
    }
    fn constraints(&mut self, x: &[f64], c: &mut [f64]) -> Result<(), EvalError> {
        self.inner.constraints(x, c)
    }
    fn jacobian_structure(&self) -> &[(u32, u32)] {
        self.inner.jacobian_structure()
    }
    fn jacobian_values(&mut self, x: &[f64], v: &mut [f64]) -> Result<(), EvalError> {
        self.inner.jacobian_values(x, v)
    }
    fn intermediate(&mut self, stat: &IterationStat) -> bool {
        if self.nested.is_none() {
            let mut other = Circle::new(1.0, Mode::Normal);
            self.nested = Some(solve(&mut other, &[1.0, 0.5], &Options::default()).map(|s| s.status));
        }
        stat.iter < 1
    }
}

#[test]
fn intermediate_callback_can_stop_and_nesting_is_refused() {
    let mut p = Stopper { inner: Circle::new(2.0, Mode::Normal), nested: None };
    let sol = solve(&mut p, &[1.0, 0.5], &Options::default()).expect("runs");
    assert_eq!(sol.status, Status::UserRequestedStop);
    assert_eq!(sol.iterations, 1);
    assert!(matches!(p.nested, Some(Err(SolveError::Create(_)))), "{:?}", p.nested);
}
