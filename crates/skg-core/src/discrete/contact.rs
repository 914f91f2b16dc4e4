//! When a node is in contact with a wall: one definition, used for the contact episodes
//! of a solve's diagnostics, the restarts of windows, the free nodes of the energy
//! artifact (σ tuning), the motion's pictures and the tests; and how finely a grid
//! resolves the contacts ([`resolution`]).
//!
//! A node is in contact with a wall of width σ when its gap `h > −CONTACT_WIDTHS·σ`.
//! The wall's Gaussian force is `A δ_σ(h) |∇h|` with `δ_σ(h) ∝ exp(−h²/2σ²)`, so at the
//! boundary of contact it has fallen to `exp(−CONTACT_WIDTHS²/2)` of its peak.

use std::ops::Range;

use indexmap::IndexMap;
use serde::Serialize;

use crate::discrete::trajectory::Trajectory;
use crate::model::Model;

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

/// Fewer grid steps per contact length than this, and a failed solve's remedy says that
/// the grid does not resolve the wall's contacts and names the node count that reaches
/// [`RESOLVED_STEPS`]. Measured on scenes with walls (SBP242, [`resolution`]'s steps):
/// failed 0.58, 1.24 (a ball between two walls at N = 1024, 2048), 1.28 (a puck in a box
/// at 1024); verified 1.53 (the vibrating plate), 1.76 (the tumbler), 2.53, 2.56 (the
/// first two at 4096, 2048). It is not a sharp bound, so it only shapes the remedy of a
/// solve that failed.
pub const MIN_STEPS: f64 = 1.5;
/// The steps per contact length the remedy's node count aims at.
pub const RESOLVED_STEPS: f64 = 2.0;

/// How finely the nodes of a trajectory resolve one wall's contacts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WallResolution {
    /// The fewest grid steps in which the gap changes by a contact's length
    /// `ℓ = σ·min(1, σ/|h_turn|)` ([`fewest_steps`]).
    pub steps: f64,
    /// The time of that node.
    pub t: f64,
    /// The gap's rate of change `|ḣ| = |∇h·q̇ + ∂h/∂t|` there.
    pub gap_rate: f64,
    /// The contact's length ℓ.
    pub length: f64,
}

/// The fewest grid steps per contact length, `ℓ / (|ḣ_k| Δt_k)`, over the nodes `k` in
/// contact or within one step of it (`h_k + |ḣ_k| Δt_k > −CONTACT_WIDTHS σ`), as
/// `(k, steps, ℓ)`; `None` if no node comes that close or the gap never changes there.
/// `Δt_k` is the spacing after node k (before it at the last node).
///
/// The contact's length: the wall's potential is `A Φ(h/σ)` (Φ the normal distribution
/// function), its force `A φ(h/σ)/σ`. A contact that turns at the gap `h_turn` (the
/// largest gap of its run of nodes) within a width of the wall is stopped over about σ;
/// one that turns further out, at `z = h_turn/σ < −1`, meets a force of about
/// `|z| A Φ(z)/σ` (as `φ(z) ≈ |z| Φ(z)` there), `|z|` times the kinetic energy it stops
/// per σ, so it is stopped over `ℓ = σ/|z| = σ²/|h_turn|`. The nodes may miss the turn
/// of a contact they do not resolve, so `|z|` is taken at most [`CONTACT_WIDTHS`].
pub fn fewest_steps(t: &[f64], gaps: &[f64], rates: &[f64], sigma: f64) -> Option<(usize, f64, f64)> {
    let n = t.len().min(gaps.len()).min(rates.len());
    if n < 2 {
        return None;
    }
    let spacing = |k: usize| if k + 1 < n { t[k + 1] - t[k] } else { t[k] - t[k - 1] };
    // The gap one step on: a node is near contact when that is in contact (NaN, never in
    // contact, where the rate is not finite).
    let reach = (0..n).map(|k| if rates[k].is_finite() { gaps[k] + rates[k].abs() * spacing(k) } else { f64::NAN });
    let mut best: Option<(usize, f64, f64)> = None;
    for run in episodes(reach, sigma) {
        let turn = gaps[run.clone()].iter().copied().fold(f64::NEG_INFINITY, f64::max).max(-CONTACT_WIDTHS * sigma);
        let length = if turn < -sigma { sigma * sigma / -turn } else { sigma };
        for j in run.filter(|&j| rates[j] != 0.0) {
            let steps = length / (rates[j].abs() * spacing(j));
            if best.is_none_or(|b| steps < b.1) {
                best = Some((j, steps, length));
            }
        }
    }
    best
}

