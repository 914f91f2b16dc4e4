//! The round-off level of a residual: how small `max |F|` can be made in floating point
//! at all. Newton's method and the Ipopt path stop there when it exceeds the tolerance
//! (at large N, or with large numbers in the equations), and a solve stopped there is
//! checked equation by equation.

/// The residual's round-off level is taken as `ROUNDOFF · ε · max_i Σ_j |J_ij| |x_j|`.
/// Measured: at N = 16384 (disk) and 65536 (tumbler) the residual stagnated at 0.4 of
/// `ε · max_i Σ_j |J_ij| |x_j|` (1.1e-11 and 3.2e-11, above the default tol 1e-11), with
/// Newton steps that no longer decreased it.
pub const ROUNDOFF: f64 = 4.0;

/// The round-off level of a residual `F(x)` whose Jacobian has the entries (row,
/// column, value): `ROUNDOFF · ε · max_i Σ_j |J_ij| |x_j|` over `rows` rows. No step
/// computed in floating point can bring `max |F|` much below it. Used as a stopping
/// test by Newton and by the Ipopt path alike.
pub fn residual_roundoff_level(entries: impl Iterator<Item = (usize, usize, f64)>, x: &[f64], rows: usize) -> f64 {
    row_roundoff_levels(entries, x, rows).into_iter().fold(0.0, f64::max)
}

/// The round-off level of each row `i` of a residual `F(x)`, `ROUNDOFF · ε · Σ_j |J_ij| |x_j|`
/// ([`residual_roundoff_level`] is their largest): what one equation's rounding error
/// can reach, so that a solve stopped at the largest level can be checked equation by
/// equation (`SquareSolver::equations_at_round_off`).
pub fn row_roundoff_levels(entries: impl Iterator<Item = (usize, usize, f64)>, x: &[f64], rows: usize) -> Vec<f64> {
    let mut sums = vec![0.0_f64; rows];
    for (r, c, v) in entries {
        sums[r] += v.abs() * x[c].abs();
    }
    sums.iter_mut().for_each(|s| *s *= ROUNDOFF * f64::EPSILON);
    sums
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `ROUNDOFF · ε · max_i Σ_j |J_ij| |x_j|`, duplicates counted separately (they are
    /// summed values whose rounding errors add up).
    #[test]
    fn roundoff_level_is_the_largest_weighted_row_sum() {
        // Rows: |2·1| + |−3·(−2)| = 8 and |0.5·1| + |1·(−2)| + |−1·(−2)| = 4.5.
        let entries = [(0, 0, 2.0), (0, 1, -3.0), (1, 0, 0.5), (1, 1, 1.0), (1, 1, -1.0)];
        let level = residual_roundoff_level(entries.into_iter(), &[1.0, -2.0], 2);
        assert_eq!(level, ROUNDOFF * f64::EPSILON * 8.0);
    }
}
