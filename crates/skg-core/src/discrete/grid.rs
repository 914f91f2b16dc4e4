//! Where a discretization puts its nodes: uniformly over the span, or along a map that
//! follows the motion ([`Grid`], [`TimeMap`]).
//!
//! A mapped grid puts node `k` of `N` at `t_k = t(ξ_k)`, `ξ_k = k/(N − 1)`, for a smooth
//! increasing map `t(ξ)` of `[0, 1]` onto the span; the SBP operator on it is
//! [`SbpOperator::on_times`](crate::sbp::SbpOperator::on_times). One map serves every
//! node count: a refinement changes `N` and keeps the map, and the grids of `N` and
//! `2N − 1` nodes are nested as uniform ones are.
//!
//! **The map from a time stepping.** An adaptive time stepper at a tight tolerance takes
//! steps that equidistribute its local error: long where the motion is smooth, short in
//! a contact, a relaxation jump or an initial layer. [`TimeMap::from_steps`] turns the
//! steps `h_j` into a node spacing `s(t)`:
//!
//! 1. *smoothed*: a few passes of the filter (¼, ½, ¼) over `ln h_j`;
//! 2. *with a uniform floor*: `s = h H / (h + H)` with `H` the mean step, i.e. a node
//!    density `1/s = 1/h + 1/H` that gives half of the nodes to the step density and
//!    half to a uniform spread, so that no part of the span is left without nodes;
//! 3. *graded*: on `N` nodes the spacing is `s(t)·S/(N − 1)` with `S = ∫ dt/s`, so
//!    neighbouring spacings differ by a factor of about `1 + |ds/dt|·S/(N − 1)`. The
//!    spacing is shortened until `|ds/dt| ≤ κ (N_min − 1)/S` (`κ` = [`GRADING`], `N_min`
//!    the fewest nodes the map is made for; two passes `s_j ← min(s_j, s_{j∓1} + slope
//!    |t_j − t_{j∓1}|)`, repeated as `S` grows), so that on every grid of at least `N_min`
//!    nodes neighbouring spacings differ by at most about `1 + κ` and the boundary
//!    closures' stretch stays positive for `SBP363` and the orders below (`SBP484`'s
//!    closures can still meet a negative one where the growth of the spacing changes
//!    within a few nodes: 10 of the 37 shipped and test scenes, docs/grids.md#limits);
//! 4. linear in `t` between the steps' midpoints.
//!
//! `ξ(t) = ∫ dt/s / ∫ dt/s` over the span is then continuous with a continuous,
//! positive derivative, and inverted in closed form on each piece (with `s` linear,
//! `∫ dt/s` is a logarithm). On a smooth motion the steps hardly vary and the map is
//! close to uniform.
//!
//! Written here because it is a few lines of arithmetic on the stepper's own output; the
//! grids of mesh-generation crates solve a different problem (elements in space).
//!
//! **Place in the flow.** Numbers only: it uses nothing of this crate; the time stepping
//! supplies the steps and the discretization holds the result.

use std::sync::Arc;

/// Neighbouring node spacings differ by a factor of at most about `1 + GRADING` on the
/// grids a map is made for.
pub const GRADING: f64 = 0.25;

/// Passes of the grading (each with the slope of the `S` the last one left).
const GRADING_PASSES: usize = 6;

/// Passes of the (¼, ½, ¼) filter over the logarithm of the graded spacing.
const SMOOTHING_PASSES: usize = 3;

/// How a discretization spreads its nodes over the span.
#[derive(Debug, Clone)]
pub enum Grid {
    /// Equally spaced.
    Uniform,
    /// Along a map that follows the motion.
    Mapped(Arc<TimeMap>),
}

impl PartialEq for Grid {
    /// Two mapped grids are equal when their maps are the same object or equal.
    fn eq(&self, other: &Grid) -> bool {
        match (self, other) {
            (Grid::Uniform, Grid::Uniform) => true,
            (Grid::Mapped(a), Grid::Mapped(b)) => Arc::ptr_eq(a, b) || a == b,
            _ => false,
        }
    }
}

impl Grid {
    /// The `nodes` node times from `t0` to `t1`.
    pub fn times(&self, t0: f64, t1: f64, nodes: usize) -> Vec<f64> {
        match self {
            Grid::Uniform => uniform_times(t0, t1, nodes),
            Grid::Mapped(map) => map.times(nodes),
        }
    }

    /// `"uniform"` or `"adaptive"`, as the scene file and the summary name it.
    pub fn name(&self) -> &'static str {
        match self {
            Grid::Uniform => "uniform",
            Grid::Mapped(_) => "adaptive",
        }
    }

    /// Whether the nodes are equally spaced.
    pub fn is_uniform(&self) -> bool {
        matches!(self, Grid::Uniform)
    }
}

