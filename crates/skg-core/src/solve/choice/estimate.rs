//! What the refinement expects of a candidate before solving it: its predicted error,
//! the proxy of [`predict`](super::predict) calibrated by the solves made so far
//! ([`calibration`], [`proxy_ratio`]), and its cost ([`cost_of`]).

use super::cost::relative_cost;
use super::predict::{along_power_law, observed_order, Candidate, Predictor, FINE_NODES};
use crate::solve::run::error::SolveError;

/// A calibration measured with a centred operator is carried to the dissipative ones
/// only up to this: beyond, it is the centred operators' odd-even mode. (Measured on
/// first grids, where nothing is calibrated yet: the disk, the tumbler and the damped
/// oscillator at tolerances 1e-3 … 1e-8 are off by 0.8 … 6 on both families; on the
/// strongly contracting test scene `SBP121` is off by 15.7, `SBP242` and `SBP484` by 0.3
/// and 0.04.)
pub(super) const CROSS_FAMILY: f64 = 10.0;
/// A calibration above this is kept for its own candidate only, not carried to the
/// others: a miss that large is that discretization's own failure (a spurious discrete
/// solution, a resonance of its grid), not the dynamics the proxy leaves out. (The stiff
/// dumbbell with `SBP242-AD` and the natural condition on 256 nodes: predicted at 0.0017
/// of the tolerance, converged 825 times it away; carried, that calibration of 5e5 put
/// every candidate beyond the budget and the refinement gave up, where `SBP242` with the
/// natural condition verifies on the same grid.)
pub(super) const OWN_FAILURE: f64 = 1e3;
/// An adaptive grid is chosen over the uniform one only where it is predicted to need
/// fewer than 1/ADAPTIVE_PENALTY of the nodes: its proxy misses more (the map's
/// transitions; on a strongly contracting scene a centred operator on it was predicted
/// at 0.38 of the tolerance and measured at 9.9), and where the motion has no brief fast
/// part the uniform grid does as well.
pub(super) const ADAPTIVE_PENALTY: f64 = 2.0;
/// The proxy is computed on grids up to the reference's fine grid; beyond, its error is
/// extrapolated with the order it shows between the two largest of them.
pub(super) const PROXY_MAX_NODES: usize = FINE_NODES;
/// On the adaptive grid up to this many nodes: its map is graded for grids of at least
/// the scene's nodes, so coarser grids need not show the order of finer ones (each grid
/// beyond the fine one costs a time stepping sampled at its nodes).
pub(super) const ADAPTIVE_PROXY_MAX_NODES: usize = (1 << 16) + 1;

/// The cost of solving `c` on `nodes` nodes relative to the others: its operator's
/// measured cost per node on `backend`, times [`ADAPTIVE_PENALTY`] on the adaptive grid.
pub(super) fn cost_of(c: Candidate, backend: crate::scene::Backend, nodes: usize) -> f64 {
    relative_cost(c.operator, backend, nodes) * if c.adaptive { ADAPTIVE_PENALTY } else { 1.0 }
}

/// The calibration of `c` given those measured so far (in order): its last measured
/// one; else, of the others' up to [`OWN_FAILURE`], the largest measured in its family
/// (centred or dissipative), at least 1;
/// else the largest measured in the other family, at least 1: always from a dissipative
/// operator to a centred one (what it carries is the scene's dynamics, which the proxy
/// leaves out and a centred operator meets as well), from a centred one only up to
/// [`CROSS_FAMILY`] (beyond, it is the centred operators' odd-even mode, which says
/// nothing of a dissipative one's error); else 1.
pub(super) fn calibration(measured: &[(Candidate, f64)], c: Candidate) -> f64 {
    if let Some(&(_, g)) = measured.iter().rev().find(|(k, _)| *k == c) {
        return g;
    }
    let largest = |same: bool| {
        measured
            .iter()
            .filter(|&&(_, g)| g <= OWN_FAILURE)
            .filter(|(k, _)| (k.operator.is_dissipative() == c.operator.is_dissipative()) == same)
            .map(|&(_, g)| g)
            .fold(f64::NAN, f64::max)
    };
    let own_family = largest(true);
    if !own_family.is_nan() {
        return own_family.max(1.0);
    }
    let other = largest(false);
    if other <= CROSS_FAMILY || !c.operator.is_dissipative() {
        other.max(1.0)
    } else {
        1.0
    }
}