/// How finely the nodes of `tr` (a time-stepping solution, with its velocities) resolve
/// each wall's contacts, for the walls it comes near, keyed by wall name.
pub fn resolution(model: &Model, tr: &Trajectory) -> IndexMap<String, WallResolution> {
    let mut out = IndexMap::new();
    for (j, wall) in model.walls.iter().enumerate() {
        let gaps: Vec<f64> = tr.h.iter().map(|h| h[j]).collect();
        let rates: Vec<f64> = tr.t.iter().zip(&tr.q).zip(&tr.v).map(|((&t, q), v)| gap_rate(model, j, t, q, v)).collect();
        if let Some((k, steps, length)) = fewest_steps(&tr.t, &gaps, &rates, wall.width) {
            out.insert(wall.name.clone(), WallResolution { steps, t: tr.t[k], gap_rate: rates[k].abs(), length });
        }
    }
    out
}

/// `ḣ = ∇h·q̇ + ∂h/∂t` of wall `j` at (t, q, q̇); `∂h/∂t` of a moving wall by a central
/// difference (it only sizes the grid).
fn gap_rate(model: &Model, j: usize, t: f64, q: &[f64], v: &[f64]) -> f64 {
    let along: f64 = model.wall_normal(j, t, q).iter().zip(v).map(|(n, v)| n * v).sum();
    if !model.wall_moves(j) {
        return along;
    }
    let dt = 1e-6 * t.abs().max(1.0);
    along + (model.wall_gaps(t + dt, q)[j] - model.wall_gaps(t - dt, q)[j]) / (2.0 * dt)
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

    /// A ball at speed 2 on a grid of spacing 0.01 meets a wall of width σ = 0.05 and
    /// turns at h = −0.1 = −2σ: the contact's length is σ²/0.1 = 0.025, crossed in
    /// 0.025 / (2 · 0.01) = 1.25 steps at the fastest node in contact or one step from it;
    /// turning within σ of the wall, the length is σ (2.5 steps). Far nodes and nodes at
    /// rest do not count.
    #[test]
    fn fewest_steps_counts_nodes_in_or_near_contact_over_the_contact_length() {
        let t = [0.0, 0.01, 0.02, 0.03, 0.04];
        let sigma = 0.05; // contact: h > −0.3
        let gaps = [-0.5, -0.31, -0.1, -0.2, -0.9];
        let rates = [9.0, 2.0, 0.5, -1.0, 0.0];
        let (k, steps, length) = fewest_steps(&t, &gaps, &rates, sigma).unwrap();
        assert_eq!(k, 1, "node 0 is 0.2 from contact, more than its step 0.09");
        assert!((length - 0.025).abs() < 1e-15 && (steps - 1.25).abs() < 1e-12, "{steps} {length}");
        let shallow = [-0.5, -0.31, -0.04, -0.2, -0.9];
        let (k, steps, length) = fewest_steps(&t, &shallow, &rates, sigma).unwrap();
        assert!(k == 1 && length == sigma && (steps - 2.5).abs() < 1e-12, "{k} {steps} {length}");
        assert_eq!(fewest_steps(&t, &[-1.0; 5], &rates, sigma), None);
        assert_eq!(fewest_steps(&t, &gaps, &[0.0; 5], sigma), None);
        assert_eq!(fewest_steps(&t[..1], &gaps[..1], &rates[..1], sigma), None);
    }
}