/// `nodes` equally spaced times from `t0` to `t1`: `t0 + k (t1 − t0)/(nodes − 1)`.
pub fn uniform_times(t0: f64, t1: f64, nodes: usize) -> Vec<f64> {
    let dt = (t1 - t0) / (nodes as f64 - 1.0);
    (0..nodes).map(|k| t0 + k as f64 * dt).collect()
}

/// A smooth increasing map of `ξ ∈ [0, 1]` onto a span, given by a node spacing `s(t)`
/// linear between breakpoints (module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct TimeMap {
    /// The breakpoints, from the span's start to its end.
    at: Vec<f64>,
    /// The spacing at each breakpoint.
    spacing: Vec<f64>,
    /// `∫ dt/s` from the start to each breakpoint.
    cumulative: Vec<f64>,
}

impl TimeMap {
    /// The map whose node spacing follows the steps of a time stepping from `t0` to `t1`,
    /// for grids of at least `min_nodes` nodes: `ends` are the times where its accepted
    /// steps ended, increasing, the last `t1` (module documentation). `None` with fewer
    /// than two steps or a span that is not finite and positive.
    pub fn from_steps(t0: f64, t1: f64, ends: &[f64], min_nodes: usize) -> Option<TimeMap> {
        let bounds: Vec<f64> = std::iter::once(t0).chain(ends.iter().copied().filter(|&t| t > t0 && t <= t1)).collect();
        let steps: Vec<f64> = bounds.windows(2).map(|w| w[1] - w[0]).filter(|h| *h > 0.0).collect();
        if steps.len() < 2 || !(t1 - t0).is_finite() || t1 <= t0 {
            return None;
        }
        let mean = (t1 - t0) / steps.len() as f64;
        let mut ln_h: Vec<f64> = steps.iter().map(|h| h.ln()).collect();
        for _ in 0..SMOOTHING_PASSES {
            ln_h = smoothed(&ln_h);
        }
        let floor = |ln_h: f64| {
            let h = ln_h.exp();
            h * mean / (h + mean)
        };
        let mut at = vec![t0];
        let mut spacing = vec![floor(ln_h[0])];
        for (w, &l) in bounds.windows(2).zip(&ln_h) {
            let mid = 0.5 * (w[0] + w[1]);
            if mid > *at.last().unwrap_or(&t0) && mid < t1 {
                at.push(mid);
                spacing.push(floor(l));
            }
        }
        at.push(t1);
        spacing.push(floor(*ln_h.last().unwrap_or(&0.0)));
        for _ in 0..GRADING_PASSES {
            let total: f64 = (0..at.len() - 1).map(|j| piece_integral(at[j + 1] - at[j], spacing[j], spacing[j + 1])).sum();
            graded(&at, &mut spacing, GRADING * (min_nodes.max(2) - 1) as f64 / total);
        }
        Some(TimeMap::new(at, spacing))
    }

    /// The map of a spacing `spacing[j] > 0` at the increasing breakpoints `at[j]`.
    fn new(at: Vec<f64>, spacing: Vec<f64>) -> TimeMap {
        let mut cumulative = vec![0.0];
        for j in 0..at.len() - 1 {
            let last = cumulative[j];
            cumulative.push(last + piece_integral(at[j + 1] - at[j], spacing[j], spacing[j + 1]));
        }
        TimeMap { at, spacing, cumulative }
    }

    /// The span `(t0, t1)`.
    pub fn span(&self) -> (f64, f64) {
        (self.at[0], self.at[self.at.len() - 1])
    }

    /// The largest ratio of the spacing to the smallest spacing over the span.
    pub fn spacing_ratio(&self) -> f64 {
        let (lo, hi) = self.spacing.iter().fold((f64::INFINITY, 0.0_f64), |(lo, hi), &s| (lo.min(s), hi.max(s)));
        hi / lo
    }

    /// The node times of `nodes ≥ 2` nodes: `t(k/(nodes − 1))`, the ends exact.
    pub fn times(&self, nodes: usize) -> Vec<f64> {
        let total = self.cumulative[self.cumulative.len() - 1];
        let (t0, t1) = self.span();
        let mut j = 0;
        let mut times = Vec::with_capacity(nodes);
        times.push(t0);
        for k in 1..nodes - 1 {
            let target = total * k as f64 / (nodes - 1) as f64;
            while j + 2 < self.at.len() && self.cumulative[j + 1] <= target {
                j += 1;
            }
            times.push(
                self.at[j] + piece_inverse(target - self.cumulative[j], self.at[j + 1] - self.at[j], self.spacing[j], self.spacing[j + 1]),
            );
        }
        times.push(t1);
        times
    }
}

