//! When a node is in contact with a wall: one definition, used for the contact episodes
//! of a solve's diagnostics ([`crate::solve`]), the free nodes of the energy artifact
//! ([`crate::tune`]) and the tests.
//!
//! A node is in contact with a wall of width σ when its gap `h > −CONTACT_WIDTHS·σ`.
//! The wall's Gaussian force is `A δ_σ(h) |∇h|` with `δ_σ(h) ∝ exp(−h²/2σ²)`, so at the
//! boundary of contact it has fallen to `exp(−CONTACT_WIDTHS²/2)` of its peak.

use std::ops::Range;

/// Contact reaches `CONTACT_WIDTHS` wall widths σ out from the wall.
///
/// Six: at `h = −6σ` the Gaussian force is `e^{−18} ≈ 1.5e-8` of its peak, so a node
/// outside contact moves in free flight to about eight digits, and quantities measured
/// there (the energy between bounces) see no wall. At `−3σ` the force is still
/// `e^{−4.5} ≈ 1.1 %` of its peak: a node there is not free. A bounce is a deep
/// excursion (`h` reaches about `−σ` or beyond, the paper's tumbler: ~20 nodes at
/// N = 256), so the wider band neither merges the tumbler's two bounces nor misses the
/// spurious missing bounce at N = 48 (tests `walls.rs`).
pub const CONTACT_WIDTHS: f64 = 6.0;

/// Whether a node with gap `h` is in contact with a wall of width `sigma`.
pub fn in_contact(h: f64, sigma: f64) -> bool {
    h > -CONTACT_WIDTHS * sigma
}

/// The contact episodes of one wall: the maximal runs of consecutive nodes in contact,
/// as node ranges, given the wall's gap at each node.
pub fn episodes(gaps: impl IntoIterator<Item = f64>, sigma: f64) -> Vec<Range<usize>> {
    let mut out: Vec<Range<usize>> = Vec::new();
    for (k, h) in gaps.into_iter().enumerate() {
        if !in_contact(h, sigma) {
            continue;
        }
        match out.last_mut() {
            Some(last) if last.end == k => last.end = k + 1,
            _ => out.push(k..k + 1),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn episodes_are_maximal_runs_within_six_widths() {
        let sigma = 0.125; // 6σ = 0.75 exactly
        assert!(in_contact(-0.74, sigma) && !in_contact(-0.75, sigma) && in_contact(0.3, sigma));
        let h = [-1.0, -0.5, 0.0, -0.8, -0.8, -0.2, -0.1, -2.0, -0.01];
        assert_eq!(episodes(h, sigma), vec![1..3, 5..7, 8..9]);
        assert!(episodes([-1.0, -2.0], sigma).is_empty());
        assert!(episodes([f64::NAN], sigma).is_empty());
    }
}
