//! Ipopt's options for a fit: the scene's solver settings and MUMPS options as for a
//! solve, then the fit's own (its tolerance and stopping, MUMPS's pivot tolerance and,
//! for the all-at-once fit's KKT matrix, its ordering, the warm start, the Hessian), then
//! the scene's `[solver.ipopt]` options, which win.

use skg_ipopt as ipopt;

use super::problem::Plans;
use super::settings::{FitHessian, FitMethod, FitSettings, ACCEPTABLE_ITER, MUMPS_PIVTOL, MUMPS_PIVTOL_LINEAR};
use crate::discrete::ParameterPlan;
use crate::scene::Scene;
use crate::solve::backend::mumps_options;

/// The reduced fit's options (its problem has no constraints: MUMPS factors only Ipopt's
/// small system in the parameters).
pub(super) fn reduced(scene: &Scene, settings: &FitSettings) -> ipopt::Options {
    ipopt_options(scene, settings, MUMPS_PIVTOL)
}

/// The all-at-once fit's options: MUMPS's pivot tolerance by whether the equations are
/// nonlinear in the trajectory, and PORD for its ordering from
/// [`DENSE_COLUMNS_FOR_PORD`] dense parameter columns on (`rows`, the equations), unless
/// the scene's `[solver.ipopt]` names an ordering.
pub(super) fn all_at_once(scene: &Scene, settings: &FitSettings, plans: &Plans, rows: usize) -> ipopt::Options {
    let nonlinear = plans.hessian.as_ref().is_some_and(|h| !h.structure.is_empty());
    let mut options = ipopt_options(scene, settings, if nonlinear { MUMPS_PIVTOL } else { MUMPS_PIVTOL_LINEAR });
    if dense_parameter_columns(&plans.parameters, rows) >= DENSE_COLUMNS_FOR_PORD && !scene.solver.ipopt.contains_key("mumps_pivot_order") {
        options.extra.push(("mumps_pivot_order".into(), ipopt::OptionValue::Int(MUMPS_PORD)));
    }
    options
}

/// Ipopt's options for a fit of `scene`: the scene's linear solver, print level and
/// MUMPS settings as for a solve, the fit's tolerance and iteration limit, the
/// constraints held to the scene's `[solver] tol`, [`ACCEPTABLE_ITER`], MUMPS's pivot
/// tolerance `pivtol` ([`MUMPS_PIVTOL`] or [`MUMPS_PIVTOL_LINEAR`]), the Hessian, then the
/// scene's `[solver.ipopt]` options.
fn ipopt_options(scene: &Scene, settings: &FitSettings, pivtol: f64) -> ipopt::Options {
    let solver = &scene.solver;
    let mut extra: Vec<(String, ipopt::OptionValue)> =
        mumps_options(scene).into_iter().map(|(k, v)| (k.to_string(), ipopt::OptionValue::Int(v))).collect();
    // The constraints of a long or stiff scene stall at a round-off floor above the
    // fit's tol: stop after a few iterations at Ipopt's acceptable level (with a warning)
    // instead of line-searching at that floor up to the iteration limit.
    // The reduced fit has no constraints, and its own acceptable level (`reduced.rs`):
    // Ipopt's, absolute in the gradient, stopped a large parameter far from its minimum
    // (as does Ipopt's `tol` test: [`REDUCED_IPOPT_TOL`]).
    let acceptable_iter = if settings.method == FitMethod::Reduced { 0 } else { ACCEPTABLE_ITER };
    extra.push(("acceptable_iter".into(), ipopt::OptionValue::Int(acceptable_iter)));
    // MUMPS's default pivot tolerance (1e-6) left its solves of the fit's KKT matrix
    // inaccurate (Ipopt's iterative refinement failed, then it raised the tolerance and
    // factored again, 2 to 3 factorizations per iteration on the disk); at 1e-3 none
    // failed on the disk, but with MUMPS's analysis made on the first KKT matrix (the
    // warm start) the disk's last iterations stalled in the line search with some BLAS
    // kernels (9 iterations instead of 6); at 0.1 (Ipopt's `mumps_pivtolmax`) none did
    // (docs/benchmarks.md#fitting). Where the trajectory block holds the misfit's
    // curvature alone, 1e-4 ([`MUMPS_PIVTOL_LINEAR`]).
    extra.push(("mumps_pivtol".into(), ipopt::OptionValue::Num(pivtol)));
    // The fit starts from its own least-squares multipliers (`multipliers.rs`) with
    // Ipopt's warm start, pushing the point into its bounds as Ipopt's cold start does.
    extra.push(("warm_start_bound_push".into(), ipopt::OptionValue::Num(1e-2)));
    extra.push(("warm_start_bound_frac".into(), ipopt::OptionValue::Num(1e-2)));
    if settings.hessian == FitHessian::LimitedMemory {
        extra.push(("hessian_approximation".into(), ipopt::OptionValue::Str("limited-memory".into())));
    }
    extra.extend(solver.ipopt.iter().map(|(k, v)| {
        let v = match v {
            crate::scene::IpoptValue::Int(i) => ipopt::OptionValue::Int(*i),
            crate::scene::IpoptValue::Num(x) => ipopt::OptionValue::Num(*x),
            crate::scene::IpoptValue::Str(s) => ipopt::OptionValue::Str(s.clone()),
        };
        (k.clone(), v)
    }));
    ipopt::Options {
        tol: if settings.method == FitMethod::Reduced { REDUCED_IPOPT_TOL } else { settings.tol },
        constr_viol_tol: solver.tol,
        max_iter: settings.max_iter,
        print_level: solver.print_level,
        linear_solver: solver.linear_solver.clone(),
        output_file: solver.ipopt_log.clone(),
        extra,
        ..ipopt::Options::default()
    }
}

