//! What Ipopt's barrier does to a fit's answer: the part of the fit's stopping test
//! (`problem.rs`) about bounded parameters, hand-written because Ipopt's own test judges
//! the barrier parameter `μ` itself, which says nothing about the parameters.
//!
//! **Derivation.** Ipopt solves the barrier problem `min f(x) − μ Σ ln sᵢ` subject to
//! `R(x) = 0`, `s` the slacks of the bounds, whose stationarity is
//! `∇f + Jᵀy − z_L + z_U = r` with `r` the dual infeasibility it reports and
//! `z = μ/s` the bound multipliers. The fit's answer is the unbarriered problem's KKT
//! point. Its bounds are of two kinds at the answer:
//! - *inactive*: its multiplier is zero, so with it removed the unbarriered stationarity
//!   at the iterate is `∇f + Jᵀy = r + g`, the barrier force `g = z_L − z_U` on the
//!   bounded parameters (and nothing on the trajectory). Eliminating the trajectory
//!   through `R(P; θ) = 0` turns `g` into a force on the reduced misfit
//!   `F(θ) = f(P(θ), θ)`, whose minimum it moves by `δθ = H⁻¹ g`, `H` the reduced
//!   Hessian; near a good fit `H` is the Gauss–Newton curvature `AᵀA` of
//!   `statistics.rs` (the two differ by `Σ wᵢ rᵢ ∇²yᵢ`, which vanishes with the
//!   residuals). So the iterate's parameters are the answer's to `|δθ|`;
//! - *active*: the answer has the parameter on its bound, the iterate holds it at the
//!   slack `s = μ/z` from it (the barrier keeps it inside), and the slack is the
//!   barrier's displacement.
//!
//! With one parameter and `F(θ) = ½ H (θ − θ*)²` the barrier's minimum lies at
//! `H (θ − θ*) = μ/s`: the answer is `max(l, θ − z/H)` and the iterate is off by
//! `min(s, z/H)`, which are the two cases above. The test: a parameter whose slack to a
//! bound is within its tolerance, or within Ipopt's relaxation of that bound, is on that
//! bound (the force there pushes towards the bound, so the answer has it there too;
//! within the relaxation it lies between the relaxed bound, where Ipopt's own answer
//! lies, and the bound); the forces on the others, through the curvature restricted to
//! them (those on a bound held), displace each by at most its tolerance
//! `tol · max(|θ|, 1)`. Ipopt's `μ` no longer needs to reach `tol`: on the rolling disk,
//! whose bound `α ∈ [0, 1.5]` lies far from α ≈ 0.52, the barrier at `μ = 2.5e-9` moves
//! α by 1e-12 and v0 by 4e-12, and the fit stops at that iteration, the 5th, where it
//! went on to the 6th to 9th (docs/fitting.md#the-problem-handed-to-ipopt).
//!
//! The slack is measured to Ipopt's relaxed bound, `bound_relax_factor · max(1, |b|)`
//! outside it (Ipopt 3.11's relaxation, 1e-8 unless the scene's `[solver.ipopt]` sets
//! it), where its barrier acts.

use nalgebra::{DMatrix, DVector};

use super::free::FreeParameter;

/// Ipopt's default `bound_relax_factor`.
pub(super) const BOUND_RELAX_FACTOR: f64 = 1e-8;

/// A bound as Ipopt's barrier sees it: finite and below Ipopt's infinity.
fn finite_bound(b: Option<f64>) -> Option<f64> {
    b.filter(|b| b.is_finite() && b.abs() < 1e19)
}

/// The barrier's hold on the bounded parameters at an iterate.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Hold {
    /// Per parameter, the barrier's force `z_L − z_U = μ/s_L − μ/s_U` (0 unbounded).
    pub force: Vec<f64>,
    /// Per parameter, whether it lies on a bound to its tolerance.
    pub on_bound: Vec<bool>,
    /// Per parameter, its tolerance `tol · max(|θ|, 1)`.
    pub tolerance: Vec<f64>,
}

/// The barrier's hold on the parameters `theta` with bounds `free` at barrier parameter
/// `mu` (module documentation).
pub(super) fn hold(free: &[FreeParameter], theta: &[f64], mu: f64, tol: f64, relax_factor: f64) -> Hold {
    let n = free.len();
    let mut h = Hold { force: vec![0.0; n], on_bound: vec![false; n], tolerance: vec![0.0; n] };
    for (j, (p, &t)) in free.iter().zip(theta).enumerate() {
        let tolerance = tol * t.abs().max(1.0);
        let relaxed = |b: f64| relax_factor * b.abs().max(1.0);
        let lower = finite_bound(p.lower).map(|l| (t - (l - relaxed(l)), relaxed(l), 1.0));
        let upper = finite_bound(p.upper).map(|u| ((u + relaxed(u)) - t, relaxed(u), -1.0));
        for (s, relaxation, sign) in lower.into_iter().chain(upper) {
            h.force[j] += sign * mu / s.max(f64::MIN_POSITIVE);
            h.on_bound[j] |= s <= tolerance.max(relaxation);
        }
        h.tolerance[j] = tolerance;
    }
    h
}

impl Hold {
    /// Whether no parameter off its bounds feels a force.
    pub(super) fn free_of_force(&self) -> bool {
        self.force.iter().zip(&self.on_bound).all(|(&f, &on)| on || f == 0.0)
    }