/// `∫ dt/s` over a piece of length `len` on which `s` goes linearly from `a` to `b`:
/// `len · ln(b/a)/(b − a)`.
fn piece_integral(len: f64, a: f64, b: f64) -> f64 {
    let r = (b - a) / a;
    if r.abs() < 1e-12 {
        len / a
    } else {
        len * r.ln_1p() / (a * r)
    }
}

/// The `τ` in `[0, len]` with `∫₀^τ dt/s = target` on the piece of [`piece_integral`]:
/// with `c = (b − a)/len`, `s(τ) = a e^{c·target}`, so `τ = a (e^{c·target} − 1)/c`.
fn piece_inverse(target: f64, len: f64, a: f64, b: f64) -> f64 {
    let c = (b - a) / len;
    let tau = if (c * target).abs() < 1e-12 { a * target } else { a * (c * target).exp_m1() / c };
    tau.clamp(0.0, len)
}

/// Shorten the spacing `s` at the breakpoints `at` until `|ds/dt| ≤ slope` (never
/// lengthened).
fn graded(at: &[f64], s: &mut [f64], slope: f64) {
    for j in 1..s.len() {
        s[j] = s[j].min(s[j - 1] + slope * (at[j] - at[j - 1]));
    }
    for j in (0..s.len() - 1).rev() {
        s[j] = s[j].min(s[j + 1] + slope * (at[j + 1] - at[j]));
    }
}

/// One pass of the filter (¼, ½, ¼), the ends repeated.
fn smoothed(x: &[f64]) -> Vec<f64> {
    let n = x.len();
    (0..n).map(|j| 0.25 * x[j.saturating_sub(1)] + 0.5 * x[j] + 0.25 * x[(j + 1).min(n - 1)]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steps of 0.01 with a burst of steps of 1e-5 around t = 0.5: the map puts the
    /// nodes densely there, the ends exact, increasing, and every spacing between the
    /// burst's and the uniform floor's; the grids of N and 2N − 1 nodes are nested.
    #[test]
    fn a_burst_of_short_steps_draws_the_nodes() {
        let mut ends = Vec::new();
        let mut t: f64 = 0.0;
        while t < 1.0 - 1e-12 {
            let h: f64 = if (t - 0.5_f64).abs() < 0.002 { 1e-5 } else { 0.01 };
            t = (t + h).min(1.0);
            ends.push(t);
        }
        let map = TimeMap::from_steps(0.0, 1.0, &ends, 201).unwrap();
        let times = map.times(201);
        assert_eq!((times[0], times[200]), (0.0, 1.0));
        assert!(times.windows(2).all(|w| w[1] > w[0]));
        let near = times.iter().filter(|t| (*t - 0.5).abs() < 0.003).count();
        // Half of the nodes follow the steps, 400 of 500 of which are in the burst.
        assert!(near > 60, "{near} nodes near the burst");
        let spacings: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(spacings.iter().all(|s| *s < 0.01 && *s > 1e-6), "{spacings:?}");
        // Neighbouring spacings change gradually.
        let worst = spacings.windows(2).map(|w| (w[1] / w[0]).max(w[0] / w[1])).fold(0.0, f64::max);
        assert!(worst < 2.0, "ratio {worst}");
        let fine = map.times(401);
        for (k, t) in times.iter().enumerate() {
            assert!((fine[2 * k] - t).abs() < 1e-14, "node {k}");
        }
    }

    /// Equal steps give the uniform grid.
    #[test]
    fn equal_steps_give_a_uniform_grid() {
        let ends: Vec<f64> = (1..=50).map(|k| 2.0 + k as f64 * 0.1).collect();
        let map = TimeMap::from_steps(2.0, 7.0, &ends, 11).unwrap();
        let times = map.times(11);
        for (k, t) in times.iter().enumerate() {
            assert!((t - (2.0 + 0.5 * k as f64)).abs() < 1e-12, "{times:?}");
        }
        assert!(TimeMap::from_steps(2.0, 7.0, &[7.0], 11).is_none());
    }

    /// The closed-form integral and its inverse agree.
    #[test]
    fn the_inverse_inverts_the_integral() {
        for (a, b) in [(1.0, 1.0), (1.0, 3.0), (2.0, 0.01)] {
            let total = piece_integral(0.7, a, b);
            for f in [0.0, 0.3, 0.9, 1.0] {
                let tau = piece_inverse(f * total, 0.7, a, b);
                let back = piece_integral(tau, a, a + (b - a) * tau / 0.7);
                assert!((back - f * total).abs() < 1e-12 * total, "a={a} b={b} f={f}");
            }
        }
    }
}