/// Ipopt's `tol` in the reduced fit, out of reach: the fit's `tol` applies to its own
/// displacement test (`reduced.rs`), which is relative to each parameter's size, where
/// Ipopt's test bounds the gradient absolutely. A damping of 1e4 fitted to noise-free
/// data (the misfit's curvature in it about 1e-11) passed Ipopt's `tol = 1e-10` at
/// `c = 9999.4`, 6 of its standard errors from the minimum.
const REDUCED_IPOPT_TOL: f64 = 1e-30;

/// The parameters whose column of `∂R/∂θ` is dense: entries in more than a tenth of the
/// equations (a stiffness or a damping, which every node's equations hold; an initial
/// value's column has a few).
fn dense_parameter_columns(plan: &ParameterPlan, rows: usize) -> usize {
    let mut count = std::collections::HashMap::<u32, usize>::new();
    plan.jacobian.iter().for_each(|&(_, j)| *count.entry(j).or_default() += 1);
    count.values().filter(|&&n| 10 * n > rows).count()
}

/// From this many dense parameter columns on, the all-at-once fit's MUMPS orders the KKT
/// matrix by PORD ([`MUMPS_PORD`]) instead of the scene's ordering (AMF without
/// position constraints), unless the scene's `[solver.ipopt]` names one. Each dense
/// column couples every node, and AMF's factor grew with them: a chain of five masses
/// with a stiffness, a second stiffness and a damping free (SBP363, 600 nodes) held 17 M
/// doubles against 0.45 M for the solve's KKT matrix (1.5 M with PORD), and the fit took
/// 73 CPU s and 43 iterations to a spurious discrete solution (2.7 s and 29 iterations to
/// the true values with PORD); three masses 1.95 M doubles (0.77 M), 1.44 → 0.43 s. With
/// one dense column (the rolling disk's incline) or none (the double pendulum's release
/// angles) AMF was the faster (0.19 against 0.23 s, 0.56 against 0.81 s); with two and
/// initial values the damped oscillator's `k, c, x0, v0` took the same time, two masses'
/// `k, c, v2` 0.33 s against 0.27 (docs/benchmarks.md#fitting).
const DENSE_COLUMNS_FOR_PORD: usize = 2;

/// MUMPS's `ICNTL(7)` for PORD (Ipopt's `mumps_pivot_order`).
const MUMPS_PORD: i32 = 4;

/// A numeric `[solver.ipopt]` value.
pub(super) fn ipopt_number(value: &crate::scene::IpoptValue) -> Option<f64> {
    match value {
        crate::scene::IpoptValue::Int(i) => Some(f64::from(*i)),
        crate::scene::IpoptValue::Num(x) => Some(*x),
        crate::scene::IpoptValue::Str(_) => None,
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::discrete::Discretization;
    use crate::model::Model;
    use crate::scene::{Overrides, SceneFile};
    use crate::solve::action_on;

    /// A stiffness and a damping are in every node's equations, an initial position and
    /// velocity in the first node's: two dense columns of four.
    #[test]
    fn the_parameters_in_every_equation_are_the_dense_columns() {
        let text = "[scene]\nname = \"o\"\nlagrangian = \"x_dot^2/2 - k*x^2/2\"\n[parameters]\nk = 4\nc = 0.3\nx0 = 1\nv0 = 0\n\
                    [[coordinates]]\nname = \"x\"\ninitial = \"x0\"\nvelocity = \"v0\"\n[forces]\nx = \"-c*x_dot\"\n\
                    [time]\nstart = 0\nend = 3\nnodes = 64\n";
        let scene = SceneFile::parse(text, "o.toml").unwrap().resolve(&Overrides::default()).unwrap();
        let count = |names: &[&str]| {
            let names: Vec<String> = names.iter().map(|n| n.to_string()).collect();
            let model = Arc::new(Model::with_free_parameters(&scene, &names).unwrap());
            let disc = Discretization::of(&scene);
            let times = disc.times(&scene);
            let action = action_on(&model, &scene, &disc, &times).unwrap();
            dense_parameter_columns(&action.parameter_plan(), action.layout.n_p)
        };
        assert_eq!(count(&["k", "c", "x0", "v0"]), 2);
        assert_eq!(count(&["x0", "v0"]), 0);
        assert_eq!(count(&["k"]), 1);
    }
}