    /// The displacement `δθ = H⁻¹ g` of the parameters off their bounds by the barrier's
    /// forces on them, `H` the `curvature` restricted to them (zero for those on a
    /// bound); `None` when that restriction cannot be inverted.
    pub(super) fn displacement(&self, curvature: &DMatrix<f64>) -> Option<Vec<f64>> {
        let off: Vec<usize> = (0..self.force.len()).filter(|&j| !self.on_bound[j]).collect();
        let h = DMatrix::from_fn(off.len(), off.len(), |a, b| curvature[(off[a], off[b])]);
        let g = DVector::from_iterator(off.len(), off.iter().map(|&j| self.force[j]));
        let d = h.cholesky()?.solve(&g);
        let mut delta = vec![0.0; self.force.len()];
        for (a, &j) in off.iter().enumerate() {
            delta[j] = d[a];
        }
        Some(delta)
    }

    /// Whether the barrier displaces every parameter by at most its tolerance, judged
    /// with the misfit's `curvature` (module documentation).
    pub(super) fn negligible(&self, curvature: &DMatrix<f64>) -> bool {
        self.free_of_force() || self.displacement(curvature).is_some_and(|d| d.iter().zip(&self.tolerance).all(|(d, t)| d.abs() <= *t))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bounded(lower: Option<f64>, upper: Option<f64>) -> FreeParameter {
        FreeParameter { name: "p".into(), lower, upper }
    }

    /// One parameter, misfit `½ H (θ − θ*)²`, bound `θ ≥ 0`: the barrier's minimum
    /// `H (θ − θ*) = μ/s` solved in closed form; the displacement the test computes is
    /// `θ − θ*` to first order, and the test's verdict follows it.
    #[test]
    fn an_inactive_bound_displaces_the_parameter_by_force_over_curvature() {
        let (h, theta_star, mu) = (2400.0, std::f64::consts::FRAC_PI_6, 2.5e-9_f64);
        // H (θ − θ*) θ = μ  →  θ − θ* = (√(θ*² + 4μ/H) − θ*) / 2, written without the
        // cancellation (no relaxation).
        let shift = 2.0 * mu / h / (theta_star + (theta_star * theta_star + 4.0 * mu / h).sqrt());
        let theta = theta_star + shift;
        let free = [bounded(Some(0.0), None)];
        let hold = hold(&free, &[theta], mu, 1e-10, 0.0);
        assert!(!hold.on_bound[0]);
        let d = hold.displacement(&DMatrix::from_element(1, 1, h)).unwrap();
        assert!((d[0] - shift).abs() < 1e-9 * shift, "{} vs {shift}", d[0]);
        assert!(hold.negligible(&DMatrix::from_element(1, 1, h)));
        // At a barrier 10⁴ times larger the displacement, 2e-8, is above tol = 1e-10.
        let far = self::hold(&free, &[theta], 2.5e-5, 1e-10, 0.0);
        assert!(!far.negligible(&DMatrix::from_element(1, 1, h)));
    }

    /// The same misfit with the answer beyond the bound (`θ* = −0.1`): the barrier holds
    /// the parameter at `s = μ/z` from its relaxed bound, and the test asks that slack,
    /// not the force, to be within the tolerance or Ipopt's relaxation of the bound.
    #[test]
    fn an_active_bound_is_met_when_the_slack_is_within_the_tolerance() {
        let (h, theta_star, relax) = (10.0, -0.1, 1e-8);
        let free = [bounded(Some(0.0), Some(2.0))];
        let curvature = DMatrix::from_element(1, 1, h);
        for (mu, met) in [(1e-6, false), (1e-9, true), (1e-12, true)] {
            // H (θ − θ*) s = μ with s = θ + relax: s ≈ μ / (H (−θ* − relax)).
            let s = mu / (h * (-theta_star - relax));
            let hold = hold(&free, &[s - relax], mu, 1e-10, relax);
            assert_eq!(hold.on_bound[0], met, "μ = {mu}");
            assert_eq!(hold.negligible(&curvature), met, "μ = {mu}");
        }
    }

    /// Two coupled parameters, one held on its bound: the other's displacement uses the
    /// curvature restricted to it; unbounded parameters feel no force.
    #[test]
    fn a_parameter_on_its_bound_is_held_and_the_others_move_alone() {
        let free = [bounded(Some(0.0), None), bounded(Some(-10.0), Some(10.0)), bounded(None, None)];
        let theta = [1e-12, 1.0, 3.0];
        let hold = hold(&free, &theta, 1e-9, 1e-10, 0.0);
        assert_eq!(hold.on_bound, [true, false, false]);
        assert_eq!(hold.force[2], 0.0);
        // Force on the second: μ/11 − μ/9 < 0.
        assert!((hold.force[1] - (1e-9 / 11.0 - 1e-9 / 9.0)).abs() < 1e-24);
        let curvature = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.5, 1.0, 2.0, 0.2, 0.5, 0.2, 1.0]);
        let d = hold.displacement(&curvature).unwrap();
        let h = DMatrix::from_row_slice(2, 2, &[2.0, 0.2, 0.2, 1.0]);
        let expected = h.try_inverse().unwrap() * DVector::from_vec(vec![hold.force[1], 0.0]);
        assert_eq!(d[0], 0.0);
        assert!((d[1] - expected[0]).abs() < 1e-24 && (d[2] - expected[1]).abs() < 1e-24, "{d:?}");
    }
}
