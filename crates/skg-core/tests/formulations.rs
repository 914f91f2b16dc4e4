//! The two formulations of docs/mathematics.md and the two Hessian modes describe the same
//! discrete critical point: on every shipped scene they must agree.

mod common;

use skg_core::scene::{Formulation, HessianMode, Overrides};

fn max_diff(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

#[test]
fn full_and_reduced_formulations_agree_on_every_shipped_scene() {
    for name in common::SHIPPED {
        let r = common::solve(name, &Overrides { formulation: Some(Formulation::Reduced), ..Default::default() });
        let f = common::solve(name, &Overrides { formulation: Some(Formulation::Full), ..Default::default() });
        let (tr, tf) = (&r.trajectory, &f.trajectory);
        let dq = max_diff(&tr.q, &tf.q);
        assert!(dq < 1e-9, "{name}: max |q_reduced − q_full| = {dq:e}");
        let dl = max_diff(&tr.lambda, &tf.lambda);
        assert!(dl < 1e-9, "{name}: max |λ_reduced − λ_full| = {dl:e}");
        // The full formulation's minus variables vanish at the physical critical point.
        let minus = f.diagnostics.max_minus_variable.unwrap();
        assert!(minus < 1e-9, "{name}: max |q-|, |λ-| = {minus:e}");
        // Sizes: the full system has exactly twice the unknowns.
        assert_eq!(f.sizes.variables, 2 * r.sizes.variables, "{name}");
        assert_eq!(r.sizes.variables, r.sizes.equations, "{name}: reduced system not square");
    }
}

/// Ipopt's step solves [H Jᵀ; J 0] [dx; dy] = −[∇ℒ; c]. For a square nonsingular J the
/// second row alone gives dx = −J⁻¹c: the primal step does not depend on the Hessian H,
/// only the multiplier step does. So the exact Hessian and the zero Hessian must walk
/// the same primal path (docs/solver.md measured identical iterates).
#[test]
fn exact_and_zero_hessian_give_the_same_iterates() {
    for name in ["rolling_disk", "tumbler"] {
        let zero = common::solve(name, &Overrides { hessian: Some(HessianMode::Zero), ..Default::default() });
        let exact = common::solve(name, &Overrides { hessian: Some(HessianMode::Exact), ..Default::default() });
        assert_eq!(zero.iterations, exact.iterations, "{name}: iteration counts differ");
        assert!(exact.sizes.hessian_nonzeros > 0 && zero.sizes.hessian_nonzeros == 0, "{name}");
        for (a, b) in zero.history.iter().zip(&exact.history) {
            let rel = (a.inf_pr - b.inf_pr).abs() / a.inf_pr.abs().max(1e-300);
            assert!(rel < 1e-6 || a.inf_pr.max(b.inf_pr) < 1e-8, "{name}: primal infeasibility {} vs {}", a.inf_pr, b.inf_pr);
        }
        let dq = max_diff(&zero.trajectory.q, &exact.trajectory.q);
        assert!(dq < 1e-12, "{name}: max |q_zero − q_exact| = {dq:e}");
    }
}
