//! A trajectory between its nodes: cubic Hermite interpolation of the coordinates, whose
//! velocities are their slopes, and linear interpolation of any node series.
//!
//! The cubic Hermite polynomial of an interval `[t₀, t₁]` takes the values `y₀`, `y₁`
//! and the slopes `ẏ₀`, `ẏ₁` at its ends: with `h = t₁ − t₀` and `s = (t − t₀)/h`,
//!
//! ```text
//! y(t) = h₀₀(s) y₀ + h₁₀(s) h ẏ₀ + h₀₁(s) y₁ + h₁₁(s) h ẏ₁,
//! h₀₀ = 2s³ − 3s² + 1,  h₁₀ = s³ − 2s² + s,  h₀₁ = −2s³ + 3s²,  h₁₁ = s³ − s².
//! ```
//!
//! It reproduces every cubic exactly (to round-off); its error on a smooth function is
//! `O(h⁴)`. A time outside the nodes' range is evaluated with the polynomial of the
//! first or the last interval (extrapolation), a time on a node gives that node's value
//! exactly.
//!
//! **Place in the flow.** Part of [`discrete`](crate::discrete): it uses the
//! [`Trajectory`] beside it and nothing else. The solve interpolates a coarser solution
//! onto a grid with it, and [`check`](crate::check) a reference onto a solution's times.

use super::trajectory::{NodeSeries, Trajectory};

/// The cubic Hermite basis of one interval `[t₀, t₁]` at one time `t` (module
/// documentation), to be applied to any number of components ([`Hermite::eval`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hermite {
    /// The interval's length `t₁ − t₀`.
    h: f64,
    /// The weight of `y₀`.
    h00: f64,
    /// The weight of `h ẏ₀`.
    h10: f64,
    /// The weight of `y₁`.
    h01: f64,
    /// The weight of `h ẏ₁`.
    h11: f64,
}

impl Hermite {
    /// The basis of the interval `[t0, t1]` at `t` (`t` outside the interval
    /// extrapolates).
    pub fn new(t0: f64, t1: f64, t: f64) -> Hermite {
        let h = t1 - t0;
        let s = (t - t0) / h;
        let (h00, h10, h01, h11) =
            (2.0 * s.powi(3) - 3.0 * s * s + 1.0, s.powi(3) - 2.0 * s * s + s, -2.0 * s.powi(3) + 3.0 * s * s, s.powi(3) - s * s);
        Hermite { h, h00, h10, h01, h11 }
    }

    /// The polynomial with the values `y0`, `y1` and the slopes `dy0`, `dy1` at the
    /// interval's ends, at the basis's time.
    pub fn eval(&self, y0: f64, dy0: f64, y1: f64, dy1: f64) -> f64 {
        self.h00 * y0 + self.h10 * self.h * dy0 + self.h01 * y1 + self.h11 * self.h * dy1
    }

    /// The weights of `y0`, `dy0`, `y1` and `dy1` in [`Hermite::eval`]: the value is
    /// linear in them (a fit's observations are rows of these weights).
    pub fn weights(&self) -> [f64; 4] {
        [self.h00, self.h10 * self.h, self.h01, self.h11 * self.h]
    }
}

/// The index `k` of the interval `[t[k], t[k+1]]` that holds `x`, clamped to the first
/// and the last interval (0 when `t` has fewer than two times). A time on a node
/// between two intervals belongs to the later one.
pub fn segment(t: &[f64], x: f64) -> usize {
    t.partition_point(|&tk| tk <= x).clamp(1, t.len().max(2) - 1) - 1
}

/// The coordinates of `tr` at `times`, each by the cubic Hermite polynomial of its
/// values and velocities on the interval that holds the time ([`segment`]). `tr` needs
/// at least two nodes.
pub fn hermite(tr: &Trajectory, times: &[f64]) -> NodeSeries {
    times
        .iter()
        .map(|&t| {
            let k = segment(&tr.t, t);
            let basis = Hermite::new(tr.t[k], tr.t[k + 1], t);
            (0..tr.q[k].len()).map(|i| basis.eval(tr.q[k][i], tr.v[k][i], tr.q[k + 1][i], tr.v[k + 1][i])).collect()
        })
        .collect()
}

/// A node series `series` at the times `t`, linearly interpolated at `times` (beyond the
/// ends, extrapolated from the first or the last interval). `t` needs at least two times.
pub fn linear(t: &[f64], series: &NodeSeries, times: &[f64]) -> NodeSeries {
    times
        .iter()
        .map(|&x| {
            let k = segment(t, x);
            let s = (x - t[k]) / (t[k + 1] - t[k]);
            series[k].iter().zip(&series[k + 1]).map(|(a, b)| a + s * (b - a)).collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cubic and its derivative.
    fn cubic(x: f64) -> f64 {
        1.0 - 2.0 * x + 0.5 * x * x - 0.3 * x.powi(3)
    }

    fn cubic_slope(x: f64) -> f64 {
        -2.0 + x - 0.9 * x * x
    }

    /// A trajectory whose coordinates are `cubic` and `−cubic`, with their slopes as
    /// velocities, on the unequally spaced times `t`.
    fn trajectory_of_cubics(t: &[f64]) -> Trajectory {
        let mut tr = Trajectory::empty();
        tr.t = t.to_vec();
        tr.q = t.iter().map(|&x| vec![cubic(x), -cubic(x)]).collect();
        tr.v = t.iter().map(|&x| vec![cubic_slope(x), -cubic_slope(x)]).collect();
        tr
    }

    #[test]
    fn hermite_reproduces_a_cubic_inside_and_beyond_the_nodes() {
        let t = [0.0, 0.4, 0.7, 1.2, 1.6, 2.0];
        let tr = trajectory_of_cubics(&t);
        // From 0.5 before the first node to 0.5 past the last, nodes included.
        let times: Vec<f64> = (0..31).map(|k| -0.5 + k as f64 * 0.1).collect();
        for (&x, q) in times.iter().zip(hermite(&tr, &times)) {
            // Measured at most 8.9e-15 (|cubic| ≤ 5.6 here); margin 5x.
            assert!((q[0] - cubic(x)).abs() < 5e-14, "{x}: {} vs {}", q[0], cubic(x));
            assert_eq!(q[1], -q[0], "{x}");
        }
        // On a node, the node's value exactly.
        for (q, &x) in hermite(&tr, &t).iter().zip(&t) {
            assert_eq!(q[0], cubic(x));
        }
    }

    #[test]
    fn segment_clamps_to_the_end_intervals() {
        let t = [0.0, 1.0, 2.0, 3.0];
        assert_eq!(segment(&t, -1.0), 0);
        assert_eq!(segment(&t, 0.0), 0);
        assert_eq!(segment(&t, 0.5), 0);
        assert_eq!(segment(&t, 1.0), 1);
        assert_eq!(segment(&t, 2.9), 2);
        assert_eq!(segment(&t, 3.0), 2);
        assert_eq!(segment(&t, 7.0), 2);
        assert_eq!(segment(&[5.0], 7.0), 0);
    }

    #[test]
    fn linear_reproduces_a_line() {
        let t = [0.0, 0.4, 0.7, 1.2];
        let series: NodeSeries = t.iter().map(|&x| vec![3.0 * x - 1.0]).collect();
        let times = [-0.2, 0.0, 0.1, 0.55, 1.2, 1.5];
        for (&x, y) in times.iter().zip(linear(&t, &series, &times)) {
            assert!((y[0] - (3.0 * x - 1.0)).abs() < 1e-15, "{x}: {}", y[0]);
        }
    }
}