/// The proxy's ratio of `c` on `nodes` nodes, extrapolated beyond [`PROXY_MAX_NODES`]
/// ([`ADAPTIVE_PROXY_MAX_NODES`] on the adaptive grid) with the order between the two
/// largest grids computed.
pub(super) fn proxy_ratio(p: &mut Predictor, c: Candidate, nodes: usize) -> Result<f64, SolveError> {
    let floor = p.roundoff_ratio(c, nodes);
    let largest = if c.adaptive { ADAPTIVE_PROXY_MAX_NODES } else { PROXY_MAX_NODES };
    if nodes <= largest {
        return Ok(p.ratio_between(c, nodes)?.max(floor));
    }
    let (hi, lo) = (largest, (largest - 1) / 2 + 1);
    let (r_hi, r_lo) = (p.ratio(c, hi)?, p.ratio(c, lo)?);
    let order = observed_order(lo, r_lo, hi, r_hi);
    if !(order.is_finite() && order > 0.0) {
        return Ok(r_hi.max(floor));
    }
    Ok(along_power_law(hi, r_hi, order, nodes).max(floor))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sbp::OperatorKind;
    use crate::scene::InitialVelocity::{Natural, Strong};

    fn cand(operator: OperatorKind, initial_velocity: crate::scene::InitialVelocity) -> Candidate {
        Candidate { operator, initial_velocity, adaptive: false }
    }

    #[test]
    fn calibrations_carry_within_a_family_and_across_it_below_the_odd_even_mode() {
        let c242 = cand(OperatorKind::Sbp242, Strong);
        let c363n = cand(OperatorKind::Sbp363, Natural);
        let d242 = cand(OperatorKind::Sbp242Ad, Natural);
        // Nothing measured: the proxy as it is.
        assert_eq!(calibration(&[], c242), 1.0);
        // Its own last measurement first, even below 1 and below the family's largest.
        let m = [(c363n, 5.0), (c242, 3.0), (c242, 0.5)];
        assert_eq!(calibration(&m, c242), 0.5);
        // Else the family's largest, at least 1.
        assert_eq!(calibration(&m, cand(OperatorKind::Sbp484, Natural)), 5.0);
        assert_eq!(calibration(&[(c242, 0.3)], c363n), 1.0);
        // The other family's, as the disk at 1e-3 measured (SBP242-AD 4.7, then SBP242
        // off by 2.6 with the proxy as it was), when it is not the odd-even mode.
        assert_eq!(calibration(&[(d242, 4.7)], c242), 4.7);
        assert_eq!(calibration(&[(c242, 4.2)], d242), 4.2);
        assert_eq!(calibration(&[(c242, 1e3)], d242), 1.0);
        // A dissipative operator's, however large, to a centred one (the rotor and spring
        // test scene: SBP242-AD off by 10.6, then SBP242 by 3.9 with the proxy as it was).
        assert_eq!(calibration(&[(d242, 10.6)], c242), 10.6);
        // A family's own measurement outranks the other's.
        assert_eq!(calibration(&[(c242, 8.0), (d242, 2.0)], cand(OperatorKind::Sbp484Ad, Strong)), 2.0);
        // A discretization's own failure stays its own (the stiff dumbbell: 5e5).
        assert_eq!(calibration(&[(d242, 5e5)], d242), 5e5);
        assert_eq!(calibration(&[(d242, 5e5)], c242), 1.0);
        assert_eq!(calibration(&[(d242, 5e5), (c363n, 3.0)], cand(OperatorKind::Sbp484Ad, Natural)), 3.0);
    }
}
